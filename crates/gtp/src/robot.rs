//! The robot as the task planner drives it: its arms (kinematic chain, tool frame, gripper
//! joint, joint space) and the motions it makes — inverse kinematics, straight Cartesian moves
//! of the tool, and RRT-Connect between configurations — all checked for collisions with the
//! `geometry` crate's checker.

use std::sync::{Arc, OnceLock};

use geometry::agent::{AgentModel, KinematicChain};
use geometry::collision::{
    CollisionChecker, HeldObject, Obstacle, SelfCollisionModel, SelfCollisionOptions,
    StaticObstacles, agent_obstacles,
};
use geometry::ik::{IkOptions, solve_ik};
use geometry::scene::{AgentId, AgentKind, ObjectId};
use geometry::world::{Attachment, World};
use parry3d::math::{Pose, Vector};

use crate::gripper::GripperModel;
use crate::rrt::{self, JointPath, JointSpace, RrtParams};
use crate::solution::HeldRecord;

/// One arm of the robot.
#[derive(Clone, Debug)]
pub struct Arm {
    /// The chain's name (`right_arm`, `left_arm`).
    pub name: String,
    /// From the torso to the tool frame.
    pub chain: KinematicChain,
    /// The tool frame link (objects are attached to it).
    pub tool_link: usize,
    /// Its name.
    pub tool_link_name: String,
    /// The configuration index of the gripper's finger joint (each finger's travel: half the
    /// jaw opening), if the model has one.
    pub gripper_dof: Option<usize>,
    /// Finger joints that move with `gripper_dof` (each finger on a joint of its own).
    pub gripper_followers: Vec<usize>,
    /// The gripper's boxes, from the robot's model, for the cheap pre-checks.
    pub gripper: GripperModel,
    /// Joint space of the chain's movable joints.
    pub space: JointSpace,
    /// Names of those joints.
    pub joint_names: Vec<String>,
    /// Distance from the wrist centre (the origin of the chain's second-to-last movable joint)
    /// to the tool frame: fixed whatever the joint values.
    pub wrist_to_tool: f32,
    /// Upper bound of the distance from the first movable joint to the wrist centre (the sum of
    /// the joint offsets in between): a wrist farther away is out of reach.
    pub wrist_reach: f32,
}

impl Arm {
    /// The degrees of freedom that move with the arm: its chain's and its fingers' (whose
    /// links hang from the chain), as a checker for many configurations of the arm
    /// ([`ArmMotion::arm_checker`]) takes them, so that one made with the gripper open serves
    /// it closed too.
    pub fn moving_dofs(&self) -> Vec<usize> {
        let fingers = self.gripper_dof.iter().chain(&self.gripper_followers);
        self.chain.dofs.iter().chain(fingers).copied().collect()
    }

    /// A necessary condition for the tool frame to reach `tool`: the wrist centre it implies
    /// (back from the tool along its x axis) lies within the arm's reach from `shoulder` (the
    /// first movable joint's world position). Cheap; inverse kinematics decides.
    pub fn may_reach(&self, shoulder: Vector, tool: &Pose) -> bool {
        let wrist = tool.translation - tool.rotation * Vector::X * self.wrist_to_tool;
        (wrist - shoulder).length() <= self.wrist_reach + 1e-3
    }
}

/// What the planner knows of the robot of a scene; built once per scene and shared.
#[derive(Debug)]
pub struct RobotSetup {
    /// The robot agent.
    pub agent: AgentId,
    /// Its model.
    pub model: Arc<AgentModel>,
    /// Its self-collision pairs.
    pub self_model: Arc<SelfCollisionModel>,
    /// Its arms, the preferred first.
    pub arms: Vec<Arm>,
}

impl RobotSetup {
    /// A sphere holding everything the arms can touch in the robot's current posture (torso
    /// and base as in `q`), with `margin` for a held object: `(centre, radius)`.
    pub fn workspace(&self, base: Pose, q: &[f32], margin: f32) -> (Vector, f32) {
        let shoulders: Vec<Vector> = self
            .arms
            .iter()
            .map(|a| {
                let j = a
                    .chain
                    .joints
                    .iter()
                    .copied()
                    .find(|&j| self.model.joints()[j].is_movable())
                    .unwrap_or(a.chain.joints[0]);
                let parent = self.model.joints()[j].parent;
                (self.model.link_pose_by_id(base, q, parent) * self.model.joints()[j].origin)
                    .translation
            })
            .collect();
        let centre =
            shoulders.iter().fold(Vector::ZERO, |a, b| a + *b) / shoulders.len().max(1) as f32;
        let reach = self
            .arms
            .iter()
            .map(|a| a.wrist_reach + a.wrist_to_tool + 0.05)
            .fold(0.0f32, f32::max);
        let spread = shoulders
            .iter()
            .map(|s| (*s - centre).length())
            .fold(0.0f32, f32::max);
        (centre, spread + reach + margin)
    }

    /// The first robot agent of the world, with the arms its SRDF declares.
    pub fn new(world: &World) -> Result<RobotSetup, String> {
        let agent = world
            .agent_ids()
            .find(|&a| world.agent(a).kind() == AgentKind::Robot)
            .ok_or("the scene has no robot agent")?;
        RobotSetup::for_agent(world, agent)
    }

    /// Any agent's arms (as its SRDF declares them), for motion planning: the robot's, or a
    /// person's in a hand-over (their hand frame is the tool frame; no gripper joint).
    pub fn for_agent(world: &World, agent: AgentId) -> Result<RobotSetup, String> {
        let model = world.agent(agent).model.clone();
        let self_model = Arc::new(SelfCollisionModel::new(
            model,
            &SelfCollisionOptions::default(),
        ));
        RobotSetup::with_self_model(world, agent, self_model)
    }

    /// [`RobotSetup::for_agent`] with the agent model's self-collision model made already
    /// (what a planner keeps between scenes that share the model).
    pub fn with_self_model(
        world: &World,
        agent: AgentId,
        self_model: Arc<SelfCollisionModel>,
    ) -> Result<RobotSetup, String> {
        let model = world.agent(agent).model.clone();
        let mut arms = Vec::new();
        for name in model.arm_names() {
            let Ok(chain) = model.chain(&name) else {
                continue;
            };
            let (chain, tool_link) = tool_chain(&model, chain, &world.agent(agent).hand_links);
            // The gripper's joint (a person's hand has none) and the fingers' joints moving with
            // it.
            let (gripper_dof, gripper_followers) = crate::gripper::finger_dofs(&model, &name);
            let limits = model.dof_limits();
            let space = JointSpace::new(
                &chain
                    .dofs
                    .iter()
                    .map(|&k| (limits[k].lower, limits[k].upper, !limits[k].is_bounded()))
                    .collect::<Vec<_>>(),
            );
            let joint_names = chain
                .dofs
                .iter()
                .map(|&k| model.dof_names()[k].clone())
                .collect();
            // Wrist geometry from the model: joints from the first movable one to the wrist.
            let movable: Vec<usize> = chain
                .joints
                .iter()
                .copied()
                .filter(|&j| model.joints()[j].is_movable())
                .collect();
            let (wrist_to_tool, wrist_reach) = if movable.len() >= 3 {
                let wrist_joint = movable[movable.len() - 2];
                let q = model.default_configuration().into_vec();
                let base = Pose::IDENTITY;
                let wrist = model
                    .link_pose_by_id(base, &q, model.joints()[wrist_joint].child)
                    .translation;
                let tool = model.link_pose_by_id(base, &q, tool_link).translation;
                let first = chain
                    .joints
                    .iter()
                    .position(|&j| j == movable[0])
                    .unwrap_or(0);
                let last = chain
                    .joints
                    .iter()
                    .position(|&j| j == wrist_joint)
                    .unwrap_or(0);
                let reach: f32 = chain.joints[first + 1..=last]
                    .iter()
                    .map(|&j| model.joints()[j].origin.translation.length())
                    .sum();
                ((tool - wrist).length(), reach)
            } else {
                (0.0, f32::INFINITY)
            };
            let gripper =
                GripperModel::of_arm(&model, &name, tool_link, (gripper_dof, &gripper_followers));
            arms.push(Arm {
                gripper,
                wrist_to_tool,
                wrist_reach,
                name,
                tool_link_name: model.links()[tool_link].name.clone(),
                chain,
                tool_link,
                gripper_dof,
                gripper_followers,
                space,
                joint_names,
            });
        }
        if arms.is_empty() {
            return Err(format!(
                "agent `{}` has no arm: no SRDF group ends at an `end_effector` (see \
                 docs/guide.md, \"Your own robot\")",
                world.agent(agent).name()
            ));
        }
        Ok(RobotSetup {
            agent,
            model,
            self_model,
            arms,
        })
    }
}

/// The obstacles of `world` for the robot: every object it does not hold (except those in
/// `skip`; objects in other agents' hands included), and the collision shapes of every other
/// agent.
pub fn obstacles(world: &World, robot: AgentId, skip: &[ObjectId]) -> StaticObstacles {
    let mut list: Vec<Obstacle> = world
        .object_ids()
        .filter(|id| !skip.contains(id))
        .filter(|&id| world.attachment(id).is_none_or(|at| at.agent != robot))
        .map(|id| Obstacle {
            name: world.object(id).name.clone(),
            pose: world.object_shape_pose(id),
            shape: world.object(id).shape.clone(),
        })
        .collect();
    for a in world.agent_ids() {
        if a == robot {
            continue;
        }
        let st = world.agent_state(a);
        let info = world.agent(a);
        list.extend(agent_obstacles(&info.model, st.base, &st.q, info.name()));
    }
    StaticObstacles::new(list)
}

/// The check of the robot's links against the one object the open gripper of `arm` is around
/// (`object`, out of the motion's obstacles): a checker with that object as its only obstacle
/// (self-collision off), and the hand's links, which it leaves to the gripper's boxes (call
/// `first_collision_except` with them).
pub fn around_object(
    setup: &RobotSetup,
    arm: &Arm,
    base: Pose,
    object: Obstacle,
) -> (CollisionChecker, Vec<usize>) {
    let obstacles = Arc::new(StaticObstacles::new(vec![object]));
    let mut checker = CollisionChecker::new(setup.self_model.clone(), obstacles, base);
    checker.set_self_collision(false);
    (checker, setup.model.hand_links(arm.tool_link))
}

/// The obstacles within `radius` of `centre` (by their bounding boxes): for arm motions, the
/// arm's workspace around the shoulders; nothing farther can touch the arm or what it holds.
pub fn near(obstacles: &StaticObstacles, centre: Vector, radius: f32) -> StaticObstacles {
    let keep: Vec<Obstacle> = obstacles
        .obstacles()
        .iter()
        .enumerate()
        .filter(|(i, _)| {
            let b = obstacles.aabb(*i);
            let closest = centre.clamp(b.mins, b.maxs);
            (closest - centre).length() <= radius
        })
        .map(|(_, o)| o.clone())
        .collect();
    StaticObstacles::new(keep)
}

/// World position of `arm`'s first movable joint in configuration `q`.
pub fn shoulder(setup: &RobotSetup, arm: &Arm, base: Pose, q: &[f32]) -> Vector {
    let model = &setup.model;
    match arm
        .chain
        .joints
        .iter()
        .copied()
        .find(|&j| model.joints()[j].is_movable())
    {
        Some(j) => {
            let parent = model.joints()[j].parent;
            (model.link_pose_by_id(base, q, parent) * model.joints()[j].origin).translation
        }
        None => base.translation,
    }
}

/// The arm's values within a full configuration.
pub fn arm_values(arm: &Arm, q: &[f32]) -> Vec<f32> {
    arm.chain.dofs.iter().map(|&k| q[k]).collect()
}

/// Writes arm values into a full configuration.
pub fn set_arm_values(arm: &Arm, q: &mut [f32], values: &[f32]) {
    for (i, &k) in arm.chain.dofs.iter().enumerate() {
        q[k] = values[i];
    }
}

/// Sets the gripper's finger joint for a jaw opening (clamped to the joint's limits).
pub fn set_opening(model: &AgentModel, arm: &Arm, q: &mut [f32], opening: f32) {
    if let Some(k) = arm.gripper_dof {
        q[k] = model.dof_limits()[k].clamp(arm.gripper.joint_value(opening));
        for &f in &arm.gripper_followers {
            q[f] = q[k];
        }
    }
}

/// What the robot holds in its grippers: each object attached to an arm's tool frame, with
/// that arm and the attachment.
pub fn in_grippers<'a>(
    world: &'a World,
    setup: &'a RobotSetup,
) -> impl Iterator<Item = (ObjectId, &'a Arm, Attachment)> + 'a {
    world.object_ids().filter_map(move |o| {
        let att = world.attachment(o).filter(|a| a.agent == setup.agent)?;
        let arm = setup.arms.iter().find(|a| a.tool_link == att.link)?;
        Some((o, arm, att))
    })
}

/// Makes `checker` carry everything the robot holds in its grippers (the base's drives must
/// carry each held object round obstacles, and no held object may pass through the robot).
pub fn carry_all(
    checker: &mut CollisionChecker,
    world: &World,
    setup: &RobotSetup,
) -> Result<(), String> {
    let mut held = in_grippers(world, setup)
        .map(|(o, arm, att)| held_object(world, setup, arm, o, att.grasp))
        .collect::<Result<Vec<_>, _>>()?
        .into_iter();
    checker.set_held_object(held.next());
    for h in held {
        checker.add_other_held_object(h);
    }
    Ok(())
}

/// The record of what the robot carries while its base drives (the object in the first
/// gripper that holds one, with its pose in that gripper's tool frame), for the trajectory.
pub fn carried_record(world: &World, setup: &RobotSetup) -> Option<HeldRecord> {
    in_grippers(world, setup)
        .next()
        .map(|(o, _, att)| HeldRecord {
            object: world.object(o).name.clone(),
            object_in_tool: att.grasp.into(),
        })
}

/// The objects the robot holds in the grippers of arms other than `arm`, as held objects for
/// `arm`'s collision checks: they stay where they are while `arm` moves, which must not pass
/// through them.
pub fn held_elsewhere(
    world: &World,
    setup: &RobotSetup,
    arm: &Arm,
) -> Result<Vec<HeldObject>, String> {
    in_grippers(world, setup)
        .filter(|(_, other, _)| other.tool_link != arm.tool_link)
        .map(|(o, other, att)| held_object(world, setup, other, o, att.grasp))
        .collect()
}

/// A held object for collision checks: `object` attached to the arm's tool frame at
/// `object_in_tool` (the object's pose in the tool frame).
pub fn held_object(
    world: &World,
    setup: &RobotSetup,
    arm: &Arm,
    object: ObjectId,
    object_in_tool: Pose,
) -> Result<HeldObject, String> {
    let o = world.object(object);
    HeldObject::new(
        &setup.model,
        &o.name,
        o.shape.clone(),
        &arm.tool_link_name,
        object_in_tool * o.shape_offset,
    )
    .map_err(|e| e.to_string())
}

/// Motion planning for one arm against one set of obstacles (and optionally a held object).
pub struct ArmMotion<'a> {
    pub setup: &'a RobotSetup,
    pub arm: &'a Arm,
    pub checker: CollisionChecker,
    /// The full configuration whose arm values are replaced (torso, head, gripper kept).
    pub template: Vec<f32>,
    pub base: Pose,
    /// [`ArmMotion::arm_checker`], made from `checker` and `template` on first use (change
    /// those before).
    fixed: OnceLock<CollisionChecker>,
}

impl<'a> ArmMotion<'a> {
    /// A motion planner for `arm` among `obstacles`, holding `held`, with the other joints as in
    /// `template`.
    pub fn new(
        setup: &'a RobotSetup,
        arm: &'a Arm,
        obstacles: Arc<StaticObstacles>,
        held: Option<HeldObject>,
        base: Pose,
        template: Vec<f32>,
    ) -> ArmMotion<'a> {
        let mut checker = CollisionChecker::new(setup.self_model.clone(), obstacles, base);
        checker.set_held_object(held);
        ArmMotion {
            setup,
            arm,
            checker,
            template,
            base,
            fixed: OnceLock::new(),
        }
    }

    /// A checker for many configurations of this arm: only the arm's joints change between
    /// checks, so the rest of the robot's poses and collisions are computed once here (worth it
    /// from a few checks on: motion planning, straight moves).
    pub fn arm_checker(&self) -> &CollisionChecker {
        self.fixed.get_or_init(|| {
            let mut checker = self.checker.clone();
            checker.set_fixed_joints(&self.template, &self.arm.moving_dofs());
            checker
        })
    }

    /// Whether the arm values `qa` are collision-free.
    pub fn free(&self, qa: &[f32]) -> bool {
        let mut q = self.template.clone();
        set_arm_values(self.arm, &mut q, qa);
        self.arm_checker().is_config_free(&q)
    }

    /// The first collision at arm values `qa`, in words (for failure reports).
    pub fn collision(&self, qa: &[f32]) -> Option<String> {
        let mut q = self.template.clone();
        set_arm_values(self.arm, &mut q, qa);
        self.arm_checker()
            .first_collision(&q)
            .map(|c| c.to_string())
    }

    /// The full configuration for arm values `qa`.
    pub fn full(&self, qa: &[f32]) -> Vec<f32> {
        let mut q = self.template.clone();
        set_arm_values(self.arm, &mut q, qa);
        q
    }

    /// World position of the arm's first movable joint (fixed while the arm moves).
    pub fn shoulder(&self) -> Vector {
        let first = self
            .arm
            .chain
            .joints
            .iter()
            .copied()
            .find(|&j| self.setup.model.joints()[j].is_movable());
        match first {
            Some(j) => {
                let parent = self.setup.model.joints()[j].parent;
                let p = self
                    .setup
                    .model
                    .link_pose_by_id(self.base, &self.template, parent);
                (p * self.setup.model.joints()[j].origin).translation
            }
            None => self.base.translation,
        }
    }

    /// World pose of the tool frame for arm values `qa`.
    pub fn tool_pose(&self, qa: &[f32]) -> Pose {
        self.setup
            .model
            .link_pose_by_id(self.base, &self.full(qa), self.arm.tool_link)
    }

    /// Inverse kinematics of the tool frame to `target`, seeded at arm values `seed`;
    /// `attempts` restarts at most. The solution is not collision-checked.
    pub fn ik(
        &self,
        target: Pose,
        seed: &[f32],
        attempts: usize,
        rng: &mut fastrand::Rng,
    ) -> Option<Vec<f32>> {
        // Tight: a grasp's held object is posed by the tool frame the solution reaches, so
        // the tolerance is how far the object seems to jump when grasped or released.
        let opts = IkOptions {
            attempts,
            iterations: 60,
            position_tolerance: 2e-4,
            orientation_tolerance: 2e-3,
            orientation: true,
        };
        let q = self.full(seed);
        solve_ik(
            &self.setup.model,
            &self.arm.chain,
            self.base,
            &q,
            target,
            &opts,
            rng,
        )
        .ok()
        .map(|s| arm_values(self.arm, &s.configuration))
    }

    /// Inverse kinematics whose solution is also collision-free (and passes `extra`): the
    /// first try from `seed`, the next ones from random arm configurations, `tries` in all.
    pub fn ik_free(
        &self,
        target: Pose,
        seed: &[f32],
        tries: usize,
        attempts: usize,
        extra: &dyn Fn(&[f32]) -> bool,
        rng: &mut fastrand::Rng,
    ) -> Result<Vec<f32>, Option<String>> {
        let mut last = None;
        let mut start = seed.to_vec();
        for t in 0..tries.max(1) {
            if t > 0 {
                self.arm.space.sample(rng, &mut start);
            }
            let Some(q) = self.ik(target, &start, attempts, rng) else {
                continue;
            };
            match self.collision(&q) {
                None if extra(&q) => return Ok(q),
                None => last = Some("an extra check failed".to_string()),
                Some(c) => last = Some(c),
            }
        }
        Err(last)
    }

    /// A straight move of the tool from its pose at `from` by `offset` (world frame), in
    /// `steps` inverse-kinematics steps seeded one from the other; every edge certified free by
    /// [`ArmMotion::motion_collision`]. `extra` is an additional validity check on the arm
    /// values (the gripper against the object it straddles, for example), at the certification
    /// resolution. The error says what failed.
    #[allow(clippy::too_many_arguments)]
    pub fn straight(
        &self,
        from: &[f32],
        offset: Vector,
        steps: usize,
        params: &RrtParams,
        extra: &dyn Fn(&[f32]) -> bool,
        rng: &mut fastrand::Rng,
        checks: &mut usize,
    ) -> Result<JointPath, String> {
        let start = self.tool_pose(from);
        let checker = self.arm_checker();
        let mut full = self.template.clone();
        let mut waypoints = vec![from.to_vec()];
        let fine = params.resolution / params.certify_factor.max(1) as f32;
        // The start too: it was checked, if at all, with the gripper otherwise opened (a
        // retreat opens it at the placement) or against other obstacles.
        set_arm_values(self.arm, &mut full, from);
        *checks += 1;
        if let Some(c) = checker.first_collision(&full) {
            return Err(format!("at the start: {c}"));
        }
        if !extra(from) {
            return Err("at the start, the gripper touches the object".into());
        }
        for s in 1..=steps {
            let t = s as f32 / steps as f32;
            let target = Pose::from_parts(start.translation + offset * t, start.rotation);
            let prev = waypoints.last().cloned().unwrap_or_else(|| from.to_vec());
            let q = self
                .ik(target, &prev, 1, rng)
                .ok_or_else(|| "inverse kinematics fails along the way".to_string())?;
            // A jump between neighbouring steps means another IK branch: not a straight move.
            if self.arm.space.max_delta(&prev, &q) > 0.6 {
                return Err("the arm would have to swing round".into());
            }
            let mut extra_holds = |qa: &[f32]| extra(qa);
            let mut none = 0;
            if !rrt::edge_valid(
                &self.arm.space,
                &prev,
                &q,
                fine,
                &mut extra_holds,
                &mut none,
            ) {
                return Err("the gripper touches the object".into());
            }
            if let Some(c) = self.motion_collision(checker, &prev, &q, checks) {
                return Err(c);
            }
            waypoints.push(q);
        }
        Ok(JointPath { waypoints })
    }

    /// RRT-Connect from `from` to `to` (arm values).
    pub fn plan(
        &self,
        from: &[f32],
        to: &[f32],
        params: &RrtParams,
        rng: &mut fastrand::Rng,
    ) -> Result<(JointPath, rrt::RrtStats), rrt::RrtError> {
        let checker = self.arm_checker();
        let mut full = self.template.clone();
        let valid = |qa: &[f32]| {
            set_arm_values(self.arm, &mut full, qa);
            checker.is_config_free(&full)
        };
        let mut certify = |a: &[f32], b: &[f32], checks: &mut usize| {
            self.motion_collision(checker, a, b, checks).is_none()
        };
        rrt::plan_certified(
            &self.arm.space,
            from,
            to,
            valid,
            Some(&mut certify),
            params,
            rng,
        )
        .map_err(|(e, _)| e)
    }

    /// The first collision (in words) on the straight joint-space motion of the arm from
    /// values `a` to `b` (the short way round for continuous joints), found by `checker` (an
    /// [`ArmMotion::arm_checker`]) by conservative advancement: the whole motion is checked,
    /// not sampled configurations. Counts the configurations posed in `checks`.
    pub fn motion_collision(
        &self,
        checker: &CollisionChecker,
        a: &[f32],
        b: &[f32],
        checks: &mut usize,
    ) -> Option<String> {
        let mut step = vec![0.0; a.len()];
        self.arm.space.delta(a, b, &mut step);
        let end: Vec<f32> = a.iter().zip(&step).map(|(x, d)| x + d).collect();
        let r = checker.check_motion(&self.full(a), &self.full(&end), MOTION_FLOOR);
        *checks += r.configurations;
        r.contact.map(|c| c.to_string())
    }
}

/// When a motion is certified (see [`ArmMotion::motion_collision`]), bodies nearer than this
/// (metres) are re-measured every this much of their relative motion: a contact between two
/// measurements is at most half as deep, far under what a re-check or a checker tolerates.
pub const MOTION_FLOOR: f32 = 2e-4;

/// An arm's chain extended to its tool frame, and the tool frame: the agent's hand link (the
/// scene's `hands`, by default the SRDF chain tips) that hangs below the chain's tip, such as a
/// gripper's tool frame below the wrist that ends a MoveIt arm group; the tip itself when no
/// hand link hangs below it. The extension adds fixed joints only (the arm's joints are the
/// same), so inverse kinematics places the tool frame itself.
fn tool_chain(
    model: &AgentModel,
    chain: KinematicChain,
    hands: &[usize],
) -> (KinematicChain, usize) {
    let below = hands
        .iter()
        .copied()
        .find(|&h| h != chain.tip_link && model.is_descendant(h, chain.tip_link));
    let Some(tool) = below else {
        let tip = chain.tip_link;
        return (chain, tip);
    };
    let links = model.links();
    match model.chain_between(&links[chain.root_link].name, &links[tool].name) {
        Ok(mut extended) if extended.dofs == chain.dofs => {
            extended.name = chain.name.clone();
            (extended, tool)
        }
        _ => {
            let tip = chain.tip_link;
            (chain, tip)
        }
    }
}
