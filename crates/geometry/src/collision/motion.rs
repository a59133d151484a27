//! Certifying a straight joint-space motion (or a straight planar motion of the base) free of
//! collisions by conservative advancement (Schwarzer, Saha and Latombe, "Exact collision
//! checking of robot paths", 2002): two bodies at distance `d` stay apart while their relative
//! motion is under `d`, and that motion is bounded by each joint's step times the bodies'
//! greatest distance from its axis: over every configuration (the arm as if stretched), or,
//! after an exact measurement, as the joints are posed (a folded arm's hand near the shoulder's
//! axis), allowing for that distance to grow with the joints below the axis
//! ([`JointReach::local_step`]). Each pair of bodies is re-measured on its own schedule: a
//! far pair once a motion, a near one as it comes closer. A link of several shapes (a mesh's
//! convex pieces) is followed against an obstacle as one body, by its ball and box, and shape
//! by shape once they come within [`SPLIT`]; a near pair of links, each shape of the link with
//! fewer against the other link as a whole first, then shape by shape. A pair nearer than
//! `floor` is re-measured every `floor` of relative motion, so a contact between two
//! measurements is at most `floor / 2` deep; elsewhere the motion is free everywhere, not only
//! at sampled configurations. Distances are proven lower bounds (see [`support_gap`]), never
//! GJK's witnesses alone.

use parry3d::bounding_volume::{Aabb, BoundingVolume};
use parry3d::math::{Pose, Vector};
use parry3d::query;
use parry3d::query::gjk::{CsoPoint, VoronoiSimplex};
use parry3d::shape::{Compound, Shape, SupportMap};

use super::self_collision::{PairGroup, ShapeEntry};
use super::{CollisionChecker, Contact, HeldObject, Hit, SCRATCH, Scratch, intersects};
use crate::agent::{AgentModel, JointKind};
use crate::world::base_pose;

/// A movable joint above a link, with a bound (over all configurations) on the distance from
/// its axis to the link frame's origin; and where only fixed joints lie between them, the
/// link's frame in the joint's child frame and the axis, for the exact distance from the axis.
#[derive(Clone, Copy, Debug)]
struct Above {
    joint: u16,
    arm: f32,
    prismatic: bool,
    rigid: Option<(Pose, Vector)>,
}

/// A body of a link for speed bounds: the link, and a ball that holds the body (centre in the
/// link's frame, radius).
pub(super) type Body = (usize, Vector, f32);

/// Per link of a model, the movable joints above it, root first: what bounds how fast a
/// link's points move when the joints do.
#[derive(Clone, Debug, Default)]
pub(super) struct JointReach {
    above: Vec<Vec<Above>>,
    /// Per joint, its child link and its axis in the child's frame (through its origin).
    axes: Vec<(usize, Vector)>,
}

impl JointReach {
    pub(super) fn new(model: &AgentModel) -> JointReach {
        let mut above: Vec<Vec<Above>> = vec![Vec::new(); model.links().len()];
        // Joints come parent first (a joint's child link is its index + 1).
        for (j, joint) in model.joints().iter().enumerate() {
            let slide = match joint.kind {
                JointKind::Prismatic => joint.limits.lower.abs().max(joint.limits.upper.abs()),
                _ => 0.0,
            };
            let step = joint.origin.translation.length() + slide;
            let fixed = !joint.is_movable();
            let mut list: Vec<Above> = above[joint.parent]
                .iter()
                .map(|a| Above {
                    arm: a.arm + step,
                    rigid: a
                        .rigid
                        .filter(|_| fixed)
                        .map(|(t, axis)| (t * joint.origin, axis)),
                    ..*a
                })
                .collect();
            if joint.is_movable() {
                list.push(Above {
                    joint: j as u16,
                    arm: 0.0,
                    prismatic: joint.kind == JointKind::Prismatic,
                    rigid: Some((Pose::IDENTITY, joint.axis)),
                });
            }
            above[joint.child] = list;
        }
        let axes = model.joints().iter().map(|j| (j.child, j.axis)).collect();
        JointReach { above, axes }
    }

    /// A bound on the speed (metres per unit of the motion's parameter) of the points of
    /// `body` relative to those of `other` (the world without it), when joint `j` moves at
    /// `speed[j]` (absolute values). The joints above both bodies move them together and do
    /// not count.
    pub(super) fn rate(&self, speed: &[f32], body: Body, other: Option<Body>) -> f32 {
        let (a, b) = self.sides(body, other);
        let rest = other.map_or(0.0, |o| b.iter().map(|e| e.speed(speed, o)).sum());
        a.iter().map(|e| e.speed(speed, body)).sum::<f32>() + rest
    }

    /// The joints that move `body` relative to `other` (the world without it): those above
    /// each, less those above both.
    fn sides(&self, body: Body, other: Option<Body>) -> (&[Above], &[Above]) {
        let a = &self.above[body.0];
        let b = other.map_or(&[][..], |o| &self.above[o.0][..]);
        let common = a
            .iter()
            .zip(b)
            .take_while(|(x, y)| x.joint == y.joint)
            .count();
        (&a[common..], &b[common..])
    }

    /// How far along the motion (in its parameter) `body` and `other` may go before their
    /// points move `gap` relative to each other, from the joints' axes as posed in `links`:
    /// the points of a body move about an axis at most as fast as their distance from it,
    /// which grows no faster than the joints below the axis move them ([`JointReach::rate`]
    /// of those). Tighter than `gap` over [`JointReach::rate`] where an arm is folded: the
    /// static bound takes every joint's distance as if the arm were stretched.
    pub(super) fn local_step(
        &self,
        speed: &[f32],
        (body, other): (Body, Option<Body>),
        links: &[Pose],
        gap: f32,
    ) -> f32 {
        let (a, b) = self.sides(body, other);
        let (mut lin, mut quad) = self.local_side(speed, a, body, links);
        if let Some(o) = other {
            let (l, q) = self.local_side(speed, b, o, links);
            (lin, quad) = (lin + l, quad + q);
        }
        // The relative motion over a step h is at most lin h + quad h^2 / 2.
        if quad > 0.0 {
            2.0 * gap / (lin + (lin * lin + 2.0 * quad * gap).sqrt())
        } else if lin > 0.0 {
            gap / lin
        } else {
            f32::INFINITY
        }
    }

    /// One side of [`JointReach::local_step`]: the speed of `body`'s points over joints `list`
    /// now (`lin`), and how fast that bound may grow (`quad`).
    fn local_side(&self, speed: &[f32], list: &[Above], body: Body, links: &[Pose]) -> (f32, f32) {
        let (link, centre, radius) = body;
        let c = links[link] * centre;
        let (mut lin, mut quad, mut below) = (0.0, 0.0, 0.0);
        for e in list.iter().rev() {
            let s = speed[e.joint as usize];
            if s == 0.0 {
                continue;
            }
            if !e.prismatic {
                let (child, axis) = self.axes[e.joint as usize];
                let (frame, axis) = (&links[child], links[child].rotation * axis);
                let v = c - frame.translation;
                lin += s * ((v - axis * v.dot(axis)).length() + radius);
                quad += s * below;
            } else {
                lin += s;
            }
            below += e.speed(speed, body);
        }
        (lin, quad)
    }
}

impl Above {
    /// A bound on the speed of `body`'s points about this joint, over all configurations.
    fn speed(&self, speed: &[f32], (_, centre, radius): Body) -> f32 {
        let s = speed[self.joint as usize];
        if self.prismatic || s == 0.0 {
            return s;
        }
        let from_axis = match self.rigid {
            Some((frame, axis)) => {
                let c = frame * centre;
                (c - axis * c.dot(axis)).length()
            }
            None => self.arm + centre.length(),
        };
        s * (from_axis + radius)
    }
}

/// Two bodies whose distance is followed along a motion.
#[derive(Clone, Copy, Debug)]
enum Pair {
    /// Agent shape and obstacle.
    Obstacle(u16, u32),
    /// A link of several shapes and an obstacle, until they are near: then its shapes.
    LinkObstacle(u16, u32),
    /// A pair of links (an index into the checked groups), until it is near: then its shapes.
    Links(u32),
    /// An agent shape and a link of several shapes (of a pair of links that is near), until
    /// they are near: then the shape and each of the link's.
    ShapeLink(u16, u16),
    /// Two agent shapes.
    Shapes(u16, u16),
    /// Held object and obstacle.
    HeldObstacle(u8, u32),
    /// Held object and a link, until they are near: then the link's shapes.
    HeldLink(u8, u16),
    /// Held object and agent shape.
    HeldShape(u8, u16),
    /// Two held objects.
    HeldObjects(u8, u8),
}

/// A pair, its relative speed bound, and when it must be measured next.
#[derive(Clone, Copy, Debug)]
struct Item {
    pair: Pair,
    rate: f32,
    next: f32,
    /// The direction that last separated the pair (zero: none yet), where GJK starts next.
    warm: Vector,
}

impl Item {
    /// Pair `pair`, due at `next`, when its bodies move relative to each other at all.
    fn moving(pair: Pair, rate: f32, next: f32) -> Option<Item> {
        (rate > 0.0).then_some(Item {
            pair,
            rate,
            next,
            warm: Vector::ZERO,
        })
    }
}

/// What a measurement of a pair found.
enum Measure {
    /// Apart by at least this much; whether that was measured exactly (between the shapes
    /// themselves, not their bounds).
    Apart(f32, bool),
    /// Near: measure the shapes of the links instead.
    Split,
    /// In collision.
    Hit(Hit),
}

/// A distance of parry's (shapes without a support function) is discounted by this fraction
/// (its relative tolerance, with margin).
const GJK_RELATIVE: f32 = 0.005;

/// [`support_gap`] stops once its best gap is within this fraction of GJK's upper bound: a
/// step of conservative advancement at most this much shorter than the exact distance would
/// allow, for fewer GJK iterations (0.5 % took 2 % more instructions in the bench).
const GJK_SETTLED: f32 = 0.05;

/// A pair due within this much of the motion's parameter is measured with the pairs due now.
const BATCH: f32 = 0.02;

/// A cheap bound (boxes, spheres) of at least this (metres) is used as it is; nearer, the
/// exact distance is measured.
const CHEAP_ENOUGH: f32 = 0.02;

/// A link nearer than this to another link or an obstacle, or a shape nearer than this to a
/// link (metres, by balls and boxes), is measured part by part.
const SPLIT: f32 = 0.03;

/// What a motion check found, and how many configurations it posed.
#[derive(Debug, Clone)]
pub struct MotionCheck {
    /// The first collision found, if any.
    pub contact: Option<Contact>,
    /// Configurations posed (the start's full check included).
    pub configurations: usize,
}

impl CollisionChecker {
    /// Whether the straight joint-space motion from `a` to `b` (full configurations; each
    /// joint value moves linearly, so a continuous joint's `b` is `a`'s value plus its step,
    /// not wrapped) is free, by conservative advancement (see the module docs): free at every
    /// configuration of the motion where no pair comes within `floor` metres, and a pair
    /// within `floor` is measured every `floor` of its relative motion. `a` is checked in
    /// full first.
    ///
    /// # Panics
    /// If `a` or `b` does not have the model's number of degrees of freedom.
    pub fn check_motion(&self, a: &[f32], b: &[f32], floor: f32) -> MotionCheck {
        if let Some(c) = self.first_collision(a) {
            return MotionCheck {
                contact: Some(c),
                configurations: 1,
            };
        }
        let model = &self.agent.model;
        assert_eq!(b.len(), model.dof(), "configuration length");
        let speed: Vec<f32> = (0..model.joints().len())
            .map(|j| (model.joint_value(j, b) - model.joint_value(j, a)).abs())
            .collect();
        SCRATCH.with(|scratch| {
            let mut s = scratch.borrow_mut();
            let (mut moving, mut groups, fixed) = self.pose_into(a, &mut s);
            if fixed.is_some_and(|f| !f.matches(b)) {
                // Joints outside the cache's move too: every shape and pair may.
                (moving, groups) = (&self.agent.all_shapes, &self.agent.groups);
            }
            let items = self.motion_items((&speed, (a, b)), moving, groups, &mut s);
            let mut q = a.to_vec();
            let pose_at = |t: f32, s: &mut Scratch| {
                for (v, (x, y)) in q.iter_mut().zip(a.iter().zip(b)) {
                    *v = x + t * (y - x);
                }
                self.pose_links_into(&q, s);
            };
            self.advance(items, floor, (&speed, groups), &mut s, pose_at)
        })
    }

    /// [`CollisionChecker::check_motion`] for a motion of the base, the joints at `q`: from
    /// planar pose `from` (x, y, yaw; see [`crate::world::base_pose`]) straight to `to` (its
    /// yaw `from`'s plus the turn, not wrapped). The agent moves as one body, so only what it
    /// and what it holds meet in the scene is followed; the checker's own base is not used.
    pub fn check_base_motion(
        &self,
        q: &[f32],
        from: [f32; 3],
        to: [f32; 3],
        floor: f32,
    ) -> MotionCheck {
        let base_at = |t: f32| {
            let [x, y, yaw] = [0, 1, 2].map(|i| from[i] + t * (to[i] - from[i]));
            base_pose(x, y, yaw)
        };
        let mut start = self.clone();
        start.fixed = None;
        start.base = base_at(0.0);
        if let Some(c) = start.first_collision(q) {
            return MotionCheck {
                contact: Some(c),
                configurations: 1,
            };
        }
        // The links in the base's frame, and how fast a body moves with the base.
        let model = &self.agent.model;
        let relative = model.link_poses(Pose::IDENTITY, q);
        let (v, w) = (
            Vector::new(to[0] - from[0], to[1] - from[1], 0.0).length(),
            (to[2] - from[2]).abs(),
        );
        let rate = |link: usize, centre: Vector, radius: f32| {
            let c = relative[link] * centre;
            v + w * (Vector::new(c.x, c.y, 0.0).length() + radius)
        };
        let pose_at = |t: f32, s: &mut Scratch| {
            let base = base_at(t);
            s.links.clear();
            s.links.extend(relative.iter().map(|l| base * *l));
            s.links_moved();
        };
        SCRATCH.with(|scratch| {
            let mut s = scratch.borrow_mut();
            pose_at(0.0, &mut s);
            s.poses.clear();
            s.aabbs.clear();
            for e in &self.agent.shapes {
                let p = s.links[e.link] * e.local_pose;
                s.poses.push(p);
                s.aabbs.push(e.aabb(&p));
            }
            s.all_posed();
            let mut items = Vec::new();
            let mut push = |pair, rate: f32| items.extend(Item::moving(pair, rate, 0.0));
            let mut candidates = std::mem::take(&mut s.candidates);
            for (i, e) in self.agent.shapes.iter().enumerate() {
                let r = rate(e.link, e.local_pose * e.ball.0, e.ball.1);
                self.obstacles
                    .candidates(&s.aabbs[i].loosened(r), &mut candidates);
                for &o in &candidates {
                    push(Pair::Obstacle(i as u16, o), r);
                }
            }
            for (k, h) in self.held.iter().chain(&self.other_held).enumerate() {
                let r = rate(h.link, h.grasp.translation, h.radius);
                let p = s.links[h.link] * h.grasp;
                self.obstacles
                    .candidates(&h.shape.compute_aabb(&p).loosened(r), &mut candidates);
                for &o in &candidates {
                    push(Pair::HeldObstacle(k as u8, o), r);
                }
            }
            s.candidates = candidates;
            self.advance(items, floor, (&[], &[]), &mut s, pose_at)
        })
    }

    /// Conservative advancement over `items` (see the module docs), the agent posed in `s` at
    /// the motion's start, `pose_at` posing it at a parameter `t` in [0, 1]. `speed` (per
    /// joint) and `groups` serve the pairs of links that split into pairs of shapes.
    fn advance(
        &self,
        mut items: Vec<Item>,
        floor: f32,
        (speed, groups): (&[f32], &[PairGroup]),
        s: &mut Scratch,
        mut pose_at: impl FnMut(f32, &mut Scratch),
    ) -> MotionCheck {
        let floor = floor.max(1e-6);
        let (mut t, mut configurations) = (0.0f32, 1);
        loop {
            let mut k = 0;
            while k < items.len() {
                k += 1;
                // Due within the window: measured now, early (which is sound), so that pairs
                // share the configurations posed. (Read in place: most items are not due, and
                // copying each out cost 3 % of the library bench's instructions.)
                if items[k - 1].next > t + BATCH {
                    continue;
                }
                let item = items[k - 1];
                let remaining = item.rate * (1.0 - t);
                self.pose_shapes_of(item.pair, s);
                let mut warm = item.warm;
                let measured = self.measure(item.pair, remaining, groups, s, &mut warm);
                items[k - 1].warm = warm;
                let next = match measured {
                    Measure::Hit(h) => {
                        return MotionCheck {
                            contact: Some(self.contact(h)),
                            configurations,
                        };
                    }
                    Measure::Split => {
                        self.split((speed, groups), (item.pair, t), s, &mut items);
                        f32::INFINITY
                    }
                    Measure::Apart(d, exact) => {
                        let gap = d.max(floor);
                        let mut step = gap / item.rate;
                        // Worth its cost where the pair is measured exactly: fewer steps.
                        if exact && !speed.is_empty() {
                            let bodies = self.bodies(item.pair, groups);
                            step =
                                step.max(self.agent.reach.local_step(speed, bodies, &s.links, gap));
                        }
                        t + step
                    }
                };
                items[k - 1].next = if next > 1.0 { f32::INFINITY } else { next };
            }
            t = items.iter().map(|i| i.next).fold(f32::INFINITY, f32::min);
            if t > 1.0 {
                return MotionCheck {
                    contact: None,
                    configurations,
                };
            }
            pose_at(t, s);
            configurations += 1;
        }
    }

    /// The bodies of `pair` for speed bounds: the first, and the second where it moves with
    /// the agent.
    fn bodies(&self, pair: Pair, groups: &[PairGroup]) -> (Body, Option<Body>) {
        let shapes = &self.agent.shapes;
        let sphere = |l: usize| self.link_body(l);
        match pair {
            Pair::Obstacle(i, _) => (body(&shapes[i as usize]), None),
            Pair::LinkObstacle(l, _) => (sphere(l as usize), None),
            Pair::Links(g) => {
                let g = groups[g as usize];
                (sphere(g.a as usize), Some(sphere(g.b as usize)))
            }
            Pair::Shapes(a, b) => (body(&shapes[a as usize]), Some(body(&shapes[b as usize]))),
            Pair::ShapeLink(i, l) => (body(&shapes[i as usize]), Some(sphere(l as usize))),
            Pair::HeldObstacle(k, _) => (held_body(self.held_k(k)), None),
            Pair::HeldLink(k, l) => (held_body(self.held_k(k)), Some(sphere(l as usize))),
            Pair::HeldShape(k, i) => (held_body(self.held_k(k)), Some(body(&shapes[i as usize]))),
            Pair::HeldObjects(k, l) => (held_body(self.held_k(k)), Some(held_body(self.held_k(l)))),
        }
    }

    /// Link `l` as a body: its sphere.
    fn link_body(&self, l: usize) -> Body {
        let (centre, radius) = self.agent.link_spheres[l];
        (l, centre, radius)
    }

    /// Poses the agent shapes of `pair` in `s` where the links moved since.
    fn pose_shapes_of(&self, pair: Pair, s: &mut Scratch) {
        let shapes = &self.agent.shapes;
        match pair {
            Pair::Obstacle(i, _) | Pair::HeldShape(_, i) | Pair::ShapeLink(i, _) => {
                s.pose_shape(i as usize, &shapes[i as usize]);
            }
            Pair::Shapes(a, b) => {
                s.pose_shape(a as usize, &shapes[a as usize]);
                s.pose_shape(b as usize, &shapes[b as usize]);
            }
            _ => {}
        }
    }

    /// Every pair that may come together during the motion from `a` to `b` (posed at its
    /// start in `s`, its joints at `speed`), due at once: the moving shapes against the
    /// obstacles within their reach, the checked pairs of links of which one moves (but those
    /// their cells prove apart all along), the held objects against the obstacles, the agent
    /// and each other.
    fn motion_items(
        &self,
        (speed, motion): (&[f32], (&[f32], &[f32])),
        moving: &[u16],
        groups: &[PairGroup],
        s: &mut Scratch,
    ) -> Vec<Item> {
        let reach = &self.agent.reach;
        let shapes = &self.agent.shapes;
        let mut items = Vec::new();
        let mut push = |pair, rate: f32| items.extend(Item::moving(pair, rate, 0.0));
        if !self.obstacles.is_empty() {
            // A link's shapes are consecutive: one pair per link of several shapes and obstacle.
            for link in moving.chunk_by(|a, b| shapes[*a as usize].link == shapes[*b as usize].link)
            {
                if let [i] = link {
                    let e = &shapes[*i as usize];
                    let rate = reach.rate(speed, body(e), None);
                    let swept = s.aabbs[*i as usize].loosened(rate);
                    self.obstacles.candidates(&swept, &mut s.candidates);
                    for &o in &s.candidates {
                        push(Pair::Obstacle(*i, o), rate);
                    }
                    continue;
                }
                let l = shapes[link[0] as usize].link;
                let rate = reach.rate(speed, self.link_body(l), None);
                let mut swept = s.aabbs[link[0] as usize];
                for &i in &link[1..] {
                    swept.merge(&s.aabbs[i as usize]);
                }
                self.obstacles
                    .candidates(&swept.loosened(rate), &mut s.candidates);
                for &o in &s.candidates {
                    push(Pair::LinkObstacle(l as u16, o), rate);
                }
            }
        }
        if self.self_collision {
            // Each link's speed (the world without it), made where needed: two links' sum
            // bounds their relative speed, and rules out most pairs before it is needed.
            let mut alone = vec![f32::NAN; s.links.len()];
            let mut speed_of = |l: usize| {
                if alone[l].is_nan() {
                    alone[l] = reach.rate(speed, self.link_body(l), None);
                }
                alone[l]
            };
            for (g, pg) in groups.iter().enumerate() {
                let (a, b) = (pg.a as usize, pg.b as usize);
                let (ba, bb) = (self.link_body(a), self.link_body(b));
                let balls = (s.centres[a] - s.centres[b]).length() - ba.2 - bb.2;
                if balls > speed_of(a) + speed_of(b) {
                    continue;
                }
                let rate = reach.rate(speed, ba, Some(bb));
                // Too far apart to meet in the whole motion (their balls, then capsules), or
                // proven apart all along it by their cells.
                if balls > rate
                    || self.agent.capsule_gap(pg, &s.links) > rate
                    || self.agent.proven_apart_along(pg, motion)
                {
                    continue;
                }
                push(Pair::Links(g as u32), rate);
            }
        }
        let held: Vec<&HeldObject> = self.held.iter().chain(&self.other_held).collect();
        for (k, h) in held.iter().enumerate() {
            let hk = held_body(h);
            let rate = reach.rate(speed, hk, None);
            let p = s.links[h.link] * h.grasp;
            let swept = h.shape.compute_aabb(&p).loosened(rate);
            self.obstacles.candidates(&swept, &mut s.candidates);
            for &o in &s.candidates {
                push(Pair::HeldObstacle(k as u8, o), rate);
            }
            let spheres = &self.agent.link_spheres;
            for (l, (centre, radius)) in spheres.iter().enumerate() {
                if *radius >= 0.0 && !h.touching[l] {
                    let rate = reach.rate(speed, hk, Some((l, *centre, *radius)));
                    push(Pair::HeldLink(k as u8, l as u16), rate);
                }
            }
            for (l, other) in held.iter().enumerate().skip(k + 1) {
                push(
                    Pair::HeldObjects(k as u8, l as u8),
                    reach.rate(speed, hk, Some(held_body(other))),
                );
            }
        }
        items
    }

    /// Replaces a near pair of bodies by pairs of their parts, due at `t`: a pair of links by
    /// each shape of the link with fewer against the other link where that one has several
    /// shapes, else by their pairs of shapes; a shape against a link by the pairs of shapes; a
    /// link against an obstacle by its shapes that may reach the obstacle in the rest of the
    /// motion; a held object near a link by the object against the link's shapes.
    fn split(
        &self,
        (speed, groups): (&[f32], &[PairGroup]),
        (pair, t): (Pair, f32),
        s: &mut Scratch,
        out: &mut Vec<Item>,
    ) {
        let (shapes, reach) = (&self.agent.shapes, &self.agent.reach);
        let mut push = |pair, rate: f32| out.extend(Item::moving(pair, rate, t));
        match pair {
            Pair::Links(g) => {
                let g = groups[g as usize];
                let count = |l: u16| {
                    let (start, end) = self.agent.link_shapes[l as usize];
                    end - start
                };
                // The shapes of the link with fewer, each against the other link as a whole
                // (where it has several), then shape by shape.
                let (small, large) = match count(g.a) <= count(g.b) {
                    true => (g.a, g.b),
                    false => (g.b, g.a),
                };
                if count(large) > 1 {
                    let (start, end) = self.agent.link_shapes[small as usize];
                    for i in start..end {
                        let e = &shapes[i as usize];
                        let rate = reach.rate(speed, body(e), Some(self.link_body(large as usize)));
                        push(Pair::ShapeLink(i, large), rate);
                    }
                } else {
                    for &(a, b) in &self.agent.pairs[g.start as usize..g.end as usize] {
                        let (ea, eb) = (&shapes[a as usize], &shapes[b as usize]);
                        let rate = reach.rate(speed, body(ea), Some(body(eb)));
                        push(Pair::Shapes(a, b), rate);
                    }
                }
            }
            Pair::ShapeLink(i, l) => {
                let (start, end) = self.agent.link_shapes[l as usize];
                for j in start..end {
                    // In the order of the pair of links (the lower link's shape first).
                    let (a, b) = match shapes[i as usize].link < l as usize {
                        true => (i, j),
                        false => (j, i),
                    };
                    let (ea, eb) = (&shapes[a as usize], &shapes[b as usize]);
                    let rate = reach.rate(speed, body(ea), Some(body(eb)));
                    push(Pair::Shapes(a, b), rate);
                }
            }
            Pair::LinkObstacle(l, o) => {
                // The shapes that may reach the obstacle in the rest of the motion.
                let obstacle = &self.obstacles.aabbs[o as usize];
                let (start, end) = self.agent.link_shapes[l as usize];
                for (i, e) in (start as usize..).zip(&shapes[start as usize..end as usize]) {
                    let rate = reach.rate(speed, body(e), None);
                    s.pose_shape(i, e);
                    if s.aabbs[i].loosened(rate * (1.0 - t)).intersects(obstacle) {
                        push(Pair::Obstacle(i as u16, o), rate);
                    }
                }
            }
            Pair::HeldLink(k, l) => {
                let hk = held_body(self.held_k(k));
                for (i, e) in shapes.iter().enumerate() {
                    if e.link == l as usize {
                        let rate = reach.rate(speed, hk, Some(body(e)));
                        push(Pair::HeldShape(k, i as u16), rate);
                    }
                }
            }
            _ => unreachable!("only links split"),
        }
    }

    /// Held object `k` (0: [`CollisionChecker::set_held_object`]'s, then the others).
    fn held_k(&self, k: u8) -> &HeldObject {
        let mut all = self.held.iter().chain(&self.other_held);
        all.nth(k as usize).expect("a held object's index")
    }

    /// A lower bound on the distance of `pair` as posed in `s`: a cheap bound where it
    /// exceeds `remaining` (how far the pair may still move), else the exact distance, and a
    /// collision where that is 0 and the exact test agrees.
    fn measure(
        &self,
        pair: Pair,
        remaining: f32,
        groups: &[PairGroup],
        s: &Scratch,
        warm: &mut Vector,
    ) -> Measure {
        let shapes = &self.agent.shapes;
        let obstacle = |o: u32| &self.obstacles.obstacles[o as usize];
        let held = |k: u8| {
            let h = self.held_k(k);
            (h, s.links[h.link] * h.grasp)
        };
        let mut apart_or =
            |cheap: f32, exact: &dyn Fn(&mut Vector) -> f32, hit: &dyn Fn() -> bool, h: Hit| {
                // A cheap bound that settles the rest of the motion, or is worth a few steps.
                if cheap >= remaining.min(CHEAP_ENOUGH) {
                    return Measure::Apart(cheap, false);
                }
                let d = exact(warm);
                if d > 0.0 {
                    Measure::Apart(d.max(cheap), true)
                } else if hit() {
                    Measure::Hit(h)
                } else {
                    Measure::Apart(cheap.max(0.0), true)
                }
            };
        match pair {
            Pair::Obstacle(i, o) => {
                let (e, p, ob) = (&shapes[i as usize], &s.poses[i as usize], obstacle(o));
                let mut cheap = aabb_gap(&s.aabbs[i as usize], &self.obstacles.aabbs[o as usize]);
                if cheap < remaining.min(CHEAP_ENOUGH) {
                    cheap = cheap.max(box_gap(e, p, None, &*ob.shape.0, &ob.pose));
                }
                apart_or(
                    cheap,
                    &|w| match ob.shape.as_compound() {
                        Some(c) => {
                            let shape = (e.support(), &*e.shape.0, p, &s.aabbs[i as usize]);
                            compound_gap(shape, (c, &ob.pose), remaining)
                        }
                        None => entry_gap(e, p, plain(&*ob.shape.0), (&ob.pose, remaining), w),
                    },
                    &|| e.hits_by_gjk(p, &*ob.shape.0, &ob.pose),
                    Hit::Obstacle(i as usize, o as usize),
                )
            }
            Pair::LinkObstacle(l, o) => {
                let l = l as usize;
                let (centre, radius) = self.agent.link_spheres[l];
                let obstacle = &self.obstacles.aabbs[o as usize];
                let c = s.links[l] * centre;
                let mut gap = (c - c.clamp(obstacle.mins, obstacle.maxs)).length() - radius;
                if gap < remaining.min(SPLIT)
                    && let Some(b) = self.agent.link_box(l, &s.links[l])
                {
                    gap = gap.max(aabb_gap(&b, obstacle));
                }
                apart_or_split(gap, remaining)
            }
            Pair::ShapeLink(i, l) => {
                let (e, l) = (&shapes[i as usize], l as usize);
                let (c, r) = ball(e, &s.poses[i as usize]);
                let mut gap = (c - s.centres[l]).length() - r - self.agent.link_spheres[l].1;
                if gap < remaining.min(SPLIT)
                    && let Some(b) = self.agent.link_box(l, &s.links[l])
                {
                    gap = gap.max(aabb_gap(&s.aabbs[i as usize], &b));
                }
                apart_or_split(gap, remaining)
            }
            Pair::Links(g) => {
                let g = groups[g as usize];
                let (a, b) = (g.a as usize, g.b as usize);
                let r = self.agent.link_spheres[a].1 + self.agent.link_spheres[b].1;
                let mut gap = (s.centres[a] - s.centres[b]).length() - r;
                if gap < remaining.min(SPLIT) {
                    gap = gap.max(self.agent.capsule_gap(&g, &s.links));
                }
                apart_or_split(gap, remaining)
            }
            Pair::HeldLink(k, l) => {
                let (h, p) = held(k);
                let (l, sphere) = (l as usize, self.agent.link_spheres[l as usize]);
                let mut gap = (s.centres[l] - p.translation).length() - sphere.1 - h.radius;
                if gap < remaining.min(SPLIT) {
                    let capsule =
                        self.agent
                            .capsule_ball_gap(l, &s.links[l], p.translation, h.radius);
                    gap = gap.max(capsule);
                }
                apart_or_split(gap, remaining)
            }
            Pair::Shapes(a, b) => {
                let (ea, eb) = (&shapes[a as usize], &shapes[b as usize]);
                let (pa, pb) = (&s.poses[a as usize], &s.poses[b as usize]);
                let ((ca, ra), (cb, rb)) = (ball(ea, pa), ball(eb, pb));
                let sphere = (ca - cb).length() - ra - rb;
                let mut cheap = sphere.max(aabb_gap(&s.aabbs[a as usize], &s.aabbs[b as usize]));
                if cheap < remaining.min(CHEAP_ENOUGH) {
                    let links = (&s.links[ea.link], &s.links[eb.link]);
                    cheap = cheap.max(ea.capsule_gap(links.0, eb, links.1));
                }
                if cheap < remaining.min(CHEAP_ENOUGH) {
                    cheap = cheap.max(box_gap(ea, pa, Some(eb), &*eb.shape.0, pb));
                }
                apart_or(
                    cheap,
                    &|w| entry_gap(ea, pa, entry(eb), (pb, remaining), w),
                    &|| ea.hits_shape_by_gjk(pa, eb, pb),
                    Hit::SelfPair(a as usize, b as usize),
                )
            }
            Pair::HeldObstacle(k, o) => {
                let ((h, p), ob) = (held(k), obstacle(o));
                let cheap = aabb_gap(&h.shape.compute_aabb(&p), &self.obstacles.aabbs[o as usize]);
                apart_or(
                    cheap,
                    &|_| lower_bound_distance(&p, &*h.shape.0, &ob.pose, &*ob.shape.0),
                    &|| intersects(&p, &*h.shape.0, &ob.pose, &*ob.shape.0),
                    Hit::HeldObstacle(k as usize, o as usize),
                )
            }
            Pair::HeldShape(k, i) => {
                let ((h, p), e) = (held(k), &shapes[i as usize]);
                let pe = &s.poses[i as usize];
                let (ce, re) = ball(e, pe);
                let cheap = (ce - p.translation).length() - re - h.radius;
                apart_or(
                    cheap,
                    &|w| entry_gap(e, pe, plain(&*h.shape.0), (&p, remaining), w),
                    &|| e.hits(pe, &*h.shape.0, &p),
                    Hit::HeldShape(k as usize, i as usize),
                )
            }
            Pair::HeldObjects(k, l) => {
                let ((a, pa), (b, pb)) = (held(k), held(l));
                let cheap = (pa.translation - pb.translation).length() - a.radius - b.radius;
                apart_or(
                    cheap,
                    &|_| lower_bound_distance(&pa, &*a.shape.0, &pb, &*b.shape.0),
                    &|| intersects(&pa, &*a.shape.0, &pb, &*b.shape.0),
                    Hit::HeldPair(k as usize, l as usize),
                )
            }
        }
    }
}

/// What a bound `gap` on a pair of links (or a link and a body) says where the pair may still
/// move `remaining`: apart, or near enough to be measured part by part ([`SPLIT`]).
fn apart_or_split(gap: f32, remaining: f32) -> Measure {
    if gap >= remaining.min(SPLIT) {
        Measure::Apart(gap, false)
    } else {
        Measure::Split
    }
}

/// An agent shape as a body of its link.
pub(super) fn body(e: &ShapeEntry) -> Body {
    (e.link, e.local_pose * e.ball.0, e.ball.1)
}

/// The world centre of an agent shape's ball at `pose`, and its radius.
fn ball(e: &ShapeEntry, pose: &Pose) -> (Vector, f32) {
    (*pose * e.ball.0, e.ball.1)
}

/// Whether agent shapes `a` and `b`, their links at `poses`, are proven at least `needed`
/// apart: by their balls or capsules, else by GJK (their climbing supports) stopped as soon as
/// that is settled.
pub(super) fn proven_apart(
    (a, b): (&ShapeEntry, &ShapeEntry),
    poses: &[Pose],
    needed: f32,
) -> bool {
    let (pa, pb) = (poses[a.link] * a.local_pose, poses[b.link] * b.local_pose);
    let balls = (pa * a.ball.0 - pb * b.ball.0).length() - a.ball.1 - b.ball.1;
    if balls >= needed || a.capsule_gap(&poses[a.link], b, &poses[b.link]) >= needed {
        return true;
    }
    let gap = match (a.support(), b.support()) {
        (Some(sa), Some(sb)) => {
            // From the line between the balls' centres (in `a`'s frame), not between the
            // frames' origins: a mesh piece's frame is its link's.
            let pos12 = pa.inv_mul(&pb);
            let mut start = a.ball.0 - pos12 * b.ball.0;
            support_gap_until(&pos12, (sa, sb), &mut start, (needed, needed))
        }
        _ => lower_bound_distance(&pa, &*a.shape.0, &pb, &*b.shape.0),
    };
    gap >= needed
}

/// A held object as a body of the link holding it.
fn held_body(h: &HeldObject) -> Body {
    (h.link, h.grasp.translation, h.radius)
}

/// The distance between two AABBs (0 where they overlap): a lower bound on their contents'.
fn aabb_gap(a: &Aabb, b: &Aabb) -> f32 {
    let gap = (a.mins - b.maxs).max(b.mins - a.maxs).max(Vector::ZERO);
    gap.length()
}

/// A lower bound on the distance between an agent shape at `pose` and another shape at
/// `other_pose` with its support function (an agent shape's climbing one, see [`entry`]), by
/// GJK started from `warm` (the direction that last separated the pair; updated); see [`gap`]
/// where either has no support function.
fn entry_gap(
    e: &ShapeEntry,
    pose: &Pose,
    (other, other_support): (&dyn Shape, Option<&dyn SupportMap>),
    (other_pose, enough): (&Pose, f32),
    warm: &mut Vector,
) -> f32 {
    match (e.support(), other_support) {
        (Some(a), Some(b)) => {
            let ends = (enough, f32::NEG_INFINITY);
            support_gap_until(&pose.inv_mul(other_pose), (a, b), warm, ends)
        }
        _ => lower_bound_distance(pose, &*e.shape.0, other_pose, other),
    }
}

/// A lower bound on the distance between a shape at `pose` (its support function where it
/// has one, a large hull's climbing one for an agent shape; its world box `bounds`) and
/// compound `c` at `c_pose`: the least over the parts whose boxes are nearer than the best so
/// far, each by GJK in the part's frame, stopped once it is known to be at least `enough` or
/// that best (which leaves the least as it is).
fn compound_gap(
    (support, shape, pose, bounds): (Option<&dyn SupportMap>, &dyn Shape, &Pose, &Aabb),
    (c, c_pose): (&Compound, &Pose),
    enough: f32,
) -> f32 {
    let mut best = f32::INFINITY;
    for (p, part) in c.shapes() {
        let at = *c_pose * *p;
        let cheap = aabb_gap(&part.compute_aabb(&at), bounds);
        if cheap >= best {
            continue;
        }
        let gap = match (support, part.as_support_map()) {
            (Some(a), Some(b)) => {
                let pos21 = at.inv_mul(pose);
                let mut start = -pos21.translation;
                let ends = (best.min(enough), f32::NEG_INFINITY);
                support_gap_until(&pos21, (b, a), &mut start, ends)
            }
            _ => lower_bound_distance(&at, &**part, pose, shape),
        };
        best = best.min(gap.max(cheap));
    }
    best
}

/// A shape that is no agent shape, with its support function.
fn plain(shape: &dyn Shape) -> (&dyn Shape, Option<&dyn SupportMap>) {
    (shape, shape.as_support_map())
}

/// An agent shape, with its support function (the climbing one of a large hull).
fn entry(e: &ShapeEntry) -> (&dyn Shape, Option<&dyn SupportMap>) {
    (&*e.shape.0, e.support())
}

/// A proven lower bound on the distance between support maps `a` and `b` (`b` at `pos12` in
/// `a`'s frame): GJK's iterations, started from `warm` where it is one, each direction giving
/// the gap along it between the shapes' support points; the best of these gaps (0 where none
/// is positive), its direction kept in `warm`. A proof whatever GJK's answer is worth. Parry's
/// GJK returns its last direction, not its best: for two long hulls a few millimetres apart,
/// face to face, that one can show a fiftieth of the gap.
fn support_gap(pos12: &Pose, a: &dyn SupportMap, b: &dyn SupportMap, warm: &mut Vector) -> f32 {
    support_gap_until(pos12, (a, b), warm, (f32::INFINITY, f32::NEG_INFINITY))
}

/// [`support_gap`], stopped as soon as the answer is known to be at least `enough`, or known
/// to be less than `below` (`enough` and `below` the same: whether two shapes are that far
/// apart, not how far).
fn support_gap_until(
    pos12: &Pose,
    (a, b): (&dyn SupportMap, &dyn SupportMap),
    warm: &mut Vector,
    (enough, below): (f32, f32),
) -> f32 {
    let start = match warm.try_normalize() {
        Some(d) => d,
        None => (-pos12.translation).try_normalize().unwrap_or(Vector::X),
    };
    let mut simplex = VoronoiSimplex::new();
    let first = CsoPoint::from_shapes(pos12, a, b, start);
    let mut best = (-first.point.dot(start), start);
    simplex.reset(first);
    let mut restarts = 0;
    for _ in 0..GJK_ITERATIONS {
        // The simplex's point nearest the origin bounds the distance from above.
        let (dir, upper) = (-simplex.project_origin_and_reduce()).normalize_and_length();
        if upper.is_nan() || upper <= 1e-7 {
            break; // the origin is on the simplex: touching or intersecting
        }
        let cso = CsoPoint::from_shapes(pos12, a, b, dir);
        let lower = -cso.point.dot(dir);
        if lower > best.0 {
            best = (lower, dir);
        }
        if upper - best.0 <= GJK_SETTLED * upper || best.0 >= enough || upper < below {
            break;
        }
        if !simplex.add_point(cso) {
            // A support point the simplex holds nearly (rounding): start again from it alone,
            // a few times.
            if restarts == GJK_RESTARTS {
                break;
            }
            restarts += 1;
            simplex.reset(cso);
        }
    }
    *warm = if best.0 > 0.0 { best.1 } else { Vector::ZERO };
    best.0.max(0.0)
}

/// The most GJK iterations of [`support_gap`] (it converges in a few dozen), and restarts.
const GJK_ITERATIONS: usize = 64;
const GJK_RESTARTS: usize = 3;

/// A lower bound on the distance between two shapes: [`support_gap`] where both are support
/// maps, the smallest over the parts of a compound, else parry's distance less its tolerance.
pub(super) fn lower_bound_distance(pa: &Pose, a: &dyn Shape, pb: &Pose, b: &dyn Shape) -> f32 {
    if b.as_compound().is_some() && a.as_compound().is_none() {
        return lower_bound_distance(pb, b, pa, a);
    }
    if let Some(c) = a.as_compound() {
        // The nearest part, its boxes first: a part whose box is farther than the best so far
        // cannot be nearer.
        let other = (b.as_support_map(), b, pb, &b.compute_aabb(pb));
        return compound_gap(other, (c, pa), f32::INFINITY);
    }
    match (a.as_support_map(), b.as_support_map()) {
        (Some(sa), Some(sb)) => {
            let mut cold = Vector::ZERO;
            support_gap(&pa.inv_mul(pb), sa, sb, &mut cold)
        }
        _ => query::distance(pa, a, pb, b)
            .map_or(0.0, |d| d.distance * (1.0 - GJK_RELATIVE) - 1e-4)
            .max(0.0),
    }
}

/// A lower bound on the distance of an agent shape at `pose` and another shape (an agent
/// shape `other_entry`, or `other`) at `other_pose`, from the bounding boxes of the polyhedra
/// among them (cheap supports); 0 where neither has one.
fn box_gap(
    e: &ShapeEntry,
    pose: &Pose,
    other_entry: Option<&ShapeEntry>,
    other: &dyn Shape,
    other_pose: &Pose,
) -> f32 {
    let other_box = other_entry.and_then(|o| o.bounds.as_ref());
    if e.bounds.is_none() && other_box.is_none() {
        return 0.0;
    }
    let (pa, a): (Pose, &dyn SupportMap) = match (&e.bounds, e.support()) {
        (Some((at, cuboid)), _) => (*pose * *at, cuboid),
        (None, Some(sm)) => (*pose, sm),
        (None, None) => return 0.0,
    };
    let (pb, b): (Pose, &dyn SupportMap) = match (other_box, other.as_support_map()) {
        (Some((at, cuboid)), _) => (*other_pose * *at, cuboid),
        (None, Some(sm)) => (*other_pose, sm),
        (None, None) => return 0.0,
    };
    let mut cold = Vector::ZERO;
    support_gap(&pa.inv_mul(&pb), a, b, &mut cold)
}

#[cfg(test)]
mod tests {
    use super::*;
    use parry3d::math::Rotation;
    use parry3d::shape::ConvexPolyhedron;

    /// A long hull of many vertices, like a forearm's piece: points of an ellipsoid.
    fn long_hull(seed: u64) -> ConvexPolyhedron {
        let mut rng = fastrand::Rng::with_seed(seed);
        let points: Vec<Vector> = (0..400)
            .map(|_| {
                let v = Vector::new(rng.f32() - 0.5, rng.f32() - 0.5, rng.f32() - 0.5);
                v.normalize() * Vector::new(0.04, 0.05, 0.16)
            })
            .collect();
        ConvexPolyhedron::from_convex_hull(&points).unwrap()
    }

    /// The best gap along directions found by a random local search from `n`: a lower bound
    /// on the distance that GJK's should come near.
    fn searched_gap(pos12: &Pose, a: &dyn SupportMap, b: &dyn SupportMap, n: Vector) -> f32 {
        let gap = |n: Vector| -CsoPoint::from_shapes(pos12, a, b, n).point.dot(n);
        let mut rng = fastrand::Rng::with_seed(1);
        let (mut best, mut step) = ((n, gap(n)), 0.05f32);
        for _ in 0..20_000 {
            let jitter = Vector::new(rng.f32() - 0.5, rng.f32() - 0.5, rng.f32() - 0.5);
            let c = (best.0 + jitter * step).normalize();
            let g = gap(c);
            if g > best.1 {
                best = (c, g);
            } else {
                step = (step * 0.999).max(1e-5);
            }
        }
        best.1
    }

    fn unit(rng: &mut fastrand::Rng) -> Vector {
        Vector::new(rng.f32() - 0.5, rng.f32() - 0.5, rng.f32() - 0.5).normalize()
    }

    /// Asserts that over [`JointReach::local_step`] from `t0` of the motion `a` to `b`, no
    /// point of `body` moves more than `gap` in the world (`other` none), or no two points of
    /// `body` and `other` come nearer or go further by more than it. Whether the step is much
    /// longer than the static bound's.
    fn assert_local_step(
        (model, reach): (&AgentModel, &JointReach),
        (a, b): (&[f32], &[f32]),
        (body, other): (Body, Option<Body>),
        (t0, gap): (f32, f32),
        rng: &mut fastrand::Rng,
    ) -> bool {
        let speed: Vec<f32> = (0..model.joints().len())
            .map(|j| (model.joint_value(j, b) - model.joint_value(j, a)).abs())
            .collect();
        let at = |t: f32| {
            let q: Vec<f32> = a.iter().zip(b).map(|(x, y)| x + t * (y - x)).collect();
            model.link_poses(Pose::IDENTITY, &q)
        };
        let start = at(t0);
        let step = reach.local_step(&speed, (body, other), &start, gap);
        let point = |(l, c, r): Body, poses: &[Pose], d: Vector| poses[l] * (c + d * r);
        for k in 1..=10 {
            let end = at(t0 + step.min(1.0) * k as f32 / 10.0);
            for _ in 0..20 {
                let (da, db) = (unit(rng) * rng.f32(), unit(rng) * rng.f32());
                let moved = match other {
                    None => (point(body, &end, da) - point(body, &start, da)).length(),
                    Some(o) => {
                        let apart = |poses: &[Pose]| {
                            (point(body, poses, da) - point(o, poses, db)).length()
                        };
                        (apart(&end) - apart(&start)).abs()
                    }
                };
                assert!(
                    moved <= gap * 1.001 + 1e-6,
                    "moved {moved} over a gap of {gap}"
                );
            }
        }
        step > gap / reach.rate(&speed, body, other) * 1.2
    }

    #[test]
    fn a_local_step_never_lets_two_bodies_come_nearer_than_the_gap() {
        let path = format!("{}/../../models/pr2.urdf", env!("CARGO_MANIFEST_DIR"));
        let model = AgentModel::from_urdf_file(&path).unwrap();
        let reach = JointReach::new(&model);
        let links = model.links().len();
        let mut rng = fastrand::Rng::with_seed(5);
        // Random motions of all the PR2's joints, random balls on its links, alone or paired.
        let mut longer = 0;
        for _ in 0..1000 {
            let (a, b) = (
                model.random_configuration(&mut rng).into_vec(),
                model.random_configuration(&mut rng).into_vec(),
            );
            let ball = |rng: &mut fastrand::Rng| (rng.usize(0..links), unit(rng) * 0.1, 0.05);
            let body = ball(&mut rng);
            let other = rng.bool().then(|| ball(&mut rng));
            let (t0, gap) = (rng.f32() * 0.8, 0.01 + 0.05 * rng.f32());
            let bodies = (body, other);
            longer += usize::from(assert_local_step(
                (&model, &reach),
                (&a, &b),
                bodies,
                (t0, gap),
                &mut rng,
            ));
        }
        // Not vacuous: the local step is often much longer than the static bound's.
        assert!(longer > 250, "{longer} of 1000 longer");
        // An arm unfolding while it turns: the hand's distance from the shoulder's axis grows
        // fast, which the bound must allow for over long steps.
        let dof = |name: &str| model.dof_index(name).unwrap();
        let tool = (
            model.link_id("r_gripper_tool_frame").unwrap(),
            Vector::ZERO,
            0.0,
        );
        for gap in [0.05, 0.1, 0.2, 0.4, 0.8] {
            let mut a = model.default_configuration().into_vec();
            let mut b = a.clone();
            (a[dof("r_elbow_flex_joint")], b[dof("r_elbow_flex_joint")]) = (-2.3, 0.0);
            (
                a[dof("r_shoulder_pan_joint")],
                b[dof("r_shoulder_pan_joint")],
            ) = (0.7, -2.2);
            assert_local_step(
                (&model, &reach),
                (&a, &b),
                (tool, None),
                (0.0, gap),
                &mut rng,
            );
        }
    }

    #[test]
    fn the_support_gap_is_a_tight_lower_bound_for_long_hulls_millimetres_apart() {
        let (a, b) = (long_hull(1), long_hull(2));
        let mut rng = fastrand::Rng::with_seed(7);
        let mut cases = 0;
        while cases < 60 {
            let turn = |rng: &mut fastrand::Rng, s: f32| {
                Rotation::from_scaled_axis(
                    Vector::new(rng.f32() - 0.5, rng.f32() - 0.5, rng.f32() - 0.5) * s,
                )
            };
            // Side by side, nearly parallel, 0.5 to 5 mm apart by parry's distance.
            let rotation = turn(&mut rng, 0.2);
            let mut pos12 = Pose::from_parts(Vector::new(0.08, 0.0, 0.0), rotation);
            let target = 0.0005 + 0.0045 * rng.f32();
            let d = query::distance(&Pose::IDENTITY, &a, &pos12, &b)
                .unwrap()
                .distance;
            pos12.translation.x += target - d;
            let Ok(d) = query::distance(&Pose::IDENTITY, &a, &pos12, &b) else {
                continue;
            };
            if d.distance <= 0.0 {
                continue;
            }
            cases += 1;
            let mut warm = Vector::ZERO;
            let lower = support_gap(&pos12, &a, &b, &mut warm);
            assert!(lower <= d.distance + 1e-5, "{lower} above {}", d.distance);
            let searched = searched_gap(&pos12, &a, &b, Vector::X);
            assert!(
                lower >= 0.9 * searched,
                "case {cases}: {lower} against {searched} by search"
            );
        }
    }
}
