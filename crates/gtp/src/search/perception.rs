//! What the human reaches and may see at an effort level, as the candidate points' filters
//! test it (microseconds a point), by the rules of `geometry::perception`: a hand at the
//! object, reach spheres around the shoulders of the stances a level allows, and the field of
//! view widened by the head's turn, with a clear line of sight.

use geometry::{effort, perception};
use parry3d::math::Vector;
use parry3d::query::{Ray, RayCast};

use super::Search;

impl Search {
    /// Points the human's arms reach from at effort levels 1 up to `level` (the shoulders of
    /// every stance those levels allow, [`perception::reach_origins`]).
    fn reach_origins_upto(&mut self, level: u8) -> Vec<Vector> {
        let Some(h) = self.human else {
            return Vec::new();
        };
        let mut out = Vec::new();
        for l in 1..=level {
            let world = &self.world;
            let origins = self.human_reach_origins.entry(l).or_insert_with(|| {
                effort::stances(world, h, l, None)
                    .iter()
                    .flat_map(|st| perception::reach_origins(world, h, st))
                    .collect()
            });
            out.extend(origins.iter().copied());
        }
        out
    }

    /// Whether the human reaches the task's object centred at `p` at effort `level` or lower
    /// (level 0: a hand at the object; 1 and more: within arm's reach of a shoulder of a
    /// stance the level allows; of a free hand's shoulder while `free_hands_only`).
    pub(super) fn human_reaches(&mut self, p: Vector, level: u8) -> bool {
        let Some(h) = self.human else { return false };
        if perception::hand_at(&self.world, h, p, self.object_inner_radius) {
            return true;
        }
        if level == 0 {
            return false;
        }
        let mut origins = self.reach_origins_upto(level);
        if let Some(free) = &self.free_hands_only {
            // Every stance gives the shoulders in `shoulder_links` order.
            let n = free.len().max(1);
            origins = (origins.into_iter().enumerate())
                .filter_map(|(i, o)| free[i % n].then_some(o))
                .collect();
        }
        perception::within_reach(&self.world, h, &origins, p)
    }

    /// Whether the eye may see `p` at effort `level`: inside the field of view (level 0) or the
    /// head's reach (level 1 and more), with a clear line of sight through the obstacles.
    pub(super) fn may_see(&self, p: Vector, level: u8) -> bool {
        let Some(h) = self.human else { return true };
        let eye = self.world.eye_pose(h);
        let d = eye.rotation.inverse() * (p - eye.translation);
        if d.x <= 0.0 {
            // Behind the eye: only a turn of the torso or more helps.
            if level < 2 {
                return false;
            }
        } else {
            let [ha, va] = perception::view_half_angles(&self.world, h, level);
            if d.y.atan2(d.x).abs() > ha || d.z.atan2(d.x).abs() > va {
                return level >= 2;
            }
        }
        self.line_of_sight(eye.translation, p)
    }

    /// Whether the segment `from`-`to` is clear of every obstacle but the task's object and
    /// the human's own body.
    pub(super) fn line_of_sight(&self, from: Vector, to: Vector) -> bool {
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
        let obstacles = &self.obstacles.scene_but_object;
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
}
