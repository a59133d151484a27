//! Scene files: the library scene loads; malformed scenes give `FILE: key.path: reason` errors
//! and never panic; meshes, supports and world mutations behave.

use std::path::{Path, PathBuf};

use geometry::scene::{Scene, ShapeKind};
use geometry::world::World;
use parry3d::math::{Pose, Vector};

fn root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../..")
}

#[test]
fn library_scene_loads_with_the_agreed_names() {
    let world = World::load(root().join("domains/library/scene.toml")).unwrap();
    for name in [
        "grey-book",
        "white-book",
        "pos-machine",
        "pos-stand",
        "platform",
        "desk",
        "shelf",
        "table",
    ] {
        assert!(world.object_id(name).is_some(), "missing object {name}");
    }
    assert!(world.agent_id("pr2").is_some());
    assert!(world.agent_id("member").is_some());
    let book = world.object_id("grey-book").unwrap();
    assert!(world.object(book).movable);
    let desk = world.object_id("desk").unwrap();
    assert!(!world.object(desk).movable);
    assert!(!world.object(desk).surfaces.is_empty());
}

#[test]
fn cluttered_desk_scene_loads() {
    let world = World::load(root().join("domains/library/cluttered-desk.toml")).unwrap();
    for name in ["big-book-1", "big-book-2", "desk", "table"] {
        assert!(world.object_id(name).is_some(), "missing object {name}");
    }
    assert!(world.agent_id("pr2").is_some() && world.agent_id("member").is_some());
}

/// Every file in tests/bad_scenes/*.toml starts with `# expect: TEXT`; loading must fail with an
/// error that names the file and contains TEXT.
#[test]
fn malformed_scenes_give_clear_errors() {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/bad_scenes");
    let mut n = 0;
    for entry in std::fs::read_dir(&dir).unwrap() {
        let path = entry.unwrap().path();
        if path.extension().is_none_or(|e| e != "toml") {
            continue;
        }
        n += 1;
        let text = std::fs::read_to_string(&path).unwrap();
        let expect = text
            .lines()
            .next()
            .and_then(|l| l.strip_prefix("# expect: "))
            .unwrap_or_else(|| panic!("{}: first line must be `# expect: ...`", path.display()));
        let result = std::panic::catch_unwind(|| World::load(&path));
        let err = match result {
            Ok(Ok(_)) => panic!("{} loaded but should fail", path.display()),
            Ok(Err(e)) => e.to_string(),
            Err(_) => panic!("{} panicked", path.display()),
        };
        assert!(
            err.starts_with(&path.display().to_string()),
            "{}: error does not name the file: {err}",
            path.display()
        );
        assert!(
            err.contains(expect.trim_end()),
            "{}: expected `{expect}` in `{err}`",
            path.display()
        );
    }
    assert!(n >= 10, "only {n} malformed scenes");
}

#[test]
fn syntax_errors_have_line_and_column_and_key_path() {
    let text = "[[objects]]\nname = \"a\"\nshape = { box = [1, 2, 3] }\n\n[[objects]]\nname = \"b\"\nshape = { box = [1, 'x', 3] }\n";
    let e = Scene::from_str(text, "t.toml", Path::new("."), "t").unwrap_err();
    assert_eq!(e.line_col, Some((7, 21)), "{e}");
    assert_eq!(e.key_path, "objects[1].shape.box[1]", "{e}");
    assert!(
        e.to_string()
            .starts_with("t.toml:7:21: objects[1].shape.box[1]: "),
        "{e}"
    );
}

#[test]
fn garbage_never_panics() {
    let mut rng = fastrand::Rng::with_seed(7);
    let good = std::fs::read_to_string(root().join("domains/library/scene.toml")).unwrap();
    let bytes = good.as_bytes();
    for _ in 0..300 {
        let mut b = bytes.to_vec();
        for _ in 0..rng.usize(1..6) {
            let i = rng.usize(..b.len());
            b[i] = *rng.choice(b"[]{}=,.\"0123456789-xyz \n").unwrap();
        }
        let text = String::from_utf8_lossy(&b);
        let base = root().join("domains/library");
        let r = std::panic::catch_unwind(|| {
            Scene::from_str(&text, "fuzz.toml", &base, "fuzz").and_then(World::from_scene)
        });
        assert!(r.is_ok(), "panicked on:\n{text}");
    }
}

#[test]
fn meshes_load_and_supports_are_derived() {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/scenes");
    let world = World::load(dir.join("meshes.toml")).unwrap();
    let cube = world.object_id("cube").unwrap();
    assert!(matches!(
        world.object(cube).kind,
        ShapeKind::Mesh { triangles: 12, .. }
    ));
    let aabb = world.object_aabb(cube);
    assert!((aabb.maxs.z - 0.2).abs() < 1e-5 && aabb.mins.z.abs() < 1e-5);
    let top = world.object(cube).surfaces[0];
    assert!((top.centre.z - 0.1).abs() < 1e-5);
    assert!((top.half_extents[0] - 0.1).abs() < 1e-5);
    let tetra = world.object_id("tetra").unwrap();
    assert!(matches!(
        world.object(tetra).kind,
        ShapeKind::Mesh { triangles: 4, .. }
    ));
}

#[test]
fn worlds_clone_cheaply_and_mutate_independently() {
    let world = World::load(root().join("domains/library/scene.toml")).unwrap();
    let book = world.object_id("grey-book").unwrap();
    let mut w2 = world.clone();
    w2.set_object_pose(book, Pose::from_translation(Vector::new(0.1, 0.3, 0.8)));
    assert!(std::sync::Arc::ptr_eq(world.model(), w2.model()));
    assert_ne!(world.object_pose(book), w2.object_pose(book));

    // Attach the book to the PR2's right gripper: it follows the arm.
    let pr2 = w2.agent_id("pr2").unwrap();
    let hand = w2.agent(pr2).hand_links[0];
    w2.attach(book, pr2, hand);
    let before = w2.object_pose(book);
    let st = w2.agent_state(pr2).clone();
    let mut q = st.q.clone();
    let lift = w2.agent(pr2).model.dof_index("torso_lift_joint").unwrap();
    q[lift] += 0.1;
    w2.set_agent_config(pr2, st.base, &q);
    let after = w2.object_pose(book);
    assert!((after.translation.z - before.translation.z - 0.1).abs() < 1e-4);
    assert!(
        w2.obstacles().all(|(id, ..)| id != book),
        "held objects are not obstacles"
    );
    w2.detach(book);
    assert!(w2.obstacles().any(|(id, ..)| id == book));
}

/// Things resting on each other touch, and half a millimetre of overlap (rounding in a
/// hand-written scene) is not a collision: such scenes load.
#[test]
fn touching_objects_load() {
    let text = r#"
[[objects]]
name = "desk"
shape = { box = [0.5, 0.5, 0.375] }
pose = { xyz = [0, 0, 0.375] }
support = true

[[objects]]
name = "book"
shape = { box = [0.1, 0.14, 0.02] }
pose = { xyz = [0, 0, 0.77] }
movable = true

[[objects]]
name = "other-book"
shape = { box = [0.1, 0.14, 0.02] }
pose = { xyz = [0, 0, 0.8095] }
movable = true
"#;
    let scene = geometry::scene::Scene::from_str(text, "t.toml", Path::new("."), "t").unwrap();
    assert!(World::from_scene(scene).is_ok());
}

/// A scene of `n` small boxes on a 100-wide grid, the last one (if `overlap`) placed inside
/// the one before it.
fn many_boxes(n: usize, overlap: bool) -> String {
    let mut text = String::new();
    for i in 0..n {
        let (x, y) = if overlap && i == n - 1 {
            (((i - 1) % 100) as f32 * 0.05, ((i - 1) / 100) as f32 * 0.05)
        } else {
            ((i % 100) as f32 * 0.05, (i / 100) as f32 * 0.05)
        };
        text += &format!(
            "[[objects]]\nname = \"o{i}\"\nmovable = true\nshape = {{ box = [0.01, 0.01, 0.01] }}\npose = {{ xyz = [{x}, {y}, 0.02] }}\n"
        );
    }
    text
}

/// At most 10,000 objects; among many, the initial overlap is found (by a sweep, not by trying
/// 50 M pairs) and named as in a small scene.
#[test]
fn object_count_is_capped_and_overlaps_among_many_are_found() {
    let dir = Path::new("/nonexistent");
    let e = Scene::from_str(&many_boxes(10_001, false), "big.toml", dir, "big").unwrap_err();
    assert!(
        e.to_string()
            .contains("objects: 10001 objects, more than the 10000 a scene may have"),
        "{e}"
    );
    let scene = Scene::from_str(&many_boxes(10_000, false), "ok.toml", dir, "ok").unwrap();
    assert!(World::from_scene(scene).is_ok());
    let scene = Scene::from_str(&many_boxes(10_000, true), "bad.toml", dir, "bad").unwrap();
    let Err(e) = World::from_scene(scene) else {
        panic!("an overlap among 10,000 objects was not found");
    };
    let e = e.to_string();
    assert!(e.contains("`o9999` starts inside `o9998`"), "{e}");
}

/// `posture` names one `group_state` or a list of them (MoveIt names one per group: a
/// two-armed robot's postures are two), applied in order before `joints`.
#[test]
fn a_posture_may_be_a_list_of_group_states() {
    let urdf = root().join("models/fetch.urdf");
    let scene = |posture: &str| {
        let text = format!(
            "[[agents]]\nname = \"fetch\"\nkind = \"robot\"\nurdf = {:?}\nposture = {posture}\n",
            urdf.display().to_string()
        );
        let scene = Scene::from_str(&text, "posture.toml", &root(), "posture").unwrap();
        World::from_scene(scene).unwrap()
    };
    let one = scene("\"tucked\"");
    let list = scene("[\"tucked\"]");
    let fetch = one.agent_id("fetch").unwrap();
    assert_eq!(one.agent_state(fetch).q, list.agent_state(fetch).q);
    let none = scene("[]");
    assert_ne!(one.agent_state(fetch).q, none.agent_state(fetch).q);
}

/// A folder `htngtp-NAME-PID` holding `arm.urdf`: a 0.2 m base box (its bottom at the base
/// frame) and an upper link on one revolute joint.
fn one_joint_arm(name: &str) -> PathBuf {
    let dir = std::path::Path::new(env!("CARGO_TARGET_TMPDIR"))
        .join(format!("htngtp-{name}-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    std::fs::write(
        dir.join("arm.urdf"),
        r#"<robot name="arm">
  <link name="base"><collision><origin xyz="0 0 0.05"/><geometry><box size="0.2 0.2 0.1"/></geometry></collision></link>
  <link name="upper"><collision><origin xyz="0 0 0.2"/><geometry><box size="0.05 0.05 0.2"/></geometry></collision></link>
  <joint name="turn" type="revolute"><parent link="base"/><child link="upper"/><origin xyz="0 0 0.1"/>
    <axis xyz="0 0 1"/><limit lower="-3" upper="3" effort="1" velocity="1"/></joint>
</robot>"#,
    )
    .unwrap();
    dir
}

/// A robot whose base rests flush on its table (an arm bolted to a table top, `base.z` the
/// table's height) is refused at load, naming both and saying what to do: the planner counts
/// touching as a collision, so every motion of it would fail; a millimetre up, it loads.
#[test]
fn a_robot_base_touching_the_scene_is_refused_with_the_fix() {
    let dir = one_joint_arm("flush-base");
    let scene = |z: &str| {
        format!(
            r#"
[[objects]]
name = "table"
shape = {{ box = [0.5, 0.5, 0.375] }}
pose = {{ xyz = [0, 0, 0.375] }}
support = true

[[agents]]
name = "arm"
kind = "robot"
urdf = "arm.urdf"
eye = "upper"
hands = ["upper"]
shoulders = ["upper"]
base = {{ x = 0, y = 0, yaw = 0, z = {z} }}
"#
        )
    };
    let flush = Scene::from_str(&scene("0.75"), "flush.toml", &dir, "flush").unwrap();
    let e = World::from_scene(flush).unwrap_err().to_string();
    assert!(
        e.contains("agents[0]: `arm` (its link `base`, fixed to its base) touches `table`")
            && e.contains("a millimetre up"),
        "{e}"
    );
    let raised = Scene::from_str(&scene("0.751"), "raised.toml", &dir, "raised").unwrap();
    assert!(World::from_scene(raised).is_ok());
}

/// An SRDF whose end effector ends no group (none holds its parent link) says so at load,
/// naming the end effector and what to add, instead of asking for an end effector.
#[test]
fn an_end_effector_ending_no_arm_is_named() {
    let dir = one_joint_arm("orphan-hand");
    std::fs::write(
        dir.join("arm.srdf"),
        r#"<robot name="arm">
  <group name="hand"><link name="upper"/></group>
  <end_effector name="hand" parent_link="upper" group="hand"/>
</robot>"#,
    )
    .unwrap();
    let text = r#"
[[agents]]
name = "arm"
kind = "robot"
urdf = "arm.urdf"
srdf = "arm.srdf"
eye = "upper"
base = { x = 0, y = 0, yaw = 0 }
"#;
    let scene = Scene::from_str(text, "orphan.toml", &dir, "orphan").unwrap();
    let e = World::from_scene(scene).unwrap_err().to_string();
    assert!(
        e.contains("no shoulders links: the SRDF's end effector `hand` (parent_link `upper`) ends no arm group")
            && e.contains("give it a `parent_group`"),
        "{e}"
    );
}
