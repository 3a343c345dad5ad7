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

    /// The centre: where a triangle's box is binned.
    fn centre(self) -> Vec3A {
        (self.lo + self.hi) * 0.5
    }

    /// Half the surface area (the heuristic only compares areas).
    fn half_area(self) -> f32 {
        let d = (self.hi - self.lo).max(Vec3A::ZERO);
        d.x * d.y + d.y * d.z + d.z * d.x
    }
}

/// The binary tree: leaves are runs of the reordered triangle indices. An inner node knows how many
/// wide nodes and leaves it is written as (when it heads a wide node), so every subtree's
/// place in the output is known before any is written and they are written in parallel.
enum Node2 {
    Leaf {
        bounds: Aabb,
        start: usize,
        count: usize,
    },
    Inner {
        bounds: Aabb,
        /// The half area of `bounds`, kept: every widening that meets the node compares it.
        area: f32,
        halves: Box<[Node2; 2]>,
        size: Size,
    },
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
        Self::Inner { bounds, area: bounds.half_area(), halves: Box::new(halves), size }
    }

    fn bounds(&self) -> Aabb {
        match self {
            Self::Leaf { bounds, .. } | Self::Inner { bounds, .. } => *bounds,
        }
    }

    /// The half area of an inner node (which a wide node may open); `None` for a leaf.
    fn inner_area(&self) -> Option<f32> {
        match self {
            Self::Leaf { .. } => None,
            Self::Inner { area, .. } => Some(*area),
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
/// The builder moves the triangles' boxes as it sorts their indices, so the passes over a node read
/// its boxes in memory order.
pub fn build(tris: &[[Vec3A; 3]]) -> (Vec<Node8>, Vec<Tri8>) {
    // The triangles' boxes. A box's centre is worked out where it is needed, not stored: every pass
    // streams the boxes through, and the partition moves them.
    let mut prims: Vec<Aabb> = tris
        .par_iter()
        .with_min_len(4096)
        .map(|&[a, b, c]| Aabb { lo: a.min(b).min(c), hi: a.max(b).max(c) })
        .collect();
    let mut order: Vec<u32> = (0..tris.len() as u32).collect();
    let bounds = bounds_of(&prims);
    let root = split(&mut prims, &mut order, 0, 0, bounds, &mut Box::new(Bins::EMPTY));
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

/// The bounds of the boxes `prims`, and of their centres.
fn bounds_of(prims: &[Aabb]) -> (Aabb, Aabb) {
    let of = |boxes: &[Aabb]| {
        boxes.iter().fold((Aabb::EMPTY, Aabb::EMPTY), |(b, c), &p| (b.grow(p), c.grow_point(p.centre())))
    };
    if prims.len() < PARALLEL {
        of(prims)
    } else {
        prims.par_chunks(4096).map(of).reduce(|| (Aabb::EMPTY, Aabb::EMPTY), |a, b| (a.0.grow(b.0), a.1.grow(b.1)))
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

    /// The bin of a centre on each axis: the whole bins it lies past the lowest centre, at most the
    /// last. The offset is never negative (no centre lies below the lowest); it is NaN where an
    /// infinite extent made the scale 0, and that centre goes to bin 0.
    #[cfg(target_arch = "x86_64")]
    #[inline]
    fn bins(&self, centre: Vec3A) -> [usize; 3] {
        use std::arch::x86_64::{_mm_cvttps_epi32, _mm_max_ps, _mm_min_ps, _mm_set1_ps, _mm_setzero_ps};
        let t = ((centre - self.lo) * self.scale).into();
        // Clamped before the conversion, all three axes at once: `maxps` answers its second operand
        // when either is NaN, so NaN becomes 0. In range, the truncation is the floor: the very bins
        // the portable conversion below finds, without its checks for NaN and overflow per axis.
        // SAFETY: the intrinsics need SSE and SSE2, which every x86_64 processor has.
        #[allow(unsafe_code)]
        let b = unsafe {
            let last = _mm_set1_ps((self.count - 1) as f32);
            _mm_cvttps_epi32(_mm_min_ps(_mm_max_ps(t, _mm_setzero_ps()), last))
        };
        let b: [i32; 4] = bytemuck::cast(b);
        [b[0] as usize, b[1] as usize, b[2] as usize]
    }

    #[cfg(not(target_arch = "x86_64"))]
    #[inline]
    fn bins(&self, centre: Vec3A) -> [usize; 3] {
        // The saturating conversion floors a non-negative offset and sends NaN to 0.
        ((centre - self.lo) * self.scale).to_array().map(|t| (t as i32).min(self.count as i32 - 1) as usize)
    }

    /// Counts the centres of `prims` in each bin in use, and bounds their boxes, into `bins` (whose
    /// bins past the count are left as they were: the cut looks at none of them).
    fn fill(&self, prims: &[Aabb], bins: &mut Bins) {
        let add = |bins: &mut Bins, prims: &[Aabb]| {
            for &p in prims {
                for (axis, b) in self.bins(p.centre()).into_iter().enumerate() {
                    bins.count[axis][b] += 1;
                    bins.bounds[axis][b] = bins.bounds[axis][b].grow(p);
                }
            }
        };
        if prims.len() < PARALLEL {
            for axis in 0..3 {
                bins.count[axis][..self.count].fill(0);
                bins.bounds[axis][..self.count].fill(Aabb::EMPTY);
            }
            add(bins, prims);
        } else {
            *bins = prims
                .par_chunks(4096)
                .map(|chunk| {
                    let mut bins = Bins::EMPTY;
                    add(&mut bins, chunk);
                    bins
                })
                .reduce(|| Bins::EMPTY, |a, b| a.merge(&b));
        }
    }
}

/// The binary tree over the triangles `order` lists, whose boxes are `prims` (both reordered alike, so
/// each leaf's triangles are a run), `start` being `order`'s offset in the whole list, given the
/// bounds of those triangles and of their centres. A binned cut hands each half its bounds: the union
/// of its bins' boxes, and its centres' bounds gathered as the cut moves them, so no node passes over
/// its triangles for them again. `bins` is the thread's room for the binning.
fn split(
    prims: &mut [Aabb],
    order: &mut [u32],
    start: usize,
    depth: u32,
    (bounds, centres): (Aabb, Aabb),
    bins: &mut Bins,
) -> Node2 {
    let n = order.len();
    if n <= LEAF_SIZE {
        return Node2::Leaf { bounds, start, count: n };
    }
    let binning = Binning::new(centres, n);
    let cut = (depth < SAH_DEPTH)
        .then(|| {
            binning.fill(prims, bins);
            best_cut(bins, binning.count, n)
        })
        .flatten();
    let (mid, below, above) = match cut {
        Some((axis, bin)) => {
            let (mid, centres_below, centres_above) = partition(prims, order, |c| binning.bins(c)[axis] < bin);
            let union = |bins: &[Aabb]| bins.iter().fold(Aabb::EMPTY, |b, &bin| b.grow(bin));
            let boxes = &bins.bounds[axis][..binning.count];
            (mid, (union(&boxes[..bin]), centres_below), (union(&boxes[bin..]), centres_above))
        }
        None => {
            // No cut separates the centres (they coincide), or the tree is deep: halve at the median
            // centre along the longest axis.
            let axis = (centres.hi - centres.lo).max_position();
            let mut both: Vec<(Aabb, u32)> = prims.iter().copied().zip(order.iter().copied()).collect();
            both.select_nth_unstable_by(n / 2, |a, b| a.0.centre()[axis].total_cmp(&b.0.centre()[axis]));
            for (k, (p, i)) in both.into_iter().enumerate() {
                (prims[k], order[k]) = (p, i);
            }
            let (left, right) = prims.split_at(n / 2);
            (n / 2, bounds_of(left), bounds_of(right))
        }
    };
    let (left, right) = order.split_at_mut(mid);
    let (prims_left, prims_right) = prims.split_at_mut(mid);
    let halves = if n >= PARALLEL {
        rayon::join(
            || split(prims_left, left, start, depth + 1, below, bins),
            || split(prims_right, right, start + mid, depth + 1, above, &mut Box::new(Bins::EMPTY)),
        )
    } else {
        (
            split(prims_left, left, start, depth + 1, below, bins),
            split(prims_right, right, start + mid, depth + 1, above, bins),
        )
    };
    Node2::inner(bounds, [halves.0, halves.1])
}

/// The cut of least surface-area cost among the first `used` bins: an axis and the first bin on its
/// upper side, the lowest axis and then the highest bin among equal costs. A cut with every centre on
/// one side splits nothing: its cost is infinite, and the answer is `None` when every cut's is.
fn best_cut(bins: &Bins, used: usize, n: usize) -> Option<(usize, usize)> {
    // The cost of the lower side of each cut, swept from below; then the whole cost, the upper side's
    // swept from above. The three axes take each step together: their sweeps are independent chains.
    let mut below = [[0.0f32; BINS]; 3];
    let (mut b, mut count) = ([Aabb::EMPTY; 3], [0u32; 3]);
    for bin in 1..used {
        for (axis, below) in below.iter_mut().enumerate() {
            b[axis] = b[axis].grow(bins.bounds[axis][bin - 1]);
            count[axis] += bins.count[axis][bin - 1];
            let lower = b[axis].half_area() * count[axis] as f32;
            below[bin] = if count[axis] == 0 || count[axis] as usize == n { f32::INFINITY } else { lower };
        }
    }
    let (mut b, mut count) = ([Aabb::EMPTY; 3], [0u32; 3]);
    // Each axis's cheapest finite cost (a NaN is never less) and its bin, the highest among equals.
    let mut best = [(f32::INFINITY, 0); 3];
    for bin in (1..used).rev() {
        for axis in 0..3 {
            b[axis] = b[axis].grow(bins.bounds[axis][bin]);
            count[axis] += bins.count[axis][bin];
            let cost = below[axis][bin] + b[axis].half_area() * count[axis] as f32;
            if cost < best[axis].0 {
                best[axis] = (cost, bin);
            }
        }
    }
    let (axis, &(cost, bin)) =
        best.iter().enumerate().reduce(|low, next| if next.1.0 < low.1.0 { next } else { low })?;
    (cost < f32::INFINITY).then_some((axis, bin))
}

/// Moves the triangles (their indices and boxes alike) whose centres `lower` holds for to the front;
/// returns how many there are, and the bounds of the centres on each side.
fn partition(prims: &mut [Aabb], order: &mut [u32], lower: impl Fn(Vec3A) -> bool) -> (usize, Aabb, Aabb) {
    let (mut mid, mut below, mut above) = (0, Aabb::EMPTY, Aabb::EMPTY);
    for i in 0..order.len() {
        let centre = prims[i].centre();
        if lower(centre) {
            prims.swap(i, mid);
            order.swap(i, mid);
            mid += 1;
            below = below.grow_point(centre);
        } else {
            above = above.grow_point(centre);
        }
    }
    (mid, below, above)
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
        let open =
            (0..kids.len).filter_map(|i| Some((i, kids.kid[i].inner_area()?))).max_by(|(_, a), (_, b)| a.total_cmp(b));
        let Some((i, _)) = open else { break };
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
