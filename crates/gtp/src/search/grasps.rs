//! The grasp choices of a search (an arm and a grasp of the object's grasp set, or the grasp
//! the robot already holds) and their cheap tests at a candidate point: the arm's reach and the
//! gripper's boxes, before any grasp is picked up.

use geometry::collision::StaticObstacles;
use geometry::scene::ObjectId;
use geometry::world::World;
use parry3d::bounding_volume::BoundingVolume;
use parry3d::math::{Pose, Vector};
use parry3d::shape::{Cuboid, Shape};

use crate::grasp::Grasp;
use crate::gripper::GripperModel;
use crate::planner::{PlannerConfig, Task};
use crate::robot::{self, RobotSetup};
use crate::task::TaskKind;

use super::verdicts::Verdict;
use super::{Obstacles, Search};

/// A grasp choice: an arm and a grasp (object frame), or the grasp the robot already holds.
#[derive(Clone, Copy, Debug)]
pub(super) struct Choice {
    pub(super) arm: usize,
    pub(super) grasp: Grasp,
    /// Tool frame in the object's frame.
    pub(super) tool_in_object: Pose,
}

/// What a search's grasp choices start from: the choices, whether the object is held already,
/// the arms left out, and what the object rests on.
#[derive(Debug, Default)]
pub(super) struct GraspChoices {
    pub(super) choices: Vec<Choice>,
    pub(super) held: bool,
    /// The robot's arms left out because their grippers hold something else.
    pub(super) busy_arms: Vec<String>,
    /// Obstacles the object touches where it rests (left unchecked at the start of the lift).
    pub(super) resting_on: Vec<String>,
}

impl GraspChoices {
    /// The choices for task `task` on object `o`: the held grasp when the robot holds `o`, else
    /// (but for navigate-to and take) every grasp of the object's set with every free arm.
    /// Errs when `o` cannot be moved or someone else holds it.
    pub(super) fn new(
        cfg: &PlannerConfig,
        setup: &RobotSetup,
        world: &World,
        task: &Task,
        o: ObjectId,
        obstacles: &Obstacles,
    ) -> Result<GraspChoices, String> {
        let model = world.object(o);
        if !model.movable && task.kind != TaskKind::NavigateTo {
            return Err(format!("object `{}` is not movable", model.name));
        }
        let mut out = GraspChoices::default();
        if let Some(att) = world.attachment(o) {
            if att.agent != setup.agent {
                return Err(format!(
                    "object `{}` is held by {}",
                    model.name,
                    world.agent(att.agent).name()
                ));
            }
            out.choices
                .push(held_choice(setup, world, o, att.link, att.grasp)?);
            out.held = true;
        } else if task.kind != TaskKind::NavigateTo && task.kind != TaskKind::Take {
            for (ai, a) in setup.arms.iter().enumerate() {
                // A gripper already holding something cannot grasp the object.
                if let Some((other, ..)) =
                    robot::in_grippers(world, setup).find(|(_, by, _)| by.tool_link == a.tool_link)
                {
                    out.busy_arms
                        .push(format!("{} holds `{}`", a.name, world.object(other).name));
                    continue;
                }
                let set = cfg
                    .grasps
                    .grasps(&*model.shape, &a.gripper)
                    .map_err(|e| e.to_string())?;
                for g in &set.grasps {
                    out.choices.push(Choice {
                        arm: ai,
                        grasp: *g,
                        tool_in_object: model.shape_offset * g.tool_in_object,
                    });
                }
            }
            out.resting_on = resting_on(world, o, &obstacles.workspace_but_object);
        }
        Ok(out)
    }
}

/// The choice of an object the robot holds with the tool of link `link`, at `grasp` (the
/// object's pose in the tool frame).
fn held_choice(
    setup: &RobotSetup,
    world: &World,
    o: ObjectId,
    link: usize,
    grasp: Pose,
) -> Result<Choice, String> {
    let model = world.object(o);
    let arm = setup
        .arms
        .iter()
        .position(|a| a.tool_link == link)
        .ok_or_else(|| {
            format!(
                "object `{}` is held by a link that is no arm's tool",
                model.name
            )
        })?;
    let tool_in_object = grasp.inverse();
    let gripper = &setup.arms[arm].gripper;
    let max_opening = gripper.max_opening;
    // The grasp's width is the jaws' opening now: carried, the object stays gripped as it is.
    // A hand without a finger joint: the object's extent along the tool's y, the axis the
    // jaws close along (its box's, exact for the boxes' axis-aligned grasps).
    let q = &world.agent_state(setup.agent).q;
    let width = match setup.arms[arm].gripper_dof {
        Some(k) => gripper.opening_at(q[k]),
        None => {
            let close = (tool_in_object.rotation * Vector::Y).abs();
            (2.0 * close.dot(model.local_aabb.half_extents())).min(max_opening)
        }
    };
    Ok(Choice {
        arm,
        grasp: Grasp {
            id: usize::MAX,
            tool_in_object,
            width,
            opening: (width + 0.02).min(max_opening),
            score: 0.0,
        },
        tool_in_object,
    })
}

/// The obstacles object `o` touches (or is within 2 mm of) where it rests.
fn resting_on(world: &World, o: ObjectId, obstacles: &StaticObstacles) -> Vec<String> {
    let model = world.object(o);
    let pose = world.object_shape_pose(o);
    let aabb = model.shape.compute_aabb(&pose).loosened(0.002);
    let mut out = Vec::new();
    for ob in obstacles.obstacles() {
        let hit = parry3d::query::intersection_test(&pose, &*model.shape, &ob.pose, &*ob.shape)
            .map(|h| h.intersecting)
            .unwrap_or(true);
        let near = ob.shape.compute_aabb(&ob.pose).intersects(&aabb);
        if hit || (near && touching(&*model.shape, &pose, &*ob.shape, &ob.pose)) {
            out.push(ob.name.clone());
        }
    }
    out
}

/// Whether two shapes are within 2 mm of each other.
fn touching(a: &dyn Shape, pa: &Pose, b: &dyn Shape, pb: &Pose) -> bool {
    parry3d::query::distance(pa, a, pb, b)
        .map(|d| d.distance <= 0.002)
        .unwrap_or(true)
}

/// The first obstacle (its name) that the `gripper`'s boxes, open by `opening`, hit with the
/// tool frame at `tool`; `None` when they are free.
pub(super) fn gripper_hits(
    gripper: &GripperModel,
    tool: &Pose,
    opening: f32,
    obstacles: &StaticObstacles,
) -> Option<String> {
    let g = gripper.at(opening);
    for (local, cuboid) in &g.boxes {
        let pose = *tool * *local;
        let aabb = cuboid.compute_aabb(&pose);
        if let Some(i) = obstacles.first_hit(&pose, cuboid as &Cuboid, &aabb) {
            return Some(obstacles.obstacles()[i].name.clone());
        }
    }
    None
}

impl Search {
    /// Whether `arm` may reach an object at point `p` at all (its tool within the arm's reach
    /// from the shoulder, with the object's size as slack): a cheap test before any grasp.
    pub(super) fn arm_may_reach_point(&self, arm: usize, p: Vector) -> bool {
        if self.task.kind == TaskKind::Pick {
            return true;
        }
        let a = &self.setup.arms[arm];
        let slack = self
            .object
            .map(|o| self.world.object(o).local_aabb.half_extents().length())
            .unwrap_or(0.0);
        let shoulder = self.arm_shoulders[arm];
        (p - shoulder).length() <= a.wrist_reach + a.wrist_to_tool + slack + 0.05
    }

    /// Whether grasp choice `grasp` could place the object in some orientation at the cursor's
    /// point: an orientation not already failed, whose tool pose is within the arm's reach and
    /// whose gripper boxes are free. Cheap (box tests), so that a grasp is not picked up for a
    /// point where it cannot be used.
    pub(super) fn choice_fits_point(&self, grasp: usize) -> bool {
        if self.task.kind == TaskKind::Pick {
            return true;
        }
        let ch = self.choices[grasp];
        let arm = &self.setup.arms[ch.arm];
        let shoulder = self.arm_shoulders[ch.arm];
        let orients = self.cursor.orientations.as_deref().unwrap_or(&[]);
        let placing = self.task.kind.places();
        for (oidx, orient) in orients.iter().enumerate() {
            if placing && self.verdict(self.cursor.placement(oidx)) == Some(Verdict::Failed) {
                continue;
            }
            let tool = orient.pose * ch.tool_in_object;
            if arm.may_reach(shoulder, &tool)
                && gripper_hits(
                    &arm.gripper,
                    &tool,
                    ch.grasp.width,
                    &self.obstacles.workspace_but_object,
                )
                .is_none()
            {
                return true;
            }
        }
        false
    }
}
