//! The geometric task planner: grasps, placements, trajectories and the paper's tasks
//! (pick, place-on, show, give, make-accessible, put-away, navigate-to).

pub mod grasp;
pub mod gripper;
pub mod placement;
pub mod rrt;
pub mod stats;
pub mod task;
