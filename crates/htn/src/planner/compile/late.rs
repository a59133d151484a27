//! The initial task network's parameters bound late. A problem's `:htn` may have parameters
//! (Woodworking's surfaces and colours of each part, left for the planner to choose). Bound
//! with the initial network, as a method's parameters are, every one of them is a choice made
//! before the first action, in the initial state, by type enumeration: a wrong value shows only
//! when the subtask that reads it is decomposed, and chronological backtracking then goes
//! through the product of all the values before it (depth first), or the best-first search
//! seeds one root node per binding of the product.
//!
//! A parameter that appears in one subtask only (once), in no literal of the network's
//! constraints (after pull-up) is instead left unbound in that subtask: the ground task keeps an
//! unbound argument, and the method that decomposes it binds it (from its precondition, in the
//! state where the subtask starts, or by its own type enumeration). This loses no plan and adds
//! none: the value is one the method may take there, of the parameter's type (the deferral is
//! made only when every method of the subtask's task takes at that argument either an object of
//! that type or a parameter whose type has no other objects), and as nothing else reads the
//! parameter, any value that the method takes is a binding of the network. The plan's
//! decomposition records the task with the value bound.

use super::{CTerm, Compiled};

/// Marks the initial task network's parameters that are bound late (see the module docs):
/// they leave the root method's `bind`.
pub(super) fn bind_late(c: &mut Compiled) {
    let root = &c.methods[c.root_method as usize];
    let mut late = Vec::new();
    for &v in &root.params {
        if root.pre.iter().any(|l| l.vars.contains(&v)) {
            continue;
        }
        let mut uses = root.subtasks.iter().flat_map(|(t, args)| {
            args.iter()
                .enumerate()
                .filter(move |(_, a)| **a == CTerm::Var(v))
                .map(move |(k, _)| (*t, k))
        });
        let (Some((t, k)), None) = (uses.next(), uses.next()) else {
            continue;
        };
        if methods_fit(c, t, k, root.slot_types[v as usize]) {
            late.push(v);
        }
    }
    let root = &mut c.methods[c.root_method as usize];
    root.bind.retain(|v| !late.contains(v));
}

/// Whether task `t` is abstract and every one of its methods takes at argument `k` only
/// objects of type `ty`.
fn methods_fit(c: &Compiled, t: u32, k: usize, ty: u32) -> bool {
    let task = &c.tasks[t as usize];
    if task.action.is_some() || task.methods.is_empty() {
        return false;
    }
    task.methods.iter().all(|&m| {
        let m = &c.methods[m as usize];
        match m.task_args.get(k) {
            Some(CTerm::Obj(o)) => c.is_of(*o, ty),
            Some(CTerm::Var(w)) => c.type_objects[m.slot_types[*w as usize] as usize]
                .iter()
                .all(|&o| c.is_of(o, ty)),
            None => false,
        }
    })
}
