//! The nearest configuration of an RRT tree to a query: a k-d tree over the joint space, with
//! continuous joints on the circle.
//!
//! A query costs about `O(log n)` instead of a scan of every node, so a query that grows its
//! trees to thousands of nodes without connecting costs `O(n log n)`, not `O(n^2)`. Points are
//! inserted as they come (each node splits on the widest axis of its cell's insertion order:
//! the axes in turn); the tree is rebuilt balanced (median splits on the axis of largest
//! spread) each time it doubles, so insertion order cannot degrade it for long.
//!
//! The answer is exactly the linear scan's: the first index of least squared distance, the
//! distance computed by the caller's function on the stored configurations. A subtree is pruned
//! when the squared distance to its cell (the sum over axes of the squared offset to the cell's
//! interval, around the circle for continuous axes) exceeds the best so far, with a small slack
//! so that rounding cannot prune the true nearest.

use std::f32::consts::PI;

/// No child.
const NONE: u32 = u32::MAX;

/// Relative slack of the pruning test (rounding of the caller's distance against the bound).
const SLACK: f32 = 1e-4;

/// Rebuilt balanced first at this size, then at each doubling.
const FIRST_BUILD: usize = 32;

/// One nearest-neighbour query in progress.
struct Query<F> {
    /// The query's coordinates, continuous ones folded.
    key: Vec<f32>,
    /// Per axis, a lower bound on the distance from the query to the current cell.
    offsets: Vec<f32>,
    /// The least squared distance so far and its index.
    best: (f32, usize),
    distance2: F,
}

#[derive(Clone, Copy, Debug)]
struct Node {
    /// The point this node holds (its index of insertion).
    point: u32,
    /// The axis it splits: lower keys go left, higher or equal right.
    axis: u16,
    left: u32,
    right: u32,
}

/// A k-d tree over points of `dim` coordinates, indexed in insertion order.
#[derive(Clone, Debug)]
pub(crate) struct KdTree {
    dim: usize,
    continuous: Vec<bool>,
    /// Coordinates with continuous ones folded into `[-pi, pi)`, flat.
    keys: Vec<f32>,
    nodes: Vec<Node>,
    root: u32,
    /// Size at the next balanced rebuild.
    next_build: usize,
}

impl KdTree {
    /// An empty tree; `continuous[k]` says whether axis `k` wraps around (an angle).
    pub(crate) fn new(continuous: &[bool]) -> KdTree {
        KdTree {
            dim: continuous.len(),
            continuous: continuous.to_vec(),
            keys: Vec::new(),
            nodes: Vec::new(),
            root: NONE,
            next_build: FIRST_BUILD,
        }
    }

    /// Number of points.
    pub(crate) fn len(&self) -> usize {
        self.nodes.len()
    }

    /// Adds the point `q` with the next index.
    pub(crate) fn insert(&mut self, q: &[f32]) {
        let i = self.len();
        let key = self.key(q);
        self.keys.extend_from_slice(&key);
        let mut parent = self.root;
        let mut axis = 0;
        let mut link: Option<(u32, bool)> = None;
        while parent != NONE {
            let n = self.nodes[parent as usize];
            axis = (n.axis as usize + 1) % self.dim.max(1);
            let right = key[n.axis as usize] >= self.coord(n.point, n.axis as usize);
            link = Some((parent, right));
            parent = if right { n.right } else { n.left };
        }
        self.nodes.push(Node {
            point: i as u32,
            axis: axis as u16,
            left: NONE,
            right: NONE,
        });
        match link {
            None => self.root = i as u32,
            Some((p, true)) => self.nodes[p as usize].right = i as u32,
            Some((p, false)) => self.nodes[p as usize].left = i as u32,
        }
        if self.len() >= self.next_build {
            self.rebuild();
            self.next_build = self.len() * 2;
        }
    }

    /// The first index of least `distance2(index)`, the caller's squared distance of the
    /// query `q` to the point of that index; `None` when empty.
    pub(crate) fn nearest(&self, q: &[f32], distance2: impl Fn(usize) -> f32) -> Option<usize> {
        if self.root == NONE {
            return None;
        }
        let mut query = Query {
            key: self.key(q),
            offsets: vec![0.0; self.dim],
            best: (f32::INFINITY, usize::MAX),
            distance2,
        };
        self.search(self.root, 0.0, &mut query);
        Some(query.best.1)
    }

    /// Visits the subtree of `n`, whose cell lies at least `sqrt(cell2)` from the query (the
    /// sum of the squared per-axis offsets in `query.offsets`), the query's side first.
    fn search<F: Fn(usize) -> f32>(&self, n: u32, cell2: f32, query: &mut Query<F>) {
        let node = self.nodes[n as usize];
        let p = node.point as usize;
        let d = (query.distance2)(p);
        if d < query.best.0 || (d == query.best.0 && p < query.best.1) {
            query.best = (d, p);
        }
        let axis = node.axis as usize;
        let (q, split) = (query.key[axis], self.coord(node.point, axis));
        let below = q < split;
        let (near, other) = if below {
            (node.left, node.right)
        } else {
            (node.right, node.left)
        };
        if near != NONE {
            self.search(near, cell2, query);
        }
        if other == NONE {
            return;
        }
        // The other side's cell: this axis's offset grows to the split plane's.
        let old = query.offsets[axis];
        let new = self.bound(axis, q, split, below).max(old);
        let other2 = cell2 - old * old + new * new;
        if other2 <= query.best.0 * (1.0 + SLACK) + f32::EPSILON {
            query.offsets[axis] = new;
            self.search(other, other2, query);
            query.offsets[axis] = old;
        }
    }

    /// A lower bound on the distance along `axis` from the query coordinate `q` to the side of
    /// `split` the query is not on (`below`: the query is below it).
    fn bound(&self, axis: usize, q: f32, split: f32, below: bool) -> f32 {
        let straight = (split - q).abs();
        if !self.continuous[axis] {
            return straight;
        }
        // The other side, around the circle: past pi (from below) or past -pi (from above).
        let around = if below { q + PI } else { PI - q };
        straight.min(around.max(0.0))
    }

    fn coord(&self, point: u32, axis: usize) -> f32 {
        self.keys[point as usize * self.dim + axis]
    }

    fn key(&self, q: &[f32]) -> Vec<f32> {
        q.iter()
            .zip(&self.continuous)
            .map(|(&x, &c)| if c { crate::rrt::wrap(x) } else { x })
            .collect()
    }

    /// Rebuilds the tree balanced over every point.
    fn rebuild(&mut self) {
        let mut points: Vec<u32> = (0..self.len() as u32).collect();
        self.root = self.build(&mut points);
    }

    /// Builds a balanced subtree over `points`; returns its root.
    fn build(&mut self, points: &mut [u32]) -> u32 {
        if points.is_empty() {
            return NONE;
        }
        let axis = self.widest_axis(points);
        let mid = points.len() / 2;
        points.select_nth_unstable_by(mid, |&a, &b| {
            self.coord(a, axis)
                .total_cmp(&self.coord(b, axis))
                .then(a.cmp(&b))
        });
        let point = points[mid];
        // Keys equal to the split's must go right (the query descends right on equality).
        let split = self.coord(point, axis);
        let (lower, rest) = points.split_at_mut(mid);
        let mut left_len = lower.len();
        while left_len > 0 && self.coord(lower[left_len - 1], axis) >= split {
            left_len -= 1;
        }
        let mut moved: Vec<u32> = lower[left_len..].to_vec();
        moved.extend_from_slice(&rest[1..]);
        let left = self.build(&mut lower[..left_len]);
        let right = self.build(&mut moved);
        let node = &mut self.nodes[point as usize];
        node.axis = axis as u16;
        node.left = left;
        node.right = right;
        point
    }

    fn widest_axis(&self, points: &[u32]) -> usize {
        let mut best = (f32::NEG_INFINITY, 0);
        for axis in 0..self.dim {
            let (lo, hi) =
                points
                    .iter()
                    .fold((f32::INFINITY, f32::NEG_INFINITY), |(lo, hi), &p| {
                        let c = self.coord(p, axis);
                        (lo.min(c), hi.max(c))
                    });
            if hi - lo > best.0 {
                best = (hi - lo, axis);
            }
        }
        best.1
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::rrt::JointSpace;

    /// The linear scan the tree must agree with.
    fn scan(points: &[Vec<f32>], d2: impl Fn(usize) -> f32) -> usize {
        let mut best = (f32::INFINITY, 0);
        for i in 0..points.len() {
            let d = d2(i);
            if d < best.0 {
                best = (d, i);
            }
        }
        best.1
    }

    fn agrees_with_the_scan(continuous: &[bool], seed: u64, n: usize, grid: bool) {
        let space = JointSpace::new(
            &continuous
                .iter()
                .map(|&c| (-2.0, 2.5, c))
                .collect::<Vec<_>>(),
        );
        let mut rng = fastrand::Rng::with_seed(seed);
        let mut tree = KdTree::new(continuous);
        let mut points: Vec<Vec<f32>> = Vec::new();
        let mut q = vec![0.0; continuous.len()];
        for i in 0..n {
            space.sample(&mut rng, &mut q);
            if grid {
                // Many equal coordinates and exact ties.
                q.iter_mut().for_each(|x| *x = (*x * 2.0).round() / 2.0);
            }
            if i == 0 {
                // A root given out of range on a continuous joint.
                q.iter_mut().for_each(|x| *x += 7.0);
            }
            tree.insert(&q);
            points.push(q.clone());
            for _ in 0..3 {
                let mut query = vec![0.0; continuous.len()];
                space.sample(&mut rng, &mut query);
                let d2 = |j: usize| space.distance_squared(&query, &points[j]);
                assert_eq!(
                    tree.nearest(&query, d2),
                    Some(scan(&points, d2)),
                    "point {i}"
                );
            }
        }
    }

    #[test]
    fn finds_what_the_linear_scan_finds_on_bounded_joints() {
        agrees_with_the_scan(&[false; 7], 1, 600, false);
    }

    #[test]
    fn finds_what_the_linear_scan_finds_across_the_wrap_of_continuous_joints() {
        agrees_with_the_scan(
            &[false, true, false, true, true, false, true],
            2,
            600,
            false,
        );
        agrees_with_the_scan(&[true, true], 3, 400, false);
    }

    #[test]
    fn breaks_ties_by_the_first_index_as_the_scan_does() {
        agrees_with_the_scan(&[false, true, false], 4, 500, true);
    }

    #[test]
    fn an_empty_tree_has_no_nearest() {
        assert_eq!(
            KdTree::new(&[false, true]).nearest(&[0.0, 0.0], |_| 0.0),
            None
        );
    }
}
