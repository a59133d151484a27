//! Robot descriptions through the built binary: a robot whose links collide as STL, COLLADA and
//! OBJ meshes loads, an SRDF posture starts it, and each kind of bad mesh, SRDF or URDF tree is
//! one clear line (file, element, what is wrong) with exit 3.

use std::path::{Path, PathBuf};
use std::process::{Command, Output, Stdio};

mod mesh_support;

use mesh_support::{binary_stl, box_triangles};

const EXE: &str = env!("CARGO_BIN_EXE_htngtp");

/// A fresh scratch directory for one test.
fn scratch(name: &str) -> PathBuf {
    let d = std::path::Path::new(env!("CARGO_TARGET_TMPDIR"))
        .join(format!("htngtp-meshes-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    d
}

/// A ROS package `name` in `dir/name` with a `meshes` folder; returns its folder.
fn package(dir: &Path, name: &str) -> PathBuf {
    let p = dir.join("src").join(name);
    std::fs::create_dir_all(p.join("meshes")).unwrap();
    std::fs::write(
        p.join("package.xml"),
        format!(
            "<?xml version=\"1.0\"?>\n<package format=\"2\">\n  <name>{name}</name>\n</package>\n"
        ),
    )
    .unwrap();
    p
}

/// A scene in `dir` with one robot whose link `body` has the collision elements `collisions`
/// (URDF text) and the visual elements `visuals`; returns the scene's path.
fn scene_with(dir: &Path, collisions: &str, visuals: &str) -> PathBuf {
    let urdf = format!(
        "<?xml version=\"1.0\"?>\n<robot name=\"meshbot\">\n  <link name=\"base\"/>\n  <link name=\"body\">\n{visuals}{collisions}  </link>\n  <joint name=\"lift\" type=\"prismatic\">\n    <parent link=\"base\"/><child link=\"body\"/>\n    <origin xyz=\"0 0 0.1\"/><axis xyz=\"0 0 1\"/><limit lower=\"0\" upper=\"0.2\" effort=\"1\" velocity=\"1\"/>\n  </joint>\n  <transmission name=\"t\"><type>SimpleTransmission</type></transmission>\n  <gazebo reference=\"body\"><material>Gazebo/Grey</material></gazebo>\n</robot>\n"
    );
    std::fs::write(dir.join("robot.urdf"), urdf).unwrap();
    let scene = dir.join("scene.toml");
    std::fs::write(
        &scene,
        "[scene]\nname = \"meshes\"\npackage_path = [\"src\"]\n\n[[agents]]\nname = \"bot\"\nkind = \"robot\"\nurdf = \"robot.urdf\"\neye = \"body\"\nshoulders = [\"body\"]\nhands = [\"body\"]\n",
    )
    .unwrap();
    scene
}

fn collision(uri: &str) -> String {
    format!("    <collision><geometry><mesh filename=\"{uri}\"/></geometry></collision>\n")
}

fn facts(scene: &Path, extra: &[&str]) -> Output {
    Command::new(EXE)
        .arg("facts")
        .arg(scene)
        .args(extra)
        .stdin(Stdio::null())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .output()
        .unwrap()
}

/// The run failed as bad input with one line of error that says each of `phrases`.
fn assert_bad_input(o: &Output, phrases: &[&str]) {
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(3), "{err}");
    let lines: Vec<&str> = err.lines().collect();
    assert_eq!(lines.len(), 1, "one line: {err}");
    assert!(!err.contains("panicked"), "{err}");
    for p in phrases {
        assert!(err.contains(p), "`{p}` in: {err}");
    }
}

#[test]
fn stl_collada_and_obj_meshes_load_with_several_collision_elements_per_link() {
    let dir = scratch("good");
    let pkg = package(&dir, "meshbot_description");
    let cube = box_triangles([-0.1, -0.1, -0.1], [0.1, 0.1, 0.1]);
    std::fs::write(pkg.join("meshes/body.stl"), binary_stl(&cube, 12)).unwrap();
    let mut ascii = String::from("solid body\n");
    for t in box_triangles([0.2, -0.05, 0.0], [0.3, 0.05, 0.1]) {
        ascii.push_str("facet normal 0 0 0\nouter loop\n");
        for v in t {
            ascii.push_str(&format!("vertex {} {} {}\n", v[0], v[1], v[2]));
        }
        ascii.push_str("endloop\nendfacet\n");
    }
    ascii.push_str("endsolid body\n");
    std::fs::write(dir.join("arm.STL"), ascii).unwrap();
    std::fs::write(
        dir.join("knob.obj"),
        "v 0 0 0.3\nv 0.1 0 0.3\nv 0 0.1 0.3\nv 0 0 0.4\nf 1 3 2\nf 1 2 4\nf 2 3 4\nf 3 1 4\n",
    )
    .unwrap();
    let collisions = [
        collision("package://meshbot_description/meshes/body.stl"),
        collision("arm.STL"),
        collision(&format!("file://{}", dir.join("knob.obj").display())),
        "    <collision><origin xyz=\"0 0 -0.3\"/><geometry><box size=\"0.1 0.1 0.1\"/></geometry></collision>\n"
            .to_string(),
        "    <collision><geometry><mesh filename=\"arm.STL\" scale=\"0.5 0.5 0.5\"/></geometry></collision>\n"
            .to_string(),
    ]
    .concat();
    let visuals = "    <visual><geometry><mesh filename=\"package://meshbot_description/meshes/body.dae\"/></geometry><material name=\"grey\"><color rgba=\"0.5 0.5 0.5 1\"/></material></visual>\n";
    let scene = scene_with(&dir, &collisions, visuals);
    let o = facts(&scene, &["--json"]);
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(0), "{err}");
    // The missing visual mesh is a warning naming the link and the file.
    assert!(err.contains("warning:"), "{err}");
    assert!(err.contains("link 'body': visual mesh"), "{err}");
    assert!(err.contains("body.dae"), "{err}");
}

#[test]
fn a_package_not_found_names_every_folder_searched() {
    let dir = scratch("nopkg");
    package(&dir, "meshbot_description");
    let extra = scratch("nopkg-extra");
    let scene = scene_with(&dir, &collision("package://other_robot/meshes/a.stl"), "");
    let o = facts(&scene, &["--package-path", extra.to_str().unwrap()]);
    assert_bad_input(
        &o,
        &[
            "robot.urdf:4",
            "link 'body'",
            "package://other_robot/meshes/a.stl",
            "package `other_robot` not found",
            &extra.display().to_string(),
            &dir.join("src").display().to_string(),
        ],
    );
}

#[test]
fn a_missing_collision_mesh_names_the_uri_and_the_file() {
    let dir = scratch("missing");
    let pkg = package(&dir, "meshbot_description");
    let scene = scene_with(
        &dir,
        &collision("package://meshbot_description/meshes/gone.stl"),
        "",
    );
    let o = facts(&scene, &[]);
    assert_bad_input(
        &o,
        &[
            "link 'body'",
            "package://meshbot_description/meshes/gone.stl",
            &pkg.join("meshes/gone.stl").display().to_string(),
            "not found",
        ],
    );
}

#[test]
fn a_truncated_stl_is_refused() {
    let dir = scratch("truncated");
    let cube = box_triangles([0.0; 3], [0.1; 3]);
    std::fs::write(dir.join("cut.stl"), binary_stl(&cube[..2], 12)).unwrap();
    let scene = scene_with(&dir, &collision("cut.stl"), "");
    let o = facts(&scene, &[]);
    assert_bad_input(
        &o,
        &[
            "link 'body'",
            "cut.stl",
            "declares 12 triangles",
            "truncated",
        ],
    );
}

#[test]
fn a_collada_file_without_triangles_is_refused() {
    let dir = scratch("dae");
    let dae = r##"<?xml version="1.0" encoding="utf-8"?>
<COLLADA xmlns="http://www.collada.org/2005/11/COLLADASchema" version="1.4.1">
  <asset><unit meter="1"/><up_axis>Z_UP</up_axis></asset>
  <library_geometries>
    <geometry id="g"><mesh>
      <source id="p"><float_array id="pa" count="6">0 0 0 1 0 0</float_array>
        <technique_common><accessor source="#pa" count="2" stride="3">
          <param name="X" type="float"/><param name="Y" type="float"/><param name="Z" type="float"/>
        </accessor></technique_common></source>
      <vertices id="v"><input semantic="POSITION" source="#p"/></vertices>
      <lines count="1"><input semantic="VERTEX" source="#v" offset="0"/><p>0 1</p></lines>
    </mesh></geometry>
  </library_geometries>
  <library_visual_scenes><visual_scene id="s"><node id="n">
    <instance_geometry url="#g"/></node></visual_scene></library_visual_scenes>
  <scene><instance_visual_scene url="#s"/></scene>
</COLLADA>
"##;
    std::fs::write(dir.join("lines.dae"), dae).unwrap();
    let scene = scene_with(&dir, &collision("lines.dae"), "");
    let o = facts(&scene, &[]);
    assert_bad_input(&o, &["link 'body'", "lines.dae", "no triangles"]);
}

#[test]
fn a_mesh_over_the_triangle_cap_is_refused() {
    let dir = scratch("cap");
    let t = [[0.0f32, 0.0, 0.0], [0.1, 0.0, 0.0], [0.0, 0.1, 0.0]];
    let many = vec![t; 250_001];
    std::fs::write(dir.join("huge.stl"), binary_stl(&many, 250_001)).unwrap();
    let scene = scene_with(&dir, &collision("huge.stl"), "");
    let o = facts(&scene, &[]);
    assert_bad_input(
        &o,
        &[
            "link 'body'",
            "huge.stl",
            "250001 triangles, more than the 250000",
        ],
    );
}

#[test]
fn a_collada_file_with_a_bad_index_is_refused_without_a_panic() {
    let dir = scratch("dae-index");
    let dae = r##"<?xml version="1.0" encoding="utf-8"?>
<COLLADA xmlns="http://www.collada.org/2005/11/COLLADASchema" version="1.4.1">
  <asset><unit meter="1"/></asset>
  <library_geometries><geometry id="g"><mesh>
    <source id="p"><float_array id="pa" count="9">0 0 0 1 0 0 0 1 0</float_array>
      <technique_common><accessor source="#pa" count="3" stride="3">
        <param name="X" type="float"/><param name="Y" type="float"/><param name="Z" type="float"/>
      </accessor></technique_common></source>
    <vertices id="v"><input semantic="POSITION" source="#p"/></vertices>
    <triangles count="1"><input semantic="VERTEX" source="#v" offset="0"/><p>0 1 9</p></triangles>
  </mesh></geometry></library_geometries>
  <library_visual_scenes><visual_scene id="s"><node id="n">
    <instance_geometry url="#g"/></node></visual_scene></library_visual_scenes>
  <scene><instance_visual_scene url="#s"/></scene>
</COLLADA>
"##;
    std::fs::write(dir.join("bad.dae"), dae).unwrap();
    let scene = scene_with(&dir, &collision("bad.dae"), "");
    let o = facts(&scene, &[]);
    assert_bad_input(&o, &["link 'body'", "bad.dae"]);
}

/// `scene_with`'s robot with the SRDF `srdf` (its body only) beside it.
fn scene_with_srdf(dir: &Path, srdf: &str) -> PathBuf {
    let scene = scene_with(dir, "", "");
    std::fs::write(
        dir.join("robot.srdf"),
        format!("<?xml version=\"1.0\"?>\n<robot name=\"meshbot\">\n{srdf}</robot>\n"),
    )
    .unwrap();
    scene
}

#[test]
fn an_srdf_naming_an_unknown_link_is_refused() {
    let dir = scratch("srdf-link");
    let scene = scene_with_srdf(
        &dir,
        "  <group name=\"arm\"><chain base_link=\"base\" tip_link=\"wrist\"/></group>\n",
    );
    let o = facts(&scene, &[]);
    assert_bad_input(&o, &["robot.srdf:3:", "unknown link `wrist`"]);
}

#[test]
fn an_srdf_naming_an_unknown_joint_is_refused() {
    let dir = scratch("srdf-joint");
    let scene = scene_with_srdf(
        &dir,
        "  <disable_collisions link1=\"base\" link2=\"body\" reason=\"Adjacent\"/>\n  <passive_joint name=\"elbow\"/>\n",
    );
    let o = facts(&scene, &[]);
    assert_bad_input(&o, &["robot.srdf:4:", "unknown joint `elbow`"]);
}

#[test]
fn a_urdf_with_a_joint_loop_is_refused() {
    let dir = scratch("loop");
    let urdf = "<?xml version=\"1.0\"?>\n<robot name=\"loopbot\">\n  <link name=\"a\"/>\n  <link name=\"b\"/>\n  <link name=\"c\"/>\n  <joint name=\"ab\" type=\"fixed\"><parent link=\"a\"/><child link=\"b\"/></joint>\n  <joint name=\"bc\" type=\"fixed\"><parent link=\"b\"/><child link=\"c\"/></joint>\n  <joint name=\"ca\" type=\"fixed\"><parent link=\"c\"/><child link=\"a\"/></joint>\n</robot>\n";
    std::fs::write(dir.join("loop.urdf"), urdf).unwrap();
    let scene = dir.join("scene.toml");
    std::fs::write(
        &scene,
        "[scene]\nname = \"loop\"\n\n[[agents]]\nname = \"bot\"\nkind = \"robot\"\nurdf = \"loop.urdf\"\neye = \"a\"\nshoulders = [\"a\"]\nhands = [\"a\"]\n",
    )
    .unwrap();
    let o = facts(&scene, &[]);
    assert_bad_input(&o, &["loop.urdf", "the joints form a cycle"]);
}

#[test]
fn a_scene_starts_an_agent_in_a_named_srdf_posture() {
    let dir = scratch("posture");
    let scene = scene_with_srdf(
        &dir,
        "  <group name=\"body\"><joint name=\"lift\"/></group>\n  <group_state name=\"up\" group=\"body\"><joint name=\"lift\" value=\"0.15\"/></group_state>\n",
    );
    let text = std::fs::read_to_string(&scene).unwrap();
    std::fs::write(&scene, format!("{text}posture = \"up\"\n")).unwrap();
    let world = geometry::world::World::load(&scene).unwrap_or_else(|e| panic!("{e}"));
    let q = &world.agent_state(geometry::scene::AgentId(0)).q;
    assert_eq!(q.as_slice(), &[0.15]);
    assert!(facts(&scene, &[]).status.success());
    std::fs::write(&scene, format!("{text}posture = \"down\"\n")).unwrap();
    let o = facts(&scene, &[]);
    assert_bad_input(
        &o,
        &["agents[0].posture", "no posture `down`", "robot.srdf"],
    );
}
