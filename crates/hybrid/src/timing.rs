//! Time parameterisation of a joint-space path: consecutive waypoints are joined by straight
//! segments, each driven by one synchronized trapezoidal (or triangular) velocity profile that
//! starts and ends at rest. Every joint moves along its segment by the same normalised profile
//! `s(t)` from 0 to 1, whose peak rate and acceleration are the largest that keep every joint
//! within its velocity and acceleration limits; the velocity is zero at every waypoint, so the
//! trajectory is continuous in position and velocity and passes through every waypoint exactly.
//!
//! Pure arithmetic, no geometry: the plan export gives it the limits read from the URDF.

/// Acceleration limit of every arm joint when none is given (rad/s^2 or m/s^2).
pub const DEFAULT_JOINT_ACCELERATION: f64 = 1.0;
/// Velocity limit of a joint whose URDF declares none (rad/s or m/s).
pub const DEFAULT_JOINT_VELOCITY: f64 = 1.0;
/// Velocity limit of the planar base's `base_x` and `base_y` (m/s).
pub const BASE_LINEAR_VELOCITY: f64 = 0.5;
/// Velocity limit of the planar base's `base_yaw` (rad/s).
pub const BASE_ANGULAR_VELOCITY: f64 = 1.0;
/// Acceleration limit of `base_x` and `base_y` (m/s^2).
pub const BASE_LINEAR_ACCELERATION: f64 = 0.5;
/// Acceleration limit of `base_yaw` (rad/s^2).
pub const BASE_ANGULAR_ACCELERATION: f64 = 1.0;

/// Largest time step between two samples of a segment (s; 10 Hz); samples are evenly spaced in
/// time.
pub const SAMPLE_STEP: f64 = 0.1;
/// Largest change of any joint between two samples (rad or m), so that the link-pose frames
/// computed from the points are as dense as a swept collision check wants.
pub const POSITION_STEP: f64 = 0.04;
/// Most samples per segment.
pub const MAX_SAMPLES: usize = 400;

/// One timed point: every joint's position and velocity at `time` seconds from the start.
#[derive(Debug, Clone, PartialEq)]
pub struct TimedPoint {
    /// Joint positions, in the order of the waypoints' values.
    pub positions: Vec<f64>,
    /// Joint velocities (per second).
    pub velocities: Vec<f64>,
    /// Seconds from the start of the trajectory.
    pub time: f64,
}

/// Why a path cannot be timed.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum TimingError {
    /// A waypoint's length differs from the number of limits.
    #[error("waypoint {index} has {found} values for {expected} joints")]
    Length {
        /// The waypoint's index.
        index: usize,
        /// Its number of values.
        found: usize,
        /// The number of joints.
        expected: usize,
    },
    /// A limit is not a positive finite number, or a waypoint value is not finite.
    #[error("joint {joint}: {what} must be finite (and limits positive)")]
    NotFinite {
        /// The joint's index.
        joint: usize,
        /// Which number.
        what: &'static str,
    },
}

/// The normalised profile of one segment: `s` rises from 0 to 1 with acceleration `accel` up
/// to the rate `peak`, holds it, then decelerates to rest at `duration`.
#[derive(Debug, Clone, Copy)]
struct Profile {
    accel: f64,
    peak: f64,
    duration: f64,
}

impl Profile {
    /// The fastest rest-to-rest profile over `s` in [0, 1] with rate at most `rate` and
    /// acceleration at most `accel` (both positive and finite).
    fn fastest(rate: f64, accel: f64) -> Profile {
        if rate * rate / accel >= 1.0 {
            // Triangular: accelerate over half the way, decelerate over the other half.
            let peak = accel.sqrt();
            Profile {
                accel,
                peak,
                duration: 2.0 * peak / accel,
            }
        } else {
            Profile {
                accel,
                peak: rate,
                duration: 1.0 / rate + rate / accel,
            }
        }
    }

    /// `(s, ds/dt)` at time `t` in [0, duration].
    fn at(&self, t: f64) -> (f64, f64) {
        let ramp = self.peak / self.accel;
        let t = t.clamp(0.0, self.duration);
        if t <= ramp {
            (0.5 * self.accel * t * t, self.accel * t)
        } else if t >= self.duration - ramp {
            let r = self.duration - t;
            (1.0 - 0.5 * self.accel * r * r, self.accel * r)
        } else {
            (
                0.5 * self.accel * ramp * ramp + self.peak * (t - ramp),
                self.peak,
            )
        }
    }
}

/// Times the path through `waypoints` (each one value per joint) within the per-joint
/// `velocity` and `acceleration` limits, starting and ending at rest and at rest at every
/// waypoint. Segments where no joint moves are skipped. The points are the waypoints (with their
/// exact values) and samples between them at most [`SAMPLE_STEP`] apart in time and
/// at most [`POSITION_STEP`] apart in every joint (up to [`MAX_SAMPLES`] per segment); times strictly
/// increase from 0. An empty path gives no points.
pub fn time_path(
    waypoints: &[Vec<f64>],
    velocity: &[f64],
    acceleration: &[f64],
) -> Result<Vec<TimedPoint>, TimingError> {
    let n = velocity.len();
    for (joint, (v, a)) in velocity.iter().zip(acceleration).enumerate() {
        if !(v.is_finite() && *v > 0.0) {
            return Err(TimingError::NotFinite {
                joint,
                what: "velocity limit",
            });
        }
        if !(a.is_finite() && *a > 0.0) {
            return Err(TimingError::NotFinite {
                joint,
                what: "acceleration limit",
            });
        }
    }
    if acceleration.len() != n {
        return Err(TimingError::Length {
            index: 0,
            found: acceleration.len(),
            expected: n,
        });
    }
    for (index, w) in waypoints.iter().enumerate() {
        if w.len() != n {
            return Err(TimingError::Length {
                index,
                found: w.len(),
                expected: n,
            });
        }
        if let Some(joint) = w.iter().position(|x| !x.is_finite()) {
            return Err(TimingError::NotFinite {
                joint,
                what: "waypoint value",
            });
        }
    }
    let Some(first) = waypoints.first() else {
        return Ok(Vec::new());
    };
    let rest = vec![0.0; n];
    let mut points = vec![TimedPoint {
        positions: first.clone(),
        velocities: rest.clone(),
        time: 0.0,
    }];
    let mut from = first;
    for to in &waypoints[1..] {
        // The normalised rate and acceleration every joint allows on this segment.
        let (mut rate, mut accel) = (f64::INFINITY, f64::INFINITY);
        for j in 0..n {
            let d = (to[j] - from[j]).abs();
            if d > 0.0 {
                rate = rate.min(velocity[j] / d);
                accel = accel.min(acceleration[j] / d);
            }
        }
        if !rate.is_finite() || !accel.is_finite() {
            // No joint moves (or a distance too small to matter): nothing to time.
            continue;
        }
        let profile = Profile::fastest(rate, accel);
        if !(profile.duration.is_finite() && profile.duration > 0.0) {
            continue;
        }
        let start = points.last().map_or(0.0, |p| p.time);
        // Evenly spaced in time, as many as keep the widest-moving joint's change per sample
        // within POSITION_STEP at the profile's peak rate.
        let widest = (0..n).map(|j| (to[j] - from[j]).abs()).fold(0.0, f64::max);
        let by_time = (profile.duration / SAMPLE_STEP).ceil();
        let by_step = (widest * profile.peak * profile.duration / POSITION_STEP).ceil();
        let samples = (by_time.max(by_step) as usize).clamp(1, MAX_SAMPLES);
        for k in 1..samples {
            let t = profile.duration * k as f64 / samples as f64;
            let (s, ds) = profile.at(t);
            points.push(TimedPoint {
                positions: (0..n).map(|j| from[j] + (to[j] - from[j]) * s).collect(),
                velocities: (0..n).map(|j| (to[j] - from[j]) * ds).collect(),
                time: start + t,
            });
        }
        points.push(TimedPoint {
            positions: to.clone(),
            velocities: rest.clone(),
            time: start + profile.duration,
        });
        from = to;
    }
    Ok(points)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn check(points: &[TimedPoint], waypoints: &[Vec<f64>], vel: &[f64], acc: &[f64]) {
        assert_eq!(points[0].time, 0.0);
        assert!(points[0].velocities.iter().all(|v| *v == 0.0));
        assert!(points.last().unwrap().velocities.iter().all(|v| *v == 0.0));
        assert_eq!(&points[0].positions, &waypoints[0]);
        assert_eq!(&points.last().unwrap().positions, waypoints.last().unwrap());
        for w in points.windows(2) {
            let dt = w[1].time - w[0].time;
            assert!(dt > 0.0, "times increase");
            for j in 0..vel.len() {
                assert!(w[1].velocities[j].abs() <= vel[j] * (1.0 + 1e-9));
                let a = (w[1].velocities[j] - w[0].velocities[j]).abs() / dt;
                assert!(a <= acc[j] * (1.0 + 1e-9), "joint {j}: {a} > {}", acc[j]);
                // The mean velocity over the step is what moved the joint.
                let mean = (w[1].positions[j] - w[0].positions[j]) / dt;
                assert!(mean.abs() <= vel[j] * (1.0 + 1e-9));
            }
        }
        // Every waypoint is a point, at rest, in order.
        let mut k = 0;
        for w in waypoints {
            while k < points.len() && &points[k].positions != w {
                k += 1;
            }
            assert!(k < points.len(), "waypoint {w:?} is a point");
            assert!(points[k].velocities.iter().all(|v| *v == 0.0));
        }
    }

    #[test]
    fn long_segment_is_trapezoidal_and_within_limits() {
        let w = vec![vec![0.0, 0.0], vec![3.0, -1.0]];
        let (vel, acc) = ([1.0, 1.0], [1.0, 1.0]);
        let p = time_path(&w, &vel, &acc).unwrap();
        check(&p, &w, &vel, &acc);
        // Joint 0 leads: 3 rad at 1 rad/s with 1 rad/s^2 takes 3 + 1 = 4 s.
        assert!((p.last().unwrap().time - 4.0).abs() < 1e-9);
        let peak = p.iter().map(|q| q.velocities[0]).fold(0.0, f64::max);
        assert!((peak - 1.0).abs() < 1e-9, "reaches its limit");
    }

    #[test]
    fn short_segment_is_triangular() {
        let w = vec![vec![0.0], vec![0.25]];
        let p = time_path(&w, &[1.0], &[1.0]).unwrap();
        check(&p, &w, &[1.0], &[1.0]);
        // 2 sqrt(d / a) = 1 s.
        assert!((p.last().unwrap().time - 1.0).abs() < 1e-9);
    }

    #[test]
    fn slow_joint_sets_the_pace_of_all() {
        let w = vec![
            vec![0.0, 0.0],
            vec![1.0, 1.0],
            vec![1.0, 3.0],
            vec![-2.0, 3.0],
        ];
        let (vel, acc) = ([2.0, 0.3], [1.5, 0.2]);
        let p = time_path(&w, &vel, &acc).unwrap();
        check(&p, &w, &vel, &acc);
    }

    #[test]
    fn repeated_waypoints_are_skipped_and_single_point_is_at_rest() {
        let w = vec![vec![0.5], vec![0.5], vec![1.0], vec![1.0]];
        let p = time_path(&w, &[1.0], &[1.0]).unwrap();
        check(&p, &w, &[1.0], &[1.0]);
        let one = time_path(&[vec![0.2, 0.3]], &[1.0, 1.0], &[1.0, 1.0]).unwrap();
        assert_eq!(one.len(), 1);
        assert_eq!(one[0].time, 0.0);
        assert!(time_path(&[], &[1.0], &[1.0]).unwrap().is_empty());
    }

    #[test]
    fn bad_input_is_an_error_not_a_panic() {
        assert!(time_path(&[vec![0.0]], &[0.0], &[1.0]).is_err());
        assert!(time_path(&[vec![0.0]], &[1.0], &[f64::NAN]).is_err());
        assert!(time_path(&[vec![0.0, 1.0]], &[1.0], &[1.0]).is_err());
        assert!(time_path(&[vec![f64::INFINITY]], &[1.0], &[1.0]).is_err());
        assert!(time_path(&[vec![0.0]], &[1.0], &[1.0, 1.0]).is_err());
    }
}
