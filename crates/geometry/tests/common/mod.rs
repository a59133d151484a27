//! Helpers shared by the geometry tests.

use geometry::agent::AgentModel;

/// The SRDF posture `name` of `model`, as `Configuration::set_many` takes it.
pub fn posture<'m>(model: &'m AgentModel, name: &str) -> Vec<(&'m str, f32)> {
    let state = model
        .semantics()
        .group_state(name)
        .unwrap_or_else(|| panic!("the SRDF has no posture {name}"));
    state.values.iter().map(|(j, v)| (j.as_str(), *v)).collect()
}
