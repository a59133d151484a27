//! Helpers shared by the geometry tests (each test file uses some of them).
#![allow(dead_code)]

use geometry::agent::AgentModel;
use geometry::collision::CollisionChecker;

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
