//! `htngtp check` as a user runs it: exit codes, the summary line, the JSON report, on a plan
//! the binary itself produces and on bad input. Whether the planner's plan is clean is not
//! asserted (that is the planner's business); only that the checker reads it and answers.

use std::path::PathBuf;
use std::process::Command;

fn htngtp() -> Command {
    Command::new(env!("CARGO_BIN_EXE_htngtp"))
}

fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../..")
}

fn temp(name: &str) -> PathBuf {
    let dir = std::path::Path::new(env!("CARGO_TARGET_TMPDIR"))
        .join(format!("htngtp-check-cli-{}", std::process::id()));
    std::fs::create_dir_all(&dir).expect("temp dir");
    dir.join(name)
}

#[test]
fn checks_a_plan_the_planner_wrote() {
    let lib = root().join("domains/library");
    let plan = temp("plan.json");
    let status = htngtp()
        .args(["plan"])
        .arg(lib.join("domain.hddl"))
        .arg(lib.join("lend-and-debit.hddl"))
        .arg("--scene")
        .arg(lib.join("scene.toml"))
        .args(["--strategy", "symbolic", "--seed", "1", "--json-out"])
        .arg(&plan)
        .output()
        .expect("runs");
    assert!(
        status.status.success(),
        "{}",
        String::from_utf8_lossy(&status.stderr)
    );
    let out = htngtp().arg("check").arg(&plan).output().expect("runs");
    let code = out.status.code();
    assert!(matches!(code, Some(0 | 1)), "exit {code:?}");
    let text = String::from_utf8_lossy(&out.stdout);
    let last = text.lines().last().unwrap_or_default();
    let summary_ok = if code == Some(0) {
        last.starts_with("clean: 0 faults in 9 steps")
    } else {
        last.contains(" faults: ")
    };
    assert!(summary_ok, "{last}");
    let out = htngtp()
        .args(["check", "--json"])
        .arg(&plan)
        .output()
        .expect("runs");
    let v: serde_json::Value = serde_json::from_slice(&out.stdout).expect("a JSON report");
    assert_eq!(v["steps"], 9);
    assert!(v["frames"].as_u64().is_some_and(|f| f > 100));
}

#[test]
fn bad_input_exits_3_with_the_place() {
    let bad = temp("bad.json");
    std::fs::write(&bad, "{\n  \"scene\": {\n    \"objects\": [1,]\n").expect("write");
    let out = htngtp().arg("check").arg(&bad).output().expect("runs");
    assert_eq!(out.status.code(), Some(3));
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(
        err.contains("bad.json: not valid JSON at line 3, column"),
        "{err}"
    );

    std::fs::write(&bad, r#"{"scene": {"objects": [], "agents": []}}"#).expect("write");
    let out = htngtp().arg("check").arg(&bad).output().expect("runs");
    assert_eq!(out.status.code(), Some(3));
    assert!(String::from_utf8_lossy(&out.stderr).contains("missing key `steps`"));

    let out = htngtp()
        .args(["check", "/nonexistent/plan.json"])
        .output()
        .expect("runs");
    assert_eq!(out.status.code(), Some(3));
    let out = htngtp()
        .args(["check", "--sub", "2"])
        .arg(&bad)
        .output()
        .expect("runs");
    assert_eq!(
        out.status.code(),
        Some(3),
        "fewer than 4 sub-frames is refused"
    );
}

/// Found by the fuzz harness: a shape of 1e30 m (or a point at 1e308, infinite as f32) made
/// the collision library panic. Such numbers are bad input now, named by key path.
#[test]
fn astronomical_sizes_and_coordinates_are_bad_input_not_a_panic() {
    let text = std::fs::read_to_string(root().join("viewer/fixtures/sample-plan.json")).unwrap();
    let sample: serde_json::Value = serde_json::from_str(&text).unwrap();
    for (key, field, value) in [
        (
            "half_extents[0]",
            "half_extents",
            serde_json::json!([1e30, 0.1, 0.1]),
        ),
        (
            "capsule.a[2]",
            "capsule",
            serde_json::json!({"a": [0, 0, 1e308], "b": [0.4, 0, 0], "radius": 0.06}),
        ),
        (
            "capsule.radius",
            "capsule",
            serde_json::json!({"a": [0, 0, 0], "b": [0.4, 0, 0], "radius": 1e-30}),
        ),
    ] {
        let mut v = sample.clone();
        *find_key(&mut v, field).expect("the sample plan has the shape") = value;
        let plan = temp(&format!(
            "astronomical-{}.json",
            key.replace(['[', ']', '.'], "_")
        ));
        std::fs::write(&plan, serde_json::to_string(&v).unwrap()).unwrap();
        let out = htngtp().arg("check").arg(&plan).output().expect("runs");
        let err = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(3), "{key}: {err}");
        assert!(err.contains(key), "{key}: {err}");
        assert!(!err.contains("panicked"), "{err}");
    }
}

/// The first value under `key` anywhere in `v`.
fn find_key<'a>(v: &'a mut serde_json::Value, key: &str) -> Option<&'a mut serde_json::Value> {
    match v {
        serde_json::Value::Object(m) => {
            if m.contains_key(key) {
                return m.get_mut(key);
            }
            m.values_mut().find_map(|x| find_key(x, key))
        }
        serde_json::Value::Array(a) => a.iter_mut().find_map(|x| find_key(x, key)),
        _ => None,
    }
}
