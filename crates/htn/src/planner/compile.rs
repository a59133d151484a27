//! Compiles the lifted model into the planner's indexed form: every name interned to a `u32`,
//! variables turned into numbered slots, preconditions flattened into conjunctions of literals
//! with their free slots listed (the binder picks the next literal by what is bound), and the
//! methods of every task listed in domain order.

use std::collections::{HashMap, HashSet};

use crate::model::{
    ArithOp, CompareOp, Domain, Effect, Formula, NumExpr, NumericEffectOp, OBJECT_TYPE, Problem,
    Subtask, Term, TypedName,
};

use super::{Limit, PlanError};
use crate::budget::Watch;

/// A slot (variable) or an object.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum CTerm {
    Var(u16),
    Obj(u32),
}

/// A numeric expression over slots.
#[derive(Clone, Debug, PartialEq)]
pub(crate) enum CNum {
    Number(f64),
    Fluent(u32, Vec<CTerm>),
    Bin(ArithOp, Box<CNum>, Box<CNum>),
    Neg(Box<CNum>),
}

/// A condition over slots.
#[derive(Clone, Debug, PartialEq)]
pub(crate) enum CFormula {
    True,
    Atom(u32, Vec<CTerm>),
    Eq(CTerm, CTerm),
    Not(Box<CFormula>),
    And(Vec<CFormula>),
    Or(Vec<CFormula>),
    Imply(Box<CFormula>, Box<CFormula>),
    /// Quantified slots with their types, and the body as a conjunction of literals.
    Exists(Vec<(u16, u32)>, Vec<CLit>),
    Forall(Vec<(u16, u32)>, Box<CFormula>),
    Compare(CompareOp, CNum, CNum),
}

/// A conjunct with the slots it reads that are free in it (bound outside it).
#[derive(Clone, Debug, PartialEq)]
pub(crate) struct CLit {
    pub f: CFormula,
    pub vars: Vec<u16>,
}

/// An effect over slots.
#[derive(Clone, Debug)]
pub(crate) enum CEffect {
    Add(u32, Vec<CTerm>),
    Del(u32, Vec<CTerm>),
    Forall(Vec<(u16, u32)>, Vec<CEffect>),
    When(CFormula, Vec<CEffect>),
    Num(NumericEffectOp, u32, Vec<CTerm>, CNum),
}

/// A compiled action.
#[derive(Clone, Debug)]
pub(crate) struct CAction {
    pub name: String,
    pub n_params: usize,
    pub slot_types: Vec<u32>,
    /// The precondition without its evaluable predicate.
    pub pre: Vec<CLit>,
    /// The geometric task asked about, if this is a GS action.
    pub evaluable: Option<(u32, Vec<CTerm>)>,
    pub effects: Vec<CEffect>,
}

/// A compiled method.
#[derive(Clone, Debug)]
pub(crate) struct CMethod {
    pub name: String,
    pub task: u32,
    pub task_args: Vec<CTerm>,
    pub n_params: usize,
    /// The parameter slots, `0..n_params`.
    pub params: Vec<u16>,
    pub slot_types: Vec<u32>,
    /// Precondition and constraints as one conjunction.
    pub pre: Vec<CLit>,
    pub subtasks: Vec<(u32, Vec<CTerm>)>,
}

/// A task or action name.
#[derive(Clone, Debug)]
pub(crate) struct CTask {
    pub name: String,
    /// The action, if primitive.
    pub action: Option<u32>,
    /// Its methods, in domain order.
    pub methods: Vec<u32>,
}

/// The whole compiled domain and problem.
#[derive(Clone, Debug)]
pub(crate) struct Compiled {
    pub objects: Vec<String>,
    pub object_ids: HashMap<String, u32>,
    pub type_objects: Vec<Vec<u32>>,
    /// Per type, a membership bitmap over objects.
    pub type_member: Vec<Vec<bool>>,
    pub preds: Vec<String>,
    pub pred_ids: HashMap<String, u32>,
    pub shared_preds: Vec<bool>,
    pub funcs: Vec<String>,
    pub func_ids: HashMap<String, u32>,
    pub tasks: Vec<CTask>,
    pub task_ids: HashMap<String, u32>,
    pub geo_tasks: Vec<String>,
    pub actions: Vec<CAction>,
    pub methods: Vec<CMethod>,
    pub init_facts: Vec<(u32, Vec<u32>)>,
    pub init_values: Vec<(u32, Vec<u32>, f64)>,
    /// The initial task network as a method of no task (index into `methods`).
    pub root_method: u32,
    pub goal: CFormula,
    pub goal_slot_types: Vec<u32>,
    /// Predicates no action changes.
    pub static_preds: Vec<bool>,
    /// Ground literals of the goal's top-level conjunction and their landmarks: fact key and
    /// sign (each once).
    pub goal_lits: Vec<(Vec<u32>, bool)>,
    /// For a landmark, the literal that needs it (its only achiever requires it).
    pub goal_parent: Vec<Option<usize>>,
    /// Per task, the goal literals (bits of `goal_lits`) it may make true.
    pub task_goal_mask: Vec<Vec<u64>>,
}

impl Compiled {
    /// Whether object `o` is of type `t`.
    #[inline]
    pub fn is_of(&self, o: u32, t: u32) -> bool {
        self.type_member[t as usize][o as usize]
    }
}

struct Builder<'a> {
    c: Compiled,
    type_ids: HashMap<String, u32>,
    domain: &'a Domain,
}

/// Compiles a domain and problem; `Err` names what the model got wrong (the parser normally
/// catches these first).
pub(crate) fn compile(
    domain: &Domain,
    problem: &Problem,
    watch: &mut Watch,
) -> Result<Compiled, PlanError> {
    let mut b = Builder {
        c: Compiled {
            objects: Vec::new(),
            object_ids: HashMap::new(),
            type_objects: Vec::new(),
            type_member: Vec::new(),
            preds: Vec::new(),
            pred_ids: HashMap::new(),
            shared_preds: Vec::new(),
            funcs: Vec::new(),
            func_ids: HashMap::new(),
            tasks: Vec::new(),
            task_ids: HashMap::new(),
            geo_tasks: Vec::new(),
            actions: Vec::new(),
            methods: Vec::new(),
            init_facts: Vec::new(),
            init_values: Vec::new(),
            root_method: 0,
            goal: CFormula::True,
            goal_slot_types: Vec::new(),
            static_preds: Vec::new(),
            goal_lits: Vec::new(),
            goal_parent: Vec::new(),
            task_goal_mask: Vec::new(),
        },
        type_ids: HashMap::new(),
        domain,
    };
    b.types_and_objects(problem, watch)?;
    for (shared, list) in [
        (false, &domain.predicates),
        (true, &domain.shared_predicates),
    ] {
        for p in list {
            if !b.c.pred_ids.contains_key(&p.name) {
                b.c.pred_ids.insert(p.name.clone(), b.c.preds.len() as u32);
                b.c.preds.push(p.name.clone());
                b.c.shared_preds.push(shared);
            }
        }
    }
    for f in &domain.functions {
        b.c.func_ids.insert(f.name.clone(), b.c.funcs.len() as u32);
        b.c.funcs.push(f.name.clone());
    }
    for g in &domain.geometric_tasks {
        b.c.geo_tasks.push(g.name.clone());
    }
    for t in &domain.tasks {
        b.add_task(&t.name, None);
    }
    for (i, a) in domain.actions.iter().enumerate() {
        b.add_task(&a.name, Some(i as u32));
    }
    for a in &domain.actions {
        let ca = b.action(a)?;
        b.c.actions.push(ca);
    }
    for m in &domain.methods {
        let cm = b.method(
            &m.name,
            Some((&m.task, &m.task_args)),
            &m.params,
            &[&m.precondition, &m.constraints],
            &m.subtasks,
        )?;
        let idx = b.c.methods.len() as u32;
        let t = cm.task;
        b.c.methods.push(cm);
        b.c.tasks[t as usize].methods.push(idx);
    }
    let root = b.method(
        "__root",
        None,
        &problem.htn.params,
        &[&problem.htn.constraints],
        &problem.htn.subtasks,
    )?;
    b.c.root_method = b.c.methods.len() as u32;
    b.c.methods.push(root);
    for (k, f) in problem.init.iter().enumerate() {
        if k % 4096 == 4095
            && let Some(limit) = watch.check()
        {
            return Err(PlanError::Stopped(limit));
        }
        let p = b.pred(&f.predicate)?;
        let args = f
            .args
            .iter()
            .map(|a| b.object(a))
            .collect::<Result<Vec<_>, _>>()?;
        b.c.init_facts.push((p, args));
    }
    for v in &problem.init_values {
        let f =
            *b.c.func_ids
                .get(&v.function)
                .ok_or_else(|| PlanError::Model(format!("unknown function `{}`", v.function)))?;
        let args = v
            .args
            .iter()
            .map(|a| b.object(a))
            .collect::<Result<Vec<_>, _>>()?;
        b.c.init_values.push((f, args, v.value));
    }
    let mut scope = Scope::default();
    let goal = b.formula(&problem.goal, &mut scope)?;
    b.c.goal = goal;
    b.c.goal_slot_types = scope.types;
    b.c.static_preds = static_predicates(&b.c);
    pull_up(&mut b.c);
    goal_relevance(&mut b.c);
    Ok(b.c)
}

/// Variables in scope while compiling a formula: name to slot, and each slot's type.
#[derive(Default)]
struct Scope {
    names: Vec<(String, u16)>,
    types: Vec<u32>,
}

impl Scope {
    fn push(&mut self, name: &str, ty: u32) -> u16 {
        let slot = self.types.len() as u16;
        self.types.push(ty);
        self.names.push((name.to_string(), slot));
        slot
    }
    fn lookup(&self, name: &str) -> Option<u16> {
        self.names
            .iter()
            .rev()
            .find(|(n, _)| n == name)
            .map(|(_, s)| *s)
    }
}

impl Builder<'_> {
    fn type_id(&mut self, name: &str) -> u32 {
        if let Some(&t) = self.type_ids.get(name) {
            return t;
        }
        let t = self.c.type_objects.len() as u32;
        self.type_ids.insert(name.to_string(), t);
        self.c.type_objects.push(Vec::new());
        t
    }

    fn types_and_objects(&mut self, problem: &Problem, watch: &mut Watch) -> Result<(), PlanError> {
        self.type_id(OBJECT_TYPE);
        let mut parents: HashMap<String, Vec<String>> = HashMap::new();
        for t in &self.domain.types {
            self.type_id(&t.name);
            parents
                .entry(t.name.clone())
                .or_default()
                .extend(t.parents.iter().cloned());
        }
        let all: Vec<&TypedName> = self
            .domain
            .constants
            .iter()
            .chain(problem.objects.iter())
            .collect();
        // (type, object) pairs recorded: a linear `contains` per object was quadratic (160k
        // objects of one type took seconds, past any time limit).
        let mut member: HashSet<(usize, u32)> = HashSet::new();
        for (k, o) in all.into_iter().enumerate() {
            if k % 4096 == 4095
                && let Some(limit) = watch.check()
            {
                return Err(PlanError::Stopped(limit));
            }
            let id = match self.c.object_ids.get(&o.name) {
                Some(&id) => id,
                None => {
                    let id = self.c.objects.len() as u32;
                    self.c.objects.push(o.name.clone());
                    self.c.object_ids.insert(o.name.clone(), id);
                    id
                }
            };
            // The object is of its type and of every ancestor.
            let mut todo = vec![o.ty.clone(), OBJECT_TYPE.to_string()];
            let mut seen: Vec<String> = Vec::new();
            while let Some(t) = todo.pop() {
                if seen.contains(&t) {
                    continue;
                }
                let tid = self.type_id(&t) as usize;
                if member.insert((tid, id)) {
                    self.c.type_objects[tid].push(id);
                }
                if let Some(ps) = parents.get(&t) {
                    todo.extend(ps.iter().cloned());
                }
                seen.push(t);
            }
        }
        // One flag per (type, object): bounded by the memory limit, not assumed small (10,000
        // types and a million objects would be 10 GB).
        let cells = (self.c.type_objects.len() as u64).saturating_mul(self.c.objects.len() as u64);
        if !watch.fits(cells) {
            return Err(PlanError::Stopped(Limit::Memory));
        }
        self.rebuild_membership();
        Ok(())
    }

    fn rebuild_membership(&mut self) {
        let n = self.c.objects.len();
        self.c.type_member = self
            .c
            .type_objects
            .iter()
            .map(|objs| {
                let mut m = vec![false; n];
                for &o in objs {
                    m[o as usize] = true;
                }
                m
            })
            .collect();
    }

    fn ty(&mut self, name: &str) -> u32 {
        let t = self.type_id(name);
        if t as usize >= self.c.type_member.len() {
            self.rebuild_membership();
        }
        t
    }

    fn add_task(&mut self, name: &str, action: Option<u32>) {
        if let Some(&t) = self.c.task_ids.get(name) {
            if action.is_some() {
                self.c.tasks[t as usize].action = action;
            }
            return;
        }
        self.c
            .task_ids
            .insert(name.to_string(), self.c.tasks.len() as u32);
        self.c.tasks.push(CTask {
            name: name.to_string(),
            action,
            methods: Vec::new(),
        });
    }

    fn pred(&self, name: &str) -> Result<u32, PlanError> {
        self.c
            .pred_ids
            .get(name)
            .copied()
            .ok_or_else(|| PlanError::Model(format!("unknown predicate `{name}`")))
    }

    fn object(&self, name: &str) -> Result<u32, PlanError> {
        self.c
            .object_ids
            .get(name)
            .copied()
            .ok_or_else(|| PlanError::Model(format!("unknown object `{name}`")))
    }

    fn term(&self, t: &Term, scope: &Scope) -> Result<CTerm, PlanError> {
        match t {
            Term::Var(v) => scope
                .lookup(v)
                .map(CTerm::Var)
                .ok_or_else(|| PlanError::Model(format!("unknown variable `{v}`"))),
            Term::Const(c) => self.object(c).map(CTerm::Obj),
        }
    }

    fn terms(&self, ts: &[Term], scope: &Scope) -> Result<Vec<CTerm>, PlanError> {
        ts.iter().map(|t| self.term(t, scope)).collect()
    }

    fn params(&mut self, params: &[TypedName], scope: &mut Scope) -> Vec<(u16, u32)> {
        params
            .iter()
            .map(|p| {
                let t = self.ty(&p.ty);
                (scope.push(&p.name, t), t)
            })
            .collect()
    }

    fn num(&self, e: &NumExpr, scope: &Scope) -> Result<CNum, PlanError> {
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

    fn formula(&mut self, f: &Formula, scope: &mut Scope) -> Result<CFormula, PlanError> {
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
    fn conjuncts(&self, f: CFormula) -> Vec<CLit> {
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

    fn effect(&mut self, e: &Effect, scope: &mut Scope) -> Result<CEffect, PlanError> {
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

    fn action(&mut self, a: &crate::model::Action) -> Result<CAction, PlanError> {
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

    fn method(
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
            slot_types: scope.types,
            pre,
            subtasks: subs,
        })
    }
}

fn flatten(f: CFormula, out: &mut Vec<CFormula>) {
    match f {
        CFormula::And(xs) => xs.into_iter().for_each(|x| flatten(x, out)),
        CFormula::True => {}
        f => out.push(f),
    }
}

fn term_var(t: &CTerm, out: &mut Vec<u16>) {
    if let CTerm::Var(v) = t {
        out.push(*v);
    }
}

fn num_vars(e: &CNum, out: &mut Vec<u16>) {
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

/// Predicates no action adds or deletes (and that are not shared: geometry changes those).
fn static_predicates(c: &Compiled) -> Vec<bool> {
    fn mark(effs: &[CEffect], changed: &mut [bool]) {
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

/// Precondition pull-up. A method's precondition gains what its subtasks certainly require:
/// - from its first subtask, everything quantifier-free that subtask requires in the state
///   where it starts (that is the state the method's precondition is evaluated in): an
///   action's precondition, or the precondition of an abstract task's only method;
/// - from every other subtask, the static literals it requires (static facts hold or fail for
///   the whole plan).
///
/// What an abstract task requires is what all its methods require over the task's arguments
/// (the literals common to every method: the only method's whole precondition, or, say, the
/// `(not (isOccupied ?p))` that every way of connecting a port needs), so requirements climb
/// through the hierarchy; this runs to a fixpoint. All of it is sound and loses no plan; it
/// prunes bindings early and lets the binder bind through the pulled atoms.
fn pull_up(c: &mut Compiled) {
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
            for (i, (t, args)) in c.methods[mi].subtasks.iter().enumerate() {
                if let Some(a) = c.tasks[*t as usize].action
                    && c.actions[a as usize].evaluable.is_some()
                    && i > 0
                {
                    continue;
                }
                for (f, st) in &req[*t as usize] {
                    if (i == 0 || *st)
                        && let Some(f) = rename(f, args)
                    {
                        extra.push(f);
                    }
                }
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
fn method_requires(m: &CMethod, is_static: &dyn Fn(&CFormula) -> bool) -> Vec<(CFormula, bool)> {
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

fn quantifier_free(f: &CFormula) -> bool {
    match f {
        CFormula::True | CFormula::Atom(..) | CFormula::Eq(..) | CFormula::Compare(..) => true,
        CFormula::Not(x) => quantifier_free(x),
        CFormula::And(xs) | CFormula::Or(xs) => xs.iter().all(quantifier_free),
        CFormula::Imply(a, b) => quantifier_free(a) && quantifier_free(b),
        CFormula::Exists(..) | CFormula::Forall(..) => false,
    }
}

/// `f` over an action's parameter slots, rewritten over the method's terms `args`.
fn rename(f: &CFormula, args: &[CTerm]) -> Option<CFormula> {
    let t = |x: &CTerm| -> Option<CTerm> {
        match *x {
            CTerm::Var(v) => args.get(v as usize).copied(),
            o => Some(o),
        }
    };
    let ts = |xs: &[CTerm]| -> Option<Vec<CTerm>> { xs.iter().map(t).collect() };
    fn num(e: &CNum, args: &[CTerm]) -> Option<CNum> {
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

/// At most this many goal literals and landmarks are tracked.
const MAX_GOAL_LITS: usize = 4096;

/// The goal's ground top-level literals and, per task, which of them the task may achieve
/// (an over-approximation through all its methods): a node whose remaining task network can
/// achieve no false goal literal is a dead end.
fn goal_relevance(c: &mut Compiled) {
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
    fn adds_pred(effs: &[CEffect], p: u32) -> bool {
        effs.iter().any(|e| match e {
            CEffect::Add(q, _) => *q == p,
            CEffect::Forall(_, inner) | CEffect::When(_, inner) => adds_pred(inner, p),
            _ => false,
        })
    }
    fn effect_mask(effs: &[CEffect], lits: &[(Vec<u32>, bool)], m: &mut [u64]) {
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
