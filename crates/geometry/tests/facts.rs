//! on / inside / covered-by on constructed stacks.

use std::path::Path;

use geometry::facts::{FactParams, covered_by, inside, on, relations};
use geometry::scene::Scene;
use geometry::world::World;

const STACK: &str = r#"
[[objects]]
name = "table"
shape = { box = [0.5, 0.4, 0.375] }
pose = { xyz = [0, 0, 0.375] }
support = true

[[objects]]
name = "book-a"
shape = { box = [0.1, 0.15, 0.02] }
pose = { xyz = [0.1, 0.0, 0.77] }
movable = true

[[objects]]
name = "book-b"
shape = { box = [0.12, 0.16, 0.02] }
pose = { xyz = [0.1, 0.0, 0.812], yaw = 10 }
movable = true

[[objects]]
name = "far-book"
shape = { box = [0.1, 0.15, 0.02] }
pose = { xyz = [2.0, 0.0, 0.77] }
movable = true

[[objects]]
name = "crate"
movable = false
support = true
container = true
pose = { xyz = [-1.0, 0, 0] }
surfaces = [{ centre = [0, 0, 0.02], half_extents = [0.18, 0.18] }]
parts = [
  { shape = { box = [0.2, 0.2, 0.01] }, pose = { xyz = [0, 0, 0.01] } },
  { shape = { box = [0.01, 0.2, 0.15] }, pose = { xyz = [0.19, 0, 0.15] } },
  { shape = { box = [0.01, 0.2, 0.15] }, pose = { xyz = [-0.19, 0, 0.15] } },
  { shape = { box = [0.2, 0.01, 0.15] }, pose = { xyz = [0, 0.19, 0.15] } },
  { shape = { box = [0.2, 0.01, 0.15] }, pose = { xyz = [0, -0.19, 0.15] } },
]

[[objects]]
name = "ball"
shape = { cylinder = { radius = 0.05, half_height = 0.05 } }
pose = { xyz = [-1.0, 0.02, 0.071] }
movable = true
"#;

fn world() -> World {
    World::from_scene(Scene::from_str(STACK, "stack.toml", Path::new("."), "stack").unwrap())
        .unwrap()
}

#[test]
fn on_follows_the_stack() {
    let w = world();
    let id = |n| w.object_id(n).unwrap();
    let tol = 0.05;
    assert!(on(&w, id("book-a"), id("table"), tol));
    assert!(on(&w, id("book-b"), id("book-a"), tol));
    assert!(
        !on(&w, id("book-b"), id("table"), tol),
        "not directly on the table"
    );
    assert!(!on(&w, id("book-a"), id("book-b"), tol), "below is not on");
    assert!(
        !on(&w, id("far-book"), id("table"), tol),
        "outside the footprint"
    );
    assert!(on(&w, id("ball"), id("crate"), tol), "on the crate's floor");
}

#[test]
fn covered_by_is_the_object_on_top() {
    let w = world();
    let id = |n| w.object_id(n).unwrap();
    assert!(covered_by(&w, id("book-a"), id("book-b"), 0.05));
    assert!(!covered_by(&w, id("book-b"), id("book-a"), 0.05));
    assert!(!covered_by(&w, id("book-a"), id("table"), 0.05));
}

#[test]
fn inside_needs_the_centre_in_the_container() {
    let w = world();
    let id = |n| w.object_id(n).unwrap();
    assert!(inside(&w, id("ball"), id("crate"), 0.05));
    assert!(
        !inside(&w, id("book-a"), id("table"), 0.05),
        "on top is not inside"
    );
    assert!(!inside(&w, id("far-book"), id("crate"), 0.05));
}

#[test]
fn moving_an_object_changes_its_relations() {
    let mut w = world();
    let id = |w: &World, n| w.object_id(n).unwrap();
    let (b, t) = (id(&w, "book-b"), id(&w, "table"));
    let mut p = w.object_pose(b);
    p.translation.x = -0.3;
    p.translation.z = 0.772;
    w.set_object_pose(b, p);
    assert!(on(&w, b, t, 0.05));
    let rel = relations(&w, &FactParams::default());
    let has = |pred: &str, a: &str, b: &str| {
        rel.iter()
            .any(|f| f.predicate == pred && f.args == [a.to_string(), b.to_string()])
    };
    assert!(has("on", "book-b", "table"));
    assert!(!has("covered-by", "book-a", "book-b"));
    assert!(has("inside", "ball", "crate"));
}
