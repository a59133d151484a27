//! Pull-up through tasks with several methods: what every method of a task requires over the
//! task's arguments becomes a precondition of the methods that use the task, so the binder
//! skips bindings that no method could use (AssemblyHierarchical's `connect`, whose eight
//! methods all need both ports free). And pull-up past the subtasks that cannot change a
//! literal: the learned Freecell methods unlock a card before they move it.

use std::path::Path;

use htn::planner::{Outcome, PlannerOptions, plan};
use htn::validate::validate;

/// The plan of a test domain's problem (validated), its steps (name, first argument) and the
/// nodes the search took.
fn solve(domain: &str, problem: &str) -> (Vec<(String, String)>, u64) {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/domains");
    let d = htn::load_domain(dir.join(domain)).unwrap();
    let p = htn::load_problem(dir.join(problem), &d).unwrap();
    let r = plan(&d, &p, &PlannerOptions::default(), None).unwrap();
    let Outcome::Found { plan } = &r.outcome else {
        panic!("no plan: {:?}", r.outcome)
    };
    validate(&d, &p, plan, &[]).unwrap();
    let steps = plan
        .actions
        .iter()
        .map(|a| (a.name.clone(), a.args[0].clone()))
        .collect();
    (steps, r.stats.nodes)
}

fn named(steps: &[(&str, &str)]) -> Vec<(String, String)> {
    steps
        .iter()
        .map(|(a, b)| (a.to_string(), b.to_string()))
        .collect()
}

#[test]
fn a_literal_every_method_requires_filters_the_parent_binding() {
    let (steps, nodes) = solve("sockets-domain.hddl", "sockets-300.hddl");
    assert_eq!(steps, named(&[("plug-flat", "s300")]));
    // One node per task: the 299 used sockets are never tried (without the pull-up through
    // `plug`'s two methods, each was a node: 302 in all).
    assert_eq!(nodes, 3);
}

#[test]
fn a_literal_no_earlier_subtask_changes_filters_the_binding() {
    let (steps, nodes) = solve("cells-domain.hddl", "cells-300.hddl");
    assert_eq!(steps, named(&[("unlock", "c300"), ("send-home", "c300")]));
    // One node per task: without the pull-up past `unlock`, every card before c300 was
    // unlocked and its move tried (two nodes each).
    assert_eq!(nodes, 3);
}

#[test]
fn a_literal_an_earlier_subtask_may_change_stays_where_it_is() {
    // `to-cell` makes `(incell ?c)` true: pulled to the method's start, it would make the
    // problem unsolvable (no card starts in a cell).
    let (steps, _) = solve("cells-domain.hddl", "cells-none.hddl");
    assert_eq!(
        steps,
        named(&[("unlock", "c1"), ("to-cell", "c1"), ("send-home", "c1")])
    );
}
