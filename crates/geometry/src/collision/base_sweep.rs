//! One configuration of the joints checked at many base poses (a navigation's search of the
//! free floor). Moving the base alone moves the robot and what it holds rigidly: what collides
//! among them is the same at every base pose and is checked once, and the robot is posed once,
//! in its base frame. At a base pose, the obstacles whose boxes meet the box holding it all
//! are tested against the shapes their boxes meet (boxes compared in the base frame), by the
//! full check's exact tests; where no obstacle's box meets it, nothing in the scene can touch
//! it. The answers are the full check's but where the robot is within the exact tests'
//! tolerance of an obstacle (a fraction of a millimetre: their poses are composed in another
//! order, and GJK may call shapes that near either way).

use parry3d::bounding_volume::{Aabb, BoundingVolume};
use parry3d::math::{Pose, Vector};
use std::sync::Arc;

use super::{CollisionChecker, StaticObstacles, aabb_overlap, intersects};

/// How much the robot's box is widened (metres): an obstacle's box this far from it is apart
/// from the robot by more than the exact tests' tolerance.
const SWEEP_MARGIN: f32 = 1e-3;

/// A checker for one joint configuration at many base poses; see the module docs.
pub struct BaseSweep {
    checker: CollisionChecker,
    /// Each collision shape's pose and box in the base frame, in the model's order.
    shapes: Vec<(Pose, Aabb)>,
    /// Each held object's pose and box in the base frame.
    held: Vec<(Pose, Aabb)>,
    /// The box holding the robot and its held objects, in the base frame (widened).
    bounds: Aabb,
    /// Whether the robot and its held objects are free of each other (the same at every base).
    free_alone: bool,
    candidates: Vec<u32>,
}

impl CollisionChecker {
    /// A checker of configuration `q` at any base pose, answering as
    /// [`CollisionChecker::is_config_free`] does with the base set there.
    ///
    /// # Panics
    /// If `q.len()` is not the model's number of degrees of freedom.
    pub fn base_sweep(&self, q: &[f32]) -> BaseSweep {
        let mut links = Vec::new();
        self.agent
            .model
            .link_poses_into(Pose::IDENTITY, q, &mut links);
        let posed =
            |pose: Pose, shape: &parry3d::shape::SharedShape| (pose, shape.compute_aabb(&pose));
        let shapes: Vec<(Pose, Aabb)> = (self.agent.shapes.iter())
            .map(|e| posed(links[e.link] * e.local_pose, &e.shape))
            .collect();
        let held: Vec<(Pose, Aabb)> = (self.held.iter().chain(&self.other_held))
            .map(|h| posed(links[h.link] * h.grasp, &h.shape))
            .collect();
        let mut bounds = Aabb::new_invalid();
        for (_, aabb) in shapes.iter().chain(&held) {
            bounds.merge(aabb);
        }
        let mut alone = self.clone();
        alone.obstacles = Arc::new(StaticObstacles::empty());
        alone.fixed = None;
        BaseSweep {
            checker: self.clone(),
            shapes,
            held,
            bounds: bounds.loosened(SWEEP_MARGIN),
            free_alone: alone.is_config_free(q),
            candidates: Vec::new(),
        }
    }
}

impl BaseSweep {
    /// Whether the configuration is free with the base at `base`.
    pub fn is_free_at(&mut self, base: Pose) -> bool {
        if !self.free_alone {
            return false;
        }
        let obstacles = &self.checker.obstacles;
        obstacles.candidates(&world_box(&self.bounds, &base), &mut self.candidates);
        let in_base = base.inverse();
        let entries = &self.checker.agent.shapes;
        let held = self.checker.held.iter().chain(&self.checker.other_held);
        // Boxes compared in the base frame (widened: rounding must not part what the full
        // check's boxes would join), exact tests in the world frame, as the full check's.
        !self.candidates.iter().any(|&o| {
            let o = &obstacles.obstacles[o as usize];
            let aabb = o
                .shape
                .compute_aabb(&(in_base * o.pose))
                .loosened(SWEEP_MARGIN);
            let shape = &*o.shape.0;
            let hits_shape = self.shapes.iter().zip(entries).any(|((at, b), e)| {
                aabb_overlap(b, &aabb) && e.hits_by_gjk(&(base * *at), shape, &o.pose)
            });
            hits_shape
                || self.held.iter().zip(held.clone()).any(|((at, b), h)| {
                    aabb_overlap(b, &aabb) && intersects(&(base * *at), &*h.shape.0, &o.pose, shape)
                })
        })
    }
}

/// The world box holding `bounds` (a box in the base frame) with the base at `base`.
fn world_box(bounds: &Aabb, base: &Pose) -> Aabb {
    let (lo, hi) = (bounds.mins, bounds.maxs);
    let mut world = Aabb::new_invalid();
    for k in 0..8 {
        let pick = |bit: usize, l: f32, h: f32| if k & bit == 0 { l } else { h };
        let corner = Vector::new(
            pick(1, lo.x, hi.x),
            pick(2, lo.y, hi.y),
            pick(4, lo.z, hi.z),
        );
        world.take_point(*base * corner);
    }
    world
}
