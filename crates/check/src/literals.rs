//! Re-measuring the `visible` and `reachable` literals a step adds or deletes, with the
//! planner's stated thresholds (`crates/geometry/src/facts.rs`, `world.rs`: half of the object's
//! pixels seen with the head as it is or turned towards the object; a shoulder within the arm's
//! reach, 0.95 m for a robot and 0.70 m for a person, of the object's surface) but this crate's
//! own ray casting and distances. Only a clear disagreement is a fault: the pixel measures of two
//! implementations differ a little, and the planner may lean or use inverse kinematics.

use parry3d::math::{Pose, Vector};
use parry3d::query::{Ray, RayCast};

use crate::bodies::{Owner, Placed, links_at, objects_at};
use crate::kinematics::Iso;
use crate::model::{AgentKind, Literal, Plan, Step};
use crate::motion::iso;
use crate::report::{Fault, FaultKind};
use crate::world::World;

/// Fraction of pixels that makes an object visible.
pub const VISIBLE: f32 = 0.5;
/// A `visible` the step adds is stale below this fraction; one it deletes, above the next.
pub const VISIBLE_LOW: f32 = 0.35;
pub const VISIBLE_HIGH: f32 = 0.65;
/// Arm reach from a shoulder (m).
pub const ROBOT_REACH: f32 = 0.95;
pub const HUMAN_REACH: f32 = 0.70;
/// An added `reachable` is stale beyond reach + this; a deleted one within reach - the next.
pub const REACH_OVER: f32 = 0.10;
pub const REACH_UNDER: f32 = 0.20;
/// A hand within this of an object touches it (reachable without moving).
pub const HAND_TOUCH: f32 = 0.03;
/// Rays per side of the pixel grid.
pub const GRID: usize = 48;

/// Re-measure the step's added and deleted literals; returns how many were measured.
pub fn check_literals(plan: &Plan, world: &World, step: &Step, faults: &mut Vec<Fault>) -> usize {
    let claims = (step.added.iter().map(|l| (l, true, "added")))
        .chain(step.deleted.iter().map(|l| (l, false, "deleted")));
    measure(plan, world, step, claims, faults)
}

/// Re-measure, after a step that moved something, the `visible` and `reachable` literals that
/// hold from earlier steps (the plan's `initial_literals` and what steps added since): a
/// placement that hides another object must have deleted its `visible`.
pub fn check_persisting<'a>(
    plan: &Plan,
    world: &World,
    step: &Step,
    persisting: impl Iterator<Item = &'a Literal>,
    faults: &mut Vec<Fault>,
) -> usize {
    let claims = persisting.map(|l| (l, true, "persisting"));
    measure(plan, world, step, claims, faults)
}

fn measure<'a>(
    plan: &Plan,
    world: &World,
    step: &Step,
    claims: impl Iterator<Item = (&'a Literal, bool, &'static str)>,
    faults: &mut Vec<Fault>,
) -> usize {
    let mut measured = 0;
    for (lit, claimed, how) in claims {
        let [pred, x, a] = lit.as_slice() else {
            continue;
        };
        let (Some(o), Some(a)) = (plan.object(x), plan.agent(a)) else {
            continue;
        };
        let verdict = match pred.as_str() {
            "visible" => visible(plan, world, o, a, claimed),
            "reachable" => reachable(plan, world, o, a, claimed),
            _ => continue,
        };
        let Some((stale, detail)) = verdict else {
            continue;
        };
        measured += 1;
        if stale {
            faults.push(Fault {
                kind: FaultKind::StaleLiteral,
                step: Some(step.index),
                action: step.action.clone(),
                trajectory: None,
                trajectory_index: None,
                frame: None,
                a: format!("({})", lit.join(" ")),
                b: how.to_string(),
                depth_mm: 0.0,
                configs: 1,
                detail,
            });
        }
    }
    measured
}

/// (stale, what was measured); `None` when the agent has no eye.
fn visible(
    plan: &Plan,
    world: &World,
    o: usize,
    a: usize,
    claimed: bool,
) -> Option<(bool, String)> {
    let agent = &plan.agents[a];
    let eye = world.agents[a][agent.eye?];
    if agent.kind == AgentKind::Human && world.holds[o].as_ref().is_some_and(|h| h.agent == a) {
        // A person sees what they hold by raising it (the planner's level-1 rule).
        return Some((!claimed, "held by the viewer".to_string()));
    }
    let fov = match agent.kind {
        AgentKind::Robot => [70f32.to_radians(), 52.5f32.to_radians()],
        AgentKind::Human => [120f32.to_radians(), 90f32.to_radians()],
    };
    let scene = Scene::new(plan, world, o, a, eye.translation);
    let now = scene.fraction(&Camera::of(&eye), Some(fov));
    let aimed = match head_aimed(plan, world, a, scene.centre()) {
        Some(turned) => scene.fraction(&Camera::of(&turned), Some(fov)),
        None => {
            let pivot = agent.head_pivot.map(|l| world.agents[a][l].translation);
            scene.fraction(&Camera::aimed(&eye, pivot, scene.centre()), None)
        }
    };
    let detail = format!(
        "visible fraction {now:.2} with the head as it is, {aimed:.2} with it turned (threshold {VISIBLE})"
    );
    let stale = if claimed {
        now.max(aimed) < VISIBLE_LOW
    } else {
        now > VISIBLE_HIGH
    };
    Some((stale, detail))
}

/// Grid steps over each head joint's range while aiming, and rounds of finer grids.
const AIM_STEPS: usize = 25;
const AIM_ROUNDS: usize = 3;

/// The eye of agent `a` with its head turned towards `target` as far as the head's joints
/// allow (from the URDF the plan carries: the joints from its `head_pivot_link`'s down to its
/// `eye_link`): of a grid over the joints' ranges, refined around the best, the pose whose
/// forward axis points nearest the target. `None` without a URDF, a pivot or an eye, or with
/// more than two head joints.
fn head_aimed(plan: &Plan, world: &World, a: usize, target: Vector) -> Option<Pose> {
    let agent = &plan.agents[a];
    let name = |l: usize| agent.links[l].name.as_str();
    let chain = agent
        .kinematics
        .as_ref()?
        .head_chain(name(agent.head_pivot?), name(agent.eye?))?;
    let root = agent.links.iter().position(|l| l.name == chain.root)?;
    let root = iso(&world.agents[a][root]);
    let limits = chain.limits();
    if limits.is_empty() || limits.len() > 2 {
        return None;
    }
    // A grid over the joints' ranges, then finer grids around the best value found (a coarse
    // grid alone can miss the aim by several degrees, enough to tip a view that grazes the
    // viewer's own shoulder).
    let mut ranges: Vec<(f64, f64)> = limits.clone();
    let mut best = (f64::NEG_INFINITY, Iso::IDENTITY, vec![0.0; limits.len()]);
    for _ in 0..AIM_ROUNDS {
        let at =
            |(lo, hi): (f64, f64), k: usize| lo + (hi - lo) * k as f64 / (AIM_STEPS - 1) as f64;
        let second = if ranges.len() == 2 { AIM_STEPS } else { 1 };
        for i in 0..AIM_STEPS {
            for k in 0..second {
                let mut values = vec![at(ranges[0], i)];
                values.extend(ranges.get(1).map(|&l| at(l, k)));
                let eye = chain.eye_pose(&root, &values);
                let to = [0, 1, 2].map(|c| f64::from(target[c]) - eye.t[c]);
                let fwd = eye.rotate([1.0, 0.0, 0.0]);
                let norm = (to[0] * to[0] + to[1] * to[1] + to[2] * to[2])
                    .sqrt()
                    .max(1e-9);
                let cos = (fwd[0] * to[0] + fwd[1] * to[1] + fwd[2] * to[2]) / norm;
                if cos > best.0 {
                    best = (cos, eye, values);
                }
            }
        }
        // The next grid: two steps of this one around the best value, within the limits.
        ranges = ranges
            .iter()
            .zip(&limits)
            .zip(&best.2)
            .map(|(((lo, hi), (min, max)), v)| {
                let step = (hi - lo) / (AIM_STEPS - 1) as f64;
                ((v - step).max(*min), (v + step).min(*max))
            })
            .collect();
    }
    Some(pose(&best.1))
}

fn pose(i: &Iso) -> Pose {
    let [x, y, z, w] = i.q.map(|v| v as f32);
    Pose::from_parts(
        Vector::new(i.t[0] as f32, i.t[1] as f32, i.t[2] as f32),
        parry3d::math::Rotation::from_xyzw(x, y, z, w).normalize(),
    )
}

/// (stale, what was measured); `None` when the agent declares no `shoulder_links`.
fn reachable(
    plan: &Plan,
    world: &World,
    o: usize,
    a: usize,
    claimed: bool,
) -> Option<(bool, String)> {
    let agent = &plan.agents[a];
    let poses = &world.agents[a];
    let object = &plan.objects[o];
    let dist = |p: Vector| {
        let d = object.parts.iter().map(|part| {
            let pose = world.objects[o] * part.pose;
            part.shape.distance_to_point(&pose, p, true)
        });
        d.fold(f32::INFINITY, f32::min)
    };
    let hand = (0..agent.links.len())
        .filter(|&l| agent.is_grasping(l))
        .map(|l| dist(poses[l].translation))
        .fold(f32::INFINITY, f32::min);
    let held = world.holds[o].as_ref().is_some_and(|h| h.agent == a);
    let shoulder = agent
        .shoulders
        .iter()
        .map(|&l| dist(poses[l].translation))
        .fold(f32::INFINITY, f32::min);
    if !shoulder.is_finite() {
        return None;
    }
    let reach = match agent.kind {
        AgentKind::Robot => ROBOT_REACH,
        AgentKind::Human => HUMAN_REACH,
    };
    let touching = held || hand <= HAND_TOUCH;
    let detail = format!(
        "{shoulder:.3} m from the nearest shoulder (reach {reach} m), hand {hand:.3} m{}",
        if held { ", held" } else { "" }
    );
    let stale = if claimed {
        !touching && shoulder > reach + REACH_OVER
    } else {
        touching || shoulder < reach - REACH_UNDER
    };
    Some((stale, detail))
}

/// A pinhole camera: origin and orthonormal forward, left, up.
struct Camera {
    origin: Vector,
    fwd: Vector,
    left: Vector,
    up: Vector,
}

impl Camera {
    /// The eye frame itself: +x forward, +z up.
    fn of(eye: &Pose) -> Self {
        Camera {
            origin: eye.translation,
            fwd: eye.rotation * Vector::X,
            left: eye.rotation * Vector::Y,
            up: eye.rotation * Vector::Z,
        }
    }

    /// The eye turned (pan about z, then tilt) to look at `target`, upright. With a `pivot`
    /// (the `head_pivot_link`'s origin) the eye swings about it as a head does; the eye's offset from
    /// the pivot is kept in the eye's frame. Without one it turns on the spot.
    fn aimed(eye: &Pose, pivot: Option<Vector>, target: Vector) -> Self {
        let offset = pivot.map(|p| eye.rotation.inverse() * (eye.translation - p));
        let mut cam = Camera::looking(eye.translation, target);
        for _ in 0..3 {
            let (Some(p), Some(off)) = (pivot, offset) else {
                break;
            };
            let turn = parry3d::math::Rotation::from_mat3(&parry3d::math::Mat3::from_cols(
                cam.fwd, cam.left, cam.up,
            ));
            cam = Camera::looking(p + turn * off, target);
        }
        cam
    }

    /// A camera at `origin` looking at `target`, upright.
    fn looking(origin: Vector, target: Vector) -> Self {
        let fwd = (target - origin).normalize_or(Vector::X);
        let left = Vector::Z.cross(fwd).normalize_or(Vector::Y);
        Camera {
            origin,
            fwd,
            left,
            up: fwd.cross(left),
        }
    }

    /// Image-plane coordinates (tangents) of a world point in front of the camera.
    fn project(&self, p: Vector) -> Option<(f32, f32)> {
        let d = p - self.origin;
        let z = d.dot(self.fwd);
        (z > 1e-3).then(|| (d.dot(self.left) / z, d.dot(self.up) / z))
    }
}

/// How near the eye a viewer's own shape is part of its head, which turns with the eye and does
/// not hide anything from it (m).
pub const HEAD: f32 = 0.10;

/// The target's shapes and the shapes that may hide it (everything else, less the viewer's
/// head: its shapes within [`HEAD`] of the eye).
struct Scene {
    target: Vec<Placed>,
    others: Vec<Placed>,
}

impl Scene {
    fn new(plan: &Plan, world: &World, o: usize, viewer: usize, eye: Vector) -> Self {
        let mut all = objects_at(plan, &world.objects, &[]);
        for a in 0..plan.agents.len() {
            all.extend(links_at(plan, a, &world.agents[a]));
        }
        let (target, others): (Vec<Placed>, Vec<Placed>) =
            all.into_iter().partition(|p| p.owner == Owner::Object(o));
        let others = others
            .into_iter()
            .filter(|p: &Placed| {
                let own = matches!(p.owner, Owner::Link(a, _) if a == viewer);
                !(own && p.shape.distance_to_point(&p.pose, eye, true) <= HEAD)
            })
            .collect();
        Scene { target, others }
    }

    fn centre(&self) -> Vector {
        let sum: Vector = self.target.iter().map(|p| p.aabb.center()).sum();
        sum / self.target.len().max(1) as f32
    }

    /// Fraction of the target's pixels shown: rays over its projected bounding rectangle that
    /// hit it (ideal), in the field of view when one is given, and not cut by another body first.
    fn fraction(&self, cam: &Camera, fov: Option<[f32; 2]>) -> f32 {
        let Some([u0, u1, v0, v1]) = self.rectangle(cam) else {
            return 0.0;
        };
        let (mut ideal, mut shown) = (0usize, 0usize);
        for j in 0..GRID {
            let v = v0 + (v1 - v0) * (j as f32 + 0.5) / GRID as f32;
            for i in 0..GRID {
                let u = u0 + (u1 - u0) * (i as f32 + 0.5) / GRID as f32;
                let dir = (cam.fwd + u * cam.left + v * cam.up).normalize();
                let ray = Ray::new(cam.origin, dir);
                let Some(t) = first_hit(&self.target, &ray, f32::MAX) else {
                    continue;
                };
                ideal += 1;
                let in_view =
                    fov.is_none_or(|[h, w]| u.atan().abs() <= 0.5 * h && v.atan().abs() <= 0.5 * w);
                if in_view && first_hit(&self.others, &ray, t - 1e-3).is_none() {
                    shown += 1;
                }
            }
        }
        if ideal == 0 {
            0.0
        } else {
            shown as f32 / ideal as f32
        }
    }

    /// The target's bounding boxes projected on the image plane: [u min, u max, v min, v max].
    fn rectangle(&self, cam: &Camera) -> Option<[f32; 4]> {
        let mut r = [
            f32::INFINITY,
            f32::NEG_INFINITY,
            f32::INFINITY,
            f32::NEG_INFINITY,
        ];
        for p in &self.target {
            let (lo, hi) = (p.aabb.mins, p.aabb.maxs);
            for c in 0..8 {
                let corner = Vector::new(
                    if c & 1 == 0 { lo.x } else { hi.x },
                    if c & 2 == 0 { lo.y } else { hi.y },
                    if c & 4 == 0 { lo.z } else { hi.z },
                );
                if let Some((u, v)) = cam.project(corner) {
                    r = [r[0].min(u), r[1].max(u), r[2].min(v), r[3].max(v)];
                }
            }
        }
        (r[0] < r[1] && r[2] < r[3]).then_some(r)
    }
}

/// Nearest hit of `ray` on `bodies` before `max` (box test first).
fn first_hit(bodies: &[Placed], ray: &Ray, max: f32) -> Option<f32> {
    bodies
        .iter()
        .filter(|p| p.aabb.cast_local_ray(ray, max, true).is_some())
        .filter_map(|p| p.shape.cast_ray(&p.pose, ray, max, true))
        .reduce(f32::min)
}
