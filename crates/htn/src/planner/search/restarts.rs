//! Randomized restarts of the depth-first search (Gomes, Selman and Kautz, 1998): short
//! depth-first runs from the initial network, each trying methods and bindings in an order
//! drawn from its own seed, each stopped after a node budget from the Luby sequence.
//!
//! Why: how long a depth-first search runs depends on its first choices far more than on the
//! problem. One wrong early choice (a couple, a car, a tent in Hiking) that shows as a dead
//! end only deep below costs millions of nodes, where another order finds a plan in a few
//! hundred; the domain's order is one draw among many. Short runs in many orders find the
//! lucky ones; the Luby budgets (1, 1, 2, 1, 1, 2, 4, ... times [`RESTART_UNIT`]) give longer
//! runs their share too, within a log factor of the best fixed budget whatever the problem
//! (Luby, Sinclair and Zuckerman, 1993). The runs are an engine of the portfolio
//! (`portfolio.rs`), beside the depth-first search in the domain's order, which they do not
//! replace: only that one can prove that no plan exists.
//!
//! A run's order is consistent, not drawn afresh at every node: each lifted task has one
//! order of its methods, and bindings come in the order of a random ranking of the objects
//! (the same couple, car or board preferred everywhere). On Hiking p23-p30 (IPC 2020, 10 s
//! each), orders drawn afresh at every node solved none, orders drawn per ground task three,
//! the consistent ranking all eight, each in about 1.1 s.

use std::time::Instant;

use super::super::PlanError;
use super::{NIL, Search, Stop};
use crate::state::mix64;

/// Nodes of the shortest run.
pub(super) const RESTART_UNIT: u64 = 1024;

impl Search<'_, '_> {
    /// Runs restarts until `until`: [`Stop::Found`] (the plan in the state), a limit,
    /// [`Stop::Switch`] at `until`, or [`Stop::Exhausted`] when a run searched its whole space
    /// within its budget (another order would search the same space: restarting is pointless;
    /// this is no proof, the depth bound and the loop check may have cut it).
    pub(super) fn restarts(&mut self, until: Instant) -> Result<Stop, PlanError> {
        self.switch_at = until.checked_duration_since(self.start);
        let mut run = 0u64;
        loop {
            if Instant::now() >= until {
                return Ok(Stop::Switch);
            }
            run += 1;
            self.reset();
            self.shuffle = mix64(self.salt ^ run) | 1;
            self.run_cap = Some(self.stats.nodes + RESTART_UNIT * luby(run));
            self.stats.restarts += 1;
            match self.dfs()? {
                Stop::Switch => continue,
                done => return Ok(done),
            }
        }
    }
}

impl Search<'_, '_> {
    /// The position in ground task `task`'s method list of its `i`-th method to try: `i`
    /// itself, or in a restart, the run's permutation of its lifted task's methods.
    pub(super) fn method_order(&self, task: u32, n: usize, i: usize) -> usize {
        if self.shuffle == 0 || n < 2 {
            return i;
        }
        let lifted = if task == NIL {
            u64::MAX
        } else {
            self.gtasks.key(task)[0] as u64
        };
        let mut perm: Vec<usize> = (0..n).collect();
        let mut r = mix64(self.shuffle ^ lifted.wrapping_mul(0x9e37_79b9));
        for k in (1..n).rev() {
            r = mix64(r);
            perm.swap(k, (r % (k as u64 + 1)) as usize);
        }
        perm[i]
    }

    /// In a restart, sorts the `count` bindings of `bindings` (flat) by the run's ranking of
    /// objects, lexicographically over the parameters.
    pub(super) fn order_bindings(&self, bindings: &mut [u32], count: usize) {
        if self.shuffle == 0 || count < 2 {
            return;
        }
        let stride = bindings.len() / count;
        if stride == 0 {
            return;
        }
        let seed = self.shuffle;
        let mut rows: Vec<&[u32]> = bindings.chunks(stride).collect();
        rows.sort_by_cached_key(|r| {
            r.iter()
                .map(|&o| mix64(seed ^ o as u64))
                .collect::<Vec<_>>()
        });
        let sorted: Vec<u32> = rows.concat();
        bindings.copy_from_slice(&sorted);
    }
}

/// The `i`-th term (from 1) of the Luby sequence: 1, 1, 2, 1, 1, 2, 4, 1, 1, 2, ...
pub(super) fn luby(i: u64) -> u64 {
    let mut i = i.max(1);
    loop {
        // The smallest k with i <= 2^k - 1.
        let k = 64 - i.leading_zeros() as u64;
        if i == (1u64 << k) - 1 {
            return 1 << (k - 1);
        }
        i -= (1u64 << (k - 1)) - 1;
    }
}

#[cfg(test)]
mod tests {
    use super::luby;

    #[test]
    fn the_luby_sequence() {
        let first: Vec<u64> = (1..=15).map(luby).collect();
        assert_eq!(first, [1, 1, 2, 1, 1, 2, 4, 1, 1, 2, 1, 1, 2, 4, 8]);
    }
}
