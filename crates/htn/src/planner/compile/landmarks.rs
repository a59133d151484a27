//! Landmarks of goal literals: a literal that every achiever of a goal literal requires.
//!
//! An achiever is a primitive subtask as a method (or the initial task network) writes it:
//! the action with the constants the method passes (directly, or through a parameter its
//! precondition sets equal to a constant), any value where it passes a variable. Unifying an
//! effect that makes the goal literal true with the literal binds more of the action's
//! parameters; the action's precondition literals that are then ground are what that
//! achiever requires. A literal that every achiever requires is a landmark of the goal
//! literal: while the goal literal is false, the landmark must hold now or be achieved later,
//! else the node is a dead end (`search/relevance.rs`). In Woodworking, a part glazed where the
//! goal asks it varnished can be varnished only while untreated, and once no task left in the
//! network can make it untreated the search stops there, not after planning every other part.

use std::collections::{HashMap, HashSet};

use super::statics::Changes;
use super::{CAction, CEffect, CFormula, CTerm, Compiled};

/// A ground literal: fact key (predicate, objects) and sign.
pub(super) type Lit = (Vec<u32>, bool);

/// An action subtask as a method writes it: the action and, per slot, the constant it is given.
type Occurrence = (u32, Vec<Option<u32>>);

/// The action subtasks of every method, by the predicates they change.
pub(super) struct Achievers {
    by_pred: HashMap<u32, Vec<Occurrence>>,
    init: HashSet<Vec<u32>>,
    init_by_pred: HashMap<u32, Vec<Vec<u32>>>,
}

impl Achievers {
    /// Collects each distinct (action, constants) written as a subtask, indexed by the
    /// predicates its effects change.
    pub(super) fn new(c: &Compiled) -> Achievers {
        // Per action, the predicates its effects change.
        let changed: Vec<Vec<u32>> = c
            .actions
            .iter()
            .map(|a| {
                let mut ch = Changes::new(c.preds.len());
                ch.mark(&a.effects);
                (0..)
                    .zip(ch.preds)
                    .filter_map(|(p, x)| x.then_some(p))
                    .collect()
            })
            .collect();
        let mut seen = HashSet::new();
        let mut by_pred: HashMap<u32, Vec<Occurrence>> = HashMap::new();
        for m in &c.methods {
            let fixed = equal_constants(&m.pre, m.slot_types.len());
            for (t, args) in &m.subtasks {
                let Some(a) = c.tasks[*t as usize].action else {
                    continue;
                };
                let act = &c.actions[a as usize];
                let mut slots: Vec<Option<u32>> = vec![None; act.slot_types.len()];
                for (s, term) in slots.iter_mut().zip(args) {
                    *s = match *term {
                        CTerm::Obj(o) => Some(o),
                        CTerm::Var(v) => fixed.get(v as usize).copied().flatten(),
                    };
                }
                if !seen.insert((a, slots.clone())) {
                    continue;
                }
                for &p in &changed[a as usize] {
                    by_pred.entry(p).or_default().push((a, slots.clone()));
                }
            }
        }
        let init = c
            .init_facts
            .iter()
            .map(|(p, args)| {
                let mut k = vec![*p];
                k.extend(args);
                k
            })
            .collect();
        let mut init_by_pred: HashMap<u32, Vec<Vec<u32>>> = HashMap::new();
        for (p, args) in &c.init_facts {
            init_by_pred.entry(*p).or_default().push(args.clone());
        }
        Achievers {
            by_pred,
            init,
            init_by_pred,
        }
    }

    /// The literals every achiever of `lit` requires (empty when none is common, when it has
    /// no achiever, or when a geometric task may achieve it).
    pub(super) fn landmarks(&self, c: &Compiled, lit: &Lit) -> Vec<Lit> {
        let (key, positive) = lit;
        let p = key[0];
        if c.shared_preds[p as usize] {
            return Vec::new();
        }
        let mut common: Option<Vec<Lit>> = None;
        for (a, slots) in self.by_pred.get(&p).map(Vec::as_slice).unwrap_or(&[]) {
            let act = &c.actions[*a as usize];
            let mut unifiers = Vec::new();
            unify_effects(&act.effects, *positive, key, slots, &mut unifiers);
            for b in unifiers {
                let Some(req) = self.required(c, act, &b) else {
                    continue;
                };
                let next = match common.take() {
                    None => req,
                    Some(prev) => prev.into_iter().filter(|l| req.contains(l)).collect(),
                };
                if next.is_empty() {
                    return Vec::new();
                }
                common = Some(next);
            }
        }
        common.unwrap_or_default()
    }

    /// The ground changeable literals of `act`'s precondition under binding `b`; `None` when
    /// a ground static literal (or equality) is false, so this achiever never applies.
    fn required(&self, c: &Compiled, act: &CAction, b: &[Option<u32>]) -> Option<Vec<Lit>> {
        let mut out = Vec::new();
        for l in &act.pre {
            let (atom, positive) = match &l.f {
                CFormula::Not(x) => (&**x, false),
                f => (f, true),
            };
            match atom {
                CFormula::Atom(q, terms) => {
                    let Some(key) = ground(*q, terms, b) else {
                        // A static atom no initial fact matches bars this achiever.
                        if positive
                            && c.static_preds[*q as usize]
                            && !self.static_match(*q, terms, b)
                        {
                            return None;
                        }
                        continue;
                    };
                    if c.static_preds[*q as usize] {
                        if self.init.contains(&key) != positive {
                            return None;
                        }
                    } else if !c.shared_preds[*q as usize]
                        && !out.contains(&(key.clone(), positive))
                    {
                        out.push((key, positive));
                    }
                }
                CFormula::Eq(x, y) => {
                    if let (Some(x), Some(y)) = (term_value(x, b), term_value(y, b))
                        && (x == y) != positive
                    {
                        return None;
                    }
                }
                _ => {}
            }
        }
        Some(out)
    }

    /// Whether an initial fact of `q` fits `terms` where `b` binds them.
    fn static_match(&self, q: u32, terms: &[CTerm], b: &[Option<u32>]) -> bool {
        self.init_by_pred.get(&q).is_some_and(|facts| {
            facts.iter().any(|f| {
                terms
                    .iter()
                    .zip(f)
                    .all(|(t, &x)| term_value(t, b).is_none_or(|v| v == x))
            })
        })
    }
}

/// Per slot, the constant a conjunct `(= ?v c)` of the precondition gives it.
fn equal_constants(pre: &[super::CLit], slots: usize) -> Vec<Option<u32>> {
    let mut fixed = vec![None; slots];
    for l in pre {
        if let CFormula::Eq(x, y) = &l.f {
            match (x, y) {
                (CTerm::Var(v), CTerm::Obj(o)) | (CTerm::Obj(o), CTerm::Var(v)) => {
                    fixed[*v as usize] = Some(*o);
                }
                _ => {}
            }
        }
    }
    fixed
}

/// Each binding (from `slots`) under which an effect of `effs` makes `key` true (`positive`)
/// or false.
fn unify_effects(
    effs: &[CEffect],
    positive: bool,
    key: &[u32],
    slots: &[Option<u32>],
    out: &mut Vec<Vec<Option<u32>>>,
) {
    for e in effs {
        match e {
            CEffect::Add(p, terms) | CEffect::Del(p, terms) => {
                if *p != key[0] || matches!(e, CEffect::Add(..)) != positive {
                    continue;
                }
                let mut b = slots.to_vec();
                let fits = terms.iter().zip(&key[1..]).all(|(t, &want)| match *t {
                    CTerm::Obj(o) => o == want,
                    CTerm::Var(v) => match b.get(v as usize).copied().flatten() {
                        Some(x) => x == want,
                        None => {
                            if let Some(s) = b.get_mut(v as usize) {
                                *s = Some(want);
                            }
                            true
                        }
                    },
                });
                if fits {
                    out.push(b);
                }
            }
            CEffect::When(_, inner) => unify_effects(inner, positive, key, slots, out),
            // A quantified slot takes any value: the binding leaves it unbound.
            CEffect::Forall(vs, inner) => {
                let from = out.len();
                unify_effects(inner, positive, key, slots, out);
                for b in &mut out[from..] {
                    for (v, _) in vs {
                        if let Some(s) = b.get_mut(*v as usize) {
                            *s = None;
                        }
                    }
                }
            }
            CEffect::Num(..) => {}
        }
    }
}

fn term_value(t: &CTerm, b: &[Option<u32>]) -> Option<u32> {
    match *t {
        CTerm::Obj(o) => Some(o),
        CTerm::Var(v) => b.get(v as usize).copied().flatten(),
    }
}

/// The fact key of atom `q(terms)` under `b`, if every term is bound.
fn ground(q: u32, terms: &[CTerm], b: &[Option<u32>]) -> Option<Vec<u32>> {
    let mut key = vec![q];
    for t in terms {
        key.push(term_value(t, b)?);
    }
    Some(key)
}
