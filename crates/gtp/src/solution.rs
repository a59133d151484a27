//! What a task's solution says, in a serialisable form: the grasp, the placement, the
//! visibility reached and the trajectories (approach, grasp, lift, transfer, place, retreat).

use parry3d::math::Pose;
use serde::{Deserialize, Serialize};

use crate::stats::Stats;
use crate::task::TaskKind;

/// A pose as plain numbers: translation (metres) and rotation quaternion `[x, y, z, w]`.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct PoseRecord {
    /// Translation in metres.
    pub xyz: [f32; 3],
    /// Unit quaternion `[x, y, z, w]`.
    pub quat: [f32; 4],
}

impl From<Pose> for PoseRecord {
    fn from(p: Pose) -> Self {
        let t = p.translation;
        let q = p.rotation;
        PoseRecord {
            xyz: [t.x, t.y, t.z],
            quat: [q.x, q.y, q.z, q.w],
        }
    }
}

impl From<PoseRecord> for Pose {
    fn from(r: PoseRecord) -> Self {
        Pose::from_parts(
            parry3d::math::Vector::from(r.xyz),
            parry3d::math::Rotation::from_xyzw(r.quat[0], r.quat[1], r.quat[2], r.quat[3])
                .normalize(),
        )
    }
}

/// The phases of a pick-and-place motion, in execution order.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum Phase {
    /// From the current arm configuration to the pre-grasp, the gripper open.
    Approach,
    /// Straight in along the gripper's axis to the grasp, then close the jaws.
    Grasp,
    /// Straight up with the object.
    Lift,
    /// Carrying the object to above the placement, or to the hand-over pose.
    Transfer,
    /// Straight down to the placement, then open the jaws.
    Place,
    /// Straight back along the gripper's axis, away from the placed object.
    Retreat,
    /// The arm back to where it started, the object left in place.
    Return,
    /// The robot's base driving on the floor (navigate-to).
    Drive,
    /// A person's other arm moved out of the way, to rest, before a take's reach.
    Clear,
    /// A person's hand out to an object the robot holds out (take; shown, not planned).
    Reach,
    /// The person's hand back with the object taken (take; shown, not planned).
    Withdraw,
}

/// An object carried during a motion.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct HeldRecord {
    /// The object's name.
    pub object: String,
    /// The object's pose in the tool frame.
    pub object_in_tool: PoseRecord,
}

/// One collision-free joint-space path of one phase.
///
/// What was checked: the robot (self-collision) against every object not held and every other
/// agent, the held object against those and the robot's links, except the obstacles listed in
/// `ignored`; an object the open gripper `straddles` (while grasping or retreating from it) is
/// checked against the gripper's palm and fingers instead of the whole robot.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Trajectory {
    /// What this motion does.
    pub phase: Phase,
    /// The agent moving (the robot's name; the human's for a take's reach and withdraw).
    pub agent: String,
    /// The arm (`right_arm`, `left_arm`), or `base` for a drive.
    pub arm: String,
    /// The joints moved, in the order of each waypoint's values (`base_x`, `base_y`, `base_yaw`
    /// for a drive).
    pub joints: Vec<String>,
    /// Waypoints; consecutive ones are joined by straight joint-space segments.
    pub waypoints: Vec<Vec<f32>>,
    /// The object carried, if any.
    pub held: Option<HeldRecord>,
    /// Jaw opening during the motion (metres).
    pub gripper_opening: f32,
    /// Obstacles not checked: the object being grasped or released (see `straddles`), or the
    /// support an object is lifted off during the first centimetres of the lift.
    pub ignored: Vec<String>,
    /// The object between the open jaws and its pose, checked against the gripper model.
    pub straddles: Option<(String, PoseRecord)>,
    /// Joint-space length (radians and metres summed).
    pub length: f32,
}

/// The grasp used, in a serialisable form.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct GraspRecord {
    /// Index in the object's grasp set (absent when the object was already held).
    pub id: Option<usize>,
    /// The gripper's tool frame relative to the object.
    pub tool_in_object: PoseRecord,
    /// Jaw opening when closed on the object (metres).
    pub width: f32,
    /// The arm that holds the object.
    pub arm: String,
}

/// Where the object ends up.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct PlacementRecord {
    /// The object's final pose in the world.
    pub pose: PoseRecord,
    /// The support it rests on (absent when held in the hand).
    pub support: Option<String>,
    /// The candidate point (on the support's surface, or in the air for a hand-over).
    pub point: [f32; 3],
    /// Index of the resting face (or of the hand-over orientation).
    pub orientation: usize,
    /// Yaw angle index within the face.
    pub yaw_index: usize,
}

/// A serialisable account of one solution.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct SolutionSummary {
    /// The task solved.
    pub task: TaskKind,
    /// Its arguments by name.
    pub args: Vec<String>,
    /// Which solution of the stream (0 first).
    pub index: usize,
    /// The effort level of the human at which it was found.
    pub effort_level: u8,
    /// The grasp (absent for navigate-to).
    pub grasp: Option<GraspRecord>,
    /// The object's final pose (absent for pick and navigate-to).
    pub placement: Option<PlacementRecord>,
    /// The object's visibility for the human, measured in the final world (absent when the task
    /// concerns no human).
    pub visibility: Option<f32>,
    /// The human's least effort level to reach the object in the final world, if any.
    pub reach_effort: Option<u8>,
    /// The robot's base pose after the task (navigate-to changes it).
    pub robot_base: Option<[f32; 3]>,
    /// The base pose `(x, y, yaw)` the task was done from when the arm could not do it from
    /// where the robot stood: the robot drove there (the first trajectory), did the task and,
    /// when it put the object down, drove back (the last) if it could; else it stays there
    /// (`robot_base`). Absent (and not in the JSON) otherwise.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub base_move: Option<[f32; 3]>,
    /// The motions, in execution order.
    pub trajectories: Vec<Trajectory>,
    /// The call's statistics when this solution was produced.
    pub stats: Stats,
}

impl SolutionSummary {
    /// Length of every trajectory, by phase, in execution order.
    pub fn trajectory_lengths(&self) -> Vec<(Phase, f32)> {
        self.trajectories
            .iter()
            .map(|t| (t.phase, t.length))
            .collect()
    }
}
