//! The scene file: furniture, objects and agents placed in a room (TOML; reference in
//! `docs/scene-format.md`).
//!
//! [`Scene::load`] reads and checks a scene file and returns a [`Scene`]: the immutable part of a
//! world (names, shapes, colours, support surfaces, agent models), shared behind an `Arc` by every
//! [`crate::world::World`] made from it. Every error is a [`SceneError`] naming the file, the
//! line and column when the TOML parser knows them, the key path (`objects[2].shape.box`), and
//! the reason. Loading never panics.

use std::collections::{BTreeMap, HashMap};
use std::fmt;
use std::path::{Path, PathBuf};

use parry3d::bounding_volume::Aabb;
use parry3d::math::{Pose, Rotation, Vector};
use parry3d::shape::{SharedShape, TriMesh};
use serde::Deserialize;

use crate::mesh_file;

mod reading;
pub use reading::read_capped;
use reading::toml_error;

/// The world's extent: every coordinate and size in a scene file lies within this many metres
/// of the origin. Rooms are metres across; a value beyond this is a typing error (`1e30`), and
/// accepting it would make every grid over the scene (the GTP's candidate points, the
/// mightability maps) astronomically large.
pub const WORLD_EXTENT_M: f32 = 1000.0;

/// The largest scene file read (4 MiB: a scene of [`MAX_OBJECTS`] objects takes about 2 MiB; the
/// library scenes are a few KiB). Reading stops there, so a device (`/dev/zero`) or a runaway
/// file cannot fill memory: parsing TOML takes about 64 times the file's size in memory
/// ([`SCENE_MEMORY_PER_BYTE`]), so 4 MiB stays near 300 MB.
pub const MAX_SCENE_BYTES: u64 = 4 << 20;

/// About how many bytes of memory reading a scene takes per byte of its file (60-65 for scenes
/// of tens of thousands of small objects, rounded up).
pub const SCENE_MEMORY_PER_BYTE: u64 = 64;

/// The most objects a scene may have: every load checks them against each other for initial
/// collisions, and the shared literals are computed per agent and object.
pub const MAX_OBJECTS: usize = 10_000;

/// An error in a scene file: `FILE[:LINE:COL]: key.path: reason`.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct SceneError {
    /// The scene file (or the name given for the text).
    pub file: String,
    /// 1-based line and column, when known.
    pub line_col: Option<(usize, usize)>,
    /// Where in the document, e.g. `objects[2].shape.box` (empty for the whole file).
    pub key_path: String,
    /// What is wrong.
    pub reason: String,
}

impl fmt::Display for SceneError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{}", self.file)?;
        if let Some((l, c)) = self.line_col {
            write!(f, ":{l}:{c}")?;
        }
        if !self.key_path.is_empty() {
            write!(f, ": {}", self.key_path)?;
        }
        write!(f, ": {}", self.reason)
    }
}

impl std::error::Error for SceneError {}

// ---------------------------------------------------------------------------------------------
// File format (serde). Field docs are the reference; docs/scene-format.md repeats them.

#[derive(Deserialize, Debug, Default)]
#[serde(deny_unknown_fields)]
struct SceneFile {
    #[serde(default)]
    scene: SceneHeader,
    #[serde(default)]
    objects: Vec<ObjectSpec>,
    #[serde(default)]
    agents: Vec<AgentSpec>,
}

#[derive(Deserialize, Debug, Default)]
#[serde(deny_unknown_fields)]
struct SceneHeader {
    name: Option<String>,
    description: Option<String>,
    /// Region covered by the mightability maps; default: the objects' bounds plus a margin.
    bounds: Option<BoundsSpec>,
    /// Folders searched for the ROS packages that `package://` mesh names in the agents' URDFs
    /// name (relative to the scene file), after the command line's `--package-path` folders and
    /// before `ROS_PACKAGE_PATH`.
    #[serde(default)]
    package_path: Vec<String>,
}

#[derive(Deserialize, Debug)]
#[serde(deny_unknown_fields)]
struct BoundsSpec {
    min: [f32; 3],
    max: [f32; 3],
}

/// A pose: `xyz` in metres and either `rpy` (roll, pitch, yaw in degrees, fixed axes X then Y
/// then Z as in URDF) or `yaw` (degrees about z). Both absent: no rotation.
#[derive(Deserialize, Debug, Default, Clone)]
#[serde(deny_unknown_fields)]
struct PoseSpec {
    #[serde(default)]
    xyz: [f32; 3],
    rpy: Option<[f32; 3]>,
    yaw: Option<f32>,
}

#[derive(Deserialize, Debug, Clone)]
#[serde(rename_all = "lowercase", deny_unknown_fields)]
enum ShapeSpec {
    /// Half extents along the object's x, y, z.
    Box([f32; 3]),
    /// Axis along the object's z.
    Cylinder { radius: f32, half_height: f32 },
    /// A triangle mesh file (.obj or .stl), relative to the scene file.
    Mesh {
        file: String,
        #[serde(default)]
        scale: Option<f32>,
    },
}

#[derive(Deserialize, Debug, Clone)]
#[serde(deny_unknown_fields)]
struct PartSpec {
    shape: ShapeSpec,
    #[serde(default)]
    pose: PoseSpec,
}

#[derive(Deserialize, Debug, Clone)]
#[serde(deny_unknown_fields)]
struct SurfaceSpec {
    /// Centre of the rectangle in the object's frame.
    centre: [f32; 3],
    /// Half sizes along the object's x and y.
    half_extents: [f32; 2],
}

#[derive(Deserialize, Debug)]
#[serde(deny_unknown_fields)]
struct ObjectSpec {
    name: String,
    shape: Option<ShapeSpec>,
    parts: Option<Vec<PartSpec>>,
    #[serde(default)]
    pose: PoseSpec,
    colour: Option<[u8; 3]>,
    #[serde(default)]
    movable: bool,
    #[serde(default)]
    support: bool,
    surfaces: Option<Vec<SurfaceSpec>>,
    /// Other objects it can contain (hollow furniture: a drawer, a box). Informative only.
    #[serde(default)]
    container: bool,
}

#[derive(Deserialize, Debug, Clone, Copy, PartialEq, Eq)]
#[serde(rename_all = "lowercase")]
enum KindSpec {
    Robot,
    Human,
}

#[derive(Deserialize, Debug, Default, Clone, Copy)]
#[serde(deny_unknown_fields)]
struct BaseSpec {
    #[serde(default)]
    x: f32,
    #[serde(default)]
    y: f32,
    /// Height of the URDF's root above the floor (a robot fixed to a table), metres.
    #[serde(default)]
    z: f32,
    /// Degrees.
    #[serde(default)]
    yaw: f32,
}

/// A fixed frame added to the agent's URDF: a tool centre point, a camera.
#[derive(Deserialize, Debug, Clone)]
#[serde(deny_unknown_fields)]
struct FrameSpec {
    name: String,
    parent: String,
    #[serde(default)]
    xyz: [f32; 3],
    /// Roll, pitch, yaw in degrees.
    #[serde(default)]
    rpy: [f32; 3],
}

/// A scene's `posture`: one `group_state` name, or a list of them.
#[derive(Debug)]
enum Postures {
    One(String),
    Many(Vec<String>),
}

impl<'de> Deserialize<'de> for Postures {
    fn deserialize<D: serde::Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        struct Names;
        impl<'de> serde::de::Visitor<'de> for Names {
            type Value = Postures;
            fn expecting(&self, f: &mut fmt::Formatter) -> fmt::Result {
                f.write_str("a posture name (a `group_state` of the SRDF) or a list of names")
            }
            fn visit_str<E: serde::de::Error>(self, v: &str) -> Result<Postures, E> {
                Ok(Postures::One(v.to_string()))
            }
            fn visit_seq<A: serde::de::SeqAccess<'de>>(
                self,
                mut seq: A,
            ) -> Result<Postures, A::Error> {
                let mut names = Vec::new();
                while let Some(name) = seq.next_element::<String>()? {
                    names.push(name);
                }
                Ok(Postures::Many(names))
            }
        }
        d.deserialize_any(Names)
    }
}

#[derive(Deserialize, Debug)]
#[serde(deny_unknown_fields)]
struct AgentSpec {
    name: String,
    kind: KindSpec,
    urdf: String,
    /// The semantic description (SRDF); default: the URDF's path with the extension `.srdf`.
    srdf: Option<String>,
    #[serde(default)]
    base: BaseSpec,
    /// Named postures of the SRDF (`group_state`s, one or a list: MoveIt names one per
    /// group), applied in order before `joints`.
    posture: Option<Postures>,
    /// Joint values by URDF joint name (radians, metres for prismatic joints).
    #[serde(default)]
    joints: BTreeMap<String, f32>,
    eye: Option<String>,
    shoulders: Option<Vec<String>>,
    hands: Option<Vec<String>>,
    /// Horizontal and vertical field of view in degrees.
    fov_deg: Option<[f32; 2]>,
    /// Arm reach from the shoulder, metres.
    reach: Option<f32>,
    /// Humans: sitting (standing up is then effort level 3).
    #[serde(default)]
    sitting: bool,
    colour: Option<[u8; 3]>,
    effort: Option<EffortSpec>,
    /// Links whose collision meshes collide as their convex hull, whatever the rule says.
    #[serde(default)]
    hull_links: Vec<String>,
    /// Links whose collision meshes are decomposed into convex pieces, whatever the rule says.
    #[serde(default)]
    decompose_links: Vec<String>,
    /// Fixed frames added to the URDF (what the description lacks: a tool frame, a camera).
    #[serde(default)]
    frames: Vec<FrameSpec>,
    /// SRDF groups the SRDF lacks (MoveIt's has no head or torso group), by name.
    #[serde(default)]
    groups: BTreeMap<String, GroupSpec>,
}

/// An SRDF group written in the scene, as MoveIt writes one: a chain, or joints.
#[derive(Deserialize, Debug, Clone)]
#[serde(deny_unknown_fields)]
struct GroupSpec {
    base_link: Option<String>,
    tip_link: Option<String>,
    #[serde(default)]
    joints: Vec<String>,
}

/// Optional overrides of an agent's effort parameters (see [`crate::effort::EffortParams`]).
#[derive(Deserialize, Debug, Default, Clone)]
#[serde(deny_unknown_fields)]
pub(crate) struct EffortSpec {
    /// Head turn allowed at level 1, +- degrees (within the URDF limits).
    pub head_pan_deg: Option<f32>,
    /// Torso turn at level 2, +- degrees (humans; within the URDF limits).
    pub torso_turn_deg: Option<f32>,
    /// Forward lean at level 2, degrees (humans; default 60).
    pub lean_deg: Option<f32>,
    /// Base turn in place at level 2, +- degrees (default: robots 180, humans 0).
    pub base_turn_deg: Option<f32>,
    /// Level 4: how far the agent may walk / drive, metres (default 3).
    pub move_radius: Option<f32>,
}

// ---------------------------------------------------------------------------------------------
// The loaded scene.

/// Index of an object in its scene (stable for the life of the scene and every world made from it).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub struct ObjectId(pub usize);

/// Index of an agent in its scene.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub struct AgentId(pub usize);

/// Which shape an object was described with (for display and for deriving support faces).
#[derive(Clone, Debug, PartialEq)]
pub enum ShapeKind {
    /// A box with these half extents.
    Box { half_extents: Vector },
    /// A cylinder along the object's z.
    Cylinder { radius: f32, half_height: f32 },
    /// A triangle mesh read from this file.
    Mesh { file: PathBuf, triangles: usize },
    /// Several parts fused into one rigid object.
    Compound { parts: usize },
}

/// A horizontal rectangle on which things can be placed, in the object's frame (the object is
/// assumed to stand upright: its z axis up).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SupportSurface {
    /// Centre of the rectangle, object frame.
    pub centre: Vector,
    /// Half sizes along the object's x and y.
    pub half_extents: [f32; 2],
}

/// The immutable description of one object: what it looks like and how it can be used.
#[derive(Clone, Debug)]
pub struct ObjectModel {
    /// Unique name (`grey-book`).
    pub name: String,
    /// The collision/render shape, in the frame `pose * shape_offset`.
    pub shape: SharedShape,
    /// Pose of the shape in the object's frame (parry's cylinders stand along y; ours along z).
    pub shape_offset: Pose,
    /// How the shape was described.
    pub kind: ShapeKind,
    /// Display colour (sRGB).
    pub colour: [u8; 3],
    /// Whether agents may pick it up and move it.
    pub movable: bool,
    /// Horizontal faces offered for placing other objects (empty: not a support).
    pub surfaces: Vec<SupportSurface>,
    /// Declared as a container (informative).
    pub container: bool,
    /// Bounding box of the shape in the object's frame.
    pub local_aabb: Aabb,
}

/// Robot or human.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum AgentKind {
    Robot,
    Human,
}

impl fmt::Display for AgentKind {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(match self {
            AgentKind::Robot => "robot",
            AgentKind::Human => "human",
        })
    }
}

/// An agent as described by the scene (its kinematic model is loaded from `urdf`).
#[derive(Clone, Debug)]
pub struct AgentSpecResolved {
    pub name: String,
    pub kind: AgentKind,
    /// Absolute (or scene-relative resolved) path of the URDF file.
    pub urdf: PathBuf,
    /// The SRDF file, when there is one (given, or beside the URDF with the same name).
    pub srdf: Option<PathBuf>,
    /// Base pose on the floor: x, y (metres), yaw (radians).
    pub base: [f32; 3],
    /// Height of the URDF's root above the base pose (a robot fixed to a table), metres.
    pub mount_height: f32,
    /// Fixed frames added to the URDF (see [`crate::agent::frames`]).
    pub frames: Vec<crate::agent::ExtraFrame>,
    /// The SRDF postures (`group_state` names) the agent starts in, in order, before `joints`.
    pub postures: Vec<String>,
    /// Joint values by name, as written.
    pub joints: Vec<(String, f32)>,
    /// Link whose frame is the eye / camera (x forward, z up).
    pub eye: Option<String>,
    pub shoulders: Option<Vec<String>>,
    pub hands: Option<Vec<String>>,
    /// Horizontal and vertical field of view, radians.
    pub fov: Option<[f32; 2]>,
    pub reach: Option<f32>,
    pub sitting: bool,
    pub colour: [u8; 3],
    pub(crate) effort: EffortSpec,
    /// SRDF groups added to the SRDF's (see `groups` in docs/scene-format.md).
    pub groups: Vec<crate::agent::srdf::Group>,
    /// Links whose collision meshes are made by a mode other than the rule's.
    pub convex_modes: Vec<(String, crate::agent::ConvexMode)>,
}

/// The immutable part of a world, loaded from a scene file.
#[derive(Clone, Debug)]
pub struct Scene {
    /// Scene name (`[scene] name`, else the file stem).
    pub name: String,
    pub description: String,
    /// The file it was loaded from (or the name given to [`Scene::from_str`]).
    pub source: String,
    /// Directory that relative paths in the file are resolved against.
    pub base_dir: PathBuf,
    pub objects: Vec<ObjectModel>,
    /// Initial object poses (the world's starting state).
    pub initial_poses: Vec<Pose>,
    pub agents: Vec<AgentSpecResolved>,
    /// Region for grids (mightability maps); explicit or derived.
    pub bounds: Option<Aabb>,
    /// The scene's `package_path` folders, resolved against its folder.
    pub package_path: Vec<PathBuf>,
    object_index: HashMap<String, usize>,
}

/// A distinct colour for the `i`-th object without one (golden-angle hue steps).
pub fn palette(i: usize) -> [u8; 3] {
    let h = (i as f32 * 137.508).rem_euclid(360.0) / 60.0;
    let (s, v) = (0.55, 0.85);
    let c = v * s;
    let x = c * (1.0 - ((h % 2.0) - 1.0).abs());
    let (r, g, b) = match h as u32 {
        0 => (c, x, 0.0),
        1 => (x, c, 0.0),
        2 => (0.0, c, x),
        3 => (0.0, x, c),
        4 => (x, 0.0, c),
        _ => (c, 0.0, x),
    };
    let m = v - c;
    let q = |u: f32| ((u + m) * 255.0).round() as u8;
    [q(r), q(g), q(b)]
}

/// Pose from translation and roll/pitch/yaw in radians (URDF convention: R = Rz(y) Ry(p) Rx(r)).
pub fn pose_from_xyz_rpy(xyz: [f32; 3], rpy: [f32; 3]) -> Pose {
    let rot = Rotation::from_rotation_z(rpy[2])
        * Rotation::from_rotation_y(rpy[1])
        * Rotation::from_rotation_x(rpy[0]);
    Pose::from_parts(Vector::from(xyz), rot)
}

impl Scene {
    /// Reads and checks a scene file. Relative paths (meshes, URDF) are resolved against the
    /// file's directory.
    pub fn load(path: impl AsRef<Path>) -> Result<Scene, SceneError> {
        let path = path.as_ref();
        let source = path.display().to_string();
        let text = read_capped(path, MAX_SCENE_BYTES).map_err(|reason| SceneError {
            file: source.clone(),
            line_col: None,
            key_path: String::new(),
            reason,
        })?;
        let base_dir = path.parent().map(Path::to_path_buf).unwrap_or_default();
        let stem = path
            .file_stem()
            .map(|s| s.to_string_lossy().into_owned())
            .unwrap_or_default();
        Scene::from_str(&text, &source, &base_dir, &stem)
    }

    /// Parses scene text; `source` names it in errors, `base_dir` resolves relative paths.
    pub fn from_str(
        text: &str,
        source: &str,
        base_dir: &Path,
        default_name: &str,
    ) -> Result<Scene, SceneError> {
        let file: SceneFile = toml::from_str(text).map_err(|e| toml_error(text, source, &e))?;
        let ck = Checker {
            file: source.to_string(),
        };
        if file.objects.len() > MAX_OBJECTS {
            return Err(ck.err(
                "objects",
                format!(
                    "{} objects, more than the {MAX_OBJECTS} a scene may have",
                    file.objects.len()
                ),
            ));
        }
        let mut objects = Vec::with_capacity(file.objects.len());
        let mut initial_poses = Vec::with_capacity(file.objects.len());
        let mut object_index = HashMap::new();
        for (i, spec) in file.objects.iter().enumerate() {
            let at = format!("objects[{i}]");
            ck.name(&spec.name, &format!("{at}.name"))?;
            if object_index.insert(spec.name.clone(), i).is_some() {
                return Err(ck.err(
                    &format!("{at}.name"),
                    format!("duplicate object name `{}`", spec.name),
                ));
            }
            let (object, pose) = object_model(&ck, spec, i, base_dir)?;
            objects.push(object);
            initial_poses.push(pose);
        }
        let mut agents = Vec::with_capacity(file.agents.len());
        let mut agent_names: HashMap<&str, usize> = HashMap::new();
        for (i, a) in file.agents.iter().enumerate() {
            let at = format!("agents[{i}]");
            ck.name(&a.name, &format!("{at}.name"))?;
            if agent_names.insert(&a.name, i).is_some() || object_index.contains_key(&a.name) {
                return Err(ck.err(
                    &format!("{at}.name"),
                    format!(
                        "duplicate name `{}` (agent and object names share one namespace)",
                        a.name
                    ),
                ));
            }
            agents.push(agent_spec(&ck, a, &at, base_dir)?);
        }
        let bounds = scene_bounds(&ck, file.scene.bounds.as_ref())?;

        Ok(Scene {
            name: file
                .scene
                .name
                .clone()
                .unwrap_or_else(|| default_name.to_string()),
            description: file.scene.description.clone().unwrap_or_default(),
            source: source.to_string(),
            base_dir: base_dir.to_path_buf(),
            objects,
            initial_poses,
            agents,
            bounds,
            package_path: file
                .scene
                .package_path
                .iter()
                .map(|d| base_dir.join(d))
                .collect(),
            object_index,
        })
    }

    /// The object with this name.
    pub fn object_id(&self, name: &str) -> Option<ObjectId> {
        self.object_index.get(name).copied().map(ObjectId)
    }

    /// The agent with this name.
    pub fn agent_id(&self, name: &str) -> Option<AgentId> {
        self.agents.iter().position(|a| a.name == name).map(AgentId)
    }

    /// An error about this scene's file at `key_path` (used when later stages, such as loading
    /// agent models, find a problem with what the file says).
    pub fn error(&self, key_path: &str, reason: impl Into<String>) -> SceneError {
        SceneError {
            file: self.source.clone(),
            line_col: None,
            key_path: key_path.to_string(),
            reason: reason.into(),
        }
    }
}

/// Top face of a shape's local bounds; for a cylinder the inscribed square of its top disc.
fn derive_top_face(kind: &ShapeKind, aabb: &Aabb) -> SupportSurface {
    let c = aabb.center();
    let he = aabb.half_extents();
    let half = match kind {
        ShapeKind::Cylinder { radius, .. } => {
            let s = radius * std::f32::consts::FRAC_1_SQRT_2;
            [s, s]
        }
        _ => [he.x, he.y],
    };
    SupportSurface {
        centre: Vector::new(c.x, c.y, aabb.maxs.z),
        half_extents: half,
    }
}

/// One object of the scene file, checked, and its initial pose.
fn object_model(
    ck: &Checker,
    spec: &ObjectSpec,
    i: usize,
    base_dir: &Path,
) -> Result<(ObjectModel, Pose), SceneError> {
    let at = format!("objects[{i}]");
    let pose = ck.pose(&spec.pose, &format!("{at}.pose"))?;
    let (shape, shape_offset, kind) = match (&spec.shape, &spec.parts) {
        (Some(s), None) => ck.shape(s, &format!("{at}.shape"), base_dir)?,
        (None, Some(parts)) if !parts.is_empty() => {
            let mut list = Vec::with_capacity(parts.len());
            for (k, p) in parts.iter().enumerate() {
                let pat = format!("{at}.parts[{k}]");
                let (s, off, _) = ck.shape(&p.shape, &format!("{pat}.shape"), base_dir)?;
                let ppose = ck.pose(&p.pose, &format!("{pat}.pose"))?;
                list.push((ppose * off, s));
            }
            let n = list.len();
            (
                SharedShape::compound(list),
                Pose::IDENTITY,
                ShapeKind::Compound { parts: n },
            )
        }
        (None, Some(_)) => {
            return Err(ck.err(&format!("{at}.parts"), "needs at least one part".into()));
        }
        (Some(_), Some(_)) => {
            return Err(ck.err(&at, "give either `shape` or `parts`, not both".into()));
        }
        (None, None) => {
            return Err(ck.err(
                &at,
                "missing `shape` (box, cylinder or mesh) or `parts`".into(),
            ));
        }
    };
    let local_aabb = shape.compute_aabb(&shape_offset);
    ck.extent(&local_aabb, &at)?;
    let mut surfaces = Vec::new();
    if let Some(list) = &spec.surfaces {
        for (k, s) in list.iter().enumerate() {
            let sat = format!("{at}.surfaces[{k}]");
            ck.coords(&s.centre, &format!("{sat}.centre"))?;
            ck.positive(&s.half_extents, &format!("{sat}.half_extents"))?;
            surfaces.push(SupportSurface {
                centre: Vector::from(s.centre),
                half_extents: s.half_extents,
            });
        }
        if !spec.support && !list.is_empty() {
            return Err(ck.err(
                &format!("{at}.surfaces"),
                "surfaces given but `support` is not true".into(),
            ));
        }
    } else if spec.support {
        surfaces.push(derive_top_face(&kind, &local_aabb));
    }
    let object = ObjectModel {
        name: spec.name.clone(),
        shape,
        shape_offset,
        kind,
        colour: spec.colour.unwrap_or_else(|| palette(i)),
        movable: spec.movable,
        surfaces,
        container: spec.container,
        local_aabb,
    };
    Ok((object, pose))
}

/// One agent of the scene file, checked, with its paths resolved.
fn agent_spec(
    ck: &Checker,
    a: &AgentSpec,
    at: &str,
    base_dir: &Path,
) -> Result<AgentSpecResolved, SceneError> {
    let urdf = base_dir.join(&a.urdf);
    if !urdf.is_file() {
        return Err(ck.err(
            &format!("{at}.urdf"),
            format!("URDF file `{}` not found", urdf.display()),
        ));
    }
    let srdf = match &a.srdf {
        Some(p) => {
            let p = base_dir.join(p);
            if !p.is_file() {
                return Err(ck.err(
                    &format!("{at}.srdf"),
                    format!("SRDF file `{}` not found", p.display()),
                ));
            }
            Some(p)
        }
        None => Some(urdf.with_extension("srdf")).filter(|p| p.is_file()),
    };
    ck.finite(&[a.base.yaw], &format!("{at}.base.yaw"))?;
    if !(a.base.z.is_finite() && (0.0..=3.0).contains(&a.base.z)) {
        return Err(ck.err(
            &format!("{at}.base.z"),
            format!("{} is outside 0 ..= 3 m", a.base.z),
        ));
    }
    ck.coords(&[a.base.x, a.base.y], &format!("{at}.base"))?;
    for (j, v) in &a.joints {
        if !v.is_finite() {
            return Err(ck.err(
                &format!("{at}.joints.{j}"),
                format!("joint value {v} is not finite"),
            ));
        }
    }
    let fov = match a.fov_deg {
        Some(f) => {
            ck.finite(&f, &format!("{at}.fov_deg"))?;
            if !(f[0] > 1.0 && f[0] < 179.0 && f[1] > 1.0 && f[1] < 179.0) {
                return Err(ck.err(
                    &format!("{at}.fov_deg"),
                    format!("field of view {f:?} must be between 1 and 179 degrees"),
                ));
            }
            Some([f[0].to_radians(), f[1].to_radians()])
        }
        None => None,
    };
    if let Some(r) = a.reach {
        ck.positive(&[r], &format!("{at}.reach"))?;
    }
    if a.sitting && a.kind == KindSpec::Robot {
        return Err(ck.err(
            &format!("{at}.sitting"),
            "only humans sit (robots use `torso_lift` effort)".into(),
        ));
    }
    let effort = a.effort.clone().unwrap_or_default();
    ck.effort(&effort, &format!("{at}.effort"))?;
    Ok(AgentSpecResolved {
        name: a.name.clone(),
        kind: match a.kind {
            KindSpec::Robot => AgentKind::Robot,
            KindSpec::Human => AgentKind::Human,
        },
        urdf,
        srdf,
        base: [a.base.x, a.base.y, a.base.yaw.to_radians()],
        mount_height: a.base.z,
        frames: extra_frames(ck, a, at)?,
        postures: match &a.posture {
            None => Vec::new(),
            Some(Postures::One(name)) => vec![name.clone()],
            Some(Postures::Many(names)) => names.clone(),
        },
        joints: a.joints.iter().map(|(k, v)| (k.clone(), *v)).collect(),
        eye: a.eye.clone(),
        shoulders: a.shoulders.clone(),
        hands: a.hands.clone(),
        fov,
        reach: a.reach,
        sitting: a.sitting,
        colour: a.colour.unwrap_or(match a.kind {
            KindSpec::Robot => [150, 160, 175],
            KindSpec::Human => [225, 180, 150],
        }),
        effort,
        groups: groups(ck, a, at)?,
        convex_modes: convex_modes(ck, a, at)?,
    })
}

/// The agent's `groups`, each a chain (`base_link` and `tip_link`) or joints, not both.
fn groups(
    ck: &Checker,
    a: &AgentSpec,
    at: &str,
) -> Result<Vec<crate::agent::srdf::Group>, SceneError> {
    let mut out = Vec::new();
    for (name, g) in &a.groups {
        let chain = match (&g.base_link, &g.tip_link) {
            (Some(b), Some(t)) => Some((b.clone(), t.clone())),
            (None, None) => None,
            _ => {
                return Err(ck.err(
                    &format!("{at}.groups.{name}"),
                    "a chain needs both `base_link` and `tip_link`".into(),
                ));
            }
        };
        if chain.is_some() != g.joints.is_empty() {
            return Err(ck.err(
                &format!("{at}.groups.{name}"),
                "give a chain (`base_link`, `tip_link`) or `joints`, one of the two".into(),
            ));
        }
        out.push(crate::agent::srdf::Group {
            name: name.clone(),
            chain,
            joints: g.joints.clone(),
            ..Default::default()
        });
    }
    Ok(out)
}

/// The agent's `frames`, checked: finite offsets within a few metres.
fn extra_frames(
    ck: &Checker,
    a: &AgentSpec,
    at: &str,
) -> Result<Vec<crate::agent::ExtraFrame>, SceneError> {
    a.frames
        .iter()
        .enumerate()
        .map(|(i, f)| {
            let at = format!("{at}.frames[{i}]");
            ck.finite(&f.rpy, &format!("{at}.rpy"))?;
            ck.finite(&f.xyz, &format!("{at}.xyz"))?;
            if f.xyz.iter().any(|v| v.abs() > 5.0) {
                return Err(ck.err(
                    &format!("{at}.xyz"),
                    format!("{:?}: a frame lies within 5 m of its parent link", f.xyz),
                ));
            }
            Ok(crate::agent::ExtraFrame {
                name: f.name.clone(),
                parent: f.parent.clone(),
                xyz: f.xyz,
                rpy: f.rpy.map(f32::to_radians),
            })
        })
        .collect()
}

/// The links a scene names in `hull_links` and `decompose_links` (in neither twice).
fn convex_modes(
    ck: &Checker,
    a: &AgentSpec,
    at: &str,
) -> Result<Vec<(String, crate::agent::ConvexMode)>, SceneError> {
    use crate::agent::ConvexMode;
    let mut modes: Vec<(String, ConvexMode)> = Vec::new();
    for (key, list, mode) in [
        ("hull_links", &a.hull_links, ConvexMode::Hull),
        ("decompose_links", &a.decompose_links, ConvexMode::Decompose),
    ] {
        for link in list {
            if modes.iter().any(|(l, _)| l == link) {
                return Err(ck.err(
                    &format!("{at}.{key}"),
                    format!("link `{link}` is named twice in hull_links/decompose_links"),
                ));
            }
            modes.push((link.clone(), mode));
        }
    }
    Ok(modes)
}

/// The scene's optional bounds, checked.
fn scene_bounds(ck: &Checker, bounds: Option<&BoundsSpec>) -> Result<Option<Aabb>, SceneError> {
    Ok(match bounds {
        Some(b) => {
            ck.coords(&b.min, "scene.bounds.min")?;
            ck.coords(&b.max, "scene.bounds.max")?;
            if (0..3).any(|k| b.min[k] >= b.max[k]) {
                return Err(ck.err(
                    "scene.bounds",
                    format!(
                        "min {:?} must be below max {:?} on every axis",
                        b.min, b.max
                    ),
                ));
            }
            Some(Aabb::new(Vector::from(b.min), Vector::from(b.max)))
        }
        None => None,
    })
}

struct Checker {
    file: String,
}

impl Checker {
    fn err(&self, key_path: &str, reason: String) -> SceneError {
        SceneError {
            file: self.file.clone(),
            line_col: None,
            key_path: key_path.to_string(),
            reason,
        }
    }

    fn name(&self, name: &str, at: &str) -> Result<(), SceneError> {
        let ok = !name.is_empty()
            && name
                .chars()
                .all(|c| c.is_ascii_alphanumeric() || c == '-' || c == '_')
            && name.chars().next().is_some_and(|c| c.is_ascii_alphabetic());
        if ok {
            Ok(())
        } else {
            Err(self.err(
                at,
                format!(
                    "name `{name}` must start with a letter and use only letters, digits, `-` and `_` \
                     (it becomes an HDDL constant)"
                ),
            ))
        }
    }

    fn finite(&self, v: &[f32], at: &str) -> Result<(), SceneError> {
        if v.iter().all(|x| x.is_finite()) {
            Ok(())
        } else {
            Err(self.err(at, format!("values {v:?} must be finite numbers")))
        }
    }

    /// Finite and within [`WORLD_EXTENT_M`] of the origin.
    fn coords(&self, v: &[f32], at: &str) -> Result<(), SceneError> {
        self.finite(v, at)?;
        if v.iter().all(|x| x.abs() <= WORLD_EXTENT_M) {
            Ok(())
        } else {
            Err(self.err(
                at,
                format!("values {v:?} lie outside the world (|value| <= {WORLD_EXTENT_M} m)"),
            ))
        }
    }

    /// A shape's bounding box in its object's frame lies within the world's extent.
    fn extent(&self, aabb: &Aabb, at: &str) -> Result<(), SceneError> {
        let far = aabb.mins.abs().max(aabb.maxs.abs()).max_element();
        if far <= WORLD_EXTENT_M {
            Ok(())
        } else {
            Err(self.err(
                at,
                format!("the shape reaches {far} m from its frame (at most {WORLD_EXTENT_M} m)"),
            ))
        }
    }

    fn positive(&self, v: &[f32], at: &str) -> Result<(), SceneError> {
        self.finite(v, at)?;
        if v.iter().all(|x| *x > 0.0) {
            Ok(())
        } else {
            Err(self.err(at, format!("sizes {v:?} must be positive")))
        }
    }

    fn pose(&self, p: &PoseSpec, at: &str) -> Result<Pose, SceneError> {
        self.coords(&p.xyz, &format!("{at}.xyz"))?;
        let rpy = match (p.rpy, p.yaw) {
            (Some(_), Some(_)) => {
                return Err(self.err(at, "give either `rpy` or `yaw`, not both".into()));
            }
            (Some(r), None) => {
                self.finite(&r, &format!("{at}.rpy"))?;
                [r[0].to_radians(), r[1].to_radians(), r[2].to_radians()]
            }
            (None, Some(y)) => {
                self.finite(&[y], &format!("{at}.yaw"))?;
                [0.0, 0.0, y.to_radians()]
            }
            (None, None) => [0.0; 3],
        };
        Ok(pose_from_xyz_rpy(p.xyz, rpy))
    }

    fn shape(
        &self,
        s: &ShapeSpec,
        at: &str,
        base_dir: &Path,
    ) -> Result<(SharedShape, Pose, ShapeKind), SceneError> {
        match s {
            ShapeSpec::Box(he) => {
                self.positive(he, &format!("{at}.box"))?;
                Ok((
                    SharedShape::cuboid(he[0], he[1], he[2]),
                    Pose::IDENTITY,
                    ShapeKind::Box {
                        half_extents: Vector::from(*he),
                    },
                ))
            }
            ShapeSpec::Cylinder {
                radius,
                half_height,
            } => {
                self.positive(&[*radius], &format!("{at}.cylinder.radius"))?;
                self.positive(&[*half_height], &format!("{at}.cylinder.half_height"))?;
                Ok((
                    SharedShape::cylinder(*half_height, *radius),
                    // parry's cylinder axis is y; turn it onto z.
                    Pose::from_rotation(Rotation::from_rotation_x(std::f32::consts::FRAC_PI_2)),
                    ShapeKind::Cylinder {
                        radius: *radius,
                        half_height: *half_height,
                    },
                ))
            }
            ShapeSpec::Mesh { file, scale } => {
                let scale = scale.unwrap_or(1.0);
                self.positive(&[scale], &format!("{at}.mesh.scale"))?;
                let path = base_dir.join(file);
                let mesh = mesh_file::read_mesh(&path).map_err(|e| {
                    self.err(
                        &format!("{at}.mesh.file"),
                        format!("{}: {e}", path.display()),
                    )
                })?;
                let n = mesh.triangles.len();
                let verts = mesh.vertices.iter().map(|v| *v * scale).collect();
                let tm = TriMesh::new(verts, mesh.triangles).map_err(|e| {
                    self.err(
                        &format!("{at}.mesh.file"),
                        format!("{}: not a usable triangle mesh: {e:?}", path.display()),
                    )
                })?;
                Ok((
                    SharedShape::new(tm),
                    Pose::IDENTITY,
                    ShapeKind::Mesh {
                        file: path,
                        triangles: n,
                    },
                ))
            }
        }
    }

    fn effort(&self, e: &EffortSpec, at: &str) -> Result<(), SceneError> {
        let ranges: [(&str, Option<f32>, f32, f32); 5] = [
            ("head_pan_deg", e.head_pan_deg, 0.0, 180.0),
            ("torso_turn_deg", e.torso_turn_deg, 0.0, 180.0),
            ("lean_deg", e.lean_deg, 0.0, 90.0),
            ("base_turn_deg", e.base_turn_deg, 0.0, 180.0),
            ("move_radius", e.move_radius, 0.0, 50.0),
        ];
        for (key, v, lo, hi) in ranges {
            if let Some(v) = v
                && !(v.is_finite() && v >= lo && v <= hi)
            {
                return Err(self.err(
                    &format!("{at}.{key}"),
                    format!("{v} is outside {lo} ..= {hi}"),
                ));
            }
        }
        Ok(())
    }
}
