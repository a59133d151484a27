//! A capsule per link that holds all of the link's collision shapes: a bound between the link's
//! sphere and its shapes. A long link (a forearm, an upper arm of a real robot, a dozen convex
//! pieces) fills little of its sphere, so two such links whose spheres overlap are mostly far
//! apart; their capsules tell so at the cost of one segment-to-segment distance, before their
//! shapes are tested pair by pair.

use parry3d::math::{Pose, Vector};

/// Added to a capsule's radius against rounding (metres).
const MARGIN: f32 = 1e-5;

/// A capsule in a link's frame: the points within `radius` of the segment `a`-`b`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(super) struct LinkCapsule {
    pub(super) a: Vector,
    pub(super) b: Vector,
    pub(super) radius: f32,
}

impl LinkCapsule {
    /// A small capsule that holds `points` (and so their convex hull): along their principal
    /// axis or a coordinate axis, whichever gives the least volume. `None` without points.
    pub(super) fn enclosing(points: &[Vector]) -> Option<LinkCapsule> {
        if points.is_empty() {
            return None;
        }
        let centre = points.iter().fold(Vector::ZERO, |s, p| s + *p) / points.len() as f32;
        [
            principal_axis(points, centre),
            Vector::X,
            Vector::Y,
            Vector::Z,
        ]
        .into_iter()
        .map(|axis| fit(points, centre, axis))
        .min_by(|x, y| x.volume().total_cmp(&y.volume()))
    }

    /// The capsule's segment in the world, its link at `pose`.
    pub(super) fn at(&self, pose: &Pose) -> (Vector, Vector) {
        (*pose * self.a, *pose * self.b)
    }

    /// A lower bound on the distance between this capsule, its link at `pose`, and `other`,
    /// its link at `other_pose` (negative where they overlap).
    pub(super) fn gap(&self, pose: &Pose, other: &LinkCapsule, other_pose: &Pose) -> f32 {
        let ((pa, qa), (pb, qb)) = (self.at(pose), other.at(other_pose));
        segment_distance(pa, qa, pb, qb) - self.radius - other.radius
    }

    /// [`LinkCapsule::gap`] between two bodies that may have no capsule: negative infinity (no
    /// bound) where either has none.
    pub(super) fn gap_of(
        a: Option<&LinkCapsule>,
        pa: &Pose,
        b: Option<&LinkCapsule>,
        pb: &Pose,
    ) -> f32 {
        match (a, b) {
            (Some(a), Some(b)) => a.gap(pa, b, pb),
            _ => f32::NEG_INFINITY,
        }
    }

    /// A lower bound on the distance between this capsule, its link at `pose`, and the ball
    /// (`centre`, `radius`).
    pub(super) fn ball_gap(&self, pose: &Pose, centre: Vector, radius: f32) -> f32 {
        let (p, q) = self.at(pose);
        point_segment_distance(centre, p, q) - self.radius - radius
    }

    fn volume(&self) -> f32 {
        let r = self.radius;
        std::f32::consts::PI * r * r * ((self.b - self.a).length() + 4.0 / 3.0 * r)
    }
}

/// The capsule about the line through `centre` along `axis` (unit) that holds `points`: its
/// radius the points' greatest distance from the line, its segment as short as that radius
/// allows.
fn fit(points: &[Vector], centre: Vector, axis: Vector) -> LinkCapsule {
    let split = |p: &Vector| {
        let d = *p - centre;
        let t = d.dot(axis);
        (t, (d - axis * t).length())
    };
    let r = points.iter().map(|p| split(p).1).fold(0.0f32, f32::max);
    // A point at `t` along the axis, `rho` from it, is inside when the segment reaches to
    // within sqrt(r^2 - rho^2) of `t`.
    let (mut lo, mut hi) = (f32::INFINITY, f32::NEG_INFINITY);
    for p in points {
        let (t, rho) = split(p);
        let h = (r * r - rho * rho).max(0.0).sqrt();
        lo = lo.min(t + h);
        hi = hi.max(t - h);
    }
    if lo > hi {
        // Any point of [hi, lo] is within reach of every point: a ball.
        let mid = 0.5 * (lo + hi);
        (lo, hi) = (mid, mid);
    }
    LinkCapsule {
        a: centre + axis * lo,
        b: centre + axis * hi,
        radius: r + MARGIN,
    }
}

/// The unit direction along which `points` spread most (power iteration on their covariance),
/// or the x axis where they do not spread.
fn principal_axis(points: &[Vector], centre: Vector) -> Vector {
    let mut cov = [[0.0f32; 3]; 3];
    for p in points {
        let d = (*p - centre).to_array();
        for (i, row) in cov.iter_mut().enumerate() {
            for (j, c) in row.iter_mut().enumerate() {
                *c += d[i] * d[j];
            }
        }
    }
    let times = |v: Vector| {
        let v = v.to_array();
        Vector::from_array(cov.map(|row| row[0] * v[0] + row[1] * v[1] + row[2] * v[2]))
    };
    let mut v = Vector::new(1.0, 0.7, 0.3).normalize();
    for _ in 0..32 {
        let w = times(v);
        if w.length() <= f32::EPSILON {
            return Vector::X;
        }
        v = w.normalize();
    }
    v
}

/// The distance between segments `p1`-`q1` and `p2`-`q2` (Ericson, Real-Time Collision
/// Detection, 5.1.9), in double precision: rounding moves the closest points it finds by far
/// less than [`MARGIN`], even for segments all but parallel.
fn segment_distance(p1: Vector, q1: Vector, p2: Vector, q2: Vector) -> f32 {
    let wide = |v: Vector| [v.x as f64, v.y as f64, v.z as f64];
    let (w1, v1, w2, v2) = (wide(p1), wide(q1), wide(p2), wide(q2));
    let sub = |x: [f64; 3], y: [f64; 3]| [x[0] - y[0], x[1] - y[1], x[2] - y[2]];
    let dot = |x: [f64; 3], y: [f64; 3]| x[0] * y[0] + x[1] * y[1] + x[2] * y[2];
    let (d1, d2, r) = (sub(v1, w1), sub(v2, w2), sub(w1, w2));
    let (a, e, f) = (dot(d1, d1), dot(d2, d2), dot(d2, r));
    const TINY: f64 = 1e-18;
    let (s, t) = if a <= TINY && e <= TINY {
        (0.0, 0.0)
    } else if a <= TINY {
        (0.0, (f / e).clamp(0.0, 1.0))
    } else {
        let c = dot(d1, r);
        if e <= TINY {
            ((-c / a).clamp(0.0, 1.0), 0.0)
        } else {
            let b = dot(d1, d2);
            let denom = a * e - b * b;
            // Parallel: any point of the first segment will do; its end.
            let s = if denom > 1e-12 * a * e {
                ((b * f - c * e) / denom).clamp(0.0, 1.0)
            } else {
                0.0
            };
            let t = (b * s + f) / e;
            if t < 0.0 {
                ((-c / a).clamp(0.0, 1.0), 0.0)
            } else if t > 1.0 {
                (((b - c) / a).clamp(0.0, 1.0), 1.0)
            } else {
                (s, t)
            }
        }
    };
    let gap: [f64; 3] = std::array::from_fn(|i| r[i] + d1[i] * s - d2[i] * t);
    dot(gap, gap).sqrt() as f32
}

/// The distance from point `p` to the segment `a`-`b`.
fn point_segment_distance(p: Vector, a: Vector, b: Vector) -> f32 {
    let ab = b - a;
    let len2 = ab.length_squared();
    let t = if len2 > 0.0 {
        ((p - a).dot(ab) / len2).clamp(0.0, 1.0)
    } else {
        0.0
    };
    (p - (a + ab * t)).length()
}

#[cfg(test)]
mod tests {
    use super::*;
    use parry3d::math::Rotation;

    fn random_vector(rng: &mut fastrand::Rng, scale: f32) -> Vector {
        Vector::new(rng.f32() - 0.5, rng.f32() - 0.5, rng.f32() - 0.5) * (2.0 * scale)
    }

    /// The least distance between points of the two segments on a grid of `n` steps each
    /// (at most the true distance plus their lengths over `n`).
    fn sampled(p1: Vector, q1: Vector, p2: Vector, q2: Vector, n: usize) -> f32 {
        let at = |p: Vector, q: Vector, k: usize| p + (q - p) * (k as f32 / n as f32);
        (0..=n)
            .flat_map(|i| (0..=n).map(move |j| (at(p1, q1, i) - at(p2, q2, j)).length()))
            .fold(f32::INFINITY, f32::min)
    }

    #[test]
    fn segment_distances_are_the_least_distances_between_their_points() {
        let mut rng = fastrand::Rng::with_seed(5);
        for k in 0..1000 {
            let ends = [0; 4].map(|_| random_vector(&mut rng, 0.5));
            // Some segments degenerate to points, some parallel or all but, some crossing.
            let (p1, mut q1, p2, mut q2) = (ends[0], ends[1], ends[2], ends[3]);
            match k % 6 {
                0 => q1 = p1,
                1 => q2 = p2,
                2 => q2 = p2 + (q1 - p1) * 0.7,
                3 => q2 = p2 + (p1 + (q1 - p1) * 0.4 - p2) * 2.0,
                4 => q2 = p2 + (q1 - p1) * 0.7 + random_vector(&mut rng, 1e-5),
                _ => {}
            }
            let ours = segment_distance(p1, q1, p2, q2);
            let n = 300;
            let grid = sampled(p1, q1, p2, q2, n);
            let step = ((q1 - p1).length() + (q2 - p2).length()) / n as f32;
            assert!(ours <= grid + 1e-5, "case {k}: {ours} above {grid}");
            assert!(
                ours >= grid - step - 1e-5,
                "case {k}: {ours} far under {grid}"
            );
            let mid = p1 + (q1 - p1) * 0.3;
            assert!(point_segment_distance(mid, p2, q2) >= ours - 1e-5);
        }
    }

    #[test]
    fn the_capsule_holds_every_point_and_is_tight_for_a_rod() {
        let mut rng = fastrand::Rng::with_seed(6);
        // A rod 0.4 m long, 0.03 m thick, turned and moved: its capsule hugs it.
        let pose = Pose::from_parts(
            Vector::new(0.1, -0.2, 0.3),
            Rotation::from_scaled_axis(Vector::new(0.3, -0.8, 0.5)),
        );
        let rod: Vec<Vector> = (0..400)
            .map(|_| {
                let (x, y, z) = (rng.f32() - 0.5, rng.f32() - 0.5, rng.f32() - 0.5);
                pose * Vector::new(x * 0.4, y * 0.03, z * 0.03)
            })
            .collect();
        let c = LinkCapsule::enclosing(&rod).unwrap();
        for p in &rod {
            assert!(point_segment_distance(*p, c.a, c.b) <= c.radius);
        }
        assert!(c.radius < 0.025, "radius {}", c.radius);
        assert!(
            (c.b - c.a).length() < 0.4,
            "length {}",
            (c.b - c.a).length()
        );
        // A cloud of any shape is held too.
        for seed in 0..50 {
            let mut rng = fastrand::Rng::with_seed(seed);
            let n = 1 + rng.usize(..40);
            let cloud: Vec<Vector> = (0..n).map(|_| random_vector(&mut rng, 0.2)).collect();
            let c = LinkCapsule::enclosing(&cloud).unwrap();
            for p in &cloud {
                assert!(
                    point_segment_distance(*p, c.a, c.b) <= c.radius,
                    "seed {seed}"
                );
            }
        }
        assert!(LinkCapsule::enclosing(&[]).is_none());
    }
}
