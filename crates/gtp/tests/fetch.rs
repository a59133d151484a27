//! The paper's tasks with a one-armed robot: the Fetch-like model (`models/fetch.urdf`) in the
//! library (`domains/library/scene-fetch.toml`). Every task grasps, carries and hands over with
//! its one arm; each solution's trajectories are replayed at 4x the planner's resolution.

use geometry::facts::{FactParams, on, reachable_effort};
use geometry::scene::{AgentId, ObjectId};
use geometry::visibility::{Aim, visibility_for_agent};
use geometry::world::World;
use gtp::planner::{CallOptions, Planner, Solution, Stage};
use gtp::solution::Phase;
use gtp::verify::recheck_trajectories;

fn fetch_library() -> World {
    World::load(concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../../domains/library/scene-fetch.toml"
    ))
    .expect("the Fetch library scene")
}

/// The scene's robot (named `pr2` there, after the library domain's constant).
fn robot(world: &World) -> AgentId {
    world.agent_id("pr2").unwrap()
}

/// The first solution of `task`, its trajectories re-checked.
fn first(planner: &Planner, world: &World, task: &str, args: &[&str]) -> Solution {
    let mut stream = planner
        .run(world, task, args, &CallOptions::seeded(3))
        .expect("task resolves");
    let s = match stream.next() {
        Some(s) => s,
        None => panic!("{task} {args:?} failed: {}", stream.failure().unwrap()),
    };
    let res = planner.config().rrt.resolution / 4.0;
    assert!(!s.summary.trajectories.is_empty());
    recheck_trajectories(planner, world, &s.summary, res)
        .unwrap_or_else(|e| panic!("{task} {args:?}: {e}"));
    // The one arm did it.
    if let Some(g) = &s.summary.grasp {
        assert_eq!(g.arm, "arm", "{task}");
    }
    s
}

fn best_visibility(w: &World, h: AgentId, o: ObjectId) -> f32 {
    let now = visibility_for_agent(w, h, o, Aim::Current, 64).fraction();
    now.max(visibility_for_agent(w, h, o, Aim::AtTarget, 64).fraction())
}

fn reach_within(w: &World, h: AgentId, o: ObjectId, level: u8) -> Option<u8> {
    let params = FactParams {
        max_effort: level,
        ..FactParams::default()
    };
    reachable_effort(w, h, o, &params)
}

#[test]
fn the_scene_has_a_one_armed_robot() {
    let world = fetch_library();
    let info = world.agent(robot(&world));
    assert_eq!(info.model.name(), "fetch");
    assert_eq!(info.model.arm_names(), ["arm"]);
    assert_eq!(info.hand_links.len(), 1);
    assert_eq!(info.shoulder_links.len(), 1);
    assert!(info.head_pivot_link().is_some());
}

#[test]
fn pick_then_place_on_the_desk_with_the_one_arm() {
    let world = fetch_library();
    let planner = Planner::new();
    let book = world.object_id("grey-book").unwrap();
    let desk = world.object_id("desk").unwrap();
    let picked = first(&planner, &world, "pick", &["grey-book"]);
    assert_eq!(
        picked.world.attachment(book).map(|a| a.agent),
        Some(robot(&world))
    );
    let placed = first(&planner, &picked.world, "place-on", &["grey-book", "desk"]);
    assert!(placed.world.attachment(book).is_none());
    assert!(on(&placed.world, book, desk, 0.05));
    // The grasp was kept: no pick phase in the second plan.
    assert!(placed.summary.grasp.as_ref().unwrap().id.is_none());
}

#[test]
fn show_give_make_accessible_and_put_away_with_the_one_arm() {
    let world = fetch_library();
    let planner = Planner::new();
    let book = world.object_id("grey-book").unwrap();
    let member = world.agent_id("member").unwrap();
    for task in ["show", "give"] {
        let s = first(&planner, &world, task, &["grey-book", "member"]);
        assert!(best_visibility(&s.world, member, book) >= 0.9, "{task}");
        assert_eq!(
            s.world.attachment(book).map(|a| a.agent),
            Some(robot(&world))
        );
    }
    let s = first(
        &planner,
        &world,
        "make-accessible",
        &["grey-book", "member"],
    );
    assert!(best_visibility(&s.world, member, book) >= 0.5);
    assert!(reach_within(&s.world, member, book, 1).is_some());
    assert!(s.world.attachment(book).is_none());
    // Put away with one hand: the POS machine from the shelf's top, out of the member's sight.
    let pos = world.object_id("pos-machine").unwrap();
    let s = first(&planner, &world, "put-away", &["pos-machine", "member"]);
    assert!(best_visibility(&s.world, member, pos) <= 0.0);
    assert!(reach_within(&s.world, member, pos, 1).is_none());
    assert!(s.world.attachment(pos).is_none());
}

#[test]
fn the_member_takes_a_given_book_from_the_one_arm_which_is_free_again() {
    let world = fetch_library();
    let planner = Planner::new();
    let book = world.object_id("grey-book").unwrap();
    let member = world.agent_id("member").unwrap();
    let given = first(&planner, &world, "give", &["grey-book", "member"]);
    // The one gripper is full: another pick says so.
    let mut full = planner
        .run(
            &given.world,
            "pick",
            &["pos-machine"],
            &CallOptions::seeded(1),
        )
        .unwrap();
    assert!(full.next().is_none());
    assert_eq!(full.failure().unwrap().stage, Stage::FreeGripper);
    let taken = first(&planner, &given.world, "take", &["grey-book", "member"]);
    let at = taken.world.attachment(book).expect("the book is held");
    assert_eq!(at.agent, member);
    let phases: Vec<Phase> = taken.summary.trajectories.iter().map(|t| t.phase).collect();
    assert_eq!(phases, [Phase::Reach, Phase::Retreat, Phase::Withdraw]);
    // The gripper is free again: the next pick works.
    first(&planner, &taken.world, "pick", &["pos-machine"]);
}
