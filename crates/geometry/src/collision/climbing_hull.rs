//! A support function that climbs a hull's vertex graph instead of visiting every vertex, for
//! GJK's exact tests of the large hulls of real robots' meshes.
//!
//! (Warm-starting parry's GJK from each pair's last separating direction, kept between checks,
//! was tried on 2026-12-06 and removed: in one plan it let a human's reach pass through a
//! robot finger that a fresh check finds; the cause was not found. A kept axis is now only
//! tried as a proof of its own, the shapes' supports along it, before a cold GJK: see
//! `ShapeEntry::hits_shape_with_axis`.)

use std::collections::HashMap;
use std::sync::atomic::{AtomicU32, Ordering};
use std::sync::{Arc, Mutex, OnceLock};

use parry3d::bounding_volume::Aabb;
use parry3d::math::{Pose, Vector};
use parry3d::query::details::intersection_test_support_map_support_map_with_params;
use parry3d::query::gjk::VoronoiSimplex;
use parry3d::shape::{ConvexPolyhedron, Shape, SharedShape, SupportMap};
use parry3d::transformation::convex_hull;

/// Hulls with more vertices than this get a [`ClimbingHull`]; below it a scan is as fast.
const CLIMB_ABOVE: usize = 32;

/// The most hull vertices whose climbing supports [`climbing_hull_of`] keeps, with their
/// shapes (about 70 bytes a vertex: some 70 MiB; the real PR2 has 8,354); past it the kept
/// ones are dropped, and made again as asked.
const MAX_KEPT_VERTICES: usize = 1 << 20;

/// The climbing support of `shape`, a convex polyhedron of more than [`CLIMB_ABOVE`]
/// vertices, made once per shape (its `Arc`) and shared by the collision checks and the
/// grippers' boxes; `None` for any other shape. The shape is kept with it, so that its
/// address names it while kept.
pub(super) fn climbing_hull_of(shape: &SharedShape) -> Option<Arc<ClimbingHull>> {
    /// The kept supports by shape address, and their vertices in all.
    type Kept = (HashMap<usize, (SharedShape, Arc<ClimbingHull>)>, usize);
    static KEPT: OnceLock<Mutex<Kept>> = OnceLock::new();
    let hull = shape
        .as_convex_polyhedron()
        .filter(|hull| hull.points().len() > CLIMB_ABOVE)?;
    let key = Arc::as_ptr(&shape.0) as *const () as usize;
    let mut guard = KEPT
        .get_or_init(Default::default)
        .lock()
        .unwrap_or_else(|e| e.into_inner());
    let (kept, vertices) = &mut *guard;
    if let Some((_, climb)) = kept.get(&key) {
        return Some(climb.clone());
    }
    let climb = Arc::new(ClimbingHull::new(hull));
    if *vertices + climb.points.len() > MAX_KEPT_VERTICES {
        kept.clear();
        *vertices = 0;
    }
    *vertices += climb.points.len();
    kept.insert(key, (shape.clone(), climb.clone()));
    Some(climb)
}

/// A convex polyhedron's support function by hill climbing over its vertex graph: from the
/// best of a few extreme vertices, move to a better neighbour until none is better. On a
/// convex polytope a vertex no neighbour improves is a global maximum of any linear function,
/// so the answer is exact; it visits tens of vertices where a scan visits all.
pub(super) struct ClimbingHull {
    points: Vec<Vector>,
    /// Neighbours of vertex `v`: `neighbours[offsets[v]..offsets[v + 1]]`.
    offsets: Vec<u32>,
    neighbours: Vec<u32>,
    /// The vertices extreme along the axes and the cube's diagonals, where climbs start.
    starts: Vec<u32>,
}

impl ClimbingHull {
    /// The climbing support of `hull`: the vertices of its triangulated surface, neighbours
    /// where a triangle joins them (parry's hull merges coplanar triangles into polygons, whose
    /// vertices would all be neighbours of each other).
    fn new(hull: &ConvexPolyhedron) -> ClimbingHull {
        let (points, triangles) = convex_hull(hull.points());
        let mut adjacent: Vec<Vec<u32>> = vec![Vec::new(); points.len()];
        for [a, b, c] in triangles {
            for (u, v) in [(a, b), (b, c), (c, a)] {
                adjacent[u as usize].push(v);
                adjacent[v as usize].push(u);
            }
        }
        let (mut offsets, mut neighbours) = (vec![0u32], Vec::new());
        for mut list in adjacent {
            list.sort_unstable();
            list.dedup();
            neighbours.extend(list);
            offsets.push(neighbours.len() as u32);
        }
        let mut starts: Vec<u32> = start_directions()
            .map(|d| scan(&points, d) as u32)
            .collect();
        starts.sort_unstable();
        starts.dedup();
        ClimbingHull {
            points,
            offsets,
            neighbours,
            starts,
        }
    }

    /// The vertex farthest along `dir` and its index, climbing from vertex `from` where it is
    /// one (the last answer for a nearby direction: a step or two away), else from the best
    /// of the start vertices.
    pub(super) fn climb(&self, dir: Vector, from: u32) -> (u32, Vector) {
        let (mut v, mut best) = match self.points.get(from as usize) {
            Some(p) => (from as usize, p.dot(dir)),
            None => {
                let mut v = self.starts[0] as usize;
                let mut best = self.points[v].dot(dir);
                for &s in &self.starts[1..] {
                    let d = self.points[s as usize].dot(dir);
                    if d > best {
                        (v, best) = (s as usize, d);
                    }
                }
                (v, best)
            }
        };
        // Each move strictly improves, so the climb ends.
        loop {
            let mut moved = false;
            let around = &self.neighbours[self.offsets[v] as usize..self.offsets[v + 1] as usize];
            for &n in around {
                let d = self.points[n as usize].dot(dir);
                if d > best {
                    (v, best, moved) = (n as usize, d, true);
                }
            }
            if !moved {
                return (v as u32, self.points[v]);
            }
        }
    }
}

/// The bounding boxes of a large hull at any pose, found by climbing to its extreme vertex
/// along each axis instead of moving every vertex: the box parry's `compute_aabb` gives (the
/// same extreme vertices, moved the same way). Each climb starts where the last one along the
/// same axis ended (a box asked for at nearby poses is a step or two away); the answer does
/// not depend on where a climb starts.
pub struct HullBounds {
    hull: Arc<ClimbingHull>,
    /// The vertex each of the six climbs (+x, -x, +y, -y, +z, -z) last ended at.
    last: [AtomicU32; 6],
}

impl Clone for HullBounds {
    fn clone(&self) -> HullBounds {
        HullBounds {
            hull: self.hull.clone(),
            last: std::array::from_fn(|k| AtomicU32::new(self.last[k].load(Ordering::Relaxed))),
        }
    }
}

impl std::fmt::Debug for HullBounds {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "HullBounds({} vertices)", self.hull.points.len())
    }
}

impl HullBounds {
    /// For a convex polyhedron of more than a few dozen vertices (its climbing support shared);
    /// `None` for any other shape, whose own `compute_aabb` is as cheap.
    pub fn of(shape: &SharedShape) -> Option<HullBounds> {
        climbing_hull_of(shape).map(|hull| HullBounds {
            hull,
            last: std::array::from_fn(|_| AtomicU32::new(u32::MAX)),
        })
    }

    /// The hull's bounding box at `pose`.
    pub fn aabb(&self, pose: &Pose) -> Aabb {
        let to_local = pose.rotation.inverse();
        let extreme = |k: usize, dir: Vector| {
            let (v, p) = self.hull.climb(dir, self.last[k].load(Ordering::Relaxed));
            self.last[k].store(v, Ordering::Relaxed);
            *pose * p
        };
        let (mut mins, mut maxs) = (Vector::ZERO, Vector::ZERO);
        for (i, axis) in [Vector::X, Vector::Y, Vector::Z].into_iter().enumerate() {
            let d = to_local * axis;
            maxs[i] = extreme(2 * i, d)[i];
            mins[i] = extreme(2 * i + 1, -d)[i];
        }
        Aabb::new(mins, maxs)
    }

    /// Whether the hull at `pose` meets `other` at `other_pose`: GJK with the hull's climbing
    /// support, from its default start, where `other` has a support function (`None` where
    /// not).
    pub fn intersects(&self, pose: &Pose, other: &dyn Shape, other_pose: &Pose) -> Option<bool> {
        let b = other.as_support_map()?;
        Some(gjk(pose, &*self.hull, other_pose, b))
    }
}

/// The 26 directions of the cube's faces, edges and corners.
fn start_directions() -> impl Iterator<Item = Vector> {
    (0..27).filter(|&k| k != 13).map(|k| {
        Vector::new(
            (k % 3) as f32 - 1.0,
            ((k / 3) % 3) as f32 - 1.0,
            (k / 9) as f32 - 1.0,
        )
    })
}

/// Index of the point farthest along `dir`, by visiting every point.
fn scan(points: &[Vector], dir: Vector) -> usize {
    let mut best = (0, f32::NEG_INFINITY);
    for (i, p) in points.iter().enumerate() {
        let d = p.dot(dir);
        if d > best.1 {
            best = (i, d);
        }
    }
    best.0
}

impl SupportMap for ClimbingHull {
    fn local_support_point(&self, dir: Vector) -> Vector {
        self.climb(dir, u32::MAX).1
    }
}

/// GJK's exact intersection test of `a` at `pose_a` and `b` at `pose_b`, from its default
/// start.
pub(super) fn gjk(pose_a: &Pose, a: &dyn SupportMap, pose_b: &Pose, b: &dyn SupportMap) -> bool {
    intersection_test_support_map_support_map_with_params(
        &pose_a.inv_mul(pose_b),
        a,
        b,
        &mut VoronoiSimplex::new(),
        None,
    )
    .0
}

#[cfg(test)]
mod tests {
    use super::*;
    use parry3d::math::Rotation;
    use parry3d::query;
    use parry3d::shape::{Ball, Cuboid};

    fn sphere_points(n: usize, seed: u64) -> Vec<Vector> {
        let mut rng = fastrand::Rng::with_seed(seed);
        (0..n)
            .map(|_| {
                let v = Vector::new(rng.f32() - 0.5, rng.f32() - 0.5, rng.f32() - 0.5);
                v.normalize() * (0.1 + 0.002 * rng.f32()) * Vector::new(1.0, 0.6, 1.5)
            })
            .collect()
    }

    #[test]
    fn the_climb_finds_the_farthest_vertex_in_every_direction() {
        let hull = ConvexPolyhedron::from_convex_hull(&sphere_points(2000, 3)).unwrap();
        assert!(
            hull.points().len() > 100,
            "{} vertices",
            hull.points().len()
        );
        let climbing = ClimbingHull::new(&hull);
        let mut rng = fastrand::Rng::with_seed(5);
        let mut last = u32::MAX;
        for k in 0..5000 {
            let d = Vector::new(rng.f32() - 0.5, rng.f32() - 0.5, rng.f32() - 0.5);
            let scanned = hull.points()[scan(hull.points(), d)].dot(d);
            assert_eq!(
                climbing.local_support_point(d).dot(d),
                scanned,
                "direction {d:?}"
            );
            // From wherever the last climb ended, or from a vertex out of range.
            let from = if k % 10 == 0 { u32::MAX - 1 } else { last };
            let (v, p) = climbing.climb(d, from);
            assert_eq!(p.dot(d), scanned, "direction {d:?} from {from}");
            last = v;
        }
    }

    #[test]
    fn a_test_with_the_climbing_support_is_sound() {
        let hull = ConvexPolyhedron::from_convex_hull(&sphere_points(500, 9)).unwrap();
        let climbing = ClimbingHull::new(&hull);
        let cuboid = Cuboid::new(Vector::new(0.1, 0.05, 0.2));
        let ball = Ball::new(0.07);
        let mut rng = fastrand::Rng::with_seed(11);
        let mut hits = 0;
        for k in 0..4000 {
            let pose = |rng: &mut fastrand::Rng| {
                Pose::from_parts(
                    Vector::new(rng.f32() - 0.5, rng.f32() - 0.5, rng.f32() - 0.5) * 0.6,
                    Rotation::from_scaled_axis(Vector::new(rng.f32(), rng.f32(), rng.f32()) * 3.0),
                )
            };
            let (pa, pb) = (pose(&mut rng), pose(&mut rng));
            let other: &dyn SupportMap = if k % 2 == 0 { &cuboid } else { &ball };
            let distance = if k % 2 == 0 {
                query::distance(&pa, &hull, &pb, &cuboid)
            } else {
                query::distance(&pa, &hull, &pb, &ball)
            };
            let distance = distance.unwrap().distance;
            let hit = gjk(&pa, &climbing, &pb, other);
            // Apart only where apart; in contact where GJK may be (within millimetres).
            assert!(
                hit || distance > 0.0,
                "case {k}: apart at distance {distance}"
            );
            assert!(
                !hit || distance < 0.01,
                "case {k}: contact at distance {distance}"
            );
            hits += hit as usize;
        }
        assert!((200..3800).contains(&hits), "{hits} of 4000 intersect");
    }

    #[test]
    fn hull_bounds_are_the_boxes_parry_computes() {
        let hull = ConvexPolyhedron::from_convex_hull(&sphere_points(800, 4)).unwrap();
        let shape = SharedShape::new(hull);
        let bounds = HullBounds::of(&shape).unwrap();
        let mut rng = fastrand::Rng::with_seed(8);
        for _ in 0..2000 {
            let pose = Pose::from_parts(
                Vector::new(rng.f32() - 0.5, rng.f32() - 0.5, rng.f32() - 0.5) * 4.0,
                Rotation::from_scaled_axis(Vector::new(rng.f32(), rng.f32(), rng.f32()) * 6.0),
            );
            let (a, b) = (bounds.aabb(&pose), shape.compute_aabb(&pose));
            assert_eq!((a.mins, a.maxs), (b.mins, b.maxs), "{pose:?}");
        }
        assert!(HullBounds::of(&SharedShape::cuboid(1.0, 1.0, 1.0)).is_none());
    }
}
