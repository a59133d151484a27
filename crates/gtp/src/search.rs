//! The task search, as in the paper: effort levels, then candidate points, then grasps, then
//! orientations; the cheap constraints first and pixel visibility last; failures remembered
//! across effort levels; the chosen tuple confirmed by collision-free trajectories.
//!
//! The search is a resumable cursor over (level, point, grasp, orientation): each call of
//! `Search::next_solution` continues where the previous solution was found, so successive
//! solutions differ in at least one of point, grasp or orientation.

use std::collections::{HashMap, HashSet};
use std::sync::Arc;
use std::time::Instant;

use geometry::collision::StaticObstacles;
use geometry::effort;
use geometry::scene::{AgentId, ObjectId};
use geometry::visibility::{self, Aim};
use geometry::world::World;
use parry3d::bounding_volume::BoundingVolume;
use parry3d::math::{Pose, Rotation, Vector};
use parry3d::query::{Ray, RayCast};
use parry3d::shape::{Cuboid, Shape};

use crate::grasp::Grasp;
use crate::gripper::Gripper;
use crate::placement::{self, RestingFace};
use crate::planner::{Failure, PlannerConfig, Solution, Task};
use crate::robot::{self, ArmMotion, RobotSetup, set_opening};
use crate::rrt::JointPath;
use crate::solution::{
    GraspRecord, HeldRecord, Phase, PlacementRecord, SolutionSummary, Trajectory,
};
use crate::stats::Stats;
use crate::target::ReachTarget;
use crate::task::{Constraints, TaskKind};

/// How far a stage of the funnel got, for the failure report (later stages are deeper).
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Hash)]
enum Stage {
    Points,
    Pick,
    ObjectCollision,
    Gripper,
    Ik,
    Reach,
    Visibility,
    Trajectory,
}

/// A grasp choice: an arm and a grasp (object frame), or the grasp the robot already holds.
#[derive(Clone, Copy, Debug)]
struct Choice {
    arm: usize,
    grasp: Grasp,
    /// Tool frame in the object's frame.
    tool_in_object: Pose,
}

/// The pick part of a plan, computed once per choice and reused across points.
#[derive(Clone, Debug)]
struct PickPlan {
    /// Planned only once a whole tuple needs it (the RRT is the costly part of a pick).
    approach: Option<JointPath>,
    /// Arm values at the pre-grasp.
    q_pre: Vec<f32>,
    grasp: JointPath,
    lift: Vec<(JointPath, Vec<String>)>,
    /// Arm values after the lift.
    q_lift: Vec<f32>,
}

/// A candidate orientation at a point: the object's pose there.
#[derive(Clone, Copy, Debug)]
struct Orientation {
    pose: Pose,
    face: usize,
    yaw_index: usize,
}

pub(crate) struct Search {
    cfg: PlannerConfig,
    setup: Arc<RobotSetup>,
    world: World,
    task: Task,
    c: Constraints,
    rng: fastrand::Rng,
    pub(crate) stats: Stats,
    started: Option<Instant>,
    elapsed: std::time::Duration,
    object: Option<ObjectId>,
    human: Option<AgentId>,
    /// Arm values of the robot at the start.
    q0_full: Vec<f32>,
    obstacles_all: Arc<StaticObstacles>,
    obstacles_wo: Arc<StaticObstacles>,
    /// Every obstacle (the two above keep only the arms' workspace).
    full_all: Arc<StaticObstacles>,
    full_wo: Arc<StaticObstacles>,
    /// World position of each arm's first movable joint.
    arm_shoulders: Vec<Vector>,
    /// The arms' workspace sphere `(centre, radius)`.
    workspace: (Vector, f32),
    /// Obstacles the object touches where it rests (left unchecked at the start of the lift).
    resting_on: Vec<String>,
    faces: Vec<RestingFace>,
    choices: Vec<Choice>,
    held: bool,
    levels: Vec<u8>,
    li: usize,
    points: Option<Vec<Vector>>,
    pi: usize,
    tried_points: HashSet<(i32, i32, i32)>,
    orientations: Option<Vec<Orientation>>,
    ci: usize,
    choice_ready: bool,
    oi: usize,
    failed_choices: HashSet<usize>,
    pick_cache: HashMap<usize, Option<PickPlan>>,
    /// Per (level, point, orientation) of a placing task: the visibility reached when the
    /// human-related constraints hold, `None` when they fail.
    verdicts: HashMap<(usize, usize, usize), Option<Option<f32>>>,
    /// Placements whose cheap human-related checks passed, the full verdict not yet measured.
    prechecked: HashSet<(usize, usize, usize)>,
    /// Per level: human shoulder positions allowed by that level (reach), computed lazily.
    human_shoulders: HashMap<u8, Vec<Vector>>,
    /// The robot's arms left out of the choices because their grippers hold something else.
    busy_arms: Vec<String>,
    deepest: Option<Stage>,
    rejections: HashMap<Stage, usize>,
    best_visibility: Option<f32>,
    last_reason: String,
    /// The last reason a grasp could not be picked up.
    pick_reason: String,
    pub(crate) failure: Option<Failure>,
    done: bool,
    /// The person's arms, for a take's reach and withdraw.
    pub(crate) person: Option<Arc<RobotSetup>>,
}

const STRAIGHT_STEPS: usize = 3;
/// Candidate points of a hiding task: distance bins (metres) within which the best hidden
/// come first.
const BIN: f32 = 0.5;
/// Gap left under a placed object once it has settled on its surface (metres): contact, with
/// a margin for rounding.
const SETTLED_GAP: f32 = 0.0002;
/// Lift height during which the object may still touch what it rested on.
const UNSTICK: f32 = 0.02;

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
        let skip: Vec<ObjectId> = object.into_iter().collect();
        // Everything, for the base's motions and lines of sight; the arms' workspace only for
        // the arms' motions and the objects they move (far obstacles cost checks for nothing).
        let full_all = robot::obstacles(&world, robot, &[]);
        let full_wo = Arc::new(robot::obstacles(&world, robot, &skip));
        let st = world.agent_state(robot);
        let margin = object
            .map(|o| world.object(o).local_aabb.half_extents().length() * 2.0)
            .unwrap_or(0.0);
        let (centre, radius) = setup.workspace(st.base, &st.q, margin);
        let obstacles_all = Arc::new(robot::near(&full_all, centre, radius));
        let arm_shoulders: Vec<Vector> = setup
            .arms
            .iter()
            .map(|a| robot::shoulder(&setup, a, st.base, &st.q))
            .collect();
        let obstacles_wo = Arc::new(robot::near(&full_wo, centre, radius));
        let full_all = Arc::new(full_all);
        let q0_full = world.agent_state(robot).q.clone();
        let mut faces = Vec::new();
        let mut choices = Vec::new();
        let mut held = false;
        let mut busy_arms = Vec::new();
        let mut resting_on = Vec::new();
        if let Some(o) = object {
            let model = world.object(o);
            if !model.movable && task.kind != TaskKind::NavigateTo {
                return Err(format!("object `{}` is not movable", model.name));
            }
            if let Some(att) = world.attachment(o) {
                if att.agent != robot {
                    return Err(format!(
                        "object `{}` is held by {}",
                        model.name,
                        world.agent(att.agent).name()
                    ));
                }
                let arm = setup
                    .arms
                    .iter()
                    .position(|a| a.tool_link == att.link)
                    .ok_or_else(|| {
                        format!(
                            "object `{}` is held by a link that is no arm's tool",
                            model.name
                        )
                    })?;
                held = true;
                let tool_in_object = att.grasp.inverse();
                // The jaws close along the tool's y axis: the object's extent along it (its
                // box's, exact for the boxes' axis-aligned grasps) is the grasp's width.
                let close = (tool_in_object.rotation * Vector::Y).abs();
                let h = model.local_aabb.half_extents();
                let width = (2.0 * close.dot(h)).min(crate::gripper::MAX_OPENING);
                choices.push(Choice {
                    arm,
                    grasp: Grasp {
                        id: usize::MAX,
                        tool_in_object,
                        width,
                        opening: (width + 0.02).min(crate::gripper::MAX_OPENING),
                        score: 0.0,
                    },
                    tool_in_object,
                });
            } else if task.kind != TaskKind::NavigateTo && task.kind != TaskKind::Take {
                let set = cfg
                    .grasps
                    .grasps(&*model.shape)
                    .map_err(|e| e.to_string())?;
                for (ai, a) in setup.arms.iter().enumerate() {
                    // A gripper already holding something cannot grasp the object.
                    if let Some((other, ..)) = robot::in_grippers(&world, &setup)
                        .find(|(_, by, _)| by.tool_link == a.tool_link)
                    {
                        busy_arms.push(format!("{} holds `{}`", a.name, world.object(other).name));
                        continue;
                    }
                    for g in &set.grasps {
                        choices.push(Choice {
                            arm: ai,
                            grasp: *g,
                            tool_in_object: model.shape_offset * g.tool_in_object,
                        });
                    }
                }
                let pose = world.object_shape_pose(o);
                let aabb = model.shape.compute_aabb(&pose).loosened(0.002);
                for ob in obstacles_wo.obstacles() {
                    let hit = parry3d::query::intersection_test(
                        &pose,
                        &*model.shape,
                        &ob.pose,
                        &*ob.shape,
                    )
                    .map(|h| h.intersecting)
                    .unwrap_or(true);
                    let near = ob.shape.compute_aabb(&ob.pose).intersects(&aabb);
                    if hit || (near && touching(&*model.shape, &pose, &*ob.shape, &ob.pose)) {
                        resting_on.push(ob.name.clone());
                    }
                }
            }
            if task.kind != TaskKind::NavigateTo {
                faces = placement::resting_faces(&*model.shape, &cfg.placement)
                    .map_err(|e| e.to_string())?;
            }
        }
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
            elapsed: Default::default(),
            object,
            q0_full,
            obstacles_all,
            obstacles_wo,
            full_all,
            full_wo,
            workspace: (centre, radius),
            arm_shoulders,
            resting_on,
            faces,
            choices,
            held,
            levels,
            li: 0,
            points: None,
            pi: 0,
            tried_points: HashSet::new(),
            orientations: None,
            ci: 0,
            choice_ready: false,
            oi: 0,
            failed_choices: HashSet::new(),
            pick_cache: HashMap::new(),
            verdicts: HashMap::new(),
            prechecked: HashSet::new(),
            human_shoulders: HashMap::new(),
            busy_arms,
            deepest: None,
            rejections: HashMap::new(),
            best_visibility: None,
            last_reason: String::new(),
            pick_reason: String::new(),
            failure: None,
            done: false,
            person: None,
        })
    }

    fn reject(&mut self, stage: Stage, reason: impl FnOnce() -> String) {
        *self.rejections.entry(stage).or_default() += 1;
        let deepest = self.deepest.is_none_or(|d| stage >= d);
        // The reason is worded only when it may be reported: the deepest stage's, a pick's
        // (given when no grasp can be picked up at all), or every one when tracing.
        if !(deepest || stage == Stage::Pick || self.cfg.trace) {
            return;
        }
        let r = reason();
        if self.cfg.trace {
            eprintln!("reject {stage:?}: {r}");
        }
        if stage == Stage::Pick {
            self.pick_reason.clone_from(&r);
        }
        if deepest {
            self.deepest = Some(stage);
            self.last_reason = r;
        }
    }

    /// `r`'s value; or, rejecting at `stage` with `what` and the error, `None`.
    fn or_reject<T, E: std::fmt::Display>(
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
    /// start in collision also drops choice `ci` (its start is the same whatever the tuple).
    fn transfer_or_reject(
        &mut self,
        r: Result<(JointPath, crate::rrt::RrtStats), crate::rrt::RrtError>,
        ci: usize,
        what: impl FnOnce() -> String,
    ) -> Option<JointPath> {
        if matches!(r, Err(crate::rrt::RrtError::InvalidStart)) {
            self.failed_choices.insert(ci);
        }
        self.or_reject(r.map(|(p, _)| p), Stage::Trajectory, what)
    }

    /// The next solution, or `None` when the search is exhausted or hit its time limit
    /// ([`Search::failure`] then says why).
    pub(crate) fn next_solution(&mut self) -> Option<Solution> {
        if self.done {
            return None;
        }
        let began = Instant::now();
        self.started.get_or_insert(began);
        let out = if self.task.kind == TaskKind::NavigateTo {
            self.next_navigation()
        } else if self.task.kind == TaskKind::Take {
            self.next_take()
        } else {
            self.next_tuple()
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

    fn next_tuple(&mut self) -> Option<Solution> {
        let began = Instant::now();
        loop {
            if self.out_of_time(began) {
                self.failure = Some(Failure {
                    constraint: "time-limit".into(),
                    message: format!(
                        "time limit of {:?} reached ({})",
                        self.c.time_limit,
                        self.explain().message
                    ),
                    limit: true,
                });
                return None;
            }
            if self.choices.is_empty() && !self.busy_arms.is_empty() {
                self.failure = Some(Failure {
                    constraint: "gripper".into(),
                    message: format!(
                        "no free gripper to grasp `{}`: {}",
                        self.object_name(),
                        self.busy_arms.join(", ")
                    ),
                    limit: false,
                });
                return None;
            }
            if !self.choices.is_empty() && self.failed_choices.len() == self.choices.len() {
                // Every grasp failed for good (no pick, no approach, a carry that cannot
                // start): no point, orientation or level can change that.
                self.failure = Some(Failure {
                    constraint: "pick".into(),
                    message: if self.held {
                        format!(
                            "the held `{}` cannot be carried ({})",
                            self.object_name(),
                            self.last_reason
                        )
                    } else {
                        format!(
                            "no grasp of `{}` can be picked up ({} tried; the last: {})",
                            self.object_name(),
                            self.choices.len(),
                            self.pick_reason
                        )
                    },
                    limit: false,
                });
                return None;
            }
            if self.choices.is_empty() {
                let name = self.object_name();
                self.failure = Some(Failure {
                    constraint: "grasp".into(),
                    message: format!(
                        "`{name}` has no grasp for the gripper (too wide for a {:.0} mm jaw opening, \
                         or every grasp collides with the object)",
                        crate::gripper::MAX_OPENING * 1000.0
                    ),
                    limit: false,
                });
                return None;
            }
            if self.points.is_none() {
                if self.li >= self.levels.len() {
                    return None;
                }
                let level = self.levels[self.li];
                self.stats.effort_level = self.stats.effort_level.max(level);
                let pts = self.candidate_points(level);
                self.points = Some(pts);
                self.pi = 0;
                self.orientations = None;
            }
            let npoints = self.points.as_ref().map_or(0, Vec::len);
            if self.pi >= npoints {
                self.li += 1;
                self.points = None;
                continue;
            }
            if self.orientations.is_none() {
                let p = self.points.as_ref().unwrap()[self.pi];
                self.tried_points.insert(key(p));
                self.stats.points += 1;
                let o = self.orientations_at(p);
                self.orientations = Some(o);
                self.ci = 0;
                self.oi = 0;
                self.choice_ready = false;
                if !self.point_has_placement() {
                    self.pi += 1;
                    self.orientations = None;
                    continue;
                }
            }
            if self.ci >= self.choices.len() {
                self.pi += 1;
                self.orientations = None;
                continue;
            }
            if !self.choice_ready {
                let p = self.points.as_ref().unwrap()[self.pi];
                if self.failed_choices.contains(&self.ci) || !self.pick_feasible(self.ci) {
                    self.ci += 1;
                    continue;
                }
                if !self.arm_may_reach_point(self.choices[self.ci].arm, p)
                    || !self.choice_fits_point(self.ci)
                {
                    let what = if self.held {
                        "the held grasp"
                    } else {
                        "a grasp"
                    };
                    self.reject(Stage::Gripper, || {
                        format!(
                            "no placement leaves {what} within the arm's reach with the gripper \
                             free"
                        )
                    });
                    self.ci += 1;
                    continue;
                }
                self.choice_ready = true;
                self.oi = 0;
            }
            let norient = self.orientations.as_ref().map_or(0, Vec::len);
            if self.oi >= norient || self.failed_choices.contains(&self.ci) {
                self.ci += 1;
                self.choice_ready = false;
                continue;
            }
            let orient = self.orientations.as_ref().unwrap()[self.oi];
            let oidx = self.oi;
            self.oi += 1;
            self.stats.orientations += 1;
            let point = self.points.as_ref().unwrap()[self.pi];
            if let Some(sol) = self.try_tuple(self.ci, point, orient, oidx) {
                // The next solution at another point: another grasp or turn of the object at
                // the same spot would mostly repeat this one's effect on the world (what it
                // hides, what it blocks), which is what a request for another solution wants
                // to change.
                if self.task.kind != TaskKind::Pick {
                    self.pi += 1;
                    self.orientations = None;
                }
                return Some(sol);
            }
        }
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

    // ---- candidate points ------------------------------------------------------------------

    /// Shoulder positions of the human's stances at effort levels up to `level`.
    fn shoulders_upto(&mut self, level: u8) -> Vec<Vector> {
        let Some(h) = self.human else {
            return Vec::new();
        };
        let mut out = Vec::new();
        for l in 1..=level {
            if !self.human_shoulders.contains_key(&l) {
                let mut s = Vec::new();
                for st in effort::stances(&self.world, h, l, None) {
                    s.extend(effort::shoulders(&self.world, h, st.base, &st.q));
                }
                self.human_shoulders.insert(l, s);
            }
            out.extend(self.human_shoulders[&l].iter().copied());
        }
        out
    }

    /// Whether the human reaches `p` at effort `level` or lower (level 0: at the hand; 1 and
    /// more: within arm's reach of a shoulder of a stance the level allows).
    fn human_reaches(&mut self, p: Vector, level: u8) -> bool {
        let Some(h) = self.human else { return false };
        let info = self.world.agent(h);
        let reach = info.reach;
        let st = self.world.agent_state(h);
        if info
            .hand_links
            .iter()
            .any(|&l| (st.link_poses()[l].translation - p).length() <= 0.1)
        {
            return true;
        }
        if level == 0 {
            return false;
        }
        self.shoulders_upto(level)
            .iter()
            .any(|s| (*s - p).length() <= reach)
    }

    /// Whether the eye may see `p` at effort `level`: inside the field of view (level 0) or the
    /// head's reach (level 1 and more), with a clear line of sight through the obstacles.
    fn may_see(&self, p: Vector, level: u8) -> bool {
        let Some(h) = self.human else { return true };
        let eye = self.world.eye_pose(h);
        let info = self.world.agent(h);
        let d = eye.rotation.inverse() * (p - eye.translation);
        if d.x <= 0.0 {
            // Behind the eye: only a turn of the torso or more helps.
            if level < 2 {
                return false;
            }
        } else {
            let (mut ha, mut va) = (info.fov[0] / 2.0, info.fov[1] / 2.0);
            if level >= 1 {
                if let Some(pan) = info.effort.head_pan {
                    ha += pan.upper.abs().max(pan.lower.abs());
                }
                if let Some(tilt) = info.effort.head_tilt {
                    va += tilt.upper.abs().max(tilt.lower.abs());
                }
            }
            if d.y.atan2(d.x).abs() > ha || d.z.atan2(d.x).abs() > va {
                return level >= 2;
            }
        }
        self.line_of_sight(eye.translation, p)
    }

    fn line_of_sight(&self, from: Vector, to: Vector) -> bool {
        let dir = to - from;
        let len = dir.length();
        if len < 1e-6 {
            return true;
        }
        let ray = Ray::new(from, dir / len);
        let skip_human = self
            .human
            .map(|h| format!("{}/", self.world.agent(h).name()));
        let max = len - 0.005;
        let obstacles = &self.full_wo;
        !obstacles.obstacles().iter().enumerate().any(|(i, o)| {
            if skip_human
                .as_ref()
                .is_some_and(|n| o.name.starts_with(n.as_str()))
            {
                return false;
            }
            // The obstacle's bounds first (a ray that misses them misses the shape).
            obstacles.aabb(i).intersects_local_ray(&ray, max)
                && o.shape.intersects_ray(&o.pose, &ray, max)
        })
    }

    /// Candidate points for level `level`, not tried at a lower level, best first.
    fn candidate_points(&mut self, level: u8) -> Vec<Vector> {
        let robot = self.setup.agent;
        let rinfo = self.world.agent(robot);
        let rshoulders = effort::shoulders(
            &self.world,
            robot,
            self.world.agent_state(robot).base,
            &self.q0_full,
        );
        let rreach = rinfo.reach;
        let obj_h = self
            .object
            .map(|o| self.world.object(o).local_aabb.half_extents().max_element())
            .unwrap_or(0.05);
        let kind = self.task.kind;
        let mut raw: Vec<Vector> = Vec::new();
        if kind == TaskKind::Pick {
            let o = self.object.unwrap();
            raw.push(self.world.object_pose(o).translation);
            return raw;
        }
        if kind.hands_over() {
            let Some(h) = self.human else { return raw };
            let eye = self.world.eye_pose(h).translation;
            let mut lo = eye.min(rshoulders.iter().fold(eye, |a, b| a.min(*b)));
            let mut hi = eye.max(rshoulders.iter().fold(eye, |a, b| a.max(*b)));
            lo -= Vector::new(0.3, 0.3, 0.6);
            hi += Vector::new(0.3, 0.3, 0.2);
            lo.z = lo.z.max(0.5);
            raw.extend(bounded_grid(lo, hi, &rshoulders, rreach));
        } else {
            let supports: Vec<ObjectId> = match (kind, self.task.support) {
                (TaskKind::PlaceOn, Some(s)) => vec![s],
                _ => self
                    .world
                    .object_ids()
                    .filter(|&id| {
                        Some(id) != self.object && !self.world.object(id).surfaces.is_empty()
                    })
                    .collect(),
            };
            for s in supports {
                let pose = self.world.object_pose(s);
                for surf in &self.world.object(s).surfaces {
                    let inset = 0.03;
                    let (hx, hy) = (surf.half_extents[0] - inset, surf.half_extents[1] - inset);
                    if hx < 0.0 || hy < 0.0 {
                        continue;
                    }
                    let step = grid_step(Vector::new(2.0 * hx, 2.0 * hy, 0.0));
                    let nx = (2.0 * hx / step).floor() as i32;
                    let ny = (2.0 * hy / step).floor() as i32;
                    let ox = -(nx as f32) * step / 2.0;
                    let oy = -(ny as f32) * step / 2.0;
                    for i in 0..=nx {
                        for j in 0..=ny {
                            let local = surf.centre
                                + Vector::new(ox + i as f32 * step, oy + j as f32 * step, 0.0);
                            raw.push(pose.transform_point(local));
                        }
                    }
                }
            }
        }
        let c = self.c.clone();
        let maps = self
            .cfg
            .mightability
            .then(|| geometry::mightability::cached(&self.world, &Default::default()));
        let mut pts = Vec::new();
        for p in raw {
            if self.tried_points.contains(&key(p)) {
                continue;
            }
            let centre = if kind.hands_over() {
                p
            } else {
                p + Vector::Z * obj_h
            };
            if let (Some(m), Some(h)) = (&maps, self.human) {
                // The maps' cells: the same tests as below, precomputed for the world state.
                let at_most = |l: Option<u8>, k: u8| l.is_some_and(|l| l <= k);
                let robot = self.setup.agent;
                if !at_most(m.reach_level(robot, centre), c.robot_effort)
                    || c.reach_within
                        .is_some_and(|k| !at_most(m.reach_level(h, centre), k.min(level)))
                    || c.unreachable_within
                        .is_some_and(|k| at_most(m.reach_level(h, centre), k))
                    || (c.min_visibility.is_some_and(|v| v > 0.0)
                        && !at_most(m.vis_level(h, centre), level))
                    || (c.max_visibility.is_some_and(|v| v < 0.05)
                        && at_most(m.vis_level(h, centre), c.max_effort))
                {
                    continue;
                }
                pts.push(p);
                continue;
            }
            if !rshoulders.iter().any(|s| (*s - centre).length() <= rreach) {
                continue;
            }
            if let Some(k) = c.reach_within
                && !self.human_reaches(centre, k.min(level))
            {
                continue;
            }
            if let Some(k) = c.unreachable_within
                && self.human_reaches(centre, k)
            {
                continue;
            }
            if c.min_visibility.is_some_and(|v| v > 0.0) && !self.may_see(centre, level) {
                continue;
            }
            if c.max_visibility.is_some_and(|v| v < 0.05) && self.may_see(centre, c.max_effort) {
                // A clear line of sight to the object's centre: it would show.
                continue;
            }
            if kind.hands_over() {
                // Free space for the object in the air.
                let ball = parry3d::shape::Ball::new(0.03);
                let pose = Pose::from_translation(p);
                let aabb = ball.compute_aabb(&pose);
                if self.obstacles_wo.first_hit(&pose, &ball, &aabb).is_some() {
                    continue;
                }
            }
            pts.push(p);
        }
        // Best first: near the human for tasks that serve them, near the robot otherwise.
        let anchor = match (self.human, kind) {
            (
                Some(h),
                TaskKind::Show
                | TaskKind::Give
                | TaskKind::MakeAccessible
                | TaskKind::PickAndMakeAccessible,
            ) => {
                let st = self.world.agent_state(h);
                let sh = effort::shoulders(&self.world, h, st.base, &st.q);
                let n = sh.len().max(1) as f32;
                let mid = sh.iter().fold(Vector::ZERO, |a, b| a + *b) / n;
                if kind == TaskKind::Show {
                    // Between the two agents.
                    let r = rshoulders.iter().fold(Vector::ZERO, |a, b| a + *b)
                        / rshoulders.len().max(1) as f32;
                    (mid + r) * 0.5
                } else {
                    mid
                }
            }
            // Elsewhere, near where the object is: the least carrying, and likely within reach
            // of the arm that holds or will pick it.
            _ => match self.object {
                Some(o) => self.world.object_pose(o).translation,
                None => {
                    rshoulders.iter().fold(Vector::ZERO, |a, b| a + *b)
                        / rshoulders.len().max(1) as f32
                }
            },
        };
        // Hiding: the best hidden first, by a cheap score (clear lines of sight from the
        // human's eyes to the top corners and centre of the object's box there), so that
        // the pixel-visibility test, the costly one, mostly confirms.
        let hiding = c.max_visibility.is_some() && self.human.is_some() && !kind.hands_over();
        let shown = |p: &Vector| -> usize {
            if !hiding {
                return 0;
            }
            let eye = self.world.eye_pose(self.human.unwrap()).translation;
            let r = self
                .object
                .map(|o| {
                    let h = self.world.object(o).local_aabb.half_extents();
                    h.x.max(h.y)
                })
                .unwrap_or(0.05);
            let top = *p + Vector::Z * (2.0 * obj_h);
            [
                top,
                top + Vector::new(r, r, 0.0),
                top + Vector::new(r, -r, 0.0),
                top + Vector::new(-r, r, 0.0),
                top + Vector::new(-r, -r, 0.0),
            ]
            .iter()
            .filter(|t| self.line_of_sight(eye, **t))
            .count()
        };
        // Distance to the anchor in bins of BIN metres, then the hiding score.
        let mut scored: Vec<((usize, usize, f32), Vector)> = pts
            .iter()
            .map(|p| {
                let d = (*p - anchor).length();
                (((d / BIN) as usize, shown(p), d), *p)
            })
            .collect();
        scored.sort_by(|(sa, a), (sb, b)| {
            (sa.0, sa.1)
                .cmp(&(sb.0, sb.1))
                .then(sa.2.total_cmp(&sb.2))
                .then(a.x.total_cmp(&b.x))
                .then(a.y.total_cmp(&b.y))
                .then(a.z.total_cmp(&b.z))
        });
        let mut pts: Vec<Vector> = scored.into_iter().map(|(_, p)| p).collect();
        pts.truncate(c.max_points);
        if pts.is_empty() {
            let r = self.no_points_reason(level);
            self.reject(Stage::Points, || r);
        }
        pts
    }

    fn no_points_reason(&self, level: u8) -> String {
        let mut parts = vec![format!(
            "reachable by {}",
            self.world.agent(self.setup.agent).name()
        )];
        let h = self.human_name();
        if let Some(k) = self.c.reach_within {
            parts.push(format!("reachable by {h} at effort <= {}", k.min(level)));
        }
        if let Some(k) = self.c.unreachable_within {
            parts.push(format!("out of {h}'s reach at effort <= {k}"));
        }
        if self.c.min_visibility.is_some() {
            parts.push(format!("in {h}'s view at effort <= {level}"));
        }
        if self.c.max_visibility.is_some() {
            parts.push(format!("out of {h}'s line of sight"));
        }
        let place = if self.task.kind.hands_over() {
            "in the air"
        } else {
            "on a support surface"
        };
        format!("no candidate point {place} is {}", parts.join(", "))
    }

    /// Collision-free orientations of the object at `p`.
    fn orientations_at(&mut self, p: Vector) -> Vec<Orientation> {
        let Some(o) = self.object else {
            return Vec::new();
        };
        if self.task.kind == TaskKind::Pick {
            return vec![Orientation {
                pose: self.world.object_pose(o),
                face: 0,
                yaw_index: 0,
            }];
        }
        let model = self.world.object(o).clone();
        let offset_inv = model.shape_offset.inverse();
        let com = crate::grasp::centre_of_mass(&*model.shape);
        let mut out = Vec::new();
        let faces = self.faces.clone();
        let yaws = self.cfg.placement.yaws.max(1);
        for (fi, f) in faces.iter().enumerate() {
            for yi in 0..yaws {
                let yaw = std::f32::consts::TAU * yi as f32 / yaws as f32;
                let shape_pose = if self.task.kind.hands_over() {
                    let r = Rotation::from_rotation_z(yaw) * f.rotation;
                    Pose::from_parts(p - r * com, r)
                } else {
                    f.pose_at(p, yaw, self.cfg.placement.clearance)
                };
                let aabb = model.shape.compute_aabb(&shape_pose);
                if let Some(hit) = self
                    .obstacles_wo
                    .first_hit(&shape_pose, &*model.shape, &aabb)
                {
                    let name = self.obstacles_wo.obstacles()[hit].name.clone();
                    let oname = model.name.clone();
                    self.reject(Stage::ObjectCollision, || {
                        format!("every orientation of `{oname}` collides (last with `{name}`)")
                    });
                    continue;
                }
                out.push(Orientation {
                    pose: shape_pose * offset_inv,
                    face: fi,
                    yaw_index: yi,
                });
            }
        }
        // The least turn of the object first: its grasp, fixed in the object, then asks the
        // least turn of the wrist, and the carry is the shorter for it.
        let now = self.world.object_pose(o).rotation;
        let turn = |r: Rotation| now.angle_between(r);
        out.sort_by(|a, b| turn(a.pose.rotation).total_cmp(&turn(b.pose.rotation)));
        out
    }

    // ---- grasps and motions ------------------------------------------------------------------

    fn gripper_free(
        &self,
        tool: &Pose,
        opening: f32,
        obstacles: &StaticObstacles,
    ) -> Option<String> {
        let g = Gripper::new(opening);
        for (local, cuboid) in &g.boxes {
            let pose = *tool * *local;
            let aabb = cuboid.compute_aabb(&pose);
            if let Some(i) = obstacles.first_hit(&pose, cuboid as &Cuboid, &aabb) {
                return Some(obstacles.obstacles()[i].name.clone());
            }
        }
        None
    }

    fn motion<'s>(
        &self,
        setup: &'s RobotSetup,
        arm: usize,
        obstacles: Arc<StaticObstacles>,
        held: Option<(ObjectId, Pose)>,
        opening: f32,
    ) -> Result<ArmMotion<'s>, String> {
        let a = &setup.arms[arm];
        let held = match held {
            Some((o, object_in_tool)) => Some(robot::held_object(
                &self.world,
                setup,
                a,
                o,
                object_in_tool,
            )?),
            None => None,
        };
        let mut template = self.q0_full.clone();
        set_opening(&setup.model, a, &mut template, opening);
        let mut m = ArmMotion::new(
            setup,
            a,
            obstacles,
            held,
            self.world.agent_state(setup.agent).base,
            template,
        );
        for h in robot::held_elsewhere(&self.world, setup, a)? {
            m.checker.add_other_held_object(h);
        }
        Ok(m)
    }

    /// Whether `arm` may reach an object at point `p` at all (its tool within the arm's reach
    /// from the shoulder, with the object's size as slack): a cheap test before any grasp.
    fn arm_may_reach_point(&self, arm: usize, p: Vector) -> bool {
        if self.task.kind == TaskKind::Pick {
            return true;
        }
        let a = &self.setup.arms[arm];
        let slack = self
            .object
            .map(|o| self.world.object(o).local_aabb.half_extents().length())
            .unwrap_or(0.0);
        let shoulder = self.arm_shoulders[arm];
        (p - shoulder).length() <= a.wrist_reach + a.wrist_to_tool + slack + 0.05
    }

    /// Whether choice `ci` could place the object in some orientation at the current point:
    /// an orientation not already failed, whose tool pose is within the arm's reach and whose
    /// gripper boxes are free. Cheap (box tests), so that a grasp is not picked up for a point
    /// where it cannot be used.
    fn choice_fits_point(&self, ci: usize) -> bool {
        if self.task.kind == TaskKind::Pick {
            return true;
        }
        let ch = self.choices[ci];
        let arm = &self.setup.arms[ch.arm];
        let shoulder = self.arm_shoulders[ch.arm];
        let orients = self.orientations.as_deref().unwrap_or(&[]);
        let placing = self.task.kind.places();
        for (oidx, orient) in orients.iter().enumerate() {
            if placing && self.verdicts.get(&(self.li, self.pi, oidx)) == Some(&None) {
                continue;
            }
            let tool = orient.pose * ch.tool_in_object;
            if arm.may_reach(shoulder, &tool)
                && self
                    .gripper_free(&tool, ch.grasp.width, &self.obstacles_wo)
                    .is_none()
            {
                return true;
            }
        }
        false
    }

    /// Whether choice `ci` can be picked up (computed once and remembered).
    fn pick_feasible(&mut self, ci: usize) -> bool {
        if self.held {
            return true;
        }
        if let Some(p) = self.pick_cache.get(&ci) {
            return p.is_some();
        }
        self.stats.grasps += 1;
        let plan = self.plan_pick(ci);
        let ok = plan.is_some();
        if !ok {
            self.failed_choices.insert(ci);
        }
        self.pick_cache.insert(ci, plan);
        ok
    }

    fn plan_pick(&mut self, ci: usize) -> Option<PickPlan> {
        let o = self.object?;
        let ch = self.choices[ci];
        let setup = self.setup.clone();
        let arm = &setup.arms[ch.arm];
        let oname = self.object_name();
        let tool = self.world.object_pose(o) * ch.tool_in_object;
        if self.cfg.trace {
            eprintln!(
                "grasp {} {}: tool at {:?} approach {:?}",
                ch.grasp.id,
                arm.name,
                tool.translation,
                tool.rotation * Vector::X
            );
        }
        if let Some(n) = self.gripper_free(&tool, ch.grasp.opening, &self.obstacles_wo.clone()) {
            self.reject(Stage::Pick, || {
                format!("no grasp of `{oname}` is free: the gripper hits `{n}`")
            });
            return None;
        }
        let back = tool.rotation * Vector::X * (-self.c.approach);
        let pre = Pose::from_parts(tool.translation + back, tool.rotation);
        if let Some(n) = self.gripper_free(&pre, ch.grasp.opening, &self.obstacles_all.clone()) {
            self.reject(Stage::Pick, || {
                format!("no approach to `{oname}` is free: the gripper hits `{n}`")
            });
            return None;
        }
        let rrt = self.cfg.rrt.clone();
        let mut rng = fastrand::Rng::with_seed(self.rng.u64(..));
        let open_wo = self
            .motion(
                &setup,
                ch.arm,
                self.obstacles_wo.clone(),
                None,
                ch.grasp.opening,
            )
            .ok()?;
        let q0 = robot::arm_values(arm, &self.q0_full);
        let hold_empty = self
            .motion(
                &setup,
                ch.arm,
                Arc::new(StaticObstacles::empty()),
                Some((o, ch.tool_in_object.inverse())),
                ch.grasp.width,
            )
            .ok()?;
        if !open_wo.arm.may_reach(open_wo.shoulder(), &tool) {
            self.reject(Stage::Pick, || {
                format!("no grasp of `{oname}` is within the arm's reach")
            });
            return None;
        }
        self.stats.ik_calls += 1;
        let held_ok = |qa: &[f32]| hold_empty.free(qa);
        let qg = match open_wo.ik_free(
            tool,
            &q0,
            self.cfg.ik_tries,
            self.cfg.ik_attempts,
            &held_ok,
            &mut rng,
        ) {
            Ok(q) => q,
            Err(None) => {
                self.reject(Stage::Pick, || {
                    format!("no grasp of `{oname}` is within the arm's reach (inverse kinematics)")
                });
                return None;
            }
            Err(Some(c)) => {
                self.reject(Stage::Pick, || {
                    format!("every grasp configuration for `{oname}` collides ({c})")
                });
                return None;
            }
        };
        // Approach: straight back from the grasp, the gripper checked against the object.
        let straddle = straddles(
            &open_wo,
            ch.grasp.opening,
            self.world.object(o).shape.clone(),
            self.world.object_shape_pose(o),
        );
        // The grasp configuration itself is the approach's start, which the straight move
        // takes as checked: the open gripper there must not touch the object either.
        if !straddle(&qg) {
            self.reject(Stage::Pick, || {
                format!("the open gripper touches `{oname}` at every grasp configuration")
            });
            return None;
        }
        let mut checks = 0;
        let back_path = self.or_reject(
            open_wo.straight(
                &qg,
                back,
                STRAIGHT_STEPS,
                &rrt,
                &straddle,
                &mut rng,
                &mut checks,
            ),
            Stage::Pick,
            || format!("no straight approach to `{oname}`"),
        )?;
        let qpre = back_path.waypoints.last().unwrap().clone();
        let open_all = self
            .motion(
                &setup,
                ch.arm,
                self.obstacles_all.clone(),
                None,
                ch.grasp.opening,
            )
            .ok()?;
        if !open_all.free(&qpre) {
            self.reject(Stage::Pick, || {
                format!("every pre-grasp configuration for `{oname}` collides")
            });
            return None;
        }
        let mut grasp_path = back_path;
        grasp_path.waypoints.reverse();
        // Lift: first clear of what it rests on, then the rest with full checks.
        let never = |_: &[f32]| true;
        let unstick = UNSTICK.min(self.c.lift);
        let rob_wo = self
            .motion(
                &setup,
                ch.arm,
                self.obstacles_wo.clone(),
                None,
                ch.grasp.width,
            )
            .ok()?;
        let resting: Vec<&str> = self.resting_on.iter().map(String::as_str).collect();
        let held_free_of_rest = self
            .motion(
                &setup,
                ch.arm,
                Arc::new(self.obstacles_wo.without(&resting)),
                Some((o, ch.tool_in_object.inverse())),
                ch.grasp.width,
            )
            .ok()?;
        let hold_check = |qa: &[f32]| held_free_of_rest.free(qa);
        let lift1 = self.or_reject(
            rob_wo.straight(
                &qg,
                Vector::Z * unstick,
                1,
                &rrt,
                &hold_check,
                &mut rng,
                &mut checks,
            ),
            Stage::Pick,
            || format!("no collision-free lift of `{oname}`"),
        )?;
        let q1 = lift1.waypoints.last().unwrap().clone();
        let held_wo = self
            .motion(
                &setup,
                ch.arm,
                self.obstacles_wo.clone(),
                Some((o, ch.tool_in_object.inverse())),
                ch.grasp.width,
            )
            .ok()?;
        let rest = self.c.lift - unstick;
        let lift2 = if rest > 1e-4 {
            held_wo.straight(
                &q1,
                Vector::Z * rest,
                STRAIGHT_STEPS,
                &rrt,
                &never,
                &mut rng,
                &mut checks,
            )
        } else {
            Ok(JointPath {
                waypoints: vec![q1.clone()],
            })
        };
        let lift2 = match lift2 {
            Ok(p) => p,
            Err(e) => {
                self.reject(Stage::Pick, || {
                    format!("no collision-free lift of `{oname}`: {e}")
                });
                return None;
            }
        };
        let q_lift = lift2.waypoints.last().unwrap().clone();
        Some(PickPlan {
            approach: None,
            q_pre: qpre,
            grasp: grasp_path,
            lift: vec![(lift1, self.resting_on.clone()), (lift2, Vec::new())],
            q_lift,
        })
    }

    /// Whether the human reaches the object in `world` at effort `level` or lower, as the
    /// `reachable` shared literal measures it (reach spheres confirmed by inverse kinematics).
    fn human_reach_at_most(&mut self, world: &World, level: u8) -> bool {
        let (Some(h), Some(o)) = (self.human, self.object) else {
            return false;
        };
        let params = geometry::facts::FactParams {
            max_effort: level,
            ..Default::default()
        };
        geometry::facts::reachable_effort(world, h, o, &params).is_some_and(|l| l <= level)
    }

    /// Plans the approach of choice `ci`'s pick (RRT-Connect from the current arm configuration
    /// to the pre-grasp), once; on failure the choice is dropped for good.
    fn ensure_approach(&mut self, ci: usize) -> bool {
        let Some(Some(plan)) = self.pick_cache.get(&ci) else {
            return self.held;
        };
        if plan.approach.is_some() {
            return true;
        }
        let qpre = plan.q_pre.clone();
        let ch = self.choices[ci];
        let setup = self.setup.clone();
        let arm = &setup.arms[ch.arm];
        let q0 = robot::arm_values(arm, &self.q0_full);
        let Ok(open_all) = self.motion(
            &setup,
            ch.arm,
            self.obstacles_all.clone(),
            None,
            ch.grasp.opening,
        ) else {
            return false;
        };
        let mut rng = fastrand::Rng::with_seed(self.rng.u64(..));
        self.stats.planner_calls += 1;
        match open_all.plan(&q0, &qpre, &self.cfg.rrt, &mut rng) {
            Ok((p, _)) => {
                if let Some(Some(plan)) = self.pick_cache.get_mut(&ci) {
                    plan.approach = Some(p);
                }
                true
            }
            Err(e) => {
                let oname = self.object_name();
                self.reject(Stage::Trajectory, || {
                    format!("no collision-free approach to `{oname}`: {e}")
                });
                self.pick_cache.insert(ci, None);
                self.failed_choices.insert(ci);
                false
            }
        }
    }

    /// Visibility of the object for the human in `world` at effort `level` (the best over what
    /// the level allows: the head as it is, turned to the object, or the stances of level 2+).
    fn measure_visibility(&mut self, world: &World, level: u8) -> f32 {
        let (Some(h), Some(o)) = (self.human, self.object) else {
            return 0.0;
        };
        let full = self.cfg.visibility_resolution;
        if let Some(max) = self.c.max_visibility {
            // Hiding (the coarse grid already passed, in the precheck): the first view (head as
            // it is, turned, other stances) that shows too much ends the measure.
            return visibility_upto(world, h, o, level, full, Some(max));
        }
        measure_visibility(world, h, o, level, full)
    }

    fn try_tuple(
        &mut self,
        ci: usize,
        point: Vector,
        orient: Orientation,
        oidx: usize,
    ) -> Option<Solution> {
        let o = self.object?;
        let ch = self.choices[ci];
        let setup = self.setup.clone();
        let level = self.levels[self.li];
        let oname = self.object_name();
        let kind = self.task.kind;
        let object_in_tool = ch.tool_in_object.inverse();
        let rrt = self.cfg.rrt.clone();
        let mut rng = fastrand::Rng::with_seed(self.rng.u64(..));
        let q0 = robot::arm_values(&self.setup.arms[ch.arm], &self.q0_full);
        if kind == TaskKind::Pick {
            if !self.ensure_approach(ci) {
                return None;
            }
            let plan = self.pick_cache.get(&ci).cloned().flatten()?;
            let mut after = self.world.clone();
            let mut q = self.q0_full.clone();
            let arm = &self.setup.arms[ch.arm];
            robot::set_arm_values(arm, &mut q, &plan.q_lift);
            set_opening(&self.setup.model, arm, &mut q, ch.grasp.width);
            let base = after.agent_state(self.setup.agent).base;
            after.set_agent_config(self.setup.agent, base, &q);
            after.attach_with_grasp(o, self.setup.agent, arm.tool_link, object_in_tool);
            let trajectories = self.pick_trajectories(ci, &plan);
            return Some(self.solution(after, ci, None, None, level, trajectories));
        }
        // A placement whose reach or visibility already failed fails for every grasp (the world
        // after a placement does not depend on the grasp: the arm returns to where it was).
        let verdict_key = (self.li, self.pi, oidx);
        if !kind.hands_over() && self.verdicts.get(&verdict_key) == Some(&None) {
            return None;
        }
        let tool = orient.pose * ch.tool_in_object;
        // Cheap: the gripper around the object at the placement.
        if let Some(n) = self.gripper_free(&tool, ch.grasp.width, &self.obstacles_wo.clone()) {
            self.reject(Stage::Gripper, || {
                format!("the gripper holding `{oname}` hits `{n}` at every placement")
            });
            return None;
        }
        // Cheap too: the gripper where the descent starts, holding the object, and where the
        // retreat ends, open (the straight moves below would fail there, after an inverse
        // kinematics each).
        if kind.places() {
            let obstacles = self.obstacles_wo.clone();
            let above = Pose::from_parts(tool.translation + Vector::Z * self.c.lift, tool.rotation);
            if let Some(n) = self.gripper_free(&above, ch.grasp.width, &obstacles) {
                self.reject(Stage::Gripper, || {
                    format!("the gripper holding `{oname}` hits `{n}` above every placement")
                });
                return None;
            }
            let back = tool.rotation * Vector::X * (-self.c.approach);
            let away = Pose::from_parts(tool.translation + back, tool.rotation);
            if let Some(n) = self.gripper_free(&away, ch.grasp.opening, &obstacles) {
                self.reject(Stage::Gripper, || {
                    format!("the open gripper hits `{n}` when retreating from every placement of `{oname}`")
                });
                return None;
            }
        }
        // For a placement, the world after the task does not depend on the grasp (the arm
        // returns to where it was): the cheap part of the human-related verdict (reach, coarse
        // visibility), once per placement, comes before the inverse kinematics; the full pixel
        // measure after the straight moves below.
        let robot = self.setup.agent;
        let base = self.world.agent_state(robot).base;
        let arm = self.setup.arms[ch.arm].clone();
        let cached = if kind.hands_over() {
            None
        } else {
            self.verdicts.get(&verdict_key).copied()
        };
        if !kind.hands_over() && cached.is_none() && !self.prechecked.contains(&verdict_key) {
            let after = self.placed_world(o, orient.pose);
            if !self.placement_precheck(&after, level) {
                self.verdicts.insert(verdict_key, None);
                return None;
            }
            self.prechecked.insert(verdict_key);
        }
        let held_wo = self
            .motion(
                &setup,
                ch.arm,
                self.obstacles_wo.clone(),
                Some((o, object_in_tool)),
                ch.grasp.width,
            )
            .ok()?;
        let seed = match self.pick_cache.get(&ci).cloned().flatten() {
            Some(p) => p.q_lift,
            None => q0.clone(),
        };
        if !held_wo.arm.may_reach(held_wo.shoulder(), &tool) {
            self.reject(Stage::Ik, || {
                format!("no placement of `{oname}` is within the arm's reach")
            });
            return None;
        }
        self.stats.ik_calls += 1;
        let any = |_: &[f32]| true;
        let qp = match held_wo.ik_free(
            tool,
            &seed,
            self.cfg.ik_place_tries,
            self.cfg.ik_place_attempts,
            &any,
            &mut rng,
        ) {
            Ok(q) => q,
            Err(None) => {
                self.reject(Stage::Ik, || {
                    format!(
                        "no placement of `{oname}` is within the arm's reach (inverse kinematics)"
                    )
                });
                return None;
            }
            Err(Some(c)) => {
                self.reject(Stage::Ik, || {
                    format!("the arm collides at every placement of `{oname}` ({c})")
                });
                return None;
            }
        };
        // The world after the task, for the visibility test.
        let after = if kind.hands_over() {
            let mut after = self.world.clone();
            let mut q = self.q0_full.clone();
            robot::set_arm_values(&arm, &mut q, &qp);
            set_opening(&self.setup.model, &arm, &mut q, ch.grasp.width);
            after.set_agent_config(robot, base, &q);
            after.attach_with_grasp(o, robot, arm.tool_link, object_in_tool);
            after
        } else {
            self.placed_world(o, orient.pose)
        };
        // Placing: the straight moves at the placement (inverse kinematics along a line, a few
        // checks: they fail often, the lift from the placement hitting what is above it), then
        // the full pixel visibility, the costly test, then the planned motions.
        let mut checks = 0;
        let never = |_: &[f32]| true;
        let placing = if kind.hands_over() {
            None
        } else {
            // Place: straight down from above the placement.
            let up = Vector::Z * self.c.lift;
            let mut down = self.or_reject(
                held_wo.straight(&qp, up, STRAIGHT_STEPS, &rrt, &never, &mut rng, &mut checks),
                Stage::Trajectory,
                || format!("no collision-free descent to place `{oname}`"),
            )?;
            down.waypoints.reverse();
            let q_above = down.waypoints[0].clone();
            // Retreat: open, straight back along the gripper, the gripper checked against the
            // object.
            let open_wo = self
                .motion(
                    &setup,
                    ch.arm,
                    self.obstacles_wo.clone(),
                    None,
                    ch.grasp.opening,
                )
                .ok()?;
            let straddle = straddles(
                &open_wo,
                ch.grasp.opening,
                self.world.object(o).shape.clone(),
                orient.pose * self.world.object(o).shape_offset,
            );
            let back = tool.rotation * Vector::X * (-self.c.approach);
            let retreat = self.or_reject(
                open_wo.straight(
                    &qp,
                    back,
                    STRAIGHT_STEPS,
                    &rrt,
                    &straddle,
                    &mut rng,
                    &mut checks,
                ),
                Stage::Trajectory,
                || format!("no collision-free retreat after placing `{oname}`"),
            )?;
            let q_ret = retreat.waypoints.last().unwrap().clone();
            Some((down, q_above, retreat, q_ret))
        };
        let visibility = match cached {
            Some(Some(v)) => v,
            Some(None) => return None,
            None => {
                let v = if kind.hands_over() {
                    self.placement_verdict(&after, level)
                } else {
                    // The precheck passed: the full measure.
                    let v = self.placement_visibility(&after, level);
                    self.verdicts.insert(verdict_key, v);
                    v
                };
                v?
            }
        };
        // Trajectories.
        if kind.hands_over() {
            let (from, mut trajectories, held_rec) =
                self.carry_start(ci, &q0, &oname, object_in_tool)?;
            self.stats.planner_calls += 1;
            let transfer =
                self.transfer_or_reject(held_wo.plan(&from, &qp, &rrt, &mut rng), ci, || {
                    format!("no collision-free trajectory to hand `{oname}` over")
                })?;
            trajectories.push(self.trajectory(
                Phase::Transfer,
                &arm,
                transfer,
                held_rec,
                ch.grasp.width,
                vec![],
                None,
            ));
            return Some(self.solution(
                after,
                ci,
                Some((point, orient, None)),
                visibility,
                level,
                trajectories,
            ));
        }
        // The motions planned by RRT, the costly part, cheapest first: the pick's approach (once
        // per grasp), the arm's return, then the transfer with the object held.
        let (down, q_above, retreat, q_ret) = placing?;
        let (from, mut trajectories, held_rec) =
            self.carry_start(ci, &q0, &oname, object_in_tool)?;
        // Return the arm to where it started, the object now an obstacle where it was placed.
        let obstacles_after = Arc::new(robot::near(
            &robot::obstacles(&after, robot, &[]),
            self.workspace.0,
            self.workspace.1,
        ));
        let open_after = self
            .motion(&setup, ch.arm, obstacles_after, None, ch.grasp.opening)
            .ok()?;
        self.stats.planner_calls += 1;
        let home = self.or_reject(
            open_after.plan(&q_ret, &q0, &rrt, &mut rng).map(|(p, _)| p),
            Stage::Trajectory,
            || format!("no collision-free return of the arm after placing `{oname}`"),
        )?;
        self.stats.planner_calls += 1;
        let transfer =
            self.transfer_or_reject(held_wo.plan(&from, &q_above, &rrt, &mut rng), ci, || {
                format!("no collision-free trajectory carrying `{oname}`")
            })?;
        trajectories.push(self.trajectory(
            Phase::Transfer,
            &arm,
            transfer,
            held_rec.clone(),
            ch.grasp.width,
            vec![],
            None,
        ));
        trajectories.push(self.trajectory(
            Phase::Place,
            &arm,
            down,
            held_rec,
            ch.grasp.width,
            vec![],
            None,
        ));
        trajectories.push(self.trajectory(
            Phase::Retreat,
            &arm,
            retreat,
            None,
            ch.grasp.opening,
            vec![oname.clone()],
            Some((oname.clone(), orient.pose)),
        ));
        trajectories.push(self.trajectory(
            Phase::Return,
            &arm,
            home,
            None,
            ch.grasp.opening,
            vec![],
            None,
        ));
        Some(self.solution(
            after,
            ci,
            Some((point, orient, self.support_under(point))),
            visibility,
            level,
            trajectories,
        ))
    }

    /// `after` with each robot gripper opened as the last of `trajectories` moving its arm
    /// left it: the world the next task plans in is the one the plan shows.
    fn grippers_as_left(&self, mut after: World, trajectories: &[Trajectory]) -> World {
        let robot = self.setup.agent;
        let (base, mut q) = {
            let st = after.agent_state(robot);
            (st.base, st.q.clone())
        };
        let name = self.world.agent(robot).name();
        for arm in &self.setup.arms {
            let last = trajectories
                .iter()
                .rev()
                .find(|t| t.agent == name && t.arm == arm.name);
            if let Some(t) = last {
                set_opening(&self.setup.model, arm, &mut q, t.gripper_opening);
            }
        }
        after.set_agent_config(robot, base, &q);
        after
    }

    /// The world after a placement: object `o` settled from its release `pose` onto the
    /// surface, the robot in its starting posture.
    fn placed_world(&self, o: ObjectId, pose: Pose) -> World {
        let mut after = self.world.clone();
        let robot = self.setup.agent;
        let base = after.agent_state(robot).base;
        after.set_agent_config(robot, base, &self.q0_full);
        after.set_object_pose(o, self.settled(pose));
        after
    }

    /// Where an object released at `pose` (the placement's clearance above its surface) comes
    /// to rest: [`SETTLED_GAP`] above the surface, straight below.
    fn settled(&self, pose: Pose) -> Pose {
        let drop = (self.cfg.placement.clearance - SETTLED_GAP).max(0.0);
        Pose::from_parts(pose.translation - Vector::Z * drop, pose.rotation)
    }

    /// For placing tasks: whether some orientation at the current point meets the human-related
    /// constraints (reach, visibility). Those do not depend on the grasp (the arm returns to
    /// where it started), so they are measured once per orientation, before any grasp is tried
    /// at the point, stopping at the first orientation that passes; a point where none passes
    /// costs no grasp. The verdicts are remembered for the tuples that follow.
    fn point_has_placement(&mut self) -> bool {
        let (Some(o), Some(_)) = (self.object, self.human) else {
            return true;
        };
        if !self.task.kind.places() {
            return true;
        }
        let level = self.levels[self.li];
        let orients = self.orientations.clone().unwrap_or_default();
        for (oidx, orient) in orients.iter().enumerate() {
            let key = (self.li, self.pi, oidx);
            let v = match self.verdicts.get(&key) {
                Some(v) => *v,
                None => {
                    let mut after = self.world.clone();
                    after.set_agent_config(
                        self.setup.agent,
                        after.agent_state(self.setup.agent).base,
                        &self.q0_full,
                    );
                    after.set_object_pose(o, orient.pose);
                    let v = self.placement_verdict(&after, level);
                    self.verdicts.insert(key, v);
                    v
                }
            };
            if v.is_some() {
                return true;
            }
        }
        false
    }

    /// The human-related constraints on the world after a tuple: reach, then pixel visibility
    /// (the expensive test, last). `Some(visibility measured)` when they hold.
    fn placement_verdict(&mut self, after: &World, level: u8) -> Option<Option<f32>> {
        if !self.placement_precheck(after, level) {
            return None;
        }
        self.placement_visibility(after, level)
    }

    /// The cheap part of [`Search::placement_verdict`]: exact reach of the object by the human
    /// and, for hiding, pixel visibility on a coarse grid (one ray reaching the object shows
    /// it, so the coarse grid proves most failures at a sixteenth of the cost). `false` when a
    /// constraint fails.
    fn placement_precheck(&mut self, after: &World, level: u8) -> bool {
        let oname = self.object_name();
        let hname = self.human_name();
        // Exact reach of the object by the human in the final world (the shared literal's test).
        if let Some(k) = self.c.reach_within
            && !self.human_reach_at_most(after, k.min(level.max(1)))
        {
            self.reject(Stage::Reach, || {
                format!("no placement of `{oname}` is within {hname}'s reach")
            });
            return false;
        }
        if let Some(k) = self.c.unreachable_within
            && self.human_reach_at_most(after, k)
        {
            self.reject(Stage::Reach, || {
                format!("every placement of `{oname}` is within {hname}'s reach")
            });
            return false;
        }
        if self.c.min_visibility.is_some() || self.c.max_visibility.is_some() {
            self.stats.visibility_checks += 1;
        }
        if let (Some(max), Some(h), Some(o)) = (self.c.max_visibility, self.human, self.object)
            && self.cfg.visibility_resolution > 8
        {
            let v = visibility_upto(after, h, o, self.c.max_effort, 8, Some(max));
            if v > max {
                self.hidden_failed(v, max);
                return false;
            }
        }
        true
    }

    /// Records a hiding place that shows too much.
    fn hidden_failed(&mut self, v: f32, max: f32) {
        let hname = self.human_name();
        self.best_visibility = Some(self.best_visibility.map_or(v, |b| b.min(v)));
        let best = self.best_visibility.unwrap();
        self.reject(Stage::Visibility, || {
            format!(
                "no placement hidden from {hname}: best visibility {best:.2} (needs <= {max:.2})"
            )
        });
    }

    /// The rest of [`Search::placement_verdict`] once the precheck passed: pixel visibility
    /// at full resolution. `Some(visibility measured)` when it meets the thresholds.
    fn placement_visibility(&mut self, after: &World, level: u8) -> Option<Option<f32>> {
        let oname = self.object_name();
        let hname = self.human_name();
        // Pixel visibility, the expensive test, last of the constraints.
        let mut visibility = None;
        if self.c.min_visibility.is_some() || self.c.max_visibility.is_some() {
            let vis_level = if self.c.max_visibility.is_some() {
                self.c.max_effort
            } else {
                level
            };
            let v = self.measure_visibility(after, vis_level);
            visibility = Some(v);
            if let Some(min) = self.c.min_visibility
                && v < min
            {
                self.best_visibility = Some(self.best_visibility.map_or(v, |b| b.max(v)));
                let best = self.best_visibility.unwrap();
                self.reject(Stage::Visibility, || {
                    format!("no placement of `{oname}` visible enough to {hname}: best visibility {best:.2} (needs >= {min:.2})")
                });
                return None;
            }
            if let Some(max) = self.c.max_visibility
                && v > max
            {
                self.hidden_failed(v, max);
                return None;
            }
        }
        Some(visibility)
    }

    fn support_under(&self, p: Vector) -> Option<String> {
        let mut best: Option<(f32, String)> = None;
        for id in self.world.object_ids() {
            if Some(id) == self.object {
                continue;
            }
            let pose = self.world.object_pose(id);
            for s in &self.world.object(id).surfaces {
                let l = pose.inverse_transform_point(p) - s.centre;
                if l.x.abs() <= s.half_extents[0] + 1e-3
                    && l.y.abs() <= s.half_extents[1] + 1e-3
                    && l.z.abs() < 0.02
                {
                    let d = l.z.abs();
                    if best.as_ref().is_none_or(|b| d < b.0) {
                        best = Some((d, self.world.object(id).name.clone()));
                    }
                }
            }
        }
        best.map(|b| b.1)
    }

    #[allow(clippy::too_many_arguments)]
    fn trajectory(
        &self,
        phase: Phase,
        arm: &robot::Arm,
        path: JointPath,
        held: Option<HeldRecord>,
        opening: f32,
        ignored: Vec<String>,
        straddles: Option<(String, Pose)>,
    ) -> Trajectory {
        Trajectory {
            phase,
            agent: self.world.agent(self.setup.agent).name().to_string(),
            arm: arm.name.clone(),
            joints: arm.joint_names.clone(),
            length: path.length(&arm.space),
            waypoints: path.unwrapped(&arm.space).waypoints,
            held,
            gripper_opening: opening,
            ignored,
            straddles: straddles.map(|(n, p)| (n, p.into())),
        }
    }

    /// Where carrying the object starts for choice `ci`: the arm lifted after the pick (whose
    /// trajectories come first), or `q0` when the object is already held; with the record of
    /// the held object. `None` when the pick has no collision-free approach.
    fn carry_start(
        &mut self,
        ci: usize,
        q0: &[f32],
        oname: &str,
        object_in_tool: Pose,
    ) -> Option<(Vec<f32>, Vec<Trajectory>, Option<HeldRecord>)> {
        if !self.held && !self.ensure_approach(ci) {
            return None;
        }
        let pick = if self.held {
            None
        } else {
            self.pick_cache.get(&ci).cloned().flatten()
        };
        let from = pick
            .as_ref()
            .map(|p| p.q_lift.clone())
            .unwrap_or_else(|| q0.to_vec());
        let trajectories = match &pick {
            Some(p) => self.pick_trajectories(ci, p),
            None => Vec::new(),
        };
        let held = Some(HeldRecord {
            object: oname.to_string(),
            object_in_tool: object_in_tool.into(),
        });
        Some((from, trajectories, held))
    }

    fn pick_trajectories(&self, ci: usize, p: &PickPlan) -> Vec<Trajectory> {
        let ch = self.choices[ci];
        let arm = self.setup.arms[ch.arm].clone();
        let oname = self.object_name();
        let o = self.object.unwrap();
        let held = Some(HeldRecord {
            object: oname.clone(),
            object_in_tool: ch.tool_in_object.inverse().into(),
        });
        let mut out = vec![
            self.trajectory(
                Phase::Approach,
                &arm,
                p.approach.clone().unwrap_or_else(|| JointPath {
                    waypoints: vec![p.q_pre.clone()],
                }),
                None,
                ch.grasp.opening,
                vec![],
                None,
            ),
            self.trajectory(
                Phase::Grasp,
                &arm,
                p.grasp.clone(),
                None,
                ch.grasp.opening,
                vec![oname.clone()],
                Some((oname.clone(), self.world.object_pose(o))),
            ),
        ];
        for (path, ignored) in &p.lift {
            out.push(self.trajectory(
                Phase::Lift,
                &arm,
                path.clone(),
                held.clone(),
                ch.grasp.width,
                ignored.clone(),
                None,
            ));
        }
        out
    }

    fn solution(
        &mut self,
        after: World,
        ci: usize,
        placed: Option<(Vector, Orientation, Option<String>)>,
        visibility: Option<f32>,
        level: u8,
        trajectories: Vec<Trajectory>,
    ) -> Solution {
        let after = self.grippers_as_left(after, &trajectories);
        let ch = self.choices[ci];
        let o = self.object.unwrap();
        let reach_effort = self.human.and_then(|h| {
            let params = geometry::facts::FactParams {
                max_effort: 3,
                ..Default::default()
            };
            geometry::facts::reachable_effort(&after, h, o, &params)
        });
        let placement = placed.map(|(p, orient, support)| PlacementRecord {
            pose: self.settled(orient.pose).into(),
            support,
            point: [p.x, p.y, p.z],
            orientation: orient.face,
            yaw_index: orient.yaw_index,
        });
        let summary = SolutionSummary {
            task: self.task.kind,
            args: self.task.args.clone(),
            index: 0,
            effort_level: level,
            grasp: Some(GraspRecord {
                id: if self.held { None } else { Some(ch.grasp.id) },
                tool_in_object: ch.tool_in_object.into(),
                width: ch.grasp.width,
                arm: self.setup.arms[ch.arm].name.clone(),
            }),
            placement,
            visibility,
            reach_effort,
            robot_base: None,
            trajectories,
            stats: self.stats,
        };
        Solution {
            world: after,
            summary,
        }
    }

    // ---- take -------------------------------------------------------------------------------

    /// `take(o, h)`: one solution. The human must reach the object where the robot holds it
    /// out; the robot then opens its gripper and draws it back (straight, else planned). The
    /// object goes to the human's nearest free hand, which keeps it there, out of the way.
    fn next_take(&mut self) -> Option<Solution> {
        let (o, h) = (self.object?, self.human?);
        let oname = self.object_name();
        let hname = self.human_name();
        if self.stats.solutions > 0 {
            return None;
        }
        if !self.held {
            self.failure = Some(Failure {
                constraint: "held".into(),
                message: format!("`{oname}` is not in the robot's gripper: nothing to take"),
                limit: false,
            });
            return None;
        }
        let k = self.c.reach_within.unwrap_or(self.c.max_effort);
        let world = self.world.clone();
        let params = geometry::facts::FactParams {
            max_effort: k,
            ..Default::default()
        };
        let Some(level) =
            geometry::facts::reachable_effort(&world, h, o, &params).filter(|l| *l <= k)
        else {
            self.reject(Stage::Reach, || {
                format!("{hname} cannot reach `{oname}` where the robot holds it (effort <= {k})")
            });
            return None;
        };
        let ch = self.choices[0];
        let setup = self.setup.clone();
        let arm = &setup.arms[ch.arm];
        let q0 = robot::arm_values(arm, &self.q0_full);
        let open = self
            .motion(
                &setup,
                ch.arm,
                self.obstacles_wo.clone(),
                None,
                ch.grasp.opening,
            )
            .ok()?;
        let straddle = straddles(
            &open,
            ch.grasp.opening,
            world.object(o).shape.clone(),
            world.object_shape_pose(o),
        );
        // Straight back along the gripper, else towards the robot, else up: the first that is
        // free. Back along the gripper the fingers slide off the object, which the human holds
        // now (they may brush it); the other ways must stay clear of it.
        let tool = open.tool_pose(&q0);
        let mut home = world.agent_state(setup.agent).base.translation - tool.translation;
        home.z = 0.0;
        let ways = [
            (tool.rotation * Vector::X * -1.0, false),
            (home.normalize_or_zero(), true),
            (Vector::Z, true),
        ];
        let free = |_: &[f32]| true;
        let rrt = self.cfg.rrt.clone();
        let mut rng = fastrand::Rng::with_seed(self.rng.u64(..));
        let mut checks = 0;
        let mut last = String::new();
        let mut retreat = None;
        for (way, clear) in ways.iter().filter(|(w, _)| w.length() > 0.5) {
            let extra: &dyn Fn(&[f32]) -> bool = if *clear { &straddle } else { &free };
            let r = open.straight(
                &q0,
                *way * self.c.approach,
                3 * STRAIGHT_STEPS,
                &rrt,
                extra,
                &mut rng,
                &mut checks,
            );
            match r {
                Ok(p) => {
                    retreat = Some((p, *clear));
                    break;
                }
                Err(e) => last = e,
            }
        }
        // No straight way (an arm near its joint limits, or in a tight spot): the arm planned to
        // where the gripper is drawn back each of those ways, the object an obstacle where the
        // human holds it.
        if retreat.is_none() {
            // The object let go: an obstacle (the robot's own held objects are none).
            let mut released = world.clone();
            released.detach(o);
            let with_object = Arc::new(robot::near(
                &robot::obstacles(&released, setup.agent, &[]),
                self.workspace.0,
                self.workspace.1,
            ));
            let clear_all = self
                .motion(&setup, ch.arm, with_object, None, ch.grasp.opening)
                .ok()?;
            let any = |_: &[f32]| true;
            for (way, _) in ways.iter().filter(|(w, _)| w.length() > 0.5) {
                let back =
                    Pose::from_parts(tool.translation + *way * self.c.approach, tool.rotation);
                self.stats.ik_calls += 1;
                match clear_all.ik_free(
                    back,
                    &q0,
                    2 * self.cfg.ik_tries,
                    self.cfg.ik_attempts,
                    &any,
                    &mut rng,
                ) {
                    Ok(q_back) => {
                        self.stats.planner_calls += 1;
                        match clear_all.plan(&q0, &q_back, &rrt, &mut rng) {
                            Ok((p, _)) => {
                                retreat = Some((p, true));
                                break;
                            }
                            Err(e) => last = e.to_string(),
                        }
                    }
                    Err(e) => {
                        last = e.unwrap_or_else(|| "no inverse kinematics drawn back".into());
                    }
                }
            }
        }
        let Some((retreat, clear)) = retreat else {
            self.reject(Stage::Trajectory, || {
                format!("no collision-free retreat after handing `{oname}` to {hname}: {last}")
            });
            return None;
        };
        // The world after: the gripper open where the retreat ends, the object in the hand.
        let mut after = world.clone();
        let robot_id = setup.agent;
        let mut q = self.q0_full.clone();
        robot::set_arm_values(arm, &mut q, retreat.waypoints.last().unwrap());
        robot::set_opening(&setup.model, arm, &mut q, ch.grasp.opening);
        let base = after.agent_state(robot_id).base;
        after.set_agent_config(robot_id, base, &q);
        let retreat = self.trajectory(
            Phase::Retreat,
            arm,
            retreat,
            None,
            ch.grasp.opening,
            vec![oname.clone()],
            clear.then(|| (oname.clone(), world.object_pose(o))),
        );
        let (motion, person) = self.person_takes(&world, &after, o)?;
        let hand = &person.arms[motion.arm];
        after.set_agent_config(h, world.agent_state(h).base, &motion.q_end);
        after.attach_with_grasp(o, h, hand.tool_link, motion.grasp);
        let human_motion = |phase, path: JointPath, held| Trajectory {
            phase,
            agent: hname.clone(),
            arm: hand.name.clone(),
            joints: hand.joint_names.clone(),
            length: path.length(&hand.space),
            waypoints: path.unwrapped(&hand.space).waypoints,
            held,
            gripper_opening: 0.0,
            ignored: vec![],
            straddles: None,
        };
        let held = HeldRecord {
            object: oname.clone(),
            object_in_tool: motion.grasp.into(),
        };
        let trajectories = vec![
            human_motion(Phase::Reach, motion.reach.clone(), None),
            retreat,
            human_motion(Phase::Withdraw, motion.withdraw.clone(), Some(held)),
        ];
        Some(self.take_solution(after, level, trajectories))
    }

    /// The person's reach and withdraw of a take, with the free hand nearest the object
    /// (`before`: the robot holds it out; `after`: the robot drawn back). `None`, with the
    /// reason recorded, when both hands are full or no collision-free motion exists.
    fn person_takes(
        &mut self,
        before: &World,
        after: &World,
        o: ObjectId,
    ) -> Option<(crate::take::TakeMotion, Arc<RobotSetup>)> {
        let oname = self.object_name();
        let hname = self.human_name();
        let Some(person) = self.person.clone() else {
            self.failure = Some(Failure {
                constraint: "held".into(),
                message: format!("{hname} has no arms to take `{oname}` with"),
                limit: false,
            });
            return None;
        };
        let at = before.object_pose(o).translation;
        let free_arm = (0..person.arms.len())
            .filter(|&i| {
                robot::in_grippers(before, &person)
                    .all(|(_, a, _)| a.tool_link != person.arms[i].tool_link)
            })
            .min_by(|&i, &j| {
                let d = |k: usize| {
                    let p = before.agent_state(person.agent).link_poses()[person.arms[k].tool_link];
                    (p.translation - at).length()
                };
                d(i).total_cmp(&d(j))
            });
        let Some(arm) = free_arm else {
            self.failure = Some(Failure {
                constraint: "held".into(),
                message: format!(
                    "both of {hname}'s hands hold something: no hand to take `{oname}` with"
                ),
                limit: false,
            });
            return None;
        };
        let mut rng = fastrand::Rng::with_seed(self.rng.u64(..));
        self.stats.planner_calls += 2;
        match crate::take::plan_take(&person, arm, before, after, o, &self.cfg.rrt, &mut rng) {
            Ok(m) => Some((m, person)),
            Err(e) => {
                self.reject(Stage::Trajectory, || {
                    format!("{hname} cannot take `{oname}`: {e}")
                });
                None
            }
        }
    }

    /// A take's solution: the world after it, the effort at which the human reached the
    /// object, the motions.
    fn take_solution(&self, after: World, level: u8, trajectories: Vec<Trajectory>) -> Solution {
        Solution {
            world: after,
            summary: SolutionSummary {
                task: self.task.kind,
                args: self.task.args.clone(),
                index: 0,
                effort_level: level,
                grasp: None,
                placement: None,
                visibility: None,
                // In the hand: reached at level 0 now.
                reach_effort: Some(0),
                robot_base: None,
                trajectories,
                stats: self.stats,
            },
        }
    }

    // ---- navigate-to ---------------------------------------------------------------------

    fn next_navigation(&mut self) -> Option<Solution> {
        let began = Instant::now();
        let robot = self.setup.agent;
        let target = match self.task.target_object {
            Some(o) => ReachTarget::object(&self.world, o),
            None => ReachTarget::Point(self.task.target_point?),
        };
        if self.points.is_none() {
            // Base poses around the target's footprint, facing it, nearest the current base
            // first; but the robot's station (its base in the scene file) before them all:
            // going back to a piece of furniture takes the robot back to where it works
            // (m9's NAVTO(desk)). A station that does not reach the target is rejected below.
            let cur = self.world.agent_state(robot).base.translation;
            let mut cands = target.base_positions(cur);
            let [sx, sy, _] = self.world.agent(robot).spec.base;
            let station = Vector::new(sx, sy, 0.0);
            if (station - Vector::new(cur.x, cur.y, 0.0)).length() > 0.01 {
                cands.insert(0, station);
            }
            self.points = Some(cands);
            self.pi = 0;
        }
        let rreach = self.world.agent(robot).reach;
        let q = self.q0_full.clone();
        let obstacles = self.full_all.clone();
        let mut checker = geometry::collision::CollisionChecker::new(
            self.setup.self_model.clone(),
            obstacles,
            self.world.agent_state(robot).base,
        );
        match robot::carry_all(&mut checker, &self.world, &self.setup) {
            Ok(()) => {}
            Err(e) => {
                self.failure = Some(Failure {
                    constraint: "object-collision".into(),
                    message: format!("the object the robot carries: {e}"),
                    limit: false,
                });
                return None;
            }
        }
        let start_base = self.world.agent_state(robot).base;
        let (sx, sy) = (start_base.translation.x, start_base.translation.y);
        // Boxed in (an arm reaching over furniture, say): no base path starts anywhere, so
        // say so now rather than after a failed path search to every candidate pose.
        if self.pi == 0 {
            let step = 0.05;
            let free = (0..16).any(|k| {
                let a = k as f32 * std::f32::consts::TAU / 16.0;
                let mut ck = checker.clone();
                ck.set_base(Pose::from_parts(
                    start_base.translation + Vector::new(a.cos(), a.sin(), 0.0) * step,
                    start_base.rotation,
                ));
                ck.is_config_free(&q)
            });
            if !free {
                let why = checker
                    .first_collision(&q)
                    .map(|c| format!(" (already: {c})"))
                    .unwrap_or_default();
                self.failure = Some(Failure {
                    constraint: "object-collision".into(),
                    message: format!(
                        "the robot cannot move its base: every move of {step} m collides{why}"
                    ),
                    limit: false,
                });
                return None;
            }
        }
        let syaw = start_base
            .rotation
            .to_euler(parry3d::glamx::EulerRot::ZYX)
            .0;
        let bounds = self
            .world
            .scene()
            .bounds
            .unwrap_or_else(|| self.world.bounds());
        let space = crate::rrt::JointSpace::new(&[
            (bounds.mins.x.min(sx), bounds.maxs.x.max(sx), false),
            (bounds.mins.y.min(sy), bounds.maxs.y.max(sy), false),
            (0.0, 0.0, true),
        ]);
        let mut region: Option<FreeRegion> = None;
        let mut rrt_failed = false;
        loop {
            if self.out_of_time(began) {
                self.failure = Some(Failure {
                    constraint: "time-limit".into(),
                    message: format!("time limit of {:?} reached", self.c.time_limit),
                    limit: true,
                });
                return None;
            }
            let cands = self.points.as_ref().unwrap();
            if self.pi >= cands.len() {
                return None;
            }
            let c = cands[self.pi];
            self.pi += 1;
            self.stats.points += 1;
            let aim = target.nearest(c);
            let yaw = (aim.y - c.y).atan2(aim.x - c.x);
            let base = geometry::world::base_pose(c.x, c.y, yaw);
            checker.set_base(base);
            if !checker.is_config_free(&q) {
                self.reject(Stage::ObjectCollision, || {
                    "every base pose near the target collides".into()
                });
                continue;
            }
            let sh = effort::shoulders(&self.world, robot, base, &q);
            if !target.within_reach(&sh, rreach) {
                self.reject(Stage::Reach, || {
                    "the target is out of the arm's reach from every free base pose".into()
                });
                continue;
            }
            // Once a path search failed: is the pose in the free region where the robot
            // stands at all? (Cheaper than a path search that cannot succeed.)
            if rrt_failed && region.is_none() {
                region = Some(free_region(
                    &checker,
                    &q,
                    (sx, sy),
                    start_base.rotation,
                    &bounds,
                ));
            }
            if region.as_ref().is_some_and(|r| !r.contains(c.x, c.y)) {
                self.reject(Stage::Trajectory, || {
                    "no collision-free base path: the base poses near the target are not \
                     connected to where the robot stands"
                        .into()
                });
                continue;
            }
            self.stats.planner_calls += 1;
            let mut rng = fastrand::Rng::with_seed(self.rng.u64(..));
            let valid = |b: &[f32]| {
                let mut ck = checker.clone();
                ck.set_base(geometry::world::base_pose(b[0], b[1], b[2]));
                ck.is_config_free(&q)
            };
            let params = crate::rrt::RrtParams {
                resolution: 0.05,
                max_step: 0.5,
                ..self.cfg.rrt.clone()
            };
            match crate::rrt::plan(
                &space,
                &[sx, sy, syaw],
                &[c.x, c.y, yaw],
                valid,
                &params,
                &mut rng,
            ) {
                Ok((path, _)) => {
                    let mut after = self.world.clone();
                    after.set_agent_config(robot, base, &q);
                    let traj = Trajectory {
                        phase: Phase::Drive,
                        agent: self.world.agent(robot).name().to_string(),
                        arm: "base".into(),
                        joints: vec!["base_x".into(), "base_y".into(), "base_yaw".into()],
                        length: path.length(&space),
                        waypoints: path.unwrapped(&space).waypoints,
                        held: robot::carried_record(&self.world, &self.setup),
                        gripper_opening: 0.0,
                        ignored: vec![],
                        straddles: None,
                    };
                    let summary = SolutionSummary {
                        task: self.task.kind,
                        args: self.task.args.clone(),
                        index: 0,
                        effort_level: 0,
                        grasp: None,
                        placement: None,
                        visibility: None,
                        reach_effort: None,
                        robot_base: Some([c.x, c.y, yaw]),
                        trajectories: vec![traj],
                        stats: self.stats,
                    };
                    return Some(Solution {
                        world: after,
                        summary,
                    });
                }
                Err((e, _)) => {
                    rrt_failed = true;
                    self.reject(Stage::Trajectory, || {
                        format!("no collision-free base path: {e}")
                    });
                }
            }
        }
    }

    /// Why the search found nothing (more): the deepest stage that rejected candidates.
    fn explain(&self) -> Failure {
        let (constraint, message) = match self.deepest {
            None => (
                "search".to_string(),
                if self.stats.solutions > 0 {
                    "no further solution".to_string()
                } else {
                    "nothing to try".to_string()
                },
            ),
            Some(stage) => {
                let name = match stage {
                    Stage::Points => "candidate-points",
                    Stage::Pick => "pick",
                    Stage::ObjectCollision => "object-collision",
                    Stage::Gripper => "gripper-collision",
                    Stage::Ik => "inverse-kinematics",
                    Stage::Reach => "reachability",
                    Stage::Visibility => "visibility",
                    Stage::Trajectory => "trajectory",
                };
                let mut m = self.last_reason.clone();
                if self.stats.solutions > 0 {
                    m = format!("no further solution after {}: {m}", self.stats.solutions);
                }
                (name.to_string(), m)
            }
        };
        Failure {
            constraint,
            message,
            limit: false,
        }
    }
}

/// A check on `motion`'s arm values: the gripper, open by `opening`, does not touch `shape` at
/// `pose` (the object it straddles while it moves in or out around it).
fn straddles<'a>(
    motion: &'a ArmMotion<'_>,
    opening: f32,
    shape: parry3d::shape::SharedShape,
    pose: Pose,
) -> impl Fn(&[f32]) -> bool + 'a {
    let gripper = Gripper::new(opening);
    move |qa: &[f32]| !gripper.intersects(&motion.tool_pose(qa), &*shape, &pose)
}

/// Visibility of object `o` for human `h` in `world` at effort `level`: the head as it is
/// (level 0), the best of that and the head turned to the object (level 1), and the best over
/// the stances of each higher level.
pub fn measure_visibility(
    world: &World,
    h: AgentId,
    o: ObjectId,
    level: u8,
    resolution: usize,
) -> f32 {
    visibility_upto(world, h, o, level, resolution, None)
}

/// [`measure_visibility`], stopping at the first view whose visibility exceeds `stop_above`
/// (the result is then that view's, a lower bound of the best: enough to reject a hiding
/// place).
fn visibility_upto(
    world: &World,
    h: AgentId,
    o: ObjectId,
    level: u8,
    resolution: usize,
    stop_above: Option<f32>,
) -> f32 {
    let done = |v: f32| stop_above.is_some_and(|m| v > m);
    let mut v =
        visibility::visibility_for_agent_upto(world, h, o, Aim::Current, resolution, stop_above)
            .fraction();
    if done(v) {
        return v;
    }
    if level >= 1 {
        v = v.max(
            visibility::visibility_for_agent_upto(
                world,
                h,
                o,
                Aim::AtTarget,
                resolution,
                stop_above,
            )
            .fraction(),
        );
        if done(v) {
            return v;
        }
    }
    for l in 2..=level {
        for st in effort::stances(world, h, l, None) {
            let mut w = world.clone();
            w.set_agent_config(h, st.base, &st.q);
            v = v.max(
                visibility::visibility_for_agent_upto(
                    &w,
                    h,
                    o,
                    Aim::AtTarget,
                    resolution,
                    stop_above,
                )
                .fraction(),
            );
            if done(v) {
                return v;
            }
        }
    }
    v
}

/// The floor cells the robot's base can reach from where it stands without turning, on a grid
/// of [`FreeRegion::STEP`] (flood fill, each cell's configuration checked): a cheap test of
/// whether a base pose is worth a path search.
struct FreeRegion {
    origin: (f32, f32),
    cells: HashSet<(i32, i32)>,
}

impl FreeRegion {
    const STEP: f32 = 0.05;

    /// Whether the cell of `(x, y)` or one next to it is reachable.
    fn contains(&self, x: f32, y: f32) -> bool {
        let i = ((x - self.origin.0) / Self::STEP).round() as i32;
        let j = ((y - self.origin.1) / Self::STEP).round() as i32;
        [(0, 0), (1, 0), (-1, 0), (0, 1), (0, -1)]
            .iter()
            .any(|(di, dj)| self.cells.contains(&(i + di, j + dj)))
    }
}

fn free_region(
    checker: &geometry::collision::CollisionChecker,
    q: &[f32],
    origin: (f32, f32),
    rotation: Rotation,
    bounds: &parry3d::bounding_volume::Aabb,
) -> FreeRegion {
    let step = FreeRegion::STEP;
    let mut ck = checker.clone();
    let mut free = |i: i32, j: i32| {
        let (x, y) = (origin.0 + i as f32 * step, origin.1 + j as f32 * step);
        if x < bounds.mins.x || x > bounds.maxs.x || y < bounds.mins.y || y > bounds.maxs.y {
            return false;
        }
        ck.set_base(Pose::from_parts(Vector::new(x, y, 0.0), rotation));
        ck.is_config_free(q)
    };
    let mut cells = HashSet::new();
    let mut todo = vec![(0, 0)];
    cells.insert((0, 0));
    while let Some((i, j)) = todo.pop() {
        for (di, dj) in [(1, 0), (-1, 0), (0, 1), (0, -1)] {
            let n = (i + di, j + dj);
            if !cells.contains(&n) && free(n.0, n.1) {
                cells.insert(n);
                todo.push(n);
            }
        }
    }
    FreeRegion { origin, cells }
}

/// The most points one candidate grid holds (a surface, or the air between two agents).
const MAX_GRID_POINTS: f32 = 100_000.0;

/// The spacing of a candidate grid over a box of size `size` (a zero side is a flat grid): 5 cm,
/// or coarser where that would make more than [`MAX_GRID_POINTS`] points.
fn grid_step(size: Vector) -> f32 {
    let points = |s: f32| ((size / s).ceil() + Vector::ONE).element_product();
    let mut step = 0.05_f32;
    while points(step) > MAX_GRID_POINTS {
        step *= 1.25;
    }
    step
}

/// The hand-over grid over the box `lo..hi`: its points within the box clipped to what the
/// robot's shoulders reach (a point beyond is rejected anyway), spaced by [`grid_step`], so far-
/// apart agents or a huge reach cannot make it exhaust memory. The lattice starts at `lo`, so
/// where nothing is clipped the points are those of the plain 5 cm grid.
fn bounded_grid(lo: Vector, hi: Vector, shoulders: &[Vector], reach: f32) -> Vec<Vector> {
    let far = Vector::splat(f32::MAX);
    let (smin, smax) = shoulders
        .iter()
        .fold((far, -far), |(a, b), s| (a.min(*s), b.max(*s)));
    let (clo, chi) = (lo.max(smin - reach), hi.min(smax + reach));
    if shoulders.is_empty() || (chi - clo).min_element() < 0.0 {
        return Vec::new();
    }
    let step = grid_step(chi - clo);
    let first = ((clo - lo) / step).floor();
    let last = ((chi - lo) / step).ceil().min(((hi - lo) / step).ceil());
    let mut out = Vec::new();
    for i in first.x as i32..=last.x as i32 {
        for j in first.y as i32..=last.y as i32 {
            for k in first.z as i32..=last.z as i32 {
                out.push(lo + Vector::new(i as f32, j as f32, k as f32) * step);
            }
        }
    }
    out
}

fn key(p: Vector) -> (i32, i32, i32) {
    (
        (p.x * 100.0).round() as i32,
        (p.y * 100.0).round() as i32,
        (p.z * 100.0).round() as i32,
    )
}

/// Whether two shapes are within 2 mm of each other.
fn touching(a: &dyn Shape, pa: &Pose, b: &dyn Shape, pb: &Pose) -> bool {
    parry3d::query::distance(pa, a, pb, b)
        .map(|d| d.distance <= 0.002)
        .unwrap_or(true)
}

#[cfg(test)]
mod grid_tests {
    use super::*;

    /// A person two kilometres away makes a bounded grid, within the robot's reach.
    #[test]
    fn far_person_grid_is_clipped_to_reach() {
        let shoulders = [Vector::new(0.0, -0.2, 1.2), Vector::new(0.0, 0.2, 1.2)];
        let (lo, hi) = (Vector::new(-0.3, -0.5, 0.5), Vector::new(2000.0, 0.5, 1.8));
        let pts = bounded_grid(lo, hi, &shoulders, 0.95);
        assert!(!pts.is_empty() && pts.len() as f32 <= MAX_GRID_POINTS);
        assert!(pts.iter().all(|p| p.x <= 0.95 + 0.05));
    }

    /// A huge reach coarsens the grid instead of growing it.
    #[test]
    fn huge_reach_grid_is_capped() {
        let shoulders = [Vector::ZERO];
        let pts = bounded_grid(Vector::splat(-900.0), Vector::splat(900.0), &shoulders, 1e3);
        assert!(pts.len() as f32 <= MAX_GRID_POINTS, "{} points", pts.len());
    }

    /// Where nothing is clipped, the grid is the plain 5 cm grid from `lo`.
    #[test]
    fn unclipped_grid_is_the_plain_grid() {
        let shoulders = [Vector::new(0.5, 0.0, 1.0)];
        let (lo, hi) = (Vector::new(0.0, 0.0, 0.5), Vector::new(1.0, 0.5, 1.5));
        let pts = bounded_grid(lo, hi, &shoulders, 2.0);
        assert_eq!(pts.len(), 21 * 11 * 21);
        assert_eq!(pts[1], lo + Vector::new(0.0, 0.0, 0.05));
    }
}
