//! The object's orientations at a candidate point (its stable resting faces x yaws, or turns
//! in the air for a hand-over), collision-free and least turn first; and the world after a
//! placement, the object settled on its surface.

use geometry::scene::ObjectId;
use geometry::world::World;
use parry3d::math::{Pose, Rotation, Vector};

use crate::task::TaskKind;

use super::{Search, Stage};

/// Gap left under a placed object once it has settled on its surface (metres): contact, with
/// a margin for rounding.
const SETTLED_GAP: f32 = 0.0002;

/// A candidate orientation at a point: the object's pose there.
#[derive(Clone, Copy, Debug)]
pub(super) struct Orientation {
    pub(super) pose: Pose,
    /// Index of the resting face.
    pub(super) face: usize,
    /// Index of the yaw about the vertical.
    pub(super) yaw_index: usize,
}

impl Search {
    /// Collision-free orientations of the object at `p`.
    pub(super) fn orientations_at(&mut self, p: Vector) -> Vec<Orientation> {
        let Some(o) = self.object else {
            return Vec::new();
        };
        if self.task.kind == TaskKind::Pick {
            return vec![Orientation {
                pose: self.world.object_pose(o),
                face: 0,
                yaw_index: 0,
            }];
        }
        let model = self.world.object(o).clone();
        let offset_inv = model.shape_offset.inverse();
        let com = crate::grasp::centre_of_mass(&*model.shape);
        let mut out = Vec::new();
        let faces = self.faces.clone();
        let yaws = self.cfg.placement.yaws.max(1);
        for (fi, f) in faces.iter().enumerate() {
            for yi in 0..yaws {
                let yaw = std::f32::consts::TAU * yi as f32 / yaws as f32;
                let shape_pose = if self.task.kind.hands_over() {
                    let r = Rotation::from_rotation_z(yaw) * f.rotation;
                    Pose::from_parts(p - r * com, r)
                } else {
                    f.pose_at(p, yaw, self.cfg.placement.clearance)
                };
                let aabb = model.shape.compute_aabb(&shape_pose);
                let obstacles = &self.obstacles.workspace_but_object;
                if let Some(hit) = obstacles.first_hit(&shape_pose, &*model.shape, &aabb) {
                    let name = obstacles.obstacles()[hit].name.clone();
                    let oname = model.name.clone();
                    self.reject(Stage::ObjectCollision, || {
                        format!("every orientation of `{oname}` collides (last with `{name}`)")
                    });
                    continue;
                }
                out.push(Orientation {
                    pose: shape_pose * offset_inv,
                    face: fi,
                    yaw_index: yi,
                });
            }
        }
        // The least turn of the object first: its grasp, fixed in the object, then asks the
        // least turn of the wrist, and the carry is the shorter for it.
        let now = self.world.object_pose(o).rotation;
        let turn = |r: Rotation| now.angle_between(r);
        out.sort_by(|a, b| turn(a.pose.rotation).total_cmp(&turn(b.pose.rotation)));
        out
    }

    /// The world after a placement: object `o` settled from its release `pose` onto the
    /// surface, the robot in its starting posture.
    pub(super) fn placed_world(&self, o: ObjectId, pose: Pose) -> World {
        let mut after = self.released_world(o, pose);
        after.set_object_pose(o, self.settled(pose));
        after
    }

    /// The world with object `o` at its release `pose` (not yet settled), the robot in its
    /// starting posture: what the human-related constraints of a placement are first
    /// measured in.
    pub(super) fn released_world(&self, o: ObjectId, pose: Pose) -> World {
        let mut after = self.world.clone();
        let robot = self.setup.agent;
        let base = after.agent_state(robot).base;
        after.set_agent_config(robot, base, &self.q0_full);
        after.set_object_pose(o, pose);
        after
    }

    /// Where an object released at `pose` (the placement's clearance above its surface) comes
    /// to rest: [`SETTLED_GAP`] above the surface, straight below.
    pub(super) fn settled(&self, pose: Pose) -> Pose {
        let drop = (self.cfg.placement.clearance - SETTLED_GAP).max(0.0);
        Pose::from_parts(pose.translation - Vector::Z * drop, pose.rotation)
    }

    /// The support whose surface `p` lies on (within 2 cm, the nearest), by name.
    pub(super) fn support_under(&self, p: Vector) -> Option<String> {
        let mut best: Option<(f32, String)> = None;
        for id in self.world.object_ids() {
            if Some(id) == self.object {
                continue;
            }
            let pose = self.world.object_pose(id);
            for s in &self.world.object(id).surfaces {
                let l = pose.inverse_transform_point(p) - s.centre;
                if l.x.abs() <= s.half_extents[0] + 1e-3
                    && l.y.abs() <= s.half_extents[1] + 1e-3
                    && l.z.abs() < 0.02
                {
                    let d = l.z.abs();
                    if best.as_ref().is_none_or(|b| d < b.0) {
                        best = Some((d, self.world.object(id).name.clone()));
                    }
                }
            }
        }
        best.map(|b| b.1)
    }
}
