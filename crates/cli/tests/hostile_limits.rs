//! The limits hold on hostile problems, through the binary: each generated problem
//! (`hostile_support`) runs as `htngtp plan --json` under a time and a memory limit, and must
//! stop within 10 % (at least 0.2 s) of the time limit, wall clock measured here from spawn to
//! exit, with the process's peak resident memory (the kernel's high-water mark) under the
//! memory limit, and say which limit stopped it (or prove, exit 1, that there is no plan).
//! The problems of one test run one after another.

mod hostile_support;

use std::path::Path;
use std::process::{Command, Stdio};
use std::time::{Duration, Instant};

/// The limits of a run: seconds, MiB.
#[derive(Clone, Copy)]
struct Limits(f64, u64);

/// The limits of most runs.
const SMALL: Limits = Limits(2.0, 300);

/// The binary under test: `HTNGTP_BIN` when set (a release build), else this build's.
fn binary() -> String {
    std::env::var("HTNGTP_BIN").unwrap_or_else(|_| env!("CARGO_BIN_EXE_htngtp").to_string())
}

/// How long a run may take before it is killed (an overrun is a fault either way).
const KILL_AFTER: Duration = Duration::from_secs(30);

/// Runs one problem; returns the exit code (`None`: killed), the wall time and the JSON
/// answer (`Null` when it gave none).
fn run(
    h: &hostile_support::Hostile,
    dir: &Path,
    Limits(time, memory_mb): Limits,
) -> (Option<i32>, Duration, serde_json::Value) {
    let (d, p) = (dir.join("domain.hddl"), dir.join("problem.hddl"));
    if let Some(keep) = std::env::var_os("HTNGTP_HOSTILE_KEEP") {
        // Keep every problem for a closer look: `HTNGTP_HOSTILE_KEEP=DIR`.
        let keep = Path::new(&keep).join(h.name.split(':').next().unwrap_or("problem"));
        std::fs::create_dir_all(&keep).unwrap();
        std::fs::write(keep.join("domain.hddl"), &h.domain).unwrap();
        std::fs::write(keep.join("problem.hddl"), &h.problem).unwrap();
    }
    std::fs::write(&d, &h.domain).unwrap();
    std::fs::write(&p, &h.problem).unwrap();
    let out_path = dir.join("answer.json");
    let t = Instant::now();
    let mut child = Command::new(binary())
        .arg("plan")
        .arg(&d)
        .arg(&p)
        .args(["--time-limit", &time.to_string()])
        .args(["--memory-limit", &memory_mb.to_string()])
        .arg("--json")
        .stdout(std::fs::File::create(&out_path).unwrap())
        .stderr(Stdio::null())
        .spawn()
        .unwrap();
    let code = loop {
        if let Some(status) = child.try_wait().unwrap() {
            break status.code();
        }
        if t.elapsed() > KILL_AFTER {
            child.kill().ok();
            child.wait().ok();
            break None;
        }
        std::thread::sleep(Duration::from_millis(5));
    };
    let wall = t.elapsed();
    let text = std::fs::read(&out_path).unwrap_or_default();
    let json = serde_json::from_slice(&text).unwrap_or(serde_json::Value::Null);
    (code, wall, json)
}

/// The faults of one run: over the time limit (with its slack), over the memory limit, or an
/// answer that is neither a named limit nor a proven "no plan".
fn faults_of(h: &hostile_support::Hostile, dir: &Path, limits: Limits) -> Vec<String> {
    let Limits(time, memory_mb) = limits;
    let (code, wall, json) = run(h, dir, limits);
    // No answer (killed): counted as over the limit.
    let peak_mb = json["peak_memory_kb"]
        .as_u64()
        .map_or(f64::INFINITY, |kb| kb as f64 / 1024.0);
    eprintln!(
        "{}: exit {code:?}, {:.2} s, {peak_mb:.1} MiB, status {}, limit {}",
        h.name,
        wall.as_secs_f64(),
        json["status"],
        json["limit"]
    );
    let mut faults = Vec::new();
    let slack = (time * 0.1).max(0.2);
    if wall.as_secs_f64() > time + slack {
        faults.push(format!("{}: {:.2} s", h.name, wall.as_secs_f64()));
    }
    if peak_mb > memory_mb as f64 {
        faults.push(format!("{}: {peak_mb:.1} MiB", h.name));
    }
    match code {
        // A limit, and which one.
        Some(2) => {
            let limit = json["limit"].as_str().unwrap_or("");
            if !["time", "memory"].contains(&limit) {
                faults.push(format!("{}: exit 2 naming limit {limit:?}", h.name));
            }
        }
        // No plan, after a complete search.
        Some(1) if json["status"] == "unsolvable" => {}
        _ => faults.push(format!("{}: exit {code:?}: {json}", h.name)),
    }
    faults
}

fn scratch(what: &str) -> std::path::PathBuf {
    let dir = std::path::Path::new(env!("CARGO_TARGET_TMPDIR"))
        .join(format!("htngtp-{what}-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

#[test]
fn every_hostile_problem_stops_at_its_limits() {
    let dir = scratch("hostile");
    let faults: Vec<String> = hostile_support::all()
        .iter()
        .flat_map(|h| faults_of(h, &dir, SMALL))
        .collect();
    std::fs::remove_dir_all(&dir).ok();
    assert!(faults.is_empty(), "limits overrun: {faults:#?}");
}

#[test]
fn hostile_problems_of_random_sizes_stop_at_their_limits() {
    let dir = scratch("hostile-random");
    let faults: Vec<String> = hostile_support::random(11, 6)
        .iter()
        .flat_map(|h| faults_of(h, &dir, SMALL))
        .collect();
    std::fs::remove_dir_all(&dir).ok();
    assert!(faults.is_empty(), "limits overrun: {faults:#?}");
}

#[test]
fn a_node_of_a_million_successors_stays_under_a_gigabyte() {
    // The best-first search's first node has every binding of twelve wide actions as a
    // successor: its tables double between two nodes.
    let dir = scratch("hostile-large");
    let faults = faults_of(
        &hostile_support::wide_actions(40, 12),
        &dir,
        Limits(5.0, 1024),
    );
    std::fs::remove_dir_all(&dir).ok();
    assert!(faults.is_empty(), "limits overrun: {faults:#?}");
}
