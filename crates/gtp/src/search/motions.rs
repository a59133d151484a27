//! The arm motions of one grasp choice, built once per choice ([`GraspMotions`]): the arm, its
//! starting values, the gripper open (by the grasp's opening) or closed (to its width), the
//! object held at the grasp and what the other grippers hold. A motion against one obstacle set
//! is then one call ([`GraspMotions::open`], [`GraspMotions::closed`],
//! [`GraspMotions::holding`]), and so is the record of a trajectory ([`GraspMotions::record`]).

use std::sync::Arc;

use geometry::collision::{HeldObject, Obstacle, StaticObstacles};
use geometry::scene::ObjectId;
use parry3d::math::Pose;
use parry3d::shape::SharedShape;

use crate::robot::{self, Arm, ArmMotion, RobotSetup, set_opening};
use crate::rrt::JointPath;
use crate::solution::{HeldRecord, Phase, Trajectory};

use super::Search;
use super::grasps::Choice;

/// The gripper during a recorded trajectory.
#[derive(Clone, Debug)]
pub(super) enum Grip {
    /// Open, clear of the object.
    Open,
    /// Open around the object (moving in to grasp it or out after letting it go): the object
    /// is left out of the obstacles, and, at `Some(pose)`, the gripper certified clear of it.
    Around(Option<Pose>),
    /// Closed on the object, carrying it; the named obstacles left unchecked (what the object
    /// rested on, at the start of the lift).
    Holding(Vec<String>),
}

/// What every motion of one grasp choice shares, built once per choice.
pub(super) struct GraspMotions {
    setup: Arc<RobotSetup>,
    /// Index of the arm in `setup.arms`.
    arm: usize,
    /// The robot's base (it does not move during an arm task).
    base: Pose,
    /// The robot's joint values at the start, the gripper open by the grasp's opening.
    open_template: Vec<f32>,
    /// The same, the gripper closed to the grasp's width.
    closed_template: Vec<f32>,
    /// The object held at the grasp.
    held: HeldObject,
    /// The objects the other arms' grippers hold (they stay where they are).
    others: Vec<HeldObject>,
    /// The arm's values at the start.
    pub(super) q0: Vec<f32>,
    /// The grasp's jaw opening while moving in or out, and its width on the object.
    pub(super) opening: f32,
    pub(super) width: f32,
    /// The object's pose in the tool frame.
    pub(super) object_in_tool: Pose,
    agent_name: String,
    object_name: String,
}

impl GraspMotions {
    /// The motions of choice `ch` of object `o` in `search`'s starting world.
    fn new(search: &Search, ch: Choice, o: ObjectId) -> Result<GraspMotions, String> {
        let setup = search.setup.clone();
        let world = &search.world;
        let a = &setup.arms[ch.arm];
        let object_in_tool = ch.tool_in_object.inverse();
        let held = robot::held_object(world, &setup, a, o, object_in_tool)?;
        let others = robot::held_elsewhere(world, &setup, a)?;
        let mut open_template = search.q0_full.clone();
        set_opening(&setup.model, a, &mut open_template, ch.grasp.opening);
        let mut closed_template = search.q0_full.clone();
        set_opening(&setup.model, a, &mut closed_template, ch.grasp.width);
        Ok(GraspMotions {
            q0: robot::arm_values(a, &search.q0_full),
            base: world.agent_state(setup.agent).base,
            agent_name: world.agent(setup.agent).name().to_string(),
            object_name: world.object(o).name.clone(),
            arm: ch.arm,
            open_template,
            closed_template,
            held,
            others,
            opening: ch.grasp.opening,
            width: ch.grasp.width,
            object_in_tool,
            setup,
        })
    }

    /// The arm.
    pub(super) fn arm(&self) -> &Arm {
        &self.setup.arms[self.arm]
    }

    fn motion(
        &self,
        obstacles: Arc<StaticObstacles>,
        held: Option<HeldObject>,
        template: &[f32],
    ) -> ArmMotion<'_> {
        let mut m = ArmMotion::new(
            &self.setup,
            self.arm(),
            obstacles,
            held,
            self.base,
            template.to_vec(),
        );
        for h in &self.others {
            m.checker.add_other_held_object(h.clone());
        }
        m
    }

    /// The arm moving among `obstacles`, the gripper open and empty.
    pub(super) fn open(&self, obstacles: Arc<StaticObstacles>) -> ArmMotion<'_> {
        self.motion(obstacles, None, &self.open_template)
    }

    /// The arm moving among `obstacles`, the gripper closed to the grasp's width and empty (the
    /// object not checked: it moves with the gripper).
    pub(super) fn closed(&self, obstacles: Arc<StaticObstacles>) -> ArmMotion<'_> {
        self.motion(obstacles, None, &self.closed_template)
    }

    /// The arm moving among `obstacles`, holding the object at the grasp.
    pub(super) fn holding(&self, obstacles: Arc<StaticObstacles>) -> ArmMotion<'_> {
        self.motion(obstacles, Some(self.held.clone()), &self.closed_template)
    }

    /// The record of the arm's motion along `path` in `phase`, the gripper as `grip` says.
    pub(super) fn record(&self, phase: Phase, path: JointPath, grip: Grip) -> Trajectory {
        let arm = self.arm();
        let (held, opening, ignored, straddles) = match grip {
            Grip::Open => (None, self.opening, vec![], None),
            Grip::Around(pose) => (
                None,
                self.opening,
                vec![self.object_name.clone()],
                pose.map(|p| (self.object_name.clone(), p.into())),
            ),
            Grip::Holding(ignored) => (Some(self.held_record()), self.width, ignored, None),
        };
        Trajectory {
            phase,
            agent: self.agent_name.clone(),
            arm: arm.name.clone(),
            joints: arm.joint_names.clone(),
            length: path.length(&arm.space),
            waypoints: path.unwrapped(&arm.space).waypoints,
            held,
            gripper_opening: opening,
            ignored,
            straddles,
        }
    }

    /// The record of the object held at the grasp.
    pub(super) fn held_record(&self) -> HeldRecord {
        HeldRecord {
            object: self.object_name.clone(),
            object_in_tool: self.object_in_tool.into(),
        }
    }
}

impl Search {
    /// The motions of grasp choice `grasp` (built on first use, then shared); `None` when the
    /// object or what the other grippers hold cannot be attached to the arm's model.
    pub(super) fn grasp_motions(&mut self, grasp: usize) -> Option<Arc<GraspMotions>> {
        if let Some(m) = self.motions.get(&grasp) {
            return Some(m.clone());
        }
        let m = Arc::new(GraspMotions::new(self, self.choices[grasp], self.object?).ok()?);
        self.motions.insert(grasp, m.clone());
        Some(m)
    }
}

/// A check on `motion`'s arm values while the gripper, open by the grasp's opening, is around
/// `m`'s object (`shape` at `pose`, left out of `motion`'s obstacles): the gripper's boxes do
/// not touch it, nor does any other link of the robot (an elbow swinging into the object as the
/// hand moves in, say). The hand's own links are left to the boxes.
pub(super) fn straddles<'a>(
    motion: &'a ArmMotion<'_>,
    m: &GraspMotions,
    shape: SharedShape,
    pose: Pose,
) -> impl Fn(&[f32]) -> bool + 'a {
    let gripper = motion.arm.gripper.at(m.opening);
    let object = Obstacle {
        name: m.object_name.clone(),
        pose,
        shape: shape.clone(),
    };
    let (mut checker, hand) = robot::around_object(motion.setup, motion.arm, motion.base, object);
    checker.set_fixed_joints(&motion.template, &motion.arm.moving_dofs());
    move |qa: &[f32]| {
        !gripper.intersects(&motion.tool_pose(qa), &*shape, &pose)
            && checker
                .first_collision_except(&motion.full(qa), &hand)
                .is_none()
    }
}

/// The last waypoint of `path` (a path holds at least its start).
pub(super) fn end(path: &JointPath) -> Option<Vec<f32>> {
    path.waypoints.last().cloned()
}
