//! Candidate points of an effort level, the outermost stage after the level: a grid on the
//! support surfaces (or in the air between the agents, for a hand-over), filtered by the robot's
//! reach and the human's reach and view at that level (directly, or by the mightability maps),
//! then ordered best first.

use geometry::effort;
use geometry::scene::ObjectId;
use parry3d::math::{Pose, Vector};
use parry3d::shape::Shape;

use crate::task::TaskKind;

use super::{Search, Stage};

/// Candidate points of a hiding task: distance bins (metres) within which the best hidden
/// come first.
const BIN: f32 = 0.5;

/// A hand-over holds the object at least this far from the person's eyes (metres): nearer,
/// it is in their face, and it fills more than their field of view, so that how much of it
/// they see depends on where they look (a book held out 19 cm from a member's eyes in a random
/// room: 0.92 of it seen by the planner's rays, 0.06 by `htngtp check`'s).
const HAND_OVER_EYE_CLEARANCE: f32 = 0.3;

/// The most points one candidate grid holds (a surface, or the air between two agents).
const MAX_GRID_POINTS: f32 = 100_000.0;

impl Search {
    /// Candidate points for level `level`, not tried at a lower level, best first.
    pub(super) fn candidate_points(&mut self, level: u8) -> Vec<Vector> {
        let robot = self.setup.agent;
        let robot_shoulders = effort::shoulders(
            &self.world,
            robot,
            self.world.agent_state(robot).base,
            &self.q0_full,
        );
        let kind = self.task.kind;
        if kind == TaskKind::Pick {
            // Where the object is.
            return self
                .object
                .map(|o| self.world.object_pose(o).translation)
                .into_iter()
                .collect();
        }
        let raw = if kind.hands_over() {
            let Some(h) = self.human else {
                return Vec::new();
            };
            let eye = self.world.eye_pose(h).translation;
            let reach = self.world.agent(robot).reach;
            hand_over_grid(eye, &robot_shoulders, reach)
        } else {
            self.surface_grid()
        };
        // A give offers the object within reach of a free hand, which the person's take
        // uses, where one hand holds something; within reach of either where no point is.
        self.free_hands_only = self.human.filter(|_| kind == TaskKind::Give).and_then(|h| {
            let free = crate::target::free_shoulders(&self.world, h);
            (free.contains(&true) && free.contains(&false)).then_some(free)
        });
        let mut pts = self.reachable_points(raw.clone(), level, &robot_shoulders);
        if pts.is_empty() && self.free_hands_only.take().is_some() {
            pts = self.reachable_points(raw, level, &robot_shoulders);
        }
        let mut pts = self.best_first(pts, &robot_shoulders);
        pts.truncate(self.c.max_points);
        if pts.is_empty() {
            let r = self.no_points_reason(level);
            self.reject(Stage::Points, || r);
        }
        pts
    }

    /// Per support surface, its point nearest `from` (horizontally) where the object would
    /// meet the task's constraints on the human at its highest effort level (hidden from their
    /// view, out of their reach), whether the robot reaches it or not: where a put-away's base
    /// moves head.
    pub(super) fn places_for_human(&mut self, from: Vector) -> Vec<Vector> {
        let Some(&level) = self.levels.last() else {
            return Vec::new();
        };
        let lift = Vector::Z * self.object_half_height();
        let flat = |p: &Vector| Vector::new(p.x - from.x, p.y - from.y, 0.0).length();
        let mut places = Vec::new();
        for mut grid in self.surface_grids() {
            grid.sort_by(|a, b| flat(a).total_cmp(&flat(b)));
            places.extend(
                grid.into_iter().find(|&p| {
                    self.meets_human_constraints(p + lift, level) && self.air_is_free(p)
                }),
            );
        }
        places
    }

    /// The grid points on the support surfaces a placement may use: the task's support, or
    /// every surface but the object's own, 3 cm in from their edges.
    fn surface_grid(&self) -> Vec<Vector> {
        self.surface_grids().concat()
    }

    /// [`Search::surface_grid`], surface by surface.
    fn surface_grids(&self) -> Vec<Vec<Vector>> {
        let supports: Vec<ObjectId> = match (self.task.kind, self.task.support) {
            (TaskKind::PlaceOn, Some(s)) => vec![s],
            _ => self
                .world
                .object_ids()
                .filter(|&id| Some(id) != self.object && !self.world.object(id).surfaces.is_empty())
                .collect(),
        };
        let mut grids = Vec::new();
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
                let mut grid = Vec::new();
                for i in 0..=nx {
                    for j in 0..=ny {
                        let local = surf.centre
                            + Vector::new(ox + i as f32 * step, oy + j as f32 * step, 0.0);
                        grid.push(pose.transform_point(local));
                    }
                }
                grids.push(grid);
            }
        }
        grids
    }

    /// The points of `raw` not tried at a lower level that the robot reaches and that meet
    /// the task's reach and view constraints at `level` (the object's centre tested, above the
    /// point on a surface), and, for a hand-over, with free space for the object.
    fn reachable_points(
        &mut self,
        raw: Vec<Vector>,
        level: u8,
        robot_shoulders: &[Vector],
    ) -> Vec<Vector> {
        let kind = self.task.kind;
        let obj_h = self.object_half_height();
        let robot_reach = self.world.agent(self.setup.agent).reach;
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
                // From where the robot stands: its arm (levels 0 and 1); the base moves are
                // tried apart.
                if !at_most(m.reach_level(robot, centre), c.robot_effort.min(1))
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
            if !robot_shoulders
                .iter()
                .any(|s| (*s - centre).length() <= robot_reach)
            {
                continue;
            }
            if self.meets_human_constraints(centre, level) && self.air_is_free(p) {
                pts.push(p);
            }
        }
        pts
    }

    /// Whether `centre` meets the task's constraints on the human's reach and view at `level`,
    /// by the direct tests.
    fn meets_human_constraints(&mut self, centre: Vector, level: u8) -> bool {
        let c = &self.c;
        let (reach_within, unreachable_within) = (c.reach_within, c.unreachable_within);
        let (min_vis, max_vis, max_effort) = (c.min_visibility, c.max_visibility, c.max_effort);
        if let Some(k) = reach_within
            && !self.human_reaches(centre, k.min(level))
        {
            return false;
        }
        if let Some(k) = unreachable_within
            && self.human_reaches(centre, k)
        {
            return false;
        }
        if min_vis.is_some_and(|v| v > 0.0) && !self.may_see(centre, level) {
            return false;
        }
        // A clear line of sight to the object's centre: it would show.
        !(max_vis.is_some_and(|v| v < 0.05) && self.may_see(centre, max_effort))
    }

    /// For a hand-over, whether the air at `p` is free for the object (a 3 cm ball); always
    /// for a placement.
    fn air_is_free(&self, p: Vector) -> bool {
        if !self.task.kind.hands_over() {
            return true;
        }
        let ball = parry3d::shape::Ball::new(0.03);
        let pose = Pose::from_translation(p);
        let aabb = ball.compute_aabb(&pose);
        self.obstacles
            .workspace_but_object
            .first_hit(&pose, &ball, &aabb)
            .is_none()
    }

    /// The object's largest half extent (5 cm without an object).
    fn object_half_height(&self) -> f32 {
        self.object
            .map(|o| self.world.object(o).local_aabb.half_extents().max_element())
            .unwrap_or(0.05)
    }

    /// `pts` best first: by distance to an anchor (near the human for tasks that serve them,
    /// near the object otherwise) in bins of [`BIN`] metres, then, hiding, the best hidden.
    fn best_first(&self, pts: Vec<Vector>, robot_shoulders: &[Vector]) -> Vec<Vector> {
        let anchor = self.anchor(robot_shoulders);
        // Distance to the anchor in bins of BIN metres, then the hiding score.
        let mut scored: Vec<((usize, usize, f32), Vector)> = pts
            .iter()
            .map(|p| {
                let d = (*p - anchor).length();
                (((d / BIN) as usize, self.shown(*p), d), *p)
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
        scored.into_iter().map(|(_, p)| p).collect()
    }

    /// Where the best points are nearest: between the agents (show), the human's shoulders
    /// (other tasks that serve them), elsewhere where the object is: the least carrying, and
    /// likely within reach of the arm that holds or will pick it.
    fn anchor(&self, robot_shoulders: &[Vector]) -> Vector {
        let mean =
            |v: &[Vector]| v.iter().fold(Vector::ZERO, |a, b| a + *b) / v.len().max(1) as f32;
        let kind = self.task.kind;
        match (self.human, kind) {
            (
                Some(h),
                TaskKind::Show
                | TaskKind::Give
                | TaskKind::MakeAccessible
                | TaskKind::PickAndMakeAccessible,
            ) => {
                let st = self.world.agent_state(h);
                let mid = mean(&effort::shoulders(&self.world, h, st.base, &st.q));
                if kind == TaskKind::Show {
                    // Between the two agents.
                    (mid + mean(robot_shoulders)) * 0.5
                } else {
                    mid
                }
            }
            _ => match self.object {
                Some(o) => self.world.object_pose(o).translation,
                None => mean(robot_shoulders),
            },
        }
    }

    /// Hiding: how much of the object placed at `p` may show, by a cheap score (clear lines of
    /// sight from the human's eyes to the top corners and centre of the object's box there),
    /// so that the pixel-visibility test, the costly one, mostly confirms. 0 when not hiding.
    fn shown(&self, p: Vector) -> usize {
        let hiding = self.c.max_visibility.is_some() && !self.task.kind.hands_over();
        let Some(h) = self.human.filter(|_| hiding) else {
            return 0;
        };
        let eye = self.world.eye_pose(h).translation;
        let r = self
            .object
            .map(|o| {
                let h = self.world.object(o).local_aabb.half_extents();
                h.x.max(h.y)
            })
            .unwrap_or(0.05);
        let top = p + Vector::Z * (2.0 * self.object_half_height());
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
}

/// The hand-over grid: the box around the human's eye and the robot's shoulders (30 cm wider,
/// 60 cm lower, 20 cm higher, at least 50 cm above the floor), clipped to the robot's `reach`,
/// without the points nearer the eye than [`HAND_OVER_EYE_CLEARANCE`].
fn hand_over_grid(eye: Vector, robot_shoulders: &[Vector], reach: f32) -> Vec<Vector> {
    let mut lo = eye.min(robot_shoulders.iter().fold(eye, |a, b| a.min(*b)));
    let mut hi = eye.max(robot_shoulders.iter().fold(eye, |a, b| a.max(*b)));
    lo -= Vector::new(0.3, 0.3, 0.6);
    hi += Vector::new(0.3, 0.3, 0.2);
    lo.z = lo.z.max(0.5);
    let mut grid = bounded_grid(lo, hi, robot_shoulders, reach);
    grid.retain(|p| (*p - eye).length() >= HAND_OVER_EYE_CLEARANCE);
    grid
}

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

/// A point's key on a 1 cm lattice: points tried at a lower level are not tried again.
pub(super) fn key(p: Vector) -> (i32, i32, i32) {
    (
        (p.x * 100.0).round() as i32,
        (p.y * 100.0).round() as i32,
        (p.z * 100.0).round() as i32,
    )
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

    /// No hand-over point is in the person's face.
    #[test]
    fn hand_over_points_keep_clear_of_the_eye() {
        let eye = Vector::new(1.0, 0.0, 1.2);
        let shoulders = [Vector::new(0.0, -0.2, 1.2), Vector::new(0.0, 0.2, 1.2)];
        let pts = hand_over_grid(eye, &shoulders, 0.95);
        assert!(pts.len() > 100, "{} points", pts.len());
        let nearest = pts
            .iter()
            .map(|p| (*p - eye).length())
            .fold(f32::MAX, f32::min);
        assert!(
            (HAND_OVER_EYE_CLEARANCE..0.35).contains(&nearest),
            "{nearest}"
        );
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
