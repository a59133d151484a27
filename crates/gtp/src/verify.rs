//! Independent re-checks of a solution: replay its trajectories phase by phase in the world
//! before the task, densified to a finer resolution than the planner used, with fresh
//! collision checkers; and re-measure what the task promised in the world after it.
//!
//! Used by the tests and by `htngtp gtp --verify`.

use std::sync::Arc;

use geometry::collision::{CollisionChecker, Obstacle};
use geometry::scene::{AgentId, ObjectId};
use geometry::world::World;
use parry3d::math::Pose;

use crate::planner::Planner;
use crate::robot::{self, Arm, RobotSetup, set_arm_values, set_opening};
use crate::rrt::{JointPath, JointSpace};
use crate::solution::{Phase, SolutionSummary, Trajectory};

/// Replays every trajectory of `summary` from `before`, checking each configuration at
/// `resolution` (per joint) for collisions, under the rules each trajectory records (what it
/// carries, what it ignores, what its open gripper straddles). Returns the first collision.
pub fn recheck_trajectories(
    planner: &Planner,
    before: &World,
    summary: &SolutionSummary,
    resolution: f32,
) -> Result<(), String> {
    let setup = planner.robot(before).map_err(|e| e.to_string())?;
    let object: Option<ObjectId> = summary.args.first().and_then(|n| before.object_id(n));
    let mut w = before.clone();
    for (ti, t) in summary.trajectories.iter().enumerate() {
        let at = |k: usize, why: String| {
            format!("trajectory {ti} ({:?}), configuration {k}: {why}", t.phase)
        };
        // A person's motions (a take's reach and withdraw) are shown, not planned: nothing to
        // re-check against the robot's model.
        if t.agent != before.agent(setup.agent).name() {
            continue;
        }
        if t.phase == Phase::Drive {
            recheck_drive(&setup, &mut w, t, resolution).map_err(|s| s.worded(at))?;
            continue;
        }
        let arm = setup
            .arms
            .iter()
            .find(|a| a.name == t.arm)
            .ok_or_else(|| format!("trajectory {ti}: unknown arm `{}`", t.arm))?;
        let q = recheck_arm(&setup, arm, &w, object, t, resolution).map_err(|s| s.worded(at))?;
        // The world after this phase.
        let base = w.agent_state(setup.agent).base;
        w.set_agent_config(setup.agent, base, &q);
        if let Some(o) = object {
            after_phase(&mut w, setup.agent, arm, o, summary, ti);
        }
    }
    Ok(())
}

/// Why the replay of a trajectory stopped.
enum Stop {
    /// The trajectory cannot be checked (what it carries, an empty path).
    Invalid(String),
    /// Configuration `.0` collides (`.1` says with what).
    Collision(usize, String),
}

impl From<String> for Stop {
    fn from(e: String) -> Stop {
        Stop::Invalid(e)
    }
}

impl Stop {
    /// In words, a collision worded by `at` (configuration index, reason).
    fn worded(self, at: impl Fn(usize, String) -> String) -> String {
        match self {
            Stop::Invalid(e) => e,
            Stop::Collision(k, why) => at(k, why),
        }
    }
}

/// Replays a base trajectory `t` in `w` at `resolution` and moves the base in `w` to where it
/// ends.
fn recheck_drive(
    setup: &RobotSetup,
    w: &mut World,
    t: &Trajectory,
    resolution: f32,
) -> Result<(), Stop> {
    let robot_id = setup.agent;
    let q = w.agent_state(robot_id).q.clone();
    let obstacles = Arc::new(robot::obstacles(w, robot_id, &[]));
    let mut checker = CollisionChecker::new(
        setup.self_model.clone(),
        obstacles,
        w.agent_state(robot_id).base,
    );
    robot::carry_all(&mut checker, w, setup)?;
    let space = JointSpace::new(&[(-1e3, 1e3, false), (-1e3, 1e3, false), (0.0, 0.0, true)]);
    let path = JointPath {
        waypoints: t.waypoints.clone(),
    };
    for (k, b) in path.densify(&space, resolution).iter().enumerate() {
        checker.set_base(geometry::world::base_pose(b[0], b[1], b[2]));
        if let Some(c) = checker.first_collision(&q) {
            return Err(Stop::Collision(k, c.to_string()));
        }
    }
    let last = t
        .waypoints
        .last()
        .ok_or_else(|| Stop::Invalid("empty trajectory".into()))?;
    w.set_agent_config(
        robot_id,
        geometry::world::base_pose(last[0], last[1], last[2]),
        &q,
    );
    Ok(())
}

/// The collision checkers of an arm trajectory `t` in `w`: what it ignores left out, what it
/// carries held, what the other grippers hold in the way. The object's own support may touch
/// it while it is lifted off (`ignored` names it): then the robot is checked against
/// everything, the held object against the rest.
fn arm_checkers(
    setup: &RobotSetup,
    arm: &Arm,
    w: &World,
    object: Option<ObjectId>,
    t: &Trajectory,
) -> Result<Vec<CollisionChecker>, String> {
    let robot_id = setup.agent;
    let mut skip: Vec<ObjectId> = Vec::new();
    for name in &t.ignored {
        if let Some(id) = w.object_id(name) {
            skip.push(id);
        }
    }
    if let Some(o) = object
        && w.attachment(o).is_some()
    {
        skip.push(o);
    }
    let obstacles = robot::obstacles(w, robot_id, &skip);
    let held = match (&t.held, object) {
        (Some(h), Some(o)) => Some(robot::held_object(
            w,
            setup,
            arm,
            o,
            h.object_in_tool.into(),
        )?),
        _ => None,
    };
    let base = w.agent_state(robot_id).base;
    let mut checkers = Vec::new();
    if held.is_some() && !t.ignored.is_empty() {
        let names: Vec<&str> = t.ignored.iter().map(String::as_str).collect();
        let mut c = CollisionChecker::new(
            setup.self_model.clone(),
            Arc::new(obstacles.without(&names)),
            base,
        );
        c.set_held_object(held);
        checkers.push(c);
        let all_but_object = robot::obstacles(w, robot_id, &object.into_iter().collect::<Vec<_>>());
        checkers.push(CollisionChecker::new(
            setup.self_model.clone(),
            Arc::new(all_but_object),
            base,
        ));
    } else {
        let mut c = CollisionChecker::new(setup.self_model.clone(), Arc::new(obstacles), base);
        c.set_held_object(held);
        checkers.push(c);
    }
    // What the other grippers hold stays where it is, in the arm's way.
    let elsewhere = robot::held_elsewhere(w, setup, arm)?;
    for c in &mut checkers {
        for h in &elsewhere {
            c.add_other_held_object(h.clone());
        }
    }
    Ok(checkers)
}

/// Replays arm trajectory `t` in `w` at `resolution`: the robot's joint values where it ends.
fn recheck_arm(
    setup: &RobotSetup,
    arm: &Arm,
    w: &World,
    object: Option<ObjectId>,
    t: &Trajectory,
    resolution: f32,
) -> Result<Vec<f32>, Stop> {
    let checkers = arm_checkers(setup, arm, w, object, t)?;
    let base = w.agent_state(setup.agent).base;
    let mut q = w.agent_state(setup.agent).q.clone();
    set_opening(&setup.model, arm, &mut q, t.gripper_opening);
    let straddled = match (&t.straddles, object) {
        (Some((_, pose)), Some(o)) => {
            let pose: Pose = (*pose).into();
            Some((w.object(o).shape.clone(), pose * w.object(o).shape_offset))
        }
        _ => None,
    };
    let gripper = arm.gripper.at(t.gripper_opening);
    // The rest of the arm may not touch the straddled object either (only the hand is exempt).
    let around = straddled.as_ref().map(|(shape, pose)| {
        let object = Obstacle {
            name: "the object it straddles".into(),
            pose: *pose,
            shape: shape.clone(),
        };
        robot::around_object(setup, arm, base, object)
    });
    let path = JointPath {
        waypoints: t.waypoints.clone(),
    };
    for (k, qa) in path.densify(&arm.space, resolution).iter().enumerate() {
        set_arm_values(arm, &mut q, qa);
        for checker in &checkers {
            if let Some(c) = checker.first_collision(&q) {
                return Err(Stop::Collision(k, c.to_string()));
            }
        }
        if let Some((shape, pose)) = &straddled {
            let tool = setup.model.link_pose_by_id(base, &q, arm.tool_link);
            if gripper.intersects(&tool, &**shape, pose) {
                return Err(Stop::Collision(
                    k,
                    "the gripper hits the object it straddles".into(),
                ));
            }
        }
        if let Some((checker, hand)) = &around {
            if let Some(c) = checker.first_collision_except(&q, hand) {
                return Err(Stop::Collision(k, c.to_string()));
            }
        }
    }
    Ok(q)
}

/// The world `w` after phase `ti` of `summary` moved object `o`: grasped (attached at the
/// grasp the next trajectory holds it with), or placed (released where the solution declares).
fn after_phase(
    w: &mut World,
    robot_id: AgentId,
    arm: &Arm,
    o: ObjectId,
    summary: &SolutionSummary,
    ti: usize,
) {
    match summary.trajectories[ti].phase {
        Phase::Grasp => {
            let next_held = summary
                .trajectories
                .get(ti + 1)
                .and_then(|n| n.held.clone());
            if let Some(h) = next_held {
                w.attach_with_grasp(o, robot_id, arm.tool_link, h.object_in_tool.into());
            }
        }
        Phase::Place => {
            // Released at the placement the solution declares (and its world holds), within
            // the inverse kinematics' tolerance of where the gripper left it.
            w.detach(o);
            if let Some(p) = &summary.placement {
                w.set_object_pose(o, p.pose.into());
            }
        }
        _ => {}
    }
}
