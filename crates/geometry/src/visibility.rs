//! Visibility by pixels, as in the paper: the fraction of an object's pixels an eye sees.
//!
//! The original planner rendered the target alone (the *ideal* pixel count), then the whole scene
//! from the same eye, and counted the target's pixels still showing: visibility = shown / ideal.
//! Here the "pixels" are a `resolution` x `resolution` grid of rays spread over the target's
//! projected bounding rectangle in the eye's image plane, so every query spends its rays on the
//! target whatever its distance (equal steps in the image plane, like pixels of a zoomed-in
//! render of the eye's camera). A ray counts as:
//!
//! * *ideal* when it hits the target alone;
//! * *shown* when, in addition, its direction lies inside the agent's field of view (measured
//!   in the eye frame actually used: the current head pose, or the head aimed at the target as the
//!   joint limits allow) and no other body (objects, agents, including the viewer's own arms) cuts
//!   it before the target.
//!
//! So an object fully in view and unoccluded scores 1, one outside the field of view 0, one half
//! hidden about 0.5. Only the target and the bodies whose bounds meet the eye-to-target region
//! are tested; nothing else of the scene is touched.

use parry3d::bounding_volume::{Aabb, BoundingVolume};
use parry3d::math::{Pose, Vector};
use parry3d::query::{Ray, RayCast};
use parry3d::shape::Shape;

use crate::effort::aim_head;
use crate::ray_capsule_cylinder;
use crate::render::look_rotation;
use crate::scene::{AgentId, ObjectId};
use crate::world::{Body, BodyOwner, World};

/// Default grid: 64 x 64 rays over the target.
pub const DEFAULT_RESOLUTION: usize = 64;

/// Result of one pixel-visibility query.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Visibility {
    /// Rays that hit the target and were seen.
    pub shown: u32,
    /// Rays that hit the target alone.
    pub ideal: u32,
}

impl Visibility {
    /// shown / ideal (0 when the target covers no pixel at all).
    pub fn fraction(&self) -> f32 {
        if self.ideal == 0 {
            0.0
        } else {
            self.shown as f32 / self.ideal as f32
        }
    }
}

/// How the agent's head is set for a query.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Aim {
    /// The head as it is now (effort level 0).
    Current,
    /// The head turned towards the target within its joint limits (effort level 1 and above).
    AtTarget,
    /// The head at these pan and tilt angles (radians; positive tilt looks down), clamped to the
    /// joint limits.
    Head { pan: f32, tilt: f32 },
}

/// Visibility of `target` from an eye frame `eye` (x forward) with field of view `fov`
/// (horizontal, vertical; radians), on a `resolution` x `resolution` grid.
pub fn visibility_from(
    world: &World,
    target: ObjectId,
    eye: &Pose,
    fov: [f32; 2],
    resolution: usize,
) -> Visibility {
    visibility_from_upto(world, target, eye, fov, resolution, None)
}

/// [`visibility_from`], stopping as soon as the fraction is certain to exceed `stop_above`
/// (more rays shown than `stop_above` x resolution², whatever the ideal count): both counts
/// are then partial, and the fraction they give exceeds `stop_above` but is not the full
/// measure (enough to reject a hiding place). With `None`, or when the fraction stays at or
/// below `stop_above`, the result is exactly [`visibility_from`]'s.
pub fn visibility_from_upto(
    world: &World,
    target: ObjectId,
    eye: &Pose,
    fov: [f32; 2],
    resolution: usize,
    stop_above: Option<f32>,
) -> Visibility {
    let res = resolution.max(1);
    let obj = world.object(target);
    let tpose = world.object_shape_pose(target);
    let e = eye.translation;

    // The rays: equal steps over the target's bounding rectangle in the eye's own image plane,
    // as pixels of the eye's camera (and the checkers' rays); a camera aimed at the centre of
    // the target's bounds when the target reaches beyond 80 degrees of the eye's axis (it is
    // then mostly out of any field of view, and the eye's plane would stretch without bound).
    let taabb = obj.shape.compute_aabb(&tpose);
    let centre = taabb.center();
    let lb = obj.shape.compute_local_aabb();
    let corners = lb.vertices().map(|c| tpose.transform_point(c));
    let rectangle = |rot: parry3d::math::Rotation| {
        let mut r = [f32::MAX, f32::MIN, f32::MAX, f32::MIN];
        let mut inside = true;
        for c in corners {
            let l = rot.inverse() * (c - e);
            // A corner at or behind the eye: the eye is (nearly) inside the target's bounds.
            let x = l.x.max(1e-3);
            let (a, b) = (l.y / x, l.z / x);
            inside &= l.x > 1e-3 && a.abs() <= 6.0 && b.abs() <= 6.0;
            let (a, b) = (a.clamp(-6.0, 6.0), b.clamp(-6.0, 6.0));
            r = [r[0].min(a), r[1].max(a), r[2].min(b), r[3].max(b)];
        }
        (r, inside)
    };
    let (rot, [a0, a1, b0, b1]) = match rectangle(eye.rotation) {
        (r, true) => (eye.rotation, r),
        _ => {
            let rot = look_rotation(centre - e);
            (rot, rectangle(rot).0)
        }
    };

    // Possible occluders: bodies whose bounds meet the region spanned by the eye and the
    // target, except the target itself and any body the eye is inside of. A compound body
    // (furniture) is split into its parts, each kept only if its own bounds meet the region:
    // a ray then stops at the first part it hits instead of searching the compound for its
    // nearest hit. The segment from the eye to the target lies inside the region, so nothing
    // outside it can block a ray.
    let mut region = taabb;
    region.take_point(e);
    let bodies = world.bodies();
    let occluders = occluders_in(&bodies, target, &region, e);

    // One convex occluder in front of the whole target (it cuts the four corner rays of the
    // grid nearer than any point of the target's bounds) cuts every ray of the grid: each is a
    // positive combination of the corner rays, so it meets the convex hull of the four corner
    // hits, inside the occluder and nearer than the target. Nothing shows; only the ideal count
    // is left to take, from the target alone.
    let ray_at = |a: f32, b: f32| {
        let dir = rot * Vector::new(1.0, a, b);
        Ray::new(e, dir)
    };
    let near_target = (e - e.clamp(taabb.mins, taabb.maxs)).length();
    let corner_rays = [(a0, b0), (a1, b0), (a0, b1), (a1, b1)].map(|(a, b)| ray_at(a, b));
    let hidden = near_target > 0.0
        && occluders.iter().any(|o| {
            o.shape.is_convex()
                && corner_rays.iter().all(|r| {
                    o.first_hit(r)
                        .is_some_and(|t| t * r.dir.length() < near_target)
                })
        });
    if hidden {
        let mut ideal = 0;
        for j in 0..res {
            let b = b0 + (b1 - b0) * (j as f32 + 0.5) / res as f32;
            for i in 0..res {
                let a = a0 + (a1 - a0) * (i as f32 + 0.5) / res as f32;
                if ray_capsule_cylinder::cast_ray(&*obj.shape, &tpose, &ray_at(a, b), f32::MAX)
                    .is_some()
                {
                    ideal += 1;
                }
            }
        }
        return Visibility { shown: 0, ideal };
    }

    // A ray counts when it hits the target, lies inside the field of view and no occluder
    // cuts it first. Neighbouring rays are mostly cut by the same body: the last one that
    // blocked is tried first (the verdict of each ray does not depend on the order of the
    // tests).
    let inv_eye = eye.rotation.inverse();
    let (tx, ty) = ((0.5 * fov[0]).tan(), (0.5 * fov[1]).tan());
    // With an early stop: shown rays beyond which the fraction exceeds `stop_above` whatever
    // the ideal count (at most res x res).
    let enough = stop_above
        .filter(|m| *m < 1.0)
        .map(|m| (m.max(0.0) * (res * res) as f32).floor() as u32 + 1);
    let mut vis = Visibility { shown: 0, ideal: 0 };
    let mut last = 0usize;
    // Where each occluder's bounds fall in the image: a ray whose pixel is outside cannot meet
    // it. Per row of pixels, the occluders that reach it.
    let rects: Vec<Option<[f32; 4]>> = occluders
        .iter()
        .map(|o| image_rect(&o.aabb, rot, e))
        .collect();
    let mut row: Vec<usize> = Vec::with_capacity(occluders.len());
    for j in 0..res {
        let b = b0 + (b1 - b0) * (j as f32 + 0.5) / res as f32;
        let in_row = |k: usize| rects[k].is_none_or(|r| r[2] <= b && b <= r[3]);
        let meets = |k: usize, a: f32| rects[k].is_none_or(|r| r[0] <= a && a <= r[1]);
        row.clear();
        row.extend((0..occluders.len()).filter(|&k| in_row(k)));
        for i in 0..res {
            let a = a0 + (a1 - a0) * (i as f32 + 0.5) / res as f32;
            let dir = rot * Vector::new(1.0, a, b);
            let ray = Ray::new(e, dir);
            let Some(toi) = ray_capsule_cylinder::cast_ray(&*obj.shape, &tpose, &ray, f32::MAX)
            else {
                continue;
            };
            vis.ideal += 1;
            let d = inv_eye * dir;
            if d.x <= 0.0 || (d.y / d.x).abs() > tx || (d.z / d.x).abs() > ty {
                continue;
            }
            let blocked = occluders
                .get(last)
                .is_some_and(|o| in_row(last) && meets(last, a) && o.blocks(&ray, toi))
                || row.iter().any(|&k| {
                    let hit = k != last && meets(k, a) && occluders[k].blocks(&ray, toi);
                    if hit {
                        last = k;
                    }
                    hit
                });
            if !blocked {
                vis.shown += 1;
                if enough.is_some_and(|n| vis.shown >= n) {
                    return vis;
                }
            }
        }
    }
    vis
}

/// The rectangle `[a0, a1, b0, b1]` of the image plane (x = 1 in the frame of `rot` at the eye
/// `e`) that holds the projection of box `aabb`: a ray `rot * (1, a, b)` from the eye with
/// `(a, b)` outside it misses the box. `None` where the box reaches to the eye's plane or
/// behind it (then no rectangle holds its projection).
fn image_rect(aabb: &Aabb, rot: parry3d::math::Rotation, e: Vector) -> Option<[f32; 4]> {
    let inv = rot.inverse();
    let mut r = [f32::MAX, f32::MIN, f32::MAX, f32::MIN];
    for c in aabb.vertices() {
        let l = inv * (c - e);
        if l.x <= 1e-3 {
            return None;
        }
        let (a, b) = (l.y / l.x, l.z / l.x);
        r = [r[0].min(a), r[1].max(a), r[2].min(b), r[3].max(b)];
    }
    // Against rounding in the projection and in the rays' directions.
    const SLACK: f32 = 1e-4;
    Some([r[0] - SLACK, r[1] + SLACK, r[2] - SLACK, r[3] + SLACK])
}

/// The bodies (compound ones split into their parts) whose bounds meet `region`, except the
/// target and any body the eye `e` is inside of.
fn occluders_in<'w>(
    bodies: &'w [Body<'w>],
    target: ObjectId,
    region: &Aabb,
    e: Vector,
) -> Vec<Occluder<'w>> {
    let mut occluders: Vec<Occluder<'w>> = Vec::new();
    for b in bodies {
        if b.owner == BodyOwner::Object(target) {
            continue;
        }
        if let Some(r) = b.radius {
            let ball = Aabb::new(
                b.pose.translation - Vector::splat(r),
                b.pose.translation + Vector::splat(r),
            );
            if !ball.intersects(region) {
                continue; // without visiting a mesh piece's vertices for its exact bounds
            }
        }
        // A convex polyhedron's world box from its own (a few operations; its exact box
        // visits every vertex, as does the test of the eye inside it).
        let hull = b.shape.as_convex_polyhedron();
        let bb = match hull {
            Some(hull) => hull.local_aabb().transform_by(&b.pose),
            None => b.shape.compute_aabb(&b.pose),
        };
        if !bb.intersects(region)
            || (bb.contains_local_point(e) && b.shape.contains_point(&b.pose, e))
        {
            continue;
        }
        match b.shape.as_compound() {
            Some(c) => {
                for (part_pose, part) in c.shapes() {
                    let pb = part.compute_aabb(&(b.pose * *part_pose)).loosened(1e-4);
                    if pb.intersects(region) {
                        occluders.push(Occluder {
                            aabb: pb,
                            pose: b.pose,
                            part: Some(*part_pose),
                            shape: &**part,
                            local: None,
                        });
                    }
                }
            }
            None => occluders.push(Occluder {
                aabb: bb,
                pose: b.pose,
                part: None,
                shape: &**b.shape,
                local: hull.map(|hull| hull.local_aabb().loosened(LOCAL_SLACK)),
            }),
        }
    }
    occluders
}

/// A body, or one part of a compound body, that may cut rays.
struct Occluder<'a> {
    /// World bounds (of the part).
    aabb: Aabb,
    /// The body's world pose.
    pose: Pose,
    /// The part's pose in the body's frame, for a part of a compound.
    part: Option<Pose>,
    shape: &'a dyn Shape,
    /// For a convex polyhedron (a robot's mesh piece): its bounds in its own frame, widened by
    /// [`LOCAL_SLACK`]. Most rays that meet a piece's world bounds miss it (99 % in the
    /// library with the real PR2); this box turns most of them away before GJK's ray cast.
    local: Option<Aabb>,
}

/// How much an occluder's own bounds are widened (metres): a ray outside them passes the
/// shape by more than GJK's tolerance.
const LOCAL_SLACK: f32 = 1e-4;

impl Occluder<'_> {
    /// Where `ray` first meets it (solid: 0 from inside), in the ray's units.
    fn first_hit(&self, ray: &Ray) -> Option<f32> {
        match &self.part {
            Some(part) => {
                let local = ray.inverse_transform_by(&self.pose);
                self.shape.cast_ray(part, &local, f32::MAX, true)
            }
            None => self.shape.cast_ray(&self.pose, ray, f32::MAX, true),
        }
    }

    /// Whether it cuts `ray` before `toi` (a part is tested in the compound's frame and counted
    /// as the compound itself counts its parts).
    fn blocks(&self, ray: &Ray, toi: f32) -> bool {
        if !self.aabb.intersects_local_ray(ray, toi) {
            return false;
        }
        if ray_capsule_cylinder::closed_form(self.shape) {
            // Capsules and cylinders (people, cups, links) in closed form, not by GJK.
            let pose = self.part.map_or(self.pose, |part| self.pose * part);
            let hit = ray_capsule_cylinder::cast_ray(self.shape, &pose, ray, toi);
            return match &self.part {
                Some(_) => hit.is_some_and(|t| t < toi),
                None => hit.is_some(),
            };
        }
        match &self.part {
            Some(part) => {
                // As the compound counts a hit: strictly before `toi` (a part flush with the
                // target's face does not hide it).
                let local = ray.inverse_transform_by(&self.pose);
                self.shape
                    .cast_ray(part, &local, toi, true)
                    .is_some_and(|t| t < toi)
            }
            None => {
                let local = ray.inverse_transform_by(&self.pose);
                self.local
                    .is_none_or(|bounds| bounds.intersects_local_ray(&local, toi))
                    && self.shape.intersects_local_ray(&local, toi)
            }
        }
    }
}

/// Visibility of `target` for an agent as it stands now, with the head as it is ([`Aim::Current`]),
/// turned towards the target ([`Aim::AtTarget`]) or at given angles ([`Aim::Head`]).
pub fn visibility_for_agent(
    world: &World,
    agent: AgentId,
    target: ObjectId,
    aim: Aim,
    resolution: usize,
) -> Visibility {
    visibility_for_agent_upto(world, agent, target, aim, resolution, None)
}

/// [`visibility_for_agent`] with [`visibility_from_upto`]'s early stop above `stop_above`.
pub fn visibility_for_agent_upto(
    world: &World,
    agent: AgentId,
    target: ObjectId,
    aim: Aim,
    resolution: usize,
    stop_above: Option<f32>,
) -> Visibility {
    let st = world.agent_state(agent);
    let eye = match aim {
        Aim::Current => world.eye_pose(agent),
        Aim::AtTarget => {
            let mut q = st.q.clone();
            let centre = world.object_aabb(target).center();
            aim_head(world, agent, st.base, &mut q, centre)
        }
        Aim::Head { pan, tilt } => {
            let info = world.agent(agent);
            let mut q = st.q.clone();
            if let Some(r) = info.effort.head_pan {
                q[r.dof] = pan.clamp(r.lower, r.upper);
            }
            if let Some(r) = info.effort.head_tilt {
                q[r.dof] = tilt.clamp(r.lower, r.upper);
            }
            info.model.link_pose_by_id(st.base, &q, info.eye_link)
        }
    };
    visibility_from_upto(
        world,
        target,
        &eye,
        world.agent(agent).fov,
        resolution,
        stop_above,
    )
}
