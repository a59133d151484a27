//! The shared core of the HTN search engines: the task network as a persistent stack of
//! cells, the state with its undo trail, the decomposition tree and the plan it gives. The
//! engines and their parts live in the submodules, each an `impl` block over [`Search`]:
//!
//! - `frames.rs`: choice points (HTN and geometric frames, addressed by typed ids), undone
//!   through the marks they keep;
//! - `dfs.rs`: the depth-first engine (methods in domain order, chronological backtracking);
//! - `geo.rs`: GS actions, whose solutions come from the geometric oracle;
//! - `repair.rs`: the geometric-first strategy's repair (other solutions of earlier
//!   geometric tasks before HTN alternatives, the paper's Figure 3);
//! - `bfs.rs`: the best-first engine (weighted A* over progression);
//! - `driver.rs`: iterative deepening and the fallback from depth-first to best-first;
//! - `limits.rs`: time, node and memory limits;
//! - `relevance.rs`: goal relevance (what a task network may still achieve);
//! - `guard.rs`: guarded achievers of goal literals.
//!
//! See the module documentation of `planner` for the design.

use std::collections::{HashSet, VecDeque};
use std::hash::BuildHasherDefault;
use std::time::Instant;

use crate::budget::Watch;
use crate::oracle::{GeometricOracle, OracleError};
use crate::plan::{Decomposition, GeoStep, Plan, PlanAction};
use crate::state::{FxHasher, Interner, State, mix64};

use super::compile::{CTerm, Compiled};
use super::eval::{Cursor, EffectBuf, Eval, UNBOUND};
use super::{Limit, PlanError, PlannerOptions, SearchStats};

mod bfs;
mod consumed;
mod guard;
mod heuristic;

mod dfs;
mod driver;
mod frames;
mod geo;
mod limits;
mod portfolio;
mod relevance;
mod repair;
mod restarts;

use driver::{fallback_time, repairs_time};
use frames::{ChoiceStack, Frame, GeoFrame, HtnFrame, Key};
use limits::{set_growth, table_growth, vec_growth};
use relevance::{MaskTable, MayAchieve, WILD};
use repair::{Mode, Repair};

const NIL: u32 = u32::MAX;

/// A method's bindings come in pieces, the binder resuming where the last piece stopped, so a
/// search holds at most this many of one method at once, never the whole product of its
/// precondition's joins.
const MAX_CHUNK: usize = 4096;

/// The first piece a depth-first frame takes (most tasks take their first binding, or one of
/// the first few); each next piece is four times larger, up to [`MAX_CHUNK`].
const FIRST_CHUNK: usize = 16;

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

/// An action of the plan so far, with its geometric solution for a GS action.
struct Step {
    occ: u32,
    task: u32,
    geo: Option<GeoStep>,
}

/// A decomposition of the plan so far (a task, its method and its subtasks' ids).
struct TreeRec {
    occ: u32,
    /// Ground task id, or `NIL` for the initial task network.
    task: u32,
    /// The task as the plan names it: `task` with the arguments it left unbound bound by the
    /// method (`compile/late.rs`).
    named: u32,
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

/// Why an engine stopped.
enum Stop {
    Found,
    /// The engine (or phase) used its share of the time: the next one takes over (the
    /// best-first search after the depth-first one, h_add after the state-free estimate).
    Switch,
    Exhausted,
    Limit(Limit),
}

/// The search: the core state every engine works on, and each engine's bookkeeping.
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
    /// The choice points, oldest first; each names its frame in `htn_frames` or `geo_frames`.
    frames: Vec<Frame>,
    htn_frames: ChoiceStack<HtnFrame>,
    geo_frames: ChoiceStack<GeoFrame>,
    visited: HashSet<u128, BuildHasherDefault<FxHasher>>,
    bound: usize,
    cutoff: bool,
    /// Whether a geometric task was asked under a strategy that caps its solutions.
    geo_capped: bool,
    /// The chronological search's round of limited discrepancy (`None`: no rounds, every
    /// geometric solution), and whether the round cut a solution off.
    discrepancy: Option<u32>,
    discrepancy_cut: bool,
    /// Whether the left-recursion check is on (off in the complete fallback search).
    loop_check: bool,
    stats: SearchStats,
    start: Instant,
    /// The time and memory limits, polled at every node and inside precondition joins.
    watch: Watch,
    effects: EffectBuf,
    /// Normal search, or replaying a path for a repair (`repair.rs`).
    mode: Mode,
    /// The choices a replay still has to take, oldest first.
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
    /// The seed of the order of methods and bindings (0: domain and binder order; see
    /// `restarts.rs`).
    shuffle: u64,
    /// The node count at which the current depth-first run stops (a restart's budget).
    run_cap: Option<u64>,
    /// What actions consume of the facts no action adds (`consumed.rs`).
    consumed: Option<consumed::Consumed>,
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
            htn_frames: ChoiceStack::default(),
            geo_frames: ChoiceStack::default(),
            visited: HashSet::default(),
            bound: opts.initial_depth_bound.max(1),
            cutoff: false,
            geo_capped: false,
            discrepancy: opts.discrepancy_rounds.then_some(0),
            discrepancy_cut: false,
            loop_check: opts.loop_check,
            start: Instant::now(),
            watch: Watch::new(
                opts.limits.time.and_then(|t| Instant::now().checked_add(t)),
                opts.limits.memory_mb,
            ),
            effects: EffectBuf::default(),
            mode: Mode::Normal,
            forced: VecDeque::new(),
            repair: None,
            salt,
            may_memo: Vec::new(),
            masks,
            lifted_masks,
            switch_at: fallback_time(c, opts).or_else(|| repairs_time(c, opts)),
            shuffle: 0,
            run_cap: None,
            consumed: consumed::Consumed::build(c),
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
        self.watch
            .set_deadline(self.opts.limits.time.and_then(|l| t.checked_add(l)));
        self
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

    /// Fingerprint of the current state and geometric world.
    fn state_fingerprint(&self) -> u64 {
        let world = self.oracle.as_deref().map_or(0, |o| o.world_fingerprint());
        self.state.hash() ^ mix64(world ^ self.salt)
    }

    /// Whether the problem's goal holds in the current state.
    fn goal_holds(&mut self) -> bool {
        let mut b = vec![UNBOUND; self.c.goal_slot_types.len()];
        let ev = Eval {
            c: self.c,
            s: &self.state,
            types: &self.c.goal_slot_types,
        };
        ev.holds(&self.c.goal, &mut b)
    }

    /// Pushes a cell for ground task `task` (occurrence `occ`, from decomposition `parent`)
    /// on top of network `next`, with the length, hash and goal mask of the network it heads.
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

    /// The methods of ground task `task` in domain order (the root method for `NIL`).
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
        let (flat, count, _) = self.bindings_after(m, task, None, max);
        (flat, count)
    }

    /// At most `max` bindings of method `m`'s parameters for ground task `task`, flat, after
    /// the one of cursor `after` (from the first when `None`), and the cursor to go on from
    /// when more may follow. The join polls the limits: once one is reached it gives what it
    /// has and no cursor (the search then stops at that limit, it does not conclude).
    fn bindings_after(
        &self,
        m: u32,
        task: u32,
        after: Option<&Cursor>,
        max: usize,
    ) -> (Vec<u32>, usize, Option<Cursor>) {
        let c = self.c;
        let method = &c.methods[m as usize];
        let mut b = vec![UNBOUND; method.slot_types.len()];
        if task != NIL && !self.bind_task_args(m, task, &mut b) {
            return (Vec::new(), 0, None);
        }
        let n = method.n_params;
        let mut out = Vec::new();
        let mut count = 0;
        let ev = Eval {
            c,
            s: &self.state,
            types: &method.slot_types,
        };
        let poll = || self.watch.check().is_some();
        let (_, more) = ev.solve_from(&method.pre, &mut b, &method.bind, after, &poll, &mut |bb| {
            out.extend_from_slice(&bb[..n]);
            count += 1;
            count >= max
        });
        (out, count, more)
    }

    /// Binds method `m`'s task parameters to the arguments of ground task `task` in `b`;
    /// `false` when they do not fit (a constant, a type, a repeated parameter). An argument
    /// left unbound (a parameter of the parent method bound late, `compile/late.rs`) binds
    /// nothing: the method's binder binds it.
    fn bind_task_args(&self, m: u32, task: u32, b: &mut [u32]) -> bool {
        let method = &self.c.methods[m as usize];
        let args = &self.gtasks.key(task)[1..];
        if args.len() != method.task_args.len() {
            return false;
        }
        for (t, &a) in method.task_args.iter().zip(args) {
            if a == UNBOUND {
                continue;
            }
            match *t {
                CTerm::Obj(o) if o != a => return false,
                CTerm::Obj(_) => {}
                CTerm::Var(v) => {
                    let cur = b[v as usize];
                    if cur == UNBOUND {
                        if !self.c.is_of(a, method.slot_types[v as usize]) {
                            return false;
                        }
                        b[v as usize] = a;
                    } else if cur != a {
                        return false;
                    }
                }
            }
        }
        true
    }

    /// Ground task `task` as method `m` decomposes it under `binding`: itself, or, when it
    /// has arguments left unbound (`compile/late.rs`), the task with the values the method
    /// bound there (what the plan's decomposition records).
    fn bound_task(&mut self, m: u32, task: u32, binding: &[u32]) -> u32 {
        if task == NIL || !self.gtasks.key(task)[1..].contains(&UNBOUND) {
            return task;
        }
        let method = &self.c.methods[m as usize];
        let mut key = vec![method.task];
        key.extend(bound_terms(&method.task_args, binding));
        self.gtasks.intern(&key)
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

    /// The plan of the current path: its actions and the decomposition tree.
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
            let (task, args) = names(t.named);
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

/// The objects `terms` stand for under `binding` (a slot the binding does not reach: unbound).
fn bound_terms<'b>(terms: &'b [CTerm], binding: &'b [u32]) -> impl Iterator<Item = u32> + 'b {
    terms.iter().map(|t| match *t {
        CTerm::Var(v) => binding.get(v as usize).copied().unwrap_or(UNBOUND),
        CTerm::Obj(o) => o,
    })
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
