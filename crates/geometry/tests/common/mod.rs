//! Helpers shared by the geometry tests (each test file uses some of them).
#![allow(dead_code)]

use std::sync::Arc;

use geometry::agent::AgentModel;
use geometry::collision::{CollisionChecker, Contact, Obstacle, StaticObstacles};
use parry3d::math::{Pose, Vector};
use parry3d::shape::SharedShape;

/// The joints of the PR2's right arm, shoulder to wrist (the real PR2's and the hand-written
/// one's names).
pub const PR2_RIGHT_ARM: [&str; 7] = [
    "r_shoulder_pan_joint",
    "r_shoulder_lift_joint",
    "r_upper_arm_roll_joint",
    "r_elbow_flex_joint",
    "r_forearm_roll_joint",
    "r_wrist_flex_joint",
    "r_wrist_roll_joint",
];

/// The SRDF posture `name` of `model`, as `Configuration::set_many` takes it.
pub fn posture<'m>(model: &'m AgentModel, name: &str) -> Vec<(&'m str, f32)> {
    let state = model
        .semantics()
        .group_state(name)
        .unwrap_or_else(|| panic!("the SRDF has no posture {name}"));
    state.values.iter().map(|(j, v)| (j.as_str(), *v)).collect()
}

/// Whether any of `n` evenly spaced configurations of the straight motion `a -> b` (the end
/// included, the start not) collides: the dense sampling the motion checks are tested against.
pub fn sampled_collision(checker: &CollisionChecker, a: &[f32], b: &[f32], n: usize) -> bool {
    let mut q = a.to_vec();
    (1..=n).any(|s| {
        let t = s as f32 / n as f32;
        for (v, (x, y)) in q.iter_mut().zip(a.iter().zip(b)) {
            *v = x + t * (y - x);
        }
        !checker.is_config_free(&q)
    })
}

/// A box obstacle of half extents `half` centred at `centre`.
pub fn boxed(name: &str, centre: Vector, half: Vector) -> Obstacle {
    Obstacle {
        name: name.to_string(),
        pose: Pose::from_translation(centre),
        shape: SharedShape::cuboid(half.x, half.y, half.z),
    }
}

/// The scene of the arm-motion tests, for a PR2 at the origin: a table at its right hand and a
/// 2 mm slab above it, which an arm can swing through between two free configurations.
pub fn table_and_slab() -> Arc<StaticObstacles> {
    Arc::new(StaticObstacles::new(vec![
        boxed(
            "table",
            Vector::new(0.95, -0.4, 0.3),
            Vector::new(0.4, 0.25, 0.3),
        ),
        boxed(
            "slab",
            Vector::new(0.8, -0.45, 0.9),
            Vector::new(0.3, 0.001, 0.3),
        ),
    ]))
}

/// A random straight motion of the joints `dofs` of `template`: from a random configuration
/// of them, each moved by up to 0.6 rad; the other joints at `template`'s values.
pub fn random_motion(
    model: &AgentModel,
    (template, dofs): (&[f32], &[usize]),
    rng: &mut fastrand::Rng,
) -> (Vec<f32>, Vec<f32>) {
    let r = model.random_configuration(rng).into_vec();
    let (mut a, mut b) = (template.to_vec(), template.to_vec());
    for &d in dofs {
        a[d] = r[d];
        b[d] = r[d] + (rng.f32() - 0.5) * 1.2;
    }
    (a, b)
}

/// `motions` random straight motions of the joints `dofs` from `template` (each joint moved
/// by up to 0.6 rad; `seed` seeds them): where the start is free for `reference`, the motion
/// check of `checked[k % len]` must find a collision exactly where `steps` evenly spaced
/// configurations do for `reference`. Returns the numbers of colliding and free motions.
pub fn motions_agree_with_sampling(
    model: &AgentModel,
    (reference, checked): (&CollisionChecker, &[&CollisionChecker]),
    (template, dofs): (&[f32], &[usize]),
    (seed, motions, steps): (u64, usize, usize),
) -> (usize, usize) {
    let mut rng = fastrand::Rng::with_seed(seed);
    let (mut hit, mut free) = (0, 0);
    for k in 0..motions {
        let (a, b) = random_motion(model, (template, dofs), &mut rng);
        if !reference.is_config_free(&a) {
            continue;
        }
        let sampled = sampled_collision(reference, &a, &b, steps);
        let checker = checked[k % checked.len()];
        let found = checker.check_motion(&a, &b, 1e-4).contact.is_some();
        assert_eq!(
            found, sampled,
            "motion {k}: dense sampling finds a collision: {sampled}"
        );
        if sampled {
            hit += 1;
        } else {
            free += 1;
        }
    }
    (hit, free)
}

/// The least exact signed distance (parry's; below 0 where shapes overlap) between the
/// shapes of links `a` and `b` of `model` in configuration `q`. Each pair's is the larger of
/// parry's distance query and its contact query, which disagree within a millimetre or so of
/// contact: the first calls two hulls 0.07 mm apart touching, the second a capsule 0.7 mm from
/// a box 0.5 mm into it (its distance query: 2.6 mm apart).
pub fn link_distance(model: &AgentModel, q: &[f32], (a, b): (&str, &str)) -> f32 {
    let (a, b) = (model.link_id(a).unwrap(), model.link_id(b).unwrap());
    let shapes = model.posed_shapes(Pose::IDENTITY, q);
    let mut best = f32::INFINITY;
    for (_, ca, pa) in shapes.iter().filter(|s| s.0 == a) {
        for (_, cb, pb) in shapes.iter().filter(|s| s.0 == b) {
            let (sa, sb) = (&*ca.shape.0, &*cb.shape.0);
            let apart = parry3d::query::distance(pa, sa, pb, sb).unwrap().distance;
            let d = match parry3d::query::contact(pa, sa, pb, sb, 0.01).unwrap() {
                Some(c) => c.dist.max(apart),
                None => apart,
            };
            best = best.min(d);
        }
    }
    best
}

/// Whether every collision `without` finds at `q` is a pair of links that parry's exact
/// distance puts apart (parry's intersection test calls a capsule and a box 5 mm apart
/// intersecting) or overlapping by at most `depth`, and one in `cell_pairs` where given: what a
/// checker with pair cells may call free.
fn only_hairs_apart(
    model: &AgentModel,
    without: &CollisionChecker,
    (q, depth): (&[f32], f32),
    cell_pairs: Option<&[(String, String)]>,
) -> bool {
    without.collisions(q).iter().all(|c| match c {
        Contact::SelfCollision { link_a, link_b } => {
            let pair = (link_a.clone(), link_b.clone());
            let flipped = (link_b.clone(), link_a.clone());
            cell_pairs.is_none_or(|p| p.contains(&pair) || p.contains(&flipped))
                && link_distance(model, q, (link_a, link_b)) > -depth
        }
        _ => false,
    })
}

/// Pair cells never free what collides: `configs` random configurations and as many random
/// straight motions of the joints `dofs` from `template` (`seed` seeds them), checked by
/// `with` (pair cells on) and `without` (off). Where `with` finds free what `without` does
/// not, every collision `without` finds must be a pair of links with cells that parry's exact
/// distance puts apart; never the other way round. A motion `with` certifies free must be
/// free at 200 configurations along it: each collision `without` finds there a pair that
/// parry's exact distance puts apart or overlapping by at most half the motion check's floor
/// (the depth of a contact its measurements may step over).
pub fn pair_cells_are_sound(
    model: &AgentModel,
    (with, without): (&CollisionChecker, &CollisionChecker),
    (template, dofs): (&[f32], &[usize]),
    (seed, configs): (u64, usize),
) {
    let cell_pairs: Vec<(String, String)> = with
        .self_collision_model()
        .pairs_with_cells()
        .iter()
        .map(|(a, b)| (a.to_string(), b.to_string()))
        .collect();
    assert!(!cell_pairs.is_empty(), "no pair of links has cells");
    const FLOOR: f32 = 1e-4;
    let mut rng = fastrand::Rng::with_seed(seed);
    for k in 0..configs {
        let (a, b) = random_motion(model, (template, dofs), &mut rng);
        let (free_with, free_without) = (with.is_config_free(&a), without.is_config_free(&a));
        assert!(
            free_with || !free_without,
            "configuration {k}: cells add a collision"
        );
        if free_with != free_without {
            assert!(
                only_hairs_apart(model, without, (&a, 0.0), Some(&cell_pairs)),
                "configuration {k}: cells free a collision: {:?}",
                without.collisions(&a)
            );
        }
        if !free_with || with.check_motion(&a, &b, FLOOR).contact.is_some() {
            continue;
        }
        let mut q = a.clone();
        for s in 1..=200 {
            let t = s as f32 / 200.0;
            for (v, (x, y)) in q.iter_mut().zip(a.iter().zip(&b)) {
                *v = x + t * (y - x);
            }
            if !without.is_config_free(&q) {
                assert!(
                    only_hairs_apart(model, without, (&q, FLOOR / 2.0), None),
                    "motion {k} at {t}: a motion certified free collides: {:?}",
                    without.collisions(&q)
                );
            }
        }
    }
}

/// An ASCII STL of an axis-aligned box with these half extents, centred at the origin.
pub fn box_stl(h: [f32; 3]) -> String {
    let v = |i: usize| {
        let s = |bit: usize, k: usize| if i >> bit & 1 == 1 { h[k] } else { -h[k] };
        [s(0, 0), s(1, 1), s(2, 2)]
    };
    // Two triangles per face, as corner indices (bit 0: +x, bit 1: +y, bit 2: +z).
    let faces = [
        [0, 2, 6, 4],
        [1, 5, 7, 3],
        [0, 4, 5, 1],
        [2, 3, 7, 6],
        [0, 1, 3, 2],
        [4, 6, 7, 5],
    ];
    let mut out = String::from("solid box\n");
    for f in faces {
        for t in [[f[0], f[1], f[2]], [f[0], f[2], f[3]]] {
            out.push_str("facet normal 0 0 0\nouter loop\n");
            for i in t {
                let p = v(i);
                out.push_str(&format!("vertex {} {} {}\n", p[0], p[1], p[2]));
            }
            out.push_str("endloop\nendfacet\n");
        }
    }
    out.push_str("endsolid box\n");
    out
}
