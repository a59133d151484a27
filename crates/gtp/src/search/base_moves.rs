//! The base moves when the arm cannot reach. A pick, place or hand-over that finds nothing from
//! where the robot stands (out of reach, or blocked from there) is tried again, inside the same
//! task call, from base poses nearby: turning in place to face the target first, then stepping
//! to poses within [`STEP_RADIUS`] (as a person turns, then steps: the effort levels 2 and 4 of
//! `geometry::effort`, allowed by the task's `robot_effort`, 4 by default). Each pose is reached
//! by a collision-free drive (a `navigate-to` search restricted to those poses); a solution from
//! there is that drive, the task, and, when the task put the object down (the hand empty), the
//! drive back to where the robot stood if there is one (the task then leaves the robot where the
//! domain put it: moving it for good is `navigate-to`'s job); else the robot stays where it
//! worked (after a pick or a hand-over, with the object held out). When no pose within
//! [`STEP_RADIUS`] is reached (the target too far for the arm from every one, or none free), the
//! poses within the agent's `move_radius` are tried the same way: level 4 is a drive (a member
//! at the far end of a long counter is handed a book after the robot drives round to them).
//! The target is the object (a pick), the support (a place-on) or the person (a hand-over); a
//! put-away's is the places that would hide the object from the person, the nearest of each
//! surface, whether the arm reaches them from here or not.

use parry3d::math::Vector;
use std::time::Duration;

use crate::planner::{Solution, Task};
use crate::stats::Stats;
use crate::task::TaskKind;

use super::{Failure, Search, Stage};

/// How far (metres) a base move inside a task may step from where the robot stands.
pub(crate) const STEP_RADIUS: f32 = 1.0;

/// At most this many poses nearby are driven to and searched from (the turn, then the nearest
/// steps): a failing task must not cost many full searches.
const MAX_POSES_SEARCHED: usize = 4;

/// Each search from a pose nearby may take at most this share of the task's time limit.
const POSE_TIME_SHARE: u32 = 16;

/// The search of a task from base poses nearby, after it failed where the robot stood.
pub(crate) struct BaseMoves {
    /// `navigate-to` over the poses nearby: each solution is a drive to one.
    stances: Search,
    /// How far from where the robot stands [`BaseMoves::stances`] looks (metres).
    radius: f32,
    /// The agent's move radius, searched once no pose within [`STEP_RADIUS`] was reached.
    drive_radius: Option<f32>,
    /// Places the poses must reach one of, in place of what the task's `navigate-to` would
    /// (see [`stances`]).
    toward: Option<Vec<Vector>>,
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
    /// Why the task failed from the last pose searched.
    last_failure: Option<Failure>,
    failure: Option<Failure>,
}

impl BaseMoves {
    /// The base moves after `search` failed from where the robot stands, or `None` when moving
    /// the base cannot help (a limit stopped it, the object has no grasp, the grippers are
    /// busy), the robot effort allowed is below 2, or the task is a take or a navigate-to.
    pub(crate) fn after(search: &mut Search, seed: u64) -> Option<BaseMoves> {
        let failure = search.failure.clone()?;
        let effort = search.c.robot_effort;
        if effort < 2
            || failure.limit
            || !base_move_may_help(failure.stage)
            || search.stats.solutions > 0
        {
            return None;
        }
        // The agent's own limits (a robot fixed to a table neither turns nor steps).
        let limits = search.world.agent(search.setup.agent).effort.clone();
        let radius = if effort >= 4 {
            STEP_RADIUS.min(limits.move_radius)
        } else {
            0.0
        };
        if radius == 0.0 && limits.base_turn == 0.0 {
            return None;
        }
        let left = search.c.time_limit.checked_sub(search.elapsed)?;
        // A put-away heads for the places that hide the object from the person (the nearest
        // of each surface): around the object held, the robot would stay where it found none.
        let toward = (search.task.kind == TaskKind::PutAway && search.held)
            .then(|| {
                let base = search.world.agent_state(search.setup.agent).base;
                search.places_for_human(base.translation)
            })
            .filter(|places| !places.is_empty());
        let stances = stances(search, (radius, toward.clone()), left, seed)?;
        // Level 4 drives within the agent's move radius when no step reaches.
        let drive_radius =
            (radius > 0.0 && limits.move_radius > radius).then_some(limits.move_radius);
        Some(BaseMoves {
            stances,
            radius,
            drive_radius,
            toward,
            here: None,
            at_start: failure,
            finished: Stats::default(),
            time_limit: search.c.time_limit,
            spent_before: search.elapsed.as_secs_f64(),
            seed,
            last_failure: None,
            failure: None,
        })
    }

    /// The next solution from a pose nearby (the drive there, the task, the drive back), or
    /// `None` when every pose is tried or the time is up ([`BaseMoves::failure`] then says why).
    pub(crate) fn next_solution(&mut self, template: &Search) -> Option<Solution> {
        loop {
            let next = self.here.as_mut().map(|(_, search)| search.next_solution());
            match next {
                Some(Some(s)) => {
                    // Back only with the hand empty: an object held out swings wide on the
                    // way back, and where the robot stood its arm often has no room.
                    let back = if template.task.kind.places() {
                        self.drive_back(template, &s)
                    } else {
                        Err(Failure::at(Stage::Search, "it holds the object".into()))
                    };
                    if let (Err(f), true) = (&back, template.cfg.trace) {
                        eprintln!("[base move] the robot stays: {f}");
                    }
                    let (drive, _) = self.here.as_ref()?;
                    return Some(around(drive, s, back.ok()));
                }
                Some(None) => {
                    if let Some((_, search)) = self.here.take() {
                        self.finished.accumulate(&search.stats);
                        self.last_failure = search.failure;
                    }
                }
                None => {}
            }
            let drive = match self.stances.stats.solutions {
                n if n >= MAX_POSES_SEARCHED => None,
                _ => self.stances.next_solution(),
            };
            if drive.is_none() && self.widen(template) {
                continue;
            }
            let (Some(drive), Some(left)) = (drive, self.time_left()) else {
                self.failure = Some(self.explain());
                return None;
            };
            let mut c = template.c.clone();
            c.time_limit = left.min(self.time_limit / POSE_TIME_SHARE);
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
            self.here = Some((drive, search.into_base_move(template)));
        }
    }

    /// Looks farther, within the agent's move radius, when no pose within [`STEP_RADIUS`] was
    /// reached (none searched, so no time went to the task from one) and time is left.
    fn widen(&mut self, template: &Search) -> bool {
        if self.stances.stats.solutions > 0
            || self.stances.failure.as_ref().is_some_and(|f| f.limit)
        {
            return false;
        }
        let Some(radius) = self.drive_radius.take() else {
            return false;
        };
        let Some(wider) = self
            .time_left()
            .and_then(|left| stances(template, (radius, self.toward.clone()), left, self.seed))
        else {
            return false;
        };
        add_stances(&mut self.finished, &self.stances.stats);
        self.stances = wider;
        self.radius = radius;
        true
    }

    /// The drive from where `task` leaves the robot back to where `template`'s search started
    /// (its statistics counted with the base moves').
    fn drive_back(&mut self, template: &Search, task: &Solution) -> Result<Solution, Failure> {
        let robot = template.setup.agent;
        let pose = template.world.agent_state(robot).base;
        let yaw = pose.rotation.to_euler(parry3d::glamx::EulerRot::ZYX).0;
        let goal = [pose.translation.x, pose.translation.y, yaw];
        let left = self.time_left().ok_or_else(|| {
            Failure::at(Stage::TimeLimit, "no time left for the drive back".into())
        })?;
        let mut nav = stance_task(template).ok_or_else(|| {
            Failure::at(Stage::Search, "no navigate-to for the drive back".into())
        })?;
        nav.target_point = Some(pose.translation);
        nav.target_object = None;
        let mut c = template.c.clone();
        c.time_limit = left;
        let mut back = Search::new(
            template.cfg.clone(),
            template.setup.clone(),
            task.world.clone(),
            nav,
            c,
            self.seed,
        )
        .map_err(|e| Failure::at(Stage::Search, e))?
        .into_base_move(template);
        let out = back.drive_to(goal);
        self.finished.planner_calls += back.stats.planner_calls;
        out
    }

    /// The statistics of every search of the base moves (the poses tried as `base_poses`).
    pub(crate) fn stats(&self) -> Stats {
        let mut s = self.finished;
        if let Some((_, search)) = &self.here {
            s.accumulate(&search.stats);
        }
        add_stances(&mut s, &self.stances.stats);
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
        let reached = self.stances.stats.solutions;
        let nearby = match (&self.stances.failure, &self.last_failure) {
            _ if out_of_time => "the time limit was reached".to_string(),
            (Some(f), _) if reached == 0 => format!("none reached: {}", f.message),
            (_, Some(last)) => format!(
                "the task failed from each of the {reached} searched (the last: {})",
                last.message
            ),
            _ => format!("the task failed from each of the {reached} searched"),
        };
        Failure {
            stage: if out_of_time {
                Stage::TimeLimit
            } else {
                self.at_start.stage
            },
            message: format!(
                "{}; then {tried} base pose(s) within {} m ({}): {nearby}",
                self.at_start.message,
                self.radius,
                if self.radius > STEP_RADIUS {
                    "turning, stepping, driving"
                } else {
                    "turning, stepping"
                }
            ),
            limit: out_of_time,
        }
    }
}

/// The `navigate-to` search over the poses within `radius` of where the robot stands in
/// `search` (0: turning in place), within `time_left` (what the call has left): poses that
/// reach one of the places `toward` where given, else what [`stance_task`] targets.
fn stances(
    search: &Search,
    (radius, toward): (f32, Option<Vec<Vector>>),
    time_left: Duration,
    seed: u64,
) -> Option<Search> {
    let nav = stance_task(search)?;
    let mut c = search.c.clone();
    c.time_limit = time_left;
    let mut stances = Search::new(
        search.cfg.clone(),
        search.setup.clone(),
        search.world.clone(),
        nav,
        c,
        seed,
    )
    .ok()?
    .into_base_move(search);
    stances.stance_radius = Some(radius);
    stances.stance_places = toward;
    Some(stances)
}

/// Adds a stance search's statistics to `into`: its poses as `base_poses`, its path searches
/// and its time.
fn add_stances(into: &mut Stats, stances: &Stats) {
    into.base_poses += stances.points;
    into.planner_calls += stances.planner_calls;
    into.time_s += stances.time_s;
}

/// Whether a base move may help after a failure at `stage`: from elsewhere the robot reaches
/// other grasps and other placements (and so other views and reaches of the human), but not a
/// grasp the object lacks, a gripper that is busy, or more time.
fn base_move_may_help(stage: Stage) -> bool {
    !matches!(
        stage,
        Stage::Grasp | Stage::FreeGripper | Stage::Held | Stage::TimeLimit
    )
}

/// The `navigate-to` whose poses serve `search`'s task: to the object while the robot does not
/// hold it; once held, to the support (place-on), the human (show, give, make-accessible) or
/// around the object itself (put-away).
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
        // Anywhere away from the human: the poses around the object held.
        (TaskKind::PutAway, true) => search.object,
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
        // What the person must take or reach is within their reach: poses from which the arm
        // reaches into it (see `ReachTarget::Person`); a show is for their eyes.
        if matches!(kind, TaskKind::Give | TaskKind::MakeAccessible) {
            nav.human = Some(h);
        }
    }
    Some(nav)
}

/// `task`'s solution from the end of `drive`, then `back` when there is one: the drives first
/// and last, the world after the drive back, the pose worked from in `base_move`. Without a
/// way back (the arm holds the object out where the robot stood), the robot stays.
fn around(drive: &Solution, mut task: Solution, back: Option<Solution>) -> Solution {
    let mut trajectories = drive.summary.trajectories.clone();
    trajectories.append(&mut task.summary.trajectories);
    task.summary.base_move = drive.summary.robot_base;
    match back {
        Some(back) => {
            trajectories.extend(back.summary.trajectories);
            task.world = back.world;
        }
        None => task.summary.robot_base = drive.summary.robot_base,
    }
    task.summary.trajectories = trajectories;
    task
}
