//! The base moves when the arm cannot reach: in `scene-cart.toml` the books stand on a low cart
//! beside the robot, beyond the arm's reach from its station. A pick with the base fixed
//! (`robot-effort` 1) fails; with the default (4: turn, then step) the same task call drives
//! the base to a pose nearby and picks from there (driving back with the book when it can),
//! every trajectory collision-free when replayed at 4x the planner's resolution.

use geometry::world::World;
use gtp::planner::{CallOptions, Planner};
use gtp::solution::Phase;
use gtp::verify::recheck_trajectories;

fn cart_scene() -> World {
    World::load(concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../../domains/library/scene-cart.toml"
    ))
    .expect("cart scene")
}

#[test]
fn a_book_on_the_cart_is_out_of_reach_with_the_base_fixed() {
    let world = cart_scene();
    let planner = Planner::new();
    let options = CallOptions::seeded(1).with("robot-effort", "1");
    let mut stream = planner
        .run(&world, "pick", &["grey-book"], &options)
        .unwrap();
    assert!(stream.next().is_none(), "picked from the station");
    let failure = stream.failure().expect("a failure");
    assert!(!failure.limit, "{failure}");
    assert!(!failure.message.contains("base pose"), "{failure}");
    assert_eq!(stream.stats().base_poses, 0);
}

#[test]
fn a_book_on_the_cart_is_picked_after_a_base_move_inside_the_task() {
    let world = cart_scene();
    let planner = Planner::new();
    let robot = planner.robot(&world).unwrap().agent;
    let station = world.agent_state(robot).base.translation;
    for book in ["grey-book", "white-book", "blue-book"] {
        let mut stream = planner
            .run(&world, "pick", &[book], &CallOptions::seeded(1))
            .unwrap();
        let s = stream
            .next()
            .unwrap_or_else(|| panic!("pick {book}: {}", stream.failure().unwrap()));
        let phases: Vec<Phase> = s.summary.trajectories.iter().map(|t| t.phase).collect();
        assert_eq!(phases[0], Phase::Drive, "{book}: {phases:?}");
        assert!(phases.contains(&Phase::Grasp) && phases.contains(&Phase::Lift));
        // Worked from a pose nearby; back where the domain put the robot when the drive back
        // is free, else still there.
        let pose = s.summary.base_move.expect("the base pose worked from");
        let moved = ((pose[0] - station.x).powi(2) + (pose[1] - station.y).powi(2)).sqrt();
        assert!(moved <= 1.0 + 1e-3, "{book}: stepped {moved} m");
        let after = s.world.agent_state(robot).base.translation;
        let expected = match phases.last() {
            Some(Phase::Drive) => station,
            _ => parry3d::math::Vector::new(pose[0], pose[1], station.z),
        };
        assert!((after - expected).length() < 1e-3, "{book}: {after:?}");
        assert!(stream.stats().base_poses >= 1);
        let o = world.object_id(book).unwrap();
        assert_eq!(
            s.world.attachment(o).map(|a| a.agent),
            Some(robot),
            "{book} held"
        );
        let res = planner.config().rrt.resolution / 4.0;
        recheck_trajectories(&planner, &world, &s.summary, res)
            .unwrap_or_else(|e| panic!("pick {book}: {e}"));
    }
}

#[test]
fn the_robot_effort_constraint_is_checked() {
    let world = cart_scene();
    let planner = Planner::new();
    let options = CallOptions::seeded(1).with("robot-effort", "7");
    let err = planner
        .run(&world, "pick", &["grey-book"], &options)
        .err()
        .expect("an error");
    assert!(err.to_string().contains("robot-effort"), "{err}");
}
