//! Perception at an effort level: where an agent's hands are, the points its shoulders reach
//! from at a stance, and how far its eyes turn. One home, with one set of tolerances, for the
//! three users: the shared literals ([`crate::facts`]), the mightability maps
//! ([`crate::mightability`]) and the GTP's candidate-point filters (`gtp::search::perception`).
//! Each user asks at its own grain (an object's surface, a grid cell, a candidate point) and
//! says by how much the thing it asks about extends beyond the point it passes.

use parry3d::math::Vector;

use crate::effort::{MAX_EFFORT, Stance};
use crate::scene::AgentId;
use crate::world::World;

/// A hand holds or touches what lies within this distance of its frame (metres): the reach of
/// effort level 0.
pub const HAND_TOLERANCE: f32 = 0.03;

/// Positions of the agent's hand frames now (world frame).
pub fn hand_positions(world: &World, agent: AgentId) -> Vec<Vector> {
    let poses = world.agent_state(agent).link_poses();
    world
        .agent(agent)
        .hand_links
        .iter()
        .map(|&h| poses[h].translation)
        .collect()
}

/// Whether a hand of `agent` is at `p` (level 0): within [`HAND_TOLERANCE`] plus `extent`, the
/// distance by which what is asked about reaches out from `p`: 0 for a point, a cell's
/// half-diagonal for a grid cell (any point of the cell), the smallest half-extent of an
/// object centred at `p` (the ball that fits in its bounding box, so that the hand is at the
/// object itself).
pub fn hand_at(world: &World, agent: AgentId, p: Vector, extent: f32) -> bool {
    let poses = world.agent_state(agent).link_poses();
    world
        .agent(agent)
        .hand_links
        .iter()
        .any(|&h| (poses[h].translation - p).length() <= HAND_TOLERANCE + extent)
}

/// The configurations a stance reaches from: the stance itself and, at the highest level
/// (standing at a free base position), also leaning forward with the torso pitch at its limit.
pub fn reach_postures(world: &World, agent: AgentId, stance: &Stance) -> Vec<Vec<f32>> {
    let mut out = vec![stance.q.clone()];
    if stance.level == MAX_EFFORT
        && let Some(r) = world.agent(agent).effort.torso_pitch
    {
        let mut q = stance.q.clone();
        q[r.dof] = r.upper;
        out.push(q);
    }
    out
}

/// Shoulder positions (world frame) of every reach posture of a stance: the points the arm
/// reaches from, each within the agent's `reach` radius.
pub fn reach_origins(world: &World, agent: AgentId, stance: &Stance) -> Vec<Vector> {
    reach_postures(world, agent, stance)
        .iter()
        .flat_map(|q| crate::effort::shoulders(world, agent, stance.base, q))
        .collect()
}

/// Whether `p` is within the agent's arm reach of one of `origins` (see [`reach_origins`]).
pub fn within_reach(world: &World, agent: AgentId, origins: &[Vector], p: Vector) -> bool {
    let reach = world.agent(agent).reach;
    origins.iter().any(|o| (*o - p).length() <= reach)
}

/// Half-angles (horizontal, vertical; radians) around the eye's axis that the agent sees at
/// `level` without moving its body: the field of view at level 0, widened by the head's pan and
/// tilt ranges from level 1. Levels 2 and more turn the body and see all around.
pub fn view_half_angles(world: &World, agent: AgentId, level: u8) -> [f32; 2] {
    let info = world.agent(agent);
    let mut half = [info.fov[0] / 2.0, info.fov[1] / 2.0];
    if level >= 1 {
        if let Some(pan) = info.effort.head_pan {
            half[0] += pan.upper.abs().max(pan.lower.abs());
        }
        if let Some(tilt) = info.effort.head_tilt {
            half[1] += tilt.upper.abs().max(tilt.lower.abs());
        }
    }
    half
}
