//! Choice points. Each frame on the search's stack keeps the marks to undo back to and the
//! id of its choice in one of two typed stacks: the method-and-binding choices of abstract
//! tasks ([`HtnFrame`]) and the solution choices of GS actions ([`GeoFrame`]). An engine
//! holding a [`ChoiceId`] reaches its frame's fields directly, with no check of the kind.

use std::marker::PhantomData;
use std::ops::{Index, IndexMut};

use crate::oracle::{GeoSolution, StreamId};

use super::super::eval::Cursor;
use super::Search;

/// Lengths of the arena, trail, plan and tree when a frame was pushed: undoing the frame's
/// choice truncates them back.
#[derive(Clone, Copy)]
pub(super) struct Marks {
    arena: usize,
    trail: usize,
    steps: usize,
    tree: usize,
    next_occ: u32,
}

/// The choice taken at a choice point, for replaying a path.
#[derive(Clone, Debug)]
pub(super) enum Key {
    Htn { method: u32, binding: Vec<u32> },
    Geo(usize),
}

/// The choice point of an abstract task: its methods in domain order, and the bindings of
/// the current one.
pub(super) struct HtnFrame {
    pub(super) occ: u32,
    pub(super) task: u32,
    pub(super) rest: u32,
    /// The decomposition the task came from.
    pub(super) parent: u32,
    /// Next position in the task's method list.
    pub(super) mpos: usize,
    pub(super) method: u32,
    pub(super) stride: usize,
    /// The current piece of the current method's bindings (`count` of them, `stride` slots
    /// each, flat), and where the binder goes on when more may follow.
    pub(super) bindings: Vec<u32>,
    pub(super) count: usize,
    pub(super) more: Option<Cursor>,
    pub(super) next: usize,
    pub(super) tried: u32,
}

impl HtnFrame {
    /// A frame for ground task `task` (occurrence `occ`, network `rest` below it, from
    /// decomposition `parent`) before any method is tried.
    pub(super) fn new(task: u32, occ: u32, rest: u32, parent: u32) -> HtnFrame {
        HtnFrame {
            occ,
            task,
            rest,
            parent,
            mpos: 0,
            method: 0,
            stride: 0,
            bindings: Vec::new(),
            count: 0,
            more: None,
            next: 0,
            tried: 0,
        }
    }

    /// The binding at position `i` of the current method's bindings.
    pub(super) fn binding(&self, i: usize) -> &[u32] {
        &self.bindings[i * self.stride..(i + 1) * self.stride]
    }
}

/// The choice point of a GS action: the oracle's stream of solutions, those fetched so far,
/// and the one applied.
pub(super) struct GeoFrame {
    pub(super) occ: u32,
    pub(super) task: u32,
    pub(super) rest: u32,
    pub(super) action: u32,
    pub(super) slots: Vec<u32>,
    pub(super) stream: StreamId,
    pub(super) cache: Vec<GeoSolution>,
    pub(super) current: usize,
    pub(super) applied: bool,
    pub(super) exhausted: bool,
    /// Whether a geometric solution was taken above this frame since its current one: its
    /// next solution then revises a choice that later geometric tasks built on (a
    /// discrepancy, counted in `revisions`); otherwise the task after it failed at once and
    /// the next solution is a local retry, free in every round of limited discrepancy.
    pub(super) deep: bool,
    pub(super) revisions: u32,
}

/// The id of a frame in a [`ChoiceStack`]; valid while the frame is on the stack.
pub(super) struct ChoiceId<T>(usize, PhantomData<fn() -> T>);

impl<T> Clone for ChoiceId<T> {
    fn clone(&self) -> Self {
        *self
    }
}

impl<T> Copy for ChoiceId<T> {}

impl<T> PartialEq for ChoiceId<T> {
    fn eq(&self, other: &Self) -> bool {
        self.0 == other.0
    }
}

impl<T> Eq for ChoiceId<T> {}

impl<T> std::fmt::Debug for ChoiceId<T> {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "ChoiceId({})", self.0)
    }
}

/// The frames of one kind, in stack order (pushed and popped with their [`Frame`]).
pub(super) struct ChoiceStack<T>(Vec<T>);

impl<T> Default for ChoiceStack<T> {
    fn default() -> Self {
        ChoiceStack(Vec::new())
    }
}

impl<T> ChoiceStack<T> {
    fn push(&mut self, f: T) -> ChoiceId<T> {
        self.0.push(f);
        ChoiceId(self.0.len() - 1, PhantomData)
    }

    fn pop(&mut self) -> Option<T> {
        self.0.pop()
    }

    /// The frames, oldest first.
    pub(super) fn iter(&self) -> std::slice::Iter<'_, T> {
        self.0.iter()
    }

    /// The frame below `id`, if any.
    pub(super) fn below_mut(&mut self, id: ChoiceId<T>) -> Option<&mut T> {
        let i = id.0.checked_sub(1)?;
        self.0.get_mut(i)
    }
}

impl<T> Index<ChoiceId<T>> for ChoiceStack<T> {
    type Output = T;
    fn index(&self, id: ChoiceId<T>) -> &T {
        &self.0[id.0]
    }
}

impl<T> IndexMut<ChoiceId<T>> for ChoiceStack<T> {
    fn index_mut(&mut self, id: ChoiceId<T>) -> &mut T {
        &mut self.0[id.0]
    }
}

pub(super) type HtnId = ChoiceId<HtnFrame>;
pub(super) type GeoId = ChoiceId<GeoFrame>;

/// Which stack holds a frame's choice.
#[derive(Clone, Copy, Debug)]
pub(super) enum Choice {
    Htn(HtnId),
    Geo(GeoId),
}

/// One choice point on the search's stack.
pub(super) struct Frame {
    pub(super) marks: Marks,
    pub(super) choice: Choice,
}

impl<'a, 'o> Search<'a, 'o> {
    pub(super) fn marks(&self) -> Marks {
        Marks {
            arena: self.arena.len(),
            trail: self.state.mark(),
            steps: self.steps.len(),
            tree: self.tree.len(),
            next_occ: self.next_occ,
        }
    }

    /// Pushes the choice point of an abstract task, with the current marks.
    pub(super) fn push_htn(&mut self, f: HtnFrame) -> HtnId {
        let marks = self.marks();
        let id = self.htn_frames.push(f);
        self.frames.push(Frame {
            marks,
            choice: Choice::Htn(id),
        });
        id
    }

    /// Pushes the choice point of a GS action, with the current marks.
    pub(super) fn push_geo(&mut self, g: GeoFrame) -> GeoId {
        let marks = self.marks();
        let id = self.geo_frames.push(g);
        self.frames.push(Frame {
            marks,
            choice: Choice::Geo(id),
        });
        id
    }

    /// Undoes everything done since the top frame was created (keeps the frame).
    pub(super) fn restore_top(&mut self) {
        let f = self.frames.last().expect("a frame to restore");
        let (m, choice) = (f.marks, f.choice);
        if let Choice::Geo(id) = choice {
            let g = &mut self.geo_frames[id];
            if g.applied {
                g.applied = false;
                if let Some(o) = self.oracle.as_deref_mut() {
                    o.undo();
                }
            }
        }
        self.state.undo_to(m.trail);
        self.arena.truncate(m.arena);
        self.steps.truncate(m.steps);
        self.tree.truncate(m.tree);
        self.next_occ = m.next_occ;
    }

    pub(super) fn pop_frame(&mut self) {
        let f = self.frames.pop().expect("a frame to pop");
        match f.choice {
            Choice::Htn(_) => {
                self.htn_frames.pop();
            }
            Choice::Geo(_) => {
                if let Some(g) = self.geo_frames.pop()
                    && let Some(o) = self.oracle.as_deref_mut()
                {
                    if g.applied {
                        o.undo();
                    }
                    o.close(g.stream);
                }
            }
        }
    }
}
