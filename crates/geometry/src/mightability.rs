//! Mightability maps: per agent, 3D grids of where it can see and reach at each effort level
//! (`../shared/notes/geometry-facts.md` beside the checkout, section 4).
//!
//! The grid covers the scene's `bounds` (or the world's bounds with a margin) in cubic cells
//! (5 cm by default). Each cell stores, per agent, the least effort level at which the agent
//! sees it and reaches it (`NONE` when no level does):
//!
//! * **Visibility**: rays are cast from the eye of every stance of a level
//!   ([`crate::effort::stances`]) through the directions that level allows — level 0 the current
//!   field of view only; from level 1 every direction the head pan/tilt range plus half the field
//!   of view covers, relative to the torso of the stance; level 4 (moving) every direction — and
//!   marched through an occupancy grid (3D DDA) until they reach an occupied cell, which is seen
//!   itself. The occupancy grid holds the objects and the other agents (an agent does not hide
//!   the world from itself here; the exact pixel test does that).
//! * **Reach**: level 0 the cells at the hands ([`crate::perception::hand_at`]); from level 1 the cells within the agent's arm
//!   reach of a shoulder of some stance of that level (level 4: standing at each free base
//!   position, facing 8 directions, upright and leaning).
//!
//! Maps describe the world state they were computed from. They are a fast filter for candidate
//! points (cells on support surfaces that satisfy set operations on the maps); facts and task
//! solutions are confirmed with the exact checks ([`crate::facts`], [`crate::visibility`]).
//! [`cached`] computes them once per world state and keeps them in memory.

use std::collections::{HashMap, HashSet};
use std::sync::{Arc, Mutex, Weak};

use parry3d::bounding_volume::Aabb;
use parry3d::math::{Pose, Rotation, Vector};
use parry3d::query::intersection_test;
use parry3d::shape::Cuboid;
use rayon::prelude::*;

use crate::effort::{JointRange, MAX_EFFORT, Stance, stances};
use crate::perception;
use crate::scene::{AgentId, ObjectId};
use crate::world::{BodyOwner, Precision, World, WorldModel};

/// A cell no effort level reaches.
pub const NONE: u8 = u8::MAX;

/// Most cells a grid may have (16 M: 16 MB per map); larger regions get coarser cells.
pub const MAX_CELLS: usize = 1 << 24;

/// Parameters of the maps.
#[derive(Clone, Debug, PartialEq)]
pub struct MightabilityParams {
    /// Cell size, metres.
    pub cell: f32,
    /// Angular step of the visibility rays at levels 0 and 1 (one eye each), degrees.
    pub ray_step_deg: f32,
    /// Angular step at levels 2 and 3 (a few dozen eyes), degrees.
    pub body_ray_step_deg: f32,
    /// Angular step of the visibility rays at level 4 (many eyes), degrees.
    pub move_ray_step_deg: f32,
    /// Level-4 base positions: every `move_stride`-th position of the effort grid in x and y.
    pub move_stride: usize,
    /// Margin added around the world's bounds when the scene gives none.
    pub margin: f32,
    /// Eyes of one level closer than this (metres) share one fan of rays.
    pub eye_merge: f32,
}

impl Default for MightabilityParams {
    fn default() -> Self {
        MightabilityParams {
            cell: 0.05,
            ray_step_deg: 1.0,
            body_ray_step_deg: 2.0,
            move_ray_step_deg: 2.0,
            move_stride: 3,
            margin: 0.5,
            eye_merge: 0.1,
        }
    }
}

/// A regular grid of cubic cells.
#[derive(Clone, Debug, PartialEq)]
pub struct Grid {
    /// Corner of cell (0, 0, 0).
    pub min: Vector,
    pub cell: f32,
    /// Cells along x, y, z.
    pub dims: [usize; 3],
}

impl Grid {
    /// A grid covering `bounds`.
    pub fn new(bounds: &Aabb, cell: f32) -> Grid {
        let ext = bounds.maxs - bounds.mins;
        let n = |e: f32| ((e / cell).ceil() as usize).max(1);
        Grid {
            min: bounds.mins,
            cell,
            dims: [n(ext.x), n(ext.y), n(ext.z)],
        }
    }

    /// Number of cells.
    pub fn len(&self) -> usize {
        self.dims[0] * self.dims[1] * self.dims[2]
    }

    /// Whether the grid has no cells.
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// Linear index of cell `(i, j, k)`.
    #[inline]
    pub fn index(&self, c: [usize; 3]) -> usize {
        (c[2] * self.dims[1] + c[1]) * self.dims[0] + c[0]
    }

    /// The cell containing `p`, if inside the grid.
    pub fn cell_of(&self, p: Vector) -> Option<[usize; 3]> {
        let l = (p - self.min) / self.cell;
        if l.x < 0.0 || l.y < 0.0 || l.z < 0.0 {
            return None;
        }
        let c = [l.x as usize, l.y as usize, l.z as usize];
        (c[0] < self.dims[0] && c[1] < self.dims[1] && c[2] < self.dims[2]).then_some(c)
    }

    /// Centre of a cell.
    pub fn centre(&self, c: [usize; 3]) -> Vector {
        self.min
            + Vector::new(
                (c[0] as f32 + 0.5) * self.cell,
                (c[1] as f32 + 0.5) * self.cell,
                (c[2] as f32 + 0.5) * self.cell,
            )
    }

    /// Cell coordinates of a linear index.
    pub fn coords(&self, idx: usize) -> [usize; 3] {
        let i = idx % self.dims[0];
        let j = (idx / self.dims[0]) % self.dims[1];
        let k = idx / (self.dims[0] * self.dims[1]);
        [i, j, k]
    }

    /// Range of cells (inclusive) overlapping a box, clamped to the grid; `None` if disjoint.
    fn cell_range(&self, b: &Aabb) -> Option<([usize; 3], [usize; 3])> {
        let mut lo = [0usize; 3];
        let mut hi = [0usize; 3];
        for a in 0..3 {
            let l = ((b.mins[a] - self.min[a]) / self.cell).floor();
            let h = ((b.maxs[a] - self.min[a]) / self.cell).floor();
            if h < 0.0 || l >= self.dims[a] as f32 {
                return None;
            }
            lo[a] = l.max(0.0) as usize;
            hi[a] = (h as usize).min(self.dims[a] - 1);
        }
        Some((lo, hi))
    }
}

/// A set of cells as bits.
#[derive(Clone, Debug, PartialEq)]
pub struct BitGrid(Vec<u64>);

impl BitGrid {
    fn new(n: usize) -> BitGrid {
        BitGrid(vec![0; n.div_ceil(64)])
    }
    #[inline]
    pub fn get(&self, i: usize) -> bool {
        self.0[i >> 6] >> (i & 63) & 1 == 1
    }
    #[inline]
    fn set(&mut self, i: usize) {
        self.0[i >> 6] |= 1 << (i & 63);
    }
    fn or(mut self, other: &BitGrid) -> BitGrid {
        for (a, b) in self.0.iter_mut().zip(&other.0) {
            *a |= *b;
        }
        self
    }
    /// Number of cells in the set.
    pub fn count(&self) -> usize {
        self.0.iter().map(|w| w.count_ones() as usize).sum()
    }
}

/// One agent's maps: the least effort level per cell.
#[derive(Clone, Debug, PartialEq)]
pub struct AgentMaps {
    pub agent: AgentId,
    /// Least level at which the cell is seen ([`NONE`]: never).
    pub vis: Vec<u8>,
    /// Least level at which the cell is reached ([`NONE`]: never).
    pub reach: Vec<u8>,
}

/// The maps of every agent of a world state.
#[derive(Clone, Debug)]
pub struct Mightability {
    pub grid: Grid,
    /// Cells occupied by objects.
    pub occupied: BitGrid,
    pub agents: Vec<AgentMaps>,
}

/// Which directions an eye may look in.
#[derive(Clone, Copy, Debug)]
enum Directions {
    /// The camera frustum of an eye pose (level 0).
    Frustum { rot: Rotation, fov: [f32; 2] },
    /// Yaw and elevation intervals (radians, world frame).
    Range { yaw: [f32; 2], el: [f32; 2] },
}

#[derive(Clone, Copy, Debug)]
struct Eye {
    pos: Vector,
    dirs: Directions,
    step: f32,
}

fn mark_body_cells(
    grid: &Grid,
    bits: &mut BitGrid,
    shape: &dyn parry3d::shape::Shape,
    pose: &Pose,
) {
    let half = 0.5 * grid.cell;
    let cube = Cuboid::new(Vector::splat(half));
    let Some((lo, hi)) = grid.cell_range(&shape.compute_aabb(pose)) else {
        return;
    };
    for k in lo[2]..=hi[2] {
        for j in lo[1]..=hi[1] {
            for i in lo[0]..=hi[0] {
                let c = [i, j, k];
                let cp = Pose::from_translation(grid.centre(c));
                if intersection_test(&cp, &cube, pose, shape)
                    .map(|r| r.intersecting)
                    .unwrap_or(true)
                {
                    bits.set(grid.index(c));
                }
            }
        }
    }
}

/// March one ray through the grid from `o` (inside the grid) along `d` (unit), marking every
/// cell passed and the first occupied one.
fn march(grid: &Grid, occ: &BitGrid, o: Vector, d: Vector, seen: &mut BitGrid) {
    let Some(mut c) = grid.cell_of(o) else { return };
    let mut step = [0i64; 3];
    let mut t_max = [f32::INFINITY; 3];
    let mut t_delta = [f32::INFINITY; 3];
    for a in 0..3 {
        if d[a] > 1e-9 {
            step[a] = 1;
            let edge = grid.min[a] + (c[a] as f32 + 1.0) * grid.cell;
            t_max[a] = (edge - o[a]) / d[a];
            t_delta[a] = grid.cell / d[a];
        } else if d[a] < -1e-9 {
            step[a] = -1;
            let edge = grid.min[a] + c[a] as f32 * grid.cell;
            t_max[a] = (edge - o[a]) / d[a];
            t_delta[a] = -grid.cell / d[a];
        }
    }
    loop {
        let idx = grid.index(c);
        seen.set(idx);
        if occ.get(idx) {
            return;
        }
        let a = if t_max[0] < t_max[1] {
            if t_max[0] < t_max[2] { 0 } else { 2 }
        } else if t_max[1] < t_max[2] {
            1
        } else {
            2
        };
        let n = c[a] as i64 + step[a];
        if step[a] == 0 || n < 0 || n >= grid.dims[a] as i64 {
            return;
        }
        c[a] = n as usize;
        t_max[a] += t_delta[a];
    }
}

fn cast_eye(grid: &Grid, occ: &BitGrid, eye: &Eye, seen: &mut BitGrid) {
    let step = eye.step;
    match eye.dirs {
        Directions::Frustum { rot, fov } => {
            let (tx, ty) = ((0.5 * fov[0]).tan(), (0.5 * fov[1]).tan());
            let nx = (fov[0] / step).ceil() as usize + 1;
            let ny = (fov[1] / step).ceil() as usize + 1;
            for j in 0..ny {
                let b = -ty + 2.0 * ty * j as f32 / (ny - 1) as f32;
                for i in 0..nx {
                    let a = -tx + 2.0 * tx * i as f32 / (nx - 1) as f32;
                    let d = (rot * Vector::new(1.0, a, b)).normalize();
                    march(grid, occ, eye.pos, d, seen);
                }
            }
        }
        Directions::Range { yaw, el } => {
            let ne = ((el[1] - el[0]) / step).ceil().max(1.0) as usize;
            for j in 0..=ne {
                let e = el[0] + (el[1] - el[0]) * j as f32 / ne as f32;
                let span = yaw[1] - yaw[0];
                let ny = ((span * e.cos()) / step).ceil().max(1.0) as usize;
                for i in 0..=ny {
                    let y = yaw[0] + span * i as f32 / ny as f32;
                    let d = Vector::new(e.cos() * y.cos(), e.cos() * y.sin(), e.sin());
                    march(grid, occ, eye.pos, d, seen);
                }
            }
        }
    }
}

fn mark_spheres(grid: &Grid, points: &[Vector], r: f32) -> BitGrid {
    points
        .par_chunks(16)
        .fold(
            || BitGrid::new(grid.len()),
            |mut bits, chunk| {
                for &p in chunk {
                    let b = Aabb::new(p - Vector::splat(r), p + Vector::splat(r));
                    let Some((lo, hi)) = grid.cell_range(&b) else {
                        continue;
                    };
                    for k in lo[2]..=hi[2] {
                        for j in lo[1]..=hi[1] {
                            for i in lo[0]..=hi[0] {
                                let c = [i, j, k];
                                if (grid.centre(c) - p).length_squared() <= r * r {
                                    bits.set(grid.index(c));
                                }
                            }
                        }
                    }
                }
                bits
            },
        )
        .reduce(|| BitGrid::new(grid.len()), |a, b| a.or(&b))
}

fn dedup_points(points: Vec<Vector>, q: f32) -> Vec<Vector> {
    let mut seen = HashSet::new();
    points
        .into_iter()
        .filter(|p| {
            seen.insert((
                (p.x / q).round() as i64,
                (p.y / q).round() as i64,
                (p.z / q).round() as i64,
            ))
        })
        .collect()
}

/// The smallest direction set holding both (a frustum widens to its eye's whole sphere).
fn union(a: Directions, b: Directions) -> Directions {
    use std::f32::consts::{PI, TAU};
    match (a, b) {
        (Directions::Range { yaw: ya, el: ea }, Directions::Range { yaw: yb, el: eb }) => {
            // Shift b's yaw interval by whole turns to lie nearest a's.
            let ca = 0.5 * (ya[0] + ya[1]);
            let cb = 0.5 * (yb[0] + yb[1]);
            let shift = ((ca - cb) / TAU).round() * TAU;
            let mut yaw = [ya[0].min(yb[0] + shift), ya[1].max(yb[1] + shift)];
            if yaw[1] - yaw[0] >= TAU {
                yaw = [-PI, PI];
            }
            Directions::Range {
                yaw,
                el: [ea[0].min(eb[0]), ea[1].max(eb[1])],
            }
        }
        _ => Directions::Range {
            yaw: [-PI, PI],
            el: [-0.5 * PI, 0.5 * PI],
        },
    }
}

/// Yaw and elevation of a frame's x axis.
fn yaw_pitch(rot: Rotation) -> (f32, f32) {
    let x = rot * Vector::X;
    (x.y.atan2(x.x), x.z.clamp(-1.0, 1.0).asin())
}

/// Directions the head allows from a stance whose head-pan parent frame is `torso`.
fn head_range(
    torso: Rotation,
    pan: Option<JointRange>,
    tilt: Option<JointRange>,
    fov: [f32; 2],
    full_turn: bool,
) -> Directions {
    let (yc, pc) = yaw_pitch(torso);
    let (plo, phi) = pan.map_or((0.0, 0.0), |r| (r.lower, r.upper));
    let (tlo, thi) = tilt.map_or((0.0, 0.0), |r| (r.lower, r.upper));
    let half = std::f32::consts::FRAC_PI_2;
    let el = [
        (pc - thi - 0.5 * fov[1]).max(-half),
        (pc - tlo + 0.5 * fov[1]).min(half),
    ];
    let mut yaw = [yc + plo - 0.5 * fov[0], yc + phi + 0.5 * fov[0]];
    if full_turn || yaw[1] - yaw[0] >= 2.0 * std::f32::consts::PI {
        yaw = [-std::f32::consts::PI, std::f32::consts::PI];
    }
    Directions::Range { yaw, el }
}

impl Mightability {
    /// Computes the maps of every agent of `world` (in parallel).
    pub fn compute(world: &World, params: &MightabilityParams) -> Mightability {
        let bounds = world.scene().bounds.unwrap_or_else(|| {
            let b = world.bounds();
            let m = Vector::splat(params.margin);
            Aabb::new(
                Vector::new(b.mins.x - m.x, b.mins.y - m.y, -0.05),
                b.maxs + m,
            )
        });
        // Keep the grid within MAX_CELLS: a huge room gets coarser cells rather than
        // exhausting memory.
        let ext = bounds.maxs - bounds.mins;
        let volume = (ext.x * ext.y * ext.z).max(0.0);
        let cell = params.cell.max((volume / MAX_CELLS as f32).cbrt());
        let grid = Grid::new(&bounds, cell);
        let bodies = world.bodies();
        let owners: Vec<BodyOwner> = bodies.iter().map(|b| b.owner).collect();
        // Occupancy per owner group: objects, then each agent.
        let group = |o: BodyOwner| match o {
            BodyOwner::Object(_) => 0usize,
            BodyOwner::Agent(a, _) => 1 + a.0,
        };
        let ngroups = 1 + world.agent_count();
        let groups: Vec<BitGrid> = (0..ngroups)
            .into_par_iter()
            .map(|g| {
                let mut bits = BitGrid::new(grid.len());
                for (b, o) in bodies.iter().zip(&owners) {
                    if group(*o) == g {
                        mark_body_cells(&grid, &mut bits, b.shape.as_ref(), &b.pose);
                    }
                }
                bits
            })
            .collect();
        let occupied = groups[0].clone();
        let agents = world
            .agent_ids()
            .collect::<Vec<_>>()
            .into_par_iter()
            .map(|a| {
                let mut occ = occupied.clone();
                for (g, bits) in groups.iter().enumerate().skip(1) {
                    if g != 1 + a.0 {
                        occ = occ.or(bits);
                    }
                }
                agent_maps(world, a, &grid, &occ, params)
            })
            .collect();
        Mightability {
            grid,
            occupied,
            agents,
        }
    }

    fn maps(&self, agent: AgentId) -> &AgentMaps {
        &self.agents[agent.0]
    }

    /// Least level at which `agent` sees the cell containing `p` (`None`: never, or outside).
    pub fn vis_level(&self, agent: AgentId, p: Vector) -> Option<u8> {
        let c = self.grid.cell_of(p)?;
        let l = self.maps(agent).vis[self.grid.index(c)];
        (l != NONE).then_some(l)
    }

    /// Least level at which `agent` reaches the cell containing `p`.
    pub fn reach_level(&self, agent: AgentId, p: Vector) -> Option<u8> {
        let c = self.grid.cell_of(p)?;
        let l = self.maps(agent).reach[self.grid.index(c)];
        (l != NONE).then_some(l)
    }

    /// Least level at which `agent` sees (`vis = true`) or reaches some cell the object
    /// occupies (its bounding box, in the world state the maps were computed from).
    pub fn object_level(
        &self,
        world: &World,
        agent: AgentId,
        object: ObjectId,
        vis: bool,
    ) -> Option<u8> {
        let m = self.maps(agent);
        let v = if vis { &m.vis } else { &m.reach };
        let (lo, hi) = self.grid.cell_range(&world.object_aabb(object))?;
        let mut best = NONE;
        for k in lo[2]..=hi[2] {
            for j in lo[1]..=hi[1] {
                for i in lo[0]..=hi[0] {
                    best = best.min(v[self.grid.index([i, j, k])]);
                }
            }
        }
        (best != NONE).then_some(best)
    }

    /// Number of cells `agent` sees (`vis = true`) or reaches at level `level` or below.
    pub fn count(&self, agent: AgentId, level: u8, vis: bool) -> usize {
        let m = self.maps(agent);
        let v = if vis { &m.vis } else { &m.reach };
        v.iter().filter(|&&l| l <= level).count()
    }

    /// Candidate points on support surfaces: for every support surface of every object (except
    /// `exclude`), the centres of the grid's columns over it, one cell above the surface, as
    /// `(support object, point on the surface)`. Filter them with [`Self::vis_level`] and
    /// [`Self::reach_level`]; `max` caps the number returned (the original: 15,000).
    pub fn support_points(
        &self,
        world: &World,
        exclude: Option<ObjectId>,
        max: usize,
    ) -> Vec<(ObjectId, Vector)> {
        let mut out = Vec::new();
        let step = self.grid.cell;
        for id in world.object_ids() {
            if Some(id) == exclude || world.attachment(id).is_some() {
                continue;
            }
            let pose = world.object_pose(id);
            for s in &world.object(id).surfaces {
                let nx = ((2.0 * s.half_extents[0]) / step).floor().max(1.0) as usize;
                let ny = ((2.0 * s.half_extents[1]) / step).floor().max(1.0) as usize;
                for i in 0..nx {
                    for j in 0..ny {
                        let lx = s.centre.x - s.half_extents[0]
                            + (i as f32 + 0.5) * (2.0 * s.half_extents[0] / nx as f32);
                        let ly = s.centre.y - s.half_extents[1]
                            + (j as f32 + 0.5) * (2.0 * s.half_extents[1] / ny as f32);
                        out.push((id, pose.transform_point(Vector::new(lx, ly, s.centre.z))));
                        if out.len() >= max {
                            return out;
                        }
                    }
                }
            }
        }
        out
    }
}

fn agent_maps(
    world: &World,
    agent: AgentId,
    grid: &Grid,
    occ: &BitGrid,
    params: &MightabilityParams,
) -> AgentMaps {
    let mut eyes: Vec<Vec<Eye>> = vec![Vec::new(); MAX_EFFORT as usize + 1];
    eyes[0].push(current_eye(world, agent, params));
    let mut origins: Vec<Vec<Vector>> = vec![Vec::new(); MAX_EFFORT as usize + 1];
    for level in 1..=MAX_EFFORT {
        let list = level_stances(world, agent, level, params);
        eyes[level as usize] = stance_eyes(world, agent, level, &list, params);
        origins[level as usize] = list
            .iter()
            .flat_map(|s| turned_reach_origins(world, agent, s))
            .collect();
    }
    AgentMaps {
        agent,
        vis: vis_levels(grid, occ, &eyes),
        reach: reach_levels(world, agent, grid, origins),
    }
}

/// The eye as it is now, seeing its field of view (level 0).
fn current_eye(world: &World, agent: AgentId, params: &MightabilityParams) -> Eye {
    let e0 = world.eye_pose(agent);
    Eye {
        pos: e0.translation,
        dirs: Directions::Frustum {
            rot: e0.rotation,
            fov: world.agent(agent).fov,
        },
        step: params.ray_step_deg.to_radians(),
    }
}

/// The stances of `level`; at the highest level the base positions thinned to every
/// `move_stride`-th grid point.
fn level_stances(
    world: &World,
    agent: AgentId,
    level: u8,
    params: &MightabilityParams,
) -> Vec<Stance> {
    let list = stances(world, agent, level, None);
    if level != MAX_EFFORT {
        return list;
    }
    let here = world.agent_state(agent).base.translation;
    let s = world.agent(agent).effort.move_step * params.move_stride as f32;
    list.into_iter()
        .filter(|x| {
            let d = (x.base.translation - here) / s;
            (d.x - d.x.round()).abs() < 1e-3 && (d.y - d.y.round()).abs() < 1e-3
        })
        .collect()
}

/// One eye per stance of `level`, turning the head through its range; eyes within
/// `eye_merge` of each other share one ray fan over the union of their ranges.
fn stance_eyes(
    world: &World,
    agent: AgentId,
    level: u8,
    list: &[Stance],
    params: &MightabilityParams,
) -> Vec<Eye> {
    let info = world.agent(agent);
    let (model, eff) = (&info.model, &info.effort);
    // The frame the head turns in: the parent link of the head-pan joint (else the base).
    let head_parent = eff
        .head_pan
        .map(|r| model.joints()[model.dof_joint(r.dof)].parent);
    let step = match level {
        1 => params.ray_step_deg,
        MAX_EFFORT => params.move_ray_step_deg,
        _ => params.body_ray_step_deg,
    }
    .to_radians();
    let merge = params.eye_merge;
    let mut keys: HashMap<(i64, i64, i64), usize> = HashMap::new();
    let mut out: Vec<Eye> = Vec::new();
    for s in list {
        let eye = model.link_pose_by_id(s.base, &s.q, info.eye_link);
        let torso_rot = match head_parent {
            Some(l) => model.link_pose_by_id(s.base, &s.q, l).rotation,
            None => s.base.rotation,
        };
        let full = level == MAX_EFFORT;
        let dirs = head_range(torso_rot, eff.head_pan, eff.head_tilt, info.fov, full);
        let key = (
            (eye.translation.x / merge).round() as i64,
            (eye.translation.y / merge).round() as i64,
            (eye.translation.z / merge).round() as i64,
        );
        match keys.get(&key) {
            Some(&k) => out[k].dirs = union(out[k].dirs, dirs),
            None => {
                keys.insert(key, out.len());
                out.push(Eye {
                    pos: eye.translation,
                    dirs,
                    step,
                });
            }
        }
    }
    out
}

/// The points a stance's arms reach from ([`perception::reach_origins`]); a standing stance
/// (the highest level) also turned 8 ways, since the grid serves every direction at once.
fn turned_reach_origins(world: &World, agent: AgentId, s: &Stance) -> Vec<Vector> {
    let turns = if s.level == MAX_EFFORT { 8 } else { 1 };
    (0..turns)
        .flat_map(|t| {
            let yaw = t as f32 * std::f32::consts::TAU / turns as f32;
            let turned = Stance {
                base: s.base * Pose::from_rotation(Rotation::from_rotation_z(yaw)),
                ..s.clone()
            };
            perception::reach_origins(world, agent, &turned)
        })
        .collect()
}

/// Least level at which each cell is seen: all eyes of all levels in one parallel pass, one
/// set of seen cells per level (levels are cumulative).
fn vis_levels(grid: &Grid, occ: &BitGrid, eyes: &[Vec<Eye>]) -> Vec<u8> {
    let levels = eyes.len();
    let tagged: Vec<(usize, &Eye)> = eyes
        .iter()
        .enumerate()
        .flat_map(|(l, list)| list.iter().map(move |e| (l, e)))
        .collect();
    let seen = tagged
        .par_iter()
        .fold(
            || vec![BitGrid::new(grid.len()); levels],
            |mut bits, (l, eye)| {
                cast_eye(grid, occ, eye, &mut bits[*l]);
                bits
            },
        )
        .reduce(
            || vec![BitGrid::new(grid.len()); levels],
            |a, b| a.into_iter().zip(&b).map(|(x, y)| x.or(y)).collect(),
        );
    least_levels(grid.len(), seen.iter())
}

/// Least level at which each cell is reached: level 0 the cells a hand is at
/// ([`perception::hand_at`] with the cell's half-diagonal as extent); from level 1 the cells
/// within the agent's arm reach of the level's reach origins.
fn reach_levels(world: &World, agent: AgentId, grid: &Grid, origins: Vec<Vec<Vector>>) -> Vec<u8> {
    let half_diagonal = 0.5 * grid.cell * 3f32.sqrt();
    let hands = perception::hand_positions(world, agent);
    let mut bits = vec![mark_spheres(
        grid,
        &hands,
        perception::HAND_TOLERANCE + half_diagonal,
    )];
    let reach = world.agent(agent).reach;
    for pts in origins.into_iter().skip(1) {
        let pts = dedup_points(pts, 0.5 * grid.cell);
        bits.push(mark_spheres(grid, &pts, reach));
    }
    least_levels(grid.len(), bits.iter())
}

/// Per cell, the index of the first bit grid that holds it ([`NONE`]: none does).
fn least_levels<'a>(n: usize, per_level: impl Iterator<Item = &'a BitGrid>) -> Vec<u8> {
    let mut out = vec![NONE; n];
    for (level, bits) in per_level.enumerate() {
        for (i, v) in out.iter_mut().enumerate() {
            if *v == NONE && bits.get(i) {
                *v = level as u8;
            }
        }
    }
    out
}

type CacheEntry = (Weak<WorldModel>, u64, MightabilityParams, Arc<Mightability>);
static CACHE: Mutex<Vec<CacheEntry>> = Mutex::new(Vec::new());

/// The maps of this world state, computed on first use and kept in memory (per scene, per state,
/// per parameters; entries of dropped scenes are discarded).
pub fn cached(world: &World, params: &MightabilityParams) -> Arc<Mightability> {
    let fp = world.fingerprint(Precision::Exact);
    {
        let mut cache = CACHE.lock().unwrap_or_else(|e| e.into_inner());
        cache.retain(|(w, ..)| w.strong_count() > 0);
        for (w, f, p, m) in cache.iter() {
            if *f == fp
                && p == params
                && w.upgrade().is_some_and(|w| Arc::ptr_eq(&w, world.model()))
            {
                return m.clone();
            }
        }
    }
    let m = Arc::new(Mightability::compute(world, params));
    let mut cache = CACHE.lock().unwrap_or_else(|e| e.into_inner());
    cache.push((Arc::downgrade(world.model()), fp, params.clone(), m.clone()));
    m
}
