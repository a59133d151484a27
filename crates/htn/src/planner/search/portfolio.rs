//! The portfolio on problems without geometric actions: when the depth-first search has
//! found no plan in its share of the time limit (`1 - best_first_share`), the best-first search
//! starts beside it, on a second thread, under the same limits, and the depth-first search goes
//! on; the first to find a plan or to prove there is none decides, and the other stops at its
//! next check. Why: each engine solves problems the other does not in time (one wrong early
//! choice ruins the depth-first search for millions of nodes; a large ground model overwhelms
//! the best-first one), and the handover that stopped the depth-first search there lost the
//! problems it would have solved a few seconds later. Problems decided in the depth-first
//! search's share are searched exactly as before, on one thread. The best-first search keeps
//! to three quarters of the memory limit, so that it never starves the depth-first one.
//!
//! Before the best-first search, from 1 s on, the second thread runs randomized restarts of
//! the depth-first search (`restarts.rs`), under the same memory share; what the depth-first
//! search decides in its first second is still decided on one thread, deterministically.

use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::{Duration, Instant};

use super::super::compile::Compiled;
use super::super::{Outcome, PlanError, PlannerOptions, SearchResult};
use super::{Search, Stop};
use crate::budget::{StopOn, Watch};

impl Search<'_, '_> {
    /// Whether [`Search::run_portfolio`] applies: no geometric oracle, and the best-first
    /// engine enabled under a time limit.
    pub fn has_portfolio(&self) -> bool {
        self.oracle.is_none() && self.switch_at.is_some()
    }

    /// Runs the depth-first engine here and, from its handover time on, the best-first engine
    /// beside it (see the module's docs); where no thread can be started, [`Search::run`] with
    /// its handover.
    pub fn run_portfolio(mut self) -> Result<SearchResult, PlanError> {
        let decided = Arc::new(AtomicBool::new(false));
        let (c, opts, start) = (self.c, self.opts, self.start);
        let begin = self.switch_at.and_then(|s| start.checked_add(s));
        std::thread::scope(|scope| {
            let flag = decided.clone();
            let spawned = std::thread::Builder::new()
                .name("htn-best-first".into())
                // The main thread's stack, where the best-first search ran before.
                .stack_size(8 << 20)
                .spawn_scoped(scope, move || second_thread(c, &opts, start, begin, &flag));
            let Ok(best_first) = spawned else {
                return self.run();
            };
            self.switch_at = None;
            let stop = StopOn::install(decided.clone());
            let depth_first = self.run();
            drop(stop);
            if depth_first.as_ref().map_or(true, |r| decisive(&r.outcome)) {
                decided.store(true, Ordering::Relaxed);
            }
            let best_first = best_first
                .join()
                .unwrap_or_else(|e| std::panic::resume_unwind(e));
            let depth_first = depth_first?;
            Ok(match best_first? {
                Some(b) => combine(depth_first, b),
                None => depth_first,
            })
        })
    }

    /// The best-first engine alone, from the initial node.
    fn run_best_first(mut self) -> SearchResult {
        let outcome = match self.best_first() {
            Stop::Found => Outcome::Found {
                plan: self.build_plan(),
            },
            Stop::Limit(limit) => Outcome::LimitReached { limit },
            Stop::Exhausted | Stop::Switch => self.unsolvable_or_limit(),
        };
        self.finish(outcome)
    }
}

/// The second thread: randomized restarts from [`RESTARTS_AFTER`] (or the handover time, when
/// sooner) to the handover time `begin`, then the best-first search; `None` when the
/// depth-first search decided first. Both keep to three quarters of the memory limit.
fn second_thread(
    c: &Compiled,
    opts: &PlannerOptions,
    start: Instant,
    begin: Option<Instant>,
    flag: &Arc<AtomicBool>,
) -> Result<Option<SearchResult>, PlanError> {
    let deadline = opts.limits.time.and_then(|t| start.checked_add(t));
    let memory = opts.limits.memory_mb.map(|m| m / 4 * 3);
    let fresh = || -> Result<Search<'_, '_>, PlanError> {
        let mut s = Search::new(c, opts, None)?.started_at(start);
        s.watch = Watch::new(deadline, memory);
        Ok(s)
    };
    let restarts_from = begin.map(|b| start.checked_add(RESTARTS_AFTER).map_or(b, |r| b.min(r)));
    if !wait_until(restarts_from, flag) {
        return Ok(None);
    }
    let _stop = StopOn::install(flag.clone());
    let mut restarts = (0, 0);
    if let Some(until) = begin.filter(|&b| Instant::now() < b) {
        let mut r = fresh()?;
        let outcome = match r.restarts(until)? {
            Stop::Found => Some(Outcome::Found {
                plan: r.build_plan(),
            }),
            Stop::Limit(limit) => Some(Outcome::LimitReached { limit }),
            Stop::Exhausted | Stop::Switch => None,
        };
        if let Some(outcome) = outcome {
            let r = r.finish(outcome);
            if decisive(&r.outcome) {
                flag.store(true, Ordering::Relaxed);
            }
            return Ok(Some(r));
        }
        restarts = (r.stats.restarts, r.stats.nodes);
    }
    if !wait_until(begin, flag) {
        return Ok(None);
    }
    let mut r = fresh()?.run_best_first();
    (r.stats.restarts, r.stats.nodes) = (restarts.0, r.stats.nodes + restarts.1);
    if decisive(&r.outcome) {
        flag.store(true, Ordering::Relaxed);
    }
    Ok(Some(r))
}

/// When the restarts start: the depth-first search runs alone for its first second, so that
/// what it decides there is decided exactly as without them (one thread, the domain's order).
const RESTARTS_AFTER: Duration = Duration::from_secs(1);

/// Waits until `begin` (at once without one); false when `decided` is set first.
fn wait_until(begin: Option<Instant>, decided: &AtomicBool) -> bool {
    while let Some(left) = begin.and_then(|b| b.checked_duration_since(Instant::now())) {
        if decided.load(Ordering::Relaxed) {
            return false;
        }
        std::thread::sleep(left.min(Duration::from_millis(5)));
    }
    !decided.load(Ordering::Relaxed)
}

/// A plan, or a proof that there is none.
fn decisive(o: &Outcome) -> bool {
    matches!(o, Outcome::Found { .. } | Outcome::Unsolvable)
}

/// The engine that decided (the depth-first one when both did), with both engines' node
/// counts and the higher memory peak; both at a limit: the depth-first one's.
fn combine(d: SearchResult, b: SearchResult) -> SearchResult {
    let (mut winner, other) = if !decisive(&d.outcome) && decisive(&b.outcome) {
        (b, d)
    } else {
        (d, b)
    };
    winner.stats.nodes += other.stats.nodes;
    winner.stats.restarts = winner.stats.restarts.max(other.stats.restarts);
    winner.stats.best_first_nodes = winner
        .stats
        .best_first_nodes
        .max(other.stats.best_first_nodes);
    winner.stats.rc_actions = winner.stats.rc_actions.max(other.stats.rc_actions);
    winner.stats.rc_methods = winner.stats.rc_methods.max(other.stats.rc_methods);
    winner.stats.peak_memory_kb = winner.stats.peak_memory_kb.max(other.stats.peak_memory_kb);
    winner.stats.time_s = winner.stats.time_s.max(other.stats.time_s);
    winner
}
