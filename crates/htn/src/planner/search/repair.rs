//! The repair of the geometric-first strategy (the paper's Figure 3). On a geometric failure
//! (a GS action with no solution, or a task none of whose methods applies while their
//! preconditions read shared literals), other solutions of earlier geometric tasks are tried
//! first, newest first, each its share of the `k` tries, replaying the HTN choices made since
//! (`Mode::Retry`); if none makes the failed task solvable, the original solutions are
//! replayed back to the failure point (`Mode::Restore`) and HTN backtracking takes over.

use std::collections::VecDeque;

use super::super::PlanError;
use super::super::compile::{CFormula, Compiled};
use super::Search;
use super::frames::{Choice, Frame, GeoId, Key};

/// Whether `f` reads a shared predicate (a fact that geometry decides).
pub(super) fn reads_shared(c: &Compiled, f: &CFormula) -> bool {
    match f {
        CFormula::Atom(p, _) => c.shared_preds[*p as usize],
        CFormula::Not(g) | CFormula::Forall(_, g) => reads_shared(c, g),
        CFormula::And(v) | CFormula::Or(v) => v.iter().any(|g| reads_shared(c, g)),
        CFormula::Imply(a, b) => reads_shared(c, a) || reads_shared(c, b),
        CFormula::Exists(_, lits) => lits.iter().any(|l| reads_shared(c, &l.f)),
        CFormula::True | CFormula::Eq(..) | CFormula::Compare(..) => false,
    }
}

/// Whether the depth-first engine explores as usual or replays a path for a repair.
#[derive(Clone, Copy, PartialEq, Eq, Debug)]
pub(super) enum Mode {
    Normal,
    /// Replaying the recorded choices after taking another geometric solution.
    Retry,
    /// Replaying the original choices to return to the failure point.
    Restore,
}

/// An earlier geometric task a repair may give another solution.
#[derive(Clone, Copy)]
struct Candidate {
    /// Its frame's position on the stack.
    frame: usize,
    geo: GeoId,
    /// The solution it had when the repair started.
    orig: usize,
}

/// A repair in progress.
pub(super) struct Repair {
    /// The choices of every frame when the failure happened, for replaying.
    path: Vec<Key>,
    /// The geometric tasks with solutions left, latest first.
    cands: Vec<Candidate>,
    pos: usize,
    tries_left: usize,
    /// Tries spent on `cands[pos]`.
    tries_here: usize,
    /// The earliest candidate tried, from which the original choices are replayed.
    oldest: Option<Candidate>,
}

impl<'a, 'o> Search<'a, 'o> {
    /// Whether a precondition of some method of ground task `task` reads a shared predicate.
    pub(super) fn methods_read_shared(&self, task: u32) -> bool {
        let c = self.c;
        self.methods_of(task).iter().any(|&m| {
            c.methods[m as usize]
                .pre
                .iter()
                .any(|l| reads_shared(c, &l.f))
        })
    }

    /// The choice frame `f` has taken.
    fn key_of(&self, f: &Frame) -> Key {
        match f.choice {
            Choice::Htn(h) => {
                let h = &self.htn_frames[h];
                Key::Htn {
                    method: h.method,
                    binding: h.binding(h.next - 1).to_vec(),
                }
            }
            Choice::Geo(g) => Key::Geo(self.geo_frames[g].current),
        }
    }

    /// Starts a repair with a budget of `k` other geometric solutions, after a geometric
    /// failure at the current node (the failing frame already popped).
    pub(super) fn start_repair(&mut self, k: usize) -> Result<bool, PlanError> {
        let path: Vec<Key> = self.frames.iter().map(|f| self.key_of(f)).collect();
        let cands: Vec<Candidate> = (0..self.frames.len())
            .rev()
            .filter_map(|i| match self.frames[i].choice {
                Choice::Geo(id) => {
                    let g = &self.geo_frames[id];
                    let left = !(g.exhausted && g.current + 1 >= g.cache.len());
                    left.then_some(Candidate {
                        frame: i,
                        geo: id,
                        orig: g.current,
                    })
                }
                Choice::Htn(_) => None,
            })
            .collect();
        if cands.is_empty() {
            return self.backtrack();
        }
        self.stats.geo_repairs += 1;
        self.repair = Some(Repair {
            path,
            cands,
            pos: 0,
            tries_left: k,
            tries_here: 0,
            oldest: None,
        });
        self.mode = Mode::Retry;
        self.next_repair_try()
    }

    /// Pops the frames above frame `fi` and restores it.
    fn unwind_to(&mut self, fi: usize) {
        while self.frames.len() > fi + 1 {
            self.pop_frame();
        }
        self.restore_top();
    }

    /// The next try of a repair: another solution of an earlier geometric task, the latest
    /// first, each task its share of the tries left (so that a budget of k reaches back k tasks
    /// rather than spending it all on the latest one, as the paper's GTP backtracks "all the
    /// way up to PICK(b1)"). Tasks are visited latest to earliest only: unwinding never has to
    /// reach a frame a failed replay did not rebuild.
    pub(super) fn next_repair_try(&mut self) -> Result<bool, PlanError> {
        loop {
            let r = self.repair.as_mut().expect("a repair in progress");
            if r.pos >= r.cands.len() || r.tries_left == 0 {
                return self.restore_after_repair();
            }
            let share = r.tries_left.div_ceil(r.cands.len() - r.pos);
            if r.tries_here >= share {
                r.pos += 1;
                r.tries_here = 0;
                continue;
            }
            let cand = r.cands[r.pos];
            r.oldest = Some(cand);
            self.unwind_to(cand.frame);
            let g = cand.geo;
            let idx = self.geo_frames[g].current + 1;
            if !self.fetch(g, idx)? {
                let r = self.repair.as_mut().expect("a repair");
                r.pos += 1;
                r.tries_here = 0;
                continue;
            }
            self.stats.geo_backtracks += 1;
            let r = self.repair.as_mut().expect("a repair");
            r.tries_left -= 1;
            r.tries_here += 1;
            let forced: VecDeque<Key> = r.path[cand.frame + 1..].iter().cloned().collect();
            self.geo_frames[g].current = idx;
            if self.apply_geo(g)? {
                self.forced = forced;
                self.mode = Mode::Retry;
                return Ok(true);
            }
        }
    }

    /// The repair's tries are spent: replays the original solution of the earliest task
    /// tried and the choices after it, back to the failure point (`Mode::Restore`).
    fn restore_after_repair(&mut self) -> Result<bool, PlanError> {
        let r = self.repair.as_ref().expect("a repair");
        let Some(t) = r.oldest else {
            self.end_repair();
            return self.backtrack();
        };
        let forced: VecDeque<Key> = r.path[t.frame + 1..].iter().cloned().collect();
        self.unwind_to(t.frame);
        self.geo_frames[t.geo].current = t.orig;
        if !self.apply_geo(t.geo)? {
            self.end_repair();
            return self.backtrack();
        }
        self.forced = forced;
        self.mode = Mode::Restore;
        Ok(true)
    }

    /// Back to normal search.
    pub(super) fn end_repair(&mut self) {
        self.repair = None;
        self.forced.clear();
        self.mode = Mode::Normal;
    }
}
