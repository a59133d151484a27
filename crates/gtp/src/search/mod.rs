//! The task search, as in the paper: effort levels, then candidate points, then grasps, then
//! orientations; the cheap constraints first and pixel visibility last; failures remembered
//! across effort levels; the chosen tuple confirmed by collision-free trajectories.
//!
//! The search is a resumable cursor (`Cursor { level, point, grasp, orientation }`): each call
//! of `Search::next_solution` continues where the previous solution was found, so successive
//! solutions differ in at least one of point, grasp or orientation.
//!
//! One file per stage a candidate passes, in the order of the constraint hierarchy:
//!
//! | file | stage |
//! |---|---|
//! | `cursor.rs` | the cursor over (level, point, grasp, orientation) and the loop that moves it |
//! | `points.rs` | candidate points of an effort level: raw grid, reach and view filters, order |
//! | `perception.rs` | what the human reaches and may see at an effort level (the points' tests) |
//! | `grasps.rs` | the grasp choices (arm x grasp, or the grasp held) and their cheap tests |
//! | `pick.rs` | picking a grasp up: gripper boxes, inverse kinematics, approach, lift |
//! | `pull_out.rs` | the lift's way out from under a board: raise, slide back, lift (and reversed) |
//! | `placements.rs` | the object's orientations at a point and the world after a placement |
//! | `verdicts.rs` | the human-related constraints of a placement: reach, pixel visibility |
//! | `tuple.rs` | a whole tuple confirmed: placement IK, straight moves, planned motions |
//! | `motions.rs` | the arm motions of one grasp choice, built once; recorded trajectories |
//! | `take.rs` | `take(o, h)`: the robot lets go, the person takes the object |
//! | `navigate.rs` | `navigate-to`: base poses and the base's path |
//! | `base_moves.rs` | a task tried again from base poses nearby when it fails where the robot stands |
//! | `failure.rs` | typed stages, the typed [`Failure`], the rejections that explain it |

mod base_moves;
mod cursor;
mod failure;
mod grasps;
mod motions;
mod navigate;
mod perception;
mod pick;
mod placements;
mod points;
mod pull_out;
mod take;
mod tuple;
mod verdicts;

use std::collections::{HashMap, HashSet};
use std::sync::Arc;
use std::sync::atomic::{AtomicUsize, Ordering};
use std::time::{Duration, Instant};

use geometry::collision::StaticObstacles;
use geometry::scene::{AgentId, ObjectId};
use geometry::world::World;
use parry3d::math::Vector;

use crate::placement::{self, RestingFace};
use crate::planner::{PlannerConfig, Solution, Task};
use crate::robot::{self, ArmMotion, RobotSetup};
use crate::rrt::{JointPath, RrtError, RrtParams, RrtStats};
use crate::stats::Stats;
use crate::task::{Constraints, TaskKind};

pub(crate) use base_moves::BaseMoves;
use cursor::{Cursor, PlacementKey};
use failure::Rejections;
pub use failure::{Failure, Stage};
use grasps::Choice;
use motions::GraspMotions;
use pick::PickPlan;
use verdicts::Verdict;
pub use verdicts::measure_visibility;

/// Straight moves (approach, descent, retreat, lift) are checked in this many steps.
const STRAIGHT_STEPS: usize = 3;

/// After this many trajectory queries of one task call used up their budget without a path,
/// each later one gets half the budget of the one before, down to a [`LEAST_RRT_SHARE`]th: a
/// query that fails costs its whole budget, and in a cluttered room the same blocked motion
/// comes back at each candidate (the slowest call of 100 rooms spent 24 failed queries). Of
/// the queries that find a path there, 99.8 % need fewer than 1,000 nodes.
const FULL_RRT_FAILURES: usize = 2;
/// See [`FULL_RRT_FAILURES`]: the least share of the budget, 250 nodes and 5,000 checks.
const LEAST_RRT_SHARE: usize = 20;
/// After this many more failed queries (beyond [`FULL_RRT_FAILURES`]) the halving resumes
/// below [`LEAST_RRT_SHARE`], down to little more than the straight connection: a call
/// whose motions keep failing must not cost a query per candidate (a random room's
/// make-accessible made 138 queries, 2.8 s, and failed).
const LEAST_SHARE_FAILURES: usize = 16;

/// The share of the configured budget (its divisor) that a call's next trajectory query gets
/// after `failures` failed ones: whole for the first [`FULL_RRT_FAILURES`], then halved per
/// failure down to a [`LEAST_RRT_SHARE`]th, then, after [`LEAST_SHARE_FAILURES`] more, halved
/// again per failure.
fn rrt_share(failures: usize) -> usize {
    let halvings = (failures + 1).saturating_sub(FULL_RRT_FAILURES);
    let share = (1usize << halvings.min(8)).min(LEAST_RRT_SHARE);
    let beyond = (failures + 1).saturating_sub(FULL_RRT_FAILURES + LEAST_SHARE_FAILURES);
    share << beyond.min(16)
}

/// The obstacle sets of a search, built once from the world at the start.
///
/// The whole scene serves the base's motions and the lines of sight; the arms' workspace only
/// (a sphere around the robot) the arms' motions and the objects they move, since far
/// obstacles cost checks for nothing. Each comes with the task's object and without it (when
/// the gripper holds or straddles the object, the object is no obstacle).
struct Obstacles {
    /// Every obstacle of the scene, the task's object included.
    scene: Arc<StaticObstacles>,
    /// Every obstacle of the scene but the task's object.
    scene_but_object: Arc<StaticObstacles>,
    /// The obstacles within the arms' workspace, the task's object included.
    workspace: Arc<StaticObstacles>,
    /// The obstacles within the arms' workspace but the task's object.
    workspace_but_object: Arc<StaticObstacles>,
    /// The arms' workspace sphere `(centre, radius)`.
    sphere: (Vector, f32),
}

impl Obstacles {
    /// The obstacle sets of `world` for `setup`'s robot; `object`, the task's, is left out of
    /// the `_but_object` sets and sizes the workspace's margin.
    fn new(world: &World, setup: &RobotSetup, object: Option<ObjectId>) -> Obstacles {
        let robot = setup.agent;
        let skip: Vec<ObjectId> = object.into_iter().collect();
        let scene = robot::obstacles(world, robot, &[]);
        let scene_but_object = robot::obstacles(world, robot, &skip);
        let st = world.agent_state(robot);
        let margin = object
            .map(|o| world.object(o).local_aabb.half_extents().length() * 2.0)
            .unwrap_or(0.0);
        let (centre, radius) = setup.workspace(st.base, &st.q, margin);
        Obstacles {
            workspace: Arc::new(robot::near(&scene, centre, radius)),
            workspace_but_object: Arc::new(robot::near(&scene_but_object, centre, radius)),
            scene: Arc::new(scene),
            scene_but_object: Arc::new(scene_but_object),
            sphere: (centre, radius),
        }
    }

    /// The obstacles within the workspace sphere in `world` (where a placed object settled),
    /// with the placed object `released` also where the gripper let it go: the arm's way back
    /// must clear both, since the plan shows the object at its release pose until the step ends.
    fn workspace_after_release(
        &self,
        world: &World,
        robot: AgentId,
        released: (ObjectId, parry3d::math::Pose),
    ) -> Arc<StaticObstacles> {
        let (o, pose) = released;
        let mut list = robot::obstacles(world, robot, &[]).obstacles().to_vec();
        let model = world.object(o);
        list.push(geometry::collision::Obstacle {
            name: model.name.clone(),
            pose: pose * model.shape_offset,
            shape: model.shape.clone(),
        });
        let all = StaticObstacles::new(list);
        Arc::new(robot::near(&all, self.sphere.0, self.sphere.1))
    }

    /// The obstacles within the workspace sphere in `world` (the world after a task: a placed
    /// object is an obstacle where it is now).
    fn workspace_in(&self, world: &World, robot: AgentId) -> Arc<StaticObstacles> {
        Arc::new(robot::near(
            &robot::obstacles(world, robot, &[]),
            self.sphere.0,
            self.sphere.1,
        ))
    }
}

/// The search of one task call: what it was given, the cursor, what it remembers across
/// tuples (failed grasps, picks, placement verdicts) and its statistics.
pub(crate) struct Search {
    cfg: PlannerConfig,
    setup: Arc<RobotSetup>,
    world: World,
    task: Task,
    c: Constraints,
    rng: fastrand::Rng,
    pub(crate) stats: Stats,
    started: Option<Instant>,
    elapsed: Duration,
    object: Option<ObjectId>,
    /// The object's smallest half-extent (0 without one): the ball that fits in its bounding
    /// box, so that the human's level 0 is claimed only with a hand at the object itself, as
    /// the fact (`geometry::facts`, the distance to the object's surface) will measure it.
    object_inner_radius: f32,
    human: Option<AgentId>,
    /// Joint values of the robot at the start.
    q0_full: Vec<f32>,
    obstacles: Obstacles,
    /// World position of each arm's first movable joint.
    arm_shoulders: Vec<Vector>,
    /// Obstacles the object touches where it rests (left unchecked at the start of the lift).
    resting_on: Vec<String>,
    faces: Vec<RestingFace>,
    choices: Vec<Choice>,
    /// Whether the robot holds the object already (the only choice is its grasp).
    held: bool,
    /// The effort levels to search, in order.
    levels: Vec<u8>,
    cursor: Cursor,
    /// Candidate points tried at a lower level (by [`points::key`]).
    tried_points: HashSet<(i32, i32, i32)>,
    /// Grasp choices that failed for good (no pick, no approach, a carry that cannot start).
    failed_choices: HashSet<usize>,
    /// Per grasp choice: transfers planned in vain since its last success (see
    /// [`failure::MAX_FAILED_TRANSFERS`]).
    failed_transfers: HashMap<usize, usize>,
    /// Trajectory queries of this call that used up their budget without a path, counted
    /// with the searches of its base moves (see [`Search::into_base_move`]).
    rrt_failures: Arc<AtomicUsize>,
    /// Whether this search is a base move of a task call (a stance nearby, the drive there
    /// or back): its base paths share the call's trajectory budget.
    base_move: bool,
    /// Per grasp choice: its pick, `None` when it cannot be picked up.
    pick_cache: HashMap<usize, Option<PickPlan>>,
    /// Per grasp choice: its motions' shared parts (built on first use).
    motions: HashMap<usize, Arc<GraspMotions>>,
    /// Per placement of a placing task: its human-related verdict so far.
    verdicts: HashMap<PlacementKey, Verdict>,
    /// Per level: the points the human's arms reach from at that level, computed lazily.
    human_reach_origins: HashMap<u8, Vec<Vector>>,
    /// While a give's candidate points must be within reach of the human's free hands: per
    /// shoulder link, whether its hand is free (see `Search::candidate_points`).
    free_hands_only: Option<Vec<bool>>,
    /// The robot's arms left out of the choices because their grippers hold something else.
    busy_arms: Vec<String>,
    rejections: Rejections,
    pub(crate) failure: Option<Failure>,
    done: bool,
    /// The person's arms, for a take's reach and withdraw.
    pub(crate) person: Option<Arc<RobotSetup>>,
    /// A navigate-to that serves a base move inside another task: only the poses within this
    /// distance of the base (metres), turning in place first ([`base_moves`]).
    stance_radius: Option<f32>,
    /// For such a navigate-to, places of which its poses must reach one (a put-away's hiding
    /// places), in place of its target.
    stance_places: Option<Vec<Vector>>,
}

impl Search {
    pub(crate) fn new(
        cfg: PlannerConfig,
        setup: Arc<RobotSetup>,
        world: World,
        task: Task,
        c: Constraints,
        seed: u64,
    ) -> Result<Search, String> {
        let robot = setup.agent;
        let object = task.object;
        let obstacles = Obstacles::new(&world, &setup, object);
        let st = world.agent_state(robot);
        let arm_shoulders: Vec<Vector> = setup
            .arms
            .iter()
            .map(|a| robot::shoulder(&setup, a, st.base, &st.q))
            .collect();
        let q0_full = st.q.clone();
        let mut grasps = grasps::GraspChoices::default();
        let mut faces = Vec::new();
        if let Some(o) = object {
            grasps = grasps::GraspChoices::new(&cfg, &setup, &world, &task, o, &obstacles)?;
            if task.kind != TaskKind::NavigateTo {
                faces = placement::resting_faces(&*world.object(o).shape, &cfg.placement)
                    .map_err(|e| e.to_string())?;
            }
        }
        let object_inner_radius = object.map_or(0.0, |o| {
            let shape = &world.object(o).shape;
            shape.compute_local_aabb().half_extents().min_element()
        });
        let levels: Vec<u8> = match task.kind {
            TaskKind::Pick | TaskKind::PlaceOn | TaskKind::NavigateTo => vec![0],
            _ => (0..=c.max_effort).collect(),
        };
        Ok(Search {
            cfg,
            setup,
            human: task.human,
            world,
            task,
            c,
            rng: fastrand::Rng::with_seed(seed),
            stats: Stats::default(),
            started: None,
            elapsed: Duration::default(),
            object,
            object_inner_radius,
            q0_full,
            obstacles,
            arm_shoulders,
            resting_on: grasps.resting_on,
            faces,
            choices: grasps.choices,
            held: grasps.held,
            levels,
            cursor: Cursor::default(),
            tried_points: HashSet::new(),
            failed_choices: HashSet::new(),
            failed_transfers: HashMap::new(),
            rrt_failures: Arc::default(),
            pick_cache: HashMap::new(),
            motions: HashMap::new(),
            verdicts: HashMap::new(),
            human_reach_origins: HashMap::new(),
            free_hands_only: None,
            busy_arms: grasps.busy_arms,
            rejections: Rejections::default(),
            failure: None,
            done: false,
            person: None,
            stance_radius: None,
            stance_places: None,
            base_move: false,
        })
    }

    /// The trajectory planner's settings for the next query of this call: the configured
    /// ones, or a smaller budget once [`FULL_RRT_FAILURES`] queries have failed.
    fn rrt_params(&self) -> RrtParams {
        let mut p = self.cfg.rrt.clone();
        let share = rrt_share(self.rrt_failures.load(Ordering::Relaxed));
        p.max_nodes = (p.max_nodes / share).max(2);
        p.max_checks = (p.max_checks / share).max(2);
        p
    }

    /// This search as a base move of `call`: its failed trajectory queries count with the
    /// call's, since the searches from other base poses are part of the same task call and
    /// each would otherwise start again with the full budget; its base paths (drives of at
    /// most a metre) get the call's budget too.
    pub(crate) fn into_base_move(mut self, call: &Search) -> Search {
        self.rrt_failures = call.rrt_failures.clone();
        self.base_move = true;
        self
    }

    /// One trajectory query of this call for `motion` from `from` to `to`: counted, with the
    /// call's budget ([`Search::rrt_params`]), its failure noted ([`Search::note_rrt`]).
    fn plan_motion(
        &mut self,
        motion: &ArmMotion<'_>,
        from: &[f32],
        to: &[f32],
        rng: &mut fastrand::Rng,
    ) -> Result<(JointPath, RrtStats), MotionFailure> {
        self.stats.planner_calls += 1;
        let planned = motion.plan(from, to, &self.rrt_params(), rng);
        self.note_rrt(&planned);
        planned.map_err(|error| {
            let why = match error {
                RrtError::InvalidStart => motion.collision(from),
                RrtError::InvalidGoal => motion.collision(to),
                _ => None,
            };
            MotionFailure { error, why }
        })
    }

    /// Counts a trajectory query that used up its budget (node, check or time limit).
    fn note_rrt<T>(&mut self, r: &Result<T, RrtError>) {
        if r.as_ref().is_err_and(RrtError::is_budget) {
            self.rrt_failures.fetch_add(1, Ordering::Relaxed);
        }
    }

    /// The next solution, or `None` when the search is exhausted or hit its time limit
    /// ([`Search::failure`] then says why).
    pub(crate) fn next_solution(&mut self) -> Option<Solution> {
        if self.done {
            return None;
        }
        let began = Instant::now();
        self.started.get_or_insert(began);
        let out = match self.task.kind {
            TaskKind::NavigateTo => self.next_navigation(),
            TaskKind::Take => self.next_take(),
            _ => self.next_tuple(),
        };
        self.elapsed += began.elapsed();
        self.stats.time_s = self.elapsed.as_secs_f64();
        self.stats.success = out.is_some();
        if out.is_some() {
            self.stats.solutions += 1;
        }
        match out {
            Some(mut s) => {
                s.summary.stats = self.stats;
                s.summary.index = self.stats.solutions - 1;
                Some(s)
            }
            None => {
                self.done = true;
                if self.failure.is_none() {
                    self.failure = Some(self.explain());
                }
                None
            }
        }
    }

    fn out_of_time(&self, began: Instant) -> bool {
        self.elapsed + began.elapsed() > self.c.time_limit
    }

    /// Ends the search with `failure`: `None`, for `?` and `return`.
    fn fail<T>(&mut self, failure: Failure) -> Option<T> {
        self.failure = Some(failure);
        None
    }

    fn object_name(&self) -> String {
        self.object
            .map(|o| self.world.object(o).name.clone())
            .unwrap_or_default()
    }

    fn human_name(&self) -> String {
        self.human
            .map(|h| self.world.agent(h).name().to_string())
            .unwrap_or_default()
    }
}

/// Why a trajectory query of a search failed: the planner's error and, where an end is in
/// collision, what it collides with (a start posture inside the furniture says so).
#[derive(Debug)]
pub(crate) struct MotionFailure {
    pub(crate) error: RrtError,
    why: Option<String>,
}

impl std::fmt::Display for MotionFailure {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match &self.why {
            Some(why) => write!(f, "{}: {why}", self.error),
            None => write!(f, "{}", self.error),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_calls_trajectory_budget_shrinks_with_its_failures() {
        let shares: Vec<usize> = (0..8).map(rrt_share).collect();
        assert_eq!(shares, [1, 1, 2, 4, 8, 16, 20, 20]);
        let floor = FULL_RRT_FAILURES + LEAST_SHARE_FAILURES;
        assert_eq!(rrt_share(floor - 1), LEAST_RRT_SHARE);
        assert_eq!(rrt_share(floor), 2 * LEAST_RRT_SHARE);
        // Long after: the straight connection and little more (2 nodes, the least).
        assert!(RrtParams::default().max_nodes / rrt_share(floor + 10) < 2);
    }
}
