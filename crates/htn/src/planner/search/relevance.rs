//! Goal relevance: each suffix of the task network carries the set of goal literals (a mask)
//! its tasks may achieve; a node where a false goal literal (or a landmark still needed) can
//! no longer be achieved is a dead end.

use super::super::compile::{CEffect, CFormula, CLit, CTerm, Compiled};
use super::super::eval::{Eval, UNBOUND};
use super::{Search, bound_terms};

/// An unknown argument in a partially ground task (only in goal-relevance reasoning).
pub(super) const WILD: u32 = u32::MAX;

/// Whether `f` is a literal over static facts (or equality).
pub(super) fn is_static_lit(c: &Compiled, f: &CFormula) -> bool {
    match f {
        CFormula::Atom(p, _) => c.static_preds[*p as usize],
        CFormula::Eq(..) => true,
        CFormula::Not(x) => is_static_lit(c, x),
        _ => false,
    }
}

/// Adds to `m` the goal literals an action with arguments `args` (some may be `WILD`) may
/// achieve.
pub(super) fn ground_effect_mask(c: &Compiled, effs: &[CEffect], args: &[u32], m: &mut [u64]) {
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

/// What [`Search::may_achieve`] knows of a ground task's goal mask.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(super) enum MayAchieve {
    Unknown,
    /// Being computed (a recursive call met it again: the lifted mask stands in).
    Computing,
    /// The id of its goal mask.
    Known(u32),
}

/// Interned bitsets over the goal literals, with memoised unions (cells share them).
pub(super) struct MaskTable {
    words: usize,
    masks: Vec<Box<[u64]>>,
    ids: crate::state::FxMap<Box<[u64]>, u32>,
    unions: crate::state::FxMap<u64, u32>,
}

impl MaskTable {
    pub(super) fn new(words: usize) -> MaskTable {
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
    pub(super) fn intern(&mut self, m: &[u64]) -> u32 {
        if let Some(&id) = self.ids.get(m) {
            return id;
        }
        let id = self.masks.len() as u32;
        self.masks.push(m.into());
        self.ids.insert(m.into(), id);
        id
    }

    pub(super) fn get(&self, id: u32) -> &[u64] {
        &self.masks[id as usize]
    }

    pub(super) fn union(&mut self, a: u32, b: u32) -> u32 {
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
    /// Whether every goal literal (or landmark still needed) that is false now may still be
    /// achieved by the network whose tasks may achieve mask `may`.
    pub(super) fn goal_reachable(&self, may: u32) -> bool {
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
                let needed = self.landmark_needed(i, unsat);
                if needed {
                    return false;
                }
            }
        }
        true
    }

    /// Whether literal `i`, false now, must still be achieved: a goal literal always; a
    /// landmark while some literal it serves is false and itself needed.
    fn landmark_needed(&self, i: usize, unsat: &[u64]) -> bool {
        let parents = &self.c.goal_parent[i];
        parents.is_empty()
            || parents
                .iter()
                .any(|&j| unsat[j / 64] & (1 << (j % 64)) != 0 && self.landmark_needed(j, unsat))
    }

    /// Orders the `count` bindings of method `m` (flat) by how many goal literals false now
    /// its subtasks may achieve under each, most first (stable: ties keep their order). A
    /// value the goal asks for is then tried before one it does not (Woodworking's colour of
    /// a part, chosen where nothing but the goal constrains it).
    pub(super) fn goals_first(&mut self, m: u32, bindings: &mut [u32], count: usize) {
        if self.c.goal_lits.is_empty() || count < 2 {
            return;
        }
        let stride = bindings.len() / count;
        let method = &self.c.methods[m as usize];
        if stride == 0 || method.subtasks.is_empty() {
            return;
        }
        let unsat = self.state.unsat().to_vec();
        let mut scores = Vec::with_capacity(count);
        let mut key = Vec::new();
        for row in bindings.chunks(stride) {
            let mut score = 0;
            let mut mask = vec![0u64; unsat.len()];
            for (t, args) in &method.subtasks {
                key.clear();
                key.push(*t);
                key.extend(bound_terms(args, row));
                let gt = self.gtasks.intern(&key);
                let may = self.may_achieve(gt);
                for (w, x) in mask.iter_mut().zip(self.masks.get(may)) {
                    *w |= x;
                }
            }
            for (u, x) in unsat.iter().zip(&mask) {
                score += (u & x).count_ones();
            }
            scores.push(score);
        }
        if scores.iter().all(|&s| s == scores[0]) {
            return;
        }
        let mut order: Vec<usize> = (0..count).collect();
        order.sort_by_key(|&i| std::cmp::Reverse(scores[i]));
        let sorted: Vec<u32> = order
            .iter()
            .flat_map(|&i| bindings[i * stride..(i + 1) * stride].to_vec())
            .collect();
        bindings.copy_from_slice(&sorted);
    }

    /// The goal literals (a mask id) that ground task `gt` may achieve, through the methods
    /// whose task arguments and static preconditions fit its arguments. Arguments may be
    /// `WILD` (unknown). Memoised; a task met again while it is being computed counts with its
    /// lifted mask (an over-approximation, so the pruning stays sound).
    pub(super) fn may_achieve(&mut self, gt: u32) -> u32 {
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
    pub(super) fn bind_by_static_facts(&self, pre: &[CLit], b: &mut [u32]) -> bool {
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
}
