//! The IPC 2020 feature tests: every problem is solved with a plan the validator accepts, and
//! the expected plans shipped with the tests validate too. Reads `../shared/benchmarks/` beside
//! the checkout; when that folder is absent the tests say so and skip.

use std::path::{Path, PathBuf};

use htn::plan::Plan;
use htn::planner::{Outcome, PlannerOptions, plan};
use htn::validate::validate;

fn feature_dir() -> Option<PathBuf> {
    let d = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../../../shared/benchmarks/ipc2020-feature-tests");
    if d.is_dir() {
        Some(d)
    } else {
        eprintln!(
            "SKIPPED: {} is absent (the shared benchmark folder beside the checkout)",
            d.display()
        );
        None
    }
}

/// The problems of the folder with their domain files.
fn problems(dir: &Path) -> Vec<(PathBuf, PathBuf)> {
    let mut v: Vec<(PathBuf, PathBuf)> = std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|e| e == "hddl"))
        .filter(|p| !htn::parser::is_domain_file_name(p))
        .map(|p| (htn::parser::domain_file_for(&p).expect("a domain file"), p))
        .collect();
    v.sort();
    v
}

#[test]
#[ignore = "needs ../shared/benchmarks beside the checkout; .ci/run runs it when present"]
fn every_feature_test_with_a_problem_is_solved_and_its_plan_validates() {
    let dir = feature_dir().expect("../shared/benchmarks beside the checkout");
    let probs = problems(&dir);
    assert!(
        probs.len() >= 8,
        "expected the feature tests, found {probs:?}"
    );
    for (d, p) in probs {
        let domain = htn::load_domain(&d).unwrap();
        let problem = htn::load_problem(&p, &domain).unwrap();
        let r = plan(&domain, &problem, &PlannerOptions::default(), None).unwrap();
        let Outcome::Found { plan: found } = r.outcome else {
            panic!("{}: no plan ({:?})", p.display(), r.outcome);
        };
        validate(&domain, &problem, &found, &[])
            .unwrap_or_else(|e| panic!("{}: {e}\n{}", p.display(), found.to_competition_format()));
        // The printed form reads back to the same plan, which validates as well.
        let reread = Plan::parse(&found.to_competition_format()).unwrap();
        assert_eq!(reread, found);
    }
}

#[test]
#[ignore = "needs ../shared/benchmarks beside the checkout; .ci/run runs it when present"]
fn the_expected_plans_shipped_with_the_feature_tests_validate() {
    let dir = feature_dir().expect("../shared/benchmarks beside the checkout");
    let mut n = 0;
    for e in std::fs::read_dir(dir.join("plans")).unwrap() {
        let plan_file = e.unwrap().path();
        let stem = plan_file.file_stem().unwrap().to_string_lossy().to_string();
        let p = dir.join(format!("{stem}.hddl"));
        let d = htn::parser::domain_file_for(&p).unwrap();
        let domain = htn::load_domain(&d).unwrap();
        let problem = htn::load_problem(&p, &domain).unwrap();
        let text = std::fs::read_to_string(&plan_file).unwrap();
        let expected = Plan::parse(&text).unwrap();
        validate(&domain, &problem, &expected, &[])
            .unwrap_or_else(|e| panic!("{}: {e}", plan_file.display()));
        n += 1;
    }
    assert!(n >= 4, "expected the shipped plans, found {n}");
}

#[test]
#[ignore = "needs ../shared/benchmarks beside the checkout; .ci/run runs it when present"]
fn planner_plans_for_feature_tests_with_expected_plans_have_their_length() {
    let dir = feature_dir().expect("../shared/benchmarks beside the checkout");
    for e in std::fs::read_dir(dir.join("plans")).unwrap() {
        let plan_file = e.unwrap().path();
        let stem = plan_file.file_stem().unwrap().to_string_lossy().to_string();
        let p = dir.join(format!("{stem}.hddl"));
        let d = htn::parser::domain_file_for(&p).unwrap();
        let domain = htn::load_domain(&d).unwrap();
        let problem = htn::load_problem(&p, &domain).unwrap();
        let expected = Plan::parse(&std::fs::read_to_string(&plan_file).unwrap()).unwrap();
        let r = plan(&domain, &problem, &PlannerOptions::default(), None).unwrap();
        let Outcome::Found { plan: found } = r.outcome else {
            panic!("{stem}: no plan");
        };
        let names = |p: &Plan| -> Vec<String> {
            p.actions
                .iter()
                .map(|a| format!("{} {}", a.name, a.args.join(" ")))
                .collect()
        };
        assert_eq!(names(&found), names(&expected), "{stem}");
    }
}
