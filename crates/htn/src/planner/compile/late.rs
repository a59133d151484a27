//! The initial task network's parameters bound late. A method's parameter that its task does
//! not give is bound when the method is applied: by its precondition, or else by type
//! enumeration, in the state where the method starts. The initial task network is a method
//! too, and a problem's `:htn` may have parameters (Woodworking's surfaces and colours of each
//! part, left to the planner): bound with the network, each is a choice made before the first
//! action, blind to the state where the subtask that reads it starts. A wrong value shows only
//! when that subtask is decomposed, and chronological backtracking then goes through the
//! product of all the values chosen before it (depth first), or the best-first search seeds one
//! root node per binding of the product (2 GB on Woodworking).
//!
//! A parameter that appears in no literal of the network's constraints (after pull-up, so the
//! first subtask's requirements still bind it there) and once in one subtask only is instead
//! left unbound in that subtask: the ground task keeps an unbound argument, and the method that
//! decomposes it binds it (from its precondition, in the state where the subtask starts, or by
//! its own type enumeration). This loses no plan and adds none: the value is one that method
//! may take there, of the parameter's type (the deferral is made only when every method of the
//! subtask's task takes at that argument either an object of that type or a parameter whose
//! type has no other objects), and as nothing else reads the parameter, any value the
//! subtask's method takes is a binding of the network. The plan's decomposition records the
//! subtask with the value bound, from which a verifier finds the network's binding.
//!
//! The same deferral for every method's parameters (`late_params` works for any method) solved
//! 14 of Woodworking's 30 problems instead of 10, but lost 3 of Factories' 8: there the
//! deferred location of a factory is then chosen among the free locations in the order of the
//! facts, not of the objects, the first is the one the last factory needs, and the depth-first
//! search sees that dead end only at the last task. Both orders are arbitrary; until the search
//! detects such dead ends, only the network's parameters (which no shared or held-out domain
//! but Woodworking has) are bound late.

use super::{CTerm, Compiled};

/// Marks the parameters bound late (see the module docs): they leave their method's `bind`.
/// Only the initial task network's: for a method's own parameters the deferral changes the
/// order in which values come (the subtask's method binds them in the order of the facts that
/// hold, not in the order of the objects), and the depth-first search depends on that order
/// where it cannot see a dead end (see the module docs).
pub(super) fn bind_late(c: &mut Compiled) {
    let m = c.root_method as usize;
    let late = late_params(c, m);
    c.methods[m].bind.retain(|v| !late.contains(v));
}

/// The parameters of method `m` bound late: in none of its task's arguments and no literal of
/// its precondition (after pull-up), once in one subtask, whose task's methods all take there
/// only objects of the parameter's type.
fn late_params(c: &Compiled, m: usize) -> Vec<u16> {
    let method = &c.methods[m];
    let mut late = Vec::new();
    for &v in &method.params {
        if method.task_args.contains(&CTerm::Var(v))
            || method.pre.iter().any(|l| l.vars.contains(&v))
        {
            continue;
        }
        let mut uses = method.subtasks.iter().flat_map(|(t, args)| {
            args.iter()
                .enumerate()
                .filter(move |(_, a)| **a == CTerm::Var(v))
                .map(move |(k, _)| (*t, k))
        });
        let (Some((t, k)), None) = (uses.next(), uses.next()) else {
            continue;
        };
        if methods_fit(c, t, k, method.slot_types[v as usize]) {
            late.push(v);
        }
    }
    late
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
