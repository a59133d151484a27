//! Whether a robot's jaws hold what they carry, in each trajectory that declares `holding` and
//! its gripper (`joint_trajectory.gripper_joint`): a finger of the holding hand (a link of its
//! `hands` entry that moves relative to the tool frame somewhere in the plan; any of its links
//! where none does) lies within [`GRIP_GAP`] of the object at the trajectory's end, and at its
//! first frame where the object has left where the trajectory found it (by more than
//! [`MOVED`]). A gripper that never closes on its object, opens while it carries it, or closes
//! only once the object is rising, leaves none there.

use parry3d::math::Pose;

use crate::bodies::{Owner, Placed, postures, within};
use crate::model::{AgentKind, Plan, Step, Trajectory};
use crate::report::{Fault, FaultKind};
use crate::world::World;

/// How far (metres) a finger may stand from the object it grips.
pub const GRIP_GAP: f32 = 0.003;

/// How far (metres) a held object moves before its jaws must grip it.
pub const MOVED: f32 = 0.001;

/// The holding hand's fingers of trajectory `traj` holding object `o` (see the module docs);
/// none where the trajectory is not a robot's holding `o` with a declared gripper.
fn fingers(plan: &Plan, traj: &Trajectory, o: usize, world: &World) -> Option<(usize, Vec<usize>)> {
    let agent = &plan.agents[traj.agent];
    let hold = world.holds[o].as_ref()?;
    let gripper = traj
        .joint_trajectory
        .as_ref()
        .and_then(|j| j.gripper_joint.as_ref());
    if agent.kind != AgentKind::Robot || hold.agent != traj.agent || gripper.is_none() {
        return None;
    }
    let hand = agent.hands.iter().find(|h| h.links.contains(&hold.link))?;
    let fingers = moving_links(plan, traj.agent, hand.tool, &hand.links);
    Some((
        hand.tool,
        if fingers.is_empty() {
            hand.links.clone()
        } else {
            fingers
        },
    ))
}

/// Whether a link of `fingers` of the trajectory's agent, its links at `poses`, lies within
/// [`GRIP_GAP`] of object `o` at `object`.
fn grips(
    plan: &Plan,
    traj: &Trajectory,
    (o, object): (usize, &Pose),
    fingers: &[usize],
    poses: &[Pose],
) -> bool {
    let agent = &plan.agents[traj.agent];
    let parts: Vec<Placed> = plan.objects[o]
        .parts
        .iter()
        .map(|p| Placed::new(Owner::Held(o), p, object))
        .collect();
    fingers.iter().any(|&l| {
        agent.links[l].parts.iter().any(|p| {
            let link = Placed::new(Owner::Link(traj.agent, l), p, &poses[l]);
            parts.iter().any(|b| within(&link, b, GRIP_GAP))
        })
    })
}

/// A `loose-grip` fault where no finger of the hand grips object `o` at the end of trajectory
/// `traj` (the `k`-th of `step`), the world at that end, or at the trajectory's first frame
/// where the object has moved (by its declared `held_pose`).
pub fn check_grip(
    plan: &Plan,
    (step, k): (&Step, usize),
    traj: &Trajectory,
    o: usize,
    world: &World,
) -> Option<Fault> {
    let (tool, fingers) = fingers(plan, traj, o, world)?;
    let start = traj.frames.first().and_then(|f| f.held_pose);
    let rising = traj.frames.iter().enumerate().find(|(_, f)| {
        matches!((start, f.held_pose), (Some(a), Some(b)) if a.translation.distance(b.translation) > MOVED)
    });
    let (frame, why) = match rising {
        Some((i, f)) if !grips(plan, traj, (o, &f.held_pose?), &fingers, &f.link_poses) => (
            i,
            format!(
                "the object has moved {:.0} mm with no finger of the hand within {:.0} mm of \
                 it: it leaves its place in open jaws",
                start?.translation.distance(f.held_pose?.translation) * 1e3,
                GRIP_GAP * 1e3
            ),
        ),
        _ if !grips(
            plan,
            traj,
            (o, &world.objects[o]),
            &fingers,
            &world.agents[traj.agent],
        ) =>
        {
            (
                traj.frames.len().saturating_sub(1),
                format!(
                    "at the trajectory's end no finger of the hand is within {:.0} mm of the \
                 object it holds: the jaws do not close on it",
                    GRIP_GAP * 1e3
                ),
            )
        }
        _ => return None,
    };
    let agent = &plan.agents[traj.agent];
    Some(Fault {
        kind: FaultKind::LooseGrip,
        step: Some(step.index),
        action: step.action.clone(),
        trajectory: Some(traj.label.clone()),
        trajectory_index: Some(k),
        frame: Some(frame.to_string()),
        a: format!("{}/{}", agent.name, agent.links[tool].name),
        b: format!("held {}", plan.objects[o].name),
        depth_mm: 0.0,
        configs: 1,
        detail: why,
    })
}

/// The links of `links` that move relative to link `tool` in some posture of agent `a` in the
/// plan (by more than 1 mm, or 1 mrad): the fingers.
fn moving_links(plan: &Plan, a: usize, tool: usize, links: &[usize]) -> Vec<usize> {
    let all = postures(plan, a);
    let relative = |p: &[Pose], l: usize| p[tool].inverse() * p[l];
    links
        .iter()
        .copied()
        .filter(|&l| {
            let first = relative(all[0], l);
            all.iter().any(|p| {
                let r = relative(p, l);
                r.translation.distance(first.translation) > 1e-3
                    || r.rotation.angle_between(first.rotation) > 1e-3
            })
        })
        .collect()
}
