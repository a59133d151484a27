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
    /// Base poses nearby tried after the task failed from where the robot stood (a base move
    /// inside the task: turning in place, then stepping). Absent from the JSON when zero.
    #[serde(default, skip_serializing_if = "is_zero")]
    pub base_poses: usize,
}

fn is_zero(n: &usize) -> bool {
    *n == 0
}

impl Stats {
    /// Adds `d` to the time.
    pub fn add_time(&mut self, d: Duration) {
        self.time_s += d.as_secs_f64();
    }

    /// What one request of a stream did: these cumulative counters minus those taken before
    /// it (`before`). Success, effort level and solutions are this request's.
    pub fn since(&self, before: &Stats) -> Stats {
        Stats {
            time_s: self.time_s - before.time_s,
            points: self.points.saturating_sub(before.points),
            grasps: self.grasps.saturating_sub(before.grasps),
            orientations: self.orientations.saturating_sub(before.orientations),
            planner_calls: self.planner_calls.saturating_sub(before.planner_calls),
            ik_calls: self.ik_calls.saturating_sub(before.ik_calls),
            visibility_checks: self
                .visibility_checks
                .saturating_sub(before.visibility_checks),
            solutions: self.solutions.saturating_sub(before.solutions),
            base_poses: self.base_poses.saturating_sub(before.base_poses),
            ..*self
        }
    }

    /// Sums another request's statistics into these (a task's totals over a run or an
    /// experiment): counters and time add up, the effort level is the highest reached, and
    /// `success` is whether any request succeeded.
    pub fn accumulate(&mut self, other: &Stats) {
        self.time_s += other.time_s;
        self.success |= other.success;
        self.points += other.points;
        self.grasps += other.grasps;
        self.orientations += other.orientations;
        self.planner_calls += other.planner_calls;
        self.ik_calls += other.ik_calls;
        self.visibility_checks += other.visibility_checks;
        self.effort_level = self.effort_level.max(other.effort_level);
        self.solutions += other.solutions;
        self.base_poses += other.base_poses;
    }
}
