//! The renderer: id buffer, depth, PNG output, views.

use std::path::Path;

use geometry::render::{Camera, agent_camera, render};
use geometry::scene::Scene;
use geometry::world::{BodyOwner, World};
use parry3d::math::Vector;

const SCENE: &str = r#"
[[objects]]
name = "red"
shape = { box = [0.2, 0.2, 0.2] }
pose = { xyz = [2.0, -0.5, 1.0] }
colour = [200, 30, 30]

[[objects]]
name = "blue"
shape = { cylinder = { radius = 0.2, half_height = 0.2 } }
pose = { xyz = [2.0, 0.5, 1.0] }
colour = [30, 30, 200]
"#;

fn world() -> World {
    World::from_scene(Scene::from_str(SCENE, "r.toml", Path::new("."), "r").unwrap()).unwrap()
}

#[test]
fn id_buffer_sees_each_object_on_its_side() {
    let w = world();
    let cam = Camera::look_at(
        Vector::new(0.0, 0.0, 1.0),
        Vector::new(2.0, 0.0, 1.0),
        1.2,
        0.9,
    );
    let img = render(&w, &cam, 120, 90);
    let red = BodyOwner::Object(w.object_id("red").unwrap());
    let blue = BodyOwner::Object(w.object_id("blue").unwrap());
    assert!(img.count(red) > 100 && img.count(blue) > 100);
    // y is to the left: blue (y = +0.5) shows on the left half, red on the right half.
    let mid = 90 / 2 * 120;
    assert_eq!(img.ids[mid + 30], Some(blue));
    assert_eq!(img.ids[mid + 90], Some(red));
    // Depth to the red box's front face (x = 1.8) along the forward axis.
    let d = img.depth[mid + 90];
    assert!((d - 1.8).abs() < 0.05, "{d}");
    // Colours differ where the objects differ.
    let px = |k: usize| [img.rgb[3 * k], img.rgb[3 * k + 1], img.rgb[3 * k + 2]];
    assert!(px(mid + 90)[0] > px(mid + 90)[2]);
    assert!(px(mid + 30)[2] > px(mid + 30)[0]);
}

#[test]
fn top_view_and_png_round_trip() {
    let w = world();
    let cam = Camera::top(&w.bounds(), 1.0);
    let img = render(&w, &cam, 64, 64);
    let red = BodyOwner::Object(w.object_id("red").unwrap());
    assert!(img.count(red) > 20);
    let path = std::env::temp_dir().join(format!("htngtp-render-{}.png", std::process::id()));
    img.save_png(&path).unwrap();
    let back = image::open(&path).unwrap().to_rgb8();
    assert_eq!(back.dimensions(), (64, 64));
    assert_eq!(back.as_raw(), &img.rgb);
    let _ = std::fs::remove_file(&path);
}

#[test]
fn the_member_sees_the_desk_and_the_robot() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("../..");
    let w = World::load(root.join("domains/library/scene.toml")).unwrap();
    let member = w.agent_id("member").unwrap();
    let pr2 = w.agent_id("pr2").unwrap();
    let img = render(&w, &agent_camera(&w, member), 160, 120);
    let desk = BodyOwner::Object(w.object_id("desk").unwrap());
    assert!(
        img.count(desk) > 160 * 120 / 10,
        "the desk fills the lower view"
    );
    let robot_pixels = img
        .ids
        .iter()
        .filter(|o| matches!(o, Some(BodyOwner::Agent(a, _)) if *a == pr2))
        .count();
    assert!(robot_pixels > 100, "the PR2 stands across the desk");
}
