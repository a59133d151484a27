//! One trajectory replayed and checked: its frames and `sub` interpolated configurations between
//! consecutive frames (translation linear, rotation slerp); the moving agent's links and the
//! object it holds against everything else, against each other and against its own body.

use std::collections::BTreeMap;

use parry3d::bounding_volume::{Aabb, BoundingVolume};
use parry3d::math::Pose;

use crate::bodies::{Adjacency, Owner, Placed, depth, links_at, objects_at};
use crate::model::{Plan, Step, Trajectory};
use crate::report::{Fault, FaultKind};
use crate::world::World;

/// How the object moving with the agent gets its pose in each configuration.
#[derive(Clone, Copy)]
pub enum Carry {
    /// From the frames' `held_pose` (the trajectory declares `holding`).
    Declared,
    /// Rigidly with a link (`rel`: the object's pose in that link's frame), for an object still
    /// in the hand while the trajectory declares `holding: null`.
    Rigid { link: usize, rel: Pose },
}

/// One configuration: its frame label and the poses of links and held object.
pub struct Config {
    pub label: String,
    pub links: Vec<Pose>,
    pub held: Option<Pose>,
}

/// Everything a sweep needs to know about where it runs.
pub struct Sweep<'a> {
    pub plan: &'a Plan,
    pub step: &'a Step,
    pub index: usize,
    pub traj: &'a Trajectory,
    pub held: Option<(usize, Carry)>,
    pub adjacency: &'a Adjacency,
    pub depth: f32,
    pub grasp_depth: f32,
    pub sub: usize,
}

/// Which depth tolerance applies to a pair.
#[derive(Clone, Copy)]
enum Tolerance {
    /// Anything but a grasp: `--depth`.
    Contact,
    /// A hand and what it grasps: the grasp tolerance.
    Grasp,
}

/// Worst fault per (kind, bodies) of one trajectory.
pub type Found = BTreeMap<(FaultKind, Owner, Owner), Fault>;

fn interpolate(a: &Pose, b: &Pose, s: f32) -> Pose {
    Pose::from_parts(
        a.translation.lerp(b.translation, s),
        a.rotation.slerp(b.rotation, s),
    )
}

/// The trajectory's configurations: each frame, then `sub` evenly spaced ones before the next.
pub fn configs(traj: &Trajectory, sub: usize, carry: Option<Carry>) -> Vec<Config> {
    let f = &traj.frames;
    let mut out = Vec::with_capacity(f.len() * (sub + 1));
    for i in 0..f.len() {
        let last = i + 1 == f.len();
        for k in 0..=if last { 0 } else { sub } {
            let s = k as f32 / (sub + 1) as f32;
            let j = if last { i } else { i + 1 };
            let links: Vec<Pose> = (f[i].link_poses.iter().zip(&f[j].link_poses))
                .map(|(a, b)| interpolate(a, b, s))
                .collect();
            let held = match carry {
                None => None,
                Some(Carry::Rigid { link, rel }) => Some(links[link] * rel),
                Some(Carry::Declared) => match (f[i].held_pose, f[j].held_pose) {
                    (Some(a), Some(b)) => Some(interpolate(&a, &b, s)),
                    (a, b) => a.or(b),
                },
            };
            let label = if k == 0 {
                format!("{i}")
            } else {
                format!("{i}+{s:.2}")
            };
            out.push(Config { label, links, held });
        }
    }
    out
}

impl Sweep<'_> {
    /// Check every configuration; returns the faults found and the number of configurations.
    pub fn run(&self, world: &World) -> (Found, usize) {
        let a = self.traj.agent;
        let held_obj = self.held.map(|(o, _)| o);
        let skip: Vec<usize> = held_obj.into_iter().collect();
        let mut fixed = objects_at(self.plan, &world.objects, &skip);
        for b in (0..self.plan.agents.len()).filter(|&b| b != a) {
            fixed.extend(links_at(self.plan, b, &world.agents[b]));
        }
        let configs = configs(self.traj, self.sub, self.held.map(|(_, c)| c));
        let moving: Vec<Vec<Placed>> = configs.iter().map(|c| self.moving(c)).collect();
        let near = near_fixed(&moving, &fixed);
        let mut found = Found::new();
        for (c, bodies) in configs.iter().zip(&moving) {
            self.check_config(c, bodies, &fixed, &near, world, &mut found);
        }
        (found, configs.len())
    }

    /// The moving shapes of one configuration: links, then the held object's parts.
    fn moving(&self, c: &Config) -> Vec<Placed> {
        let mut out = links_at(self.plan, self.traj.agent, &c.links);
        if let (Some((o, _)), Some(p)) = (self.held, c.held) {
            let parts = &self.plan.objects[o].parts;
            out.extend(
                parts
                    .iter()
                    .map(|part| Placed::new(Owner::Held(o), part, &p)),
            );
        }
        out
    }

    fn check_config(
        &self,
        c: &Config,
        bodies: &[Placed],
        fixed: &[Placed],
        near: &[Vec<usize>],
        world: &World,
        found: &mut Found,
    ) {
        for (m, body) in bodies.iter().enumerate() {
            for &f in &near[m] {
                if let Some(tol) = self.tolerance(body.owner, fixed[f].owner, world) {
                    self.record(found, c, body, &fixed[f], tol);
                }
            }
            for other in &bodies[m + 1..] {
                if let Some(tol) = self.tolerance(body.owner, other.owner, world) {
                    self.record(found, c, body, other, tol);
                }
            }
        }
    }

    fn record(&self, found: &mut Found, c: &Config, a: &Placed, b: &Placed, tol: Tolerance) {
        let d = depth(a, b);
        let limit = match tol {
            Tolerance::Contact => self.depth,
            Tolerance::Grasp => self.grasp_depth,
        };
        if d <= limit {
            return;
        }
        let kind = match (a.owner, b.owner) {
            (Owner::Link(x, _), Owner::Link(y, _)) if x == y => FaultKind::SelfCollision,
            _ => FaultKind::Collision,
        };
        let (oa, ob) = (a.owner.min(b.owner), a.owner.max(b.owner));
        let f = found.entry((kind, oa, ob)).or_insert_with(|| Fault {
            kind,
            step: Some(self.step.index),
            action: self.step.action.clone(),
            trajectory: Some(self.traj.label.clone()),
            trajectory_index: Some(self.index),
            frame: None,
            a: oa.name(self.plan),
            b: ob.name(self.plan),
            depth_mm: 0.0,
            configs: 0,
            detail: match tol {
                Tolerance::Contact => String::new(),
                Tolerance::Grasp => format!(
                    "a grasp deeper than the {:.0} mm grasp tolerance",
                    limit * 1000.0
                ),
            },
        });
        f.configs += 1;
        if d * 1000.0 > f.depth_mm {
            f.depth_mm = d * 1000.0;
            f.frame = Some(c.label.clone());
        }
    }

    /// How deep two bodies may interpenetrate (`None`: at will). Adjacent links of one agent
    /// at will; the hand that holds an object and that object, and any grasping link and the
    /// step's target object (grasp, release, hand-over; unless another hand of the same agent
    /// holds it) up to the grasp tolerance; everything else up to the contact tolerance.
    fn tolerance(&self, x: Owner, y: Owner, world: &World) -> Option<Tolerance> {
        let plan = self.plan;
        match (x, y) {
            (Owner::Link(p, i), Owner::Link(q, j)) if p == q => {
                (!self.adjacency.allowed(i, j)).then_some(Tolerance::Contact)
            }
            (Owner::Link(b, l), Owner::Object(o) | Owner::Held(o))
            | (Owner::Object(o) | Owner::Held(o), Owner::Link(b, l)) => {
                let hold = world.holds[o].as_ref();
                let in_hand = hold.is_some_and(|h| h.agent == b && h.hand.contains(&l));
                let free = hold.is_none_or(|h| h.agent != b);
                let grasping = plan.agents[b].is_grasping(l);
                let grasp = in_hand || (self.step.target == Some(o) && grasping && free);
                Some(if grasp {
                    Tolerance::Grasp
                } else {
                    Tolerance::Contact
                })
            }
            _ => Some(Tolerance::Contact),
        }
    }
}

/// For each moving shape, the fixed shapes whose boxes meet the box it sweeps.
fn near_fixed(moving: &[Vec<Placed>], fixed: &[Placed]) -> Vec<Vec<usize>> {
    let Some(first) = moving.first() else {
        return Vec::new();
    };
    (0..first.len())
        .map(|m| {
            let swept = moving
                .iter()
                .filter_map(|c| c.get(m).map(|p| p.aabb))
                .reduce(|a, b| a.merged(&b))
                .unwrap_or_else(Aabb::new_invalid);
            (0..fixed.len())
                .filter(|&f| swept.intersects(&fixed[f].aabb))
                .collect()
        })
        .collect()
}
