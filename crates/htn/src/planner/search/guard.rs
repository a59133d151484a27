//! Guarded achievers: a goal literal that is false now, whose every way of being made true
//! again is barred by a literal that can no longer change, is a dead end.
//!
//! A predicate no action adds can only become false; one no action deletes, only true. A
//! method whose precondition requires, under the arguments that lead to a given achiever, a
//! fact of the first kind that is false now (or the negation of a fact of the second kind that
//! is true now) can never be applied on that path again. For each goal literal of the
//! problem's top-level conjunction, the planner builds once the lifted "achiever graph": the
//! actions that may make the literal true, partially ground by the literal's arguments, and,
//! climbing through every method that has such a task as subtask, the (partially ground) tasks
//! that may decompose into one, each edge labelled with the monotone literals it requires
//! ("guards"). In a state where the literal is false, it can still be made true only if some
//! task of the current task network is reached from an achiever through edges whose guards
//! hold now (a method applied later is applied in a later state, where a guard false now is
//! still false). If none is, the node is a dead end, however deep the search below it would
//! go before finding out at the goal check.
//!
//! The case it is for (IPC 2020's Multiarm-Blocksworld): a block stacked in place (its `goal_on` fact
//! consumed, never to be added again) is unstacked again by a method that picks any clear
//! block; the goal literal `(on b d)` can then only be achieved through `release-stack`,
//! which requires the consumed fact, and the depth-first search finds out only after
//! building the rest of the plan, at the goal check, then backtracks through all of it.
//!
//! The check runs after an action made a goal literal false or changed a guard's fact, for
//! the literals concerned only; it is sound (it prunes only nodes with no plan below them).

use std::collections::HashMap;

use super::super::compile::{CEffect, CFormula, CTerm, Compiled};
use super::super::eval::UNBOUND;
use super::{NIL, Search, WILD};
use crate::state::State;

/// Nodes of one literal's achiever graph beyond which the literal is left unguarded.
const MAX_NODES: usize = 512;
/// Network cells a check looks at; a longer network counts as able to achieve the literal.
const MAX_SCAN: usize = 4096;

/// A guard: the fact must hold (`true`) or must not.
type Guard = (u32, bool);

/// One goal literal's achiever graph.
struct Graph {
    /// Partially ground tasks: `[task, args..]`, `WILD` for an unknown argument.
    nodes: Vec<Vec<u32>>,
    /// Achieving actions (nodes) and the guards of their own preconditions.
    starts: Vec<(u32, Vec<Guard>)>,
    /// Per node, the tasks it may come from: (parent node, guards of that method).
    up: Vec<Vec<(u32, Vec<Guard>)>>,
}

/// The achiever graphs of the goal literals that have guards.
pub(super) struct Guards {
    /// Per goal literal, its graph (`None`: no guard anywhere, or too large: never pruned).
    graphs: Vec<Option<Graph>>,
    /// Per fact id, the goal literals whose graphs read it.
    readers: HashMap<u32, Vec<u32>>,
    /// Scratch: reached nodes.
    reached: Vec<bool>,
    stack: Vec<u32>,
}

/// What a literal of a precondition says under a partial binding.
enum Lit {
    /// Nothing that cannot change (or not all of it bound).
    Free,
    /// False for good.
    Dead,
    Guard(Vec<u32>, bool),
}

impl Guards {
    /// How many goal literals have a guarded achiever graph.
    pub(super) fn count(&self) -> u32 {
        self.graphs.iter().filter(|g| g.is_some()).count() as u32
    }

    /// `None` when no goal literal has a guarded achiever (the check would never prune) or the
    /// problem has geometric actions (geometry changes facts no action names).
    pub(super) fn build(c: &Compiled, state: &mut State) -> Option<Guards> {
        if c.goal_lits.is_empty() || c.actions.iter().any(|a| a.evaluable.is_some()) {
            return None;
        }
        let n = c.preds.len();
        let (mut added, mut deleted) = (c.shared_preds.clone(), c.shared_preds.clone());
        for a in &c.actions {
            mark(&a.effects, &mut added, &mut deleted);
        }
        let mut action_task = vec![u32::MAX; c.actions.len()];
        for (t, task) in c.tasks.iter().enumerate() {
            if let Some(a) = task.action {
                action_task[a as usize] = t as u32;
            }
        }
        // Per task, the (method, subtask position) occurrences.
        let mut parents: Vec<Vec<(u32, usize)>> = vec![Vec::new(); c.tasks.len()];
        for (m, method) in c.methods.iter().enumerate() {
            if m as u32 == c.root_method {
                continue;
            }
            for (i, (st, _)) in method.subtasks.iter().enumerate() {
                parents[*st as usize].push((m as u32, i));
            }
        }
        let env = Env {
            c,
            added: &added[..n],
            deleted: &deleted[..n],
        };
        let mut graphs = Vec::with_capacity(c.goal_lits.len());
        let mut readers: HashMap<u32, Vec<u32>> = HashMap::new();
        let mut any = false;
        for (i, (key, positive)) in c.goal_lits.iter().enumerate() {
            let g = if !c.goal_parent[i].is_empty() {
                None
            } else {
                env.graph(key, *positive, &action_task, &parents, state)
            };
            if let Some(g) = &g {
                any = true;
                let mut facts: Vec<u32> = g
                    .starts
                    .iter()
                    .flat_map(|(_, gs)| gs.iter().map(|x| x.0))
                    .chain(
                        g.up.iter()
                            .flatten()
                            .flat_map(|(_, gs)| gs.iter().map(|x| x.0)),
                    )
                    .collect();
                facts.sort_unstable();
                facts.dedup();
                for f in facts {
                    readers.entry(f).or_default().push(i as u32);
                }
            }
            graphs.push(g);
        }
        any.then_some(Guards {
            graphs,
            readers,
            reached: Vec::new(),
            stack: Vec::new(),
        })
    }
}

struct Env<'a> {
    c: &'a Compiled,
    /// Per predicate: some action adds it / deletes it (shared predicates: both).
    added: &'a [bool],
    deleted: &'a [bool],
}

impl Env<'_> {
    fn graph(
        &self,
        key: &[u32],
        positive: bool,
        action_task: &[u32],
        parents: &[Vec<(u32, usize)>],
        state: &mut State,
    ) -> Option<Graph> {
        let c = self.c;
        let mut g = Graph {
            nodes: Vec::new(),
            starts: Vec::new(),
            up: Vec::new(),
        };
        let mut ids: HashMap<Vec<u32>, u32> = HashMap::new();
        let mut guarded = false;
        for (a, act) in c.actions.iter().enumerate() {
            let mut found: Vec<Vec<u32>> = Vec::new();
            achievers(c, &act.effects, key, positive, &act.slot_types, &mut found);
            for b in found {
                let mut b = b;
                // Only the parameters bind the action's own precondition (the quantified slots
                // of effects are another scope).
                for x in b.iter_mut().skip(act.n_params) {
                    *x = UNBOUND;
                }
                let Some(guards) = self.guards(&act.pre, &b, state) else {
                    continue;
                };
                guarded |= !guards.is_empty();
                let mut node = vec![action_task[a]];
                node.extend(b[..act.n_params].iter().map(|&x| wild(x)));
                let id = intern(&mut g, &mut ids, node);
                g.starts.push((id, guards));
            }
        }
        let mut next = 0;
        while next < g.nodes.len() {
            if g.nodes.len() > MAX_NODES {
                return None;
            }
            let node = g.nodes[next].clone();
            for &(m, pos) in &parents[node[0] as usize] {
                let method = &c.methods[m as usize];
                let mut b = vec![UNBOUND; method.slot_types.len()];
                if !unify(
                    c,
                    &method.subtasks[pos].1,
                    &node[1..],
                    &method.slot_types,
                    &mut b,
                ) {
                    continue;
                }
                let Some(guards) = self.guards(&method.pre, &b, state) else {
                    continue;
                };
                guarded |= !guards.is_empty();
                let mut parent = vec![method.task];
                parent.extend(method.task_args.iter().map(|t| match *t {
                    CTerm::Obj(o) => o,
                    CTerm::Var(v) => wild(b[v as usize]),
                }));
                let id = intern(&mut g, &mut ids, parent);
                g.up[next].push((id, guards));
            }
            next += 1;
        }
        guarded.then_some(g)
    }

    /// The guards of a precondition under binding `b`; `None` if a literal is false for good.
    fn guards(
        &self,
        pre: &[super::super::compile::CLit],
        b: &[u32],
        state: &mut State,
    ) -> Option<Vec<Guard>> {
        let mut out = Vec::new();
        for l in pre {
            match self.lit(&l.f, b, state) {
                Lit::Free => {}
                Lit::Dead => return None,
                Lit::Guard(key, must) => {
                    let id = state.intern_fact(&key);
                    if !out.contains(&(id, must)) {
                        out.push((id, must));
                    }
                }
            }
        }
        Some(out)
    }

    fn lit(&self, f: &CFormula, b: &[u32], state: &State) -> Lit {
        let ground = |args: &[CTerm]| -> Option<Vec<u32>> {
            args.iter()
                .map(|t| match *t {
                    CTerm::Obj(o) => Some(o),
                    CTerm::Var(v) => b.get(v as usize).copied().filter(|&x| x != UNBOUND),
                })
                .collect()
        };
        let term = |t: &CTerm| match *t {
            CTerm::Obj(o) => Some(o),
            CTerm::Var(v) => b.get(v as usize).copied().filter(|&x| x != UNBOUND),
        };
        let atom = |p: u32, args: &[CTerm], positive: bool| -> Lit {
            let Some(a) = ground(args) else {
                return Lit::Free;
            };
            // Positive: it must hold, and only an add could make it hold later.
            let (can_change, other_way) = if positive {
                (self.added[p as usize], self.deleted[p as usize])
            } else {
                (self.deleted[p as usize], self.added[p as usize])
            };
            if can_change {
                return Lit::Free;
            }
            let mut key = vec![p];
            key.extend(a);
            if !other_way {
                // Static: decided now.
                return if state.holds(&key) == positive {
                    Lit::Free
                } else {
                    Lit::Dead
                };
            }
            Lit::Guard(key, positive)
        };
        match f {
            CFormula::Atom(p, args) => atom(*p, args, true),
            CFormula::Eq(x, y) => match (term(x), term(y)) {
                (Some(x), Some(y)) if x != y => Lit::Dead,
                _ => Lit::Free,
            },
            CFormula::Not(inner) => match &**inner {
                CFormula::Atom(p, args) => atom(*p, args, false),
                CFormula::Eq(x, y) => match (term(x), term(y)) {
                    (Some(x), Some(y)) if x == y => Lit::Dead,
                    _ => Lit::Free,
                },
                _ => Lit::Free,
            },
            _ => Lit::Free,
        }
    }
}

fn wild(x: u32) -> u32 {
    if x == UNBOUND { WILD } else { x }
}

fn intern(g: &mut Graph, ids: &mut HashMap<Vec<u32>, u32>, node: Vec<u32>) -> u32 {
    if let Some(&id) = ids.get(&node) {
        return id;
    }
    let id = g.nodes.len() as u32;
    ids.insert(node.clone(), id);
    g.nodes.push(node);
    g.up.push(Vec::new());
    id
}

/// Binds slots so that `terms` match `args` (`WILD` matches anything); `false` on a clash or
/// a type that does not fit.
fn unify(c: &Compiled, terms: &[CTerm], args: &[u32], types: &[u32], b: &mut [u32]) -> bool {
    if terms.len() != args.len() {
        return false;
    }
    for (t, &a) in terms.iter().zip(args) {
        if a == WILD {
            continue;
        }
        match *t {
            CTerm::Obj(o) => {
                if o != a {
                    return false;
                }
            }
            CTerm::Var(v) => {
                let cur = b[v as usize];
                if cur == UNBOUND {
                    if !c.is_of(a, types[v as usize]) {
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

/// The bindings (over the action's slots) under which an effect of `effs` makes the literal
/// `key` (`[pred, args..]`) take the sign `positive`.
fn achievers(
    c: &Compiled,
    effs: &[CEffect],
    key: &[u32],
    positive: bool,
    types: &[u32],
    out: &mut Vec<Vec<u32>>,
) {
    for e in effs {
        match e {
            CEffect::Add(p, terms) | CEffect::Del(p, terms) => {
                if *p != key[0] || matches!(e, CEffect::Add(..)) != positive {
                    continue;
                }
                let mut b = vec![UNBOUND; types.len()];
                if unify(c, terms, &key[1..], types, &mut b) {
                    out.push(b);
                }
            }
            CEffect::Forall(_, inner) | CEffect::When(_, inner) => {
                achievers(c, inner, key, positive, types, out)
            }
            CEffect::Num(..) => {}
        }
    }
}

fn mark(effs: &[CEffect], added: &mut [bool], deleted: &mut [bool]) {
    for e in effs {
        match e {
            CEffect::Add(p, _) => added[*p as usize] = true,
            CEffect::Del(p, _) => deleted[*p as usize] = true,
            CEffect::Forall(_, inner) | CEffect::When(_, inner) => mark(inner, added, deleted),
            CEffect::Num(..) => {}
        }
    }
}

impl<'a, 'o> Search<'a, 'o> {
    /// After an action: whether every goal literal it made false, or whose guards it changed,
    /// can still be made true by the network from cell `net` (see the module docs). Reads the
    /// state changes since trail mark `mark`.
    pub(super) fn guarded_goals_alive(&mut self, mark: usize, net: u32) -> bool {
        let Some(mut gd) = self.guards.take() else {
            return true;
        };
        let mut ok = true;
        let mut todo: Vec<u32> = Vec::new();
        for f in self.state.changed_since(mark) {
            if let Some(i) = self.state.watched_pos(f)
                && gd.graphs[i as usize].is_some()
            {
                todo.push(i);
            }
            if let Some(i) = self.state.watched_neg(f)
                && gd.graphs[i as usize].is_some()
            {
                todo.push(i);
            }
            if let Some(rs) = gd.readers.get(&f) {
                todo.extend_from_slice(rs);
            }
        }
        todo.sort_unstable();
        todo.dedup();
        for i in todo {
            let unsat = self.state.unsat();
            if unsat[i as usize / 64] & (1 << (i % 64)) == 0 {
                continue;
            }
            if !self.achievable(&mut gd, i as usize, net) {
                ok = false;
                break;
            }
        }
        self.guards = Some(gd);
        ok
    }

    fn achievable(&self, gd: &mut Guards, i: usize, net: u32) -> bool {
        let Some(g) = &gd.graphs[i] else {
            return true;
        };
        let holds = |gs: &[Guard]| gs.iter().all(|&(f, must)| self.state.holds_id(f) == must);
        gd.reached.clear();
        gd.reached.resize(g.nodes.len(), false);
        gd.stack.clear();
        for (s, gs) in &g.starts {
            if !gd.reached[*s as usize] && holds(gs) {
                gd.reached[*s as usize] = true;
                gd.stack.push(*s);
            }
        }
        while let Some(n) = gd.stack.pop() {
            for (p, gs) in &g.up[n as usize] {
                if !gd.reached[*p as usize] && holds(gs) {
                    gd.reached[*p as usize] = true;
                    gd.stack.push(*p);
                }
            }
        }
        let live: Vec<&[u32]> = g
            .nodes
            .iter()
            .zip(&gd.reached)
            .filter(|(_, r)| **r)
            .map(|(n, _)| n.as_slice())
            .collect();
        if live.is_empty() {
            return false;
        }
        let mut cur = net;
        let mut k = 0;
        while cur != NIL {
            if k == MAX_SCAN {
                return true;
            }
            let cell = &self.arena[cur as usize];
            let key = self.gtasks.key(cell.task);
            for n in &live {
                if n[0] == key[0]
                    && n.len() == key.len()
                    && n[1..]
                        .iter()
                        .zip(&key[1..])
                        .all(|(&x, &y)| x == WILD || y == UNBOUND || x == y)
                {
                    return true;
                }
            }
            cur = cell.next;
            k += 1;
        }
        false
    }
}
