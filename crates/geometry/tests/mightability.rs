//! Mightability maps on a small constructed room with a seated person.

use std::path::Path;

use geometry::mightability::{Mightability, MightabilityParams, cached};
use geometry::scene::Scene;
use geometry::world::World;
use parry3d::math::Vector;

fn room() -> World {
    let models = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../models");
    let text = format!(
        r#"
[scene]
bounds = {{ min = [-2.5, -2.5, -0.05], max = [2.5, 2.5, 2.0] }}

[[objects]]
name = "wall"
shape = {{ box = [0.05, 1.0, 1.0] }}
pose = {{ xyz = [1.5, 0.0, 1.0] }}

[[agents]]
name = "person"
kind = "human"
urdf = "{}"
sitting = true
base = {{ x = 0, y = 0, yaw = 0 }}
effort = {{ move_radius = 1.0 }}
"#,
        models.join("human.urdf").display()
    );
    World::from_scene(Scene::from_str(&text, "room.toml", Path::new("."), "room").unwrap()).unwrap()
}

#[test]
fn levels_grow_with_effort() {
    let w = room();
    let m = Mightability::compute(&w, &MightabilityParams::default());
    let a = w.agent_id("person").unwrap();
    // In front at eye height: seen without effort.
    assert_eq!(m.vis_level(a, Vector::new(1.0, 0.0, 1.2)), Some(0));
    // Behind the person: the head alone does not turn that far, the torso does.
    let behind = m.vis_level(a, Vector::new(-1.0, 0.0, 1.2));
    assert!(behind.is_some_and(|l| l == 2), "behind: {behind:?}");
    // Behind the wall: hidden from where the person sits (levels 0 to 3).
    let hidden = m.vis_level(a, Vector::new(2.0, 0.0, 1.0));
    assert!(hidden.is_none_or(|l| l == 4), "behind the wall: {hidden:?}");
    // Reach: half a metre in front of the shoulder is an arm's length, a metre needs a lean,
    // two metres a walk (or nothing).
    assert_eq!(m.reach_level(a, Vector::new(0.45, -0.2, 1.0)), Some(1));
    let lean = m.reach_level(a, Vector::new(0.95, 0.0, 0.8));
    assert!(lean.is_some_and(|l| l == 2), "lean: {lean:?}");
    let far = m.reach_level(a, Vector::new(-2.2, 0.0, 1.0));
    assert!(far.is_none_or(|l| l >= 3), "far: {far:?}");
    // Levels are cumulative.
    for l in 0..4 {
        assert!(m.count(a, l, true) <= m.count(a, l + 1, true));
        assert!(m.count(a, l, false) <= m.count(a, l + 1, false));
    }
}

#[test]
fn maps_are_cached_per_world_state() {
    let w = room();
    let p = MightabilityParams {
        cell: 0.1,
        ..MightabilityParams::default()
    };
    let m1 = cached(&w, &p);
    let m2 = cached(&w.clone(), &p);
    assert!(std::sync::Arc::ptr_eq(&m1, &m2));
    let mut moved = w.clone();
    let wall = moved.object_id("wall").unwrap();
    let mut pose = moved.object_pose(wall);
    pose.translation.x = 2.0;
    moved.set_object_pose(wall, pose);
    assert!(!std::sync::Arc::ptr_eq(&m1, &cached(&moved, &p)));
}

#[test]
fn library_maps_agree_with_the_exact_facts_on_the_books() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("../..");
    let w = World::load(root.join("domains/library/scene.toml")).unwrap();
    let m = Mightability::compute(&w, &MightabilityParams::default());
    let pr2 = w.agent_id("pr2").unwrap();
    let member = w.agent_id("member").unwrap();
    for book in ["grey-book", "white-book"] {
        let b = w.object_id(book).unwrap();
        // The robot reaches the books with an arm's extension; the seated member does not
        // reach them without walking.
        assert!(
            m.object_level(&w, pr2, b, false).is_some_and(|l| l <= 1),
            "{book}"
        );
        assert!(
            m.object_level(&w, member, b, false).is_none_or(|l| l >= 3),
            "{book}"
        );
        // The maps are optimistic about visibility (a cell counts when any ray reaches it):
        // never a higher level than the exact pixel measure's (the top of the big white book
        // shows over the screens to rays, though not half its pixels).
        let exact = geometry::facts::visible_effort(&w, member, b, &Default::default());
        let mapped = m.object_level(&w, member, b, true);
        assert!(exact.is_some_and(|e| e >= 3), "{book}: exact {exact:?}");
        assert!(
            mapped.is_some_and(|l| exact.is_some_and(|e| l <= e)),
            "{book}: maps {mapped:?}, exact {exact:?}"
        );
    }
}

#[test]
fn huge_rooms_get_coarser_cells() {
    let text = r#"
[scene]
bounds = { min = [-500, -500, 0], max = [500, 500, 10] }
[[objects]]
name = "box"
shape = { box = [1, 1, 1] }
pose = { xyz = [0, 0, 1] }
"#;
    let w = World::from_scene(Scene::from_str(text, "big.toml", Path::new("."), "big").unwrap())
        .unwrap();
    let m = Mightability::compute(&w, &MightabilityParams::default());
    assert!(m.grid.len() <= geometry::mightability::MAX_CELLS + 3 * 1024 * 1024);
    assert!(m.grid.cell > 0.05);
    assert!(m.occupied.count() > 0);
}
