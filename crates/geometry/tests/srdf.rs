//! The SRDF reader: the shipped models' descriptions, and every kind of bad content with its
//! `file:line:col`.

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
