//! Facts consumed for good (`planner/search/consumed.rs`): a site is free until something is
//! built on it, and nothing frees it again. The network builds `n` sheds, each on any free
//! site, and then the hall on site `s0`, the first site in object order. A shed built on
//! `s0` dooms the hall: the depth-first search skips that binding when the shed's method is
//! chosen, instead of finding out at the hall after every other choice.

use std::path::PathBuf;
use std::sync::Arc;

use htn::planner::{Outcome, PlannerOptions, SearchResult, plan};
use htn::validate::validate;
use htn::{parse_domain, parse_problem};

const DOMAIN: &str = "(define (domain sites)
  (:requirements :typing :hierarchy :negative-preconditions)
  (:types site shed)
  (:predicates (free ?s - site) (built ?b - shed))
  (:task put-shed :parameters (?b - shed))
  (:method m-shed :parameters (?b - shed ?s - site) :task (put-shed ?b)
    :precondition (free ?s)
    :ordered-subtasks (and (build-shed ?b ?s)))
  (:action build-shed :parameters (?b - shed ?s - site)
    :precondition (and (free ?s) (not (built ?b)))
    :effect (and (not (free ?s)) (built ?b)))
  (:action build-hall :parameters (?s - site)
    :precondition (free ?s)
    :effect (not (free ?s))))";

fn problem(sheds: usize) -> String {
    let bs: Vec<String> = (0..sheds).map(|i| format!("b{i}")).collect();
    let ss: Vec<String> = (0..=sheds).map(|i| format!("s{i}")).collect();
    let tasks: Vec<String> = bs.iter().map(|b| format!("(put-shed {b})")).collect();
    let free: Vec<String> = ss.iter().map(|s| format!("(free {s})")).collect();
    format!(
        "(define (problem sites-p) (:domain sites)
          (:objects {} - shed {} - site)
          (:htn :ordered-subtasks (and {} (build-hall s0)))
          (:init {}))",
        bs.join(" "),
        ss.join(" "),
        tasks.join(" "),
        free.join(" ")
    )
}

fn solve(sheds: usize) -> (SearchResult, Vec<String>) {
    let src = |f: &str| Arc::new(PathBuf::from(f));
    let d = parse_domain(DOMAIN, src("d.hddl")).unwrap();
    let p = parse_problem(&problem(sheds), src("p.hddl"), &d).unwrap();
    let r = plan(&d, &p, &PlannerOptions::default(), None).unwrap();
    let mut steps = Vec::new();
    if let Outcome::Found { plan } = &r.outcome {
        validate(&d, &p, plan, &[]).unwrap();
        steps = plan
            .actions
            .iter()
            .map(|a| format!("{} {}", a.name, a.args.join(" ")))
            .collect();
    }
    (r, steps)
}

#[test]
fn a_shed_is_never_put_on_the_site_the_hall_needs() {
    let (r, steps) = solve(3);
    assert_eq!(steps.len(), 4);
    assert_eq!(steps[3], "build-hall s0");
    assert!(steps[..3].iter().all(|s| !s.ends_with(" s0")), "{steps:?}");
    // Each shed's binding to s0 was skipped, none tried and undone.
    assert_eq!(r.stats.consumed_pruned, 3);
    assert_eq!(r.stats.htn_backtracks, 0);
}

#[test]
fn many_sheds_are_placed_without_search() {
    // Without the check, the first shed takes s0 and the search finds out only at the hall,
    // after placing the other eleven. With it, it goes straight through.
    let (r, steps) = solve(12);
    assert_eq!(steps.len(), 13);
    assert!(r.stats.nodes < 100, "{} nodes", r.stats.nodes);
}
