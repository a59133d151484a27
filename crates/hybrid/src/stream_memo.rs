//! The memo of geometric solution streams. A request is a task, its arguments and the exact
//! world it is asked in; the GTP answers it once. When the HTN search asks it again (the next
//! round of limited discrepancy, a restart with a deeper bound, the chronological pass after
//! geometric-first's repairs all start over from the initial node), the solutions given
//! before are read back in their order, and the GTP's stream, parked in the meantime, goes on
//! where it stopped when more are wanted. The GTP's calls are seeded by the request, so what
//! is read back is what it would compute again.
//!
//! A parked stream holds its search's state (candidate points, verdicts, a world or two), so
//! at most [`MAX_PARKED`] are kept, the least recently used given up first; a request whose
//! stream was given up is asked again from its start, past the solutions already given.

use std::collections::HashMap;

use gtp::planner::{SolutionStream, Stage};
use htn::oracle::GeoSolution;

/// At most this many GTP streams are parked at once.
pub(crate) const MAX_PARKED: usize = 64;

/// A request: the task as the domain names it, its arguments, and the exact fingerprint of
/// the world it is asked in.
#[derive(Clone, Debug, PartialEq, Eq, Hash)]
pub(crate) struct Request {
    pub(crate) task: String,
    pub(crate) args: Vec<String>,
    pub(crate) world: u64,
}

/// Why a request's stream ended: the GTP's reason and the stage that stopped it.
#[derive(Clone, Debug, Default)]
pub(crate) struct End {
    pub(crate) failure: Option<String>,
    pub(crate) stage: Option<Stage>,
}

/// What the memo knows of solution `pos` of a request.
pub(crate) enum Known {
    /// It was given out before.
    Solution(GeoSolution),
    /// The stream ended before it.
    End(End),
    /// The GTP has to say.
    Unknown,
}

#[derive(Default)]
struct Entry {
    given: Vec<GeoSolution>,
    end: Option<End>,
    /// The GTP's stream, after `given`; `None` while it is read from or once given up.
    parked: Option<SolutionStream>,
    last_use: u64,
}

/// The memo: every request's solutions so far, and the parked streams.
#[derive(Default)]
pub(crate) struct StreamMemo {
    entries: HashMap<Request, Entry>,
    clock: u64,
    parked: usize,
    /// Solutions and ends read back instead of asked of the GTP.
    pub(crate) replays: u64,
}

impl StreamMemo {
    /// Whether `request` was asked before.
    pub(crate) fn contains(&self, request: &Request) -> bool {
        self.entries.contains_key(request)
    }

    /// Solution `pos` of `request`, if the memo knows it (counted as a replay).
    pub(crate) fn known(&mut self, request: &Request, pos: usize) -> Known {
        let Some(e) = self.entries.get(request) else {
            return Known::Unknown;
        };
        let known = match (e.given.get(pos), &e.end) {
            (Some(s), _) => Known::Solution(s.clone()),
            (None, Some(end)) => Known::End(end.clone()),
            (None, None) => return Known::Unknown,
        };
        self.replays += 1;
        known
    }

    /// How many solutions of `request` were given out.
    pub(crate) fn given(&self, request: &Request) -> usize {
        self.entries.get(request).map_or(0, |e| e.given.len())
    }

    /// The parked stream of `request`, taken out to be read from.
    pub(crate) fn unpark(&mut self, request: &Request) -> Option<SolutionStream> {
        let e = self.entries.get_mut(request)?;
        let s = e.parked.take()?;
        self.parked -= 1;
        Some(s)
    }

    /// Records the next solution of `request`.
    pub(crate) fn push(&mut self, request: &Request, solution: GeoSolution) {
        self.entry(request).given.push(solution);
    }

    /// Records that `request`'s stream ended after the solutions given.
    pub(crate) fn end(&mut self, request: &Request, end: End) {
        self.entry(request).end = Some(end);
    }

    /// Parks `stream` for `request`, giving up the least recently used parked stream when
    /// [`MAX_PARKED`] are kept.
    pub(crate) fn park(&mut self, request: &Request, stream: SolutionStream) {
        if self.parked >= MAX_PARKED
            && let Some(old) = self
                .entries
                .values_mut()
                .filter(|e| e.parked.is_some())
                .min_by_key(|e| e.last_use)
        {
            old.parked = None;
            self.parked -= 1;
        }
        let e = self.entry(request);
        if e.parked.replace(stream).is_none() {
            self.parked += 1;
        }
    }

    fn entry(&mut self, request: &Request) -> &mut Entry {
        self.clock += 1;
        let clock = self.clock;
        let e = self.entries.entry(request.clone()).or_default();
        e.last_use = clock;
        e
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use htn::oracle::SolutionId;

    fn request(world: u64) -> Request {
        Request {
            task: "pick".into(),
            args: vec!["b1".into()],
            world,
        }
    }

    fn solution(id: u64) -> GeoSolution {
        GeoSolution {
            add: Vec::new(),
            delete: Vec::new(),
            id: SolutionId(id),
        }
    }

    #[test]
    fn a_request_reads_back_its_solutions_then_its_end() {
        let mut m = StreamMemo::default();
        let r = request(7);
        assert!(matches!(m.known(&r, 0), Known::Unknown));
        m.push(&r, solution(3));
        m.push(&r, solution(5));
        assert!(matches!(m.known(&r, 1), Known::Solution(s) if s.id == SolutionId(5)));
        assert!(matches!(m.known(&r, 2), Known::Unknown));
        m.end(&r, End::default());
        assert!(matches!(m.known(&r, 2), Known::End(_)));
        assert_eq!(m.replays, 2);
        // The same task in another world is another request.
        assert!(matches!(m.known(&request(8), 0), Known::Unknown));
        assert_eq!(m.given(&r), 2);
    }
}
