//! Timed joint trajectories: each `joint_trajectory` is checked against the limits it declares,
//! using only its own numbers. Rules (see `docs/check.md`):
//! * `time_from_start` is 0 at the first point and strictly increases;
//! * every velocity at the first and last point is 0 (the trajectory starts and ends at rest);
//! * every |velocity| and every mean speed between consecutive points (position change over
//!   time) is within the joint's velocity limit;
//! * the acceleration implied by consecutive points (velocity change over time) is within the
//!   joint's acceleration limit;
//! * the first and last points' positions are the first and last waypoints, when declared.
//!
//! Violations of one rule on one joint of one trajectory are one fault: the worst point, with how
//! many points showed it.

use std::collections::BTreeMap;

use crate::model::{JointTrajectory, Step, Trajectory};
use crate::report::{Fault, FaultKind};

/// Relative tolerance on limits (rounding of the JSON's numbers).
pub const LIMIT_TOLERANCE: f64 = 1e-6;
/// Absolute tolerance on velocities at rest, times and waypoint positions (rad, m, s).
pub const VALUE_TOLERANCE: f64 = 1e-6;

/// One rule broken at one point: the rule, the joint (`None`: the whole point), the point, how
/// far over, and the measurement in words.
struct Breach {
    rule: &'static str,
    joint: Option<usize>,
    point: usize,
    excess: f64,
    detail: String,
}

/// The timing faults of trajectory `k` of `step` (none when it has no joint trajectory).
pub fn check_timing(step: &Step, k: usize, traj: &Trajectory, agent: &str) -> Vec<Fault> {
    let Some(jt) = &traj.joint_trajectory else {
        return Vec::new();
    };
    // Worst breach and count per (rule, joint).
    let mut worst: BTreeMap<(&'static str, Option<usize>), (Breach, usize)> = BTreeMap::new();
    for b in breaches(jt) {
        let e = worst.entry((b.rule, b.joint)).or_insert((
            Breach {
                rule: b.rule,
                joint: b.joint,
                point: b.point,
                excess: f64::NEG_INFINITY,
                detail: String::new(),
            },
            0,
        ));
        e.1 += 1;
        if b.excess > e.0.excess {
            e.0 = b;
        }
    }
    worst
        .into_values()
        .map(|(b, configs)| Fault {
            kind: FaultKind::Timing,
            step: Some(step.index),
            action: step.action.clone(),
            trajectory: Some(traj.label.clone()),
            trajectory_index: Some(k),
            frame: Some(format!("point {}", b.point)),
            a: match b.joint.and_then(|j| jt.joint_names.get(j)) {
                Some(name) => format!("{agent}/{name}"),
                None => agent.to_string(),
            },
            b: b.rule.to_string(),
            depth_mm: 0.0,
            configs,
            detail: b.detail,
        })
        .collect()
}

/// Whether `value` exceeds `limit` by more than the tolerance.
fn over(value: f64, limit: f64) -> bool {
    value > limit * (1.0 + LIMIT_TOLERANCE) + 1e-9
}

fn breaches(jt: &JointTrajectory) -> Vec<Breach> {
    let mut out = Vec::new();
    let Some(first) = jt.points.first() else {
        out.push(Breach {
            rule: "no points",
            joint: None,
            point: 0,
            excess: 0.0,
            detail: "a joint trajectory needs at least one point".into(),
        });
        return out;
    };
    if first.time.abs() > VALUE_TOLERANCE {
        out.push(Breach {
            rule: "start time",
            joint: None,
            point: 0,
            excess: first.time.abs(),
            detail: format!("time_from_start {} s, not 0", first.time),
        });
    }
    let last_index = jt.points.len() - 1;
    for (i, p) in [(0, first), (last_index, &jt.points[last_index])] {
        let rule = if i == 0 {
            "start at rest"
        } else {
            "end at rest"
        };
        for (j, v) in p.velocities.iter().enumerate() {
            if v.abs() > VALUE_TOLERANCE {
                out.push(Breach {
                    rule,
                    joint: Some(j),
                    point: i,
                    excess: v.abs(),
                    detail: format!("velocity {v:.6}, not 0"),
                });
            }
        }
    }
    for (i, p) in jt.points.iter().enumerate() {
        for (j, v) in p.velocities.iter().enumerate() {
            let limit = jt.velocity_limits[j];
            if over(v.abs(), limit) {
                out.push(Breach {
                    rule: "velocity limit",
                    joint: Some(j),
                    point: i,
                    excess: v.abs() - limit,
                    detail: format!("|velocity| {:.6} > limit {limit}", v.abs()),
                });
            }
        }
    }
    for (i, w) in jt.points.windows(2).enumerate() {
        let dt = w[1].time - w[0].time;
        if dt <= 0.0 {
            out.push(Breach {
                rule: "time order",
                joint: None,
                point: i + 1,
                excess: -dt,
                detail: format!(
                    "time_from_start {} s after {} s: times must strictly increase",
                    w[1].time, w[0].time
                ),
            });
            continue;
        }
        for j in 0..jt.joint_names.len() {
            let speed = (w[1].positions[j] - w[0].positions[j]).abs() / dt;
            let limit = jt.velocity_limits[j];
            if over(speed, limit) {
                out.push(Breach {
                    rule: "velocity limit",
                    joint: Some(j),
                    point: i + 1,
                    excess: speed - limit,
                    detail: format!(
                        "mean speed {speed:.6} since the previous point > limit {limit}"
                    ),
                });
            }
            let accel = (w[1].velocities[j] - w[0].velocities[j]).abs() / dt;
            let limit = jt.acceleration_limits[j];
            if over(accel, limit) {
                out.push(Breach {
                    rule: "acceleration limit",
                    joint: Some(j),
                    point: i + 1,
                    excess: accel - limit,
                    detail: format!("|acceleration| {accel:.6} > limit {limit}"),
                });
            }
        }
    }
    if let Some(ws) = jt.waypoints.as_ref().filter(|w| !w.is_empty()) {
        let ends = [
            ("start waypoint", 0, &ws[0]),
            ("end waypoint", last_index, &ws[ws.len() - 1]),
        ];
        for (rule, i, w) in ends {
            for (j, (p, x)) in jt.points[i].positions.iter().zip(w).enumerate() {
                if (p - x).abs() > VALUE_TOLERANCE {
                    out.push(Breach {
                        rule,
                        joint: Some(j),
                        point: i,
                        excess: (p - x).abs(),
                        detail: format!("position {p:.6}, waypoint {x:.6}"),
                    });
                }
            }
        }
    }
    out
}
