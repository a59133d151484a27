//! Shared literals: the symbolic facts a world makes true (`../shared/notes/geometry-facts.md` beside the checkout, section 7).
//!
//! * `visible(o, a)` with the least effort level at which agent `a` sees at least
//!   [`FactParams::vis_threshold`] of object `o`'s pixels ([`crate::visibility`]): level 0 with the
//!   head as it is, level 1 with the head turned towards the object, levels 2 to 4 from every
//!   stance the level allows ([`crate::effort::stances`]), the head turned towards the object.
//! * `reachable(o, a)` with the least effort level: 0 when a hand of `a` holds or touches `o`
//!   (within [`crate::perception::HAND_TOLERANCE`] of its surface);
//!   from level 1, when some shoulder of a stance of that level is within the agent's arm reach of
//!   the object's surface (exact point-to-shape distance), confirmed by inverse kinematics of an
//!   arm (the hand frame on the object's nearest surface point, joint limits respected) unless
//!   it is within [`SURE_REACH_MARGIN`] less than the reach.
//! * `on(a, b)`: the centre of `a` lies over one of `b`'s support surfaces (or, for objects with
//!   none, over `b`'s footprint) and `a`'s bottom is within `on_tolerance` above that surface.
//! * `inside(a, b)`: the centre of `a` lies inside `b`'s oriented bounding box, and `a` is not
//!   resting on `b`'s top face.
//! * `covered-by(a, b)`: `b` lies on top of `a`: `b`'s footprint covers `a`'s centre and `b`'s
//!   bottom is within `on_tolerance` of `a`'s top.
//!
//! `visible`, `reachable`, `on`, `inside` and `covered-by` are computed for the movable objects
//! (the HDDL `thing`s) as first argument; the second argument of `on`, `inside` and
//! `covered-by` can be any object.

use parry3d::bounding_volume::Aabb;
use parry3d::math::{Pose, Vector};
use serde::Serialize;

use crate::agent::KinematicChain;
use crate::effort::{MAX_EFFORT, aim_head, shoulders, stances};
use crate::ik::{IkOptions, solve_ik};
use crate::perception::{HAND_TOLERANCE, hand_positions, reach_postures};
use crate::scene::{AgentId, AgentKind, ObjectId};
use crate::visibility::{Aim, visibility_for_agent, visibility_from};
use crate::world::World;

/// Within this much less than the arm's reach of a shoulder an object is reachable without an
/// inverse-kinematics confirmation (which only decides the band beyond): the convention of the
/// plan checkers, `htngtp check` and the reference checker, which call an object this close to
/// a shoulder reachable whatever the arm's joint limits say.
pub const SURE_REACH_MARGIN: f32 = 0.2;

/// Thresholds and resolutions of the fact computation.
#[derive(Clone, Debug, PartialEq)]
pub struct FactParams {
    /// Fraction of an object's pixels that must be seen (the paper's experiment: 0.5).
    pub vis_threshold: f32,
    /// Pixel grid per visibility query (square).
    pub resolution: usize,
    /// How far above a support an object's bottom may be and still be `on` it (m).
    pub on_tolerance: f32,
    /// Level-4 stances tried per object, nearest to the object first.
    pub max_move_stances: usize,
    /// Confirm reach with inverse kinematics of an arm (position of the hand frame at the
    /// object's point nearest the arm's root; seeded, a few restarts), not only the reach radius.
    pub confirm_with_ik: bool,
    /// Highest effort level examined: a literal needing more comes out as not holding (`None`).
    /// A planner that only uses levels <= 1 saves most of the work with `max_effort: 1`.
    pub max_effort: u8,
}

impl Default for FactParams {
    fn default() -> Self {
        FactParams {
            vis_threshold: 0.5,
            resolution: 64,
            on_tolerance: 0.05,
            max_move_stances: 40,
            confirm_with_ik: true,
            max_effort: MAX_EFFORT,
        }
    }
}

/// One shared literal, as the planner and `htngtp facts --json` see it.
#[derive(Clone, Debug, PartialEq, Eq, Serialize)]
pub struct Fact {
    pub predicate: String,
    pub args: Vec<String>,
    /// Least effort level (visible, reachable); `None` for the others.
    pub effort: Option<u8>,
}

/// The least effort level at which `agent` sees `object` (None: not even by moving).
pub fn visible_effort(
    world: &World,
    agent: AgentId,
    object: ObjectId,
    params: &FactParams,
) -> Option<u8> {
    let thr = params.vis_threshold;
    let res = params.resolution;
    // A person sees what they hold by raising it into view (a level-1 effort), wherever
    // the hand is.
    if world.agent(agent).kind() == AgentKind::Human
        && world.attachment(object).is_some_and(|a| a.agent == agent)
    {
        let now = visibility_for_agent(world, agent, object, Aim::Current, res).fraction() >= thr;
        return Some(if now { 0 } else { 1 });
    }
    if visibility_for_agent(world, agent, object, Aim::Current, res).fraction() >= thr {
        return Some(0);
    }
    if params.max_effort >= 1
        && visibility_for_agent(world, agent, object, Aim::AtTarget, res).fraction() >= thr
    {
        return Some(1);
    }
    let target = world.object_aabb(object).center();
    let fov = world.agent(agent).fov;
    for level in 2..=params.max_effort.min(MAX_EFFORT) {
        let mut list = stances(world, agent, level, Some(target));
        if level == MAX_EFFORT {
            sort_by_distance(&mut list, target);
            list.truncate(params.max_move_stances);
        }
        let mut w = world.clone();
        for s in list {
            let mut q = s.q.clone();
            let eye = aim_head(world, agent, s.base, &mut q, target);
            // The agent's own body moves with the stance (it may hide things itself).
            w.set_agent_config(agent, s.base, &q);
            if visibility_from(&w, object, &eye, fov, res).fraction() >= thr {
                return Some(level);
            }
        }
    }
    None
}

fn sort_by_distance(list: &mut [crate::effort::Stance], target: Vector) {
    list.sort_by(|a, b| {
        let da = (a.base.translation - target).truncate().length();
        let db = (b.base.translation - target).truncate().length();
        da.total_cmp(&db)
    });
}

/// Distance from a point to an object's surface (0 inside).
pub fn distance_to_object(world: &World, object: ObjectId, p: Vector) -> f32 {
    let o = world.object(object);
    o.shape
        .distance_to_point(&world.object_shape_pose(object), p, true)
}

/// The least effort level at which `agent` can reach `object` (None: not even by moving).
pub fn reachable_effort(
    world: &World,
    agent: AgentId,
    object: ObjectId,
    params: &FactParams,
) -> Option<u8> {
    let info = world.agent(agent);
    if world.attachment(object).is_some_and(|a| a.agent == agent) {
        return Some(0);
    }
    if hand_positions(world, agent)
        .into_iter()
        .any(|h| distance_to_object(world, object, h) <= HAND_TOLERANCE)
    {
        return Some(0);
    }
    let target = world.object_aabb(object).center();
    for level in 1..=params.max_effort.min(MAX_EFFORT) {
        let mut list = stances(world, agent, level, Some(target));
        if level == MAX_EFFORT {
            sort_by_distance(&mut list, target);
            list.truncate(params.max_move_stances);
        }
        for s in &list {
            for q in reach_postures(world, agent, s) {
                let nearest = shoulders(world, agent, s.base, &q)
                    .into_iter()
                    .map(|p| distance_to_object(world, object, p))
                    .fold(f32::INFINITY, f32::min);
                let sure = nearest <= info.reach - SURE_REACH_MARGIN;
                let near = nearest <= info.reach;
                if sure
                    || (near
                        && (!params.confirm_with_ik
                            || ik_confirms(world, agent, s.base, &q, object)))
                {
                    return Some(level);
                }
            }
        }
    }
    None
}

/// Whether an arm of the agent (the arms of its model's SRDF) can put its
/// hand frame on the object's surface point nearest the arm's root, from this stance.
fn ik_confirms(world: &World, agent: AgentId, base: Pose, q: &[f32], object: ObjectId) -> bool {
    let model = &world.agent(agent).model;
    let mut rng = fastrand::Rng::with_seed(0x5eed);
    model.arm_names().iter().any(|name| {
        model
            .chain(name)
            .is_ok_and(|chain| arm_reach(world, agent, &chain, base, q, object, &mut rng).is_some())
    })
}

/// The agent's configuration with arm `chain` reaching `object` from the stance `base`, `q`:
/// its tip (the hand frame) on the object's surface point nearest the arm's root, by inverse
/// kinematics of the position alone. `None` when the arm does not get there.
pub fn arm_reach(
    world: &World,
    agent: AgentId,
    chain: &KinematicChain,
    base: Pose,
    q: &[f32],
    object: ObjectId,
    rng: &mut fastrand::Rng,
) -> Option<Vec<f32>> {
    let model = &world.agent(agent).model;
    let obj = world.object(object);
    let pose = world.object_shape_pose(object);
    let options = IkOptions {
        attempts: 6,
        iterations: 80,
        position_tolerance: 0.01,
        orientation_tolerance: 1.0,
        orientation: false,
    };
    let root = model.link_pose_by_id(base, q, chain.root_link).translation;
    let point = obj.shape.project_point(&pose, root, true).point;
    solve_ik(
        model,
        chain,
        base,
        q,
        Pose::from_translation(point),
        &options,
        rng,
    )
    .ok()
    .map(|s| s.configuration)
}

/// Centre of an object's world bounding box.
fn centre_of(world: &World, o: ObjectId) -> Vector {
    world.object_aabb(o).center()
}

/// `on(a, b)`: see the module docs. When `a` rests on something else lying on `b` (a book on a
/// book on the table), `a` is on that thing, not on `b`.
pub fn on(world: &World, a: ObjectId, b: ObjectId, tolerance: f32) -> bool {
    if a == b {
        return false;
    }
    let aabb_a = world.object_aabb(a);
    let c = aabb_a.center();
    let bottom = aabb_a.mins.z;
    let Some(height) = support_height_under(world, b, c, bottom, tolerance) else {
        return false;
    };
    // Something between a's bottom and b's surface, under a's centre, carries a instead.
    !world.object_ids().any(|o| {
        if o == a || o == b {
            return false;
        }
        let bb = world.object_aabb(o);
        inside_xy(c, &bb) && bb.maxs.z > height + 0.005 && bb.maxs.z <= bottom + 0.01
    })
}

/// Height of the support surface of `b` under the point `c` on which an object with its
/// bottom at `bottom` could rest (within `tolerance`).
fn support_height_under(
    world: &World,
    b: ObjectId,
    c: Vector,
    bottom: f32,
    tolerance: f32,
) -> Option<f32> {
    let ob = world.object(b);
    if ob.surfaces.is_empty() {
        let bb = world.object_aabb(b);
        let ok = inside_xy(c, &bb) && bottom >= bb.maxs.z - 0.01 && bottom <= bb.maxs.z + tolerance;
        return ok.then_some(bb.maxs.z);
    }
    let pose_b = world.object_pose(b);
    let local = pose_b.inverse_transform_point(c);
    let local_bottom = bottom - pose_b.translation.z;
    ob.surfaces
        .iter()
        .find(|s| {
            (local.x - s.centre.x).abs() <= s.half_extents[0]
                && (local.y - s.centre.y).abs() <= s.half_extents[1]
                && local_bottom >= s.centre.z - 0.01
                && local_bottom <= s.centre.z + tolerance
        })
        .map(|s| s.centre.z + pose_b.translation.z)
}

fn inside_xy(p: Vector, b: &Aabb) -> bool {
    p.x >= b.mins.x && p.x <= b.maxs.x && p.y >= b.mins.y && p.y <= b.maxs.y
}

/// `inside(a, b)`: see the module docs.
pub fn inside(world: &World, a: ObjectId, b: ObjectId, tolerance: f32) -> bool {
    if a == b {
        return false;
    }
    let c = centre_of(world, a);
    let ob = world.object(b);
    let local = world.object_shape_pose(b).inverse_transform_point(c);
    let lb = ob.shape.compute_local_aabb();
    let within = (0..3).all(|k| local[k] >= lb.mins[k] && local[k] <= lb.maxs[k]);
    if !within {
        return false;
    }
    // Resting on the very top of b is `on`, not `inside`.
    let top = world.object_aabb(b).maxs.z;
    !(world.object_aabb(a).mins.z >= top - 0.01 - tolerance && on(world, a, b, tolerance))
}

/// `covered-by(a, b)`: see the module docs.
pub fn covered_by(world: &World, a: ObjectId, b: ObjectId, tolerance: f32) -> bool {
    if a == b {
        return false;
    }
    let aa = world.object_aabb(a);
    let bb = world.object_aabb(b);
    inside_xy(aa.center(), &bb)
        && bb.mins.z >= aa.maxs.z - 0.01
        && bb.mins.z <= aa.maxs.z + tolerance
}

/// Visibility and reachability effort of every movable object for one agent.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct AgentFacts {
    pub agent: String,
    pub kind: String,
    /// `(object, visible effort, reachable effort)`.
    pub objects: Vec<(String, Option<u8>, Option<u8>)>,
}

/// Per-agent effort table (the paper's Fig. 5) for the given objects (default: movable ones).
pub fn effort_table(
    world: &World,
    objects: Option<&[ObjectId]>,
    params: &FactParams,
) -> Vec<AgentFacts> {
    use rayon::prelude::*;
    let objs: Vec<ObjectId> = match objects {
        Some(o) => o.to_vec(),
        None => world
            .object_ids()
            .filter(|&o| world.object(o).movable)
            .collect(),
    };
    world
        .agent_ids()
        .map(|a| {
            let rows = objs
                .par_iter()
                .map(|&o| {
                    (
                        world.object(o).name.clone(),
                        visible_effort(world, a, o, params),
                        reachable_effort(world, a, o, params),
                    )
                })
                .collect();
            AgentFacts {
                agent: world.agent(a).name().to_string(),
                kind: world.agent(a).kind().to_string(),
                objects: rows,
            }
        })
        .collect()
}

/// The spatial relations on / inside / covered-by among objects (movable first argument).
pub fn relations(world: &World, params: &FactParams) -> Vec<Fact> {
    let tol = params.on_tolerance;
    let mut out = Vec::new();
    for a in world.object_ids().filter(|&a| world.object(a).movable) {
        for b in world.object_ids() {
            let args = || vec![world.object(a).name.clone(), world.object(b).name.clone()];
            if on(world, a, b, tol) {
                out.push(Fact {
                    predicate: "on".into(),
                    args: args(),
                    effort: None,
                });
            }
            if inside(world, a, b, tol) {
                out.push(Fact {
                    predicate: "inside".into(),
                    args: args(),
                    effort: None,
                });
            }
            if covered_by(world, a, b, tol) {
                out.push(Fact {
                    predicate: "covered-by".into(),
                    args: args(),
                    effort: None,
                });
            }
        }
    }
    out
}

/// Every shared literal of the world: `visible` and `reachable` (with their least effort level,
/// when there is one) for each movable object and agent, then the relations.
pub fn shared_literals(world: &World, params: &FactParams) -> Vec<Fact> {
    let mut out = Vec::new();
    for t in effort_table(world, None, params) {
        for (o, vis, reach) in &t.objects {
            if let Some(e) = vis {
                out.push(Fact {
                    predicate: "visible".into(),
                    args: vec![o.clone(), t.agent.clone()],
                    effort: Some(*e),
                });
            }
            if let Some(e) = reach {
                out.push(Fact {
                    predicate: "reachable".into(),
                    args: vec![o.clone(), t.agent.clone()],
                    effort: Some(*e),
                });
            }
        }
    }
    out.extend(relations(world, params));
    out
}
