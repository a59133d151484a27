//! Lowering: formulas, effects, actions and methods over numbered slots, preconditions
//! flattened into conjunctions of literals with their free slots listed.

use crate::model::{Effect, Formula, NumExpr, Subtask, Term, TypedName};

use super::super::PlanError;
use super::{Builder, CAction, CEffect, CFormula, CLit, CMethod, CNum, CTerm};

/// Variables in scope while compiling a formula: name to slot, and each slot's type.
#[derive(Default)]
pub(super) struct Scope {
    names: Vec<(String, u16)>,
    pub(super) types: Vec<u32>,
}

impl Scope {
    pub(super) fn push(&mut self, name: &str, ty: u32) -> u16 {
        let slot = self.types.len() as u16;
        self.types.push(ty);
        self.names.push((name.to_string(), slot));
        slot
    }
    pub(super) fn lookup(&self, name: &str) -> Option<u16> {
        self.names
            .iter()
            .rev()
            .find(|(n, _)| n == name)
            .map(|(_, s)| *s)
    }
}

impl Builder<'_> {
    pub(super) fn term(&self, t: &Term, scope: &Scope) -> Result<CTerm, PlanError> {
        match t {
            Term::Var(v) => scope
                .lookup(v)
                .map(CTerm::Var)
                .ok_or_else(|| PlanError::Model(format!("unknown variable `{v}`"))),
            Term::Const(c) => self.object(c).map(CTerm::Obj),
        }
    }

    pub(super) fn terms(&self, ts: &[Term], scope: &Scope) -> Result<Vec<CTerm>, PlanError> {
        ts.iter().map(|t| self.term(t, scope)).collect()
    }

    pub(super) fn params(&mut self, params: &[TypedName], scope: &mut Scope) -> Vec<(u16, u32)> {
        params
            .iter()
            .map(|p| {
                let t = self.ty(&p.ty);
                (scope.push(&p.name, t), t)
            })
            .collect()
    }

    pub(super) fn num(&self, e: &NumExpr, scope: &Scope) -> Result<CNum, PlanError> {
        Ok(match e {
            NumExpr::Number(x) => CNum::Number(*x),
            NumExpr::Fluent(f) => {
                let id = *self.c.func_ids.get(&f.function).ok_or_else(|| {
                    PlanError::Model(format!("unknown function `{}`", f.function))
                })?;
                CNum::Fluent(id, self.terms(&f.args, scope)?)
            }
            NumExpr::Binary(op, a, b) => CNum::Bin(
                *op,
                Box::new(self.num(a, scope)?),
                Box::new(self.num(b, scope)?),
            ),
            NumExpr::Neg(a) => CNum::Neg(Box::new(self.num(a, scope)?)),
        })
    }

    pub(super) fn formula(
        &mut self,
        f: &Formula,
        scope: &mut Scope,
    ) -> Result<CFormula, PlanError> {
        Ok(match f {
            Formula::True => CFormula::True,
            Formula::Atom(a) => {
                CFormula::Atom(self.pred(&a.predicate)?, self.terms(&a.args, scope)?)
            }
            Formula::Equal(a, b, _) => CFormula::Eq(self.term(a, scope)?, self.term(b, scope)?),
            Formula::Not(x) => CFormula::Not(Box::new(self.formula(x, scope)?)),
            Formula::And(xs) => CFormula::And(
                xs.iter()
                    .map(|x| self.formula(x, scope))
                    .collect::<Result<_, _>>()?,
            ),
            Formula::Or(xs) => CFormula::Or(
                xs.iter()
                    .map(|x| self.formula(x, scope))
                    .collect::<Result<_, _>>()?,
            ),
            Formula::Imply(a, b) => CFormula::Imply(
                Box::new(self.formula(a, scope)?),
                Box::new(self.formula(b, scope)?),
            ),
            Formula::Exists(vars, body) => {
                let n = scope.names.len();
                let vs = self.params(vars, scope);
                let body = self.formula(body, scope)?;
                scope.names.truncate(n);
                CFormula::Exists(vs, self.conjuncts(body))
            }
            Formula::Forall(vars, body) => {
                let n = scope.names.len();
                let vs = self.params(vars, scope);
                let body = self.formula(body, scope)?;
                scope.names.truncate(n);
                CFormula::Forall(vs, Box::new(body))
            }
            Formula::Compare(op, a, b, _) => {
                CFormula::Compare(*op, self.num(a, scope)?, self.num(b, scope)?)
            }
            Formula::Evaluable { task, .. } => {
                return Err(PlanError::Model(format!(
                    "evaluable predicate `{task}` is allowed only in the top-level conjunction of an action's precondition"
                )));
            }
        })
    }

    /// Flattens nested `and`s into a list of literals with their free slots.
    pub(super) fn conjuncts(&self, f: CFormula) -> Vec<CLit> {
        let mut out = Vec::new();
        flatten(f, &mut out);
        out.into_iter()
            .map(|f| {
                let mut vars = Vec::new();
                free_vars(&f, &mut vars);
                vars.sort_unstable();
                vars.dedup();
                CLit { f, vars }
            })
            .collect()
    }

    pub(super) fn effect(&mut self, e: &Effect, scope: &mut Scope) -> Result<CEffect, PlanError> {
        Ok(match e {
            Effect::Add(a) => CEffect::Add(self.pred(&a.predicate)?, self.terms(&a.args, scope)?),
            Effect::Delete(a) => {
                CEffect::Del(self.pred(&a.predicate)?, self.terms(&a.args, scope)?)
            }
            Effect::Forall(vars, effs) => {
                let n = scope.names.len();
                let vs = self.params(vars, scope);
                let effs = effs
                    .iter()
                    .map(|e| self.effect(e, scope))
                    .collect::<Result<_, _>>()?;
                scope.names.truncate(n);
                CEffect::Forall(vs, effs)
            }
            Effect::When(c, effs) => CEffect::When(
                self.formula(c, scope)?,
                effs.iter()
                    .map(|e| self.effect(e, scope))
                    .collect::<Result<_, _>>()?,
            ),
            Effect::Numeric(op, f, e) => {
                let id = *self.c.func_ids.get(&f.function).ok_or_else(|| {
                    PlanError::Model(format!("unknown function `{}`", f.function))
                })?;
                CEffect::Num(*op, id, self.terms(&f.args, scope)?, self.num(e, scope)?)
            }
        })
    }

    pub(super) fn action(&mut self, a: &crate::model::Action) -> Result<CAction, PlanError> {
        let mut scope = Scope::default();
        self.params(&a.params, &mut scope);
        let mut evaluable = None;
        let mut rest = Vec::new();
        let top: Vec<&Formula> = match &a.precondition {
            Formula::And(xs) => xs.iter().collect(),
            f => vec![f],
        };
        for f in top {
            if let Formula::Evaluable { task, args, .. } = f {
                let g = self
                    .c
                    .geo_tasks
                    .iter()
                    .position(|g| g == task)
                    .ok_or_else(|| PlanError::Model(format!("unknown geometric task `{task}`")))?;
                evaluable = Some((g as u32, self.terms(args, &scope)?));
            } else {
                rest.push(self.formula(f, &mut scope)?);
            }
        }
        let pre = self.conjuncts(CFormula::And(rest));
        let effects = a
            .effects
            .iter()
            .map(|e| self.effect(e, &mut scope))
            .collect::<Result<_, _>>()?;
        Ok(CAction {
            name: a.name.clone(),
            n_params: a.params.len(),
            slot_types: scope.types,
            pre,
            evaluable,
            effects,
        })
    }

    pub(super) fn method(
        &mut self,
        name: &str,
        task: Option<(&String, &Vec<Term>)>,
        params: &[TypedName],
        conds: &[&Formula],
        subtasks: &[Subtask],
    ) -> Result<CMethod, PlanError> {
        let mut scope = Scope::default();
        self.params(params, &mut scope);
        let (task_id, task_args) = match task {
            Some((t, args)) => {
                let id = *self.c.task_ids.get(t).ok_or_else(|| {
                    PlanError::Model(format!("method `{name}`: unknown task `{t}`"))
                })?;
                (id, self.terms(args, &scope)?)
            }
            None => (u32::MAX, Vec::new()),
        };
        let mut pre = Vec::new();
        for c in conds {
            pre.push(self.formula(c, &mut scope)?);
        }
        let pre = self.conjuncts(CFormula::And(pre));
        let mut subs = Vec::new();
        for s in subtasks {
            let id = *self.c.task_ids.get(&s.name).ok_or_else(|| {
                PlanError::Model(format!("method `{name}`: unknown task `{}`", s.name))
            })?;
            subs.push((id, self.terms(&s.args, &scope)?));
        }
        Ok(CMethod {
            name: name.to_string(),
            task: task_id,
            task_args,
            n_params: params.len(),
            params: (0..params.len() as u16).collect(),
            bind: (0..params.len() as u16).collect(),
            slot_types: scope.types,
            pre,
            subtasks: subs,
        })
    }
}

pub(super) fn flatten(f: CFormula, out: &mut Vec<CFormula>) {
    match f {
        CFormula::And(xs) => xs.into_iter().for_each(|x| flatten(x, out)),
        CFormula::True => {}
        f => out.push(f),
    }
}

pub(super) fn term_var(t: &CTerm, out: &mut Vec<u16>) {
    if let CTerm::Var(v) = t {
        out.push(*v);
    }
}

pub(super) fn num_vars(e: &CNum, out: &mut Vec<u16>) {
    match e {
        CNum::Number(_) => {}
        CNum::Fluent(_, args) => args.iter().for_each(|t| term_var(t, out)),
        CNum::Bin(_, a, b) => {
            num_vars(a, out);
            num_vars(b, out);
        }
        CNum::Neg(a) => num_vars(a, out),
    }
}

/// The slots `f` reads that are not bound inside it.
pub(crate) fn free_vars(f: &CFormula, out: &mut Vec<u16>) {
    match f {
        CFormula::True => {}
        CFormula::Atom(_, args) => args.iter().for_each(|t| term_var(t, out)),
        CFormula::Eq(a, b) => {
            term_var(a, out);
            term_var(b, out);
        }
        CFormula::Not(x) => free_vars(x, out),
        CFormula::And(xs) | CFormula::Or(xs) => xs.iter().for_each(|x| free_vars(x, out)),
        CFormula::Imply(a, b) => {
            free_vars(a, out);
            free_vars(b, out);
        }
        CFormula::Exists(vs, body) => {
            let mut inner: Vec<u16> = Vec::new();
            body.iter().for_each(|l| inner.extend(&l.vars));
            out.extend(
                inner
                    .into_iter()
                    .filter(|v| !vs.iter().any(|(s, _)| s == v)),
            );
        }
        CFormula::Forall(vs, body) => {
            let mut inner = Vec::new();
            free_vars(body, &mut inner);
            out.extend(
                inner
                    .into_iter()
                    .filter(|v| !vs.iter().any(|(s, _)| s == v)),
            );
        }
        CFormula::Compare(_, a, b) => {
            num_vars(a, out);
            num_vars(b, out);
        }
    }
}
