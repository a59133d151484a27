//! The geometric task planner: grasps, placements, trajectories and the paper's tasks
//! (pick, place-on, show, give, make-accessible, put-away, navigate-to).

pub mod grasp;
pub mod gripper;
pub mod placement;
pub mod planner;
pub mod robot;
pub mod rrt;
pub mod search;
pub mod solution;
pub mod stats;
pub mod task;
pub mod verify;
