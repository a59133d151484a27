//! Inverse kinematics for a serial chain (an arm to its tool or hand frame, or the head to its
//! eye frame): find joint values that put the chain's tip at a target pose.
//!
//! The solver is numerical: damped least squares (Levenberg-Marquardt) on the 6D pose error
//! (position error in metres, orientation error as a rotation vector in radians), using the
//! geometric Jacobian of the chain. Each step is clamped into the joint limits, so every
//! solution respects them; continuous joints are kept in [-pi, pi]. The first attempt starts
//! from the given configuration (to find a nearby solution), the following ones from uniform
//! random configurations drawn from a caller-seeded generator, so results are deterministic.
//! Targets farther from the chain's first joint than the chain can reach are rejected at once.

use parry3d::math::{Pose, Rotation, Vector};

use crate::agent::{AgentModel, JointKind, KinematicChain, random_in};

/// Settings of the solver.
#[derive(Debug, Clone, PartialEq)]
pub struct IkOptions {
    /// Number of attempts: the first from the seed configuration, then random restarts.
    pub attempts: usize,
    /// Iterations per attempt.
    pub iterations: usize,
    /// Position tolerance (metres) for success.
    pub position_tolerance: f32,
    /// Orientation tolerance (radians) for success.
    pub orientation_tolerance: f32,
    /// Whether the orientation of the target matters (false: position only).
    pub orientation: bool,
}

impl Default for IkOptions {
    /// 40 attempts of 100 iterations, 0.1 mm and 1 mrad: well inside the 1 mm / 0.01 rad the
    /// planner needs.
    fn default() -> Self {
        IkOptions {
            attempts: 40,
            iterations: 100,
            position_tolerance: 1e-4,
            orientation_tolerance: 1e-3,
            orientation: true,
        }
    }
}

/// A configuration that reaches the target.
#[derive(Debug, Clone, PartialEq)]
pub struct IkSolution {
    /// The full configuration of the agent: the input configuration with the chain's joints
    /// replaced by the solution.
    pub configuration: Vec<f32>,
    /// Remaining position error (metres).
    pub position_error: f32,
    /// Remaining orientation error (radians; 0 when orientation is ignored).
    pub orientation_error: f32,
    /// Attempts used (1 = found from the seed).
    pub attempts: usize,
    /// Iterations used over all attempts.
    pub iterations: usize,
}

/// Why inverse kinematics failed.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum IkError {
    /// The target is farther from the chain's first joint than the chain can reach.
    #[error(
        "chain '{chain}': target is {distance:.3} m from the first joint, beyond the chain's reach of {reach:.3} m"
    )]
    OutOfReach {
        /// The chain.
        chain: String,
        /// Distance from the first joint to the target position.
        distance: f32,
        /// Upper bound of the chain's reach.
        reach: f32,
    },
    /// No attempt converged.
    #[error(
        "chain '{chain}': no solution within tolerance after {attempts} attempts (best: {best_position_error:.4} m, {best_orientation_error:.4} rad)"
    )]
    NoSolution {
        /// The chain.
        chain: String,
        /// Attempts made.
        attempts: usize,
        /// Smallest position error reached.
        best_position_error: f32,
        /// Orientation error at that point.
        best_orientation_error: f32,
    },
    /// Bad input: configuration length or a non-finite target.
    #[error("inverse kinematics: {0}")]
    BadInput(String),
}

/// Per-joint data of the chain, precomputed once per solve.
struct ChainJoint {
    origin: Pose,
    axis: Vector,
    kind: JointKind,
    /// Index into the chain's own joint-value vector, for movable joints.
    var: Option<usize>,
}

/// Solves inverse kinematics for `chain` of `model`.
///
/// * `base`: the agent's base pose in the world.
/// * `q`: the full configuration; joints outside the chain keep their values, the chain's
///   joints are the seed of the first attempt.
/// * `target`: the wanted world pose of the chain's tip link.
/// * `rng`: the generator of restart configurations (seed it for reproducible results).
pub fn solve_ik(
    model: &AgentModel,
    chain: &KinematicChain,
    base: Pose,
    q: &[f32],
    target: Pose,
    options: &IkOptions,
    rng: &mut fastrand::Rng,
) -> Result<IkSolution, IkError> {
    if q.len() != model.dof() {
        return Err(IkError::BadInput(format!(
            "configuration has {} values, model '{}' has {} degrees of freedom",
            q.len(),
            model.name(),
            model.dof()
        )));
    }
    if !target.is_finite() || !base.is_finite() {
        return Err(IkError::BadInput(
            "target or base pose is not finite".into(),
        ));
    }
    // The chain must be a path of this model, its dofs those of its joints.
    let consistent = chain.root_link < model.links().len()
        && chain.tip_link < model.links().len()
        && chain.joints.iter().all(|&j| j < model.joints().len())
        && {
            let mut at = chain.root_link;
            let mut dofs = Vec::new();
            for &j in &chain.joints {
                let joint = &model.joints()[j];
                if joint.parent != at || joint.mimic.is_some() {
                    at = usize::MAX;
                    break;
                }
                dofs.extend(joint.dof);
                at = joint.child;
            }
            at == chain.tip_link && dofs == chain.dofs
        };
    if !consistent {
        return Err(IkError::BadInput(format!(
            "chain '{}' does not belong to model '{}'",
            chain.name,
            model.name()
        )));
    }
    let root = model.link_pose_by_id(base, q, chain.root_link);
    // Target in the chain root's frame, with a normalised rotation.
    let mut goal = root.inv_mul(&target);
    goal.rotation = goal.rotation.normalize();

    let mut joints = Vec::with_capacity(chain.joints.len());
    let mut limits = Vec::with_capacity(chain.dofs.len());
    for &j in &chain.joints {
        let joint = &model.joints()[j];
        let var = joint.dof.map(|d| {
            limits.push(model.dof_limits()[d]);
            limits.len() - 1
        });
        joints.push(ChainJoint {
            origin: joint.origin,
            axis: joint.axis,
            kind: joint.kind,
            var,
        });
    }
    let n = limits.len();

    // Reach bound: from the first movable joint's origin, the sum of the offsets after it.
    let first = joints.iter().position(|j| j.var.is_some());
    if let Some(first) = first {
        let mut frame = Pose::IDENTITY;
        for j in &joints[..first] {
            frame *= j.origin;
        }
        let origin = (frame * joints[first].origin).translation;
        let mut reach = 0.0f32;
        for (k, j) in joints.iter().enumerate().skip(first) {
            if k > first {
                reach += j.origin.translation.length();
            }
            if j.kind == JointKind::Prismatic {
                let l = limits[j.var.expect("prismatic joints are movable")];
                reach += l.lower.abs().max(l.upper.abs());
            }
        }
        let distance = (goal.translation - origin).length();
        if distance > reach + options.position_tolerance {
            return Err(IkError::OutOfReach {
                chain: chain.name.clone(),
                distance,
                reach,
            });
        }
    }

    let seed: Vec<f32> = chain.dofs.iter().map(|&d| q[d]).collect();
    let mut x = seed.clone();
    let mut best = (f32::INFINITY, f32::INFINITY);
    let mut total_iterations = 0;
    let mut work = Work::new(n);
    for attempt in 0..options.attempts.max(1) {
        if attempt > 0 {
            for (v, l) in x.iter_mut().zip(&limits) {
                *v = random_in(l, rng);
            }
        } else {
            for (v, l) in x.iter_mut().zip(&limits) {
                *v = normalise(*v, l);
            }
        }
        let (iters, pe, oe) = descend(&joints, &limits, &goal, &mut x, options, &mut work);
        total_iterations += iters;
        if pe <= options.position_tolerance && oe <= options.orientation_tolerance {
            let mut configuration = q.to_vec();
            for (k, &d) in chain.dofs.iter().enumerate() {
                configuration[d] = x[k];
            }
            return Ok(IkSolution {
                configuration,
                position_error: pe,
                orientation_error: oe,
                attempts: attempt + 1,
                iterations: total_iterations,
            });
        }
        if pe < best.0 {
            best = (pe, oe);
        }
    }
    Err(IkError::NoSolution {
        chain: chain.name.clone(),
        attempts: options.attempts.max(1),
        best_position_error: best.0,
        best_orientation_error: best.1,
    })
}

/// A value moved into its limits; continuous joints wrapped into [-pi, pi].
fn normalise(v: f32, l: &crate::agent::JointLimits) -> f32 {
    if l.is_bounded() {
        l.clamp(v)
    } else {
        let two_pi = std::f32::consts::TAU;
        let s = v + std::f32::consts::PI;
        // Already in range (the common case): `rem_euclid` would return `s` itself.
        if (0.0..two_pi).contains(&s) {
            return s - std::f32::consts::PI;
        }
        let w = s.rem_euclid(two_pi) - std::f32::consts::PI;
        if w.is_finite() { w } else { 0.0 }
    }
}

/// Scratch memory of one solve.
struct Work {
    /// Jacobian, 6 rows by n columns, column-major.
    jac: Vec<[f64; 6]>,
    /// The Jacobian at the trial configuration (becomes `jac` when the step is taken).
    trial_jac: Vec<[f64; 6]>,
    trial: Vec<f32>,
}

impl Work {
    fn new(n: usize) -> Work {
        Work {
            jac: vec![[0.0; 6]; n],
            trial_jac: vec![[0.0; 6]; n],
            trial: vec![0.0; n],
        }
    }
}

/// Tip pose and 6D error; fills the Jacobian when `jac` is given.
fn evaluate(
    joints: &[ChainJoint],
    goal: &Pose,
    x: &[f32],
    orientation: bool,
    jac: Option<&mut [[f64; 6]]>,
) -> ([f64; 6], f32, f32) {
    let mut frame = Pose::IDENTITY;
    // (axis, origin, is_revolute) of each movable joint in the root frame.
    let mut axes: [(Vector, Vector, bool); 16] = [(Vector::ZERO, Vector::ZERO, false); 16];
    let mut many = Vec::new();
    for j in joints {
        let at = frame * j.origin;
        match j.var {
            Some(k) => {
                let axis = at.rotation * j.axis;
                let revolute = j.kind != JointKind::Prismatic;
                if k < 16 {
                    axes[k] = (axis, at.translation, revolute);
                } else {
                    many.push((axis, at.translation, revolute));
                }
                let v = x[k];
                frame = if revolute {
                    at * Rotation::from_axis_angle(j.axis, v)
                } else {
                    let mut p = at;
                    p.translation += axis * v;
                    p
                };
            }
            None => frame = at,
        }
    }
    let ep = goal.translation - frame.translation;
    let mut dr = goal.rotation * frame.rotation.inverse();
    if dr.w < 0.0 {
        dr = -dr;
    }
    let er = if orientation {
        dr.normalize().to_scaled_axis()
    } else {
        Vector::ZERO
    };
    if let Some(jac) = jac {
        for (k, col) in jac.iter_mut().enumerate() {
            let (axis, origin, revolute) = if k < 16 { axes[k] } else { many[k - 16] };
            let (lin, ang) = if revolute {
                (axis.cross(frame.translation - origin), axis)
            } else {
                (axis, Vector::ZERO)
            };
            let ang = if orientation { ang } else { Vector::ZERO };
            *col = [
                lin.x as f64,
                lin.y as f64,
                lin.z as f64,
                ang.x as f64,
                ang.y as f64,
                ang.z as f64,
            ];
        }
    }
    (
        [
            ep.x as f64,
            ep.y as f64,
            ep.z as f64,
            er.x as f64,
            er.y as f64,
            er.z as f64,
        ],
        ep.length(),
        er.length(),
    )
}

fn sq(e: &[f64; 6]) -> f64 {
    e.iter().map(|v| v * v).sum()
}

/// Iterations between stagnation checks.
const STALL_WINDOW: usize = 10;
/// An attempt stops when its squared error did not fall below this fraction of the value
/// `STALL_WINDOW` iterations earlier.
const STALL_GAIN: f64 = 0.9;

/// One attempt of damped least squares from `x`; returns (iterations, position error,
/// orientation error) at the end, `x` holding the last accepted values.
fn descend(
    joints: &[ChainJoint],
    limits: &[crate::agent::JointLimits],
    goal: &Pose,
    x: &mut [f32],
    options: &IkOptions,
    work: &mut Work,
) -> (usize, f32, f32) {
    let mut lambda = 1e-2f64;
    let (mut e, mut pe, mut oe) =
        evaluate(joints, goal, x, options.orientation, Some(&mut work.jac));
    let mut err = sq(&e);
    let mut checkpoint = err;
    for it in 0..options.iterations {
        if pe <= options.position_tolerance && oe <= options.orientation_tolerance {
            return (it, pe, oe);
        }
        // Stagnation: less than STALL_GAIN of the error gone in STALL_WINDOW iterations means a
        // local minimum or a joint limit; a restart is a better use of the time.
        if it > 0 && it % STALL_WINDOW == 0 {
            if err > checkpoint * STALL_GAIN {
                return (it, pe, oe);
            }
            checkpoint = err;
        }
        // (J J^T + lambda I) y = e; dq = J^T y.
        // Symmetric: the upper triangle summed, mirrored (the same products in the same order).
        let mut a = [[0.0f64; 6]; 6];
        for col in &work.jac {
            for r in 0..6 {
                for c in r..6 {
                    a[r][c] += col[r] * col[c];
                }
            }
        }
        #[allow(clippy::needless_range_loop)]
        for r in 1..6 {
            for c in 0..r {
                a[r][c] = a[c][r];
            }
        }
        for (r, row) in a.iter_mut().enumerate() {
            row[r] += lambda;
        }
        let Some(y) = solve6(a, e) else {
            lambda *= 10.0;
            continue;
        };
        let mut step_norm = 0.0f64;
        for (k, col) in work.jac.iter().enumerate() {
            let d: f64 = (0..6).map(|r| col[r] * y[r]).sum();
            step_norm = step_norm.max(d.abs());
            work.trial[k] = d as f32;
        }
        // Keep steps small enough for the linearisation to hold.
        let scale = if step_norm > 0.5 {
            0.5 / step_norm
        } else {
            1.0
        } as f32;
        for k in 0..x.len() {
            work.trial[k] = normalise(x[k] + work.trial[k] * scale, &limits[k]);
        }
        // The trial's Jacobian comes with its forward kinematics (a few cross products more):
        // a step taken, the most common outcome, then needs no second evaluation.
        let (e2, pe2, oe2) = evaluate(
            joints,
            goal,
            &work.trial,
            options.orientation,
            Some(&mut work.trial_jac),
        );
        let err2 = sq(&e2);
        if err2 < err {
            x.copy_from_slice(&work.trial);
            std::mem::swap(&mut work.jac, &mut work.trial_jac);
            e = e2;
            pe = pe2;
            oe = oe2;
            err = err2;
            lambda = (lambda * 0.3).max(1e-9);
        } else {
            lambda *= 10.0;
            if lambda > 1e4 {
                // Stuck (a local minimum or a joint limit): give up this attempt.
                return (it + 1, pe, oe);
            }
        }
    }
    (options.iterations, pe, oe)
}

/// Solves the symmetric positive definite 6x6 system `a y = b` by Gaussian elimination with
/// partial pivoting; `None` if singular.
fn solve6(mut a: [[f64; 6]; 6], mut b: [f64; 6]) -> Option<[f64; 6]> {
    for c in 0..6 {
        let p = (c..6).max_by(|&i, &j| a[i][c].abs().total_cmp(&a[j][c].abs()))?;
        if a[p][c].abs() < 1e-14 {
            return None;
        }
        a.swap(c, p);
        b.swap(c, p);
        let pivot_row = a[c];
        let pivot_b = b[c];
        for (row, br) in a.iter_mut().zip(b.iter_mut()).skip(c + 1) {
            let f = row[c] / pivot_row[c];
            if f != 0.0 {
                for k in c..6 {
                    row[k] -= f * pivot_row[k];
                }
                *br -= f * pivot_b;
            }
        }
    }
    let mut y = [0.0f64; 6];
    for r in (0..6).rev() {
        let s: f64 = (r + 1..6).map(|k| a[r][k] * y[k]).sum();
        y[r] = (b[r] - s) / a[r][r];
    }
    y.iter().all(|v| v.is_finite()).then_some(y)
}
