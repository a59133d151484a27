//! Loading the project's URDF models, and clear errors for malformed ones.

use geometry::agent::{AgentModel, JointKind, ModelError, Primitive};

fn model_path(name: &str) -> String {
    format!("{}/../../models/{name}", env!("CARGO_MANIFEST_DIR"))
}

#[test]
fn pr2_structure() {
    let pr2 = AgentModel::from_urdf_file(model_path("pr2.urdf")).unwrap();
    assert_eq!(pr2.name(), "pr2");
    assert_eq!(pr2.links()[0].name, "base_link");
    // torso, head pan/tilt, 2 x 7 arm joints, 2 gripper dofs (the other fingers mimic).
    assert_eq!(pr2.dof(), 1 + 2 + 14 + 2, "{:?}", pr2.dof_names());
    // Parents precede children.
    for (i, l) in pr2.links().iter().enumerate() {
        if let Some(p) = l.parent {
            assert!(p < i);
        }
    }
    let j = &pr2.joints()[pr2.joint_id("r_forearm_roll_joint").unwrap()];
    assert_eq!(j.kind, JointKind::Continuous);
    assert!(!j.limits.is_bounded());
    let i = pr2.dof_index("l_shoulder_pan_joint").unwrap();
    assert_eq!(pr2.dof_limits()[i].lower, -0.7146);
    assert_eq!(pr2.dof_limits()[i].upper, 2.2854);
    // Capsules on the arm links.
    let ua = pr2.link("r_upper_arm_link").unwrap();
    assert!(matches!(
        ua.collisions[0].primitive,
        Primitive::Capsule { .. }
    ));
    for chain in ["right_arm", "left_arm"] {
        let c = pr2.chain(chain).unwrap();
        assert_eq!(c.dofs.len(), 7, "{chain}");
        assert_eq!(pr2.links()[c.root_link].name, "torso_lift_link");
    }
    assert_eq!(pr2.chain("head").unwrap().dofs.len(), 2);
    assert!(pr2.chain("tail").is_err());
}

#[test]
fn human_structure() {
    let h = AgentModel::from_urdf_file(model_path("human.urdf")).unwrap();
    for chain in ["right_arm", "left_arm"] {
        let c = h.chain(chain).unwrap();
        assert_eq!(c.dofs.len(), 7, "{chain}");
        assert_eq!(
            h.links()[c.tip_link].name,
            if chain == "right_arm" {
                "r_hand"
            } else {
                "l_hand"
            }
        );
    }
    assert_eq!(h.chain("head").unwrap().dofs.len(), 2);
    h.link("eye").unwrap();
}

#[test]
fn configuration_rejects_out_of_limit_values() {
    let pr2 = AgentModel::from_urdf_file(model_path("pr2.urdf")).unwrap();
    let mut q = pr2.default_configuration();
    let e = q.set("torso_lift_joint", 0.5).unwrap_err();
    assert!(matches!(e, ModelError::OutOfLimits { .. }), "{e}");
    assert!(e.to_string().contains("torso_lift_joint"));
    q.set_clamped("torso_lift_joint", 0.5).unwrap();
    assert_eq!(q.get("torso_lift_joint").unwrap(), 0.33);
    assert!(q.set("no_such_joint", 0.0).is_err());
    assert!(q.set("head_pan_joint", f32::NAN).is_err());
    // Continuous joints take any finite value.
    q.set("r_wrist_roll_joint", 12.0).unwrap();
    assert!(pr2.configuration(vec![0.0; 3]).is_err());
}
