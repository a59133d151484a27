//! Where a ray first meets a capsule or a cylinder, in closed form.
//!
//! parry casts rays against these shapes by GJK on their support maps, which is exact but
//! costs tens of support-point steps a ray; the visibility measure casts thousands of rays per
//! object against people's capsules and the cups and links nearby, and spent most of its time
//! there. A capsule is the points within `radius` of a segment; a cylinder is parry's, its axis
//! along the local y axis. Solid: a ray that starts inside hits at 0.

use parry3d::math::{Pose, Vector};
use parry3d::query::Ray;
use parry3d::shape::{Capsule, Cylinder, Shape};

/// Whether rays meet `shape` in closed form here (a capsule or a cylinder).
pub fn closed_form(shape: &dyn Shape) -> bool {
    shape.as_capsule().is_some() || shape.as_cylinder().is_some()
}

/// The first hit of `ray` (in the shape's frame) with `shape` at a parameter in `[0, max]`:
/// `Some(answer)` for a capsule or a cylinder, `None` for another shape (ask parry).
fn first_hit(shape: &dyn Shape, ray: &Ray, max: f32) -> Option<Option<f32>> {
    if let Some(c) = shape.as_capsule() {
        return Some(capsule_first_hit(c, ray, max));
    }
    if let Some(c) = shape.as_cylinder() {
        return Some(cylinder_first_hit(c, ray, max));
    }
    None
}

/// The first hit of world `ray` with `shape` at `pose` within `max` (solid): in closed form
/// for a capsule or a cylinder, by parry otherwise.
pub fn cast_ray(shape: &dyn Shape, pose: &Pose, ray: &Ray, max: f32) -> Option<f32> {
    let local = ray.inverse_transform_by(pose);
    match first_hit(shape, &local, max) {
        Some(hit) => hit,
        None => shape.cast_local_ray(&local, max, true),
    }
}

/// The first parameter in `[0, max]` where `ray` is within the capsule.
fn capsule_first_hit(c: &Capsule, ray: &Ray, max: f32) -> Option<f32> {
    let (a, b, r) = (c.segment.a, c.segment.b, c.radius);
    let axis = b - a;
    let len2 = axis.length_squared();
    if len2 <= f32::EPSILON {
        return sphere_first_hit(a, r, ray, max);
    }
    // The infinite cylinder around the axis, then the two end spheres: the first hit of the
    // capsule is the least of the cylinder's (inside the segment's span) and the spheres'.
    let mut best: Option<f32> = None;
    let mut keep = |t: f32| {
        if (0.0..=max).contains(&t) && best.is_none_or(|b| t < b) {
            best = Some(t);
        }
    };
    // Where the ray enters the infinite cylinder beside the segment; entering it beyond an
    // end, the ray meets that end's sphere first (or never enters the capsule there).
    if let Some((t0, t1)) = infinite_cylinder_interval(a, axis, len2, r, ray) {
        let t = t0.max(0.0);
        let s = (ray.point_at(t) - a).dot(axis) / len2;
        if t <= t1 && (0.0..=1.0).contains(&s) {
            keep(t);
        }
    }
    for centre in [a, b] {
        if let Some(t) = sphere_first_hit(centre, r, ray, max) {
            keep(t);
        }
    }
    best
}

/// The parameters `[t0, t1]` where `ray` is within `r` of the line through `a` along `axis`
/// (`len2` its squared length); `None` when never. A ray along the axis, within `r`: always.
fn infinite_cylinder_interval(
    a: Vector,
    axis: Vector,
    len2: f32,
    r: f32,
    ray: &Ray,
) -> Option<(f32, f32)> {
    // Components perpendicular to the axis.
    let perp = |v: Vector| v - axis * (v.dot(axis) / len2);
    let o = perp(ray.origin - a);
    let d = perp(ray.dir);
    quadratic_interval(
        d.length_squared(),
        2.0 * o.dot(d),
        o.length_squared() - r * r,
    )
}

/// Where `qa t² + qb t + qc <= 0`, as an interval; with `qa` about 0, everywhere or nowhere by
/// the sign of `qc` (a ray parallel to the axis).
fn quadratic_interval(qa: f32, qb: f32, qc: f32) -> Option<(f32, f32)> {
    if qa <= 1e-12 {
        return (qc <= 0.0).then_some((f32::NEG_INFINITY, f32::INFINITY));
    }
    let disc = qb * qb - 4.0 * qa * qc;
    if disc < 0.0 {
        return None;
    }
    let s = disc.sqrt();
    // The numerically stable pair of roots.
    let q = -0.5 * (qb + s.copysign(qb));
    let (mut t0, mut t1) = if q == 0.0 {
        (0.0, 0.0)
    } else {
        (q / qa, qc / q)
    };
    if t0 > t1 {
        std::mem::swap(&mut t0, &mut t1);
    }
    Some((t0, t1))
}

/// The first parameter in `[0, max]` where `ray` is within `r` of `centre`.
fn sphere_first_hit(centre: Vector, r: f32, ray: &Ray, max: f32) -> Option<f32> {
    let o = ray.origin - centre;
    let d = ray.dir;
    let (t0, t1) = quadratic_interval(
        d.length_squared(),
        2.0 * o.dot(d),
        o.length_squared() - r * r,
    )?;
    let t = t0.max(0.0);
    (t <= t1 && t <= max).then_some(t)
}

/// The first parameter in `[0, max]` where `ray` is inside parry's cylinder (axis y).
fn cylinder_first_hit(c: &Cylinder, ray: &Ray, max: f32) -> Option<f32> {
    let (o, d) = (ray.origin, ray.dir);
    let (h, r) = (c.half_height, c.radius);
    let radial = quadratic_interval(
        d.x * d.x + d.z * d.z,
        2.0 * (o.x * d.x + o.z * d.z),
        o.x * o.x + o.z * o.z - r * r,
    )?;
    let axial = if d.y.abs() <= 1e-12 {
        if o.y.abs() > h {
            return None;
        }
        (f32::NEG_INFINITY, f32::INFINITY)
    } else {
        let (ta, tb) = ((-h - o.y) / d.y, (h - o.y) / d.y);
        (ta.min(tb), ta.max(tb))
    };
    let lo = radial.0.max(axial.0).max(0.0);
    let hi = radial.1.min(axial.1).min(max);
    (lo <= hi).then_some(lo)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn random_ray(rng: &mut fastrand::Rng) -> Ray {
        let mut v = || Vector::new(rng.f32() - 0.5, rng.f32() - 0.5, rng.f32() - 0.5);
        let origin = v() * 1.2;
        let target = v() * 0.4;
        Ray::new(origin, (target - origin) * (0.5 + rng.f32()))
    }

    /// Exact where parry's GJK cast is approximate (it stops up to a few millimetres off the
    /// surface, far along a grazing ray): our hit lies on the surface; parry's hits, and its
    /// hits where we find none, lie within 3 mm of it; we hit where parry misses only at a
    /// graze, rarely. Returns how many rays hit.
    fn agrees(shape: &dyn Shape, rng: &mut fastrand::Rng) -> usize {
        let (mut hits, mut only_ours) = (0, 0);
        let near_surface =
            |t: f32, ray: &Ray| shape.distance_to_local_point(ray.point_at(t), false);
        for _ in 0..4000 {
            let ray = random_ray(rng);
            let max = 0.5 + rng.f32() * 2.0;
            let ours = first_hit(shape, &ray, max).expect("a capsule or a cylinder");
            let theirs = shape.cast_local_ray(&ray, max, true);
            if let Some(a) = ours {
                hits += 1;
                let d = near_surface(a, &ray);
                assert!(
                    a == 0.0 || d < 1e-4,
                    "{ray:?}: our hit {a} is {d} m off the surface"
                );
            }
            if let Some(b) = theirs {
                let d = near_surface(b, &ray);
                assert!(
                    d < 3e-3,
                    "{ray:?}: parry's hit {b} is {d} m off, ours {ours:?}"
                );
            }
            if ours.is_some() && theirs.is_none() {
                only_ours += 1;
            }
        }
        assert!(
            only_ours * 100 < hits,
            "{only_ours} hits parry misses, of {hits}"
        );
        hits
    }

    #[test]
    fn capsule_hits_agree_with_parry() {
        let mut rng = fastrand::Rng::with_seed(3);
        let c = Capsule::new(
            Vector::new(-0.1, -0.2, 0.05),
            Vector::new(0.15, 0.1, -0.05),
            0.08,
        );
        assert!(agrees(&c, &mut rng) > 500);
        let ball_like = Capsule::new(Vector::ZERO, Vector::ZERO, 0.1);
        assert!(agrees(&ball_like, &mut rng) > 100);
    }

    #[test]
    fn cylinder_hits_agree_with_parry() {
        let mut rng = fastrand::Rng::with_seed(4);
        let c = Cylinder::new(0.2, 0.07);
        assert!(agrees(&c, &mut rng) > 500);
    }

    #[test]
    fn a_ray_from_inside_hits_at_zero_and_a_short_one_misses() {
        let c = Cylinder::new(0.2, 0.1);
        let inside = Ray::new(Vector::ZERO, Vector::X);
        assert_eq!(first_hit(&c, &inside, 1.0), Some(Some(0.0)));
        let short = Ray::new(Vector::new(-1.0, 0.0, 0.0), Vector::X);
        assert_eq!(first_hit(&c, &short, 0.5), Some(None));
        let far = Ray::new(Vector::new(-1.0, 0.0, 0.0), Vector::X);
        let t = first_hit(&c, &far, 2.0).unwrap().unwrap();
        assert!((t - 0.9).abs() < 1e-5);
        let cap = Capsule::new(Vector::new(0.0, -0.2, 0.0), Vector::new(0.0, 0.2, 0.0), 0.1);
        let hit_end = Ray::new(Vector::new(0.0, 1.0, 0.0), -Vector::Y);
        let t = first_hit(&cap, &hit_end, 2.0).unwrap().unwrap();
        assert!((t - 0.7).abs() < 1e-5, "{t}");
        assert_eq!(first_hit(&parry3d::shape::Ball::new(0.1), &far, 2.0), None);
    }
}
