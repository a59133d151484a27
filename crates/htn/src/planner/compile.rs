//! Compiles the lifted model into the planner's indexed form: every name interned to a `u32`,
//! variables turned into numbered slots, preconditions flattened into conjunctions of literals
//! with their free slots listed (the binder picks the next literal by what is bound), and the
//! methods of every task listed in domain order.
//!
//! The passes, in the order [`compile`] runs them, each in its own file:
//! - `names.rs`: types, objects and tasks interned (each type with its objects);
//! - `lower.rs`: actions, methods, the initial task network and the goal lowered over
//!   numbered slots;
//! - `statics.rs`: the predicates no action changes;
//! - `pull_up.rs`: precondition pull-up (methods gain what their subtasks require);
//! - `late.rs`: parameters (of methods and of the initial task network) bound late, by the
//!   method of the one subtask that uses them;
//! - `goals.rs`: the goal's literals and their landmarks (`landmarks.rs`), and what each
//!   task may achieve of them.

use std::collections::HashMap;

use crate::model::{ArithOp, CompareOp, Domain, NumericEffectOp, Problem};

use super::PlanError;
use crate::budget::Watch;

mod goals;
mod landmarks;
mod late;
mod lower;
mod names;
mod pull_up;
mod statics;

use goals::goal_relevance;
use late::bind_late;
use lower::Scope;
pub(crate) use lower::free_vars;
use pull_up::pull_up;
use statics::static_predicates;

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
    /// The parameters the search binds when it applies the method: all of them but those left
    /// to the one subtask that uses them (`late.rs`), which stay unbound in the subtask until
    /// one of its methods binds them.
    pub bind: Vec<u16>,
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
    /// For a landmark, the literals that need it (each of their achievers requires it);
    /// empty for a literal of the goal itself.
    pub goal_parent: Vec<Vec<usize>>,
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
    bind_late(&mut b.c);
    goal_relevance(&mut b.c, watch);
    Ok(b.c)
}
