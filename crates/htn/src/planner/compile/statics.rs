//! Static predicates: those no action changes; and what effects change, which the pull-up
//! asks of every task.

use super::{CEffect, CFormula, Compiled};

/// Predicates no action adds or deletes (and that are not shared: geometry changes those).
pub(super) fn static_predicates(c: &Compiled) -> Vec<bool> {
    let mut changed = Changes {
        preds: c.shared_preds.clone(),
        fluents: false,
    };
    for a in &c.actions {
        changed.mark(&a.effects);
    }
    changed.preds.iter().map(|x| !x).collect()
}

/// The predicates (and whether any numeric fluent) some effects may change.
#[derive(Clone, PartialEq)]
pub(super) struct Changes {
    pub preds: Vec<bool>,
    pub fluents: bool,
}

impl Changes {
    /// Nothing changed, over `n` predicates.
    pub fn new(n: usize) -> Changes {
        Changes {
            preds: vec![false; n],
            fluents: false,
        }
    }

    pub fn union(&mut self, o: &Changes) {
        for (a, b) in self.preds.iter_mut().zip(&o.preds) {
            *a |= *b;
        }
        self.fluents |= o.fluents;
    }

    /// Marks what effects `effs` change.
    pub fn mark(&mut self, effs: &[CEffect]) {
        for e in effs {
            match e {
                CEffect::Add(p, _) | CEffect::Del(p, _) => self.preds[*p as usize] = true,
                CEffect::Forall(_, inner) | CEffect::When(_, inner) => self.mark(inner),
                CEffect::Num(..) => self.fluents = true,
            }
        }
    }

    /// Whether `f`'s truth may change: it reads a changed predicate or a fluent that may
    /// change.
    pub fn touches(&self, f: &CFormula) -> bool {
        match f {
            CFormula::True | CFormula::Eq(..) => false,
            CFormula::Atom(p, _) => self.preds[*p as usize],
            CFormula::Not(x) => self.touches(x),
            CFormula::And(xs) | CFormula::Or(xs) => xs.iter().any(|x| self.touches(x)),
            CFormula::Imply(a, b) => self.touches(a) || self.touches(b),
            CFormula::Compare(..) => self.fluents,
            CFormula::Exists(..) | CFormula::Forall(..) => true,
        }
    }
}
