//! The SRDF reader: the shipped models' descriptions, and every kind of bad content with its
//! `file:line:col`.

mod common;

use geometry::agent::AgentModel;

fn models(file: &str) -> String {
    format!("{}/../../models/{file}", env!("CARGO_MANIFEST_DIR"))
}

fn pr2_alone() -> AgentModel {
    let text = std::fs::read_to_string(models("pr2.urdf")).unwrap();
    AgentModel::from_urdf_str(&text, "pr2.urdf").unwrap()
}

/// The error of reading `srdf` for the PR2.
fn error(srdf: &str) -> String {
    pr2_alone()
        .with_srdf_str(srdf, "test.srdf")
        .expect_err("an error")
        .to_string()
}

#[test]
fn the_shipped_models_have_arms_grippers_a_head_and_postures() {
    let pr2 = AgentModel::from_urdf_file(models("pr2.urdf")).unwrap();
    assert_eq!(pr2.arm_names(), ["right_arm", "left_arm"]);
    let arm = pr2.chain("right_arm").unwrap();
    assert_eq!(pr2.links()[arm.tip_link].name, "r_gripper_tool_frame");
    let ee = pr2.semantics().end_effector("left_arm").unwrap();
    assert_eq!(ee.group, "l_gripper");
    assert_eq!(
        pr2.links()[pr2.chain("head").unwrap().tip_link].name,
        "head_camera"
    );
    assert!(pr2.group_dof("torso_lift").is_some());
    let human = AgentModel::from_urdf_file(models("human.urdf")).unwrap();
    assert_eq!(human.arm_names(), ["right_arm", "left_arm"]);
    assert_eq!(human.posture("standing").len(), 5);
    assert!(human.group_dof("torso_yaw").is_some() && human.group_dof("torso_lift").is_none());
}

#[test]
fn a_model_without_srdf_has_no_chains_and_says_so() {
    let e = pr2_alone().chain("right_arm").unwrap_err().to_string();
    assert!(e.contains("no SRDF"), "{e}");
}

#[test]
fn an_undeclared_group_is_named_with_its_position() {
    let e = error(
        "<robot name=\"pr2\">\n  <end_effector name=\"g\" parent_link=\"r_gripper_tool_frame\"\n    group=\"r_gripper\" parent_group=\"right_arm\"/>\n</robot>",
    );
    assert!(e.starts_with("test.srdf:3:12: no group `r_gripper`"), "{e}");
}

#[test]
fn an_unknown_link_is_named_with_its_position() {
    let e = error(
        "<robot name=\"pr2\">\n<group name=\"a\"><chain base_link=\"torso_lift_link\" tip_link=\"wing\"/></group>\n</robot>",
    );
    assert!(e.starts_with("test.srdf:2:"), "{e}");
    assert!(e.contains("unknown link `wing`"), "{e}");
}

#[test]
fn a_bad_joint_value_is_an_error() {
    let state = |v: &str| {
        format!(
            "<robot name=\"pr2\"><group name=\"t\"><joint name=\"torso_lift_joint\"/></group>\n<group_state name=\"up\" group=\"t\"><joint name=\"torso_lift_joint\" value=\"{v}\"/></group_state></robot>"
        )
    };
    let e = error(&state("high"));
    assert!(
        e.starts_with("test.srdf:2:") && e.contains("is not a number"),
        "{e}"
    );
    let e = error(&state("7"));
    assert!(e.contains("outside its limits"), "{e}");
    let e = error(
        "<robot name=\"pr2\"><group_state name=\"up\" group=\"t\"><joint name=\"no_such_joint\" value=\"0\"/></group_state></robot>",
    );
    assert!(e.contains("unknown joint `no_such_joint`"), "{e}");
}

#[test]
fn malformed_xml_and_another_robot_are_errors() {
    let e = error("<robot name=\"pr2\">\n  <group name=\"a\">\n</robot>");
    assert!(e.starts_with("test.srdf:3:"), "{e}");
    let e = error("<robot name=\"fetch\"/>");
    assert!(e.contains("describes `fetch`"), "{e}");
}

#[test]
fn the_fetch_has_one_arm_a_gripper_a_head_and_a_tucked_posture() {
    let fetch = AgentModel::from_urdf_file(models("fetch.urdf")).unwrap();
    assert_eq!(fetch.arm_names(), ["arm"]);
    let arm = fetch.chain("arm").unwrap();
    assert_eq!(arm.dofs.len(), 7, "a 7-DOF arm");
    let ee = fetch.semantics().end_effector("arm").unwrap();
    assert_eq!(ee.group, "gripper");
    assert_eq!(ee.parent_link, fetch.links()[arm.tip_link].name);
    let head = fetch.chain("head").unwrap();
    assert_eq!(head.dofs.len(), 2, "pan and tilt");
    let lift = fetch.group_dof("torso_lift").unwrap();
    assert!((fetch.dof_limits()[lift].upper - 0.386).abs() < 1e-6);
    // The hand: the palm and both fingers (and the tool frame) may touch what it holds.
    assert_eq!(fetch.hand_links(arm.tip_link).len(), 4);
    // The tucked posture sets the arm's seven joints, each within its limits.
    let tucked = fetch.posture("tucked");
    assert_eq!(tucked.len(), 7);
    assert!(
        tucked
            .iter()
            .all(|&(d, v)| arm.dofs.contains(&d) && fetch.dof_limits()[d].contains(v))
    );
}

#[test]
fn the_fetch_tucked_posture_is_free_of_self_collision() {
    use geometry::collision::{
        CollisionChecker, SelfCollisionModel, SelfCollisionOptions, StaticObstacles,
    };
    use std::sync::Arc;
    let fetch = Arc::new(AgentModel::from_urdf_file(models("fetch.urdf")).unwrap());
    let model = Arc::new(SelfCollisionModel::new(
        fetch.clone(),
        &SelfCollisionOptions::default(),
    ));
    let checker = CollisionChecker::new(
        model,
        Arc::new(StaticObstacles::empty()),
        parry3d::math::Pose::IDENTITY,
    );
    let mut q = fetch.default_configuration().into_vec();
    for (d, v) in fetch.posture("tucked") {
        q[d] = v;
    }
    // With the torso raised as the library scenes have it (lowered fully, the folded elbow
    // meets the base).
    for lift in [0.25, 0.3, 0.386] {
        q[fetch.group_dof("torso_lift").unwrap()] = lift;
        let hit = checker.first_collision(&q);
        assert!(hit.is_none(), "lift {lift}: {hit:?}");
    }
}

/// A MoveIt SRDF as the setup assistant often writes it (the Fetch's): arms given by their
/// joints, a gripper by its links, an end effector without `parent_group`. The arm is the
/// group of fewest joints whose chain holds the end effector's `parent_link`, its chain
/// spans its joints, and the gripper's joint is a finger's (a link brings its parent joint).
#[test]
fn groups_of_joints_and_links_and_an_inferred_arm_are_read_as_moveit_reads_them() {
    let arm: String = common::PR2_RIGHT_ARM
        .iter()
        .map(|j| format!("<joint name=\"{j}\"/>"))
        .collect();
    let srdf = format!(
        "<robot name=\"pr2\">\n\
         <group name=\"arm_with_torso\"><joint name=\"torso_lift_joint\"/>{arm}</group>\n\
         <group name=\"arm\">{arm}</group>\n\
         <group name=\"gripper\"><link name=\"r_gripper_palm_link\"/>\
         <link name=\"r_gripper_l_finger_link\"/><link name=\"r_gripper_r_finger_link\"/></group>\n\
         <end_effector name=\"gripper\" parent_link=\"r_wrist_roll_link\" group=\"gripper\"/>\n\
         </robot>"
    );
    let pr2 = pr2_alone().with_srdf_str(&srdf, "joints.srdf").unwrap();
    assert_eq!(pr2.arm_names(), ["arm"]);
    let chain = pr2.chain("arm").unwrap();
    assert_eq!(pr2.links()[chain.root_link].name, "torso_lift_link");
    assert_eq!(pr2.links()[chain.tip_link].name, "r_wrist_roll_link");
    assert_eq!(chain.dofs.len(), 7);
    assert!(pr2.chain("arm_with_torso").is_ok());
    let gripper = pr2.semantics().group("gripper").unwrap();
    assert!(
        gripper
            .joints
            .contains(&"r_gripper_l_finger_joint".to_string())
    );
    assert!(gripper.chain.is_none());
}

/// As xArm's MoveIt SRDF has it: the arm's group lists the fixed joints out to the tool frame,
/// and the gripper's group, given by links, brings the same fixed joints; the end effector
/// names no `parent_group`. Only movable joints shared with the gripper rule a group out, so
/// the arm is found, ending at the tool frame.
#[test]
fn an_arm_sharing_fixed_joints_with_its_gripper_is_inferred() {
    let arm: String = common::PR2_RIGHT_ARM
        .iter()
        .chain(&["r_gripper_palm_joint", "r_gripper_tool_joint"])
        .map(|j| format!("<joint name=\"{j}\"/>"))
        .collect();
    let srdf = format!(
        "<robot name=\"pr2\">\n\
         <group name=\"arm\">{arm}</group>\n\
         <group name=\"gripper\"><link name=\"r_gripper_palm_link\"/>\
         <link name=\"r_gripper_l_finger_link\"/><link name=\"r_gripper_r_finger_link\"/>\
         <link name=\"r_gripper_tool_frame\"/></group>\n\
         <end_effector name=\"gripper\" parent_link=\"r_gripper_tool_frame\" group=\"gripper\"/>\n\
         </robot>"
    );
    let pr2 = pr2_alone().with_srdf_str(&srdf, "xarm-like.srdf").unwrap();
    assert_eq!(pr2.arm_names(), ["arm"]);
    let chain = pr2.chain("arm").unwrap();
    assert_eq!(pr2.links()[chain.tip_link].name, "r_gripper_tool_frame");
}

/// MoveIt's Baxter SRDF marks its virtual joint passive: read, as MoveIt reads it; a passive
/// joint that is neither a joint nor a virtual joint is an error with its position.
#[test]
fn a_passive_joint_may_name_the_virtual_joint() {
    let srdf = "<robot name=\"pr2\">\n\
         <virtual_joint name=\"world_joint\" type=\"planar\" parent_frame=\"odom\" child_link=\"base_link\"/>\n\
         <passive_joint name=\"world_joint\"/>\n\
         </robot>";
    let pr2 = pr2_alone().with_srdf_str(srdf, "passive.srdf").unwrap();
    assert_eq!(pr2.semantics().passive_joints, ["world_joint"]);
    let e = error(&srdf.replace(
        "<passive_joint name=\"world_joint\"",
        "<passive_joint name=\"world\"",
    ));
    assert!(
        e.contains("test.srdf:3:") && e.contains("unknown joint `world`"),
        "{e}"
    );
}
