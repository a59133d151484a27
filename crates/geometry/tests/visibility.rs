//! Pixel visibility with known answers on constructed scenes.

mod common;

use std::path::Path;

use geometry::render::look_rotation;
use geometry::scene::Scene;
use geometry::visibility::{Aim, visibility_for_agent, visibility_from};
use geometry::world::World;
use parry3d::math::{Pose, Vector};

fn world(objects: &str) -> World {
    let scene = Scene::from_str(objects, "test.toml", Path::new("."), "test").unwrap();
    World::from_scene(scene).unwrap()
}

fn eye_looking(from: Vector, at: Vector) -> Pose {
    Pose::from_parts(from, look_rotation(at - from))
}

const TARGET: &str = "[[objects]]\nname = \"target\"\nshape = { box = [0.05, 0.2, 0.2] }\npose = { xyz = [2.0, 0.0, 1.0] }\n";
const FOV: [f32; 2] = [1.2, 0.9];

#[test]
fn unoccluded_object_in_view_is_fully_visible() {
    let w = world(TARGET);
    let t = w.object_id("target").unwrap();
    let eye = eye_looking(Vector::new(0.0, 0.0, 1.0), Vector::new(2.0, 0.0, 1.0));
    let v = visibility_from(&w, t, &eye, FOV, 64);
    assert!(v.ideal > 1000, "{v:?}");
    assert!(v.fraction() > 0.999, "{v:?}");
}

#[test]
fn object_behind_a_wall_is_invisible() {
    let w = world(&format!(
        "{TARGET}[[objects]]\nname = \"wall\"\nshape = {{ box = [0.05, 1.0, 1.0] }}\npose = {{ xyz = [1.0, 0.0, 1.0] }}\n"
    ));
    let t = w.object_id("target").unwrap();
    let eye = eye_looking(Vector::new(0.0, 0.0, 1.0), Vector::new(2.0, 0.0, 1.0));
    let v = visibility_from(&w, t, &eye, FOV, 64);
    assert!(v.ideal > 1000);
    assert_eq!(v.shown, 0, "{v:?}");
}

#[test]
fn object_half_behind_an_occluder_is_half_visible() {
    // The occluder's edge is at y = 0, the eye too: it hides exactly the target's y < 0 half.
    let w = world(&format!(
        "{TARGET}[[objects]]\nname = \"panel\"\nshape = {{ box = [0.05, 0.25, 0.5] }}\npose = {{ xyz = [1.0, -0.25, 1.0] }}\n"
    ));
    let t = w.object_id("target").unwrap();
    let eye = eye_looking(Vector::new(0.0, 0.0, 1.0), Vector::new(2.0, 0.0, 1.0));
    let v = visibility_from(&w, t, &eye, FOV, 64);
    assert!((v.fraction() - 0.5).abs() < 0.1, "{v:?}");
    // Resolution changes the estimate only a little.
    let v16 = visibility_from(&w, t, &eye, FOV, 16);
    assert!((v16.fraction() - 0.5).abs() < 0.1, "{v16:?}");
}

#[test]
fn object_outside_the_field_of_view_is_invisible() {
    let w = world(TARGET);
    let t = w.object_id("target").unwrap();
    // Looking the other way.
    let eye = eye_looking(Vector::new(0.0, 0.0, 1.0), Vector::new(-2.0, 0.0, 1.0));
    assert_eq!(visibility_from(&w, t, &eye, FOV, 64).shown, 0);
    // Looking 80 degrees to the side with a 70-degree field of view.
    let side = Vector::new(80f32.to_radians().cos(), 80f32.to_radians().sin(), 0.0);
    let eye = eye_looking(
        Vector::new(0.0, 0.0, 1.0),
        Vector::new(0.0, 0.0, 1.0) + side,
    );
    let v = visibility_from(&w, t, &eye, [70f32.to_radians(), 50f32.to_radians()], 64);
    assert_eq!(v.shown, 0, "{v:?}");
    assert!(v.ideal > 0);
}

#[test]
fn object_across_the_edge_of_the_view_is_partly_visible() {
    let w = world(TARGET);
    let t = w.object_id("target").unwrap();
    // Turn the eye so that the target's centre lies exactly on the left edge of the view.
    let half = 0.5 * FOV[0];
    let dir = Vector::new(half.cos(), -half.sin(), 0.0);
    let eye = eye_looking(Vector::new(0.0, 0.0, 1.0), Vector::new(0.0, 0.0, 1.0) + dir);
    let v = visibility_from(&w, t, &eye, FOV, 64);
    assert!((v.fraction() - 0.5).abs() < 0.1, "{v:?}");
}

#[test]
fn pixels_are_equal_steps_in_the_eyes_image_plane() {
    // A panel facing the eye, from straight ahead to 51 degrees to the side (its near face at
    // x = 1.95, y from 0 to 2.38); the field of view reaches 35 degrees, u = tan 35 = 0.70 in
    // the eye's image plane, of the panel's 0 to 2.38 / 1.95 = 1.22: 0.574 of its pixels.
    // (Rays in a camera aimed at the panel's centre would weigh its near part more: 0.69.)
    let w = world(
        "[[objects]]\nname = \"panel\"\nshape = { box = [0.05, 1.19, 0.2] }\npose = { xyz = [2.0, 1.19, 1.0] }\n",
    );
    let t = w.object_id("panel").unwrap();
    let eye = eye_looking(Vector::new(0.0, 0.0, 1.0), Vector::new(2.0, 0.0, 1.0));
    let v = visibility_from(&w, t, &eye, [70f32.to_radians(), 50f32.to_radians()], 64);
    let expected = 35f32.to_radians().tan() / (2.38 / 1.95);
    assert!(
        (v.fraction() - expected).abs() < 0.03,
        "{v:?}, expected {expected}"
    );
}

#[test]
fn agents_see_what_is_in_front_of_them() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("../..");
    let w = World::load(root.join("domains/library/scene.toml")).unwrap();
    let member = w.agent_id("member").unwrap();
    let platform = w.object_id("platform").unwrap();
    let v = visibility_for_agent(&w, member, platform, Aim::Current, 64);
    assert!(
        v.fraction() > 0.9,
        "member sees the platform in front: {v:?}"
    );
    // The member's back is to the chair's backrest: turning the head cannot show what is
    // directly behind, and the grey book behind the screens stays hidden.
    let book = w.object_id("grey-book").unwrap();
    let v = visibility_for_agent(&w, member, book, Aim::AtTarget, 64);
    assert!(v.fraction() < 0.5, "{v:?}");
}

/// The paper's definition, literally: render the target alone and with the scene from the same
/// camera and count its pixels. The ray grid over the target agrees with it.
#[test]
fn agrees_with_counting_pixels_of_full_renders() {
    use geometry::render::{Camera, Projection, render};
    use geometry::world::BodyOwner;
    let occluded = world(&format!(
        "{TARGET}[[objects]]\nname = \"panel\"\nshape = {{ box = [0.05, 0.25, 0.5] }}\npose = {{ xyz = [1.0, -0.1, 1.05] }}\n"
    ));
    let alone = world(TARGET);
    let eye = eye_looking(Vector::new(0.0, 0.3, 1.2), Vector::new(2.0, 0.0, 1.0));
    let cam = Camera {
        pose: eye,
        projection: Projection::Perspective {
            fov_x: 0.4,
            fov_y: 0.4,
        },
    };
    let t = BodyOwner::Object(occluded.object_id("target").unwrap());
    let shown = render(&occluded, &cam, 200, 200).count(t) as f32;
    let ideal = render(&alone, &cam, 200, 200).count(t) as f32;
    let by_render = shown / ideal;
    let by_rays = visibility_from(
        &occluded,
        occluded.object_id("target").unwrap(),
        &eye,
        FOV,
        64,
    )
    .fraction();
    assert!(ideal > 1000.0);
    assert!(by_render > 0.05 && by_render < 0.95, "{by_render}");
    assert!(
        (by_render - by_rays).abs() < 0.05,
        "render {by_render} rays {by_rays}"
    );
}

#[test]
fn head_angles_decide_what_is_in_view() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("../..");
    let w = World::load(root.join("domains/library/scene.toml")).unwrap();
    let member = w.agent_id("member").unwrap();
    let platform = w.object_id("platform").unwrap();
    let ahead = visibility_for_agent(
        &w,
        member,
        platform,
        Aim::Head {
            pan: 0.0,
            tilt: 0.4,
        },
        32,
    );
    assert!(ahead.fraction() > 0.9, "{ahead:?}");
    // Head turned fully to one side and up: the platform in front leaves the view.
    let away = visibility_for_agent(
        &w,
        member,
        platform,
        Aim::Head {
            pan: 1.4,
            tilt: -0.8,
        },
        32,
    );
    assert!(away.fraction() < 0.1, "{away:?}");
}

/// The measure as first written: whole bodies as occluders (a compound tested as one shape),
/// every ray cast, no early stop. The optimised measure must give the same counts.
fn reference(
    w: &World,
    target: geometry::scene::ObjectId,
    eye: &Pose,
    fov: [f32; 2],
    res: usize,
) -> (u32, u32) {
    use geometry::world::BodyOwner;
    use parry3d::bounding_volume::BoundingVolume;
    use parry3d::query::Ray;
    let obj = w.object(target);
    let tpose = w.object_shape_pose(target);
    let e = eye.translation;
    let taabb = obj.shape.compute_aabb(&tpose);
    let lb = obj.shape.compute_local_aabb();
    // The eye's image plane when every corner lies within 80 degrees in front of the eye, else a
    // camera aimed at the target's centre.
    let rectangle = |rot: parry3d::math::Rotation| {
        let (mut a0, mut a1, mut b0, mut b1) = (f32::MAX, f32::MIN, f32::MAX, f32::MIN);
        let mut inside = true;
        for k in 0..8 {
            let c = Vector::new(
                if k & 1 == 0 { lb.mins.x } else { lb.maxs.x },
                if k & 2 == 0 { lb.mins.y } else { lb.maxs.y },
                if k & 4 == 0 { lb.mins.z } else { lb.maxs.z },
            );
            let l = rot.inverse() * (tpose.transform_point(c) - e);
            let x = l.x.max(1e-3);
            inside &= l.x > 1e-3 && (l.y / x).abs() <= 6.0 && (l.z / x).abs() <= 6.0;
            let (a, b) = ((l.y / x).clamp(-6.0, 6.0), (l.z / x).clamp(-6.0, 6.0));
            a0 = a0.min(a);
            a1 = a1.max(a);
            b0 = b0.min(b);
            b1 = b1.max(b);
        }
        ((a0, a1, b0, b1), inside)
    };
    let (rot, (a0, a1, b0, b1)) = match rectangle(eye.rotation) {
        (r, true) => (eye.rotation, r),
        _ => {
            let rot = look_rotation(taabb.center() - e);
            (rot, rectangle(rot).0)
        }
    };
    let mut region = taabb;
    region.take_point(e);
    let bodies = w.bodies();
    let occluders: Vec<_> = bodies
        .iter()
        .filter(|b| b.owner != BodyOwner::Object(target))
        .filter(|b| {
            b.shape.compute_aabb(&b.pose).intersects(&region) && !b.shape.contains_point(&b.pose, e)
        })
        .collect();
    let inv_eye = eye.rotation.inverse();
    let (tx, ty) = ((0.5 * fov[0]).tan(), (0.5 * fov[1]).tan());
    let (mut shown, mut ideal) = (0, 0);
    for j in 0..res {
        let b = b0 + (b1 - b0) * (j as f32 + 0.5) / res as f32;
        for i in 0..res {
            let a = a0 + (a1 - a0) * (i as f32 + 0.5) / res as f32;
            let dir = rot * Vector::new(1.0, a, b);
            let ray = Ray::new(e, dir);
            let Some(toi) = obj.shape.cast_ray(&tpose, &ray, f32::MAX, true) else {
                continue;
            };
            ideal += 1;
            let d = inv_eye * dir;
            if d.x <= 0.0 || (d.y / d.x).abs() > tx || (d.z / d.x).abs() > ty {
                continue;
            }
            if !occluders
                .iter()
                .any(|b| b.shape.intersects_ray(&b.pose, &ray, toi))
            {
                shown += 1;
            }
        }
    }
    (shown, ideal)
}

#[test]
fn the_optimised_measure_counts_as_the_reference_and_stops_only_when_it_may() {
    use geometry::visibility::visibility_from_upto;
    let mut w = World::load(concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../../domains/library/scene.toml"
    ))
    .unwrap();
    let member = w.agent_id("member").unwrap();
    let fov = w.agent(member).fov;
    let eye = w.eye_pose(member);
    let (mut partly, mut hidden, mut full, mut n) = (0, 0, 0, 0);
    for name in ["pos-machine", "grey-book"] {
        let o = w.object_id(name).unwrap();
        let start = w.object_pose(o);
        // A grid over the scene's furniture: in the shelf, behind the monitor, on the desk.
        for i in 0..24 {
            for j in 0..24 {
                for z in [0.1f32, 0.5, 0.8, 0.9, 1.3] {
                    let p = Vector::new(-1.3 + 0.08 * i as f32, -1.2 + 0.1 * j as f32, z);
                    w.set_object_pose(o, Pose::from_parts(p, start.rotation));
                    let (shown, ideal) = reference(&w, o, &eye, fov, 16);
                    let v = visibility_from(&w, o, &eye, fov, 16);
                    assert_eq!((v.shown, v.ideal), (shown, ideal), "{name} at {p:?}");
                    let f = v.fraction();
                    for m in [0.0f32, 0.25, 0.9] {
                        let u = visibility_from_upto(&w, o, &eye, fov, 16, Some(m));
                        assert_eq!(u.fraction() > m, f > m, "{name} at {p:?}, stop above {m}");
                        if f <= m {
                            assert_eq!(u, v, "{name} at {p:?}: no early stop below {m}");
                        }
                    }
                    n += 1;
                    if shown == 0 && ideal > 0 {
                        hidden += 1;
                    } else if shown == ideal {
                        full += 1;
                    } else {
                        partly += 1;
                    }
                }
            }
        }
    }
    // The sample holds every kind of case.
    assert!(
        hidden > 50 && partly > 50 && full > 50,
        "{n}: {hidden} hidden, {partly} partly, {full} full"
    );
}

/// A world with the target and a one-link robot whose collision is `geometry` (URDF), a long
/// slab turned across the view: as a mesh, a convex polyhedron whose world bounds it fills
/// badly. Files are written to a folder of its own, `name`.
fn slab_robot(name: &str, geometry: &str) -> World {
    let root = std::path::Path::new(env!("CARGO_TARGET_TMPDIR"))
        .join(format!("htngtp-visibility-{name}-{}", std::process::id()));
    std::fs::create_dir_all(&root).unwrap();
    std::fs::write(root.join("slab.stl"), common::box_stl([0.6, 0.03, 0.08])).unwrap();
    let urdf = format!(
        r#"<robot name="bot">
  <link name="base_link">
    <collision><origin xyz="1 0 1" rpy="0.6 0.5 0.7"/>
      <geometry>{geometry}</geometry></collision>
  </link>
</robot>"#
    );
    std::fs::write(root.join("bot.urdf"), urdf).unwrap();
    std::fs::write(root.join("bot.srdf"), r#"<robot name="bot"/>"#).unwrap();
    let scene = format!(
        r#"{TARGET}
[scene]
bounds = {{ min = [-1, -2, 0], max = [3, 2, 2] }}

[[agents]]
name = "bot"
kind = "robot"
urdf = "bot.urdf"
eye = "base_link"
hands = ["base_link"]
shoulders = ["base_link"]
colour = [30, 30, 200]
base = {{ x = 0, y = 0, yaw = 0 }}
"#
    );
    World::from_scene(Scene::from_str(&scene, "v.toml", &root, "v").unwrap()).unwrap()
}

/// A robot's mesh link hides what the same link as a box primitive hides (parry's exact slab
/// test), but for rays that graze its edges: GJK's ray casts on the hull call a few of those
/// either way (8 rays in the 144 queries here, of 32 x 32 rays each; 9 without the occluders' own
/// bounds).
#[test]
fn a_mesh_link_hides_what_the_same_box_hides() {
    let mut mesh = slab_robot("mesh", r#"<mesh filename="slab.stl"/>"#);
    let mut boxed = slab_robot("box", r#"<box size="1.2 0.06 0.16"/>"#);
    let eye = eye_looking(Vector::new(-0.5, 0.0, 1.0), Vector::new(2.0, 0.0, 1.0));
    let (mut partly, mut differ) = (0, 0);
    for i in 0..12 {
        for j in 0..12 {
            let p = Vector::new(2.0, -0.6 + 0.1 * i as f32, 0.5 + 0.1 * j as f32);
            let see = |w: &mut World| {
                let t = w.object_id("target").unwrap();
                w.set_object_pose(t, Pose::from_translation(p));
                visibility_from(w, t, &eye, [2.0, 2.0], 32)
            };
            let (m, b) = (see(&mut mesh), see(&mut boxed));
            assert_eq!(m.ideal, b.ideal);
            assert!(m.shown.abs_diff(b.shown) <= 1, "at {p:?}: {m:?} {b:?}");
            differ += (m.shown != b.shown) as usize;
            partly += (b.shown > 0 && b.shown < b.ideal) as usize;
        }
    }
    assert!(
        partly > 10 && differ <= 12,
        "{partly} partly hidden, {differ} differ"
    );
}
