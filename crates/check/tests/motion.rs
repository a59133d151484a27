//! The motion rules: trajectories join up (continuity) and frames are the forward kinematics of
//! the agent's URDF at their timed points.

use check::FaultKind;
use serde_json::{Value, json};

/// One revolute joint `turn` about z, 1 m above the base, carrying link `upper`.
const URDF: &str = r#"<robot name="arm">
  <link name="base_link"/><link name="upper"/>
  <joint name="turn" type="revolute"><parent link="base_link"/><child link="upper"/>
    <origin xyz="0 0 1" rpy="0 0 0"/><axis xyz="0 0 1"/>
    <limit lower="-3" upper="3" effort="1" velocity="1"/></joint>
</robot>"#;

/// The link poses of the arm standing at (x, 0) with the joint at `q`.
fn poses(x: f64, q: f64) -> Value {
    let (s, c) = (q / 2.0).sin_cos();
    json!({
        "base_link": { "t": [x, 0.0, 0.0], "q": [0.0, 0.0, 0.0, 1.0] },
        "upper": { "t": [x, 0.0, 1.0], "q": [0.0, 0.0, s, c] },
    })
}

/// A trajectory turning the joint from `from` to `to` in three timed points, its frames the
/// forward kinematics of each point.
fn turn(from: f64, to: f64) -> Value {
    let mid = (from + to) / 2.0;
    let v = to - from;
    let points = [(from, 0.0, 0.0), (mid, v, 1.0), (to, 0.0, 2.0)];
    let frames: Vec<Value> = points
        .iter()
        .map(|(q, _, t)| json!({ "t": t, "link_poses": poses(0.0, *q), "held_pose": null }))
        .collect();
    let pts: Vec<Value> = points
        .iter()
        .map(|(q, v, t)| json!({ "positions": [q], "velocities": [v], "time_from_start": t }))
        .collect();
    json!({
        "agent": "arm", "label": "turn", "holding": null, "frames": frames,
        "joint_trajectory": {
            "agent": "arm", "group": "arm", "joint_names": ["turn"],
            "velocity_limits": [1.0], "acceleration_limits": [1.0], "points": pts,
        },
    })
}

fn plan(trajectories: Vec<Value>) -> Value {
    json!({
        "format": "htngtp-plan", "version": 1, "status": "solved",
        "scene": {
            "objects": [],
            "agents": [{
                "name": "arm", "kind": "robot",
                "links": [{ "name": "base_link" }, { "name": "upper" }],
                "link_poses": poses(0.0, 0.0),
                "urdf": URDF,
                "joint_positions": { "turn": 0.0, "base_x": 0.0, "base_y": 0.0, "base_yaw": 0.0 },
            }],
        },
        "steps": [{
            "index": 0, "id": 0, "action": "turn", "args": [], "added": [], "deleted": [],
            "gtp": { "task": "turn", "args": [], "trajectories": trajectories },
            "object_poses": {},
        }],
    })
}

fn faults(plan: &Value) -> Vec<(FaultKind, String)> {
    let text = serde_json::to_string(plan).unwrap();
    let p = check::parse_plan(&text, "test.json").expect("a valid plan");
    let r = check::check_plan(&p, &check::Options::default());
    r.faults.iter().map(|f| (f.kind, f.a.clone())).collect()
}

#[test]
fn frames_at_the_forward_kinematics_and_joined_trajectories_are_clean() {
    assert_eq!(faults(&plan(vec![turn(0.0, 0.5), turn(0.5, -0.2)])), vec![]);
}

#[test]
fn a_frame_off_the_forward_kinematics_is_a_kinematics_fault() {
    let mut p = plan(vec![turn(0.0, 0.5)]);
    let t = &mut p["steps"][0]["gtp"]["trajectories"][0]["frames"][1]["link_poses"]["upper"]["t"];
    t[1] = json!(0.005);
    assert_eq!(
        faults(&p),
        vec![(FaultKind::Kinematics, "arm/upper".to_string())]
    );
}

#[test]
fn the_initial_link_poses_are_checked_too() {
    let mut p = plan(vec![]);
    p["scene"]["agents"][0]["joint_positions"]["turn"] = json!(0.3);
    assert_eq!(
        faults(&p),
        vec![(FaultKind::Kinematics, "arm/upper".to_string())]
    );
}

#[test]
fn a_trajectory_that_starts_elsewhere_is_a_discontinuity() {
    let p = plan(vec![turn(0.0, 0.5), turn(0.4, 0.0)]);
    assert_eq!(
        faults(&p),
        vec![(FaultKind::Discontinuity, "arm/turn".to_string())]
    );
}

#[test]
fn frames_that_are_not_one_per_point_are_a_kinematics_fault() {
    let mut p = plan(vec![turn(0.0, 0.5)]);
    let frames = p["steps"][0]["gtp"]["trajectories"][0]["frames"]
        .as_array_mut()
        .unwrap();
    frames.pop();
    assert_eq!(faults(&p), vec![(FaultKind::Kinematics, "arm".to_string())]);
}

#[test]
fn a_broken_urdf_is_an_input_error_naming_the_field() {
    let mut p = plan(vec![]);
    p["scene"]["agents"][0]["urdf"] = json!("<robot");
    let text = serde_json::to_string(&p).unwrap();
    let e = check::parse_plan(&text, "test.json")
        .err()
        .expect("an error");
    assert!(e.to_string().contains("urdf"), "{e}");
}
