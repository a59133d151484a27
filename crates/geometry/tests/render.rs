//! The renderer: id buffer, depth, PNG output, views.

mod common;

use std::path::Path;

use geometry::render::{Camera, agent_camera, render, render_visual};
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
    let path = std::path::Path::new(env!("CARGO_TARGET_TMPDIR"))
        .join(format!("htngtp-render-{}.png", std::process::id()));
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

/// A camera from above over the 2 m x 2 m square around the origin.
fn top_of_square() -> Camera {
    let area = parry3d::bounding_volume::Aabb::new(
        Vector::new(-1.0, -1.0, 0.0),
        Vector::new(1.0, 1.0, 1.0),
    );
    Camera::top(&area, 1.0)
}

/// A new folder `htngtp-visual-NAME-PID` for a test's files.
fn scratch(name: &str) -> std::path::PathBuf {
    let root = std::path::Path::new(env!("CARGO_TARGET_TMPDIR"))
        .join(format!("htngtp-visual-{name}-{}", std::process::id()));
    std::fs::create_dir_all(&root).unwrap();
    root
}

/// A one-link robot whose collision is a 0.1 m box and whose visual is `visual` (a mesh file
/// name), in a scene of its own; the world and the link's owner.
fn one_link_robot(dir: &str, visual: &str) -> (World, BodyOwner) {
    let root = scratch(dir);
    std::fs::write(root.join("big.stl"), common::box_stl([0.2, 0.2, 0.2])).unwrap();
    std::fs::write(root.join("bad.stl"), b"solid x\nfacet normal 0 0 1\n").unwrap();
    std::fs::write(
        root.join("bot.urdf"),
        format!(
            r#"<robot name="bot">
  <material name="red"><color rgba="0.9 0.1 0.1 1"/></material>
  <link name="base_link">
    <collision><origin xyz="0 0 0.5"/><geometry><box size="0.1 0.1 0.1"/></geometry></collision>
    <visual><origin xyz="0 0 0.5"/><geometry><mesh filename="{visual}"/></geometry>
      <material name="red"/></visual>
  </link>
</robot>"#
        ),
    )
    .unwrap();
    std::fs::write(root.join("bot.srdf"), r#"<robot name="bot"/>"#).unwrap();
    let scene = r#"
[scene]
bounds = { min = [-1, -1, 0], max = [1, 1, 1] }

[[agents]]
name = "bot"
kind = "robot"
urdf = "bot.urdf"
eye = "base_link"
hands = ["base_link"]
shoulders = ["base_link"]
colour = [30, 30, 200]
base = { x = 0, y = 0, yaw = 0 }
"#;
    let w = World::from_scene(Scene::from_str(scene, "v.toml", &root, "v").unwrap()).unwrap();
    let bot = w.agent_id("bot").unwrap();
    (w, BodyOwner::Agent(bot, 0))
}

#[test]
fn links_are_drawn_by_their_visual_meshes_in_the_material_colour() {
    let (w, link) = one_link_robot("big", "big.stl");
    let model = &w.agent(w.agent_id("bot").unwrap()).model;
    assert_eq!(model.links()[0].visuals.len(), 1);
    assert!(
        model.load_warnings().is_empty(),
        "{:?}",
        model.load_warnings()
    );
    let cam = top_of_square();
    let collision = render(&w, &cam, 200, 200);
    let (visual, warnings) = render_visual(&w, &cam, 200, 200);
    assert!(warnings.is_empty(), "{warnings:?}");
    // The visual box is 4 times as wide as the collision box: 16 times the pixels, about.
    let (c, v) = (collision.count(link), visual.count(link));
    assert!(
        c > 10 && v > 12 * c && v < 22 * c,
        "collision {c} px, visual {v} px"
    );
    // Drawn in the material's red, not the agent's blue; the collision picture in blue.
    let mid = 100 * 200 + 100;
    let px = |img: &geometry::render::Rendered| {
        [img.rgb[3 * mid], img.rgb[3 * mid + 1], img.rgb[3 * mid + 2]]
    };
    assert_eq!(visual.ids[mid], Some(link));
    assert!(px(&visual)[0] > 2 * px(&visual)[2], "{:?}", px(&visual));
    assert!(
        px(&collision)[2] > 2 * px(&collision)[0],
        "{:?}",
        px(&collision)
    );
    // Deterministic: the same picture again.
    assert_eq!(render_visual(&w, &cam, 200, 200).0.rgb, visual.rgb);
}

#[test]
fn a_missing_visual_mesh_is_a_warning_and_the_link_keeps_its_collision_shape() {
    let (w, link) = one_link_robot("missing", "nowhere.stl");
    let model = &w.agent(w.agent_id("bot").unwrap()).model;
    assert!(model.links()[0].visuals.is_empty());
    let warnings = model.load_warnings();
    assert!(
        warnings.len() == 1 && warnings[0].contains("nowhere.stl"),
        "{warnings:?}"
    );
    let cam = top_of_square();
    let (visual, _) = render_visual(&w, &cam, 100, 100);
    assert_eq!(visual.count(link), render(&w, &cam, 100, 100).count(link));
}

#[test]
fn an_unreadable_visual_mesh_falls_back_with_a_warning() {
    let (w, link) = one_link_robot("bad", "bad.stl");
    let cam = top_of_square();
    let (visual, warnings) = render_visual(&w, &cam, 100, 100);
    assert!(
        warnings.len() == 1 && warnings[0].contains("bad.stl") && warnings[0].contains("collision"),
        "{warnings:?}"
    );
    assert_eq!(visual.count(link), render(&w, &cam, 100, 100).count(link));
}

/// A robot whose eye sits inside the visual mesh of its head (a shell around the camera, as
/// Baxter's screen is), a red box in front of it.
fn robot_with_a_housed_eye() -> World {
    let root = scratch("housed");
    std::fs::write(root.join("head.stl"), common::box_stl([0.2, 0.2, 0.2])).unwrap();
    std::fs::write(
        root.join("bot.urdf"),
        r#"<robot name="bot">
  <link name="base_link">
    <collision><origin xyz="0 0 0.5"/><geometry><box size="0.1 0.1 0.1"/></geometry></collision>
    <visual><origin xyz="0 0 0.5"/><geometry><mesh filename="head.stl"/></geometry></visual>
  </link>
  <link name="eye"/>
  <joint name="eye_joint" type="fixed">
    <parent link="base_link"/><child link="eye"/><origin xyz="0 0 0.5"/>
  </joint>
</robot>"#,
    )
    .unwrap();
    std::fs::write(root.join("bot.srdf"), r#"<robot name="bot"/>"#).unwrap();
    let scene = r#"
[scene]
bounds = { min = [-1, -1, 0], max = [2, 1, 1] }

[[objects]]
name = "red"
shape = { box = [0.1, 0.2, 0.2] }
pose = { xyz = [1.2, 0.0, 0.5] }
colour = [200, 30, 30]

[[agents]]
name = "bot"
kind = "robot"
urdf = "bot.urdf"
eye = "eye"
hands = ["eye"]
shoulders = ["base_link"]
colour = [30, 30, 200]
base = { x = 0, y = 0, yaw = 0 }
"#;
    World::from_scene(Scene::from_str(scene, "h.toml", &root, "h").unwrap()).unwrap()
}

#[test]
fn an_eye_inside_its_heads_visual_mesh_sees_out_of_it() {
    let w = robot_with_a_housed_eye();
    let bot = w.agent_id("bot").unwrap();
    let model = &w.agent(bot).model;
    assert_eq!(model.rigid_links(model.link_id("eye").unwrap()), vec![0, 1]);
    let red = BodyOwner::Object(w.object_id("red").unwrap());
    // Drawn as any camera draws the world, the head's mesh fills the picture.
    let (walled, _) = render_visual(&w, &agent_camera(&w, bot), 80, 60);
    assert_eq!(walled.count(red), 0);
    assert!(walled.count(BodyOwner::Agent(bot, 0)) > 80 * 60 / 2);
    // From the eye, the housing is left out: the box ahead fills the middle.
    let (seen, warnings) = geometry::render::render_eye_view(&w, bot, 80, 60);
    assert!(warnings.is_empty(), "{warnings:?}");
    assert_eq!(seen.ids[30 * 80 + 40], Some(red));
    assert_eq!(seen.count(BodyOwner::Agent(bot, 0)), 0);
}
