//! Precondition pull-up: methods' preconditions gain what their subtasks certainly require,
//! so that bindings fail early and bind through static facts.

use super::statics::Changes;
use super::{CFormula, CLit, CMethod, CNum, CTerm, Compiled, free_vars};

/// Precondition pull-up. A method's precondition gains what its subtasks certainly require:
/// from each subtask, every quantifier-free literal it requires in the state where it starts
/// (an action's precondition, or the precondition of an abstract task's only method) over
/// predicates that no subtask before it may change. The first subtask starts in the state
/// the method's precondition is evaluated in; a later one starts in a state that agrees with
/// it on every predicate its predecessors' decompositions leave alone (static facts, and in
/// the learned domains, say, a card's place across the unlocking steps before the move).
///
/// What an abstract task requires is what all its methods require over the task's arguments
/// (the literals common to every method: the only method's whole precondition, or, say, the
/// `(not (isOccupied ?p))` that every way of connecting a port needs), so requirements climb
/// through the hierarchy; this runs to a fixpoint. All of it is sound and loses no plan; it
/// prunes bindings early and lets the binder bind through the pulled atoms.
pub(super) fn pull_up(c: &mut Compiled) {
    let stat = c.static_preds.clone();
    let is_static = |f: &CFormula| -> bool {
        match f {
            CFormula::Atom(p, _) => stat[*p as usize],
            CFormula::Eq(..) => true,
            CFormula::Not(x) => match &**x {
                CFormula::Atom(p, _) => stat[*p as usize],
                CFormula::Eq(..) => true,
                _ => false,
            },
            _ => false,
        }
    };
    let changes = may_change(c);
    for _round in 0..6 {
        // What each task requires, over its argument positions: (literal, static).
        let mut req: Vec<Vec<(CFormula, bool)>> = vec![Vec::new(); c.tasks.len()];
        for (t, task) in c.tasks.iter().enumerate() {
            if let Some(a) = task.action {
                let act = &c.actions[a as usize];
                for lit in &act.pre {
                    if lit.vars.iter().all(|&v| (v as usize) < act.n_params)
                        && quantifier_free(&lit.f)
                    {
                        req[t].push((lit.f.clone(), is_static(&lit.f)));
                    }
                }
            } else if !task.methods.is_empty() {
                // A task requires what every one of its methods requires over its arguments.
                let mut common: Option<Vec<(CFormula, bool)>> = None;
                for &m in &task.methods {
                    let mine = method_requires(&c.methods[m as usize], &is_static);
                    common = Some(match common {
                        None => mine,
                        Some(prev) => prev.into_iter().filter(|x| mine.contains(x)).collect(),
                    });
                    if common.as_ref().is_some_and(Vec::is_empty) {
                        break;
                    }
                }
                req[t] = common.unwrap_or_default();
            }
        }
        let mut changed = false;
        for mi in 0..c.methods.len() {
            let mut extra: Vec<CFormula> = Vec::new();
            // What the subtasks before the current one may change.
            let mut before = Changes::new(c.preds.len());
            for (i, (t, args)) in c.methods[mi].subtasks.iter().enumerate() {
                let evaluable = c.tasks[*t as usize]
                    .action
                    .is_some_and(|a| c.actions[a as usize].evaluable.is_some());
                if !(evaluable && i > 0) {
                    for (f, st) in &req[*t as usize] {
                        if (*st || !before.touches(f))
                            && let Some(f) = rename(f, args)
                        {
                            extra.push(f);
                        }
                    }
                }
                before.union(&changes[*t as usize]);
            }
            let m = &mut c.methods[mi];
            for f in extra {
                if m.pre.iter().any(|l| l.f == f) {
                    continue;
                }
                let mut vars = Vec::new();
                free_vars(&f, &mut vars);
                vars.sort_unstable();
                vars.dedup();
                m.pre.push(CLit { f, vars });
                changed = true;
            }
        }
        if !changed {
            break;
        }
    }
}

/// What method `m`'s precondition requires over its task's argument positions (the
/// quantifier-free literals over slots that are task arguments), with their static flag.
pub(super) fn method_requires(
    m: &CMethod,
    is_static: &dyn Fn(&CFormula) -> bool,
) -> Vec<(CFormula, bool)> {
    // Slot to argument position.
    let pos: Vec<CTerm> = (0..m.slot_types.len())
        .map(|s| {
            m.task_args
                .iter()
                .position(|t| *t == CTerm::Var(s as u16))
                .map_or(CTerm::Obj(u32::MAX), |k| CTerm::Var(k as u16))
        })
        .collect();
    let mut out = Vec::new();
    for lit in &m.pre {
        if !quantifier_free(&lit.f)
            || lit
                .vars
                .iter()
                .any(|&v| pos[v as usize] == CTerm::Obj(u32::MAX))
        {
            continue;
        }
        if let Some(f) = rename(&lit.f, &pos)
            && !out.iter().any(|(g, _)| *g == f)
        {
            out.push((f, is_static(&lit.f)));
        }
    }
    out
}

pub(super) fn quantifier_free(f: &CFormula) -> bool {
    match f {
        CFormula::True | CFormula::Atom(..) | CFormula::Eq(..) | CFormula::Compare(..) => true,
        CFormula::Not(x) => quantifier_free(x),
        CFormula::And(xs) | CFormula::Or(xs) => xs.iter().all(quantifier_free),
        CFormula::Imply(a, b) => quantifier_free(a) && quantifier_free(b),
        CFormula::Exists(..) | CFormula::Forall(..) => false,
    }
}

/// `f` over an action's parameter slots, rewritten over the method's terms `args`.
pub(super) fn rename(f: &CFormula, args: &[CTerm]) -> Option<CFormula> {
    let t = |x: &CTerm| -> Option<CTerm> {
        match *x {
            CTerm::Var(v) => args.get(v as usize).copied(),
            o => Some(o),
        }
    };
    let ts = |xs: &[CTerm]| -> Option<Vec<CTerm>> { xs.iter().map(t).collect() };
    pub(super) fn num(e: &CNum, args: &[CTerm]) -> Option<CNum> {
        Some(match e {
            CNum::Number(x) => CNum::Number(*x),
            CNum::Fluent(f, xs) => CNum::Fluent(
                *f,
                xs.iter()
                    .map(|x| match *x {
                        CTerm::Var(v) => args.get(v as usize).copied(),
                        o => Some(o),
                    })
                    .collect::<Option<_>>()?,
            ),
            CNum::Bin(op, a, b) => CNum::Bin(*op, Box::new(num(a, args)?), Box::new(num(b, args)?)),
            CNum::Neg(a) => CNum::Neg(Box::new(num(a, args)?)),
        })
    }
    Some(match f {
        CFormula::True => CFormula::True,
        CFormula::Atom(p, xs) => CFormula::Atom(*p, ts(xs)?),
        CFormula::Eq(a, b) => CFormula::Eq(t(a)?, t(b)?),
        CFormula::Not(x) => CFormula::Not(Box::new(rename(x, args)?)),
        CFormula::And(xs) => {
            CFormula::And(xs.iter().map(|x| rename(x, args)).collect::<Option<_>>()?)
        }
        CFormula::Or(xs) => {
            CFormula::Or(xs.iter().map(|x| rename(x, args)).collect::<Option<_>>()?)
        }
        CFormula::Imply(a, b) => {
            CFormula::Imply(Box::new(rename(a, args)?), Box::new(rename(b, args)?))
        }
        CFormula::Compare(op, a, b) => CFormula::Compare(*op, num(a, args)?, num(b, args)?),
        CFormula::Exists(..) | CFormula::Forall(..) => return None,
    })
}

/// Per task, what its decompositions may change: an action its effects (an evaluable one
/// also every shared predicate, which geometry sets), an abstract task what its methods'
/// subtasks may change (to a fixpoint).
fn may_change(c: &Compiled) -> Vec<Changes> {
    let n = c.preds.len();
    let mut out: Vec<Changes> = c
        .tasks
        .iter()
        .map(|t| {
            let mut ch = Changes::new(n);
            if let Some(a) = t.action {
                let act = &c.actions[a as usize];
                ch.mark(&act.effects);
                if act.evaluable.is_some() {
                    ch.union(&Changes {
                        preds: c.shared_preds.clone(),
                        fluents: false,
                    });
                }
            }
            ch
        })
        .collect();
    loop {
        let mut changed = false;
        for t in 0..c.tasks.len() {
            if c.tasks[t].action.is_some() {
                continue;
            }
            let mut ch = out[t].clone();
            for &m in &c.tasks[t].methods {
                for (st, _) in &c.methods[m as usize].subtasks {
                    ch.union(&out[*st as usize]);
                }
            }
            if ch != out[t] {
                out[t] = ch;
                changed = true;
            }
        }
        if !changed {
            return out;
        }
    }
}
