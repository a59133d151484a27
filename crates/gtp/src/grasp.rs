//! Grasps for a robot's parallel gripper: antipodal contact pairs inside a friction cone,
//! several rotations about each pair's axis, filtered for collision with the object itself,
//! ranked and cached per object shape (`../shared/notes/geometry-facts.md` beside the checkout, section 5).
//!
//! A [`Grasp`] is the pose of the gripper's tool frame relative to the object, plus the jaw
//! opening. Grasps depend only on the object's shape and the gripper's ([`GripperModel`]), so
//! they are computed once per shape and gripper and shared by every task through a
//! [`GraspCache`].

use std::collections::HashMap;
use std::f32::consts::TAU;
use std::hash::{Hash, Hasher};
use std::sync::{Arc, Mutex};

use parry3d::math::{Pose, Rotation, Vector};
use parry3d::query::Ray;
use parry3d::shape::Shape;
use serde::{Deserialize, Serialize};

use crate::gripper::GripperModel;

/// How grasps are generated. The defaults follow the original planner.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct GraspParams {
    /// Surface points sampled on the object.
    pub surface_samples: usize,
    /// Coulomb friction coefficient of the finger pads; contacts must lie in the cone `atan(mu)`.
    pub friction: f32,
    /// A cap on the jaw opening of a grasp below the gripper's own widest (metres); `None`:
    /// the gripper's ([`GripperModel::max_opening`]).
    pub max_opening: Option<f32>,
    /// Extra opening (metres, total) of the jaws while approaching, on top of the object's width.
    pub approach_clearance: f32,
    /// Rotations of the gripper about each contact pair's axis.
    pub rotations: usize,
    /// Grasps kept per object (the best by [`Grasp::score`]).
    pub keep: usize,
    /// Grasps closer than this (metres, tool-frame origins) and [`Self::min_angle`] are duplicates.
    pub min_separation: f32,
    /// Minimum angle (radians) between the approach axes of two kept grasps at the same place.
    pub min_angle: f32,
    /// Seed of the surface sampling (the result is deterministic for a seed and a shape).
    pub seed: u64,
}

impl Default for GraspParams {
    fn default() -> Self {
        GraspParams {
            surface_samples: 1000,
            friction: 0.3,
            max_opening: None,
            approach_clearance: 0.02,
            rotations: 8,
            keep: 80,
            min_separation: 0.03,
            min_angle: 0.35,
            seed: 7,
        }
    }
}

/// One grasp of an object.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Grasp {
    /// Index in the object's [`GraspSet`]; stable for a shape and parameters.
    pub id: usize,
    /// Pose of the tool frame in the object's frame.
    pub tool_in_object: Pose,
    /// The jaw opening when closed on the object: the contacts' distance, or wider where the
    /// fingers meet the object before the contacts (a flat pad across a tilted axis).
    pub width: f32,
    /// Jaw opening while approaching (width plus clearance, at most the maximum opening).
    pub opening: f32,
    /// Distance of the grasp axis from the object's centre of mass (smaller is better: less torque).
    pub score: f32,
}

impl Grasp {
    /// The tool frame in the world when the object is at `object_pose`.
    pub fn tool_pose(&self, object_pose: &Pose) -> Pose {
        *object_pose * self.tool_in_object
    }

    /// The object's pose in the world when the tool frame is at `tool_pose`.
    pub fn object_pose(&self, tool_pose: &Pose) -> Pose {
        *tool_pose * self.tool_in_object.inverse()
    }
}

/// A point on an object's surface with the outward normal there.
#[derive(Clone, Copy, Debug)]
pub struct SurfacePoint {
    /// The point, in the shape's frame.
    pub point: Vector,
    /// Outward unit normal.
    pub normal: Vector,
}

/// The grasps of one object shape, best first.
#[derive(Clone, Debug)]
pub struct GraspSet {
    /// Grasps ordered by score (best first); `grasps[i].id == i`.
    pub grasps: Vec<Grasp>,
    /// Antipodal contact pairs found before the rotations and the collision filter.
    pub antipodal_pairs: usize,
    /// Grasps (pair x rotation) dropped because the gripper collided with the object.
    pub colliding: usize,
}

/// Errors of grasp generation.
#[derive(Debug, thiserror::Error, PartialEq)]
pub enum GraspError {
    /// The shape has no usable surface (empty mesh, zero size).
    #[error("cannot sample the surface of this shape: {0}")]
    NoSurface(String),
}

/// Generates the grasps of `shape` (in its own frame) for `gripper`.
///
/// Every kept grasp has its contacts inside the friction cone, a width within the maximum
/// opening, and a gripper (open to [`Grasp::opening`]) clear of the object.
pub fn generate_grasps(
    shape: &dyn Shape,
    params: &GraspParams,
    gripper: &GripperModel,
) -> Result<GraspSet, GraspError> {
    let max_opening = params
        .max_opening
        .map_or(gripper.max_opening, |m| m.min(gripper.max_opening));
    let mut rng = fastrand::Rng::with_seed(params.seed);
    let samples = sample_surface(shape, params.surface_samples, &mut rng)?;
    let com = centre_of_mass(shape);
    let cone = params.friction.atan();
    let cos_cone = cone.cos();
    let mut candidates: Vec<Grasp> = Vec::new();
    let mut pairs = 0;
    let mut colliding = 0;
    let eps = 1e-4;
    for s in &samples {
        // Close the jaws along the inward normal, tilted at random inside the friction cone.
        let dir = random_in_cone(-s.normal, cone * 0.8, &mut rng);
        let ray = Ray::new(s.point + dir * eps, dir);
        let Some(hit) = shape.cast_local_ray_and_get_normal(&ray, max_opening, false) else {
            continue;
        };
        let width = hit.time_of_impact + eps;
        if width < 0.004 || width > max_opening {
            continue;
        }
        // Leaving the solid, the outward normal points along the ray.
        let n2 = if hit.normal.dot(dir) < 0.0 {
            -hit.normal
        } else {
            hit.normal
        };
        if dir.dot(-s.normal) < cos_cone || dir.dot(n2) < cos_cone {
            continue;
        }
        pairs += 1;
        let p2 = ray.point_at(hit.time_of_impact);
        let centre = (s.point + p2) * 0.5;
        let axis = dir;
        let offset = com - centre;
        let score = (offset - axis * offset.dot(axis)).length();
        let opening = (width + params.approach_clearance).min(max_opening);
        let boxes = gripper.at(opening);
        let u = any_perpendicular(axis);
        let w = axis.cross(u);
        for k in 0..params.rotations {
            let theta = TAU * k as f32 / params.rotations as f32;
            let x = u * theta.cos() + w * theta.sin();
            let z = x.cross(axis);
            let rotation = Rotation::from_mat3(&parry3d::math::Mat3::from_cols(x, axis, z));
            let tool = Pose::from_parts(centre, rotation.normalize());
            if boxes.intersects(&tool, shape, &Pose::IDENTITY) {
                colliding += 1;
                continue;
            }
            candidates.push(Grasp {
                id: 0,
                tool_in_object: tool,
                width: closed_width(gripper, &tool, shape, width, opening),
                opening,
                score,
            });
        }
    }
    candidates.sort_by(|a, b| a.score.total_cmp(&b.score));
    let mut kept: Vec<Grasp> = Vec::with_capacity(params.keep);
    for g in candidates {
        if kept.len() >= params.keep {
            break;
        }
        let duplicate = kept.iter().any(|k| {
            let near = (k.tool_in_object.translation - g.tool_in_object.translation).length()
                < params.min_separation;
            let ax = k.tool_in_object.rotation * Vector::X;
            let bx = g.tool_in_object.rotation * Vector::X;
            let ay = k.tool_in_object.rotation * Vector::Y;
            let by = g.tool_in_object.rotation * Vector::Y;
            // The jaws are symmetric: a grasp and its flip about x are the same grasp.
            near && ax.dot(bx) > params.min_angle.cos() && ay.dot(by).abs() > params.min_angle.cos()
        });
        if !duplicate {
            kept.push(Grasp {
                id: kept.len(),
                ..g
            });
        }
    }
    Ok(GraspSet {
        grasps: kept,
        antipodal_pairs: pairs,
        colliding,
    })
}

/// The jaw opening at which the fingers, closing on `shape` with the tool at `tool`, stop:
/// `width` (the contacts' distance) when the gripper's own shapes clear the object there, else
/// the narrowest opening up to `opening` at which they do, to 0.1 mm. Closing across a tilted
/// axis (inside the friction cone), a flat pad meets a box's edge before the contact point:
/// held at `width`, it would stand millimetres inside the object (the Panda's pads 2 mm inside
/// the POS machine). The shapes, not their boxes: a Robotiq 2F-85's linkage, boxed, stopped
/// its jaws 1 cm short of the object on each side.
fn closed_width(
    gripper: &GripperModel,
    tool: &Pose,
    shape: &dyn Shape,
    width: f32,
    opening: f32,
) -> f32 {
    let clear = |w: f32| !gripper.shapes_meet(w, tool, shape, &Pose::IDENTITY);
    if clear(width) {
        return width;
    }
    let (mut lo, mut hi) = (width, opening);
    while hi - lo > 1e-4 {
        let mid = 0.5 * (lo + hi);
        if clear(mid) {
            hi = mid;
        } else {
            lo = mid;
        }
    }
    hi
}

/// The centre of mass of a shape of uniform density (the AABB centre when the shape has no
/// volume, such as an open mesh).
pub fn centre_of_mass(shape: &dyn Shape) -> Vector {
    let props = shape.mass_properties(1.0);
    if props.mass() > 1e-9 && props.local_com.is_finite() {
        props.local_com
    } else {
        shape.compute_local_aabb().center()
    }
}

/// Samples `n` points on the surface of `shape`, area-weighted for boxes, cylinders and
/// triangle meshes, and by rays towards the centre for any other shape.
pub fn sample_surface(
    shape: &dyn Shape,
    n: usize,
    rng: &mut fastrand::Rng,
) -> Result<Vec<SurfacePoint>, GraspError> {
    let mut out = Vec::with_capacity(n);
    if let Some(c) = shape.as_cuboid() {
        let h = c.half_extents;
        // Faces: +-x (area 4 hy hz), +-y, +-z.
        let areas = [h.y * h.z, h.x * h.z, h.x * h.y];
        let total: f32 = areas.iter().sum::<f32>() * 2.0;
        if total <= 0.0 {
            return Err(GraspError::NoSurface("box of zero size".into()));
        }
        for _ in 0..n {
            let mut r = rng.f32() * total;
            let mut face = 0;
            while face < 5 && r > areas[face / 2] {
                r -= areas[face / 2];
                face += 1;
            }
            let axis = face / 2;
            let sign = if face % 2 == 0 { 1.0 } else { -1.0 };
            let mut p = Vector::new(
                (rng.f32() * 2.0 - 1.0) * h.x,
                (rng.f32() * 2.0 - 1.0) * h.y,
                (rng.f32() * 2.0 - 1.0) * h.z,
            );
            let mut normal = Vector::ZERO;
            p[axis] = sign * h[axis];
            normal[axis] = sign;
            out.push(SurfacePoint { point: p, normal });
        }
    } else if let Some(c) = shape.as_cylinder() {
        // parry's cylinders stand along their local y axis.
        let (r, hh) = (c.radius, c.half_height);
        let side = TAU * r * 2.0 * hh;
        let caps = 2.0 * std::f32::consts::PI * r * r;
        if side + caps <= 0.0 {
            return Err(GraspError::NoSurface("cylinder of zero size".into()));
        }
        for _ in 0..n {
            let a = rng.f32() * TAU;
            if rng.f32() * (side + caps) < side {
                let normal = Vector::new(a.cos(), 0.0, a.sin());
                let y = (rng.f32() * 2.0 - 1.0) * hh;
                out.push(SurfacePoint {
                    point: normal * r + Vector::Y * y,
                    normal,
                });
            } else {
                let rr = r * rng.f32().sqrt();
                let sign = if rng.bool() { 1.0 } else { -1.0 };
                out.push(SurfacePoint {
                    point: Vector::new(rr * a.cos(), sign * hh, rr * a.sin()),
                    normal: Vector::Y * sign,
                });
            }
        }
    } else if let Some(mesh) = shape.as_trimesh() {
        let tris: Vec<_> = mesh.triangles().collect();
        let areas: Vec<f32> = tris.iter().map(|t| t.area()).collect();
        let total: f32 = areas.iter().sum();
        if tris.is_empty() || total <= 0.0 {
            return Err(GraspError::NoSurface(
                "mesh without triangles of positive area".into(),
            ));
        }
        // Meshes wound clockwise have negative signed volume: flip their normals.
        let volume: f32 = tris.iter().map(|t| t.a.dot(t.b.cross(t.c))).sum();
        let flip = if volume < 0.0 { -1.0 } else { 1.0 };
        let mut cumulative = Vec::with_capacity(areas.len());
        let mut acc = 0.0;
        for a in &areas {
            acc += a;
            cumulative.push(acc);
        }
        for _ in 0..n {
            let r = rng.f32() * total;
            let i = cumulative.partition_point(|&c| c < r).min(tris.len() - 1);
            let t = &tris[i];
            let (mut u, mut v) = (rng.f32(), rng.f32());
            if u + v > 1.0 {
                (u, v) = (1.0 - u, 1.0 - v);
            }
            let Some(normal) = t.normal() else { continue };
            out.push(SurfacePoint {
                point: t.a + (t.b - t.a) * u + (t.c - t.a) * v,
                normal: normal * flip,
            });
        }
    } else {
        let aabb = shape.compute_local_aabb();
        let centre = aabb.center();
        let radius = aabb.half_extents().length() * 1.5 + 1e-3;
        let mut tries = 0;
        while out.len() < n && tries < n * 4 {
            tries += 1;
            let d = random_unit(rng);
            let ray = Ray::new(centre + d * radius, -d);
            if let Some(hit) = shape.cast_local_ray_and_get_normal(&ray, radius * 2.0, true) {
                out.push(SurfacePoint {
                    point: ray.point_at(hit.time_of_impact),
                    normal: hit.normal,
                });
            }
        }
    }
    if out.is_empty() {
        return Err(GraspError::NoSurface("no surface point found".into()));
    }
    Ok(out)
}

/// A unit vector uniformly distributed on the sphere.
pub(crate) fn random_unit(rng: &mut fastrand::Rng) -> Vector {
    let z = rng.f32() * 2.0 - 1.0;
    let a = rng.f32() * TAU;
    let r = (1.0 - z * z).max(0.0).sqrt();
    Vector::new(r * a.cos(), r * a.sin(), z)
}

/// A unit vector within `half_angle` of the unit vector `axis`.
fn random_in_cone(axis: Vector, half_angle: f32, rng: &mut fastrand::Rng) -> Vector {
    let u = any_perpendicular(axis);
    let w = axis.cross(u);
    let tilt = rng.f32() * half_angle;
    let a = rng.f32() * TAU;
    (axis * tilt.cos() + (u * a.cos() + w * a.sin()) * tilt.sin()).normalize()
}

/// Some unit vector perpendicular to the unit vector `v`.
pub(crate) fn any_perpendicular(v: Vector) -> Vector {
    let other = if v.x.abs() < 0.9 {
        Vector::X
    } else {
        Vector::Y
    };
    v.cross(other).normalize()
}

/// A key identifying a shape's geometry, for caching what depends only on the shape.
///
/// Boxes, cylinders and meshes are keyed by their exact dimensions or vertices; other shapes by
/// their type, bounds and volume.
pub fn shape_key(shape: &dyn Shape) -> u64 {
    let mut h = std::collections::hash_map::DefaultHasher::new();
    if let Some(c) = shape.as_cuboid() {
        "cuboid".hash(&mut h);
        hash_vec(&mut h, c.half_extents);
    } else if let Some(c) = shape.as_cylinder() {
        "cylinder".hash(&mut h);
        c.radius.to_bits().hash(&mut h);
        c.half_height.to_bits().hash(&mut h);
    } else if let Some(m) = shape.as_trimesh() {
        "trimesh".hash(&mut h);
        for v in m.vertices() {
            hash_vec(&mut h, *v);
        }
        m.indices().hash(&mut h);
    } else {
        (shape.shape_type() as u32).hash(&mut h);
        let aabb = shape.compute_local_aabb();
        hash_vec(&mut h, aabb.mins);
        hash_vec(&mut h, aabb.maxs);
        shape.mass_properties(1.0).mass().to_bits().hash(&mut h);
    }
    h.finish()
}

fn hash_vec(h: &mut impl Hasher, v: Vector) {
    for c in [v.x, v.y, v.z] {
        c.to_bits().hash(h);
    }
}

/// Grasp sets computed once per object shape and gripper and shared (thread-safe, cheap to
/// clone).
#[derive(Clone, Debug, Default)]
pub struct GraspCache {
    params: GraspParams,
    sets: Arc<Mutex<HashMap<u64, Arc<GraspSet>>>>,
}

impl GraspCache {
    /// An empty cache generating grasps with `params`.
    pub fn new(params: GraspParams) -> GraspCache {
        GraspCache {
            params,
            sets: Arc::default(),
        }
    }

    /// The parameters grasps are generated with.
    pub fn params(&self) -> &GraspParams {
        &self.params
    }

    /// The grasps of `shape` for `gripper`, generated on first request.
    pub fn grasps(
        &self,
        shape: &dyn Shape,
        gripper: &GripperModel,
    ) -> Result<Arc<GraspSet>, GraspError> {
        let key = shape_key(shape) ^ gripper.key().rotate_left(17);
        if let Some(set) = self
            .sets
            .lock()
            .unwrap_or_else(|e| e.into_inner())
            .get(&key)
        {
            return Ok(set.clone());
        }
        let set = Arc::new(generate_grasps(shape, &self.params, gripper)?);
        self.sets
            .lock()
            .unwrap_or_else(|e| e.into_inner())
            .insert(key, set.clone());
        Ok(set)
    }

    /// How many shapes have grasps cached.
    pub fn len(&self) -> usize {
        self.sets.lock().unwrap_or_else(|e| e.into_inner()).len()
    }

    /// Whether nothing is cached yet.
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::gripper::tests::pr2_gripper;
    use parry3d::shape::{Cuboid, Cylinder, TriMesh};

    fn check_antipodal(shape: &dyn Shape, set: &GraspSet) {
        assert!(!set.grasps.is_empty());
        for (i, g) in set.grasps.iter().enumerate() {
            assert_eq!(g.id, i);
            assert!(g.width <= 0.09 && g.opening <= 0.09);
            assert!(g.opening >= g.width);
            // The contacts lie on the surface along the tool's y axis, within the closed jaws,
            // the centre between them.
            let y = g.tool_in_object.rotation * Vector::Y;
            let c = g.tool_in_object.translation;
            let exits: Vec<f32> = [-1.0f32, 1.0]
                .iter()
                .map(|&side| {
                    let far = c + y * side * 0.1;
                    let hit = shape.cast_local_ray(&Ray::new(far, -y * side), 0.1, true);
                    0.1 - hit.expect("the surface across the jaws")
                })
                .collect();
            assert!((exits[0] - exits[1]).abs() < 2e-3, "off centre: {exits:?}");
            assert!(
                exits[0] + exits[1] <= g.width + 2e-3,
                "{exits:?} {}",
                g.width
            );
            // Neither open (its boxes) nor closed (its shapes) does the gripper enter the
            // object.
            let gripper = pr2_gripper();
            let open = gripper.at(g.opening);
            assert!(!open.intersects(&g.tool_in_object, shape, &Pose::IDENTITY));
            assert!(!gripper.shapes_meet(g.width, &g.tool_in_object, shape, &Pose::IDENTITY));
        }
        for w in set.grasps.windows(2) {
            assert!(w[0].score <= w[1].score);
        }
    }

    #[test]
    fn book_grasps_are_across_the_thickness_near_an_edge() {
        // A book 24 x 17 x 3 cm: only its thickness fits in the jaws, and the palm stays outside.
        let book = Cuboid::new(Vector::new(0.12, 0.085, 0.015));
        let set = generate_grasps(&book, &GraspParams::default(), &pr2_gripper()).unwrap();
        check_antipodal(&book, &set);
        assert!(set.grasps.len() >= 20, "only {} grasps", set.grasps.len());
        for g in &set.grasps {
            let y = g.tool_in_object.rotation * Vector::Y;
            assert!(
                y.z.abs() > 0.95,
                "jaws must close across the thickness: {y:?}"
            );
            // Closed at the thickness, or wider where a tilted pad meets an edge first.
            assert!(g.width > 0.029 && g.width <= g.opening, "{}", g.width);
        }
        assert!(
            set.colliding > 0,
            "grasps reaching into the middle must be dropped"
        );
    }

    #[test]
    fn cylinder_and_mesh_grasps() {
        let can = Cylinder::new(0.06, 0.03);
        let set = generate_grasps(&can, &GraspParams::default(), &pr2_gripper()).unwrap();
        check_antipodal(&can, &set);
        assert_eq!(set.grasps.len(), 80);

        // A closed tetrahedron-free mesh: a 6 cm cube as 12 triangles.
        let c = Cuboid::new(Vector::splat(0.03));
        let (v, i) = c.to_trimesh();
        let mesh = TriMesh::new(v, i).unwrap();
        let set = generate_grasps(&mesh, &GraspParams::default(), &pr2_gripper()).unwrap();
        check_antipodal(&mesh, &set);
        assert!(set.grasps.len() >= 40);
    }

    #[test]
    fn too_wide_objects_have_no_grasps() {
        let crate_box = Cuboid::new(Vector::splat(0.2));
        let set = generate_grasps(&crate_box, &GraspParams::default(), &pr2_gripper()).unwrap();
        assert!(set.grasps.is_empty());
        assert_eq!(set.antipodal_pairs, 0);
    }

    #[test]
    fn cache_generates_once_per_shape() {
        let cache = GraspCache::new(GraspParams::default());
        let g = pr2_gripper();
        let book = Cuboid::new(Vector::new(0.12, 0.085, 0.015));
        let a = cache.grasps(&book, &g).unwrap();
        let b = cache.grasps(&book, &g).unwrap();
        assert!(Arc::ptr_eq(&a, &b));
        cache.grasps(&Cylinder::new(0.06, 0.03), &g).unwrap();
        assert_eq!(cache.len(), 2);
        // Another gripper has grasp sets of its own.
        let fetch = crate::gripper::GripperModel::of_named_arm(
            &crate::gripper::tests::model("fetch"),
            "arm",
        )
        .unwrap();
        let c = cache.grasps(&book, &fetch).unwrap();
        assert!(!Arc::ptr_eq(&a, &c));
        assert_eq!(cache.len(), 3);
    }
}
