//! The relaxed-composition (RC) heuristic of pandaPI (Höller, Bercher, Behnke and Biundo,
//! "On Guiding Search in HTN Planning with Classical Planning Heuristics", IJCAI 2019), with
//! h_add over it, for the best-first search (`bfs.rs`).
//!
//! The HTN problem is ground to a delete-relaxed STRIPS model in which a ground task is a
//! fact too: an action's operator needs its (positive, relaxed) precondition and makes its add
//! effects and its own task fact true; a method's operator needs its method precondition and
//! the facts of all its subtasks and makes its task's fact true. A task fact is thus "reached"
//! when some decomposition of the task could be executed in the relaxed model. The estimate of
//! a search node (state, task network) is the h_add cost (actions cost 1, methods 0) of the
//! facts of every task in the network and of the goal facts that are false.
//!
//! The grounding over-approximates every ground action and method that can ever apply, with
//! the binder of `eval.rs` over the facts reached so far: first the actions, to a relaxed
//! reachability fixpoint from the initial state (negative and numeric conditions dropped,
//! conditional effects counted as unconditional); then the methods, top down from the
//! initial task network, of every task some ground method (relaxed precondition) may lead
//! to; last, the operators that cannot apply in the relaxation from the initial state are
//! dropped (pandaPI's pruning). So a task the model lacks, or whose fact cannot be reached
//! from a state, has no decomposition executable from it, and an infinite estimate is a
//! sound dead end: the heuristic never makes the search incomplete.
//!
//! The grounding stops, and the search keeps its state-free heuristic, when it passes
//! [`MAX_ACTIONS`] ground actions, [`MAX_METHODS`] ground methods, its deadline or the memory
//! limit, so that it never spends what the search needs.

use std::cmp::Reverse;
use std::collections::{BinaryHeap, HashSet};
use std::hash::BuildHasherDefault;
use std::time::Instant;

use crate::state::{FxHasher, State};

use super::super::compile::{CEffect, CFormula, CLit, CTerm, Compiled};
use super::super::current_rss_kb;
use super::super::eval::{Enumerated, Eval, UNBOUND};
use super::bfs::INF;

/// The most ground actions the grounding makes before it gives up.
pub(super) const MAX_ACTIONS: usize = 50_000;
/// The most ground methods the grounding makes before it gives up.
pub(super) const MAX_METHODS: usize = 200_000;

/// A search fact or task not mapped yet.
const UNMAPPED: u32 = u32::MAX;
/// A search fact or task with no relaxed fact (a static fact, or a task key with an unbound
/// argument).
const NONE: u32 = u32::MAX - 1;
/// A search task whose relaxed fact was never reached by the grounding: no decomposition of
/// it can ever be executed.
const UNREACHABLE: u32 = u32::MAX - 2;

/// What the grounding may spend.
#[derive(Clone, Copy, Debug)]
pub(super) struct Caps {
    pub actions: usize,
    pub methods: usize,
    pub deadline: Option<Instant>,
    pub memory_kb: Option<u64>,
}

impl Caps {
    /// Whether the deadline has passed or the resident memory is over its cap (asked every few
    /// hundred grounding steps and every few thousand join steps: reading the memory costs a
    /// few microseconds).
    fn spent(&self) -> bool {
        self.deadline.is_some_and(|d| Instant::now() >= d)
            || crate::budget::stopped()
            || self.memory_kb.is_some_and(|kb| current_rss_kb() > kb)
    }
}

/// The ground relaxed model and the scratch space of its h_add evaluation.
pub(super) struct Rc {
    n_preds: u32,
    /// Relaxed facts: `[pred, args..]` for predicates, `[n_preds + task, args..]` for tasks.
    facts: crate::state::Interner,
    static_preds: Vec<bool>,
    /// Per operator: its cost (1 an action, 0 a method), where its preconditions start in
    /// `need`'s count (`pre_start`) and its effects (a range of `eff`).
    op_cost: Vec<u32>,
    pre_start: Vec<u32>,
    eff_start: Vec<u32>,
    eff: Vec<u32>,
    /// Per fact, the operators that need it (a range of `need`).
    need_start: Vec<u32>,
    need: Vec<u32>,
    /// Operators with no precondition that a state can make false.
    free_ops: Vec<u32>,
    /// The positive goal facts (relaxed ids; `UNREACHABLE` for one never reached).
    goal: Vec<u32>,
    /// Ground actions and methods made.
    pub n_actions: usize,
    pub n_methods: usize,
    /// Per search fact id / search task id, its relaxed fact (lazily filled).
    fact_map: Vec<u32>,
    task_map: Vec<u32>,
    /// The evaluation: fact costs in the last state, per operator the preconditions not yet
    /// reached and the sum of their costs.
    cost: Vec<u32>,
    done: Vec<bool>,
    left: Vec<u32>,
    acc: Vec<u32>,
    heap: BinaryHeap<Reverse<(u32, u32)>>,
    goal_cost: u32,
}

type Seen = HashSet<Box<[u32]>, BuildHasherDefault<FxHasher>>;

/// The grounding under way.
struct Grounder<'a> {
    c: &'a Compiled,
    caps: Caps,
    rs: State,
    seen: Seen,
    action_task: Vec<u32>,
    /// Relaxed preconditions per action and method (positive atoms and equalities).
    action_lits: Vec<Vec<CLit>>,
    method_lits: Vec<Vec<CLit>>,
    op_cost: Vec<u32>,
    op_pre: Vec<Vec<u32>>,
    op_eff: Vec<Vec<u32>>,
    n_actions: usize,
    n_methods: usize,
    checks: u32,
    over: bool,
    /// Per relaxed fact, whether it is a requested task (see [`Grounder::methods`]).
    requested: Vec<bool>,
}

/// The literals of a precondition the relaxation keeps: positive atoms and equalities.
fn relaxed(pre: &[CLit]) -> Vec<CLit> {
    pre.iter()
        .filter(|l| matches!(l.f, CFormula::Atom(..) | CFormula::Eq(..)))
        .cloned()
        .collect()
}

fn ground_key(head: u32, args: &[CTerm], b: &[u32]) -> Option<Vec<u32>> {
    let mut key = Vec::with_capacity(args.len() + 1);
    key.push(head);
    for a in args {
        let o = match *a {
            CTerm::Var(v) => b.get(v as usize).copied().unwrap_or(UNBOUND),
            CTerm::Obj(o) => o,
        };
        if o == UNBOUND {
            return None;
        }
        key.push(o);
    }
    Some(key)
}

/// Which operators apply in the relaxation from the facts `init` (by a breadth-first
/// fixpoint over precondition counters).
fn live_ops(n_facts: usize, pre: &[Vec<u32>], eff: &[Vec<u32>], init: &[u32]) -> Vec<bool> {
    let mut need: Vec<Vec<u32>> = vec![Vec::new(); n_facts];
    let mut left: Vec<usize> = pre.iter().map(Vec::len).collect();
    let mut live = vec![false; pre.len()];
    let mut reached = vec![false; n_facts];
    let mut queue: Vec<u32> = Vec::new();
    for (o, p) in pre.iter().enumerate() {
        for &f in p {
            need[f as usize].push(o as u32);
        }
    }
    let mut fire = |o: usize, reached: &mut Vec<bool>, queue: &mut Vec<u32>| {
        live[o] = true;
        for &f in &eff[o] {
            if !reached[f as usize] {
                reached[f as usize] = true;
                queue.push(f);
            }
        }
    };
    for &f in init {
        if !reached[f as usize] {
            reached[f as usize] = true;
            queue.push(f);
        }
    }
    for (o, p) in pre.iter().enumerate() {
        if p.is_empty() {
            fire(o, &mut reached, &mut queue);
        }
    }
    while let Some(f) = queue.pop() {
        for &o in &need[f as usize] {
            let o = o as usize;
            left[o] -= 1;
            if left[o] == 0 {
                fire(o, &mut reached, &mut queue);
            }
        }
    }
    live
}

/// Binds the slots of `method`'s task arguments to `args`; false when they do not fit (an
/// object of another type, a constant or repeated variable that differs).
fn bind_head(
    c: &Compiled,
    method: &super::super::compile::CMethod,
    args: &[u32],
    b: &mut [u32],
) -> bool {
    if args.len() != method.task_args.len() {
        return false;
    }
    for (t, &a) in method.task_args.iter().zip(args) {
        match *t {
            CTerm::Obj(o) => {
                if o != a {
                    return false;
                }
            }
            CTerm::Var(v) => {
                let cur = b[v as usize];
                if cur == UNBOUND {
                    if !c.is_of(a, method.slot_types[v as usize]) {
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

impl Grounder<'_> {
    /// Whether a cap is passed (the clock and memory are read every 256 calls).
    fn over_caps(&mut self) -> bool {
        if self.over {
            return true;
        }
        if self.n_actions > self.caps.actions || self.n_methods > self.caps.methods {
            self.over = true;
            return true;
        }
        self.checks = self.checks.wrapping_add(1);
        if self.checks % 256 == 0 && self.caps.spent() {
            self.over = true;
        }
        self.over
    }

    /// Makes a relaxed fact true; returns its id.
    fn reach(&mut self, key: &[u32]) -> u32 {
        let id = self.rs.intern_fact(key);
        self.rs.add(id);
        id
    }

    /// The add effects of an action under binding `b` (quantified effects over every object
    /// of their types, conditional ones regardless of the condition).
    fn adds(&self, effs: &[CEffect], b: &mut [u32], out: &mut Vec<Vec<u32>>) {
        for e in effs {
            match e {
                CEffect::Add(p, args) => {
                    if let Some(k) = ground_key(*p, args, b) {
                        out.push(k);
                    }
                }
                CEffect::Del(..) | CEffect::Num(..) => {}
                CEffect::When(_, inner) => self.adds(inner, b, out),
                CEffect::Forall(vs, inner) => self.forall_adds(vs, inner, b, out),
            }
        }
    }

    fn forall_adds(
        &self,
        vs: &[(u16, u32)],
        inner: &[CEffect],
        b: &mut [u32],
        out: &mut Vec<Vec<u32>>,
    ) {
        let Some(&(slot, ty)) = vs.first() else {
            self.adds(inner, b, out);
            return;
        };
        if slot as usize >= b.len() {
            return;
        }
        for &o in &self.c.type_objects[ty as usize] {
            b[slot as usize] = o;
            self.forall_adds(&vs[1..], inner, b, out);
        }
        b[slot as usize] = UNBOUND;
    }

    /// The bindings of `need` that satisfy `lits` over the facts reached so far.
    /// (`init`, when not empty, binds some slots first.)
    fn bindings(
        &mut self,
        lits: &[CLit],
        types: &[u32],
        need: &[u16],
        init: &[u32],
    ) -> Vec<Vec<u32>> {
        let mut found: Vec<Vec<u32>> = Vec::new();
        let mut b = if init.is_empty() {
            vec![UNBOUND; types.len()]
        } else {
            init.to_vec()
        };
        let mut stop = false;
        {
            let ev = Eval {
                c: self.c,
                s: &self.rs,
                types,
            };
            let caps = self.caps;
            // The join polls the deadline and the memory cap itself.
            let poll = || caps.spent();
            let (how, _) = ev.solve_from(lits, &mut b, need, None, &poll, &mut |b| {
                found.push(b.to_vec());
                stop = found.len() > caps.methods;
                stop
            });
            stop |= how == Enumerated::Aborted;
        }
        if stop {
            self.over = true;
        }
        found
    }

    /// One round over every action; whether it made a new ground action.
    fn round(&mut self) -> bool {
        let c = self.c;
        let np = c.preds.len() as u32;
        let mut new = false;
        for (a, act) in c.actions.iter().enumerate() {
            if self.over_caps() {
                return false;
            }
            let need: Vec<u16> = (0..act.n_params as u16).collect();
            let lits = std::mem::take(&mut self.action_lits[a]);
            let found = self.bindings(&lits, &act.slot_types, &need, &[]);
            for mut b in found {
                let mut key = Vec::with_capacity(act.n_params + 1);
                key.push(a as u32);
                key.extend_from_slice(&b[..act.n_params]);
                if !self.seen.insert(key.into()) {
                    continue;
                }
                new = true;
                self.n_actions += 1;
                let pre = self.pre_facts(&lits, &b);
                let mut adds = Vec::new();
                self.adds(&act.effects, &mut b, &mut adds);
                let eff = adds.iter().map(|k| self.reach(k)).collect();
                let mut task = vec![np + self.action_task[a]];
                task.extend_from_slice(&b[..act.n_params]);
                let mut eff: Vec<u32> = eff;
                eff.push(self.rs.intern_fact(&task));
                self.op_cost.push(1);
                self.op_pre.push(pre);
                self.op_eff.push(eff);
                if self.over_caps() {
                    break;
                }
            }
            self.action_lits[a] = lits;
        }
        self.rs.commit();
        new && !self.over
    }

    /// Marks ground task `key` (`[n_preds + task, args..]`) requested: its methods are ground
    /// when it is taken from the work list. Returns its relaxed fact.
    fn request(&mut self, key: &[u32], todo: &mut Vec<u32>) -> u32 {
        let id = self.rs.intern_fact(key);
        if id as usize >= self.requested.len() {
            self.requested.resize(id as usize + 1, false);
        }
        if !self.requested[id as usize] {
            self.requested[id as usize] = true;
            todo.push(id);
        }
        id
    }

    /// Grounds, top down from the initial task network, the methods of every task that some
    /// ground method whose relaxed precondition holds may lead to: every task of a task
    /// network the search can reach is among them.
    fn methods(&mut self) {
        let c = self.c;
        let np = c.preds.len() as u32;
        let mut todo: Vec<u32> = Vec::new();
        let root = &c.methods[c.root_method as usize];
        let lits = relaxed(&root.pre);
        for b in self.bindings(&lits, &root.slot_types, &root.params, &[]) {
            for (st, args) in &root.subtasks {
                if let Some(k) = ground_key(np + st, args, &b) {
                    self.request(&k, &mut todo);
                }
            }
        }
        let mut next = 0;
        while next < todo.len() {
            if self.over_caps() {
                return;
            }
            let head = todo[next];
            next += 1;
            let key: Vec<u32> = self.rs.facts.key(head).to_vec();
            let t = (key[0] - np) as usize;
            for &m in &c.tasks[t].methods {
                let method = &c.methods[m as usize];
                let mut b = vec![UNBOUND; method.slot_types.len()];
                if !bind_head(c, method, &key[1..], &mut b) {
                    continue;
                }
                let lits = std::mem::take(&mut self.method_lits[m as usize]);
                let found = self.bindings(&lits, &method.slot_types, &method.params, &b);
                for b in found {
                    self.n_methods += 1;
                    let mut pre = self.pre_facts(&lits, &b);
                    for (st, args) in &method.subtasks {
                        if let Some(k) = ground_key(np + st, args, &b) {
                            pre.push(self.request(&k, &mut todo));
                        }
                    }
                    self.op_cost.push(0);
                    self.op_pre.push(pre);
                    self.op_eff.push(vec![head]);
                    if self.over_caps() {
                        break;
                    }
                }
                self.method_lits[m as usize] = lits;
            }
        }
    }

    /// The relaxed facts of the atoms of `lits` under `b` that a state can make false.
    fn pre_facts(&mut self, lits: &[CLit], b: &[u32]) -> Vec<u32> {
        let mut out = Vec::new();
        for l in lits {
            if let CFormula::Atom(p, args) = &l.f {
                if self
                    .c
                    .static_preds
                    .get(*p as usize)
                    .copied()
                    .unwrap_or(false)
                {
                    continue;
                }
                if let Some(k) = ground_key(*p, args, b) {
                    out.push(self.rs.intern_fact(&k));
                }
            }
        }
        out
    }
}

impl Rc {
    /// Grounds the relaxed model of `c`; `None` when a cap stopped it.
    pub(super) fn build(c: &Compiled, caps: Caps) -> Option<Rc> {
        let np = c.preds.len();
        let nt = c.tasks.len();
        let mut rs = State::new(np + nt, 0);
        for (p, args) in &c.init_facts {
            let mut key = vec![*p];
            key.extend_from_slice(args);
            let id = rs.intern_fact(&key);
            rs.add(id);
        }
        rs.commit();
        let mut is_static = c.static_preds.clone();
        is_static.resize(np + nt, false);
        rs.index_static(&is_static);
        let mut action_task = vec![0u32; c.actions.len()];
        for (t, task) in c.tasks.iter().enumerate() {
            if let Some(a) = task.action {
                action_task[a as usize] = t as u32;
            }
        }
        let action_lits = c.actions.iter().map(|a| relaxed(&a.pre)).collect();
        let method_lits = c.methods.iter().map(|m| relaxed(&m.pre)).collect();
        let mut g = Grounder {
            c,
            caps,
            rs,
            seen: Seen::default(),
            action_task,
            action_lits,
            method_lits,
            op_cost: Vec::new(),
            op_pre: Vec::new(),
            op_eff: Vec::new(),
            n_actions: 0,
            n_methods: 0,
            checks: 0,
            over: false,
            requested: Vec::new(),
        };
        while g.round() {}
        if !g.over {
            g.methods();
        }
        if g.over || g.over_caps() {
            return None;
        }
        let n_facts = g.rs.facts.len();
        // Operators that cannot apply in the relaxation from the initial state cannot apply
        // from any state the search reaches: drop them (the h_add of every state is the same
        // without them, and cheaper).
        let init: Vec<u32> = c
            .init_facts
            .iter()
            .filter_map(|(p, args)| {
                let mut key = vec![*p];
                key.extend_from_slice(args);
                g.rs.facts.get(&key)
            })
            .collect();
        let live = live_ops(n_facts, &g.op_pre, &g.op_eff, &init);
        let mut k = 0;
        g.op_cost.retain(|_| {
            k += 1;
            live[k - 1]
        });
        let mut k = 0;
        g.op_pre.retain(|_| {
            k += 1;
            live[k - 1]
        });
        let mut k = 0;
        g.op_eff.retain(|_| {
            k += 1;
            live[k - 1]
        });
        g.n_actions = g.op_cost.iter().filter(|&&c| c == 1).count();
        g.n_methods = g.op_cost.len() - g.n_actions;
        let n_ops = g.op_cost.len();
        let mut pre_start = Vec::with_capacity(n_ops + 1);
        let mut eff_start = Vec::with_capacity(n_ops + 1);
        let (mut pre, mut eff) = (Vec::new(), Vec::new());
        let mut need_count = vec![0u32; n_facts + 1];
        let mut free_ops = Vec::new();
        for o in 0..n_ops {
            pre_start.push(pre.len() as u32);
            eff_start.push(eff.len() as u32);
            pre.extend_from_slice(&g.op_pre[o]);
            eff.extend_from_slice(&g.op_eff[o]);
            for &f in &g.op_pre[o] {
                need_count[f as usize] += 1;
            }
            if g.op_pre[o].is_empty() {
                free_ops.push(o as u32);
            }
        }
        pre_start.push(pre.len() as u32);
        eff_start.push(eff.len() as u32);
        let mut need_start = vec![0u32; n_facts + 1];
        for f in 0..n_facts {
            need_start[f + 1] = need_start[f] + need_count[f];
        }
        let mut fill = need_start.clone();
        let mut need = vec![0u32; pre.len()];
        for o in 0..n_ops {
            for &f in &g.op_pre[o] {
                need[fill[f as usize] as usize] = o as u32;
                fill[f as usize] += 1;
            }
        }
        let goal = c
            .goal_lits
            .iter()
            .zip(&c.goal_parent)
            .filter(|((key, positive), parent)| {
                *positive
                    && parent.is_empty()
                    && !c
                        .static_preds
                        .get(key[0] as usize)
                        .copied()
                        .unwrap_or(false)
            })
            .map(|((key, _), _)| g.rs.facts.get(key).unwrap_or(UNREACHABLE))
            .collect();
        Some(Rc {
            n_preds: np as u32,
            facts: g.rs.facts,
            static_preds: c.static_preds.clone(),
            op_cost: g.op_cost,
            pre_start,
            eff_start,
            eff,
            need_start,
            need,
            free_ops,
            goal,
            n_actions: g.n_actions,
            n_methods: g.n_methods,
            fact_map: Vec::new(),
            task_map: Vec::new(),
            cost: vec![INF; n_facts],
            done: vec![false; n_facts],
            left: vec![0; n_ops],
            acc: vec![0; n_ops],
            heap: BinaryHeap::new(),
            goal_cost: 0,
        })
    }

    /// The relaxed fact of search fact `id` (key `key`).
    fn map_fact(&mut self, id: u32, key: &[u32]) -> u32 {
        let i = id as usize;
        if i >= self.fact_map.len() {
            self.fact_map.resize(i + 1, UNMAPPED);
        }
        if self.fact_map[i] == UNMAPPED {
            self.fact_map[i] = if self
                .static_preds
                .get(key[0] as usize)
                .copied()
                .unwrap_or(false)
            {
                NONE
            } else {
                self.facts.get(key).unwrap_or(NONE)
            };
        }
        self.fact_map[i]
    }

    /// Computes the h_add cost of every relaxed fact from the state `s` (of the search, whose
    /// facts are interned in `s.facts`; search fact ids are mapped once, so every state
    /// given must intern facts alike, as the search's one state does).
    pub(super) fn evaluate(&mut self, s: &State) {
        self.cost.fill(INF);
        self.done.fill(false);
        self.acc.fill(0);
        for o in 0..self.left.len() {
            self.left[o] = self.pre_start[o + 1] - self.pre_start[o];
        }
        self.heap.clear();
        for p in 0..self.n_preds {
            if self.static_preds.get(p as usize).copied().unwrap_or(false) {
                continue;
            }
            for &f in s.facts_of(p) {
                let r = self.map_fact(f, s.facts.key(f));
                if r < NONE && self.cost[r as usize] != 0 {
                    self.cost[r as usize] = 0;
                    self.heap.push(Reverse((0, r)));
                }
            }
        }
        for i in 0..self.free_ops.len() {
            let o = self.free_ops[i];
            self.fire(o, self.op_cost[o as usize]);
        }
        while let Some(Reverse((c, f))) = self.heap.pop() {
            let fi = f as usize;
            if self.done[fi] || c > self.cost[fi] {
                continue;
            }
            self.done[fi] = true;
            let (s, e) = (self.need_start[fi], self.need_start[fi + 1]);
            for k in s..e {
                let o = self.need[k as usize] as usize;
                self.acc[o] = (self.acc[o] + c).min(INF);
                self.left[o] -= 1;
                if self.left[o] == 0 {
                    let v = (self.acc[o] + self.op_cost[o]).min(INF);
                    self.fire(o as u32, v);
                }
            }
        }
        let mut g = 0u32;
        for &f in &self.goal {
            g = (g + if f == UNREACHABLE {
                INF
            } else {
                self.cost[f as usize]
            })
            .min(INF);
        }
        self.goal_cost = g;
    }

    fn fire(&mut self, o: u32, v: u32) {
        if v >= INF {
            return;
        }
        let (s, e) = (self.eff_start[o as usize], self.eff_start[o as usize + 1]);
        for k in s..e {
            let f = self.eff[k as usize] as usize;
            if v < self.cost[f] {
                self.cost[f] = v;
                self.heap.push(Reverse((v, f as u32)));
            }
        }
    }

    /// The cost of the false goal facts in the last evaluated state.
    pub(super) fn goal_cost(&self) -> u32 {
        self.goal_cost
    }

    /// The cost of search task `gt` (key `[task, args..]`) in the last evaluated state: `INF`
    /// when no decomposition of it can be executed from there; 0 for a key the model cannot
    /// name (an unbound argument), which stays sound.
    pub(super) fn task_cost(&mut self, gt: u32, key: &[u32]) -> u32 {
        let i = gt as usize;
        if i >= self.task_map.len() {
            self.task_map.resize(i + 1, UNMAPPED);
        }
        if self.task_map[i] == UNMAPPED {
            self.task_map[i] = if key[1..].contains(&UNBOUND) {
                NONE
            } else {
                let mut k = key.to_vec();
                k[0] += self.n_preds;
                self.facts.get(&k).unwrap_or(UNREACHABLE)
            };
        }
        match self.task_map[i] {
            NONE => 0,
            UNREACHABLE => INF,
            r => self.cost[r as usize],
        }
    }
}

#[cfg(test)]
mod tests {
    use std::path::PathBuf;
    use std::sync::Arc;

    use super::*;
    use crate::budget::Watch;
    use crate::planner::compile::compile;

    /// A line of places a-b-c (d apart); `goto` reaches a place by `move`s along links.
    const DOMAIN: &str = "(define (domain line)
      (:requirements :typing :hierarchy :negative-preconditions)
      (:types place)
      (:predicates (at ?p - place) (link ?a ?b - place))
      (:task goto :parameters (?to - place))
      (:method arrived :parameters (?to - place) :task (goto ?to)
        :precondition (at ?to) :ordered-subtasks ())
      (:method step :parameters (?to ?from ?mid - place) :task (goto ?to)
        :precondition (and (at ?from) (link ?from ?mid) (not (at ?to)))
        :ordered-subtasks (and (move ?from ?mid) (goto ?to)))
      (:action move :parameters (?a ?b - place)
        :precondition (and (at ?a) (link ?a ?b))
        :effect (and (not (at ?a)) (at ?b))))";
    const PROBLEM: &str = "(define (problem p) (:domain line)
      (:objects a b c d - place)
      (:htn :ordered-subtasks (goto c))
      (:init (at a) (link a b) (link b c))
      (:goal (at c)))";

    fn model() -> (Compiled, Rc) {
        let src = Arc::new(PathBuf::from("line.hddl"));
        let d = crate::parse_domain(DOMAIN, src.clone()).unwrap();
        let p = crate::parse_problem(PROBLEM, src, &d).unwrap();
        let c = compile(&d, &p, &mut Watch::new(None, None)).unwrap();
        let caps = Caps {
            actions: MAX_ACTIONS,
            methods: MAX_METHODS,
            deadline: None,
            memory_kb: None,
        };
        let rc = Rc::build(&c, caps).expect("a tiny model fits the caps");
        (c, rc)
    }

    /// The search state with exactly the given `at` facts and the static links.
    fn state(c: &Compiled, at: &[&str]) -> State {
        let mut s = State::new(c.preds.len(), 0);
        for (p, args) in &c.init_facts {
            if c.static_preds[*p as usize] {
                let mut key = vec![*p];
                key.extend_from_slice(args);
                let id = s.intern_fact(&key);
                s.add(id);
            }
        }
        // Every state interns the facts in the same order, as the search's one state does
        // (the model maps search fact ids once).
        for place in ["a", "b", "c", "d"] {
            let key = [c.pred_ids["at"], c.object_ids[place]];
            let id = s.intern_fact(&key);
            if at.contains(&place) {
                s.add(id);
            }
        }
        s.commit();
        s
    }

    fn goto(c: &Compiled, place: &str) -> [u32; 2] {
        [c.task_ids["goto"], c.object_ids[place]]
    }

    #[test]
    fn the_grounding_keeps_what_the_relaxation_reaches() {
        let (_, rc) = model();
        // move(a,b) and move(b,c); nothing moves from c or to d.
        assert_eq!(rc.n_actions, 2);
        // Only goto(c) is requested (the initial network): arrived(c), step(c, a, b) and
        // step(c, b, c) (the negative precondition is relaxed away).
        assert_eq!(rc.n_methods, 3);
    }

    #[test]
    fn h_add_over_the_relaxed_composition() {
        let (c, mut rc) = model();
        let s = state(&c, &["a"]);
        rc.evaluate(&s);
        // (at c) takes move(a,b) (1) then move(b,c) (1 + cost of (at b)) = 2.
        assert_eq!(rc.goal_cost(), 2);
        let tasks: Vec<u32> = ["a", "b", "c", "d"]
            .iter()
            .enumerate()
            .map(|(i, p)| rc.task_cost(i as u32, &goto(&c, p)))
            .collect();
        assert_eq!(
            tasks,
            [INF, INF, 2, INF],
            "only goto c is in a network the search can reach"
        );
        let mv = [c.task_ids["move"], c.object_ids["b"], c.object_ids["c"]];
        assert_eq!(rc.task_cost(4, &mv), 2, "move(b,c) needs (at b): 1 + 1");
        // From (at b), goto c takes one action and move(a,b) is a dead end (no link back).
        let s = state(&c, &["b"]);
        rc.evaluate(&s);
        assert_eq!(rc.goal_cost(), 1);
        assert_eq!(rc.task_cost(2, &goto(&c, "c")), 1);
        let back = [c.task_ids["move"], c.object_ids["a"], c.object_ids["b"]];
        assert_eq!(rc.task_cost(5, &back), INF);
        // A goal that holds costs nothing.
        let s = state(&c, &["c"]);
        rc.evaluate(&s);
        assert_eq!(rc.goal_cost(), 0);
        assert_eq!(rc.task_cost(2, &goto(&c, "c")), 0);
    }

    #[test]
    fn the_grounding_stops_at_its_caps() {
        let src = Arc::new(PathBuf::from("line.hddl"));
        let d = crate::parse_domain(DOMAIN, src.clone()).unwrap();
        let p = crate::parse_problem(PROBLEM, src, &d).unwrap();
        let c = compile(&d, &p, &mut Watch::new(None, None)).unwrap();
        let caps = Caps {
            actions: 1,
            methods: MAX_METHODS,
            deadline: None,
            memory_kb: None,
        };
        assert!(
            Rc::build(&c, caps).is_none(),
            "two actions pass a cap of one"
        );
        let caps = Caps {
            actions: MAX_ACTIONS,
            methods: 2,
            deadline: None,
            memory_kb: None,
        };
        assert!(
            Rc::build(&c, caps).is_none(),
            "three methods pass a cap of two"
        );
    }
}
