//! Names are matched whatever their case but printed as the files declare them: the
//! competition's verifier matches names exactly. The texts mix case on purpose (a method named
//! like its task in another case, an object used in lower case in `:init`).

use std::path::PathBuf;
use std::sync::Arc;

use htn::parser::{parse_domain, parse_problem};
use htn::planner::{Outcome, PlannerOptions, plan};
use htn::validate::{Names, validate, validate_with};

const DOMAIN: &str = r#"
(define (domain Mixed)
  (:requirements :hierarchy :typing)
  (:types Room - object)
  (:constants Hall - Room)
  (:predicates (At ?r - Room))
  (:task GoTo :parameters (?r - Room))
  (:method goto
    :parameters (?from ?to - Room)
    :task (goto ?to)
    :precondition (at ?from)
    :ordered-subtasks (MOVE ?from ?to))
  (:action Move
    :parameters (?from ?to - Room)
    :precondition (AT ?from)
    :effect (and (not (at ?from)) (at ?to))))
"#;

const PROBLEM: &str = r#"
(define (problem P1) (:domain Mixed)
  (:objects Kitchen - Room)
  (:htn :ordered-subtasks (GOTO kitchen))
  (:init (at hall)))
"#;

fn model() -> (htn::model::Domain, htn::model::Problem) {
    let d = parse_domain(DOMAIN, Arc::new(PathBuf::from("d.hddl"))).unwrap();
    let p = parse_problem(PROBLEM, Arc::new(PathBuf::from("p.hddl")), &d).unwrap();
    (d, p)
}

#[test]
fn the_plan_spells_every_name_as_declared() {
    let (d, p) = model();
    let r = plan(&d, &p, &PlannerOptions::default(), None).unwrap();
    let Outcome::Found { plan } = r.outcome else {
        panic!("no plan: {:?}", r.outcome)
    };
    assert_eq!(
        plan.to_competition_format(),
        "==>\n1 Move Hall Kitchen\nroot 0\n0 GoTo Kitchen -> goto 1\n<==\n"
    );
    validate(&d, &p, &plan, &[]).unwrap();
}

#[test]
fn a_plan_in_another_case_is_valid_only_when_lenient() {
    let (d, p) = model();
    let text = "==>\n1 move hall kitchen\nroot 0\n0 goto kitchen -> GOTO 1\n<==\n";
    let plan = htn::plan::Plan::parse(text).unwrap();
    let f = validate(&d, &p, &plan, &[]).unwrap_err().0;
    assert!(
        f.contains("task `move` is not declared in the domain (declared as `Move`)"),
        "{f}"
    );
    validate_with(&d, &p, &plan, &[], Names::CaseInsensitive).unwrap();
}

#[test]
fn faults_name_things_as_the_files_spell_them() {
    let (d, p) = model();
    let text = "==>\n1 Move Kitchen Kitchen\nroot 0\n0 GoTo Kitchen -> goto 1\n<==\n";
    let plan = htn::plan::Plan::parse(text).unwrap();
    let f = validate(&d, &p, &plan, &[]).unwrap_err().0;
    assert!(
        f.contains("task 0 (GoTo Kitchen): the precondition of method `goto` does not hold"),
        "{f}"
    );
    let text = "==>\n1 Move Hall Kitchen\nroot 0\n0 GoTo Hall -> goto 1\n<==\n";
    let plan = htn::plan::Plan::parse(text).unwrap();
    let f = validate(&d, &p, &plan, &[]).unwrap_err().0;
    assert!(f.contains(r#"is `GoTo` with arguments ["Hall"]"#), "{f}");
}
