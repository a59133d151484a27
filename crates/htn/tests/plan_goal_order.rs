//! Bindings that serve the goal come first (`planner/search/relevance.rs`, `goals_first`):
//! each part is painted a colour that nothing but the goal constrains, and the goal asks for
//! the last colour in object order. The depth-first search tries the goal's colour first for
//! every part, so it never backtracks; in object order it would go through every colour of
//! every part before the goal check at the end.

use std::path::PathBuf;
use std::sync::Arc;

use htn::planner::{Outcome, PlannerOptions, plan};
use htn::validate::validate;
use htn::{parse_domain, parse_problem};

const DOMAIN: &str = "(define (domain paint)
  (:requirements :typing :hierarchy :negative-preconditions)
  (:types part colour)
  (:predicates (colour-of ?p - part ?c - colour) (painted ?p - part))
  (:task finish :parameters (?p - part))
  (:method m-finish :parameters (?p - part ?c - colour) :task (finish ?p)
    :ordered-subtasks (and (paint ?p ?c)))
  (:action paint :parameters (?p - part ?c - colour)
    :precondition (not (painted ?p))
    :effect (and (painted ?p) (colour-of ?p ?c))))";

#[test]
fn the_goals_colour_is_tried_first() {
    let parts: Vec<String> = (0..6).map(|i| format!("p{i}")).collect();
    let tasks: Vec<String> = parts.iter().map(|p| format!("(finish {p})")).collect();
    let goal: Vec<String> = parts
        .iter()
        .map(|p| format!("(colour-of {p} red)"))
        .collect();
    let problem = format!(
        "(define (problem paint-p) (:domain paint)
          (:objects {} - part green blue black red - colour)
          (:htn :ordered-subtasks (and {}))
          (:init)
          (:goal (and {})))",
        parts.join(" "),
        tasks.join(" "),
        goal.join(" ")
    );
    let src = |f: &str| Arc::new(PathBuf::from(f));
    let d = parse_domain(DOMAIN, src("d.hddl")).unwrap();
    let p = parse_problem(&problem, src("p.hddl"), &d).unwrap();
    let r = plan(&d, &p, &PlannerOptions::default(), None).unwrap();
    let Outcome::Found { plan } = &r.outcome else {
        panic!("no plan: {:?}", r.outcome)
    };
    validate(&d, &p, plan, &[]).unwrap();
    assert!(plan.actions.iter().all(|a| a.args[1] == "red"));
    assert_eq!(r.stats.htn_backtracks, 0);
}
