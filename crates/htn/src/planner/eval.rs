//! Evaluating compiled conditions on the state, enumerating the bindings that satisfy a
//! conjunction, and computing an action's effects.
//!
//! Bindings live in a slot array (`u32::MAX` = unbound). The binder is a small backtracking
//! join: it first tests every literal whose slots are all bound (fail fast), then extends the
//! binding through the positive atom with the fewest candidate facts, then through equalities,
//! and only as a last resort enumerates the objects of a slot's type.

use crate::model::CompareOp;
use crate::state::State;

use super::compile::{CEffect, CFormula, CLit, CNum, CTerm, Compiled};

/// An unbound slot.
pub(crate) const UNBOUND: u32 = u32::MAX;

/// Where an enumeration of [`Eval::solve_from`] stands: the position in each choice of the
/// join (candidate facts, objects of a type) that led to one binding.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub(crate) struct Cursor(Vec<u32>);

/// How an enumeration of [`Eval::solve_from`] ended.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum Enumerated {
    /// The callback asked to stop: more bindings may follow.
    Stopped,
    /// Every binding was given.
    Exhausted,
    /// The poll asked to give up: the bindings given are not all of them.
    Aborted,
}

/// Join steps between two polls of [`Eval::solve_from`]'s `poll`.
const POLL_EVERY: u32 = 4096;

/// The state of one enumeration: the choice path, the cursor it resumes after, the poll.
#[derive(Default)]
struct Control<'p> {
    /// Positions in the enclosing choices, outermost first.
    path: Vec<u32>,
    /// The path of the binding to resume after.
    resume: &'p [u32],
    /// Still descending along `resume` (each choice starts at its position there).
    resuming: bool,
    poll: Option<&'p dyn Fn() -> bool>,
    steps: u32,
    aborted: bool,
}

impl Control<'_> {
    /// Enters a choice: the position to start from (the resumed one's, or the first).
    fn enter(&mut self) -> usize {
        let depth = self.path.len();
        self.path.push(0);
        if self.resuming {
            self.resume.get(depth).map_or(0, |&p| p as usize)
        } else {
            0
        }
    }

    /// The current choice is at position `pos`.
    fn at(&mut self, pos: usize) {
        if let Some(last) = self.path.last_mut() {
            *last = pos as u32;
        }
    }

    fn leave(&mut self) {
        self.path.pop();
    }

    /// Whether to stop the whole enumeration: the poll said so (now or before).
    fn give_up(&mut self) -> bool {
        if self.aborted {
            return true;
        }
        self.steps += 1;
        if self.steps % POLL_EVERY == 0
            && let Some(poll) = self.poll
            && poll()
        {
            self.aborted = true;
        }
        self.aborted
    }
}

/// Read-only evaluation context.
pub(crate) struct Eval<'a> {
    pub c: &'a Compiled,
    pub s: &'a State,
    pub types: &'a [u32],
}

#[inline]
fn val(t: &CTerm, b: &[u32]) -> u32 {
    match *t {
        CTerm::Var(v) => b[v as usize],
        CTerm::Obj(o) => o,
    }
}

/// Builds `[head, args..]` into `buf` and calls `f` with it.
#[inline]
fn with_key<R>(head: u32, args: &[CTerm], b: &[u32], f: impl FnOnce(&[u32]) -> R) -> R {
    let mut arr = [0u32; 16];
    if args.len() < 16 {
        arr[0] = head;
        for (i, t) in args.iter().enumerate() {
            arr[i + 1] = val(t, b);
        }
        f(&arr[..=args.len()])
    } else {
        let mut v = Vec::with_capacity(args.len() + 1);
        v.push(head);
        v.extend(args.iter().map(|t| val(t, b)));
        f(&v)
    }
}

impl Eval<'_> {
    /// The value of a numeric expression; NaN when a fluent is undefined.
    pub fn num(&self, e: &CNum, b: &[u32]) -> f64 {
        match e {
            CNum::Number(x) => *x,
            CNum::Fluent(f, args) => with_key(*f, args, b, |k| self.s.value(k)),
            CNum::Bin(op, x, y) => {
                let (x, y) = (self.num(x, b), self.num(y, b));
                op.apply(x, y).unwrap_or(f64::NAN)
            }
            CNum::Neg(x) => -self.num(x, b),
        }
    }

    /// Whether a condition whose free slots are all bound holds.
    pub fn holds(&self, f: &CFormula, b: &mut [u32]) -> bool {
        match f {
            CFormula::True => true,
            CFormula::Atom(p, args) => with_key(*p, args, b, |k| self.s.holds(k)),
            CFormula::Eq(x, y) => val(x, b) == val(y, b),
            CFormula::Not(x) => !self.holds(x, b),
            CFormula::And(xs) => xs.iter().all(|x| self.holds(x, b)),
            CFormula::Or(xs) => xs.iter().any(|x| self.holds(x, b)),
            CFormula::Imply(x, y) => !self.holds(x, b) || self.holds(y, b),
            CFormula::Exists(vs, body) => {
                let need: Vec<u16> = vs.iter().map(|(s, _)| *s).collect();
                self.solve(body, b, &need, &mut |_| true)
            }
            CFormula::Forall(vs, body) => self.forall(vs, body, b),
            CFormula::Compare(op, x, y) => {
                let (x, y) = (self.num(x, b), self.num(y, b));
                match op {
                    CompareOp::Lt => x < y,
                    CompareOp::Le => x <= y,
                    CompareOp::Eq => x == y,
                    CompareOp::Ge => x >= y,
                    CompareOp::Gt => x > y,
                }
            }
        }
    }

    fn forall(&self, vs: &[(u16, u32)], body: &CFormula, b: &mut [u32]) -> bool {
        let Some(&(slot, ty)) = vs.first() else {
            return self.holds(body, b);
        };
        for &o in &self.c.type_objects[ty as usize] {
            b[slot as usize] = o;
            if !self.forall(&vs[1..], body, b) {
                b[slot as usize] = UNBOUND;
                return false;
            }
        }
        b[slot as usize] = UNBOUND;
        true
    }

    /// Whether every literal holds (all slots bound).
    pub fn all_hold(&self, lits: &[CLit], b: &mut [u32]) -> bool {
        lits.iter().all(|l| self.holds(&l.f, b))
    }

    /// Enumerates the bindings of the unbound slots of `lits` and of `need` that make every
    /// literal true, calling `cb` with each; `cb` returns `true` to stop. Returns whether it
    /// stopped. The slot array is left as it was given.
    pub fn solve(
        &self,
        lits: &[CLit],
        b: &mut [u32],
        need: &[u16],
        cb: &mut dyn FnMut(&[u32]) -> bool,
    ) -> bool {
        let mut done = vec![false; lits.len()];
        let mut ctl = Control::default();
        self.solve_rec(lits, b, need, &mut done, &mut ctl, &mut |bb, _| cb(bb))
    }

    /// [`Eval::solve`] one piece at a time: the bindings after the one whose [`Cursor`] is
    /// `after` (from the first when `None`), in the same order, until `cb` returns `true`;
    /// then also the cursor of the binding it stopped at. Between two calls the state must be
    /// the same. `poll` is asked every few thousand steps of the join whether to give up (a
    /// limit was reached).
    pub fn solve_from(
        &self,
        lits: &[CLit],
        b: &mut [u32],
        need: &[u16],
        after: Option<&Cursor>,
        poll: &dyn Fn() -> bool,
        cb: &mut dyn FnMut(&[u32]) -> bool,
    ) -> (Enumerated, Option<Cursor>) {
        let mut done = vec![false; lits.len()];
        let mut ctl = Control {
            resume: after.map_or(&[], |c| &c.0),
            resuming: after.is_some(),
            poll: Some(poll),
            ..Control::default()
        };
        let mut last = None;
        let stopped = self.solve_rec(lits, b, need, &mut done, &mut ctl, &mut |bb, path| {
            let stop = cb(bb);
            if stop {
                last = Some(Cursor(path.to_vec()));
            }
            stop
        });
        match (ctl.aborted, stopped) {
            (true, _) => (Enumerated::Aborted, None),
            (false, true) => (Enumerated::Stopped, last),
            (false, false) => (Enumerated::Exhausted, None),
        }
    }

    fn solve_rec(
        &self,
        lits: &[CLit],
        b: &mut [u32],
        need: &[u16],
        done: &mut [bool],
        ctl: &mut Control,
        cb: &mut dyn FnMut(&[u32], &[u32]) -> bool,
    ) -> bool {
        // Test every literal that is fully bound (remember which, to unmark them after).
        let mut tested_mask: u64 = 0;
        let mut tested_more: Vec<usize> = Vec::new();
        let mut ok = true;
        for (i, l) in lits.iter().enumerate() {
            if !done[i] && l.vars.iter().all(|&v| b[v as usize] != UNBOUND) {
                if !self.holds(&l.f, b) {
                    ok = false;
                    break;
                }
                done[i] = true;
                if i < 64 {
                    tested_mask |= 1 << i;
                } else {
                    tested_more.push(i);
                }
            }
        }
        let stop = ok && self.extend(lits, b, need, done, ctl, cb);
        let mut m = tested_mask;
        while m != 0 {
            done[m.trailing_zeros() as usize] = false;
            m &= m - 1;
        }
        for j in tested_more {
            done[j] = false;
        }
        stop
    }

    fn extend(
        &self,
        lits: &[CLit],
        b: &mut [u32],
        need: &[u16],
        done: &mut [bool],
        ctl: &mut Control,
        cb: &mut dyn FnMut(&[u32], &[u32]) -> bool,
    ) -> bool {
        if ctl.give_up() {
            return true;
        }
        // The positive atom with the fewest candidates (static atoms through the index).
        let mut best: Option<(usize, &[u32])> = None;
        for (i, l) in lits.iter().enumerate() {
            if done[i] {
                continue;
            }
            if let CFormula::Atom(p, args) = &l.f {
                let mut cands = self.s.facts_of(*p);
                if self.s.is_static(*p) {
                    for (k, t) in args.iter().enumerate() {
                        let o = val(t, b);
                        if o != UNBOUND {
                            let c = self.s.static_facts_with(*p, k, o);
                            if c.len() < cands.len() {
                                cands = c;
                            }
                        }
                    }
                }
                if best.is_none_or(|(_, m)| cands.len() < m.len()) {
                    best = Some((i, cands));
                }
            }
        }
        if let Some((i, cands)) = best {
            let CFormula::Atom(_, args) = &lits[i].f else {
                unreachable!()
            };
            done[i] = true;
            let mut stop = false;
            let mut bound: [u16; 16] = [0; 16];
            let first = ctl.enter();
            for (pos, &fid) in cands.iter().enumerate().skip(first) {
                ctl.at(pos);
                let fa = self.s.fact_args(fid);
                let mut nb = 0;
                let mut ok = true;
                for (k, t) in args.iter().enumerate() {
                    match *t {
                        CTerm::Obj(o) => {
                            if fa[k] != o {
                                ok = false;
                                break;
                            }
                        }
                        CTerm::Var(v) => {
                            let cur = b[v as usize];
                            if cur == UNBOUND {
                                if !self.c.is_of(fa[k], self.types[v as usize]) || nb == 16 {
                                    ok = false;
                                    break;
                                }
                                b[v as usize] = fa[k];
                                bound[nb] = v;
                                nb += 1;
                            } else if cur != fa[k] {
                                ok = false;
                                break;
                            }
                        }
                    }
                }
                if ok && self.solve_rec(lits, b, need, done, ctl, cb) {
                    stop = true;
                }
                for &v in &bound[..nb] {
                    b[v as usize] = UNBOUND;
                }
                ctl.resuming = false;
                if stop {
                    break;
                }
            }
            ctl.leave();
            done[i] = false;
            return stop;
        }
        // An equality with one side bound binds the other.
        for (i, l) in lits.iter().enumerate() {
            if done[i] {
                continue;
            }
            if let CFormula::Eq(x, y) = &l.f {
                let (vx, vy) = (val(x, b), val(y, b));
                let (slot, o) = match (x, y) {
                    (CTerm::Var(v), _) if vx == UNBOUND && vy != UNBOUND => (*v, vy),
                    (_, CTerm::Var(v)) if vy == UNBOUND && vx != UNBOUND => (*v, vx),
                    _ => continue,
                };
                if !self.c.is_of(o, self.types[slot as usize]) {
                    return false;
                }
                b[slot as usize] = o;
                let stop = self.solve_rec(lits, b, need, done, ctl, cb);
                b[slot as usize] = UNBOUND;
                return stop;
            }
        }
        // Otherwise enumerate the type of some unbound slot.
        let slot = lits
            .iter()
            .enumerate()
            .filter(|(i, _)| !done[*i])
            .flat_map(|(_, l)| l.vars.iter())
            .chain(need.iter())
            .copied()
            .find(|&v| b[v as usize] == UNBOUND);
        if let Some(v) = slot {
            let mut stop = false;
            let first = ctl.enter();
            let objects = &self.c.type_objects[self.types[v as usize] as usize];
            for (pos, &o) in objects.iter().enumerate().skip(first) {
                ctl.at(pos);
                b[v as usize] = o;
                let found = self.solve_rec(lits, b, need, done, ctl, cb);
                ctl.resuming = false;
                if found {
                    stop = true;
                    break;
                }
            }
            ctl.leave();
            b[v as usize] = UNBOUND;
            return stop;
        }
        if ctl.resuming {
            // The binding the enumeration resumes after: already given.
            ctl.resuming = false;
            return false;
        }
        cb(b, &ctl.path)
    }

    /// Collects the effects of an action (evaluated in the current state) into `out`.
    /// Returns `false` when an effect reads an undefined fluent.
    pub fn effects(&self, effs: &[CEffect], b: &mut [u32], out: &mut EffectBuf) -> bool {
        for e in effs {
            match e {
                CEffect::Add(p, args) => with_key(*p, args, b, |k| out.push_fact(true, k)),
                CEffect::Del(p, args) => with_key(*p, args, b, |k| out.push_fact(false, k)),
                CEffect::Forall(vs, inner) => {
                    if !self.forall_effects(vs, inner, b, out) {
                        return false;
                    }
                }
                CEffect::When(cond, inner) => {
                    if self.holds(cond, b) && !self.effects(inner, b, out) {
                        return false;
                    }
                }
                CEffect::Num(op, f, args, e) => {
                    let cur = with_key(*f, args, b, |k| self.s.value(k));
                    let x = self.num(e, b);
                    // NaN (undefined) stays NaN, except where assigned.
                    let v = op.apply(cur, x).unwrap_or(f64::NAN);
                    if v.is_nan() {
                        return false;
                    }
                    with_key(*f, args, b, |k| out.push_value(k, v));
                }
            }
        }
        true
    }

    fn forall_effects(
        &self,
        vs: &[(u16, u32)],
        inner: &[CEffect],
        b: &mut [u32],
        out: &mut EffectBuf,
    ) -> bool {
        let Some(&(slot, ty)) = vs.first() else {
            return self.effects(inner, b, out);
        };
        for &o in &self.c.type_objects[ty as usize] {
            b[slot as usize] = o;
            if !self.forall_effects(&vs[1..], inner, b, out) {
                b[slot as usize] = UNBOUND;
                return false;
            }
        }
        b[slot as usize] = UNBOUND;
        true
    }
}

/// Effects collected before being applied: facts as `[len, pred, args..]` runs.
#[derive(Default)]
pub(crate) struct EffectBuf {
    pub adds: Vec<u32>,
    pub dels: Vec<u32>,
    pub values: Vec<(Vec<u32>, f64)>,
}

impl EffectBuf {
    pub fn clear(&mut self) {
        self.adds.clear();
        self.dels.clear();
        self.values.clear();
    }
    fn push_fact(&mut self, add: bool, key: &[u32]) {
        let v = if add { &mut self.adds } else { &mut self.dels };
        v.push(key.len() as u32);
        v.extend_from_slice(key);
    }
    fn push_value(&mut self, key: &[u32], v: f64) {
        self.values.push((key.to_vec(), v));
    }

    /// Applies the collected effects: values, then deletes, then adds (an atom both added
    /// and deleted ends up true, as in PDDL).
    pub fn apply(&self, s: &mut State) {
        for (k, v) in &self.values {
            let id = s.intern_fluent(k);
            s.set_value(id, *v);
        }
        let mut i = 0;
        while i < self.dels.len() {
            let n = self.dels[i] as usize;
            if let Some(id) = s.facts.get(&self.dels[i + 1..i + 1 + n]) {
                s.delete(id);
            }
            i += n + 1;
        }
        let mut i = 0;
        while i < self.adds.len() {
            let n = self.adds[i] as usize;
            let id = s.intern_fact(&self.adds[i + 1..i + 1 + n]);
            s.add(id);
            i += n + 1;
        }
    }
}
