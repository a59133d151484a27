//! Why a search found nothing (more): the stages of the paper's constraint hierarchy as a typed
//! [`Stage`], the typed [`Failure`] a stream ends with, and the bookkeeping of rejections that
//! explains it (the deepest stage that rejected a candidate, and that stage's last reason).

use std::collections::HashMap;
use std::fmt;

use serde::{Deserialize, Serialize};

use crate::rrt::{JointPath, RrtError, RrtStats};

use super::{MotionFailure, Search};

/// A stage of the search: the constraints a candidate passes, cheapest first, and the verdicts
/// on a whole search that name no single candidate.
///
/// The first eight variants are the funnel of the constraint hierarchy in order: a later one is
/// deeper (`Ord` compares depth), and the failure report names the deepest stage that rejected
/// a candidate. Each serialises and displays as the name the reports have always used
/// (`candidate-points`, `gripper-collision`, ...).
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Hash, Serialize, Deserialize)]
pub enum Stage {
    /// No candidate point meets the robot's and the human's reach and view.
    #[serde(rename = "candidate-points")]
    Points,
    /// A grasp cannot be picked up (gripper, approach, inverse kinematics, lift); as a whole-
    /// search verdict: no grasp can be.
    #[serde(rename = "pick")]
    Pick,
    /// The object (or the robot's base) collides in every orientation (pose).
    #[serde(rename = "object-collision")]
    ObjectCollision,
    /// The gripper's boxes collide at a placement (or above it, or retreating from it).
    #[serde(rename = "gripper-collision")]
    Gripper,
    /// No inverse kinematics (collision-free) at a placement.
    #[serde(rename = "inverse-kinematics")]
    Ik,
    /// The human's reach (or the robot's, from a base pose) is not as the task asks.
    #[serde(rename = "reachability")]
    Reach,
    /// Pixel visibility is not as the task asks.
    #[serde(rename = "visibility")]
    Visibility,
    /// No collision-free trajectory.
    #[serde(rename = "trajectory")]
    Trajectory,
    /// The object has no grasp for the gripper at all.
    #[serde(rename = "grasp")]
    Grasp,
    /// Every gripper that could grasp the object holds something else.
    #[serde(rename = "gripper")]
    FreeGripper,
    /// What a take needs held is not (the object by the robot, a free hand of the person).
    #[serde(rename = "held")]
    Held,
    /// The call's time limit.
    #[serde(rename = "time-limit")]
    TimeLimit,
    /// Nothing was rejected: nothing (more) to try.
    #[serde(rename = "search")]
    Search,
}

impl Stage {
    /// The stage's name in reports (as it serialises).
    pub fn name(self) -> &'static str {
        match self {
            Stage::Points => "candidate-points",
            Stage::Pick => "pick",
            Stage::ObjectCollision => "object-collision",
            Stage::Gripper => "gripper-collision",
            Stage::Ik => "inverse-kinematics",
            Stage::Reach => "reachability",
            Stage::Visibility => "visibility",
            Stage::Trajectory => "trajectory",
            Stage::Grasp => "grasp",
            Stage::FreeGripper => "gripper",
            Stage::Held => "held",
            Stage::TimeLimit => "time-limit",
            Stage::Search => "search",
        }
    }
}

impl fmt::Display for Stage {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

/// A grasp choice whose transfers failed this many times in a row (each a motion-planning
/// query run to its limit, to different placements) is given up: its carry is boxed in where it
/// starts (one held out between furniture, say), and more targets would spend the call's whole
/// time limit on it.
pub(super) const MAX_FAILED_TRANSFERS: usize = 12;

/// Why a task call produced no (further) solution: which stage of the search stopped it.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Failure {
    /// The stage that rejected the last candidates, or the whole-search verdict (serialised
    /// as `constraint`, the name reports have always used).
    #[serde(rename = "constraint")]
    pub stage: Stage,
    /// In words, with the best value reached where it helps ("best visibility 0.31").
    pub message: String,
    /// Whether a limit (time) stopped the search rather than exhaustion.
    pub limit: bool,
}

impl Failure {
    /// A failure at `stage` that no limit caused.
    pub(crate) fn at(stage: Stage, message: String) -> Failure {
        Failure {
            stage,
            message,
            limit: false,
        }
    }
}

impl fmt::Display for Failure {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{} ({})", self.message, self.stage)
    }
}

/// The rejections of a search so far: per stage how many, the deepest stage and its last
/// reason (what the failure report says), and the last reason a grasp could not be picked up.
#[derive(Debug, Default)]
pub(super) struct Rejections {
    /// Candidates rejected per stage.
    counts: HashMap<Stage, usize>,
    /// The deepest stage that rejected a candidate.
    pub(super) deepest: Option<Stage>,
    /// That stage's last reason.
    pub(super) last_reason: String,
    /// The last reason a grasp could not be picked up.
    pub(super) pick_reason: String,
    /// Why an arm's approach could not leave its start posture (in collision), where one
    /// could not: every approach of that arm fails alike.
    pub(super) start_reason: Option<String>,
    /// The best visibility a placement reached (the most for showing, the least for hiding).
    pub(super) best_visibility: Option<f32>,
}

impl Search {
    /// Records a candidate rejected at `stage`; `reason` is worded only when it may be reported.
    pub(super) fn reject(&mut self, stage: Stage, reason: impl FnOnce() -> String) {
        let r = &mut self.rejections;
        *r.counts.entry(stage).or_default() += 1;
        let deepest = r.deepest.is_none_or(|d| stage >= d);
        // The reason is worded only when it may be reported: the deepest stage's, a pick's
        // (given when no grasp can be picked up at all), or every one when tracing.
        if !(deepest || stage == Stage::Pick || self.cfg.trace) {
            return;
        }
        let text = reason();
        if self.cfg.trace {
            eprintln!("reject {stage:?}: {text}");
        }
        if stage == Stage::Pick {
            r.pick_reason.clone_from(&text);
        }
        if deepest {
            r.deepest = Some(stage);
            r.last_reason = text;
        }
    }

    /// `r`'s value; or, rejecting at `stage` with `what` and the error, `None`.
    pub(super) fn or_reject<T, E: fmt::Display>(
        &mut self,
        r: Result<T, E>,
        stage: Stage,
        what: impl FnOnce() -> String,
    ) -> Option<T> {
        match r {
            Ok(v) => Some(v),
            Err(e) => {
                self.reject(stage, || format!("{}: {e}", what()));
                None
            }
        }
    }

    /// A motion carrying the object, as [`Search::or_reject`] at the trajectory stage; a
    /// start in collision (the same whatever the tuple), or [`MAX_FAILED_TRANSFERS`] failures
    /// in a row, also drops grasp choice `grasp`.
    pub(super) fn transfer_or_reject(
        &mut self,
        r: Result<(JointPath, RrtStats), MotionFailure>,
        grasp: usize,
        what: impl FnOnce() -> String,
    ) -> Option<JointPath> {
        let failed = self.failed_transfers.entry(grasp).or_default();
        *failed = if r.is_ok() { 0 } else { *failed + 1 };
        let invalid_start = matches!(&r, Err(e) if e.error == RrtError::InvalidStart);
        if invalid_start || *failed >= MAX_FAILED_TRANSFERS {
            self.failed_choices.insert(grasp);
        }
        self.or_reject(r.map(|(p, _)| p), Stage::Trajectory, what)
    }

    /// Why the search found nothing (more): the deepest stage that rejected candidates.
    pub(super) fn explain(&self) -> Failure {
        let r = &self.rejections;
        match r.deepest {
            None => Failure::at(
                Stage::Search,
                if self.stats.solutions > 0 {
                    "no further solution".to_string()
                } else {
                    "nothing to try".to_string()
                },
            ),
            Some(stage) => {
                let mut m = r.last_reason.clone();
                if self.stats.solutions > 0 {
                    m = format!("no further solution after {}: {m}", self.stats.solutions);
                }
                Failure::at(stage, m)
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Every stage serialises and displays as the name reports have always used, and a
    /// failure's stage serialises under `constraint`, so report JSON keeps its shape.
    #[test]
    fn stages_keep_their_report_names() {
        let all = [
            Stage::Points,
            Stage::Pick,
            Stage::ObjectCollision,
            Stage::Gripper,
            Stage::Ik,
            Stage::Reach,
            Stage::Visibility,
            Stage::Trajectory,
            Stage::Grasp,
            Stage::FreeGripper,
            Stage::Held,
            Stage::TimeLimit,
            Stage::Search,
        ];
        for s in all {
            let json = serde_json::to_string(&s).expect("a stage serialises");
            assert_eq!(json, format!("\"{}\"", s.name()));
            assert_eq!(s.to_string(), s.name());
            assert_eq!(
                serde_json::from_str::<Stage>(&json).expect("and reads back"),
                s
            );
        }
        let f = Failure::at(Stage::Gripper, "the gripper hits `desk`".into());
        let v = serde_json::to_value(&f).expect("a failure serialises");
        assert_eq!(v["constraint"], "gripper-collision");
        assert_eq!(f.to_string(), "the gripper hits `desk` (gripper-collision)");
    }

    /// The funnel's stages are ordered by depth: pixel visibility after inverse kinematics,
    /// the trajectories last.
    #[test]
    fn funnel_stages_are_ordered_by_depth() {
        assert!(Stage::Points < Stage::Pick);
        assert!(Stage::Gripper < Stage::Ik);
        assert!(Stage::Ik < Stage::Reach);
        assert!(Stage::Reach < Stage::Visibility);
        assert!(Stage::Visibility < Stage::Trajectory);
    }
}
