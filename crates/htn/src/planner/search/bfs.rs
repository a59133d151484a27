//! The fallback search: weighted A* (best-first) progression over search nodes (state, task
//! network), as in pandaPI's progression search. A node's successors are those of its first
//! task: the action applied, or every method and binding that applies. Each (state, network)
//! pair is generated once (duplicate detection). The heuristic is pandaPI's relaxed
//! composition with h_add (`heuristic.rs`) when its grounding fits its caps (after a first
//! phase with the state-free estimate, [`CHEAP_SHARE`] of the time left); otherwise the
//! network's least number of actions, looking a few levels of decomposition down in the
//! state (the sum over its tasks of the fewest actions any decomposition of the task may end
//! with). A node whose estimate is infinite has no plan below it and is dropped. Ties go to
//! the newest node, so a plateau is searched depth first.
//!
//! It runs only on purely symbolic problems (no geometric back end) and only when the
//! depth-first search used its share of the time limit: there it finds plans the domain-order
//! search gets lost before (learned domains that amount to a blind state-space search).

use std::cmp::Reverse;
use std::collections::BinaryHeap;
use std::collections::HashSet;
use std::hash::BuildHasherDefault;

use crate::state::{FxHasher, FxMap};

use super::super::compile::{CTerm, Compiled};
use super::super::eval::{Eval, UNBOUND};
use super::super::{Limit, current_rss_kb};
use super::heuristic::{Caps, MAX_ACTIONS, MAX_METHODS, Rc};
use super::limits::drop_in_background;
use super::{
    Cell, MAX_CHUNK, NIL, Search, Step, Stop, TreeRec, bound_terms, set_growth, table_growth,
    vec_growth,
};

/// An unreachable cost.
pub(super) const INF: u32 = u32::MAX / 4;

/// Per task, the fewest actions any decomposition may end with, states ignored (`INF` if the
/// task has no decomposition into actions).
pub(super) fn min_costs(c: &Compiled) -> Vec<u32> {
    let mut cost: Vec<u32> = c
        .tasks
        .iter()
        .map(|t| if t.action.is_some() { 1 } else { INF })
        .collect();
    loop {
        let mut changed = false;
        for t in 0..c.tasks.len() {
            if c.tasks[t].action.is_some() {
                continue;
            }
            for &m in &c.tasks[t].methods {
                let sum = c.methods[m as usize]
                    .subtasks
                    .iter()
                    .fold(0u32, |s, (st, _)| (s + cost[*st as usize]).min(INF));
                if sum < cost[t] {
                    cost[t] = sum;
                    changed = true;
                }
            }
        }
        if !changed {
            return cost;
        }
    }
}

/// What led from a node's parent to it.
#[derive(Clone, Copy)]
enum Op {
    /// The initial task network (under a binding of the problem's parameters).
    Root {
        first: u32,
        n: u32,
    },
    Action {
        occ: u32,
        task: u32,
    },
    Method {
        occ: u32,
        task: u32,
        method: u32,
        first: u32,
        n: u32,
    },
}

struct Node {
    parent: u32,
    state: u32,
    /// The network's top cell, or `NIL` when empty.
    tn: u32,
    next_occ: u32,
    /// Actions on the path to the node.
    g: u32,
    op: Op,
}

/// Interned states: the true facts of changing predicates (sorted), then fluent values.
#[derive(Default)]
struct States {
    list: Vec<Box<[u32]>>,
    ids: FxMap<Box<[u32]>, u32>,
}

/// The priority of a node is `G_WEIGHT * actions so far + H_WEIGHT * estimate` (weighted A*
/// over actions: abstract steps cost nothing).
const G_WEIGHT: u32 = 1;
const H_WEIGHT: u32 = 3;
/// The weight of the relaxed-composition estimate (h_add counts actions more than once, so
/// it weighs less than the state-free lower bound).
const RC_H_WEIGHT: u32 = 2;
/// The share of the time left that the grounding of the relaxed composition may take.
const GROUNDING_SHARE: f64 = 0.3;
/// The share of the time left after the grounding that the search with the state-free
/// estimate takes before the one with the relaxed composition.
const CHEAP_SHARE: f64 = 0.25;
/// How many levels of decomposition the heuristic looks at in the current state.
const LOOKAHEAD: u8 = 2;
/// How many bindings of a method the heuristic looks at.
const LOOK_BINDINGS: usize = 4;
/// How many tasks of a network the heuristic estimates in the state (the rest count with
/// their state-free costs).
const LOOK_TASKS: usize = 64;

/// The heuristic's memory: the lifted costs and the estimates per (ground task, state, depth);
/// the relaxed composition when it was ground, and the state it was last evaluated in.
struct Heur {
    cost: Vec<u32>,
    memo: FxMap<(u32, u32, u8), u32>,
    depth: u8,
    k: usize,
    rc: Option<Rc>,
    rc_state: u32,
}

/// The best-first search's open list and the tables behind it: interned states, the nodes
/// (each pointing to its parent), the state-free cost per network cell, the (state, network)
/// pairs generated so far, and the heuristic's memory.
struct Frontier {
    hr: Heur,
    /// The weight of the estimate in a node's priority.
    wh: u32,
    states: States,
    nodes: Vec<Node>,
    cell_cost: Vec<u32>,
    /// (priority, tie-break, node); the tie-break counts down so the newest node comes first.
    open: BinaryHeap<Reverse<(u32, u64, u32)>>,
    seen: HashSet<(u32, u64), BuildHasherDefault<FxHasher>>,
    seq: u64,
    /// The state the search's state holds now.
    cur_state: u32,
    rss: RssCache,
    /// When this search hands over to the next phase (`Stop::Switch`), if it does.
    until: Option<std::time::Instant>,
}

impl Frontier {
    fn push(&mut self, node: Node, priority: u32) {
        self.nodes.push(node);
        self.open
            .push(Reverse((priority, self.seq, self.nodes.len() as u32 - 1)));
        self.seq -= 1;
    }

    /// Bytes the tables are about to allocate (those at capacity double).
    fn growth(&self) -> usize {
        vec_growth::<Node>(self.nodes.len(), self.nodes.capacity())
            + vec_growth::<Reverse<(u32, u64, u32)>>(self.open.len(), self.open.capacity())
            + set_growth(&self.seen)
            + vec_growth::<Box<[u32]>>(self.states.list.len(), self.states.list.capacity())
            + table_growth::<(Box<[u32]>, u32)>(self.states.ids.len(), self.states.ids.capacity())
            + table_growth::<((u32, u32, u8), u32)>(self.hr.memo.len(), self.hr.memo.capacity())
            + vec_growth::<u32>(self.cell_cost.len(), self.cell_cost.capacity())
    }
}

impl<'a, 'o> Search<'a, 'o> {
    /// The fewest actions ground task `gt` may need, looking `depth` levels down in the
    /// current state (state `sid`): a task's estimate is the least, over the methods and
    /// bindings (the first few) that apply now, of its subtasks' estimates one level less;
    /// one more than its state-free cost when none applies now. Depth 0 is state-free.
    fn estimate(&mut self, gt: u32, sid: u32, depth: u8, hr: &mut Heur) -> u32 {
        let t = self.gtasks.key(gt)[0] as usize;
        if depth == 0 || self.c.tasks[t].action.is_some() || hr.cost[t] >= INF {
            return hr.cost[t];
        }
        if let Some(&e) = hr.memo.get(&(gt, sid, depth)) {
            return e;
        }
        let c = self.c;
        let mut best = INF;
        let mut key: Vec<u32> = Vec::with_capacity(8);
        for &m in self.methods_of(gt) {
            let (bindings, count) = self.bindings_upto(m, gt, hr.k);
            let stride = c.methods[m as usize].n_params;
            for i in 0..count {
                let mut sum = 0u32;
                for (st, args) in &c.methods[m as usize].subtasks {
                    key.clear();
                    key.push(*st);
                    key.extend(args.iter().map(|a| match *a {
                        CTerm::Var(v) => {
                            let v = v as usize;
                            if v < stride {
                                bindings[i * stride + v]
                            } else {
                                UNBOUND
                            }
                        }
                        CTerm::Obj(o) => o,
                    }));
                    let sub = self.gtasks.intern(&key);
                    sum = (sum + self.estimate(sub, sid, depth - 1, hr)).min(INF);
                    if sum >= best {
                        break;
                    }
                }
                best = best.min(sum);
            }
        }
        if best >= INF {
            best = (hr.cost[t] + 1).min(INF);
        }
        hr.memo.insert((gt, sid, depth), best);
        best
    }

    /// The heuristic value of network `top` in the current state `sid`.
    fn net_estimate(&mut self, top: u32, sid: u32, hr: &mut Heur, cell_cost: &[u32]) -> u32 {
        if let Some(rc) = hr.rc.as_mut() {
            if hr.rc_state != sid {
                rc.evaluate(&self.state);
                hr.rc_state = sid;
            }
            let mut h = rc.goal_cost();
            let mut cur = top;
            while cur != NIL && h < INF {
                let cell = self.arena[cur as usize];
                h = (h + rc.task_cost(cell.task, self.gtasks.key(cell.task))).min(INF);
                cur = cell.next;
            }
            return h;
        }
        let mut h = 0u32;
        let mut cur = top;
        let mut k = 0;
        while cur != NIL {
            if k == LOOK_TASKS {
                return (h + cell_cost[cur as usize]).min(INF);
            }
            let cell = self.arena[cur as usize];
            h = (h + self.estimate(cell.task, sid, hr.depth, hr)).min(INF);
            cur = cell.next;
            k += 1;
        }
        h
    }

    /// The hash of the task network that starts at cell `top` (0 for the empty network).
    fn network_hash(&self, top: u32) -> u64 {
        if top == NIL {
            0
        } else {
            self.arena[top as usize].hash
        }
    }

    /// The current state as a key of [`States`].
    fn snapshot(&self) -> Vec<u32> {
        let mut v: Vec<u32> = Vec::new();
        for p in 0..self.c.preds.len() as u32 {
            if !self.state.is_static(p) {
                v.extend_from_slice(self.state.facts_of(p));
            }
        }
        v.sort_unstable();
        let values = self.state.values();
        if !values.is_empty() {
            v.push(u32::MAX);
            for x in values {
                let b = x.to_bits();
                v.push((b >> 32) as u32);
                v.push(b as u32);
            }
        }
        v
    }

    /// Makes the state the one `key` describes (from [`Search::snapshot`]).
    fn load(&mut self, key: &[u32]) {
        let n = key.iter().position(|&x| x == u32::MAX).unwrap_or(key.len());
        let (facts, values) = key.split_at(n);
        let mut drop = Vec::new();
        for p in 0..self.c.preds.len() as u32 {
            if !self.state.is_static(p) {
                for &f in self.state.facts_of(p) {
                    if facts.binary_search(&f).is_err() {
                        drop.push(f);
                    }
                }
            }
        }
        for f in drop {
            self.state.delete(f);
        }
        for &f in facts {
            self.state.add(f);
        }
        let stored = values.len().saturating_sub(1) / 2;
        for i in 0..self.state.values().len() {
            let v = if i < stored {
                let (hi, lo) = (values[1 + 2 * i], values[2 + 2 * i]);
                f64::from_bits(((hi as u64) << 32) | lo as u64)
            } else {
                f64::NAN
            };
            self.state.set_value(i as u32, v);
        }
        self.canonical_order();
        self.state.commit();
    }

    /// Puts the true facts in key order: bindings then come in an order that depends on the
    /// state alone, not on the path (nor on how far the depth-first search went before).
    fn canonical_order(&mut self) {
        for p in 0..self.c.preds.len() as u32 {
            if !self.state.is_static(p) {
                self.state.sort_facts_of(p);
            }
        }
    }

    /// The best-first search, until a plan, exhaustion or a limit of the options. With the
    /// relaxed composition ground, a first phase ([`CHEAP_SHARE`] of the time left) runs
    /// with the state-free estimate, which is fast where h_add is slow to compute (Transport's
    /// road networks), then the search starts again with h_add, which domains whose
    /// decompositions must be followed to the end need (AssemblyHierarchical).
    pub(super) fn best_first(&mut self) -> Stop {
        self.stats.best_first = true;
        self.reset();
        self.canonical_order();
        self.state.commit();
        // Each phase starts from this state (the first leaves the state wherever it was).
        let init = self.snapshot();
        let rc = Rc::build(self.c, self.grounding_caps());
        if let Some(rc) = &rc {
            self.stats.rc_actions = rc.n_actions as u64;
            self.stats.rc_methods = rc.n_methods as u64;
        }
        // The fallback runs only under a time limit; without one there is no first phase.
        if let (Some(_), Some(t)) = (&rc, self.opts.limits.time) {
            let left = t.saturating_sub(self.start.elapsed());
            let until = std::time::Instant::now() + left.mul_f64(CHEAP_SHARE);
            match self.best_first_with(&init, None, Some(until)) {
                Stop::Switch => {}
                stop => return stop,
            }
        }
        self.best_first_with(&init, rc, None)
    }

    /// One weighted A* search from state `init` with heuristic `rc` (the state-free estimate
    /// when `None`), handing over at `until`.
    fn best_first_with(
        &mut self,
        init: &[u32],
        rc: Option<Rc>,
        until: Option<std::time::Instant>,
    ) -> Stop {
        self.reset();
        self.load(init);
        let mut f = self.new_frontier(rc, until);
        let stop = self.best_first_over(&mut f);
        match stop {
            // The next phase or engine allocates its own tables: free these first.
            Stop::Switch | Stop::Exhausted => drop(f),
            Stop::Found | Stop::Limit(_) => drop_in_background(f),
        }
        stop
    }

    /// The search of [`Search::best_first_with`] over the open list `f`.
    fn best_first_over(&mut self, f: &mut Frontier) -> Stop {
        self.seed_roots(f);
        while let Some(Reverse((_, _, ni))) = f.open.pop() {
            self.stats.nodes += 1;
            self.stats.best_first_nodes += 1;
            if let Some(stop) = self.bfs_limit(f) {
                return stop;
            }
            let node = &f.nodes[ni as usize];
            let (sid, tn) = (node.state, node.tn);
            if sid != f.cur_state {
                let key = f.states.list[sid as usize].clone();
                self.load(&key);
                f.cur_state = sid;
            }
            if tn == NIL {
                if self.goal_holds() {
                    self.rebuild_path(&f.nodes, ni);
                    return Stop::Found;
                }
                continue;
            }
            let cell = self.arena[tn as usize];
            if !self.goal_reachable(cell.may) {
                self.stats.goal_pruned += 1;
                continue;
            }
            let task = self.gtasks.key(cell.task)[0];
            match self.c.tasks[task as usize].action {
                Some(a) => self.bfs_apply_action(f, ni, cell, a),
                None => self.bfs_decompose(f, ni, cell),
            }
        }
        Stop::Exhausted
    }

    /// Whether the tables about to double (the frontier's and the network cells) fit within
    /// the memory limit, with the resident memory read at most every [`RSS_EVERY`]; if not,
    /// the memory limit is passed. Asked per node and per successor: one node's successors
    /// can double a table of hundreds of MB.
    fn frontier_fits(&mut self, f: &mut Frontier) -> bool {
        let growth = f.growth() + vec_growth::<Cell>(self.arena.len(), self.arena.capacity());
        growth == 0
            || self.opts.limits.memory_mb.is_none()
            || self.watch.fits_at(f.rss.get(), growth as u64)
    }

    /// The open list of a new best-first search with heuristic `rc` (the state-free estimate
    /// when `None`), and the initial state interned.
    fn new_frontier(&mut self, rc: Option<Rc>, until: Option<std::time::Instant>) -> Frontier {
        let c = self.c;
        let wh = if rc.is_some() { RC_H_WEIGHT } else { H_WEIGHT };
        let mut f = Frontier {
            hr: Heur {
                cost: min_costs(c),
                memo: FxMap::default(),
                depth: LOOKAHEAD,
                k: LOOK_BINDINGS,
                rc,
                rc_state: u32::MAX,
            },
            wh,
            states: States::default(),
            nodes: Vec::new(),
            cell_cost: Vec::new(),
            open: BinaryHeap::new(),
            seen: HashSet::default(),
            seq: u64::MAX,
            cur_state: 0,
            rss: RssCache::default(),
            until,
        };
        f.cur_state = intern_state(&mut f.states, self.snapshot());
        f
    }

    /// The initial networks, one per binding of the problem's parameters, as root nodes
    /// (their priority the bare estimate).
    fn seed_roots(&mut self, f: &mut Frontier) {
        let c = self.c;
        let sid0 = f.cur_state;
        let root = c.root_method;
        let (bindings, count) = self.bindings(root, NIL);
        let stride = c.methods[root as usize].n_params;
        for i in 0..count {
            if self.watch.check().is_some() || !self.frontier_fits(f) {
                return;
            }
            let binding = bindings[i * stride..(i + 1) * stride].to_vec();
            let subs = &c.methods[root as usize].subtasks;
            let n = subs.len() as u32;
            let (top, h) = self.push_network(subs, &binding, 0, NIL, 0, f);
            if h >= INF || !f.seen.insert((sid0, self.network_hash(top))) {
                continue;
            }
            let h = self.net_estimate(top, sid0, &mut f.hr, &f.cell_cost);
            if h < INF {
                f.push(
                    Node {
                        parent: NIL,
                        state: sid0,
                        tn: top,
                        next_occ: n,
                        g: 0,
                        op: Op::Root { first: 0, n },
                    },
                    h,
                );
            }
        }
    }

    /// The limit that stops the search now, if any: memory (the tables' coming growth
    /// counted before it happens), time or nodes.
    fn bfs_limit(&mut self, f: &mut Frontier) -> Option<Stop> {
        if !self.frontier_fits(f) {
            return Some(Stop::Limit(Limit::Memory));
        }
        if let Some(l) = self.check_limits() {
            return Some(Stop::Limit(l));
        }
        if f.until.is_some_and(|u| std::time::Instant::now() >= u) {
            return Some(Stop::Switch);
        }
        if self.stats.nodes % 4096 == 0 {
            self.stats.peak_memory_kb = self.stats.peak_memory_kb.max(current_rss_kb());
        }
        None
    }

    /// Node `ni`'s successor by action `a` (its first task), if the action applies.
    fn bfs_apply_action(&mut self, f: &mut Frontier, ni: u32, cell: Cell, a: u32) {
        let c = self.c;
        let (next_occ, g) = (f.nodes[ni as usize].next_occ, f.nodes[ni as usize].g);
        let act = &c.actions[a as usize];
        let Some(mut slots) = self.action_slots(a, cell.task) else {
            return;
        };
        let ev = Eval {
            c,
            s: &self.state,
            types: &act.slot_types,
        };
        if !ev.all_hold(&act.pre, &mut slots) {
            return;
        }
        self.effects.clear();
        if !ev.effects(&act.effects, &mut slots, &mut self.effects) {
            return;
        }
        self.effects.apply(&mut self.state);
        self.canonical_order();
        self.state.commit();
        let sid2 = intern_state(&mut f.states, self.snapshot());
        f.cur_state = sid2;
        if !f.seen.insert((sid2, self.network_hash(cell.next))) {
            self.stats.revisits_pruned += 1;
            return;
        }
        let h = self.net_estimate(cell.next, sid2, &mut f.hr, &f.cell_cost);
        if h >= INF {
            return;
        }
        let node = Node {
            parent: ni,
            state: sid2,
            tn: cell.next,
            next_occ,
            g: g + 1,
            op: Op::Action {
                occ: cell.occ,
                task: cell.task,
            },
        };
        f.push(node, prio(g + 1, h, G_WEIGHT, f.wh));
    }

    /// Node `ni`'s successors by every method and binding of its first task, in domain order.
    fn bfs_decompose(&mut self, f: &mut Frontier, ni: u32, cell: Cell) {
        let c = self.c;
        for &m in self.methods_of(cell.task) {
            let stride = c.methods[m as usize].n_params;
            let mut after = None;
            loop {
                // The bindings in pieces: memory for one piece, not the whole join.
                let (bindings, count, more) =
                    self.bindings_after(m, cell.task, after.as_ref(), MAX_CHUNK);
                for i in 0..count {
                    if self.watch.check().is_some() || !self.frontier_fits(f) {
                        // A node of many successors: the limit stops it midway (the caller
                        // sees the limit at its next node).
                        return;
                    }
                    let binding = &bindings[i * stride..(i + 1) * stride];
                    self.bfs_push_decomposition(f, ni, cell, m, binding);
                }
                match more {
                    Some(cursor) => after = Some(cursor),
                    None => break,
                }
            }
        }
    }

    /// The successor of node `ni` that decomposes its first task `cell` by method `m` under
    /// `binding`, pushed unless it is a dead end or seen.
    fn bfs_push_decomposition(
        &mut self,
        f: &mut Frontier,
        ni: u32,
        cell: Cell,
        m: u32,
        binding: &[u32],
    ) {
        let node = &f.nodes[ni as usize];
        let (sid, next_occ, g) = (node.state, node.next_occ, node.g);
        let rest_cost = if cell.next == NIL {
            0
        } else {
            f.cell_cost[cell.next as usize]
        };
        let c = self.c;
        let subs = &c.methods[m as usize].subtasks;
        let n = subs.len() as u32;
        let (top, h) = self.push_network(subs, binding, next_occ, cell.next, rest_cost, f);
        if h >= INF {
            return;
        }
        if !f.seen.insert((sid, self.network_hash(top))) {
            self.stats.revisits_pruned += 1;
            return;
        }
        let h = self.net_estimate(top, sid, &mut f.hr, &f.cell_cost);
        if h >= INF {
            return;
        }
        let task = self.bound_task(m, cell.task, binding);
        let node = Node {
            parent: ni,
            state: sid,
            tn: top,
            next_occ: next_occ + n,
            g,
            op: Op::Method {
                occ: cell.occ,
                task,
                method: m,
                first: next_occ,
                n,
            },
        };
        f.push(node, prio(g, h, G_WEIGHT, f.wh));
    }

    /// What the grounding of the relaxed composition may spend: its caps, a share of the
    /// time left and the memory limit.
    fn grounding_caps(&self) -> Caps {
        let l = self.opts.limits;
        let deadline = l.time.map(|t| {
            let left = t.saturating_sub(self.start.elapsed());
            std::time::Instant::now() + left.mul_f64(GROUNDING_SHARE)
        });
        Caps {
            actions: MAX_ACTIONS,
            methods: MAX_METHODS,
            deadline,
            memory_kb: self.watch.memory_mb().map(|mb| mb.saturating_mul(1024)),
        }
    }

    /// Pushes `subs` under `binding` on top of network `next` (whose cost is `rest`), with
    /// occurrence ids from `first`; returns the top cell and the network's cost (the
    /// state-free costs of its tasks, kept per cell in the frontier).
    fn push_network(
        &mut self,
        subs: &[(u32, Vec<CTerm>)],
        binding: &[u32],
        first: u32,
        next: u32,
        rest: u32,
        f: &mut Frontier,
    ) -> (u32, u32) {
        let (cost, cell_cost) = (&f.hr.cost, &mut f.cell_cost);
        let mut top = next;
        let mut h = rest;
        let mut key: Vec<u32> = Vec::with_capacity(8);
        for (i, (t, args)) in subs.iter().enumerate().rev() {
            h = (h + cost[*t as usize]).min(INF);
            if h >= INF {
                return (top, INF);
            }
            key.clear();
            key.push(*t);
            key.extend(bound_terms(args, binding));
            let gt = self.gtasks.intern(&key);
            top = self.push_cell(gt, first + i as u32, top, NIL);
            if cell_cost.len() < self.arena.len() {
                cell_cost.resize(self.arena.len(), 0);
            }
            cell_cost[top as usize] = h;
        }
        (top, h)
    }

    /// Fills the plan's steps and decomposition tree from the path to node `ni`.
    fn rebuild_path(&mut self, nodes: &[Node], ni: u32) {
        let mut path = Vec::new();
        let mut i = ni;
        while i != NIL {
            path.push(nodes[i as usize].op);
            i = nodes[i as usize].parent;
        }
        path.reverse();
        self.steps.clear();
        self.tree.clear();
        for op in path {
            match op {
                Op::Root { first, n } => self.tree.push(TreeRec {
                    occ: NIL,
                    task: NIL,
                    named: NIL,
                    method: self.c.root_method,
                    first,
                    n,
                    parent: NIL,
                    steps: 0,
                    state: 0,
                }),
                Op::Action { occ, task } => self.steps.push(Step {
                    occ,
                    task,
                    geo: None,
                }),
                Op::Method {
                    occ,
                    task,
                    method,
                    first,
                    n,
                } => self.tree.push(TreeRec {
                    occ,
                    task,
                    named: task,
                    method,
                    first,
                    n,
                    parent: NIL,
                    steps: 0,
                    state: 0,
                }),
            }
        }
    }
}

/// The resident memory, read from /proc at most every [`RSS_EVERY`]: small tables are
/// "about to double" at almost every node, and a read of /proc per node showed in profiles.
#[derive(Default)]
struct RssCache {
    kb: u64,
    at: Option<std::time::Instant>,
}

/// How long a reading of the resident memory is used.
const RSS_EVERY: std::time::Duration = std::time::Duration::from_millis(10);

impl RssCache {
    fn get(&mut self) -> u64 {
        let now = std::time::Instant::now();
        if self.at.is_none_or(|t| now.duration_since(t) >= RSS_EVERY) {
            self.kb = current_rss_kb();
            self.at = Some(now);
        }
        self.kb
    }
}

fn prio(g: u32, h: u32, wg: u32, wh: u32) -> u32 {
    if h >= INF {
        return INF;
    }
    (g.saturating_mul(wg))
        .saturating_add(h.saturating_mul(wh))
        .min(INF - 1)
}

fn intern_state(states: &mut States, key: Vec<u32>) -> u32 {
    if let Some(&id) = states.ids.get(key.as_slice()) {
        return id;
    }
    let id = states.list.len() as u32;
    let b: Box<[u32]> = key.into();
    states.list.push(b.clone());
    states.ids.insert(b, id);
    id
}
