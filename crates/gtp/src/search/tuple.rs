//! A whole tuple (grasp, point, orientation) confirmed, the last stages of the hierarchy:
//! the gripper's boxes at the placement, the human-related precheck, inverse kinematics at the
//! placement, the straight moves there, the full verdict (pixel visibility), then the motions
//! planned by RRT-Connect; and the solution it makes.

use geometry::world::World;
use parry3d::math::{Pose, Vector};

use crate::planner::Solution;
use crate::robot::{self, ArmMotion, set_opening};
use crate::rrt::JointPath;
use crate::solution::{GraspRecord, Phase, PlacementRecord, SolutionSummary, Trajectory};
use crate::task::TaskKind;

use super::cursor::{PlacementKey, Tuple};
use super::grasps::gripper_hits;
use super::motions::{GraspMotions, Grip, end, straddles};
use super::pull_out::Pull;
use super::verdicts::Verdict;
use super::{STRAIGHT_STEPS, Search, Stage};

/// A tuple whose placement (or hand-over pose) passed every constraint but the trajectories.
struct Confirmed {
    tuple: Tuple,
    level: u8,
    /// The world after the task.
    after: World,
    /// The visibility measured, when the task asks for one.
    visibility: Option<f32>,
    /// The arm's values at the placement (or hand-over pose).
    q_place: Vec<f32>,
}

/// The straight moves at a placement: the descent holding the object, the retreat open.
struct PlaceMoves {
    down: JointPath,
    /// The arm's values above the placement, where the descent starts.
    q_above: Vec<f32>,
    retreat: JointPath,
    /// The arm's values where the retreat ends.
    q_retreat: Vec<f32>,
}

impl Search {
    /// The solution of tuple `t`, or `None` with the stage that rejected it recorded.
    pub(super) fn try_tuple(&mut self, t: Tuple) -> Option<Solution> {
        let o = self.object?;
        let level = self.levels[self.cursor.level];
        let mut rng = fastrand::Rng::with_seed(self.rng.u64(..));
        let kind = self.task.kind;
        if kind == TaskKind::Pick {
            return self.pick_solution(t.grasp, level);
        }
        // A placement whose reach or visibility already failed fails for every grasp (the world
        // after a placement does not depend on the grasp: the arm returns to where it was); so
        // does a hand-over pose whose bound on visibility failed.
        let key = self.cursor.placement(t.orientation_index);
        let placing = !kind.hands_over();
        if self.verdict(key) == Some(Verdict::Failed) {
            return None;
        }
        let ch = self.choices[t.grasp];
        let tool = t.orientation.pose * ch.tool_in_object;
        let grip = (ch.grasp.width, ch.grasp.opening);
        if !self.gripper_fits_placement(ch.arm, grip, tool, t.orientation.pose) {
            return None;
        }
        // For a placement, the world after the task does not depend on the grasp (the arm
        // returns to where it was): the cheap part of the human-related verdict (reach, coarse
        // visibility), once per placement, comes before the inverse kinematics; the full pixel
        // measure after the straight moves below.
        let cached = if placing { self.verdict(key) } else { None };
        if placing && cached.is_none() {
            let after = self.placed_world(o, t.orientation.pose);
            if !self.placement_precheck(&after, level) {
                self.verdicts.insert(key, Verdict::Failed);
                return None;
            }
            self.verdicts.insert(key, Verdict::Prechecked);
        }
        let m = self.grasp_motions(t.grasp)?;
        let held = m.holding(self.obstacles.workspace_but_object.clone());
        let q_place = self.placement_ik(t.grasp, &held, tool, &mut rng)?;
        if !placing && !self.hand_over_may_show(key, o, t.orientation.pose, level) {
            return None;
        }
        // The world after the task, for the visibility test.
        let after = if placing {
            self.placed_world(o, t.orientation.pose)
        } else {
            self.handed_world(&m, &q_place)
        };
        // Placing: the straight moves at the placement (inverse kinematics along a line, a few
        // checks: they fail often, the lift from the placement hitting what is above it), then
        // the full pixel visibility, the costly test, then the planned motions.
        let moves = if placing {
            Some(self.place_moves(&m, &held, &q_place, t.orientation.pose, tool, &mut rng)?)
        } else {
            None
        };
        let verdict = match cached {
            Some(Verdict::Prechecked) | None => self.full_verdict(placing, key, &after, level),
            Some(v) => v,
        };
        let Verdict::Holds(visibility) = verdict else {
            return None;
        };
        let confirmed = Confirmed {
            tuple: t,
            level,
            after,
            visibility,
            q_place,
        };
        match moves {
            None => self.hand_over_solution(&m, &held, confirmed, &mut rng),
            Some(moves) => self.placing_solution(&m, &held, confirmed, moves, &mut rng),
        }
    }

    /// The full human-related verdict of a tuple's world `after`: for a placement the pixel
    /// measure after its precheck (remembered under `key`), for a hand-over the whole verdict.
    fn full_verdict(
        &mut self,
        placing: bool,
        key: PlacementKey,
        after: &World,
        level: u8,
    ) -> Verdict {
        if !placing {
            return self.placement_verdict(after, level);
        }
        // The precheck passed: the full measure.
        let v = self.placement_visibility(after, level);
        self.verdicts.insert(key, v);
        v
    }

    /// A pick's solution: the object held where the lift of grasp choice `grasp` ends.
    fn pick_solution(&mut self, grasp: usize, level: u8) -> Option<Solution> {
        let o = self.object?;
        if !self.ensure_approach(grasp) {
            return None;
        }
        let plan = self.pick_cache.get(&grasp).cloned().flatten()?;
        let m = self.grasp_motions(grasp)?;
        let mut after = self.world.clone();
        let mut q = self.q0_full.clone();
        let arm = m.arm();
        robot::set_arm_values(arm, &mut q, &plan.q_lift);
        set_opening(&self.setup.model, arm, &mut q, m.width);
        let base = after.agent_state(self.setup.agent).base;
        after.set_agent_config(self.setup.agent, base, &q);
        after.attach_with_grasp(o, self.setup.agent, arm.tool_link, m.object_in_tool);
        let trajectories = self.pick_trajectories(&m, &plan);
        Some(self.solution(after, grasp, None, None, level, trajectories))
    }

    /// Cheap box tests of the gripper (closed to `width`, or open by `opening`: `grip`) with
    /// the tool at `tool`, the object at `pose`: around the object at the placement, and for a
    /// placing task where the descent starts (above the placement, or in front of it for a
    /// [`Pull`] in), holding the object, and where the retreat ends, open (the straight moves
    /// would fail there, after an inverse kinematics each).
    fn gripper_fits_placement(
        &mut self,
        arm: usize,
        (width, opening): (f32, f32),
        tool: Pose,
        pose: Pose,
    ) -> bool {
        let oname = self.object_name();
        let setup = self.setup.clone();
        let gripper = &setup.arms[arm].gripper;
        let obstacles = self.obstacles.workspace_but_object.clone();
        if let Some(n) = gripper_hits(gripper, &tool, width, &obstacles) {
            self.reject(Stage::Gripper, || {
                format!("the gripper holding `{oname}` hits `{n}` at every placement")
            });
            return false;
        }
        if !self.task.kind.places() {
            return true;
        }
        let above = Pose::from_parts(tool.translation + Vector::Z * self.c.lift, tool.rotation);
        if let Some(n) = gripper_hits(gripper, &above, width, &obstacles) {
            let in_front = self.pull_for_placement(tool, pose).map(|p| {
                let [raise, slide, lift] = p.moves(self.c.lift);
                Pose::from_parts(tool.translation + raise + slide + lift, tool.rotation)
            });
            if in_front.is_none_or(|t| gripper_hits(gripper, &t, width, &obstacles).is_some()) {
                self.reject(Stage::Gripper, || {
                    format!("the gripper holding `{oname}` hits `{n}` above every placement")
                });
                return false;
            }
        }
        let back = tool.rotation * Vector::X * (-self.c.approach);
        let away = Pose::from_parts(tool.translation + back, tool.rotation);
        if let Some(n) = gripper_hits(gripper, &away, opening, &obstacles) {
            self.reject(Stage::Gripper, || {
                format!(
                    "the open gripper hits `{n}` when retreating from every placement of \
                     `{oname}`"
                )
            });
            return false;
        }
        true
    }

    /// The pull that puts the object at `pose` (the tool at `tool`) in under what is above it,
    /// reversed; `None` when there is none (see [`Pull::find`]).
    fn pull_for_placement(&self, tool: Pose, pose: Pose) -> Option<Pull> {
        let o = self.object?;
        let model = self.world.object(o);
        let shape_pose = pose * model.shape_offset;
        let obstacles = &self.obstacles.workspace_but_object;
        Pull::find(&*model.shape, &shape_pose, &tool, self.c.lift, obstacles)
    }

    /// The arm's values with the tool at `tool`, holding the object (`held`), from where the
    /// lift of grasp choice `grasp` ends (or the arm's start, the object held already).
    fn placement_ik(
        &mut self,
        grasp: usize,
        held: &ArmMotion<'_>,
        tool: Pose,
        rng: &mut fastrand::Rng,
    ) -> Option<Vec<f32>> {
        let oname = self.object_name();
        let seed = match self.pick_cache.get(&grasp).cloned().flatten() {
            Some(p) => p.q_lift,
            None => robot::arm_values(held.arm, &self.q0_full),
        };
        if !held.arm.may_reach(held.shoulder(), &tool) {
            self.reject(Stage::Ik, || {
                format!("no placement of `{oname}` is within the arm's reach")
            });
            return None;
        }
        self.stats.ik_calls += 1;
        let any = |_: &[f32]| true;
        let r = held.ik_free(
            tool,
            &seed,
            self.cfg.ik_place_tries,
            self.cfg.ik_place_attempts,
            &any,
            rng,
        );
        match r {
            Ok(q) => {
                self.cursor.ik_reached = true;
                self.cursor.ik_free = true;
                Some(q)
            }
            Err(None) => {
                self.cursor.ik_misses += 1;
                self.cursor.ik_failures += 1;
                self.reject(Stage::Ik, || {
                    format!(
                        "no placement of `{oname}` is within the arm's reach (inverse kinematics)"
                    )
                });
                None
            }
            Err(Some(c)) => {
                self.cursor.ik_reached = true;
                self.cursor.ik_failures += 1;
                self.reject(Stage::Ik, || {
                    format!("the arm collides at every placement of `{oname}` ({c})")
                });
                None
            }
        }
    }

    /// The world after a hand-over: the robot's arm at `q_place`, the gripper closed on the
    /// object.
    fn handed_world(&self, m: &GraspMotions, q_place: &[f32]) -> World {
        let robot = self.setup.agent;
        let mut after = self.world.clone();
        let base = after.agent_state(robot).base;
        let mut q = self.q0_full.clone();
        let arm = m.arm();
        robot::set_arm_values(arm, &mut q, q_place);
        set_opening(&self.setup.model, arm, &mut q, m.width);
        after.set_agent_config(robot, base, &q);
        if let Some(o) = self.object {
            after.attach_with_grasp(o, robot, arm.tool_link, m.object_in_tool);
        }
        after
    }

    /// The straight moves at a placement of the object at `pose` (tool at `tool`, arm at
    /// `q_place`): straight down from above it, holding the object, and the retreat, open,
    /// straight back along the gripper, the gripper checked against the object.
    fn place_moves(
        &mut self,
        m: &GraspMotions,
        held: &ArmMotion<'_>,
        q_place: &[f32],
        pose: Pose,
        tool: Pose,
        rng: &mut fastrand::Rng,
    ) -> Option<PlaceMoves> {
        let o = self.object?;
        let oname = self.object_name();
        let rrt = self.cfg.rrt.clone();
        let mut checks = 0;
        let never = |_: &[f32]| true;
        let up = Vector::Z * self.c.lift;
        let straight_down =
            held.straight(q_place, up, STRAIGHT_STEPS, &rrt, &never, rng, &mut checks);
        let straight_down = straight_down.or_else(|blocked| -> Result<JointPath, String> {
            let pull = self
                .pull_for_placement(tool, pose)
                .ok_or_else(|| blocked.clone())?;
            let steps = [1, pull.slide_steps(), STRAIGHT_STEPS];
            let mut q = q_place.to_vec();
            let mut path = vec![q.clone()];
            for (offset, n) in pull.moves(self.c.lift).into_iter().zip(steps) {
                let part = held
                    .straight(&q, offset, n, &rrt, &never, rng, &mut checks)
                    .map_err(|e| format!("{blocked}; pushed in: {e}"))?;
                path.extend(part.waypoints.into_iter().skip(1));
                q = path.last().cloned().unwrap_or_default();
            }
            Ok(JointPath { waypoints: path })
        });
        let mut down = self.or_reject(straight_down, Stage::Trajectory, || {
            format!("no collision-free descent to place `{oname}`")
        })?;
        down.waypoints.reverse();
        let q_above = down.waypoints.first()?.clone();
        let open = m.open(self.obstacles.workspace_but_object.clone());
        let straddle = straddles(
            &open,
            m,
            self.world.object(o).shape.clone(),
            pose * self.world.object(o).shape_offset,
        );
        let back = tool.rotation * Vector::X * (-self.c.approach);
        let retreat = self.or_reject(
            open.straight(
                q_place,
                back,
                STRAIGHT_STEPS,
                &rrt,
                &straddle,
                rng,
                &mut checks,
            ),
            Stage::Trajectory,
            || format!("no collision-free retreat after placing `{oname}`"),
        )?;
        let q_retreat = end(&retreat)?;
        Some(PlaceMoves {
            down,
            q_above,
            retreat,
            q_retreat,
        })
    }

    /// A hand-over's solution once confirmed: the pick (when the object is not held yet), then
    /// the transfer to the hand-over pose.
    fn hand_over_solution(
        &mut self,
        m: &GraspMotions,
        held: &ArmMotion<'_>,
        c: Confirmed,
        rng: &mut fastrand::Rng,
    ) -> Option<Solution> {
        let oname = self.object_name();
        let grasp = c.tuple.grasp;
        let (from, mut trajectories) = self.carry_start(m, grasp)?;
        let transfer = self.plan_motion(held, &from, &c.q_place, rng);
        let transfer = self.transfer_or_reject(transfer, grasp, || {
            format!("no collision-free trajectory to hand `{oname}` over")
        })?;
        trajectories.push(m.record(Phase::Transfer, transfer, Grip::Holding(vec![])));
        let placed = Some((c.tuple.point, c.tuple.orientation, None));
        Some(self.solution(c.after, grasp, placed, c.visibility, c.level, trajectories))
    }

    /// A placement's solution once confirmed: the motions planned by RRT, the costly part,
    /// cheapest first: the pick's approach (once per grasp), the arm's return, then the
    /// transfer with the object held; then the straight moves.
    fn placing_solution(
        &mut self,
        m: &GraspMotions,
        held: &ArmMotion<'_>,
        c: Confirmed,
        moves: PlaceMoves,
        rng: &mut fastrand::Rng,
    ) -> Option<Solution> {
        let oname = self.object_name();
        let grasp = c.tuple.grasp;
        let (from, mut trajectories) = self.carry_start(m, grasp)?;
        // Return the arm to where it started, the object now an obstacle where it was released
        // and where it settled.
        let o = self.object?;
        let released = (o, c.tuple.orientation.pose);
        let obstacles =
            self.obstacles
                .workspace_after_release(&c.after, self.setup.agent, released);
        let open_after = m.open(obstacles);
        let home = self.plan_motion(&open_after, &moves.q_retreat, &m.q0, rng);
        let home = self.or_reject(home.map(|(p, _)| p), Stage::Trajectory, || {
            format!("no collision-free return of the arm after placing `{oname}`")
        })?;
        let transfer = self.plan_motion(held, &from, &moves.q_above, rng);
        let transfer = self.transfer_or_reject(transfer, grasp, || {
            format!("no collision-free trajectory carrying `{oname}`")
        })?;
        let pose = c.tuple.orientation.pose;
        trajectories.extend([
            m.record(Phase::Transfer, transfer, Grip::Holding(vec![])),
            m.record(Phase::Place, moves.down, Grip::Holding(vec![])),
            m.record(Phase::Retreat, moves.retreat, Grip::Around(Some(pose))),
            m.record(Phase::Return, home, Grip::Open),
        ]);
        let support = self.support_under(c.tuple.point);
        let placed = Some((c.tuple.point, c.tuple.orientation, support));
        Some(self.solution(c.after, grasp, placed, c.visibility, c.level, trajectories))
    }

    /// Where carrying the object starts for grasp choice `grasp`: the arm lifted after the pick
    /// (whose trajectories come first), or the arm's start when the object is already held.
    /// `None` when the pick has no collision-free approach.
    fn carry_start(
        &mut self,
        m: &GraspMotions,
        grasp: usize,
    ) -> Option<(Vec<f32>, Vec<Trajectory>)> {
        if self.held {
            return Some((m.q0.clone(), Vec::new()));
        }
        if !self.ensure_approach(grasp) {
            return None;
        }
        match self.pick_cache.get(&grasp).cloned().flatten() {
            Some(p) => Some((p.q_lift.clone(), self.pick_trajectories(m, &p))),
            None => Some((m.q0.clone(), Vec::new())),
        }
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

    /// The solution of grasp choice `grasp`: the world `after` (grippers as the trajectories
    /// left them), what it placed where (`placed`: point, orientation, support), the
    /// visibility reached, the effort level and the trajectories.
    fn solution(
        &mut self,
        after: World,
        grasp: usize,
        placed: Option<(Vector, super::placements::Orientation, Option<String>)>,
        visibility: Option<f32>,
        level: u8,
        trajectories: Vec<Trajectory>,
    ) -> Solution {
        let after = self.grippers_as_left(after, &trajectories);
        let ch = self.choices[grasp];
        let reach_effort = self.human.zip(self.object).and_then(|(h, o)| {
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
            base_move: None,
            trajectories,
            stats: self.stats,
        };
        Solution {
            world: after,
            summary,
        }
    }
}
