//! A small hand-made library scene as plan JSON, and helpers to add steps to it.
//!
//! The robot `bot` stands at the origin facing +x; the desk (top at z 0.75, x 0.5..1.5,
//! y -0.5..0.5) is in front of it with a book lying on it at (1.0, -0.2) and a small monitor at
//! (1.0, 0.3); a bin stands on the floor at (0, 1); the member sits behind the desk at x 2.0
//! facing -x.

#![allow(dead_code)]

use check::{Fault, FaultKind, Options, Report};
use serde_json::{Value, json};

/// A pose with the identity rotation.
pub fn at(x: f32, y: f32, z: f32) -> Value {
    json!({ "t": [x, y, z], "q": [0.0, 0.0, 0.0, 1.0] })
}

fn cuboid(hx: f32, hy: f32, hz: f32) -> Value {
    json!({ "box": { "half_extents": [hx, hy, hz] } })
}

fn capsule(b: [f32; 3], r: f32) -> Value {
    json!({ "capsule": { "a": [0.0, 0.0, 0.0], "b": b, "radius": r } })
}

/// A link of a test agent: name, shape (if any), initial position.
pub type LinkSpec = (&'static str, Option<fn() -> Value>, [f32; 3]);

/// The robot's links in order, with their shapes and initial positions.
pub const BOT: &[LinkSpec] = &[
    ("base_link", Some(|| cuboid(0.3, 0.3, 0.2)), [0.0, 0.0, 0.2]),
    ("r_shoulder_pan_link", None, [0.1, -0.2, 1.0]),
    (
        "r_upper_arm_link",
        Some(|| capsule([0.25, 0.0, 0.0], 0.05)),
        [0.1, -0.2, 1.0],
    ),
    (
        "r_forearm_link",
        Some(|| capsule([0.2, 0.0, 0.0], 0.04)),
        [0.6, -0.4, 1.0],
    ),
    (
        "r_gripper_palm_link",
        Some(|| cuboid(0.03, 0.03, 0.03)),
        [0.5, -0.2, 1.0],
    ),
    (
        "r_gripper_l_finger_link",
        Some(|| cuboid(0.02, 0.005, 0.01)),
        [0.5, -0.25, 1.0],
    ),
    (
        "l_gripper_palm_link",
        Some(|| cuboid(0.03, 0.03, 0.03)),
        [0.5, 0.3, 1.0],
    ),
    ("camera", None, [0.2, 0.0, 1.3]),
];

/// The member's links in order.
pub const MEMBER: &[LinkSpec] = &[
    (
        "torso_link",
        Some(|| capsule([0.0, 0.0, 0.6], 0.15)),
        [2.0, 0.0, 0.6],
    ),
    ("r_shoulder_pitch_link", None, [2.0, -0.2, 1.2]),
    (
        "r_hand_link",
        Some(|| cuboid(0.04, 0.02, 0.08)),
        [1.7, -0.2, 0.9],
    ),
    ("eye", None, [2.0, 0.0, 1.5]),
];

/// Link poses of an agent: the initial positions with some links moved to `moved`.
pub fn posture(links: &[LinkSpec], moved: &[(&str, [f32; 3])]) -> Value {
    let mut m = serde_json::Map::new();
    for (name, _, p) in links {
        let p = moved
            .iter()
            .find(|(n, _)| n == name)
            .map_or(*p, |(_, q)| *q);
        let mut pose = at(p[0], p[1], p[2]);
        if *name == "eye" {
            pose["q"] = json!([0.0, 0.0, 1.0, 0.0]); // facing -x
        }
        m.insert(name.to_string(), pose);
    }
    Value::Object(m)
}

/// What an agent's links are for, as the planner exports it from the SRDF: its shoulders and
/// its hands (`(tool link, links)` each).
struct Roles {
    shoulders: &'static [&'static str],
    hands: &'static [(&'static str, &'static [&'static str])],
}

const BOT_ROLES: Roles = Roles {
    shoulders: &["r_shoulder_pan_link"],
    hands: &[
        (
            "r_gripper_palm_link",
            &["r_gripper_palm_link", "r_gripper_l_finger_link"],
        ),
        ("l_gripper_palm_link", &["l_gripper_palm_link"]),
    ],
};

const MEMBER_ROLES: Roles = Roles {
    shoulders: &["r_shoulder_pitch_link"],
    hands: &[("r_hand_link", &["r_hand_link"])],
};

fn agent(name: &str, kind: &str, eye: &str, links: &[LinkSpec], roles: &Roles) -> Value {
    let ls: Vec<Value> = links
        .iter()
        .map(|(n, s, _)| {
            let shapes: Vec<Value> = s.iter().map(|f| json!({ "shape": f() })).collect();
            json!({ "name": n, "shapes": shapes })
        })
        .collect();
    let hands: Vec<Value> = roles
        .hands
        .iter()
        .map(|(tool, links)| json!({ "tool_link": tool, "links": links }))
        .collect();
    json!({ "name": name, "kind": kind, "eye_link": eye, "links": ls,
            "shoulder_links": roles.shoulders, "hands": hands,
            "link_poses": posture(links, &[]) })
}

/// The scene with no steps.
pub fn scene() -> Value {
    json!({
        "format": "htngtp-plan", "version": 1, "status": "solved",
        "scene": {
            "objects": [
                { "name": "desk", "movable": false, "parts": [
                    { "shape": cuboid(0.5, 0.5, 0.02), "pose": at(0.0, 0.0, 0.73) } ],
                  "pose": at(1.0, 0.0, 0.0) },
                { "name": "monitor", "movable": false, "shape": cuboid(0.05, 0.05, 0.05),
                  "pose": at(1.0, 0.3, 0.80) },
                { "name": "bin", "movable": false, "shape": cuboid(0.2, 0.2, 0.1),
                  "pose": at(0.0, 1.0, 0.1) },
                { "name": "book", "movable": true, "shape": cuboid(0.1, 0.07, 0.02),
                  "pose": at(1.0, -0.2, 0.77) }
            ],
            "agents": [
                agent("bot", "robot", "camera", BOT, &BOT_ROLES),
                agent("member", "human", "eye", MEMBER, &MEMBER_ROLES)
            ]
        },
        "steps": []
    })
}

/// A trajectory of `agent` through `frames` (link poses), holding `holding` at `held`.
pub fn trajectory(
    agent: &str,
    label: &str,
    frames: Vec<Value>,
    holding: Option<(&str, Vec<Value>)>,
) -> Value {
    let (name, held) = match holding {
        Some((n, h)) => (json!(n), h.into_iter().map(Some).collect()),
        None => (Value::Null, vec![None; frames.len()]),
    };
    let fs: Vec<Value> = frames
        .into_iter()
        .zip(held)
        .map(|(lp, h)| json!({ "link_poses": lp, "held_pose": h }))
        .collect();
    json!({ "agent": agent, "label": label, "holding": name, "frames": fs })
}

/// Append a step about `target` with these trajectories, literals and poses after it.
pub fn push_step(
    plan: &mut Value,
    action: &str,
    target: &str,
    trajs: Vec<Value>,
    added: Value,
    deleted: Value,
    poses: Value,
) {
    let steps = plan["steps"].as_array_mut().expect("steps");
    let index = steps.len();
    let gtp = if trajs.is_empty() {
        Value::Null
    } else {
        json!({ "task": action, "args": [target], "trajectories": trajs })
    };
    steps.push(
        json!({ "index": index, "id": index, "action": action, "args": [target],
        "added": added, "deleted": deleted, "gtp": gtp, "object_poses": poses }),
    );
}

/// Check a plan value with the default options.
pub fn check(plan: &Value) -> Report {
    check_with(plan, &Options::default())
}

pub fn check_with(plan: &Value, opts: &Options) -> Report {
    let text = serde_json::to_string(plan).expect("json");
    let p = check::parse_plan(&text, "test.json").expect("a valid plan");
    check::check_plan(&p, opts)
}

/// (kind, a, b) of every fault, for exact comparisons.
pub fn kinds(r: &Report) -> Vec<(FaultKind, String, String)> {
    r.faults
        .iter()
        .map(|f| (f.kind, f.a.clone(), f.b.clone()))
        .collect()
}

/// The single fault of the report (panics with the list otherwise).
pub fn only(r: &Report) -> &Fault {
    assert_eq!(r.faults.len(), 1, "expected one fault, got {:#?}", kinds(r));
    &r.faults[0]
}
