//! Parameters bound late. A method's parameter that its task does
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
//! The same deferral applies to every method's parameters. It was once kept to the initial
//! network's: it solved 14 of Woodworking's 30 problems instead of 10 but lost 3 of
//! Factories' 8, where the deferred location of a factory is chosen among the free locations
//! in the order of the facts, the first is the one the last factory needs, and the depth-first
//! search saw that dead end only at the last task. It now sees it when the factory's method
//! is chosen (`search/consumed.rs`), and Factories gains instead of losing.

use super::{CTerm, Compiled};

/// Marks the parameters bound late, of every method and of the initial task network (see the
/// module docs): they leave their method's `bind`.
pub(super) fn bind_late(c: &mut Compiled) {
    for m in 0..c.methods.len() {
        let late = late_params(c, m);
        c.methods[m].bind.retain(|v| !late.contains(v));
    }
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
