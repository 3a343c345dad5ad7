//! Building the tree: a binary tree by the surface area heuristic over binned centroids (Wald, "On fast
//! Construction of SAH-based Bounding Volume Hierarchies", 2007), on every core, then collapsed into
//! eight-wide nodes whose leaves hold up to eight triangles.

use glam::Vec3A;
use rayon::prelude::*;

use super::wide::{Child, LANES, LEAF, Node8, Tri8};

/// Bins per axis a node's centroids are sorted into, at most: a node of fewer triangles gets one bin
/// per triangle, which finds its cuts as well and sweeps fewer bins.
const BINS: usize = 16;
/// Triangles a leaf holds at most: one [`Tri8`].
const LEAF_SIZE: usize = LANES;
/// Nodes with at least this many triangles are binned, and their halves built, in parallel.
const PARALLEL: usize = 1 << 13;
/// Below this depth the split is the best binned one; deeper, it is the median, so the binary tree is at
/// most this deep plus log2 of the triangle count, and a traversal stack of [`STACK`] never overflows.
const SAH_DEPTH: u32 = 48;
/// Entries a traversal stack holds: a wide node pushes at most `LANES - 1` more entries than it pops,
/// and the wide tree is no deeper than the binary one (at most [`SAH_DEPTH`] + 32).
pub const STACK: usize = (LANES - 1) * (SAH_DEPTH as usize + 32) + 1;

/// An axis-aligned box.
#[derive(Clone, Copy)]
struct Aabb {
    lo: Vec3A,
    hi: Vec3A,
}

impl Aabb {
    const EMPTY: Self = Self { lo: Vec3A::INFINITY, hi: Vec3A::NEG_INFINITY };

    fn grow(self, other: Self) -> Self {
        Self { lo: self.lo.min(other.lo), hi: self.hi.max(other.hi) }
    }

    fn grow_point(self, p: Vec3A) -> Self {
        Self { lo: self.lo.min(p), hi: self.hi.max(p) }
    }

    /// Half the surface area (the heuristic only compares areas).
    fn half_area(self) -> f32 {
        let d = (self.hi - self.lo).max(Vec3A::ZERO);
        d.x * d.y + d.y * d.z + d.z * d.x
    }
}

/// A triangle's box and its centre.
#[derive(Clone, Copy)]
struct Prim {
    bounds: Aabb,
    centre: Vec3A,
}

/// The binary tree: leaves are runs of the reordered triangle indices. An inner node knows how many
/// wide nodes and leaves it is written as (when it heads a wide node), so every subtree's
/// place in the output is known before any is written and they are written in parallel.
enum Node2 {
    Leaf { bounds: Aabb, start: usize, count: usize },
    Inner { bounds: Aabb, halves: Box<[Node2; 2]>, size: Size },
}

/// Wide nodes and leaves a subtree is written as.
#[derive(Clone, Copy, Default)]
struct Size {
    nodes: usize,
    leaves: usize,
}

impl Node2 {
    fn inner(bounds: Aabb, halves: [Node2; 2]) -> Self {
        let mut size = Size { nodes: 1, leaves: 0 };
        for kid in widen(&halves).iter() {
            let s = kid.size();
            size.nodes += s.nodes;
            size.leaves += s.leaves;
        }
        Self::Inner { bounds, halves: Box::new(halves), size }
    }

    fn bounds(&self) -> Aabb {
        match self {
            Self::Leaf { bounds, .. } | Self::Inner { bounds, .. } => *bounds,
        }
    }

    /// What the node is written as when it is a wide node's child.
    fn size(&self) -> Size {
        match self {
            Self::Leaf { .. } => Size { nodes: 0, leaves: 1 },
            Self::Inner { size, .. } => *size,
        }
    }
}

/// The wide tree over `tris`: its nodes (the root first) and its leaves.
///
/// The builder sorts a list of triangle indices, not the triangles' boxes: partitioning 4-byte indices
/// in place measured faster here than moving the boxes, though the passes over a node then read its
/// boxes out of order.
pub fn build(tris: &[[Vec3A; 3]]) -> (Vec<Node8>, Vec<Tri8>) {
    let prims: Vec<Prim> = tris
        .par_iter()
        .with_min_len(4096)
        .map(|&[a, b, c]| {
            let bounds = Aabb { lo: a.min(b).min(c), hi: a.max(b).max(c) };
            Prim { bounds, centre: (bounds.lo + bounds.hi) * 0.5 }
        })
        .collect();
    let mut order: Vec<u32> = (0..tris.len() as u32).collect();
    let root = split(&prims, &mut order, 0, 0);
    // The root is always a wide node: over the widened halves of an inner root, or over a root
    // that is a single leaf.
    let (kids, size) = match &root {
        Node2::Inner { halves, size, .. } => (widen(halves), *size),
        leaf => (Kids { kid: [leaf; LANES], len: 1 }, Size { nodes: 1, leaves: 1 }),
    };
    let mut nodes = vec![Node8::EMPTY; size.nodes];
    let mut leaves = vec![Tri8::EMPTY; size.leaves];
    Out { tris, order: &order }.write(kids, &mut nodes, 0, &mut leaves, 0);
    (nodes, leaves)
}

/// The bounds of the triangles `order` lists, and of their centres.
fn bounds_of(prims: &[Prim], order: &[u32]) -> (Aabb, Aabb) {
    let of = |ids: &[u32]| {
        ids.iter().fold((Aabb::EMPTY, Aabb::EMPTY), |(b, c), &i| {
            let p = prims[i as usize];
            (b.grow(p.bounds), c.grow_point(p.centre))
        })
    };
    if order.len() < PARALLEL {
        of(order)
    } else {
        order.par_chunks(4096).map(of).reduce(|| (Aabb::EMPTY, Aabb::EMPTY), |a, b| (a.0.grow(b.0), a.1.grow(b.1)))
    }
}

/// Counts and boxes of the triangles whose centres fall in each bin, per axis.
#[derive(Clone, Copy)]
struct Bins {
    count: [[u32; BINS]; 3],
    bounds: [[Aabb; BINS]; 3],
}

impl Bins {
    const EMPTY: Self = Self { count: [[0; BINS]; 3], bounds: [[Aabb::EMPTY; BINS]; 3] };

    fn merge(mut self, other: &Self) -> Self {
        for axis in 0..3 {
            for b in 0..BINS {
                self.count[axis][b] += other.count[axis][b];
                self.bounds[axis][b] = self.bounds[axis][b].grow(other.bounds[axis][b]);
            }
        }
        self
    }
}

/// Where a centre falls among the bins spanning the centres' bounds.
#[derive(Clone, Copy)]
struct Binning {
    lo: Vec3A,
    scale: Vec3A,
    /// Bins in use (at most [`BINS`]).
    count: usize,
}

impl Binning {
    fn new(centres: Aabb, triangles: usize) -> Self {
        let count = triangles.min(BINS);
        let extent = centres.hi - centres.lo;
        // Scaled a hair under the count, so the upper bound's centre lands in the last bin, not past it.
        let scale = Vec3A::select(extent.cmpgt(Vec3A::ZERO), (count as f32 * 0.999_99) / extent, Vec3A::ZERO);
        Self { lo: centres.lo, scale, count }
    }

    /// The bin of a centre along one axis.
    fn bin(&self, centre: Vec3A, axis: usize) -> usize {
        let at = |v: Vec3A| v.to_array()[axis];
        self.clamped((at(centre) - at(self.lo)) * at(self.scale))
    }

    /// The bin of a centre on each axis.
    fn bins(&self, centre: Vec3A) -> [usize; 3] {
        ((centre - self.lo) * self.scale).to_array().map(|t| self.clamped(t))
    }

    /// The bin at `t` bins past the lowest centre: `t` is not negative (no centre lies below the lowest),
    /// so the conversion through i32 (a shorter one than to usize) floors it, NaN to 0.
    #[inline]
    fn clamped(&self, t: f32) -> usize {
        (t as i32).min(self.count as i32 - 1) as usize
    }

    fn fill(&self, prims: &[Prim], order: &[u32]) -> Bins {
        let of = |ids: &[u32]| {
            let mut bins = Bins::EMPTY;
            for &i in ids {
                let p = prims[i as usize];
                for (axis, b) in self.bins(p.centre).into_iter().enumerate() {
                    bins.count[axis][b] += 1;
                    bins.bounds[axis][b] = bins.bounds[axis][b].grow(p.bounds);
                }
            }
            bins
        };
        if order.len() < PARALLEL {
            of(order)
        } else {
            order.par_chunks(4096).map(of).reduce(|| Bins::EMPTY, |a, b| a.merge(&b))
        }
    }
}

/// The binary tree over the triangles `order` lists (which it reorders so each leaf's are a run),
/// `start` being `order`'s offset in the whole list.
fn split(prims: &[Prim], order: &mut [u32], start: usize, depth: u32) -> Node2 {
    let (bounds, centres) = bounds_of(prims, order);
    let n = order.len();
    if n <= LEAF_SIZE {
        return Node2::Leaf { bounds, start, count: n };
    }
    let binning = Binning::new(centres, n);
    let cut = if depth < SAH_DEPTH { best_cut(&binning.fill(prims, order), binning.count, n) } else { None };
    let mid = match cut {
        Some((axis, bin)) => partition(order, |i| binning.bin(prims[i as usize].centre, axis) < bin),
        None => {
            // No cut separates the centres (they coincide), or the tree is deep: halve at the median
            // centre along the longest axis.
            let axis = (centres.hi - centres.lo).max_position();
            order.select_nth_unstable_by(n / 2, |&a, &b| {
                prims[a as usize].centre[axis].total_cmp(&prims[b as usize].centre[axis])
            });
            n / 2
        }
    };
    let (left, right) = order.split_at_mut(mid);
    let halves = if n >= PARALLEL {
        rayon::join(|| split(prims, left, start, depth + 1), || split(prims, right, start + mid, depth + 1))
    } else {
        (split(prims, left, start, depth + 1), split(prims, right, start + mid, depth + 1))
    };
    Node2::inner(bounds, [halves.0, halves.1])
}

/// The cut of least surface-area cost among the first `used` bins: an axis and the first bin on its
/// upper side. `None` when every centre is in one bin on every axis.
fn best_cut(bins: &Bins, used: usize, n: usize) -> Option<(usize, usize)> {
    let mut best: Option<(f32, usize, usize)> = None;
    for axis in 0..3 {
        // The cost of the lower side of each cut, swept from below; then the upper side's from above.
        // A cut with every centre on one side splits nothing: its cost is infinite.
        let mut below = [0.0f32; BINS];
        let (mut b, mut count) = (Aabb::EMPTY, 0);
        for (bin, cost) in below.iter_mut().enumerate().take(used).skip(1) {
            b = b.grow(bins.bounds[axis][bin - 1]);
            count += bins.count[axis][bin - 1];
            *cost = if count == 0 || count as usize == n { f32::INFINITY } else { b.half_area() * count as f32 };
        }
        let (mut b, mut count) = (Aabb::EMPTY, 0);
        for bin in (1..used).rev() {
            b = b.grow(bins.bounds[axis][bin]);
            count += bins.count[axis][bin];
            let cost = below[bin] + b.half_area() * count as f32;
            if cost.is_finite() && best.is_none_or(|(c, ..)| cost < c) {
                best = Some((cost, axis, bin));
            }
        }
    }
    best.map(|(_, axis, bin)| (axis, bin))
}

/// Moves the indices for which `lower` holds to the front; returns how many there are.
fn partition(order: &mut [u32], lower: impl Fn(u32) -> bool) -> usize {
    let mut mid = 0;
    for i in 0..order.len() {
        if lower(order[i]) {
            order.swap(i, mid);
            mid += 1;
        }
    }
    mid
}

/// Up to [`LANES`] children of a wide node.
#[derive(Clone, Copy)]
struct Kids<'a> {
    kid: [&'a Node2; LANES],
    len: usize,
}

impl<'a> Kids<'a> {
    fn iter(&self) -> impl Iterator<Item = &'a Node2> + '_ {
        self.kid[..self.len].iter().copied()
    }
}

/// The children of a wide node over the binary node with `halves`: the inner child of largest
/// area is opened into its own halves while there is room.
fn widen(halves: &[Node2; 2]) -> Kids<'_> {
    let mut kids = Kids { kid: [&halves[1]; LANES], len: 2 };
    kids.kid[0] = &halves[0];
    while kids.len < LANES {
        let open = (0..kids.len)
            .filter(|&i| matches!(kids.kid[i], Node2::Inner { .. }))
            .max_by(|&a, &b| kids.kid[a].bounds().half_area().total_cmp(&kids.kid[b].bounds().half_area()));
        let Some(i) = open else { break };
        let Node2::Inner { halves, .. } = kids.kid[i] else { unreachable!("only inner kids are opened") };
        kids.kid[i] = &halves[0];
        kids.kid[kids.len] = &halves[1];
        kids.len += 1;
    }
    kids
}

/// Writes the wide tree, depth first: a node, then each child's subtree in turn.
struct Out<'a> {
    tris: &'a [[Vec3A; 3]],
    order: &'a [u32],
}

impl Out<'_> {
    /// Writes a node over `kids` at `nodes[0]` (index `node_at` in the whole tree) and its subtrees
    /// after it, their leaves into `leaves` (from index `leaf_at`). Each subtree's slices are cut by
    /// its size, so a node with many leaves below writes its subtrees in parallel.
    fn write(&self, mut kids: Kids<'_>, nodes: &mut [Node8], node_at: usize, leaves: &mut [Tri8], leaf_at: usize) {
        let parallel = leaves.len() >= PARALLEL / LEAF_SIZE;
        // A subtree's slice holds its own node first: every inner size counts itself.
        let (node, mut nodes_rest) = nodes.split_first_mut().expect("a slot for the node");
        // The children in order along the axis their centres spread most on.
        let centre = |n: &Node2| n.bounds().lo + n.bounds().hi;
        let spread = kids.iter().fold(Aabb::EMPTY, |b, k| b.grow_point(centre(k)));
        let axis = (spread.hi - spread.lo).max_position();
        kids.kid[..kids.len].sort_by(|a, b| centre(a)[axis].total_cmp(&centre(b)[axis]));
        node.axis = axis as u32;
        let mut leaves_rest = leaves;
        let (mut next_node, mut next_leaf) = (node_at + 1, leaf_at);
        let mut below: [Option<Subtree<'_, '_>>; LANES] = std::array::from_fn(|_| None);
        for (k, kid) in kids.iter().enumerate() {
            let size = kid.size();
            let (kid_nodes, more_nodes) = std::mem::take(&mut nodes_rest).split_at_mut(size.nodes);
            let (kid_leaves, more_leaves) = std::mem::take(&mut leaves_rest).split_at_mut(size.leaves);
            (nodes_rest, leaves_rest) = (more_nodes, more_leaves);
            let child = match kid {
                Node2::Leaf { start, count, .. } => {
                    let ids = &self.order[*start..start + count];
                    kid_leaves[0] = Tri8::new(ids.len(), |i| self.tris[ids[i] as usize]);
                    LEAF | next_leaf as Child
                }
                Node2::Inner { halves, .. } => {
                    below[k] = Some((widen(halves), kid_nodes, next_node, kid_leaves, next_leaf));
                    next_node as Child
                }
            };
            let b = kid.bounds();
            node.set(k, child, b.lo, b.hi);
            next_node += size.nodes;
            next_leaf += size.leaves;
        }
        let below = below.into_iter().flatten();
        if parallel {
            rayon::scope(|scope| {
                for (kids, nodes, at, leaves, leaf_at) in below {
                    scope.spawn(move |_| self.write(kids, nodes, at, leaves, leaf_at));
                }
            });
        } else {
            for (kids, nodes, at, leaves, leaf_at) in below {
                self.write(kids, nodes, at, leaves, leaf_at);
            }
        }
    }
}

/// A subtree still to be written: its root's children, its slices and where they start in the tree.
type Subtree<'k, 's> = (Kids<'k>, &'s mut [Node8], usize, &'s mut [Tri8], usize);
