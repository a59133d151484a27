//! Exact intersection tests of convex shapes, warm-started by the separating direction found
//! the last time the same pair was tested, and a support function that climbs a hull's vertex
//! graph instead of visiting every vertex.
//!
//! A planner checks an edge as a run of nearby configurations: a pair of shapes apart at one
//! step is almost always apart along the same direction at the next. The remembered direction
//! `n` (world frame) is tried first: if the farthest point of the first shape along `n` is
//! still below the nearest point of the second, the plane between them separates the shapes,
//! an exact certificate for two support calls. Otherwise parry's GJK runs from `n`. A hint
//! only orders the work: any hint, even a wrong or stale one, gives the exact answer.

use parry3d::math::{Pose, Vector};
use parry3d::query::details::intersection_test_support_map_support_map_with_params;
use parry3d::query::gjk::VoronoiSimplex;
use parry3d::shape::{ConvexPolyhedron, SupportMap};
use parry3d::transformation::convex_hull;

/// Hulls with more vertices than this get a [`ClimbingHull`]; below it a scan is as fast.
pub(super) const CLIMB_ABOVE: usize = 32;

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
    pub(super) fn new(hull: &ConvexPolyhedron) -> ClimbingHull {
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

/// A shape's support function for the separating-plane test: a climbing hull's, which can
/// start where the last test of the pair ended, or any other.
#[derive(Clone, Copy)]
pub(super) enum Support<'a> {
    Climb(&'a ClimbingHull),
    Map(&'a dyn SupportMap),
}

impl<'a> Support<'a> {
    /// As a support map, for GJK.
    pub(super) fn map(self) -> &'a dyn SupportMap {
        match self {
            Support::Climb(c) => c,
            Support::Map(m) => m,
        }
    }

    /// The largest `n . x` over the shape at `pose` (`n` in the world frame); `vertex` is
    /// where a climb starts and is left where it ended.
    fn top(self, pose: &Pose, n: Vector, vertex: &mut u32) -> f32 {
        match self {
            Support::Climb(c) => {
                let (v, p) = c.climb(pose.rotation.inverse() * n, *vertex);
                *vertex = v;
                n.dot(*pose * p)
            }
            Support::Map(m) => m.support_point(pose, n).dot(n),
        }
    }
}

/// What is remembered of a pair of shapes between tests: the last separating direction
/// (world frame; zero for none) and the vertices the climbs along it ended at.
#[derive(Clone, Copy, Debug)]
pub(super) struct PairHint {
    pub(super) dir: Vector,
    vertex: [u32; 2],
}

impl PairHint {
    /// Nothing known.
    pub(super) const NONE: PairHint = PairHint {
        dir: Vector::ZERO,
        vertex: [u32::MAX; 2],
    };
}

/// Whether the hint's direction is a plane that separates the two shapes (`a`'s farthest
/// point along it below `b`'s nearest: an exact certificate).
pub(super) fn hint_separates(
    hint: &mut PairHint,
    pose_a: &Pose,
    a: Support,
    pose_b: &Pose,
    b: Support,
) -> bool {
    let n = hint.dir;
    if n == Vector::ZERO {
        return false;
    }
    let [va, vb] = &mut hint.vertex;
    a.top(pose_a, n, va) < -b.top(pose_b, -n, vb)
}

/// GJK's exact test started from `hint`; where the shapes are apart, `hint` becomes the
/// separating direction found.
pub(super) fn gjk_warm(
    pose_a: &Pose,
    a: &dyn SupportMap,
    pose_b: &Pose,
    b: &dyn SupportMap,
    hint: &mut PairHint,
) -> bool {
    let pos12 = pose_a.inv_mul(pose_b);
    let init = (hint.dir != Vector::ZERO).then(|| pose_a.rotation.inverse() * hint.dir);
    let (hit, dir) = intersection_test_support_map_support_map_with_params(
        &pos12,
        a,
        b,
        &mut VoronoiSimplex::new(),
        init,
    );
    if !hit {
        hint.dir = pose_a.rotation * dir;
    }
    hit
}

/// The remembered separating directions of one checker's pairs: agent shape `i` and obstacle
/// `o` at `obstacle[i * obstacles + o]`, self-collision pair `p` at `self_pairs[p]`; zero
/// where none is known.
pub(super) struct PairHints {
    key: (usize, usize),
    pub(super) obstacle: Vec<PairHint>,
    pub(super) self_pairs: Vec<PairHint>,
}

/// Hints of more pairs than this are not kept (a scene of thousands of obstacles): at most
/// 5 MB per checker a thread keeps hints for.
const MAX_OBSTACLE_HINTS: usize = 1 << 18;

/// The hints of the last few checkers a thread used, keyed by their agent and obstacles.
#[derive(Default)]
pub(super) struct HintCache {
    recent: Vec<PairHints>,
}

impl HintCache {
    /// The hints for `key`, sized for `obstacle_pairs` and `self_pairs` (kept, most recent
    /// first, for four keys).
    pub(super) fn get(
        &mut self,
        key: (usize, usize),
        obstacle_pairs: usize,
        self_pairs: usize,
    ) -> &mut PairHints {
        match self.recent.iter().position(|h| h.key == key) {
            Some(i) => self.recent[..=i].rotate_right(1),
            None => {
                self.recent.truncate(3);
                self.recent.insert(
                    0,
                    PairHints {
                        key,
                        obstacle: Vec::new(),
                        self_pairs: Vec::new(),
                    },
                );
            }
        }
        let hints = &mut self.recent[0];
        let obstacle_pairs = if obstacle_pairs > MAX_OBSTACLE_HINTS {
            0
        } else {
            obstacle_pairs
        };
        hints.obstacle.resize(obstacle_pairs, PairHint::NONE);
        hints.self_pairs.resize(self_pairs, PairHint::NONE);
        hints
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use parry3d::math::Rotation;
    use parry3d::query;
    use parry3d::shape::{Ball, Cuboid};

    /// Whether `a` at `pose_a` and `b` at `pose_b` intersect, as a check tests a pair: the
    /// hint's plane first, then GJK started from it.
    fn intersect_warm(
        pose_a: &Pose,
        a: Support,
        pose_b: &Pose,
        b: Support,
        hint: &mut PairHint,
    ) -> bool {
        !hint_separates(hint, pose_a, a, pose_b, b)
            && gjk_warm(pose_a, a.map(), pose_b, b.map(), hint)
    }

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
    fn a_warm_test_is_sound_whatever_the_hint() {
        let hull = ConvexPolyhedron::from_convex_hull(&sphere_points(500, 9)).unwrap();
        let climbing = ClimbingHull::new(&hull);
        let cuboid = Cuboid::new(Vector::new(0.1, 0.05, 0.2));
        let ball = Ball::new(0.07);
        let mut rng = fastrand::Rng::with_seed(11);
        let mut hits = 0;
        let mut hint = PairHint::NONE;
        for k in 0..4000 {
            let pose = |rng: &mut fastrand::Rng| {
                Pose::from_parts(
                    Vector::new(rng.f32() - 0.5, rng.f32() - 0.5, rng.f32() - 0.5) * 0.6,
                    Rotation::from_scaled_axis(Vector::new(rng.f32(), rng.f32(), rng.f32()) * 3.0),
                )
            };
            let (pa, pb) = (pose(&mut rng), pose(&mut rng));
            if k % 7 == 0 {
                hint.dir = Vector::new(rng.f32() - 0.5, rng.f32() - 0.5, rng.f32() - 0.5);
            }
            let other = Support::Map(if k % 2 == 0 { &cuboid } else { &ball });
            let distance = if k % 2 == 0 {
                query::distance(&pa, &hull, &pb, &cuboid)
            } else {
                query::distance(&pa, &hull, &pb, &ball)
            };
            let distance = distance.unwrap().distance;
            let hit = intersect_warm(&pa, Support::Climb(&climbing), &pb, other, &mut hint);
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
        assert!((500..3500).contains(&hits), "{hits} of 4000 intersect");
    }
}
