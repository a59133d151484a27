//! Self-collision of an agent: which pairs of its links to test, found once per agent model
//! (adjacent, default-colliding, always-colliding and never-colliding pairs are left out, as
//! MoveIt's setup assistant does for its SRDF).

use std::fmt;
use std::sync::Arc;

use parry3d::bounding_volume::Aabb;
use parry3d::math::{Mat3, Pose, Vector};
use parry3d::query::details::intersection_test_support_map_support_map_with_params;
use parry3d::query::gjk::VoronoiSimplex;
use parry3d::shape::{Cuboid, Shape, SharedShape, SupportMap};

use super::climbing_hull::{ClimbingHull, climbing_hull_of, gjk};
use super::intersects;
use super::link_capsule::LinkCapsule;
use super::motion::{JointReach, body, lower_bound_distance};
use super::pair_cells::{CellProof, CellProver, PairCells};
use crate::agent::{AgentModel, ModelError};

/// How the self-collision pairs to ignore are found.
#[derive(Debug, Clone, PartialEq)]
pub struct SelfCollisionOptions {
    /// Random configurations sampled to find the pairs that always collide.
    pub samples: usize,
    /// Seed of the sampling.
    pub seed: u64,
    /// A pair colliding in at least this fraction of the samples is ignored (MoveIt's default
    /// is 0.95).
    pub always_fraction: f32,
    /// Whether pairs of links whose relative pose depends on two degrees of freedom skip
    /// their exact tests where cells of those two prove them apart (see `pair_cells.rs`).
    /// Answers change only where the exact test calls shapes a hair apart touching.
    pub pair_cells: bool,
}

impl Default for SelfCollisionOptions {
    fn default() -> Self {
        SelfCollisionOptions {
            samples: 1000,
            seed: 0,
            always_fraction: 0.95,
            pair_cells: true,
        }
    }
}

/// Why a pair of links is not checked for self-collision.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum AllowedReason {
    /// A link and its parent link (one joint apart).
    Adjacent,
    /// They collide in the default configuration.
    Default,
    /// They collide in (almost) every sampled configuration.
    Always,
    /// The model's SRDF says so (`<disable_collisions>`).
    Srdf,
    /// Their relative pose depends on at most one degree of freedom (the two fingers of a
    /// gripper, an elbow and the forearm rolling beside it), and they are proven at least
    /// 0.1 mm apart over its whole range: they never collide.
    Never,
}

/// How far apart (metres) two links must stay over their degree of freedom's whole range to
/// be left out as [`AllowedReason::Never`].
const NEVER_MARGIN: f32 = 1e-4;

/// The degrees of freedom that move link `b` relative to link `a` (mimic joints count as
/// their master), sorted and deduplicated.
fn relative_dofs(model: &AgentModel, a: usize, b: usize) -> Vec<usize> {
    let path = |mut l: usize| {
        let mut v = vec![l];
        while let Some(p) = model.links()[l].parent {
            v.push(p);
            l = p;
        }
        v
    };
    let (pa, pb) = (path(a), path(b));
    let mut dofs = Vec::new();
    for (p, other) in [(&pa, &pb), (&pb, &pa)] {
        for &l in p {
            if other.contains(&l) {
                break; // the common ancestor
            }
            let j = &model.joints()[model.links()[l].parent_joint.expect("non-root")];
            let dof = j
                .dof
                .or_else(|| j.mimic.and_then(|m| model.joints()[m.master].dof));
            dofs.extend(dof);
        }
    }
    dofs.sort_unstable();
    dofs.dedup();
    dofs
}

/// A pair of links left out of self-collision checks.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct AllowedPair {
    /// First link's name.
    pub link_a: String,
    /// Second link's name.
    pub link_b: String,
    /// Why.
    pub reason: AllowedReason,
}

/// How much a polyhedron's bounding box is widened (metres): shapes that touch (distance 0,
/// which parry's exact test may count as contact) are never separated by their boxes alone.
const BOUNDS_MARGIN: f32 = 1e-4;

/// One collision shape of the agent, flattened out of its link.
#[derive(Clone)]
pub(super) struct ShapeEntry {
    pub(super) link: usize,
    pub(super) local_pose: Pose,
    pub(super) shape: SharedShape,
    pub(super) radius: f32,
    /// For a shape costly to test (a convex polyhedron, whose support function visits every
    /// vertex): its bounding box in its own frame, tested first (see [`ShapeEntry::hits`]).
    pub(super) bounds: Option<(Pose, Cuboid)>,
    /// For a polyhedron of many vertices: its support by hill climbing (see [`ClimbingHull`]).
    climb: Option<Arc<ClimbingHull>>,
    /// A ball that holds the shape: its centre in the shape's frame, its radius (tighter than
    /// `radius` for a mesh piece, whose frame is its link's).
    pub(super) ball: (Vector, f32),
    /// For a polyhedron: a capsule that holds it, in its link's frame (a cheap bound before
    /// GJK on its vertices).
    pub(super) capsule: Option<LinkCapsule>,
    /// For a polyhedron: a box in its link's frame (centre, half extents) that holds its
    /// bounding box (see [`ShapeEntry::aabb_on_link`]).
    bounds_in_link: Option<(Vector, Vector)>,
}

impl ShapeEntry {
    fn new(link: usize, local_pose: Pose, shape: SharedShape, radius: f32) -> ShapeEntry {
        let bounds = shape.as_convex_polyhedron().map(|_| {
            let aabb = shape.compute_local_aabb();
            (
                Pose::from_translation(aabb.center()),
                Cuboid::new(aabb.half_extents() + Vector::splat(BOUNDS_MARGIN)),
            )
        });
        let climb = climbing_hull_of(&shape);
        // The smaller of two balls that hold the shape: `radius` about its frame's origin, or
        // parry's bounding sphere (about its box's centre).
        let sphere = shape.compute_local_bounding_sphere();
        let ball = if radius <= sphere.radius {
            (Vector::ZERO, radius)
        } else {
            (sphere.center, sphere.radius)
        };
        let mut entry = ShapeEntry {
            link,
            local_pose,
            radius,
            bounds,
            climb,
            ball,
            capsule: None,
            bounds_in_link: bounds.map(|(at, cuboid)| {
                let abs = Mat3::from_quat(local_pose.rotation).abs();
                (local_pose * at.translation, abs * cuboid.half_extents)
            }),
            shape,
        };
        if entry.shape.as_convex_polyhedron().is_some() {
            entry.capsule = LinkCapsule::enclosing(&entry.points());
        }
        entry
    }

    /// A lower bound on the distance between this shape and `other`, their links at `link`
    /// and `other_link`, by their capsules; negative infinity where either has none.
    pub(super) fn capsule_gap(&self, link: &Pose, other: &ShapeEntry, other_link: &Pose) -> f32 {
        LinkCapsule::gap_of(
            self.capsule.as_ref(),
            link,
            other.capsule.as_ref(),
            other_link,
        )
    }

    /// Points in its link's frame whose convex hull holds the shape: a polyhedron's vertices,
    /// another shape's bounding-box corners.
    fn points(&self) -> Vec<Vector> {
        let local: Vec<Vector> = match self.shape.as_convex_polyhedron() {
            Some(hull) => hull.points().to_vec(),
            None => self.shape.compute_local_aabb().vertices().to_vec(),
        };
        local.into_iter().map(|p| self.local_pose * p).collect()
    }

    /// The shape's world AABB at `pose`: for a polyhedron, that of its bounding box (a few
    /// operations, where the exact one visits every vertex).
    pub(super) fn aabb(&self, pose: &Pose) -> Aabb {
        match &self.bounds {
            Some((at, cuboid)) => cuboid.compute_aabb(&(*pose * *at)),
            None => self.shape.compute_aabb(pose),
        }
    }

    /// Whether [`ShapeEntry::aabb_on_link`] needs its matrix.
    pub(super) fn bounded_in_link(&self) -> bool {
        self.bounds_in_link.is_some()
    }

    /// [`ShapeEntry::aabb`] from its link's pose `link` and that pose's rotation matrix with
    /// absolute entries `abs` (shared by the link's shapes): for a polyhedron, that of its
    /// bounding box as it lies in the link's frame (the same box for a mesh piece, whose frame
    /// is its link's).
    pub(super) fn aabb_on_link(&self, pose: &Pose, link: &Pose, abs: &Mat3) -> Aabb {
        match &self.bounds_in_link {
            Some((centre, half)) => {
                let (c, h) = (*link * *centre, *abs * *half);
                Aabb::new(c - h, c + h)
            }
            None => self.shape.compute_aabb(pose),
        }
    }

    /// Whether the shape at `pose` intersects `other` at `other_pose`: its bounding box first
    /// (a separating-axis test against a box), which rules out most pairs whose AABBs overlap,
    /// then the exact shapes. The box holds the shape: where it is apart from `other`, so is
    /// the shape (parry's GJK test between polyhedra of hundreds of vertices may report contact
    /// at a few millimetres of distance; the box does not).
    pub(super) fn hits(&self, pose: &Pose, other: &dyn Shape, other_pose: &Pose) -> bool {
        if let Some((at, cuboid)) = &self.bounds
            && !intersects(&(*pose * *at), cuboid, other_pose, other)
        {
            return false;
        }
        intersects(pose, &*self.shape.0, other_pose, other)
    }

    /// The shape's support function, where it has one: the climbing one for a large hull.
    pub(super) fn support(&self) -> Option<&dyn SupportMap> {
        match &self.climb {
            Some(climb) => Some(&**climb),
            None => self.shape.as_support_map(),
        }
    }

    /// The shape's bounding box at `pose` as a support map, or the shape where it has none.
    fn bound<'a>(&'a self, pose: &Pose, exact: &'a dyn SupportMap) -> (Pose, &'a dyn SupportMap) {
        match &self.bounds {
            Some((at, cuboid)) => (*pose * *at, cuboid),
            None => (*pose, exact),
        }
    }

    /// [`ShapeEntry::hits`] with the climbing support of a large hull: the bounding box, then
    /// the exact shapes, each by GJK from its default start (see `climbing_hull.rs`).
    pub(super) fn hits_by_gjk(&self, pose: &Pose, other: &dyn Shape, other_pose: &Pose) -> bool {
        let (Some(a), Some(b)) = (self.support(), other.as_support_map()) else {
            return self.hits(pose, other, other_pose);
        };
        let (box_pose, bounds) = self.bound(pose, a);
        (self.bounds.is_none() || gjk(&box_pose, bounds, other_pose, b))
            && gjk(pose, a, other_pose, b)
    }

    /// [`ShapeEntry::hits_shape`] with climbing supports, as [`ShapeEntry::hits_by_gjk`].
    pub(super) fn hits_shape_by_gjk(
        &self,
        pose: &Pose,
        other: &ShapeEntry,
        other_pose: &Pose,
    ) -> bool {
        let (Some(a), Some(b)) = (self.support(), other.support()) else {
            return self.hits_shape(pose, other, other_pose);
        };
        self.boxes_meet(pose, other, other_pose, (a, b)) && gjk(pose, a, other_pose, b)
    }

    /// Whether the bounding boxes of two agent shapes (the shapes themselves where they have
    /// none; `a`, `b` their supports) meet.
    fn boxes_meet(
        &self,
        pose: &Pose,
        other: &ShapeEntry,
        other_pose: &Pose,
        (a, b): (&dyn SupportMap, &dyn SupportMap),
    ) -> bool {
        match (&self.bounds, &other.bounds) {
            (None, None) => true,
            // Two boxes: the separating-axis test, exact and cheaper than GJK.
            (Some((at, ca)), Some((bt, cb))) => {
                intersects(&(*pose * *at), ca, &(*other_pose * *bt), cb)
            }
            _ => {
                let ((pa, ba), (pb, bb)) = (self.bound(pose, a), other.bound(other_pose, b));
                gjk(&pa, ba, &pb, bb)
            }
        }
    }

    /// [`ShapeEntry::hits_shape_by_gjk`], first trying `axis` (in this shape's frame, from a
    /// former check of the pair): shapes apart along it by more than [`AXIS_GAP`] do not
    /// meet, whatever the axis's origin. Where it fails, `axis` becomes the one GJK found, or
    /// zero where the shapes meet.
    pub(super) fn hits_shape_with_axis(
        &self,
        pose: &Pose,
        other: &ShapeEntry,
        other_pose: &Pose,
        axis: &mut Vector,
    ) -> bool {
        let (Some(a), Some(b)) = (self.support(), other.support()) else {
            return self.hits_shape(pose, other, other_pose);
        };
        let pos12 = pose.inv_mul(other_pose);
        if *axis != Vector::ZERO && gap_along(&pos12, (a, b), *axis) > AXIS_GAP {
            return false;
        }
        if !self.boxes_meet(pose, other, other_pose, (a, b)) {
            return false;
        }
        let (hit, dir) = separation(&pos12, (a, b));
        *axis = dir;
        hit
    }

    /// Whether two agent shapes intersect: their bounding boxes first, then the exact shapes.
    pub(super) fn hits_shape(&self, pose: &Pose, other: &ShapeEntry, other_pose: &Pose) -> bool {
        if let Some((at, cuboid)) = &other.bounds
            && !self.hits(pose, cuboid, &(*other_pose * *at))
        {
            return false;
        }
        self.hits(pose, &*other.shape.0, other_pose)
    }
}

/// How far apart (metres) two shapes must be along a cached axis for it to prove them apart.
const AXIS_GAP: f32 = 1e-5;

/// GJK's exact intersection test of `a` and `b` (at `pos12` in `a`'s frame), as
/// [`gjk`], and where they are apart, the axis it found that separates them by more than
/// [`AXIS_GAP`] (zero where none does).
fn separation(pos12: &Pose, (a, b): (&dyn SupportMap, &dyn SupportMap)) -> (bool, Vector) {
    let (hit, dir) = intersection_test_support_map_support_map_with_params(
        pos12,
        a,
        b,
        &mut VoronoiSimplex::new(),
        None,
    );
    if hit {
        return (true, Vector::ZERO);
    }
    let apart = [dir, -dir].into_iter().find_map(|d| {
        d.try_normalize()
            .filter(|&d| gap_along(pos12, (a, b), d) > AXIS_GAP)
    });
    (false, apart.unwrap_or(Vector::ZERO))
}

/// How far `b` (at `pos12` in `a`'s frame) lies beyond `a` along unit `axis` (`a`'s frame):
/// positive where the axis separates them.
fn gap_along(pos12: &Pose, (a, b): (&dyn SupportMap, &dyn SupportMap), axis: Vector) -> f32 {
    let far_a = axis.dot(a.local_support_point(axis));
    let near_b = pos12 * b.local_support_point(pos12.rotation.inverse() * -axis);
    axis.dot(near_b) - far_a
}

/// A pair of links whose shapes are tested against each other: links `a < b`, their shape
/// pairs `pairs[start..end]`. The links' spheres are tested first, which rules most pairs of
/// links out at once.
#[derive(Clone, Copy, Debug)]
pub(super) struct PairGroup {
    pub(super) a: u16,
    pub(super) b: u16,
    pub(super) start: u32,
    pub(super) end: u32,
    /// For links whose relative pose depends on two degrees of freedom, an index into
    /// [`SelfCollisionModel`]'s cells of them ([`NO_CELLS`]: none).
    pub(super) cells: u32,
}

/// A pair of links with more shape pairs than this is measured by the links' capsules before
/// its shapes (see `link_capsule.rs`).
const CAPSULE_PAIRS: u32 = 4;

/// [`PairGroup::cells`] of a pair without cells.
pub(super) const NO_CELLS: u32 = u32::MAX;

/// An agent model's collision shapes and its self-collision pair list. Build once per model.
#[derive(Clone)]
pub struct SelfCollisionModel {
    pub(super) model: Arc<AgentModel>,
    pub(super) shapes: Vec<ShapeEntry>,
    /// Shape index pairs to test for self-collision, those of one pair of links together.
    pub(super) pairs: Vec<(u16, u16)>,
    /// The pairs of links to test, each with its run of `pairs` (see [`PairGroup`]).
    pub(super) groups: Vec<PairGroup>,
    /// Per link, the sphere (centre in the link's frame, radius) that holds its shapes; a
    /// radius below 0 for a link without shapes.
    pub(super) link_spheres: Vec<(Vector, f32)>,
    /// Per link, the capsule (in the link's frame) that holds its shapes; `None` for a link
    /// without shapes.
    pub(super) link_capsules: Vec<Option<LinkCapsule>>,
    /// Per link, a box in its frame (centre, half extents) that holds its shapes; `None` for
    /// a link without shapes.
    pub(super) link_boxes: Vec<Option<(Vector, Vector)>>,
    /// Per link, its shapes: `shapes[start..end]` (a link's shapes are consecutive).
    pub(super) link_shapes: Vec<(u16, u16)>,
    /// 0, 1, .. shapes.len() - 1.
    pub(super) all_shapes: Vec<u16>,
    /// How fast each link's points may move with the joints (for motion checks).
    pub(super) reach: JointReach,
    /// The cells of the link pairs whose relative pose depends on two degrees of freedom,
    /// proven free as checks come to them (shared by the model's clones).
    cells: Arc<Vec<PairCells>>,
    allowed: Vec<AllowedPair>,
}

impl fmt::Debug for SelfCollisionModel {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.debug_struct("SelfCollisionModel")
            .field("model", &self.model.name())
            .field("shapes", &self.shapes.len())
            .field("pairs", &self.pairs.len())
            .field("allowed", &self.allowed)
            .finish()
    }
}

impl SelfCollisionModel {
    /// Flattens the model's shapes and computes the pairs to check (see the module docs).
    pub fn new(model: Arc<AgentModel>, options: &SelfCollisionOptions) -> SelfCollisionModel {
        let mut shapes = Vec::new();
        for (i, link) in model.links().iter().enumerate() {
            for c in &link.collisions {
                shapes.push(ShapeEntry::new(
                    i,
                    c.local_pose,
                    c.shape.clone(),
                    c.bounding_radius,
                ));
            }
        }
        let nl = model.links().len();
        let mut by_link = vec![Vec::new(); nl];
        for (i, e) in shapes.iter().enumerate() {
            by_link[e.link].push(i);
        }
        let link_capsules: Vec<Option<LinkCapsule>> = by_link
            .iter()
            .map(|ids| {
                let points: Vec<Vector> = ids.iter().flat_map(|&i| shapes[i].points()).collect();
                LinkCapsule::enclosing(&points)
            })
            .collect();
        let link_boxes = by_link
            .iter()
            .map(|ids| {
                let mut points = ids.iter().flat_map(|&i| shapes[i].points());
                let first = points.next()?;
                let (lo, hi) = points.fold((first, first), |(lo, hi), p| (lo.min(p), hi.max(p)));
                Some((
                    (lo + hi) * 0.5,
                    (hi - lo) * 0.5 + Vector::splat(BOUNDS_MARGIN),
                ))
            })
            .collect();
        let link_shapes = by_link
            .iter()
            .map(|ids| match (ids.first(), ids.last()) {
                (Some(&a), Some(&b)) => (a as u16, b as u16 + 1),
                _ => (0, 0),
            })
            .collect();
        let bodies = Bodies {
            shapes: &shapes,
            by_link: &by_link,
            capsules: &link_capsules,
        };
        // Link-level pair status: None = check, Some(reason) = ignore.
        let mut status: Vec<Option<AllowedReason>> = vec![None; nl * nl];
        let key = |a: usize, b: usize| a.min(b) * nl + a.max(b);
        for (i, link) in model.links().iter().enumerate() {
            if link.collisions.is_empty() {
                continue;
            }
            if let Some(p) = link.parent
                && !model.links()[p].collisions.is_empty()
            {
                status[key(i, p)] = Some(AllowedReason::Adjacent);
            }
            // Shapes of one link never collide with each other.
            status[key(i, i)] = Some(AllowedReason::Adjacent);
        }
        for (a, b) in &model.semantics().disabled_collisions {
            if let (Ok(a), Ok(b)) = (model.link_id(a), model.link_id(b)) {
                status[key(a, b)].get_or_insert(AllowedReason::Srdf);
            }
        }
        let mut candidate_links = Vec::new();
        for a in 0..nl {
            for b in a + 1..nl {
                if !model.links()[a].collisions.is_empty()
                    && !model.links()[b].collisions.is_empty()
                    && status[key(a, b)].is_none()
                {
                    candidate_links.push((a, b));
                }
            }
        }
        let mut poses = Vec::new();
        let link_pairs_colliding = |q: &[f32], poses: &mut Vec<Pose>, out: &mut Vec<bool>| {
            model.link_poses_into(Pose::IDENTITY, q, poses);
            out.clear();
            for &(a, b) in &candidate_links {
                out.push(bodies.collide(poses, a, b));
            }
        };
        let mut hits = Vec::new();
        let default = model.default_configuration();
        link_pairs_colliding(default.as_slice(), &mut poses, &mut hits);
        for (k, &(a, b)) in candidate_links.iter().enumerate() {
            if hits[k] {
                status[key(a, b)] = Some(AllowedReason::Default);
            }
        }
        // The pairs left out already (colliding in the default configuration) are not sampled.
        let open: Vec<(usize, usize)> = (candidate_links.iter().copied())
            .filter(|&(a, b)| status[key(a, b)].is_none())
            .collect();
        let always = always_colliding(&model, &open, options, |poses, a, b| {
            bodies.collide(poses, a, b)
        });
        for (k, &(a, b)) in open.iter().enumerate() {
            if always[k] {
                status[key(a, b)] = Some(AllowedReason::Always);
            }
        }
        // Pairs whose relative pose depends on at most one degree of freedom: sweep it.
        let reach = JointReach::new(&model);
        for &(a, b) in &candidate_links {
            if status[key(a, b)].is_some() {
                continue;
            }
            let never = match relative_dofs(&model, a, b).as_slice() {
                [] => true, // rigidly connected and apart in the default configuration
                [d] => {
                    let sweep = Sweep {
                        model: &model,
                        shapes: &shapes,
                        reach: &reach,
                    };
                    sweep.apart_over_dof((&by_link[a], &by_link[b]), *d, default.as_slice())
                }
                _ => false,
            };
            if never {
                status[key(a, b)] = Some(AllowedReason::Never);
            }
        }
        let mut pairs = Vec::new();
        let mut groups = Vec::new();
        let mut cells = Vec::new();
        let prover = CellProver {
            model: &model,
            shapes: &shapes,
            reach: &reach,
        };
        for a in 0..nl {
            for b in a + 1..nl {
                if by_link[a].is_empty() || by_link[b].is_empty() || status[key(a, b)].is_some() {
                    continue;
                }
                let start = pairs.len() as u32;
                for &i in &by_link[a] {
                    pairs.extend(by_link[b].iter().map(|&j| (i as u16, j as u16)));
                }
                let mut group = PairGroup {
                    a: a as u16,
                    b: b as u16,
                    start,
                    end: pairs.len() as u32,
                    cells: NO_CELLS,
                };
                if options.pair_cells
                    && let &[d, e] = relative_dofs(&model, a, b).as_slice()
                    && let Some(c) = prover.cells([d, e], &pairs[start as usize..])
                {
                    group.cells = cells.len() as u32;
                    cells.push(c);
                }
                groups.push(group);
            }
        }
        let link_spheres = by_link
            .iter()
            .map(|ids| {
                if ids.is_empty() {
                    return (Vector::ZERO, -1.0);
                }
                let ball = |i: usize| {
                    let e: &ShapeEntry = &shapes[i];
                    (e.local_pose * e.ball.0, e.ball.1)
                };
                let centre = ids
                    .iter()
                    .map(|&i| ball(i).0)
                    .fold(Vector::ZERO, |sum, c| sum + c)
                    / ids.len() as f32;
                let radius = ids
                    .iter()
                    .map(|&i| (ball(i).0 - centre).length() + ball(i).1)
                    .fold(0.0f32, f32::max);
                (centre, radius)
            })
            .collect();
        let mut allowed = Vec::new();
        for a in 0..nl {
            for b in a + 1..nl {
                if let Some(reason) = status[key(a, b)] {
                    allowed.push(AllowedPair {
                        link_a: model.links()[a].name.clone(),
                        link_b: model.links()[b].name.clone(),
                        reason,
                    });
                }
            }
        }
        SelfCollisionModel {
            reach,
            cells: Arc::new(cells),
            model,
            all_shapes: (0..shapes.len() as u16).collect(),
            shapes,
            pairs,
            groups,
            link_spheres,
            link_capsules,
            link_boxes,
            link_shapes,
            allowed,
        }
    }

    /// The world box of link `l` at pose `link` that holds its shapes (that of its box in its
    /// frame); `None` for a link without shapes.
    pub(super) fn link_box(&self, l: usize, link: &Pose) -> Option<Aabb> {
        let (centre, half) = self.link_boxes[l]?;
        let (c, h) = (*link * centre, Mat3::from_quat(link.rotation).abs() * half);
        Some(Aabb::new(c - h, c + h))
    }

    /// A lower bound on the distance between the links of `group` at world poses `links` by
    /// their capsules; negative infinity (no bound) for a pair of at most [`CAPSULE_PAIRS`]
    /// shape pairs, whose shapes cost no more to test than the capsules.
    #[inline]
    pub(super) fn capsule_gap(&self, group: &PairGroup, links: &[Pose]) -> f32 {
        if group.end - group.start <= CAPSULE_PAIRS {
            return f32::NEG_INFINITY;
        }
        self.capsules_gap(group.a as usize, group.b as usize, links)
    }

    /// A lower bound on the distance between links `a` and `b` at world poses `links` by their
    /// capsules (negative infinity for a link without shapes).
    fn capsules_gap(&self, a: usize, b: usize, links: &[Pose]) -> f32 {
        let capsules = (
            self.link_capsules[a].as_ref(),
            self.link_capsules[b].as_ref(),
        );
        LinkCapsule::gap_of(capsules.0, &links[a], capsules.1, &links[b])
    }

    /// A lower bound on the distance between link `l` at world pose `link` and a ball
    /// (`centre`, `radius`) by the link's capsule (negative infinity for a link without shapes).
    pub(super) fn capsule_ball_gap(
        &self,
        l: usize,
        link: &Pose,
        centre: Vector,
        radius: f32,
    ) -> f32 {
        let Some(c) = &self.link_capsules[l] else {
            return f32::NEG_INFINITY;
        };
        c.ball_gap(link, centre, radius)
    }

    /// What the cells of the links of `group` (see `pair_cells.rs`) say in configuration
    /// `q`: apart, or which of the group's shape pairs remain to be tested; every pair for a
    /// group without cells.
    pub(super) fn cell_proof(&self, group: &PairGroup, q: &[f32]) -> CellProof<'_> {
        match self.cells.get(group.cells as usize) {
            Some(cells) => self.prover().free(cells, self.group_pairs(group), q),
            None => CellProof::All,
        }
    }

    /// Whether the links of `group` are proven apart all along the straight motion from `a`
    /// to `b` by their cells; false for a pair without cells.
    pub(super) fn proven_apart_along(&self, group: &PairGroup, (a, b): (&[f32], &[f32])) -> bool {
        self.with_cells(group, |prover, cells, pairs| {
            prover.free_along(cells, pairs, (a, b))
        })
    }

    fn with_cells(
        &self,
        group: &PairGroup,
        proof: impl FnOnce(&CellProver, &PairCells, &[(u16, u16)]) -> bool,
    ) -> bool {
        let Some(cells) = self.cells.get(group.cells as usize) else {
            return false;
        };
        proof(&self.prover(), cells, self.group_pairs(group))
    }

    fn prover(&self) -> CellProver<'_> {
        CellProver {
            model: &self.model,
            shapes: &self.shapes,
            reach: &self.reach,
        }
    }

    /// The shape pairs of `group`.
    fn group_pairs(&self, group: &PairGroup) -> &[(u16, u16)] {
        &self.pairs[group.start as usize..group.end as usize]
    }

    /// The agent model.
    pub fn model(&self) -> &Arc<AgentModel> {
        &self.model
    }

    /// Link pairs left out of self-collision checks, and why.
    pub fn allowed_pairs(&self) -> &[AllowedPair] {
        &self.allowed
    }

    /// The pairs of links (names) whose tests go through cells of their two degrees of
    /// freedom ([`SelfCollisionOptions::pair_cells`]).
    pub fn pairs_with_cells(&self) -> Vec<(&str, &str)> {
        let name = |l: u16| self.model.links()[l as usize].name.as_str();
        self.groups
            .iter()
            .filter(|g| g.cells != NO_CELLS)
            .map(|g| (name(g.a), name(g.b)))
            .collect()
    }

    /// Number of shape pairs tested for self-collision.
    pub fn checked_pair_count(&self) -> usize {
        self.pairs.len()
    }

    /// Whether links `a` and `b` (names) are checked against each other.
    pub fn is_checked(&self, a: &str, b: &str) -> Result<bool, ModelError> {
        let (a, b) = (self.model.link_id(a)?, self.model.link_id(b)?);
        Ok(self.pairs.iter().any(|&(i, j)| {
            let (la, lb) = (self.shapes[i as usize].link, self.shapes[j as usize].link);
            (la == a && lb == b) || (la == b && lb == a)
        }))
    }
}

/// What a sweep of one degree of freedom needs of the model being built.
struct Sweep<'a> {
    model: &'a AgentModel,
    shapes: &'a [ShapeEntry],
    reach: &'a JointReach,
}

impl Sweep<'_> {
    /// Whether shapes `a` and shapes `b` (indices into `shapes`, of two links whose relative
    /// pose depends on degree of freedom `d` alone) stay at least [`NEVER_MARGIN`] apart over
    /// `d`'s whole range (a continuous joint's full turn), the other joints at `q`. Proven by
    /// conservative advancement, as a motion check is (see `motion.rs`): each pair of shapes
    /// is measured (a proven lower bound on its distance, never parry's intersection test,
    /// which calls hulls a millimetre apart touching) and measured again once its bodies may
    /// have moved by that much.
    fn apart_over_dof(&self, (a, b): (&[usize], &[usize]), d: usize, q: &[f32]) -> bool {
        let model = self.model;
        let limits = model.dof_limits()[d];
        let (lo, hi) = if limits.is_bounded() {
            (limits.lower, limits.upper)
        } else {
            (-std::f32::consts::PI, std::f32::consts::PI)
        };
        let (mut from, mut to) = (q.to_vec(), q.to_vec());
        (from[d], to[d]) = (lo, hi);
        let speed: Vec<f32> = (0..model.joints().len())
            .map(|j| (model.joint_value(j, &to) - model.joint_value(j, &from)).abs())
            .collect();
        // Each pair of shapes, its relative speed bound and when it is measured next.
        let mut items: Vec<(usize, usize, f32, f32)> = Vec::new();
        for &i in a {
            for &j in b {
                let rate =
                    self.reach
                        .rate(&speed, body(&self.shapes[i]), Some(body(&self.shapes[j])));
                items.push((i, j, rate, 0.0));
            }
        }
        let (mut t, mut poses) = (0.0f32, Vec::new());
        loop {
            from[d] = lo + t * (hi - lo);
            model.link_poses_into(Pose::IDENTITY, &from, &mut poses);
            for (i, j, rate, next) in items.iter_mut() {
                if *next > t + SWEEP_BATCH {
                    continue;
                }
                let gap = self.gap(*i, *j, &poses);
                if gap < NEVER_MARGIN {
                    return false;
                }
                *next = if *rate > 0.0 {
                    t + gap / *rate
                } else {
                    f32::INFINITY
                };
            }
            t = items.iter().map(|i| i.3).fold(f32::INFINITY, f32::min);
            if t > 1.0 {
                return true;
            }
        }
    }

    /// A proven lower bound on the distance of shapes `i` and `j`, their links at `poses`:
    /// their balls' where that settles it, else the exact one.
    fn gap(&self, i: usize, j: usize, poses: &[Pose]) -> f32 {
        let (ei, ej) = (&self.shapes[i], &self.shapes[j]);
        let (pi, pj) = (
            poses[ei.link] * ei.local_pose,
            poses[ej.link] * ej.local_pose,
        );
        let balls = (pi * ei.ball.0 - pj * ej.ball.0).length() - ei.ball.1 - ej.ball.1;
        if balls >= SWEEP_CHEAP_ENOUGH {
            return balls;
        }
        lower_bound_distance(&pi, &*ei.shape.0, &pj, &*ej.shape.0).max(balls)
    }
}

/// Pairs due within this much of a sweep (of its parameter, 0 to 1) are measured together.
const SWEEP_BATCH: f32 = 0.001;

/// A bound from the shapes' balls of at least this (metres) is used as it is in a sweep.
const SWEEP_CHEAP_ENOUGH: f32 = 0.01;

/// Which of the pairs of links `candidates` collide in at least `options.always_fraction` of
/// `options.samples` random configurations. A pair is no longer tested once it has missed in
/// too many samples to reach the fraction, which settles most pairs in a few dozen samples;
/// the answer is that of testing every pair in every sample.
fn always_colliding(
    model: &AgentModel,
    candidates: &[(usize, usize)],
    options: &SelfCollisionOptions,
    collide: impl Fn(&[Pose], usize, usize) -> bool,
) -> Vec<bool> {
    let n = options.samples;
    if n == 0 {
        return vec![false; candidates.len()];
    }
    let can_reach = |misses: usize| (n - misses) as f32 / n as f32 >= options.always_fraction;
    let (mut counts, mut misses) = (
        vec![0usize; candidates.len()],
        vec![0usize; candidates.len()],
    );
    let mut rng = fastrand::Rng::with_seed(options.seed);
    let mut poses = Vec::new();
    for _ in 0..n {
        if !misses.iter().any(|&m| can_reach(m)) {
            break;
        }
        let q = model.random_configuration(&mut rng);
        model.link_poses_into(Pose::IDENTITY, q.as_slice(), &mut poses);
        for (k, &(a, b)) in candidates.iter().enumerate() {
            if can_reach(misses[k]) {
                if collide(&poses, a, b) {
                    counts[k] += 1;
                } else {
                    misses[k] += 1;
                }
            }
        }
    }
    counts
        .iter()
        .zip(&misses)
        .map(|(&c, &m)| can_reach(m) && c as f32 / n as f32 >= options.always_fraction)
        .collect()
}

/// A model's shapes by link, and each link's capsule, for finding the pairs to leave out.
struct Bodies<'a> {
    shapes: &'a [ShapeEntry],
    /// Per link, its shapes' indices into `shapes`.
    by_link: &'a [Vec<usize>],
    capsules: &'a [Option<LinkCapsule>],
}

impl Bodies<'_> {
    /// Whether links `a` and `b` collide with the links at `poses`.
    fn collide(&self, poses: &[Pose], a: usize, b: usize) -> bool {
        let capsules = (self.capsules[a].as_ref(), self.capsules[b].as_ref());
        if LinkCapsule::gap_of(capsules.0, &poses[a], capsules.1, &poses[b]) > 0.0 {
            return false; // the links' capsules, which hold their shapes, are apart
        }
        for ca in self.by_link[a].iter().map(|&i| &self.shapes[i]) {
            let pa = poses[a] * ca.local_pose;
            for cb in self.by_link[b].iter().map(|&i| &self.shapes[i]) {
                let pb = poses[b] * cb.local_pose;
                // Exact tests behind bounds that hold the shapes (no tolerances), as the pairs
                // to leave out were always found: which pairs a model checks does not change
                // with how fast checks are.
                if (pa.translation - pb.translation).length() <= ca.radius + cb.radius
                    && intersects(&pa, &*ca.shape.0, &pb, &*cb.shape.0)
                {
                    return true;
                }
            }
        }
        false
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use parry3d::bounding_volume::BoundingVolume;

    /// A 10 x 6 x 4 cm box as a convex polyhedron (a mesh's hull), turned by `yaw` about z.
    fn hull_entry(yaw: f32) -> (ShapeEntry, Pose) {
        let mut corners = Vec::new();
        for x in [-0.05, 0.05] {
            for y in [-0.03, 0.03] {
                for z in [-0.02, 0.02] {
                    corners.push(Vector::new(x, y, z));
                }
            }
        }
        let shape = SharedShape::convex_hull(&corners).expect("hull");
        let entry = ShapeEntry::new(0, Pose::IDENTITY, shape, 0.07);
        (
            entry,
            Pose::from_rotation(parry3d::math::Rotation::from_rotation_z(yaw)),
        )
    }

    #[test]
    fn a_polyhedron_is_tested_through_its_bounding_box_with_the_exact_answer() {
        let wall = Cuboid::new(Vector::new(0.01, 0.5, 0.5));
        for yaw in [0.0f32, 0.3, 1.0] {
            let (entry, pose) = hull_entry(yaw);
            assert!(entry.bounds.is_some());
            // The hull's extent along x when turned by `yaw`.
            let reach = 0.05 * yaw.cos() + 0.03 * yaw.sin();
            for (gap, hit) in [(0.003, false), (-0.001, true), (0.0005, false)] {
                let at = Pose::from_translation(Vector::X * (reach + 0.01 + gap));
                assert_eq!(entry.hits(&pose, &wall, &at), hit, "yaw {yaw}, gap {gap}");
                // Against another polyhedron the same (its box, then its shape).
                let (other, _) = hull_entry(0.0);
                let at = Pose::from_translation(Vector::X * (reach + 0.05 + gap));
                assert_eq!(
                    entry.hits_shape(&pose, &other, &at),
                    hit,
                    "yaw {yaw}, gap {gap}"
                );
            }
            // The AABB from the box holds the exact one.
            let exact = entry.shape.compute_aabb(&pose);
            let boxed = entry.aabb(&pose);
            assert!(boxed.contains(&exact), "{boxed:?} {exact:?}");
        }
    }

    /// The exact distance between the shapes of links `a` and `b` at `links`.
    fn link_distance(m: &SelfCollisionModel, a: usize, b: usize, links: &[Pose]) -> f32 {
        let of = |l: usize| m.shapes.iter().filter(move |e| e.link == l);
        of(a)
            .flat_map(|ea| of(b).map(move |eb| (ea, eb)))
            .map(|(ea, eb)| {
                let (pa, pb) = (links[a] * ea.local_pose, links[b] * eb.local_pose);
                parry3d::query::distance(&pa, &*ea.shape.0, &pb, &*eb.shape.0)
                    .map_or(0.0, |d| d.distance)
            })
            .fold(f32::INFINITY, f32::min)
    }

    #[test]
    fn shape_capsules_never_put_polyhedra_further_apart_than_they_are() {
        // Long random hulls (a forearm's pieces) on two links, at random poses near each other.
        let mut rng = fastrand::Rng::with_seed(3);
        let mut hull = |link: usize| {
            let half = Vector::new(0.02 + 0.03 * rng.f32(), 0.03, 0.08 + 0.1 * rng.f32());
            let points: Vec<Vector> = (0..200)
                .map(|_| {
                    let v = Vector::new(rng.f32() - 0.5, rng.f32() - 0.5, rng.f32() - 0.5);
                    v.normalize() * half
                })
                .collect();
            let shape = SharedShape::convex_hull(&points).expect("hull");
            let at = Pose::from_rotation(parry3d::math::Rotation::from_rotation_x(rng.f32()));
            ShapeEntry::new(link, at, shape, 0.3)
        };
        let (ea, eb) = (hull(1), hull(2));
        assert!(ea.capsule.is_some() && eb.capsule.is_some());
        let (mut told, mut near) = (0, 0);
        for _ in 0..2000 {
            let axis = Vector::new(rng.f32() - 0.5, rng.f32() - 0.5, rng.f32() - 0.5);
            let turn = parry3d::math::Rotation::from_scaled_axis(axis * 6.0);
            let offset = Vector::new(rng.f32() - 0.5, rng.f32() - 0.5, rng.f32() - 0.5) * 0.5;
            let (la, lb) = (Pose::IDENTITY, Pose::from_parts(offset, turn));
            let bound = ea.capsule_gap(&la, &eb, &lb);
            let (pa, pb) = (la * ea.local_pose, lb * eb.local_pose);
            let exact = parry3d::query::distance(&pa, &*ea.shape.0, &pb, &*eb.shape.0)
                .unwrap()
                .distance;
            assert!(bound <= exact + 1e-5, "{bound} above {exact}");
            near += usize::from(exact < 0.02);
            told += usize::from(exact > 0.0 && bound > 0.5 * exact);
        }
        // Not vacuous: pairs come near, and the bound is within half the distance for most.
        assert!(near > 50 && told > 1000, "{near} near, {told} told apart");
    }

    #[test]
    fn link_capsules_never_put_links_further_apart_than_their_shapes() {
        // The hand-written PR2 (boxes, capsules, cylinders, spheres), its right forearm made of
        // two boxes as mesh hulls.
        let path = format!("{}/../../models/pr2.urdf", env!("CARGO_MANIFEST_DIR"));
        let model = Arc::new(AgentModel::from_urdf_file(&path).unwrap());
        let mut m = SelfCollisionModel::new(model.clone(), &SelfCollisionOptions::default());
        let hull_link = model.link_id("r_forearm_link").unwrap();
        m.shapes.retain(|s| s.link != hull_link);
        for (yaw, x) in [(0.4f32, 0.0f32), (1.2, 0.12)] {
            let (mut e, turn) = hull_entry(yaw);
            (e.link, e.local_pose) = (hull_link, Pose::from_translation(Vector::X * x) * turn);
            m.shapes.push(e);
        }
        let points: Vec<Vector> = m
            .shapes
            .iter()
            .filter(|e| e.link == hull_link)
            .flat_map(|e| e.points())
            .collect();
        m.link_capsules[hull_link] = LinkCapsule::enclosing(&points);
        let with_shapes: Vec<usize> = (0..m.link_capsules.len())
            .filter(|&l| m.shapes.iter().any(|e| e.link == l))
            .collect();
        let mut rng = fastrand::Rng::with_seed(8);
        let (mut near, mut far, mut apart) = (0, 0, 0);
        for _ in 0..60 {
            let q = model.random_configuration(&mut rng);
            let links = model.link_poses(Pose::IDENTITY, q.as_slice());
            for (i, &a) in with_shapes.iter().enumerate() {
                for &b in &with_shapes[i + 1..] {
                    let bound = m.capsules_gap(a, b, &links);
                    let exact = link_distance(&m, a, b, &links);
                    assert!(bound <= exact + 1e-5, "{a} {b}: {bound} above {exact}");
                    near += usize::from(exact < 0.05);
                    far += usize::from(exact > 0.1);
                    apart += usize::from(exact > 0.1 && bound > 0.0);
                }
            }
        }
        // Not vacuous: many pairs come near, and the capsules tell most far ones apart.
        assert!(
            near > 500 && apart * 4 > far * 3,
            "{near} near; {apart} of {far} far apart"
        );
    }
}
