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
//!   `<mesh filename=".." scale="..">` (STL, COLLADA, OBJ; `package://`, `file://` or relative
//!   names, [`packages`]) collides as convex pieces, its hull or a decomposition ([`convex`]);
//!   a link may have several collision elements. Visual mesh elements are kept as
//!   [`VisualMesh`]es (the file, origin, scale and material colour; the file is not read:
//!   planning never needs it, pictures and the viewer read it), a missing file is a warning;
//!   visual primitives, transmissions, Gazebo, ros2_control and textures are ignored.
//! * Revolute and prismatic joints must have `<limit lower=".." upper="..">` with
//!   `lower < upper`; continuous joints have no limits.
//! * Every number must be finite.

use std::collections::HashMap;
use std::fmt;
use std::path::Path;
use std::sync::Arc;

use parry3d::math::{Pose, Rotation, Vector};
use parry3d::shape::SharedShape;

pub mod convex;
mod convex_cache;
pub mod frames;
mod loader;
pub mod packages;
pub mod srdf;
mod xml;

pub use convex::ConvexMode;
pub use frames::ExtraFrame;
pub use packages::PackagePath;
pub use srdf::Semantics;

/// How the mesh elements of a URDF are read: where its file names lead, and how each link's
/// collision meshes become convex (by [`convex`]'s rule unless a link is named here).
#[derive(Clone, Debug, Default)]
pub struct MeshOptions {
    /// The URDF's folder and the package path.
    pub packages: PackagePath,
    /// Links whose collision meshes are made by a mode other than [`ConvexMode::Auto`].
    pub modes: HashMap<String, ConvexMode>,
}

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
    /// The SRDF (semantic description) is malformed or names what the URDF does not have.
    #[error("{source_name}:{line}:{col}: {message}")]
    Srdf {
        /// The SRDF file.
        source_name: String,
        /// 1-based line.
        line: usize,
        /// 1-based column.
        col: usize,
        /// What is wrong.
        message: String,
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
    /// One convex piece of a collision mesh (its hull, or a part of its decomposition).
    Convex {
        /// Vertices of this piece.
        vertices: usize,
        /// Pieces the mesh was made into.
        pieces: usize,
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
    /// Visual meshes whose files exist (pictures and the viewer draw the link by them when
    /// there are any, by its collision shapes otherwise).
    pub visuals: Vec<VisualMesh>,
}

/// A URDF `<visual>` element with a `<mesh>`: where its file is and how it is placed. The file
/// is read only when a picture is drawn ([`crate::render::render_visual`]) or a viewer loads it.
#[derive(Debug, Clone, PartialEq)]
pub struct VisualMesh {
    /// The file name as the URDF writes it (`package://..`, `file://..` or relative).
    pub uri: String,
    /// The file it resolves to (absolute when it could be made so; it existed at load time).
    pub path: std::path::PathBuf,
    /// Pose of the mesh in the link frame (the visual's `<origin>`).
    pub local_pose: Pose,
    /// The mesh's `scale` (1, 1, 1 when absent).
    pub scale: Vector,
    /// RGBA of the visual's material (given inline, or by name from the robot's top-level
    /// `<material>`s), when it has a colour.
    pub colour: Option<[f32; 4]>,
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

fn read_text(path: &Path) -> Result<String, ModelError> {
    std::fs::read_to_string(path).map_err(|source| ModelError::Io {
        path: path.display().to_string(),
        source,
    })
}

/// An agent's kinematic tree with collision shapes. Cheap to share behind an `Arc`.
#[derive(Debug, Clone)]
pub struct AgentModel {
    name: String,
    source_name: String,
    /// The URDF text the model was read from (exported with plans so that a checker can compute
    /// the forward kinematics on its own).
    urdf: Arc<str>,
    /// What the SRDF says the links and joints are for (empty without one).
    semantics: Arc<Semantics>,
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
    /// What loading found wrong but could read past (a visual mesh that names no file).
    warnings: Vec<String>,
}

impl AgentModel {
    /// Loads a URDF file, and beside it the SRDF of the same name (`pr2.urdf`, `pr2.srdf`) when
    /// there is one. Errors name the file and what is wrong; never panics.
    pub fn from_urdf_file(path: impl AsRef<Path>) -> Result<AgentModel, ModelError> {
        let path = path.as_ref();
        let text = read_text(path)?;
        let model = Self::from_urdf_str(&text, &path.display().to_string())?;
        let srdf = path.with_extension("srdf");
        if srdf.is_file() {
            return model.with_srdf_file(&srdf);
        }
        Ok(model)
    }

    /// This model with the semantic description in the SRDF file `path`.
    pub fn with_srdf_file(self, path: impl AsRef<Path>) -> Result<AgentModel, ModelError> {
        let path = path.as_ref();
        let text = read_text(path)?;
        self.with_srdf_str(&text, &path.display().to_string())
    }

    /// This model with the semantic description in SRDF `text` (`source_name` for errors).
    pub fn with_srdf_str(
        mut self,
        text: &str,
        source_name: &str,
    ) -> Result<AgentModel, ModelError> {
        self.semantics = Arc::new(srdf::read(text, source_name, &self)?);
        Ok(self)
    }

    /// This model with `groups` added to its SRDF's (what a MoveIt SRDF lacks, written in a
    /// scene): each chain must run down the model from its base link to its tip, each joint
    /// must be the model's (joints that form a chain are that chain, as in an SRDF), and no
    /// group may have the name of one of the SRDF's.
    pub fn with_groups(mut self, groups: &[srdf::Group]) -> Result<AgentModel, ModelError> {
        if groups.is_empty() {
            return Ok(self);
        }
        let mut semantics = (*self.semantics).clone();
        for g in groups {
            let err = |message: String| ModelError::Invalid {
                source_name: self.name.clone(),
                line: None,
                message: format!("group `{}`: {message}", g.name),
            };
            if semantics.group(&g.name).is_some() {
                return Err(err(format!(
                    "the SRDF {} already has a group of that name",
                    semantics.source_name
                )));
            }
            if let Some((base, tip)) = &g.chain {
                self.chain_between(base, tip)?;
            }
            if let Some(j) = g.joints.iter().find(|j| !self.joint_index.contains_key(*j)) {
                return Err(err(format!("no joint `{j}` in the URDF")));
            }
            // As the SRDF's groups are read: joints that form a chain are that chain.
            let mut g = g.clone();
            if g.chain.is_none() {
                g.chain = srdf::joints_chain(&self, &g.joints);
            }
            semantics.groups.push(g);
        }
        self.semantics = Arc::new(semantics);
        Ok(self)
    }

    /// What the SRDF says (empty when the model has none).
    pub fn semantics(&self) -> &Semantics {
        &self.semantics
    }

    /// The arms the SRDF declares (groups ending in an end effector), in its order.
    pub fn arm_names(&self) -> Vec<String> {
        self.semantics
            .arms()
            .into_iter()
            .map(str::to_string)
            .collect()
    }

    /// The configuration index of the one joint of SRDF group `group` (`torso_lift`, ...).
    pub fn group_dof(&self, group: &str) -> Option<usize> {
        let g = self.semantics.group(group)?;
        g.joints.iter().find_map(|j| self.dof_index(j).ok())
    }

    /// The values of the SRDF's posture `name`, by configuration index.
    pub fn posture(&self, name: &str) -> Vec<(usize, f32)> {
        self.semantics
            .group_state(name)
            .map(|s| {
                s.values
                    .iter()
                    .filter_map(|(j, v)| self.dof_index(j).ok().map(|d| (d, *v)))
                    .collect()
            })
            .unwrap_or_default()
    }

    /// Loads URDF text; `source_name` (a file name, usually) is used in error messages.
    /// Mesh file names are resolved against `source_name`'s folder and the package path of
    /// the command line and `ROS_PACKAGE_PATH` ([`packages`]).
    pub fn from_urdf_str(text: &str, source_name: &str) -> Result<AgentModel, ModelError> {
        let options = MeshOptions {
            packages: PackagePath {
                urdf_dir: Path::new(source_name)
                    .parent()
                    .map(Path::to_path_buf)
                    .unwrap_or_default(),
                scene_dirs: Vec::new(),
            },
            modes: HashMap::new(),
        };
        Self::from_urdf_str_with(text, source_name, &options)
    }

    /// Loads URDF text with its meshes read as `meshes` says.
    pub fn from_urdf_str_with(
        text: &str,
        source_name: &str,
        meshes: &MeshOptions,
    ) -> Result<AgentModel, ModelError> {
        crate::agent::loader::load(text, source_name, meshes)
    }

    /// What loading read past with a warning (a visual mesh that names no file).
    pub fn load_warnings(&self) -> &[String] {
        &self.warnings
    }

    /// The robot name from the URDF.
    pub fn name(&self) -> &str {
        &self.name
    }

    /// The file (or other name) the model was loaded from.
    pub fn source_name(&self) -> &str {
        &self.source_name
    }

    /// The URDF text the model was read from.
    pub fn urdf(&self) -> &str {
        &self.urdf
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

    /// Link `link` and the links fixed to it: those joined to it by fixed joints alone (a
    /// camera's frame, the housing it sits in, the frames on that), in link order.
    pub fn rigid_links(&self, link: usize) -> Vec<usize> {
        let fixed = |l: usize| {
            self.links[l]
                .parent_joint
                .is_some_and(|j| !self.joints[j].is_movable())
        };
        let mut root = link;
        while let (true, Some(p)) = (fixed(root), self.links[root].parent) {
            root = p;
        }
        let mut out = vec![root];
        let mut k = 0;
        while let Some(&l) = out.get(k) {
            k += 1;
            out.extend(self.links[l].children.iter().filter(|&&c| fixed(c)));
        }
        out.sort_unstable();
        out
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

    /// The links an object held at `tool` may touch: the nearest link with geometry at or above
    /// `tool` (the palm of a gripper, a person's hand) and all its descendants (the fingers), in
    /// link order. The collision checker leaves exactly these out for a held object.
    pub fn hand_links(&self, tool: usize) -> Vec<usize> {
        let hand = self.geometric_ancestor(tool).unwrap_or(tool);
        (0..self.links.len())
            .filter(|&l| self.is_descendant(l, hand))
            .collect()
    }

    /// The serial chain of the SRDF group called `name` (an arm such as `right_arm`, or
    /// `head`), from its `base_link` to its `tip_link`.
    pub fn chain(&self, name: &str) -> Result<KinematicChain, ModelError> {
        let err = |message: String| ModelError::Chain {
            model: self.name.clone(),
            chain: name.to_string(),
            message,
        };
        let (root, tip) = self
            .semantics
            .group(name)
            .and_then(|g| g.chain.as_ref())
            .ok_or_else(|| {
                let known: Vec<&str> = self
                    .semantics
                    .groups
                    .iter()
                    .filter(|g| g.chain.is_some())
                    .map(|g| g.name.as_str())
                    .collect();
                err(format!(
                    "no SRDF group of that name with a <chain> (chains: {})",
                    if known.is_empty() {
                        "none; the model has no SRDF".to_string()
                    } else {
                        known.join(", ")
                    }
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
