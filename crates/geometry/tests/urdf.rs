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

/// Every malformed file in `tests/bad_urdf/` with (the line reported, a phrase of the message).
const BAD: &[(&str, Option<usize>, &str)] = &[
    ("bad_number.urdf", Some(8), "expected 3 found 2"),
    (
        "duplicate_joint.urdf",
        Some(6),
        "joint 'j' is defined twice",
    ),
    (
        "duplicate_link.urdf",
        Some(4),
        "link 'arm' is defined twice",
    ),
    (
        "floating_joint.urdf",
        Some(5),
        "type floating is not supported",
    ),
    ("infinite_collision_origin.urdf", Some(3), "non-finite"),
    (
        "inverted_limits.urdf",
        Some(5),
        "lower limit 1 must be below upper limit -1",
    ),
    ("joint_cycle.urdf", Some(4), "cycle"),
    (
        "joint_to_itself.urdf",
        Some(4),
        "connects link 'base' to itself",
    ),
    (
        "mesh_geometry.urdf",
        Some(3),
        "collision mesh 'package://pr2/base.stl': package `pr2` not found",
    ),
    (
        "mimic_unknown_joint.urdf",
        Some(5),
        "mimics joint 'elbow', which is not defined",
    ),
    ("missing_limit.urdf", Some(5), "a missing <limit>"),
    (
        "missing_parent_link.urdf",
        Some(5),
        "parent link 'torso' is not defined",
    ),
    ("nan_origin.urdf", Some(5), "non-finite"),
    (
        "negative_box.urdf",
        Some(3),
        "box size y must be a positive finite number",
    ),
    ("no_links.urdf", None, "has no <link>"),
    ("not_xml.urdf", None, "not a valid URDF document"),
    (
        "two_parents.urdf",
        Some(13),
        "link 'b' has two parent joints",
    ),
    ("two_roots.urdf", Some(5), "not one tree"),
    (
        "unknown_joint_type.urdf",
        Some(5),
        "unknown variant `hinge`",
    ),
    (
        "zero_axis.urdf",
        Some(5),
        "axis [0.0, 0.0, 0.0] is not a finite non-zero vector",
    ),
    (
        "zero_radius_capsule.urdf",
        Some(3),
        "capsule radius must be a positive finite number",
    ),
];

#[test]
fn malformed_urdf_files_give_clear_errors() {
    let dir = format!("{}/tests/bad_urdf", env!("CARGO_MANIFEST_DIR"));
    let mut files: Vec<String> = std::fs::read_dir(&dir)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    files.sort();
    let listed: Vec<&str> = BAD.iter().map(|b| b.0).collect();
    assert_eq!(
        files, listed,
        "every file in tests/bad_urdf needs an expectation"
    );
    for &(file, line, phrase) in BAD {
        let path = format!("{dir}/{file}");
        let err = AgentModel::from_urdf_file(&path).unwrap_err();
        let text = err.to_string();
        let prefix = match line {
            Some(l) => format!("{path}:{l}: "),
            None => format!("{path}: "),
        };
        assert!(text.starts_with(&prefix), "{file}: {text}");
        assert!(text.contains(phrase), "{file}: {text}");
    }
}

#[test]
fn missing_file_names_the_file() {
    let err = AgentModel::from_urdf_file("no/such/robot.urdf").unwrap_err();
    assert!(matches!(err, ModelError::Io { .. }));
    assert!(
        err.to_string()
            .starts_with("no/such/robot.urdf: cannot read")
    );
}

/// Truncated and corrupted versions of the real models give errors or models, never panics.
#[test]
fn corrupted_models_never_panic() {
    for file in ["pr2.urdf", "human.urdf"] {
        let text = std::fs::read_to_string(model_path(file)).unwrap();
        let mut rng = fastrand::Rng::with_seed(9);
        for cut in (0..text.len()).step_by(97) {
            let _ = AgentModel::from_urdf_str(&text[..cut], file);
        }
        let bytes = text.as_bytes();
        for _ in 0..200 {
            let mut b = bytes.to_vec();
            for _ in 0..3 {
                let i = rng.usize(..b.len());
                b[i] = *rng.choice(b"<>\"/= -e9.x0".iter()).unwrap();
            }
            if let Ok(t) = String::from_utf8(b) {
                let _ = AgentModel::from_urdf_str(&t, file);
            }
        }
    }
}

#[test]
fn velocity_limits_are_read_from_the_urdf() {
    let pr2 = AgentModel::from_urdf_file(model_path("pr2.urdf")).unwrap();
    let i = pr2.dof_index("r_shoulder_pan_joint").unwrap();
    assert_eq!(pr2.dof_velocity_limit(i), Some(1.0));
    // A continuous joint without a <limit> declares none.
    let i = pr2.dof_index("r_wrist_roll_joint").unwrap();
    assert_eq!(pr2.dof_velocity_limit(i), None);
    assert_eq!(pr2.dof_velocity_limit(pr2.dof()), None, "out of range");
    let urdf = |velocity: &str| {
        format!(
            r#"<robot name="r"><link name="a"/><link name="b"/>
            <joint name="j" type="revolute"><parent link="a"/><child link="b"/>
            <axis xyz="0 0 1"/><limit lower="-1" upper="1" effort="1" {velocity}/></joint></robot>"#
        )
    };
    let m = AgentModel::from_urdf_str(&urdf(r#"velocity="2.5""#), "r.urdf").unwrap();
    assert_eq!(m.dof_velocity_limit(0), Some(2.5));
    assert_eq!(
        m.dof_acceleration_limit(0),
        None,
        "URDF 1.0 has no acceleration"
    );
    for bad in [r#"velocity="0""#, r#"velocity="-1""#] {
        let m = AgentModel::from_urdf_str(&urdf(bad), "r.urdf").unwrap();
        assert_eq!(m.dof_velocity_limit(0), None, "{bad}");
    }
    // URDF 1.2's acceleration attribute (read in a file that says it is URDF 1.2).
    let text = urdf(r#"velocity="2" acceleration="3""#)
        .replace(r#"<robot name="r">"#, r#"<robot name="r" version="1.2">"#);
    let m = AgentModel::from_urdf_str(&text, "r.urdf").unwrap();
    assert_eq!(m.dof_acceleration_limit(0), Some(3.0));
}
