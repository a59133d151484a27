//! The geometric world state: a loaded [`Scene`] plus where everything is now.
//!
//! A [`World`] is what the geometric task planner copies, mutates and throws away while it
//! searches: the immutable parts (shapes, names, agent models) sit behind one `Arc`, so a clone
//! copies only the object poses, attachments and agent configurations. Mutations: move an
//! object ([`World::set_object_pose`]), attach an object to a link of an agent (a grasp: it
//! then follows that link, [`World::attach`]) and release it ([`World::detach`]), set an
//! agent's base pose or joint values ([`World::set_agent_config`]).
//!
//! Everything solid in the world is a [`Body`]: an object, or one collision shape of an agent's
//! link posed by forward kinematics. The renderer, pixel visibility and the mightability maps
//! all work on bodies; the collision checker uses [`World::obstacles`] for the static part.

use std::path::Path;
use std::sync::Arc;

use parry3d::bounding_volume::{Aabb, BoundingVolume};
use parry3d::math::{Pose, Rotation, Vector};
use parry3d::shape::SharedShape;

mod swallowing_hulls;

use crate::agent::{AgentModel, ConvexMode, KinematicChain, MeshOptions, PackagePath, Primitive};
use crate::effort::EffortParams;
use crate::scene::{
    AgentId, AgentKind, AgentSpecResolved, ObjectId, ObjectModel, Scene, SceneError,
};

/// An agent of the scene with its kinematic model and the frames the world needs.
#[derive(Clone, Debug)]
pub struct AgentInfo {
    /// What the scene file says.
    pub spec: AgentSpecResolved,
    /// Kinematics and collision shapes (from the URDF).
    pub model: Arc<AgentModel>,
    /// Link whose frame is the eye (x forward, y left, z up).
    pub eye_link: usize,
    /// Shoulder links (reach is measured from their origins).
    pub shoulder_links: Vec<usize>,
    /// Hand / tool frames (objects are attached to these).
    pub hand_links: Vec<usize>,
    /// Horizontal and vertical field of view, radians.
    pub fov: [f32; 2],
    /// Arm reach from a shoulder, metres.
    pub reach: f32,
    /// What each effort level allows this agent to do.
    pub effort: EffortParams,
    /// The configuration the scene starts the agent in (its posture and joints).
    pub initial_q: Vec<f32>,
}

impl AgentInfo {
    /// The link the head turns about: the child of the first movable joint of the SRDF's `head`
    /// chain (the pan joint); `None` without one. A viewer's eye swings about its origin.
    pub fn head_pivot_link(&self) -> Option<usize> {
        let pan = self.effort.head_pan?;
        Some(self.model.joints()[self.model.dof_joint(pan.dof)].child)
    }

    /// Name of the agent.
    pub fn name(&self) -> &str {
        &self.spec.name
    }
    /// Robot or human.
    pub fn kind(&self) -> AgentKind {
        self.spec.kind
    }
}

/// The shared, immutable part of every world made from one scene.
#[derive(Debug)]
pub struct WorldModel {
    pub scene: Scene,
    pub agents: Vec<AgentInfo>,
}

/// An object held by an agent: it follows `link` with a fixed relative pose.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Attachment {
    pub agent: AgentId,
    pub link: usize,
    /// Pose of the object in the link frame.
    pub grasp: Pose,
}

/// Where an agent is and how its joints are set, with its link poses cached.
#[derive(Clone, Debug)]
pub struct AgentState {
    /// Base (root link) pose in the world.
    pub base: Pose,
    /// Joint values in the model's degree-of-freedom order.
    pub q: Vec<f32>,
    link_poses: Vec<Pose>,
}

impl AgentState {
    /// World pose of every link (forward kinematics of `base` and `q`).
    pub fn link_poses(&self) -> &[Pose] {
        &self.link_poses
    }
}

/// Who a body belongs to.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum BodyOwner {
    Object(ObjectId),
    /// An agent's link (the link index in its model).
    Agent(AgentId, usize),
}

/// One solid shape placed in the world.
#[derive(Clone)]
pub struct Body<'a> {
    pub owner: BodyOwner,
    pub shape: &'a SharedShape,
    /// World pose of the shape.
    pub pose: Pose,
    pub colour: [u8; 3],
    /// The radius of a ball about `pose`'s origin that holds the shape, where it is known
    /// without visiting the shape (an agent's collision shapes): a cheap first bound.
    pub radius: Option<f32>,
}

/// How deep two bodies may interpenetrate in a scene as loaded: a book resting on a desk
/// touches it (within rounding), which is not a collision.
pub const CONTACT_TOLERANCE_M: f32 = 0.001;

/// How deep two bodies interpenetrate, when more than [`CONTACT_TOLERANCE_M`] (bounding boxes
/// first; shapes parry cannot compare are taken as apart).
fn penetration(a: &Body<'_>, b: &Body<'_>) -> Option<f32> {
    touching(a, b).filter(|&depth| depth > CONTACT_TOLERANCE_M)
}

/// How deep two bodies overlap where they touch at all (0 for touching): what the planner's
/// collision checks count, which leave no tolerance.
fn touching(a: &Body<'_>, b: &Body<'_>) -> Option<f32> {
    let (ba, bb) = (a.shape.compute_aabb(&a.pose), b.shape.compute_aabb(&b.pose));
    if !ba.intersects(&bb) {
        return None;
    }
    let c = parry3d::query::contact(&a.pose, &**a.shape, &b.pose, &**b.shape, 0.0).ok()??;
    Some((-c.dist).max(0.0))
}

/// Why a model has no arm, for the error that says so: its SRDF's end effectors that end no
/// group, or that it has none.
fn no_arm_hint(model: &AgentModel) -> String {
    let orphans: Vec<String> = model
        .semantics()
        .end_effectors
        .iter()
        .filter(|e| {
            e.parent_group
                .as_ref()
                .is_none_or(|g| model.chain(g).is_err())
        })
        .map(|e| format!("`{}` (parent_link `{}`)", e.name, e.parent_link))
        .collect();
    if orphans.is_empty() {
        "give the model an SRDF with arms (groups ending in an `end_effector`)".into()
    } else {
        format!(
            "the SRDF's end effector {} ends no arm group whose chain holds its parent_link \
             (a chain group sharing no movable joint with it): give it a `parent_group`",
            orphans.join(", ")
        )
    }
}

/// Per link: whether it is rigidly fixed to the root (the robot's base; the links are in
/// topological order, parents first).
fn base_links(model: &AgentModel) -> Vec<bool> {
    let mut base = vec![false; model.links().len()];
    for (i, link) in model.links().iter().enumerate() {
        base[i] = match (link.parent, link.parent_joint) {
            (Some(p), Some(j)) => base[p] && !model.joints()[j].is_movable(),
            _ => true,
        };
    }
    base
}

/// The world state. Cheap to clone (see the module docs).
#[derive(Clone, Debug)]
pub struct World {
    model: Arc<WorldModel>,
    poses: Vec<Pose>,
    attachments: Vec<Option<Attachment>>,
    agents: Vec<AgentState>,
}

/// Base pose on the floor from x, y and yaw (radians).
pub fn base_pose(x: f32, y: f32, yaw: f32) -> Pose {
    Pose::from_parts(Vector::new(x, y, 0.0), Rotation::from_rotation_z(yaw))
}

/// `model` (loaded by `load` with `meshes`), with the collision meshes whose hulls overlap
/// another link in the initial configuration `q`, where their decompositions do not, loaded
/// decomposed instead ([`swallowing_hulls`]).
fn decompose_swallowing_hulls(
    model: AgentModel,
    q: &[f32],
    mut meshes: MeshOptions,
    load: impl Fn(&MeshOptions) -> Result<AgentModel, SceneError>,
) -> Result<AgentModel, SceneError> {
    let has_hulls = model.links().iter().any(|l| {
        l.collisions
            .iter()
            .any(|c| matches!(c.primitive, Primitive::Convex { pieces: 1, .. }))
    });
    if !has_hulls {
        return Ok(model);
    }
    let links = swallowing_hulls::colliding_hull_links(&model, q, &meshes.modes);
    if links.is_empty() {
        return Ok(model);
    }
    for l in &links {
        meshes.modes.insert(l.clone(), ConvexMode::Decompose);
    }
    let decomposed = load(&meshes)?;
    let back = swallowing_hulls::still_colliding(&decomposed, q, &links);
    if back.is_empty() {
        return Ok(decomposed);
    }
    if back.len() == links.len() {
        return Ok(model);
    }
    for l in &back {
        meshes.modes.remove(l);
    }
    load(&meshes)
}

/// The URDF text of an agent of `scene`.
fn read_model(path: &Path, scene: &Scene, at: &str) -> Result<String, SceneError> {
    std::fs::read_to_string(path).map_err(|e| {
        scene.error(
            &format!("{at}.urdf"),
            format!("cannot read `{}`: {e}", path.display()),
        )
    })
}

/// How closely [`World::fingerprint`] tells worlds apart.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Precision {
    /// Every bit of every value.
    Exact,
    /// Positions to the millimetre (quaternion components and joint values to 0.001).
    Millimetre,
}

impl World {
    /// Loads a scene file and its agents' URDF models.
    pub fn load(path: impl AsRef<Path>) -> Result<World, SceneError> {
        World::from_scene(Scene::load(path)?)
    }

    /// Loads a scene as [`World::load`] does, but objects that start inside one another are a
    /// warning (returned), not an error: `--allow-initial-contact`. A robot's base inside an
    /// object stays an error.
    pub fn load_allowing_contact(
        path: impl AsRef<Path>,
    ) -> Result<(World, Option<SceneError>), SceneError> {
        let world = World::unchecked(Scene::load(path)?)?;
        if let Some(e) = world.robot_overlap() {
            return Err(e);
        }
        let warning = world.object_overlap();
        Ok((world, warning))
    }

    /// Builds the initial world of a loaded scene: loads each agent's URDF, checks the joint and
    /// link names the scene uses, applies the scene's posture, and refuses a world that starts
    /// in collision (`World::initial_overlap`).
    pub fn from_scene(scene: Scene) -> Result<World, SceneError> {
        let world = World::unchecked(scene)?;
        match world.initial_overlap() {
            Some(e) => Err(e),
            None => Ok(world),
        }
    }

    /// [`World::from_scene`] without the check for initial collisions.
    fn unchecked(scene: Scene) -> Result<World, SceneError> {
        let mut infos = Vec::with_capacity(scene.agents.len());
        let mut states = Vec::with_capacity(scene.agents.len());
        for (i, spec) in scene.agents.iter().enumerate() {
            let at = format!("agents[{i}]");
            let meshes = MeshOptions {
                packages: PackagePath {
                    urdf_dir: spec
                        .urdf
                        .parent()
                        .map(Path::to_path_buf)
                        .unwrap_or_default(),
                    scene_dirs: scene.package_path.clone(),
                },
                modes: spec.convex_modes.iter().cloned().collect(),
            };
            let text = crate::agent::frames::add_frames(
                &read_model(&spec.urdf, &scene, &at)?,
                &spec.frames,
                spec.mount_height,
            )
            .map_err(|e| scene.error(&format!("{at}.{}", e.key), e.message))?;
            let load = |meshes: &MeshOptions| {
                let model =
                    AgentModel::from_urdf_str_with(&text, &spec.urdf.display().to_string(), meshes)
                        .map_err(|e| scene.error(&format!("{at}.urdf"), e.to_string()))?;
                let model = match &spec.srdf {
                    Some(path) => model
                        .with_srdf_file(path)
                        .map_err(|e| scene.error(&format!("{at}.srdf"), e.to_string()))?,
                    None => model,
                };
                model
                    .with_groups(&spec.groups)
                    .map_err(|e| scene.error(&format!("{at}.groups"), e.to_string()))
            };
            let model = load(&meshes)?;
            for (link, _) in &spec.convex_modes {
                if model.link_id(link).is_err() {
                    return Err(scene.error(
                        &at,
                        format!(
                            "hull_links/decompose_links: no link `{link}` in {}",
                            spec.urdf.display()
                        ),
                    ));
                }
            }
            let mut q = model.default_configuration().into_vec();
            for name in &spec.postures {
                let values = model.posture(name);
                if values.is_empty() {
                    return Err(scene.error(
                        &format!("{at}.posture"),
                        format!(
                            "no posture `{name}` (a `group_state` with joint values) in the SRDF{}",
                            spec.srdf
                                .as_ref()
                                .map_or(String::new(), |p| format!(" {}", p.display()))
                        ),
                    ));
                }
                for (k, v) in values {
                    q[k] = model.dof_limits()[k].clamp(v);
                }
            }
            for (name, v) in &spec.joints {
                let k = model.dof_index(name).map_err(|_| {
                    scene.error(
                        &format!("{at}.joints.{name}"),
                        format!(
                            "unknown joint `{name}` (movable joints of {}: {})",
                            spec.urdf.display(),
                            model.dof_names().join(", ")
                        ),
                    )
                })?;
                let lim = model.dof_limits()[k];
                if !lim.contains(*v) {
                    return Err(scene.error(
                        &format!("{at}.joints.{name}"),
                        format!(
                            "{v} is outside the joint limits {} ..= {}",
                            lim.lower, lim.upper
                        ),
                    ));
                }
                q[k] = *v;
            }
            let model = decompose_swallowing_hulls(model, &q, meshes, load)?;
            let link = |key: &str, name: &str| {
                model.link_id(name).map_err(|_| {
                    scene.error(
                        &format!("{at}.{key}"),
                        format!("no link `{name}` in {}", spec.urdf.display()),
                    )
                })
            };
            let human = spec.kind == AgentKind::Human;
            let eye_link = match &spec.eye {
                Some(n) => link("eye", n)?,
                None => model.chain("head").map(|c| c.tip_link).map_err(|_| {
                    scene.error(
                        &at,
                        "no eye link: give the model an SRDF `head` group whose chain ends at the eye or camera, or name it with `eye = \"LINK\"`",
                    )
                })?,
            };
            let arms: Vec<KinematicChain> = model
                .arm_names()
                .iter()
                .filter_map(|a| model.chain(a).ok())
                .collect();
            let links_or = |key: &str, given: &Option<Vec<String>>, found: Vec<usize>| match given {
                Some(list) => list
                    .iter()
                    .map(|n| link(key, n))
                    .collect::<Result<Vec<_>, _>>(),
                None if found.is_empty() => Err(scene.error(
                    &at,
                    format!(
                        "no {key} links: {}, or name them with `{key} = [..]`",
                        no_arm_hint(&model)
                    ),
                )),
                None => Ok(found),
            };
            // A shoulder is the link its arm's first movable joint turns; a hand, the arm's tip.
            let shoulders = arms
                .iter()
                .filter_map(|c| c.joints.iter().find(|&&j| model.joints()[j].is_movable()))
                .map(|&j| model.joints()[j].child)
                .collect();
            let shoulder_links = links_or("shoulders", &spec.shoulders, shoulders)?;
            let hands = arms.iter().map(|c| c.tip_link).collect();
            let hand_links = links_or("hands", &spec.hands, hands)?;
            let fov = spec.fov.unwrap_or(if human {
                // Attention field of a person (facts: 120 deg, vertical 0.75 of it).
                [120f32.to_radians(), 90f32.to_radians()]
            } else {
                // A head camera of the PR2's kind.
                [70f32.to_radians(), 52.5f32.to_radians()]
            });
            let reach = spec.reach.unwrap_or(if human { 0.70 } else { 0.95 });
            let effort = EffortParams::for_agent(spec, &model);
            let base = base_pose(spec.base[0], spec.base[1], spec.base[2]);
            let link_poses = model.link_poses(base, &q);
            states.push(AgentState {
                base,
                q: q.clone(),
                link_poses,
            });
            infos.push(AgentInfo {
                spec: spec.clone(),
                model: Arc::new(model),
                eye_link,
                shoulder_links,
                hand_links,
                fov,
                reach,
                effort,
                initial_q: q,
            });
        }
        let poses = scene.initial_poses.clone();
        let n = poses.len();
        let world = World {
            model: Arc::new(WorldModel {
                scene,
                agents: infos,
            }),
            poses,
            attachments: vec![None; n],
            agents: states,
        };
        Ok(world)
    }

    /// The first overlap deeper than [`CONTACT_TOLERANCE_M`] between a movable object and
    /// another object, or the first contact at all between a robot's base (its links rigidly
    /// fixed to the root; an arm may start against a wall) and an object, as an error naming
    /// both: a
    /// scene that starts in collision would only make every plan fail ("no plan exists")
    /// without saying why. Furniture may overlap furniture (walls joined at a corner), and
    /// people are not checked (a seated person's model rests in the chair).
    fn initial_overlap(&self) -> Option<SceneError> {
        self.object_overlap().or_else(|| self.robot_overlap())
    }

    /// The first overlap between a movable object and another object (see
    /// [`World::initial_overlap`]).
    fn object_overlap(&self) -> Option<SceneError> {
        let bodies = self.bodies();
        let objects: Vec<&Body<'_>> = bodies
            .iter()
            .filter(|b| matches!(b.owner, BodyOwner::Object(_)))
            .collect();
        let movable =
            |b: &Body<'_>| matches!(b.owner, BodyOwner::Object(id) if self.object(id).movable);
        // Object pairs: the first overlap in the file's order (the pair (i, j), i < j, least;
        // the later object named first), found by a sweep along the axis where the objects
        // spread most, not by trying every pair (10,000 objects would be 50 M pairs).
        let boxes: Vec<Aabb> = objects
            .iter()
            .map(|b| b.shape.compute_aabb(&b.pose))
            .collect();
        let spread = |axis: usize| {
            let (lo, hi) = boxes.iter().fold((f32::MAX, f32::MIN), |(lo, hi), b| {
                let c = (b.mins[axis] + b.maxs[axis]) * 0.5;
                (lo.min(c), hi.max(c))
            });
            hi - lo
        };
        let axis = (0..3)
            .max_by(|&a, &b| spread(a).total_cmp(&spread(b)))
            .unwrap_or(0);
        let mut order: Vec<usize> = (0..objects.len()).collect();
        order.sort_by(|&a, &b| boxes[a].mins[axis].total_cmp(&boxes[b].mins[axis]));
        let mut first: Option<(usize, usize, f32)> = None;
        for (k, &i) in order.iter().enumerate() {
            for &j in &order[k + 1..] {
                if boxes[j].mins[axis] > boxes[i].maxs[axis] {
                    break;
                }
                let (lo, hi) = (i.min(j), i.max(j));
                if first.is_some_and(|(a, b, _)| (lo, hi) >= (a, b))
                    || !boxes[i].intersects(&boxes[j])
                    || !(movable(objects[i]) || movable(objects[j]))
                {
                    continue;
                }
                if let Some(depth) = penetration(objects[hi], objects[lo]) {
                    first = Some((lo, hi, depth));
                }
            }
        }
        first.map(|(lo, hi, depth)| self.overlap_error(objects[hi], objects[lo], depth))
    }

    /// The first overlap between a robot's base and an object (see
    /// [`World::initial_overlap`]).
    fn robot_overlap(&self) -> Option<SceneError> {
        let bodies = self.bodies();
        let objects: Vec<&Body<'_>> = bodies
            .iter()
            .filter(|b| matches!(b.owner, BodyOwner::Object(_)))
            .collect();
        let bases: Vec<Vec<bool>> = self
            .agent_ids()
            .map(|a| base_links(&self.agent(a).model))
            .collect();
        let robot_links = bodies.iter().filter(|b| {
            matches!(b.owner, BodyOwner::Agent(a, l)
                if self.agent(a).kind() == AgentKind::Robot && bases[a.0][l])
        });
        // No tolerance here: the base never moves relative to the scene, and the planner counts
        // touching as a collision, so every motion would fail (an arm's base flush on its table).
        let (a, b, depth) = robot_links
            .flat_map(|l| objects.iter().map(move |o| (l, *o)))
            .find_map(|(a, b)| Some((a, b, touching(a, b)?)))?;
        match (a.owner, b.owner) {
            (BodyOwner::Agent(ag, l), BodyOwner::Object(o)) => {
                Some(self.base_contact_error(ag, l, o, depth))
            }
            _ => Some(self.overlap_error(a, b, depth)),
        }
    }

    /// The error for link `l` of robot `ag`'s base touching object `o` (`depth` metres deep).
    fn base_contact_error(&self, ag: AgentId, l: usize, o: ObjectId, depth: f32) -> SceneError {
        let (object, agent) = (&self.object(o).name, self.agent(ag));
        let who = format!(
            "`{}` (its link `{}`, fixed to its base)",
            agent.name(),
            agent.model.links()[l].name
        );
        let message = if depth > CONTACT_TOLERANCE_M {
            format!(
                "{who} starts inside `{object}` ({:.1} mm deep): a robot's base must start clear \
                 of the scene; move the base (`base`)",
                depth * 1000.0
            )
        } else {
            format!(
                "{who} touches `{object}`: a robot's base must start clear of the scene, since \
                 the planner counts touching as a collision and every motion would fail; move \
                 the base (`base`: a millimetre up is enough for a base resting on a table)"
            )
        };
        self.scene().error(&format!("agents[{}]", ag.0), message)
    }

    /// The error for body `a` overlapping object `b` by `depth` metres, at `a`'s key path.
    fn overlap_error(&self, a: &Body<'_>, b: &Body<'_>, depth: f32) -> SceneError {
        let name = |o: BodyOwner| match o {
            BodyOwner::Object(id) => format!("`{}`", self.object(id).name),
            BodyOwner::Agent(ag, l) => format!(
                "`{}` (its link `{}`)",
                self.agent(ag).name(),
                self.agent(ag).model.links()[l].name
            ),
        };
        let at = match a.owner {
            BodyOwner::Object(id) => format!("objects[{}]", id.0),
            BodyOwner::Agent(ag, _) => format!("agents[{}]", ag.0),
        };
        self.scene().error(
            &at,
            format!(
                "{} starts inside {} ({:.1} mm deep; a scene must start free of collisions, \
                 touching within {} mm is allowed)",
                name(a.owner),
                name(b.owner),
                depth * 1000.0,
                CONTACT_TOLERANCE_M * 1000.0
            ),
        )
    }

    /// The scene this world was made from.
    pub fn scene(&self) -> &Scene {
        &self.model.scene
    }

    /// The shared immutable part (for checking that two worlds come from the same scene:
    /// `Arc::ptr_eq`).
    pub fn model(&self) -> &Arc<WorldModel> {
        &self.model
    }

    // ---- objects -------------------------------------------------------------------------

    /// Number of objects.
    pub fn object_count(&self) -> usize {
        self.poses.len()
    }

    /// All object ids, in scene order.
    pub fn object_ids(&self) -> impl Iterator<Item = ObjectId> + '_ {
        (0..self.poses.len()).map(ObjectId)
    }

    /// The object called `name`.
    pub fn object_id(&self, name: &str) -> Option<ObjectId> {
        self.model.scene.object_id(name)
    }

    /// Immutable description of an object.
    pub fn object(&self, id: ObjectId) -> &ObjectModel {
        &self.model.scene.objects[id.0]
    }

    /// Current pose of the object's frame.
    pub fn object_pose(&self, id: ObjectId) -> Pose {
        self.poses[id.0]
    }

    /// Current world pose of the object's shape (`object_pose * shape_offset`).
    pub fn object_shape_pose(&self, id: ObjectId) -> Pose {
        self.poses[id.0] * self.object(id).shape_offset
    }

    /// Current world bounding box of the object.
    pub fn object_aabb(&self, id: ObjectId) -> Aabb {
        let o = self.object(id);
        o.shape.compute_aabb(&self.object_shape_pose(id))
    }

    /// Moves an object. If it is attached, it is released first.
    pub fn set_object_pose(&mut self, id: ObjectId, pose: Pose) {
        self.attachments[id.0] = None;
        self.poses[id.0] = pose;
    }

    /// Attaches an object to a link of an agent at its current relative pose (a grasp already
    /// made: the object then follows the link when the agent moves).
    pub fn attach(&mut self, id: ObjectId, agent: AgentId, link: usize) {
        let link_pose = self.agents[agent.0].link_poses[link];
        let grasp = link_pose.inv_mul(&self.poses[id.0]);
        self.attachments[id.0] = Some(Attachment { agent, link, grasp });
    }

    /// Attaches an object to a link with a given grasp (object pose in the link frame) and
    /// moves the object there.
    pub fn attach_with_grasp(&mut self, id: ObjectId, agent: AgentId, link: usize, grasp: Pose) {
        self.poses[id.0] = self.agents[agent.0].link_poses[link] * grasp;
        self.attachments[id.0] = Some(Attachment { agent, link, grasp });
    }

    /// Releases an attached object where it is.
    pub fn detach(&mut self, id: ObjectId) {
        self.attachments[id.0] = None;
    }

    /// The attachment of an object, if it is held.
    pub fn attachment(&self, id: ObjectId) -> Option<Attachment> {
        self.attachments[id.0]
    }

    /// A hash of the world's state: every object's pose and attachment, every agent's base
    /// pose and joint values. The one fingerprint of a world: the HTN search tells worlds
    /// apart by it to the millimetre, the mightability maps are cached by it exactly.
    pub fn fingerprint(&self, precision: Precision) -> u64 {
        use std::hash::{Hash, Hasher};
        let mut h = std::collections::hash_map::DefaultHasher::new();
        let key = |v: f32| match precision {
            Precision::Exact => i64::from(v.to_bits()),
            Precision::Millimetre => (v * 1000.0).round() as i64,
        };
        for id in self.object_ids() {
            let p = self.object_pose(id);
            let r = p.rotation;
            for v in [
                p.translation.x,
                p.translation.y,
                p.translation.z,
                r.x,
                r.y,
                r.z,
                r.w,
            ] {
                key(v).hash(&mut h);
            }
            self.attachment(id)
                .map(|a| (a.agent.0, a.link))
                .hash(&mut h);
        }
        for id in self.agent_ids() {
            let s = self.agent_state(id);
            let (t, r) = (s.base.translation, s.base.rotation);
            // A base turns about z only; the tilt parts count where every bit does. (The
            // millimetre hash seeds the GTP's calls: changing it changes the plans.)
            if precision == Precision::Exact {
                [r.x, r.y].map(key).hash(&mut h);
            }
            for v in [t.x, t.y, r.z, r.w].iter().chain(&s.q) {
                key(*v).hash(&mut h);
            }
        }
        h.finish()
    }

    // ---- agents --------------------------------------------------------------------------

    /// Number of agents.
    pub fn agent_count(&self) -> usize {
        self.agents.len()
    }

    /// All agent ids.
    pub fn agent_ids(&self) -> impl Iterator<Item = AgentId> + '_ {
        (0..self.agents.len()).map(AgentId)
    }

    /// The agent called `name`.
    pub fn agent_id(&self, name: &str) -> Option<AgentId> {
        self.model.scene.agent_id(name)
    }

    /// Model and parameters of an agent.
    pub fn agent(&self, id: AgentId) -> &AgentInfo {
        &self.model.agents[id.0]
    }

    /// Current base pose, joint values and link poses of an agent.
    pub fn agent_state(&self, id: AgentId) -> &AgentState {
        &self.agents[id.0]
    }

    /// Sets an agent's base pose and joint values (model order) and moves what it holds.
    /// Values are used as given (the caller keeps them within limits).
    pub fn set_agent_config(&mut self, id: AgentId, base: Pose, q: &[f32]) {
        let info = &self.model.agents[id.0];
        let st = &mut self.agents[id.0];
        st.base = base;
        st.q.clear();
        st.q.extend_from_slice(q);
        info.model.link_poses_into(base, q, &mut st.link_poses);
        for (k, a) in self.attachments.iter().enumerate() {
            if let Some(a) = a
                && a.agent == id
            {
                self.poses[k] = self.agents[id.0].link_poses[a.link] * a.grasp;
            }
        }
    }

    /// Sets one joint by name.
    pub fn set_joint(&mut self, id: AgentId, joint: &str, value: f32) -> Result<(), String> {
        let k = self.model.agents[id.0]
            .model
            .dof_index(joint)
            .map_err(|e| e.to_string())?;
        let mut q = self.agents[id.0].q.clone();
        q[k] = value;
        let base = self.agents[id.0].base;
        self.set_agent_config(id, base, &q);
        Ok(())
    }

    /// World pose of an agent's eye frame (x forward, y left, z up).
    pub fn eye_pose(&self, id: AgentId) -> Pose {
        self.agents[id.0].link_poses[self.agent(id).eye_link]
    }

    // ---- bodies --------------------------------------------------------------------------

    /// Every solid thing: objects (in scene order) then every collision shape of every agent.
    pub fn bodies(&self) -> Vec<Body<'_>> {
        let mut out: Vec<Body<'_>> = self
            .object_ids()
            .map(|id| Body {
                owner: BodyOwner::Object(id),
                shape: &self.object(id).shape,
                pose: self.object_shape_pose(id),
                colour: self.object(id).colour,
                radius: None,
            })
            .collect();
        for a in self.agent_ids() {
            let info = self.agent(a);
            let poses = &self.agents[a.0].link_poses;
            for (li, link) in info.model.links().iter().enumerate() {
                for c in &link.collisions {
                    out.push(Body {
                        owner: BodyOwner::Agent(a, li),
                        shape: &c.shape,
                        pose: poses[li] * c.local_pose,
                        colour: info.spec.colour,
                        radius: Some(c.bounding_radius),
                    });
                }
            }
        }
        out
    }

    /// The obstacles for an agent's collision checks: every object not attached to an agent,
    /// as `(id, shape, world pose)`.
    pub fn obstacles(&self) -> impl Iterator<Item = (ObjectId, &SharedShape, Pose)> + '_ {
        self.object_ids()
            .filter(|id| self.attachments[id.0].is_none())
            .map(|id| (id, &self.object(id).shape, self.object_shape_pose(id)))
    }

    /// Bounding box of everything (objects and agents).
    pub fn bounds(&self) -> Aabb {
        let mut b = Aabb::new_invalid();
        for body in self.bodies() {
            b.merge(&body.shape.compute_aabb(&body.pose));
        }
        b
    }
}
