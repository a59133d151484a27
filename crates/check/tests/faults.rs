//! `check` on hand-made plans: one clean plan, and one plan per kind of fault, each asserting
//! the exact fault kinds and bodies.

mod common;

use check::{FaultKind, InputError, Options, Report};
use common::*;
use serde_json::json;

/// The robot reaches over the desk and back; it sees and can reach the book.
fn clean_plan() -> serde_json::Value {
    let mut plan = scene();
    let frames = (0..=4)
        .map(|i| {
            let x = 0.5 + 0.1 * i as f32;
            posture(
                BOT,
                &[
                    ("r_gripper_palm_link", [x, -0.2, 1.0]),
                    ("r_gripper_l_finger_link", [x, -0.25, 1.0]),
                ],
            )
        })
        .collect();
    let traj = trajectory("bot", "approach", frames, None);
    let added = json!([
        ["visible", "book", "bot"],
        ["reachable", "book", "bot"],
        ["visible", "book", "member"]
    ]);
    push_step(
        &mut plan,
        "show",
        "book",
        vec![traj],
        added,
        json!([]),
        json!({}),
    );
    plan
}

#[test]
fn clean_plan_has_no_fault() {
    let r = check(&clean_plan());
    assert!(r.faults.is_empty(), "{:#?}", kinds(&r));
    assert_eq!(r.literals, 3);
    assert_eq!(r.frames, 5);
    assert_eq!(r.configs, 4 * 5 + 1, "4 sub-frames between 5 frames");
    assert!(
        r.summary()
            .starts_with("clean: 0 faults in 1 steps, 1 trajectories, 5 frames")
    );
}

#[test]
fn link_through_object() {
    let mut plan = scene();
    let frames = [1.0, 0.85, 0.72]
        .iter()
        .map(|&z| posture(BOT, &[("r_forearm_link", [0.9, -0.4, z])]))
        .collect();
    push_step(
        &mut plan,
        "pick",
        "book",
        vec![trajectory("bot", "approach", frames, None)],
        json!([]),
        json!([]),
        json!({}),
    );
    let r = check(&plan);
    let f = only(&r);
    assert_eq!(
        (f.kind, f.a.as_str(), f.b.as_str()),
        (FaultKind::Collision, "bot/r_forearm_link", "object desk")
    );
    assert_eq!(
        (f.step, f.trajectory.as_deref(), f.frame.as_deref()),
        (Some(0), Some("approach"), Some("2"))
    );
    // the capsule (radius 0.04) at z 0.72 spans 0.68..0.76 in the slab 0.71..0.75: pushing it
    // out downwards is the shorter way, 0.05 m
    assert!((f.depth_mm - 50.0).abs() < 1.0, "{}", f.depth_mm);
    assert_eq!(
        r.summary(),
        "1 faults: 1 collision (in 1 steps, 1 trajectories, 3 frames)"
    );
}

#[test]
fn motion_between_frames_is_checked() {
    let mut plan = scene();
    // Above the desk, then below it: neither frame touches the 4 cm slab, the motion does.
    let frames = [1.0, 0.5]
        .iter()
        .map(|&z| posture(BOT, &[("r_forearm_link", [0.9, -0.4, z])]))
        .collect();
    push_step(
        &mut plan,
        "pick",
        "book",
        vec![trajectory("bot", "approach", frames, None)],
        json!([]),
        json!([]),
        json!({}),
    );
    let f = only(&check(&plan)).clone();
    assert_eq!(
        (f.kind, f.b.as_str()),
        (FaultKind::Collision, "object desk")
    );
    assert_eq!(f.frame.as_deref(), Some("0+0.60"));
    let opts = Options {
        sub: 9,
        ..Options::default()
    };
    let f = only(&check_with(&plan, &opts)).clone();
    assert!(
        f.frame.as_deref().is_some_and(|fr| fr.starts_with("0+0.")),
        "{:?}",
        f.frame
    );
}

/// The robot lifts the book and carries it through the monitor; returns the plan and the
/// (palm, held) path used.
fn carry_through_monitor() -> serde_json::Value {
    let mut plan = scene();
    let path: Vec<[f32; 3]> = vec![
        [1.0, -0.2, 0.77],
        [1.0, -0.2, 0.82],
        [1.0, 0.1, 0.82],
        [1.0, 0.3, 0.82],
        [1.0, 0.6, 0.82],
    ];
    let frames = path
        .iter()
        .map(|p| {
            posture(
                BOT,
                &[
                    ("r_gripper_palm_link", [p[0], p[1], p[2] + 0.1]),
                    ("r_gripper_l_finger_link", [p[0], p[1] - 0.05, p[2] + 0.1]),
                ],
            )
        })
        .collect();
    let held = path.iter().map(|p| at(p[0], p[1], p[2])).collect();
    let traj = trajectory("bot", "lift", frames, Some(("book", held)));
    push_step(
        &mut plan,
        "pick",
        "book",
        vec![traj],
        json!([]),
        json!([]),
        json!({ "book": at(1.0, 0.6, 0.82) }),
    );
    plan
}

#[test]
fn held_object_through_object() {
    let r = check(&carry_through_monitor());
    let f = only(&r);
    assert_eq!(
        (f.kind, f.a.as_str(), f.b.as_str()),
        (FaultKind::Collision, "object monitor", "held book")
    );
    assert_eq!(f.trajectory.as_deref(), Some("lift"));
    assert!(f.depth_mm > 30.0, "{}", f.depth_mm);
}

/// A plan whose one step lifts the book through `heights` (from z 0.77 m) held in the right
/// hand, the robot's links `moved` as each frame's z gives them, the lift's trajectory changed
/// by `more`.
fn lift_book(
    heights: &[f32],
    moved: impl Fn(f32) -> Vec<(&'static str, [f32; 3])>,
    more: impl FnOnce(&mut serde_json::Value),
) -> serde_json::Value {
    let mut plan = scene();
    let frames = heights.iter().map(|&z| posture(BOT, &moved(z))).collect();
    let held = heights.iter().map(|&z| at(1.0, -0.2, z)).collect();
    let mut traj = trajectory("bot", "lift", frames, Some(("book", held)));
    more(&mut traj);
    let last = heights.last().copied().unwrap_or(0.77);
    push_step(
        &mut plan,
        "pick",
        "book",
        vec![traj],
        json!([]),
        json!([]),
        json!({ "book": at(1.0, -0.2, last) }),
    );
    plan
}

#[test]
fn a_hand_may_squeeze_what_it_holds_but_not_pass_through_it() {
    let lift = |palm_over_book: f32| {
        let palm = move |z: f32| vec![("r_gripper_palm_link", [1.0, -0.2, z + palm_over_book])];
        check(&lift_book(&[0.77, 0.82], palm, |_| {}))
    };
    // The palm (half height 0.03) 0.045 m over the book's centre (half height 0.02): 5 mm in.
    let r = lift(0.045);
    assert!(r.faults.is_empty(), "{:#?}", kinds(&r));
    // Its centre on the book's top face: 30 mm in, while lifting and at rest after the step.
    let r = lift(0.02);
    let got: Vec<_> = r
        .faults
        .iter()
        .map(|f| (f.kind, f.a.as_str(), f.b.as_str()))
        .collect();
    assert_eq!(
        got,
        vec![
            (FaultKind::Collision, "bot/r_gripper_palm_link", "held book"),
            (
                FaultKind::Penetration,
                "object book",
                "bot/r_gripper_palm_link"
            ),
        ]
    );
    assert!(
        r.faults
            .iter()
            .all(|f| f.detail.contains("10 mm grasp tolerance"))
    );
}

#[test]
fn self_collision_of_non_adjacent_links() {
    let mut plan = scene();
    let frames = [0.3, 0.0, -0.18]
        .iter()
        .map(|&y| posture(BOT, &[("l_gripper_palm_link", [0.5, y, 1.0])]))
        .collect();
    push_step(
        &mut plan,
        "pick",
        "book",
        vec![trajectory("bot", "approach", frames, None)],
        json!([]),
        json!([]),
        json!({}),
    );
    let f = only(&check(&plan)).clone();
    assert_eq!(
        (f.kind, f.a.as_str(), f.b.as_str()),
        (
            FaultKind::SelfCollision,
            "bot/r_gripper_palm_link",
            "bot/l_gripper_palm_link"
        )
    );
    // the boxes overlap 0.04 m in y (0.06 in x and z)
    assert!((f.depth_mm - 40.0).abs() < 0.5, "{}", f.depth_mm);
    // A pair the robot's SRDF says may touch (`disabled_collisions`) is left out; another
    // named there does not hide it.
    let mut disabled = plan.clone();
    disabled["scene"]["agents"][0]["disabled_collisions"] =
        json!([["l_gripper_palm_link", "r_gripper_palm_link"]]);
    assert!(check(&disabled).faults.is_empty());
    disabled["scene"]["agents"][0]["disabled_collisions"] =
        json!([["l_gripper_palm_link", "r_gripper_l_finger_link"]]);
    assert_eq!(only(&check(&disabled)).kind, FaultKind::SelfCollision);
    disabled["scene"]["agents"][0]["disabled_collisions"] = json!([["l_gripper_palm_link"]]);
    let e = check::parse_plan(&disabled.to_string(), "test.json")
        .err()
        .expect("an error");
    assert!(e.to_string().contains("expected two link names"), "{e}");
}

/// The palm and finger in the right hand move from `y0` to `y1` (finger's y).
fn finger_moves(initial_y: f32, to_y: f32) -> check::Report {
    let mut plan = scene();
    let lp = &mut plan["scene"]["agents"][0]["link_poses"]["r_gripper_l_finger_link"]["t"];
    *lp = json!([0.5, initial_y, 1.0]);
    let frames = [initial_y, to_y]
        .iter()
        .map(|&y| posture(BOT, &[("r_gripper_l_finger_link", [0.5, y, 1.0])]))
        .collect();
    push_step(
        &mut plan,
        "pick",
        "book",
        vec![trajectory("bot", "grasp", frames, None)],
        json!([]),
        json!([]),
        json!({}),
    );
    check(&plan)
}

#[test]
fn links_touching_in_the_initial_posture_are_adjacent() {
    // The finger starts against the palm (y -0.235 +- 0.005, palm from -0.23): adjacent.
    let r = finger_moves(-0.235, -0.215);
    assert!(r.faults.is_empty(), "{:#?}", kinds(&r));
    // 15 mm apart at first and moving in the palm's frame: not adjacent.
    let r = finger_moves(-0.25, -0.215);
    let f = only(&r);
    assert_eq!(
        (f.kind, f.a.as_str(), f.b.as_str()),
        (
            FaultKind::SelfCollision,
            "bot/r_gripper_palm_link",
            "bot/r_gripper_l_finger_link"
        )
    );
}

#[test]
fn links_joined_by_a_joint_are_adjacent() {
    let mut plan = scene();
    // The forearm turns about its origin, which stays 3 cm in front of the upper arm's end: the
    // origin is fixed in the upper arm's frame over every frame, so the pair is adjacent even
    // though they were apart at first and touch when bent.
    let start = [0.47, -0.2, 1.0];
    plan["scene"]["agents"][0]["link_poses"]["r_forearm_link"]["t"] = json!(start);
    let bend = |angle: f32| {
        let mut p = posture(BOT, &[("r_forearm_link", start)]);
        let (s, c) = (0.5 * angle).sin_cos();
        p["r_forearm_link"]["q"] = json!([0.0, 0.0, s, c]);
        p
    };
    let frames = [0.0f32, 1.5, 3.0].iter().map(|&a| bend(a)).collect();
    push_step(
        &mut plan,
        "pick",
        "book",
        vec![trajectory("bot", "bend", frames, None)],
        json!([]),
        json!([]),
        json!({}),
    );
    let r = check(&plan);
    assert!(r.faults.is_empty(), "{:#?}", kinds(&r));
}

#[test]
fn person_through_furniture() {
    let mut plan = scene();
    let frames = [[1.7, -0.2, 0.9], [1.5, -0.2, 0.8], [1.3, -0.2, 0.74]]
        .iter()
        .map(|&p| posture(MEMBER, &[("r_hand_link", p)]))
        .collect();
    push_step(
        &mut plan,
        "waittake",
        "book",
        vec![trajectory("member", "reach", frames, None)],
        json!([]),
        json!([]),
        json!({}),
    );
    let f = only(&check(&plan)).clone();
    assert_eq!(
        (f.kind, f.a.as_str(), f.b.as_str()),
        (FaultKind::Collision, "member/r_hand_link", "object desk")
    );
    assert_eq!(f.trajectory.as_deref(), Some("reach"));
}

#[test]
fn floating_object() {
    let mut plan = scene();
    push_step(
        &mut plan,
        "place",
        "book",
        vec![],
        json!([]),
        json!([]),
        json!({ "book": at(1.0, -0.2, 0.78) }),
    );
    let r = check(&plan);
    let f = only(&r);
    assert_eq!(
        (f.kind, f.a.as_str(), f.step),
        (FaultKind::Unsupported, "object book", Some(0))
    );
    assert!((f.depth_mm - 10.0).abs() < 0.1, "gap {}", f.depth_mm);
    assert!(f.detail.contains("object desk"), "{}", f.detail);
}

#[test]
fn resting_within_the_gap_is_supported() {
    let mut plan = scene();
    push_step(
        &mut plan,
        "place",
        "book",
        vec![],
        json!([]),
        json!([]),
        json!({ "book": at(1.0, -0.2, 0.7715) }),
    );
    let r = check(&plan);
    assert!(r.faults.is_empty(), "{:#?}", kinds(&r));
}

#[test]
fn object_inside_another() {
    let mut plan = scene();
    push_step(
        &mut plan,
        "put-away",
        "book",
        vec![],
        json!([]),
        json!([]),
        json!({ "book": at(0.0, 1.0, 0.1) }),
    );
    let r = check(&plan);
    let f = only(&r);
    assert_eq!(
        (f.kind, f.a.as_str(), f.b.as_str()),
        (FaultKind::Penetration, "object book", "object bin")
    );
    // the book's bottom (0.08) is 0.12 m under the bin's top (0.2)
    assert!((f.depth_mm - 120.0).abs() < 1.0, "{}", f.depth_mm);
}

#[test]
fn persisting_rest_faults_are_reported_once() {
    let mut plan = scene();
    push_step(
        &mut plan,
        "put-away",
        "book",
        vec![],
        json!([]),
        json!([]),
        json!({ "book": at(0.0, 1.0, 0.1) }),
    );
    push_step(
        &mut plan,
        "say",
        "book",
        vec![],
        json!([]),
        json!([]),
        json!({}),
    );
    assert_eq!(check(&plan).faults.len(), 1);
}

#[test]
fn stale_literals() {
    let mut plan = scene();
    // A screen between the robot's camera and the book.
    plan["scene"]["objects"]
        .as_array_mut()
        .unwrap()
        .push(json!({
        "name": "screen", "movable": false,
        "shape": { "box": { "half_extents": [0.02, 0.6, 0.5] } }, "pose": at(0.45, 0.0, 1.25) }));
    let added = json!([["visible", "book", "bot"], ["reachable", "book", "member"]]);
    let deleted = json!([["visible", "book", "member"]]);
    push_step(&mut plan, "show", "book", vec![], added, deleted, json!({}));
    // The book put down near the robot's shoulder (0.45 m), and "not reachable".
    let near = json!({ "book": at(0.6, -0.2, 0.77) });
    push_step(
        &mut plan,
        "place",
        "book",
        vec![],
        json!([]),
        json!([["reachable", "book", "bot"]]),
        near,
    );
    let r = check(&plan);
    let got: Vec<_> = r
        .faults
        .iter()
        .map(|f| (f.kind, f.a.as_str(), f.b.as_str()))
        .collect();
    let want = vec![
        (FaultKind::StaleLiteral, "(visible book bot)", "added"),
        (FaultKind::StaleLiteral, "(reachable book member)", "added"),
        (FaultKind::StaleLiteral, "(visible book member)", "deleted"),
        (FaultKind::StaleLiteral, "(reachable book bot)", "deleted"),
    ];
    assert_eq!(got, want);
    assert!(
        r.faults[0].detail.contains("0.00"),
        "{}",
        r.faults[0].detail
    );
}

/// A step that hides the book behind a board must delete `(visible book bot)`: with the plan's
/// initial literals the checker knows it is still claimed (the cluttered desk's stale literal).
#[test]
fn persisting_literal_hidden_by_a_step_is_stale() {
    let hidden = |initial: bool| {
        let mut plan = clean_plan();
        plan["scene"]["objects"]
            .as_array_mut()
            .unwrap()
            .push(json!({
            "name": "board", "movable": true,
            "shape": { "box": { "half_extents": [0.02, 0.6, 0.5] } }, "pose": at(3.0, 3.0, 0.5) }));
        if initial {
            plan["initial_literals"] = json!([["visible", "book", "bot"]]);
        }
        let traj = plan["steps"][0]["gtp"]["trajectories"][0].clone();
        let between = json!({ "board": at(0.45, 0.0, 1.25) });
        push_step(
            &mut plan,
            "hide",
            "board",
            vec![traj],
            json!([]),
            json!([]),
            between,
        );
        let r = check(&plan);
        let stale: Vec<(usize, String, String)> = r
            .faults
            .iter()
            .filter(|f| f.kind == FaultKind::StaleLiteral)
            .map(|f| (f.step.unwrap(), f.a.clone(), f.b.clone()))
            .collect();
        stale
    };
    assert_eq!(
        hidden(true),
        vec![(
            1,
            "(visible book bot)".to_string(),
            "persisting".to_string()
        )]
    );
    assert!(
        hidden(false).is_empty(),
        "without initial literals only changes are measured"
    );
}

#[test]
fn undeclared_carry_is_a_fault_and_checked_as_carried() {
    let mut plan = scene();
    // Lift the book in the right gripper (declared) ...
    let lift = vec![
        posture(
            BOT,
            &[
                ("r_gripper_palm_link", [1.0, -0.2, 0.87]),
                ("r_gripper_l_finger_link", [1.0, -0.25, 0.87]),
            ],
        ),
        posture(
            BOT,
            &[
                ("r_gripper_palm_link", [1.0, -0.2, 0.92]),
                ("r_gripper_l_finger_link", [1.0, -0.25, 0.92]),
            ],
        ),
    ];
    let held = vec![at(1.0, -0.2, 0.77), at(1.0, -0.2, 0.82)];
    let lift = trajectory("bot", "lift", lift, Some(("book", held)));
    push_step(
        &mut plan,
        "pick",
        "book",
        vec![lift],
        json!([]),
        json!([]),
        json!({ "book": at(1.0, -0.2, 0.82) }),
    );
    // ... then drive it through the monitor saying `holding: null`.
    let drive = [-0.2, 0.3, 0.6]
        .iter()
        .map(|&y| {
            posture(
                BOT,
                &[
                    ("r_gripper_palm_link", [1.0, y, 0.92]),
                    ("r_gripper_l_finger_link", [1.0, y - 0.05, 0.92]),
                ],
            )
        })
        .collect();
    let drive = trajectory("bot", "drive", drive, None);
    push_step(
        &mut plan,
        "navto",
        "desk",
        vec![drive],
        json!([]),
        json!([]),
        json!({ "book": at(1.0, 0.6, 0.82) }),
    );
    let r = check(&plan);
    let got: Vec<_> = r
        .faults
        .iter()
        .map(|f| (f.kind, f.step, f.a.as_str(), f.b.as_str()))
        .collect();
    assert_eq!(
        got,
        vec![
            (
                FaultKind::UndeclaredCarry,
                Some(1),
                "bot/r_gripper_palm_link",
                "held book"
            ),
            (FaultKind::Collision, Some(1), "object monitor", "held book"),
        ]
    );
}

#[test]
fn bad_json_names_file_line_and_column() {
    let err = check::parse_plan("{\n  \"scene\": [1,\n}", "plan.json")
        .err()
        .expect("an error");
    match &err {
        InputError::Syntax { file, line, .. } => {
            assert_eq!((file.as_str(), *line), ("plan.json", 3))
        }
        other => panic!("{other}"),
    }
    assert!(
        err.to_string()
            .starts_with("plan.json: not valid JSON at line 3, column"),
        "{err}"
    );
}

#[test]
fn missing_key_names_its_path() {
    let mut plan = carry_through_monitor();
    plan["steps"][0]["gtp"]["trajectories"][0]["frames"][2]["link_poses"]["camera"]
        .as_object_mut()
        .unwrap()
        .remove("q");
    let err = check::parse_plan(&plan.to_string(), "p.json")
        .err()
        .expect("an error");
    assert_eq!(
        err.to_string(),
        "missing key `steps[0].gtp.trajectories[0].frames[2].link_poses.camera.q`"
    );
}

#[test]
fn unknown_names_and_bad_values_are_bad_input() {
    let mut plan = clean_plan();
    plan["steps"][0]["gtp"]["trajectories"][0]["agent"] = json!("nobody");
    let err = check::parse_plan(&plan.to_string(), "p.json")
        .err()
        .expect("an error");
    assert!(err.to_string().contains("no agent `nobody`"), "{err}");
    let mut plan = scene();
    plan["scene"]["objects"][3]["shape"]["box"]["half_extents"] = json!([0.1, -1, 0.1]);
    let err = check::parse_plan(&plan.to_string(), "p.json")
        .err()
        .expect("an error");
    assert!(matches!(err, InputError::Bad { .. }), "{err}");
}

/// One joint from 0 to 1 in 2 s: a triangular profile at 1 rad/s^2 peaking at 1 rad/s.
fn joint_trajectory() -> serde_json::Value {
    json!({
        "agent": "bot",
        "group": "right_arm",
        "joint_names": ["r_shoulder_pan_joint"],
        "velocity_limits": [1.0],
        "acceleration_limits": [1.0],
        "waypoints": [[0.0], [1.0]],
        "points": [
            { "positions": [0.0], "velocities": [0.0], "time_from_start": 0.0 },
            { "positions": [0.5], "velocities": [1.0], "time_from_start": 1.0 },
            { "positions": [1.0], "velocities": [0.0], "time_from_start": 2.0 },
        ],
    })
}

/// The clean plan with `jt` as its trajectory's `joint_trajectory`.
fn timed(jt: serde_json::Value) -> serde_json::Value {
    let mut plan = clean_plan();
    plan["steps"][0]["gtp"]["trajectories"][0]["joint_trajectory"] = jt;
    plan
}

/// The timing faults of a plan as (joint, rule, point, configs).
fn timing_faults(plan: &serde_json::Value) -> Vec<(String, String, String, usize)> {
    let r = check(plan);
    assert!(r.faults.iter().all(|f| f.kind == FaultKind::Timing));
    r.faults
        .iter()
        .map(|f| {
            (
                f.a.clone(),
                f.b.clone(),
                f.frame.clone().unwrap_or_default(),
                f.configs,
            )
        })
        .collect()
}

fn fault(joint: &str, rule: &str, point: usize, configs: usize) -> (String, String, String, usize) {
    (
        joint.to_string(),
        rule.to_string(),
        format!("point {point}"),
        configs,
    )
}

#[test]
fn timed_trajectory_within_its_limits_is_clean() {
    let r = check(&timed(joint_trajectory()));
    assert!(r.faults.is_empty(), "{:#?}", kinds(&r));
}

#[test]
fn velocity_over_its_limit() {
    let mut jt = joint_trajectory();
    jt["velocity_limits"] = json!([0.8]);
    assert_eq!(
        timing_faults(&timed(jt)),
        vec![fault("bot/r_shoulder_pan_joint", "velocity limit", 1, 1)]
    );
    // Positions that move faster than the declared velocities say.
    let mut jt = joint_trajectory();
    jt["points"][1]["time_from_start"] = json!(0.2);
    jt["points"][1]["velocities"] = json!([0.1]);
    jt["points"][1]["positions"] = json!([0.9]);
    let got = timing_faults(&timed(jt));
    assert!(
        got.contains(&fault("bot/r_shoulder_pan_joint", "velocity limit", 1, 1)),
        "{got:?}"
    );
}

#[test]
fn acceleration_over_its_limit() {
    let mut jt = joint_trajectory();
    jt["acceleration_limits"] = json!([0.5]);
    assert_eq!(
        timing_faults(&timed(jt)),
        vec![fault(
            "bot/r_shoulder_pan_joint",
            "acceleration limit",
            1,
            2
        )]
    );
}

#[test]
fn times_must_start_at_zero_and_increase() {
    let mut jt = joint_trajectory();
    jt["points"][2]["time_from_start"] = json!(1.0);
    assert_eq!(
        timing_faults(&timed(jt)),
        vec![fault("bot", "time order", 2, 1)]
    );
    let mut jt = joint_trajectory();
    jt["points"][0]["time_from_start"] = json!(0.5);
    let got = timing_faults(&timed(jt));
    assert!(got.contains(&fault("bot", "start time", 0, 1)), "{got:?}");
}

#[test]
fn trajectory_must_start_and_end_at_rest() {
    let mut jt = joint_trajectory();
    jt["points"][2]["velocities"] = json!([0.3]);
    assert_eq!(
        timing_faults(&timed(jt)),
        vec![fault("bot/r_shoulder_pan_joint", "end at rest", 2, 1)]
    );
    let mut jt = joint_trajectory();
    jt["points"][0]["velocities"] = json!([0.3]);
    assert_eq!(
        timing_faults(&timed(jt)),
        vec![fault("bot/r_shoulder_pan_joint", "start at rest", 0, 1)]
    );
}

#[test]
fn ends_must_be_the_waypoints() {
    let mut jt = joint_trajectory();
    jt["waypoints"] = json!([[0.0], [0.4], [1.2]]);
    assert_eq!(
        timing_faults(&timed(jt)),
        vec![fault("bot/r_shoulder_pan_joint", "end waypoint", 2, 1)]
    );
    // Without waypoints there is nothing to compare.
    let mut jt = joint_trajectory();
    jt.as_object_mut().unwrap().remove("waypoints");
    assert!(timing_faults(&timed(jt)).is_empty());
}

#[test]
fn malformed_joint_trajectory_is_bad_input() {
    let bad = |jt: serde_json::Value| {
        check::parse_plan(&timed(jt).to_string(), "p.json")
            .err()
            .expect("an error")
            .to_string()
    };
    let mut jt = joint_trajectory();
    jt["points"][1]["velocities"] = json!([1.0, 2.0]);
    assert!(
        bad(jt).contains("joint_trajectory.points[1].velocities"),
        "names the path"
    );
    let mut jt = joint_trajectory();
    jt["acceleration_limits"] = json!([-1.0]);
    assert!(bad(jt).contains("positive"));
    let mut jt = joint_trajectory();
    jt["points"][0]["time_from_start"] = json!("soon");
    assert!(bad(jt).contains("finite number"));
    let mut jt = joint_trajectory();
    jt.as_object_mut().unwrap().remove("velocity_limits");
    assert!(bad(jt).contains("missing key"));
}

/// The grasping links are the plan's declared `hands`, not names: the palm 5 mm into the book it
/// lifts is allowed while the palm is in a declared hand, a collision once no hand lists it.
#[test]
fn grasping_links_are_the_declared_hands() {
    let lift = |hands: serde_json::Value| {
        let mut plan = scene();
        plan["scene"]["agents"][0]["hands"] = hands;
        let frames = [0.77, 0.82]
            .iter()
            .map(|&z| posture(BOT, &[("r_gripper_palm_link", [1.0, -0.2, z + 0.045])]))
            .collect();
        let held = vec![at(1.0, -0.2, 0.77), at(1.0, -0.2, 0.82)];
        let traj = trajectory("bot", "lift", frames, Some(("book", held)));
        let after = json!({ "book": at(1.0, -0.2, 0.82) });
        push_step(
            &mut plan,
            "pick",
            "book",
            vec![traj],
            json!([]),
            json!([]),
            after,
        );
        plan
    };
    let palm = json!([{ "tool_link": "r_gripper_palm_link", "links": ["r_gripper_palm_link"] }]);
    let r = check(&lift(palm));
    assert!(r.faults.is_empty(), "{:#?}", kinds(&r));
    let r = check(&lift(json!([])));
    assert!(
        kinds(&r)
            .iter()
            .any(|(k, a, _)| *k == FaultKind::Collision && a == "bot/r_gripper_palm_link"),
        "{:#?}",
        kinds(&r)
    );
    // A hand naming a link the agent lacks is bad input, with its path.
    let bad = json!([{ "tool_link": "r_gripper_palm_link", "links": ["wing"] }]);
    let err = check::parse_plan(&lift(bad).to_string(), "p.json")
        .err()
        .expect("an error")
        .to_string();
    assert!(
        err.contains("agents[0].hands[0].links[0]") && err.contains("no link `wing`"),
        "{err}"
    );
}

/// The robot with a head its URDF turns: pan about z (within `pan` either way), then tilt
/// about y, the camera fixed below that; the book put on the bin, 90 degrees to its left, with
/// `(visible book bot)` added. Seen only when the pan reaches that far.
fn book_beside_a_head_that_pans(pan: f32) -> Report {
    let mut plan = scene();
    let bot = &mut plan["scene"]["agents"][0];
    bot["links"]
        .as_array_mut()
        .unwrap()
        .push(json!({ "name": "head_pan_link", "shapes": [] }));
    bot["link_poses"]["head_pan_link"] = at(0.2, 0.0, 1.3);
    bot["link_poses"]["camera"] = at(0.2, 0.0, 1.3);
    bot["head_pivot_link"] = json!("head_pan_link");
    bot["urdf"] = json!(format!(
        r#"<robot name="bot">
      <link name="base_link"/><link name="head_pan_link"/><link name="head_tilt_link"/><link name="camera"/>
      <joint name="head_pan_joint" type="revolute"><parent link="base_link"/><child link="head_pan_link"/>
        <origin xyz="0.2 0 1.1"/><axis xyz="0 0 1"/><limit lower="-{pan}" upper="{pan}" effort="1" velocity="1"/></joint>
      <joint name="head_tilt_joint" type="revolute"><parent link="head_pan_link"/><child link="head_tilt_link"/>
        <axis xyz="0 1 0"/><limit lower="-0.5" upper="1.2" effort="1" velocity="1"/></joint>
      <joint name="camera_joint" type="fixed"><parent link="head_tilt_link"/><child link="camera"/></joint>
    </robot>"#
    ));
    let on_bin = json!({ "book": at(0.0, 1.0, 0.22) });
    let added = json!([["visible", "book", "bot"]]);
    push_step(&mut plan, "place", "book", vec![], added, json!([]), on_bin);
    check(&plan)
}

/// With the URDF at hand, "visible with the head turned" turns the head by its joints within
/// their limits (not a free swing): a pan limited to 0.4 rad leaves the book unseen.
#[test]
fn a_head_turns_only_as_far_as_its_joints_allow() {
    let stale = |r: &Report| {
        r.faults
            .iter()
            .filter(|f| f.kind == FaultKind::StaleLiteral)
            .map(|f| f.a.clone())
            .collect::<Vec<_>>()
    };
    assert!(stale(&book_beside_a_head_that_pans(3.0)).is_empty());
    let limited = book_beside_a_head_that_pans(0.4);
    assert_eq!(stale(&limited), vec!["(visible book bot)".to_string()]);
    assert!(limited.faults[0].detail.contains("0.00 with it turned"));
}

/// A robot hand's fingers must grip what it carries: at the end of a trajectory that holds
/// the book and declares its gripper, a finger (a hand link that moves relative to the tool
/// frame) within 3 mm of the book, else a `loose-grip` fault.
#[test]
fn a_finger_must_grip_what_the_hand_carries() {
    let lift = |finger_beside_book: bool| {
        let hand = move |z: f32| {
            let mut moved = vec![("r_gripper_palm_link", [1.0, -0.2, z + 0.045])];
            if finger_beside_book {
                // The book's -y face at -0.27; the finger's half width 5 mm: 1 mm apart.
                moved.push(("r_gripper_l_finger_link", [1.0, -0.276, z]));
            }
            moved
        };
        check(&lift_book(&[0.77, 0.82], hand, declares_gripper))
    };
    let r = lift(true);
    assert!(r.faults.is_empty(), "{:#?}", kinds(&r));
    let r = lift(false);
    assert_eq!(
        kinds(&r),
        vec![(
            FaultKind::LooseGrip,
            "bot/r_gripper_palm_link".to_string(),
            "held book".to_string()
        )]
    );
}

/// A hand must grip its object before it moves it: a lift whose finger reaches the book only at
/// its end (the jaws closing as the book rises) is a `loose-grip` at its first frame where the
/// book has moved; the same lift with the finger beside the book all along is clean.
#[test]
fn a_held_object_must_not_rise_in_open_jaws() {
    let lift = |closed_from_the_start: bool| {
        let hand = move |z: f32| {
            // Beside the book's -y face (1 mm), or 2 cm out until the last frame.
            let y = if closed_from_the_start || z >= 0.82 {
                -0.276
            } else {
                -0.296
            };
            vec![
                ("r_gripper_palm_link", [1.0, -0.2, z + 0.045]),
                ("r_gripper_l_finger_link", [1.0, y, z]),
            ]
        };
        check(&lift_book(&[0.77, 0.79, 0.82], hand, declares_gripper))
    };
    let r = lift(true);
    assert!(r.faults.is_empty(), "{:#?}", kinds(&r));
    let r = lift(false);
    let f = only(&r);
    assert_eq!(f.kind, FaultKind::LooseGrip);
    assert_eq!(f.frame.as_deref(), Some("1"));
    assert!(
        f.detail.contains("moved 20 mm") && f.detail.contains("open jaws"),
        "{}",
        f.detail
    );
}

/// Declares the right gripper's joint in a trajectory (a `joint_trajectory` of its own).
fn declares_gripper(traj: &mut serde_json::Value) {
    let mut jt = joint_trajectory();
    jt["gripper_joint"] = json!("r_gripper_l_finger_joint");
    traj["joint_trajectory"] = jt;
}
