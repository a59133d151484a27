//! Issue 13 through the built binary: bad limits, full disks, closed pipes, devices as input,
//! far-away scene coordinates. Each test asserts the exit code and what the message says.

use std::path::{Path, PathBuf};
use std::process::{Command, Output, Stdio};

const EXE: &str = env!("CARGO_BIN_EXE_htngtp");

/// The repository root.
fn root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../..")
}

/// A fresh scratch directory for one test.
fn scratch(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("htngtp-robustness-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    d
}

/// A one-action symbolic problem (domain, problem) written into `dir`.
fn tiny_problem(dir: &Path) -> (PathBuf, PathBuf) {
    let d = dir.join("domain.hddl");
    let p = dir.join("problem.hddl");
    std::fs::write(
        &d,
        "(define (domain tiny) (:requirements :hierarchy) (:predicates (done))
           (:task go :parameters ())
           (:method m :parameters () :task (go) :ordered-subtasks (and (finish)))
           (:action finish :parameters () :effect (done)))",
    )
    .unwrap();
    std::fs::write(
        &p,
        "(define (problem p) (:domain tiny) (:htn :parameters () :ordered-subtasks (and (go))) (:init))",
    )
    .unwrap();
    (d, p)
}

/// The library scene with the member moved to `x` (URDF paths made absolute).
fn library_scene_with_member_at(dir: &Path, x: &str) -> PathBuf {
    library_scene_edited(
        dir,
        "base = { x = 0.68, y = 0.0, yaw = 180 }",
        &format!("base = {{ x = {x}, y = 0.0, yaw = 180 }}"),
    )
}

/// The library scene with `from` replaced by `to` (URDF paths made absolute).
fn library_scene_edited(dir: &Path, from: &str, to: &str) -> PathBuf {
    let models = root().join("models").canonicalize().unwrap();
    let text = std::fs::read_to_string(root().join("domains/library/scene.toml")).unwrap();
    assert!(
        text.contains(from),
        "the library scene changed: no `{from}`"
    );
    let text = text
        .replace("../../models", &models.display().to_string())
        .replace(from, to);
    let path = dir.join("edited.toml");
    std::fs::write(&path, text).unwrap();
    path
}

fn run(args: &[&str], stdout: Stdio) -> Output {
    Command::new(EXE)
        .args(args)
        .stdin(Stdio::null())
        .stdout(stdout)
        .stderr(Stdio::piped())
        .output()
        .unwrap()
}

fn code(o: &Output) -> i32 {
    o.status.code().expect("exited, not killed by a signal")
}

fn stderr(o: &Output) -> String {
    String::from_utf8_lossy(&o.stderr).into_owned()
}

fn s(p: &Path) -> &str {
    p.to_str().unwrap()
}

fn full_disk() -> Stdio {
    Stdio::from(std::fs::File::create("/dev/full").unwrap())
}

#[test]
fn time_limits_that_are_not_durations_are_bad_input() {
    let dir = scratch("time-limits");
    let (d, p) = tiny_problem(&dir);
    for bad in ["inf", "nan", "1e20", "-1", "0"] {
        let flag = format!("--time-limit={bad}");
        for cmd in [
            vec!["plan", s(&d), s(&p), &flag],
            vec!["bench-hddl", s(&dir), &flag],
        ] {
            let o = run(&cmd, Stdio::piped());
            assert_eq!(code(&o), 3, "{cmd:?}: {}", stderr(&o));
            assert!(
                stderr(&o).contains("expected seconds"),
                "{cmd:?}: {}",
                stderr(&o)
            );
        }
    }
}

#[test]
fn plan_help_states_the_default_limits() {
    let o = run(&["plan", "--help"], Stdio::piped());
    let help = String::from_utf8_lossy(&o.stdout);
    assert!(help.contains("[default: 300]"), "{help}");
    assert!(help.contains("[default: 8192]"), "{help}");
}

#[test]
fn writing_to_a_full_disk_is_an_error_not_a_panic() {
    let dir = scratch("full-disk");
    let (d, p) = tiny_problem(&dir);
    let plan = run(&["plan", s(&d), s(&p)], Stdio::piped());
    assert_eq!(code(&plan), 0, "{}", stderr(&plan));
    let plan_file = dir.join("plan.txt");
    std::fs::write(&plan_file, &plan.stdout).unwrap();
    let scene = root().join("domains/library/scene.toml");
    for cmd in [
        vec!["plan", s(&d), s(&p)],
        vec!["validate", s(&d), s(&p), s(&plan_file)],
        vec!["facts", s(&scene)],
    ] {
        let o = run(&cmd, full_disk());
        assert_eq!(code(&o), 3, "{cmd:?}: {}", stderr(&o));
        assert!(
            stderr(&o).contains("cannot write the output"),
            "{cmd:?}: {}",
            stderr(&o)
        );
        assert!(!stderr(&o).contains("panicked"), "{cmd:?}: {}", stderr(&o));
    }
}

#[test]
fn a_closed_output_pipe_ends_quietly() {
    let dir = scratch("closed-pipe");
    let (d, p) = tiny_problem(&dir);
    // A plan longer than a pipe's buffer: the planner cannot finish writing before the pipe
    // is closed, whoever the scheduler runs first.
    let tasks = "(go) ".repeat(10_000);
    std::fs::write(
        &p,
        format!("(define (problem p) (:domain tiny) (:htn :parameters () :ordered-subtasks (and {tasks})) (:init))"),
    )
    .unwrap();
    let mut child = Command::new(EXE)
        .args(["plan", s(&d), s(&p)])
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    drop(child.stdout.take()); // closed before the planner can write
    let o = child.wait_with_output().unwrap();
    assert_eq!(code(&o), 141, "{}", stderr(&o));
    assert!(!stderr(&o).contains("panicked"), "{}", stderr(&o));
}

#[test]
fn render_to_a_full_disk_fails() {
    let scene = root().join("domains/library/scene.toml");
    let o = run(
        &[
            "render",
            s(&scene),
            "--view",
            "top",
            "--width",
            "16",
            "--out",
            "/dev/full",
        ],
        Stdio::piped(),
    );
    assert_eq!(code(&o), 3, "{}", stderr(&o));
    assert!(stderr(&o).contains("cannot write PNG"), "{}", stderr(&o));
    assert!(!stderr(&o).contains("wrote"), "{}", stderr(&o));
}

#[test]
fn devices_and_directories_as_input_are_refused() {
    let dir = scratch("devices");
    let (d, p) = tiny_problem(&dir);
    let o = run(&["plan", "/dev/zero", s(&p)], Stdio::piped());
    assert_eq!(code(&o), 3);
    assert!(
        stderr(&o).contains("/dev/zero: is a device"),
        "{}",
        stderr(&o)
    );
    let o = run(&["validate", s(&d), s(&p), "/dev/urandom"], Stdio::piped());
    assert_eq!(code(&o), 3);
    assert!(
        stderr(&o).contains("/dev/urandom: is a device"),
        "{}",
        stderr(&o)
    );
    let o = run(&["plan", s(&d), s(&dir)], Stdio::piped());
    assert_eq!(code(&o), 3);
    assert!(stderr(&o).contains("is a directory"), "{}", stderr(&o));
    let o = run(&["facts", "/dev/zero"], Stdio::piped());
    assert_eq!(code(&o), 3);
    assert!(
        stderr(&o).contains("more than the 64 MiB allowed"),
        "{}",
        stderr(&o)
    );
}

#[test]
fn an_input_over_the_cap_is_refused_before_reading() {
    let dir = scratch("cap");
    let (d, p) = tiny_problem(&dir);
    let big = dir.join("big.hddl");
    let f = std::fs::File::create(&big).unwrap();
    f.set_len(2 << 20).unwrap(); // 2 MiB, sparse
    let o = Command::new(EXE)
        .args(["plan", s(&d), s(&big)])
        .env("HTNGTP_MAX_INPUT_MIB", "1")
        .output()
        .unwrap();
    assert_eq!(code(&o), 3);
    assert!(
        stderr(&o).contains("more than the 1 MiB input cap"),
        "{}",
        stderr(&o)
    );
    let _ = p;
}

#[test]
fn a_far_away_person_is_an_error_with_its_key_path() {
    let dir = scratch("far");
    let scene = library_scene_with_member_at(&dir, "1e30");
    let o = run(
        &["gtp", s(&scene), "give", "grey-book", "member"],
        Stdio::piped(),
    );
    assert_eq!(code(&o), 3, "{}", stderr(&o));
    assert!(
        stderr(&o).contains("agents[1].base: values [1e30, 0.0] lie outside the world"),
        "{}",
        stderr(&o)
    );
}

/// The children of process `pid` (all its threads'), from /proc.
fn children(pid: u32) -> Vec<u32> {
    let Ok(tasks) = std::fs::read_dir(format!("/proc/{pid}/task")) else {
        return Vec::new();
    };
    tasks
        .filter_map(|t| std::fs::read_to_string(t.ok()?.path().join("children")).ok())
        .flat_map(|s| {
            s.split_whitespace()
                .filter_map(|p| p.parse().ok())
                .collect::<Vec<u32>>()
        })
        .collect()
}

fn alive(pid: u32) -> bool {
    std::fs::read_to_string(format!("/proc/{pid}/stat")).is_ok_and(|s| {
        !s.rsplit(')')
            .next()
            .unwrap_or("")
            .trim_start()
            .starts_with('Z')
    })
}

/// Polls `done` every 20 ms for up to 20 s (a liveness bound, not a measurement).
fn eventually(mut done: impl FnMut() -> bool) -> bool {
    (0..1000).any(|_| {
        std::thread::sleep(std::time::Duration::from_millis(20));
        done()
    })
}

/// SIGTERM to `bench-hddl` ends the child planner too, and the CSV keeps the finished rows.
#[test]
fn bench_hddl_interrupted_keeps_its_rows_and_leaves_no_child() {
    let dir = scratch("bench-hddl");
    let tiny = dir.join("a-tiny");
    std::fs::create_dir_all(&tiny).unwrap();
    tiny_problem(&tiny);
    std::fs::rename(tiny.join("problem.hddl"), tiny.join("p01.hddl")).unwrap();
    let endless = dir.join("b-counter");
    std::fs::create_dir_all(&endless).unwrap();
    let htn_tests = root().join("crates/htn/tests/domains");
    std::fs::copy(
        htn_tests.join("counter-domain.hddl"),
        endless.join("domain.hddl"),
    )
    .unwrap();
    std::fs::copy(htn_tests.join("counter.hddl"), endless.join("p01.hddl")).unwrap();
    let csv = dir.join("rows.csv");
    let mut bench = Command::new(EXE)
        .args([
            "bench-hddl",
            s(&dir),
            "--time-limit",
            "120",
            "--csv",
            s(&csv),
        ])
        .stdout(Stdio::null())
        .stderr(Stdio::null())
        .spawn()
        .unwrap();
    let mut child = None;
    let started = eventually(|| {
        child = children(bench.id()).into_iter().find(|&c| {
            std::fs::read(format!("/proc/{c}/cmdline"))
                .is_ok_and(|b| String::from_utf8_lossy(&b).contains("b-counter"))
        });
        child.is_some()
    });
    assert!(started, "the endless problem's planner never started");
    let child = child.unwrap();
    let killed = Command::new("kill").arg(bench.id().to_string()).status();
    assert!(killed.unwrap().success());
    bench.wait().unwrap();
    assert!(
        eventually(|| !alive(child)),
        "the child planner {child} outlived bench-hddl"
    );
    let rows = std::fs::read_to_string(&csv).unwrap();
    assert!(rows.starts_with("domain,problem,status,"), "{rows}");
    assert!(rows.contains("\na-tiny,p01.hddl,found,"), "{rows}");
}

/// An endless search (a count that only grows) stops at the memory limit, says so, and its
/// peak resident memory stays within 50 MiB of the limit.
#[test]
fn the_memory_limit_stops_an_endless_search_near_the_limit() {
    let htn_tests = root().join("crates/htn/tests/domains");
    let (d, p) = (
        htn_tests.join("counter-domain.hddl"),
        htn_tests.join("counter.hddl"),
    );
    let o = run(
        &["plan", s(&d), s(&p), "--memory-limit", "120", "--json"],
        Stdio::piped(),
    );
    assert_eq!(code(&o), 2, "{}", stderr(&o));
    let v: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    assert_eq!(v["status"], "limit-reached");
    assert_eq!(v["limit"], "memory");
    let peak_mib = v["peak_memory_kb"].as_u64().unwrap() / 1024;
    assert!(peak_mib <= 120 + 50, "peak {peak_mib} MiB");
}

/// A robot standing inside the desk is refused at load, naming both, not planned in.
#[test]
fn a_scene_that_starts_in_collision_is_refused_by_name() {
    let dir = scratch("in-collision");
    let scene = library_scene_edited(
        &dir,
        "base = { x = -0.72, y = 0.0, yaw = 0 }",
        "base = { x = 0.0, y = 0.0, yaw = 0 }",
    );
    let lib = root().join("domains/library");
    let (d, p) = (lib.join("domain-compound.hddl"), lib.join("fig4.hddl"));
    let o = run(
        &["plan", s(&d), s(&p), "--scene", s(&scene)],
        Stdio::piped(),
    );
    assert_eq!(code(&o), 3, "{}", stderr(&o));
    let e = stderr(&o);
    assert!(e.contains("agents[0]: `pr2` (its link"), "{e}");
    assert!(e.contains("starts inside `desk`"), "{e}");
}
