//! The real PR2 of `../shared/robots` (ROS's description and MoveIt's SRDF, unchanged) in the
//! library scene, through the binary: `facts` reads it, and a plan JSON describes its links as
//! the convex pieces that were checked, which `htngtp check` reads.

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

const EXE: &str = env!("CARGO_BIN_EXE_htngtp");

fn root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../..")
}

/// The library scene with the hand-written PR2 replaced by the real one; what htngtp needs
/// beyond the SRDF (the eye link, the tool frames) is named in the scene.
fn real_pr2_scene(dir: &Path) -> PathBuf {
    let robots = root().join("../shared/robots").canonicalize().unwrap();
    let models = root().join("models").canonicalize().unwrap();
    let text = std::fs::read_to_string(root().join("domains/library/scene.toml")).unwrap();
    let pr2 = format!(
        "\"{}\"\nsrdf = \"{}\"\neye = \"head_mount_kinect_rgb_link\"\nhands = [\"r_gripper_tool_frame\", \"l_gripper_tool_frame\"]",
        robots.join("pr2_description/urdf/robot.xml").display(),
        robots.join("pr2_description/srdf/robot.xml").display()
    );
    assert!(
        text.contains("\"../../models/pr2.urdf\""),
        "the library scene changed"
    );
    let text = text
        .replace("\"../../models/pr2.urdf\"", &pr2)
        .replace("../../models", &models.display().to_string());
    let path = dir.join("real-pr2.toml");
    std::fs::write(&path, text).unwrap();
    path
}

fn run(args: &[&str]) -> Output {
    Command::new(EXE).args(args).output().unwrap()
}

fn scratch(name: &str) -> PathBuf {
    let d = std::path::Path::new(env!("CARGO_TARGET_TMPDIR"))
        .join(format!("htngtp-real-pr2-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    d
}

/// `htngtp plan` of a library problem (`domain`, `problem`: file stems in domains/library) in
/// the shipped scene `scene`, its plan JSON written to `json`, with `more` arguments.
fn plan_library(domain: &str, problem: &str, scene: &str, json: &Path, more: &[&str]) -> Output {
    let lib = root().join("domains/library");
    let file = |name: &str| lib.join(name).to_str().unwrap().to_string();
    let (d, p, s) = (
        file(&format!("{domain}.hddl")),
        file(&format!("{problem}.hddl")),
        file(scene),
    );
    let mut args = vec![
        "plan",
        &d,
        &p,
        "--scene",
        &s,
        "--json-out",
        json.to_str().unwrap(),
    ];
    args.extend_from_slice(more);
    run(&args)
}

/// `htngtp check` finds the plan JSON `json` clean.
fn assert_clean(json: &Path) {
    let o = run(&["check", json.to_str().unwrap()]);
    assert_eq!(
        o.status.code(),
        Some(0),
        "{}{}",
        String::from_utf8_lossy(&o.stdout),
        String::from_utf8_lossy(&o.stderr)
    );
}

#[test]
#[ignore = "needs ../shared/robots beside the checkout; .ci/run runs it when present"]
fn facts_read_the_real_pr2() {
    let dir = scratch("facts");
    let scene = real_pr2_scene(&dir);
    let robots = root().join("../shared/robots");
    let o = run(&[
        "facts",
        scene.to_str().unwrap(),
        "--package-path",
        robots.to_str().unwrap(),
    ]);
    let out = String::from_utf8_lossy(&o.stdout);
    assert_eq!(
        o.status.code(),
        Some(0),
        "{}",
        String::from_utf8_lossy(&o.stderr)
    );
    assert!(out.contains("For PR2 (robot)"), "{out}");
    assert!(out.contains("on(grey-book, table)"), "{out}");
    // Without the package path, the first package:// mesh is not found.
    let o = run(&["facts", scene.to_str().unwrap()]);
    let err = String::from_utf8_lossy(&o.stderr);
    if std::env::var_os("ROS_PACKAGE_PATH").is_none() {
        assert_eq!(o.status.code(), Some(3), "{err}");
        assert!(
            err.contains("package `moveit_resources_pr2_description` not found"),
            "{err}"
        );
    }
}

#[test]
#[ignore = "needs ../shared/robots beside the checkout; .ci/run runs it when present"]
fn the_plan_json_carries_the_convex_pieces_checked() {
    // The shipped real-PR2 library scene: fig4 is planned with every geometric task solved,
    // and `htngtp check` finds the plan clean, the turning fingers closed on what they hold.
    let dir = scratch("json");
    let json = dir.join("plan.json");
    let more = ["--time-limit", "60"];
    let o = plan_library("domain", "fig4", "scene-real-pr2.toml", &json, &more);
    assert_eq!(
        o.status.code(),
        Some(0),
        "{}",
        String::from_utf8_lossy(&o.stderr)
    );
    let plan: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&json).unwrap()).unwrap();
    let pr2 = plan["scene"]["agents"]
        .as_array()
        .unwrap()
        .iter()
        .find(|a| a["name"] == "pr2")
        .unwrap();
    let meshes: Vec<&serde_json::Value> = pr2["links"]
        .as_array()
        .unwrap()
        .iter()
        .flat_map(|l| l["shapes"].as_array().unwrap())
        .filter_map(|s| s["shape"].get("mesh"))
        .collect();
    // Every collision mesh of the URDF is at least one convex piece, each its own shape.
    assert!(meshes.len() >= 35, "{} mesh shapes", meshes.len());
    for m in &meshes {
        assert!(m["vertices"].as_array().unwrap().len() >= 4);
    }
    let geometric = plan["steps"]
        .as_array()
        .unwrap()
        .iter()
        .filter(|s| s["gtp"].is_object())
        .count();
    assert!(geometric >= 4, "{geometric} geometric steps");
    assert_clean(&json);
}

#[test]
#[ignore = "needs ../shared/robots beside the checkout; .ci/run runs it when present"]
fn the_real_grippers_turning_fingers_give_grasps() {
    // The PR2's fingers turn (revolute joints): the jaw opening is measured between their
    // pads, and the tool frame is the scene's hand link below the SRDF chain's wrist.
    let dir = scratch("grasps");
    let scene = real_pr2_scene(&dir);
    let robots = root().join("../shared/robots");
    let o = run(&[
        "--package-path",
        robots.to_str().unwrap(),
        "gtp",
        scene.to_str().unwrap(),
        "pick",
        "grey-book",
        "--json",
    ]);
    let json: serde_json::Value = serde_json::from_slice(&o.stdout)
        .unwrap_or_else(|e| panic!("{e}: {}", String::from_utf8_lossy(&o.stderr)));
    let grasps = json["stats"]["grasps"].as_u64().unwrap_or(0);
    assert!(grasps > 0, "no grasp for the real gripper: {json}");
}

/// The shipped library scenes with the hand-written PR2 and their versions with the real one.
const REAL_PR2_SCENES: [(&str, &str); 3] = [
    ("scene.toml", "scene-real-pr2.toml"),
    ("cluttered-desk.toml", "cluttered-desk-real-pr2.toml"),
    ("scene-far-pos.toml", "scene-far-pos-real-pr2.toml"),
];

/// A scene's text split into its `pr2` agent (from its `[[agents]]` line to the next agent's)
/// and the rest from its `[scene]` table on, without the lines that say which robot it is
/// (the scene's `name` and `package_path`): the header comment above `[scene]` is left out.
fn split_pr2(text: &str) -> (String, String) {
    let start = text
        .find("[[agents]]\nname = \"pr2\"")
        .expect("a pr2 agent");
    let end = start
        + text[start + 1..]
            .find("[[agents]]")
            .expect("an agent after pr2")
        + 1;
    let body = text[..start].to_string() + &text[end..];
    let from = body.find("[scene]").expect("a [scene] table");
    let mut in_scene_table = false;
    let rest = body[from..]
        .lines()
        .filter(|l| {
            if l.starts_with('[') {
                in_scene_table = *l == "[scene]";
            }
            !(in_scene_table && (l.starts_with("name = ") || l.starts_with("package_path = ")))
        })
        .collect::<Vec<_>>()
        .join("\n");
    (text[start..end].to_string(), rest)
}

#[test]
fn the_real_pr2_library_scenes_are_the_library_scenes_but_their_robot() {
    let lib = root().join("domains/library");
    let read = |name: &str| {
        std::fs::read_to_string(lib.join(name)).unwrap_or_else(|e| panic!("{name}: {e}"))
    };
    let mut robots = Vec::new();
    for (ours, real) in REAL_PR2_SCENES {
        let (_, ours_rest) = split_pr2(&read(ours));
        let (robot, real_rest) = split_pr2(&read(real));
        assert_eq!(
            real_rest, ours_rest,
            "domains/library/{real} and {ours} differ outside the robot"
        );
        assert!(robot.contains("pr2_description/urdf/robot.xml"), "{real}");
        robots.push((real, robot));
    }
    // One real PR2 in all of them (its station, posture and decomposed links).
    for (real, robot) in &robots[1..] {
        assert_eq!(
            robot, &robots[0].1,
            "the real PR2 of {real} differs from scene-real-pr2.toml's"
        );
    }
}

#[test]
#[ignore = "needs ../shared/robots beside the checkout; .ci/run runs it when present"]
fn the_real_pr2_picks_a_book_in_the_shipped_scene() {
    // Its folded posture is free of self-collision and its upper arms are decomposed, so the
    // right arm reaches the grey book from the station.
    let scene = root().join("domains/library/scene-real-pr2.toml");
    let o = run(&[
        "gtp",
        scene.to_str().unwrap(),
        "pick",
        "grey-book",
        "--json",
    ]);
    let json: serde_json::Value = serde_json::from_slice(&o.stdout)
        .unwrap_or_else(|e| panic!("{e}: {}", String::from_utf8_lossy(&o.stderr)));
    assert_eq!(o.status.code(), Some(0), "{json}");
    assert_eq!(
        json["solutions"].as_array().map(Vec::len),
        Some(1),
        "{json}"
    );
}

/// The robot's lines of `htngtp facts SCENE` (its `visible`/`reachable` effort levels).
fn robot_facts(scene: &Path) -> String {
    let o = run(&["facts", scene.to_str().unwrap()]);
    assert_eq!(
        o.status.code(),
        Some(0),
        "{}",
        String::from_utf8_lossy(&o.stderr)
    );
    let out = String::from_utf8_lossy(&o.stdout).to_string();
    let start = out.find("For PR2 (robot)").expect("the robot's facts");
    let end = out[start..].find("\n\n").map_or(out.len(), |e| start + e);
    out[start..end].to_string()
}

#[test]
#[ignore = "needs ../shared/robots beside the checkout; .ci/run runs it when present"]
fn the_real_pr2_turns_its_head_by_the_groups_its_scene_adds() {
    // MoveIt's PR2 SRDF has no head group: the scene's `groups` give the head chain, and the
    // books on the table beside the robot are seen with a turn of the head (level 1).
    let shipped = root().join("domains/library/scene-far-pos-real-pr2.toml");
    let facts = robot_facts(&shipped);
    assert!(facts.contains("white-book is Vis with E=1"), "{facts}");
    let text = std::fs::read_to_string(&shipped).unwrap();
    let start = text.find("[agents.groups]").expect("the scene's groups");
    let end = start + text[start..].find("\n\n").unwrap();
    let variant = |groups: &str| {
        // Beside the shipped scene: its paths are relative to its folder.
        let path = root().join(format!(
            "domains/library/groups-variant-{}.toml",
            std::process::id()
        ));
        std::fs::write(&path, format!("{}{groups}{}", &text[..start], &text[end..])).unwrap();
        let facts = robot_facts(&path);
        let _ = std::fs::remove_file(&path);
        facts
    };
    // The head given by its joints, as an SRDF may: the same chain.
    let joints = "[agents.groups]\nhead = { joints = [\"head_pan_joint\", \"head_tilt_joint\"] }";
    let facts = variant(joints);
    assert!(facts.contains("white-book is Vis with E=1"), "{facts}");
    // Without them the head does not turn: the robot must turn around (level 2).
    let facts = variant("");
    assert!(facts.contains("white-book is Vis with E=2"), "{facts}");
}

#[test]
#[ignore = "needs ../shared/robots beside the checkout; .ci/run runs it when present"]
fn the_real_pr2_puts_the_pos_machine_away_where_the_member_cannot_see_it() {
    // After the card payment the POS machine stands at the far end of the desk, where no
    // place in the arm's reach hides it: the put-away's base moves head for the places that
    // do (the symbolic strategy stopped at its cap when they circled the machine held).
    let dir = scratch("put-away");
    let plan = dir.join("plan.json");
    let more = ["--strategy", "symbolic", "--seed", "1"];
    let o = plan_library(
        "domain",
        "pos-out-of-reach",
        "scene-far-pos-real-pr2.toml",
        &plan,
        &more,
    );
    let out = String::from_utf8_lossy(&o.stdout);
    assert_eq!(o.status.code(), Some(0), "{out}");
    assert!(out.contains("putaway pos-machine member"), "{out}");
    assert_clean(&plan);
}
