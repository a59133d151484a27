//! Collision checking of an agent (robot or human) in a configuration: self-collision, the agent
//! against the static obstacles of a scene, and an object held in a gripper or hand against both.
//!
//! Three pieces, built in this order and shared behind `Arc`s:
//!
//! * [`StaticObstacles`]: the scene's fixed geometry (name, pose, parry shape), with cached world
//!   AABBs and, for larger sets, a parry [`Bvh`] over them. Built once per scene.
//! * [`SelfCollisionModel`]: an [`AgentModel`]'s collision shapes flattened into one list, and
//!   the list of shape pairs to test for self-collision. Pairs are left out, as MoveIt's setup
//!   assistant does for its SRDF, when their links are *adjacent* (a link and its parent, one
//!   joint apart), when they collide in the *default* configuration (all joints at 0,
//!   clamped into the limits), when they collide in at least [`SelfCollisionOptions::always_fraction`]
//!   of seeded random configurations (*always*: they overlap by construction), or when their
//!   relative pose depends on at most one joint and a fine sweep of it finds no contact
//!   (*never*: the two fingers of a gripper). Built once per
//!   agent model; the left-out pairs and why are listed by [`SelfCollisionModel::allowed_pairs`].
//! * [`CollisionChecker`]: the two above, the agent's base pose, and optionally a
//!   [`HeldObject`]. Answers [`CollisionChecker::is_config_free`] (fast, early exit) and
//!   [`CollisionChecker::first_collision`] / [`CollisionChecker::collisions`] (which pair).
//!
//! A check runs forward kinematics once, poses every shape, then tests shape AABBs against the
//! obstacles' AABBs (broad phase) and, for self pairs, the bounding spheres of the two links and
//! then of the two shapes, before parry's exact intersection test (narrow phase). A convex
//! polyhedron (a mesh's hull or piece, whose exact test and AABB visit every vertex) has its AABB
//! from its bounding box in its own frame, and that box is tested first in the narrow phase. Whether shapes exactly touching (distance 0) count as
//! colliding is up to parry's tests and rounding; design shapes with a small gap instead.
//!
//! Obstacles that touch the agent by design must be kept out of the set: a floor should lie just
//! below z = 0 (the PR2's base and a standing human's feet touch z = 0), and an object being
//! picked up must be removed ([`StaticObstacles::without`]) and given as the held object.

use std::cell::RefCell;
use std::fmt;
use std::sync::{Arc, Mutex};

use parry3d::bounding_volume::Aabb;
use parry3d::math::{Mat3, Pose, Vector};
use parry3d::partitioning::{Bvh, BvhBuildStrategy};
use parry3d::query;
use parry3d::shape::{Shape, SharedShape};

use crate::agent::{AgentModel, ModelError};
use pair_cells::CellProof;

mod base_sweep;
mod climbing_hull;
mod link_capsule;
mod motion;
mod pair_cells;
mod self_collision;
pub use base_sweep::BaseSweep;
pub use climbing_hull::HullBounds;
pub use motion::MotionCheck;
pub use self_collision::{AllowedPair, AllowedReason, SelfCollisionModel, SelfCollisionOptions};

/// One piece of static scene geometry.
#[derive(Clone)]
pub struct Obstacle {
    /// Name (for reports: the scene object's name).
    pub name: String,
    /// World pose of the shape.
    pub pose: Pose,
    /// The shape.
    pub shape: SharedShape,
}

impl fmt::Debug for Obstacle {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.debug_struct("Obstacle")
            .field("name", &self.name)
            .field("pose", &self.pose)
            .finish()
    }
}

/// Above this many obstacles the broad phase walks a BVH; below, a flat AABB sweep is faster.
const LINEAR_SWEEP_MAX: usize = 32;

/// The static obstacles of a scene, with cached world AABBs and a BVH over them.
#[derive(Clone)]
pub struct StaticObstacles {
    obstacles: Vec<Obstacle>,
    aabbs: Vec<Aabb>,
    bvh: Option<Bvh>,
    /// The unmoving parts of agents last checked against these obstacles (see
    /// [`CollisionChecker::set_fixed_joints`]).
    fixed: FixedParts,
}

/// The last [`FIXED_PARTS_KEPT`] unmoving parts made for one set of obstacles: a task plans
/// many motions of one arm, each with a checker of its own, the rest of the robot as it was.
#[derive(Default)]
struct FixedParts(Mutex<Vec<Arc<FixedJoints>>>);

/// How many unmoving parts a set of obstacles keeps (a few kilobytes each).
const FIXED_PARTS_KEPT: usize = 8;

impl Clone for FixedParts {
    fn clone(&self) -> FixedParts {
        FixedParts::default()
    }
}

impl FixedParts {
    fn find(&self, wanted: impl Fn(&FixedJoints) -> bool) -> Option<Arc<FixedJoints>> {
        let kept = self.0.lock().unwrap_or_else(|e| e.into_inner());
        kept.iter().rev().find(|f| wanted(f)).cloned()
    }

    fn keep(&self, f: Arc<FixedJoints>) {
        let mut kept = self.0.lock().unwrap_or_else(|e| e.into_inner());
        if kept.len() == FIXED_PARTS_KEPT {
            kept.remove(0);
        }
        kept.push(f);
    }
}

impl fmt::Debug for StaticObstacles {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.debug_list()
            .entries(self.obstacles.iter().map(|o| &o.name))
            .finish()
    }
}

impl StaticObstacles {
    /// Caches the obstacles' world AABBs and builds the broad phase.
    pub fn new(obstacles: Vec<Obstacle>) -> StaticObstacles {
        let aabbs: Vec<Aabb> = obstacles
            .iter()
            .map(|o| o.shape.compute_aabb(&o.pose))
            .collect();
        let bvh = (obstacles.len() > LINEAR_SWEEP_MAX)
            .then(|| Bvh::from_leaves(BvhBuildStrategy::default(), &aabbs));
        StaticObstacles {
            obstacles,
            aabbs,
            bvh,
            fixed: FixedParts::default(),
        }
    }

    /// No obstacles.
    pub fn empty() -> StaticObstacles {
        StaticObstacles::new(Vec::new())
    }

    /// A copy without the obstacles whose names are listed (for example the object being picked).
    pub fn without(&self, names: &[&str]) -> StaticObstacles {
        StaticObstacles::new(
            self.obstacles
                .iter()
                .filter(|o| !names.contains(&o.name.as_str()))
                .cloned()
                .collect(),
        )
    }

    /// Number of obstacles.
    pub fn len(&self) -> usize {
        self.obstacles.len()
    }

    /// Whether there are none.
    pub fn is_empty(&self) -> bool {
        self.obstacles.is_empty()
    }

    /// The obstacles, in the order given.
    pub fn obstacles(&self) -> &[Obstacle] {
        &self.obstacles
    }

    /// World AABB of obstacle `i`.
    pub fn aabb(&self, i: usize) -> &Aabb {
        &self.aabbs[i]
    }

    /// The first obstacle that intersects `shape` at `pose` (whose world AABB is `aabb`).
    pub fn first_hit(&self, pose: &Pose, shape: &dyn Shape, aabb: &Aabb) -> Option<usize> {
        let mut hit = None;
        self.for_each_hit(pose, shape, aabb, |i| {
            hit = Some(i);
            true
        });
        hit
    }

    /// The indices of the obstacles whose AABBs overlap `aabb`, into `out` (cleared first).
    fn candidates(&self, aabb: &Aabb, out: &mut Vec<u32>) {
        out.clear();
        match &self.bvh {
            None => out.extend(
                self.aabbs
                    .iter()
                    .enumerate()
                    .filter(|(_, b)| aabb_overlap(aabb, b))
                    .map(|(i, _)| i as u32),
            ),
            Some(bvh) => out.extend(bvh.intersect_aabb(aabb)),
        }
    }

    /// Calls `f` with every obstacle that intersects `shape` at `pose`, until `f` returns true.
    /// Returns whether `f` stopped the walk.
    fn for_each_hit(
        &self,
        pose: &Pose,
        shape: &dyn Shape,
        aabb: &Aabb,
        mut f: impl FnMut(usize) -> bool,
    ) -> bool {
        let mut narrow = |i: usize| -> bool {
            let o = &self.obstacles[i];
            intersects(pose, shape, &o.pose, &*o.shape.0) && f(i)
        };
        match &self.bvh {
            None => {
                for (i, b) in self.aabbs.iter().enumerate() {
                    if aabb_overlap(aabb, b) && narrow(i) {
                        return true;
                    }
                }
                false
            }
            Some(bvh) => {
                for i in bvh.intersect_aabb(aabb) {
                    if narrow(i as usize) {
                        return true;
                    }
                }
                false
            }
        }
    }
}

#[inline]
fn aabb_overlap(a: &Aabb, b: &Aabb) -> bool {
    a.mins.x <= b.maxs.x
        && a.maxs.x >= b.mins.x
        && a.mins.y <= b.maxs.y
        && a.maxs.y >= b.mins.y
        && a.mins.z <= b.maxs.z
        && a.maxs.z >= b.mins.z
}

/// Exact test; pairs parry does not support count as colliding (conservative).
#[inline]
fn intersects(p1: &Pose, s1: &dyn Shape, p2: &Pose, s2: &dyn Shape) -> bool {
    query::intersection_test(p1, s1, p2, s2).map_or(true, |i| i.intersecting)
}

/// An object held by the agent: a shape fixed to one of its links (a tool or hand frame).
#[derive(Clone)]
pub struct HeldObject {
    /// Name (for reports).
    pub name: String,
    /// The object's shape.
    pub shape: SharedShape,
    /// The link it is attached to.
    pub link: usize,
    /// The object's pose in that link's frame (the grasp).
    pub grasp: Pose,
    /// Links the object may touch (the gripper or hand holding it): `touching[l]`.
    touching: Vec<bool>,
    radius: f32,
}

impl fmt::Debug for HeldObject {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.debug_struct("HeldObject")
            .field("name", &self.name)
            .field("link", &self.link)
            .field("grasp", &self.grasp)
            .finish()
    }
}

impl HeldObject {
    /// An object attached to link `link_name` (a gripper's tool frame or a person's hand frame)
    /// at pose `grasp` in that link's frame. It is not checked against the hand holding it:
    /// [`AgentModel::hand_links`] of `link_name` (the palm and the fingers).
    pub fn new(
        model: &AgentModel,
        name: &str,
        shape: SharedShape,
        link_name: &str,
        grasp: Pose,
    ) -> Result<HeldObject, ModelError> {
        let link = model.link_id(link_name)?;
        let hand = model.hand_links(link);
        let touching = (0..model.links().len())
            .map(|l| hand.contains(&l))
            .collect();
        let radius = shape.compute_local_bounding_sphere();
        let radius = radius.center.length() + radius.radius;
        Ok(HeldObject {
            name: name.to_string(),
            shape,
            link,
            grasp,
            touching,
            radius,
        })
    }

    /// Names of the links the object is allowed to touch.
    pub fn touching_links<'a>(&self, model: &'a AgentModel) -> Vec<&'a str> {
        model
            .links()
            .iter()
            .zip(&self.touching)
            .filter(|(_, t)| **t)
            .map(|(l, _)| l.name.as_str())
            .collect()
    }
}

/// What collides with what, by name.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum Contact {
    /// Two links of the agent.
    SelfCollision {
        /// A link.
        link_a: String,
        /// Another link.
        link_b: String,
    },
    /// A link and a scene obstacle.
    Obstacle {
        /// The agent's link.
        link: String,
        /// The obstacle's name.
        obstacle: String,
    },
    /// The held object and a scene obstacle.
    HeldObstacle {
        /// The held object's name.
        object: String,
        /// The obstacle's name.
        obstacle: String,
    },
    /// The held object and a link of the agent.
    HeldLink {
        /// The held object's name.
        object: String,
        /// The agent's link.
        link: String,
    },
    /// Two objects the agent holds (one in each hand).
    HeldObjects {
        /// One held object's name.
        object_a: String,
        /// The other's.
        object_b: String,
    },
}

impl fmt::Display for Contact {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Contact::SelfCollision { link_a, link_b } => {
                write!(f, "self-collision: {link_a} with {link_b}")
            }
            Contact::Obstacle { link, obstacle } => write!(f, "link {link} hits {obstacle}"),
            Contact::HeldObstacle { object, obstacle } => {
                write!(f, "held {object} hits {obstacle}")
            }
            Contact::HeldLink { object, link } => write!(f, "held {object} hits link {link}"),
            Contact::HeldObjects { object_a, object_b } => {
                write!(f, "held {object_a} hits held {object_b}")
            }
        }
    }
}

/// A collision found by a check, as indices.
#[derive(Debug, Clone, Copy)]
enum Hit {
    SelfPair(usize, usize),
    Obstacle(usize, usize),
    /// Held object `k` (0: the one of [`CollisionChecker::set_held_object`], then the others in
    /// the order added) against obstacle `o`.
    HeldObstacle(usize, usize),
    /// Held object `k` against shape `i` of the agent.
    HeldShape(usize, usize),
    /// Held objects `k` and `l` (`k < l`) against each other.
    HeldPair(usize, usize),
}

/// Per-thread buffers so that checks do not allocate.
#[derive(Default)]
struct Scratch {
    links: Vec<Pose>,
    poses: Vec<Pose>,
    aabbs: Vec<Aabb>,
    candidates: Vec<u32>,
    /// World centres of the links' bounding spheres.
    centres: Vec<Vector>,
    /// Per shape, the `generation` of the links its pose and AABB were made from.
    stamps: Vec<u32>,
    /// Counts the link posings.
    generation: u32,
    /// Per shape pair of the self-collision model (`agent`'s address), the axis that last
    /// separated its shapes, in the first shape's frame (zero: none).
    axes: (usize, Vec<Vector>),
}

impl Scratch {
    /// Marks the shapes' poses stale: the links moved.
    fn links_moved(&mut self) {
        self.generation = self.generation.wrapping_add(1);
        if self.generation == 0 {
            // Wrapped: no stamp may equal a later generation by chance.
            self.stamps.fill(0);
            self.generation = 1;
        }
    }

    /// Marks every shape posed for the links as they are.
    fn all_posed(&mut self) {
        self.stamps.clear();
        self.stamps.resize(self.poses.len(), self.generation);
    }

    /// Poses shape `i` (`e`) and its AABB from its link, unless done since the links moved.
    fn pose_shape(&mut self, i: usize, e: &self_collision::ShapeEntry) {
        if self.stamps[i] != self.generation {
            self.poses[i] = self.links[e.link] * e.local_pose;
            self.aabbs[i] = e.aabb(&self.poses[i]);
            self.stamps[i] = self.generation;
        }
    }
}

/// What a posing leaves to the checks: the shapes and the link pairs that may move (all of
/// them without the cache of [`CollisionChecker::set_fixed_joints`]), and the cache used.
type Posed<'a> = (
    &'a [u16],
    &'a [self_collision::PairGroup],
    Option<&'a FixedJoints>,
);

thread_local! {
    static SCRATCH: RefCell<Scratch> = RefCell::new(Scratch::default());
}

/// Collision checks of one agent at a fixed base pose among static obstacles, optionally
/// holding an object. Cheap to clone (shares the models); `Send + Sync`.
#[derive(Clone, Debug)]
pub struct CollisionChecker {
    agent: Arc<SelfCollisionModel>,
    obstacles: Arc<StaticObstacles>,
    base: Pose,
    held: Option<HeldObject>,
    /// Objects held in the agent's other hands (see [`CollisionChecker::add_other_held_object`]).
    other_held: Vec<HeldObject>,
    self_collision: bool,
    fixed: Option<Arc<FixedJoints>>,
}

/// The cached, unmoving part of the agent when only some joints move (see
/// [`CollisionChecker::set_fixed_joints`]).
#[derive(Debug)]
struct FixedJoints {
    /// What it was made for besides the template: the agent, its base and whether
    /// self-collisions are checked.
    agent: Arc<SelfCollisionModel>,
    base: Pose,
    self_collision: bool,
    template: Vec<f32>,
    moving_dofs: Vec<usize>,
    moving_dof: Vec<bool>,
    /// The joints whose child link moves, parents first.
    moving_joints: Vec<usize>,
    link_poses: Vec<Pose>,
    /// The world centres of the links' spheres in the template.
    link_centres: Vec<Vector>,
    shape_poses: Vec<Pose>,
    shape_aabbs: Vec<Aabb>,
    moving_shapes: Vec<u16>,
    /// The pairs of links (groups of [`SelfCollisionModel`]'s pairs) of which one moves.
    moving_groups: Vec<self_collision::PairGroup>,
    /// Collisions among the unmoving shapes and between them and the obstacles.
    static_hits: Vec<Hit>,
}

impl FixedJoints {
    /// Whether it serves `checker` for template `template` with `moving_dofs` moving.
    fn serves(&self, checker: &CollisionChecker, template: &[f32], moving_dofs: &[usize]) -> bool {
        Arc::ptr_eq(&self.agent, &checker.agent)
            && self.base == checker.base
            && self.self_collision == checker.self_collision
            && self.moving_dofs == moving_dofs
            && self.matches(template)
    }

    /// Whether `q` has the template's values on every unmoving joint.
    fn matches(&self, q: &[f32]) -> bool {
        q.len() == self.template.len()
            && q.iter()
                .zip(&self.template)
                .zip(&self.moving_dof)
                .all(|((a, b), m)| *m || a == b)
    }
}

impl CollisionChecker {
    /// A checker for `agent` with base pose `base` among `obstacles`.
    pub fn new(
        agent: Arc<SelfCollisionModel>,
        obstacles: Arc<StaticObstacles>,
        base: Pose,
    ) -> CollisionChecker {
        CollisionChecker {
            agent,
            obstacles,
            base,
            held: None,
            other_held: Vec::new(),
            self_collision: true,
            fixed: None,
        }
    }

    /// Speeds up checks of configurations that differ from `template` only in `moving_dofs`
    /// (an arm moving while the base, torso, head and other arm stay put, as in arm motion
    /// planning): the poses of the unmoving links, their shapes' AABBs and their collisions
    /// with each other and with the obstacles are computed once here. Configurations that differ
    /// from the template elsewhere are still checked in full, so answers never change, only
    /// speed. Moving the base or switching self-collision recomputes the cache.
    ///
    /// # Panics
    /// If `template.len()` is not the model's number of degrees of freedom or a dof index is
    /// out of range.
    pub fn set_fixed_joints(&mut self, template: &[f32], moving_dofs: &[usize]) {
        self.fixed = None;
        let model = &self.agent.model;
        assert_eq!(template.len(), model.dof(), "template length");
        let kept = (self.obstacles.fixed).find(|f| f.serves(self, template, moving_dofs));
        if let Some(f) = kept {
            self.fixed = Some(f);
            return;
        }
        let mut moving_dof = vec![false; model.dof()];
        for &d in moving_dofs {
            moving_dof[d] = true;
        }
        let mut moving_link = vec![false; model.links().len()];
        for (j, joint) in model.joints().iter().enumerate() {
            let dof = joint
                .dof
                .or_else(|| joint.mimic.and_then(|m| model.joints()[m.master].dof));
            moving_link[j + 1] = moving_link[joint.parent] || dof.is_some_and(|d| moving_dof[d]);
        }
        let shapes = &self.agent.shapes;
        let moving = |i: u16| moving_link[shapes[i as usize].link];
        let (moving_shapes, unmoving_shapes): (Vec<u16>, Vec<u16>) =
            (0..shapes.len() as u16).partition(|&i| moving(i));
        let (moving_groups, unmoving_groups): (Vec<_>, Vec<_>) = self
            .agent
            .groups
            .iter()
            .copied()
            .partition(|g| moving_link[g.a as usize] || moving_link[g.b as usize]);
        // The unmoving part's collisions, found once: its shapes against the obstacles and
        // each other (not the held objects: they move with the hand).
        let mut static_hits = Vec::new();
        let moving_joints = (0..model.joints().len())
            .filter(|&j| moving_link[j + 1])
            .collect();
        let (link_poses, link_centres, shape_poses, shape_aabbs) = SCRATCH.with(|scratch| {
            let mut s = scratch.borrow_mut();
            self.pose_into(template, &mut s);
            let parts = (&unmoving_shapes[..], &unmoving_groups[..]);
            self.check_posed(&mut s, template, parts, false, |h| {
                static_hits.push(h);
                false
            });
            (
                s.links.clone(),
                s.centres.clone(),
                s.poses.clone(),
                s.aabbs.clone(),
            )
        });
        let fixed = Arc::new(FixedJoints {
            agent: self.agent.clone(),
            base: self.base,
            self_collision: self.self_collision,
            template: template.to_vec(),
            moving_dofs: moving_dofs.to_vec(),
            moving_dof,
            moving_joints,
            link_poses,
            link_centres,
            shape_poses,
            shape_aabbs,
            moving_shapes,
            moving_groups,
            static_hits,
        });
        self.obstacles.fixed.keep(fixed.clone());
        self.fixed = Some(fixed);
    }

    /// Drops the cache made by [`CollisionChecker::set_fixed_joints`].
    pub fn clear_fixed_joints(&mut self) {
        self.fixed = None;
    }

    fn refresh_fixed(&mut self) {
        if let Some(f) = self.fixed.take() {
            self.set_fixed_joints(&f.template, &f.moving_dofs);
        }
    }

    /// The same checker with an object held (replacing any other).
    ///
    /// # Panics
    /// If `held` was made for another agent model.
    pub fn with_held_object(mut self, held: HeldObject) -> CollisionChecker {
        self.set_held_object(Some(held));
        self
    }

    /// Sets or clears the held object.
    ///
    /// # Panics
    /// If `held` was made for another agent model.
    pub fn set_held_object(&mut self, held: Option<HeldObject>) {
        if let Some(h) = &held {
            assert!(
                h.touching.len() == self.agent.model.links().len(),
                "held object '{}' was made for another agent model than '{}'",
                h.name,
                self.agent.model.name()
            );
        }
        self.held = held;
    }

    /// Adds an object held in another hand of the agent (a second gripper's): checked like the
    /// held object, against the scene and every link but its own hand's, so that a moving arm
    /// does not pass through what the other arm holds.
    ///
    /// # Panics
    /// If `held` was made for another agent model.
    pub fn add_other_held_object(&mut self, held: HeldObject) {
        assert!(
            held.touching.len() == self.agent.model.links().len(),
            "held object '{}' was made for another agent model than '{}'",
            held.name,
            self.agent.model.name()
        );
        self.other_held.push(held);
    }

    /// Turns self-collision checks on or off (on by default).
    pub fn set_self_collision(&mut self, on: bool) {
        self.self_collision = on;
        self.refresh_fixed();
    }

    /// Moves the agent's base.
    pub fn set_base(&mut self, base: Pose) {
        self.base = base;
        self.refresh_fixed();
    }

    /// The agent's base pose.
    pub fn base(&self) -> Pose {
        self.base
    }

    /// The agent model.
    pub fn model(&self) -> &Arc<AgentModel> {
        &self.agent.model
    }

    /// The self-collision model.
    pub fn self_collision_model(&self) -> &Arc<SelfCollisionModel> {
        &self.agent
    }

    /// The obstacles.
    pub fn obstacles(&self) -> &Arc<StaticObstacles> {
        &self.obstacles
    }

    /// The held object, if any.
    pub fn held_object(&self) -> Option<&HeldObject> {
        self.held.as_ref()
    }

    /// Whether configuration `q` is free of collisions (stops at the first one found).
    ///
    /// # Panics
    /// If `q.len()` is not the model's number of degrees of freedom.
    pub fn is_config_free(&self, q: &[f32]) -> bool {
        let mut found = false;
        self.check(q, |_| {
            found = true;
            true
        });
        !found
    }

    /// The first collision found in configuration `q`, or `None` if it is free.
    pub fn first_collision(&self, q: &[f32]) -> Option<Contact> {
        let mut hit = None;
        self.check(q, |h| {
            hit = Some(h);
            true
        });
        hit.map(|h| self.contact(h))
    }

    /// The first collision in configuration `q` of a link outside `exempt` (link indices; a
    /// self-collision counts unless both links are exempt), or `None`. For an open gripper
    /// around the object it grasps: its hand may touch the object, the rest of the arm not.
    pub fn first_collision_except(&self, q: &[f32], exempt: &[usize]) -> Option<Contact> {
        let link = |s: usize| self.agent.shapes[s].link;
        let counts = |h: Hit| match h {
            Hit::Obstacle(s, _) | Hit::HeldShape(_, s) => !exempt.contains(&link(s)),
            Hit::SelfPair(a, b) => !(exempt.contains(&link(a)) && exempt.contains(&link(b))),
            Hit::HeldObstacle(..) | Hit::HeldPair(..) => true,
        };
        let mut hit = None;
        self.check(q, |h| {
            let found = counts(h);
            if found {
                hit = Some(h);
            }
            found
        });
        hit.map(|h| self.contact(h))
    }

    /// Every collision in configuration `q`.
    pub fn collisions(&self, q: &[f32]) -> Vec<Contact> {
        let mut hits = Vec::new();
        self.check(q, |h| {
            hits.push(h);
            false
        });
        hits.into_iter().map(|h| self.contact(h)).collect()
    }

    fn contact(&self, h: Hit) -> Contact {
        let links = self.agent.model.links();
        let shape_link = |s: usize| links[self.agent.shapes[s].link].name.clone();
        let held = |k: usize| {
            self.held
                .iter()
                .chain(&self.other_held)
                .nth(k)
                .map(|o| o.name.clone())
                .unwrap_or_default()
        };
        match h {
            Hit::SelfPair(a, b) => Contact::SelfCollision {
                link_a: shape_link(a),
                link_b: shape_link(b),
            },
            Hit::Obstacle(s, o) => Contact::Obstacle {
                link: shape_link(s),
                obstacle: self.obstacles.obstacles[o].name.clone(),
            },
            Hit::HeldObstacle(k, o) => Contact::HeldObstacle {
                object: held(k),
                obstacle: self.obstacles.obstacles[o].name.clone(),
            },
            Hit::HeldShape(k, s) => Contact::HeldLink {
                object: held(k),
                link: shape_link(s),
            },
            Hit::HeldPair(k, l) => Contact::HeldObjects {
                object_a: held(k),
                object_b: held(l),
            },
        }
    }

    /// Poses the agent's links and shapes for `q` into `s`, through the cache of
    /// [`CollisionChecker::set_fixed_joints`] where `q` matches it.
    fn pose_into<'a>(&'a self, q: &[f32], s: &mut Scratch) -> Posed<'a> {
        let posed = self.pose_links_into(q, s);
        let shapes = &self.agent.shapes;
        match posed.2 {
            Some(f) => {
                s.poses.clear();
                s.poses.extend_from_slice(&f.shape_poses);
                s.aabbs.clear();
                s.aabbs.extend_from_slice(&f.shape_aabbs);
            }
            None => {
                s.poses.resize(shapes.len(), Pose::IDENTITY);
                s.aabbs.resize(shapes.len(), Aabb::new_invalid());
            }
        }
        // A link's shapes come together: its rotation matrix serves them all.
        let mut abs = (usize::MAX, Mat3::IDENTITY);
        for &i in posed.0 {
            let (i, e) = (i as usize, &shapes[i as usize]);
            let link = &s.links[e.link];
            if abs.0 != e.link && e.bounded_in_link() {
                abs = (e.link, Mat3::from_quat(link.rotation).abs());
            }
            s.poses[i] = *link * e.local_pose;
            s.aabbs[i] = e.aabb_on_link(&s.poses[i], link, &abs.1);
        }
        s.all_posed();
        posed
    }

    /// [`CollisionChecker::pose_into`] for the links alone (and their spheres' centres): the
    /// shapes' poses are left stale, to be made by [`Scratch::pose_shape`] where needed.
    fn pose_links_into<'a>(&'a self, q: &[f32], s: &mut Scratch) -> Posed<'a> {
        let model = &self.agent.model;
        let fixed = self.fixed.as_deref().filter(|f| f.matches(q));
        let (links, centres) = (&mut s.links, &mut s.centres);
        let spheres = &self.agent.link_spheres;
        let (moving, groups): (&[u16], &[self_collision::PairGroup]) = match fixed {
            Some(f) => {
                links.clear();
                links.extend_from_slice(&f.link_poses);
                centres.clear();
                centres.extend_from_slice(&f.link_centres);
                let joints = model.joints();
                for &j in &f.moving_joints {
                    let joint = &joints[j];
                    links[j + 1] = links[joint.parent] * joint.transform(model.joint_value(j, q));
                    centres[j + 1] = links[j + 1] * spheres[j + 1].0;
                }
                (&f.moving_shapes, &f.moving_groups)
            }
            None => {
                model.link_poses_into(self.base, q, links);
                centres.clear();
                centres.extend(links.iter().zip(spheres).map(|(l, (c, _))| *l * *c));
                (&self.agent.all_shapes, &self.agent.groups)
            }
        };
        s.links_moved();
        (moving, groups, fixed)
    }

    /// Runs the checks, calling `report` for each collision until it returns true.
    fn check(&self, q: &[f32], mut report: impl FnMut(Hit) -> bool) {
        SCRATCH.with(|scratch| {
            let mut guard = scratch.borrow_mut();
            let (moving, groups, fixed) = self.pose_into(q, &mut guard);
            if let Some(f) = fixed {
                for &h in &f.static_hits {
                    if report(h) {
                        return;
                    }
                }
            }
            self.check_posed(&mut guard, q, (moving, groups), true, report);
        });
    }

    /// The checks of shapes `moving` against the obstacles and of the pairs of links `groups`,
    /// and where `with_held`, of the held objects, the agent posed at `q` in `s`; `report` is
    /// called for each collision until it returns true.
    fn check_posed(
        &self,
        s: &mut Scratch,
        q: &[f32],
        (moving, groups): (&[u16], &[self_collision::PairGroup]),
        with_held: bool,
        mut report: impl FnMut(Hit) -> bool,
    ) {
        let model_id = Arc::as_ptr(&self.agent) as usize;
        if s.axes.0 != model_id || s.axes.1.len() != self.agent.pairs.len() {
            s.axes = (model_id, vec![Vector::ZERO; self.agent.pairs.len()]);
        }
        let Scratch {
            links,
            poses,
            aabbs,
            candidates,
            centres,
            axes,
            ..
        } = s;
        let axes = &mut axes.1;
        let shapes = &self.agent.shapes;
        // Agent against the scene: first the obstacles near the moving shapes, then per shape.
        if !self.obstacles.is_empty() && !moving.is_empty() {
            let mut all = aabbs[moving[0] as usize];
            for &i in &moving[1..] {
                let b = &aabbs[i as usize];
                all.mins = all.mins.min(b.mins);
                all.maxs = all.maxs.max(b.maxs);
            }
            self.obstacles.candidates(&all, candidates);
            for &i in moving {
                let (i, s) = (i as usize, &shapes[i as usize]);
                for &o in candidates.iter() {
                    let o = o as usize;
                    let obstacle = &self.obstacles.obstacles[o];
                    if aabb_overlap(&aabbs[i], &self.obstacles.aabbs[o])
                        && s.hits_by_gjk(&poses[i], &*obstacle.shape.0, &obstacle.pose)
                        && report(Hit::Obstacle(i, o))
                    {
                        return;
                    }
                }
            }
        }
        // Self-collision.
        if self.self_collision {
            let spheres = &self.agent.link_spheres;
            let pairs = &self.agent.pairs;
            for g in groups {
                let (ra, rb) = (spheres[g.a as usize].1, spheres[g.b as usize].1);
                let d = centres[g.a as usize] - centres[g.b as usize];
                if d.length_squared() > (ra + rb) * (ra + rb)
                    || self.agent.capsule_gap(g, links) > 0.0
                {
                    continue;
                }
                // The group's shape pairs (indices into `pairs`) that its cells leave to test.
                let (start, end) = (g.start as usize, g.end as usize);
                let only = match self.agent.cell_proof(g, q) {
                    CellProof::Apart => continue,
                    CellProof::Only(list) => Some(list),
                    CellProof::All => None,
                };
                let listed = only.into_iter().flatten().map(|&k| start + k as usize);
                let whole = (start..end).filter(|_| only.is_none());
                for k in listed.chain(whole) {
                    let (a, b) = (pairs[k].0 as usize, pairs[k].1 as usize);
                    let r = shapes[a].radius + shapes[b].radius;
                    if (poses[a].translation - poses[b].translation).length_squared() > r * r {
                        continue;
                    }
                    if !aabb_overlap(&aabbs[a], &aabbs[b])
                        || shapes[a].capsule_gap(
                            &links[shapes[a].link],
                            &shapes[b],
                            &links[shapes[b].link],
                        ) > 0.0
                    {
                        continue;
                    }
                    let axis = &mut axes[k];
                    if shapes[a].hits_shape_with_axis(&poses[a], &shapes[b], &poses[b], axis)
                        && report(Hit::SelfPair(a, b))
                    {
                        return;
                    }
                }
            }
        }
        if !with_held {
            return;
        }
        // The held objects against the scene and the agent.
        for (k, held) in self.held.iter().chain(&self.other_held).enumerate() {
            let p = links[held.link] * held.grasp;
            let aabb = held.shape.compute_aabb(&p);
            let stop = self.obstacles.for_each_hit(&p, &*held.shape.0, &aabb, |o| {
                report(Hit::HeldObstacle(k, o))
            });
            if stop {
                return;
            }
            let centre = p.translation;
            for (i, s) in shapes.iter().enumerate() {
                if held.touching[s.link] {
                    continue;
                }
                let r = s.radius + held.radius;
                if (poses[i].translation - centre).length_squared() > r * r
                    || !aabb_overlap(&aabbs[i], &aabb)
                {
                    continue;
                }
                if s.hits(&poses[i], &*held.shape.0, &p) && report(Hit::HeldShape(k, i)) {
                    return;
                }
            }
        }
        // The held objects against each other (what one hand carries past the other's).
        let all = || self.held.iter().chain(&self.other_held);
        for (k, a) in all().enumerate() {
            let pa = links[a.link] * a.grasp;
            for (l, b) in all().enumerate().skip(k + 1) {
                let pb = links[b.link] * b.grasp;
                if intersects(&pa, &*a.shape.0, &pb, &*b.shape.0) && report(Hit::HeldPair(k, l)) {
                    return;
                }
            }
        }
    }
}

/// World poses and shapes of an agent's collision geometry in configuration `q`, as obstacles
/// named `"{prefix}/{link}"`: for putting another agent (the human, seen by the robot) into a
/// [`StaticObstacles`] set.
pub fn agent_obstacles(model: &AgentModel, base: Pose, q: &[f32], prefix: &str) -> Vec<Obstacle> {
    model
        .posed_shapes(base, q)
        .into_iter()
        .map(|(link, c, pose)| Obstacle {
            name: format!("{prefix}/{}", model.links()[link].name),
            pose,
            shape: c.shape.clone(),
        })
        .collect()
}
