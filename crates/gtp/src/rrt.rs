//! RRT-Connect in an arm's joint space, with edges checked at a fixed resolution and shortcut
//! smoothing of the path found.
//!
//! The planner knows nothing of geometry: it takes the joint limits (continuous joints wrap
//! around) and a validity check, a closure over one configuration. It is deterministic for a
//! seed.

use std::f32::consts::{PI, TAU};
use std::time::{Duration, Instant};

use serde::{Deserialize, Serialize};

use crate::nearest_kd_tree::KdTree;

/// The joint space of an arm: one entry per joint.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct JointSpace {
    /// Lower limits (ignored for continuous joints).
    pub lower: Vec<f32>,
    /// Upper limits (ignored for continuous joints).
    pub upper: Vec<f32>,
    /// Whether each joint turns without limits; distances and interpolation wrap around.
    pub continuous: Vec<bool>,
}

impl JointSpace {
    /// A joint space from per-joint `(lower, upper, continuous)`.
    pub fn new(joints: &[(f32, f32, bool)]) -> JointSpace {
        JointSpace {
            lower: joints.iter().map(|j| j.0).collect(),
            upper: joints.iter().map(|j| j.1).collect(),
            continuous: joints.iter().map(|j| j.2).collect(),
        }
    }

    /// Number of joints.
    pub fn dim(&self) -> usize {
        self.lower.len()
    }

    /// The per-joint difference `b - a`, the short way round for continuous joints.
    pub fn delta(&self, a: &[f32], b: &[f32], out: &mut [f32]) {
        for i in 0..a.len() {
            let mut d = b[i] - a[i];
            if self.continuous[i] {
                d = wrap(d);
            }
            out[i] = d;
        }
    }

    /// Euclidean distance in joint space (the short way round for continuous joints).
    pub fn distance(&self, a: &[f32], b: &[f32]) -> f32 {
        self.distance_squared(a, b).sqrt()
    }

    /// The square of [`JointSpace::distance`] (for comparisons: no root).
    pub fn distance_squared(&self, a: &[f32], b: &[f32]) -> f32 {
        let mut s = 0.0;
        for i in 0..a.len() {
            let mut d = b[i] - a[i];
            if self.continuous[i] {
                d = wrap(d);
            }
            s += d * d;
        }
        s
    }

    /// The largest per-joint difference (the short way round for continuous joints).
    pub fn max_delta(&self, a: &[f32], b: &[f32]) -> f32 {
        let mut m: f32 = 0.0;
        for i in 0..a.len() {
            let mut d = b[i] - a[i];
            if self.continuous[i] {
                d = wrap(d);
            }
            m = m.max(d.abs());
        }
        m
    }

    /// `a + t (b - a)` along the short way, continuous joints normalised to `[-pi, pi)`.
    pub fn interpolate(&self, a: &[f32], b: &[f32], t: f32, out: &mut [f32]) {
        for i in 0..a.len() {
            if self.continuous[i] {
                out[i] = wrap(a[i] + t * wrap(b[i] - a[i]));
            } else {
                out[i] = a[i] + t * (b[i] - a[i]);
            }
        }
    }

    /// Whether `q` is within the limits (continuous joints always are).
    pub fn within_limits(&self, q: &[f32]) -> bool {
        q.len() == self.dim()
            && (0..q.len()).all(|i| {
                self.continuous[i] || (q[i] >= self.lower[i] - 1e-5 && q[i] <= self.upper[i] + 1e-5)
            })
    }

    /// A uniformly random configuration within the limits.
    pub fn sample(&self, rng: &mut fastrand::Rng, out: &mut [f32]) {
        for (i, q) in out.iter_mut().enumerate() {
            *q = if self.continuous[i] {
                rng.f32() * TAU - PI
            } else {
                self.lower[i] + rng.f32() * (self.upper[i] - self.lower[i])
            };
        }
    }
}

/// An angle difference folded into `[-pi, pi)`.
#[inline]
pub(crate) fn wrap(a: f32) -> f32 {
    let s = a + PI;
    // Already in range (the common case): `rem_euclid` would return `s` itself, at the cost
    // of a floating-point remainder (the nearest-neighbour search calls this per node).
    if (0.0..TAU).contains(&s) {
        return s - PI;
    }
    // One turn off (a difference of two angles in range): no remainder needed either.
    if (-TAU..0.0).contains(&s) {
        return s + TAU - PI;
    }
    if (TAU..2.0 * TAU).contains(&s) {
        return s - TAU - PI;
    }
    s.rem_euclid(TAU) - PI
}

/// Below this many nodes a tree's nearest node is found by a scan: in seven joint dimensions
/// a scan of a small tree is faster than the k-d tree's descent, a large tree's the reverse
/// (`cargo bench -p gtp --bench rrt -- unconnectable` compares them).
const SCAN_BELOW: usize = 1024;

/// As [`JointSpace::distance_squared`] from `q` to a tree node `c`, with fewer branches: on a
/// continuous joint, ends within [-pi, pi) (all but a root given out of range) differ by less
/// than a turn, and one turn, added or taken, folds the difference.
fn distance_squared_to_node(space: &JointSpace, q: &[f32], c: &[f32]) -> f32 {
    let mut d2 = 0.0;
    for k in 0..c.len() {
        let mut d = q[k] - c[k];
        if space.continuous[k] {
            d -= TAU * ((d >= PI) as i32 - (d < -PI) as i32) as f32;
            if !(-PI..PI).contains(&d) {
                d = wrap(d);
            }
        }
        d2 += d * d;
    }
    d2
}

/// Limits and settings of one RRT-Connect query.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct RrtParams {
    /// Largest per-joint step (radians or metres) between two configurations checked on an edge.
    pub resolution: f32,
    /// Longest extension of a tree towards a sample (joint-space distance).
    pub max_step: f32,
    /// The query fails after this many tree nodes (both trees together).
    pub max_nodes: usize,
    /// The query fails after this many configurations checked (the search's main cost): with
    /// `max_nodes`, the budget that normally ends a query, the same on any machine however
    /// loaded, so that a seed gives the same answer.
    #[serde(default = "default_max_checks")]
    pub max_checks: usize,
    /// The query fails after this long: a safety net for robots whose checks are costly (a
    /// mesh model), above what `max_checks` takes with the bundled models.
    pub time_limit: Duration,
    /// The query fails at this instant too (the caller's deadline; not serialised).
    #[serde(skip)]
    pub deadline: Option<Instant>,
    /// Shortcut attempts on the path found.
    pub shortcut_iterations: usize,
    /// The final path is checked at `resolution / certify_factor`, on the configurations that
    /// [`JointPath::densify`] gives at that resolution, so that the path returned stays valid
    /// when re-checked that much finer (1: no certification); [`plan_certified`] with a
    /// certifier checks each edge by it instead.
    pub certify_factor: u32,
}

/// 100,000 checks: about 0.3 s with the bundled PR2 model in a cluttered room, as many as
/// 5,000 nodes of an arm's trees take there.
fn default_max_checks() -> usize {
    100_000
}

impl Default for RrtParams {
    fn default() -> Self {
        RrtParams {
            resolution: 0.1,
            max_step: 1.0,
            max_nodes: 5000,
            max_checks: default_max_checks(),
            time_limit: Duration::from_secs(1),
            deadline: None,
            shortcut_iterations: 10,
            certify_factor: 16,
        }
    }
}

/// Why a query found no path.
#[derive(Clone, Debug, PartialEq, thiserror::Error, Serialize, Deserialize)]
pub enum RrtError {
    /// The start configuration is in collision or out of limits.
    #[error("the start configuration is invalid (in collision or out of limits)")]
    InvalidStart,
    /// The goal configuration is in collision or out of limits.
    #[error("the goal configuration is invalid (in collision or out of limits)")]
    InvalidGoal,
    /// The trees reached the node limit without connecting.
    #[error("no path within {0} nodes")]
    NodeLimit(usize),
    /// The trees checked `max_checks` configurations without connecting.
    #[error("no path within {0} collision checks")]
    CheckLimit(usize),
    /// The time limit passed without the trees connecting.
    #[error("no path within {0:?}")]
    TimeLimit(Duration),
    /// Every path found cut a corner through an obstacle between the checks at the search
    /// resolution (found when re-checking it finer).
    #[error("the path found fails when re-checked at {0} finer resolution")]
    Certification(u32),
    /// Start and goal have a different number of joints than the space.
    #[error("configuration has {got} joints, the space has {expected}")]
    Dimension { expected: usize, got: usize },
}

impl RrtError {
    /// Whether the query spent its budget (nodes, checks or time) without connecting.
    pub fn is_budget(&self) -> bool {
        matches!(
            self,
            RrtError::NodeLimit(_) | RrtError::CheckLimit(_) | RrtError::TimeLimit(_)
        )
    }
}

/// What one query did.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct RrtStats {
    /// Tree nodes created (both trees).
    pub nodes: usize,
    /// Configurations checked for validity.
    pub checks: usize,
    /// Waypoints of the path before smoothing.
    pub raw_waypoints: usize,
}

/// A path found by [`plan`]: waypoints from start to goal; consecutive waypoints are joined by
/// straight joint-space edges that were checked at the query's resolution.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct JointPath {
    /// Waypoints, start first, goal last.
    pub waypoints: Vec<Vec<f32>>,
}

impl JointPath {
    /// Joint-space length of the path.
    pub fn length(&self, space: &JointSpace) -> f32 {
        self.waypoints
            .windows(2)
            .map(|w| space.distance(&w[0], &w[1]))
            .sum()
    }

    /// The same path with each continuous joint's values unwrapped (consecutive waypoints differ
    /// by at most half a turn), so that plain linear interpolation between waypoints, as an
    /// exporter or a controller does it, follows the short way the planner checked.
    pub fn unwrapped(&self, space: &JointSpace) -> JointPath {
        let mut waypoints: Vec<Vec<f32>> = Vec::with_capacity(self.waypoints.len());
        for w in &self.waypoints {
            let mut q = w.clone();
            if let Some(prev) = waypoints.last() {
                for i in 0..q.len().min(space.dim()) {
                    if space.continuous[i] {
                        q[i] = prev[i] + wrap(w[i] - prev[i]);
                    }
                }
            }
            waypoints.push(q);
        }
        JointPath { waypoints }
    }

    /// The path's configurations with at most `resolution` per joint between consecutive ones.
    pub fn densify(&self, space: &JointSpace, resolution: f32) -> Vec<Vec<f32>> {
        let mut out = Vec::new();
        if let Some(first) = self.waypoints.first() {
            out.push(first.clone());
        }
        let mut q = vec![0.0; space.dim()];
        for w in self.waypoints.windows(2) {
            let steps = (space.max_delta(&w[0], &w[1]) / resolution).ceil().max(1.0) as usize;
            for s in 1..=steps {
                space.interpolate(&w[0], &w[1], s as f32 / steps as f32, &mut q);
                out.push(q.clone());
            }
        }
        out
    }
}

/// Whether the straight edge `a -> b` is valid, checked every `resolution` per joint (the
/// end `b` included, `a` assumed checked). Counts the checks in `checks`.
pub fn edge_valid(
    space: &JointSpace,
    a: &[f32],
    b: &[f32],
    resolution: f32,
    valid: &mut impl FnMut(&[f32]) -> bool,
    checks: &mut usize,
) -> bool {
    let steps = (space.max_delta(a, b) / resolution).ceil().max(1.0) as usize;
    check_steps(space, a, b, steps, 0, valid, checks)
}

/// Whether the edge `a -> b`, already found valid by [`edge_valid`] at `resolution`, stays
/// valid at `resolution / factor`: the configurations [`JointPath::densify`] gives at that
/// resolution (so that a re-check of the path at it sees only checked configurations), less
/// those the coarse check already covered.
pub fn edge_refine(
    space: &JointSpace,
    a: &[f32],
    b: &[f32],
    resolution: f32,
    factor: u32,
    valid: &mut impl FnMut(&[f32]) -> bool,
    checks: &mut usize,
) -> bool {
    let delta = space.max_delta(a, b);
    let coarse = (delta / resolution).ceil().max(1.0) as usize;
    let fine = (delta / (resolution / factor.max(1) as f32))
        .ceil()
        .max(1.0) as usize;
    check_steps(space, a, b, fine, coarse, valid, checks)
}

/// Checks the configurations `k / steps` of the edge `a -> b`, `k` in `1..=steps`, except
/// those that are also `j / done` (checked already) when `done > 0`.
fn check_steps(
    space: &JointSpace,
    a: &[f32],
    b: &[f32],
    steps: usize,
    done: usize,
    valid: &mut impl FnMut(&[f32]) -> bool,
    checks: &mut usize,
) -> bool {
    let mut q = vec![0.0; space.dim()];
    // Check the far end first, then bisect: collisions are found sooner than by a sweep.
    let mut order: Vec<usize> = Vec::with_capacity(steps);
    order.push(steps);
    let mut stride = steps.next_power_of_two();
    while stride > 1 {
        let half = stride / 2;
        let mut k = half;
        while k < steps {
            if (k / half) % 2 == 1 {
                order.push(k);
            }
            k += half;
        }
        stride = half;
    }
    for k in order {
        if done > 0 && (k * done) % steps == 0 {
            continue;
        }
        space.interpolate(a, b, k as f32 / steps as f32, &mut q);
        *checks += 1;
        if !valid(&q) {
            return false;
        }
    }
    true
}

/// Node storage of one tree: flat configurations and parent indices, and the k-d tree that
/// finds a node's nearest.
struct Tree {
    dim: usize,
    configs: Vec<f32>,
    parents: Vec<usize>,
    index: KdTree,
}

impl Tree {
    fn new(space: &JointSpace, root: &[f32]) -> Tree {
        let mut index = KdTree::new(&space.continuous);
        index.insert(root);
        Tree {
            dim: root.len(),
            configs: root.to_vec(),
            parents: vec![usize::MAX],
            index,
        }
    }
    fn len(&self) -> usize {
        self.parents.len()
    }
    fn get(&self, i: usize) -> &[f32] {
        &self.configs[i * self.dim..(i + 1) * self.dim]
    }
    fn push(&mut self, q: &[f32], parent: usize) -> usize {
        self.configs.extend_from_slice(q);
        self.parents.push(parent);
        self.index.insert(q);
        self.len() - 1
    }
    /// The first node of least distance to `q`.
    fn nearest(&self, space: &JointSpace, q: &[f32]) -> usize {
        let d2 = |i: usize| distance_squared_to_node(space, q, self.get(i));
        if self.len() < SCAN_BELOW {
            // The first index of least distance, as the k-d tree answers.
            let mut best = (f32::INFINITY, 0);
            for i in 0..self.len() {
                let d = d2(i);
                if d < best.0 {
                    best = (d, i);
                }
            }
            return best.1;
        }
        self.index.nearest(q, d2).unwrap_or(0)
    }
    /// Root-to-node configurations.
    fn branch(&self, mut i: usize) -> Vec<Vec<f32>> {
        let mut out = Vec::new();
        while i != usize::MAX {
            out.push(self.get(i).to_vec());
            i = self.parents[i];
        }
        out.reverse();
        out
    }
}

enum Extend {
    Trapped,
    Advanced(usize),
    Reached(usize),
}

/// One step of `tree` from node `near`, the tree's nearest to `target`, towards `target`.
fn extend(
    tree: &mut Tree,
    near: usize,
    space: &JointSpace,
    target: &[f32],
    params: &RrtParams,
    valid: &mut impl FnMut(&[f32]) -> bool,
    stats: &mut RrtStats,
) -> Extend {
    let from = tree.get(near).to_vec();
    let d = space.distance(&from, target);
    let (to, reached) = if d <= params.max_step {
        (target.to_vec(), true)
    } else {
        let mut q = vec![0.0; space.dim()];
        space.interpolate(&from, target, params.max_step / d, &mut q);
        (q, false)
    };
    if !edge_valid(
        space,
        &from,
        &to,
        params.resolution,
        valid,
        &mut stats.checks,
    ) {
        return Extend::Trapped;
    }
    let i = tree.push(&to, near);
    stats.nodes += 1;
    if reached {
        Extend::Reached(i)
    } else {
        Extend::Advanced(i)
    }
}

fn connect(
    tree: &mut Tree,
    space: &JointSpace,
    target: &[f32],
    params: &RrtParams,
    valid: &mut impl FnMut(&[f32]) -> bool,
    stats: &mut RrtStats,
) -> Extend {
    let mut near = tree.nearest(space, target);
    loop {
        // A node that advanced towards the target is the tree's nearest to it (nearer than
        // the node it grew from, the nearest before): no search needed for the next step.
        match extend(tree, near, space, target, params, valid, stats) {
            Extend::Advanced(i) => near = i,
            other => return other,
        }
    }
}

/// Plans a path from `start` to `goal` with RRT-Connect, then smooths it by shortcuts.
///
/// `valid` says whether one configuration is free (collision checks, extra constraints). The
/// direct edge is tried first. Both ends are checked. Deterministic for the state of `rng`.
/// The path's edges are certified by re-checking each at `resolution / certify_factor`; a tree
/// edge that fails the certification (it cut a thin obstacle between its coarse checks) is
/// searched for again between its ends, and where that fails the whole path with new trees,
/// up to [`CERTIFY_ATTEMPTS`] times.
pub fn plan(
    space: &JointSpace,
    start: &[f32],
    goal: &[f32],
    valid: impl FnMut(&[f32]) -> bool,
    params: &RrtParams,
    rng: &mut fastrand::Rng,
) -> Result<(JointPath, RrtStats), (RrtError, RrtStats)> {
    plan_certified(space, start, goal, valid, None, params, rng)
}

/// Certifies a straight edge `a -> b` of a path found (the arm values at its ends), counting
/// what it checked: a continuous alternative to re-checking the edge at a finer resolution.
pub type EdgeCertifier<'a> = &'a mut dyn FnMut(&[f32], &[f32], &mut usize) -> bool;

/// [`plan`], with the path's edges certified by `certify` where given (instead of being
/// re-checked at `resolution / certify_factor`; `certify_factor <= 1` still turns
/// certification off).
pub fn plan_certified(
    space: &JointSpace,
    start: &[f32],
    goal: &[f32],
    mut valid: impl FnMut(&[f32]) -> bool,
    mut certify: Option<EdgeCertifier<'_>>,
    params: &RrtParams,
    rng: &mut fastrand::Rng,
) -> Result<(JointPath, RrtStats), (RrtError, RrtStats)> {
    let mut checks = 0;
    for attempt in 1..=CERTIFY_ATTEMPTS {
        let certify = certify.as_mut().map(|c| &mut **c as EdgeCertifier<'_>);
        match plan_once(space, start, goal, &mut valid, certify, params, rng, true) {
            Err((RrtError::Certification(_), st)) if attempt < CERTIFY_ATTEMPTS => {
                checks += st.checks;
            }
            Ok((p, mut st)) => {
                st.checks += checks;
                return Ok((p, st));
            }
            Err((e, mut st)) => {
                st.checks += checks;
                return Err((e, st));
            }
        }
    }
    unreachable!("the last attempt returns")
}

/// Whether every edge of `path` passes its certification: `certify`, or a re-check at `fine`.
fn certified(
    space: &JointSpace,
    path: &JointPath,
    fine: f32,
    valid: &mut impl FnMut(&[f32]) -> bool,
    certify: &mut Option<EdgeCertifier<'_>>,
    checks: &mut usize,
) -> bool {
    path.waypoints.windows(2).all(|w| match certify {
        Some(c) => c(&w[0], &w[1], checks),
        None => edge_valid(space, &w[0], &w[1], fine, valid, checks),
    })
}

/// `path` certified edge by edge; where `repair`, each edge that fails replaced by the path
/// of a search between its ends (certified itself, with no repair inside, within what is left
/// of the search's time: `params`). `Ok(None)` where an edge fails and is not repaired, the
/// time limit as the error. A tree path's failing edge, as a rule, grazes a thin obstacle that
/// the discrete checks stepped over: a new search between its ends goes round it, where a search
/// from scratch would build the whole tree again.
fn repaired(
    space: &JointSpace,
    path: &JointPath,
    (fine, params, repair): (f32, &RrtParams, bool),
    valid: &mut dyn FnMut(&[f32]) -> bool,
    certify: &mut Option<EdgeCertifier<'_>>,
    rng: &mut fastrand::Rng,
    stats: &mut RrtStats,
) -> Result<Option<JointPath>, RrtError> {
    let mut out = vec![path.waypoints[0].clone()];
    for w in path.waypoints.windows(2) {
        let one = JointPath {
            waypoints: w.to_vec(),
        };
        let mut v = &mut *valid;
        if certified(space, &one, fine, &mut v, certify, &mut stats.checks) {
            out.push(w[1].clone());
            continue;
        }
        if !repair {
            return Ok(None);
        }
        let sub = certify.as_mut().map(|c| &mut **c as EdgeCertifier<'_>);
        let found = plan_once(space, &w[0], &w[1], valid, sub, params, rng, false);
        let st = match &found {
            Ok((_, st)) | Err((_, st)) => st,
        };
        (stats.checks, stats.nodes) = (stats.checks + st.checks, stats.nodes + st.nodes);
        match found {
            Ok((sub, _)) => out.extend(sub.waypoints.into_iter().skip(1)),
            Err((e @ RrtError::TimeLimit(_), _)) => return Err(e),
            Err(_) => return Ok(None),
        }
    }
    Ok(Some(JointPath { waypoints: out }))
}

/// Searches with new trees after a path fails its certification, at most this many times.
pub const CERTIFY_ATTEMPTS: usize = 3;

/// One RRT-Connect search, its path shortcut and certified; where `repair`, a tree path
/// whose edges fail their certification gets each failing edge searched for again between its
/// ends ([`repaired`]).
#[allow(clippy::too_many_arguments)]
fn plan_once(
    space: &JointSpace,
    start: &[f32],
    goal: &[f32],
    mut valid: &mut dyn FnMut(&[f32]) -> bool,
    mut certify: Option<EdgeCertifier<'_>>,
    params: &RrtParams,
    rng: &mut fastrand::Rng,
    repair: bool,
) -> Result<(JointPath, RrtStats), (RrtError, RrtStats)> {
    let mut stats = RrtStats::default();
    for q in [start, goal] {
        if q.len() != space.dim() {
            return Err((
                RrtError::Dimension {
                    expected: space.dim(),
                    got: q.len(),
                },
                stats,
            ));
        }
    }
    stats.checks += 1;
    if !space.within_limits(start) || !valid(start) {
        return Err((RrtError::InvalidStart, stats));
    }
    stats.checks += 1;
    if !space.within_limits(goal) || !valid(goal) {
        return Err((RrtError::InvalidGoal, stats));
    }
    let fine = params.resolution / params.certify_factor.max(1) as f32;
    let direct = JointPath {
        waypoints: vec![start.to_vec(), goal.to_vec()],
    };
    if edge_valid(
        space,
        start,
        goal,
        params.resolution,
        &mut valid,
        &mut stats.checks,
    ) && (params.certify_factor <= 1
        || certified(
            space,
            &direct,
            fine,
            &mut valid,
            &mut certify,
            &mut stats.checks,
        ))
    {
        stats.raw_waypoints = 2;
        return Ok((direct, stats));
    }
    let began = Instant::now();
    let mut a = Tree::new(space, start);
    let mut b = Tree::new(space, goal);
    let mut a_is_start = true;
    let mut sample = vec![0.0; space.dim()];
    loop {
        if a.len() + b.len() >= params.max_nodes {
            return Err((RrtError::NodeLimit(params.max_nodes), stats));
        }
        if stats.checks >= params.max_checks {
            return Err((RrtError::CheckLimit(params.max_checks), stats));
        }
        if began.elapsed() > params.time_limit
            || params.deadline.is_some_and(|d| Instant::now() >= d)
        {
            return Err((RrtError::TimeLimit(params.time_limit), stats));
        }
        space.sample(rng, &mut sample);
        let near = a.nearest(space, &sample);
        let new = match extend(&mut a, near, space, &sample, params, &mut valid, &mut stats) {
            Extend::Trapped => None,
            Extend::Advanced(i) | Extend::Reached(i) => Some(i),
        };
        if let Some(i) = new {
            let q = a.get(i).to_vec();
            if let Extend::Reached(j) = connect(&mut b, space, &q, params, &mut valid, &mut stats) {
                let (from_start, from_goal) = if a_is_start { (&a, i) } else { (&b, j) };
                let (other, other_i) = if a_is_start { (&b, j) } else { (&a, i) };
                let mut waypoints = from_start.branch(from_goal);
                let mut tail = other.branch(other_i);
                tail.pop(); // the meeting configuration, already last in `waypoints`
                tail.reverse();
                waypoints.extend(tail);
                stats.raw_waypoints = waypoints.len();
                let raw = JointPath { waypoints };
                let mut path = raw.clone();
                shortcut(space, &mut path, params, &mut valid, rng, &mut stats.checks);
                if params.certify_factor > 1 {
                    // Every edge of the path was checked at the search resolution (tree
                    // edges, shortcuts); now certified: by `certify`, or at the finer
                    // resolution, on the very configurations a re-check at it visits
                    // ([`JointPath::densify`]): the steps of the coarse grid refined by the
                    // factor need not be those.
                    if !certified(
                        space,
                        &path,
                        fine,
                        &mut valid,
                        &mut certify,
                        &mut stats.checks,
                    ) {
                        // A shortcut cut a corner between the coarse checks: fall back to the
                        // tree's own path, whose edges are short, its failing edges searched
                        // for again where `repair`, in the time left to this search.
                        let left = RrtParams {
                            time_limit: params.time_limit.saturating_sub(began.elapsed()),
                            ..params.clone()
                        };
                        let how = (fine, &left, repair);
                        path = match repaired(
                            space,
                            &raw,
                            how,
                            valid,
                            &mut certify,
                            rng,
                            &mut stats,
                        ) {
                            Ok(Some(p)) => p,
                            Ok(None) => {
                                let e = RrtError::Certification(params.certify_factor);
                                return Err((e, stats));
                            }
                            // Stopped by the time left: this search's limit.
                            Err(_) => return Err((RrtError::TimeLimit(params.time_limit), stats)),
                        };
                    }
                }
                return Ok((path, stats));
            }
        }
        std::mem::swap(&mut a, &mut b);
        a_is_start = !a_is_start;
    }
}

/// Shortcut smoothing: repeatedly joins two random points of the path by a straight edge when
/// that edge is valid, then drops waypoints made redundant. Shortcuts are checked at the
/// search resolution; [`plan`] certifies the result at the finer one.
pub fn shortcut(
    space: &JointSpace,
    path: &mut JointPath,
    params: &RrtParams,
    valid: &mut impl FnMut(&[f32]) -> bool,
    rng: &mut fastrand::Rng,
    checks: &mut usize,
) {
    let res = params.resolution;
    greedy_shortcut(space, path, res, valid, checks);
    // Random shortcuts between points inside edges.
    let mut a = vec![0.0; space.dim()];
    let mut b = vec![0.0; space.dim()];
    for _ in 0..params.shortcut_iterations {
        let n = path.waypoints.len();
        if n < 3 {
            break;
        }
        let i = rng.usize(0..n - 1);
        let j = rng.usize(0..n - 1);
        let (i, j) = (i.min(j), i.max(j));
        if j <= i {
            continue;
        }
        let (ti, tj) = (rng.f32(), rng.f32());
        space.interpolate(&path.waypoints[i], &path.waypoints[i + 1], ti, &mut a);
        space.interpolate(&path.waypoints[j], &path.waypoints[j + 1], tj, &mut b);
        let old = space.distance(&a, &path.waypoints[i + 1])
            + path.waypoints[i + 1..=j]
                .windows(2)
                .map(|w| space.distance(&w[0], &w[1]))
                .sum::<f32>()
            + space.distance(&path.waypoints[j], &b);
        if space.distance(&a, &b) >= old - 1e-4 {
            continue;
        }
        if edge_valid(space, &a, &b, res, valid, checks) {
            let mut w: Vec<Vec<f32>> = path.waypoints[..=i].to_vec();
            w.push(a.clone());
            w.push(b.clone());
            w.extend_from_slice(&path.waypoints[j + 1..]);
            path.waypoints = w;
        }
    }
    greedy_shortcut(space, path, res, valid, checks);
}

/// From each waypoint, jumps to the farthest later one reachable by a valid straight edge.
fn greedy_shortcut(
    space: &JointSpace,
    path: &mut JointPath,
    resolution: f32,
    valid: &mut impl FnMut(&[f32]) -> bool,
    checks: &mut usize,
) {
    let n = path.waypoints.len();
    let mut out = vec![path.waypoints[0].clone()];
    let mut i = 0;
    while i + 1 < n {
        let mut j = n - 1;
        while j > i + 1
            && !edge_valid(
                space,
                &path.waypoints[i],
                &path.waypoints[j],
                resolution,
                valid,
                checks,
            )
        {
            j -= 1;
        }
        out.push(path.waypoints[j].clone());
        i = j;
    }
    path.waypoints = out;
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A 2-joint planar space with a wall at x in [0.4, 0.6] except a gap at y > 0.8.
    fn wall(q: &[f32]) -> bool {
        !(q[0] > 0.4 && q[0] < 0.6 && q[1] < 0.8)
    }

    #[test]
    fn finds_a_path_through_the_gap_and_every_edge_is_valid() {
        let space = JointSpace::new(&[(0.0, 1.0, false), (0.0, 1.0, false)]);
        let params = RrtParams {
            resolution: 0.01,
            max_step: 0.2,
            ..RrtParams::default()
        };
        let mut rng = fastrand::Rng::with_seed(3);
        let (path, stats) =
            plan(&space, &[0.1, 0.1], &[0.9, 0.1], wall, &params, &mut rng).unwrap();
        assert!(stats.nodes > 0);
        assert_eq!(path.waypoints.first().unwrap(), &vec![0.1, 0.1]);
        assert_eq!(path.waypoints.last().unwrap(), &vec![0.9, 0.1]);
        // Re-check at 4x finer resolution.
        for q in path.densify(&space, params.resolution / 4.0) {
            assert!(wall(&q), "path enters the wall at {q:?}");
        }
        assert!(path.waypoints.iter().any(|q| q[1] > 0.8));
        // Smoothing leaves few waypoints: up, across, down.
        assert!(
            path.waypoints.len() <= 6,
            "{} waypoints",
            path.waypoints.len()
        );
    }

    #[test]
    fn edges_that_fail_their_certification_are_searched_for_again() {
        // A wall thinner than the search's resolution at x in [0.5, 0.56] except a gap at
        // y > 0.8: the discrete checks often step over it, the certifier (the exact crossing
        // of a segment with the wall) never does. Every path returned passes the certifier.
        let space = JointSpace::new(&[(0.0, 1.0, false), (0.0, 1.0, false)]);
        let thin = |q: &[f32]| !(q[0] > 0.5 && q[0] < 0.56 && q[1] < 0.8);
        let crosses = |a: &[f32], b: &[f32]| {
            // Sampled finely enough to be exact for this wall (0.06 wide, steps of 0.001).
            (0..=1000).any(|k| {
                let t = k as f32 / 1000.0;
                !thin(&[a[0] + t * (b[0] - a[0]), a[1] + t * (b[1] - a[1])])
            })
        };
        let params = RrtParams {
            resolution: 0.1,
            max_step: 0.3,
            ..RrtParams::default()
        };
        let (mut solved, mut certifications) = (0, 0);
        for seed in 0..20 {
            let mut rng = fastrand::Rng::with_seed(seed);
            let mut certify = |a: &[f32], b: &[f32], _: &mut usize| {
                certifications += 1;
                !crosses(a, b)
            };
            let found = plan_certified(
                &space,
                &[0.1, 0.1],
                &[0.9, 0.1],
                thin,
                Some(&mut certify),
                &params,
                &mut rng,
            );
            if let Ok((path, _)) = found {
                solved += 1;
                for w in path.waypoints.windows(2) {
                    assert!(
                        !crosses(&w[0], &w[1]),
                        "seed {seed}: {w:?} crosses the wall"
                    );
                }
            }
        }
        // Not vacuous: the edges fail often; with the repair 5 of the 20 searches succeed, 2
        // without it (new trees from scratch).
        assert!(
            solved >= 4 && certifications > 300,
            "{solved} solved, {certifications}"
        );
    }

    #[test]
    fn a_certified_path_passes_a_recheck_at_the_finer_resolution() {
        // Slabs thinner than the fine resolution: checks on one grid may step over a slab that
        // a check on another grid hits. The path returned must pass the re-check that the
        // certification promises (every configuration `densify` gives at the finer resolution).
        let slab = |q: &[f32]| {
            [0.3f32, 0.5, 0.7]
                .iter()
                .any(|x| (q[0] - x).abs() < 0.001 && q[1] < 0.4)
        };
        let valid = |q: &[f32]| !slab(q);
        let space = JointSpace::new(&[(0.0, 1.0, false), (0.0, 1.0, false)]);
        let params = RrtParams {
            resolution: 0.01,
            max_step: 0.3,
            ..RrtParams::default()
        };
        let (mut found, mut certified_out) = (0, 0);
        for seed in 0..200 {
            let mut rng = fastrand::Rng::with_seed(seed);
            match plan(&space, &[0.1, 0.1], &[0.9, 0.1], valid, &params, &mut rng) {
                Ok((path, _)) => {
                    found += 1;
                    if let Some(q) = path
                        .densify(&space, params.resolution / params.certify_factor as f32)
                        .into_iter()
                        .find(|q| slab(q))
                    {
                        panic!("seed {seed}: the certified path crosses a slab at {q:?}");
                    }
                }
                Err((RrtError::Certification(_), _)) => certified_out += 1,
                Err((e, _)) => panic!("seed {seed}: {e}"),
            }
        }
        // Some queries find a path around the slabs; the others are refused by the
        // certification (their coarse edges cross a slab).
        assert!(found > 0, "{found} paths, {certified_out} refused");
    }

    #[test]
    fn refining_an_edge_checks_only_the_new_configurations_and_finds_thin_obstacles() {
        let space = JointSpace::new(&[(0.0, 1.0, false)]);
        // A thin wall between the coarse checks at 0.1 spacing.
        let mut valid = |q: &[f32]| !(q[0] > 0.42 && q[0] < 0.44);
        let mut checks = 0;
        assert!(edge_valid(
            &space,
            &[0.0],
            &[1.0],
            0.1,
            &mut valid,
            &mut checks
        ));
        assert_eq!(checks, 10);
        assert!(!edge_refine(
            &space,
            &[0.0],
            &[1.0],
            0.1,
            4,
            &mut valid,
            &mut checks
        ));
        // A free edge: 30 new configurations (40 at the fine spacing, 10 already checked).
        let mut checks = 0;
        let mut free = |_: &[f32]| true;
        assert!(edge_refine(
            &space,
            &[0.0],
            &[1.0],
            0.1,
            4,
            &mut free,
            &mut checks
        ));
        assert_eq!(checks, 30);
    }

    #[test]
    fn same_seed_same_path() {
        let space = JointSpace::new(&[(0.0, 1.0, false), (0.0, 1.0, false)]);
        let params = RrtParams::default();
        let run = |seed| {
            let mut rng = fastrand::Rng::with_seed(seed);
            plan(&space, &[0.1, 0.1], &[0.9, 0.1], wall, &params, &mut rng)
                .unwrap()
                .0
        };
        assert_eq!(run(5), run(5));
    }

    #[test]
    fn continuous_joints_go_the_short_way_round() {
        let space = JointSpace::new(&[(0.0, 0.0, true)]);
        // Forbid the region around 0: from 3.0 to -3.0 the short way crosses pi, not 0.
        let valid = |q: &[f32]| q[0].abs() > 0.5;
        let mut rng = fastrand::Rng::with_seed(1);
        let (path, _) = plan(
            &space,
            &[3.0],
            &[-3.0],
            valid,
            &RrtParams::default(),
            &mut rng,
        )
        .unwrap();
        assert_eq!(path.waypoints.len(), 2);
        assert!((path.length(&space) - (TAU - 6.0)).abs() < 1e-4);
        for q in path.densify(&space, 0.01) {
            assert!(q[0].abs() > 2.9);
        }
    }

    #[test]
    fn reports_invalid_ends_and_limits() {
        let space = JointSpace::new(&[(0.0, 1.0, false), (0.0, 1.0, false)]);
        let mut rng = fastrand::Rng::with_seed(1);
        let p = RrtParams::default();
        let e = plan(&space, &[0.5, 0.5], &[0.9, 0.1], wall, &p, &mut rng).unwrap_err();
        assert_eq!(e.0, RrtError::InvalidStart);
        let e = plan(&space, &[0.1, 0.1], &[1.5, 0.1], wall, &p, &mut rng).unwrap_err();
        assert_eq!(e.0, RrtError::InvalidGoal);
        // A closed wall: no path; the node limit stops the search.
        let closed = |q: &[f32]| !(q[0] > 0.4 && q[0] < 0.6);
        let p = RrtParams {
            max_nodes: 300,
            ..RrtParams::default()
        };
        let e = plan(&space, &[0.1, 0.1], &[0.9, 0.1], closed, &p, &mut rng).unwrap_err();
        assert_eq!(e.0, RrtError::NodeLimit(300));
        // The check budget stops it too, with the checks it counted, on any machine.
        let p = RrtParams {
            max_checks: 2_000,
            ..RrtParams::default()
        };
        let (e, stats) = plan(&space, &[0.1, 0.1], &[0.9, 0.1], closed, &p, &mut rng).unwrap_err();
        assert_eq!(e, RrtError::CheckLimit(2_000));
        assert!(
            stats.checks >= 2_000 && stats.checks < 2_100,
            "{}",
            stats.checks
        );
    }

    /// A continuous joint crossing +-pi: the planner goes the short way (0.2 rad); the recorded
    /// waypoints must say so to anyone interpolating them linearly, not swing 6.08 rad back.
    #[test]
    fn unwrapped_waypoints_interpolate_linearly_the_short_way() {
        let space = JointSpace::new(&[(-1.0, 1.0, false), (0.0, 0.0, true)]);
        let path = JointPath {
            waypoints: vec![vec![0.0, 3.04], vec![0.5, -3.04], vec![0.6, -2.9]],
        };
        let u = path.unwrapped(&space);
        assert_eq!(u.waypoints[0], vec![0.0, 3.04]);
        for w in u.waypoints.windows(2) {
            assert!((w[1][1] - w[0][1]).abs() < 0.25, "{:?}", u.waypoints);
        }
        // Same configurations as the planner's, modulo whole turns, and the same densified path.
        let (a, b) = (path.densify(&space, 0.01), u.densify(&space, 0.01));
        assert_eq!(a.len(), b.len());
        for (x, y) in a.iter().zip(&b) {
            assert!((x[0] - y[0]).abs() < 1e-6);
            assert!(wrap(x[1] - y[1]).abs() < 1e-5);
        }
        let mid = |p: &JointPath| {
            let (x, y) = (&p.waypoints[0][1], &p.waypoints[1][1]);
            (x + y) / 2.0
        };
        assert!(
            wrap(mid(&u) - PI).abs() < 1e-5,
            "the linear midpoint is at pi"
        );
        assert!(
            mid(&path).abs() < 1e-5,
            "the raw midpoint was at 0, the long way"
        );
    }
}
