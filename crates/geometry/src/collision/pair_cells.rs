//! Link pairs whose relative pose depends on two degrees of freedom (an upper arm and the
//! forearm roll link turning in its clevis, two joints down): the plane of those two split
//! into cells, each proven free (the pair apart over the whole cell) or not the first time a
//! check lands in it, and a cell not proven split again, down to cells within which the
//! shapes move [`CELL_MOTION`]. A check skips the exact tests of a pair whose cell is proven:
//! on the real PR2 such pairs, within millimetres of each other wherever the arm is, took two
//! thirds of the self-collision tests' time.
//!
//! A proof is conservative advancement's argument over a box instead of a line: the pair's
//! distance at the cell's centre, a proven lower bound (see `motion.rs`), exceeds how far its
//! shapes can move relative to each other while the two joints stay in the cell (each joint's
//! half-width times the shapes' greatest distance from its axis), with [`CELL_MARGIN`] to
//! spare. A cell's answer depends on the cell alone, so checks answer the same whatever order
//! they come in; where no cell is proven the pair is tested exactly, as before. A cell not
//! proven tells its smaller cells which shape pairs it did not prove: the others are apart
//! over the whole cell, so a smaller cell proves only those (of the upper arm's 12 pieces and
//! the forearm roll link's 13, a few instead of 156). A pair splits at most [`MAX_SPLITS`]
//! cells (14 MiB), so a run that wanders everywhere keeps its memory: past that, a cell not
//! proven is not split but tested exactly.

use std::sync::OnceLock;
use std::sync::atomic::{AtomicU8, AtomicU32, Ordering};

use parry3d::math::Pose;

use super::motion::{JointReach, body, proven_apart};
use super::self_collision::ShapeEntry;
use crate::agent::AgentModel;

/// How far (metres) the shapes of a pair may move relative to each other within one of the
/// smallest cells: a pair more than this apart is proven free in those. Nearer pairs are
/// tested exactly; 1 mm cells proved them too, at more cost than they saved (3-4 % more
/// instructions in the library bench and in one plan; 2, 4 and 6 mm: up to 1 % more).
const CELL_MOTION: f32 = 0.003;

/// Each cell not proven splits into `SPLIT` x `SPLIT` cells, `LEVELS - 1` times: the largest
/// cells allow 32 times [`CELL_MOTION`] (a pair 10 cm apart is proven at once).
const SPLIT: u32 = 2;
const LEVELS: u32 = 6;

/// How far apart (metres) a pair must stay over a cell to be proven free there.
const CELL_MARGIN: f32 = 1e-4;

/// The most of the largest cells along one degree of freedom, and in all.
const MAX_CELLS_PER_DOF: f32 = 1024.0;
const MAX_CELLS: u32 = 1 << 16;

/// The most cells one pair splits (each into `SPLIT` x `SPLIT`, 48 bytes a cell, with at
/// most [`MAX_KEPT_PAIRS`] pair indices): 14 MiB.
const MAX_SPLITS: u32 = 1 << 16;

/// The most of the largest cells a motion's check looks at (a longer motion is followed by
/// conservative advancement alone).
const MAX_CELLS_CROSSED: i64 = 256;

/// A cell's state.
const UNTRIED: u8 = 0;
const FREE: u8 = 1;
/// Not proven: split (the smallest cells: tested exactly).
const NOT_PROVEN: u8 = 2;

/// One degree of freedom split into the largest cells: `n` of `width` from `lo`, around the
/// circle for a continuous joint.
#[derive(Debug)]
struct CellAxis {
    dof: usize,
    lo: f32,
    width: f32,
    n: u32,
    wraps: bool,
}

impl CellAxis {
    /// Where value `v` lies, in units of the largest cells from `lo`; none outside the joint's
    /// limits.
    fn position(&self, v: f32) -> Option<f32> {
        let mut t = (v - self.lo) / self.width;
        if self.wraps {
            t = t.rem_euclid(self.n as f32);
        }
        if t.is_nan() || t < 0.0 || t > self.n as f32 {
            return None;
        }
        Some(t.min(self.n as f32 - 1e-3))
    }

    /// Where value `v` lies, in units of the largest cells from `lo`, not wrapped.
    fn unwrapped(&self, v: f32) -> f32 {
        (v - self.lo) / self.width
    }

    /// The centre of cell `i` (unwrapped) of the cells `scale` times smaller than the largest.
    fn centre(&self, i: i64, scale: u32) -> f32 {
        self.lo + (i as f32 + 0.5) * self.width / scale as f32
    }
}

/// A cell: its state and, once it is found not proven (and can split), its smaller cells.
#[derive(Debug, Default)]
struct Cell {
    state: AtomicU8,
    smaller: OnceLock<Smaller>,
}

/// A cell's smaller cells, and the shape pairs its proof did not prove apart (indices into
/// the pair's list): the only ones the smaller cells, inside it, need to prove. None where
/// there were more than [`MAX_KEPT_PAIRS`]: the smaller cells take the list the cell had.
#[derive(Debug)]
struct Smaller {
    cells: Box<[Cell]>,
    pairs: Option<Box<[u16]>>,
}

/// The most shape pairs a split cell keeps for its smaller cells (bounds the memory a split
/// takes; a longer list is not kept, see [`Smaller`]).
const MAX_KEPT_PAIRS: usize = 16;

fn new_cells(n: u32) -> Box<[Cell]> {
    (0..n).map(|_| Cell::default()).collect()
}

/// The cells of one pair of links; see the module docs.
#[derive(Debug)]
pub(super) struct PairCells {
    axes: [CellAxis; 2],
    largest: Box<[Cell]>,
    /// Every shape pair's index, the list the largest cells prove.
    all: Box<[u16]>,
    /// The shape pair that last failed a proof, tried first in the next (neighbouring cells
    /// fail alike); the order changes how soon a proof fails, not its answer.
    last_failed: AtomicU32,
    /// Cells split so far, at most [`MAX_SPLITS`]: a long run that wanders everywhere keeps
    /// its memory bounded (a cell it may not split is tested exactly).
    splits: AtomicU32,
}

impl Cell {
    /// Splits `self` into smaller cells that need to prove only the shape pairs `unproven`,
    /// unless split already or `cells` may split no more.
    fn split(&self, cells: &PairCells, unproven: Vec<u16>) {
        if self.smaller.get().is_some() {
            return;
        }
        // Loaded first, so that the count stops near the cap instead of wrapping around.
        if cells.splits.load(Ordering::Relaxed) >= MAX_SPLITS
            || cells.splits.fetch_add(1, Ordering::Relaxed) >= MAX_SPLITS
        {
            return;
        }
        self.smaller.get_or_init(|| Smaller {
            cells: new_cells(SPLIT * SPLIT),
            pairs: (unproven.len() <= MAX_KEPT_PAIRS).then(|| unproven.into_boxed_slice()),
        });
    }
}

impl PairCells {
    /// The index of the cell at unwrapped indices `(i, j)` of level `level` among its
    /// siblings: the largest cells in their grid, smaller ones in the cell they split.
    fn sibling(&self, (i, j): (i64, i64), level: u32) -> usize {
        let [a, b] = &self.axes;
        if level == 0 {
            let (i, j) = (i.rem_euclid(a.n as i64), j.rem_euclid(b.n as i64));
            (i * b.n as i64 + j) as usize
        } else {
            let split = SPLIT as i64;
            (i.rem_euclid(split) * split + j.rem_euclid(split)) as usize
        }
    }
}

/// A motion's two degrees of freedom as a segment in units of the largest cells.
struct Segment {
    from: (f32, f32),
    to: (f32, f32),
}

impl Segment {
    /// Whether the segment meets cell `(i, j)` (closed) of the cells `scale` times smaller
    /// than the largest (Liang and Barsky's clipping).
    fn meets(&self, (i, j): (i64, i64), scale: u32) -> bool {
        let k = scale as f32;
        let (mut enter, mut leave) = (0.0f32, 1.0f32);
        for (p, q, lo) in [(self.from.0, self.to.0, i), (self.from.1, self.to.1, j)] {
            let (p, d) = (p * k, (q - p) * k);
            let (lo, hi) = (lo as f32, lo as f32 + 1.0);
            if d.abs() < 1e-12 {
                if p < lo || p > hi {
                    return false;
                }
                continue;
            }
            let (t0, t1) = ((lo - p) / d, (hi - p) / d);
            enter = enter.max(t0.min(t1));
            leave = leave.min(t0.max(t1));
        }
        enter <= leave
    }
}

/// What the cells of a pair of links say at one configuration ([`CellProver::free`]).
pub(super) enum CellProof<'c> {
    /// Every shape pair is apart.
    Apart,
    /// Only these shape pairs (indices into the pair's list) are to be tested; the others
    /// are apart.
    Only(&'c [u16]),
    /// Every shape pair is to be tested (no cells, or beyond a joint's limits).
    All,
}

/// What a cell says of a pair ([`CellProver::look`]).
enum Look<'c> {
    Free,
    Unproven,
    /// Look at the smaller cells, which prove these of the shape pairs.
    Smaller(&'c [Cell], &'c [u16]),
}

/// What a proof needs of the model: its links, shapes and joint reach.
pub(super) struct CellProver<'a> {
    pub(super) model: &'a AgentModel,
    pub(super) shapes: &'a [ShapeEntry],
    pub(super) reach: &'a JointReach,
}

impl CellProver<'_> {
    /// The cells of shape pairs `pairs` (of two links whose relative pose depends on degrees
    /// of freedom `dofs` alone), sized so that the shapes move at most [`CELL_MOTION`] within
    /// the smallest. None where there would be too many.
    pub(super) fn cells(&self, dofs: [usize; 2], pairs: &[(u16, u16)]) -> Option<PairCells> {
        let largest_motion = CELL_MOTION * SPLIT.pow(LEVELS - 1) as f32;
        let axes = dofs.map(|d| {
            let limits = self.model.dof_limits()[d];
            let (lo, hi, wraps) = if limits.is_bounded() {
                (limits.lower, limits.upper, false)
            } else {
                (-std::f32::consts::PI, std::f32::consts::PI, true)
            };
            // How fast the pair's shapes move relative to each other per unit of this degree
            // of freedom; half the allowed motion is this one's.
            let speed = self.joint_speeds(d);
            let rate = pairs
                .iter()
                .map(|&(a, b)| {
                    let (a, b) = (&self.shapes[a as usize], &self.shapes[b as usize]);
                    self.reach.rate(&speed, body(a), Some(body(b)))
                })
                .fold(0.0f32, f32::max);
            let n = ((hi - lo) * rate * 2.0 / largest_motion).ceil().max(1.0);
            (d, lo, hi, wraps, n)
        });
        if axes.iter().any(|a| a.4.is_nan() || a.4 > MAX_CELLS_PER_DOF) {
            return None;
        }
        let n = axes.map(|a| a.4 as u32);
        if n[0] * n[1] > MAX_CELLS || pairs.len() > usize::from(u16::MAX) {
            return None;
        }
        let axes = axes.map(|(dof, lo, hi, wraps, n)| CellAxis {
            dof,
            lo,
            width: (hi - lo) / n,
            n: n as u32,
            wraps,
        });
        Some(PairCells {
            axes,
            largest: new_cells(n[0] * n[1]),
            all: (0..pairs.len() as u16).collect(),
            last_failed: AtomicU32::new(0),
            splits: AtomicU32::new(0),
        })
    }

    /// Each joint's speed when degree of freedom `d` moves at speed 1 (mimic joints at their
    /// multiplier).
    fn joint_speeds(&self, d: usize) -> Vec<f32> {
        let from = self.model.default_configuration().into_vec();
        let mut to = from.clone();
        to[d] += 1.0;
        (0..self.model.joints().len())
            .map(|j| (self.model.joint_value(j, &to) - self.model.joint_value(j, &from)).abs())
            .collect()
    }

    /// What the cells say of shape pairs `pairs` at configuration `q`: apart (the proofs of
    /// the cells `q` lies in, largest first, each made on first use), or which of the pairs
    /// (indices into `pairs`) remain to be tested: those the cell that failed had to prove,
    /// the others being apart over a larger cell that holds it; all of them beyond a
    /// joint's limits.
    pub(super) fn free<'c>(
        &self,
        cells: &'c PairCells,
        pairs: &[(u16, u16)],
        q: &[f32],
    ) -> CellProof<'c> {
        let [a, b] = &cells.axes;
        let (Some(s), Some(t)) = (a.position(q[a.dof]), b.position(q[b.dof])) else {
            return CellProof::All;
        };
        let (mut list, mut unproven): (&[Cell], &[u16]) = (&cells.largest, &cells.all);
        for level in 0..LEVELS {
            let scale = SPLIT.pow(level) as f32;
            let at = ((s * scale) as i64, (t * scale) as i64);
            let cell = &list[cells.sibling(at, level)];
            match self.look(cells, cell, (at, level), (pairs, unproven)) {
                Look::Free => return CellProof::Apart,
                Look::Unproven => return CellProof::Only(unproven),
                Look::Smaller(smaller, left) => (list, unproven) = (smaller, left),
            }
        }
        CellProof::Only(unproven)
    }

    /// Whether shape pairs `pairs` are apart all along the straight motion from
    /// configuration `qa` to `qb` (each joint value moving linearly, a continuous joint's
    /// not wrapped): every cell the motion's two degrees of freedom cross is proven, or
    /// split into cells that are where the motion crosses them. False beyond a joint's
    /// limits, or across more than [`MAX_CELLS_CROSSED`] of the largest cells.
    pub(super) fn free_along(
        &self,
        cells: &PairCells,
        pairs: &[(u16, u16)],
        (qa, qb): (&[f32], &[f32]),
    ) -> bool {
        let [a, b] = &cells.axes;
        let ends = [a, b].map(|x| (x.unwrapped(qa[x.dof]), x.unwrapped(qb[x.dof])));
        let within = |x: &CellAxis, (u, v): (f32, f32)| {
            x.wraps || (u >= 0.0 && v >= 0.0 && u <= x.n as f32 && v <= x.n as f32)
        };
        if !within(a, ends[0])
            || !within(b, ends[1])
            || ends.iter().any(|e| e.0.is_nan() || e.1.is_nan())
        {
            return false;
        }
        let range = |x: &CellAxis, (u, v): (f32, f32)| {
            let (lo, hi) = (u.min(v).floor() as i64, u.max(v).floor() as i64);
            if x.wraps {
                (lo, hi)
            } else {
                (lo.max(0), hi.min(x.n as i64 - 1))
            }
        };
        let (ri, rj) = (range(a, ends[0]), range(b, ends[1]));
        if (ri.1 - ri.0 + 1) * (rj.1 - rj.0 + 1) > MAX_CELLS_CROSSED {
            return false;
        }
        let segment = Segment {
            from: (ends[0].0, ends[1].0),
            to: (ends[0].1, ends[1].1),
        };
        (ri.0..=ri.1).all(|i| {
            (rj.0..=rj.1).all(|j| {
                !segment.meets((i, j), 1)
                    || self.covers(
                        cells,
                        (pairs, &cells.all),
                        &cells.largest[cells.sibling((i, j), 0)],
                        ((i, j), 0),
                        &segment,
                    )
            })
        })
    }

    /// Whether `cell` (at unwrapped indices `at` of level `level`) is proven, or its smaller
    /// cells that `segment` meets all are.
    fn covers(
        &self,
        cells: &PairCells,
        (pairs, unproven): (&[(u16, u16)], &[u16]),
        cell: &Cell,
        (at, level): ((i64, i64), u32),
        segment: &Segment,
    ) -> bool {
        let (smaller, left) = match self.look(cells, cell, (at, level), (pairs, unproven)) {
            Look::Free => return true,
            Look::Unproven => return false,
            Look::Smaller(smaller, left) => (smaller, left),
        };
        let (split, scale) = (SPLIT as i64, SPLIT.pow(level));
        (0..split).all(|di| {
            (0..split).all(|dj| {
                let child = (at.0 * split + di, at.1 * split + dj);
                !segment.meets(child, scale * SPLIT)
                    || self.covers(
                        cells,
                        (pairs, left),
                        &smaller[cells.sibling(child, level + 1)],
                        (child, level + 1),
                        segment,
                    )
            })
        })
    }

    /// What `cell` (at unwrapped indices `at` of level `level`) says, proven now if not yet
    /// tried, of the shape pairs `unproven` (those its larger cells did not prove): proven
    /// free, not (a smallest cell, or one that may not split), or look at its smaller cells.
    fn look<'c>(
        &self,
        cells: &PairCells,
        cell: &'c Cell,
        (at, level): ((i64, i64), u32),
        (pairs, unproven): (&[(u16, u16)], &'c [u16]),
    ) -> Look<'c> {
        let last = level + 1 == LEVELS;
        if cell.state.load(Ordering::Acquire) == UNTRIED {
            let left = self.prove(cells, at, SPLIT.pow(level), (pairs, unproven), last);
            if left.is_empty() {
                cell.state.store(FREE, Ordering::Release);
                return Look::Free;
            }
            if !last {
                cell.split(cells, left);
            }
            // After the split: a cell seen not proven has its smaller cells, or may not split.
            cell.state.store(NOT_PROVEN, Ordering::Release);
        }
        match (cell.state.load(Ordering::Acquire), cell.smaller.get()) {
            (FREE, _) => Look::Free,
            (_, Some(s)) if !last => {
                Look::Smaller(&s.cells, s.pairs.as_deref().unwrap_or(unproven))
            }
            _ => Look::Unproven,
        }
    }

    /// The shape pairs of `unproven` not proven to stay at least [`CELL_MARGIN`] apart over
    /// cell `(i, j)` of the cells `scale` times smaller than the largest: all of them, for the
    /// smaller cells to prove, or (`first_only`, a cell that does not split) the first found.
    fn prove(
        &self,
        cells: &PairCells,
        (i, j): (i64, i64),
        scale: u32,
        (pairs, unproven): (&[(u16, u16)], &[u16]),
        first_only: bool,
    ) -> Vec<u16> {
        if unproven.is_empty() {
            return Vec::new();
        }
        let model = self.model;
        let [a, b] = &cells.axes;
        let mut centre = model.default_configuration().into_vec();
        (centre[a.dof], centre[b.dof]) = (a.centre(i, scale), b.centre(j, scale));
        let mut corner = centre.clone();
        corner[a.dof] += 0.5 * a.width / scale as f32;
        corner[b.dof] += 0.5 * b.width / scale as f32;
        let speed: Vec<f32> = (0..model.joints().len())
            .map(|k| (model.joint_value(k, &corner) - model.joint_value(k, &centre)).abs())
            .collect();
        // The pairs' two links posed (the rest of the model is not needed).
        let links = |(p, r): (u16, u16)| [p, r].map(|s| self.shapes[s as usize].link);
        debug_assert!(pairs.iter().all(|&pr| links(pr) == links(pairs[0])));
        let mut poses = vec![Pose::IDENTITY; model.links().len()];
        for link in links(pairs[0]) {
            poses[link] = model.link_pose_by_id(Pose::IDENTITY, &centre, link);
        }
        // The pair that failed last first: where one fails, it is likely that one.
        let last = cells.last_failed.load(Ordering::Relaxed) as u16;
        let first = unproven.iter().position(|&k| k == last).unwrap_or(0);
        let order = std::iter::once(first).chain((0..unproven.len()).filter(|&k| k != first));
        let mut left = Vec::new();
        for k in order.map(|k| unproven[k]) {
            let (p, r) = pairs[k as usize];
            let (ep, er) = (&self.shapes[p as usize], &self.shapes[r as usize]);
            let motion = self.reach.rate(&speed, body(ep), Some(body(er)));
            if !proven_apart((ep, er), &poses, motion + CELL_MARGIN) {
                cells.last_failed.store(k as u32, Ordering::Relaxed);
                left.push(k);
                if first_only {
                    break;
                }
            }
        }
        left.sort_unstable();
        left
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn axis(lo: f32, hi: f32, n: u32, wraps: bool) -> CellAxis {
        CellAxis {
            dof: 0,
            lo,
            width: (hi - lo) / n as f32,
            n,
            wraps,
        }
    }

    #[test]
    fn values_fall_in_the_cell_that_holds_them() {
        let pi = std::f32::consts::PI;
        let bounded = axis(-1.0, 1.0, 4, false);
        let cell = |x: &CellAxis, v: f32| x.position(v).map(|t| t as u32);
        assert_eq!(cell(&bounded, -1.0), Some(0));
        assert_eq!(cell(&bounded, -0.4), Some(1));
        assert_eq!(cell(&bounded, 0.9), Some(3));
        assert_eq!(cell(&bounded, 1.0), Some(3));
        assert_eq!(cell(&bounded, 1.01), None);
        assert_eq!(cell(&bounded, -1.01), None);
        assert_eq!(cell(&bounded, f32::NAN), None);
        let turning = axis(-pi, pi, 8, true);
        // A turn and a half is half a turn: the same cell.
        let v = pi / 2.0 + 0.1;
        assert_eq!(cell(&turning, v), cell(&turning, v + 2.0 * pi));
        assert_eq!(cell(&turning, v), cell(&turning, v - 4.0 * pi));
        for k in 0..8 {
            assert_eq!(cell(&turning, turning.centre(k, 1)), Some(k as u32));
            // Cells of a turn further on have their centres a turn further.
            let next = turning.centre(k + 8, 1) - turning.centre(k, 1);
            assert!((next - 2.0 * pi).abs() < 1e-5, "{next}");
        }
        // Smaller cells: the fourth of four in the second largest one.
        assert!((bounded.centre(7, 4) - (-1.0 + 7.5 * 0.125)).abs() < 1e-6);
    }

    #[test]
    fn a_segment_meets_the_cells_it_crosses() {
        let s = Segment {
            from: (0.5, 0.5),
            to: (2.5, 1.5),
        };
        // y = 0.5 + (x - 0.5) / 2: through (0, 0), (1, 0), (1, 1), (2, 1).
        for (cell, meets) in [
            ((0, 0), true),
            ((1, 0), true),
            ((1, 1), true),
            ((2, 1), true),
            ((0, 1), false),
            ((2, 0), false),
            ((3, 1), false),
        ] {
            assert_eq!(s.meets(cell, 1), meets, "{cell:?}");
        }
        // Halved cells: (1.5, 1.0) lies on the segment, so the cell (3, 2) from there meets it,
        // but (2, 3) above does not.
        assert!(s.meets((3, 2), 2));
        assert!(!s.meets((2, 3), 2));
        // A segment along a cell's edge meets both cells beside it; a point meets its cell.
        let edge = Segment {
            from: (1.0, 0.2),
            to: (1.0, 0.8),
        };
        assert!(edge.meets((0, 0), 1) && edge.meets((1, 0), 1) && !edge.meets((2, 0), 1));
        let point = Segment {
            from: (0.3, 0.3),
            to: (0.3, 0.3),
        };
        assert!(point.meets((0, 0), 1) && !point.meets((1, 0), 1));
    }
}
