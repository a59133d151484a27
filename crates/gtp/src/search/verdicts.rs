//! The human-related constraints of a placement or hand-over, the deepest but the trajectories:
//! exact reach of the object by the human (the `reachable` shared literal's test), then pixel
//! visibility (the costly test, last). For a placement they do not depend on the grasp (the arm
//! returns to where it was), so each placement's [`Verdict`] is remembered.

use geometry::effort;
use geometry::scene::{AgentId, ObjectId};
use geometry::visibility::{self, Aim};
use geometry::world::World;
use parry3d::math::{Pose, Vector};

use super::cursor::PlacementKey;
use super::{Search, Stage};

/// What the human-related constraints say of a placement so far.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(super) enum Verdict {
    /// A constraint fails: the placement fails for every grasp.
    Failed,
    /// The cheap checks passed (reach, coarse visibility); the full pixel measure is to come.
    Prechecked,
    /// The constraints hold, with the visibility measured (`None` when none is asked).
    Holds(Option<f32>),
}

/// The coarse visibility grid (rays per side) of a hiding task's precheck.
const COARSE_RESOLUTION: usize = 8;

/// How far below the floor the robot is put for [`Search::hand_over_may_show`]'s bound (metres):
/// out of every view.
const FAR_BELOW: f32 = 1000.0;

/// How much the bound of [`Search::hand_over_may_show`] may fall short of the visibility needed
/// and still pass: the object held ends where inverse kinematics puts the hand, within
/// millimetres of the pose measured, which moves a few of its pixels.
const HAND_OVER_BOUND_SLACK: f32 = 0.02;

impl Search {
    /// The verdict remembered for `key`, if any.
    pub(super) fn verdict(&self, key: PlacementKey) -> Option<Verdict> {
        self.verdicts.get(&key).copied()
    }

    /// For placing tasks: whether some orientation at the current point meets the human-related
    /// constraints (reach, visibility). Those do not depend on the grasp (the arm returns to
    /// where it started), so they are measured once per orientation, before any grasp is tried
    /// at the point, stopping at the first orientation that passes; a point where none passes
    /// costs no grasp. The verdicts are remembered for the tuples that follow.
    pub(super) fn point_has_placement(&mut self) -> bool {
        let (Some(o), Some(_)) = (self.object, self.human) else {
            return true;
        };
        if !self.task.kind.places() {
            return true;
        }
        let level = self.levels[self.cursor.level];
        let orients = self.cursor.orientations.clone().unwrap_or_default();
        for (oidx, orient) in orients.iter().enumerate() {
            let key = self.cursor.placement(oidx);
            let v = match self.verdict(key) {
                Some(v @ (Verdict::Failed | Verdict::Holds(_))) => v,
                _ => {
                    let after = self.released_world(o, orient.pose);
                    let v = self.placement_verdict(&after, level);
                    self.verdicts.insert(key, v);
                    v
                }
            };
            if v != Verdict::Failed {
                return true;
            }
        }
        false
    }

    /// For a hand-over that must be seen: whether the object held at `pose` may be visible
    /// enough, measured with the robot out of the way (its arm only hides more of the object,
    /// so that measure bounds what any grasp and arm posture leaves). Once per hand-over pose
    /// (remembered under `key`), after the first grasp whose arm posture reaches it (most
    /// poses are out of reach, cheaper to find than any visibility): one `pick-and-show` of a
    /// random room spent 22,702 IK calls, each followed by a pixel measure, on poses seen 0.87
    /// where 0.9 was needed.
    pub(super) fn hand_over_may_show(
        &mut self,
        key: PlacementKey,
        o: ObjectId,
        pose: Pose,
        level: u8,
    ) -> bool {
        let (Some(min), Some(h)) = (self.c.min_visibility, self.human) else {
            return true;
        };
        if let Some(v) = self.verdict(key) {
            return v != Verdict::Failed;
        }
        let mut world = self.world.clone();
        let away = Pose::from_parts(Vector::new(0.0, 0.0, -FAR_BELOW), Default::default());
        world.set_agent_config(self.setup.agent, away, &self.q0_full);
        world.set_object_pose(o, pose);
        self.stats.visibility_checks += 1;
        let resolution = self.cfg.visibility_resolution;
        // The first view (head as it is, turned, a stance) that shows enough ends the measure.
        let enough = Some(min - HAND_OVER_BOUND_SLACK);
        let bound = visibility_upto(&world, h, o, level, resolution, enough);
        let v = if bound + HAND_OVER_BOUND_SLACK < min {
            self.shown_too_little(bound, min, "hand-over pose");
            Verdict::Failed
        } else {
            Verdict::Prechecked
        };
        self.verdicts.insert(key, v);
        v != Verdict::Failed
    }

    /// The human-related constraints on the world after a tuple: reach, then pixel visibility
    /// (the expensive test, last): [`Verdict::Holds`] or [`Verdict::Failed`].
    pub(super) fn placement_verdict(&mut self, after: &World, level: u8) -> Verdict {
        if !self.placement_precheck(after, level) {
            return Verdict::Failed;
        }
        self.placement_visibility(after, level)
    }

    /// The cheap part of [`Search::placement_verdict`]: exact reach of the object by the human
    /// and, for hiding, pixel visibility on a coarse grid (one ray reaching the object shows
    /// it, so the coarse grid proves most failures at a sixteenth of the cost). `false` when a
    /// constraint fails.
    pub(super) fn placement_precheck(&mut self, after: &World, level: u8) -> bool {
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
            && self.cfg.visibility_resolution > COARSE_RESOLUTION
        {
            let v = visibility_upto(after, h, o, self.c.max_effort, COARSE_RESOLUTION, Some(max));
            if v > max {
                self.hidden_failed(v, max);
                return false;
            }
        }
        true
    }

    /// Records a `what` (placement, hand-over pose) that shows the object too little.
    fn shown_too_little(&mut self, v: f32, min: f32, what: &str) {
        let oname = self.object_name();
        let hname = self.human_name();
        let best = self.rejections.best_visibility.map_or(v, |b| b.max(v));
        self.rejections.best_visibility = Some(best);
        self.reject(Stage::Visibility, || {
            format!(
                "no {what} of `{oname}` visible enough to {hname}: best visibility {best:.2} \
                 (needs >= {min:.2})"
            )
        });
    }

    /// Records a hiding place that shows too much.
    fn hidden_failed(&mut self, v: f32, max: f32) {
        let hname = self.human_name();
        let best = self.rejections.best_visibility.map_or(v, |b| b.min(v));
        self.rejections.best_visibility = Some(best);
        self.reject(Stage::Visibility, || {
            format!(
                "no placement hidden from {hname}: best visibility {best:.2} (needs <= {max:.2})"
            )
        });
    }

    /// The rest of [`Search::placement_verdict`] once the precheck passed: pixel visibility
    /// at full resolution. [`Verdict::Holds`] when it meets the thresholds.
    pub(super) fn placement_visibility(&mut self, after: &World, level: u8) -> Verdict {
        // Pixel visibility, the expensive test, last of the constraints.
        if self.c.min_visibility.is_none() && self.c.max_visibility.is_none() {
            return Verdict::Holds(None);
        }
        let vis_level = if self.c.max_visibility.is_some() {
            self.c.max_effort
        } else {
            level
        };
        let v = self.visibility_at(after, vis_level);
        if let Some(min) = self.c.min_visibility
            && v < min
        {
            self.shown_too_little(v, min, "placement");
            return Verdict::Failed;
        }
        if let Some(max) = self.c.max_visibility
            && v > max
        {
            self.hidden_failed(v, max);
            return Verdict::Failed;
        }
        Verdict::Holds(Some(v))
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

    /// Visibility of the object for the human in `world` at effort `level` (the best over what
    /// the level allows: the head as it is, turned to the object, or the stances of level 2+).
    fn visibility_at(&mut self, world: &World, level: u8) -> f32 {
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
    let view = |w: &World, aim| {
        visibility::visibility_for_agent_upto(w, h, o, aim, resolution, stop_above).fraction()
    };
    let mut v = view(world, Aim::Current);
    if done(v) {
        return v;
    }
    if level >= 1 {
        v = v.max(view(world, Aim::AtTarget));
        if done(v) {
            return v;
        }
    }
    for l in 2..=level {
        for st in effort::stances(world, h, l, None) {
            let mut w = world.clone();
            w.set_agent_config(h, st.base, &st.q);
            v = v.max(view(&w, Aim::AtTarget));
            if done(v) {
                return v;
            }
        }
    }
    v
}
