//! The search's limits: time, nodes, and the resident memory, with the growth of its tables
//! counted before they double.

use std::cell::Cell;
use std::collections::HashSet;
use std::time::Instant;

use super::super::{Limit, current_rss_kb};
use super::Search;

/// How often the search reads its resident memory (a read of /proc costs microseconds).
pub(super) const MEMORY_CHECK_EVERY: std::time::Duration = std::time::Duration::from_millis(2);

/// The search stops this far below the memory limit (a 32nd of it, 4 MiB to 256 MiB): what it
/// may allocate between two reads, and what printing the result needs after the stop.
fn headroom_kb(limit_kb: u64) -> u64 {
    (limit_kb / 32).clamp(4 << 10, 256 << 10)
}

/// Whether a table of `len` entries with room for `capacity` may double before the next
/// check: one node's expansion inserts many entries (every method and binding, the heuristic's
/// memo), so a table within 1/16 of full counts as doubling (a table doubled between two
/// checks took Freecell 13-1 from 281 to 339 MB under a 300 MB limit).
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

/// The time and memory limits, read through a shared reference, so that loops that hold the
/// search's state borrowed (a precondition's join, the grounding of its heuristic) can poll
/// them too. A limit once reached stays reached.
#[derive(Debug)]
pub(super) struct Watch {
    start: Instant,
    time: Option<std::time::Duration>,
    /// The resident memory at which to stop: the limit less its headroom.
    memory_kb: Option<u64>,
    next_memory_check: Cell<Instant>,
    peak_kb: Cell<u64>,
    hit: Cell<Option<Limit>>,
}

impl Watch {
    pub(super) fn new(
        start: Instant,
        time: Option<std::time::Duration>,
        memory_mb: Option<u64>,
    ) -> Watch {
        Watch {
            start,
            time,
            memory_kb: memory_mb.map(|mb| {
                let kb = mb.saturating_mul(1024);
                kb.saturating_sub(headroom_kb(kb))
            }),
            next_memory_check: Cell::new(start),
            peak_kb: Cell::new(0),
            hit: Cell::new(None),
        }
    }

    /// The limit reached, if any: the clock at every call (tens of nanoseconds), the resident
    /// memory every [`MEMORY_CHECK_EVERY`] (a read of /proc costs microseconds).
    pub(super) fn poll(&self) -> Option<Limit> {
        if let Some(l) = self.hit.get() {
            return Some(l);
        }
        let now = Instant::now();
        if let Some(t) = self.time
            && now.duration_since(self.start) >= t
        {
            self.hit.set(Some(Limit::Time));
        } else if now >= self.next_memory_check.get() {
            self.next_memory_check.set(now + MEMORY_CHECK_EVERY);
            let rss = current_rss_kb();
            self.peak_kb.set(self.peak_kb.get().max(rss));
            if self.memory_kb.is_some_and(|kb| rss > kb) {
                self.hit.set(Some(Limit::Memory));
            }
        }
        self.hit.get()
    }

    /// The limit reached so far, without reading the clock.
    pub(super) fn reached(&self) -> Option<Limit> {
        self.hit.get()
    }

    /// The highest resident memory read so far, in KiB.
    pub(super) fn peak_kb(&self) -> u64 {
        self.peak_kb.get()
    }

    /// Counts the time limit from `t`.
    pub(super) fn restart_at(&mut self, t: Instant) {
        self.start = t;
    }

    /// Whether growing by `extra` bytes (while a table doubles, the old and the new one are
    /// both resident) stays within the memory limit; if not, the limit is reached.
    fn growth_fits(&self, extra: usize) -> bool {
        let Some(kb) = self.memory_kb else {
            return true;
        };
        if extra == 0 {
            return true;
        }
        let fits = current_rss_kb() + (extra as u64 >> 10) <= kb;
        if !fits {
            self.hit.set(Some(Limit::Memory));
        }
        fits
    }
}

impl<'a, 'o> Search<'a, 'o> {
    /// The limits, checked at every node: the clock is cheap (far below a node's cost), so a
    /// limit stops the search within one node of it, however costly nodes are (best-first
    /// nodes, geometric calls); inside a node, the precondition joins poll the same
    /// [`Watch`].
    pub(super) fn check_limits(&mut self) -> Option<Limit> {
        if let Some(n) = self.opts.limits.nodes
            && self.stats.nodes >= n
        {
            return Some(Limit::Nodes);
        }
        let hit = self.watch.poll();
        self.stats.peak_memory_kb = self.stats.peak_memory_kb.max(self.watch.peak_kb());
        hit
    }

    /// Whether the search may grow a table by `extra` bytes within the memory limit; if not,
    /// the memory limit is marked reached, for [`Search::check_limits`]. `extra` 0 (nothing
    /// doubles) costs nothing.
    pub(super) fn growth_fits(&mut self, extra: usize) -> bool {
        self.watch.growth_fits(extra)
    }
}
