//! One combined HTN-GTP planning run: a domain, a problem and a 3D scene in, a plan whose GS
//! actions carry their geometric solutions out.

use std::path::Path;
use std::sync::Arc;

use geometry::world::World;
use gtp::planner::Planner;
use htn::model::{Domain, Problem};
use htn::planner::{Outcome, PlannerOptions, SearchResult};

use crate::oracle::{GtpOracle, OracleConfig};

/// Why a run could not start or was stopped by a broken input.
#[derive(Debug, thiserror::Error)]
pub enum HybridError {
    #[error(transparent)]
    Parse(#[from] htn::ParseError),
    #[error(transparent)]
    Scene(#[from] geometry::scene::SceneError),
    #[error(transparent)]
    Plan(#[from] htn::planner::PlanError),
    #[error("the plan found does not validate: {0}")]
    Invalid(String),
}

/// Options of a run: the HTN search's and the oracle's.
#[derive(Clone, Debug, Default)]
pub struct RunOptions {
    pub planner: PlannerOptions,
    pub oracle: OracleConfig,
}

/// A finished run: the search result and the oracle, which still holds every geometric
/// solution the plan refers to (for pictures, trajectories and final poses).
pub struct Run {
    pub result: SearchResult,
    pub oracle: GtpOracle,
    /// The world the run started from.
    pub initial: World,
}

impl Run {
    /// The world after the plan's last GS action (the initial world when there is none).
    pub fn final_world(&self) -> &World {
        match &self.result.outcome {
            Outcome::Found { plan } => plan
                .actions
                .iter()
                .rev()
                .filter_map(|a| a.geometric.as_ref())
                .find_map(|g| self.oracle.solution_world(g.solution))
                .unwrap_or(&self.initial),
            _ => &self.initial,
        }
    }
}

impl Run {
    /// Why no plan was found, in words: the last geometric task that failed and the constraint
    /// that stopped it, when there is one.
    pub fn failure_message(&self) -> String {
        match self.oracle.last_failure() {
            Some(f) => format!(
                "no decomposition works; the last geometric task to fail was {}({}): {}",
                f.task,
                f.args.join(", "),
                f.why
            ),
            None => "no decomposition works (no geometric task failed)".into(),
        }
    }
}

/// The names the HTN problem knows: its objects and the domain's constants.
pub fn known_names(domain: &Domain, problem: &Problem) -> Vec<String> {
    domain
        .constants
        .iter()
        .chain(&problem.objects)
        .map(|t| t.name.clone())
        .collect()
}

/// Plans `problem` with the geometric tasks answered by `planner` in `world`. The plan is
/// checked by the `htn` validator (its symbolic part) before it is returned.
pub fn plan(
    domain: &Domain,
    problem: &Problem,
    world: World,
    planner: Arc<Planner>,
    options: &RunOptions,
) -> Result<Run, HybridError> {
    let mut oracle = GtpOracle::new(
        planner,
        world.clone(),
        known_names(domain, problem),
        options.oracle.clone(),
    );
    let result = htn::planner::plan(domain, problem, &options.planner, Some(&mut oracle))?;
    if let Outcome::Found { plan } = &result.outcome {
        htn::validate::validate(domain, problem, plan, &oracle.initial_literals())
            .map_err(|e| HybridError::Invalid(e.to_string()))?;
    }
    Ok(Run {
        result,
        oracle,
        initial: world,
    })
}

/// Loads a domain, a problem and a scene from files and plans.
pub fn plan_files(
    domain: &Path,
    problem: &Path,
    scene: &Path,
    options: &RunOptions,
) -> Result<Run, HybridError> {
    let domain = htn::load_domain(domain)?;
    let problem = htn::load_problem(problem, &domain)?;
    let world = World::load(scene)?;
    plan(&domain, &problem, world, Arc::new(Planner::new()), options)
}
