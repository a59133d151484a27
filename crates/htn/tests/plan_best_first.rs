//! The best-first fallback: a search the domain-order depth-first search gets lost in is
//! solved once the depth-first search has used its share of the time limit, and, when the
//! shared benchmarks are there, a Freecell problem (IPC 2020, learned methods) and an
//! AssemblyHierarchical one (solved by the relaxed composition, after the phase with the
//! state-free estimate has used its share).

use std::path::{Path, PathBuf};
use std::time::Duration;

use htn::model::{Domain, Problem};
use htn::plan::Plan;
use htn::planner::{Limit, Limits, Outcome, PlannerOptions, SearchResult, SearchStats, plan};
use htn::validate::validate;

fn load(dir: &Path, domain: &str, problem: &str) -> (Domain, Problem) {
    let d = htn::load_domain(dir.join(domain)).unwrap();
    let p = htn::load_problem(dir.join(problem), &d).unwrap();
    (d, p)
}

fn wander(time: f64, share: f64) -> (Domain, Problem, SearchResult) {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/domains");
    let (d, p) = load(&dir, "wander-domain.hddl", "wander-22.hddl");
    let opts = PlannerOptions {
        limits: Limits {
            time: Some(Duration::from_secs_f64(time)),
            ..Limits::default()
        },
        best_first_share: share,
        ..PlannerOptions::default()
    };
    let r = plan(&d, &p, &opts, None).unwrap();
    (d, p, r)
}

#[test]
fn the_best_first_fallback_takes_the_short_way_the_depth_first_search_never_reaches() {
    let (d, p, r) = wander(2.0, 0.8);
    let Outcome::Found { plan } = &r.outcome else {
        panic!("no plan: {:?}", r.outcome)
    };
    assert!(r.stats.best_first, "the plan comes from the fallback");
    assert!(r.stats.best_first_nodes > 0);
    validate(&d, &p, plan, &[]).unwrap();
    let names: Vec<&str> = plan.actions.iter().map(|a| a.name.as_str()).collect();
    assert_eq!(names, ["finish"]);
    // The same plan again (the fallback does not depend on how far the depth-first search got).
    let (_, _, again) = wander(1.0, 0.8);
    assert_eq!(again.outcome, r.outcome);
}

#[test]
fn without_the_fallback_the_depth_first_search_runs_out_of_time() {
    let (_, _, r) = wander(0.3, 0.0);
    assert_eq!(r.outcome, Outcome::LimitReached { limit: Limit::Time });
    assert!(!r.stats.best_first);
}

fn shared(domain: &str) -> Option<PathBuf> {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../../../shared/benchmarks/ipc2020-total-order")
        .join(domain);
    if dir.join("domain.hddl").is_file() {
        Some(dir)
    } else {
        eprintln!(
            "skipped: no benchmark folder at {} (the shared benchmarks are absent)",
            dir.display()
        );
        None
    }
}

/// A shared benchmark problem solved by the best-first search from the start (the
/// depth-first search gets lost in these) within `secs`, its plan validated; the plan and the
/// search's statistics.
fn solve_best_first(domain: &str, problem: &str, secs: u64) -> (Plan, SearchStats) {
    let dir = shared(domain).expect("../shared/benchmarks beside the checkout");
    let (d, p) = load(&dir, "domain.hddl", problem);
    let opts = PlannerOptions {
        limits: Limits {
            time: Some(Duration::from_secs(secs)),
            ..Limits::default()
        },
        best_first_share: 1.0,
        ..PlannerOptions::default()
    };
    let r = plan(&d, &p, &opts, None).unwrap();
    let plan = match r.outcome {
        Outcome::Found { plan } => plan,
        other => panic!("no plan: {other:?} after {:?}", r.stats),
    };
    validate(&d, &p, &plan, &[]).unwrap();
    (plan, r.stats)
}

#[test]
#[ignore = "needs ../shared/benchmarks beside the checkout; .ci/run runs it when present"]
fn a_freecell_problem_is_solved_by_the_fallback() {
    let (_, stats) = solve_best_first("Freecell-Learned-ECAI-16", "probfreecell-02-2.hddl", 60);
    assert!(stats.best_first);
}

#[test]
#[ignore = "needs ../shared/benchmarks beside the checkout; .ci/run runs it when present"]
fn an_assembly_problem_is_solved_from_the_initial_state_after_the_first_phase() {
    let (plan, stats) = solve_best_first(
        "AssemblyHierarchical",
        "genericLinearProblem_depth08.hddl",
        20,
    );
    // The state-free estimate does not find this plan in its share (about 5 s): the plan
    // comes from the second phase, which must start from the initial state again (the
    // validation in `solve_best_first` fails otherwise).
    assert!(stats.rc_methods > 0, "{stats:?}");
    assert_eq!(plan.actions.len(), 18, "2 x depth + 2 actions");
}

#[test]
fn randomized_restarts_find_the_short_way_before_the_best_first_search_starts() {
    // Handover at 2 s; the restarts run from 1 s: some run tries `go` before wandering.
    let (d, p, r) = wander(10.0, 0.8);
    let Outcome::Found { plan } = &r.outcome else {
        panic!("no plan: {:?}", r.outcome)
    };
    assert!(r.stats.restarts > 0, "the plan comes from a restart");
    assert!(!r.stats.best_first, "found before the best-first search");
    validate(&d, &p, plan, &[]).unwrap();
}
