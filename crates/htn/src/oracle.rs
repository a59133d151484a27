//! The evaluable-predicate interface: how the HTN planner asks the geometric world.
//!
//! An action whose precondition holds `(evaluable (t args))` is a *GS action*. When the planner
//! tries one, it asks the [`GeometricOracle`] for the solutions of the ground geometric task
//! `t(args)` in the current world. Solutions come lazily, one at a time; each is a choice point.
//! Taking a solution ([`GeometricOracle::apply`]) changes the world (an object is placed, the
//! arm moved); backtracking over it ([`GeometricOracle::undo`]) restores the world as it was.
//! The planner keeps stack discipline: `undo` always undoes the most recent `apply` not yet
//! undone, so the oracle can keep a stack of worlds.
//!
//! A stream is asked for its next solution only while the world is the one it was opened in
//! (every solution taken from it in between has been undone). A solution may be applied again
//! later in that same world (after backtracking and replaying), so `apply` must work from the
//! solution's data alone.
//!
//! This crate knows nothing of geometry; the `hybrid` crate implements this trait with the GTP.

use serde::{Deserialize, Serialize};

/// A ground atom over names: `(on grey-book desk)`.
#[derive(Clone, Debug, PartialEq, Eq, Hash, PartialOrd, Ord, Serialize, Deserialize)]
pub struct GroundAtom {
    pub predicate: String,
    pub args: Vec<String>,
}

impl GroundAtom {
    /// An atom from a predicate and argument names.
    pub fn new(predicate: &str, args: &[&str]) -> GroundAtom {
        GroundAtom {
            predicate: predicate.to_string(),
            args: args.iter().map(|a| a.to_string()).collect(),
        }
    }
}

impl std::fmt::Display for GroundAtom {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "({}", self.predicate)?;
        for a in &self.args {
            write!(f, " {a}")?;
        }
        write!(f, ")")
    }
}

/// An opaque handle on one solution of the geometric back end. What it stands for (grasp,
/// placement, trajectories, the world after it) stays with the back end that gave it out; the
/// plan step keeps the handle, so the back end's caller can look the solution up, typed.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord, Serialize, Deserialize)]
pub struct SolutionId(pub u64);

/// One solution of a geometric task: the shared literals it makes true (`t+`) and false (`t-`),
/// and the back end's handle on it.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct GeoSolution {
    pub add: Vec<GroundAtom>,
    pub delete: Vec<GroundAtom>,
    pub id: SolutionId,
}

/// A handle on a lazy stream of solutions, given out by [`GeometricOracle::open`].
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub struct StreamId(pub u64);

/// An error of the geometric back end; it stops the search.
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
#[error("geometric back end: {0}")]
pub struct OracleError(pub String);

/// The geometric half as the HTN planner sees it.
pub trait GeometricOracle {
    /// The facts of the shared predicates that hold in the initial world.
    fn initial_facts(&mut self) -> Result<Vec<GroundAtom>, OracleError>;

    /// Starts looking for solutions of the geometric task `task(args)` in the current world.
    fn open(&mut self, task: &str, args: &[String]) -> Result<StreamId, OracleError>;

    /// The next solution of `stream`, or `None` when there are no more. Called only while the
    /// world is the one the stream was opened in.
    fn next_solution(&mut self, stream: StreamId) -> Result<Option<GeoSolution>, OracleError>;

    /// Forgets a stream (no more solutions will be asked of it).
    fn close(&mut self, stream: StreamId);

    /// Takes the solution `id` (one this oracle gave out): the world becomes the world after it.
    fn apply(&mut self, id: SolutionId) -> Result<(), OracleError>;

    /// Undoes the most recent `apply` not yet undone.
    fn undo(&mut self);

    /// A hash of the current world; the planner's duplicate detection includes it, so two nodes
    /// with the same symbolic state but different worlds are told apart. Return a constant only
    /// if the world is fully described by the shared literals.
    fn world_fingerprint(&self) -> u64;

    /// The instant the search must end by (its time limit), so that a geometric call stops
    /// there too rather than run past it; called when a search starts. The default ignores it.
    fn set_deadline(&mut self, _deadline: Option<std::time::Instant>) {}
}
