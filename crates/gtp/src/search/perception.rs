//! What the human reaches and may see at an effort level, as the candidate points' filters
//! test it (microseconds a point): reach spheres around the shoulders of the stances a level
//! allows, and the field of view widened by the head's turn, with a clear line of sight.

use geometry::effort;
use parry3d::math::Vector;
use parry3d::query::{Ray, RayCast};

use super::Search;

/// A hand counts as at a point within this distance (metres): level 0's reach.
const HAND_TOLERANCE: f32 = 0.1;

impl Search {
    /// Shoulder positions of the human's stances at effort levels up to `level`.
    fn shoulders_upto(&mut self, level: u8) -> Vec<Vector> {
        let Some(h) = self.human else {
            return Vec::new();
        };
        let mut out = Vec::new();
        for l in 1..=level {
            let world = &self.world;
            let shoulders = self.human_shoulders.entry(l).or_insert_with(|| {
                let mut s = Vec::new();
                for st in effort::stances(world, h, l, None) {
                    s.extend(effort::shoulders(world, h, st.base, &st.q));
                }
                s
            });
            out.extend(shoulders.iter().copied());
        }
        out
    }

    /// Whether the human reaches `p` at effort `level` or lower (level 0: at the hand; 1 and
    /// more: within arm's reach of a shoulder of a stance the level allows).
    pub(super) fn human_reaches(&mut self, p: Vector, level: u8) -> bool {
        let Some(h) = self.human else { return false };
        let info = self.world.agent(h);
        let reach = info.reach;
        let st = self.world.agent_state(h);
        if info
            .hand_links
            .iter()
            .any(|&l| (st.link_poses()[l].translation - p).length() <= HAND_TOLERANCE)
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
    pub(super) fn may_see(&self, p: Vector, level: u8) -> bool {
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
