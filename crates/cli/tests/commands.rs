//! The binary as a user runs it: each exit code reached (0 plan, 1 proven unsolvable or
//! invalid, 2 limit, 3 bad input), combined planning in the library scene with its report,
//! `facts --json`, `gtp`, and `validate` on a plan the binary printed and on a broken one.

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../..")
}

fn htn_file(name: &str) -> PathBuf {
    root().join("crates/htn/tests/domains").join(name)
}

fn library(name: &str) -> PathBuf {
    root().join("domains/library").join(name)
}

fn htngtp(args: &[&str], files: &[&Path]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_htngtp"))
        .args(args.iter().take(1))
        .args(files)
        .args(args.iter().skip(1))
        .output()
        .expect("htngtp runs")
}

fn text(bytes: &[u8]) -> String {
    String::from_utf8_lossy(bytes).into_owned()
}

fn scratch(name: &str) -> PathBuf {
    let dir = std::path::Path::new(env!("CARGO_TARGET_TMPDIR"))
        .join(format!("htngtp-cmd-{name}-{}", std::process::id()));
    std::fs::create_dir_all(&dir).expect("temp dir");
    dir
}

#[test]
fn a_plan_is_printed_in_the_competition_format_and_validates() {
    let (d, p) = (
        htn_file("payment-domain.hddl"),
        htn_file("payment-credit-7.hddl"),
    );
    let out = htngtp(&["plan"], &[&d, &p]);
    assert_eq!(out.status.code(), Some(0), "{}", text(&out.stderr));
    let plan = text(&out.stdout);
    assert!(plan.starts_with("==>") && plan.contains("root"), "{plan}");
    assert!(text(&out.stderr).contains("plan found and validated"));

    let dir = scratch("validate");
    let file = dir.join("plan.txt");
    std::fs::write(&file, &plan).unwrap();
    let ok = htngtp(&["validate"], &[&d, &p, &file]);
    assert_eq!(ok.status.code(), Some(0), "{}", text(&ok.stdout));
    // The first action dropped: the decomposition no longer matches the actions.
    let first = plan.lines().nth(1).expect("an action line");
    std::fs::write(&file, plan.replacen(&format!("{first}\n"), "", 1)).unwrap();
    let bad = htngtp(&["validate"], &[&d, &p, &file]);
    let _ = std::fs::remove_dir_all(&dir);
    assert_eq!(bad.status.code(), Some(1), "{}", text(&bad.stdout));
}

#[test]
fn a_complete_search_without_a_plan_exits_1() {
    let out = htngtp(
        &["plan"],
        &[
            &htn_file("payment-domain.hddl"),
            &htn_file("unsolvable.hddl"),
        ],
    );
    assert_eq!(out.status.code(), Some(1), "{}", text(&out.stderr));
    assert!(text(&out.stderr).contains("no plan exists"));
}

#[test]
fn a_limit_exits_2_and_names_the_limit() {
    let out = htngtp(
        &["plan", "--node-limit", "1"],
        &[
            &htn_file("payment-domain.hddl"),
            &htn_file("payment-credit-20.hddl"),
        ],
    );
    assert_eq!(out.status.code(), Some(2), "{}", text(&out.stderr));
    assert!(
        text(&out.stderr).contains("node limit"),
        "{}",
        text(&out.stderr)
    );
}

#[test]
fn bad_input_exits_3_with_file_line_and_column() {
    let dir = scratch("bad");
    let broken = dir.join("broken.hddl");
    std::fs::write(
        &broken,
        "(define (domain d)\n  (:requirements :typing)\n  (:types a - ))\n",
    )
    .unwrap();
    let out = htngtp(&["plan"], &[&broken, &htn_file("counter.hddl")]);
    let _ = std::fs::remove_dir_all(&dir);
    assert_eq!(out.status.code(), Some(3));
    let err = text(&out.stderr);
    assert!(
        err.contains("broken.hddl:3:13: expected a type name"),
        "{err}"
    );
}

#[test]
fn combined_planning_reports_each_gtp_solution_and_writes_the_plan_json() {
    let dir = scratch("scene");
    let json = dir.join("plan.json");
    let out = htngtp(
        &["plan", "--strategy", "chronological", "--seed", "1"],
        &[
            &library("domain-compound.hddl"),
            &library("pay-by-card.hddl"),
            Path::new("--scene"),
            &library("scene.toml"),
            Path::new("--json-out"),
            &json,
        ],
    );
    assert_eq!(out.status.code(), Some(0), "{}", text(&out.stderr));
    let report = text(&out.stdout);
    assert!(
        report.contains("Decomposition:") && report.contains("GTP: "),
        "{report}"
    );
    assert!(
        report.contains("grasp ") && report.contains("trajectory length"),
        "{report}"
    );
    let plan: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&json).unwrap()).unwrap();
    let _ = std::fs::remove_dir_all(&dir);
    let steps = plan["steps"].as_array().expect("steps");
    assert!(steps.iter().any(|s| {
        s["gtp"]["trajectories"]
            .as_array()
            .is_some_and(|t| !t.is_empty())
    }));
}

#[test]
fn facts_json_lists_the_shared_literals_of_the_library() {
    let out = htngtp(&["facts", "--json"], &[&library("scene.toml")]);
    assert_eq!(out.status.code(), Some(0), "{}", text(&out.stderr));
    let facts: serde_json::Value = serde_json::from_slice(&out.stdout).expect("JSON");
    let has = |pred: &str, a: &str| {
        facts
            .as_array()
            .unwrap()
            .iter()
            .any(|f| f["predicate"] == pred && f["args"].as_array().is_some_and(|x| x[0] == a))
    };
    assert!(has("visible", "grey-book") && has("reachable", "grey-book") && has("on", "grey-book"));
}

#[test]
fn one_gtp_task_from_the_command_line() {
    let out = htngtp(
        &["gtp", "make-accessible", "grey-book", "member", "--json"],
        &[&library("scene.toml")],
    );
    assert_eq!(out.status.code(), Some(0), "{}", text(&out.stderr));
    assert!(text(&out.stdout).contains("grey-book"));
    let unknown = htngtp(
        &["gtp", "make-accessible", "no-such-book", "member"],
        &[&library("scene.toml")],
    );
    assert_eq!(unknown.status.code(), Some(3), "{}", text(&unknown.stderr));
}

/// `plan --gtp-set` takes the thresholds of `gtp --set`, checked before any search: an unknown
/// key or a bad value is bad input (exit 3) naming the setting.
#[test]
fn plan_gtp_settings_are_checked_before_the_search() {
    let files = [
        &*library("domain.hddl"),
        &*library("fig4.hddl"),
        &*library("scene.toml"),
    ];
    for (setting, said) in [
        ("robot-effort=9", "robot-effort"),
        ("colour=red", "unknown constraint"),
        ("robot-effort", "KEY=VALUE"),
    ] {
        let out = Command::new(env!("CARGO_BIN_EXE_htngtp"))
            .arg("plan")
            .args(&files[..2])
            .arg("--scene")
            .arg(files[2])
            .args(["--gtp-set", setting])
            .output()
            .expect("htngtp runs");
        assert_eq!(
            out.status.code(),
            Some(3),
            "{setting}: {}",
            text(&out.stderr)
        );
        assert!(text(&out.stderr).contains(said), "{}", text(&out.stderr));
    }
}

/// `bench library --layout room`: the rooms are written as scene files that plan again, the
/// `--json` summary has success and GTP latencies per strategy, and `--save-scenes` without a
/// random layout is refused.
#[test]
fn random_rooms_are_saved_and_summarised() {
    let dir = scratch("rooms");
    let (scenes, json) = (dir.join("scenes"), dir.join("summary.json"));
    let run = Command::new(env!("CARGO_BIN_EXE_htngtp"))
        .args([
            "bench", "library", "--layout", "room", "--runs", "2", "--seed", "1",
        ])
        .args([
            "--strategy",
            "geometric-first",
            "--time-limit",
            "30",
            "--out",
        ])
        .arg(dir.join("out"))
        .arg("--save-scenes")
        .arg(&scenes)
        .arg("--json")
        .arg(&json)
        .output()
        .expect("htngtp runs");
    assert_eq!(run.status.code(), Some(0), "{}", text(&run.stderr));
    assert!(text(&run.stdout).contains("### Random rooms (geometric-first)"));
    let summary: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&json).unwrap()).unwrap();
    let s = &summary["strategies"][0];
    assert_eq!(s["strategy"], "geometric-first");
    assert_eq!(s["runs"], 2);
    let latency = &s["gtp_latency"];
    assert!(latency["requests"].as_u64().unwrap() > 0, "{summary}");
    assert!(latency["p99_ms"].as_f64().unwrap() <= latency["max_ms"].as_f64().unwrap());
    for i in 0..2 {
        let scene = scenes.join(format!("layout-00{i}.toml"));
        let facts = htngtp(&["facts"], &[&scene]);
        assert_eq!(facts.status.code(), Some(0), "{}", text(&facts.stderr));
    }
    let refused = htngtp(&["bench", "library", "--save-scenes", "x"], &[]);
    assert_eq!(refused.status.code(), Some(3), "{}", text(&refused.stderr));
    assert!(text(&refused.stderr).contains("--layout random or room"));
    let _ = std::fs::remove_dir_all(&dir);
}
