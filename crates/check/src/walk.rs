//! The replay: steps in order, each trajectory swept, then the rest state and the literals.

use std::collections::BTreeSet;

use crate::Options;
use crate::bodies::Adjacency;
use crate::grip::check_grip;
use crate::literals::{check_literals, check_persisting};
use crate::model::{Literal, Plan, Step, Trajectory};
use crate::motion::Controllers;
use crate::report::{Fault, FaultKind, Report};
use crate::rest::check_rest;
use crate::sweep::{Carry, Sweep};
use crate::timing::check_timing;
use crate::world::World;

/// Check a whole plan.
pub fn check_plan(plan: &Plan, opts: &Options) -> Report {
    let adjacency: Vec<Adjacency> = (0..plan.agents.len())
        .map(|a| Adjacency::new(plan, a))
        .collect();
    let (trajectories, frames) = plan.counts();
    let mut report = Report {
        status: plan.status.clone().filter(|s| s != "solved"),
        steps: plan.steps.len(),
        trajectories,
        frames,
        ..Report::default()
    };
    let (mut controllers, initial_faults) = Controllers::new(plan);
    report.faults.extend(initial_faults);
    let mut world = World::initial(plan);
    let mut resting = check_rest(plan, &world, None, opts, &BTreeSet::new(), &mut report);
    // The claimed state, when the plan says where it starts.
    let mut state: Option<BTreeSet<&Literal>> =
        plan.initial_literals.as_ref().map(|l| l.iter().collect());
    for step in &plan.steps {
        release_handed_over(plan, step, &mut world);
        let mut declared = BTreeSet::new();
        for (k, traj) in step.trajectories.iter().enumerate() {
            let agent = &plan.agents[traj.agent].name;
            report.faults.extend(check_timing(step, k, traj, agent));
            report
                .faults
                .extend(controllers.follow(plan, step, k, traj));
            let ctx = (step, k, &adjacency[traj.agent]);
            run_trajectory(
                plan,
                ctx,
                traj,
                &mut world,
                &mut declared,
                opts,
                &mut report,
            );
        }
        for (o, p) in &step.object_poses {
            world.objects[*o] = *p;
        }
        resting = check_rest(plan, &world, Some(step), opts, &resting, &mut report);
        report.literals += check_literals(plan, &world, step, &mut report.faults);
        if let Some(state) = &mut state {
            for l in &step.deleted {
                state.remove(l);
            }
            if !step.trajectories.is_empty() {
                let persisting = state.iter().copied().filter(|l| !step.added.contains(l));
                report.literals +=
                    check_persisting(plan, &world, step, persisting, &mut report.faults);
            }
            state.extend(&step.added);
        }
    }
    report.kinematics_max_mm = controllers.largest.0 * 1e3;
    report.kinematics_max_rad = controllers.largest.1;
    report
}

/// An object that another agent declares holding during this step changes hands: the one who
/// held it lets go when the step begins.
fn release_handed_over(plan: &Plan, step: &Step, world: &mut World) {
    for o in 0..plan.objects.len() {
        let Some(h) = &world.holds[o] else { continue };
        let taker = step
            .trajectories
            .iter()
            .any(|t| t.holding == Some(o) && t.agent != h.agent);
        if taker {
            world.holds[o] = None;
        }
    }
}

/// Sweep one trajectory and move the world to its end.
fn run_trajectory(
    plan: &Plan,
    (step, k, adjacency): (&Step, usize, &Adjacency),
    traj: &Trajectory,
    world: &mut World,
    declared: &mut BTreeSet<usize>,
    opts: &Options,
    report: &mut Report,
) {
    let a = traj.agent;
    // Let go of what this agent held earlier in the step and no longer declares (place, retreat).
    for o in 0..plan.objects.len() {
        let mine = world.holds[o].as_ref().is_some_and(|h| h.agent == a);
        if mine && traj.holding != Some(o) && declared.contains(&o) {
            world.holds[o] = None;
        }
    }
    let held = match traj.holding {
        Some(o) => {
            declared.insert(o);
            Some((o, declared_carry(plan, traj, o, world)))
        }
        None => undeclared_carry(plan, step, k, traj, world, &mut report.faults),
    };
    let sweep = Sweep {
        plan,
        step,
        index: k,
        traj,
        held,
        adjacency,
        depth: opts.depth,
        grasp_depth: opts.grasp_depth,
        sub: opts.sub,
    };
    let (found, configs) = sweep.run(world);
    report.configs += configs;
    report.faults.extend(found.into_values());
    let last = traj.frames.last().map(|f| f.link_poses.clone());
    if let (Some((o, carry)), Some(end)) = (held, &last) {
        world.objects[o] = match carry {
            Carry::Rigid { link, rel } => end[link] * rel,
            Carry::Declared => traj
                .frames
                .last()
                .and_then(|f| f.held_pose)
                .unwrap_or(world.objects[o]),
        };
    }
    if let Some(end) = last {
        world.agents[a] = end;
    }
    if let Some(o) = traj.holding {
        report
            .faults
            .extend(check_grip(plan, (step, k), traj, o, world));
    }
}

/// How a declared held object moves: by `held_pose`, or rigidly with the hand where a frame
/// lacks one. Starts the hold when the agent did not hold it yet.
fn declared_carry(plan: &Plan, traj: &Trajectory, o: usize, world: &mut World) -> Carry {
    let first = &traj.frames[0];
    let start = first.held_pose.unwrap_or(world.objects[o]);
    let holder = world.holds[o].as_ref().map(|h| h.agent);
    if holder != Some(traj.agent) {
        world.grasp(plan, traj.agent, o, &first.link_poses, &start);
    }
    if traj.frames.iter().all(|f| f.held_pose.is_some()) {
        return Carry::Declared;
    }
    match &world.holds[o] {
        Some(h) => Carry::Rigid {
            link: h.link,
            rel: first.link_poses[h.link].inverse() * world.objects[o],
        },
        None => Carry::Declared,
    }
}

/// An object the agent still holds while the trajectory says `holding: null`: if the hand moves,
/// the object goes with it (checked so) and the omission is a fault.
fn undeclared_carry(
    plan: &Plan,
    step: &Step,
    k: usize,
    traj: &Trajectory,
    world: &World,
    faults: &mut Vec<Fault>,
) -> Option<(usize, Carry)> {
    let (o, h) = world
        .holds
        .iter()
        .enumerate()
        .find_map(|(o, h)| h.as_ref().filter(|h| h.agent == traj.agent).map(|h| (o, h)))?;
    let start = traj.frames[0].link_poses[h.link];
    let moved = traj
        .frames
        .iter()
        .map(|f| f.link_poses[h.link].translation.distance(start.translation))
        .fold(0.0f32, f32::max);
    if moved <= 1e-3 {
        return None;
    }
    let agent = &plan.agents[traj.agent];
    faults.push(Fault {
        kind: FaultKind::UndeclaredCarry,
        step: Some(step.index),
        action: step.action.clone(),
        trajectory: Some(traj.label.clone()),
        trajectory_index: Some(k),
        frame: None,
        a: format!("{}/{}", agent.name, agent.links[h.link].name),
        b: format!("held {}", plan.objects[o].name),
        depth_mm: 0.0,
        configs: traj.frames.len(),
        detail: format!("the hand moves {moved:.2} m with `holding: null`; checked as carried"),
    });
    let rel = start.inverse() * world.objects[o];
    Some((o, Carry::Rigid { link: h.link, rel }))
}
