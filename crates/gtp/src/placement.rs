//! Placements: the stable resting faces of an object's convex hull, turned by several yaw
//! angles and set down at candidate points on support surfaces
//! (`../shared/notes/geometry-facts.md` beside the checkout, section 5, point 2).
//!
//! A face is stable when the object's centre of mass, projected onto the face's plane, lies
//! inside the face; the distance from that projection to the face's nearest edge is the
//! face's stability margin, and faces are ranked by it.

use std::f32::consts::TAU;

use parry3d::math::{Pose, Rotation, Vector};
use parry3d::shape::Shape;
use parry3d::transformation;
use serde::{Deserialize, Serialize};

use crate::grasp::centre_of_mass;

/// How placements are enumerated. The defaults follow the original planner.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct PlacementParams {
    /// Resting faces kept per object (the most stable first).
    pub max_faces: usize,
    /// Yaw angles per face, evenly spaced over a full turn.
    pub yaws: usize,
    /// Height above the support surface at which the gripper releases the object (metres); it
    /// then settles onto the surface (the planner's world and the plan hold it there).
    pub clearance: f32,
    /// Faces whose stability margin is below this (metres) are not resting faces.
    pub min_margin: f32,
}

impl Default for PlacementParams {
    fn default() -> Self {
        PlacementParams {
            max_faces: 11,
            yaws: 10,
            clearance: 0.002,
            min_margin: 0.003,
        }
    }
}

/// A face of the convex hull on which the object rests stably.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RestingFace {
    /// Outward normal of the face in the object's frame (it points down when resting).
    pub normal: Vector,
    /// Rotation taking the object's frame to its resting orientation (before any yaw).
    pub rotation: Rotation,
    /// Height of the object's origin above the support when resting on this face.
    pub height: f32,
    /// Distance from the projected centre of mass to the face's nearest edge (metres).
    pub margin: f32,
    /// Area of the face (square metres).
    pub area: f32,
}

impl RestingFace {
    /// The object's pose resting on this face, its origin above `point` (on the support's top
    /// surface), turned by `yaw` about the vertical, raised by `clearance`.
    pub fn pose_at(&self, point: Vector, yaw: f32, clearance: f32) -> Pose {
        let rotation = Rotation::from_rotation_z(yaw) * self.rotation;
        Pose::from_parts(
            Vector::new(point.x, point.y, point.z + self.height + clearance),
            rotation,
        )
    }
}

/// A candidate placement: a resting face and a yaw at a point.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Placement {
    /// The object's pose in the world.
    pub pose: Pose,
    /// Index of the resting face in the object's face list.
    pub face: usize,
    /// Index of the yaw angle.
    pub yaw_index: usize,
    /// The yaw angle (radians).
    pub yaw: f32,
    /// The point on the support surface below the object.
    pub point: Vector,
}

/// Errors of placement generation.
#[derive(Debug, thiserror::Error, PartialEq)]
pub enum PlacementError {
    /// The convex hull could not be computed (flat or degenerate shape).
    #[error("cannot compute the convex hull of this shape: {0}")]
    Hull(String),
}

/// The stable resting faces of `shape`, the most stable first, at most `params.max_faces`.
pub fn resting_faces(
    shape: &dyn Shape,
    params: &PlacementParams,
) -> Result<Vec<RestingFace>, PlacementError> {
    let points = hull_points(shape);
    let (vertices, triangles) = transformation::try_convex_hull(&points)
        .map_err(|e| PlacementError::Hull(format!("{e:?}")))?;
    let com = centre_of_mass(shape);
    // Group the hull's triangles into planar faces.
    let mut groups: Vec<(Vector, f32, Vec<usize>)> = Vec::new();
    for t in &triangles {
        let [a, b, c] = t.map(|i| vertices[i as usize]);
        let n = (b - a).cross(c - a);
        if n.length() < 1e-12 {
            continue;
        }
        let n = n.normalize();
        let d = n.dot(a);
        let group = groups
            .iter_mut()
            .find(|(gn, gd, _)| gn.dot(n) > 0.9999 && (gd - d).abs() < 1e-4);
        match group {
            Some((_, _, members)) => members.extend(t.iter().map(|&i| i as usize)),
            None => groups.push((n, d, t.iter().map(|&i| i as usize).collect())),
        }
    }
    let mut faces = Vec::new();
    for (normal, d, members) in groups {
        let u = crate::grasp::any_perpendicular(normal);
        let w = normal.cross(u);
        let mut poly: Vec<(f32, f32)> = members
            .iter()
            .map(|&i| (vertices[i].dot(u), vertices[i].dot(w)))
            .collect();
        poly = convex_hull_2d(&mut poly);
        if poly.len() < 3 {
            continue;
        }
        let c = (com.dot(u), com.dot(w));
        let margin = inside_margin(&poly, c);
        if margin < params.min_margin {
            continue;
        }
        faces.push(RestingFace {
            normal,
            rotation: Rotation::from_rotation_arc(normal, -Vector::Z),
            height: d,
            margin,
            area: polygon_area(&poly),
        });
    }
    faces.sort_by(|a, b| {
        b.margin
            .total_cmp(&a.margin)
            .then(b.area.total_cmp(&a.area))
    });
    faces.truncate(params.max_faces);
    Ok(faces)
}

/// All placements of an object with `faces` at `point`: faces x yaws, in face-major order.
pub fn placements_at<'a>(
    faces: &'a [RestingFace],
    point: Vector,
    params: &'a PlacementParams,
) -> impl Iterator<Item = Placement> + 'a {
    let yaws = params.yaws.max(1);
    (0..faces.len()).flat_map(move |face| {
        (0..yaws).map(move |yaw_index| {
            let yaw = TAU * yaw_index as f32 / yaws as f32;
            Placement {
                pose: faces[face].pose_at(point, yaw, params.clearance),
                face,
                yaw_index,
                yaw,
                point,
            }
        })
    })
}

/// Points whose convex hull is the shape's (exactly for polyhedra, 32-gon for cylinders).
fn hull_points(shape: &dyn Shape) -> Vec<Vector> {
    if let Some(c) = shape.as_cuboid() {
        return c.to_trimesh().0;
    }
    if let Some(c) = shape.as_cylinder() {
        return c.to_trimesh(32).0;
    }
    if let Some(m) = shape.as_trimesh() {
        return m.vertices().to_vec();
    }
    if let Some(p) = shape.as_convex_polyhedron() {
        return p.points().to_vec();
    }
    if let Some(compound) = shape.as_compound() {
        return compound
            .shapes()
            .iter()
            .flat_map(|(pose, s)| {
                hull_points(s.as_ref())
                    .into_iter()
                    .map(move |p| pose.transform_point(p))
            })
            .collect();
    }
    // Any convex shape: support points in many directions.
    let mut points = Vec::new();
    if let Some(support) = shape.as_support_map() {
        let mut rng = fastrand::Rng::with_seed(1);
        for _ in 0..256 {
            points.push(support.local_support_point(crate::grasp::random_unit(&mut rng)));
        }
    } else {
        let aabb = shape.compute_local_aabb();
        points.extend(aabb.vertices());
    }
    points
}

/// Andrew's monotone chain; counter-clockwise, no collinear points.
fn convex_hull_2d(points: &mut [(f32, f32)]) -> Vec<(f32, f32)> {
    points.sort_by(|a, b| a.0.total_cmp(&b.0).then(a.1.total_cmp(&b.1)));
    let cross = |o: (f32, f32), a: (f32, f32), b: (f32, f32)| {
        (a.0 - o.0) * (b.1 - o.1) - (a.1 - o.1) * (b.0 - o.0)
    };
    let mut hull: Vec<(f32, f32)> = Vec::new();
    for pass in 0..2 {
        let start = hull.len();
        let iter: Box<dyn Iterator<Item = &(f32, f32)>> = if pass == 0 {
            Box::new(points.iter())
        } else {
            Box::new(points.iter().rev())
        };
        for &p in iter {
            while hull.len() >= start + 2
                && cross(hull[hull.len() - 2], hull[hull.len() - 1], p) <= 1e-12
            {
                hull.pop();
            }
            hull.push(p);
        }
        hull.pop();
    }
    hull
}

/// Signed distance from `p` to the nearest edge of the counter-clockwise convex polygon
/// (positive inside).
fn inside_margin(poly: &[(f32, f32)], p: (f32, f32)) -> f32 {
    let mut margin = f32::INFINITY;
    for i in 0..poly.len() {
        let a = poly[i];
        let b = poly[(i + 1) % poly.len()];
        let (ex, ey) = (b.0 - a.0, b.1 - a.1);
        let len = (ex * ex + ey * ey).sqrt();
        if len < 1e-9 {
            continue;
        }
        let d = (ex * (p.1 - a.1) - ey * (p.0 - a.0)) / len;
        margin = margin.min(d);
    }
    margin
}

fn polygon_area(poly: &[(f32, f32)]) -> f32 {
    let mut a = 0.0;
    for i in 0..poly.len() {
        let p = poly[i];
        let q = poly[(i + 1) % poly.len()];
        a += p.0 * q.1 - q.0 * p.1;
    }
    a.abs() / 2.0
}

#[cfg(test)]
mod tests {
    use super::*;
    use parry3d::shape::{ConvexPolyhedron, Cuboid, Cylinder};

    #[test]
    fn a_box_rests_on_six_faces_largest_margin_first() {
        let book = Cuboid::new(Vector::new(0.12, 0.085, 0.015));
        let faces = resting_faces(&book, &PlacementParams::default()).unwrap();
        assert_eq!(faces.len(), 6);
        // Lying flat (on +-z) has the widest margin (0.085) and the object origin 1.5 cm up.
        assert!((faces[0].margin - 0.085).abs() < 1e-4);
        assert!(faces[0].normal.z.abs() > 0.999);
        assert!((faces[0].height - 0.015).abs() < 1e-5);
        // Resting pose: the face points down and the lowest point is at clearance height.
        let pose = faces[0].pose_at(Vector::new(1.0, 2.0, 0.75), 0.3, 0.01);
        let down = pose.rotation * faces[0].normal;
        assert!((down - (-Vector::Z)).length() < 1e-4);
        let aabb = book.compute_aabb(&pose);
        assert!((aabb.mins.z - 0.76).abs() < 1e-4);
    }

    #[test]
    fn a_cylinder_prefers_its_ends_and_a_wedge_tips_over() {
        let can = Cylinder::new(0.06, 0.03);
        let faces = resting_faces(&can, &PlacementParams::default()).unwrap();
        assert!(faces[0].normal.y.abs() > 0.999, "an end face first");
        assert!(faces.len() <= 11);
        // A leaning tetrahedron whose centre of mass overhangs one face: that face is unstable.
        let pts = [
            Vector::new(0.0, 0.0, 0.0),
            Vector::new(0.1, 0.0, 0.0),
            Vector::new(0.0, 0.1, 0.0),
            Vector::new(0.5, 0.5, 0.1),
        ];
        let wedge = ConvexPolyhedron::from_convex_hull(&pts).unwrap();
        let faces = resting_faces(&wedge, &PlacementParams::default()).unwrap();
        assert!(!faces.is_empty() && faces.iter().all(|f| f.margin > 0.0));
        assert!(
            faces.len() < 4,
            "some face of the leaning tetrahedron must be unstable"
        );
    }

    #[test]
    fn placements_enumerate_faces_times_yaws() {
        let book = Cuboid::new(Vector::new(0.12, 0.085, 0.015));
        let params = PlacementParams::default();
        let faces = resting_faces(&book, &params).unwrap();
        let all: Vec<_> = placements_at(&faces, Vector::new(0.0, 0.0, 0.7), &params).collect();
        assert_eq!(all.len(), 60);
        assert!(all.iter().all(|p| p.pose.translation.z > 0.7));
    }
}
