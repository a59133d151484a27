//! Goal relevance at compile time: the goal's ground literals (and landmarks), and per task
//! which of them it may achieve; the search prunes networks that can no longer achieve a
//! false goal literal.

use super::{CAction, CEffect, CFormula, CTerm, Compiled};

/// At most this many goal literals and landmarks are tracked.
pub(super) const MAX_GOAL_LITS: usize = 4096;

/// The goal's ground top-level literals and, per task, which of them the task may achieve
/// (an over-approximation through all its methods): a node whose remaining task network can
/// achieve no false goal literal is a dead end.
pub(super) fn goal_relevance(c: &mut Compiled) {
    let mut lits = Vec::new();
    let top: Vec<&CFormula> = match &c.goal {
        CFormula::And(xs) => xs.iter().collect(),
        f => vec![f],
    };
    for f in top {
        let (atom, positive) = match f {
            CFormula::Not(x) => (&**x, false),
            f => (f, true),
        };
        if let CFormula::Atom(p, args) = atom
            && lits.len() < MAX_GOAL_LITS
        {
            let mut key = vec![*p];
            let mut ground = true;
            for a in args {
                match a {
                    CTerm::Obj(o) => key.push(*o),
                    CTerm::Var(_) => ground = false,
                }
            }
            if ground && !lits.contains(&(key.clone(), positive)) {
                lits.push((key, positive));
            }
        }
    }
    // Landmarks: when a positive literal has a single achiever, an action without parameters,
    // that action's ground positive preconditions must hold at some point before it.
    let mut parent: Vec<Option<usize>> = vec![None; lits.len()];
    let mut i = 0;
    while i < lits.len() {
        if lits[i].1 {
            let p = lits[i].0[0];
            let achievers: Vec<&CAction> = c
                .actions
                .iter()
                .filter(|a| {
                    adds_pred(&a.effects, p)
                        || (a.evaluable.is_some() && c.shared_preds[p as usize])
                })
                .collect();
            if let [a] = achievers[..]
                && a.n_params == 0
            {
                for l in &a.pre {
                    if let CFormula::Atom(q, args) = &l.f
                        && lits.len() < MAX_GOAL_LITS
                    {
                        let mut key = vec![*q];
                        if args.iter().all(|t| match t {
                            CTerm::Obj(o) => {
                                key.push(*o);
                                true
                            }
                            CTerm::Var(_) => false,
                        }) && !lits.iter().any(|(k, pos)| *pos && *k == key)
                        {
                            lits.push((key, true));
                            parent.push(Some(i));
                        }
                    }
                }
            }
        }
        i += 1;
    }
    pub(super) fn adds_pred(effs: &[CEffect], p: u32) -> bool {
        effs.iter().any(|e| match e {
            CEffect::Add(q, _) => *q == p,
            CEffect::Forall(_, inner) | CEffect::When(_, inner) => adds_pred(inner, p),
            _ => false,
        })
    }
    pub(super) fn effect_mask(effs: &[CEffect], lits: &[(Vec<u32>, bool)], m: &mut [u64]) {
        for e in effs {
            match e {
                CEffect::Add(p, _) | CEffect::Del(p, _) => {
                    let add = matches!(e, CEffect::Add(..));
                    for (i, (k, pos)) in lits.iter().enumerate() {
                        if k[0] == *p && *pos == add {
                            m[i / 64] |= 1 << (i % 64);
                        }
                    }
                }
                CEffect::Forall(_, inner) | CEffect::When(_, inner) => effect_mask(inner, lits, m),
                CEffect::Num(..) => {}
            }
        }
    }
    let words = lits.len().div_ceil(64);
    let mut mask = vec![vec![0u64; words]; c.tasks.len()];
    for (t, task) in c.tasks.iter().enumerate() {
        if let Some(a) = task.action {
            let act = &c.actions[a as usize];
            effect_mask(&act.effects, &lits, &mut mask[t]);
            if act.evaluable.is_some() {
                for (i, (k, _)) in lits.iter().enumerate() {
                    if c.shared_preds[k[0] as usize] {
                        mask[t][i / 64] |= 1 << (i % 64);
                    }
                }
            }
        }
    }
    loop {
        let mut changed = false;
        for t in 0..c.tasks.len() {
            let mut m = mask[t].clone();
            for &mi in &c.tasks[t].methods {
                for (st, _) in &c.methods[mi as usize].subtasks {
                    for (w, x) in m.iter_mut().zip(&mask[*st as usize]) {
                        *w |= x;
                    }
                }
            }
            if m != mask[t] {
                mask[t] = m;
                changed = true;
            }
        }
        if !changed {
            break;
        }
    }
    c.goal_lits = lits;
    c.goal_parent = parent;
    c.task_goal_mask = mask;
}
