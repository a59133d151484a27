//! Guarded goal achievers (`planner/search/guard.rs`): a goal literal made false whose only
//! achiever needs a fact no action gives back is a dead end at once, not at the goal check
//! after the rest of the plan (the trap of IPC 2020 Multiarm-Blocksworld).

use std::path::Path;

use htn::model::{Domain, Problem};
use htn::planner::{Limit, Limits, Outcome, PlannerOptions, SearchResult, plan};
use htn::validate::validate;

fn load() -> (Domain, Problem) {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/domains");
    let d = htn::load_domain(dir.join("tokens-domain.hddl")).unwrap();
    let p = htn::load_problem(dir.join("tokens-14.hddl"), &d).unwrap();
    (d, p)
}

fn run(d: &Domain, p: &Problem, goal_guards: bool) -> SearchResult {
    let opts = PlannerOptions {
        limits: Limits {
            nodes: Some(20_000),
            ..Limits::default()
        },
        goal_guards,
        ..PlannerOptions::default()
    };
    plan(d, p, &opts, None).unwrap()
}

#[test]
fn an_item_taken_back_after_its_token_was_spent_is_a_dead_end_at_once() {
    let (d, p) = load();
    let r = run(&d, &p, true);
    let Outcome::Found { plan } = &r.outcome else {
        panic!("no plan within 20000 nodes: {:?}", r.outcome)
    };
    validate(&d, &p, plan, &[]).unwrap();
    assert_eq!(r.stats.guarded_goals, 14);
    assert!(r.stats.goal_pruned > 0);
    assert!(r.stats.nodes < 1_000, "{} nodes", r.stats.nodes);
    assert!(plan.actions.iter().all(|a| a.name != "unplace"));
    assert_eq!(plan.actions.len(), 28);
    // Deterministic.
    assert_eq!(run(&d, &p, true).stats.nodes, r.stats.nodes);
}

#[test]
fn without_the_guards_the_search_finds_out_only_at_the_goal_check() {
    let (d, p) = load();
    let r = run(&d, &p, false);
    assert_eq!(
        r.outcome,
        Outcome::LimitReached {
            limit: Limit::Nodes
        }
    );
    assert_eq!(r.stats.guarded_goals, 0);
}
