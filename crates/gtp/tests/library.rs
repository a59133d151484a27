//! The paper's tasks in the library scene, each solution checked from scratch: trajectories
//! replayed at 4x the planner's resolution, the promised visibility and reach re-measured in
//! the world after the task with the `geometry` crate's own functions.

use geometry::facts::{FactParams, on, reachable_effort};
use geometry::scene::{AgentId, ObjectId};
use geometry::visibility::{Aim, visibility_for_agent};
use geometry::world::World;
use gtp::planner::{CallOptions, GtpError, Planner, Solution, Stage};
use gtp::solution::Phase;
use gtp::verify::recheck_trajectories;
use parry3d::math::{Pose, Rotation};

/// A scene of `domains/library/`.
fn scene(file: &str) -> World {
    let dir = concat!(env!("CARGO_MANIFEST_DIR"), "/../../domains/library/");
    World::load(format!("{dir}{file}")).unwrap_or_else(|e| panic!("{file}: {e}"))
}

fn library() -> World {
    scene("scene.toml")
}

fn first(planner: &Planner, world: &World, task: &str, args: &[&str]) -> Solution {
    let mut stream = planner
        .run(world, task, args, &CallOptions::seeded(3))
        .expect("task resolves");
    match stream.next() {
        Some(s) => s,
        None => panic!("{task} {args:?} failed: {}", stream.failure().unwrap()),
    }
}

/// The trajectories are collision-free at 4x the planner's resolution.
fn recheck(planner: &Planner, before: &World, s: &Solution) {
    let res = planner.config().rrt.resolution / 4.0;
    assert!(!s.summary.trajectories.is_empty());
    recheck_trajectories(planner, before, &s.summary, res)
        .unwrap_or_else(|e| panic!("{:?} {:?}: {e}", s.summary.task, s.summary.args));
}

/// Visibility of `o` for `h` with the head as it is and turned to it (effort levels 0 and 1).
fn visibility(planner: &Planner, w: &World, h: AgentId, o: ObjectId) -> (f32, f32) {
    let res = planner.config().visibility_resolution;
    (
        visibility_for_agent(w, h, o, Aim::Current, res).fraction(),
        visibility_for_agent(w, h, o, Aim::AtTarget, res).fraction(),
    )
}

fn reach_within(w: &World, h: AgentId, o: ObjectId, level: u8) -> Option<u8> {
    let params = FactParams {
        max_effort: level,
        ..FactParams::default()
    };
    reachable_effort(w, h, o, &params)
}

/// The object rests free of every other object (it may touch nothing but air and its support
/// gap of 1 cm).
fn rests_free(w: &World, o: ObjectId) {
    let pose = w.object_shape_pose(o);
    let shape = &w.object(o).shape;
    for other in w.object_ids().filter(|&x| x != o) {
        let hit = parry3d::query::intersection_test(
            &pose,
            &**shape,
            &w.object_shape_pose(other),
            &*w.object(other).shape,
        )
        .unwrap()
        .intersecting;
        assert!(
            !hit,
            "{} intersects {}",
            w.object(o).name,
            w.object(other).name
        );
    }
}

#[test]
fn make_accessible_show_give_and_put_away_the_grey_book() {
    let world = library();
    let planner = Planner::new();
    let book = world.object_id("grey-book").unwrap();
    let member = world.agent_id("member").unwrap();
    let robot = world.agent_id("pr2").unwrap();

    let s = first(
        &planner,
        &world,
        "make-accessible",
        &["grey-book", "member"],
    );
    recheck(&planner, &world, &s);
    let (v0, v1) = visibility(&planner, &s.world, member, book);
    assert!(v0.max(v1) >= 0.5, "visibility {v0} / {v1}");
    assert!(reach_within(&s.world, member, book, 1).is_some());
    assert!(s.world.attachment(book).is_none());
    rests_free(&s.world, book);
    assert!(s.summary.placement.as_ref().unwrap().support.is_some());

    for task in ["show", "give"] {
        let s = first(&planner, &world, task, &["grey-book", "member"]);
        recheck(&planner, &world, &s);
        let (v0, v1) = visibility(&planner, &s.world, member, book);
        assert!(v0.max(v1) >= 0.9, "{task}: visibility {v0} / {v1}");
        assert_eq!(
            s.world.attachment(book).map(|a| a.agent),
            Some(robot),
            "{task}: held"
        );
        if task == "give" {
            assert!(
                reach_within(&s.world, member, book, 1).is_some(),
                "give: reach"
            );
        }
    }

    let s = first(&planner, &world, "put-away", &["grey-book", "member"]);
    recheck(&planner, &world, &s);
    let (v0, v1) = visibility(&planner, &s.world, member, book);
    assert!(v0 <= 0.0 && v1 <= 0.0, "put-away: visibility {v0} / {v1}");
    assert!(
        reach_within(&s.world, member, book, 1).is_none(),
        "put-away: reachable"
    );
    rests_free(&s.world, book);
}

#[test]
fn put_away_the_pos_machine() {
    let world = library();
    let planner = Planner::new();
    let pos = world.object_id("pos-machine").unwrap();
    let member = world.agent_id("member").unwrap();
    let s = first(&planner, &world, "put-away", &["pos-machine", "member"]);
    recheck(&planner, &world, &s);
    let (v0, v1) = visibility(&planner, &s.world, member, pos);
    assert!(v0 <= 0.0 && v1 <= 0.0, "visibility {v0} / {v1}");
    assert!(reach_within(&s.world, member, pos, 1).is_none());
    rests_free(&s.world, pos);
}

#[test]
fn pick_then_place_on_the_desk() {
    let world = library();
    let planner = Planner::new();
    let book = world.object_id("grey-book").unwrap();
    let desk = world.object_id("desk").unwrap();
    let robot = world.agent_id("pr2").unwrap();
    let picked = first(&planner, &world, "pick", &["grey-book"]);
    recheck(&planner, &world, &picked);
    assert_eq!(picked.world.attachment(book).map(|a| a.agent), Some(robot));
    let lift = picked.world.object_pose(book).translation.z - world.object_pose(book).translation.z;
    assert!(lift > 0.1, "lifted {lift} m");
    // From the world after the pick, the held book goes onto the desk.
    let placed = first(&planner, &picked.world, "place-on", &["grey-book", "desk"]);
    recheck(&planner, &picked.world, &placed);
    assert!(placed.world.attachment(book).is_none());
    assert!(on(&placed.world, book, desk, 0.05));
    rests_free(&placed.world, book);
    // The grasp was kept: no pick phase in the second plan, and the jaws stay as the pick
    // closed them while they carry the book.
    assert!(placed.summary.grasp.as_ref().unwrap().id.is_none());
    let gripped = picked.summary.trajectories.last().unwrap().gripper_opening;
    let carried: Vec<_> = placed
        .summary
        .trajectories
        .iter()
        .filter(|t| t.held.is_some())
        .collect();
    assert!(!carried.is_empty());
    for t in carried {
        let o = t.gripper_opening;
        assert!(
            (o - gripped).abs() < 1e-4,
            "{:?}: jaws {o} m, gripped at {gripped} m",
            t.phase
        );
    }
}

#[test]
fn make_accessible_streams_five_distinct_solutions() {
    let world = library();
    let planner = Planner::new();
    let stream = planner
        .run(
            &world,
            "make-accessible",
            &["grey-book", "member"],
            &CallOptions::seeded(5),
        )
        .unwrap();
    let book = world.object_id("grey-book").unwrap();
    let member = world.agent_id("member").unwrap();
    let mut seen = Vec::new();
    for s in stream.take(5) {
        let p = s.summary.placement.clone().unwrap();
        let key = (
            s.summary.grasp.as_ref().unwrap().id,
            s.summary.grasp.as_ref().unwrap().arm.clone(),
            p.point.map(|c| (c * 1000.0).round() as i32),
            p.orientation,
            p.yaw_index,
        );
        assert!(!seen.contains(&key), "solution repeated: {key:?}");
        seen.push(key);
        let (v0, v1) = visibility(&planner, &s.world, member, book);
        assert!(v0.max(v1) >= 0.5);
    }
    assert_eq!(seen.len(), 5);
}

#[test]
fn an_impossible_task_names_the_constraint_that_stopped_it() {
    // The member moved far away: nothing on a support is within their reach.
    let mut world = library();
    let planner = Planner::new();
    let member = world.agent_id("member").unwrap();
    let st = world.agent_state(member).clone();
    let far = geometry::world::base_pose(6.0, 0.0, std::f32::consts::PI);
    world.set_agent_config(member, far, &st.q);
    let mut stream = planner
        .run(
            &world,
            "make-accessible",
            &["grey-book", "member"],
            &CallOptions::seeded(1),
        )
        .unwrap();
    assert!(stream.next().is_none());
    let f = stream.failure().unwrap();
    assert_eq!(f.stage, Stage::Points, "{f}");
    assert!(f.message.contains("reachable by member"), "{f}");
    assert!(!f.limit);

    // Nowhere to hide: out of the member's reach even when they may walk (effort level 4).
    let world = library();
    let mut stream = planner
        .run(
            &world,
            "put-away",
            &["grey-book", "member"],
            &CallOptions::seeded(1).with("unreachable-within", "4"),
        )
        .unwrap();
    assert!(stream.next().is_none());
    let f = stream.failure().unwrap();
    assert!([Stage::Points, Stage::Reach].contains(&f.stage), "{f}");
    assert!(f.message.contains("reach"), "{f}");
    println!("{f}");
}

#[test]
fn bad_calls_are_errors_with_the_reason() {
    let world = library();
    let planner = Planner::new();
    let e = planner
        .run(&world, "juggle", &["grey-book"], &CallOptions::default())
        .err()
        .unwrap();
    assert!(matches!(e, GtpError::UnknownTask(_)));
    let e = planner
        .run(&world, "show", &["grey-book"], &CallOptions::default())
        .err()
        .unwrap();
    assert!(e.to_string().contains("takes 2 argument"), "{e}");
    let e = planner
        .run(
            &world,
            "show",
            &["blue-book", "member"],
            &CallOptions::default(),
        )
        .err()
        .unwrap();
    assert!(e.to_string().contains("no such object"), "{e}");
    let e = planner
        .run(&world, "show", &["desk", "member"], &CallOptions::default())
        .err()
        .unwrap();
    assert!(e.to_string().contains("not movable"), "{e}");
    let e = planner
        .run(
            &world,
            "give",
            &["grey-book", "pr2"],
            &CallOptions::default(),
        )
        .err()
        .unwrap();
    assert!(e.to_string().contains("not a human"), "{e}");
    let e = planner
        .run(
            &world,
            "give",
            &["grey-book", "member"],
            &CallOptions::default().with("min-visibility", "2"),
        )
        .err()
        .unwrap();
    assert!(e.to_string().contains("fraction"), "{e}");
}

#[test]
fn the_same_seed_gives_the_same_solution() {
    let world = library();
    let planner = Planner::new();
    let a = first(&planner, &world, "give", &["grey-book", "member"]);
    let b = first(&Planner::new(), &world, "give", &["grey-book", "member"]);
    let (mut sa, mut sb) = (a.summary.clone(), b.summary.clone());
    sa.stats.time_s = 0.0;
    sb.stats.time_s = 0.0;
    assert_eq!(sa, sb);
}

#[test]
fn candidate_points_from_the_mightability_maps() {
    let world = library();
    let planner = Planner::with_config(gtp::planner::PlannerConfig {
        mightability: true,
        ..Default::default()
    });
    let book = world.object_id("grey-book").unwrap();
    let member = world.agent_id("member").unwrap();
    for task in ["make-accessible", "put-away"] {
        let s = first(&planner, &world, task, &["grey-book", "member"]);
        recheck(&planner, &world, &s);
        let (v0, v1) = visibility(&planner, &s.world, member, book);
        if task == "put-away" {
            assert!(v0 <= 0.0 && v1 <= 0.0, "{task}: visibility {v0} / {v1}");
            assert!(reach_within(&s.world, member, book, 1).is_none());
        } else {
            assert!(v0.max(v1) >= 0.5, "{task}: visibility {v0} / {v1}");
            assert!(reach_within(&s.world, member, book, 1).is_some());
        }
    }
}

#[test]
fn the_time_limit_stops_a_call_and_says_so() {
    let world = library();
    let planner = Planner::new();
    let mut stream = planner
        .run(
            &world,
            "put-away",
            &["pos-machine", "member"],
            &CallOptions::seeded(1).with("time-limit", "0.000001"),
        )
        .unwrap();
    assert!(stream.next().is_none());
    let f = stream.failure().unwrap();
    assert!(f.limit, "{f}");
    assert_eq!(f.stage, Stage::TimeLimit);
    assert!(!stream.stats().success);
}

/// A caller's deadline that has passed stops a call as its own time limit would.
#[test]
fn a_passed_deadline_stops_a_call_and_says_so() {
    let world = library();
    let planner = Planner::new();
    let options = CallOptions {
        deadline: Some(std::time::Instant::now()),
        ..CallOptions::seeded(1)
    };
    let mut stream = planner
        .run(&world, "give", &["grey-book", "member"], &options)
        .unwrap();
    assert!(stream.next().is_none());
    let f = stream.failure().unwrap();
    assert!(f.limit, "{f}");
    assert_eq!(f.stage, Stage::TimeLimit);
}

#[test]
fn tasks_chain_from_the_world_a_solution_leaves() {
    // Show the book (held in the air), then make it accessible from there: the grasp is kept.
    let world = library();
    let planner = Planner::new();
    let book = world.object_id("grey-book").unwrap();
    let member = world.agent_id("member").unwrap();
    let shown = first(&planner, &world, "show", &["grey-book", "member"]);
    let s = first(
        &planner,
        &shown.world,
        "make-accessible",
        &["grey-book", "member"],
    );
    recheck(&planner, &shown.world, &s);
    assert!(
        s.summary.grasp.as_ref().unwrap().id.is_none(),
        "the held grasp is reused"
    );
    let (v0, v1) = visibility(&planner, &s.world, member, book);
    assert!(v0.max(v1) >= 0.5);
    assert!(s.world.attachment(book).is_none());
}

/// Navigating to furniture brings a point of its support surface within the arm's reach
/// (its centre may stay out of reach: the desk's top is 1.8 m long), along a base path that is
/// collision-free when re-checked; a small object is reached at its centre.
#[test]
fn navigate_to_furniture_reaches_its_support_surface() {
    let world = library();
    let planner = Planner::new();
    let robot = planner.robot(&world).unwrap().agent;
    let reach = world.agent(robot).reach;
    for target in ["desk", "table", "white-book"] {
        let s = first(&planner, &world, "navigate-to", &[target]);
        recheck(&planner, &world, &s);
        let st = s.world.agent_state(robot);
        let b = s.summary.robot_base.expect("a base pose");
        assert!((st.base.translation.x - b[0]).abs() < 1e-4);
        let shoulders = geometry::effort::shoulders(&s.world, robot, st.base, &st.q);
        let o = world.object_id(target).unwrap();
        let model = world.object(o);
        // Points to reach, measured independently: a 2 cm grid over each support surface, or
        // the centre of an object without one.
        let mut points = Vec::new();
        let pose = world.object_pose(o);
        for surface in &model.surfaces {
            let [hx, hy] = surface.half_extents;
            for i in 0..=20 {
                for j in 0..=20 {
                    let local = surface.centre
                        + parry3d::math::Vector::new(
                            hx * (i as f32 / 10.0 - 1.0),
                            hy * (j as f32 / 10.0 - 1.0),
                            0.0,
                        );
                    points.push(pose.transform_point(local));
                }
            }
        }
        if model.surfaces.is_empty() {
            points.push(world.object_aabb(o).center());
        }
        let best = points
            .iter()
            .flat_map(|p| shoulders.iter().map(move |s| (*p - *s).length()))
            .fold(f32::INFINITY, f32::min);
        assert!(
            best <= reach + 0.01,
            "{target}: nearest point {best:.2} m from a shoulder, reach {reach:.2} m"
        );
    }
}

/// A world of the bundled PR2, its arms tucked, standing at `(x, y, yaw in degrees)` in the
/// scene `objects` (its `[scene]` table and `[[objects]]`).
fn tucked_pr2_world(objects: &str, (x, y, yaw): (f32, f32, f32)) -> World {
    let urdf = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../../models/pr2.urdf");
    let text = format!(
        r#"{objects}
[[agents]]
name = "pr2"
kind = "robot"
urdf = "{urdf}"
base = {{ x = {x}, y = {y}, yaw = {yaw} }}
[agents.joints]
torso_lift_joint = 0.3
r_shoulder_pan_joint = -0.383
r_shoulder_lift_joint = 0.886
r_upper_arm_roll_joint = -0.895
r_elbow_flex_joint = -2.321
r_forearm_roll_joint = 0.501
r_wrist_flex_joint = -1.479
r_wrist_roll_joint = 0.304
l_shoulder_pan_joint = 0.383
l_shoulder_lift_joint = 0.886
l_upper_arm_roll_joint = 0.895
l_elbow_flex_joint = -2.321
l_forearm_roll_joint = -0.501
l_wrist_flex_joint = -1.479
l_wrist_roll_joint = -0.304
"#,
        urdf = urdf.display()
    );
    let scene =
        geometry::scene::Scene::from_str(&text, "pr2.toml", std::path::Path::new("."), "pr2");
    World::from_scene(scene.unwrap()).unwrap()
}

/// A member standing 1 m past the far end of a long counter, 3 m from the robot: from no base
/// pose within a step (1 m) does the robot's arm reach into the member's, so the give drives
/// the robot round with the book it picked (effort level 4, within the robot's move radius)
/// and hands the book over from there, every trajectory re-checked, the book within the
/// member's reach.
#[test]
fn a_give_drives_to_a_member_beyond_a_step() {
    let human = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../../models/human.urdf");
    let text = format!(
        r#"
[scene]
bounds = {{ min = [-2.0, -2.0, -0.05], max = [2.0, 3.0, 2.0] }}
[[objects]]
name = "counter"
support = true
surfaces = [{{ centre = [0.0, 0.0, 1.0], half_extents = [0.3, 1.2] }}]
shape = {{ box = [0.3, 1.2, 0.5] }}
pose = {{ xyz = [0.0, 0.0, 0.5] }}
[[objects]]
name = "book"
shape = {{ box = [0.07, 0.1, 0.015] }}
pose = {{ xyz = [-0.15, -0.8, 1.0702], rpy = [0, 90, 0] }}
movable = true
[[agents]]
name = "member"
kind = "human"
urdf = "{human}"
base = {{ x = 0.0, y = 2.2, yaw = -90 }}
sitting = false
[agents.joints]
pelvis_lift_joint = 0.4
r_hip_joint = 1.5708
l_hip_joint = 1.5708
r_knee_joint = -1.5708
l_knee_joint = -1.5708
r_shoulder_roll_joint = -0.1
l_shoulder_roll_joint = 0.1
"#,
        human = human.display()
    );
    let world = tucked_pr2_world(&text, (-0.75, -0.8, 0.0));
    let planner = Planner::new();
    let robot = planner.robot(&world).unwrap().agent;
    let held = first(&planner, &world, "pick", &["book"]).world;
    // Where the robot stands when asked to give (the pick may have moved it).
    let station = held.agent_state(robot).base.translation;
    let s = first(&planner, &held, "give", &["book", "member"]);
    recheck(&planner, &held, &s);
    assert_eq!(s.summary.trajectories[0].phase, Phase::Drive);
    let pose = s.summary.base_move.expect("the base pose worked from");
    let moved = ((pose[0] - station.x).powi(2) + (pose[1] - station.y).powi(2)).sqrt();
    assert!(moved > 1.0, "stepped only {moved} m");
    let (h, o) = (
        world.agent_id("member").unwrap(),
        world.object_id("book").unwrap(),
    );
    assert!(
        reach_within(&s.world, h, o, 1).is_some(),
        "out of the member's reach"
    );
}

/// A PR2 in a closed pen, its target outside: navigate-to fails on the free region (the poses
/// near the target are not connected to where the robot stands) without a path search; with
/// the pen's walls against the base, at once. The crate in a pen of its own, the robot
/// outside: the same, without a path search either.
#[test]
fn navigate_to_says_when_the_base_is_penned_in() {
    let pen = |gap: f32, open: bool| {
        let h = 0.36 + gap; // the PR2's base is about 0.67 m square
        // The east wall stands between the robot and the crate; open, it is far away.
        let east = if open { 2.9 } else { h };
        pen_world(h, east, 2.2, (0.0, 0.0, 0.0))
    };
    let planner = Planner::new();
    let world = pen(0.12, true);
    let mut stream = planner
        .run(&world, "navigate-to", &["crate"], &CallOptions::seeded(1))
        .unwrap();
    let s = stream.next().expect("out of the open pen");
    recheck(&planner, &world, &s);
    for (gap, words) in [
        (0.12, "not connected to where the robot stands"),
        (0.0, "cannot move its base"),
    ] {
        let world = pen(gap, false);
        let mut stream = planner
            .run(&world, "navigate-to", &["crate"], &CallOptions::seeded(1))
            .unwrap();
        assert!(stream.next().is_none(), "gap {gap}: a way out of the pen");
        let f = stream.failure().unwrap();
        assert!(f.message.contains(words), "gap {gap}: {f}");
        assert!(!f.limit, "gap {gap}: {f}");
        assert_eq!(stream.stats().planner_calls, 0, "gap {gap}: {f}");
    }
    // The robot 1.5 m west of a closed pen around the crate (walls 1 m from its centre).
    let world = pen_world(1.0, 1.0, 0.0, (-2.0, 0.0, 0.0));
    let mut stream = planner
        .run(&world, "navigate-to", &["crate"], &CallOptions::seeded(1))
        .unwrap();
    assert!(stream.next().is_none(), "into the crate's closed pen");
    let f = stream.failure().unwrap();
    assert!(f.message.contains("not connected"), "{f}");
    assert_eq!(stream.stats().planner_calls, 0, "{f}");
}

/// A PR2 at `(x, y, yaw)` (degrees) and a crate at `(crate_x, 0)` with walls around the
/// origin, `h` from it to the north, south and west, `east` to the east.
fn pen_world(h: f32, east: f32, crate_x: f32, robot: (f32, f32, f32)) -> World {
    let text = format!(
        r#"
[scene]
bounds = {{ min = [-3.0, -2.0, -0.05], max = [3.0, 2.0, 2.0] }}
[[objects]]
name = "wall-n"
shape = {{ box = [{w}, 0.02, 0.5] }}
pose = {{ xyz = [0.0, {h}, 0.5] }}
[[objects]]
name = "wall-s"
shape = {{ box = [{w}, 0.02, 0.5] }}
pose = {{ xyz = [0.0, -{h}, 0.5] }}
[[objects]]
name = "wall-e"
shape = {{ box = [0.02, {w}, 0.5] }}
pose = {{ xyz = [{east}, 0.0, 0.5] }}
[[objects]]
name = "wall-w"
shape = {{ box = [0.02, {w}, 0.5] }}
pose = {{ xyz = [-{h}, 0.0, 0.5] }}
[[objects]]
name = "crate"
shape = {{ box = [0.2, 0.2, 0.45] }}
pose = {{ xyz = [{crate_x}, 0.0, 0.45] }}
movable = true
"#,
        w = h + 0.02,
    );
    tucked_pr2_world(&text, robot)
}

/// A wall with a gap the PR2's base (about 0.67 m square) passes only turned square to it, the
/// robot standing at 45 degrees: the free region that screens base poses joins the far side
/// (the base fits the gap at another heading), so a pose there gets a path search, not a "not
/// connected"; a gap narrower than the base at every heading splits the room. Trajectory
/// queries get 2 nodes, so that every one but a straight drive fails and the screen decides.
#[test]
fn the_free_region_joins_rooms_through_a_gap_the_base_passes_turned() {
    let room = |gap: f32| {
        // The wall at x = 1.0 from y = -2 to 2, open between y = 1.0 -/+ gap / 2.
        let (lo, hi) = (1.0 - gap / 2.0, 1.0 + gap / 2.0);
        let (s_half, s_mid) = ((lo + 2.0) / 2.0, (lo - 2.0) / 2.0);
        let (n_half, n_mid) = ((2.0 - hi) / 2.0, (2.0 + hi) / 2.0);
        let text = format!(
            r#"
[scene]
bounds = {{ min = [-1.5, -2.0, -0.05], max = [3.0, 2.0, 2.0] }}
[[objects]]
name = "wall-s"
shape = {{ box = [0.02, {s_half}, 0.5] }}
pose = {{ xyz = [1.0, {s_mid}, 0.5] }}
[[objects]]
name = "wall-n"
shape = {{ box = [0.02, {n_half}, 0.5] }}
pose = {{ xyz = [1.0, {n_mid}, 0.5] }}
[[objects]]
name = "crate"
shape = {{ box = [0.2, 0.2, 0.45] }}
pose = {{ xyz = [2.4, -1.0, 0.45] }}
movable = true
"#
        );
        tucked_pr2_world(&text, (0.0, -1.0, 45.0))
    };
    let mut config = gtp::planner::PlannerConfig::default();
    config.rrt.max_nodes = 2;
    let planner = Planner::with_config(config);
    let failure = |gap: f32| {
        let world = room(gap);
        let mut stream = planner
            .run(&world, "navigate-to", &["crate"], &CallOptions::seeded(1))
            .unwrap();
        assert!(stream.next().is_none(), "gap {gap}: a straight drive");
        stream.failure().unwrap().message.clone()
    };
    let turned = failure(0.8);
    assert!(!turned.contains("not connected"), "0.8 m gap: {turned}");
    let narrow = failure(0.5);
    assert!(narrow.contains("not connected"), "0.5 m gap: {narrow}");
}

/// Give, then take: the member ends with the book in a hand, the robot's gripper open and
/// drawn back along a trajectory that re-checks; the gripper is free for the next pick.
#[test]
fn the_member_takes_a_given_book_and_the_gripper_is_free_again() {
    let world = library();
    let planner = Planner::new();
    let book = world.object_id("grey-book").unwrap();
    let member = world.agent_id("member").unwrap();
    let given = first(&planner, &world, "give", &["grey-book", "member"]);
    let arm = given.summary.grasp.as_ref().unwrap().arm.clone();
    // While the book is held, the other gripper does the next pick.
    let other = first(&planner, &given.world, "pick", &["pos-machine"]);
    assert_ne!(other.summary.grasp.as_ref().unwrap().arm, arm);
    let taken = first(&planner, &given.world, "take", &["grey-book", "member"]);
    recheck(&planner, &given.world, &taken);
    let at = taken.world.attachment(book).expect("the book is held");
    assert_eq!(at.agent, member);
    assert!(world.agent(member).hand_links.contains(&at.link));
    // The member's arm goes out to the book (planned) and comes back with it (planned), to
    // where the member then holds it.
    let phases: Vec<(String, Phase)> = taken
        .summary
        .trajectories
        .iter()
        .map(|t| (t.agent.clone(), t.phase))
        .collect();
    assert_eq!(
        phases,
        [
            ("member".to_string(), Phase::Reach),
            ("pr2".to_string(), Phase::Retreat),
            ("member".to_string(), Phase::Withdraw)
        ]
    );
    let reach = &taken.summary.trajectories[0];
    let withdraw = &taken.summary.trajectories[2];
    assert_eq!(withdraw.held.as_ref().unwrap().object, "grey-book");
    assert_eq!(withdraw.waypoints.first(), reach.waypoints.last());
    let model = &world.agent(member).model;
    let q_end = &taken.world.agent_state(member).q;
    let q_start = &given.world.agent_state(member).q;
    for (i, name) in withdraw.joints.iter().enumerate() {
        let k = model.dof_index(name).unwrap();
        assert!((q_end[k] - withdraw.waypoints.last().unwrap()[i]).abs() < 1e-5);
        assert!((q_start[k] - reach.waypoints[0][i]).abs() < 1e-5);
    }
    // The book is where the hand took it from the gripper: no jump at the hand-over.
    let mut q_take = q_start.clone();
    for (i, name) in reach.joints.iter().enumerate() {
        q_take[model.dof_index(name).unwrap()] = reach.waypoints.last().unwrap()[i];
    }
    let base = given.world.agent_state(member).base;
    let hand = model.link_pose_by_id(base, &q_take, at.link);
    let grasp: parry3d::math::Pose = withdraw.held.as_ref().unwrap().object_in_tool.into();
    let jump = (hand * grasp).translation - given.world.object_pose(book).translation;
    assert!(jump.length() < 1e-3, "the book jumps {} m", jump.length());
    // The hands keep clear of the member's eyes where the reach and the withdraw end.
    let eye_link = world.agent(member).eye_link;
    for q in [&q_take, q_end] {
        let eye = model.link_pose_by_id(base, q, eye_link).translation;
        for &l in &world.agent(member).hand_links {
            let pose = model.link_pose_by_id(base, q, l);
            for c in &model.links()[l].collisions {
                let d = c.shape.distance_to_point(&(pose * c.local_pose), eye, true);
                assert!(d >= 0.12, "a hand {d} m from the member's eye");
            }
        }
    }
    // The book is an obstacle in the member's hand now, and the gripper can pick again.
    let next = first(&planner, &taken.world, "pick", &["white-book"]);
    recheck(&planner, &taken.world, &next);
    // Nothing to take from an empty gripper: a failure that says so.
    let mut again = planner
        .run(
            &taken.world,
            "take",
            &["white-book", "member"],
            &CallOptions::seeded(1),
        )
        .unwrap();
    assert!(again.next().is_none());
    assert_eq!(again.failure().unwrap().stage, Stage::Held);
}

/// The member with the left arm raised across the desk, its hand nearer the book than the
/// right: the left cannot take it, the right does. And the other arm moves to rest on a
/// planned, collision-free path when asked to clear the way.
#[test]
fn a_person_takes_with_the_other_hand_and_moves_an_arm_out_of_the_way() {
    let world = library();
    let planner = Planner::new();
    let member = world.agent_id("member").unwrap();
    let book = world.object_id("grey-book").unwrap();
    let seeded = |w: &World, task: &str| {
        let mut stream = planner
            .run(w, task, &["grey-book", "member"], &CallOptions::seeded(1))
            .unwrap();
        stream
            .next()
            .unwrap_or_else(|| panic!("{task}: {}", stream.failure().unwrap()))
    };
    let given = seeded(&world, "give");
    let model = world.agent(member).model.clone();
    let mut w = given.world.clone();
    let mut q = w.agent_state(member).q.clone();
    let raised = [
        ("l_shoulder_pitch_joint", -1.3),
        ("l_shoulder_roll_joint", 0.8),
        ("l_shoulder_yaw_joint", 0.0),
        ("l_elbow_joint", 0.0),
    ];
    for (name, v) in raised {
        q[model.dof_index(name).unwrap()] = v;
    }
    let base = w.agent_state(member).base;
    w.set_agent_config(member, base, &q);
    let at = w.object_pose(book).translation;
    let hand = |n: &str| {
        (w.agent_state(member).link_poses()[model.link_id(n).unwrap()].translation - at).length()
    };
    assert!(
        hand("l_hand") < hand("r_hand"),
        "the left hand is the nearer"
    );
    let taken = seeded(&w, "take");
    recheck(&planner, &w, &taken);
    let arms: Vec<(Phase, &str)> = taken
        .summary
        .trajectories
        .iter()
        .filter(|t| t.agent == "member")
        .map(|t| (t.phase, t.arm.as_str()))
        .collect();
    assert_eq!(
        arms,
        [(Phase::Reach, "right_arm"), (Phase::Withdraw, "right_arm")]
    );
    // Clearing the way: the left arm back to where the scene started it, on a planned path.
    let person = planner.agent_setup(&w, member).unwrap();
    let right = person
        .arms
        .iter()
        .position(|a| a.name == "right_arm")
        .unwrap();
    let left = person
        .arms
        .iter()
        .position(|a| a.name == "left_arm")
        .unwrap();
    let mut rng = fastrand::Rng::with_seed(1);
    let rrt = planner.config().rrt.clone();
    let rested = gtp::take::rest_other_arms(&person, right, &w, &w, book, &rrt, &mut rng).unwrap();
    let (moves, before) = (rested.moves, rested.before);
    assert_eq!(moves.len(), 1);
    assert_eq!(moves[0].0, left);
    let rest = &world.agent(member).initial_q;
    let end = before.agent_state(member).q.clone();
    for (name, _) in raised {
        let k = model.dof_index(name).unwrap();
        assert!((end[k] - rest[k]).abs() < 1e-4, "{name} at rest");
    }
    assert!(moves[0].1.waypoints.len() >= 2);
    // At rest already, there is nothing to clear.
    let again = gtp::take::rest_other_arms(&person, right, &before, &before, book, &rrt, &mut rng);
    assert!(again.is_err());
}

/// Both grippers full: a pick fails and names the gripper, not the object's size.
#[test]
fn a_pick_with_both_grippers_full_says_so() {
    let world = library();
    let planner = Planner::new();
    let a = first(&planner, &world, "pick", &["grey-book"]);
    let b = first(&planner, &a.world, "pick", &["pos-machine"]);
    let mut stream = planner
        .run(&b.world, "pick", &["white-book"], &CallOptions::seeded(1))
        .unwrap();
    assert!(stream.next().is_none());
    let f = stream.failure().unwrap();
    assert_eq!(f.stage, Stage::FreeGripper);
    assert!(f.message.contains("holds `grey-book`"), "{}", f.message);
}

/// An object no grasp can pick up where it lies (the POS machine on the far shelf, out of the
/// arm's reach from the station): the search stops after the first point, where every grasp
/// was tried, and says the pick stopped it (not the deepest stage some candidate reached). The
/// base stays where it is (`robot-effort` 1).
#[test]
fn when_no_grasp_can_be_picked_up_the_search_stops_and_says_so() {
    let world = scene("scene-far-pos.toml");
    let planner = Planner::new();
    let mut stream = planner
        .run(
            &world,
            "show",
            &["pos-machine", "member"],
            &CallOptions::seeded(1).with("robot-effort", "1"),
        )
        .unwrap();
    assert!(stream.next().is_none());
    let f = stream.failure().unwrap();
    assert_eq!(f.stage, Stage::Pick, "{f}");
    assert!(f.message.contains("can be picked up"), "{f}");
    assert_eq!(stream.stats().points, 1);
}

/// The library's shelf with a tall book standing in its middle compartment, 5 cm under the
/// board above, and the robot in front of the shelf.
fn shelf() -> World {
    scene("scene-shelf.toml")
}

/// A book under a board cannot be lifted straight up: it is raised a centimetre, pulled out
/// back along the gripper's approach, then lifted; put back into the shelf, it is pushed in the
/// same way, reversed.
#[test]
fn a_book_under_a_board_is_pulled_out_and_pushed_back_in() {
    let world = shelf();
    let planner = Planner::new();
    let book = world.object_id("tall-book").unwrap();
    let shelf_id = world.object_id("shelf").unwrap();
    let picked = first(&planner, &world, "pick", &["tall-book"]);
    recheck(&planner, &world, &picked);
    let lifts: Vec<_> = picked
        .summary
        .trajectories
        .iter()
        .filter(|t| t.phase == Phase::Lift)
        .collect();
    assert_eq!(lifts.len(), 3, "raise, pull out, lift");
    let start = world.object_pose(book).translation;
    let end = picked.world.object_pose(book).translation;
    assert!(end.z - start.z > 0.15, "lifted {} m", end.z - start.z);
    // Out of the shelf: the compartment opens towards -y, its front at y = 0.64.
    assert!(end.y < 0.64 - 0.1, "pulled out to y = {}", end.y);
    let placed = first(&planner, &picked.world, "place-on", &["tall-book", "shelf"]);
    recheck(&planner, &picked.world, &placed);
    // In the upper compartment (board at 0.84 m, the next at 1.18 m): the 30 cm book's top 4 cm
    // under the board, so it went in sideways, not down from 15 cm above.
    let at = placed.world.object_pose(book).translation;
    assert!((at.z - 0.99).abs() < 0.01, "placed at {at:?}");
    assert!(on(&placed.world, book, shelf_id, 0.05));
    rests_free(&placed.world, book);
}

/// The member behind a grille (slats 3 cm wide, 1 cm apart, across and upright, over their
/// whole view of the desk): no hand-over pose shows the book well enough, and the show fails
/// on visibility, with the best it found (each pose the arm reaches measured once, with the
/// robot out of the way: the robot's arm only hides more of the book).
#[test]
fn a_show_behind_a_grille_fails_on_visibility() {
    let dir = concat!(env!("CARGO_MANIFEST_DIR"), "/../../domains/library/");
    let mut text = std::fs::read_to_string(format!("{dir}scene.toml")).unwrap();
    let slat = |half: [f32; 3], at: [f32; 3]| {
        format!("{{ shape = {{ box = {half:?} }}, pose = {{ xyz = {at:?} }} }}")
    };
    let rows = (0..30).map(|k| slat([0.005, 1.2, 0.015], [0.0, 0.0, 0.8 + 0.04 * k as f32]));
    let columns = (0..60).map(|k| slat([0.005, 0.015, 0.6], [0.0, -1.2 + 0.04 * k as f32, 1.4]));
    let slats: Vec<String> = rows.chain(columns).collect();
    text.push_str(&format!(
        "\n[[objects]]\nname = \"grille\"\nparts = [{}]\npose = {{ xyz = [0.36, 0.0, 0.0] }}\n",
        slats.join(", ")
    ));
    let scene =
        geometry::scene::Scene::from_str(&text, "scene.toml", std::path::Path::new(dir), "library")
            .unwrap();
    let world = World::from_scene(scene).unwrap();
    let planner = Planner::new();
    let mut stream = planner
        .run(
            &world,
            "show",
            &["grey-book", "member"],
            &CallOptions::seeded(1).with("robot-effort", "0"),
        )
        .unwrap();
    assert!(stream.next().is_none(), "the book shown through the grille");
    let f = stream.failure().unwrap();
    assert_eq!(f.stage, Stage::Visibility, "{f}");
    let best: f32 = f
        .message
        .split("best visibility ")
        .nth(1)
        .and_then(|t| t.split_whitespace().next())
        .and_then(|t| t.parse().ok())
        .unwrap_or_else(|| panic!("no best visibility in: {f}"));
    assert!((0.0..0.9).contains(&best), "{f}");
}

/// A person's reach for what is handed to them is that of their free hands: with a book in
/// one hand, only the other arm's shoulder counts.
#[test]
fn a_person_holding_a_book_is_reached_at_the_free_hand() {
    use gtp::target::ReachTarget;
    let mut w = library();
    let h = w.agent_id("member").unwrap();
    let book = w.object_id("grey-book").unwrap();
    let shoulders = |w: &World| match ReachTarget::person(w, h) {
        ReachTarget::Person { shoulders, .. } => shoulders,
        _ => unreachable!("a person's target"),
    };
    let both = shoulders(&w);
    assert_eq!(both.len(), 2);
    let hand = w.agent(h).hand_links[0];
    w.attach(book, h, hand);
    let free = shoulders(&w);
    assert_eq!(free.len(), 1);
    // The free shoulder is the one farther from the hand that holds the book.
    let at = w.agent_state(h).link_poses()[hand].translation;
    let far = both
        .iter()
        .copied()
        .max_by(|a, b| (*a - at).length().total_cmp(&(*b - at).length()))
        .unwrap();
    assert!((free[0] - far).length() < 1e-6);
}

/// A give hands the object to a free hand: with a book in one of the member's hands, every
/// hand-over of the first five solutions lies within reach of the other arm's shoulder (turned
/// by 0.75 rad, the member has such points within the robot's reach, and the first hand-over
/// was 4-11 mm beyond it before). Turned by 1.2 rad, none is: the give then offers the object
/// within reach of either hand, as before, rather than fail.
#[test]
fn a_give_offers_the_object_to_the_free_hand() {
    use gtp::target::ReachTarget;
    let library = library();
    let h = library.agent_id("member").unwrap();
    let book = library.object_id("grey-book").unwrap();
    let white = library.object_id("white-book").unwrap();
    for turn in [0.75f32, -0.75, 1.2] {
        // Turned sideways to the desk, one shoulder nearer the robot than the other.
        let mut w = library.clone();
        let state = w.agent_state(h).clone();
        let base = Pose::from_translation(state.base.translation)
            * Pose::from_rotation(Rotation::from_rotation_z(turn))
            * Pose::from_rotation(state.base.rotation);
        w.set_agent_config(h, base, &state.q);
        for hand in w.agent(h).hand_links.clone() {
            let mut held = w.clone();
            held.attach(white, h, hand);
            let ReachTarget::Person { shoulders, reach } = ReachTarget::person(&held, h) else {
                unreachable!("a person's target")
            };
            assert_eq!(shoulders.len(), 1);
            let mut stream = Planner::new()
                .run(
                    &held,
                    "give",
                    &["grey-book", "member"],
                    &CallOptions::seeded(3),
                )
                .expect("task resolves");
            let mut solutions = 0;
            while let Some(s) = stream.next().filter(|_| solutions < 5) {
                solutions += 1;
                let d = (s.world.object_aabb(book).center() - shoulders[0]).length();
                assert!(
                    turn > 1.0 || d <= reach,
                    "turned {turn}: hand-over {d:.3} m from the free shoulder (reach {reach})"
                );
            }
            assert!(
                solutions > 0,
                "turned {turn}: no give: {:?}",
                stream.failure()
            );
        }
    }
}
