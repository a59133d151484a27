//! The time and memory a command may spend before its search starts: reading, parsing and
//! compiling. The binary sets one budget for the process ([`set`]) from `--time-limit` and
//! `--memory-limit`; the reader, the parser and the compiler ask [`check`] every few thousand
//! steps and stop with an error when it is spent. [`tripped`] then says which limit it was, so
//! that the binary ends with exit 2 (a limit), not 3 (bad input). Without a budget (library
//! use, tests) every check passes.
//!
//! [`Watch`] is the deadline and memory cap itself; the planner's compiler and search each
//! hold one for their own limits (the search's joins and expansions poll it too).

use std::cell::Cell;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{Arc, Mutex};
use std::time::{Duration, Instant};

use crate::planner::{Limit, current_rss_kb};

/// How often the resident memory is read (a read of /proc costs microseconds).
const MEMORY_CHECK_EVERY: Duration = Duration::from_millis(2);

/// A watch stops this far below its memory cap (a 32nd of it, 4 MiB to 256 MiB): what may be
/// allocated between two reads, and what printing the result needs after the stop.
fn headroom_kb(cap_kb: u64) -> u64 {
    (cap_kb / 32).clamp(4 << 10, 256 << 10)
}

/// A deadline and a cap on resident memory, checked on demand through a shared reference (so
/// that loops holding other state borrowed, such as a precondition's join, can check it). A
/// limit once passed stays passed.
#[derive(Clone, Debug)]
pub struct Watch {
    deadline: Option<Instant>,
    /// The cap as given.
    cap_kb: Option<u64>,
    /// Where checks stop: the cap less its headroom.
    stop_kb: Option<u64>,
    next_memory_check: Cell<Instant>,
    peak_kb: Cell<u64>,
    passed: Cell<Option<Limit>>,
}

impl Watch {
    /// A watch that ends at `deadline` or when the process holds more than `memory_mb` MiB
    /// (less a headroom).
    pub fn new(deadline: Option<Instant>, memory_mb: Option<u64>) -> Watch {
        let cap_kb = memory_mb.map(|m| m.saturating_mul(1024));
        Watch {
            deadline,
            cap_kb,
            stop_kb: cap_kb.map(|kb| kb.saturating_sub(headroom_kb(kb))),
            next_memory_check: Cell::new(Instant::now()),
            peak_kb: Cell::new(0),
            passed: Cell::new(None),
        }
    }

    /// Moves the deadline.
    pub fn set_deadline(&mut self, deadline: Option<Instant>) {
        self.deadline = deadline;
    }

    /// The limit passed, if one is: the clock every call (tens of nanoseconds), the memory
    /// every 2 ms.
    pub fn check(&self) -> Option<Limit> {
        if let Some(l) = self.passed.get() {
            return Some(l);
        }
        let now = Instant::now();
        if stopped() || self.deadline.is_some_and(|d| now >= d) {
            self.passed.set(Some(Limit::Time));
        } else if now >= self.next_memory_check.get() {
            self.next_memory_check.set(now + MEMORY_CHECK_EVERY);
            let rss = current_rss_kb();
            self.peak_kb.set(self.peak_kb.get().max(rss));
            if self.stop_kb.is_some_and(|kb| rss > kb) {
                self.passed.set(Some(Limit::Memory));
            }
        }
        self.passed.get()
    }

    /// The limit passed so far, without reading the clock.
    pub fn passed(&self) -> Option<Limit> {
        self.passed.get()
    }

    /// The highest resident memory a check read, in KiB.
    pub fn peak_kb(&self) -> u64 {
        self.peak_kb.get()
    }

    /// Whether `bytes` more would still fit under the memory cap (less its headroom); if not,
    /// the memory limit is passed.
    pub fn fits(&self, bytes: u64) -> bool {
        self.stop_kb.is_none() || self.fits_at(current_rss_kb(), bytes)
    }

    /// [`Watch::fits`] with the resident memory `rss_kb` read by the caller (one that reads
    /// it less often than it asks).
    pub fn fits_at(&self, rss_kb: u64, bytes: u64) -> bool {
        let fits = self
            .stop_kb
            .is_none_or(|kb| rss_kb.saturating_add(bytes >> 10) <= kb);
        if !fits {
            self.passed.set(Some(Limit::Memory));
        }
        fits
    }

    /// The memory cap in MiB, if any.
    pub fn memory_mb(&self) -> Option<u64> {
        self.cap_kb.map(|kb| kb >> 10)
    }
}

thread_local! {
    static STOP: std::cell::RefCell<Option<Arc<AtomicBool>>> = const { std::cell::RefCell::new(None) };
}

/// While alive, every [`Watch`] of this thread (and the heuristic's grounding) stops as at its
/// deadline once `flag` is set: another engine of a portfolio has decided.
pub struct StopOn(());

impl StopOn {
    /// Installs `flag` for this thread until the guard is dropped.
    pub fn install(flag: Arc<AtomicBool>) -> StopOn {
        STOP.with(|s| *s.borrow_mut() = Some(flag));
        StopOn(())
    }
}

impl Drop for StopOn {
    fn drop(&mut self) {
        STOP.with(|s| *s.borrow_mut() = None);
    }
}

/// Whether this thread's portfolio flag ([`StopOn`]) is set.
pub fn stopped() -> bool {
    STOP.with(|s| {
        s.borrow()
            .as_ref()
            .is_some_and(|f| f.load(Ordering::Relaxed))
    })
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
    fn a_watch_stops_when_the_other_engine_has_decided() {
        let flag = Arc::new(AtomicBool::new(false));
        let guard = StopOn::install(flag.clone());
        let w = Watch::new(None, None);
        assert_eq!(w.check(), None);
        flag.store(true, Ordering::Relaxed);
        assert_eq!(w.check(), Some(Limit::Time));
        drop(guard);
        // Only this thread's watches, and only while the guard lives.
        assert_eq!(Watch::new(None, None).check(), None);
    }

    #[test]
    fn a_watch_stops_at_its_deadline_and_memory() {
        let w = Watch::new(Some(Instant::now()), None);
        assert_eq!(w.check(), Some(Limit::Time));
        let w = Watch::new(None, Some(1));
        assert_eq!(
            w.check(),
            Some(Limit::Memory),
            "a test process holds over 1 MiB"
        );
        let w = Watch::new(None, None);
        assert_eq!(w.check(), None);
        assert!(w.fits(u64::MAX));
    }

    #[test]
    fn a_limit_passed_stays_passed_and_stops_below_the_cap() {
        let w = Watch::new(None, Some(1 << 20));
        assert_eq!(w.check(), None);
        // 1 TiB cap: the headroom is its largest, 256 MiB.
        assert!(!w.fits((1 << 40) - (200 << 20)));
        assert_eq!(w.passed(), Some(Limit::Memory));
        assert_eq!(w.check(), Some(Limit::Memory));
    }
}
