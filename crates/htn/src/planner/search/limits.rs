//! The search's limits: time, nodes, and the resident memory, with the growth of its tables
//! counted before they double.

use std::collections::HashSet;
use std::time::Instant;

use super::super::{Limit, current_rss_kb};
use super::Search;

/// How often the search reads its resident memory (a read of /proc costs microseconds).
pub(super) const MEMORY_CHECK_EVERY: std::time::Duration = std::time::Duration::from_millis(10);

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
    /// The limits, checked at every node: the clock is cheap (tens of nanoseconds, far below
    /// a node's cost), so a limit stops the search within one node of it, however costly nodes
    /// are (best-first nodes, geometric calls). The resident memory costs a read of /proc, so
    /// it is read every [`MEMORY_CHECK_EVERY`] of search instead.
    pub(super) fn check_limits(&mut self) -> Option<Limit> {
        let l = self.opts.limits;
        if let Some(n) = l.nodes
            && self.stats.nodes >= n
        {
            return Some(Limit::Nodes);
        }
        if self.memory_reached {
            return Some(Limit::Memory);
        }
        let now = Instant::now();
        if let Some(t) = l.time
            && now.duration_since(self.start) >= t
        {
            return Some(Limit::Time);
        }
        if now >= self.next_memory_check {
            self.next_memory_check = now + MEMORY_CHECK_EVERY;
            let rss = current_rss_kb();
            self.stats.peak_memory_kb = self.stats.peak_memory_kb.max(rss);
            if let Some(mb) = l.memory_mb
                && rss > mb.saturating_mul(1024)
            {
                return Some(Limit::Memory);
            }
        }
        None
    }

    /// Whether the search may grow a table by `extra` bytes (while it doubles, the old and the
    /// new table are both resident) within the memory limit; if not, the memory limit is
    /// marked reached, for [`Search::check_limits`]. `extra` 0 (nothing doubles) costs nothing.
    pub(super) fn growth_fits(&mut self, extra: usize) -> bool {
        let Some(mb) = self.opts.limits.memory_mb else {
            return true;
        };
        if extra == 0 {
            return true;
        }
        let fits = current_rss_kb() + (extra as u64 >> 10) <= mb.saturating_mul(1024);
        if !fits {
            self.memory_reached = true;
        }
        fits
    }
}
