//! Pull-up through tasks with several methods: what every method of a task requires over the
//! task's arguments becomes a precondition of the methods that use the task, so the binder
//! skips bindings that no method could use (AssemblyHierarchical's `connect`, whose eight
//! methods all need both ports free).

use std::path::Path;

use htn::planner::{Outcome, PlannerOptions, plan};
use htn::validate::validate;

#[test]
fn a_literal_every_method_requires_filters_the_parent_binding() {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/domains");
    let d = htn::load_domain(dir.join("sockets-domain.hddl")).unwrap();
    let p = htn::load_problem(dir.join("sockets-300.hddl"), &d).unwrap();
    let r = plan(&d, &p, &PlannerOptions::default(), None).unwrap();
    let Outcome::Found { plan } = &r.outcome else {
        panic!("no plan: {:?}", r.outcome)
    };
    validate(&d, &p, plan, &[]).unwrap();
    let steps: Vec<(&str, &str)> = plan
        .actions
        .iter()
        .map(|a| (a.name.as_str(), a.args[0].as_str()))
        .collect();
    assert_eq!(steps, [("plug-flat", "s300")]);
    // One node per task: the 299 used sockets are never tried (without the pull-up through
    // `plug`'s two methods, each was a node: 302 in all).
    assert_eq!(r.stats.nodes, 3);
}
