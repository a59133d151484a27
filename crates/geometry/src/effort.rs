//! Effort levels: how much an agent must move to see or reach something.
//!
//! From the original mightability-map work (`../shared/notes/geometry-facts.md` beside the checkout, section 3), least effort first:
//!
//! | level | to see | to reach |
//! |---|---|---|
//! | 0 | already in the field of view | already at the hand |
//! | 1 | turn the head | extend the arm |
//! | 2 | turn head and torso, lean (PR2: turn the base in place) | arm and torso |
//! | 3 | whole body, same place (human: stand up; PR2: torso lift high/low) | the same |
//! | 4 | whole body, change position (walk / drive) | the same |
//!
//! An agent's *stances* at a level are the body configurations that level allows beyond the
//! lower levels: a base pose and joint values, produced with the agent's real kinematics (the
//! URDF joints named below) so that eyes and shoulders land where the model puts them. At levels
//! 1 and above the head is free: visibility checks aim it at the target within its joint limits
//! ([`aim_head`]).

use std::f32::consts::PI;

use parry3d::math::{Pose, Rotation, Vector};
use parry3d::query::intersection_test;
use parry3d::shape::{Cylinder, SharedShape};

use crate::agent::AgentModel;
use crate::scene::{AgentId, AgentKind, AgentSpecResolved};
use crate::world::World;

/// The highest effort level (walk / drive).
pub const MAX_EFFORT: u8 = 4;

/// What a level means for seeing, in words (for reports).
pub fn describe_vis(level: u8, kind: AgentKind) -> &'static str {
    match (level, kind) {
        (0, _) => "in the field of view",
        (1, _) => "turn the head",
        (2, AgentKind::Human) => "turn the torso / lean",
        (2, AgentKind::Robot) => "turn around",
        (3, AgentKind::Human) => "stand up",
        (3, AgentKind::Robot) => "raise / lower the torso",
        (4, AgentKind::Human) => "walk",
        (4, AgentKind::Robot) => "drive",
        _ => "not possible",
    }
}

/// What a level means for reaching, in words.
pub fn describe_reach(level: u8, kind: AgentKind) -> &'static str {
    match (level, kind) {
        (0, _) => "in the hand",
        (1, _) => "extend the arm",
        (2, AgentKind::Human) => "lean / turn the torso",
        (2, AgentKind::Robot) => "turn around",
        (3, AgentKind::Human) => "stand up",
        (3, AgentKind::Robot) => "raise / lower the torso",
        (4, AgentKind::Human) => "walk",
        (4, AgentKind::Robot) => "drive",
        _ => "not possible",
    }
}

/// A movable joint and the range of values an effort level may use.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct JointRange {
    /// Index in the agent's configuration.
    pub dof: usize,
    pub lower: f32,
    pub upper: f32,
}

/// What each effort level lets an agent change; derived from the URDF joint names and the
/// scene's `[agents.effort]` overrides.
#[derive(Clone, Debug, PartialEq)]
pub struct EffortParams {
    /// Head pan and tilt (positive tilt looks down), level 1.
    pub head_pan: Option<JointRange>,
    pub head_tilt: Option<JointRange>,
    /// Torso turn and forward lean (humans), level 2.
    pub torso_yaw: Option<JointRange>,
    pub torso_pitch: Option<JointRange>,
    /// Turning the base in place at level 2, +- radians (robots: a full turn).
    pub base_turn: f32,
    /// Posture switch at level 3 (a sitting human stands up): joint values.
    pub posture_switch: Vec<(usize, f32)>,
    /// Torso lift range used at level 3 (robots).
    pub lift: Option<JointRange>,
    /// Level 4: base positions within this radius of the current one.
    pub move_radius: f32,
    /// Spacing of the level-4 base positions.
    pub move_step: f32,
    /// Radius of the agent's footprint (level-4 positions must be free of objects).
    pub footprint_radius: f32,
    /// Height of the footprint cylinder checked for level-4 positions.
    pub footprint_height: f32,
}

fn range(model: &AgentModel, dof: Option<usize>, limit: Option<f32>) -> Option<JointRange> {
    let dof = dof?;
    let l = model.dof_limits()[dof];
    let (mut lower, mut upper) = if l.is_bounded() {
        (l.lower, l.upper)
    } else {
        (-PI, PI)
    };
    if let Some(m) = limit {
        lower = lower.max(-m);
        upper = upper.min(m);
    }
    Some(JointRange { dof, lower, upper })
}

impl EffortParams {
    /// Effort parameters for an agent of the scene: joints found by the model's SRDF (the
    /// `head` group's first two movable joints pan and tilt; the groups `torso_yaw`,
    /// `torso_pitch`, `torso_lift`; a seated person stands up to the `standing` posture), limits
    /// from the URDF, narrowed by the scene's overrides.
    pub fn for_agent(spec: &AgentSpecResolved, model: &AgentModel) -> EffortParams {
        let e = &spec.effort;
        let human = spec.kind == AgentKind::Human;
        let rad = |d: Option<f32>| d.map(f32::to_radians);
        let mut posture_switch = Vec::new();
        if human && spec.sitting {
            for (k, v) in model.posture("standing") {
                posture_switch.push((k, model.dof_limits()[k].clamp(v)));
            }
        }
        let head = model.chain("head").map(|c| c.dofs).unwrap_or_default();
        let lean = rad(e.lean_deg).unwrap_or(60f32.to_radians());
        EffortParams {
            head_pan: range(model, head.first().copied(), rad(e.head_pan_deg)),
            head_tilt: range(model, head.get(1).copied(), None),
            torso_yaw: range(model, model.group_dof("torso_yaw"), rad(e.torso_turn_deg)),
            torso_pitch: range(model, model.group_dof("torso_pitch"), None).map(|mut r| {
                r.lower = r.lower.max(0.0);
                r.upper = r.upper.min(lean).max(r.lower);
                r
            }),
            base_turn: rad(e.base_turn_deg).unwrap_or(if human { 0.0 } else { PI }),
            posture_switch,
            lift: if human {
                None
            } else {
                range(model, model.group_dof("torso_lift"), None)
            },
            move_radius: e.move_radius.unwrap_or(3.0),
            move_step: 0.25,
            footprint_radius: if human { 0.25 } else { 0.34 },
            footprint_height: if human { 1.0 } else { 0.6 },
        }
    }
}

/// A body configuration an effort level allows.
#[derive(Clone, Debug, PartialEq)]
pub struct Stance {
    /// The least effort level that allows it.
    pub level: u8,
    pub base: Pose,
    pub q: Vec<f32>,
}

fn samples(lo: f32, hi: f32, n: usize) -> Vec<f32> {
    if n <= 1 || hi <= lo {
        return vec![0.5 * (lo + hi)];
    }
    (0..n)
        .map(|i| lo + (hi - lo) * i as f32 / (n - 1) as f32)
        .collect()
}

fn with_value(q: &[f32], changes: &[(usize, f32)]) -> Vec<f32> {
    let mut q = q.to_vec();
    for &(k, v) in changes {
        q[k] = v;
    }
    q
}

/// Body variations of level 2 applied to a stance: torso turn x lean (humans), base turn
/// (robots). Includes the unchanged stance.
fn level2_variants(p: &EffortParams, base: Pose, q: &[f32]) -> Vec<(Pose, Vec<f32>)> {
    let mut out = Vec::new();
    let yaws = match p.torso_yaw {
        Some(r) => samples(r.lower, r.upper, 7),
        None => vec![f32::NAN],
    };
    let pitches = match p.torso_pitch {
        Some(r) => samples(r.lower, r.upper, 4),
        None => vec![f32::NAN],
    };
    let turns = if p.base_turn > 0.0 {
        let n = ((2.0 * p.base_turn) / (PI / 6.0)).round().max(1.0) as usize;
        let full = p.base_turn >= PI - 1e-3;
        // A full turn: n steps without repeating the end.
        (0..if full { n } else { n + 1 })
            .map(|i| -p.base_turn + 2.0 * p.base_turn * i as f32 / n as f32)
            .collect()
    } else {
        vec![0.0]
    };
    for &t in &turns {
        let b = base * Pose::from_rotation(Rotation::from_rotation_z(t));
        for &y in &yaws {
            for &pi in &pitches {
                let mut ch = Vec::new();
                if let (Some(r), false) = (p.torso_yaw, y.is_nan()) {
                    ch.push((r.dof, y));
                }
                if let (Some(r), false) = (p.torso_pitch, pi.is_nan()) {
                    ch.push((r.dof, pi));
                }
                out.push((b, with_value(q, &ch)));
            }
        }
    }
    out
}

/// Level 3 variations: the posture switch (stand up) and torso lift samples, each combined with
/// the level-2 variations.
fn level3_variants(p: &EffortParams, base: Pose, q: &[f32]) -> Vec<(Pose, Vec<f32>)> {
    let mut heads = Vec::new();
    if !p.posture_switch.is_empty() {
        heads.push(with_value(q, &p.posture_switch));
    }
    if let Some(r) = p.lift {
        for v in samples(r.lower, r.upper, 3) {
            heads.push(with_value(q, &[(r.dof, v)]));
        }
    }
    if heads.is_empty() {
        // Nothing to switch: level 3 adds nothing beyond level 2.
        return Vec::new();
    }
    heads
        .into_iter()
        .flat_map(|q3| level2_variants(p, base, &q3))
        .collect()
}

/// Free base positions for level 4: a grid of `move_step` within `move_radius` of the current
/// base, where the agent's footprint cylinder touches no object, nearest first.
pub fn free_base_positions(world: &World, agent: AgentId) -> Vec<Vector> {
    let info = world.agent(agent);
    let p = &info.effort;
    let here = world.agent_state(agent).base.translation;
    let foot = Cylinder::new(0.5 * p.footprint_height, p.footprint_radius);
    let obstacles: Vec<(SharedShape, Pose)> = world
        .obstacles()
        .map(|(_, s, pose)| (s.clone(), pose))
        .collect();
    let n = (p.move_radius / p.move_step).floor() as i32;
    let mut out = Vec::new();
    for i in -n..=n {
        for j in -n..=n {
            let off = Vector::new(i as f32 * p.move_step, j as f32 * p.move_step, 0.0);
            if off.length() > p.move_radius || (i == 0 && j == 0) {
                continue;
            }
            let c = here + off;
            // parry cylinders stand along y: turn onto z, lift off the floor by 2 cm.
            let fpose = Pose::from_parts(
                Vector::new(c.x, c.y, 0.02 + 0.5 * p.footprint_height),
                Rotation::from_rotation_x(std::f32::consts::FRAC_PI_2),
            );
            let free = obstacles.iter().all(|(s, pose)| {
                !intersection_test(&fpose, &foot, pose, s.as_ref())
                    .map(|r| r.intersecting)
                    .unwrap_or(true)
            });
            if free {
                out.push(c);
            }
        }
    }
    out.sort_by(|a, b| (*a - here).length().total_cmp(&(*b - here).length()));
    out
}

/// The stances that level `level` adds for `agent` in `world` (levels 0 and 1 share the current
/// stance: level 1 only frees the head and the arm). Level 4 stances face `facing` when given
/// (a target point), else the current direction.
pub fn stances(world: &World, agent: AgentId, level: u8, facing: Option<Vector>) -> Vec<Stance> {
    let info = world.agent(agent);
    let p = &info.effort;
    let st = world.agent_state(agent);
    let mk = |v: Vec<(Pose, Vec<f32>)>| {
        v.into_iter()
            .map(|(base, q)| Stance { level, base, q })
            .collect::<Vec<_>>()
    };
    match level {
        0 | 1 => vec![Stance {
            level,
            base: st.base,
            q: st.q.clone(),
        }],
        2 => mk(level2_variants(p, st.base, &st.q)),
        3 => mk(level3_variants(p, st.base, &st.q)),
        4 => {
            let standing = if p.posture_switch.is_empty() {
                st.q.clone()
            } else {
                with_value(&st.q, &p.posture_switch)
            };
            let mut out = Vec::new();
            for c in free_base_positions(world, agent) {
                let yaw = match facing {
                    Some(t) => (t.y - c.y).atan2(t.x - c.x),
                    None => st.base.rotation.to_euler(parry3d::glamx::EulerRot::ZYX).0,
                };
                let base = crate::world::base_pose(c.x, c.y, yaw);
                let mut q = standing.clone();
                if let Some(r) = p.lift {
                    q[r.dof] = r.upper;
                }
                out.push(Stance { level, base, q });
            }
            out
        }
        _ => Vec::new(),
    }
}

/// Sets the head pan/tilt of `q` so that the eye looks at `target` as closely as the joint
/// limits allow (a few fixed-point steps of forward kinematics). Returns the eye pose.
pub fn aim_head(world: &World, agent: AgentId, base: Pose, q: &mut [f32], target: Vector) -> Pose {
    let info = world.agent(agent);
    let model = &info.model;
    let eye = |q: &[f32]| model.link_pose_by_id(base, q, info.eye_link);
    let (Some(pan), Some(tilt)) = (info.effort.head_pan, info.effort.head_tilt) else {
        return eye(q);
    };
    for _ in 0..4 {
        let e = eye(q);
        let local = e.inverse_transform_point(target);
        let dyaw = local.y.atan2(local.x);
        let dpitch = -(local
            .z
            .atan2((local.x * local.x + local.y * local.y).sqrt()));
        q[pan.dof] = (q[pan.dof] + dyaw).clamp(pan.lower, pan.upper);
        q[tilt.dof] = (q[tilt.dof] + dpitch).clamp(tilt.lower, tilt.upper);
        if dyaw.abs() < 1e-3 && dpitch.abs() < 1e-3 {
            break;
        }
    }
    eye(q)
}

/// Shoulder positions of a stance (world frame).
pub fn shoulders(world: &World, agent: AgentId, base: Pose, q: &[f32]) -> Vec<Vector> {
    let info = world.agent(agent);
    info.shoulder_links
        .iter()
        .map(|&l| info.model.link_pose_by_id(base, q, l).translation)
        .collect()
}
