//! The initial task network's parameters (`(:htn :parameters ...)`) that one subtask alone
//! uses are bound by that subtask's method, in the state where it starts, not by type
//! enumeration with the network (`planner/compile/late.rs`). Here every part needs its own
//! surface, known from the state: bound late, the search never backtracks; the plan's
//! decompositions record the values bound. A parameter two subtasks share, or whose methods
//! could give it a value outside its type, is still bound with the network.

use std::path::PathBuf;
use std::sync::Arc;

use htn::planner::{Outcome, PlannerOptions, SearchResult, plan};
use htn::validate::validate;
use htn::{parse_domain, parse_problem};

const DOMAIN: &str = "(define (domain late)
  (:requirements :typing :hierarchy :negative-preconditions)
  (:types part surface - object good - surface)
  (:predicates (surface-of ?p - part ?s - surface) (done ?p - part))
  (:task fix :parameters (?p - part ?s - surface))
  (:method m-fix :parameters (?p - part ?s - surface) :task (fix ?p ?s)
    :precondition (surface-of ?p ?s)
    :ordered-subtasks (and (treat ?p ?s)))
  (:action treat :parameters (?p - part ?s - surface)
    :precondition (and (surface-of ?p ?s) (not (done ?p)))
    :effect (done ?p)))";

/// Parts `a0..`, surfaces `s0..s{n-1}` (part `ai` has surface `s{n-1-i}`: the last ones), the
/// good surface `g`, the network `htn` and extra facts.
fn problem(parts: usize, n: usize, htn: &str, extra: &str) -> String {
    let ps: Vec<String> = (0..parts).map(|i| format!("a{i}")).collect();
    let ss: Vec<String> = (0..n).map(|i| format!("s{i}")).collect();
    let facts: Vec<String> = (0..parts)
        .map(|i| format!("(surface-of a{i} s{})", n - 1 - i))
        .collect();
    format!(
        "(define (problem late-p) (:domain late)
          (:objects {} - part {} - surface g - good)
          (:htn {htn})
          (:init {} {extra}))",
        ps.join(" "),
        ss.join(" "),
        facts.join(" ")
    )
}

fn solve(problem_text: &str) -> (SearchResult, Vec<String>) {
    let src = |f: &str| Arc::new(PathBuf::from(f));
    let d = parse_domain(DOMAIN, src("d.hddl")).unwrap();
    let p = parse_problem(problem_text, src("p.hddl"), &d).unwrap();
    let r = plan(&d, &p, &PlannerOptions::default(), None).unwrap();
    let mut lines = Vec::new();
    if let Outcome::Found { plan } = &r.outcome {
        validate(&d, &p, plan, &[]).unwrap();
        lines = plan
            .decompositions
            .iter()
            .map(|m| format!("{} {} -> {}", m.task, m.args.join(" "), m.method))
            .collect();
    }
    (r, lines)
}

#[test]
fn a_parameter_one_subtask_uses_is_bound_by_its_method() {
    // Three parts over 12 surfaces: bound with the network, the right triple would be the last
    // of 12^3 (every other failing at a treat); bound late, each comes from the state.
    let htn = ":parameters (?x ?y ?z - surface)
        :ordered-subtasks (and (fix a0 ?x) (fix a1 ?y) (fix a2 ?z))";
    let (r, lines) = solve(&problem(3, 12, htn, ""));
    assert!(
        matches!(r.outcome, Outcome::Found { .. }),
        "{:?}",
        r.outcome
    );
    assert_eq!(r.stats.htn_backtracks, 0);
    assert_eq!(
        lines,
        [
            "fix a0 s11 -> m-fix",
            "fix a1 s10 -> m-fix",
            "fix a2 s9 -> m-fix"
        ]
    );
}

#[test]
fn a_parameter_two_subtasks_share_is_bound_with_the_network() {
    // Both parts would need the same surface: with different ones there is no plan.
    let htn = ":parameters (?x - surface)
        :ordered-subtasks (and (fix a0 ?x) (fix a1 ?x))";
    let (r, _) = solve(&problem(2, 4, htn, ""));
    assert_eq!(r.outcome, Outcome::Unsolvable);
    let (r, lines) = solve(&problem(2, 4, htn, "(surface-of a1 s3)"));
    assert!(
        matches!(r.outcome, Outcome::Found { .. }),
        "{:?}",
        r.outcome
    );
    assert_eq!(lines, ["fix a0 s3 -> m-fix", "fix a1 s3 -> m-fix"]);
}

#[test]
fn a_parameter_of_a_narrower_type_than_its_methods_take_is_bound_with_the_network() {
    // `?x - good`, but `fix` takes any surface: bound late, the method would take `s0` first
    // (part a0 has surfaces s0 and g), which is not a `good`. Bound with the network, it is g.
    let htn = ":parameters (?x - good) :ordered-subtasks (and (fix a0 ?x))";
    let (r, lines) = solve(&problem(1, 1, htn, "(surface-of a0 g)"));
    assert!(
        matches!(r.outcome, Outcome::Found { .. }),
        "{:?}",
        r.outcome
    );
    assert_eq!(lines, ["fix a0 g -> m-fix"]);
}
