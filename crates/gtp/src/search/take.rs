//! `take(o, h)`: the robot holds the object out and lets go; the person reaches it with their
//! nearest free hand and withdraws it. One solution: the human must reach the object where the
//! robot holds it; the robot opens its gripper and draws it back (straight, else planned).

use std::sync::Arc;
use std::sync::atomic::Ordering;

use geometry::collision::StaticObstacles;
use geometry::scene::{AgentId, ObjectId};
use geometry::world::World;
use parry3d::math::{Pose, Vector};

use crate::planner::Solution;
use crate::robot::{self, RobotSetup};
use crate::rrt::JointPath;
use crate::solution::{HeldRecord, Phase, SolutionSummary, Trajectory};

use super::motions::{GraspMotions, Grip, end, straddles};
use super::{Failure, STRAIGHT_STEPS, Search, Stage};

/// A person's side of a take: their motions, their setup, the other arms moved out of the way.
type PersonTake = (
    crate::take::TakeMotion,
    Arc<RobotSetup>,
    crate::take::ArmPaths,
);

impl Search {
    /// `take(o, h)`: one solution. The object goes to the human's nearest free hand, which
    /// keeps it there, out of the way.
    pub(super) fn next_take(&mut self) -> Option<Solution> {
        let (o, h) = (self.object?, self.human?);
        let oname = self.object_name();
        let hname = self.human_name();
        if self.stats.solutions > 0 {
            return None;
        }
        if !self.held {
            return self.fail(Failure::at(
                Stage::Held,
                format!("`{oname}` is not in the robot's gripper: nothing to take"),
            ));
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
        let m = self.grasp_motions(0)?;
        let mut rng = fastrand::Rng::with_seed(self.rng.u64(..));
        let (retreat, clear, mut after, (motion, person, cleared)) =
            self.retreat_and_take(&m, &world, o, &mut rng)?;
        let pose = clear.then(|| world.object_pose(o));
        let retreat = m.record(Phase::Retreat, retreat, Grip::Around(pose));
        let hand = &person.arms[motion.arm];
        after.set_agent_config(h, world.agent_state(h).base, &motion.q_end);
        after.attach_with_grasp(o, h, hand.tool_link, motion.grasp);
        let human_motion = |phase, arm: usize, path: &JointPath, held| {
            let a = &person.arms[arm];
            Trajectory {
                phase,
                agent: hname.clone(),
                arm: a.name.clone(),
                joints: a.joint_names.clone(),
                length: path.length(&a.space),
                waypoints: path.unwrapped(&a.space).waypoints,
                held,
                gripper_opening: 0.0,
                ignored: vec![],
                straddles: None,
            }
        };
        let held = HeldRecord {
            object: oname.clone(),
            object_in_tool: motion.grasp.into(),
        };
        let mut trajectories: Vec<Trajectory> = cleared
            .iter()
            .map(|(k, path)| human_motion(Phase::Clear, *k, path, None))
            .collect();
        trajectories.extend([
            human_motion(Phase::Reach, motion.arm, &motion.reach, None),
            retreat,
            human_motion(Phase::Withdraw, motion.arm, &motion.withdraw, Some(held)),
        ]);
        Some(self.take_solution(after, level, trajectories))
    }

    /// The robot's retreat after letting go of `o` and the person's take, with the world
    /// after the retreat. The robot draws back while the person's hand is on the object: the
    /// retreat is first planned against the person as they stand, then, when it hits their
    /// reaching arm, once more against it; `None` (the reason recorded) when neither clears it.
    fn retreat_and_take(
        &mut self,
        m: &GraspMotions,
        world: &World,
        o: ObjectId,
        rng: &mut fastrand::Rng,
    ) -> Option<(JointPath, bool, World, PersonTake)> {
        let (oname, hname) = (self.object_name(), self.human_name());
        let ways = self.retreat_ways(m, world);
        let mut around = self.obstacles.workspace_but_object.clone();
        for pass in 0..2 {
            let (retreat, clear) = match self.take_retreat(m, world, o, &ways, &around, rng) {
                Ok(r) => r,
                Err(last) => {
                    self.reject(Stage::Trajectory, || {
                        format!(
                            "no collision-free retreat after handing `{oname}` to {hname}: {last}"
                        )
                    });
                    return None;
                }
            };
            // The world after: the gripper open where the retreat ends, the object in the hand.
            let mut after = world.clone();
            let robot_id = self.setup.agent;
            let mut q = self.q0_full.clone();
            robot::set_arm_values(m.arm(), &mut q, &end(&retreat)?);
            robot::set_opening(&self.setup.model, m.arm(), &mut q, m.opening);
            let base = after.agent_state(robot_id).base;
            after.set_agent_config(robot_id, base, &q);
            let takes = self.person_takes(world, &after, o)?;
            let reached = reached_world(world, self.human?, &takes);
            around = self.obstacles.workspace_in(&reached, robot_id);
            let resolution = self.cfg.rrt.resolution;
            match first_hit_on(&m.open(around.clone()), &retreat, resolution) {
                None => return Some((retreat, clear, after, takes)),
                Some(hit) if pass == 1 => self.reject(Stage::Trajectory, || {
                    format!("the robot's retreat after handing `{oname}` over hits {hname}: {hit}")
                }),
                Some(_) => {}
            }
        }
        None
    }

    /// The ways the robot's gripper may draw back from the object it let go: straight back
    /// along the gripper, towards the robot, up; each with whether the gripper must stay clear
    /// of the object (back along the gripper the fingers slide off the object, which the human
    /// holds now: they may brush it; the other ways must stay clear of it).
    fn retreat_ways(&self, m: &GraspMotions, world: &World) -> RetreatWays {
        let tool = m
            .open(self.obstacles.workspace_but_object.clone())
            .tool_pose(&m.q0);
        let mut home = world.agent_state(self.setup.agent).base.translation - tool.translation;
        home.z = 0.0;
        let ways = [
            (tool.rotation * Vector::X * -1.0, false),
            (home.normalize_or_zero(), true),
            (Vector::Z, true),
        ];
        RetreatWays {
            tool,
            ways: ways.into_iter().filter(|(w, _)| w.length() > 0.5).collect(),
        }
    }

    /// The robot's retreat once it let go of `o` in `world`: the first of `ways` that is free
    /// straight among `around`, else the arm planned to where the gripper is drawn back each
    /// of those ways (among the obstacles of `world`);
    /// with whether the gripper stays clear of the object. Errs with the last reason when no
    /// way is free.
    fn take_retreat(
        &mut self,
        m: &GraspMotions,
        world: &World,
        o: ObjectId,
        ways: &RetreatWays,
        around: &Arc<StaticObstacles>,
        rng: &mut fastrand::Rng,
    ) -> Result<(JointPath, bool), String> {
        let open = m.open(around.clone());
        let straddle = straddles(
            &open,
            m,
            world.object(o).shape.clone(),
            world.object_shape_pose(o),
        );
        let free = |_: &[f32]| true;
        let rrt = self.cfg.rrt.clone();
        let mut checks = 0;
        let mut last = String::new();
        for &(way, clear) in &ways.ways {
            let extra: &dyn Fn(&[f32]) -> bool = if clear { &straddle } else { &free };
            let r = open.straight(
                &m.q0,
                way * self.c.approach,
                3 * STRAIGHT_STEPS,
                &rrt,
                extra,
                rng,
                &mut checks,
            );
            match r {
                Ok(p) => return Ok((p, clear)),
                Err(e) => last = e,
            }
        }
        // No straight way (an arm near its joint limits, or in a tight spot).
        self.planned_take_retreat(m, world, o, ways, rng, last)
            .map(|p| (p, true))
    }

    /// The arm planned to where the gripper is drawn back each of `ways`, the object an
    /// obstacle where the human holds it; the first that succeeds. Errs with the last reason
    /// (`last`, the straight moves', when none was tried).
    fn planned_take_retreat(
        &mut self,
        m: &GraspMotions,
        world: &World,
        o: ObjectId,
        ways: &RetreatWays,
        rng: &mut fastrand::Rng,
        mut last: String,
    ) -> Result<JointPath, String> {
        // The object let go: an obstacle (the robot's own held objects are none).
        let mut released = world.clone();
        released.detach(o);
        let clear_all = m.open(self.obstacles.workspace_in(&released, self.setup.agent));
        let any = |_: &[f32]| true;
        let tool = ways.tool;
        for &(way, _) in &ways.ways {
            let back = Pose::from_parts(tool.translation + way * self.c.approach, tool.rotation);
            self.stats.ik_calls += 1;
            let ik = clear_all.ik_free(
                back,
                &m.q0,
                2 * self.cfg.ik_tries,
                self.cfg.ik_attempts,
                &any,
                rng,
            );
            match ik {
                Ok(q_back) => match self.plan_motion(&clear_all, &m.q0, &q_back, rng) {
                    Ok((p, _)) => return Ok(p),
                    Err(e) => last = e.to_string(),
                },
                Err(e) => {
                    last = e.unwrap_or_else(|| "no inverse kinematics drawn back".into());
                }
            }
        }
        Err(last)
    }

    /// The person's side of the take: their nearest free hand, else another free hand, else
    /// the nearest with their other arms moved to rest first (a hand blocked by the person's
    /// own other arm); with the other arms' paths, empty unless they moved.
    fn person_takes(&mut self, before: &World, after: &World, o: ObjectId) -> Option<PersonTake> {
        let oname = self.object_name();
        let hname = self.human_name();
        let Some(person) = self.person.clone() else {
            return self.fail(Failure::at(
                Stage::Held,
                format!("{hname} has no arms to take `{oname}` with"),
            ));
        };
        let at = before.object_pose(o).translation;
        let distance = |k: usize| {
            let p = before.agent_state(person.agent).link_poses()[person.arms[k].tool_link];
            (p.translation - at).length()
        };
        let mut free: Vec<usize> = (0..person.arms.len())
            .filter(|&i| {
                robot::in_grippers(before, &person)
                    .all(|(_, a, _)| a.tool_link != person.arms[i].tool_link)
            })
            .collect();
        free.sort_by(|&i, &j| distance(i).total_cmp(&distance(j)));
        let Some(&nearest) = free.first() else {
            return self.fail(Failure::at(
                Stage::Held,
                format!("both of {hname}'s hands hold something: no hand to take `{oname}` with"),
            ));
        };
        let mut rng = fastrand::Rng::with_seed(self.rng.u64(..));
        let mut first_error = None;
        // Each reach gets the call's budget (Search::rrt_params): smaller after failed ones.
        for &arm in &free {
            self.stats.planner_calls += 2;
            let rrt = self.rrt_params();
            match crate::take::plan_take(&person, arm, before, after, o, &rrt, &mut rng) {
                Ok(m) => return Some((m, person, Vec::new())),
                Err(e) => {
                    self.note_take_failure(&e);
                    first_error.get_or_insert(e);
                }
            }
        }
        let rrt = self.rrt_params();
        let rested =
            crate::take::rest_other_arms(&person, nearest, before, after, o, &rrt, &mut rng);
        if let Ok(r) = rested {
            self.stats.planner_calls += 2 + r.moves.len();
            // The nearest arm's reach again, the others out of its way: with half the budget
            // at most, the whole spent once already.
            let mut rrt = self.rrt_params();
            if first_error.as_ref().is_some_and(|e| e.search_failed) {
                rrt.max_nodes = rrt.max_nodes.min(self.cfg.rrt.max_nodes / 2);
                rrt.max_checks = rrt.max_checks.min(self.cfg.rrt.max_checks / 2);
            }
            let take =
                crate::take::plan_take(&person, nearest, &r.before, &r.after, o, &rrt, &mut rng);
            match take {
                Ok(m) => return Some((m, person, r.moves)),
                Err(e) => self.note_take_failure(&e),
            }
        }
        let e = first_error.unwrap_or_default();
        self.reject(Stage::Trajectory, || {
            format!("{hname} cannot take `{oname}`: {e}")
        });
        None
    }

    /// Counts a take whose reach search spent its budget with the call's failed trajectory
    /// queries (see [`Search::rrt_params`]).
    fn note_take_failure(&mut self, e: &crate::take::TakeError) {
        if e.search_failed {
            self.rrt_failures.fetch_add(1, Ordering::Relaxed);
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
                base_move: None,
                trajectories,
                stats: self.stats,
            },
        }
    }
}

/// Where the robot's tool is when it lets go, and the ways it may draw back from there (unit
/// directions, with whether the gripper must stay clear of the object).
struct RetreatWays {
    tool: Pose,
    ways: Vec<(Vector, bool)>,
}

/// `world` with the person `h` as they are when their hand reaches the object: the taking arm
/// at the end of its reach, the arms moved out of the way at the end of theirs.
fn reached_world(world: &World, h: AgentId, takes: &PersonTake) -> World {
    let (motion, person, cleared) = takes;
    let mut q = world.agent_state(h).q.clone();
    let moves = cleared.iter().map(|(arm, path)| (*arm, path));
    for (arm, path) in moves.chain([(motion.arm, &motion.reach)]) {
        if let Some(last) = path.waypoints.last() {
            robot::set_arm_values(&person.arms[arm], &mut q, last);
        }
    }
    let mut reached = world.clone();
    reached.set_agent_config(h, world.agent_state(h).base, &q);
    reached
}

/// The first collision along `path`, checked every `resolution` of joint motion, in words.
fn first_hit_on(
    motion: &robot::ArmMotion<'_>,
    path: &JointPath,
    resolution: f32,
) -> Option<String> {
    path.densify(&motion.arm.space, resolution)
        .iter()
        .find_map(|q| motion.collision(q))
}
