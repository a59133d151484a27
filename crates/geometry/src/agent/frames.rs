//! Frames a scene adds to an agent's URDF without editing the user's file: tool frames and
//! cameras a description lacks (the Panda's URDF has no tool centre point and no camera), and
//! the height at which a robot is mounted (a Panda fixed to a table, as MoveIt's `virtual_joint`
//! to `world` places it).
//!
//! They become fixed joints added to the URDF text in memory before the model is read, so
//! that the URDF a plan JSON carries (and a checker computes its kinematics from) has them too.
//! The mount is a new root link, `floor_mount`, on the floor at the agent's base pose, with the
//! URDF's root above it: every base pose stays a pose on the floor.

use std::collections::HashSet;

/// A fixed frame added to an agent's kinematic tree.
#[derive(Clone, Debug, PartialEq)]
pub struct ExtraFrame {
    /// The new link's name (its joint is `NAME_joint`).
    pub name: String,
    /// The link it hangs from: one of the URDF or an earlier frame.
    pub parent: String,
    /// Its origin in the parent link, metres.
    pub xyz: [f32; 3],
    /// Its orientation in the parent link, roll, pitch, yaw in radians (URDF's convention).
    pub rpy: [f32; 3],
}

/// The name of the root link added under a mounted robot.
pub const MOUNT_LINK: &str = "floor_mount";

/// What is wrong with a scene's frames or mount: the scene key (`frames`, `base.z`) and why.
#[derive(Clone, Debug, PartialEq)]
pub struct FrameError {
    pub key: &'static str,
    pub message: String,
}

/// `text` (a URDF) with `frames` added, and with its root link `mount_height` metres above a
/// new root [`MOUNT_LINK`] when the height is not 0. Errors say what is wrong with a frame (a
/// name already used, a parent that is not a link) or the mount. A document urdf-rs cannot read
/// is returned unchanged, for the model's loader to report where it is wrong.
pub fn add_frames(
    text: &str,
    frames: &[ExtraFrame],
    mount_height: f32,
) -> Result<String, FrameError> {
    let frame_error = |message: String| FrameError {
        key: "frames",
        message,
    };
    let mount_error = |message: String| FrameError {
        key: "base.z",
        message,
    };
    if frames.is_empty() && mount_height == 0.0 {
        return Ok(text.to_string());
    }
    let Ok(Ok(robot)) = std::panic::catch_unwind(|| urdf_rs::read_from_string(text)) else {
        return Ok(text.to_string());
    };
    let Some(end) = text.rfind("</robot>") else {
        return Ok(text.to_string());
    };
    let mut links: HashSet<String> = robot.links.iter().map(|l| l.name.clone()).collect();
    let mut joints: HashSet<String> = robot.joints.iter().map(|j| j.name.clone()).collect();
    let mut added = String::from("\n  <!-- added by the htngtp scene -->\n");
    for f in frames {
        let joint = format!("{}_joint", f.name);
        check_name(&f.name).map_err(frame_error)?;
        if links.contains(&f.name) || joints.contains(&joint) {
            return Err(frame_error(format!(
                "frame `{}`: the URDF already has a link `{}` or a joint `{joint}`",
                f.name, f.name
            )));
        }
        if !links.contains(&f.parent) {
            return Err(frame_error(format!(
                "frame `{}`: no link `{}` to hang it from",
                f.name, f.parent
            )));
        }
        added.push_str(&format!("  <link name=\"{}\"/>\n", f.name));
        added.push_str(&fixed_joint(&joint, &f.parent, &f.name, f.xyz, f.rpy));
        links.insert(f.name.clone());
        joints.insert(joint);
    }
    if mount_height != 0.0 {
        let children: HashSet<&str> = robot.joints.iter().map(|j| j.child.link.as_str()).collect();
        let roots: Vec<&str> = robot
            .links
            .iter()
            .map(|l| l.name.as_str())
            .filter(|l| !children.contains(l))
            .collect();
        let [root] = roots[..] else {
            return Err(mount_error(format!(
                "the URDF has {} root links, so there is no one link to mount",
                roots.len()
            )));
        };
        let joint = format!("{MOUNT_LINK}_joint");
        if links.contains(MOUNT_LINK) || joints.contains(&joint) {
            return Err(mount_error(format!(
                "the URDF already has a link `{MOUNT_LINK}` or a joint `{joint}`"
            )));
        }
        added.push_str(&format!("  <link name=\"{MOUNT_LINK}\"/>\n"));
        added.push_str(&fixed_joint(
            &joint,
            MOUNT_LINK,
            root,
            [0.0, 0.0, mount_height],
            [0.0; 3],
        ));
    }
    Ok(format!("{}{added}{}", &text[..end], &text[end..]))
}

/// Frame names go into XML attributes: letters, digits and `_-./` only.
fn check_name(name: &str) -> Result<(), String> {
    let ok = !name.is_empty()
        && name
            .chars()
            .all(|c| c.is_ascii_alphanumeric() || "_-./".contains(c));
    if ok {
        Ok(())
    } else {
        Err(format!(
            "frame name `{name}`: use letters, digits and `_-./` only"
        ))
    }
}

/// A fixed joint's element.
fn fixed_joint(name: &str, parent: &str, child: &str, xyz: [f32; 3], rpy: [f32; 3]) -> String {
    format!(
        "  <joint name=\"{name}\" type=\"fixed\"><parent link=\"{parent}\"/>\
         <child link=\"{child}\"/><origin xyz=\"{} {} {}\" rpy=\"{} {} {}\"/></joint>\n",
        xyz[0], xyz[1], xyz[2], rpy[0], rpy[1], rpy[2]
    )
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::agent::AgentModel;
    use parry3d::math::Pose;

    const ARM: &str = r#"<robot name="arm">
  <link name="base"/><link name="hand"/>
  <joint name="j" type="revolute"><parent link="base"/><child link="hand"/>
    <origin xyz="0 0 0.5"/><axis xyz="0 0 1"/><limit lower="-1" upper="1" effort="1" velocity="1"/></joint>
</robot>"#;

    fn tcp() -> ExtraFrame {
        ExtraFrame {
            name: "tcp".into(),
            parent: "hand".into(),
            xyz: [0.0, 0.0, 0.1],
            rpy: [0.0, -std::f32::consts::FRAC_PI_2, 0.0],
        }
    }

    #[test]
    fn a_frame_and_a_mount_are_where_the_scene_puts_them() {
        let text = add_frames(ARM, &[tcp()], 0.75).unwrap();
        let model = AgentModel::from_urdf_str(&text, "arm.urdf").unwrap();
        let q = vec![0.0; model.dof()];
        let base = Pose::translation(1.0, 2.0, 0.0);
        let at = |name: &str| model.link_pose(base, &q, name).unwrap();
        assert_eq!(model.links()[0].name, MOUNT_LINK);
        assert!(
            (at("base").translation - parry3d::math::Vector::new(1.0, 2.0, 0.75)).length() < 1e-6
        );
        let tcp = at("tcp");
        assert!((tcp.translation.z - 1.35).abs() < 1e-5);
        // x of the new frame is the hand's z (the approach direction).
        let x = tcp.rotation * parry3d::math::Vector::X;
        assert!((x.z - 1.0).abs() < 1e-5, "{x:?}");
    }

    #[test]
    fn a_frame_on_a_missing_link_or_reusing_a_name_is_refused() {
        let mut f = tcp();
        f.parent = "wrist".into();
        let e = add_frames(ARM, &[f], 0.0).unwrap_err();
        assert_eq!(e.key, "frames");
        assert!(e.message.contains("no link `wrist`"), "{e:?}");
        let mut f = tcp();
        f.name = "hand".into();
        let e = add_frames(ARM, &[f], 0.0).unwrap_err();
        assert!(e.message.contains("already has a link `hand`"), "{e:?}");
        let mut f = tcp();
        f.name = "a\"b".into();
        let e = add_frames(ARM, &[f], 0.0).unwrap_err();
        assert!(e.message.contains("letters"), "{e:?}");
    }

    #[test]
    fn frames_may_hang_from_earlier_frames_and_nothing_changes_without_any() {
        let mut cam = tcp();
        cam.name = "camera".into();
        cam.parent = "tcp".into();
        assert!(add_frames(ARM, &[tcp(), cam], 0.0).is_ok());
        assert_eq!(add_frames(ARM, &[], 0.0).unwrap(), ARM);
    }
}
