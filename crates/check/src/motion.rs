//! What a controller would be sent: per agent, the joint values of the timed trajectories in
//! plan order. Rules (see `docs/check.md`):
//! * continuity: a trajectory starts where the agent's previous trajectory (or the scene's
//!   `joint_positions`) left each of its joints and its gripper, within [`CONTINUITY_TOLERANCE`];
//! * kinematics: every frame's link poses are the forward kinematics of the agent's URDF at the
//!   frame's point (the point's joints, the gripper and the joints that follow it, and every
//!   other joint where it was last left), within [`POSITION_TOLERANCE`] and
//!   [`ANGLE_TOLERANCE`]; so are the scene's initial link poses at `joint_positions`.
//!
//! Plans without `joint_trajectory`, `urdf` or `joint_positions` (older files) skip the rules
//! they cannot apply.

use std::collections::BTreeMap;

use parry3d::math::Pose;

use crate::kinematics::{Iso, Kinematics};
use crate::model::{Agent, JointTrajectory, Plan, Step, Trajectory};
use crate::report::{Fault, FaultKind};

/// Largest jump of a joint between two consecutive trajectories (rad or m).
pub const CONTINUITY_TOLERANCE: f64 = 1e-4;
/// Largest distance between a frame's link origin and the forward kinematics' (m).
pub const POSITION_TOLERANCE: f64 = 1e-3;
/// Largest angle between a frame's link rotation and the forward kinematics' (rad).
pub const ANGLE_TOLERANCE: f64 = 1e-3;

/// Per agent, where each joint was last left.
pub struct Controllers {
    state: Vec<BTreeMap<String, f64>>,
    /// The largest distance (m) and angle (rad) of any link from the forward kinematics seen.
    pub largest: (f64, f64),
}

/// Where a fault was found, for the report.
struct At<'a> {
    step: Option<&'a Step>,
    trajectory: Option<(usize, &'a Trajectory)>,
    agent: &'a Agent,
}

impl Controllers {
    /// The scene's joint values, and the faults of its initial link poses.
    pub fn new(plan: &Plan) -> (Controllers, Vec<Fault>) {
        let state: Vec<_> = plan
            .agents
            .iter()
            .map(|a| a.joint_positions.clone())
            .collect();
        let mut faults = Vec::new();
        let mut largest = (0.0, 0.0);
        for (a, q) in plan.agents.iter().zip(&state) {
            if let (Some(k), false) = (&a.kinematics, q.is_empty()) {
                let at = At {
                    step: None,
                    trajectory: None,
                    agent: a,
                };
                let worst = worst_link(k, a, q, &a.link_poses).filter(|w| note(&mut largest, w));
                faults.extend(kinematics_fault(&at, worst.map(|w| (0, w)), 1));
            }
        }
        (Controllers { state, largest }, faults)
    }

    /// The faults of trajectory `k` of `step`; then its agent's joints are left at its end.
    pub fn follow(&mut self, plan: &Plan, step: &Step, k: usize, traj: &Trajectory) -> Vec<Fault> {
        let Some(jt) = &traj.joint_trajectory else {
            return Vec::new();
        };
        let agent = &plan.agents[traj.agent];
        let at = At {
            step: Some(step),
            trajectory: Some((k, traj)),
            agent,
        };
        let state = &mut self.state[traj.agent];
        let mut faults: Vec<Fault> = discontinuity(&at, jt, state).into_iter().collect();
        if let Some(kin) = &agent.kinematics {
            faults.extend(frames_fault(&at, kin, jt, state, &mut self.largest));
        }
        if let Some(last) = jt.points.last() {
            set_point(state, jt, last);
        }
        faults
    }
}

fn set_point(q: &mut BTreeMap<String, f64>, jt: &JointTrajectory, p: &crate::model::JointPoint) {
    for (name, v) in jt.joint_names.iter().zip(&p.positions) {
        q.insert(name.clone(), *v);
    }
    if let (Some(name), Some(v)) = (&jt.gripper_joint, p.gripper) {
        q.insert(name.clone(), v);
        for f in &jt.gripper_followers {
            q.insert(f.clone(), v);
        }
    }
}

/// The worst jump at the trajectory's first point, with how many joints jumped.
fn discontinuity(at: &At, jt: &JointTrajectory, state: &BTreeMap<String, f64>) -> Option<Fault> {
    let first = jt.points.first()?;
    let mut values: Vec<(&String, f64)> = jt
        .joint_names
        .iter()
        .zip(first.positions.iter().copied())
        .collect();
    if let (Some(name), Some(v)) = (&jt.gripper_joint, first.gripper) {
        values.push((name, v));
        values.extend(jt.gripper_followers.iter().map(|f| (f, v)));
    }
    let jumps: Vec<(&String, f64, f64)> = values
        .into_iter()
        .filter_map(|(name, v)| state.get(name).map(|&was| (name, was, v)))
        .filter(|(_, was, v)| (v - was).abs() > CONTINUITY_TOLERANCE)
        .collect();
    let &(name, was, v) = jumps
        .iter()
        .max_by(|a, b| (a.2 - a.1).abs().total_cmp(&(b.2 - b.1).abs()))?;
    Some(fault(
        at,
        FaultKind::Discontinuity,
        "point 0".into(),
        format!("{}/{name}", at.agent.name),
        jumps.len(),
        format!("starts at {v:.6}, left at {was:.6} (jump {:.6})", v - was),
    ))
}

/// The worst frame whose link poses are not the forward kinematics of its point.
fn frames_fault(
    at: &At,
    kin: &Kinematics,
    jt: &JointTrajectory,
    state: &BTreeMap<String, f64>,
    largest: &mut (f64, f64),
) -> Option<Fault> {
    let (_, traj) = at.trajectory?;
    if traj.frames.len() != jt.points.len() {
        let detail = format!(
            "{} frames for {} timed points: frames must be computed from the points",
            traj.frames.len(),
            jt.points.len()
        );
        return Some(fault(
            at,
            FaultKind::Kinematics,
            "all".into(),
            at.agent.name.clone(),
            traj.frames.len(),
            detail,
        ));
    }
    let mut q = state.clone();
    let mut worst: Option<(usize, Worst)> = None;
    let mut bad = 0;
    for (i, (frame, point)) in traj.frames.iter().zip(&jt.points).enumerate() {
        set_point(&mut q, jt, point);
        let beyond = worst_link(kin, at.agent, &q, &frame.link_poses).filter(|w| note(largest, w));
        if let Some(w) = beyond {
            bad += 1;
            if worst.as_ref().is_none_or(|(_, o)| w.score() > o.score()) {
                worst = Some((i, w));
            }
        }
    }
    kinematics_fault(at, worst, bad)
}

/// A link's distance from the forward kinematics.
struct Worst {
    link: String,
    distance: f64,
    angle: f64,
}

impl Worst {
    fn score(&self) -> f64 {
        (self.distance / POSITION_TOLERANCE).max(self.angle / ANGLE_TOLERANCE)
    }
}

/// Records `w` in `largest`; whether it is beyond the tolerances.
fn note(largest: &mut (f64, f64), w: &Worst) -> bool {
    largest.0 = largest.0.max(w.distance);
    largest.1 = largest.1.max(w.angle);
    w.score() > 1.0
}

/// The link farthest (relative to the tolerances) from the forward kinematics.
fn worst_link(
    kin: &Kinematics,
    agent: &Agent,
    q: &BTreeMap<String, f64>,
    poses: &[Pose],
) -> Option<Worst> {
    let fk = kin.link_poses(q);
    let mut worst: Option<Worst> = None;
    for (link, pose) in agent.links.iter().zip(poses) {
        let Some(expected) = fk.get(&link.name) else {
            continue;
        };
        let (distance, angle) = expected.distance(&iso(pose));
        let w = Worst {
            link: link.name.clone(),
            distance,
            angle,
        };
        if worst.as_ref().is_none_or(|o| w.score() > o.score()) {
            worst = Some(w);
        }
    }
    worst
}

fn kinematics_fault(at: &At, worst: Option<(usize, Worst)>, configs: usize) -> Option<Fault> {
    let (frame, w) = worst?;
    let detail = format!(
        "the link is {:.2} mm and {:.4} rad from the forward kinematics of the URDF",
        w.distance * 1e3,
        w.angle
    );
    let frame = if at.trajectory.is_some() {
        frame.to_string()
    } else {
        "initial".to_string()
    };
    Some(fault(
        at,
        FaultKind::Kinematics,
        frame,
        format!("{}/{}", at.agent.name, w.link),
        configs,
        detail,
    ))
}

fn fault(
    at: &At,
    kind: FaultKind,
    frame: String,
    a: String,
    configs: usize,
    detail: String,
) -> Fault {
    Fault {
        kind,
        step: at.step.map(|s| s.index),
        action: at.step.map_or("(scene)".into(), |s| s.action.clone()),
        trajectory: at.trajectory.map(|(_, t)| t.label.clone()),
        trajectory_index: at.trajectory.map(|(k, _)| k),
        frame: Some(frame),
        a,
        b: kind.name().to_string(),
        depth_mm: 0.0,
        configs,
        detail,
    }
}

/// The f64 transform of a link or object pose.
pub(crate) fn iso(p: &Pose) -> Iso {
    let (t, r) = (p.translation, p.rotation);
    Iso {
        q: [r.x, r.y, r.z, r.w].map(f64::from),
        t: [t.x, t.y, t.z].map(f64::from),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::model::JointPoint;

    /// A point's gripper position drives the gripper joint and the joints that follow it.
    #[test]
    fn the_gripper_followers_take_the_gripper_position() {
        let jt = JointTrajectory {
            joint_names: vec!["elbow".into()],
            velocity_limits: vec![1.0],
            acceleration_limits: vec![1.0],
            waypoints: None,
            gripper_joint: Some("l_finger".into()),
            gripper_followers: vec!["r_finger".into()],
            points: vec![JointPoint {
                positions: vec![0.5],
                velocities: vec![0.0],
                time: 0.0,
                gripper: Some(0.03),
            }],
        };
        let mut q = BTreeMap::new();
        set_point(&mut q, &jt, &jt.points[0]);
        assert_eq!(q.get("elbow"), Some(&0.5));
        assert_eq!(q.get("l_finger"), Some(&0.03));
        assert_eq!(q.get("r_finger"), Some(&0.03));
    }
}
