//! Forward kinematics of an agent from the URDF text its plan JSON carries, in f64, written here
//! from the URDF specification (origin `xyz`/`rpy` with R = Rz(yaw) Ry(pitch) Rx(roll), axis,
//! revolute/continuous/prismatic/fixed joints, `mimic`) so that the check shares no code with the
//! planner's kinematics. The base link's pose is the planar base (`base_x`, `base_y`,
//! `base_yaw`, at z = 0).

use std::collections::BTreeMap;
use std::f64::consts::PI;

/// A rigid transform: rotation as a unit quaternion `[x, y, z, w]`, then translation.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Iso {
    pub q: [f64; 4],
    pub t: [f64; 3],
}

impl Iso {
    pub const IDENTITY: Iso = Iso {
        q: [0.0, 0.0, 0.0, 1.0],
        t: [0.0; 3],
    };

    /// A turn of `angle` about the unit `axis`.
    pub fn rotation(axis: [f64; 3], angle: f64) -> Iso {
        let (s, c) = (angle / 2.0).sin_cos();
        Iso {
            q: [axis[0] * s, axis[1] * s, axis[2] * s, c],
            t: [0.0; 3],
        }
    }

    /// URDF's fixed-axis roll, pitch, yaw: R = Rz(yaw) Ry(pitch) Rx(roll).
    pub fn from_urdf(xyz: [f64; 3], rpy: [f64; 3]) -> Iso {
        let r = Iso::rotation([0.0, 0.0, 1.0], rpy[2])
            .then(&Iso::rotation([0.0, 1.0, 0.0], rpy[1]))
            .then(&Iso::rotation([1.0, 0.0, 0.0], rpy[0]));
        Iso { q: r.q, t: xyz }
    }

    /// `self * other`: `other` expressed in `self`'s frame.
    pub fn then(&self, other: &Iso) -> Iso {
        let [ax, ay, az, aw] = self.q;
        let [bx, by, bz, bw] = other.q;
        let q = [
            aw * bx + ax * bw + ay * bz - az * by,
            aw * by - ax * bz + ay * bw + az * bx,
            aw * bz + ax * by - ay * bx + az * bw,
            aw * bw - ax * bx - ay * by - az * bz,
        ];
        let r = self.rotate(other.t);
        Iso {
            q,
            t: [r[0] + self.t[0], r[1] + self.t[1], r[2] + self.t[2]],
        }
    }

    /// `v` rotated by this transform's rotation.
    pub fn rotate(&self, v: [f64; 3]) -> [f64; 3] {
        let [x, y, z, w] = self.q;
        // v + 2w (u x v) + 2 u x (u x v), with u the vector part.
        let c1 = [
            y * v[2] - z * v[1],
            z * v[0] - x * v[2],
            x * v[1] - y * v[0],
        ];
        let c2 = [
            y * c1[2] - z * c1[1],
            z * c1[0] - x * c1[2],
            x * c1[1] - y * c1[0],
        ];
        [
            v[0] + 2.0 * (w * c1[0] + c2[0]),
            v[1] + 2.0 * (w * c1[1] + c2[1]),
            v[2] + 2.0 * (w * c1[2] + c2[2]),
        ]
    }

    /// Distance between the origins (m) and angle between the rotations (rad). The angle is
    /// taken from the relative rotation's vector part (atan2), which stays exact near zero where
    /// `acos` of a dot product of f32 quaternions would not.
    pub fn distance(&self, other: &Iso) -> (f64, f64) {
        let d = (0..3)
            .map(|i| (self.t[i] - other.t[i]).powi(2))
            .sum::<f64>();
        let [x, y, z, w] = self.q;
        let inverse = Iso {
            q: [-x, -y, -z, w],
            t: [0.0; 3],
        };
        let r = inverse.then(other).q;
        let v = (r[0] * r[0] + r[1] * r[1] + r[2] * r[2]).sqrt();
        (d.sqrt(), 2.0 * v.atan2(r[3].abs()))
    }
}

#[derive(Clone, Copy, Debug, PartialEq)]
enum Motion {
    Fixed,
    Turn,
    Slide,
}

#[derive(Clone, Debug)]
struct Joint {
    name: String,
    parent: String,
    child: String,
    origin: Iso,
    axis: [f64; 3],
    motion: Motion,
    /// `(master, multiplier, offset)`.
    mimic: Option<(String, f64, f64)>,
    /// Lower and upper limit (a continuous joint: a full turn either way).
    limits: (f64, f64),
}

/// An agent's kinematic tree, joints ordered parents first.
#[derive(Clone, Debug)]
pub struct Kinematics {
    root: String,
    joints: Vec<Joint>,
}

impl Kinematics {
    /// Reads URDF text; the error says what is wrong.
    pub fn from_urdf(text: &str) -> Result<Kinematics, String> {
        let robot = std::panic::catch_unwind(|| urdf_rs::read_from_string(text))
            .map_err(|_| "the URDF reader failed".to_string())?
            .map_err(|e| format!("not a valid URDF document: {e}"))?;
        let children: Vec<&str> = robot.joints.iter().map(|j| j.child.link.as_str()).collect();
        let root = robot
            .links
            .iter()
            .find(|l| !children.contains(&l.name.as_str()))
            .ok_or("no root link (every link is some joint's child)")?
            .name
            .clone();
        let joints: Vec<Joint> = robot.joints.iter().map(joint).collect::<Result<_, _>>()?;
        Ok(Kinematics {
            joints: parents_first(&root, joints)?,
            root,
        })
    }

    /// Every link's pose for the joint values `q` (by joint name; the base by `base_x`,
    /// `base_y`, `base_yaw`; a movable joint without a value is at 0).
    pub fn link_poses(&self, q: &BTreeMap<String, f64>) -> BTreeMap<String, Iso> {
        let value = |n: &str| q.get(n).copied().unwrap_or(0.0);
        let mut base = Iso::rotation([0.0, 0.0, 1.0], value("base_yaw"));
        base.t = [value("base_x"), value("base_y"), 0.0];
        let mut poses = BTreeMap::from([(self.root.clone(), base)]);
        for j in &self.joints {
            let v = match &j.mimic {
                Some((master, m, o)) => value(master) * m + o,
                None => value(&j.name),
            };
            let motion = match j.motion {
                Motion::Fixed => Iso::IDENTITY,
                Motion::Turn => Iso::rotation(j.axis, v),
                Motion::Slide => Iso {
                    q: Iso::IDENTITY.q,
                    t: [j.axis[0] * v, j.axis[1] * v, j.axis[2] * v],
                },
            };
            let parent = poses.get(&j.parent).copied().unwrap_or(Iso::IDENTITY);
            poses.insert(j.child.clone(), parent.then(&j.origin).then(&motion));
        }
        poses
    }
}

/// The joints that turn an agent's head: from the joint above its pivot link (the pan joint)
/// down to its eye link, as the URDF declares them.
#[derive(Clone, Debug)]
pub struct HeadChain {
    /// The link the first joint hangs from (it does not move when the head turns).
    pub root: String,
    joints: Vec<Joint>,
}

impl Kinematics {
    /// The head chain from the joint whose child is `pivot` down to `eye`; `None` when `eye`
    /// does not hang below `pivot` or the chain has a mimic joint.
    pub fn head_chain(&self, pivot: &str, eye: &str) -> Option<HeadChain> {
        let mut joints = Vec::new();
        let mut link = eye;
        loop {
            let j = self.joints.iter().find(|j| j.child == link)?;
            if j.mimic.is_some() && j.motion != Motion::Fixed {
                return None;
            }
            joints.push(j.clone());
            if j.child == pivot {
                break;
            }
            link = &j.parent;
        }
        joints.reverse();
        Some(HeadChain {
            root: joints[0].parent.clone(),
            joints,
        })
    }
}

impl HeadChain {
    /// The limits of the chain's movable joints, in chain order.
    pub fn limits(&self) -> Vec<(f64, f64)> {
        self.movable().map(|j| j.limits).collect()
    }

    /// The eye's pose with the movable joints at `values` (chain order) when the root link is
    /// at `root`.
    pub fn eye_pose(&self, root: &Iso, values: &[f64]) -> Iso {
        let mut pose = *root;
        let mut v = values.iter();
        for j in &self.joints {
            pose = pose.then(&j.origin);
            if j.motion != Motion::Fixed {
                let x = v.next().copied().unwrap_or(0.0);
                pose = pose.then(&match j.motion {
                    Motion::Turn => Iso::rotation(j.axis, x),
                    _ => Iso {
                        q: Iso::IDENTITY.q,
                        t: j.axis.map(|a| a * x),
                    },
                });
            }
        }
        pose
    }

    fn movable(&self) -> impl Iterator<Item = &Joint> {
        self.joints.iter().filter(|j| j.motion != Motion::Fixed)
    }
}

fn joint(j: &urdf_rs::Joint) -> Result<Joint, String> {
    let a = j.axis.xyz.0;
    let norm = (a[0] * a[0] + a[1] * a[1] + a[2] * a[2]).sqrt();
    let motion = match j.joint_type {
        urdf_rs::JointType::Revolute | urdf_rs::JointType::Continuous => Motion::Turn,
        urdf_rs::JointType::Prismatic => Motion::Slide,
        urdf_rs::JointType::Fixed => Motion::Fixed,
        ref other => {
            return Err(format!(
                "joint `{}`: type {other:?} is not supported",
                j.name
            ));
        }
    };
    if motion != Motion::Fixed && !(norm.is_finite() && norm > 0.0) {
        return Err(format!("joint `{}`: its axis has no direction", j.name));
    }
    Ok(Joint {
        name: j.name.clone(),
        parent: j.parent.link.clone(),
        child: j.child.link.clone(),
        origin: Iso::from_urdf(j.origin.xyz.0, j.origin.rpy.0),
        axis: a.map(|x| x / norm),
        motion,
        limits: match j.joint_type {
            urdf_rs::JointType::Continuous => (-PI, PI),
            _ => (j.limit.lower, j.limit.upper),
        },
        mimic: j.mimic.as_ref().map(|m| {
            (
                m.joint.clone(),
                m.multiplier.unwrap_or(1.0),
                m.offset.unwrap_or(0.0),
            )
        }),
    })
}

/// The joints ordered so that each comes after the joint of its parent link.
fn parents_first(root: &str, mut rest: Vec<Joint>) -> Result<Vec<Joint>, String> {
    let mut known = vec![root.to_string()];
    let mut out = Vec::with_capacity(rest.len());
    while !rest.is_empty() {
        let before = rest.len();
        let (ready, later): (Vec<Joint>, Vec<Joint>) =
            rest.into_iter().partition(|j| known.contains(&j.parent));
        known.extend(ready.iter().map(|j| j.child.clone()));
        out.extend(ready);
        rest = later;
        if rest.len() == before {
            return Err(format!(
                "joint `{}` hangs from link `{}`, which is not connected to the root",
                rest[0].name, rest[0].parent
            ));
        }
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    const ARM: &str = r#"<robot name="arm">
      <link name="base"/><link name="upper"/><link name="tip"/><link name="finger"/>
      <joint name="shoulder" type="revolute"><parent link="base"/><child link="upper"/>
        <origin xyz="0 0 1" rpy="0 0 0"/><axis xyz="0 0 1"/>
        <limit lower="-3" upper="3" effort="1" velocity="1"/></joint>
      <joint name="elbow" type="fixed"><parent link="upper"/><child link="tip"/>
        <origin xyz="1 0 0" rpy="0 0 1.5707963267948966"/></joint>
      <joint name="slide" type="prismatic"><parent link="tip"/><child link="finger"/>
        <origin xyz="0 0 0"/><axis xyz="1 0 0"/><mimic joint="shoulder" multiplier="2" offset="0.5"/>
        <limit lower="0" upper="1" effort="1" velocity="1"/></joint>
    </robot>"#;

    fn close(a: [f64; 3], b: [f64; 3]) -> bool {
        (0..3).all(|i| (a[i] - b[i]).abs() < 1e-9)
    }

    #[test]
    fn chain_with_turn_fixed_rpy_and_mimic_slide() {
        let k = Kinematics::from_urdf(ARM).unwrap();
        let q = BTreeMap::from([
            ("shoulder".to_string(), std::f64::consts::FRAC_PI_2),
            ("base_x".to_string(), 1.0),
        ]);
        let p = k.link_poses(&q);
        // Shoulder turned a quarter: the tip is at (1, 1, 1) instead of (2, 0, 1).
        assert!(close(p["tip"].t, [1.0, 1.0, 1.0]));
        // The finger slides by 2 * pi/2 + 0.5 along the tip's x, which points along world -x.
        let s = std::f64::consts::PI + 0.5;
        assert!(close(p["finger"].t, [1.0 - s, 1.0, 1.0]));
    }

    #[test]
    fn disconnected_joint_and_bad_text_are_errors() {
        assert!(Kinematics::from_urdf("<robot").is_err());
        let orphan = ARM.replace(r#"<parent link="tip"/>"#, r#"<parent link="nowhere"/>"#);
        let e = Kinematics::from_urdf(&orphan).unwrap_err();
        assert!(e.contains("nowhere"), "{e}");
    }
}
