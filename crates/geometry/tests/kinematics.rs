//! Forward kinematics with known answers (hand-computed from the joint origins in
//! `models/pr2.urdf` and `models/human.urdf`).

mod common;

use common::posture;
use geometry::agent::AgentModel;
use parry3d::math::{Pose, Rotation, Vector};

fn model(name: &str) -> AgentModel {
    let path = format!("{}/../../models/{name}", env!("CARGO_MANIFEST_DIR"));
    AgentModel::from_urdf_file(&path).unwrap_or_else(|e| panic!("{e}"))
}

fn close(a: Vector, b: Vector, tol: f32) -> bool {
    (a - b).length() < tol
}

#[test]
fn pr2_tool_frames_at_zero_configuration() {
    let pr2 = model("pr2.urdf");
    let q = pr2.default_configuration();
    assert!(q.as_slice().iter().all(|&v| v == 0.0));
    let base = Pose::IDENTITY;
    let x = -0.05 + 0.1 + 0.4 + 0.321 + 0.18;
    let r = pr2
        .link_pose(base, q.as_slice(), "r_gripper_tool_frame")
        .unwrap();
    assert!(
        close(r.translation, Vector::new(x, -0.188, 0.739675), 1e-5),
        "{r:?}"
    );
    let l = pr2
        .link_pose(base, q.as_slice(), "l_gripper_tool_frame")
        .unwrap();
    assert!(
        close(l.translation, Vector::new(x, 0.188, 0.739675), 1e-5),
        "{l:?}"
    );
    // Tool x axis points forward at zero.
    assert!(close(r.rotation * Vector::X, Vector::X, 1e-6));
}

#[test]
fn pr2_torso_lift_and_base_pose_move_the_tool_frame() {
    let pr2 = model("pr2.urdf");
    let mut q = pr2.default_configuration();
    q.set("torso_lift_joint", 0.2).unwrap();
    let base = Pose::from_parts(
        Vector::new(1.0, 2.0, 0.0),
        Rotation::from_rotation_z(1.5707964),
    );
    let r = pr2
        .link_pose(base, q.as_slice(), "r_gripper_tool_frame")
        .unwrap();
    // Rotated by +90 degrees about z: local (x, y) -> world (-y, x).
    let x = -0.05 + 0.1 + 0.4 + 0.321 + 0.18;
    let expected = Vector::new(1.0 + 0.188, 2.0 + x, 0.739675 + 0.2);
    assert!(close(r.translation, expected, 1e-4), "{r:?}");
}

#[test]
fn pr2_head_camera_frame() {
    let pr2 = model("pr2.urdf");
    let mut q = pr2.default_configuration();
    let cam = pr2
        .link_pose(Pose::IDENTITY, q.as_slice(), "head_camera")
        .unwrap();
    let expected = Vector::new(-0.05 - 0.01707 + 0.068 + 0.1, 0.0, 0.739675 + 0.38145 + 0.1);
    assert!(close(cam.translation, expected, 1e-5), "{cam:?}");
    // Pan by 90 degrees: the camera looks along +y.
    q.set("head_pan_joint", std::f32::consts::FRAC_PI_2)
        .unwrap();
    let cam = pr2
        .link_pose(Pose::IDENTITY, q.as_slice(), "head_camera")
        .unwrap();
    assert!(close(cam.rotation * Vector::X, Vector::Y, 1e-5));
    // Positive tilt looks down.
    q.set("head_pan_joint", 0.0).unwrap();
    q.set("head_tilt_joint", 0.5).unwrap();
    let cam = pr2
        .link_pose(Pose::IDENTITY, q.as_slice(), "head_camera")
        .unwrap();
    assert!((cam.rotation * Vector::X).z < -0.4);
}

#[test]
fn pr2_elbow_flex_bends_the_forearm() {
    let pr2 = model("pr2.urdf");
    let mut q = pr2.default_configuration();
    q.set("r_elbow_flex_joint", -std::f32::consts::FRAC_PI_2)
        .unwrap();
    let t = pr2
        .link_pose(Pose::IDENTITY, q.as_slice(), "r_gripper_tool_frame")
        .unwrap();
    // The elbow is at x = -0.05 + 0.1 + 0.4; a negative flex about y raises the forearm.
    let elbow = Vector::new(0.45, -0.188, 0.739675);
    assert!(
        close(
            t.translation,
            elbow + Vector::new(0.0, 0.0, 0.321 + 0.18),
            1e-5
        ),
        "{t:?}"
    );
}

#[test]
fn link_poses_agree_with_link_pose() {
    let pr2 = model("pr2.urdf");
    let mut rng = fastrand::Rng::with_seed(7);
    let base = Pose::from_parts(Vector::new(0.3, -0.2, 0.0), Rotation::from_rotation_z(0.4));
    for _ in 0..20 {
        let q = pr2.random_configuration(&mut rng);
        let all = pr2.link_poses(base, q.as_slice());
        for (i, link) in pr2.links().iter().enumerate() {
            let p = pr2.link_pose(base, q.as_slice(), &link.name).unwrap();
            assert!(close(p.translation, all[i].translation, 1e-5));
        }
    }
}

#[test]
fn pr2_gripper_fingers_mimic() {
    let pr2 = model("pr2.urdf");
    let mut q = pr2.default_configuration();
    q.set("r_gripper_l_finger_joint", 0.04).unwrap();
    let l = pr2
        .link_pose(Pose::IDENTITY, q.as_slice(), "r_gripper_l_finger_link")
        .unwrap();
    let r = pr2
        .link_pose(Pose::IDENTITY, q.as_slice(), "r_gripper_r_finger_link")
        .unwrap();
    assert!(((l.translation - r.translation).y - 0.08).abs() < 1e-6);
    assert!(
        q.set("r_gripper_r_finger_joint", 0.01).is_err(),
        "mimic joints are not set directly"
    );
}

#[test]
fn human_eye_and_shoulders_sitting_and_standing() {
    let human = model("human.urdf");
    let mut q = human.default_configuration();
    q.set_many(&posture(&human, "sitting")).unwrap();
    let eye = human
        .link_pose(Pose::IDENTITY, q.as_slice(), "eye")
        .unwrap();
    assert!((eye.translation.z - 1.20).abs() < 1e-4, "{eye:?}");
    assert!(close(eye.rotation * Vector::X, Vector::X, 1e-5));
    let sh = human
        .link_pose(Pose::IDENTITY, q.as_slice(), "r_upper_arm_link")
        .unwrap();
    assert!(
        close(sh.translation, Vector::new(0.0, -0.2, 1.0), 1e-5),
        "{sh:?}"
    );
    q.set_many(&posture(&human, "standing")).unwrap();
    let eye = human
        .link_pose(Pose::IDENTITY, q.as_slice(), "eye")
        .unwrap();
    assert!((eye.translation.z - 1.60).abs() < 1e-4, "{eye:?}");
    let sh = human
        .link_pose(Pose::IDENTITY, q.as_slice(), "l_upper_arm_link")
        .unwrap();
    assert!(
        close(sh.translation, Vector::new(0.0, 0.2, 1.4), 1e-5),
        "{sh:?}"
    );
    // Standing: the feet are on the floor, under the hips.
    let shin = human
        .link_pose(Pose::IDENTITY, q.as_slice(), "r_shin_link")
        .unwrap();
    assert!(
        close(shin.translation, Vector::new(0.0, -0.09, 0.45), 1e-4),
        "{shin:?}"
    );
}

#[test]
fn human_arm_reach_is_070() {
    let human = model("human.urdf");
    let mut q = human.default_configuration();
    // Raise the straight right arm forward, horizontal.
    q.set("r_shoulder_pitch_joint", -std::f32::consts::FRAC_PI_2)
        .unwrap();
    let hand = human
        .link_pose(Pose::IDENTITY, q.as_slice(), "r_hand")
        .unwrap();
    assert!(
        close(hand.translation, Vector::new(0.70, -0.2, 1.0), 1e-4),
        "{hand:?}"
    );
    // The hand frame's x points along the arm.
    assert!(close(hand.rotation * Vector::X, Vector::X, 1e-4));
}

mod ik {
    use super::*;
    use geometry::ik::{IkError, IkOptions, solve_ik};

    /// Rotation angle between two orientations.
    fn angle(a: Rotation, b: Rotation) -> f32 {
        let d = a * b.inverse();
        2.0 * d.w.abs().min(1.0).acos()
    }

    /// FK(IK(pose)) within 1 mm / 0.01 rad for 100 seeded reachable poses (poses from FK of
    /// random in-limit arm configurations), solutions within the joint limits.
    fn round_trips(file: &str, chain_name: &str, seed: u64) {
        let m = model(file);
        let chain = m.chain(chain_name).unwrap();
        let tip = &m.links()[chain.tip_link].name;
        let base = Pose::from_parts(Vector::new(0.5, -1.0, 0.0), Rotation::from_rotation_z(0.3));
        let rest = m.default_configuration();
        let mut rng = fastrand::Rng::with_seed(seed);
        let mut solved = 0;
        for _ in 0..100 {
            let mut q = rest.as_slice().to_vec();
            let random = m.random_configuration(&mut rng);
            for &d in &chain.dofs {
                q[d] = random.as_slice()[d];
            }
            let target = m.link_pose(base, &q, tip).unwrap();
            let sol = solve_ik(
                &m,
                &chain,
                base,
                rest.as_slice(),
                target,
                &IkOptions::default(),
                &mut rng,
            );
            let Ok(sol) = sol else { continue };
            let got = m.link_pose(base, &sol.configuration, tip).unwrap();
            assert!((got.translation - target.translation).length() < 1e-3);
            assert!(angle(got.rotation, target.rotation) < 0.01);
            // Limits respected, joints outside the chain untouched.
            let checked = m.configuration(sol.configuration.clone()).unwrap();
            assert!(checked.is_within_limits());
            for d in 0..m.dof() {
                if !chain.dofs.contains(&d) {
                    assert_eq!(sol.configuration[d], rest.as_slice()[d]);
                }
            }
            solved += 1;
        }
        assert!(solved >= 98, "{file} {chain_name}: solved {solved} of 100");
    }

    #[test]
    fn pr2_right_arm_round_trips() {
        round_trips("pr2.urdf", "right_arm", 1);
    }

    #[test]
    fn pr2_left_arm_round_trips() {
        round_trips("pr2.urdf", "left_arm", 2);
    }

    #[test]
    fn human_right_arm_round_trips() {
        round_trips("human.urdf", "right_arm", 3);
    }

    #[test]
    fn pr2_unreachable_target_fails_fast() {
        let m = model("pr2.urdf");
        let chain = m.chain("right_arm").unwrap();
        let q = m.default_configuration();
        let target = Pose::from_translation(Vector::new(3.0, 0.0, 1.0));
        let mut rng = fastrand::Rng::with_seed(4);
        let e = solve_ik(
            &m,
            &chain,
            Pose::IDENTITY,
            q.as_slice(),
            target,
            &IkOptions::default(),
            &mut rng,
        )
        .unwrap_err();
        assert!(matches!(e, IkError::OutOfReach { .. }), "{e}");
    }

    #[test]
    fn pr2_target_behind_the_shoulder_limits_fails() {
        // Within reach distance but demanding the arm to bend past its limits: the tool frame
        // right behind the back of the robot, pointing forward.
        let m = model("pr2.urdf");
        let chain = m.chain("right_arm").unwrap();
        let q = m.default_configuration();
        let target = Pose::from_translation(Vector::new(-0.6, 0.3, 0.75));
        let mut rng = fastrand::Rng::with_seed(5);
        let opts = IkOptions {
            attempts: 10,
            ..IkOptions::default()
        };
        let e = solve_ik(
            &m,
            &chain,
            Pose::IDENTITY,
            q.as_slice(),
            target,
            &opts,
            &mut rng,
        );
        assert!(matches!(e, Err(IkError::NoSolution { .. })), "{e:?}");
    }

    #[test]
    fn chain_of_another_model_is_rejected() {
        let pr2 = model("pr2.urdf");
        let human = model("human.urdf");
        let chain = pr2.chain("right_arm").unwrap();
        let q = human.default_configuration();
        let mut rng = fastrand::Rng::with_seed(8);
        let e = solve_ik(
            &human,
            &chain,
            Pose::IDENTITY,
            q.as_slice(),
            Pose::IDENTITY,
            &IkOptions::default(),
            &mut rng,
        )
        .unwrap_err();
        assert!(matches!(e, IkError::BadInput(_)), "{e}");
    }

    #[test]
    fn position_only_target() {
        let m = model("pr2.urdf");
        let chain = m.chain("right_arm").unwrap();
        let q = m.default_configuration();
        let target = Pose::from_translation(Vector::new(0.6, -0.3, 0.9));
        let mut rng = fastrand::Rng::with_seed(6);
        let opts = IkOptions {
            orientation: false,
            ..IkOptions::default()
        };
        let sol = solve_ik(
            &m,
            &chain,
            Pose::IDENTITY,
            q.as_slice(),
            target,
            &opts,
            &mut rng,
        )
        .unwrap();
        let got = m
            .link_pose(Pose::IDENTITY, &sol.configuration, "r_gripper_tool_frame")
            .unwrap();
        assert!((got.translation - target.translation).length() < 1e-3);
    }
}
