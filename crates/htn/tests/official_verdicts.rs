//! The strict validator agrees with the competition's verifier (pandaPIparser `--verify`) on
//! every plan of the verdict corpus (`tests/verdicts/`, see its README): plans htngtp found for
//! shared benchmark problems, and broken variants of them (names in another case, swapped
//! arguments, a missing decomposition, actions out of order, another object, a dropped action).
//!
//! The domains and problems live beside the checkout (`../shared/benchmarks/`); when they are
//! absent the test says so on stderr and checks nothing.

use std::path::{Path, PathBuf};

use htn::plan::Plan;
use htn::validate::validate;

fn shared() -> Option<PathBuf> {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../../shared");
    if dir.join("benchmarks").is_dir() {
        Some(dir)
    } else {
        eprintln!(
            "SKIPPED: {} is absent; the official-verdict corpus was not checked",
            dir.join("benchmarks").display()
        );
        None
    }
}

/// One row of `verdicts.tsv`.
struct Row {
    plan: PathBuf,
    domain: PathBuf,
    problem: PathBuf,
    valid: bool,
    why: String,
}

fn rows(shared: &Path) -> Vec<Row> {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/verdicts");
    let text = std::fs::read_to_string(dir.join("verdicts.tsv")).expect("verdicts.tsv");
    text.lines()
        .filter(|l| !l.starts_with('#') && !l.trim().is_empty())
        .map(|l| {
            let f: Vec<&str> = l.split('\t').collect();
            assert_eq!(f.len(), 5, "a row of five fields: {l}");
            assert!(matches!(f[3], "valid" | "invalid"), "verdict: {l}");
            Row {
                plan: dir.join(f[0]),
                domain: shared.join(f[1]),
                problem: shared.join(f[2]),
                valid: f[3] == "valid",
                why: f[4].to_string(),
            }
        })
        .collect()
}

/// The strict validator's verdict, and its fault when it refuses.
fn our_verdict(r: &Row) -> (bool, String) {
    let d = htn::load_domain(&r.domain).unwrap_or_else(|e| panic!("{e}"));
    let p = htn::load_problem(&r.problem, &d).unwrap_or_else(|e| panic!("{e}"));
    let text = std::fs::read_to_string(&r.plan).expect("plan file");
    match Plan::parse(&text) {
        Err(e) => (false, e.to_string()),
        Ok(plan) => match validate(&d, &p, &plan, &[]) {
            Ok(()) => (true, String::new()),
            Err(f) => (false, f.0),
        },
    }
}

#[test]
#[ignore = "needs ../shared/benchmarks beside the checkout; .ci/run runs it when present"]
fn the_strict_validator_agrees_with_every_official_verdict() {
    let shared = shared().expect("../shared/benchmarks beside the checkout");
    let rows = rows(&shared);
    let invalid = rows.iter().filter(|r| !r.valid).count();
    assert!(rows.len() >= 60 && invalid >= 20, "the corpus is too small");
    let mut disagreements = Vec::new();
    for r in &rows {
        let (ours, fault) = our_verdict(r);
        if ours != r.valid {
            disagreements.push(format!(
                "{}: official {} ({}), htngtp {} {fault}",
                r.plan.display(),
                r.valid,
                r.why,
                ours
            ));
        }
    }
    assert!(
        disagreements.is_empty(),
        "{} of {} verdicts differ:\n{}",
        disagreements.len(),
        rows.len(),
        disagreements.join("\n")
    );
}
