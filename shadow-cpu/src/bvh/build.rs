//! Building the tree by the surface area heuristic over binned centroids (Wald, "On fast Construction of
//! SAH-based Bounding Volume Hierarchies", 2007), on every core, into eight-wide nodes whose leaves hold
//! up to eight triangles. A wide node's children come from cutting its triangles in two, then cutting
//! the child of largest area again while there is room: the tree a binary SAH tree collapses into, with
//! no binary tree ever built.

use glam::Vec3A;
use rayon::prelude::*;

use super::wide::{Child, LANES, LEAF, NONE, Node8, Tri8};

/// Bins per axis a node's centroids are sorted into, at most: a node of fewer triangles gets one bin
/// per triangle, which finds its cuts as well and sweeps fewer bins.
const BINS: usize = 16;
/// Triangles a leaf holds at most: one [`Tri8`].
const LEAF_SIZE: usize = LANES;
/// Nodes with at least this many triangles are binned, and their children's subtrees built, in parallel.
const PARALLEL: usize = 1 << 13;
/// Fewer cuts than this down from the root, a piece is cut at its best binned cut; deeper, at the
/// median, so no leaf lies more than this many cuts plus log2 of the triangle count down, and a
/// traversal stack of [`STACK`] never overflows.
const SAH_DEPTH: u32 = 48;
/// Entries a traversal stack holds: a wide node pushes at most `LANES - 1` more entries than it pops,
/// and each wide node lies at least one cut below its parent, so the tree is at most [`SAH_DEPTH`] + 32
/// nodes deep.
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

/// The wide tree over `tris` (at least one): its nodes (the root first), its leaves, and each leaf's
/// triangles as indices into `tris`, lane by lane (a leaf of fewer than eight repeats its last one, as
/// its [`Tri8`] does).
///
/// The builder moves the triangles' boxes as it sorts their indices, so the passes over a node read
/// its boxes in memory order.
pub fn build(tris: &[[Vec3A; 3]]) -> (Vec<Node8>, Vec<Tri8>, Vec<Members>) {
    // The triangles' boxes. A box's centre is worked out where it is needed, not stored: every pass
    // streams the boxes through, and the partition moves them.
    let mut prims: Vec<Aabb> = tris
        .par_iter()
        .with_min_len(4096)
        .map(|&[a, b, c]| Aabb { lo: a.min(b).min(c), hi: a.max(b).max(c) })
        .collect();
    let mut order: Vec<u32> = (0..tris.len() as u32).collect();
    let (bounds, centres) = bounds_of(&prims);
    let root = Piece { prims: &mut prims, order: &mut order, depth: 0, bounds, centres };
    if root.is_leaf() {
        // The root is always a wide node, here over a single leaf.
        let mut node = Node8::EMPTY;
        node.set(0, LEAF, bounds.lo, bounds.hi);
        return (
            vec![node],
            vec![Tri8::new(root.order.len(), |i| tris[root.order[i] as usize])],
            vec![members(root.order)],
        );
    }
    let built = subtree(root, &mut Box::new(Bins::EMPTY));
    let size = built.size();
    let mut nodes = vec![Node8::EMPTY; size.nodes];
    let mut leaves = vec![Tri8::EMPTY; size.leaves];
    let mut lanes = vec![[0; LANES]; size.leaves];
    built.write(tris, &mut nodes, 0, (&mut leaves, &mut lanes), 0);
    (nodes, leaves, lanes)
}

/// A leaf's triangles, lane by lane.
pub type Members = [u32; LANES];

/// The lanes of a leaf of the triangles `ids` (one to eight), the last repeated.
fn members(ids: &[u32]) -> Members {
    std::array::from_fn(|k| ids[k.min(ids.len() - 1)])
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

/// Triangles not yet in a leaf: their boxes and indices (reordered alike, so each leaf's triangles are
/// a run), how many cuts down from the root they lie, and the bounds of their boxes and of their
/// centres.
struct Piece<'a> {
    prims: &'a mut [Aabb],
    order: &'a mut [u32],
    depth: u32,
    bounds: Aabb,
    centres: Aabb,
}

impl<'a> Piece<'a> {
    fn is_leaf(&self) -> bool {
        self.order.len() <= LEAF_SIZE
    }

    /// Cuts the piece (more than a leaf's triangles) in two, the lower half first: by the cheapest
    /// binned cut, or at the median. A binned cut hands each half its bounds: the union of its bins'
    /// boxes, and its centres' bounds gathered as the cut moves them, so no piece passes over its
    /// triangles for them again. `bins` is the thread's room for the binning.
    fn cut(self, bins: &mut Bins) -> [Piece<'a>; 2] {
        let Piece { prims, order, depth, centres, .. } = self;
        let n = order.len();
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
                // No cut separates the centres (they coincide), or the tree is deep: halve at the
                // median centre along the longest axis.
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
        let (prims_low, prims_high) = prims.split_at_mut(mid);
        let (order_low, order_high) = order.split_at_mut(mid);
        let depth = depth + 1;
        [
            Piece { prims: prims_low, order: order_low, depth, bounds: below.0, centres: below.1 },
            Piece { prims: prims_high, order: order_high, depth, bounds: above.0, centres: above.1 },
        ]
    }

    /// The children of the wide node over the piece (more than a leaf's triangles): its halves, and
    /// while there is room the child of largest area that is not a leaf cut in two in its place, its
    /// upper half last. Then in order of their centres along the axis they spread most on, so a ray
    /// can open them nearest first; that axis comes with them.
    fn open(self, bins: &mut Bins) -> (Vec<Piece<'a>>, u32) {
        let mut kids = Vec::with_capacity(LANES);
        kids.extend(self.cut(bins));
        while kids.len() < LANES {
            // `max_by` answers the last of equal areas.
            let widest = kids.iter().enumerate().filter(|(_, k)| !k.is_leaf()).map(|(i, k)| (i, k.bounds.half_area()));
            let Some((i, _)) = widest.max_by(|(_, a), (_, b)| a.total_cmp(b)) else { break };
            let [low, high] = kids.remove(i).cut(bins);
            kids.insert(i, low);
            kids.push(high);
        }
        let centre = |k: &Piece<'_>| k.bounds.lo + k.bounds.hi;
        let spread = kids.iter().fold(Aabb::EMPTY, |b, k| b.grow_point(centre(k)));
        let axis = (spread.hi - spread.lo).max_position();
        kids.sort_by(|a, b| centre(a)[axis].total_cmp(&centre(b)[axis]));
        (kids, axis as u32)
    }
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

/// The subtree of the wide node over `piece` (more than a leaf's triangles). A piece of at least
/// [`PARALLEL`] triangles builds its children's subtrees in parallel, each with a [`Bins`] of its own;
/// a smaller one is built whole on this thread, which keeps a thread on one piece of work long enough
/// to be worth waking.
fn subtree<'a>(piece: Piece<'a>, bins: &mut Bins) -> Built<'a> {
    if piece.order.len() < PARALLEL {
        let mut tree = Tree { nodes: Vec::new(), leaves: Vec::new() };
        grow(piece, bins, &mut tree);
        return Built::Alone(tree);
    }
    let (kids, axis) = piece.open(bins);
    let kids = kids
        .into_par_iter()
        .map(|kid| {
            let bounds = kid.bounds;
            (bounds, if kid.is_leaf() { Built::Leaf(kid.order) } else { subtree(kid, &mut Box::new(Bins::EMPTY)) })
        })
        .collect();
    Built::Node { axis, kids }
}

/// Appends the wide node over `piece` (more than a leaf's triangles) to `tree`, then each child's
/// leaf or subtree in turn; answers the node's index.
fn grow<'a>(piece: Piece<'a>, bins: &mut Bins, tree: &mut Tree<'a>) -> Child {
    let (kids, axis) = piece.open(bins);
    let at = tree.nodes.len();
    tree.nodes.push(Node8 { axis, ..Node8::EMPTY });
    for (k, kid) in kids.into_iter().enumerate() {
        let bounds = kid.bounds;
        let child = if kid.is_leaf() {
            tree.leaves.push(kid.order);
            LEAF | (tree.leaves.len() - 1) as Child
        } else {
            grow(kid, bins, tree)
        };
        tree.nodes[at].set(k, child, bounds.lo, bounds.hi);
    }
    at as Child
}

/// A subtree's wide nodes (its root first, each node's children's subtrees after it in turn) and its
/// leaves' triangles (in the order a depth-first walk meets them), numbered from 0 within it.
struct Tree<'a> {
    nodes: Vec<Node8>,
    leaves: Vec<&'a [u32]>,
}

/// A subtree as its threads built it.
enum Built<'a> {
    /// The triangles of a leaf child of a node built in parallel.
    Leaf(&'a [u32]),
    /// A subtree built on one thread.
    Alone(Tree<'a>),
    /// A node whose children's subtrees were built in parallel: the axis of its children's order, and
    /// their boxes and subtrees.
    Node { axis: u32, kids: Vec<(Aabb, Built<'a>)> },
}

/// Wide nodes and leaves a subtree is written as.
#[derive(Clone, Copy)]
struct Size {
    nodes: usize,
    leaves: usize,
}

impl Built<'_> {
    fn size(&self) -> Size {
        match self {
            Self::Leaf(_) => Size { nodes: 0, leaves: 1 },
            Self::Alone(tree) => Size { nodes: tree.nodes.len(), leaves: tree.leaves.len() },
            Self::Node { kids, .. } => {
                kids.iter().map(|(_, kid)| kid.size()).fold(Size { nodes: 1, leaves: 0 }, |a, b| Size {
                    nodes: a.nodes + b.nodes,
                    leaves: a.leaves + b.leaves,
                })
            }
        }
    }

    /// Writes the subtree into the whole tree's `nodes` (from index `node_at`) and leaves with their
    /// members (from `leaf_at`), slices cut to its size; a node built in parallel writes its children
    /// in parallel.
    fn write(
        self,
        tris: &[[Vec3A; 3]],
        nodes: &mut [Node8],
        node_at: usize,
        (leaves, lanes): (&mut [Tri8], &mut [Members]),
        leaf_at: usize,
    ) {
        let leaf = |ids: &[u32]| Tri8::new(ids.len(), |i| tris[ids[i] as usize]);
        match self {
            Self::Leaf(ids) => (leaves[0], lanes[0]) = (leaf(ids), members(ids)),
            Self::Alone(tree) => {
                // Its numbers start at 0: every child moves by where the subtree starts.
                for (to, mut node) in nodes.iter_mut().zip(tree.nodes) {
                    for child in node.child.iter_mut().filter(|c| **c != NONE) {
                        *child += if *child & LEAF != 0 { leaf_at } else { node_at } as Child;
                    }
                    *to = node;
                }
                for ((to, lanes), ids) in leaves.iter_mut().zip(lanes.iter_mut()).zip(tree.leaves) {
                    (*to, *lanes) = (leaf(ids), members(ids));
                }
            }
            Self::Node { axis, kids } => {
                // A subtree's slice holds its own node first: a parallel node's size counts itself.
                let (node, mut nodes_rest) = nodes.split_first_mut().expect("a slot for the node");
                let (mut leaves_rest, mut lanes_rest) = (leaves, lanes);
                node.axis = axis;
                let (mut next_node, mut next_leaf) = (node_at + 1, leaf_at);
                let mut parts = Vec::with_capacity(kids.len());
                for (k, (b, kid)) in kids.into_iter().enumerate() {
                    let size = kid.size();
                    let child = match kid {
                        Self::Leaf(_) => LEAF | next_leaf as Child,
                        _ => next_node as Child,
                    };
                    node.set(k, child, b.lo, b.hi);
                    let (kid_nodes, more_nodes) = std::mem::take(&mut nodes_rest).split_at_mut(size.nodes);
                    let (kid_leaves, more_leaves) = std::mem::take(&mut leaves_rest).split_at_mut(size.leaves);
                    let (kid_lanes, more_lanes) = std::mem::take(&mut lanes_rest).split_at_mut(size.leaves);
                    (nodes_rest, leaves_rest, lanes_rest) = (more_nodes, more_leaves, more_lanes);
                    parts.push((kid, kid_nodes, next_node, (kid_leaves, kid_lanes), next_leaf));
                    next_node += size.nodes;
                    next_leaf += size.leaves;
                }
                parts.into_par_iter().for_each(|(kid, nodes, node_at, leaves, leaf_at)| {
                    kid.write(tris, nodes, node_at, leaves, leaf_at)
                });
            }
        }
    }
}
