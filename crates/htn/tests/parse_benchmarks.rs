//! Every domain and problem file of the shared benchmark folders parses.
//!
//! The folders live beside the checkout (`../shared/benchmarks/`); when they are absent the
//! tests say so on stderr and check nothing else.

use std::path::{Path, PathBuf};
use std::time::Instant;

use htn::parser::{domain_file_for, is_domain_file_name, load_domain, load_problem};

fn benchmarks() -> Option<PathBuf> {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../../shared/benchmarks");
    if dir.is_dir() {
        Some(dir.canonicalize().unwrap_or(dir))
    } else {
        eprintln!(
            "SKIPPED: benchmark folder {} is absent; the benchmark parsing tests checked nothing",
            dir.display()
        );
        None
    }
}

/// All `.hddl` files under `dir`, sorted, leaving out `other/` folders (auxiliary material of
/// the IPC collection: a hybrid-planning domain and PDDL variants, not part of the track) and
/// `plans/` (expected plans; one of them carries the `.hddl` extension).
fn hddl_files(dir: &Path) -> Vec<PathBuf> {
    let mut out = Vec::new();
    let mut todo = vec![dir.to_path_buf()];
    while let Some(d) = todo.pop() {
        for entry in std::fs::read_dir(&d).unwrap() {
            let path = entry.unwrap().path();
            if path.is_dir() {
                if path
                    .file_name()
                    .is_some_and(|n| n != "other" && n != "plans")
                {
                    todo.push(path);
                }
            } else if path.extension().is_some_and(|e| e == "hddl") {
                out.push(path);
            }
        }
    }
    out.sort();
    out
}

fn parse_folder(dir: &Path) -> (usize, usize) {
    let files = hddl_files(dir);
    assert!(!files.is_empty(), "no .hddl files under {}", dir.display());
    let mut failures = Vec::new();
    let (mut domains, mut problems) = (0, 0);
    let mut slowest: Option<(std::time::Duration, PathBuf)> = None;
    for f in &files {
        if is_domain_file_name(f) {
            domains += 1;
            if let Err(e) = load_domain(f) {
                failures.push(e.to_string());
            }
            continue;
        }
        problems += 1;
        let Some(dfile) = domain_file_for(f) else {
            failures.push(format!("{}: no domain file found", f.display()));
            continue;
        };
        match load_domain(&dfile) {
            Ok(d) => {
                let start = Instant::now();
                if let Err(e) = load_problem(f, &d) {
                    failures.push(e.to_string());
                }
                let took = start.elapsed();
                if slowest.as_ref().is_none_or(|(t, _)| took > *t) {
                    slowest = Some((took, f.clone()));
                }
            }
            Err(e) => failures.push(e.to_string()),
        }
    }
    assert!(
        failures.is_empty(),
        "{} of {} files failed:\n{}",
        failures.len(),
        files.len(),
        failures.join("\n")
    );
    // For information only (timings are not asserted in tests).
    if let Some((t, f)) = slowest {
        let size = std::fs::metadata(&f).map(|m| m.len()).unwrap_or(0);
        eprintln!(
            "slowest problem: {} ({size} bytes) read and parsed in {t:?}",
            f.display()
        );
    }
    (domains, problems)
}

#[test]
#[ignore = "needs ../shared/benchmarks beside the checkout; .ci/run runs it when present"]
fn every_ipc2020_total_order_file_parses() {
    let b = benchmarks().expect("../shared/benchmarks beside the checkout");
    let start = Instant::now();
    let (d, p) = parse_folder(&b.join("ipc2020-total-order"));
    eprintln!(
        "parsed {d} domains and {p} problems in {:?}",
        start.elapsed()
    );
    assert!(
        d >= 18 && p >= 300,
        "suspiciously few files: {d} domains, {p} problems"
    );
}

#[test]
#[ignore = "needs ../shared/benchmarks beside the checkout; .ci/run runs it when present"]
fn every_feature_test_file_parses() {
    let b = benchmarks().expect("../shared/benchmarks beside the checkout");
    let (d, p) = parse_folder(&b.join("ipc2020-feature-tests"));
    assert!(
        d >= 10 && p >= 9,
        "suspiciously few files: {d} domains, {p} problems"
    );
}

#[test]
#[ignore = "needs ../shared/benchmarks beside the checkout; .ci/run runs it when present"]
fn the_hybrid_domain_in_other_is_refused_with_a_clear_error() {
    let b = benchmarks().expect("../shared/benchmarks beside the checkout");
    let f = b.join(
        "ipc2020-total-order/AssemblyHierarchical/other/Hybrid_Domain/verkabelung_domain_noComplexOperations.hddl",
    );
    if !f.is_file() {
        eprintln!("SKIPPED: {} is absent", f.display());
        return;
    }
    let e = load_domain(&f).unwrap_err();
    eprintln!("{e}");
    assert!(e.message.contains("hybrid"), "{e}");
    assert!(e.line > 0 && e.col > 0);
}

#[test]
#[ignore = "needs ../shared/benchmarks beside the checkout; .ci/run runs it when present"]
fn a_reversed_ordering_in_a_benchmark_is_followed() {
    let b = benchmarks().expect("../shared/benchmarks beside the checkout");
    let dir = b.join("ipc2020-total-order/Logistics-Learned-ECAI-16");
    let d = load_domain(dir.join("domain.hddl")).unwrap_or_else(|e| panic!("{e}"));
    let p = load_problem(dir.join("probLOGISTICS-09-1.hddl"), &d).unwrap_or_else(|e| panic!("{e}"));
    // The file lists task0..task8 and orders them `(< task8 task7) ... (< task1 task0)`.
    let ids: Vec<&str> = p
        .htn
        .subtasks
        .iter()
        .map(|s| s.id.as_deref().unwrap())
        .collect();
    let expected: Vec<String> = (0..ids.len()).rev().map(|i| format!("task{i}")).collect();
    assert_eq!(ids, expected);
    assert!(ids.len() >= 2);
    assert_eq!(
        p.htn.subtasks[0].name, "achieve-at",
        "names are lower-cased"
    );
}

/// Every HDDL file the project ships (`domains/`) parses, each problem with every domain of its
/// folder, and with no warning.
#[test]
fn every_shipped_file_parses_without_warnings() {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../domains");
    let files = hddl_files(&dir);
    assert!(files.len() >= 7, "{} files", files.len());
    for f in &files {
        if is_domain_file_name(f) {
            let d = load_domain(f).unwrap_or_else(|e| panic!("{e}"));
            assert!(d.warnings.is_empty(), "{:?}", d.warnings);
            continue;
        }
        // Each domain file of the problem's folder (the library has two).
        let domains: Vec<_> = files
            .iter()
            .filter(|d| is_domain_file_name(d) && d.parent() == f.parent())
            .collect();
        assert!(!domains.is_empty(), "no domain beside {}", f.display());
        for d in domains {
            let d = load_domain(d).unwrap_or_else(|e| panic!("{e}"));
            load_problem(f, &d).unwrap_or_else(|e| panic!("{e}"));
        }
    }
}

/// The IPC's AssemblyHierarchical names a parent type (`enum`) that it never declares: read, as
/// the competition's parser reads it, with a warning at the place.
#[test]
#[ignore = "needs ../shared/benchmarks beside the checkout; .ci/run runs it when present"]
fn an_undeclared_parent_type_is_a_warning() {
    let b = benchmarks().expect("../shared/benchmarks beside the checkout");
    let d = load_domain(b.join("ipc2020-total-order/AssemblyHierarchical/domain.hddl"))
        .unwrap_or_else(|e| panic!("{e}"));
    let w = d.warnings.first().expect("a warning");
    assert!(w.message.contains("parent type `enum`"), "{w}");
    assert!(w.line > 0 && w.col > 0, "{w}");
}
