//! What `navigate-to` must bring within the arm's reach, and where the base may stand for it.
//!
//! A small object or an agent is a point (its centre, an agent's eyes). Furniture is not: the
//! desk's centre lies 0.9 m inside its top, out of reach from anywhere beside it. For an object
//! with support surfaces, "in reach" means a point of one of those surfaces is within reach (the
//! point nearest the shoulder); for another large object, the point of its shape nearest the
//! shoulder. Base poses are then tried around the target's footprint, not around its centre.

use geometry::scene::{AgentId, ObjectId};
use geometry::world::World;
use parry3d::math::{Pose, Vector};
use parry3d::shape::SharedShape;

/// An object whose footprint has a half size above this (metres) is large: reached at its
/// surface rather than at its centre.
const LARGE_HALF_SIZE: f32 = 0.25;

/// The region whose nearest point must be within the arm's reach.
#[derive(Clone)]
pub enum ReachTarget {
    /// One point: a small object's centre, an agent's eyes.
    Point(Vector),
    /// Several points, any one of which will do (places to put an object).
    Points(Vec<Vector>),
    /// Support-surface rectangles: world pose of each centre (rectangle in its x-y plane) and
    /// half sizes.
    Surfaces(Vec<(Pose, [f32; 2])>),
    /// A large object's shape at its world pose.
    Shape(SharedShape, Pose),
    /// What a person reaches with an arm extended (effort level 1): a ball of their reach
    /// around each shoulder. A placement or hand-over for them lies in it, so the robot's arm
    /// must reach into it, not up to their eyes (across a counter, the eyes are out of reach
    /// where the person's hand is not).
    Person { shoulders: Vec<Vector>, reach: f32 },
}

/// Base stand-off distances (metres) from the footprint of a point target (the rings the base
/// poses lie on).
const POINT_RINGS: [f32; 4] = [0.55, 0.65, 0.75, 0.85];
/// Same, from the edge of a large target's footprint (the PR2's base reaches 0.33 m from its
/// centre; the arm then leans over the edge).
const EDGE_RINGS: [f32; 4] = [0.4, 0.5, 0.6, 0.75];

impl ReachTarget {
    /// The target of `navigate-to` an object in `world`.
    pub fn object(world: &World, id: ObjectId) -> ReachTarget {
        let o = world.object(id);
        let aabb = world.object_aabb(id);
        let half = aabb.half_extents();
        if !o.surfaces.is_empty() {
            let pose = world.object_pose(id);
            ReachTarget::Surfaces(
                o.surfaces
                    .iter()
                    .map(|s| (pose * Pose::from_translation(s.centre), s.half_extents))
                    .collect(),
            )
        } else if half.x.max(half.y) > LARGE_HALF_SIZE {
            ReachTarget::Shape(o.shape.clone(), world.object_shape_pose(id))
        } else {
            ReachTarget::Point(aabb.center())
        }
    }

    /// The reach of person `h` in `world` where they stand now: that of the arms whose hands
    /// hold nothing (what is handed to them or put down for them is taken by a free hand), of
    /// both when neither is free.
    pub fn person(world: &World, h: AgentId) -> ReachTarget {
        let state = world.agent_state(h);
        let all = geometry::effort::shoulders(world, h, state.base, &state.q);
        let free = free_shoulders(world, h);
        let shoulders: Vec<Vector> = all
            .iter()
            .zip(&free)
            .filter(|(_, f)| **f)
            .map(|(s, _)| *s)
            .collect();
        ReachTarget::Person {
            shoulders: if shoulders.is_empty() { all } else { shoulders },
            reach: world.agent(h).reach,
        }
    }

    /// The point of the target nearest `p`.
    pub fn nearest(&self, p: Vector) -> Vector {
        let nearest_of = |list: &[Vector]| {
            list.iter()
                .copied()
                .min_by(|a, b| (*a - p).length().total_cmp(&(*b - p).length()))
                .unwrap_or(p)
        };
        match self {
            ReachTarget::Point(c) => *c,
            ReachTarget::Points(list) => nearest_of(list),
            ReachTarget::Person { shoulders, reach } => shoulders
                .iter()
                .map(|s| *s + (p - *s).clamp_length_max(*reach))
                .min_by(|a, b| (*a - p).length().total_cmp(&(*b - p).length()))
                .unwrap_or(p),
            ReachTarget::Surfaces(list) => list
                .iter()
                .map(|(pose, h)| {
                    let local = pose.inverse_transform_point(p);
                    let clamped =
                        Vector::new(local.x.clamp(-h[0], h[0]), local.y.clamp(-h[1], h[1]), 0.0);
                    pose.transform_point(clamped)
                })
                .min_by(|a, b| (*a - p).length().total_cmp(&(*b - p).length()))
                .unwrap_or(p),
            ReachTarget::Shape(shape, pose) => shape.project_point(pose, p, true).point,
        }
    }

    /// Whether a point of the target lies within `reach` of one of `shoulders`.
    pub fn within_reach(&self, shoulders: &[Vector], reach: f32) -> bool {
        shoulders
            .iter()
            .any(|s| (self.nearest(*s) - *s).length() <= reach)
    }

    /// The target's footprint on the floor: `(min, max)` corners in x-y (a point for a point
    /// target).
    fn footprint(&self) -> ([f32; 2], [f32; 2]) {
        let mut lo = [f32::INFINITY; 2];
        let mut hi = [f32::NEG_INFINITY; 2];
        let mut add = |v: Vector| {
            lo = [lo[0].min(v.x), lo[1].min(v.y)];
            hi = [hi[0].max(v.x), hi[1].max(v.y)];
        };
        match self {
            ReachTarget::Point(c) => add(*c),
            ReachTarget::Points(list) => list.iter().for_each(|p| add(*p)),
            ReachTarget::Surfaces(list) => {
                for (pose, h) in list {
                    for (sx, sy) in [(-1.0, -1.0), (-1.0, 1.0), (1.0, -1.0), (1.0, 1.0)] {
                        add(pose.transform_point(Vector::new(sx * h[0], sy * h[1], 0.0)));
                    }
                }
            }
            ReachTarget::Shape(shape, pose) => {
                let b = shape.compute_aabb(pose);
                add(b.mins);
                add(b.maxs);
            }
            ReachTarget::Person { shoulders, reach } => {
                for s in shoulders {
                    add(*s - Vector::splat(*reach));
                    add(*s + Vector::splat(*reach));
                }
            }
        }
        (lo, hi)
    }

    /// Candidate base positions (z = 0): on rounded rectangles at the stand-off distances
    /// around the footprint, about 0.15 m apart (24 per ring around a point), nearest `from`
    /// first.
    pub fn base_positions(&self, from: Vector) -> Vec<Vector> {
        if let ReachTarget::Points(list) = self {
            // Around each point, as around a point target.
            let mut out: Vec<Vector> = list
                .iter()
                .flat_map(|p| ReachTarget::Point(*p).base_positions(from))
                .collect();
            out.sort_by(|a, b| (*a - from).length().total_cmp(&(*b - from).length()));
            return out;
        }
        let (lo, hi) = self.footprint();
        let rings: &[f32] = match self {
            ReachTarget::Point(_) => &POINT_RINGS,
            _ => &EDGE_RINGS,
        };
        let mut out = Vec::new();
        for &r in rings {
            // Corners: quarter circles; sides: straight runs.
            let corners = [
                (hi[0], hi[1]),
                (lo[0], hi[1]),
                (lo[0], lo[1]),
                (hi[0], lo[1]),
            ];
            for (q, &(cx, cy)) in corners.iter().enumerate() {
                let a0 = std::f32::consts::FRAC_PI_2 * q as f32;
                for k in 0..6 {
                    let a = a0 + std::f32::consts::FRAC_PI_2 * k as f32 / 6.0;
                    out.push(Vector::new(cx + r * a.cos(), cy + r * a.sin(), 0.0));
                }
                // The side from this corner's quarter circle end to the next corner.
                let (nx, ny) = corners[(q + 1) % 4];
                let a1 = a0 + std::f32::consts::FRAC_PI_2;
                let (dx, dy) = (nx - cx, ny - cy);
                let len = (dx * dx + dy * dy).sqrt();
                let n = (len / 0.15).floor() as usize;
                for k in 0..n {
                    let t = k as f32 / n as f32;
                    out.push(Vector::new(
                        cx + t * dx + r * a1.cos(),
                        cy + t * dy + r * a1.sin(),
                        0.0,
                    ));
                }
            }
        }
        out.sort_by(|a, b| (*a - from).length().total_cmp(&(*b - from).length()));
        out
    }
}

/// Per shoulder link of person `h` (in `shoulder_links` order), whether its arm's hand is free:
/// no object is attached to a link below the shoulder.
pub(crate) fn free_shoulders(world: &World, h: AgentId) -> Vec<bool> {
    let info = world.agent(h);
    let links = info.model.links();
    let below = |shoulder: usize, mut l: usize| loop {
        if l == shoulder {
            break true;
        }
        match links[l].parent {
            Some(p) => l = p,
            None => break false,
        }
    };
    let held: Vec<usize> = world
        .object_ids()
        .filter_map(|o| world.attachment(o).filter(|a| a.agent == h).map(|a| a.link))
        .collect();
    info.shoulder_links
        .iter()
        .map(|&s| !held.iter().any(|&l| below(s, l)))
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A person across a counter: their eyes are beyond the robot's reach where their hand is
    /// not, so a pose from which the arms meet over the counter counts as reaching them.
    #[test]
    fn a_person_is_reached_where_the_arms_meet() {
        let shoulders = vec![Vector::new(0.9, -0.2, 1.4), Vector::new(0.9, 0.2, 1.4)];
        let eye = Vector::new(0.9, 0.0, 1.6);
        let robot = [Vector::new(-0.45, 0.0, 1.2)];
        let reach = 0.9;
        assert!(!ReachTarget::Point(eye).within_reach(&robot, reach));
        let person = ReachTarget::Person {
            shoulders,
            reach: 0.7,
        };
        assert!(person.within_reach(&robot, reach));
        // The point nearest the robot lies on a shoulder's ball, towards the robot.
        let p = person.nearest(robot[0]);
        let d = (p - Vector::new(0.9, -0.2, 1.4))
            .length()
            .min((p - Vector::new(0.9, 0.2, 1.4)).length());
        assert!((d - 0.7).abs() < 1e-4, "{d}");
        assert!(p.x < 0.9);
        // Beyond both reaches, it is not.
        assert!(!person.within_reach(&[Vector::new(-1.0, 0.0, 1.2)], reach));
    }

    /// Places of which any will do: reached when one is, the poses around each, nearest first.
    #[test]
    fn several_places_are_reached_where_one_is() {
        let near = Vector::new(1.0, 0.0, 0.8);
        let far = Vector::new(-3.0, 0.0, 0.8);
        let places = ReachTarget::Points(vec![far, near]);
        let shoulder = [Vector::new(0.4, 0.0, 1.0)];
        assert!(places.within_reach(&shoulder, 0.8));
        assert!(!ReachTarget::Point(far).within_reach(&shoulder, 0.8));
        assert_eq!(places.nearest(Vector::ZERO), near);
        let poses = places.base_positions(Vector::ZERO);
        assert_eq!(
            poses.len(),
            2 * ReachTarget::Point(near).base_positions(Vector::ZERO).len()
        );
        // Nearest first: the first poses ring the near place.
        assert!((poses[0] - Vector::new(near.x, near.y, 0.0)).length() < 0.9);
        assert!(
            poses
                .windows(2)
                .all(|w| w[0].length() <= w[1].length() + 1e-6)
        );
    }
}
