//! What the checker found: faults, counts, the summary line and the JSON report.

use std::collections::BTreeMap;
use std::fmt;

use serde::Serialize;

/// The kinds of fault the checker reports.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Hash, Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum FaultKind {
    /// Two bodies of different owners (link, held object, scene object, other agent) interpenetrate
    /// during a trajectory.
    Collision,
    /// Two non-adjacent links of one agent interpenetrate during a trajectory.
    SelfCollision,
    /// An object at rest after a step has no support surface within the gap tolerance under it.
    Unsupported,
    /// An object at rest after a step penetrates another body (object inside object, book in a thigh).
    Penetration,
    /// An added or deleted `visible` / `reachable` literal that the re-measure clearly contradicts.
    StaleLiteral,
    /// A trajectory moves the gripper that holds an object but declares `holding: null`.
    UndeclaredCarry,
    /// A timed joint trajectory breaks a rule of its timing: times not strictly increasing from
    /// 0, not at rest at its ends, a velocity or acceleration over its declared limit, or ends
    /// that are not its first and last waypoints.
    Timing,
    /// A timed trajectory does not start where its agent's previous trajectory (or the scene)
    /// left one of its joints or its gripper.
    Discontinuity,
    /// A frame's link poses are not the forward kinematics of the agent's URDF at its point.
    Kinematics,
    /// At the end of a robot's trajectory that holds an object and declares its gripper, no
    /// finger of the holding hand is within 3 mm of it: the jaws do not close on what they
    /// carry.
    LooseGrip,
}

impl FaultKind {
    /// The kebab-case name used in the text and JSON reports.
    pub fn name(self) -> &'static str {
        match self {
            FaultKind::Collision => "collision",
            FaultKind::SelfCollision => "self-collision",
            FaultKind::Unsupported => "unsupported",
            FaultKind::Penetration => "penetration",
            FaultKind::StaleLiteral => "stale-literal",
            FaultKind::UndeclaredCarry => "undeclared-carry",
            FaultKind::Timing => "timing",
            FaultKind::Discontinuity => "discontinuity",
            FaultKind::Kinematics => "kinematics",
            FaultKind::LooseGrip => "loose-grip",
        }
    }
}

/// One fault. Trajectory faults are grouped per (kind, step, trajectory, bodies): the worst
/// configuration is kept, with how many configurations showed the fault.
#[derive(Clone, Debug, Serialize)]
pub struct Fault {
    pub kind: FaultKind,
    /// Step index; `None` for the initial scene.
    pub step: Option<usize>,
    pub action: String,
    /// Trajectory label and its index in the step (`None` for faults at rest).
    pub trajectory: Option<String>,
    pub trajectory_index: Option<usize>,
    /// Frame of the worst configuration, `12+0.50` for a sub-frame.
    pub frame: Option<String>,
    /// The two bodies (`AGENT/LINK`, `object desk`, `held white-book`), or the literal
    /// and `added` / `deleted` for a stale literal.
    pub a: String,
    pub b: String,
    /// Penetration depth (collisions, penetrations) or gap to the nearest body below
    /// (unsupported), in millimetres; 0 where it does not apply.
    pub depth_mm: f32,
    /// Configurations (frames and sub-frames) that showed this fault.
    pub configs: usize,
    /// Measurements behind the verdict, in words.
    pub detail: String,
}

impl fmt::Display for Fault {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let step = self
            .step
            .map_or("initial".to_string(), |s| format!("step {s}"));
        write!(f, "{:<16} {step} ({})", self.kind.name(), self.action)?;
        if let Some(t) = &self.trajectory {
            write!(f, " / {t}")?;
        }
        if let Some(fr) = &self.frame {
            write!(f, " / frame {fr}")?;
        }
        write!(f, ": {} vs {}", self.a, self.b)?;
        if self.depth_mm > 0.0 {
            write!(f, ", {:.1} mm", self.depth_mm)?;
        }
        if self.configs > 1 {
            write!(f, " ({} configs)", self.configs)?;
        }
        if !self.detail.is_empty() {
            write!(f, " [{}]", self.detail)?;
        }
        Ok(())
    }
}

/// The whole verdict on one plan.
#[derive(Clone, Debug, Default, Serialize)]
pub struct Report {
    /// The plan's own `status`, when it is not `solved` (an unsolved run has no steps to check).
    pub status: Option<String>,
    pub faults: Vec<Fault>,
    pub steps: usize,
    pub trajectories: usize,
    pub frames: usize,
    /// Frames and interpolated sub-frames checked.
    pub configs: usize,
    /// Literals re-measured.
    pub literals: usize,
    /// The largest distance of a frame's link origin from the forward kinematics of its point
    /// (mm), over every frame checked against a URDF.
    pub kinematics_max_mm: f64,
    /// The largest angle of a frame's link rotation from the forward kinematics (rad).
    pub kinematics_max_rad: f64,
}

impl Report {
    /// Number of faults of each kind, in kind order.
    pub fn counts(&self) -> BTreeMap<FaultKind, usize> {
        let mut m = BTreeMap::new();
        for f in &self.faults {
            *m.entry(f.kind).or_insert(0) += 1;
        }
        m
    }

    /// `clean: 0 faults in S steps, T trajectories, F frames` or `N faults: X collisions, ...`.
    pub fn summary(&self) -> String {
        let status = self
            .status
            .as_ref()
            .map_or(String::new(), |s| format!(" (the plan's status: {s})"));
        if self.faults.is_empty() {
            return format!(
                "clean: 0 faults in {} steps, {} trajectories, {} frames{status}",
                self.steps, self.trajectories, self.frames
            );
        }
        let parts: Vec<String> = self
            .counts()
            .iter()
            .map(|(k, n)| format!("{n} {}", plural(*k, *n)))
            .collect();
        format!(
            "{} faults: {} (in {} steps, {} trajectories, {} frames){status}",
            self.faults.len(),
            parts.join(", "),
            self.steps,
            self.trajectories,
            self.frames
        )
    }
}

fn plural(k: FaultKind, n: usize) -> String {
    let s = if n == 1 { "" } else { "s" };
    match k {
        FaultKind::Unsupported => "unsupported".to_string(),
        FaultKind::Timing => format!("timing fault{s}"),
        FaultKind::Kinematics => format!("kinematics fault{s}"),
        FaultKind::Discontinuity if n != 1 => "discontinuities".to_string(),
        other => format!("{}{s}", other.name()),
    }
}
