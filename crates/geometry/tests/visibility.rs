//! Pixel visibility with known answers on constructed scenes.

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
