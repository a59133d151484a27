//! A method's bindings are enumerated in pieces, the binder resuming after the last binding of
//! each piece: the search must try them in the order of one whole enumeration, none skipped,
//! none twice. Here exactly one of 100 x 100 bindings works, far past the first pieces, and
//! every binding before it fails after one step: the HTN backtracks count the bindings tried.

use std::path::PathBuf;
use std::sync::Arc;

use htn::planner::{Outcome, PlannerOptions, plan};
use htn::validate::validate;
use htn::{parse_domain, parse_problem};

/// The domain: `t` binds `?a ?b` by `pre` (a precondition or none), marks `?a` (which may
/// change `good`, so `finish`'s precondition stays where it is), then needs `(good ?a ?b)`.
/// `bless`, never used, may add `good`: a binding whose `mark` deletes the `good` fact that
/// `finish` needs is then tried like any other (`search/consumed.rs` would skip it).
fn domain(pre: &str) -> String {
    format!(
        "(define (domain pieces)
          (:requirements :typing :hierarchy :negative-preconditions)
          (:types obj)
          (:predicates (p ?x - obj) (good ?x ?y - obj) (marked ?x - obj))
          (:task t :parameters ())
          (:method m :parameters (?a ?b - obj) :task (t) :precondition {pre}
            :ordered-subtasks (and (mark ?a) (finish ?a ?b)))
          (:action mark :parameters (?x - obj)
            :effect (and (marked ?x) (not (good ?x ?x))))
          (:action finish :parameters (?x ?y - obj) :precondition (good ?x ?y))
          (:action bless :parameters (?x ?y - obj) :effect (good ?x ?y)))"
    )
}

/// `n` objects, all `p`, and the one good pair `(a, b)`.
fn problem(n: usize, (a, b): (usize, usize)) -> String {
    let objects: Vec<String> = (0..n).map(|i| format!("o{i}")).collect();
    let facts: Vec<String> = objects.iter().map(|o| format!("(p {o})")).collect();
    format!(
        "(define (problem pieces-{n}) (:domain pieces)
          (:objects {} - obj)
          (:htn :ordered-subtasks (and (t)))
          (:init {} (good o{a} o{b})))",
        objects.join(" "),
        facts.join(" ")
    )
}

/// The plan's actions as text and the HTN backtracks it took.
fn solve(pre: &str, n: usize, good: (usize, usize)) -> (Vec<String>, u64) {
    let src = |f: &str| Arc::new(PathBuf::from(f));
    let d = parse_domain(&domain(pre), src("d.hddl")).unwrap();
    let p = parse_problem(&problem(n, good), src("p.hddl"), &d).unwrap();
    let r = plan(&d, &p, &PlannerOptions::default(), None).unwrap();
    let Outcome::Found { plan } = &r.outcome else {
        panic!("no plan: {:?}", r.outcome)
    };
    validate(&d, &p, plan, &[]).unwrap();
    let steps = plan
        .actions
        .iter()
        .map(|a| format!("{} {}", a.name, a.args.join(" ")))
        .collect();
    (steps, r.stats.htn_backtracks)
}

#[test]
fn bindings_from_facts_come_in_one_order_across_pieces() {
    // `?a` from the first `p` atom, `?b` from the second: row by row.
    let (steps, backtracks) = solve("(and (p ?a) (p ?b))", 100, (57, 83));
    assert_eq!(steps, ["mark o57", "finish o57 o83"]);
    assert_eq!(backtracks, 57 * 100 + 83);
}

#[test]
fn bindings_from_the_objects_of_a_type_come_in_one_order_across_pieces() {
    // No precondition: both parameters range over the objects of their type.
    let (steps, backtracks) = solve("()", 100, (91, 4));
    assert_eq!(steps, ["mark o91", "finish o91 o4"]);
    assert_eq!(backtracks, 91 * 100 + 4);
}

#[test]
fn the_first_binding_of_a_piece_is_not_given_twice() {
    // The good pair is the first binding of a later piece or the last of an earlier one (the
    // pieces hold 16, 64, 256, 1024, 4096 bindings): each is tried exactly once.
    for k in [15, 16, 17, 79, 80, 81, 1359, 1360, 5455, 5456, 5457] {
        let (steps, backtracks) = solve("(and (p ?a) (p ?b))", 100, (k / 100, k % 100));
        assert_eq!(steps.len(), 2, "binding {k}");
        assert_eq!(backtracks, k as u64, "binding {k}");
    }
}
