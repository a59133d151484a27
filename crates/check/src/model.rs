//! The checker's own typed view of a plan JSON (`docs/plan-json.md`): only what the file declares,
//! names resolved to indices once so the sweeps work on plain vectors.

use parry3d::math::Pose;
use parry3d::shape::SharedShape;

/// One primitive of a body, posed in its owner's frame (object or link).
#[derive(Clone)]
pub struct Part {
    pub shape: SharedShape,
    pub pose: Pose,
}

/// A scene object: furniture or a movable thing.
#[derive(Clone)]
pub struct Object {
    pub name: String,
    pub movable: bool,
    pub parts: Vec<Part>,
    /// Initial pose.
    pub pose: Pose,
}

/// Robot or person.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum AgentKind {
    Robot,
    Human,
}

/// One link of an agent and its shapes (possibly none).
#[derive(Clone)]
pub struct Link {
    pub name: String,
    pub parts: Vec<Part>,
}

/// A hand or gripper as the plan declares it (`hands`): the frame a held object rides in and
/// the links that may touch what it grasps.
#[derive(Clone, Debug)]
pub struct Hand {
    /// Index of the `tool_link`.
    pub tool: usize,
    /// Indices of its `links` (palm, fingers, the tool frame).
    pub links: Vec<usize>,
}

/// An agent: its links and its initial posture (`link_poses`, one pose per link).
#[derive(Clone)]
pub struct Agent {
    pub name: String,
    pub kind: AgentKind,
    /// Index of the `eye_link`, when declared.
    pub eye: Option<usize>,
    /// Index of the `head_pivot_link` (the eye swings about its origin when the head turns).
    pub head_pivot: Option<usize>,
    /// Indices of the `shoulder_links` (reach is measured from their origins).
    pub shoulders: Vec<usize>,
    /// Its `hands` (none declared: no link may grasp).
    pub hands: Vec<Hand>,
    /// Link pairs its robot description says may touch (`disabled_collisions`, from the SRDF):
    /// left out of the self-collision check.
    pub disabled: Vec<(usize, usize)>,
    pub links: Vec<Link>,
    pub link_poses: Vec<Pose>,
    /// The agent's kinematics, read from the `urdf` text when the file carries it.
    pub kinematics: Option<crate::kinematics::Kinematics>,
    /// Initial joint values by name (`joint_positions`; the base as `base_x`, `base_y`,
    /// `base_yaw`); empty when absent.
    pub joint_positions: std::collections::BTreeMap<String, f64>,
}

/// One frame of a trajectory: every link's pose, and the held object's pose when holding.
#[derive(Clone)]
pub struct Frame {
    pub link_poses: Vec<Pose>,
    pub held_pose: Option<Pose>,
    /// Seconds from the trajectory's start (`t`), when declared.
    pub time: Option<f64>,
}

/// One trajectory of a GS step.
#[derive(Clone)]
pub struct Trajectory {
    pub agent: usize,
    pub label: String,
    /// Object index declared in `holding`.
    pub holding: Option<usize>,
    pub frames: Vec<Frame>,
    /// The timed joint trajectory (`joint_trajectory`; absent in older plan JSONs).
    pub joint_trajectory: Option<JointTrajectory>,
}

/// A trajectory's joints over time, with the limits it declares (lengths checked when parsed:
/// every per-joint list has one value per joint name).
#[derive(Clone)]
pub struct JointTrajectory {
    pub joint_names: Vec<String>,
    /// Per joint, the velocity limit (rad/s or m/s, positive).
    pub velocity_limits: Vec<f64>,
    /// Per joint, the acceleration limit (rad/s^2 or m/s^2, positive).
    pub acceleration_limits: Vec<f64>,
    /// The planner's waypoints the points pass through, when declared.
    pub waypoints: Option<Vec<Vec<f64>>>,
    /// The gripper joint whose position each point gives, when the trajectory moves a gripper.
    pub gripper_joint: Option<String>,
    /// Joints that take the gripper joint's position too (fingers each on a joint of its own).
    pub gripper_followers: Vec<String>,
    pub points: Vec<JointPoint>,
}

/// One timed point of a [`JointTrajectory`].
#[derive(Clone)]
pub struct JointPoint {
    pub positions: Vec<f64>,
    pub velocities: Vec<f64>,
    /// Seconds from the trajectory's start.
    pub time: f64,
    /// The gripper joint's position (`gripper_position`), when declared.
    pub gripper: Option<f64>,
}

/// A literal as the JSON writes it: predicate then arguments.
pub type Literal = Vec<String>;

/// One primitive action of the plan.
#[derive(Clone)]
pub struct Step {
    pub index: usize,
    pub action: String,
    pub added: Vec<Literal>,
    pub deleted: Vec<Literal>,
    /// The GS task's first argument (the object it is about), if any.
    pub target: Option<usize>,
    pub trajectories: Vec<Trajectory>,
    /// Poses of movable objects after the step (object index, pose).
    pub object_poses: Vec<(usize, Pose)>,
}

/// A whole plan.
#[derive(Clone)]
pub struct Plan {
    /// `solved`, `unsolvable` or `limit` (absent: `None`).
    pub status: Option<String>,
    pub objects: Vec<Object>,
    pub agents: Vec<Agent>,
    pub steps: Vec<Step>,
    /// The shared literals true before the first step (`initial_literals`; absent in older plan
    /// JSONs): with them the claimed state is known after every step.
    pub initial_literals: Option<Vec<Literal>>,
}

impl Plan {
    /// Index of the object called `name`.
    pub fn object(&self, name: &str) -> Option<usize> {
        self.objects.iter().position(|o| o.name == name)
    }

    /// Index of the agent called `name`.
    pub fn agent(&self, name: &str) -> Option<usize> {
        self.agents.iter().position(|a| a.name == name)
    }

    /// Number of trajectories and frames in the plan.
    pub fn counts(&self) -> (usize, usize) {
        let trajs = self.steps.iter().flat_map(|s| &s.trajectories);
        trajs.fold((0, 0), |(t, f), tr| (t + 1, f + tr.frames.len()))
    }
}

impl Agent {
    /// Index of the link called `name`.
    pub fn link(&self, name: &str) -> Option<usize> {
        self.links.iter().position(|l| l.name == name)
    }

    /// Whether link `l` belongs to one of the agent's hands: it may touch what it grasps.
    pub fn is_grasping(&self, l: usize) -> bool {
        self.hands.iter().any(|h| h.links.contains(&l))
    }
}
