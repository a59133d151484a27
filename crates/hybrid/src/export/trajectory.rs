//! One trajectory of the plan JSON: its timed joint points (`joint_trajectory`) and, computed
//! from exactly those points, every link's pose per frame for the viewer (one frame per point,
//! at the point's `time_from_start`).
//!
//! Continuous joints (and the planar base's yaw) are unwrapped: each trajectory is shifted by
//! whole turns so that it starts where the same joint was left by the agent's previous
//! trajectory, so a controller never sees a jump of 2*pi between two of them.

use std::collections::BTreeMap;
use std::f64::consts::TAU;

use geometry::agent::{AgentModel, JointKind};
use geometry::scene::AgentId;
use geometry::world::World;
use gtp::solution::Trajectory;
use parry3d::math::Pose;
use serde_json::{Value, json};

use super::{link_poses_json, pose_json};
use crate::timing;

/// Settings of the exported timing.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TimingOptions {
    /// Acceleration limit of every arm joint whose URDF declares none (rad/s^2 or m/s^2).
    pub joint_acceleration: f64,
}

impl Default for TimingOptions {
    fn default() -> Self {
        TimingOptions {
            joint_acceleration: timing::DEFAULT_JOINT_ACCELERATION,
        }
    }
}

/// Where the export last left each joint of each agent (by joint name; the base as `base_x`,
/// `base_y`, `base_yaw`), unwrapped: the values a controller has been sent so far.
#[derive(Clone, Debug, Default)]
pub struct JointTracker {
    last: BTreeMap<(String, String), f64>,
}

impl JointTracker {
    /// The configuration of every agent of `world` (what the plan JSON's scene declares).
    pub fn of_world(world: &World) -> JointTracker {
        let mut last = BTreeMap::new();
        for id in world.agent_ids() {
            let name = world.agent(id).name().to_string();
            for (joint, value) in joint_positions(world, id) {
                last.insert((name.clone(), joint), value);
            }
        }
        JointTracker { last }
    }

    fn get(&self, agent: &str, joint: &str) -> Option<f64> {
        self.last
            .get(&(agent.to_string(), joint.to_string()))
            .copied()
    }

    fn set(&mut self, agent: &str, joint: &str, value: f64) {
        self.last
            .insert((agent.to_string(), joint.to_string()), value);
    }
}

/// Every joint value of agent `id` in `world` by name, the planar base's included.
pub fn joint_positions(world: &World, id: AgentId) -> BTreeMap<String, f64> {
    let state = world.agent_state(id);
    let model = &world.agent(id).model;
    let mut out: BTreeMap<String, f64> = model
        .dof_names()
        .iter()
        .zip(&state.q)
        .map(|(n, &v)| (n.clone(), f64::from(v)))
        .collect();
    let b = state.base;
    out.insert("base_x".into(), f64::from(b.translation.x));
    out.insert("base_y".into(), f64::from(b.translation.y));
    out.insert("base_yaw".into(), f64::from(yaw_of(b)));
    out
}

/// The yaw of a base pose (a pure turn about z).
fn yaw_of(p: Pose) -> f32 {
    2.0 * p.rotation.z.atan2(p.rotation.w)
}

/// Whether the joint `name` of `model` turns without limits (so whole turns may be added).
fn is_continuous(model: &AgentModel, name: &str) -> bool {
    name == "base_yaw"
        || model
            .joint_id(name)
            .is_some_and(|j| model.joints()[j].kind == JointKind::Continuous)
}

/// The velocity and acceleration limits of the joint `name` of `model`: the planar base's
/// defaults for `base_x`, `base_y` and `base_yaw`, else the URDF's velocity limit (or
/// [`timing::DEFAULT_JOINT_VELOCITY`] where it declares none) and its URDF 1.2 acceleration
/// limit (or `opts.joint_acceleration`, as for the shipped models).
pub fn joint_limits(model: &AgentModel, name: &str, opts: &TimingOptions) -> (f64, f64) {
    match name {
        "base_x" | "base_y" => (
            timing::BASE_LINEAR_VELOCITY,
            timing::BASE_LINEAR_ACCELERATION,
        ),
        "base_yaw" => (
            timing::BASE_ANGULAR_VELOCITY,
            timing::BASE_ANGULAR_ACCELERATION,
        ),
        _ => {
            let dof = model.dof_index(name).ok();
            (
                dof.and_then(|d| model.dof_velocity_limit(d))
                    .map_or(timing::DEFAULT_JOINT_VELOCITY, f64::from),
                dof.and_then(|d| model.dof_acceleration_limit(d))
                    .map_or(opts.joint_acceleration, f64::from),
            )
        }
    }
}

/// The waypoints of `t` in f64, continuous joints shifted by whole turns to start nearest to
/// where `tracker` last left them.
fn unwrapped_waypoints(
    model: &AgentModel,
    t: &Trajectory,
    tracker: &JointTracker,
) -> Vec<Vec<f64>> {
    let mut waypoints: Vec<Vec<f64>> = t
        .waypoints
        .iter()
        .map(|w| w.iter().map(|&x| f64::from(x)).collect())
        .collect();
    let Some(first) = waypoints.first().cloned() else {
        return waypoints;
    };
    for (i, joint) in t.joints.iter().enumerate() {
        let (Some(&start), Some(last)) = (first.get(i), tracker.get(&t.agent, joint)) else {
            continue;
        };
        if !is_continuous(model, joint) {
            continue;
        }
        let shift = TAU * ((last - start) / TAU).round();
        if shift != 0.0 {
            for w in &mut waypoints {
                if let Some(v) = w.get_mut(i) {
                    *v += shift;
                }
            }
        }
    }
    waypoints
}

/// What the exported trajectory needs besides the trajectory itself.
pub struct TrajectoryContext<'a> {
    /// The robot's arm that moves, when the agent is the robot (its tool frame carries the held
    /// object; its gripper opens or closes).
    pub arm: Option<&'a gtp::robot::Arm>,
    /// The link that holds the trajectory's held object when no arm moves (a base drive inside
    /// a task, after the pick that took it): the tool link of the arm that last carried it.
    pub held_link: Option<usize>,
    /// Timing settings.
    pub opts: &'a TimingOptions,
}

/// The JSON of trajectory `t` starting from `world`: `joint_trajectory` (timed points with the
/// gripper's position and the held object per point) and one frame of link poses per point.
/// Returns the world with the agent at the trajectory's end, and updates `tracker`.
pub fn trajectory_json(
    world: &World,
    t: &Trajectory,
    cx: &TrajectoryContext,
    tracker: &mut JointTracker,
) -> (Value, World) {
    let mut world = world.clone();
    let Some(agent) = world.agent_id(&t.agent) else {
        return (Value::Null, world);
    };
    let model = world.agent(agent).model.clone();
    let waypoints = unwrapped_waypoints(&model, t, tracker);
    let (velocity, acceleration): (Vec<f64>, Vec<f64>) = t
        .joints
        .iter()
        .map(|j| joint_limits(&model, j, cx.opts))
        .unzip();
    let Ok(points) = timing::time_path(&waypoints, &velocity, &acceleration) else {
        // Mismatched lengths or non-finite values, which the planner never writes.
        return (Value::Null, world);
    };
    let tool_link = cx
        .arm
        .map(|a| a.tool_link)
        .or_else(|| attached_link(&world, agent, t))
        .or_else(|| t.held.as_ref().and(cx.held_link))
        .or_else(|| model.chain(&t.arm).ok().map(|c| c.tip_link));
    // The finger joint's value for the jaw opening, by the arm's gripper model (half the
    // opening for sliding fingers, an angle for turning ones).
    let gripper = cx
        .arm
        .and_then(|a| Some((a, a.gripper_dof?)))
        .map(|(a, k)| {
            let from = world.agent_state(agent).q[k];
            let to = model.dof_limits()[k].clamp(a.gripper.joint_value(t.gripper_opening));
            (k, from, to, a.gripper_followers.as_slice())
        });
    let holding = t.held.as_ref().map(|h| h.object.clone());
    // The gripper moves to the trajectory's opening first, the arm still (closing on an object
    // before lifting it, opening before leaving it), then the arm moves.
    let lead = gripper
        .map(|(k, from, to, _)| gripper_lead(&model, k, (from, to), cx.opts))
        .unwrap_or_default();
    let points = with_lead(points, &lead);
    let (mut frames, mut json_points) = (Vec::new(), Vec::new());
    for (j, p) in points.iter().enumerate() {
        let state = world.agent_state(agent);
        let (mut base, mut q) = (state.base, state.q.clone());
        let mut gripper_position = Value::Null;
        if let Some((k, _, to, followers)) = gripper {
            q[k] = lead.get(j).map_or(to, |&(_, v)| v as f32);
            for &f in followers {
                q[f] = q[k];
            }
            gripper_position = json!(q[k]);
        }
        base = set_point(&model, &t.joints, &p.positions, base, &mut q);
        world.set_agent_config(agent, base, &q);
        let poses = world.agent_state(agent).link_poses();
        let held = match (&t.held, tool_link) {
            (Some(h), Some(link)) => pose_json(poses[link] * Pose::from(h.object_in_tool)),
            _ => Value::Null,
        };
        frames.push(json!({
            "t": p.time,
            "link_poses": link_poses_json(&world, agent, poses),
            "held_pose": held,
        }));
        json_points.push(json!({
            "positions": p.positions,
            "velocities": p.velocities,
            "time_from_start": p.time,
            "gripper_position": gripper_position,
            "holding": holding,
        }));
    }
    if let Some(last) = points.last() {
        for (joint, v) in t.joints.iter().zip(&last.positions) {
            tracker.set(&t.agent, joint, *v);
        }
    }
    let gripper_joint = gripper.map(|(k, ..)| model.dof_names()[k].clone());
    let followers: Vec<String> = gripper
        .map(|(.., f)| f.iter().map(|&k| model.dof_names()[k].clone()).collect())
        .unwrap_or_default();
    if let (Some((k, ..)), Some(name)) = (gripper, &gripper_joint) {
        let v = f64::from(world.agent_state(agent).q[k]);
        for joint in std::iter::once(name).chain(&followers) {
            tracker.set(&t.agent, joint, v);
        }
    }
    // The frames and points are moved in, not copied: `json!` would copy them.
    let mut value = json!({
        "agent": t.agent,
        "label": t.phase,
        "holding": holding,
        "frames": null,
        "joint_trajectory": {
            "agent": t.agent,
            "group": t.arm,
            "joint_names": t.joints,
            "gripper_joint": gripper_joint,
            "gripper_followers": followers,
            "velocity_limits": velocity,
            "acceleration_limits": acceleration,
            "waypoints": waypoints,
            "points": null,
        },
    });
    value["frames"] = Value::Array(frames);
    value["joint_trajectory"]["points"] = Value::Array(json_points);
    (value, world)
}

/// The gripper's motion from value `from` to `to` of degree of freedom `k`, timed within its
/// limits: (seconds, value) per point; none where it does not move.
fn gripper_lead(
    model: &AgentModel,
    k: usize,
    (from, to): (f32, f32),
    opts: &TimingOptions,
) -> Vec<(f64, f64)> {
    if (to - from).abs() <= 1e-6 {
        return Vec::new();
    }
    let (v, a) = joint_limits(model, &model.dof_names()[k], opts);
    let path = [vec![f64::from(from)], vec![f64::from(to)]];
    match timing::time_path(&path, &[v], &[a]) {
        Ok(timed) => timed.iter().map(|p| (p.time, p.positions[0])).collect(),
        Err(_) => Vec::new(),
    }
}

/// `points` after the gripper's `lead`: the first point held still through the lead's times,
/// then the rest shifted by its duration.
fn with_lead(points: Vec<timing::TimedPoint>, lead: &[(f64, f64)]) -> Vec<timing::TimedPoint> {
    let (Some(first), Some(&(duration, _))) = (points.first(), lead.last()) else {
        return points;
    };
    let still = |time: f64| timing::TimedPoint {
        positions: first.positions.clone(),
        velocities: vec![0.0; first.velocities.len()],
        time,
    };
    let mut out: Vec<timing::TimedPoint> = lead.iter().map(|&(time, _)| still(time)).collect();
    out.extend(points.into_iter().skip(1).map(|mut p| {
        p.time += duration;
        p
    }));
    out
}

/// Writes one point's `positions` of `joints` into the base pose and the configuration `q`;
/// returns the base pose.
fn set_point(
    model: &AgentModel,
    joints: &[String],
    positions: &[f64],
    base: Pose,
    q: &mut [f32],
) -> Pose {
    let (mut bx, mut by, mut yaw) = (base.translation.x, base.translation.y, None);
    for (name, &v) in joints.iter().zip(positions) {
        let v = v as f32;
        match name.as_str() {
            "base_x" => bx = v,
            "base_y" => by = v,
            "base_yaw" => yaw = Some(v),
            _ => {
                if let Ok(d) = model.dof_index(name) {
                    q[d] = v;
                }
            }
        }
    }
    if joints.iter().any(|j| j.starts_with("base_")) {
        geometry::world::base_pose(bx, by, yaw.unwrap_or_else(|| yaw_of(base)))
    } else {
        base
    }
}

/// The link of `agent` that the object `t` carries is attached to in `world` (a drive carries
/// what the grippers hold).
fn attached_link(world: &World, agent: AgentId, t: &Trajectory) -> Option<usize> {
    let o = world.object_id(&t.held.as_ref()?.object)?;
    world
        .attachment(o)
        .filter(|a| a.agent == agent)
        .map(|a| a.link)
}

#[cfg(test)]
mod tests {
    use super::*;
    use gtp::solution::Phase;

    fn pr2() -> AgentModel {
        let path = concat!(env!("CARGO_MANIFEST_DIR"), "/../../models/pr2.urdf");
        AgentModel::from_urdf_file(path).expect("the shipped PR2 model")
    }

    fn moving(joints: &[&str], waypoints: Vec<Vec<f32>>) -> Trajectory {
        Trajectory {
            phase: Phase::Approach,
            agent: "pr2".into(),
            arm: "right_arm".into(),
            joints: joints.iter().map(|j| j.to_string()).collect(),
            waypoints,
            held: None,
            gripper_opening: 0.08,
            ignored: Vec::new(),
            straddles: None,
            length: 0.0,
        }
    }

    #[test]
    fn continuous_joints_and_the_base_yaw_start_where_they_were_left() {
        let mut tracker = JointTracker::default();
        tracker.set("pr2", "r_forearm_roll_joint", 6.0);
        tracker.set("pr2", "r_shoulder_pan_joint", 0.0);
        tracker.set("pr2", "base_yaw", -3.1);
        let joints = ["r_forearm_roll_joint", "r_shoulder_pan_joint", "base_yaw"];
        let t = moving(&joints, vec![vec![-0.2, 0.1, 3.1], vec![-0.1, 0.2, 3.0]]);
        let w = unwrapped_waypoints(&pr2(), &t, &tracker);
        let turn = std::f64::consts::TAU;
        let close = |a: f64, b: f64| (a - b).abs() < 1e-6;
        // A whole turn is added to the roll (6.0 is nearest -0.2 + 2 pi) and taken from the yaw.
        assert!(
            close(w[0][0], -0.2 + turn) && close(w[1][0], -0.1 + turn),
            "{w:?}"
        );
        // A limited joint is never shifted.
        assert!(close(w[0][1], 0.1) && close(w[1][1], 0.2), "{w:?}");
        assert!(
            close(w[0][2], 3.1 - turn) && close(w[1][2], 3.0 - turn),
            "{w:?}"
        );
    }
}
