//! Hostile input through the built binary: bad limits, full disks, closed pipes, devices as input,
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
    let d = std::path::Path::new(env!("CARGO_TARGET_TMPDIR"))
        .join(format!("htngtp-robustness-{}-{name}", std::process::id()));
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
        vec!["gtp", s(&scene), "pick", "grey-book"],
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
        stderr(&o).contains("more than the 4 MiB allowed"),
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

/// Runs the binary and measures its peak resident memory (VmHWM of /proc, polled every 5 ms
/// until it ends), in KiB.
fn run_measuring_memory(args: &[&str]) -> (Output, u64) {
    let mut child = Command::new(EXE)
        .args(args)
        .stdin(Stdio::null())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    let status = format!("/proc/{}/status", child.id());
    let mut measured_kb = 0u64;
    while child.try_wait().unwrap().is_none() {
        if let Ok(text) = std::fs::read_to_string(&status)
            && let Some(kb) = text
                .lines()
                .find(|l| l.starts_with("VmHWM:"))
                .and_then(|l| l.split_whitespace().nth(1)?.parse::<u64>().ok())
        {
            measured_kb = measured_kb.max(kb);
        }
        std::thread::sleep(std::time::Duration::from_millis(5));
    }
    (child.wait_with_output().unwrap(), measured_kb)
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
    // The test measures the child's peak resident memory itself besides what it reports.
    let (o, measured_kb) =
        run_measuring_memory(&["plan", s(&d), s(&p), "--memory-limit", "120", "--json"]);
    assert!(
        measured_kb / 1024 <= 120 + 50,
        "peak {} MiB measured",
        measured_kb / 1024
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

/// Two books that start inside one another are refused by name; `--allow-initial-contact`
/// reads the scene with a warning, but never a robot inside furniture.
#[test]
fn allow_initial_contact_reads_overlapping_objects_with_a_warning() {
    let dir = scratch("allow-contact");
    let books = library_scene_edited(
        &dir,
        "pose = { xyz = [-0.68, -0.86, 0.8602], rpy = [0, 90, -8] }",
        "pose = { xyz = [-0.48, -0.62, 0.8602], rpy = [0, 90, -8] }",
    );
    let refused = run(&["facts", s(&books)], Stdio::piped());
    assert_eq!(code(&refused), 3, "{}", stderr(&refused));
    assert!(stderr(&refused).contains("`white-book` starts inside `grey-book`"));
    let allowed = run(
        &["facts", s(&books), "--allow-initial-contact"],
        Stdio::piped(),
    );
    assert_eq!(code(&allowed), 0, "{}", stderr(&allowed));
    assert!(
        stderr(&allowed).contains("warning: "),
        "{}",
        stderr(&allowed)
    );
    assert!(stderr(&allowed).contains("--allow-initial-contact"));

    let robot = library_scene_edited(
        &dir,
        "base = { x = -0.72, y = 0.0, yaw = 0 }",
        "base = { x = 0.0, y = 0.0, yaw = 0 }",
    );
    let o = run(
        &[
            "gtp",
            s(&robot),
            "pick",
            "grey-book",
            "--allow-initial-contact",
        ],
        Stdio::piped(),
    );
    assert_eq!(code(&o), 3, "{}", stderr(&o));
    assert!(
        stderr(&o).contains("starts inside `desk`"),
        "{}",
        stderr(&o)
    );
}

/// The tiny domain with `from` replaced by `to`, written to `dir/name`.
fn tiny_domain_edited(dir: &Path, name: &str, from: &str, to: &str) -> PathBuf {
    let (d, _) = tiny_problem(dir);
    let text = std::fs::read_to_string(&d).unwrap();
    assert!(text.contains(from), "no `{from}` in the tiny domain");
    let path = dir.join(name);
    std::fs::write(&path, text.replace(from, to)).unwrap();
    path
}

/// What HDDL does not allow is refused through the binary (exit 3), each
/// with FILE:LINE:COL and a message that says what is wrong.
#[test]
fn hddl_the_language_does_not_allow_is_refused_with_its_place() {
    let dir = scratch("hddl-leniency");
    let (_, p) = tiny_problem(&dir);
    let cases: Vec<(PathBuf, &str)> = vec![
        (
            tiny_domain_edited(&dir, "nul.hddl", "(done))", "(do\0ne))"),
            ":1:66: control character U+0000 is not allowed",
        ),
        (
            tiny_domain_edited(&dir, "quoted.hddl", "(done))", "(\"done\"))"),
            ":1:64: quoted strings are not HDDL",
        ),
        (
            tiny_domain_edited(&dir, "bom.hddl", "(define", "\u{feff}(define"),
            ":1:1: a UTF-8 byte-order mark (U+FEFF)",
        ),
        (
            tiny_domain_edited(
                &dir,
                "number-type.hddl",
                "(:predicates",
                "(:types 123 - object) (:predicates",
            ),
            ":1:58: a name must start with a letter, found `123`",
        ),
        (
            tiny_domain_edited(
                &dir,
                "requirement.hddl",
                ":hierarchy",
                ":hierarchy :time-travel",
            ),
            ":1:49: unknown requirement `:time-travel`",
        ),
        (
            tiny_domain_edited(
                &dir,
                "action-twice.hddl",
                "(:action finish",
                "(:action finish :parameters ()) (:action finish",
            ),
            "`finish` is already declared as an action at",
        ),
        (
            // The method's `)` is missing: its section swallows the action after it.
            tiny_domain_edited(&dir, "unclosed.hddl", "(and (finish)))", "(and (finish))"),
            ":3:12: this `(` is never closed: the section `(:action` at 4:12 lies inside it",
        ),
    ];
    for (d, phrase) in cases {
        let o = run(&["plan", s(&d), s(&p)], Stdio::piped());
        let e = stderr(&o);
        assert_eq!(code(&o), 3, "{}: {e}", d.display());
        assert!(
            e.contains(phrase),
            "{}: expected `{phrase}` in\n{e}",
            d.display()
        );
        assert_eq!(e.lines().count(), 1, "one line: {e}");
    }
    // A problem's object named by a number.
    let (d, _) = tiny_problem(&dir);
    let bad = dir.join("number-object.hddl");
    std::fs::write(
        &bad,
        "(define (problem p) (:domain tiny) (:objects 123) (:htn :parameters () :ordered-subtasks (and (go))) (:init))",
    )
    .unwrap();
    let o = run(&["plan", s(&d), s(&bad)], Stdio::piped());
    assert_eq!(code(&o), 3, "{}", stderr(&o));
    assert!(
        stderr(&o).contains(":1:46: a name must start with a letter, found `123`"),
        "{}",
        stderr(&o)
    );
}

/// An undeclared parent type is read (as the IPC's files need) with a warning at its place.
#[test]
fn an_undeclared_parent_type_is_a_warning_through_the_binary() {
    let dir = scratch("parent-type");
    let (_, p) = tiny_problem(&dir);
    let d = tiny_domain_edited(
        &dir,
        "parent.hddl",
        "(:predicates",
        "(:types a - thing) (:predicates",
    );
    let o = run(&["plan", s(&d), s(&p)], Stdio::piped());
    assert_eq!(code(&o), 0, "{}", stderr(&o));
    assert!(
        stderr(&o).contains("warning: ".to_string().as_str())
            && stderr(&o).contains(":1:58: the parent type `thing` of `a` is not declared"),
        "{}",
        stderr(&o)
    );
}

/// `validate` cuts a 300 KB token in its messages, and calls an empty plan empty.
#[test]
fn validate_cuts_long_tokens_and_names_an_empty_plan() {
    let dir = scratch("validate-messages");
    let (d, p) = tiny_problem(&dir);
    let long = "x".repeat(300_000);
    for (name, text) in [
        (
            "long-name.plan",
            format!("==>\n1 {long}\nroot 0\n0 go -> m 1\n<==\n"),
        ),
        ("long-id.plan", format!("==>\n{long} finish\nroot 0\n<==\n")),
    ] {
        let plan = dir.join(name);
        std::fs::write(&plan, text).unwrap();
        let o = run(&["validate", s(&d), s(&p), s(&plan)], Stdio::piped());
        let all = format!("{}{}", String::from_utf8_lossy(&o.stdout), stderr(&o));
        assert!(matches!(code(&o), 1 | 3), "{all}");
        assert!(all.len() < 1000, "{name}: {} bytes of messages", all.len());
        assert!(all.contains("xxxx…"), "{name}: {all}");
    }
    let plan = dir.join("long-id.plan");
    let o = run(&["validate", s(&d), s(&p), s(&plan)], Stdio::piped());
    assert!(
        stderr(&o).contains("long-id.plan:2:1: `xxx"),
        "{}",
        stderr(&o)
    );
    let empty = dir.join("empty.plan");
    std::fs::write(&empty, "").unwrap();
    let o = run(&["validate", s(&d), s(&p), s(&empty)], Stdio::piped());
    assert_eq!(code(&o), 3, "{}", stderr(&o));
    let e = stderr(&o);
    assert!(e.contains("empty.plan: the plan is empty"), "{e}");
    assert!(!e.contains("line 0"), "{e}");
}

/// A GTP error under `plan --scene` is printed once.
#[test]
fn a_geometric_error_under_plan_scene_is_printed_once() {
    let dir = scratch("gtp-error-once");
    let lib = root().join("domains/library");
    let problem = dir.join("purple.hddl");
    let text = std::fs::read_to_string(lib.join("fig4.hddl")).unwrap();
    std::fs::write(&problem, text.replace("grey-book", "purple-book")).unwrap();
    let o = run(
        &[
            "plan",
            s(&lib.join("domain-compound.hddl")),
            s(&problem),
            "--scene",
            s(&lib.join("scene.toml")),
        ],
        Stdio::piped(),
    );
    let e = stderr(&o);
    assert_eq!(code(&o), 3, "{e}");
    assert_eq!(e.matches("no such object").count(), 1, "{e}");
    assert!(
        e.contains("argument object `purple-book`: no such object"),
        "{e}"
    );
}

/// The limits hold while reading: a memory limit smaller than the file stops the command with
/// exit 2 and says where, before the search; so does a time limit passed while reading
/// (a file far longer than can be read in the time given).
#[test]
fn limits_stop_reading_and_parsing_with_exit_2() {
    let dir = scratch("limits-while-reading");
    let (d, _) = tiny_problem(&dir);
    let objects: String = (0..200_000).map(|i| format!("o{i} ")).collect();
    let big = dir.join("big.hddl");
    std::fs::write(
        &big,
        format!(
            "(define (problem p) (:domain tiny) (:objects {objects}) (:htn :parameters () :ordered-subtasks (and (go))) (:init))"
        ),
    )
    .unwrap();
    let o = run(
        &["plan", s(&d), s(&big), "--memory-limit", "1"],
        Stdio::piped(),
    );
    assert_eq!(code(&o), 2, "{}", stderr(&o));
    assert!(
        stderr(&o).contains("stopped: memory limit reached while reading this file"),
        "{}",
        stderr(&o)
    );
    // A problem whose reading alone would take far more memory than allowed stops near the
    // limit (measured here).
    let objects: String = (0..1_000_000).map(|i| format!("o{i} ")).collect();
    let huge = dir.join("huge.hddl");
    std::fs::write(
        &huge,
        format!(
            "(define (problem p) (:domain tiny) (:objects {objects}) (:htn :parameters () :ordered-subtasks (and (go))) (:init))"
        ),
    )
    .unwrap();
    let (o, peak_kb) = run_measuring_memory(&["plan", s(&d), s(&huge), "--memory-limit", "40"]);
    assert_eq!(code(&o), 2, "{}", stderr(&o));
    assert!(
        stderr(&o).contains("stopped: memory limit reached while"),
        "{}",
        stderr(&o)
    );
    assert!(peak_kb / 1024 <= 40 + 50, "peak {} MiB", peak_kb / 1024);
    let o = run(
        &["plan", s(&d), s(&big), "--time-limit", "0.000001"],
        Stdio::piped(),
    );
    assert_eq!(code(&o), 2, "{}", stderr(&o));
    assert!(
        stderr(&o).contains("stopped: time limit reached while"),
        "{}",
        stderr(&o)
    );
    // bench-hddl counts such a child as stopped at its limit, not as a crash.
    let folder = dir.join("bench").join("tiny");
    std::fs::create_dir_all(&folder).unwrap();
    std::fs::copy(&d, folder.join("domain.hddl")).unwrap();
    std::fs::copy(&big, folder.join("p01.hddl")).unwrap();
    let csv = dir.join("bench.csv");
    let o = run(
        &[
            "bench-hddl",
            s(&dir.join("bench")),
            "--time-limit",
            "0.000001",
            "--csv",
            s(&csv),
        ],
        Stdio::piped(),
    );
    assert_eq!(code(&o), 0, "{}", stderr(&o));
    let rows = std::fs::read_to_string(&csv).unwrap();
    assert!(rows.contains("\ntiny,p01.hddl,limit-reached,"), "{rows}");
}

/// A scene with a 300 KB unknown key: `facts`, `gtp` and `render` say so in one short line, exit 3
/// (the whole key in the message once made a 512 KB error line).
#[test]
fn a_scene_error_quoting_a_huge_key_is_one_short_line() {
    let dir = scratch("huge-key");
    let scene = dir.join("scene.toml");
    std::fs::write(&scene, format!("[scene]\n{} = 1\n", "a".repeat(300_000))).unwrap();
    let s = scene.to_str().unwrap();
    let out = dir.join("x.png");
    for args in [
        vec!["facts", s],
        vec!["gtp", s, "pick", "book"],
        vec!["render", s, "--out", out.to_str().unwrap()],
    ] {
        let o = Command::new(EXE).args(&args).output().unwrap();
        let err = String::from_utf8_lossy(&o.stderr);
        assert_eq!(o.status.code(), Some(3), "{args:?}: {err:.300}");
        assert!(err.len() < 3000, "{args:?}: {} bytes", err.len());
        assert!(err.contains("unknown field"), "{args:?}: {err}");
        assert_eq!(err.lines().count(), 1, "{args:?}: {err}");
    }
}
