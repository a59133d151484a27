//! The time and memory a command may spend before its search starts: reading, parsing and
//! compiling. The binary sets one budget for the process ([`set`]) from `--time-limit` and
//! `--memory-limit`; the reader, the parser and the compiler ask [`check`] every few thousand
//! steps and stop with an error when it is spent. [`tripped`] then says which limit it was, so
//! that the binary ends with exit 2 (a limit), not 3 (bad input). Without a budget (library
//! use, tests) every check passes.

use std::sync::Mutex;
use std::time::{Duration, Instant};

use crate::planner::{Limit, current_rss_kb};

/// How often the resident memory is read (a read of /proc costs microseconds).
const MEMORY_CHECK_EVERY: Duration = Duration::from_millis(10);

/// A deadline and a cap on resident memory, checked on demand.
#[derive(Clone, Copy, Debug)]
pub struct Watch {
    deadline: Option<Instant>,
    memory_kb: Option<u64>,
    next_memory_check: Instant,
}

impl Watch {
    /// A watch that ends at `deadline` or when the process holds more than `memory_mb` MiB.
    pub fn new(deadline: Option<Instant>, memory_mb: Option<u64>) -> Watch {
        Watch {
            deadline,
            memory_kb: memory_mb.map(|m| m.saturating_mul(1024)),
            next_memory_check: Instant::now(),
        }
    }

    /// The limit passed, if one is: the clock every call, the memory every 10 ms.
    pub fn check(&mut self) -> Option<Limit> {
        let now = Instant::now();
        if self.deadline.is_some_and(|d| now >= d) {
            return Some(Limit::Time);
        }
        if let Some(kb) = self.memory_kb
            && now >= self.next_memory_check
        {
            self.next_memory_check = now + MEMORY_CHECK_EVERY;
            if current_rss_kb() > kb {
                return Some(Limit::Memory);
            }
        }
        None
    }

    /// Whether `bytes` more would still fit under the memory cap (false: the cap is passed).
    pub fn fits(&self, bytes: u64) -> bool {
        self.memory_kb
            .is_none_or(|kb| current_rss_kb().saturating_add(bytes >> 10) <= kb)
    }

    /// The memory cap in MiB, if any.
    pub fn memory_mb(&self) -> Option<u64> {
        self.memory_kb.map(|kb| kb >> 10)
    }
}

static BUDGET: Mutex<Option<Watch>> = Mutex::new(None);
static TRIPPED: Mutex<Option<Limit>> = Mutex::new(None);

/// Sets the process's budget for reading, parsing and compiling.
pub fn set(deadline: Option<Instant>, memory_mb: Option<u64>) {
    if let Ok(mut b) = BUDGET.lock() {
        *b = Some(Watch::new(deadline, memory_mb));
    }
}

/// Removes the budget (and forgets a limit passed).
pub fn clear() {
    if let Ok(mut b) = BUDGET.lock() {
        *b = None;
    }
    if let Ok(mut t) = TRIPPED.lock() {
        *t = None;
    }
}

/// The limit of the budget that is passed, if one is (recorded for [`tripped`]).
pub fn check() -> Option<Limit> {
    let limit = BUDGET.lock().ok()?.as_mut()?.check()?;
    trip(limit);
    Some(limit)
}

/// Whether `bytes` more fit in the memory budget; if not, the memory limit is recorded as
/// passed.
pub fn fits(bytes: u64) -> bool {
    let fits = BUDGET
        .lock()
        .ok()
        .and_then(|b| b.as_ref().map(|w| w.fits(bytes)))
        .unwrap_or(true);
    if !fits {
        trip(Limit::Memory);
    }
    fits
}

/// The budget's memory cap in MiB, if any.
pub fn memory_mb() -> Option<u64> {
    BUDGET.lock().ok()?.as_ref()?.memory_mb()
}

fn trip(limit: Limit) {
    if let Ok(mut t) = TRIPPED.lock() {
        t.get_or_insert(limit);
    }
}

/// The limit that stopped reading, parsing or compiling, if one did.
pub fn tripped() -> Option<Limit> {
    TRIPPED.lock().ok().and_then(|t| *t)
}

/// The message of an error that a passed limit caused, `what` being what was under way.
pub fn message(limit: Limit, what: &str) -> String {
    match limit {
        Limit::Memory => format!(
            "stopped: memory limit reached while {what} (--memory-limit {} MiB)",
            memory_mb().unwrap_or(0)
        ),
        other => format!("stopped: {other} reached while {what}"),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_watch_stops_at_its_deadline_and_memory() {
        let mut w = Watch::new(Some(Instant::now()), None);
        assert_eq!(w.check(), Some(Limit::Time));
        let mut w = Watch::new(None, Some(1));
        assert_eq!(
            w.check(),
            Some(Limit::Memory),
            "a test process holds over 1 MiB"
        );
        let mut w = Watch::new(None, None);
        assert_eq!(w.check(), None);
        assert!(w.fits(u64::MAX));
    }
}
