//! Landmarks of goal literals (`planner/compile/landmarks.rs`): every way of coating a part
//! requires it raw, so once a part is coated the wrong finish, no task left in the network
//! can give the goal's finish, even though a touch-up of any part may coat with any finish.
//! The depth-first search tries the wrong finish first (domain order) and must learn that
//! at once, not at the goal check after every other part: with n parts that is 2^n
//! decompositions. Each part is polished before it is coated, and the goal asks for the
//! polish first, so the landmark `(raw p)` serves two goal literals of which one already
//! holds when the coat goes wrong (a landmark is needed while any literal it serves is false).
//! A part can be stripped raw again, but only by a task no method of this network reaches, so
//! `raw` is not a fact that can only be deleted (`search/guard.rs` does not apply).

use std::path::PathBuf;
use std::sync::Arc;

use htn::planner::{Limits, Outcome, PlannerOptions, plan};
use htn::validate::validate;
use htn::{parse_domain, parse_problem};

const DOMAIN: &str = "(define (domain coat)
  (:requirements :typing :hierarchy :negative-preconditions)
  (:types part finish)
  (:constants gloss matte - finish)
  (:predicates (raw ?p - part) (polished ?p - part) (coated ?p - part ?f - finish)
    (buffed ?p - part))
  (:task process :parameters (?p - part))
  (:task touch-up :parameters (?p - part))
  (:task refinish :parameters (?p - part))
  (:method m-matte :parameters (?p - part ?x - part) :task (process ?p)
    :ordered-subtasks (and (polish ?p) (coat ?p matte) (touch-up ?x)))
  (:method m-gloss :parameters (?p - part ?x - part) :task (process ?p)
    :ordered-subtasks (and (polish ?p) (coat ?p gloss) (touch-up ?x)))
  (:method m-buff :parameters (?x - part) :task (touch-up ?x)
    :ordered-subtasks (and (buff ?x)))
  (:method m-recoat :parameters (?x - part ?f - finish) :task (touch-up ?x)
    :ordered-subtasks (and (coat ?x ?f)))
  (:method m-strip :parameters (?p - part) :task (refinish ?p)
    :ordered-subtasks (and (strip ?p)))
  (:action strip :parameters (?p - part) :effect (raw ?p))
  (:action polish :parameters (?p - part) :precondition (raw ?p) :effect (polished ?p))
  (:action coat :parameters (?p - part ?f - finish) :precondition (raw ?p)
    :effect (and (not (raw ?p)) (coated ?p ?f)))
  (:action buff :parameters (?p - part) :effect (buffed ?p)))";

fn problem(n: usize) -> String {
    let parts: Vec<String> = (0..n).map(|i| format!("p{i}")).collect();
    let each = |f: &dyn Fn(&String) -> String| parts.iter().map(f).collect::<Vec<_>>().join(" ");
    format!(
        "(define (problem coat-{n}) (:domain coat)
          (:objects {} - part)
          (:htn :ordered-subtasks (and {}))
          (:init {})
          (:goal (and {})))",
        parts.join(" "),
        each(&|p| format!("(process {p})")),
        each(&|p| format!("(raw {p})")),
        each(&|p| format!("(polished {p}) (coated {p} gloss)")),
    )
}

#[test]
fn a_part_coated_the_wrong_finish_is_a_dead_end_at_once() {
    let n = 10;
    let src = |f: &str| Arc::new(PathBuf::from(f));
    let d = parse_domain(DOMAIN, src("d.hddl")).unwrap();
    let p = parse_problem(&problem(n), src("p.hddl"), &d).unwrap();
    let opts = PlannerOptions {
        limits: Limits {
            nodes: Some(100_000),
            ..Limits::default()
        },
        ..PlannerOptions::default()
    };
    let r = plan(&d, &p, &opts, None).unwrap();
    let Outcome::Found { plan } = &r.outcome else {
        panic!("no plan: {:?} after {:?}", r.outcome, r.stats)
    };
    validate(&d, &p, plan, &[]).unwrap();
    let glossy = plan
        .actions
        .iter()
        .filter(|a| a.name == "coat" && a.args[1] == "gloss");
    assert_eq!(glossy.count(), n);
    // One wrong finish per part, each refused right after its coat.
    assert!(
        r.stats.htn_backtracks <= 4 * n as u64,
        "{} backtracks",
        r.stats.htn_backtracks
    );
}
