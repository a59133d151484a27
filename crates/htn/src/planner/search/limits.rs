//! The search's limits: time, nodes, and the resident memory, with the growth of its tables
//! counted before they double.

use std::collections::HashSet;

use super::super::Limit;
use super::Search;

/// Whether a table of `len` entries with room for `capacity` may double before the next
/// check: one node's expansion inserts many entries (every method and binding, the heuristic's
/// memo), so a table within 1/16 of full counts as doubling: a table that doubles between two
/// checks holds its old and its new array at once and can pass the limit by its whole size.
pub(super) fn may_double(len: usize, capacity: usize) -> bool {
    len.saturating_add((capacity / 16).max(256)) >= capacity
}

/// The bytes a vector allocates when it next doubles, if that may happen before the next
/// check (0 while it has room).
pub(super) fn vec_growth<T>(len: usize, capacity: usize) -> usize {
    if !may_double(len, capacity) {
        0
    } else {
        capacity.max(4) * 2 * std::mem::size_of::<T>()
    }
}

/// The bytes a hash set allocates when it next doubles, if that may happen before the next
/// check (0 while it has room): twice its buckets, each an entry and a control byte.
pub(super) fn set_growth<T, S>(set: &HashSet<T, S>) -> usize {
    table_growth::<T>(set.len(), set.capacity())
}

/// [`set_growth`] of a hash table of `len` entries of type `T` with room for `capacity`.
pub(super) fn table_growth<T>(len: usize, capacity: usize) -> usize {
    if !may_double(len, capacity) {
        0
    } else {
        (capacity.max(4) * 2).next_power_of_two() * (std::mem::size_of::<T>() + 1)
    }
}

impl<'a, 'o> Search<'a, 'o> {
    /// The limits, checked at every node: the clock is cheap (far below a node's cost), so a
    /// limit stops the search within one node of it, however costly nodes are (best-first
    /// nodes, geometric calls); inside a node, the precondition joins poll the same
    /// [`Watch`](crate::budget::Watch).
    pub(super) fn check_limits(&mut self) -> Option<Limit> {
        if let Some(n) = self.opts.limits.nodes
            && self.stats.nodes >= n
        {
            return Some(Limit::Nodes);
        }
        let hit = self.watch.check();
        self.stats.peak_memory_kb = self.stats.peak_memory_kb.max(self.watch.peak_kb());
        hit
    }

    /// Whether the search may grow a table by `extra` bytes within the memory limit; if not,
    /// the memory limit is marked reached, for [`Search::check_limits`]. `extra` 0 (nothing
    /// doubles) costs nothing.
    pub(super) fn growth_fits(&mut self, extra: usize) -> bool {
        extra == 0 || self.watch.fits(extra as u64)
    }
}

/// Frees `tables` on a thread of its own: a search's millions of small allocations take
/// tenths of a second to free, which would come after its time limit; the binary exits
/// without waiting for them. Freed in place if no thread can be started.
pub(super) fn drop_in_background<T: Send + 'static>(tables: T) {
    let _ = std::thread::Builder::new()
        .name("htn-free".into())
        .spawn(move || drop(tables));
}
