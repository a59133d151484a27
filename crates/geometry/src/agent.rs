//! Agent models: a robot or a human described by a URDF file, loaded with `urdf-rs`.
//!
//! An [`AgentModel`] is a tree of [`Link`]s connected by [`Joint`]s. Links are numbered in
//! topological order (the root is link 0 and every parent has a smaller index than its
//! children), so forward kinematics is one pass over the link array (see
//! [`AgentModel::link_poses`] in [`crate::kinematics`]). Joint `j` is the joint whose child is
//! link `j + 1`.
//!
//! The base of an agent (its root link) is placed in the world by the scene, as a [`Pose`]; the
//! URDF describes no joint for it. The movable joints (revolute, continuous, prismatic, not
//! mimicking another joint) are the agent's degrees of freedom; a joint configuration is a
//! `&[f32]` with one value per degree of freedom, in [`AgentModel::dof_names`] order, or a
//! [`Configuration`] that carries the names and limits with it.
//!
//! ## URDF conventions of this project
//!
//! * Supported joint types: `fixed`, `revolute`, `continuous` (no limits), `prismatic`, and
//!   `<mimic joint=".." multiplier=".." offset=".."/>` on any of the movable types.
//!   `floating`, `planar` and `spherical` are rejected: the scene places the base.
//! * Collision geometry: `<box>`, `<sphere>`, `<cylinder>` (axis along the element's z, as in
//!   URDF) and `<capsule radius=".." length=".."/>`: a capsule whose axis is the element's z and
//!   whose `length` is the distance between the centres of its two hemispherical caps (the
//!   SDFormat convention; `urdf-rs` reads this element although ROS's URDF 1.0 has no capsule).
//!   Meshes are rejected: the agent models are made of primitives so that collision checks are
//!   cheap. Visual elements are ignored.
//! * Revolute and prismatic joints must have `<limit lower=".." upper="..">` with
//!   `lower < upper`; continuous joints have no limits.
//! * Every number must be finite.

use std::collections::HashMap;
use std::fmt;
use std::path::Path;
use std::sync::Arc;

use parry3d::math::{Pose, Rotation, Vector};
use parry3d::shape::SharedShape;

/// Errors from loading an agent model or from using it with bad names or values.
#[derive(Debug, thiserror::Error)]
pub enum ModelError {
    /// The URDF file could not be read.
    #[error("{path}: cannot read the file: {source}")]
    Io {
        /// The file.
        path: String,
        /// The underlying error.
        source: std::io::Error,
    },
    /// The text is not well-formed URDF XML (as reported by `urdf-rs`).
    #[error("{source_name}{}: not a valid URDF document: {message}", line.map(|l| format!(":{l}")).unwrap_or_default())]
    Syntax {
        /// File name (or another name given for the text).
        source_name: String,
        /// The 1-based line of the offending text, when the message quotes it and it could be
        /// found (urdf-rs reports no positions).
        line: Option<usize>,
        /// What `urdf-rs` reported.
        message: String,
    },
    /// The URDF parses but describes something this project cannot use, or is inconsistent.
    #[error("{source_name}{}: {message}", line.map(|l| format!(":{l}")).unwrap_or_default())]
    Invalid {
        /// File name (or another name given for the text).
        source_name: String,
        /// The 1-based line of the offending element, when it could be located in the text.
        line: Option<usize>,
        /// What is wrong, naming the element.
        message: String,
    },
    /// A joint name that the model does not have (or that is not a degree of freedom).
    #[error("agent model '{model}' has no movable joint named '{name}'")]
    UnknownJoint {
        /// The model's name.
        model: String,
        /// The name asked for.
        name: String,
    },
    /// A link name that the model does not have.
    #[error("agent model '{model}' has no link named '{name}'")]
    UnknownLink {
        /// The model's name.
        model: String,
        /// The name asked for.
        name: String,
    },
    /// A joint value outside the joint's limits.
    #[error("joint '{joint}': value {value} is outside its limits [{lower}, {upper}]")]
    OutOfLimits {
        /// The joint.
        joint: String,
        /// The rejected value.
        value: f32,
        /// Lower limit.
        lower: f32,
        /// Upper limit.
        upper: f32,
    },
    /// A joint value that is NaN or infinite.
    #[error("joint '{joint}': value {value} is not a finite number")]
    NonFinite {
        /// The joint.
        joint: String,
        /// The rejected value.
        value: f32,
    },
    /// A configuration vector of the wrong length.
    #[error("agent model '{model}' has {expected} degrees of freedom, got {got} values")]
    WrongLength {
        /// The model's name.
        model: String,
        /// The model's number of degrees of freedom.
        expected: usize,
        /// The length given.
        got: usize,
    },
    /// A kinematic chain that cannot be formed.
    #[error("agent model '{model}': chain '{chain}': {message}")]
    Chain {
        /// The model's name.
        model: String,
        /// The chain asked for.
        chain: String,
        /// Why it cannot be formed.
        message: String,
    },
}

/// The type of a joint (the URDF types this project supports).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum JointKind {
    /// Rigid connection.
    Fixed,
    /// Rotation about the axis, within limits.
    Revolute,
    /// Rotation about the axis, unlimited.
    Continuous,
    /// Translation along the axis, within limits.
    Prismatic,
}

/// Position limits of a joint (radians or metres). Continuous joints have
/// `lower = -inf, upper = +inf`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct JointLimits {
    /// Lowest allowed value.
    pub lower: f32,
    /// Highest allowed value.
    pub upper: f32,
}

impl JointLimits {
    /// No limits (continuous joints).
    pub const UNLIMITED: JointLimits = JointLimits {
        lower: f32::NEG_INFINITY,
        upper: f32::INFINITY,
    };

    /// Whether both limits are finite.
    pub fn is_bounded(&self) -> bool {
        self.lower.is_finite() && self.upper.is_finite()
    }

    /// Whether `value` lies within the limits (with a tolerance of 1e-5 for rounding).
    pub fn contains(&self, value: f32) -> bool {
        value >= self.lower - 1e-5 && value <= self.upper + 1e-5
    }

    /// `value` moved into the limits.
    pub fn clamp(&self, value: f32) -> f32 {
        value.clamp(self.lower, self.upper)
    }
}

/// A joint's value follows another joint: `value = multiplier * master + offset`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Mimic {
    /// The joint (index into [`AgentModel::joints`]) that this one follows.
    pub master: usize,
    /// Scale of the master's value.
    pub multiplier: f32,
    /// Added to the scaled value.
    pub offset: f32,
}

/// A joint of the tree: connects `parent` to `child` (link indices).
#[derive(Debug, Clone)]
pub struct Joint {
    /// Name from the URDF.
    pub name: String,
    /// Type.
    pub kind: JointKind,
    /// Parent link index.
    pub parent: usize,
    /// Child link index (always `parent`'s index + something > 0, and equal to joint index + 1).
    pub child: usize,
    /// Pose of the joint frame in the parent link frame (URDF `<origin>`).
    pub origin: Pose,
    /// Unit axis in the joint frame (URDF `<axis>`, normalised). Unused for fixed joints.
    pub axis: Vector,
    /// Limits; `UNLIMITED` for continuous and fixed joints.
    pub limits: JointLimits,
    /// Index of this joint's value in a configuration vector, for movable joints that are not
    /// mimic joints. For mimic joints: `None` (see `mimic`). For fixed joints: `None`.
    pub dof: Option<usize>,
    /// Set when the joint mimics another joint.
    pub mimic: Option<Mimic>,
}

impl Joint {
    /// Whether the joint moves (revolute, continuous or prismatic, mimic or not).
    pub fn is_movable(&self) -> bool {
        self.kind != JointKind::Fixed
    }

    /// The transform from the parent link frame to the child link frame at joint value `value`.
    #[inline]
    pub fn transform(&self, value: f32) -> Pose {
        match self.kind {
            JointKind::Fixed => self.origin,
            JointKind::Revolute | JointKind::Continuous => {
                self.origin * Rotation::from_axis_angle(self.axis, value)
            }
            JointKind::Prismatic => {
                let mut p = self.origin;
                p.translation += self.origin.rotation * (self.axis * value);
                p
            }
        }
    }
}

/// The geometry a collision shape was made from (kept for rendering and reports).
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Primitive {
    /// Box with these half extents.
    Box {
        /// Half extents along x, y, z.
        half_extents: Vector,
    },
    /// Sphere.
    Sphere {
        /// Radius.
        radius: f32,
    },
    /// Cylinder along the local z axis.
    Cylinder {
        /// Radius.
        radius: f32,
        /// Full length.
        length: f32,
    },
    /// Capsule along the local z axis; `length` between the cap centres.
    Capsule {
        /// Radius.
        radius: f32,
        /// Distance between the centres of the two caps.
        length: f32,
    },
}

/// One collision shape of a link: a parry shape placed in the link frame.
#[derive(Clone)]
pub struct CollisionShape {
    /// Pose of the shape in the link frame. For cylinders this includes the quarter turn that
    /// maps parry's y-axis cylinder onto URDF's z-axis cylinder.
    pub local_pose: Pose,
    /// The shape, ready for parry queries.
    pub shape: SharedShape,
    /// What it was made from.
    pub primitive: Primitive,
    /// Radius of a sphere centred at `local_pose.translation` that contains the shape.
    pub bounding_radius: f32,
}

impl fmt::Debug for CollisionShape {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.debug_struct("CollisionShape")
            .field("local_pose", &self.local_pose)
            .field("primitive", &self.primitive)
            .finish()
    }
}

/// A link (rigid body) of the tree.
#[derive(Debug, Clone)]
pub struct Link {
    /// Name from the URDF.
    pub name: String,
    /// Parent link index (`None` for the root, link 0).
    pub parent: Option<usize>,
    /// The joint connecting this link to its parent (`None` for the root).
    pub parent_joint: Option<usize>,
    /// Child link indices.
    pub children: Vec<usize>,
    /// Collision shapes (may be empty: pure frames such as a tool frame).
    pub collisions: Vec<CollisionShape>,
}

/// Names and limits of an agent's degrees of freedom, shared by a model and its
/// configurations.
#[derive(Debug)]
pub struct DofTable {
    model: String,
    names: Vec<String>,
    limits: Vec<JointLimits>,
    index: HashMap<String, usize>,
}

impl DofTable {
    /// Number of degrees of freedom.
    pub fn len(&self) -> usize {
        self.names.len()
    }
    /// Whether there are none.
    pub fn is_empty(&self) -> bool {
        self.names.is_empty()
    }
    /// Joint names in configuration order.
    pub fn names(&self) -> &[String] {
        &self.names
    }
    /// Limits in configuration order.
    pub fn limits(&self) -> &[JointLimits] {
        &self.limits
    }
    /// Index in the configuration of the joint called `name`.
    pub fn index(&self, name: &str) -> Option<usize> {
        self.index.get(name).copied()
    }
}

/// Joint values of one agent, with their names and limits.
///
/// Values outside a joint's limits are **rejected** by [`Configuration::set`] (an error that
/// names the joint and its limits); [`Configuration::set_clamped`] clamps instead. Continuous
/// joints accept any finite value.
#[derive(Debug, Clone)]
pub struct Configuration {
    values: Vec<f32>,
    dofs: Arc<DofTable>,
}

impl PartialEq for Configuration {
    fn eq(&self, other: &Self) -> bool {
        Arc::ptr_eq(&self.dofs, &other.dofs) && self.values == other.values
    }
}

impl Configuration {
    /// Joint values in [`AgentModel::dof_names`] order.
    pub fn as_slice(&self) -> &[f32] {
        &self.values
    }

    /// Mutable access to the raw values. No limit checking: use [`Configuration::set`] for that.
    pub fn as_mut_slice(&mut self) -> &mut [f32] {
        &mut self.values
    }

    /// The values, consuming the configuration.
    pub fn into_vec(self) -> Vec<f32> {
        self.values
    }

    /// The degree-of-freedom table (names and limits).
    pub fn dofs(&self) -> &DofTable {
        &self.dofs
    }

    /// Value of the joint called `name`.
    pub fn get(&self, name: &str) -> Result<f32, ModelError> {
        let i = self.dof_index(name)?;
        Ok(self.values[i])
    }

    /// Sets the joint called `name`; rejects unknown names, non-finite values and values outside
    /// the joint's limits.
    pub fn set(&mut self, name: &str, value: f32) -> Result<(), ModelError> {
        let i = self.dof_index(name)?;
        let limits = self.dofs.limits[i];
        if !value.is_finite() {
            return Err(ModelError::NonFinite {
                joint: name.to_string(),
                value,
            });
        }
        if !limits.contains(value) {
            return Err(ModelError::OutOfLimits {
                joint: name.to_string(),
                value,
                lower: limits.lower,
                upper: limits.upper,
            });
        }
        self.values[i] = limits.clamp(value);
        Ok(())
    }

    /// Sets the joint called `name`, clamping the value into the joint's limits. Rejects unknown
    /// names and non-finite values.
    pub fn set_clamped(&mut self, name: &str, value: f32) -> Result<(), ModelError> {
        let i = self.dof_index(name)?;
        if !value.is_finite() {
            return Err(ModelError::NonFinite {
                joint: name.to_string(),
                value,
            });
        }
        self.values[i] = self.dofs.limits[i].clamp(value);
        Ok(())
    }

    /// Sets several joints by name (see [`Configuration::set`]).
    pub fn set_many(&mut self, values: &[(&str, f32)]) -> Result<(), ModelError> {
        for &(name, v) in values {
            self.set(name, v)?;
        }
        Ok(())
    }

    /// Whether every value is finite and within its joint's limits.
    pub fn is_within_limits(&self) -> bool {
        self.values
            .iter()
            .zip(&self.dofs.limits)
            .all(|(v, l)| v.is_finite() && l.contains(*v))
    }

    fn dof_index(&self, name: &str) -> Result<usize, ModelError> {
        self.dofs
            .index(name)
            .ok_or_else(|| ModelError::UnknownJoint {
                model: self.dofs.model.clone(),
                name: name.to_string(),
            })
    }
}

/// A serial chain of joints from a root link to a tip link, for inverse kinematics.
#[derive(Debug, Clone, PartialEq)]
pub struct KinematicChain {
    /// The chain's name (for example `right_arm`).
    pub name: String,
    /// The link the chain hangs from (fixed while the chain moves).
    pub root_link: usize,
    /// The link whose pose the chain controls (a tool, hand or eye frame).
    pub tip_link: usize,
    /// All joints from root to tip, in order (fixed ones included).
    pub joints: Vec<usize>,
    /// The configuration indices of the chain's movable joints, from root to tip.
    pub dofs: Vec<usize>,
}

/// Known chain names with their (root link, tip link) candidates, tried in order: the PR2's,
/// then the human's. A model has the chain when it has both links of a candidate.
pub const NAMED_CHAINS: &[(&str, &[(&str, &str)])] = &[
    (
        "right_arm",
        &[
            ("torso_lift_link", "r_gripper_tool_frame"),
            ("torso_link", "r_hand"),
        ],
    ),
    (
        "left_arm",
        &[
            ("torso_lift_link", "l_gripper_tool_frame"),
            ("torso_link", "l_hand"),
        ],
    ),
    (
        "head",
        &[("torso_lift_link", "head_camera"), ("torso_link", "eye")],
    ),
];

/// An agent's kinematic tree with collision shapes. Cheap to share behind an `Arc`.
#[derive(Debug, Clone)]
pub struct AgentModel {
    name: String,
    source_name: String,
    links: Vec<Link>,
    joints: Vec<Joint>,
    link_index: HashMap<String, usize>,
    joint_index: HashMap<String, usize>,
    dofs: Arc<DofTable>,
    /// For each configuration index, the joint index.
    dof_joints: Vec<usize>,
    /// For each configuration index, the URDF's `<limit velocity="..">` (rad/s or m/s), `None`
    /// when the URDF gives none (absent, zero, negative or not finite).
    dof_velocity_limits: Vec<Option<f32>>,
    /// For each configuration index, URDF 1.2's `<limit acceleration="..">` (rad/s^2 or
    /// m/s^2), `None` when absent, not positive or not finite.
    dof_acceleration_limits: Vec<Option<f32>>,
}

impl AgentModel {
    /// Loads a URDF file. Errors name the file and what is wrong; never panics.
    pub fn from_urdf_file(path: impl AsRef<Path>) -> Result<AgentModel, ModelError> {
        let path = path.as_ref();
        let text = std::fs::read_to_string(path).map_err(|source| ModelError::Io {
            path: path.display().to_string(),
            source,
        })?;
        Self::from_urdf_str(&text, &path.display().to_string())
    }

    /// Loads URDF text; `source_name` (a file name, usually) is used in error messages.
    pub fn from_urdf_str(text: &str, source_name: &str) -> Result<AgentModel, ModelError> {
        crate::agent::loader::load(text, source_name)
    }

    /// The robot name from the URDF.
    pub fn name(&self) -> &str {
        &self.name
    }

    /// The file (or other name) the model was loaded from.
    pub fn source_name(&self) -> &str {
        &self.source_name
    }

    /// All links; index 0 is the root, parents come before children.
    pub fn links(&self) -> &[Link] {
        &self.links
    }

    /// All joints; joint `j` has child link `j + 1`.
    pub fn joints(&self) -> &[Joint] {
        &self.joints
    }

    /// The link called `name`.
    pub fn link(&self, name: &str) -> Result<&Link, ModelError> {
        Ok(&self.links[self.link_id(name)?])
    }

    /// Index of the link called `name`.
    pub fn link_id(&self, name: &str) -> Result<usize, ModelError> {
        self.link_index
            .get(name)
            .copied()
            .ok_or_else(|| ModelError::UnknownLink {
                model: self.name.clone(),
                name: name.to_string(),
            })
    }

    /// Index of the joint (any type) called `name`.
    pub fn joint_id(&self, name: &str) -> Option<usize> {
        self.joint_index.get(name).copied()
    }

    /// Number of degrees of freedom (length of a configuration vector).
    pub fn dof(&self) -> usize {
        self.dofs.len()
    }

    /// Names of the degrees of freedom, in configuration order.
    pub fn dof_names(&self) -> &[String] {
        self.dofs.names()
    }

    /// Limits of the degrees of freedom, in configuration order.
    pub fn dof_limits(&self) -> &[JointLimits] {
        self.dofs.limits()
    }

    /// Configuration index of the movable joint called `name`.
    pub fn dof_index(&self, name: &str) -> Result<usize, ModelError> {
        self.dofs
            .index(name)
            .ok_or_else(|| ModelError::UnknownJoint {
                model: self.name.clone(),
                name: name.to_string(),
            })
    }

    /// The URDF velocity limit of configuration index `dof` (rad/s or m/s): `None` when the
    /// URDF declares none (a zero, negative or non-finite `velocity`; a continuous joint without
    /// `<limit>`) or `dof` is out of range.
    pub fn dof_velocity_limit(&self, dof: usize) -> Option<f32> {
        self.dof_velocity_limits.get(dof).copied().flatten()
    }

    /// The URDF acceleration limit of configuration index `dof` (URDF 1.2's `acceleration`
    /// attribute, rad/s^2 or m/s^2): `None` when absent, not positive, not finite, or `dof` is
    /// out of range.
    pub fn dof_acceleration_limit(&self, dof: usize) -> Option<f32> {
        self.dof_acceleration_limits.get(dof).copied().flatten()
    }

    /// The joint index of configuration entry `dof`.
    pub fn dof_joint(&self, dof: usize) -> usize {
        self.dof_joints[dof]
    }

    /// The default configuration: every joint at 0, moved into its limits when 0 is outside.
    pub fn default_configuration(&self) -> Configuration {
        Configuration {
            values: self.dofs.limits.iter().map(|l| l.clamp(0.0)).collect(),
            dofs: self.dofs.clone(),
        }
    }

    /// A configuration from raw values, checked for length, finiteness and limits.
    pub fn configuration(&self, values: Vec<f32>) -> Result<Configuration, ModelError> {
        if values.len() != self.dof() {
            return Err(ModelError::WrongLength {
                model: self.name.clone(),
                expected: self.dof(),
                got: values.len(),
            });
        }
        for (i, &v) in values.iter().enumerate() {
            let joint = &self.dofs.names[i];
            if !v.is_finite() {
                return Err(ModelError::NonFinite {
                    joint: joint.clone(),
                    value: v,
                });
            }
            let l = self.dofs.limits[i];
            if !l.contains(v) {
                return Err(ModelError::OutOfLimits {
                    joint: joint.clone(),
                    value: v,
                    lower: l.lower,
                    upper: l.upper,
                });
            }
        }
        Ok(Configuration {
            values,
            dofs: self.dofs.clone(),
        })
    }

    /// A uniformly random configuration within the limits (continuous joints in [-pi, pi]).
    pub fn random_configuration(&self, rng: &mut fastrand::Rng) -> Configuration {
        let values = self.dofs.limits.iter().map(|l| random_in(l, rng)).collect();
        Configuration {
            values,
            dofs: self.dofs.clone(),
        }
    }

    /// The value of joint `joint` in configuration `q` (follows mimic joints; 0 for fixed).
    #[inline]
    pub fn joint_value(&self, joint: usize, q: &[f32]) -> f32 {
        let j = &self.joints[joint];
        if let Some(d) = j.dof {
            q[d]
        } else if let Some(m) = j.mimic {
            let master = &self.joints[m.master];
            // Masters are never mimic joints themselves (checked at load time).
            master.dof.map(|d| q[d]).unwrap_or(0.0) * m.multiplier + m.offset
        } else {
            0.0
        }
    }

    /// Whether link `a` is link `b` or one of its descendants.
    pub fn is_descendant(&self, a: usize, b: usize) -> bool {
        let mut cur = Some(a);
        while let Some(c) = cur {
            if c == b {
                return true;
            }
            cur = self.links[c].parent;
        }
        false
    }

    /// The nearest ancestor of `link` (itself included) that has collision shapes.
    pub fn geometric_ancestor(&self, link: usize) -> Option<usize> {
        let mut cur = Some(link);
        while let Some(c) = cur {
            if !self.links[c].collisions.is_empty() {
                return Some(c);
            }
            cur = self.links[c].parent;
        }
        None
    }

    /// The serial chain called `name`: one of [`NAMED_CHAINS`] (`right_arm`, `left_arm`, `head`),
    /// using the first (root, tip) candidate whose links this model has. For the PR2 the arms run
    /// from `torso_lift_link` (shoulder pan first) to `r_/l_gripper_tool_frame`; for the human
    /// from `torso_link` (shoulder pitch first) to `r_/l_hand`.
    pub fn chain(&self, name: &str) -> Result<KinematicChain, ModelError> {
        let err = |message: String| ModelError::Chain {
            model: self.name.clone(),
            chain: name.to_string(),
            message,
        };
        let (_, candidates) = NAMED_CHAINS
            .iter()
            .find(|(n, _)| *n == name)
            .ok_or_else(|| {
                let known: Vec<&str> = NAMED_CHAINS.iter().map(|(n, _)| *n).collect();
                err(format!("unknown chain name; known: {}", known.join(", ")))
            })?;
        let (root, tip) = candidates
            .iter()
            .find(|(r, t)| self.link_index.contains_key(*r) && self.link_index.contains_key(*t))
            .ok_or_else(|| {
                err(format!(
                    "the model has none of the (root, tip) links {candidates:?}"
                ))
            })?;
        let mut chain = self.chain_between(root, tip)?;
        chain.name = name.to_string();
        Ok(chain)
    }

    /// The serial chain from link `root` down to link `tip` (`root` must be an ancestor of
    /// `tip`). Mimic joints inside the chain are rejected (inverse kinematics cannot drive them).
    pub fn chain_between(&self, root: &str, tip: &str) -> Result<KinematicChain, ModelError> {
        let name = format!("{root}->{tip}");
        let err = |message: String| ModelError::Chain {
            model: self.name.clone(),
            chain: name.clone(),
            message,
        };
        let r = self.link_id(root)?;
        let t = self.link_id(tip)?;
        let mut joints = Vec::new();
        let mut cur = t;
        while cur != r {
            match self.links[cur].parent_joint {
                Some(j) => {
                    joints.push(j);
                    cur = self.joints[j].parent;
                }
                None => return Err(err(format!("'{root}' is not an ancestor of '{tip}'"))),
            }
        }
        joints.reverse();
        let mut dofs = Vec::new();
        for &j in &joints {
            let joint = &self.joints[j];
            if joint.mimic.is_some() {
                return Err(err(format!(
                    "joint '{}' mimics another joint; chains cannot contain mimic joints",
                    joint.name
                )));
            }
            if let Some(d) = joint.dof {
                dofs.push(d);
            }
        }
        Ok(KinematicChain {
            name,
            root_link: r,
            tip_link: t,
            joints,
            dofs,
        })
    }
}

/// A uniform sample within `l` (continuous joints in [-pi, pi]).
pub(crate) fn random_in(l: &JointLimits, rng: &mut fastrand::Rng) -> f32 {
    let (lo, hi) = if l.is_bounded() {
        (l.lower, l.upper)
    } else {
        (-std::f32::consts::PI, std::f32::consts::PI)
    };
    lo + (hi - lo) * rng.f32()
}

/// Named postures of the project's human model (`models/human.urdf`): joint values to give
/// [`Configuration::set_many`]. Joints not named stay at 0 (arms hanging, head straight).
pub mod human_postures {
    /// Sitting on a chair (the zero configuration): pelvis at 0.50 m, eyes at 1.20 m,
    /// shoulders at 1.00 m, thighs horizontal, shins vertical.
    pub const SITTING: &[(&str, f32)] = &[
        ("pelvis_lift_joint", 0.0),
        ("r_hip_joint", 0.0),
        ("l_hip_joint", 0.0),
        ("r_knee_joint", 0.0),
        ("l_knee_joint", 0.0),
    ];
    /// Standing: pelvis at 0.90 m, eyes at 1.60 m, shoulders at 1.40 m, legs straight.
    pub const STANDING: &[(&str, f32)] = &[
        ("pelvis_lift_joint", 0.40),
        ("r_hip_joint", std::f32::consts::FRAC_PI_2),
        ("l_hip_joint", std::f32::consts::FRAC_PI_2),
        ("r_knee_joint", -std::f32::consts::FRAC_PI_2),
        ("l_knee_joint", -std::f32::consts::FRAC_PI_2),
    ];
}

mod loader {
    //! URDF (as parsed by `urdf-rs`) to [`AgentModel`], with validation.

    use super::*;

    struct Ctx<'a> {
        text: &'a str,
        source_name: &'a str,
    }

    impl Ctx<'_> {
        /// An `Invalid` error located at the element `<tag ... name="name"`, when found.
        fn invalid(&self, tag: &str, name: &str, message: String) -> ModelError {
            ModelError::Invalid {
                source_name: self.source_name.to_string(),
                line: locate(self.text, tag, name),
                message,
            }
        }
    }

    /// 1-based line of the first `<tag` element whose `name` attribute is `name`.
    fn locate(text: &str, tag: &str, name: &str) -> Option<usize> {
        let open = format!("<{tag}");
        let mut from = 0;
        while let Some(pos) = text[from..].find(&open) {
            let start = from + pos;
            let after = start + open.len();
            let end = text[after..]
                .find('>')
                .map(|e| after + e)
                .unwrap_or(text.len());
            let head = &text[after..end];
            if head.starts_with(|c: char| c.is_whitespace())
                && (head.contains(&format!("name=\"{name}\""))
                    || head.contains(&format!("name='{name}'")))
            {
                return Some(text[..start].matches('\n').count() + 1);
            }
            from = after;
        }
        None
    }

    /// The line of the text that `message` quotes (between backticks or square brackets), as
    /// an attribute value: urdf-rs quotes the bad value but gives no position.
    fn locate_quoted(text: &str, message: &str) -> Option<usize> {
        let quoted = |open: char, close: char| -> Option<&str> {
            let start = message.find(open)? + open.len_utf8();
            let end = start + message[start..].find(close)?;
            Some(&message[start..end])
        };
        let needle = quoted('`', '`').or_else(|| quoted('[', ']'))?;
        if needle.trim().is_empty() {
            return None;
        }
        let pos = text
            .find(&format!("\"{needle}\""))
            .or_else(|| text.find(&format!("'{needle}'")))?;
        Some(text[..pos].matches('\n').count() + 1)
    }

    fn finite3(v: &[f64; 3]) -> bool {
        v.iter().all(|x| x.is_finite())
    }

    fn to_pose(o: &urdf_rs::Pose) -> Pose {
        let [r, p, y] = o.rpy.0;
        let rot = Rotation::from_rotation_z(y as f32)
            * Rotation::from_rotation_y(p as f32)
            * Rotation::from_rotation_x(r as f32);
        Pose::from_parts(
            Vector::new(o.xyz[0] as f32, o.xyz[1] as f32, o.xyz[2] as f32),
            rot.normalize(),
        )
    }

    fn convert_geometry(
        ctx: &Ctx,
        link: &str,
        c: &urdf_rs::Collision,
    ) -> Result<CollisionShape, ModelError> {
        let bad = |m: String| ctx.invalid("link", link, format!("link '{link}': collision {m}"));
        if !finite3(&c.origin.xyz) || !finite3(&c.origin.rpy) {
            return Err(bad(format!(
                "origin has a non-finite number (xyz {:?}, rpy {:?})",
                c.origin.xyz.0, c.origin.rpy.0
            )));
        }
        let pos = |v: f64, what: &str| -> Result<f32, ModelError> {
            if v.is_finite() && v > 0.0 {
                Ok(v as f32)
            } else {
                Err(bad(format!(
                    "{what} must be a positive finite number, got {v}"
                )))
            }
        };
        let origin = to_pose(&c.origin);
        let (shape, local_pose, primitive, bounding_radius) = match &c.geometry {
            urdf_rs::Geometry::Box { size } => {
                let h = Vector::new(
                    pos(size[0], "box size x")?,
                    pos(size[1], "box size y")?,
                    pos(size[2], "box size z")?,
                ) * 0.5;
                (
                    SharedShape::cuboid(h.x, h.y, h.z),
                    origin,
                    Primitive::Box { half_extents: h },
                    h.length(),
                )
            }
            urdf_rs::Geometry::Sphere { radius } => {
                let r = pos(*radius, "sphere radius")?;
                (
                    SharedShape::ball(r),
                    origin,
                    Primitive::Sphere { radius: r },
                    r,
                )
            }
            urdf_rs::Geometry::Cylinder { radius, length } => {
                let r = pos(*radius, "cylinder radius")?;
                let l = pos(*length, "cylinder length")?;
                // parry's cylinder is along y; URDF's along z.
                let quarter = Rotation::from_rotation_x(std::f32::consts::FRAC_PI_2);
                (
                    SharedShape::cylinder(l / 2.0, r),
                    origin * Pose::from_rotation(quarter),
                    Primitive::Cylinder {
                        radius: r,
                        length: l,
                    },
                    (r * r + l * l / 4.0).sqrt(),
                )
            }
            urdf_rs::Geometry::Capsule { radius, length } => {
                let r = pos(*radius, "capsule radius")?;
                let l = pos(*length, "capsule length")?;
                (
                    SharedShape::capsule_z(l / 2.0, r),
                    origin,
                    Primitive::Capsule {
                        radius: r,
                        length: l,
                    },
                    r + l / 2.0,
                )
            }
            urdf_rs::Geometry::Mesh { filename, .. } => {
                return Err(bad(format!(
                    "uses mesh '{filename}': meshes are not supported in agent models; \
                     use box, sphere, cylinder or capsule"
                )));
            }
        };
        Ok(CollisionShape {
            local_pose,
            shape,
            primitive,
            bounding_radius,
        })
    }

    pub(super) fn load(text: &str, source_name: &str) -> Result<AgentModel, ModelError> {
        let ctx = Ctx { text, source_name };
        // urdf-rs should not panic, but a malformed document must never take the caller down.
        let parsed = std::panic::catch_unwind(|| urdf_rs::read_from_string(text));
        let robot = match parsed {
            Ok(Ok(r)) => r,
            Ok(Err(e)) => {
                let message = e.to_string();
                return Err(ModelError::Syntax {
                    source_name: source_name.to_string(),
                    line: locate_quoted(text, &message),
                    message,
                });
            }
            Err(_) => {
                return Err(ModelError::Syntax {
                    source_name: source_name.to_string(),
                    line: None,
                    message: "the URDF parser failed on this document".to_string(),
                });
            }
        };
        if robot.links.is_empty() {
            return Err(ModelError::Invalid {
                source_name: source_name.to_string(),
                line: None,
                message: format!("robot '{}' has no <link>", robot.name),
            });
        }

        // Names must be unique and non-empty.
        let mut urdf_link: HashMap<&str, usize> = HashMap::new();
        for (i, l) in robot.links.iter().enumerate() {
            if l.name.trim().is_empty() {
                return Err(ModelError::Invalid {
                    source_name: source_name.to_string(),
                    line: None,
                    message: "a <link> has an empty name".to_string(),
                });
            }
            if urdf_link.insert(l.name.as_str(), i).is_some() {
                return Err(ctx.invalid(
                    "link",
                    &l.name,
                    format!("link '{}' is defined twice", l.name),
                ));
            }
        }
        let mut urdf_joint: HashMap<&str, usize> = HashMap::new();
        for (i, j) in robot.joints.iter().enumerate() {
            if j.name.trim().is_empty() {
                return Err(ModelError::Invalid {
                    source_name: source_name.to_string(),
                    line: None,
                    message: "a <joint> has an empty name".to_string(),
                });
            }
            if urdf_joint.insert(j.name.as_str(), i).is_some() {
                return Err(ctx.invalid(
                    "joint",
                    &j.name,
                    format!("joint '{}' is defined twice", j.name),
                ));
            }
        }

        // Tree structure: each link has at most one parent joint; exactly one root.
        let mut parent_joint_of: Vec<Option<usize>> = vec![None; robot.links.len()];
        let mut children_of: Vec<Vec<usize>> = vec![Vec::new(); robot.links.len()];
        for (ji, j) in robot.joints.iter().enumerate() {
            let p = *urdf_link.get(j.parent.link.as_str()).ok_or_else(|| {
                ctx.invalid(
                    "joint",
                    &j.name,
                    format!(
                        "joint '{}': parent link '{}' is not defined",
                        j.name, j.parent.link
                    ),
                )
            })?;
            let c = *urdf_link.get(j.child.link.as_str()).ok_or_else(|| {
                ctx.invalid(
                    "joint",
                    &j.name,
                    format!(
                        "joint '{}': child link '{}' is not defined",
                        j.name, j.child.link
                    ),
                )
            })?;
            if p == c {
                return Err(ctx.invalid(
                    "joint",
                    &j.name,
                    format!(
                        "joint '{}' connects link '{}' to itself",
                        j.name, j.parent.link
                    ),
                ));
            }
            if let Some(other) = parent_joint_of[c] {
                return Err(ctx.invalid(
                    "joint",
                    &j.name,
                    format!(
                        "link '{}' has two parent joints ('{}' and '{}'); a URDF is a tree",
                        j.child.link, robot.joints[other].name, j.name
                    ),
                ));
            }
            parent_joint_of[c] = Some(ji);
            children_of[p].push(c);
        }
        let roots: Vec<usize> = (0..robot.links.len())
            .filter(|&i| parent_joint_of[i].is_none())
            .collect();
        if roots.is_empty() {
            return Err(ModelError::Invalid {
                source_name: source_name.to_string(),
                line: None,
                message: "every link has a parent joint: the joints form a cycle".to_string(),
            });
        }
        if roots.len() > 1 {
            let names: Vec<&str> = roots
                .iter()
                .map(|&i| robot.links[i].name.as_str())
                .collect();
            return Err(ctx.invalid(
                "link",
                names[1],
                format!(
                    "the links are not one tree: {} links have no parent joint ({})",
                    names.len(),
                    names.join(", ")
                ),
            ));
        }
        // Topological order (breadth first from the root); links not reached lie on a cycle.
        let mut order = vec![roots[0]];
        let mut k = 0;
        while k < order.len() {
            let l = order[k];
            order.extend(children_of[l].iter().copied());
            k += 1;
        }
        if order.len() != robot.links.len() {
            let reached: std::collections::HashSet<usize> = order.iter().copied().collect();
            let on_cycle = (0..robot.links.len())
                .find(|i| !reached.contains(i))
                .unwrap_or(0);
            let name = &robot.links[on_cycle].name;
            return Err(ctx.invalid(
                "link",
                name,
                format!(
                    "link '{name}' is not connected to the root '{}': its joints form a cycle",
                    robot.links[roots[0]].name
                ),
            ));
        }
        let mut new_index = vec![0usize; robot.links.len()];
        for (n, &old) in order.iter().enumerate() {
            new_index[old] = n;
        }

        // Links.
        let mut links = Vec::with_capacity(order.len());
        for &old in &order {
            let l = &robot.links[old];
            let collisions = l
                .collision
                .iter()
                .map(|c| convert_geometry(&ctx, &l.name, c))
                .collect::<Result<Vec<_>, _>>()?;
            let parent = parent_joint_of[old]
                .map(|j| new_index[urdf_link[robot.joints[j].parent.link.as_str()]]);
            links.push(Link {
                name: l.name.clone(),
                parent,
                parent_joint: parent_joint_of[old].map(|_| new_index[old] - 1),
                children: children_of[old].iter().map(|&c| new_index[c]).collect(),
                collisions,
            });
        }

        // Joints, in child-link order: joint n has child link n + 1.
        let mut joints = Vec::with_capacity(order.len() - 1);
        let mut joint_index = HashMap::new();
        for &old_link in &order[1..] {
            let ji = parent_joint_of[old_link].expect("non-root link has a parent joint");
            let j = &robot.joints[ji];
            let bad = |m: String| ctx.invalid("joint", &j.name, format!("joint '{}': {m}", j.name));
            let kind = match j.joint_type {
                urdf_rs::JointType::Fixed => JointKind::Fixed,
                urdf_rs::JointType::Revolute => JointKind::Revolute,
                urdf_rs::JointType::Continuous => JointKind::Continuous,
                urdf_rs::JointType::Prismatic => JointKind::Prismatic,
                ref other => {
                    return Err(bad(format!(
                        "type {other:?} is not supported (fixed, revolute, continuous or \
                         prismatic; the scene places the base)"
                    )
                    .to_lowercase()));
                }
            };
            if !finite3(&j.origin.xyz) || !finite3(&j.origin.rpy) {
                return Err(bad(format!(
                    "origin has a non-finite number (xyz {:?}, rpy {:?})",
                    j.origin.xyz.0, j.origin.rpy.0
                )));
            }
            let [ax, ay, az] = j.axis.xyz.0;
            let norm = (ax * ax + ay * ay + az * az).sqrt();
            let mut axis = Vector::X;
            if kind != JointKind::Fixed {
                if !norm.is_finite() || norm < 1e-9 {
                    return Err(bad(format!(
                        "axis {:?} is not a finite non-zero vector",
                        j.axis.xyz.0
                    )));
                }
                axis = Vector::new((ax / norm) as f32, (ay / norm) as f32, (az / norm) as f32);
            }
            let limits = match kind {
                JointKind::Fixed | JointKind::Continuous => JointLimits::UNLIMITED,
                JointKind::Revolute | JointKind::Prismatic => {
                    let (lo, hi) = (j.limit.lower, j.limit.upper);
                    if !lo.is_finite() || !hi.is_finite() {
                        return Err(bad(format!(
                            "limits [{lo}, {hi}] must be finite (use a continuous joint for an \
                             unlimited rotation)"
                        )));
                    }
                    if lo >= hi {
                        return Err(bad(format!(
                            "lower limit {lo} must be below upper limit {hi} (a missing <limit> \
                             reads as [0, 0])"
                        )));
                    }
                    JointLimits {
                        lower: lo as f32,
                        upper: hi as f32,
                    }
                }
            };
            let n = joints.len();
            joint_index.insert(j.name.clone(), n);
            joints.push(Joint {
                name: j.name.clone(),
                kind,
                parent: new_index[urdf_link[j.parent.link.as_str()]],
                child: new_index[old_link],
                origin: to_pose(&j.origin),
                axis,
                limits,
                dof: None,
                mimic: None,
            });
        }

        // Mimic joints, then degrees of freedom.
        for &old_link in &order[1..] {
            let j = &robot.joints[parent_joint_of[old_link].expect("has parent joint")];
            let Some(m) = &j.mimic else { continue };
            let bad =
                |msg: String| ctx.invalid("joint", &j.name, format!("joint '{}': {msg}", j.name));
            let me = joint_index[&j.name];
            if joints[me].kind == JointKind::Fixed {
                return Err(bad("a fixed joint cannot mimic another joint".into()));
            }
            let master = *joint_index
                .get(&m.joint)
                .ok_or_else(|| bad(format!("mimics joint '{}', which is not defined", m.joint)))?;
            let mult = m.multiplier.unwrap_or(1.0);
            let off = m.offset.unwrap_or(0.0);
            if !mult.is_finite() || !off.is_finite() {
                return Err(bad("mimic multiplier and offset must be finite".into()));
            }
            let master_joint = &robot.joints[urdf_joint[m.joint.as_str()]];
            if master_joint.mimic.is_some() || master_joint.joint_type == urdf_rs::JointType::Fixed
            {
                return Err(bad(format!(
                    "mimics joint '{}', which is fixed or itself a mimic joint",
                    m.joint
                )));
            }
            joints[me].mimic = Some(Mimic {
                master,
                multiplier: mult as f32,
                offset: off as f32,
            });
        }
        let mut names = Vec::new();
        let mut limits = Vec::new();
        let mut index = HashMap::new();
        let mut dof_joints = Vec::new();
        let mut dof_velocity_limits = Vec::new();
        let mut dof_acceleration_limits = Vec::new();
        let positive = |v: f64| (v.is_finite() && v > 0.0).then_some(v as f32);
        for (n, joint) in joints.iter_mut().enumerate() {
            if joint.kind != JointKind::Fixed && joint.mimic.is_none() {
                let limit = urdf_joint
                    .get(joint.name.as_str())
                    .map(|&i| &robot.joints[i].limit);
                dof_velocity_limits.push(limit.and_then(|l| positive(l.velocity)));
                dof_acceleration_limits.push(limit.and_then(|l| positive(l.acceleration)));
                joint.dof = Some(names.len());
                index.insert(joint.name.clone(), names.len());
                names.push(joint.name.clone());
                limits.push(joint.limits);
                dof_joints.push(n);
            }
        }
        let link_index = links
            .iter()
            .enumerate()
            .map(|(i, l)| (l.name.clone(), i))
            .collect();
        Ok(AgentModel {
            name: robot.name.clone(),
            source_name: source_name.to_string(),
            links,
            joints,
            link_index,
            joint_index,
            dofs: Arc::new(DofTable {
                model: robot.name,
                names,
                limits,
                index,
            }),
            dof_joints,
            dof_velocity_limits,
            dof_acceleration_limits,
        })
    }
}
