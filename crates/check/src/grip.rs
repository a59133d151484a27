//! Whether a robot's jaws hold what they carry: at the end of each trajectory that declares
//! `holding` and its gripper (`joint_trajectory.gripper_joint`), a finger of the holding hand
//! (a link of its `hands` entry that moves relative to the tool frame somewhere in the plan;
//! any of its links where none does) lies within [`GRIP_GAP`] of the object. A gripper that
//! never closes on its object, or opens while it carries it, leaves none there.

use parry3d::math::Pose;

use crate::bodies::{Owner, Placed, postures, within};
use crate::model::{AgentKind, Plan, Step, Trajectory};
use crate::report::{Fault, FaultKind};
use crate::world::World;

/// How far (metres) a finger may stand from the object it grips.
pub const GRIP_GAP: f32 = 0.003;

/// A `loose-grip` fault where no finger of the hand grips object `o` at the end of trajectory
/// `traj` (the `k`-th of `step`), the world at that end.
pub fn check_grip(
    plan: &Plan,
    (step, k): (&Step, usize),
    traj: &Trajectory,
    o: usize,
    world: &World,
) -> Option<Fault> {
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
    let fingers = if fingers.is_empty() {
        hand.links.clone()
    } else {
        fingers
    };
    let poses = &world.agents[traj.agent];
    let object: Vec<Placed> = plan.objects[o]
        .parts
        .iter()
        .map(|p| Placed::new(Owner::Held(o), p, &world.objects[o]))
        .collect();
    let touches = |l: usize| {
        agent.links[l].parts.iter().any(|p| {
            let link = Placed::new(Owner::Link(traj.agent, l), p, &poses[l]);
            object.iter().any(|b| within(&link, b, GRIP_GAP))
        })
    };
    if fingers.iter().any(|&l| touches(l)) {
        return None;
    }
    Some(Fault {
        kind: FaultKind::LooseGrip,
        step: Some(step.index),
        action: step.action.clone(),
        trajectory: Some(traj.label.clone()),
        trajectory_index: Some(k),
        frame: Some(traj.frames.len().saturating_sub(1).to_string()),
        a: format!("{}/{}", agent.name, agent.links[hand.tool].name),
        b: format!("held {}", plan.objects[o].name),
        depth_mm: 0.0,
        configs: 1,
        detail: format!(
            "at the trajectory's end no finger of the hand is within {:.0} mm of the object \
             it holds: the jaws do not close on it",
            GRIP_GAP * 1e3
        ),
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
