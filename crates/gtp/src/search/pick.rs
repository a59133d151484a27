//! Picking a grasp choice up, once per choice and remembered: the gripper's boxes free at the
//! grasp and the pre-grasp, a collision-free grasp configuration (inverse kinematics), the
//! straight approach, the two-step lift; the approach from the arm's start planned (RRT-Connect)
//! only once a whole tuple needs it.

use std::sync::Arc;

use parry3d::math::{Pose, Vector};

use crate::robot::ArmMotion;
use crate::rrt::{JointPath, RrtError};
use crate::solution::{Phase, Trajectory};

use super::grasps::gripper_hits;
use super::motions::{GraspMotions, Grip, end, straddles};
use super::pull_out::Pull;
use super::{STRAIGHT_STEPS, Search, Stage};

/// Lift height during which the object may still touch what it rested on.
const UNSTICK: f32 = 0.02;

/// The pick part of a plan, computed once per choice and reused across points.
#[derive(Clone, Debug)]
pub(super) struct PickPlan {
    /// Planned only once a whole tuple needs it (the RRT is the costly part of a pick).
    pub(super) approach: Option<JointPath>,
    /// Arm values at the pre-grasp.
    pub(super) q_pre: Vec<f32>,
    grasp: JointPath,
    lift: Vec<(JointPath, Vec<String>)>,
    /// Arm values after the lift.
    pub(super) q_lift: Vec<f32>,
}

impl Search {
    /// Whether grasp choice `grasp` can be picked up (computed once and remembered).
    pub(super) fn pick_feasible(&mut self, grasp: usize) -> bool {
        if self.held {
            return true;
        }
        if let Some(p) = self.pick_cache.get(&grasp) {
            return p.is_some();
        }
        self.stats.grasps += 1;
        let plan = self.plan_pick(grasp);
        let ok = plan.is_some();
        if !ok {
            self.failed_choices.insert(grasp);
        }
        self.pick_cache.insert(grasp, plan);
        ok
    }

    /// The pick of grasp choice `grasp` but its planned approach; `None`, the reason
    /// rejected at [`Stage::Pick`], when it cannot be picked up.
    fn plan_pick(&mut self, grasp: usize) -> Option<PickPlan> {
        let o = self.object?;
        let ch = self.choices[grasp];
        let oname = self.object_name();
        let tool = self.world.object_pose(o) * ch.tool_in_object;
        if self.cfg.trace {
            eprintln!(
                "grasp {} {}: tool at {:?} approach {:?}",
                ch.grasp.id,
                self.setup.arms[ch.arm].name,
                tool.translation,
                tool.rotation * Vector::X
            );
        }
        let gripper = &self.setup.arms[ch.arm].gripper;
        if let Some(n) = gripper_hits(
            gripper,
            &tool,
            ch.grasp.opening,
            &self.obstacles.workspace_but_object,
        ) {
            self.reject(Stage::Pick, || {
                format!("no grasp of `{oname}` is free: the gripper hits `{n}`")
            });
            return None;
        }
        let back = tool.rotation * Vector::X * (-self.c.approach);
        let pre = Pose::from_parts(tool.translation + back, tool.rotation);
        if let Some(n) = gripper_hits(gripper, &pre, ch.grasp.opening, &self.obstacles.workspace) {
            self.reject(Stage::Pick, || {
                format!("no approach to `{oname}` is free: the gripper hits `{n}`")
            });
            return None;
        }
        let mut rng = fastrand::Rng::with_seed(self.rng.u64(..));
        let m = self.grasp_motions(grasp)?;
        let open = m.open(self.obstacles.workspace_but_object.clone());
        let qg = self.grasp_configuration(&m, &open, tool, &mut rng)?;
        let (grasp_path, q_pre) = self.straight_approach(&m, &open, &qg, back, &mut rng)?;
        let (lift, q_lift) = self.lift(&m, &qg, tool, &mut rng)?;
        Some(PickPlan {
            approach: None,
            q_pre,
            grasp: grasp_path,
            lift,
            q_lift,
        })
    }

    /// A collision-free arm configuration with the tool at `tool`, the open gripper among the
    /// obstacles but the object (`open`), the object held there free of the robot.
    fn grasp_configuration(
        &mut self,
        m: &GraspMotions,
        open: &ArmMotion<'_>,
        tool: Pose,
        rng: &mut fastrand::Rng,
    ) -> Option<Vec<f32>> {
        let oname = self.object_name();
        let hold_empty = m.holding(Arc::new(geometry::collision::StaticObstacles::empty()));
        if !open.arm.may_reach(open.shoulder(), &tool) {
            self.reject(Stage::Pick, || {
                format!("no grasp of `{oname}` is within the arm's reach")
            });
            return None;
        }
        self.stats.ik_calls += 1;
        let held_ok = |qa: &[f32]| hold_empty.free(qa);
        let r = open.ik_free(
            tool,
            &m.q0,
            self.cfg.ik_tries,
            self.cfg.ik_attempts,
            &held_ok,
            rng,
        );
        match r {
            Ok(q) => Some(q),
            Err(None) => {
                self.reject(Stage::Pick, || {
                    format!("no grasp of `{oname}` is within the arm's reach (inverse kinematics)")
                });
                None
            }
            Err(Some(c)) => {
                self.reject(Stage::Pick, || {
                    format!("every grasp configuration for `{oname}` collides ({c})")
                });
                None
            }
        }
    }

    /// The approach: straight back from the grasp configuration `qg` by `back`, the open gripper
    /// clear of the object; the path pre-grasp to grasp, and the pre-grasp's values (free of
    /// every obstacle, the object included).
    fn straight_approach(
        &mut self,
        m: &GraspMotions,
        open: &ArmMotion<'_>,
        qg: &[f32],
        back: Vector,
        rng: &mut fastrand::Rng,
    ) -> Option<(JointPath, Vec<f32>)> {
        let o = self.object?;
        let oname = self.object_name();
        let straddle = straddles(
            open,
            m,
            self.world.object(o).shape.clone(),
            self.world.object_shape_pose(o),
        );
        // The grasp configuration itself is the approach's start, which the straight move
        // takes as checked: the open gripper there must not touch the object either.
        if !straddle(qg) {
            self.reject(Stage::Pick, || {
                format!(
                    "the open gripper or the arm touches `{oname}` at every grasp configuration"
                )
            });
            return None;
        }
        let rrt = self.cfg.rrt.clone();
        let mut checks = 0;
        let back_path = self.or_reject(
            open.straight(qg, back, STRAIGHT_STEPS, &rrt, &straddle, rng, &mut checks),
            Stage::Pick,
            || format!("no straight approach to `{oname}`"),
        )?;
        let q_pre = end(&back_path)?;
        let open_all = m.open(self.obstacles.workspace.clone());
        if !open_all.free(&q_pre) {
            self.reject(Stage::Pick, || {
                format!("every pre-grasp configuration for `{oname}` collides")
            });
            return None;
        }
        let mut grasp_path = back_path;
        grasp_path.waypoints.reverse();
        Some((grasp_path, q_pre))
    }

    /// The lift from the grasp configuration `qg` (the tool at `tool`): straight up, first
    /// clear of what the object rests on (those obstacles unchecked), then the rest with full
    /// checks; when that is blocked (a board above), a [`Pull`] out first. The paths with the
    /// obstacles each leaves unchecked, and the arm's values at the top.
    #[allow(clippy::type_complexity)]
    fn lift(
        &mut self,
        m: &GraspMotions,
        qg: &[f32],
        tool: Pose,
        rng: &mut fastrand::Rng,
    ) -> Option<(Vec<(JointPath, Vec<String>)>, Vec<f32>)> {
        let unstick = UNSTICK.min(self.c.lift);
        let up = [Vector::Z * unstick, Vector::Z * (self.c.lift - unstick)];
        let straight_up = self.lift_moves(m, qg, &up, &[1, STRAIGHT_STEPS], rng);
        let blocked = match straight_up {
            Ok(lift) => return Some(lift),
            Err(e) => e,
        };
        let pulled = self.pull_for_pick(tool).map(|pull| {
            let steps = [1, pull.slide_steps(), STRAIGHT_STEPS];
            self.lift_moves(m, qg, &pull.moves(self.c.lift), &steps, rng)
        });
        match pulled {
            Some(Ok(lift)) => Some(lift),
            Some(Err(e)) => {
                let oname = self.object_name();
                self.reject(Stage::Pick, || {
                    format!("no collision-free lift of `{oname}`: {blocked}; pulled out: {e}")
                });
                None
            }
            None => {
                let oname = self.object_name();
                self.reject(Stage::Pick, || {
                    format!("no collision-free lift of `{oname}`: {blocked}")
                });
                None
            }
        }
    }

    /// The pull out of the task's object, grasped with the tool at `tool`, where it rests.
    fn pull_for_pick(&self, tool: Pose) -> Option<Pull> {
        let o = self.object?;
        let shape = self.world.object(o).shape.clone();
        let pose = self.world.object_shape_pose(o);
        let obstacles = &self.obstacles.workspace_but_object;
        Pull::find(&*shape, &pose, &tool, self.c.lift, obstacles)
    }

    /// Straight moves of the tool from `qg` holding the object, each in its number of `steps`:
    /// the first with what the object rests on unchecked, the others with full checks.
    #[allow(clippy::type_complexity)]
    fn lift_moves(
        &self,
        m: &GraspMotions,
        qg: &[f32],
        moves: &[Vector],
        steps: &[usize],
        rng: &mut fastrand::Rng,
    ) -> Result<(Vec<(JointPath, Vec<String>)>, Vec<f32>), String> {
        let rrt = self.cfg.rrt.clone();
        let mut checks = 0;
        let never = |_: &[f32]| true;
        let closed = m.closed(self.obstacles.workspace_but_object.clone());
        let resting: Vec<&str> = self.resting_on.iter().map(String::as_str).collect();
        let held_free_of_rest = m.holding(Arc::new(
            self.obstacles.workspace_but_object.without(&resting),
        ));
        let hold_check = |qa: &[f32]| held_free_of_rest.free(qa);
        let held = m.holding(self.obstacles.workspace_but_object.clone());
        let mut out = Vec::new();
        let mut q = qg.to_vec();
        for (k, (&offset, &n)) in moves.iter().zip(steps).enumerate() {
            let path = if offset.length() <= 1e-4 {
                JointPath {
                    waypoints: vec![q.clone()],
                }
            } else if k == 0 {
                closed.straight(&q, offset, n, &rrt, &hold_check, rng, &mut checks)?
            } else {
                held.straight(&q, offset, n, &rrt, &never, rng, &mut checks)?
            };
            q = path.waypoints.last().cloned().ok_or("an empty path")?;
            let ignored = if k == 0 {
                self.resting_on.clone()
            } else {
                Vec::new()
            };
            out.push((path, ignored));
        }
        Ok((out, q))
    }

    /// Plans the approach of grasp choice `grasp`'s pick (RRT-Connect from the arm's start to
    /// the pre-grasp), once; on failure the choice is dropped for good.
    pub(super) fn ensure_approach(&mut self, grasp: usize) -> bool {
        let Some(Some(plan)) = self.pick_cache.get(&grasp) else {
            return self.held;
        };
        if plan.approach.is_some() {
            return true;
        }
        let q_pre = plan.q_pre.clone();
        let Some(m) = self.grasp_motions(grasp) else {
            return false;
        };
        let open_all = m.open(self.obstacles.workspace.clone());
        let mut rng = fastrand::Rng::with_seed(self.rng.u64(..));
        match self.plan_motion(&open_all, &m.q0, &q_pre, &mut rng) {
            Ok((p, _)) => {
                if let Some(Some(plan)) = self.pick_cache.get_mut(&grasp) {
                    plan.approach = Some(p);
                }
                true
            }
            Err(e) => {
                let oname = self.object_name();
                if e.error == RrtError::InvalidStart {
                    self.rejections.start_reason = Some(e.to_string());
                }
                self.reject(Stage::Trajectory, || {
                    format!("no collision-free approach to `{oname}`: {e}")
                });
                self.pick_cache.insert(grasp, None);
                self.failed_choices.insert(grasp);
                false
            }
        }
    }

    /// The trajectories of pick `p` with the motions `m` of its grasp choice: approach (the
    /// pre-grasp alone when not planned), grasp, lift.
    pub(super) fn pick_trajectories(&self, m: &GraspMotions, p: &PickPlan) -> Vec<Trajectory> {
        let pose = self.object.map(|o| self.world.object_pose(o));
        let approach = p.approach.clone().unwrap_or_else(|| JointPath {
            waypoints: vec![p.q_pre.clone()],
        });
        let mut out = vec![
            m.record(Phase::Approach, approach, Grip::Open),
            m.record(Phase::Grasp, p.grasp.clone(), Grip::Around(pose)),
        ];
        for (path, ignored) in &p.lift {
            out.push(m.record(Phase::Lift, path.clone(), Grip::Holding(ignored.clone())));
        }
        out
    }
}
