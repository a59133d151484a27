//! Shapes placed in the world, the depth query, and the body naming and grouping rules that
//! depend only on the JSON (which hand holds an object, which link pairs are adjacent).

use parry3d::bounding_volume::{Aabb, BoundingVolume};
use parry3d::math::{Pose, Vector};
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
/// boxes that are apart (a finger 2.9 mm from a book read as 1.5 mm deep). The intersection
/// test can err the same way between hulls of hundreds of vertices (a finger's hull 3.0 mm
/// from a forearm's piece read as intersecting), so where it reports contact a pair is still
/// cleared if a separating plane proves it apart ([`separated`]).
pub fn depth(a: &Placed, b: &Placed) -> f32 {
    if !a.aabb.intersects(&b.aabb) {
        return 0.0;
    }
    if query::intersection_test(&a.pose, &*a.shape, &b.pose, &*b.shape)
        .is_ok_and(|i| !i.intersecting)
        || separated(a, b)
    {
        return 0.0;
    }
    match query::contact(&a.pose, &*a.shape, &b.pose, &*b.shape, 0.0) {
        Ok(Some(c)) => (-c.dist).max(0.0),
        _ => 0.0,
    }
}

/// Whether a plane provably separates two convex shapes: the one through parry's closest
/// points, normal to the segment between them, with all of `a` strictly on one side and all of
/// `b` on the other, as the shapes' support points (their farthest points along the normal)
/// show. A proof, whatever the closest points are worth; `false` where there is none.
pub fn separated(a: &Placed, b: &Placed) -> bool {
    let (Some(sa), Some(sb)) = (a.shape.as_support_map(), b.shape.as_support_map()) else {
        return false;
    };
    let margin = 0.05;
    let apart_along = |n: Vector| {
        let top_a = sa.support_point(&a.pose, n).dot(n);
        let bottom_b = sb.support_point(&b.pose, -n).dot(n);
        top_a < bottom_b
    };
    if let Ok(query::ClosestPoints::WithinMargin(pa, pb)) =
        query::closest_points(&a.pose, &*a.shape, &b.pose, &*b.shape, margin)
        && let Some(n) = (pb - pa).try_normalize()
        && apart_along(n)
    {
        return true;
    }
    // Where parry's closest points are no use (its GJK may call large hulls 5 mm apart
    // intersecting): the separating axes.
    separated_by_axes(a, b)
}

/// Whether one of the separating axes of two polyhedra (their faces' normals and the cross
/// products of their edges, one of which separates any two convex polyhedra that are apart)
/// separates `a` and `b`, as their support points show; `false` for a curved shape, and
/// without trying the edges' products when they are more than [`MAX_EDGE_PAIRS`].
pub fn separated_by_axes(a: &Placed, b: &Placed) -> bool {
    let (Some(sa), Some(sb)) = (a.shape.as_support_map(), b.shape.as_support_map()) else {
        return false;
    };
    let (Some((fa, ea)), Some((fb, eb))) = (polyhedral_axes(a), polyhedral_axes(b)) else {
        return false;
    };
    let apart_along = |n: Vector| {
        let (lo_a, hi_a) = (-sa.support_point(&a.pose, -n), sa.support_point(&a.pose, n));
        let (lo_b, hi_b) = (-sb.support_point(&b.pose, -n), sb.support_point(&b.pose, n));
        hi_a.dot(n) < -lo_b.dot(n) || hi_b.dot(n) < -lo_a.dot(n)
    };
    if fa
        .iter()
        .chain(&fb)
        .filter_map(|n| n.try_normalize())
        .any(apart_along)
    {
        return true;
    }
    // The edge pairs too, unless there are so many that a pair overlapping for real (which
    // tries every axis) would cost seconds a configuration: then no proof.
    if ea.len() * eb.len() > MAX_EDGE_PAIRS {
        return false;
    }
    ea.iter()
        .flat_map(|x| eb.iter().map(move |y| x.cross(*y)))
        .filter_map(|n| n.try_normalize())
        .any(apart_along)
}

/// Most edge pairs [`separated_by_axes`] tries (a 455-vertex hull has about 1,350 edges).
const MAX_EDGE_PAIRS: usize = 200_000;

/// The face normals and edge directions of a polyhedral shape (a cuboid's three axes serve as
/// both), in world coordinates; `None` for a curved one.
fn polyhedral_axes(p: &Placed) -> Option<(Vec<Vector>, Vec<Vector>)> {
    let turn = |v: Vector| p.pose.rotation * v;
    if p.shape.as_cuboid().is_some() {
        let axes: Vec<Vector> = [Vector::X, Vector::Y, Vector::Z].map(turn).to_vec();
        return Some((axes.clone(), axes));
    }
    let hull = p.shape.as_convex_polyhedron()?;
    let normals = hull.faces().iter().map(|f| turn(f.normal)).collect();
    let edges = hull.edges().iter().map(|e| turn(e.dir)).collect();
    Some((normals, edges))
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
///    shapeless links), so they may touch as it turns, or
/// 3. the robot's description says so (`disabled_collisions`, its SRDF's pairs).
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
        for &(i, j) in &agent.disabled {
            adj.allowed[i * n + j] = true;
            adj.allowed[j * n + i] = true;
        }
        adj
    }

    /// Whether links `i` and `j` may touch.
    pub fn allowed(&self, i: usize, j: usize) -> bool {
        i == j || self.allowed[i * self.n + j]
    }
}

/// The initial posture and every frame of agent `a`.
pub fn postures(plan: &Plan, a: usize) -> Vec<&[Pose]> {
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

/// Whether `a` and `b` are within `gap` (metres) of each other.
pub fn within(a: &Placed, b: &Placed, gap: f32) -> bool {
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

    /// The two hulls of `testdata/hulls_3mm_apart.json` as a planned approach placed them: `a`,
    /// a convex piece of the real PR2's left forearm (120 vertices), and `b`, its right gripper
    /// finger (376), moved by `shift` metres along the segment between their closest points.
    fn fixture_hulls(shift: f32) -> (Placed, Placed) {
        let text = include_str!("testdata/hulls_3mm_apart.json");
        let json: serde_json::Value = serde_json::from_str(text).unwrap();
        let hull = |key: &str, owner: Owner, shift: Vector| {
            let body = &json[key];
            let f = |v: &serde_json::Value| v.as_f64().unwrap() as f32;
            let points: Vec<Vector> = body["vertices"]
                .as_array()
                .unwrap()
                .iter()
                .map(|p| Vector::new(f(&p[0]), f(&p[1]), f(&p[2])))
                .collect();
            let t = &body["translation"];
            let q = &body["rotation_xyzw"];
            let part = Part {
                shape: SharedShape::convex_hull(&points).unwrap(),
                pose: Pose::IDENTITY,
            };
            let frame = Pose::from_parts(
                Vector::new(f(&t[0]), f(&t[1]), f(&t[2])) + shift,
                Rotation::from_xyzw(f(&q[0]), f(&q[1]), f(&q[2]), f(&q[3])),
            );
            Placed::new(owner, &part, &frame)
        };
        let (a, b) = (
            hull("a", Owner::Link(0, 0), Vector::ZERO),
            hull("b", Owner::Link(0, 1), Vector::ZERO),
        );
        let Ok(query::ClosestPoints::WithinMargin(pa, pb)) =
            query::closest_points(&a.pose, &*a.shape, &b.pose, &*b.shape, 0.1)
        else {
            panic!("the fixture's hulls are near");
        };
        let n = (pb - pa).normalize();
        (a, hull("b", Owner::Link(0, 1), n * shift))
    }

    /// parry's intersection test reports these hulls, 3.0 mm apart, as intersecting (and its
    /// contact as 2.8 mm deep); a separating plane proves them apart.
    #[test]
    fn hulls_apart_have_no_depth_though_the_intersection_test_says_otherwise() {
        let (a, b) = fixture_hulls(0.0);
        let gap = query::distance(&a.pose, &*a.shape, &b.pose, &*b.shape)
            .unwrap()
            .distance;
        assert!((0.0029..0.0031).contains(&gap), "{gap} m apart");
        assert!(
            query::intersection_test(&a.pose, &*a.shape, &b.pose, &*b.shape)
                .unwrap()
                .intersecting,
            "the fixture shows parry's false contact"
        );
        assert!(separated(&a, &b) && separated(&b, &a));
        assert_eq!(depth(&a, &b), 0.0);
        assert_eq!(depth(&b, &a), 0.0);
    }

    /// The separating axes alone (no closest points) prove polyhedra more than 1 mm apart
    /// apart, and never those that overlap by more than 1 mm, however they are turned.
    #[test]
    fn separating_axes_prove_polyhedra_apart_and_only_those() {
        // A small xorshift generator (the crate has no random numbers of its own).
        let mut rng = 0x9e37_79b9_7f4a_7c15u64;
        let unit = |s: &mut u64| {
            *s ^= *s << 13;
            *s ^= *s >> 7;
            *s ^= *s << 17;
            (*s >> 40) as f32 / (1u64 << 24) as f32
        };
        let random = |s: &mut u64| Vector::new(unit(s), unit(s), unit(s));
        let (mut apart, mut overlap) = (0, 0);
        for k in 0..400 {
            let hull = |rng: &mut u64, owner| {
                let corners: Vec<Vector> = (0..8)
                    .map(|c| Vector::new((c & 1) as f32, ((c >> 1) & 1) as f32, (c >> 2) as f32))
                    .map(|v| (v - 0.5) * 0.2)
                    .collect();
                let part = Part {
                    shape: SharedShape::convex_hull(&corners).unwrap(),
                    pose: Pose::IDENTITY,
                };
                let at = Pose::from_parts(
                    (random(rng) - 0.5) * 0.5,
                    Rotation::from_scaled_axis(random(rng) * 3.0),
                );
                Placed::new(owner, &part, &at)
            };
            let (a, b) = (
                hull(&mut rng, Owner::Link(0, 0)),
                hull(&mut rng, Owner::Link(0, 1)),
            );
            let d = query::distance(&a.pose, &*a.shape, &b.pose, &*b.shape)
                .unwrap()
                .distance;
            let deep = query::contact(&a.pose, &*a.shape, &b.pose, &*b.shape, 0.0)
                .unwrap()
                .is_some_and(|c| c.dist < -0.001);
            if d > 0.001 {
                assert!(separated_by_axes(&a, &b), "case {k}: {d} m apart");
                apart += 1;
            } else if deep {
                assert!(
                    !separated_by_axes(&a, &b),
                    "case {k}: overlapping read as apart"
                );
                overlap += 1;
            }
        }
        assert!(
            apart > 50 && overlap > 50,
            "{apart} apart, {overlap} overlapping"
        );
    }

    /// A piece of the real PR2's forearm 5.0 mm from a monitor's box (from a benchmark plan):
    /// parry's intersection test calls them intersecting and its closest points give no
    /// separating plane; the separating axes prove them apart, so they have no depth.
    #[test]
    fn a_forearm_piece_apart_from_a_box_has_no_depth() {
        let text = include_str!("testdata/forearm_piece_5mm_from_box.json");
        let json: serde_json::Value = serde_json::from_str(text).unwrap();
        let v3 = |p: &serde_json::Value| {
            let f = |i: usize| p[i].as_f64().unwrap() as f32;
            Vector::new(f(0), f(1), f(2))
        };
        let points: Vec<Vector> = json["vertices"]
            .as_array()
            .unwrap()
            .iter()
            .map(v3)
            .collect();
        let piece = Part {
            shape: SharedShape::convex_hull(&points).unwrap(),
            pose: Pose::IDENTITY,
        };
        let q = &json["rotation_xyzw"];
        let f = |i: usize| q[i].as_f64().unwrap() as f32;
        let at = Pose::from_parts(
            v3(&json["translation"]),
            Rotation::from_xyzw(f(0), f(1), f(2), f(3)),
        );
        let half = v3(&json["box_half_extents"]);
        let boxed = Part {
            shape: SharedShape::cuboid(half.x, half.y, half.z),
            pose: Pose::IDENTITY,
        };
        let a = Placed::new(Owner::Link(0, 0), &piece, &at);
        let b = Placed::new(
            Owner::Object(0),
            &boxed,
            &Pose::from_translation(v3(&json["box_centre"])),
        );
        assert!(
            query::intersection_test(&a.pose, &*a.shape, &b.pose, &*b.shape)
                .unwrap()
                .intersecting,
            "the fixture shows parry's false contact"
        );
        assert!(separated_by_axes(&a, &b));
        assert_eq!(depth(&a, &b), 0.0);
    }

    /// The same hulls pushed 1 cm into each other: no plane separates them, and the depth is
    /// about what they overlap.
    #[test]
    fn hulls_that_overlap_are_not_cleared() {
        let (a, b) = fixture_hulls(-0.013);
        assert!(!separated(&a, &b) && !separated(&b, &a));
        let d = depth(&a, &b);
        assert!((0.005..0.02).contains(&d), "depth {d}");
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
