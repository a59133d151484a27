//! The cursor of the search over (effort level, candidate point, grasp, orientation), and the
//! loop that moves it: the outermost loop of the constraint hierarchy. Each call of
//! [`Search::next_tuple`] resumes where the previous solution was found.

use std::time::Instant;

use parry3d::math::Vector;

use crate::planner::Solution;
use crate::task::TaskKind;

use super::placements::Orientation;
use super::{Failure, Search, Stage};

/// Where the search stands: indices into the effort levels, the level's candidate points, the
/// grasp choices and the point's orientations, with the lists computed for the current level
/// and point.
#[derive(Debug, Default)]
pub(super) struct Cursor {
    /// Index into the search's effort levels.
    pub(super) level: usize,
    /// The current level's candidate points, best first (`None`: not computed yet). A
    /// navigate-to search keeps its candidate base positions here.
    pub(super) points: Option<Vec<Vector>>,
    /// Index into `points`.
    pub(super) point: usize,
    /// The current point's collision-free orientations of the object (`None`: not computed
    /// yet).
    pub(super) orientations: Option<Vec<Orientation>>,
    /// Index into the search's grasp choices.
    pub(super) grasp: usize,
    /// Whether the current grasp passed its tests at the current point.
    pub(super) grasp_ready: bool,
    /// Index into `orientations`: the next one to try with the current grasp.
    pub(super) orientation: usize,
    /// Tool poses at the current point for which inverse kinematics found no arm posture,
    /// and whether it found one for some tool pose there.
    pub(super) ik_misses: usize,
    pub(super) ik_reached: bool,
    /// Tool poses at the current point for which inverse kinematics found no collision-free
    /// arm posture (missed, or every posture found collides), and whether it found one for
    /// some tool pose there.
    pub(super) ik_failures: usize,
    pub(super) ik_free: bool,
}

/// A candidate point where inverse kinematics missed this many tool poses, and reached none,
/// is left for the next point: its (grasp, orientation) pairs, hundreds for a hand-over, are
/// then mostly beyond the wrist's reach, each costing an IK call (one `pick-and-show` of a
/// random room: 67,638 missed calls at 173 points, 3.3 s).
pub(super) const MAX_IK_MISSES_AT_POINT: usize = 16;

/// A candidate point where inverse kinematics found no collision-free arm posture for this
/// many tool poses is left for the next point too: where the arm reaches but collides (a
/// hand-over pose among furniture), every (grasp, orientation) pair would cost an IK call
/// (one `pick-and-show` of a random room: 23,699 calls at 513 points, a few points taking
/// 160 to 527 each; 1.5 s).
pub(super) const MAX_IK_FAILURES_AT_POINT: usize = 48;

/// A placement of a placing task: an orientation at a point of a level. What the human-related
/// constraints say of it does not depend on the grasp (the arm returns to where it was).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub(super) struct PlacementKey {
    level: usize,
    point: usize,
    orientation: usize,
}

/// One tuple to try: a grasp choice, a point, an orientation there and its index.
#[derive(Clone, Copy, Debug)]
pub(super) struct Tuple {
    pub(super) grasp: usize,
    pub(super) point: Vector,
    pub(super) orientation: Orientation,
    pub(super) orientation_index: usize,
}

/// What one move of the cursor came to.
enum Advance {
    /// Every level is done.
    Exhausted,
    /// The cursor moved on (another level, point or grasp): check the limits, move again.
    Moved,
    /// A tuple to try.
    Tuple(Tuple),
}

impl Cursor {
    /// The placement of orientation `orientation` at the current point and level.
    pub(super) fn placement(&self, orientation: usize) -> PlacementKey {
        PlacementKey {
            level: self.level,
            point: self.point,
            orientation,
        }
    }

    /// The current candidate point, if the current level has one left.
    pub(super) fn current_point(&self) -> Option<Vector> {
        self.points.as_ref()?.get(self.point).copied()
    }

    fn next_level(&mut self) {
        self.level += 1;
        self.points = None;
    }

    pub(super) fn next_point(&mut self) {
        self.point += 1;
        self.orientations = None;
    }

    /// Whether inverse kinematics missed so many tool poses at the current point, and reached
    /// none, that the point is given up ([`MAX_IK_MISSES_AT_POINT`]), or found no
    /// collision-free posture for so many ([`MAX_IK_FAILURES_AT_POINT`]).
    fn point_out_of_reach(&self) -> bool {
        (!self.ik_reached && self.ik_misses >= MAX_IK_MISSES_AT_POINT)
            || (!self.ik_free && self.ik_failures >= MAX_IK_FAILURES_AT_POINT)
    }

    fn next_grasp(&mut self) {
        self.grasp += 1;
        self.grasp_ready = false;
    }
}

impl Search {
    /// The next solution of a pick, placing or hand-over task, moving the cursor.
    pub(super) fn next_tuple(&mut self) -> Option<Solution> {
        let began = Instant::now();
        loop {
            if self.out_of_time(began) {
                let failure = Failure {
                    stage: Stage::TimeLimit,
                    message: format!(
                        "time limit of {:?} reached ({})",
                        self.c.time_limit,
                        self.explain().message
                    ),
                    limit: true,
                };
                return self.fail(failure);
            }
            if let Some(f) = self.dead_end() {
                return self.fail(f);
            }
            let tuple = match self.advance() {
                Advance::Exhausted => return None,
                Advance::Moved => continue,
                Advance::Tuple(t) => t,
            };
            if let Some(sol) = self.try_tuple(tuple) {
                // The next solution at another point: another grasp or turn of the object at
                // the same spot would mostly repeat this one's effect on the world (what it
                // hides, what it blocks), which is what a request for another solution wants
                // to change.
                if self.task.kind != TaskKind::Pick {
                    self.cursor.next_point();
                }
                return Some(sol);
            }
        }
    }

    /// Why no tuple can ever succeed, whatever the cursor: no free gripper, every grasp failed
    /// for good, or no grasp at all.
    fn dead_end(&self) -> Option<Failure> {
        if self.choices.is_empty() && !self.busy_arms.is_empty() {
            return Some(Failure::at(
                Stage::FreeGripper,
                format!(
                    "no free gripper to grasp `{}`: {}",
                    self.object_name(),
                    self.busy_arms.join(", ")
                ),
            ));
        }
        if !self.choices.is_empty() && self.failed_choices.len() == self.choices.len() {
            // Every grasp failed for good (no pick, no approach, a carry that cannot
            // start): no point, orientation or level can change that.
            let message = if self.held {
                format!(
                    "the held `{}` cannot be carried ({})",
                    self.object_name(),
                    self.rejections.last_reason
                )
            } else if let Some(start) = &self.rejections.start_reason {
                format!(
                    "no grasp of `{}` can be picked up ({} tried): no approach leaves the \
                     arm's start posture ({start})",
                    self.object_name(),
                    self.choices.len(),
                )
            } else {
                format!(
                    "no grasp of `{}` can be picked up ({} tried; the last: {})",
                    self.object_name(),
                    self.choices.len(),
                    self.rejections.pick_reason
                )
            };
            return Some(Failure::at(Stage::Pick, message));
        }
        if self.choices.is_empty() {
            let widest = self.setup.arms.iter().map(|a| a.gripper.max_opening);
            let widest = widest.fold(0.0f32, f32::max);
            let message = if widest > 0.0 {
                format!(
                    "`{}` has no grasp for the gripper (too wide for a {:.0} mm jaw opening, \
                     or every grasp collides with the object)",
                    self.object_name(),
                    widest * 1000.0
                )
            } else {
                format!(
                    "`{}` has no grasp: no arm's gripper opens its jaws (no finger joint in or \
                     below its SRDF end effector group, or its fingers do not face each other \
                     across the tool frame's y axis: the scene's `hands` tool frame has x \
                     forward out of the palm, y along which the fingers close)",
                    self.object_name()
                )
            };
            return Some(Failure::at(Stage::Grasp, message));
        }
        None
    }

    /// One move of the cursor: into a level (its points), a point (its orientations), a grasp
    /// (its tests at the point), or to the next orientation, the tuple to try.
    fn advance(&mut self) -> Advance {
        if self.cursor.points.is_none() {
            let Some(&level) = self.levels.get(self.cursor.level) else {
                return Advance::Exhausted;
            };
            self.stats.effort_level = self.stats.effort_level.max(level);
            let points = self.candidate_points(level);
            let cursor = &mut self.cursor;
            cursor.points = Some(points);
            cursor.point = 0;
            cursor.orientations = None;
        }
        let Some(point) = self.cursor.current_point() else {
            self.cursor.next_level();
            return Advance::Moved;
        };
        if self.cursor.orientations.is_none() && !self.enter_point(point) {
            self.cursor.next_point();
            return Advance::Moved;
        }
        if self.cursor.grasp >= self.choices.len() {
            self.cursor.next_point();
            return Advance::Moved;
        }
        if self.cursor.point_out_of_reach() {
            let oname = self.object_name();
            self.reject(Stage::Ik, || {
                format!("no placement of `{oname}` is within the arm's reach (inverse kinematics)")
            });
            self.cursor.next_point();
            return Advance::Moved;
        }
        if !self.cursor.grasp_ready && !self.enter_grasp(point) {
            self.cursor.grasp += 1;
            return Advance::Moved;
        }
        let cursor = &self.cursor;
        let next = cursor
            .orientations
            .as_ref()
            .and_then(|o| o.get(cursor.orientation).copied());
        let Some(orientation) = next.filter(|_| !self.failed_choices.contains(&cursor.grasp))
        else {
            self.cursor.next_grasp();
            return Advance::Moved;
        };
        let tuple = Tuple {
            grasp: cursor.grasp,
            point,
            orientation,
            orientation_index: cursor.orientation,
        };
        self.cursor.orientation += 1;
        self.stats.orientations += 1;
        Advance::Tuple(tuple)
    }

    /// Enters candidate point `point`: its orientations, the grasps from the first. `false`
    /// when no orientation there meets the human-related constraints.
    fn enter_point(&mut self, point: Vector) -> bool {
        self.tried_points.insert(super::points::key(point));
        self.stats.points += 1;
        let orientations = self.orientations_at(point);
        let cursor = &mut self.cursor;
        cursor.orientations = Some(orientations);
        cursor.grasp = 0;
        cursor.orientation = 0;
        cursor.grasp_ready = false;
        cursor.ik_misses = 0;
        cursor.ik_reached = false;
        cursor.ik_failures = 0;
        cursor.ik_free = false;
        self.point_has_placement()
    }

    /// Enters the cursor's grasp choice at `point`: `false` when it cannot be picked up or
    /// cannot place the object there.
    fn enter_grasp(&mut self, point: Vector) -> bool {
        let grasp = self.cursor.grasp;
        if self.failed_choices.contains(&grasp) || !self.pick_feasible(grasp) {
            return false;
        }
        if !self.arm_may_reach_point(self.choices[grasp].arm, point)
            || !self.choice_fits_point(grasp)
        {
            let what = if self.held {
                "the held grasp"
            } else {
                "a grasp"
            };
            self.reject(Stage::Gripper, || {
                format!("no placement leaves {what} within the arm's reach with the gripper free")
            });
            return false;
        }
        self.cursor.grasp_ready = true;
        self.cursor.orientation = 0;
        true
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_point_is_given_up_after_its_ik_misses_or_failures_and_kept_once_the_arm_is_free() {
        let mut c = Cursor {
            ik_misses: MAX_IK_MISSES_AT_POINT,
            ik_failures: MAX_IK_MISSES_AT_POINT,
            ..Cursor::default()
        };
        assert!(c.point_out_of_reach(), "missed every tool pose");
        // The arm reached some tool pose (in collision): misses alone no longer give up.
        c.ik_reached = true;
        assert!(!c.point_out_of_reach());
        c.ik_failures = MAX_IK_FAILURES_AT_POINT;
        assert!(c.point_out_of_reach(), "no collision-free posture at any");
        // One collision-free posture there: the point is searched to the end.
        c.ik_free = true;
        c.ik_failures = 10 * MAX_IK_FAILURES_AT_POINT;
        assert!(!c.point_out_of_reach());
    }
}
