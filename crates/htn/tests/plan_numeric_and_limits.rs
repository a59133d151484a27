//! Numeric fluents deciding the method (the paper's TAKEPAYMENT with m6/m7), a proof of
//! unsolvability, and the limits stopping a search that never ends.

use std::path::Path;
use std::time::Duration;

use htn::model::{Domain, Problem};
use htn::planner::{Limit, Limits, Outcome, PlannerOptions, plan};
use htn::validate::validate;

fn load(domain: &str, problem: &str) -> (Domain, Problem) {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/domains");
    let d = htn::load_domain(dir.join(domain)).unwrap();
    let p = htn::load_problem(dir.join(problem), &d).unwrap();
    (d, p)
}

fn payment_method(problem: &str) -> (String, Vec<String>) {
    let (d, p) = load("payment-domain.hddl", problem);
    let r = plan(&d, &p, &PlannerOptions::default(), None).unwrap();
    let Outcome::Found { plan } = r.outcome else {
        panic!("no plan for {problem}")
    };
    validate(&d, &p, &plan, &[]).unwrap();
    let m = plan
        .decompositions
        .iter()
        .find(|x| x.task == "take-payment")
        .unwrap()
        .method
        .clone();
    (m, plan.actions.iter().map(|a| a.name.clone()).collect())
}

#[test]
fn enough_credit_pays_from_the_account() {
    // Two books at 4 and credit 20: m6.
    let (m, actions) = payment_method("payment-credit-20.hddl");
    assert_eq!(m, "m6-debit-account");
    assert_eq!(actions, ["give", "give", "debit"]);
}

#[test]
fn too_little_credit_pays_by_card() {
    // Two books at 4 and credit 7: the count of lent books, kept by `increase`, rules m6 out.
    let (m, actions) = payment_method("payment-credit-7.hddl");
    assert_eq!(m, "m7-pay-by-card");
    assert_eq!(actions, ["give", "give", "swipe-card"]);
}

#[test]
fn an_unsolvable_problem_is_proven_unsolvable() {
    let (d, p) = load("payment-domain.hddl", "unsolvable.hddl");
    let r = plan(&d, &p, &PlannerOptions::default(), None).unwrap();
    assert_eq!(r.outcome, Outcome::Unsolvable);
    assert!(r.stats.nodes > 0);
}

fn counter(limits: Limits) -> (Outcome, u64) {
    let (d, p) = load("counter-domain.hddl", "counter.hddl");
    let opts = PlannerOptions {
        limits,
        ..PlannerOptions::default()
    };
    let r = plan(&d, &p, &opts, None).unwrap();
    (r.outcome, r.stats.nodes)
}

#[test]
fn the_node_limit_stops_the_search_and_says_so() {
    let (o, nodes) = counter(Limits {
        nodes: Some(5000),
        ..Limits::default()
    });
    assert_eq!(
        o,
        Outcome::LimitReached {
            limit: Limit::Nodes
        }
    );
    assert_eq!(nodes, 5000);
}

#[test]
fn the_time_limit_stops_the_search_and_says_so() {
    let (o, _) = counter(Limits {
        time: Some(Duration::from_millis(200)),
        ..Limits::default()
    });
    assert_eq!(o, Outcome::LimitReached { limit: Limit::Time });
}

#[test]
fn the_memory_limit_stops_the_search_and_says_so() {
    // 1 MiB is less than any process needs: the first check stops the search.
    let (o, _) = counter(Limits {
        memory_mb: Some(1),
        ..Limits::default()
    });
    assert_eq!(
        o,
        Outcome::LimitReached {
            limit: Limit::Memory
        }
    );
}

#[test]
fn goal_relevance_cuts_dead_ends_early() {
    // 24 switches, each tried off first: checking the goal only at the end would need about
    // 2^24 nodes; with goal relevance a switch left off is a dead end at once.
    let (d, p) = load("switches-domain.hddl", "switches-24.hddl");
    let opts = PlannerOptions {
        limits: Limits {
            nodes: Some(20_000),
            ..Limits::default()
        },
        ..PlannerOptions::default()
    };
    let r = plan(&d, &p, &opts, None).unwrap();
    let Outcome::Found { plan } = r.outcome else {
        panic!("no plan within 20000 nodes: {:?}", r.outcome)
    };
    validate(&d, &p, &plan, &[]).unwrap();
    assert!(plan.actions.iter().all(|a| a.name == "turn-on"));
    assert_eq!(plan.actions.len(), 24);
    assert!(r.stats.goal_pruned > 0);
}

#[test]
fn the_search_is_deterministic_for_a_seed() {
    let (d, p) = load("payment-domain.hddl", "payment-credit-7.hddl");
    let opts = PlannerOptions {
        seed: 42,
        ..PlannerOptions::default()
    };
    let a = plan(&d, &p, &opts, None).unwrap();
    let b = plan(&d, &p, &opts, None).unwrap();
    assert_eq!(a.outcome, b.outcome);
    assert_eq!(a.stats.nodes, b.stats.nodes);
}

#[test]
fn the_loop_check_cuts_a_recursion_that_returned_to_the_same_state() {
    // fix -> mark fix tidy -> mark fix tidy: the second mark changes nothing, so the innermost fix starts
    // in the state of its parent fix and is cut; the parent then takes its next method (the
    // second mark undone) and finishes: mark finish tidy. Comparing only the number of actions executed, the
    // recursion would run to the length bound (about a thousand marks) before finishing.
    let (d, p) = load("noop-loop-domain.hddl", "noop-loop.hddl");
    let r = plan(&d, &p, &PlannerOptions::default(), None).unwrap();
    let Outcome::Found { plan } = r.outcome else {
        panic!("no plan: {:?}", r.outcome)
    };
    validate(&d, &p, &plan, &[]).unwrap();
    let names: Vec<&str> = plan.actions.iter().map(|a| a.name.as_str()).collect();
    assert_eq!(names, ["mark", "finish", "tidy"]);
    assert!(r.stats.loops_pruned > 0);
    assert_eq!(r.stats.depth_cutoffs, 0);
}
