//! Statistics of one task call: the columns of the paper's Table II.

use std::time::Duration;

use serde::{Deserialize, Serialize};

/// What one call of a task did (the paper's Table II columns, plus a few details).
///
/// Counters are cumulative over the whole stream: asking for the next solution keeps counting.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct Stats {
    /// Wall-clock time spent searching (seconds).
    pub time_s: f64,
    /// Whether the last request produced a solution.
    pub success: bool,
    /// Candidate points tested (`pts`).
    pub points: usize,
    /// Grasps tried (`grasps`).
    pub grasps: usize,
    /// Orientations (placement or hand-over poses) tried (`orts`).
    pub orientations: usize,
    /// Trajectory-planner (RRT-Connect) calls (`calls`).
    pub planner_calls: usize,
    /// Inverse-kinematics calls.
    pub ik_calls: usize,
    /// Pixel-visibility measurements.
    pub visibility_checks: usize,
    /// Highest effort level the search reached.
    pub effort_level: u8,
    /// Solutions produced so far.
    pub solutions: usize,
}

impl Stats {
    /// Adds `d` to the time.
    pub fn add_time(&mut self, d: Duration) {
        self.time_s += d.as_secs_f64();
    }
}
