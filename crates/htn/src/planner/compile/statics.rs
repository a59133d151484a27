//! Static predicates: those no action changes.

use super::{CEffect, Compiled};

/// Predicates no action adds or deletes (and that are not shared: geometry changes those).
pub(super) fn static_predicates(c: &Compiled) -> Vec<bool> {
    pub(super) fn mark(effs: &[CEffect], changed: &mut [bool]) {
        for e in effs {
            match e {
                CEffect::Add(p, _) | CEffect::Del(p, _) => changed[*p as usize] = true,
                CEffect::Forall(_, inner) | CEffect::When(_, inner) => mark(inner, changed),
                CEffect::Num(..) => {}
            }
        }
    }
    let mut changed = c.shared_preds.clone();
    for a in &c.actions {
        mark(&a.effects, &mut changed);
    }
    changed.iter().map(|x| !x).collect()
}
