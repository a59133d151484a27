//! The depth-first search itself: the task-network stack, choice points, backtracking
//! strategies and limits. See the module documentation of `planner` for the design.

use std::collections::{HashMap, HashSet, VecDeque};
use std::hash::BuildHasherDefault;
use std::time::Instant;

use crate::oracle::{GeoSolution, GeometricOracle, OracleError, StreamId};
use crate::plan::{Decomposition, GeoStep, Plan, PlanAction};
use crate::state::{FxHasher, Interner, State, mix64};

use super::compile::{CEffect, CFormula, CLit, CTerm, Compiled};
use super::eval::{EffectBuf, Eval, UNBOUND};
use super::{
    Limit, Outcome, PlanError, PlannerOptions, SearchResult, SearchStats, Strategy, current_rss_kb,
};

mod bfs;
mod guard;
mod heuristic;

const NIL: u32 = u32::MAX;

/// How many ancestors the loop check compares states with (beyond, only ancestors with no
/// action executed since count).
const LOOP_WINDOW: usize = 32;

/// An unknown argument in a partially ground task (only in goal-relevance reasoning).
const WILD: u32 = u32::MAX;

/// How often the search reads its resident memory (a read of /proc costs microseconds).
const MEMORY_CHECK_EVERY: std::time::Duration = std::time::Duration::from_millis(10);

/// Whether a table of `len` entries with room for `capacity` may double before the next
/// check: one node's expansion inserts many entries (every method and binding, the heuristic's
/// memo), so a table within 1/16 of full counts as doubling (a table doubled between two
/// checks took Freecell 13-1 from 281 to 339 MB under a 300 MB limit).
fn may_double(len: usize, capacity: usize) -> bool {
    len.saturating_add((capacity / 16).max(256)) >= capacity
}

/// The bytes a vector allocates when it next doubles, if that may happen before the next
/// check (0 while it has room).
pub(super) fn vec_growth<T>(len: usize, capacity: usize) -> usize {
    if !may_double(len, capacity) {
        0
    } else {
        capacity.max(4) * 2 * std::mem::size_of::<T>()
    }
}

/// The bytes a hash set allocates when it next doubles, if that may happen before the next
/// check (0 while it has room): twice its buckets, each an entry and a control byte.
pub(super) fn set_growth<T, S>(set: &HashSet<T, S>) -> usize {
    table_growth::<T>(set.len(), set.capacity())
}

/// [`set_growth`] of a hash table of `len` entries of type `T` with room for `capacity`.
pub(super) fn table_growth<T>(len: usize, capacity: usize) -> usize {
    if !may_double(len, capacity) {
        0
    } else {
        (capacity.max(4) * 2).next_power_of_two() * (std::mem::size_of::<T>() + 1)
    }
}

/// Whether `f` is a literal over static facts (or equality).
fn is_static_lit(c: &Compiled, f: &CFormula) -> bool {
    match f {
        CFormula::Atom(p, _) => c.static_preds[*p as usize],
        CFormula::Eq(..) => true,
        CFormula::Not(x) => is_static_lit(c, x),
        _ => false,
    }
}

/// Whether `f` reads a shared predicate (a fact that geometry decides).
fn reads_shared(c: &Compiled, f: &CFormula) -> bool {
    match f {
        CFormula::Atom(p, _) => c.shared_preds[*p as usize],
        CFormula::Not(g) | CFormula::Forall(_, g) => reads_shared(c, g),
        CFormula::And(v) | CFormula::Or(v) => v.iter().any(|g| reads_shared(c, g)),
        CFormula::Imply(a, b) => reads_shared(c, a) || reads_shared(c, b),
        CFormula::Exists(_, lits) => lits.iter().any(|l| reads_shared(c, &l.f)),
        CFormula::True | CFormula::Eq(..) | CFormula::Compare(..) => false,
    }
}

/// Adds to `m` the goal literals an action with arguments `args` (some may be `WILD`) may
/// achieve.
fn ground_effect_mask(c: &Compiled, effs: &[CEffect], args: &[u32], m: &mut [u64]) {
    for e in effs {
        match e {
            CEffect::Add(p, terms) | CEffect::Del(p, terms) => {
                let add = matches!(e, CEffect::Add(..));
                for (i, (k, pos)) in c.goal_lits.iter().enumerate() {
                    if k[0] != *p || *pos != add {
                        continue;
                    }
                    let fits = terms.iter().zip(&k[1..]).all(|(t, &want)| match *t {
                        CTerm::Obj(o) => o == want,
                        CTerm::Var(v) => match args.get(v as usize) {
                            Some(&a) => a == WILD || a == want,
                            None => true,
                        },
                    });
                    if fits {
                        m[i / 64] |= 1 << (i % 64);
                    }
                }
            }
            CEffect::Forall(vs, inner) => {
                // Quantified slots are unknown.
                let mut a2 = args.to_vec();
                for (slot, _) in vs {
                    if (*slot as usize) < a2.len() {
                        a2[*slot as usize] = WILD;
                    }
                }
                ground_effect_mask(c, inner, &a2, m);
            }
            CEffect::When(_, inner) => ground_effect_mask(c, inner, args, m),
            CEffect::Num(..) => {}
        }
    }
}

/// One cell of the persistent task-network stack.
#[derive(Clone, Copy)]
struct Cell {
    /// Ground task id.
    task: u32,
    /// Plan id of this task occurrence.
    occ: u32,
    next: u32,
    /// Length of the network from this cell down.
    len: u32,
    /// Hash of the network from this cell down.
    hash: u64,
    /// The decomposition (index in the tree) that created this cell, or `NIL`.
    parent: u32,
    /// The goal literals the network from this cell down may achieve (a mask id).
    may: u32,
}

struct Step {
    occ: u32,
    task: u32,
    geo: Option<GeoStep>,
}

struct TreeRec {
    occ: u32,
    /// Ground task id, or `NIL` for the initial task network.
    task: u32,
    method: u32,
    first: u32,
    n: u32,
    /// The decomposition this task occurrence came from, or `NIL`.
    parent: u32,
    /// Actions in the plan when this decomposition was made.
    steps: u32,
    /// Fingerprint of the state (and geometric world) in which this decomposition was made.
    state: u64,
}

#[derive(Clone, Copy)]
struct Marks {
    arena: usize,
    trail: usize,
    steps: usize,
    tree: usize,
    next_occ: u32,
}

/// The choice taken at a choice point, for replaying a path.
#[derive(Clone, Debug)]
enum Key {
    Htn { method: u32, binding: Vec<u32> },
    Geo(usize),
}

struct HtnFrame {
    occ: u32,
    task: u32,
    rest: u32,
    /// The decomposition the task came from.
    parent: u32,
    /// Next position in the task's method list.
    mpos: usize,
    method: u32,
    stride: usize,
    bindings: Vec<u32>,
    count: usize,
    next: usize,
    tried: u32,
}

struct GeoFrame {
    occ: u32,
    task: u32,
    rest: u32,
    action: u32,
    slots: Vec<u32>,
    stream: StreamId,
    cache: Vec<GeoSolution>,
    current: usize,
    applied: bool,
    exhausted: bool,
}

enum Kind {
    Htn(HtnFrame),
    Geo(GeoFrame),
}

struct Frame {
    marks: Marks,
    kind: Kind,
}

#[derive(Clone, Copy, PartialEq, Eq, Debug)]
enum Mode {
    Normal,
    /// Replaying the recorded choices after taking another geometric solution.
    Retry,
    /// Replaying the original choices to return to the failure point.
    Restore,
}

struct Repair {
    path: Vec<Key>,
    cands: Vec<usize>,
    pos: usize,
    tries_left: usize,
    /// Tries spent on `cands[pos]`.
    tries_here: usize,
    oldest: Option<usize>,
    orig: HashMap<usize, usize>,
}

enum Stop {
    Found,
    /// The depth-first search used its share of the time: the best-first search takes over.
    Switch,
    Exhausted,
    Limit(Limit),
}

/// What [`Search::may_achieve`] knows of a ground task's goal mask.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum MayAchieve {
    Unknown,
    /// Being computed (a recursive call met it again: the lifted mask stands in).
    Computing,
    /// The id of its goal mask.
    Known(u32),
}

pub(crate) struct Search<'a, 'o> {
    c: &'a Compiled,
    opts: PlannerOptions,
    oracle: Option<&'o mut (dyn GeometricOracle + 'o)>,
    state: State,
    gtasks: Interner,
    arena: Vec<Cell>,
    top: u32,
    steps: Vec<Step>,
    tree: Vec<TreeRec>,
    next_occ: u32,
    frames: Vec<Frame>,
    visited: HashSet<u128, BuildHasherDefault<FxHasher>>,
    bound: usize,
    cutoff: bool,
    /// Whether a geometric task was asked under a strategy that caps its solutions.
    geo_capped: bool,
    /// Whether the left-recursion check is on (off in the complete fallback search).
    loop_check: bool,
    stats: SearchStats,
    start: Instant,
    /// When the resident memory is read next (every [`MEMORY_CHECK_EVERY`]).
    next_memory_check: Instant,
    /// A table's doubling would have passed the memory limit ([`Search::growth_fits`]).
    memory_reached: bool,
    effects: EffectBuf,
    mode: Mode,
    forced: VecDeque<Key>,
    repair: Option<Repair>,
    salt: u64,
    /// Per (partially) ground task, the goal mask it may achieve ([`Search::may_achieve`]).
    may_memo: Vec<MayAchieve>,
    masks: MaskTable,
    /// Per task, the id of its lifted goal mask.
    lifted_masks: Vec<u32>,
    /// When (since the start) the depth-first search hands over to the best-first search.
    switch_at: Option<std::time::Duration>,
    /// Goal literals' guarded achievers (`guard.rs`), when some goal literal has any.
    guards: Option<guard::Guards>,
}

/// Interned bitsets over the goal literals, with memoised unions (cells share them).
struct MaskTable {
    words: usize,
    masks: Vec<Box<[u64]>>,
    ids: crate::state::FxMap<Box<[u64]>, u32>,
    unions: crate::state::FxMap<u64, u32>,
}

impl MaskTable {
    fn new(words: usize) -> MaskTable {
        let mut t = MaskTable {
            words,
            masks: Vec::new(),
            ids: Default::default(),
            unions: Default::default(),
        };
        t.intern(&vec![0; words]);
        t
    }

    /// The id of a mask; id 0 is the empty mask.
    fn intern(&mut self, m: &[u64]) -> u32 {
        if let Some(&id) = self.ids.get(m) {
            return id;
        }
        let id = self.masks.len() as u32;
        self.masks.push(m.into());
        self.ids.insert(m.into(), id);
        id
    }

    fn get(&self, id: u32) -> &[u64] {
        &self.masks[id as usize]
    }

    fn union(&mut self, a: u32, b: u32) -> u32 {
        if a == 0 || a == b {
            return b;
        }
        if b == 0 {
            return a;
        }
        let key = ((a.min(b) as u64) << 32) | a.max(b) as u64;
        if let Some(&u) = self.unions.get(&key) {
            return u;
        }
        let m: Vec<u64> = (0..self.words)
            .map(|w| self.masks[a as usize][w] | self.masks[b as usize][w])
            .collect();
        let u = self.intern(&m);
        self.unions.insert(key, u);
        u
    }
}

impl<'a, 'o> Search<'a, 'o> {
    pub fn new(
        c: &'a Compiled,
        opts: &PlannerOptions,
        mut oracle: Option<&'o mut (dyn GeometricOracle + 'o)>,
    ) -> Result<Search<'a, 'o>, PlanError> {
        let salt = mix64(opts.seed ^ 0x6874_6e67_7470);
        let mut state = State::new(c.preds.len(), salt);
        for (p, args) in &c.init_facts {
            let mut key = vec![*p];
            key.extend(args);
            let id = state.intern_fact(&key);
            state.add(id);
        }
        if let Some(o) = oracle.as_deref_mut() {
            for atom in o.initial_facts()? {
                let key = atom_key(c, &atom.predicate, &atom.args)?;
                let id = state.intern_fact(&key);
                state.add(id);
            }
        }
        for (f, args, v) in &c.init_values {
            let mut key = vec![*f];
            key.extend(args);
            let id = state.intern_fluent(&key);
            state.set_value(id, *v);
        }
        state.commit();
        state.index_static(&c.static_preds);
        state.watch(&c.goal_lits);
        let guards = if opts.goal_guards {
            guard::Guards::build(c, &mut state)
        } else {
            None
        };
        let words = c.goal_lits.len().div_ceil(64);
        let mut masks = MaskTable::new(words);
        let lifted_masks = c.task_goal_mask.iter().map(|m| masks.intern(m)).collect();
        Ok(Search {
            c,
            opts: *opts,
            oracle,
            state,
            gtasks: Interner::default(),
            arena: Vec::new(),
            top: NIL,
            steps: Vec::new(),
            tree: Vec::new(),
            next_occ: 0,
            frames: Vec::new(),
            visited: HashSet::default(),
            bound: opts.initial_depth_bound.max(1),
            cutoff: false,
            geo_capped: false,
            loop_check: opts.loop_check,
            start: Instant::now(),
            next_memory_check: Instant::now(),
            memory_reached: false,
            effects: EffectBuf::default(),
            mode: Mode::Normal,
            forced: VecDeque::new(),
            repair: None,
            salt,
            may_memo: Vec::new(),
            masks,
            lifted_masks,
            switch_at: fallback_time(c, opts),
            stats: SearchStats {
                guarded_goals: guards.as_ref().map_or(0, guard::Guards::count),
                ..SearchStats::default()
            },
            guards,
        })
    }

    /// Counts the limits and the statistics' time from `t` (before compiling) instead of from
    /// when the search was made.
    pub fn started_at(mut self, t: Instant) -> Self {
        self.start = t;
        self
    }

    pub fn run(mut self) -> Result<SearchResult, PlanError> {
        let deadline = self
            .opts
            .limits
            .time
            .and_then(|t| self.start.checked_add(t));
        if let Some(o) = self.oracle.as_deref_mut() {
            o.set_deadline(deadline);
        }
        let outcome = loop {
            self.stats.iterations += 1;
            self.stats.depth_bound = self.bound;
            self.cutoff = false;
            let loops_before = self.stats.loops_pruned;
            match self.dfs()? {
                Stop::Found => {
                    break Outcome::Found {
                        plan: self.build_plan(),
                    };
                }
                Stop::Limit(l) => break Outcome::LimitReached { limit: l },
                Stop::Switch => {
                    self.switch_at = None;
                    break match self.best_first() {
                        Stop::Found => Outcome::Found {
                            plan: self.build_plan(),
                        },
                        Stop::Limit(l) => Outcome::LimitReached { limit: l },
                        // Every node reachable was generated (only sound pruning).
                        Stop::Exhausted | Stop::Switch => Outcome::Unsolvable,
                    };
                }
                Stop::Exhausted => {
                    if self.loop_check && self.stats.loops_pruned > loops_before {
                        // The left-recursion check may have cut off the only plans: search
                        // again without it before calling the problem unsolvable.
                        self.loop_check = false;
                        self.reset();
                        continue;
                    }
                    if !self.cutoff {
                        break if self.geo_capped {
                            Outcome::LimitReached {
                                limit: Limit::GeometricAlternatives,
                            }
                        } else {
                            Outcome::Unsolvable
                        };
                    }
                    self.reset();
                    self.bound = self.bound.saturating_mul(2);
                }
            }
        };
        self.stats.time_s = self.start.elapsed().as_secs_f64();
        self.stats.peak_memory_kb = self.stats.peak_memory_kb.max(current_rss_kb());
        Ok(SearchResult {
            outcome,
            stats: self.stats,
        })
    }

    /// Back to the initial node after an exhausted iteration.
    fn reset(&mut self) {
        while !self.frames.is_empty() {
            self.restore_top();
            self.pop_frame();
        }
        self.state.undo_to(0);
        self.arena.clear();
        self.steps.clear();
        self.tree.clear();
        self.next_occ = 0;
        self.visited = HashSet::default();
        self.top = NIL;
    }

    fn marks(&self) -> Marks {
        Marks {
            arena: self.arena.len(),
            trail: self.state.mark(),
            steps: self.steps.len(),
            tree: self.tree.len(),
            next_occ: self.next_occ,
        }
    }

    /// The limits, checked at every node: the clock is cheap (tens of nanoseconds, far below
    /// a node's cost), so a limit stops the search within one node of it, however costly nodes
    /// are (best-first nodes, geometric calls). The resident memory costs a read of /proc, so
    /// it is read every [`MEMORY_CHECK_EVERY`] of search instead.
    fn check_limits(&mut self) -> Option<Limit> {
        let l = self.opts.limits;
        if let Some(n) = l.nodes
            && self.stats.nodes >= n
        {
            return Some(Limit::Nodes);
        }
        if self.memory_reached {
            return Some(Limit::Memory);
        }
        let now = Instant::now();
        if let Some(t) = l.time
            && now.duration_since(self.start) >= t
        {
            return Some(Limit::Time);
        }
        if now >= self.next_memory_check {
            self.next_memory_check = now + MEMORY_CHECK_EVERY;
            let rss = current_rss_kb();
            self.stats.peak_memory_kb = self.stats.peak_memory_kb.max(rss);
            if let Some(mb) = l.memory_mb
                && rss > mb.saturating_mul(1024)
            {
                return Some(Limit::Memory);
            }
        }
        None
    }

    /// Whether the search may grow a table by `extra` bytes (while it doubles, the old and the
    /// new table are both resident) within the memory limit; if not, the memory limit is
    /// marked reached, for [`Search::check_limits`]. `extra` 0 (nothing doubles) costs nothing.
    pub(super) fn growth_fits(&mut self, extra: usize) -> bool {
        let Some(mb) = self.opts.limits.memory_mb else {
            return true;
        };
        if extra == 0 {
            return true;
        }
        let fits = current_rss_kb() + (extra as u64 >> 10) <= mb.saturating_mul(1024);
        if !fits {
            self.memory_reached = true;
        }
        fits
    }

    fn dfs(&mut self) -> Result<Stop, PlanError> {
        self.top = NIL;
        if !self.push_htn_frame(NIL, NIL, NIL, NIL)? && !self.fail()? {
            return Ok(Stop::Exhausted);
        }
        loop {
            if let Some(l) = self.check_limits() {
                return Ok(Stop::Limit(l));
            }
            if let Some(t) = self.switch_at
                && self.start.elapsed() >= t
            {
                return Ok(Stop::Switch);
            }
            if self.top == NIL {
                if self.goal_holds() {
                    return Ok(Stop::Found);
                }
                if !self.fail()? {
                    return Ok(Stop::Exhausted);
                }
                continue;
            }
            self.stats.nodes += 1;
            let cell = self.arena[self.top as usize];
            let ok = if cell.len as usize > self.bound {
                self.cutoff = true;
                self.stats.depth_cutoffs += 1;
                false
            } else if !self.goal_reachable(cell.may) {
                self.stats.goal_pruned += 1;
                false
            } else if self.mode == Mode::Normal
                && self.opts.duplicate_detection
                && !self.first_visit(cell.hash)
            {
                self.stats.revisits_pruned += 1;
                false
            } else {
                let task = self.gtasks.key(cell.task)[0];
                match self.c.tasks[task as usize].action {
                    Some(a) => self.expand_action(a, cell)?,
                    None => {
                        if self.loop_check && self.no_progress_repeat(cell) {
                            self.stats.loops_pruned += 1;
                            false
                        } else {
                            self.push_htn_frame(cell.task, cell.occ, cell.next, cell.parent)?
                        }
                    }
                }
            };
            if !ok && !self.fail()? {
                return Ok(Stop::Exhausted);
            }
        }
    }

    /// Fingerprint of the current state and geometric world.
    fn state_fingerprint(&self) -> u64 {
        let world = self.oracle.as_deref().map_or(0, |o| o.world_fingerprint());
        self.state.hash() ^ mix64(world ^ self.salt)
    }

    /// Whether the same ground task is being decomposed by one of its own ancestors in the
    /// same state (recursion that made no progress: whatever was executed since, if anything,
    /// led back to the state the outer occurrence started in, so the inner occurrence can only
    /// repeat what the outer one may do). Ancestors with no action since are all looked at;
    /// with actions since, only the nearest [`LOOP_WINDOW`] (the walk stays cheap in deep
    /// decompositions, and seeing fewer repeats only prunes less).
    fn no_progress_repeat(&self, cell: Cell) -> bool {
        let steps = self.steps.len() as u32;
        let mut r = cell.parent;
        let mut now = None;
        let mut dist = 0;
        while r != NIL {
            let rec = &self.tree[r as usize];
            let same_steps = rec.steps == steps;
            if !same_steps && dist >= LOOP_WINDOW {
                return false;
            }
            if rec.task == cell.task {
                if same_steps {
                    return true;
                }
                let now = *now.get_or_insert_with(|| self.state_fingerprint());
                if rec.state == now {
                    return true;
                }
            }
            dist += 1;
            r = rec.parent;
        }
        false
    }

    /// Whether every goal literal (or landmark still needed) that is false now may still be
    /// achieved by the network whose tasks may achieve mask `may`.
    fn goal_reachable(&self, may: u32) -> bool {
        if self.c.goal_lits.is_empty() {
            return true;
        }
        let unsat = self.state.unsat();
        let may = self.masks.get(may);
        for (w, (&u, &m)) in unsat.iter().zip(may).enumerate() {
            let mut bad = u & !m;
            while bad != 0 {
                let i = w * 64 + bad.trailing_zeros() as usize;
                bad &= bad - 1;
                // A landmark is needed only while every literal it serves is still false.
                let mut needed = true;
                let mut p = self.c.goal_parent[i];
                while let Some(j) = p {
                    if unsat[j / 64] & (1 << (j % 64)) == 0 {
                        needed = false;
                        break;
                    }
                    p = self.c.goal_parent[j];
                }
                if needed {
                    return false;
                }
            }
        }
        true
    }

    /// The goal literals (a mask id) that ground task `gt` may achieve, through the methods
    /// whose task arguments and static preconditions fit its arguments. Arguments may be
    /// `WILD` (unknown). Memoised; a task met again while it is being computed counts with its
    /// lifted mask (an over-approximation, so the pruning stays sound).
    fn may_achieve(&mut self, gt: u32) -> u32 {
        if self.c.goal_lits.is_empty() {
            return 0;
        }
        let n = self.gtasks.len();
        if self.may_memo.len() < n {
            self.may_memo.resize(n, MayAchieve::Unknown);
        }
        let c = self.c;
        let key = self.gtasks.key(gt).to_vec();
        let t = key[0] as usize;
        let lifted = self.lifted_masks[t];
        match self.may_memo[gt as usize] {
            MayAchieve::Known(m) => return m,
            MayAchieve::Computing => return lifted,
            MayAchieve::Unknown => {}
        }
        self.may_memo[gt as usize] = MayAchieve::Computing;
        let args = &key[1..];
        let mut m = vec![0u64; self.masks.words];
        if let Some(a) = c.tasks[t].action {
            ground_effect_mask(c, &c.actions[a as usize].effects, args, &mut m);
            if c.actions[a as usize].evaluable.is_some() {
                for (i, (k, _)) in c.goal_lits.iter().enumerate() {
                    if c.shared_preds[k[0] as usize] {
                        m[i / 64] |= 1 << (i % 64);
                    }
                }
            }
        } else {
            let mut sub: Vec<u32> = Vec::new();
            'methods: for &mi in &c.tasks[t].methods {
                if *m == *self.masks.get(lifted) {
                    break;
                }
                let method = &c.methods[mi as usize];
                let mut b = vec![UNBOUND; method.slot_types.len()];
                for (term, &a) in method.task_args.iter().zip(args) {
                    match *term {
                        CTerm::Obj(o) => {
                            if a != WILD && a != o {
                                continue 'methods;
                            }
                        }
                        CTerm::Var(v) => {
                            if a == WILD {
                                continue;
                            }
                            let cur = b[v as usize];
                            if cur == UNBOUND {
                                if !c.is_of(a, method.slot_types[v as usize]) {
                                    continue 'methods;
                                }
                                b[v as usize] = a;
                            } else if cur != a {
                                continue 'methods;
                            }
                        }
                    }
                }
                // A static atom with one unbound slot binds it when the facts allow a single
                // value (none: the method never applies).
                if !self.bind_by_static_facts(&method.pre, &mut b) {
                    continue 'methods;
                }
                // Static literals whose slots are all bound must hold.
                let ev = Eval {
                    c,
                    s: &self.state,
                    types: &method.slot_types,
                };
                for l in &method.pre {
                    if is_static_lit(c, &l.f)
                        && l.vars.iter().all(|&v| b[v as usize] != UNBOUND)
                        && !ev.holds(&l.f, &mut b)
                    {
                        continue 'methods;
                    }
                }
                for (st, sargs) in &method.subtasks {
                    sub.clear();
                    sub.push(*st);
                    sub.extend(sargs.iter().map(|a| match *a {
                        CTerm::Obj(o) => o,
                        CTerm::Var(v) => {
                            let x = b[v as usize];
                            if x == UNBOUND { WILD } else { x }
                        }
                    }));
                    let id = self.gtasks.intern(&sub);
                    let sm = self.may_achieve(id);
                    for (w, x) in m.iter_mut().zip(self.masks.get(sm)) {
                        *w |= x;
                    }
                }
            }
        }
        let id = self.masks.intern(&m);
        if self.may_memo.len() <= gt as usize {
            self.may_memo.resize(gt as usize + 1, MayAchieve::Unknown);
        }
        self.may_memo[gt as usize] = MayAchieve::Known(id);
        id
    }

    /// Binds slots through static atoms that leave a single candidate; `false` if one leaves none.
    fn bind_by_static_facts(&self, pre: &[CLit], b: &mut [u32]) -> bool {
        loop {
            let mut changed = false;
            for l in pre {
                let CFormula::Atom(p, args) = &l.f else {
                    continue;
                };
                if !self.state.is_static(*p) {
                    continue;
                }
                let unbound: Vec<u16> = l
                    .vars
                    .iter()
                    .copied()
                    .filter(|&v| b[v as usize] == UNBOUND)
                    .collect();
                let [v] = unbound[..] else {
                    continue;
                };
                // Candidates: through the index on some bound argument, else all facts.
                let mut cands = self.state.facts_of(*p);
                for (k, t) in args.iter().enumerate() {
                    let o = match *t {
                        CTerm::Obj(o) => o,
                        CTerm::Var(x) => b[x as usize],
                    };
                    if o != UNBOUND {
                        let c = self.state.static_facts_with(*p, k, o);
                        if c.len() < cands.len() {
                            cands = c;
                        }
                    }
                }
                let mut value = UNBOUND;
                let mut several = false;
                for &f in cands {
                    let fa = self.state.fact_args(f);
                    let mut cand = UNBOUND;
                    let fits = args.iter().zip(fa).all(|(t, &x)| match *t {
                        CTerm::Obj(o) => o == x,
                        CTerm::Var(y) if y == v => {
                            let ok = cand == UNBOUND || cand == x;
                            cand = x;
                            ok
                        }
                        CTerm::Var(y) => b[y as usize] == x,
                    });
                    if fits {
                        if value == UNBOUND {
                            value = cand;
                        } else if value != cand {
                            several = true;
                            break;
                        }
                    }
                }
                if value == UNBOUND {
                    return false;
                }
                if !several {
                    b[v as usize] = value;
                    changed = true;
                }
            }
            if !changed {
                return true;
            }
        }
    }

    fn first_visit(&mut self, net_hash: u64) -> bool {
        if !self.growth_fits(set_growth(&self.visited)) {
            // The table would double past the memory limit: stop (at the next check) rather
            // than grow. Taking the node as new loses nothing, the search ends there.
            return true;
        }
        let h = self.state_fingerprint();
        self.visited.insert(((h as u128) << 64) | net_hash as u128)
    }

    fn goal_holds(&mut self) -> bool {
        let mut b = vec![UNBOUND; self.c.goal_slot_types.len()];
        let ev = Eval {
            c: self.c,
            s: &self.state,
            types: &self.c.goal_slot_types,
        };
        ev.holds(&self.c.goal, &mut b)
    }

    /// A search failure at the current node.
    fn fail(&mut self) -> Result<bool, PlanError> {
        match self.mode {
            Mode::Normal => self.backtrack(),
            Mode::Retry => self.next_repair_try(),
            Mode::Restore => {
                // The replay of the original choices did not reproduce them (a back end that
                // is not deterministic): give up the repair and backtrack from here.
                self.end_repair();
                self.backtrack()
            }
        }
    }

    fn backtrack(&mut self) -> Result<bool, PlanError> {
        while !self.frames.is_empty() {
            self.restore_top();
            if self.next_alternative()? {
                return Ok(true);
            }
            self.pop_frame();
        }
        Ok(false)
    }

    /// Undoes everything done since the top frame was created (keeps the frame).
    fn restore_top(&mut self) {
        let f = self.frames.last_mut().expect("a frame to restore");
        let m = f.marks;
        if let Kind::Geo(g) = &mut f.kind
            && g.applied
        {
            g.applied = false;
            if let Some(o) = self.oracle.as_deref_mut() {
                o.undo();
            }
        }
        self.state.undo_to(m.trail);
        self.arena.truncate(m.arena);
        self.steps.truncate(m.steps);
        self.tree.truncate(m.tree);
        self.next_occ = m.next_occ;
    }

    fn pop_frame(&mut self) {
        let f = self.frames.pop().expect("a frame to pop");
        if let Kind::Geo(g) = f.kind
            && let Some(o) = self.oracle.as_deref_mut()
        {
            if g.applied {
                o.undo();
            }
            o.close(g.stream);
        }
    }

    fn push_cell(&mut self, task: u32, occ: u32, next: u32, parent: u32) -> u32 {
        let (len, h, may) = if next == NIL {
            (0, 0, 0)
        } else {
            let n = &self.arena[next as usize];
            (n.len, n.hash, n.may)
        };
        let mine = self.may_achieve(task);
        let may = self.masks.union(mine, may);
        let hash = mix64(h.rotate_left(7) ^ mix64(task as u64 ^ self.salt));
        self.arena.push(Cell {
            task,
            occ,
            next,
            len: len + 1,
            hash,
            parent,
            may,
        });
        (self.arena.len() - 1) as u32
    }

    fn methods_of(&self, task: u32) -> &'a [u32] {
        let c = self.c;
        if task == NIL {
            std::slice::from_ref(&c.root_method)
        } else {
            let t = self.gtasks.key(task)[0];
            &c.tasks[t as usize].methods
        }
    }

    /// All bindings of method `m`'s parameters for ground task `task`, flat.
    fn bindings(&self, m: u32, task: u32) -> (Vec<u32>, usize) {
        self.bindings_upto(m, task, usize::MAX)
    }

    /// The first `max` bindings of method `m`'s parameters for ground task `task`, flat.
    fn bindings_upto(&self, m: u32, task: u32, max: usize) -> (Vec<u32>, usize) {
        let c = self.c;
        let method = &c.methods[m as usize];
        let mut b = vec![UNBOUND; method.slot_types.len()];
        if task != NIL {
            let args = &self.gtasks.key(task)[1..];
            if args.len() != method.task_args.len() {
                return (Vec::new(), 0);
            }
            for (t, &a) in method.task_args.iter().zip(args) {
                match *t {
                    CTerm::Obj(o) => {
                        if o != a {
                            return (Vec::new(), 0);
                        }
                    }
                    CTerm::Var(v) => {
                        let cur = b[v as usize];
                        if cur == UNBOUND {
                            if !c.is_of(a, method.slot_types[v as usize]) {
                                return (Vec::new(), 0);
                            }
                            b[v as usize] = a;
                        } else if cur != a {
                            return (Vec::new(), 0);
                        }
                    }
                }
            }
        }
        let need = &method.params;
        let n = method.n_params;
        let mut out = Vec::new();
        let mut count = 0;
        let ev = Eval {
            c,
            s: &self.state,
            types: &method.slot_types,
        };
        ev.solve(&method.pre, &mut b, need, &mut |bb| {
            out.extend_from_slice(&bb[..n]);
            count += 1;
            count >= max
        });
        (out, count)
    }

    fn push_htn_frame(
        &mut self,
        task: u32,
        occ: u32,
        rest: u32,
        parent: u32,
    ) -> Result<bool, PlanError> {
        if self.mode == Mode::Restore && self.forced.is_empty() && task != NIL {
            // Back at a failure point of a repair with the original choices: fall back to HTN
            // backtracking from here (see `expand_gs`).
            self.end_repair();
            return Ok(false);
        }
        let marks = self.marks();
        self.frames.push(Frame {
            marks,
            kind: Kind::Htn(HtnFrame {
                occ,
                task,
                rest,
                parent,
                mpos: 0,
                method: 0,
                stride: 0,
                bindings: Vec::new(),
                count: 0,
                next: 0,
                tried: 0,
            }),
        });
        if self.mode != Mode::Normal && !self.forced.is_empty() {
            let Some(Key::Htn { method, binding }) = self.forced.pop_front() else {
                return Ok(false);
            };
            let methods = self.methods_of(task);
            let Some(pos) = methods.iter().position(|&m| m == method) else {
                return Ok(false);
            };
            let (bindings, count) = self.bindings(method, task);
            let stride = self.c.methods[method as usize].n_params;
            let Some(idx) = (0..count).find(|&i| bindings[i * stride..(i + 1) * stride] == binding)
            else {
                return Ok(false);
            };
            let Some(Frame {
                kind: Kind::Htn(f), ..
            }) = self.frames.last_mut()
            else {
                unreachable!()
            };
            f.mpos = pos + 1;
            f.method = method;
            f.stride = stride;
            f.bindings = bindings;
            f.count = count;
            f.next = idx + 1;
            f.tried = 1;
            self.apply_method(method, &binding);
            return Ok(true);
        }
        if self.next_alternative()? {
            if self.mode == Mode::Retry && self.forced.is_empty() {
                // The task that had no applicable method has one after the repair.
                self.stats.geo_repairs_succeeded += 1;
                self.end_repair();
            }
            return Ok(true);
        }
        // No method applies, and some method's precondition reads shared literals: the
        // geometry made it fail (Fig. 4: a book placed so that it hides another). With
        // geometric-first, other solutions of earlier geometric tasks come first, as on a
        // failing GS action.
        if self.mode == Mode::Normal
            && task != NIL
            && let Strategy::GeometricFirst { k } = self.opts.strategy
            && k > 0
            && self.methods_read_shared(task)
        {
            self.pop_frame();
            return self.start_repair(k);
        }
        Ok(false)
    }

    /// Whether a precondition of some method of ground task `task` reads a shared predicate.
    fn methods_read_shared(&self, task: u32) -> bool {
        let c = self.c;
        self.methods_of(task).iter().any(|&m| {
            c.methods[m as usize]
                .pre
                .iter()
                .any(|l| reads_shared(c, &l.f))
        })
    }

    /// Tries the top frame's next alternative (the frame is restored).
    fn next_alternative(&mut self) -> Result<bool, PlanError> {
        let top = self.frames.len() - 1;
        match &mut self.frames[top].kind {
            Kind::Htn(_) => Ok(self.next_method_alternative(top)),
            Kind::Geo(g) => {
                if self.opts.strategy != Strategy::Chronological || g.exhausted {
                    return Ok(false);
                }
                loop {
                    let Kind::Geo(g) = &self.frames[top].kind else {
                        unreachable!()
                    };
                    let idx = g.current + 1;
                    if !self.fetch(top, idx)? {
                        return Ok(false);
                    }
                    self.stats.geo_backtracks += 1;
                    if let Kind::Geo(g) = &mut self.frames[top].kind {
                        g.current = idx;
                    }
                    if self.apply_geo(top)? {
                        return Ok(true);
                    }
                }
            }
        }
    }

    fn next_method_alternative(&mut self, top: usize) -> bool {
        loop {
            let Kind::Htn(f) = &mut self.frames[top].kind else {
                unreachable!()
            };
            if f.next < f.count {
                let i = f.next;
                f.next += 1;
                if f.tried > 0 {
                    self.stats.htn_backtracks += 1;
                }
                f.tried += 1;
                let m = f.method;
                let binding = f.bindings[i * f.stride..(i + 1) * f.stride].to_vec();
                self.apply_method(m, &binding);
                return true;
            }
            let (task, mpos) = (f.task, f.mpos);
            let methods = self.methods_of(task);
            if mpos >= methods.len() {
                return false;
            }
            let m = methods[mpos];
            let (bindings, count) = self.bindings(m, task);
            let Kind::Htn(f) = &mut self.frames[top].kind else {
                unreachable!()
            };
            f.mpos = mpos + 1;
            f.method = m;
            f.stride = self.c.methods[m as usize].n_params;
            f.bindings = bindings;
            f.count = count;
            f.next = 0;
        }
    }

    /// Decomposes the top frame's task with method `m` under `binding`.
    fn apply_method(&mut self, m: u32, binding: &[u32]) {
        let top = self.frames.len() - 1;
        let Kind::Htn(f) = &self.frames[top].kind else {
            unreachable!()
        };
        let (occ, task, rest, parent) = (f.occ, f.task, f.rest, f.parent);
        let method = &self.c.methods[m as usize];
        let first = self.next_occ;
        let n = method.subtasks.len() as u32;
        let rec = self.tree.len() as u32;
        self.tree.push(TreeRec {
            occ,
            task,
            method: m,
            first,
            n,
            parent,
            steps: self.steps.len() as u32,
            state: self.state_fingerprint(),
        });
        self.next_occ += n;
        let mut top_cell = rest;
        let mut key: Vec<u32> = Vec::with_capacity(8);
        for (i, (t, args)) in method.subtasks.iter().enumerate().rev() {
            key.clear();
            key.push(*t);
            key.extend(args.iter().map(|a| match *a {
                CTerm::Var(v) => binding[v as usize],
                CTerm::Obj(o) => o,
            }));
            let gt = self.gtasks.intern(&key);
            top_cell = self.push_cell(gt, first + i as u32, top_cell, rec);
        }
        self.top = top_cell;
    }

    /// The slots of action `a` bound to the arguments of ground task `task`, if their types fit.
    fn action_slots(&self, a: u32, task: u32) -> Option<Vec<u32>> {
        let act = &self.c.actions[a as usize];
        let args = &self.gtasks.key(task)[1..];
        if args.len() != act.n_params {
            return None;
        }
        let mut slots = vec![UNBOUND; act.slot_types.len()];
        for (i, &o) in args.iter().enumerate() {
            if !self.c.is_of(o, act.slot_types[i]) {
                return None;
            }
            slots[i] = o;
        }
        Some(slots)
    }

    fn expand_action(&mut self, a: u32, cell: Cell) -> Result<bool, PlanError> {
        let c = self.c;
        let act = &c.actions[a as usize];
        let Some(mut slots) = self.action_slots(a, cell.task) else {
            return Ok(false);
        };
        let ev = Eval {
            c,
            s: &self.state,
            types: &act.slot_types,
        };
        if !ev.all_hold(&act.pre, &mut slots) {
            return Ok(false);
        }
        if act.evaluable.is_some() {
            return self.expand_gs(a, cell, slots);
        }
        self.effects.clear();
        if !ev.effects(&act.effects, &mut slots, &mut self.effects) {
            return Ok(false);
        }
        let mark = self.state.mark();
        self.effects.apply(&mut self.state);
        if self.guards.is_some() && !self.guarded_goals_alive(mark, cell.next) {
            self.stats.goal_pruned += 1;
            return Ok(false);
        }
        self.steps.push(Step {
            occ: cell.occ,
            task: cell.task,
            geo: None,
        });
        self.top = cell.next;
        Ok(true)
    }

    fn expand_gs(&mut self, a: u32, cell: Cell, slots: Vec<u32>) -> Result<bool, PlanError> {
        if self.mode == Mode::Restore && self.forced.is_empty() {
            // Back at the failure point with the original choices: fall back to HTN
            // backtracking from here.
            self.end_repair();
            return Ok(false);
        }
        let c = self.c;
        let (g, args) = c.actions[a as usize]
            .evaluable
            .as_ref()
            .expect("a GS action");
        let names: Vec<String> = args
            .iter()
            .map(|t| {
                let o = match *t {
                    CTerm::Var(v) => slots[v as usize],
                    CTerm::Obj(o) => o,
                };
                c.objects[o as usize].clone()
            })
            .collect();
        let oracle = self
            .oracle
            .as_deref_mut()
            .expect("GS actions need an oracle");
        let stream = oracle.open(&c.geo_tasks[*g as usize], &names)?;
        self.geo_capped |= self.opts.strategy != Strategy::Chronological;
        let marks = self.marks();
        self.frames.push(Frame {
            marks,
            kind: Kind::Geo(GeoFrame {
                occ: cell.occ,
                task: cell.task,
                rest: cell.next,
                action: a,
                slots,
                stream,
                cache: Vec::new(),
                current: 0,
                applied: false,
                exhausted: false,
            }),
        });
        let top = self.frames.len() - 1;
        let replaying = self.mode != Mode::Normal && !self.forced.is_empty();
        let want = if replaying {
            match self.forced.pop_front() {
                Some(Key::Geo(j)) if self.mode == Mode::Restore => j,
                Some(Key::Geo(_)) => 0,
                _ => return Ok(false),
            }
        } else {
            0
        };
        if self.fetch(top, want)? {
            if let Kind::Geo(gf) = &mut self.frames[top].kind {
                gf.current = want;
            }
            if self.apply_geo(top)? {
                if self.mode == Mode::Retry && self.forced.is_empty() {
                    // The failed geometric task has a solution after the repair.
                    self.stats.geo_repairs_succeeded += 1;
                    self.end_repair();
                }
                return Ok(true);
            }
        }
        // A geometric failure.
        if self.mode == Mode::Normal
            && let Strategy::GeometricFirst { k } = self.opts.strategy
            && k > 0
        {
            self.pop_frame();
            return self.start_repair(k);
        }
        Ok(false)
    }

    /// Makes solution `idx` of geo frame `fi` available in its cache; `false` if the stream
    /// has fewer solutions.
    fn fetch(&mut self, fi: usize, idx: usize) -> Result<bool, PlanError> {
        loop {
            let Kind::Geo(g) = &mut self.frames[fi].kind else {
                unreachable!()
            };
            if idx < g.cache.len() {
                return Ok(true);
            }
            if g.exhausted || (self.opts.strategy == Strategy::Symbolic && !g.cache.is_empty()) {
                return Ok(false);
            }
            let oracle = self
                .oracle
                .as_deref_mut()
                .expect("GS actions need an oracle");
            match oracle.next_solution(g.stream)? {
                Some(s) => g.cache.push(s),
                None => {
                    g.exhausted = true;
                    return Ok(false);
                }
            }
        }
    }

    /// Takes the current solution of geo frame `fi` (the top frame, restored).
    fn apply_geo(&mut self, fi: usize) -> Result<bool, PlanError> {
        let c = self.c;
        let Kind::Geo(g) = &mut self.frames[fi].kind else {
            unreachable!()
        };
        let act = &c.actions[g.action as usize];
        let ev = Eval {
            c,
            s: &self.state,
            types: &act.slot_types,
        };
        self.effects.clear();
        if !ev.effects(&act.effects, &mut g.slots, &mut self.effects) {
            return Ok(false);
        }
        self.effects.apply(&mut self.state);
        let sol = &g.cache[g.current];
        for atom in &sol.delete {
            let key = atom_key(c, &atom.predicate, &atom.args)?;
            if let Some(id) = self.state.facts.get(&key) {
                self.state.delete(id);
            }
        }
        for atom in &sol.add {
            let key = atom_key(c, &atom.predicate, &atom.args)?;
            let id = self.state.intern_fact(&key);
            self.state.add(id);
        }
        let oracle = self
            .oracle
            .as_deref_mut()
            .expect("GS actions need an oracle");
        oracle.apply(sol.id)?;
        g.applied = true;
        let (gt, gargs) = act.evaluable.as_ref().expect("a GS action");
        let geo = GeoStep {
            task: c.geo_tasks[*gt as usize].clone(),
            args: gargs
                .iter()
                .map(|t| match *t {
                    CTerm::Var(v) => c.objects[g.slots[v as usize] as usize].clone(),
                    CTerm::Obj(o) => c.objects[o as usize].clone(),
                })
                .collect(),
            add: sol.add.clone(),
            delete: sol.delete.clone(),
            solution: sol.id,
        };
        self.steps.push(Step {
            occ: g.occ,
            task: g.task,
            geo: Some(geo),
        });
        self.top = g.rest;
        Ok(true)
    }

    fn key_of(f: &Frame) -> Key {
        match &f.kind {
            Kind::Htn(h) => {
                let i = h.next - 1;
                Key::Htn {
                    method: h.method,
                    binding: h.bindings[i * h.stride..(i + 1) * h.stride].to_vec(),
                }
            }
            Kind::Geo(g) => Key::Geo(g.current),
        }
    }

    fn start_repair(&mut self, k: usize) -> Result<bool, PlanError> {
        let path: Vec<Key> = self.frames.iter().map(Self::key_of).collect();
        let cands: Vec<usize> = (0..self.frames.len())
            .rev()
            .filter(|&i| matches!(&self.frames[i].kind, Kind::Geo(g) if !(g.exhausted && g.current + 1 >= g.cache.len())))
            .collect();
        if cands.is_empty() {
            return self.backtrack();
        }
        let orig = cands
            .iter()
            .map(|&i| match &self.frames[i].kind {
                Kind::Geo(g) => (i, g.current),
                Kind::Htn(_) => unreachable!(),
            })
            .collect();
        self.stats.geo_repairs += 1;
        self.repair = Some(Repair {
            path,
            cands,
            pos: 0,
            tries_left: k,
            tries_here: 0,
            oldest: None,
            orig,
        });
        self.mode = Mode::Retry;
        self.next_repair_try()
    }

    fn unwind_to(&mut self, fi: usize) {
        while self.frames.len() > fi + 1 {
            self.pop_frame();
        }
        self.restore_top();
    }

    /// The next try of a repair: another solution of an earlier geometric task, the latest
    /// first, each task its share of the tries left (so that a budget of k reaches back k tasks
    /// rather than spending it all on the latest one, as the paper's GTP backtracks "all the
    /// way up to PICK(b1)"). Tasks are visited latest to earliest only: unwinding never has to
    /// reach a frame a failed replay did not rebuild.
    fn next_repair_try(&mut self) -> Result<bool, PlanError> {
        loop {
            let r = self.repair.as_mut().expect("a repair in progress");
            if r.pos >= r.cands.len() || r.tries_left == 0 {
                return self.restore_after_repair();
            }
            let share = r.tries_left.div_ceil(r.cands.len() - r.pos);
            if r.tries_here >= share {
                r.pos += 1;
                r.tries_here = 0;
                continue;
            }
            let g = r.cands[r.pos];
            r.oldest = Some(g);
            self.unwind_to(g);
            let Kind::Geo(gf) = &self.frames[g].kind else {
                unreachable!()
            };
            let idx = gf.current + 1;
            if !self.fetch(g, idx)? {
                let r = self.repair.as_mut().expect("a repair");
                r.pos += 1;
                r.tries_here = 0;
                continue;
            }
            self.stats.geo_backtracks += 1;
            let r = self.repair.as_mut().expect("a repair");
            r.tries_left -= 1;
            r.tries_here += 1;
            let forced: VecDeque<Key> = r.path[g + 1..].iter().cloned().collect();
            if let Kind::Geo(gf) = &mut self.frames[g].kind {
                gf.current = idx;
            }
            if self.apply_geo(g)? {
                self.forced = forced;
                self.mode = Mode::Retry;
                return Ok(true);
            }
        }
    }

    fn restore_after_repair(&mut self) -> Result<bool, PlanError> {
        let r = self.repair.as_ref().expect("a repair");
        let Some(t) = r.oldest else {
            self.end_repair();
            return self.backtrack();
        };
        let orig = r.orig[&t];
        let forced: VecDeque<Key> = r.path[t + 1..].iter().cloned().collect();
        self.unwind_to(t);
        if let Kind::Geo(gf) = &mut self.frames[t].kind {
            gf.current = orig;
        }
        if !self.apply_geo(t)? {
            self.end_repair();
            return self.backtrack();
        }
        self.forced = forced;
        self.mode = Mode::Restore;
        Ok(true)
    }

    fn end_repair(&mut self) {
        self.repair = None;
        self.forced.clear();
        self.mode = Mode::Normal;
    }

    fn build_plan(&self) -> Plan {
        let c = self.c;
        let names = |gt: u32| -> (String, Vec<String>) {
            let k = self.gtasks.key(gt);
            (
                c.tasks[k[0] as usize].name.clone(),
                k[1..]
                    .iter()
                    .map(|&o| c.objects[o as usize].clone())
                    .collect(),
            )
        };
        let mut plan = Plan::default();
        for s in &self.steps {
            let (name, args) = names(s.task);
            plan.actions.push(PlanAction {
                id: s.occ,
                name,
                args,
                geometric: s.geo.clone(),
            });
        }
        for t in &self.tree {
            let ids: Vec<u32> = (t.first..t.first + t.n).collect();
            if t.task == NIL {
                plan.root = ids;
                continue;
            }
            let (task, args) = names(t.task);
            plan.decompositions.push(Decomposition {
                id: t.occ,
                task,
                args,
                method: c.methods[t.method as usize].name.clone(),
                subtasks: ids,
            });
        }
        plan
    }
}

/// When the depth-first search hands over to the best-first one: after its share of the time
/// limit, on purely symbolic problems, when the fallback is on.
fn fallback_time(c: &Compiled, opts: &PlannerOptions) -> Option<std::time::Duration> {
    let t = opts.limits.time?;
    if opts.best_first_share <= 0.0
        || opts.best_first_share > 1.0
        || opts.best_first_share.is_nan()
        || c.actions.iter().any(|a| a.evaluable.is_some())
    {
        return None;
    }
    Some(t.mul_f64(1.0 - opts.best_first_share))
}

/// The fact key of a shared literal given by name.
fn atom_key(c: &Compiled, predicate: &str, args: &[String]) -> Result<Vec<u32>, OracleError> {
    let p = c.pred_ids.get(predicate).ok_or_else(|| {
        OracleError(format!(
            "the back end gave a literal of unknown predicate `{predicate}`"
        ))
    })?;
    let mut key = vec![*p];
    for a in args {
        key.push(*c.object_ids.get(a).ok_or_else(|| {
            OracleError(format!(
                "the back end gave a literal over unknown object `{a}` ({predicate})"
            ))
        })?);
    }
    Ok(key)
}
