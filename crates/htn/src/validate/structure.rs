//! The plan's structure: ids, the decomposition tree (every id used once, leaves in the
//! plan's order), the root against the initial task network, and each decomposition line
//! against a method of its task under one binding of the method's parameters.

use crate::model::{Domain, Problem, Term, TypedName};
use crate::plan::Plan;

use super::world::World;
use super::{Env, FastMap, FastSet, Fault, fault, within_budget};

/// The plan's ids and tree, checked.
pub(super) struct Tree<'p> {
    plan: &'p Plan,
    /// Action id to its position in the plan.
    action_at: FastMap<u32, usize>,
    /// Decomposed task id to its line.
    dec_of: FastMap<u32, usize>,
    /// (decomposition line, leaf position) in depth-first order: each method's precondition
    /// is checked before the action at that position.
    pub(super) dec_pos: Vec<(usize, usize)>,
}

impl<'p> Tree<'p> {
    /// Checks that ids are unique, every id is used exactly once in the tree rooted at
    /// `root`, and the leaves, left to right, are the plan's actions in order.
    pub(super) fn new(plan: &'p Plan) -> Result<Tree<'p>, Fault> {
        let mut action_at: FastMap<u32, usize> = FastMap::default();
        for (i, a) in plan.actions.iter().enumerate() {
            if action_at.insert(a.id, i).is_some() {
                return fault(format!("id {} is used by two actions", a.id));
            }
        }
        let mut dec_of: FastMap<u32, usize> = FastMap::default();
        for (i, d) in plan.decompositions.iter().enumerate() {
            if action_at.contains_key(&d.id) {
                return fault(format!(
                    "id {} is both an action and a decomposed task",
                    d.id
                ));
            }
            if dec_of.insert(d.id, i).is_some() {
                return fault(format!("task id {} is decomposed twice", d.id));
            }
        }

        // The tree: every id used exactly once, leaves in order.
        let mut used: FastSet<u32> = FastSet::default();
        let mut leaves: Vec<u32> = Vec::new();
        // (decomposition index, leaf position) in depth-first order.
        let mut dec_pos: Vec<(usize, usize)> = Vec::new();
        // Depth first, left to right, with an explicit stack (trees can be very deep).
        let mut todo: Vec<u32> = plan.root.iter().rev().copied().collect();
        while let Some(id) = todo.pop() {
            if used.len() % 4096 == 4095 {
                within_budget()?;
            }
            if !used.insert(id) {
                return fault(format!("id {id} occurs twice in the decomposition tree"));
            }
            if action_at.contains_key(&id) {
                leaves.push(id);
                continue;
            }
            let Some(&d) = dec_of.get(&id) else {
                return fault(format!(
                    "id {id} is neither an action nor a decomposed task"
                ));
            };
            dec_pos.push((d, leaves.len()));
            todo.extend(plan.decompositions[d].subtasks.iter().rev());
        }
        for a in &plan.actions {
            if !used.contains(&a.id) {
                return fault(format!(
                    "action {} ({}) is not reached from the root",
                    a.id, a.name
                ));
            }
        }
        for d in &plan.decompositions {
            if !used.contains(&d.id) {
                return fault(format!(
                    "decomposed task {} ({}) is not reached from the root",
                    d.id, d.task
                ));
            }
        }
        for (i, (&leaf, a)) in leaves.iter().zip(&plan.actions).enumerate() {
            if leaf != a.id {
                return fault(format!(
                    "the tree puts action {leaf} at position {} of the plan, but the plan lists action {} there",
                    i + 1,
                    a.id
                ));
            }
        }
        Ok(Tree {
            plan,
            action_at,
            dec_of,
            dec_pos,
        })
    }

    /// The name and arguments of an id.
    fn name_args(&self, id: u32) -> (&'p str, &'p [String]) {
        let plan = self.plan;
        if let Some(&i) = self.action_at.get(&id) {
            (&plan.actions[i].name, &plan.actions[i].args)
        } else {
            let d = &plan.decompositions[self.dec_of[&id]];
            (&d.task, &d.args)
        }
    }

    /// Checks the root against the problem's initial task network; returns the binding of
    /// the network's parameters (for its constraints).
    pub(super) fn check_root(&self, w: &World, problem: &Problem) -> Result<Env, Fault> {
        let plan = self.plan;
        let net = &problem.htn.subtasks;
        if net.len() != plan.root.len() {
            return fault(format!(
                "the root has {} tasks, the problem's initial task network {}",
                plan.root.len(),
                net.len()
            ));
        }
        let mut root_env: Env = Env::default();
        for (k, (st, &id)) in net.iter().zip(&plan.root).enumerate() {
            let (name, args) = self.name_args(id);
            if st.name != name || !unify(w, &mut root_env, &st.args, args, &problem.htn.params) {
                return fault(format!(
                    "root task {} is `{name}` with arguments {args:?}, but task {} of the initial network is ({} {})",
                    id,
                    k + 1,
                    st.name,
                    show_terms(&st.args)
                ));
            }
        }
        Ok(root_env)
    }

    /// Checks every decomposition line against a method of its task; returns each line's
    /// binding of the method's parameters.
    pub(super) fn check_decompositions(
        &self,
        w: &World,
        domain: &Domain,
    ) -> Result<Vec<Env>, Fault> {
        let plan = self.plan;
        let mut bindings: Vec<Env> = vec![Env::default(); plan.decompositions.len()];
        for (i, d) in plan.decompositions.iter().enumerate() {
            if i % 256 == 255 {
                within_budget()?;
            }
            let Some(task) = domain.tasks.iter().find(|t| t.name == d.task) else {
                return fault(format!(
                    "task {} `{}` is not an abstract task of the domain",
                    d.id, d.task
                ));
            };
            if task.params.len() != d.args.len() {
                return fault(format!(
                    "task {} `{}` has {} arguments, the domain declares {}",
                    d.id,
                    d.task,
                    d.args.len(),
                    task.params.len()
                ));
            }
            for (p, a) in task.params.iter().zip(&d.args) {
                if !w.is_of(a, &p.ty) {
                    return fault(format!(
                        "task {} `{}`: `{a}` is not an object of type `{}`",
                        d.id, d.task, p.ty
                    ));
                }
            }
            let Some(m) = domain.methods.iter().find(|m| m.name == d.method) else {
                return fault(format!(
                    "task {}: `{}` is not a method of the domain",
                    d.id, d.method
                ));
            };
            if m.task != d.task {
                return fault(format!(
                    "task {}: method `{}` decomposes `{}`, not `{}`",
                    d.id, m.name, m.task, d.task
                ));
            }
            let mut env = Env::default();
            if !unify(w, &mut env, &m.task_args, &d.args, &m.params) {
                return fault(format!(
                    "task {} ({} {}): the arguments do not match method `{}`'s task ({} {})",
                    d.id,
                    d.task,
                    d.args.join(" "),
                    m.name,
                    m.task,
                    show_terms(&m.task_args)
                ));
            }
            if m.subtasks.len() != d.subtasks.len() {
                return fault(format!(
                    "task {}: method `{}` has {} subtasks, the plan gives {}",
                    d.id,
                    m.name,
                    m.subtasks.len(),
                    d.subtasks.len()
                ));
            }
            for (k, (st, &c)) in m.subtasks.iter().zip(&d.subtasks).enumerate() {
                let (name, args) = self.name_args(c);
                if st.name != name || !unify(w, &mut env, &st.args, args, &m.params) {
                    return fault(format!(
                        "task {}: subtask {} of method `{}` is ({} {}), but id {c} is ({name} {})",
                        d.id,
                        k + 1,
                        m.name,
                        st.name,
                        show_terms(&st.args),
                        args.join(" ")
                    ));
                }
            }
            bindings[i] = env;
        }
        Ok(bindings)
    }
}

fn show_terms(ts: &[Term]) -> String {
    ts.iter()
        .map(|t| match t {
            Term::Var(v) | Term::Const(v) => v.as_str(),
        })
        .collect::<Vec<_>>()
        .join(" ")
}

/// Extends `env` so that `terms` denote `args`; variables must be among `params` and the
/// objects of their types.
fn unify(w: &World, env: &mut Env, terms: &[Term], args: &[String], params: &[TypedName]) -> bool {
    if terms.len() != args.len() {
        return false;
    }
    for (t, a) in terms.iter().zip(args) {
        match t {
            Term::Const(c) => {
                if c != a {
                    return false;
                }
            }
            Term::Var(v) => match env.get(v) {
                Some(b) => {
                    if b != a {
                        return false;
                    }
                }
                None => {
                    let Some(p) = params.iter().find(|p| &p.name == v) else {
                        return false;
                    };
                    if !w.is_of(a, &p.ty) {
                        return false;
                    }
                    env.insert(v.clone(), a.clone());
                }
            },
        }
    }
    true
}
