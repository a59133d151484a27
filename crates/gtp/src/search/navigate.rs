//! `navigate-to`: base poses around the target, facing it (the robot's station first, then
//! nearest the current base), each tested for collision and for the arm's reach of the target,
//! then a base path planned (RRT-Connect over x, y, yaw). A flood fill of the floor where the
//! robot stands spares path searches that cannot succeed.

use std::collections::HashSet;
use std::sync::Arc;
use std::time::Instant;

use geometry::collision::{CollisionChecker, StaticObstacles};
use geometry::effort;
use parry3d::bounding_volume::Aabb;
use parry3d::math::{Pose, Vector};

use crate::planner::Solution;
use crate::robot::{self, MOTION_FLOOR};
use crate::rrt::{JointPath, JointSpace, RrtParams};
use crate::solution::{Phase, SolutionSummary, Trajectory};
use crate::target::ReachTarget;

use super::{Failure, Search, Stage};

/// The base's start and the space its path is planned in.
struct BaseStart {
    /// The robot's joint values (they do not change while the base moves).
    q: Vec<f32>,
    pose: Pose,
    /// Start `(x, y, yaw)`.
    xy_yaw: [f32; 3],
    /// The scene's bounds.
    bounds: Aabb,
    /// x, y within the bounds (and the start), yaw free.
    space: JointSpace,
}

impl Search {
    /// The next base pose the robot can drive to, facing the target, within the arm's reach.
    pub(super) fn next_navigation(&mut self) -> Option<Solution> {
        let began = Instant::now();
        let robot = self.setup.agent;
        if self.stance_radius.is_none() && self.world.agent(robot).effort.move_radius == 0.0 {
            return self.fail(Failure::at(
                Stage::Reach,
                "the robot's base is fixed (its effort's move_radius is 0): it does not drive"
                    .into(),
            ));
        }
        let target = match (
            &self.stance_places,
            self.task.target_object,
            self.task.human,
        ) {
            (Some(places), _, _) => ReachTarget::Points(places.clone()),
            (None, Some(o), _) => ReachTarget::object(&self.world, o),
            (None, None, Some(h)) => ReachTarget::person(&self.world, h),
            (None, None, None) => ReachTarget::Point(self.task.target_point?),
        };
        if self.cursor.points.is_none() {
            self.cursor.points = Some(self.base_candidates(&target));
            self.cursor.point = 0;
        }
        let mut checker = match self.base_checker() {
            Ok(c) => c,
            Err(f) => return self.fail(f),
        };
        let start = self.base_start();
        // Boxed in (an arm reaching over furniture, say): no base path starts anywhere, so
        // say so now rather than after a failed path search to every candidate pose.
        if self.cursor.point == 0
            && let Some(f) = boxed_in(&checker, &start)
        {
            return self.fail(f);
        }
        let reach = self.world.agent(robot).reach;
        let mut connected = Connectivity::new(&checker, &start);
        loop {
            if self.out_of_time(began) {
                return self.fail(Failure {
                    stage: Stage::TimeLimit,
                    message: format!("time limit of {:?} reached", self.c.time_limit),
                    limit: true,
                });
            }
            let c = self.cursor.current_point()?;
            self.cursor.point += 1;
            self.stats.points += 1;
            let aim = target.nearest(c);
            let yaw = (aim.y - c.y).atan2(aim.x - c.x);
            let base = geometry::world::base_pose(c.x, c.y, yaw);
            checker.set_base(base);
            if !checker.is_config_free(&start.q) {
                self.reject(Stage::ObjectCollision, || {
                    "every base pose near the target collides".into()
                });
                continue;
            }
            let sh = effort::shoulders(&self.world, robot, base, &start.q);
            if !target.within_reach(&sh, reach) {
                self.reject(Stage::Reach, || {
                    "the target is out of the arm's reach from every free base pose".into()
                });
                continue;
            }
            let goal = [c.x, c.y, yaw];
            if connected.apart(&checker, &start, goal) {
                self.reject(Stage::Trajectory, || {
                    "no collision-free base path: the base poses near the target are not \
                     connected to where the robot stands"
                        .into()
                });
                continue;
            }
            match self.base_path(&checker, &start, goal) {
                Ok(path) => return Some(self.navigation_solution(&start, base, goal, path)),
                Err(e) => {
                    connected.rrt_failed = true;
                    self.reject(Stage::Trajectory, || {
                        format!("no collision-free base path: {e}")
                    });
                }
            }
        }
    }

    /// The drive from where the base stands to `goal` `(x, y, yaw)` as a solution (the way
    /// back of a base move), or why there is none.
    pub(super) fn drive_to(&mut self, goal: [f32; 3]) -> Result<Solution, Failure> {
        let checker = self.base_checker()?;
        let start = self.base_start();
        let base = geometry::world::base_pose(goal[0], goal[1], goal[2]);
        let path = self.base_path(&checker, &start, goal).map_err(|e| {
            Failure::at(
                Stage::Trajectory,
                format!("no collision-free drive back: {e}"),
            )
        })?;
        Ok(self.navigation_solution(&start, base, goal, path))
    }

    /// Base positions around the target's footprint, facing it, nearest the current base
    /// first; but the robot's station (its base in the scene file) before them all: going back
    /// to a piece of furniture takes the robot back to where it works (m9's NAVTO(desk)). A
    /// station that does not reach the target is rejected by the search.
    fn base_candidates(&self, target: &ReachTarget) -> Vec<Vector> {
        let robot = self.setup.agent;
        let cur = self.world.agent_state(robot).base.translation;
        if let Some(radius) = self.stance_radius {
            let turns = self.world.agent(robot).effort.base_turn > 0.0;
            return nearby_candidates(target, self.world.agent_state(robot).base, radius, turns);
        }
        let mut cands = target.base_positions(cur);
        let [sx, sy, _] = self.world.agent(robot).spec.base;
        let station = Vector::new(sx, sy, 0.0);
        if (station - Vector::new(cur.x, cur.y, 0.0)).length() > 0.01 {
            cands.insert(0, station);
        }
        cands
    }

    /// The collision checker of the whole robot, with what it carries, among every obstacle of
    /// the scene; errs when what it carries cannot be checked.
    fn base_checker(&self) -> Result<CollisionChecker, Failure> {
        let robot = self.setup.agent;
        let mut checker = CollisionChecker::new(
            self.setup.self_model.clone(),
            self.obstacles.scene.clone(),
            self.world.agent_state(robot).base,
        );
        robot::carry_all(&mut checker, &self.world, &self.setup).map_err(|e| {
            Failure::at(
                Stage::ObjectCollision,
                format!("the object the robot carries: {e}"),
            )
        })?;
        // Every base pose is checked with the joints where they are now (`q0_full`), and moving
        // the base alone keeps the links' relative poses: the robot's self-collision is the same
        // at every base pose. Free here, it is left out of the base checks (a robot of many
        // mesh pieces spends most of a check on its own folded arms); what the robot and what it
        // carries hit in the scene, and what it carries against its links, are still checked.
        let alone = CollisionChecker::new(
            self.setup.self_model.clone(),
            Arc::new(StaticObstacles::empty()),
            self.world.agent_state(robot).base,
        );
        if alone.is_config_free(&self.q0_full) {
            checker.set_self_collision(false);
        }
        Ok(checker)
    }

    /// Where the base starts and the space of its path.
    fn base_start(&self) -> BaseStart {
        let pose = self.world.agent_state(self.setup.agent).base;
        let (sx, sy) = (pose.translation.x, pose.translation.y);
        let syaw = pose.rotation.to_euler(parry3d::glamx::EulerRot::ZYX).0;
        let bounds = self
            .world
            .scene()
            .bounds
            .unwrap_or_else(|| self.world.bounds());
        let space = JointSpace::new(&[
            (bounds.mins.x.min(sx), bounds.maxs.x.max(sx), false),
            (bounds.mins.y.min(sy), bounds.maxs.y.max(sy), false),
            (0.0, 0.0, true),
        ]);
        BaseStart {
            q: self.q0_full.clone(),
            pose,
            xy_yaw: [sx, sy, syaw],
            bounds,
            space,
        }
    }

    /// The base's path from the start to `goal` `(x, y, yaw)` (RRT-Connect, 5 cm resolution):
    /// with the full budget for `navigate-to`, with the call's (see [`Search::rrt_params`])
    /// for a base move.
    fn base_path(
        &mut self,
        checker: &CollisionChecker,
        start: &BaseStart,
        goal: [f32; 3],
    ) -> Result<JointPath, String> {
        self.stats.planner_calls += 1;
        let mut rng = fastrand::Rng::with_seed(self.rng.u64(..));
        let mut ck = checker.clone();
        let valid = |b: &[f32]| {
            ck.set_base(geometry::world::base_pose(b[0], b[1], b[2]));
            ck.is_config_free(&start.q)
        };
        // The path's edges certified whole (conservative advancement), not sampled.
        let mut certify = |a: &[f32], b: &[f32], checks: &mut usize| {
            let mut turn = [0.0; 3];
            start.space.delta(a, b, &mut turn);
            let to = [a[0] + turn[0], a[1] + turn[1], a[2] + turn[2]];
            let r = checker.check_base_motion(&start.q, [a[0], a[1], a[2]], to, MOTION_FLOOR);
            *checks += r.configurations;
            r.contact.is_none()
        };
        let budget = if self.base_move {
            self.rrt_params()
        } else {
            self.cfg.rrt.clone()
        };
        let params = RrtParams {
            resolution: 0.05,
            max_step: 0.5,
            ..budget
        };
        let path = crate::rrt::plan_certified(
            &start.space,
            &start.xy_yaw,
            &goal,
            valid,
            Some(&mut certify),
            &params,
            &mut rng,
        )
        .map(|(path, _)| path)
        .map_err(|(e, _)| e);
        self.note_rrt(&path);
        path.map_err(|e| e.to_string())
    }

    /// The solution of a base path to `base` (`goal`: its x, y, yaw).
    fn navigation_solution(
        &self,
        start: &BaseStart,
        base: Pose,
        goal: [f32; 3],
        path: JointPath,
    ) -> Solution {
        let robot = self.setup.agent;
        let mut after = self.world.clone();
        after.set_agent_config(robot, base, &start.q);
        let traj = Trajectory {
            phase: Phase::Drive,
            agent: self.world.agent(robot).name().to_string(),
            arm: "base".into(),
            joints: vec!["base_x".into(), "base_y".into(), "base_yaw".into()],
            length: path.length(&start.space),
            waypoints: path.unwrapped(&start.space).waypoints,
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
            robot_base: Some(goal),
            base_move: None,
            trajectories: vec![traj],
            stats: self.stats,
        };
        Solution {
            world: after,
            summary,
        }
    }
}

/// The base poses of a base move inside a task: turning in place to face the target (when
/// `turns` allows it and the base does not face it already), then the positions around the
/// target within `radius` of the base, nearest first.
fn nearby_candidates(target: &ReachTarget, base: Pose, radius: f32, turns: bool) -> Vec<Vector> {
    let cur = Vector::new(base.translation.x, base.translation.y, 0.0);
    let aim = target.nearest(cur) - cur;
    let facing = base.rotation * Vector::X;
    let turn = crate::rrt::wrap(aim.y.atan2(aim.x) - facing.y.atan2(facing.x));
    let mut out = Vec::new();
    if turns && turn.abs() > 5f32.to_radians() {
        out.push(cur);
    }
    out.extend(
        target
            .base_positions(cur)
            .into_iter()
            .filter(|p| (*p - cur).length() <= radius),
    );
    out
}

/// Whether every move of the base by 5 cm from the start collides: the failure to report.
fn boxed_in(checker: &CollisionChecker, start: &BaseStart) -> Option<Failure> {
    let step = 0.05;
    let free = (0..16).any(|k| {
        let a = k as f32 * std::f32::consts::TAU / 16.0;
        let mut ck = checker.clone();
        ck.set_base(Pose::from_parts(
            start.pose.translation + Vector::new(a.cos(), a.sin(), 0.0) * step,
            start.pose.rotation,
        ));
        ck.is_config_free(&start.q)
    });
    if free {
        return None;
    }
    let why = checker
        .first_collision(&start.q)
        .map(|c| format!(" (already: {c})"))
        .unwrap_or_default();
    Some(Failure::at(
        Stage::ObjectCollision,
        format!("the robot cannot move its base: every move of {step} m collides{why}"),
    ))
}

/// Headings tried per cell of the free region, over a whole turn.
const REGION_YAWS: usize = 8;

/// The floor cells the robot's base can reach from where it stands, on a grid of
/// [`FreeRegion::STEP`] (flood fill, each cell's configuration checked at a few headings): a
/// cheap test of whether a base pose is worth a path search.
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

/// The largest free region around the start (in cells of [`FreeRegion::STEP`]: 2 m² at 5 cm)
/// worked out before any path search; a flood fill that grows beyond it stops (about 5 ms with
/// the bundled PR2) and the path searches come first.
const START_REGION_CELLS: usize = 800;

/// The largest pocket around a goal pose worked out before a path search to it (2.5 m²).
const POCKET_CELLS: usize = 1000;

/// What a `navigate-to` search knows of which base poses are connected to where the robot
/// stands: a path search to a pose apart from it would spend its whole budget to fail (about
/// 0.3 s with the bundled PR2), a flood fill of the free floor settles it in milliseconds when
/// the region it fills is small: the robot in a pocket of the room (boxed in by furniture, the
/// member, what it put down), or the goal in one (between a desk and a chair).
struct Connectivity {
    /// The free region around the start, when known (small, or after a failed path search).
    start: Option<FreeRegion>,
    /// Closed regions around earlier goals, apart from the start.
    pockets: Vec<FreeRegion>,
    /// Whether a path search failed: the whole free region around the start is then worth
    /// working out, however large.
    rrt_failed: bool,
}

impl Connectivity {
    fn new(checker: &CollisionChecker, start: &BaseStart) -> Self {
        Connectivity {
            start: free_region(checker, start, start.xy_yaw, Some(START_REGION_CELLS)),
            pockets: Vec::new(),
            rrt_failed: false,
        }
    }

    /// Whether the base pose `goal` `(x, y, yaw)` is known, or found cheaply, to be apart from
    /// the start (no base path joins them); `false` when a path search must decide.
    fn apart(&mut self, checker: &CollisionChecker, start: &BaseStart, goal: [f32; 3]) -> bool {
        if self.rrt_failed && self.start.is_none() {
            self.start = free_region(checker, start, start.xy_yaw, None);
        }
        if let Some(r) = &self.start {
            return !r.contains(goal[0], goal[1]);
        }
        if self.pockets.iter().any(|p| p.contains(goal[0], goal[1])) {
            return true;
        }
        match free_region(checker, start, goal, Some(POCKET_CELLS)) {
            Some(pocket) if !pocket.contains(start.xy_yaw[0], start.xy_yaw[1]) => {
                self.pockets.push(pocket);
                true
            }
            _ => false,
        }
    }
}

/// The free region around `from` `(x, y, yaw)`: the cells where the base fits at one of
/// [`REGION_YAWS`] headings (`from`'s first), joined side to side. It may join cells the base
/// cannot pass between (turning is not checked), never the reverse at those headings: a
/// filter before path searches, which decide. (At the start's heading only, it split rooms whose
/// doorway-like gaps the base passes only turned.) `None` when it grows beyond `cap` cells.
fn free_region(
    checker: &CollisionChecker,
    start: &BaseStart,
    from: [f32; 3],
    cap: Option<usize>,
) -> Option<FreeRegion> {
    let step = FreeRegion::STEP;
    let origin = (from[0], from[1]);
    let bounds = &start.bounds;
    let mut sweep = checker.base_sweep(&start.q);
    let mut free = |i: i32, j: i32| {
        let (x, y) = (origin.0 + i as f32 * step, origin.1 + j as f32 * step);
        if x < bounds.mins.x || x > bounds.maxs.x || y < bounds.mins.y || y > bounds.maxs.y {
            return false;
        }
        (0..REGION_YAWS).any(|k| {
            let yaw = from[2] + k as f32 * std::f32::consts::TAU / REGION_YAWS as f32;
            sweep.is_free_at(geometry::world::base_pose(x, y, yaw))
        })
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
        if cap.is_some_and(|c| cells.len() > c) {
            return None;
        }
    }
    Some(FreeRegion { origin, cells })
}
