//! Goal relevance at compile time: the goal's ground literals (and landmarks), and per task
//! which of them it may achieve; the search prunes networks that can no longer achieve a
//! false goal literal.

use super::landmarks::Achievers;
use super::{CEffect, CFormula, CTerm, Compiled};
use crate::budget::Watch;

/// At most this many goal literals and landmarks are tracked.
pub(super) const MAX_GOAL_LITS: usize = 4096;
/// Landmarks of landmarks are looked for down to this depth below a goal literal (Monroe's
/// progress literals `l1`..`l8` form a chain).
const LANDMARK_DEPTH: usize = 64;

/// The goal's ground top-level literals and, per task, which of them the task may achieve
/// (an over-approximation through all its methods): a node whose remaining task network can
/// achieve no false goal literal is a dead end.
pub(super) fn goal_relevance(c: &mut Compiled, watch: &Watch) {
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
    // Landmarks: what every achiever of a literal requires (`landmarks.rs`), and theirs.
    let mut parent: Vec<Vec<usize>> = vec![Vec::new(); lits.len()];
    let mut depth = vec![0; lits.len()];
    let achievers = Achievers::new(c);
    let mut i = 0;
    // Landmarks only prune: at a limit the search starts without the rest (and stops at once).
    while i < lits.len() && watch.check().is_none() {
        if depth[i] < LANDMARK_DEPTH {
            for l in achievers.landmarks(c, &lits[i]) {
                match lits.iter().position(|x| *x == l) {
                    // Already a goal literal: needed whenever false.
                    Some(j) if parent[j].is_empty() => {}
                    // A parent always comes before its landmark (no cycles).
                    Some(j) if j <= i => {}
                    Some(j) if !parent[j].contains(&i) => parent[j].push(i),
                    Some(_) => {}
                    None if lits.len() < MAX_GOAL_LITS => {
                        lits.push(l);
                        parent.push(vec![i]);
                        depth.push(depth[i] + 1);
                    }
                    None => {}
                }
            }
        }
        i += 1;
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
