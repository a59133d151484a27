//! A person's side of a hand-over (the take task): their arm out to the object the robot holds
//! out, then back with it to where they hold it. Planned like the robot's arm motions: inverse
//! kinematics, RRT-Connect, every configuration collision-checked against the scene, the robot
//! and the person's own body, the object checked too on the way back.

use std::sync::Arc;

use geometry::ik::{IkOptions, solve_ik};
use geometry::scene::ObjectId;
use geometry::world::World;
use parry3d::math::{Pose, Rotation, Vector};

use crate::robot::{self, ArmMotion, RobotSetup};
use crate::rrt::{JointPath, RrtParams};

/// How far in front of the person's chest a taken object is held, and how far below the
/// shoulders (metres): elbows bent, the object over the lap.
const HOLD_FORWARD: f32 = 0.35;
const HOLD_BELOW: f32 = 0.2;
/// Fractions of the way from the hand-over to the holding point tried, nearest the body first.
const HOLD_FRACTIONS: [f32; 4] = [1.0, 0.75, 0.5, 0.25];

/// The person's planned motions of one take.
#[derive(Clone, Debug)]
pub struct TakeMotion {
    /// Index of the arm in the person's setup.
    pub arm: usize,
    /// From the person's posture to the object (arm values).
    pub reach: JointPath,
    /// From the object back to where the person holds it (arm values), the object in hand.
    pub withdraw: JointPath,
    /// The object's pose in the hand frame (rigid from the hand-over on).
    pub grasp: Pose,
    /// The person's whole configuration at the end.
    pub q_end: Vec<f32>,
}

/// Why a take cannot be planned: which motion failed and why, and whether the reach's path
/// search spent its budget to fail (the caller's later searches may then get less).
#[derive(Clone, Debug, Default)]
pub struct TakeError {
    pub message: String,
    pub search_failed: bool,
}

impl From<String> for TakeError {
    fn from(message: String) -> Self {
        TakeError {
            message,
            search_failed: false,
        }
    }
}

impl std::fmt::Display for TakeError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(&self.message)
    }
}

/// Plans a take of `object` by `person`'s arm `arm`: the reach in `before` (the robot holding
/// the object out), the withdraw in `after` (the robot drawn back). The reach's end, the hand on
/// the object, just clear of it, fixes the grasp; from then on the object is rigid in the hand.
pub fn plan_take(
    person: &RobotSetup,
    arm: usize,
    before: &World,
    after: &World,
    object: ObjectId,
    rrt: &RrtParams,
    rng: &mut fastrand::Rng,
) -> Result<TakeMotion, TakeError> {
    let h = person.agent;
    let a = &person.arms[arm];
    let q0 = before.agent_state(h).q.clone();
    // The object is in the way of the hand on its way there: the hand ends just clear of it.
    let reach_motion = arm_motion_among(person, arm, before, &[], None, object)?;
    let qa0 = robot::arm_values(a, &q0);
    if let Some(c) = reach_motion.collision(&qa0) {
        return Err(format!("the person's posture collides before the reach: {c}").into());
    }
    let goal = reach_goal(&reach_motion, before, object, &qa0, rng).map_err(|why| {
        format!(
            "no collision-free posture of the {} reaches the object ({why})",
            a.name
        )
    })?;
    let reach = reach_motion
        .plan(&qa0, &goal, rrt, rng)
        .map_err(|e| TakeError {
            message: format!("no collision-free reach: {e}"),
            search_failed: e.is_budget(),
        })?
        .0;
    let grasp = reach_motion.tool_pose(&goal).inverse() * before.object_pose(object);
    let carry = arm_motion(person, arm, after, object, Some(grasp))?;
    if let Some(c) = carry.collision(&goal) {
        return Err(format!("holding the object at the hand-over collides: {c}").into());
    }
    let withdraw = withdraw(&carry, after, &goal, rrt, rng);
    let q_end = carry.full(withdraw.waypoints.last().unwrap_or(&goal));
    Ok(TakeMotion {
        arm,
        reach,
        withdraw,
        grasp,
        q_end,
    })
}

/// The person's other arms (all but `arm`, holding nothing) moved to rest in `before`, the
/// robot holding `object` out: to where the scene started them, else to the model's default
/// configuration (arms hanging), the first of those it is not at that is free and that a
/// collision-free path reaches. Each arm's path, and `before` and `after` with the arms there;
/// the error says why an arm cannot move, or that none can.
pub fn rest_other_arms(
    person: &RobotSetup,
    arm: usize,
    before: &World,
    after: &World,
    object: ObjectId,
    rrt: &RrtParams,
    rng: &mut fastrand::Rng,
) -> Result<RestedArms, String> {
    let h = person.agent;
    let rests = [
        before.agent(h).initial_q.clone(),
        person.model.default_configuration().into_vec(),
    ];
    let busy: Vec<usize> = robot::in_grippers(before, person)
        .map(|(_, a, _)| a.tool_link)
        .collect();
    let (mut b, mut a) = (before.clone(), after.clone());
    let mut moves = Vec::new();
    for (k, other) in person.arms.iter().enumerate() {
        if k == arm || busy.contains(&other.tool_link) {
            continue;
        }
        let from = robot::arm_values(other, &b.agent_state(h).q);
        let at = |to: &[f32]| from.iter().zip(to).all(|(x, y)| (x - y).abs() < 1e-3);
        let targets: Vec<Vec<f32>> = rests
            .iter()
            .map(|r| robot::arm_values(other, r))
            .filter(|t| !at(t))
            .collect();
        if targets.is_empty() {
            continue;
        }
        let m = arm_motion_among(person, k, &b, &[], None, object)?;
        let (path, to) = rest_path(&m, &from, targets, rrt, rng)
            .map_err(|e| format!("the {} cannot move out of the way: {e}", other.name))?;
        for w in [&mut b, &mut a] {
            let mut q = w.agent_state(h).q.clone();
            robot::set_arm_values(other, &mut q, &to);
            let base = w.agent_state(h).base;
            w.set_agent_config(h, base, &q);
        }
        moves.push((k, path));
    }
    if moves.is_empty() {
        return Err("the other arms are at rest already".into());
    }
    Ok(RestedArms {
        moves,
        before: b,
        after: a,
    })
}

/// Paths of a person's arms: each arm's index in the person's setup and its path.
pub type ArmPaths = Vec<(usize, JointPath)>;

/// Arms moved out of the way ([`rest_other_arms`]).
pub struct RestedArms {
    /// Each arm moved and its path.
    pub moves: ArmPaths,
    /// The world before the take with the arms at rest.
    pub before: World,
    /// The world after the take with the arms at rest.
    pub after: World,
}

/// The path from `from` to the first of `targets` that is free and reachable, with it; else
/// why the last one is not.
fn rest_path(
    m: &ArmMotion,
    from: &[f32],
    targets: Vec<Vec<f32>>,
    rrt: &RrtParams,
    rng: &mut fastrand::Rng,
) -> Result<(JointPath, Vec<f32>), String> {
    let mut last = String::from("no rest posture");
    for to in targets {
        if let Some(c) = m.collision(&to) {
            last = format!("at rest it collides: {c}");
            continue;
        }
        match m.plan(from, &to, rrt, rng) {
            Ok((path, _)) => return Ok((path, to)),
            Err(e) => last = e.to_string(),
        }
    }
    Err(last)
}

/// Arm values with the palm against `object`: the hand's flat side (its y axis) facing the
/// surface point nearest the shoulder, just clear of it, the fingers turned about the normal
/// in [`REACH_TURNS`] ways; from the person's posture first, then from random postures of the
/// arm. Nothing but the object may be touched. The error is the last collision met.
fn reach_goal(
    m: &ArmMotion,
    world: &World,
    object: ObjectId,
    qa0: &[f32],
    rng: &mut fastrand::Rng,
) -> Result<Vec<f32>, String> {
    let pose = world.object_shape_pose(object);
    let shoulder = m.shoulder();
    let surface = world
        .object(object)
        .shape
        .project_point(&pose, shoulder, true)
        .point;
    let normal = (shoulder - surface).normalize_or_zero();
    let palm = Rotation::from_rotation_arc(Vector::Y, -normal);
    let at = surface + normal * (PALM_HALF_THICKNESS + PALM_CLEARANCE);
    let mut last = "inverse kinematics does not get there".to_string();
    for t in 0..REACH_TURNS {
        let turn = t as f32 * std::f32::consts::TAU / REACH_TURNS as f32;
        let target = Pose::from_parts(at, Rotation::from_axis_angle(normal, turn) * palm);
        let Some(q) = m.ik(target, qa0, 2, rng) else {
            continue;
        };
        if hand_depth(m, &q, world, object) > 0.0 {
            continue;
        }
        if covers_eyes(m, world, &q) {
            last = COVERS_EYES.to_string();
            continue;
        }
        match m.collision(&q) {
            None => return Ok(q),
            Some(c) => last = c,
        }
    }
    // The wrist cannot turn the palm that way: the hand where it gets to, backed off along the
    // normal by how deep it sinks into the object.
    let mut seed = qa0.to_vec();
    for t in 0..REACH_TRIES {
        if t > 0 {
            m.arm.space.sample(rng, &mut seed);
        }
        let mut off = 0.0;
        let mut q = seed.clone();
        for _ in 0..BACK_OFF_STEPS {
            let Some(s) = position_ik(m, &q, surface + normal * off, rng) else {
                break;
            };
            q = s;
            let depth = hand_depth(m, &q, world, object);
            if depth == 0.0 && off > 0.0 {
                if covers_eyes(m, world, &q) {
                    last = COVERS_EYES.to_string();
                    break;
                }
                match m.collision(&q) {
                    None => return Ok(q),
                    Some(c) => last = c,
                }
                break;
            }
            off += depth + PALM_CLEARANCE;
        }
    }
    Err(last)
}

/// How far a person keeps their arm from their eyes where a take ends (metres): nearer, the
/// hand or forearm would cover the eyes and hide what the person looks at (and no one takes a
/// book with the wrist at their face).
const EYE_CLEARANCE: f32 = 0.12;
const COVERS_EYES: &str = "the hand or forearm would cover the person's eyes";

/// Whether a shape of the arm (its chain's links and the hand's) comes within
/// [`EYE_CLEARANCE`] of the person's eye at arm values `qa`.
fn covers_eyes(m: &ArmMotion, world: &World, qa: &[f32]) -> bool {
    let model = &m.setup.model;
    let q = m.full(qa);
    let eye_link = world.agent(m.setup.agent).eye_link;
    let eye = model.link_pose_by_id(m.base, &q, eye_link).translation;
    let mut links: Vec<usize> = m
        .arm
        .chain
        .joints
        .iter()
        .map(|&j| model.joints()[j].child)
        .collect();
    links.extend(model.hand_links(m.arm.tool_link));
    links.iter().any(|&l| {
        let pose = model.link_pose_by_id(m.base, &q, l);
        model.links()[l]
            .collisions
            .iter()
            .any(|c| c.shape.distance_to_point(&(pose * c.local_pose), eye, true) < EYE_CLEARANCE)
    })
}

/// Rounds of backing the hand off the object.
const BACK_OFF_STEPS: usize = 5;

/// How deep the hand's shapes sink into `object` at arm values `qa` (0 when clear).
fn hand_depth(m: &ArmMotion, qa: &[f32], world: &World, object: ObjectId) -> f32 {
    let model = &m.setup.model;
    let Some(hand) = model.geometric_ancestor(m.arm.tool_link) else {
        return 0.0;
    };
    let link = model.link_pose_by_id(m.base, &m.full(qa), hand);
    let (shape, pose) = (&world.object(object).shape, world.object_shape_pose(object));
    model.links()[hand]
        .collisions
        .iter()
        .filter_map(|c| {
            parry3d::query::contact(&(link * c.local_pose), &*c.shape, &pose, &**shape, 0.0)
                .ok()
                .flatten()
        })
        .map(|c| (-c.dist).max(0.0))
        .fold(0.0, f32::max)
}

/// Turns of the fingers about the surface normal tried from the person's posture; then tries
/// from random postures.
const REACH_TURNS: usize = 8;
const REACH_TRIES: usize = 12;
/// Half the hand's thickness (the human model's hand box is 3 cm thick), and the gap left
/// between palm and object at the hand-over (metres).
const PALM_HALF_THICKNESS: f32 = 0.015;
const PALM_CLEARANCE: f32 = 0.0005;

/// A motion planner for the person's arm in `world`, the object left out of the obstacles
/// (`held`: carried at that grasp).
fn arm_motion<'s>(
    person: &'s RobotSetup,
    arm: usize,
    world: &World,
    object: ObjectId,
    held: Option<Pose>,
) -> Result<ArmMotion<'s>, String> {
    arm_motion_among(person, arm, world, &[object], held, object)
}

/// A motion planner for the person's arm in `world` among every object but `skip` (the object
/// released from the robot's gripper, an obstacle where it is unless skipped).
fn arm_motion_among<'s>(
    person: &'s RobotSetup,
    arm: usize,
    world: &World,
    skip: &[ObjectId],
    held: Option<Pose>,
    object: ObjectId,
) -> Result<ArmMotion<'s>, String> {
    let a = &person.arms[arm];
    let h = person.agent;
    let mut released = world.clone();
    released.detach(object);
    let obstacles = Arc::new(robot::obstacles(&released, h, skip));
    let held = held
        .map(|g| robot::held_object(world, person, a, object, g))
        .transpose()?;
    let st = world.agent_state(h);
    let mut m = ArmMotion::new(person, a, obstacles, held, st.base, st.q.clone());
    for other in robot::held_elsewhere(world, person, a)? {
        m.checker.add_other_held_object(other);
    }
    Ok(m)
}

/// The way back from the hand-over `from`: to the first free holding posture, nearest the
/// body first, that a collision-free path reaches; none found, the person keeps the object
/// where they took it (a one-waypoint path).
fn withdraw(
    carry: &ArmMotion,
    world: &World,
    from: &[f32],
    rrt: &RrtParams,
    rng: &mut fastrand::Rng,
) -> JointPath {
    let handover = carry.tool_pose(from).translation;
    let hold = holding_point(carry);
    for f in HOLD_FRACTIONS {
        let target = handover + (hold - handover) * f;
        let Some(q) = position_ik(carry, from, target, rng) else {
            continue;
        };
        if !carry.free(&q) || covers_eyes(carry, world, &q) {
            continue;
        }
        if let Ok((path, _)) = carry.plan(from, &q, rrt, rng) {
            return path;
        }
    }
    JointPath {
        waypoints: vec![from.to_vec()],
    }
}

/// Where a person holds what they took: in front of their chest, below the shoulders, in the
/// direction their pelvis faces.
fn holding_point(m: &ArmMotion) -> Vector {
    let model = &m.setup.model;
    let shoulders: Vec<Vector> = m
        .setup
        .arms
        .iter()
        .filter_map(|a| a.chain.joints.first())
        .map(|&j| {
            let parent = model.joints()[j].parent;
            (model.link_pose_by_id(m.base, &m.template, parent) * model.joints()[j].origin)
                .translation
        })
        .collect();
    let centre = shoulders.iter().fold(Vector::ZERO, |s, p| s + *p) / shoulders.len().max(1) as f32;
    let mut forward = m.base.rotation * Vector::X;
    forward.z = 0.0;
    centre + forward.normalize_or_zero() * HOLD_FORWARD - Vector::Z * HOLD_BELOW
}

/// The arm values putting the hand frame at `target` (position only), seeded at `seed`.
fn position_ik(
    m: &ArmMotion,
    seed: &[f32],
    target: Vector,
    rng: &mut fastrand::Rng,
) -> Option<Vec<f32>> {
    let options = IkOptions {
        attempts: 4,
        iterations: 80,
        position_tolerance: 0.01,
        orientation_tolerance: 1.0,
        orientation: false,
    };
    solve_ik(
        &m.setup.model,
        &m.arm.chain,
        m.base,
        &m.full(seed),
        Pose::from_translation(target),
        &options,
        rng,
    )
    .ok()
    .map(|s| robot::arm_values(m.arm, &s.configuration))
}
