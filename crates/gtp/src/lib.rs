//! The geometric task planner (GTP): grasps, placements, trajectories and the paper's tasks
//! (pick, place-on, show, give, make-accessible, put-away, navigate-to, and the compound
//! pick-and-make-accessible).
//!
//! # Using it (the `hybrid` crate's view)
//!
//! * [`planner::Planner`] keeps what depends only on the scene (grasp sets per object shape,
//!   the robot's arms and self-collision model); share one per session (`Send + Sync`).
//! * [`planner::Planner::run`]`(world, "make-accessible", &["grey-book", "member"], &options)`
//!   resolves the names and returns a [`planner::SolutionStream`]; nothing is searched yet.
//! * Each `next()` continues the search and yields a [`planner::Solution`]: the world after it
//!   (`geometry::world::World`, cheap to clone: object poses, attachments and joint values
//!   over a shared `Arc` model) and a serialisable [`solution::SolutionSummary`] (grasp,
//!   placement, visibility reached, reach effort, trajectories with their lengths, statistics).
//!   Successive solutions differ in point, grasp or orientation.
//! * When the stream ends, [`planner::SolutionStream::failure`] says which constraint stopped
//!   it ("no placement hidden from member: best visibility 0.31 (needs <= 0.00)") and whether
//!   the time limit did; [`planner::SolutionStream::stats`] gives the paper's Table II columns.
//! * Thresholds have per-task defaults ([`task::Constraints::defaults`]) and can be set per call
//!   ([`planner::CallOptions::with`]).
//!
//! # The search ([`search`])
//!
//! Effort levels of the human -> candidate points (on support surfaces, or in the air for a
//! hand-over; filtered by the robot's reach and the human's reach and view at that level, or by
//! the mightability maps) -> grasps ([`grasp`], the object's cached grasp set, both arms) ->
//! orientations (the object's stable resting faces x yaws, [`placement`]). Cheap tests first
//! (collision of the object, boxes of the gripper, wrist reach), then inverse kinematics, the
//! exact reach test and pixel visibility, then the trajectories: approach, grasp, lift,
//! transfer, place, retreat and return, each collision-checked ([`robot`]) and the free-space
//! ones planned with RRT-Connect ([`rrt`]). Failed points and grasps are remembered across
//! effort levels. [`verify`] re-checks a solution independently.
//!
//! # Example
//!
//! Make the grey book of the library scene accessible to the member: the first solution puts
//! it where the member sees and reaches it, and its world is the start of the next task.
//!
//! ```
//! use geometry::world::World;
//! use gtp::planner::{CallOptions, Planner};
//!
//! let scene = concat!(env!("CARGO_MANIFEST_DIR"), "/../../domains/library/scene.toml");
//! let world = World::load(scene)?;
//! let planner = Planner::new();
//! let mut stream =
//!     planner.run(&world, "make-accessible", &["grey-book", "member"], &CallOptions::default())?;
//! let solution = stream.next().expect("the library's grey book can be made accessible");
//! let summary = &solution.summary;
//! let placement = summary.placement.as_ref().expect("a make-accessible places the book");
//! println!("on {:?} at {:?}, visibility {:?}", placement.support, placement.point, summary.visibility);
//! assert!(summary.visibility.is_some_and(|v| v > 0.5));
//! assert!(!summary.trajectories.is_empty());
//! // The world after the solution: the book at its new place.
//! let book = solution.world.object_id("grey-book").unwrap();
//! assert_ne!(solution.world.object_pose(book), world.object_pose(book));
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```
pub mod grasp;
pub mod gripper;
mod nearest_kd_tree;
pub mod placement;
pub mod planner;
pub mod robot;
pub mod rrt;
pub mod search;
pub mod solution;
pub mod stats;
pub mod take;
pub mod target;
pub mod task;
pub mod verify;
