//! Pulling an object out from under what is above it (a book standing between a bookshelf's
//! boards): when the straight lift is blocked, the object is raised just clear of its support,
//! pulled back horizontally along the gripper's approach until its way up is free, then lifted.
//! A placement under something is reached the same way, reversed: down in front of it, pushed
//! in, set down.

use geometry::collision::StaticObstacles;
use parry3d::math::{Pose, Vector};
use parry3d::shape::Shape;

/// How far the object is raised before it is pulled out or after it is pushed in (metres):
/// clear of the support it slides over, under the board above.
pub(super) const PULL_RAISE: f32 = 0.01;
/// The longest pull tried (metres).
const MAX_PULL: f32 = 0.5;
/// Pull lengths are tried this far apart, and the way up is tested at this spacing (metres).
const PULL_STEP: f32 = 0.02;
/// A pull needs an approach this close to the horizontal (its horizontal part, of 1).
const MIN_HORIZONTAL: f32 = 0.5;
/// The slide is followed in steps of at most this length (metres).
const SLIDE_STEP: f32 = 0.04;

/// A pull out of (or push into) a place under something: the moves of the tool from where the
/// object rests, in order: raised, slid out, lifted.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(super) struct Pull {
    /// Horizontal unit vector back along the gripper's approach.
    pub(super) direction: Vector,
    /// How far the object slides (metres).
    pub(super) length: f32,
}

impl Pull {
    /// The pull for an object `shape` at `pose` grasped with the tool at `tool`: the shortest
    /// slide back along the approach after which the object, raised by [`PULL_RAISE`], rises
    /// by `lift` free of `obstacles`. `None` for an approach from above or below, or when no
    /// slide up to [`MAX_PULL`] frees the way up.
    pub(super) fn find(
        shape: &dyn Shape,
        pose: &Pose,
        tool: &Pose,
        lift: f32,
        obstacles: &StaticObstacles,
    ) -> Option<Pull> {
        let direction = back_horizontal(tool)?;
        let rises = (lift / PULL_STEP).ceil() as usize;
        let free_at = |offset: Vector| {
            let p = Pose::from_parts(pose.translation + offset, pose.rotation);
            obstacles
                .first_hit(&p, shape, &shape.compute_aabb(&p))
                .is_none()
        };
        let pulls = (MAX_PULL / PULL_STEP).round() as usize;
        let length = (1..=pulls).map(|k| k as f32 * PULL_STEP).find(|&s| {
            (0..=rises).all(|k| {
                let up = PULL_RAISE + lift * k as f32 / rises as f32;
                free_at(direction * s + Vector::Z * up)
            })
        })?;
        Some(Pull { direction, length })
    }

    /// The tool's moves from the resting pose: raise, slide, lift by `lift`.
    pub(super) fn moves(&self, lift: f32) -> [Vector; 3] {
        [
            Vector::Z * PULL_RAISE,
            self.direction * self.length,
            Vector::Z * lift,
        ]
    }

    /// Steps in which the slide is followed.
    pub(super) fn slide_steps(&self) -> usize {
        ((self.length / SLIDE_STEP).ceil() as usize).max(1)
    }
}

/// The horizontal unit vector back along the approach (the tool frame's -x), `None` when the
/// approach is mostly vertical.
fn back_horizontal(tool: &Pose) -> Option<Vector> {
    let back = -(tool.rotation * Vector::X);
    let h = Vector::new(back.x, back.y, 0.0);
    (h.length() >= MIN_HORIZONTAL).then(|| h.normalize())
}

#[cfg(test)]
mod tests {
    use super::*;
    use geometry::collision::Obstacle;
    use parry3d::math::Rotation;
    use parry3d::shape::{Cuboid, SharedShape};
    use std::f32::consts::FRAC_PI_2;

    /// A board 5 cm above a book standing on the floor of a compartment 0.3 m deep (along y,
    /// open towards -y).
    fn board_above() -> StaticObstacles {
        StaticObstacles::new(vec![Obstacle {
            name: "board".into(),
            shape: SharedShape::new(Cuboid::new(Vector::new(0.4, 0.15, 0.01))),
            pose: Pose::from_translation(Vector::new(0.0, 0.15, 0.36)),
        }])
    }

    fn book() -> (Cuboid, Pose) {
        // 4 cm thick, 20 cm deep, 30 cm tall; its front at y = 0.02.
        let b = Cuboid::new(Vector::new(0.02, 0.1, 0.15));
        (b, Pose::from_translation(Vector::new(0.0, 0.12, 0.15)))
    }

    /// The tool at the book's front edge, approaching from -y towards +y (its x along +y).
    fn from_the_front() -> Pose {
        Pose::from_parts(
            Vector::new(0.0, 0.03, 0.25),
            Rotation::from_rotation_z(FRAC_PI_2),
        )
    }

    #[test]
    fn a_book_under_a_board_is_pulled_out_until_its_way_up_is_free() {
        let (b, pose) = book();
        let tool = from_the_front();
        let pull = Pull::find(&b, &pose, &tool, 0.15, &board_above()).expect("a pull");
        assert!((pull.direction - Vector::new(0.0, -1.0, 0.0)).length() < 1e-5);
        // The board's front is at y = 0; the book's back at 0.22: a pull of 0.22 or a step more.
        assert!(
            pull.length >= 0.22 - 1e-4 && pull.length <= 0.24 + 1e-4,
            "{}",
            pull.length
        );
        let m = pull.moves(0.15);
        assert!((m[1].length() - pull.length).abs() < 1e-5 && m[1].z == 0.0);
        assert!(pull.slide_steps() >= 6);
    }

    #[test]
    fn an_approach_from_above_has_no_pull() {
        let (b, pose) = book();
        // Tool x pointing down.
        let tool = Pose::from_parts(
            Vector::new(0.0, 0.12, 0.32),
            Rotation::from_rotation_y(FRAC_PI_2),
        );
        assert_eq!(Pull::find(&b, &pose, &tool, 0.15, &board_above()), None);
    }

    #[test]
    fn no_pull_when_the_way_out_is_blocked_everywhere() {
        let (b, pose) = book();
        let tool = from_the_front();
        // A ceiling over the whole pull.
        let low = StaticObstacles::new(vec![Obstacle {
            name: "ceiling".into(),
            shape: SharedShape::new(Cuboid::new(Vector::new(1.0, 1.0, 0.01))),
            pose: Pose::from_translation(Vector::new(0.0, 0.0, 0.36)),
        }]);
        assert_eq!(Pull::find(&b, &pose, &tool, 0.15, &low), None);
    }
}
