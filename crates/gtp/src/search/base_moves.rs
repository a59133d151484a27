//! The base moves when the arm cannot reach. A pick, place or hand-over that finds nothing from
//! where the robot stands (out of reach, or blocked from there) is tried again, inside the same
//! task call, from base poses nearby: turning in place to face the target first, then stepping
//! to poses within [`STEP_RADIUS`] (as a person turns, then steps: the effort levels 2 and 4 of
//! `geometry::effort`, allowed by the task's `robot_effort`, 4 by default). Each pose is reached by a collision-free drive (a `navigate-to` search
//! restricted to those poses), and a solution from there starts with that drive.

use std::time::Duration;

use crate::planner::{Solution, Task};
use crate::stats::Stats;
use crate::task::TaskKind;

use super::{Failure, Search, Stage};

/// How far (metres) a base move inside a task may step from where the robot stands.
pub(crate) const STEP_RADIUS: f32 = 1.0;

/// The search of a task from base poses nearby, after it failed where the robot stood.
pub(crate) struct BaseMoves {
    /// `navigate-to` over the poses nearby: each solution is a drive to one.
    stances: Search,
    /// The drive to the current pose and the task's search from there.
    here: Option<(Solution, Search)>,
    /// Why the task failed where the robot stood.
    at_start: Failure,
    /// The statistics of the task's searches from the poses left behind.
    finished: Stats,
    /// The task's time limit, shared by every search of the call.
    time_limit: Duration,
    /// Time spent before the base moves (the search where the robot stood).
    spent_before: f64,
    seed: u64,
    failure: Option<Failure>,
}

impl BaseMoves {
    /// The base moves after `search` failed from where the robot stands, or `None` when moving
    /// the base cannot help: a limit stopped it, the failure concerns the human or the grasp
    /// set, or the task hands over or puts away what the robot already holds in a take.
    pub(crate) fn after(search: &Search, seed: u64) -> Option<BaseMoves> {
        let failure = search.failure.clone()?;
        let effort = search.c.robot_effort;
        if effort < 2 || failure.limit || !robot_bound(failure.stage) || search.stats.solutions > 0
        {
            return None;
        }
        let nav = stance_task(search)?;
        let mut c = search.c.clone();
        c.time_limit = search.c.time_limit.checked_sub(search.elapsed)?;
        let mut stances = Search::new(
            search.cfg.clone(),
            search.setup.clone(),
            search.world.clone(),
            nav,
            c,
            seed,
        )
        .ok()?;
        // Level 2 turns the base in place; level 4 steps too.
        stances.stance_radius = Some(if effort >= 4 { STEP_RADIUS } else { 0.0 });
        Some(BaseMoves {
            stances,
            here: None,
            at_start: failure,
            finished: Stats::default(),
            time_limit: search.c.time_limit,
            spent_before: search.elapsed.as_secs_f64(),
            seed,
            failure: None,
        })
    }

    /// The next solution from a pose nearby (the drive, then the task), or `None` when every
    /// pose is tried or the time is up ([`BaseMoves::failure`] then says why).
    pub(crate) fn next_solution(&mut self, template: &Search) -> Option<Solution> {
        loop {
            if let Some((drive, search)) = &mut self.here {
                if let Some(s) = search.next_solution() {
                    return Some(after_drive(drive, s));
                }
                self.finished.accumulate(&search.stats);
                self.here = None;
            }
            let Some(drive) = self.stances.next_solution() else {
                self.failure = Some(self.explain());
                return None;
            };
            let Some(left) = self.time_left() else {
                self.failure = Some(self.explain());
                return None;
            };
            let mut c = template.c.clone();
            c.time_limit = left;
            let Ok(search) = Search::new(
                template.cfg.clone(),
                template.setup.clone(),
                drive.world.clone(),
                template.task.clone(),
                c,
                self.seed,
            ) else {
                continue;
            };
            self.here = Some((drive, search));
        }
    }

    /// The statistics of every search of the base moves (the poses tried as `base_poses`).
    pub(crate) fn stats(&self) -> Stats {
        let mut s = self.finished;
        if let Some((_, search)) = &self.here {
            s.accumulate(&search.stats);
        }
        s.base_poses += self.stances.stats.points;
        s.planner_calls += self.stances.stats.planner_calls;
        s.time_s += self.stances.stats.time_s;
        s
    }

    /// Why the base moves found nothing (more), once they have.
    pub(crate) fn failure(&self) -> Option<&Failure> {
        self.failure.as_ref()
    }

    /// The time the call has left, `None` when it is up.
    fn time_left(&self) -> Option<Duration> {
        let spent = self.spent_before + self.stats().time_s;
        self.time_limit
            .checked_sub(Duration::from_secs_f64(spent))
            .filter(|d| !d.is_zero())
    }

    /// The failure of the whole call: the one where the robot stood, with what the poses
    /// nearby gave.
    fn explain(&self) -> Failure {
        let tried = self.stances.stats.points;
        let out_of_time = self.time_left().is_none();
        let nearby = match self.stances.failure.as_ref() {
            _ if out_of_time => "the time limit was reached".to_string(),
            Some(f) if self.stances.stats.solutions == 0 => format!("none reached: {}", f.message),
            _ => format!(
                "the task failed from each of the {} reached",
                self.stances.stats.solutions
            ),
        };
        Failure {
            stage: if out_of_time {
                Stage::TimeLimit
            } else {
                self.at_start.stage
            },
            message: format!(
                "{}; then {tried} base pose(s) within {STEP_RADIUS} m (turning, stepping): {nearby}",
                self.at_start.message
            ),
            limit: out_of_time,
        }
    }
}

/// Whether a failure at `stage` concerns the robot's own reach or room to move (a base move
/// may help), not the human's reach or view or the object's grasp set (it cannot).
fn robot_bound(stage: Stage) -> bool {
    matches!(
        stage,
        Stage::Points
            | Stage::Pick
            | Stage::ObjectCollision
            | Stage::Gripper
            | Stage::Ik
            | Stage::Trajectory
            | Stage::Search
    )
}

/// The `navigate-to` whose poses serve `search`'s task: to the object while the robot does not
/// hold it; once held, to the support (place-on) or the human (show, give, make-accessible).
fn stance_task(search: &Search) -> Option<Task> {
    let kind = search.task.kind;
    let world = &search.world;
    let mut nav = Task {
        kind: TaskKind::NavigateTo,
        args: Vec::new(),
        object: None,
        support: None,
        human: None,
        target_point: None,
        target_object: None,
    };
    let target_object = match (kind, search.held) {
        (TaskKind::Take | TaskKind::NavigateTo, _) => return None,
        (_, false) => search.object,
        (TaskKind::PlaceOn, true) => search.task.support,
        (TaskKind::Show | TaskKind::Give | TaskKind::MakeAccessible, true) => None,
        _ => return None,
    };
    if let Some(o) = target_object {
        nav.args.push(world.object(o).name.clone());
        nav.target_point = Some(world.object_aabb(o).center());
        nav.target_object = Some(o);
    } else {
        let h = search.human?;
        nav.args.push(world.agent(h).name().to_string());
        nav.target_point = Some(world.eye_pose(h).translation);
    }
    Some(nav)
}

/// `task`'s solution from the end of `drive`: the drive's trajectory first, the base where it
/// ends.
fn after_drive(drive: &Solution, mut task: Solution) -> Solution {
    let mut trajectories = drive.summary.trajectories.clone();
    trajectories.append(&mut task.summary.trajectories);
    task.summary.trajectories = trajectories;
    task.summary.robot_base = drive.summary.robot_base;
    task
}
