//! Facts consumed for good. A fact of a predicate that no action adds (and that is no shared
//! literal, which geometric solutions may add) only ever becomes false. When a method's
//! primitive subtask deletes such a fact unconditionally and a primitive task after it in the
//! network needs it, the network cannot be executed: every task of a totally ordered network
//! is executed, in order, and nothing gives the fact back. The depth-first search skips such a
//! method binding when it is chosen, not when the needing task fails, maybe thousands of nodes
//! later (Factories: a factory built at the one free location the last factory needs).

use super::super::compile::{CEffect, CFormula, CTerm, Compiled};
use super::super::eval::UNBOUND;
use super::{NIL, Search, bound_terms};

/// A literal over an action's parameters: predicate and argument terms.
type Lit = (u32, Vec<CTerm>);

/// What each action consumes and needs of the facts no action adds.
pub(super) struct Consumed {
    /// Per action, its unconditional deletes of such facts.
    dels: Vec<Vec<Lit>>,
    /// Per action, its positive preconditions over such facts.
    needs: Vec<Vec<Lit>>,
    /// Per method, whether a primitive subtask of it deletes such a fact.
    consumer: Vec<bool>,
}

impl Consumed {
    /// The table of `c`; `None` when no action deletes a fact no action adds.
    pub(super) fn build(c: &Compiled) -> Option<Consumed> {
        let mut added = vec![false; c.preds.len()];
        for a in &c.actions {
            mark_adds(&a.effects, &mut added);
        }
        let kept = |p: u32| !added[p as usize] && !c.shared_preds[p as usize];
        let over_params = |n: usize, terms: &[CTerm]| {
            terms.iter().all(|t| match t {
                CTerm::Var(v) => (*v as usize) < n,
                CTerm::Obj(_) => true,
            })
        };
        let mut dels = Vec::with_capacity(c.actions.len());
        let mut needs = Vec::with_capacity(c.actions.len());
        for a in &c.actions {
            let n = a.n_params;
            dels.push(
                a.effects
                    .iter()
                    .filter_map(|e| match e {
                        CEffect::Del(p, t) if kept(*p) && over_params(n, t) => {
                            Some((*p, t.clone()))
                        }
                        _ => None,
                    })
                    .collect::<Vec<_>>(),
            );
            needs.push(
                a.pre
                    .iter()
                    .filter_map(|l| match &l.f {
                        CFormula::Atom(p, t) if kept(*p) && over_params(n, t) => {
                            Some((*p, t.clone()))
                        }
                        _ => None,
                    })
                    .collect::<Vec<_>>(),
            );
        }
        if dels.iter().all(Vec::is_empty) {
            return None;
        }
        let consumer = c
            .methods
            .iter()
            .map(|m| {
                m.subtasks.iter().any(|(t, _)| {
                    c.tasks[*t as usize]
                        .action
                        .is_some_and(|a| !dels[a as usize].is_empty())
                })
            })
            .collect();
        Some(Consumed {
            dels,
            needs,
            consumer,
        })
    }
}

/// Marks in `added` the predicates `effs` may add.
fn mark_adds(effs: &[CEffect], added: &mut [bool]) {
    for e in effs {
        match e {
            CEffect::Add(p, _) => added[*p as usize] = true,
            CEffect::Forall(_, inner) | CEffect::When(_, inner) => mark_adds(inner, added),
            CEffect::Del(..) | CEffect::Num(..) => {}
        }
    }
}

/// The ground fact of `lit` for an action with arguments `args`; `None` when an argument is
/// still unbound.
fn ground(lit: &Lit, args: &[u32]) -> Option<Vec<u32>> {
    let mut key = Vec::with_capacity(lit.1.len() + 1);
    key.push(lit.0);
    for t in &lit.1 {
        let o = match *t {
            CTerm::Var(v) => args[v as usize],
            CTerm::Obj(o) => o,
        };
        if o == UNBOUND {
            return None;
        }
        key.push(o);
    }
    Some(key)
}

impl Search<'_, '_> {
    /// Whether method `m` under `binding`, with network `rest` after it, deletes a fact no
    /// action adds that a later primitive task needs (see the module docs).
    pub(super) fn consumes_needed(&self, m: u32, binding: &[u32], rest: u32) -> bool {
        let Some(k) = &self.consumed else {
            return false;
        };
        if !k.consumer[m as usize] {
            return false;
        }
        let c = self.c;
        let mut gone: Vec<Vec<u32>> = Vec::new();
        let mut args = Vec::new();
        let needed = |a: usize, args: &[u32], gone: &[Vec<u32>]| {
            k.needs[a]
                .iter()
                .filter_map(|l| ground(l, args))
                .any(|f| gone.contains(&f))
        };
        for (t, targs) in &c.methods[m as usize].subtasks {
            let Some(a) = c.tasks[*t as usize].action else {
                continue;
            };
            args.clear();
            args.extend(bound_terms(targs, binding));
            if needed(a as usize, &args, &gone) {
                return true;
            }
            gone.extend(k.dels[a as usize].iter().filter_map(|l| ground(l, &args)));
        }
        if gone.is_empty() {
            return false;
        }
        let mut cell = rest;
        while cell != NIL {
            let cl = &self.arena[cell as usize];
            let key = self.gtasks.key(cl.task);
            if let Some(a) = c.tasks[key[0] as usize].action
                && needed(a as usize, &key[1..], &gone)
            {
                return true;
            }
            cell = cl.next;
        }
        false
    }
}
