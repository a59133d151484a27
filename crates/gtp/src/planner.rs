//! The planner's public face: run a task by name with string arguments on a [`World`], pull
//! its solutions lazily ([`SolutionStream`]), read each solution's resulting world and summary,
//! and the call's statistics.
//!
//! ```no_run
//! # use gtp::planner::{Planner, CallOptions};
//! # let world = geometry::world::World::load("domains/library/scene.toml").unwrap();
//! let planner = Planner::new();
//! let mut stream = planner
//!     .run(&world, "make-accessible", &["grey-book", "member"], &CallOptions::default())
//!     .unwrap();
//! if let Some(solution) = stream.next() {
//!     let after = solution.world; // the book moved, the robot back in its posture
//!     println!("{:?}", solution.summary.placement);
//! } else {
//!     println!("failed: {}", stream.failure().unwrap());
//! }
//! println!("{:?}", stream.stats());
//! ```

use std::sync::{Arc, Mutex, Weak};
use std::time::{Duration, Instant};

use geometry::agent::AgentModel;
use geometry::collision::{SelfCollisionModel, SelfCollisionOptions};
use geometry::scene::{AgentId, AgentKind, ObjectId};
use geometry::world::{World, WorldModel};
use parry3d::math::Vector;

use crate::grasp::{GraspCache, GraspParams};
use crate::placement::PlacementParams;
use crate::robot::RobotSetup;
use crate::rrt::RrtParams;
use crate::search::{BaseMoves, Search};
pub use crate::search::{Failure, Stage};
use crate::solution::SolutionSummary;
use crate::stats::Stats;
use crate::task::{Constraints, TaskKind};

/// Errors in a task call itself (before any search): unknown task, wrong arguments, a scene
/// without a robot. A task that has no solution is not an error: see [`Failure`].
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum GtpError {
    /// The task name is not one of the known tasks.
    #[error(
        "unknown task `{0}` (known: pick, place-on, show, give, take, make-accessible, put-away, navigate-to, pick-and-make-accessible, pick-and-show, pick-and-give, pick-and-put-away, pick-and-place-on)"
    )]
    UnknownTask(String),
    /// Wrong number of arguments.
    #[error("task `{task}` takes {} argument(s) ({}), got {got}", expected.len(), expected.join(", "))]
    Arity {
        task: TaskKind,
        expected: Vec<&'static str>,
        got: usize,
    },
    /// An argument names nothing suitable in the world.
    #[error("task `{task}`, argument {role} `{name}`: {reason}")]
    BadArgument {
        task: TaskKind,
        role: &'static str,
        name: String,
        reason: String,
    },
    /// A constraint override is malformed.
    #[error("constraint: {0}")]
    Constraint(String),
    /// The world cannot be planned in (no robot, no arm, an object that cannot be grasped).
    #[error("{0}")]
    Setup(String),
}

/// A task with its arguments resolved in a world.
#[derive(Clone, Debug, PartialEq)]
pub struct Task {
    /// Which task.
    pub kind: TaskKind,
    /// The arguments as given.
    pub args: Vec<String>,
    /// The object moved (all tasks but navigate-to).
    pub object: Option<ObjectId>,
    /// The support (place-on).
    pub support: Option<ObjectId>,
    /// The human concerned (show, give, make-accessible, put-away).
    pub human: Option<AgentId>,
    /// The point to reach (navigate-to: the target object's centre or agent's eyes).
    pub target_point: Option<Vector>,
    /// The object to reach (navigate-to an object): furniture counts as reached when a point of
    /// its support surface is (see [`crate::target::ReachTarget`]).
    pub target_object: Option<ObjectId>,
}

impl Task {
    /// Resolves `name(args...)` in `world`.
    pub fn resolve(world: &World, name: &str, args: &[&str]) -> Result<Task, GtpError> {
        let kind = TaskKind::from_name(name).ok_or_else(|| GtpError::UnknownTask(name.into()))?;
        let roles = kind.parameters();
        if args.len() != roles.len() {
            return Err(GtpError::Arity {
                task: kind,
                expected: roles.to_vec(),
                got: args.len(),
            });
        }
        let objects = || {
            world
                .object_ids()
                .map(|o| world.object(o).name.clone())
                .collect::<Vec<_>>()
                .join(", ")
        };
        let bad = |role: &'static str, name: &str, reason: String| GtpError::BadArgument {
            task: kind,
            role,
            name: name.to_string(),
            reason,
        };
        let mut task = Task {
            kind,
            args: args.iter().map(|s| s.to_string()).collect(),
            object: None,
            support: None,
            human: None,
            target_point: None,
            target_object: None,
        };
        for (role, name) in roles.iter().zip(args) {
            match *role {
                "object" => {
                    let id = world.object_id(name).ok_or_else(|| {
                        bad(
                            role,
                            name,
                            format!("no such object (objects: {})", objects()),
                        )
                    })?;
                    if !world.object(id).movable {
                        return Err(bad(role, name, "the object is not movable".into()));
                    }
                    task.object = Some(id);
                }
                "support" => {
                    let id = world.object_id(name).ok_or_else(|| {
                        bad(
                            role,
                            name,
                            format!("no such object (objects: {})", objects()),
                        )
                    })?;
                    if world.object(id).surfaces.is_empty() {
                        return Err(bad(role, name, "the object has no support surface".into()));
                    }
                    task.support = Some(id);
                }
                "human" => {
                    let id = world.agent_id(name).ok_or_else(|| {
                        let humans: Vec<String> = world
                            .agent_ids()
                            .filter(|&a| world.agent(a).kind() == AgentKind::Human)
                            .map(|a| world.agent(a).name().to_string())
                            .collect();
                        bad(
                            role,
                            name,
                            format!("no such agent (humans: {})", humans.join(", ")),
                        )
                    })?;
                    if world.agent(id).kind() != AgentKind::Human {
                        return Err(bad(role, name, "the agent is not a human".into()));
                    }
                    task.human = Some(id);
                }
                _ => {
                    // navigate-to: an object or an agent.
                    if let Some(id) = world.object_id(name) {
                        task.target_point = Some(world.object_aabb(id).center());
                        task.target_object = Some(id);
                    } else if let Some(a) = world.agent_id(name) {
                        task.target_point = Some(world.eye_pose(a).translation);
                    } else {
                        return Err(bad(
                            role,
                            name,
                            format!("no object or agent of that name (objects: {})", objects()),
                        ));
                    }
                }
            }
        }
        Ok(task)
    }
}

/// One solution: the world after it, and what it says.
#[derive(Clone, Debug)]
pub struct Solution {
    /// The world after the task: the object moved (and held, for pick, show and give), the
    /// robot's arm where the task left it.
    pub world: World,
    /// Grasp, placement, visibility, trajectories and statistics, serialisable.
    pub summary: SolutionSummary,
}

/// Options of one task call.
#[derive(Clone, Debug, PartialEq)]
pub struct CallOptions {
    /// Seed of every random choice (IK restarts, RRT samples).
    pub seed: u64,
    /// Threshold overrides, `(name, value)` as [`Constraints::set`] takes them.
    pub constraints: Vec<(String, String)>,
    /// The caller's deadline (an HTN search's time limit): the call's time limit and every
    /// motion-planning query end there at the latest. `None`: only the call's own limit.
    pub deadline: Option<Instant>,
}

impl Default for CallOptions {
    fn default() -> Self {
        CallOptions {
            seed: 1,
            constraints: Vec::new(),
            deadline: None,
        }
    }
}

impl CallOptions {
    /// Default options with this seed.
    pub fn seeded(seed: u64) -> CallOptions {
        CallOptions {
            seed,
            ..CallOptions::default()
        }
    }

    /// Adds a threshold override.
    pub fn with(mut self, key: &str, value: &str) -> CallOptions {
        self.constraints.push((key.into(), value.into()));
        self
    }
}

/// Settings shared by every call of a planner.
#[derive(Clone, Debug)]
pub struct PlannerConfig {
    /// Grasps per object shape (shared cache).
    pub grasps: GraspCache,
    /// Placement enumeration.
    pub placement: PlacementParams,
    /// RRT-Connect limits and resolution.
    pub rrt: RrtParams,
    /// Inverse-kinematics attempts (random restarts inside the solver) per call.
    pub ik_attempts: usize,
    /// Calls per target (from the current configuration, then from random ones) until one
    /// gives a collision-free solution.
    pub ik_tries: usize,
    /// Inverse kinematics at a placement or hand-over pose: calls and attempts per call. Fewer
    /// than for a grasp: there are many placements, and the search moves on to the next.
    pub ik_place_tries: usize,
    /// See `ik_place_tries`.
    pub ik_place_attempts: usize,
    /// Pixel-visibility grid (rays per side).
    pub visibility_resolution: usize,
    /// Filter candidate points with the world's mightability maps (`geometry::mightability`,
    /// computed once per world state and cached: about 0.6 s for the library scene) instead of
    /// testing each point directly with the same criteria (stance reach spheres, field of view
    /// and line of sight). Off by default: the direct tests cost microseconds per point, while
    /// a task call after every change of the world would recompute the maps.
    pub mightability: bool,
    /// Print every rejected candidate to stderr (for debugging a scene).
    pub trace: bool,
}

impl Default for PlannerConfig {
    fn default() -> Self {
        PlannerConfig {
            grasps: GraspCache::new(GraspParams::default()),
            placement: PlacementParams::default(),
            rrt: RrtParams::default(),
            ik_attempts: 2,
            ik_tries: 2,
            ik_place_tries: 1,
            ik_place_attempts: 2,
            visibility_resolution: 32,
            mightability: false,
            trace: std::env::var_os("GTP_TRACE").is_some(),
        }
    }
}

/// A cached agent setup: the scene it belongs to (while alive), the agent, the setup.
type SetupEntry = (Weak<WorldModel>, AgentId, Arc<RobotSetup>);

/// The geometric task planner. Keeps what depends only on the scene (grasp sets, the robot's
/// self-collision model) between calls; `Send + Sync`, cheap to share behind an `Arc`.
#[derive(Debug, Default)]
pub struct Planner {
    config: PlannerConfig,
    setups: Mutex<Vec<SetupEntry>>,
    /// Self-collision models per agent model (while alive): scenes that differ only in their
    /// objects (a randomized benchmark's) share their robot's, which is costly to make.
    self_models: Mutex<Vec<(Weak<AgentModel>, Arc<SelfCollisionModel>)>>,
}

impl Planner {
    /// A planner with the default settings.
    pub fn new() -> Planner {
        Planner::default()
    }

    /// A planner with these settings.
    pub fn with_config(config: PlannerConfig) -> Planner {
        Planner {
            config,
            setups: Mutex::default(),
            self_models: Mutex::default(),
        }
    }

    /// The settings.
    pub fn config(&self) -> &PlannerConfig {
        &self.config
    }

    /// The robot of the world's scene (built on first use per scene, then shared).
    pub fn robot(&self, world: &World) -> Result<Arc<RobotSetup>, GtpError> {
        let agent = world
            .agent_ids()
            .find(|&a| world.agent(a).kind() == AgentKind::Robot)
            .ok_or_else(|| GtpError::Setup("the scene has no robot agent".into()))?;
        self.agent_setup(world, agent)
    }

    /// The arms of any agent of the world's scene, for motion planning (a person's in a
    /// hand-over); built on first use per scene and agent, then shared.
    pub fn agent_setup(&self, world: &World, agent: AgentId) -> Result<Arc<RobotSetup>, GtpError> {
        let mut setups = self.setups.lock().unwrap_or_else(|e| e.into_inner());
        setups.retain(|(w, _, _)| w.strong_count() > 0);
        if let Some((_, _, s)) = setups
            .iter()
            .find(|(w, a, _)| *a == agent && std::ptr::eq(w.as_ptr(), Arc::as_ptr(world.model())))
        {
            return Ok(s.clone());
        }
        let self_model = self.self_model(&world.agent(agent).model);
        let setup = RobotSetup::with_self_model(world, agent, self_model);
        let setup = Arc::new(setup.map_err(GtpError::Setup)?);
        setups.push((Arc::downgrade(world.model()), agent, setup.clone()));
        Ok(setup)
    }

    /// The self-collision model of agent model `model`: made on first use, then shared.
    fn self_model(&self, model: &Arc<AgentModel>) -> Arc<SelfCollisionModel> {
        let mut models = self.self_models.lock().unwrap_or_else(|e| e.into_inner());
        models.retain(|(m, _)| m.strong_count() > 0);
        if let Some((_, s)) = models
            .iter()
            .find(|(m, _)| std::ptr::eq(m.as_ptr(), Arc::as_ptr(model)))
        {
            return s.clone();
        }
        let options = SelfCollisionOptions::default();
        let made = Arc::new(SelfCollisionModel::new(model.clone(), &options));
        models.push((Arc::downgrade(model), made.clone()));
        made
    }

    /// Runs task `name` with arguments `args` (object and agent names) on `world`. The search
    /// starts lazily: pull solutions from the stream.
    pub fn run(
        &self,
        world: &World,
        name: &str,
        args: &[&str],
        options: &CallOptions,
    ) -> Result<SolutionStream, GtpError> {
        let task = Task::resolve(world, name, args)?;
        self.solve(world, task, options)
    }

    /// Runs a resolved task.
    pub fn solve(
        &self,
        world: &World,
        task: Task,
        options: &CallOptions,
    ) -> Result<SolutionStream, GtpError> {
        let mut constraints = Constraints::defaults(task.kind);
        for (k, v) in &options.constraints {
            constraints.set(k, v).map_err(GtpError::Constraint)?;
        }
        let mut config = self.config.clone();
        if let Some(d) = options.deadline {
            let left = d.saturating_duration_since(Instant::now());
            constraints.time_limit = constraints.time_limit.min(left);
            config.rrt.deadline = Some(d);
        }
        let setup = self.robot(world)?;
        let person = match (task.kind, task.human) {
            (TaskKind::Take, Some(h)) => Some(self.agent_setup(world, h)?),
            _ => None,
        };
        let mut search = Search::new(
            config,
            setup,
            world.clone(),
            task.clone(),
            constraints.clone(),
            options.seed,
        )
        .map_err(GtpError::Setup)?;
        search.person = person;
        Ok(SolutionStream {
            task,
            constraints,
            search,
            base_moves: None,
            seed: options.seed,
        })
    }
}

/// The solutions of one task call, produced lazily: the first, then on request the next
/// different one (another point, grasp or orientation). When the task finds nothing from where
/// the robot stands, the stream goes on from base poses nearby (the robot turns or steps,
/// `crate::search::BaseMoves`); those solutions start with the drive.
pub struct SolutionStream {
    task: Task,
    constraints: Constraints,
    search: Search,
    base_moves: Option<BaseMoves>,
    seed: u64,
}

impl SolutionStream {
    /// The task being solved.
    pub fn task(&self) -> &Task {
        &self.task
    }

    /// The thresholds in force.
    pub fn constraints(&self) -> &Constraints {
        &self.constraints
    }

    /// The statistics so far (cumulative over every solution pulled, the base moves included).
    pub fn stats(&self) -> Stats {
        let mut s = self.search.stats;
        if let Some(m) = &self.base_moves {
            s.accumulate(&m.stats());
        }
        s
    }

    /// Why the stream ended, once it has.
    pub fn failure(&self) -> Option<&Failure> {
        match &self.base_moves {
            Some(m) => m.failure(),
            None => self.search.failure.as_ref(),
        }
    }
}

impl Iterator for SolutionStream {
    type Item = Solution;

    fn next(&mut self) -> Option<Solution> {
        if self.base_moves.is_none() {
            if let Some(s) = self.search.next_solution() {
                return Some(s);
            }
            self.base_moves = Some(BaseMoves::after(&mut self.search, self.seed)?);
        }
        let moves = self.base_moves.as_mut()?;
        let mut s = moves.next_solution(&self.search)?;
        let stats = self.stats();
        s.summary.stats = stats;
        s.summary.index = stats.solutions - 1;
        Some(s)
    }
}

/// How long the default call may run.
pub const DEFAULT_TIME_LIMIT: Duration = Duration::from_secs(60);
