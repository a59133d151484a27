//! Shapes placed in the world, the depth query, and the body naming and grouping rules that
//! depend only on the JSON (which hand holds an object, which link pairs are adjacent).

use parry3d::bounding_volume::{Aabb, BoundingVolume};
use parry3d::math::Pose;
use parry3d::query;
use parry3d::shape::SharedShape;

use crate::model::{Agent, Part, Plan};

/// Who a placed shape belongs to.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum Owner {
    /// A link of an agent (agent index, link index).
    Link(usize, usize),
    /// A scene object at rest (or held by an agent that is not moving it).
    Object(usize),
    /// The object the moving agent holds (declared or carried).
    Held(usize),
}

impl Owner {
    /// The report's name: `AGENT/LINK`, `object desk`, `held white-book`.
    pub fn name(self, plan: &Plan) -> String {
        match self {
            Owner::Link(a, l) => {
                let a = &plan.agents[a];
                format!("{}/{}", a.name, a.links[l].name)
            }
            Owner::Object(o) => format!("object {}", plan.objects[o].name),
            Owner::Held(o) => format!("held {}", plan.objects[o].name),
        }
    }
}

/// One shape in world coordinates with its bounding box.
#[derive(Clone)]
pub struct Placed {
    pub owner: Owner,
    pub shape: SharedShape,
    pub pose: Pose,
    pub aabb: Aabb,
}

impl Placed {
    /// `part` of `owner` whose frame is at `frame`.
    pub fn new(owner: Owner, part: &Part, frame: &Pose) -> Self {
        let pose = *frame * part.pose;
        Placed {
            owner,
            aabb: part.shape.compute_aabb(&pose),
            shape: part.shape.clone(),
            pose,
        }
    }
}

/// How deep two shapes interpenetrate (m); 0 when they are apart or only touch. Only called
/// after the boxes met; a pair parry cannot query counts as apart (never a panic).
///
/// The exact intersection test decides first: parry's `contact` between two cuboids takes the
/// general support-map path (GJK/EPA), which can report a penetration of a few millimetres for
/// boxes that are apart (a finger 2.9 mm from a book read as 1.5 mm deep).
pub fn depth(a: &Placed, b: &Placed) -> f32 {
    if !a.aabb.intersects(&b.aabb) {
        return 0.0;
    }
    if query::intersection_test(&a.pose, &*a.shape, &b.pose, &*b.shape)
        .is_ok_and(|i| !i.intersecting)
    {
        return 0.0;
    }
    match query::contact(&a.pose, &*a.shape, &b.pose, &*b.shape, 0.0) {
        Ok(Some(c)) => (-c.dist).max(0.0),
        _ => 0.0,
    }
}

/// Every shape of every object at its pose (`skip` left out).
pub fn objects_at(plan: &Plan, poses: &[Pose], skip: &[usize]) -> Vec<Placed> {
    let mut out = Vec::new();
    for (i, o) in plan.objects.iter().enumerate() {
        if skip.contains(&i) {
            continue;
        }
        out.extend(
            o.parts
                .iter()
                .map(|p| Placed::new(Owner::Object(i), p, &poses[i])),
        );
    }
    out
}

/// Every shape of agent `a`'s links at `link_poses`.
pub fn links_at(plan: &Plan, a: usize, link_poses: &[Pose]) -> Vec<Placed> {
    let mut out = Vec::new();
    for (l, link) in plan.agents[a].links.iter().enumerate() {
        let frame = &link_poses[l];
        out.extend(
            link.parts
                .iter()
                .map(|p| Placed::new(Owner::Link(a, l), p, frame)),
        );
    }
    out
}

/// The hand that holds an object posed at `held`: among the links of the agent's declared
/// `hands`, the one whose origin is nearest the object, and every link of the hands it belongs
/// to. Returns (the nearest link, the hand's links); `None` when the agent declares no hand.
pub fn hand_of(agent: &Agent, link_poses: &[Pose], held: &Pose) -> Option<(usize, Vec<usize>)> {
    let near = (0..agent.links.len())
        .filter(|&l| agent.is_grasping(l))
        .min_by(|&i, &j| {
            let di = link_poses[i].translation.distance(held.translation);
            let dj = link_poses[j].translation.distance(held.translation);
            di.total_cmp(&dj)
        })?;
    let mut hand: Vec<usize> = agent
        .hands
        .iter()
        .filter(|h| h.links.contains(&near))
        .flat_map(|h| h.links.iter().copied())
        .collect();
    hand.sort_unstable();
    hand.dedup();
    Some((near, hand))
}

/// Link pairs of one agent that may touch (the self-collision rule):
/// 1. their shapes are within 1 cm of each other in the initial posture (`link_poses`), or
/// 2. one link's origin stays at a fixed point of the other's frame (within 1 mm) in every
///    posture the plan shows: they are joined by a joint (parent and child, possibly through
///    shapeless links), so they may touch as it turns.
pub struct Adjacency {
    n: usize,
    allowed: Vec<bool>,
}

impl Adjacency {
    /// The rule applied to agent `a` over the initial posture and every frame of the plan.
    pub fn new(plan: &Plan, a: usize) -> Self {
        let agent = &plan.agents[a];
        let n = agent.links.len();
        let mut adj = Adjacency {
            n,
            allowed: vec![false; n * n],
        };
        let postures = postures(plan, a);
        for i in 0..n {
            for j in i + 1..n {
                let ok = touch_initially(agent, i, j)
                    || joined(&postures, i, j)
                    || joined(&postures, j, i);
                adj.allowed[i * n + j] = ok;
                adj.allowed[j * n + i] = ok;
            }
        }
        adj
    }

    /// Whether links `i` and `j` may touch.
    pub fn allowed(&self, i: usize, j: usize) -> bool {
        i == j || self.allowed[i * self.n + j]
    }
}

/// The initial posture and every frame of agent `a`.
fn postures(plan: &Plan, a: usize) -> Vec<&[Pose]> {
    let mut out: Vec<&[Pose]> = vec![&plan.agents[a].link_poses];
    for s in &plan.steps {
        for t in s.trajectories.iter().filter(|t| t.agent == a) {
            out.extend(t.frames.iter().map(|f| f.link_poses.as_slice()));
        }
    }
    out
}

fn touch_initially(agent: &Agent, i: usize, j: usize) -> bool {
    let poses = &agent.link_poses;
    agent.links[i].parts.iter().any(|p| {
        let a = Placed::new(Owner::Link(0, i), p, &poses[i]);
        agent.links[j].parts.iter().any(|q| {
            let b = Placed::new(Owner::Link(0, j), q, &poses[j]);
            within(&a, &b, 0.01)
        })
    })
}

fn within(a: &Placed, b: &Placed, gap: f32) -> bool {
    if !a.aabb.loosened(gap).intersects(&b.aabb) {
        return false;
    }
    matches!(
        query::contact(&a.pose, &*a.shape, &b.pose, &*b.shape, gap),
        Ok(Some(_))
    )
}

/// Whether link `child`'s origin is fixed in link `parent`'s frame over all postures.
fn joined(postures: &[&[Pose]], parent: usize, child: usize) -> bool {
    let local = |p: &[Pose]| p[parent].inverse_transform_point(p[child].translation);
    let first = local(postures[0]);
    postures.iter().all(|p| local(p).distance(first) < 1e-3)
}

#[cfg(test)]
mod tests {
    use super::*;
    use parry3d::math::{Rotation, Vector};

    fn placed(owner: Owner, half: [f32; 3], t: [f32; 3], q: [f32; 4]) -> Placed {
        let part = Part {
            shape: SharedShape::cuboid(half[0], half[1], half[2]),
            pose: Pose::IDENTITY,
        };
        let frame = Pose::from_parts(
            Vector::from(t),
            Rotation::from_xyzw(q[0], q[1], q[2], q[3]).normalize(),
        );
        Placed::new(owner, &part, &frame)
    }

    /// A gripper finger 2.9 mm from a book, poses as a planned transfer has them: parry's
    /// `contact` reports 1.5 mm of depth here, so the exact intersection test must decide.
    #[test]
    fn boxes_apart_have_no_depth_though_contact_says_otherwise() {
        let finger = placed(
            Owner::Link(0, 0),
            [0.06, 0.01, 0.015],
            [-0.053_762_64, 0.047_885_887, 1.029_009],
            [-0.834_223_7, 0.437_074_95, 0.312_441_67, 0.124_163_43],
        );
        let book = placed(
            Owner::Object(0),
            [0.12, 0.17, 0.02],
            [0.15, 0.05, 0.8702],
            [-0.572_061_4, 0.415_626_9, 0.572_061_4, 0.415_626_9],
        );
        let gap = query::distance(&finger.pose, &*finger.shape, &book.pose, &*book.shape)
            .unwrap()
            .distance;
        assert!(gap > 0.002, "the boxes are {gap} m apart");
        assert_eq!(depth(&finger, &book), 0.0);
        assert_eq!(depth(&book, &finger), 0.0);
    }

    #[test]
    fn overlapping_boxes_have_their_depth() {
        let a = placed(
            Owner::Object(0),
            [0.1, 0.1, 0.1],
            [0.0, 0.0, 0.0],
            [0.0, 0.0, 0.0, 1.0],
        );
        let b = placed(
            Owner::Object(1),
            [0.1, 0.1, 0.1],
            [0.195, 0.0, 0.0],
            [0.0, 0.0, 0.0, 1.0],
        );
        assert!((depth(&a, &b) - 0.005).abs() < 1e-4, "{}", depth(&a, &b));
    }
}
