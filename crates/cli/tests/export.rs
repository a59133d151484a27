//! `htngtp export --format joint-trajectory-yaml`: a library problem is planned, its plan JSON
//! checked clean (timing included), exported, and every YAML file parsed back (by the small
//! reader below, which knows the block layout of ROS's JointTrajectory and flow sequences of
//! numbers) into exactly the joint names, positions, velocities and times of the JSON's points.

use std::path::{Path, PathBuf};
use std::process::Command;

use serde_json::Value;

fn htngtp() -> Command {
    Command::new(env!("CARGO_BIN_EXE_htngtp"))
}

/// `htngtp export PLAN --format joint-trajectory-yaml DIR`.
fn export(plan: &Path, dir: impl AsRef<Path>) -> std::process::Output {
    htngtp()
        .arg("export")
        .arg(plan)
        .args(["--format", "joint-trajectory-yaml"])
        .arg(dir.as_ref())
        .output()
        .expect("runs")
}

fn library(name: &str) -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("../../domains/library")
        .join(name)
}

fn scratch(name: &str) -> PathBuf {
    let dir = std::path::Path::new(env!("CARGO_TARGET_TMPDIR"))
        .join(format!("htngtp-export-{name}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).expect("temp dir");
    dir
}

/// One point as read back: (positions, velocities, accelerations, sec, nanosec).
type Point = (Vec<f64>, Vec<f64>, Vec<f64>, i64, u32);

/// One JointTrajectory as read back from YAML.
#[derive(Debug, Default)]
struct Read {
    frame_id: String,
    joint_names: Vec<String>,
    points: Vec<Point>,
}

fn flow(s: &str) -> Vec<f64> {
    let inner = s
        .trim()
        .strip_prefix('[')
        .and_then(|s| s.strip_suffix(']'))
        .expect("a flow sequence");
    inner
        .split(',')
        .map(str::trim)
        .filter(|x| !x.is_empty())
        .map(|x| x.parse().expect("a number"))
        .collect()
}

fn unquote(s: &str) -> String {
    serde_json::from_str(s.trim()).expect("a double-quoted string")
}

/// Reads the block layout `htngtp export` writes: top-level keys, `- ` items, `key: value`.
fn read(yaml: &str) -> Read {
    let mut r = Read::default();
    let mut section = "";
    for line in yaml.lines() {
        if line.trim_start().starts_with('#') || line.trim().is_empty() {
            continue;
        }
        if !line.starts_with(' ') {
            section = line.split(':').next().unwrap();
            continue;
        }
        let item = line.trim_start();
        let (item, new) = match item.strip_prefix("- ") {
            Some(rest) => (rest, true),
            None => (item, false),
        };
        match section {
            "header" => {
                if let Some(v) = item.strip_prefix("frame_id:") {
                    r.frame_id = unquote(v);
                }
            }
            "joint_names" => r.joint_names.push(unquote(item)),
            "points" => {
                if new {
                    r.points.push(Default::default());
                }
                let p = r.points.last_mut().expect("a point");
                let (key, value) = item.split_once(':').expect("key: value");
                match key {
                    "positions" => p.0 = flow(value),
                    "velocities" => p.1 = flow(value),
                    "accelerations" => p.2 = flow(value),
                    "effort" => assert!(flow(value).is_empty()),
                    "time_from_start" => {}
                    "sec" => p.3 = value.trim().parse().expect("seconds"),
                    "nanosec" => p.4 = value.trim().parse().expect("nanoseconds"),
                    other => panic!("unexpected key {other}"),
                }
            }
            other => panic!("unexpected section {other}"),
        }
    }
    r
}

fn numbers(v: &Value) -> Vec<f64> {
    v.as_array()
        .expect("array")
        .iter()
        .map(|x| x.as_f64().expect("number"))
        .collect()
}

/// The gripper of trajectory `jt` reaches the trajectory's opening with the arm still: it
/// closes on an object before lifting it and opens before the arm leaves it (it used to close
/// over the lift's first points, the object rising in open jaws).
fn gripper_moves_with_the_arm_still(jt: &Value, name: &str) {
    let points = jt["points"].as_array().unwrap();
    let last = points.last().unwrap()["gripper_position"].as_f64();
    for (j, p) in points.iter().enumerate() {
        if p["gripper_position"].as_f64() != last {
            assert_eq!(
                numbers(&p["positions"]),
                numbers(&points[0]["positions"]),
                "{name}: point {j}: the arm moves while the gripper does"
            );
        }
    }
}

#[test]
fn exported_yaml_reads_back_into_the_plan_json_points() {
    let dir = scratch("yaml");
    let json = dir.join("plan.json");
    let plan = htngtp()
        .arg("plan")
        .arg(library("domain-compound.hddl"))
        .arg(library("pay-by-card.hddl"))
        .arg("--scene")
        .arg(library("scene.toml"))
        .args(["--strategy", "chronological", "--seed", "1"])
        .arg("--json-out")
        .arg(&json)
        .output()
        .expect("runs");
    assert_eq!(
        plan.status.code(),
        Some(0),
        "{}",
        String::from_utf8_lossy(&plan.stderr)
    );
    // The timing of every trajectory passes the independent check.
    let check = htngtp().arg("check").arg(&json).output().expect("runs");
    assert_eq!(
        check.status.code(),
        Some(0),
        "{}",
        String::from_utf8_lossy(&check.stdout)
    );

    let out_dir = dir.join("yaml");
    let exported = export(&json, &out_dir);
    assert_eq!(
        exported.status.code(),
        Some(0),
        "{}",
        String::from_utf8_lossy(&exported.stderr)
    );

    let v: Value = serde_json::from_str(&std::fs::read_to_string(&json).unwrap()).unwrap();
    let mut expected = Vec::new();
    for (i, step) in v["steps"].as_array().unwrap().iter().enumerate() {
        let trajs = step["gtp"]["trajectories"].as_array().cloned();
        for (k, t) in trajs.into_iter().flatten().enumerate() {
            let jt = &t["joint_trajectory"];
            assert!(jt.is_object(), "step {i} trajectory {k} is timed");
            let name = format!(
                "step-{i:03}-traj-{k}-{}-{}",
                jt["agent"].as_str().unwrap(),
                jt["group"].as_str().unwrap()
            );
            expected.push((format!("{name}.yaml"), jt.clone()));
            // A gripper's trajectory of its own: its joint at each point's position.
            if let Some(joint) = jt["gripper_joint"].as_str() {
                gripper_moves_with_the_arm_still(jt, &name);
                let points: Vec<Value> = jt["points"]
                    .as_array()
                    .unwrap()
                    .iter()
                    .map(|p| {
                        serde_json::json!({
                            "positions": [p["gripper_position"]],
                            "time_from_start": p["time_from_start"],
                        })
                    })
                    .collect();
                let g = serde_json::json!({
                    "group": "gripper", "joint_names": [joint], "points": points,
                });
                expected.push((format!("{name}-gripper.yaml"), g));
            }
        }
    }
    assert!(
        expected.iter().any(|(n, _)| n.ends_with("-gripper.yaml")),
        "some trajectory moves a gripper"
    );
    assert!(!expected.is_empty(), "the plan has trajectories");
    let written = std::fs::read_dir(&out_dir).unwrap().count();
    assert_eq!(written, expected.len(), "one file per trajectory");
    for (name, jt) in &expected {
        let text = std::fs::read_to_string(out_dir.join(name)).expect(name);
        let r = read(&text);
        let names: Vec<String> = jt["joint_names"]
            .as_array()
            .unwrap()
            .iter()
            .map(|n| n.as_str().unwrap().to_string())
            .collect();
        assert_eq!(r.joint_names, names, "{name}");
        if jt["group"] == "base" {
            assert_eq!(r.frame_id, "world");
            assert_eq!(names, ["base_x", "base_y", "base_yaw"]);
        } else {
            assert!(!r.frame_id.is_empty(), "{name}");
        }
        let points = jt["points"].as_array().unwrap();
        assert_eq!(r.points.len(), points.len(), "{name}");
        for (p, q) in points.iter().zip(&r.points) {
            assert_eq!(numbers(&p["positions"]), q.0, "{name}");
            if p.get("velocities").is_some() {
                assert_eq!(numbers(&p["velocities"]), q.1, "{name}");
            } else {
                assert_eq!(q.1.len(), 1, "{name}");
            }
            assert!(q.2.is_empty());
            let t = p["time_from_start"].as_f64().unwrap();
            let back = q.3 as f64 + q.4 as f64 * 1e-9;
            assert!(
                q.4 < 1_000_000_000 && (back - t).abs() < 1e-9,
                "{t} vs {back}"
            );
        }
    }
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn export_refuses_a_plan_without_joint_trajectories_and_bad_json() {
    let dir = scratch("bad");
    let plain = dir.join("plain.json");
    std::fs::write(&plain, r#"{"steps": [{"action": "a", "gtp": null}]}"#).unwrap();
    let out = export(&plain, dir.join("out"));
    assert_eq!(out.status.code(), Some(3));
    assert!(
        String::from_utf8_lossy(&out.stderr).contains("no trajectory has a `joint_trajectory`")
    );
    std::fs::write(&plain, "{ not json").unwrap();
    let out = export(&plain, dir.join("out"));
    assert_eq!(out.status.code(), Some(3));
    let bad = dir.join("bad.json");
    let jt = r#"{"agent": "a", "group": "g", "joint_names": ["j"], "points": [{"positions": [1, 2], "velocities": [0], "time_from_start": 0}]}"#;
    std::fs::write(
        &bad,
        format!(r#"{{"steps": [{{"gtp": {{"trajectories": [{{"joint_trajectory": {jt}}}]}}}}]}}"#),
    )
    .unwrap();
    let out = export(&bad, dir.join("out"));
    assert_eq!(out.status.code(), Some(3));
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(
        err.contains("points[0].positions") && err.contains("2 values for 1 joints"),
        "{err}"
    );
    assert!(!dir.join("out").exists(), "nothing written on bad input");
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn export_help_names_the_format() {
    let out = htngtp().args(["export", "--help"]).output().expect("runs");
    assert_eq!(out.status.code(), Some(0));
    let help = String::from_utf8_lossy(&out.stdout);
    assert!(
        help.contains("joint-trajectory-yaml") && help.contains("JointTrajectory"),
        "{help}"
    );
}
