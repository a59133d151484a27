//! Helpers shared by the geometry tests (each test file uses some of them).
#![allow(dead_code)]

use std::sync::Arc;

use geometry::agent::AgentModel;
use geometry::collision::{CollisionChecker, Obstacle, StaticObstacles};
use parry3d::math::{Pose, Vector};
use parry3d::shape::SharedShape;

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
    let mut a = template.to_vec();
    for k in 0..motions {
        let r = model.random_configuration(&mut rng).into_vec();
        let mut b = template.to_vec();
        for &d in dofs {
            a[d] = r[d];
            b[d] = r[d] + (rng.f32() - 0.5) * 1.2;
        }
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
