//! The PR2 parallel gripper as collision boxes in its tool frame.
//!
//! Convention (a gripper tool frame as ROS robots define it): x points forward out of the palm (the
//! approach direction), y is the axis along which the two fingers close, z completes the frame.
//! The tool frame sits between the fingertips, 0.18 m ahead of the palm frame
//! (`../shared/notes/geometry-facts.md` beside the checkout, section 1).

use parry3d::math::{Pose, Vector};
use parry3d::query;
use parry3d::shape::{Cuboid, Shape};

/// Distance from the palm frame (wrist roll link) to the tool frame along x.
pub const PALM_TO_TOOL: f32 = 0.18;
/// The widest jaw opening of the PR2 gripper (metres).
pub const MAX_OPENING: f32 = 0.09;

/// The gripper's collision boxes for one jaw opening.
#[derive(Clone, Debug)]
pub struct Gripper {
    /// Each box with its pose in the tool frame.
    pub boxes: Vec<(Pose, Cuboid)>,
    /// The jaw opening these boxes were built for.
    pub opening: f32,
}

impl Gripper {
    /// The palm and two fingers with the jaws `opening` metres apart (clamped to
    /// `0 ..= MAX_OPENING`).
    ///
    /// Palm: the palm link's bounds `(0.029, -0.05, -0.024) .. (0.125, 0.051, 0.024)` in the palm
    /// frame. Fingers: 0.12 long from 0.077 ahead of the palm frame, 0.02 thick along y (outside
    /// the opening), 0.03 wide along z.
    pub fn new(opening: f32) -> Gripper {
        let opening = opening.clamp(0.0, MAX_OPENING);
        let palm_min = Vector::new(0.029 - PALM_TO_TOOL, -0.05, -0.024);
        let palm_max = Vector::new(0.125 - PALM_TO_TOOL, 0.051, 0.024);
        let finger_x = (0.077 - PALM_TO_TOOL, 0.077 + 0.12 - PALM_TO_TOOL);
        let (thick, wide) = (0.02, 0.03);
        let mut boxes = vec![aabb_box(palm_min, palm_max)];
        for side in [-1.0f32, 1.0] {
            let inner = side * opening / 2.0;
            let outer = side * (opening / 2.0 + thick);
            let min = Vector::new(finger_x.0, inner.min(outer), -wide / 2.0);
            let max = Vector::new(finger_x.1, inner.max(outer), wide / 2.0);
            boxes.push(aabb_box(min, max));
        }
        Gripper { boxes, opening }
    }

    /// Whether the gripper, with its tool frame at `tool` (world), intersects `shape` at `pose`.
    pub fn intersects(&self, tool: &Pose, shape: &dyn Shape, pose: &Pose) -> bool {
        self.boxes.iter().any(|(local, cuboid)| {
            let at = *tool * *local;
            query::intersection_test(&at, cuboid, pose, shape)
                .map(|hit| hit.intersecting)
                // Unsupported shape pairs count as colliding: never claim a free grasp we cannot check.
                .unwrap_or(true)
        })
    }
}

fn aabb_box(min: Vector, max: Vector) -> (Pose, Cuboid) {
    let centre = (min + max) * 0.5;
    (
        Pose::from_translation(centre),
        Cuboid::new((max - min) * 0.5),
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn fingers_sit_outside_the_opening() {
        let g = Gripper::new(0.04);
        // A 3 cm cube between the jaws touches neither finger nor the palm.
        let cube = Cuboid::new(Vector::splat(0.015));
        assert!(!g.intersects(&Pose::IDENTITY, &cube, &Pose::IDENTITY));
        // A 5 cm cube does.
        let big = Cuboid::new(Vector::splat(0.025));
        assert!(g.intersects(&Pose::IDENTITY, &big, &Pose::IDENTITY));
        // Pushed back 6 cm it meets the palm even when it fits between the fingers.
        let back = Pose::from_translation(Vector::new(-0.08, 0.0, 0.0));
        assert!(g.intersects(&Pose::IDENTITY, &cube, &back));
    }
}
