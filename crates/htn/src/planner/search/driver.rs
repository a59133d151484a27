//! The driver over the engines: depth-first iterations with a doubling depth bound (and one
//! more without the left-recursion check before calling a problem unsolvable), the rounds of
//! limited discrepancy of chronological backtracking (until one cuts nothing off), the
//! chronological pass after geometric-first's repairs (when they are spent or have used their
//! share of the time limit), and the fallback to the best-first engine after the depth-first
//! one's share of the time limit.

use super::super::compile::Compiled;
use super::super::{
    Limit, Outcome, PlanError, PlannerOptions, SearchResult, Strategy, current_rss_kb,
};
use super::limits::drop_in_background;
use super::{Search, Stop};

impl<'a, 'o> Search<'a, 'o> {
    /// Runs the search to a plan, a proof that there is none, or a limit.
    pub fn run(mut self) -> Result<SearchResult, PlanError> {
        let deadline = self
            .opts
            .limits
            .time
            .and_then(|t| self.start.checked_add(t));
        if let Some(o) = self.oracle.as_deref_mut() {
            o.set_deadline(deadline);
        }
        let outcome = loop {
            self.stats.iterations += 1;
            self.stats.depth_bound = self.bound;
            self.cutoff = false;
            let loops_before = self.stats.loops_pruned;
            match self.dfs()? {
                Stop::Found => {
                    break Outcome::Found {
                        plan: self.build_plan(),
                    };
                }
                Stop::Limit(l) => break Outcome::LimitReached { limit: l },
                Stop::Switch if matches!(self.opts.strategy, Strategy::GeometricFirst { .. }) => {
                    self.go_chronological();
                    continue;
                }
                Stop::Switch => {
                    self.switch_at = None;
                    break match self.best_first() {
                        Stop::Found => Outcome::Found {
                            plan: self.build_plan(),
                        },
                        Stop::Limit(l) => Outcome::LimitReached { limit: l },
                        // Every node reachable was generated (only sound pruning), unless a
                        // join gave up at a limit.
                        Stop::Exhausted | Stop::Switch => self.unsolvable_or_limit(),
                    };
                }
                Stop::Exhausted => {
                    if self.discrepancy_cut {
                        // The round cut geometric solutions off: the next allows more.
                        self.next_discrepancy_round();
                        continue;
                    }
                    if self.loop_check && self.stats.loops_pruned > loops_before {
                        // The left-recursion check may have cut off the only plans: search
                        // again without it before calling the problem unsolvable.
                        self.loop_check = false;
                        self.reset();
                        continue;
                    }
                    if !self.cutoff && self.repairs_spent() {
                        // Geometric-first's repairs found nothing: go on chronologically, over
                        // every geometric solution, so that it is as complete as that strategy.
                        self.go_chronological();
                        continue;
                    }
                    if !self.cutoff {
                        break if self.geo_capped {
                            Outcome::LimitReached {
                                limit: Limit::GeometricAlternatives,
                            }
                        } else {
                            self.unsolvable_or_limit()
                        };
                    }
                    self.reset();
                    self.bound = self.bound.saturating_mul(2);
                }
            }
        };
        Ok(self.finish(outcome))
    }

    /// The result of an engine that ended with `outcome`: its statistics completed, the tables
    /// that grew with the search freed off the caller's time.
    pub(super) fn finish(mut self, outcome: Outcome) -> SearchResult {
        self.stats.time_s = self.start.elapsed().as_secs_f64();
        drop_in_background((
            std::mem::take(&mut self.gtasks),
            std::mem::take(&mut self.arena),
            std::mem::take(&mut self.tree),
            std::mem::take(&mut self.visited),
            std::mem::take(&mut self.may_memo),
            std::mem::take(&mut self.htn_frames),
        ));
        self.stats.peak_memory_kb = self.stats.peak_memory_kb.max(current_rss_kb());
        SearchResult {
            outcome,
            stats: self.stats,
        }
    }
}

impl Search<'_, '_> {
    /// Whether a geometric-first search ended with geometric solutions it never tried (its
    /// repairs' budget spent): a chronological pass comes next.
    fn repairs_spent(&self) -> bool {
        self.geo_capped && matches!(self.opts.strategy, Strategy::GeometricFirst { .. })
    }

    /// Starts the next round of limited discrepancy from the initial node.
    fn next_discrepancy_round(&mut self) {
        let r = self.discrepancy.map_or(0, |r| r + 1);
        self.discrepancy = Some(r);
        self.discrepancy_cut = false;
        self.stats.discrepancy_round = r;
        self.reset();
    }

    /// Starts the chronological pass that follows geometric-first's repairs.
    fn go_chronological(&mut self) {
        // The handover may come in the middle of a repair: its candidates name frames that
        // the reset pops.
        self.end_repair();
        self.opts.strategy = Strategy::Chronological;
        self.geo_capped = false;
        self.stats.chronological_after_repairs = true;
        self.loop_check = self.opts.loop_check;
        self.switch_at = None;
        self.reset();
    }

    /// "No plan": only when no precondition join gave up at a limit on the way (a join cut
    /// short leaves bindings untried).
    pub(super) fn unsolvable_or_limit(&self) -> Outcome {
        match self.watch.passed() {
            Some(limit) => Outcome::LimitReached { limit },
            None => Outcome::Unsolvable,
        }
    }
}

/// When the depth-first search hands over to the best-first one: after its share of the time
/// limit, on purely symbolic problems, when the fallback is on.
pub(super) fn fallback_time(c: &Compiled, opts: &PlannerOptions) -> Option<std::time::Duration> {
    let t = opts.limits.time?;
    if opts.best_first_share <= 0.0
        || opts.best_first_share > 1.0
        || opts.best_first_share.is_nan()
        || c.actions.iter().any(|a| a.evaluable.is_some())
    {
        return None;
    }
    Some(t.mul_f64(1.0 - opts.best_first_share))
}

/// When geometric-first's repairs hand over to the chronological pass: after their share of
/// the time limit, on problems with geometric tasks.
pub(super) fn repairs_time(c: &Compiled, opts: &PlannerOptions) -> Option<std::time::Duration> {
    let t = opts.limits.time?;
    let share = opts.chronological_share;
    let applies = matches!(opts.strategy, Strategy::GeometricFirst { .. })
        && share > 0.0
        && share <= 1.0
        && c.actions.iter().any(|a| a.evaluable.is_some());
    applies.then(|| t.mul_f64(1.0 - share))
}
