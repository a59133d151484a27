//! The totally-ordered HTN planner: forward decomposition, depth first (the SHOP family).
//!
//! The search keeps the task network as a persistent stack (cells in an arena, so undoing a
//! choice is resetting a pointer), the state with an undo trail, and one stack of choice points:
//! method-and-binding choices of abstract tasks, and solution choices of evaluable predicates.
//! Methods are tried in domain order, bindings in the order the binder finds them.
//!
//! Against endless descent, three guards. A task is not decomposed while one of its ancestors
//! decomposes the same ground task in the same state: with no action executed in between (left
//! recursion that made no progress; as HyperTensioN's "dejavu"), or with actions that only led
//! back to that state (bookkeeping actions whose effects already held, say). This may cut off plans in contrived domains,
//! so an exhausted search that used it is repeated without it before the problem is called
//! unsolvable. Then, every node (state, remaining task network, geometric world) is
//! fingerprinted and expanded at most once per search (a revisited node is either on the
//! current path, a cycle, or already failed), and the task network's length is bounded; when
//! the bound cut something off and no plan was found, the search restarts with the bound
//! doubled (iterative deepening). A search that ends with nothing cut off proves the problem
//! unsolvable.
//!
//! Pruning that loses no plan (all of it sound):
//! - *precondition pull-up* (`compile/pull_up.rs`): a method's precondition gains what each
//!   subtask requires over predicates no subtask before it may change (all of the first
//!   subtask's precondition, which is evaluated in the same state; the static literals of every
//!   subtask; a later move's own literals past bookkeeping steps that cannot touch them),
//!   climbing through abstract tasks (a task requires what every one of its methods requires
//!   over its arguments), so bindings fail early and bind through static facts (indexed by
//!   argument);
//! - *late binding* (`compile/late.rs`): a parameter of the problem's `:htn` that the
//!   network's constraints do not read and that one subtask alone uses is left unbound in that
//!   subtask and bound by the subtask's method, in the state where it starts, instead of by
//!   type enumeration before the first action (where a wrong value shows only when the subtask
//!   is reached, and chronological backtracking goes through every value chosen before it);
//! - *goal relevance* (`search/relevance.rs`): each suffix of the task network carries the
//!   set of goal literals its tasks may achieve (per ground task, through the methods whose arguments and
//!   static preconditions fit); a node where a false goal literal can no longer be achieved is
//!   a dead end. Landmarks extend the goal (`compile/landmarks.rs`): a ground literal that
//!   every achiever of a goal literal requires (every action subtask, with the constants its
//!   methods pass, whose effect gives the literal) must hold now or be achievable while a
//!   literal it serves is false; landmarks of landmarks too;
//! - *guarded achievers* (`search/guard.rs`): after an action made a goal literal false (or
//!   changed a fact that guards one), the literal must still be reachable from a task of the
//!   network through methods whose literals over facts that can only be deleted (or only
//!   added) still hold; else the node is a dead end (Multiarm-Blocksworld's consumed
//!   `goal_on` markers).
//!
//! Chronological backtracking goes in rounds of limited discrepancy over geometric solutions
//! (`search/driver.rs`; after Harvey and Ginsberg's LDS). A geometric task's next solution is
//! a *local retry* when no geometric task after it took a solution since its current one (the
//! task after it failed at once): always allowed. Otherwise it *revises* a choice that later
//! geometric tasks built on: round `r` allows revisions at no more than `r` geometric tasks of
//! a path, each at most `2^r` times. Round 0 is the symbolic strategy's search plus local
//! retries. A round that cut no revision off was the plain chronological search, so its
//! failure proves that no plan exists. Plain chronological backtracking (`discrepancy_rounds`
//! off) revises the latest geometric task through all its solutions, times every solution of
//! the ones between, before it revisits an earlier choice or an HTN alternative: in random
//! rooms, thousands of placements of the POS machine before the HTN alternative that works.
//!
//! Geometric-first's chronological pass (`search/driver.rs`): with geometric tasks, the
//! repairs get the first `1 - chronological_share` of the time limit (all of it without one);
//! when that is used, or the search ends with geometric solutions untried, it starts again
//! with chronological backtracking, which tries every solution.
//!
//! Portfolio (`search/portfolio.rs`): with a time limit, on a purely symbolic problem, the
//! depth-first search runs alone for the first `1 - best_first_share` of the time; if it has
//! found no plan by then, a weighted best-first progression search (`search/bfs.rs`, as
//! pandaPI's) starts beside it on a second thread, and the first of the two to decide ends
//! both. Before it, from 1 s on, that thread runs randomized restarts of the depth-first
//! search (`search/restarts.rs`). The best-first search spends a quarter of its time with the state-free estimate, then, when the relaxed
//! composition was ground, the rest with h_add over it (fast estimates solve Transport's
//! road networks, h_add AssemblyHierarchical). It finds the
//! plans of learned domains (Freecell) that amount to a blind state-space search, where the
//! domain-order depth-first search gets lost in abstract descent.

mod compile;
mod eval;
mod search;

use std::time::Duration;

use serde::{Deserialize, Serialize};

use crate::model::{Domain, Problem};
use crate::oracle::{GeometricOracle, OracleError};
use crate::plan::Plan;

/// How the search backtracks over the solutions of evaluable predicates.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize, Default)]
#[serde(rename_all = "kebab-case", tag = "kind")]
pub enum Strategy {
    /// Each geometric task gives at most its first solution; only HTN choices are revisited
    /// (the paper's experiment).
    Symbolic,
    /// Every choice point, latest first (interleaved backtracking), in rounds of limited
    /// discrepancy over geometric revisions (see [`PlannerOptions::discrepancy_rounds`]).
    #[default]
    Chronological,
    /// On a geometric failure (a GS action with no solution, or a task none of whose methods
    /// applies while their preconditions read shared literals), first try up to `k` other
    /// solutions of earlier geometric tasks, newest first, each its share of the `k`, keeping
    /// the HTN choices made since and re-planning the geometric tasks after it; if none makes
    /// the failed task solvable, fall back to HTN alternatives (the paper's Figure 3). When the
    /// search ends with other solutions untried this way, it starts again chronologically, so
    /// that it is as complete as [`Strategy::Chronological`].
    GeometricFirst { k: usize },
}

/// Search limits; `None` is unlimited.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct Limits {
    pub time: Option<Duration>,
    pub nodes: Option<u64>,
    /// Resident memory of the whole process, in MiB.
    pub memory_mb: Option<u64>,
}

/// The limit that stopped a search.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum Limit {
    Time,
    Nodes,
    Memory,
    /// The symbolic strategy's cap of one geometric solution per task: every choice within
    /// the cap failed, which proves nothing.
    GeometricAlternatives,
}

impl std::fmt::Display for Limit {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(match self {
            Limit::Time => "time limit",
            Limit::Nodes => "node limit",
            Limit::Memory => "memory limit",
            Limit::GeometricAlternatives => {
                "strategy's cap on geometric alternatives (not a proof that no plan exists: \
                 --strategy chronological or geometric-first tries every geometric solution)"
            }
        })
    }
}

/// Planner options.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct PlannerOptions {
    pub limits: Limits,
    /// Seeds the search's hashing; the search is deterministic for a given seed.
    pub seed: u64,
    pub strategy: Strategy,
    /// The initial bound on the task network's length (doubled on each restart).
    pub initial_depth_bound: usize,
    /// Prune nodes (state, task network) expanded before. Off only for experiments.
    pub duplicate_detection: bool,
    /// Prune tasks decomposed again by an ancestor with no progress (see the module docs).
    pub loop_check: bool,
    /// Prune a node where a false goal literal's every achiever is barred by a literal that
    /// can no longer change (`search/guard.rs`). Off only for experiments.
    #[serde(default = "default_true")]
    pub goal_guards: bool,
    /// The share of the time limit the best-first search runs beside the depth-first one (see
    /// the module docs): it starts when the depth-first search has used the rest without
    /// deciding. 0 turns it off; without a time limit there is none.
    #[serde(default = "default_best_first_share")]
    pub best_first_share: f64,
    /// With [`Strategy::GeometricFirst`] and a time limit, on a problem with geometric tasks:
    /// the share of the time limit left to the chronological pass; geometric-first's repairs
    /// hand over when they have used the rest without a plan (or earlier, when they are
    /// spent). 0 gives the repairs all the time (the pass only after them).
    #[serde(default = "default_chronological_share")]
    pub chronological_share: f64,
    /// Chronological backtracking over geometric solutions in rounds of limited discrepancy
    /// (see the module docs): round `r` lets at most `r` geometric tasks of a path revise a
    /// solution that later geometric tasks built on, each at most `2^r` times (a retry after a
    /// task that failed at once is always allowed); a round that cut nothing off is the plain
    /// chronological search, so the rounds are as complete. Off: one plain chronological
    /// search.
    #[serde(default = "default_true")]
    pub discrepancy_rounds: bool,
}

fn default_true() -> bool {
    true
}

fn default_best_first_share() -> f64 {
    0.8
}

fn default_chronological_share() -> f64 {
    0.5
}

impl Default for PlannerOptions {
    fn default() -> Self {
        PlannerOptions {
            limits: Limits::default(),
            seed: 0,
            strategy: Strategy::default(),
            initial_depth_bound: 1024,
            duplicate_detection: true,
            loop_check: true,
            goal_guards: true,
            best_first_share: default_best_first_share(),
            chronological_share: default_chronological_share(),
            discrepancy_rounds: true,
        }
    }
}

/// What the search found.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case", tag = "status")]
pub enum Outcome {
    /// A plan.
    Found { plan: Plan },
    /// The whole search space was explored: no plan exists. Never with [`Strategy::Symbolic`]
    /// once a geometric task was asked: its cap on geometric solutions makes the search
    /// incomplete ([`Limit::GeometricAlternatives`]).
    Unsolvable,
    /// A limit stopped the search.
    LimitReached { limit: Limit },
}

/// Search statistics.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct SearchStats {
    /// Nodes expanded (tasks taken off the network).
    pub nodes: u64,
    /// Times an abstract task's next method or binding was tried after a failure.
    pub htn_backtracks: u64,
    /// Times a geometric task's next solution was asked for after a failure.
    pub geo_backtracks: u64,
    /// Nodes pruned because they were expanded before.
    pub revisits_pruned: u64,
    /// Tasks pruned because an ancestor decomposes the same task in the same state.
    pub loops_pruned: u64,
    /// Nodes pruned because the remaining tasks cannot achieve a false goal literal.
    pub goal_pruned: u64,
    /// Method bindings skipped because a subtask deletes, for good, a fact a later task
    /// needs (see `search/consumed.rs`).
    #[serde(default)]
    pub consumed_pruned: u64,
    /// Goal literals with guarded achievers (see `search/guard.rs`); pruning by them counts
    /// in `goal_pruned`.
    #[serde(default)]
    pub guarded_goals: u32,
    /// Nodes cut off by the task-network length bound.
    pub depth_cutoffs: u64,
    /// Searches run (1 + restarts: with a doubled bound, or for a round of limited
    /// discrepancy).
    pub iterations: u32,
    /// The task-network length bound of the last iteration.
    pub depth_bound: usize,
    /// Geometric-first repairs attempted and those that succeeded.
    pub geo_repairs: u64,
    pub geo_repairs_succeeded: u64,
    /// Geometric-first's repairs were spent without a plan and a chronological pass followed.
    #[serde(default)]
    pub chronological_after_repairs: bool,
    /// The last round of limited discrepancy the chronological search ran (0: no geometric
    /// revisions, local retries only; see [`PlannerOptions::discrepancy_rounds`]).
    #[serde(default)]
    pub discrepancy_round: u32,
    /// Whether the best-first fallback search ran, and the nodes it expanded (counted in
    /// `nodes` too).
    #[serde(default)]
    pub best_first: bool,
    #[serde(default)]
    pub best_first_nodes: u64,
    /// Randomized depth-first runs of the portfolio (`search/restarts.rs`); their nodes count
    /// in `nodes`.
    #[serde(default)]
    pub restarts: u64,
    /// Ground actions and methods of the best-first search's relaxed composition (both 0
    /// when it was not ground: no fallback, or a cap of `search/heuristic.rs` stopped it).
    #[serde(default)]
    pub rc_actions: u64,
    #[serde(default)]
    pub rc_methods: u64,
    /// Wall-clock time of the search, in seconds.
    pub time_s: f64,
    /// Peak resident memory of the process seen during the search, in KiB (0 if unknown).
    pub peak_memory_kb: u64,
}

/// The result of a search: the outcome and how it went.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct SearchResult {
    #[serde(flatten)]
    pub outcome: Outcome,
    pub stats: SearchStats,
}

/// Why planning could not run.
#[derive(Debug, thiserror::Error)]
pub enum PlanError {
    /// The model is inconsistent (unknown names); the parser normally catches these.
    #[error("invalid model: {0}")]
    Model(String),
    /// The domain uses evaluable predicates and no geometric back end was given.
    #[error(
        "action `{action}` is a GS action (its precondition holds `(evaluable ({task} ...))`): planning it needs a geometric back end (a scene), and none was given"
    )]
    NoOracle { action: String, task: String },
    #[error(transparent)]
    Oracle(#[from] OracleError),
    /// A limit passed while compiling (the search would have stopped at once).
    #[error("stopped: {0} reached while compiling")]
    Stopped(Limit),
}

/// Plans `problem` in `domain`. `oracle` answers evaluable predicates; without one, a domain
/// with GS actions is refused with [`PlanError::NoOracle`]. The time limit covers compiling
/// too (and the geometric back end's initial facts): the search's clock starts before it. A plan
/// found spells its names as the files declare them.
pub fn plan<'o>(
    domain: &Domain,
    problem: &Problem,
    options: &PlannerOptions,
    oracle: Option<&'o mut (dyn GeometricOracle + 'o)>,
) -> Result<SearchResult, PlanError> {
    let began = std::time::Instant::now();
    let mut watch = crate::budget::Watch::new(
        options.limits.time.map(|t| began + t),
        options.limits.memory_mb,
    );
    let stopped = |limit: Limit| SearchResult {
        outcome: Outcome::LimitReached { limit },
        stats: SearchStats {
            time_s: began.elapsed().as_secs_f64(),
            peak_memory_kb: current_rss_kb(),
            ..SearchStats::default()
        },
    };
    let compiled = match compile::compile(domain, problem, &mut watch) {
        Ok(c) => c,
        Err(PlanError::Stopped(limit)) => return Ok(stopped(limit)),
        Err(e) => return Err(e),
    };
    if let Some(limit) = watch.check() {
        return Ok(stopped(limit));
    }
    if oracle.is_none()
        && let Some(a) = compiled.actions.iter().find(|a| a.evaluable.is_some())
    {
        let g = a.evaluable.as_ref().map(|(g, _)| *g).unwrap_or(0);
        return Err(PlanError::NoOracle {
            action: a.name.clone(),
            task: compiled.geo_tasks[g as usize].clone(),
        });
    }
    let search = search::Search::new(&compiled, options, oracle)?.started_at(began);
    let mut result = if search.has_portfolio() {
        search.run_portfolio()?
    } else {
        search.run()?
    };
    if let Outcome::Found { plan } = &mut result.outcome {
        plan.respell(domain, problem);
    }
    Ok(result)
}

/// Resident memory of this process in KiB, from `/proc/self/statm` (0 where unavailable).
pub fn current_rss_kb() -> u64 {
    std::fs::read_to_string("/proc/self/statm")
        .ok()
        .and_then(|s| s.split_whitespace().nth(1)?.parse::<u64>().ok())
        .map_or(0, |pages| pages * 4)
}

/// Peak resident memory of this process in KiB (`VmHWM` of `/proc/self/status`; 0 where unavailable).
pub fn peak_rss_kb() -> u64 {
    std::fs::read_to_string("/proc/self/status")
        .ok()
        .and_then(|s| {
            s.lines()
                .find(|l| l.starts_with("VmHWM:"))?
                .split_whitespace()
                .nth(1)?
                .parse()
                .ok()
        })
        .unwrap_or(0)
}
