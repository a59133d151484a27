//! The geometric task planner: grasps, placements, trajectories and the paper's tasks
//! (pick, place-on, show, give, make-accessible, put-away, navigate-to).
