//! The eight-wide blocks the BVH is made of, and the tests a shadow ray runs against them: a node holds
//! the boxes of up to eight children side by side, a leaf up to eight triangles side by side, one per
//! lane, so one pass of plain per-lane arithmetic (which the compiler turns into vector instructions:
//! one 8-wide AVX operation, or two 4-wide SSE ones) tests all eight.
//!
//! Eight, not four: the walk is bound by arithmetic, not by memory, and an eight-wide tree is two thirds
//! as deep, so a ray runs fewer, wider tests. With AVX2 that is a quarter to a third more rays per
//! second than a four-wide tree on the bench sets; with SSE alone about the same.

use glam::{Mat4, Vec3A};

/// The lanes of a block.
pub const LANES: usize = 8;

/// A reference to a child: a [`Node8`] index, or (with [`LEAF`] set) a [`Tri8`] index.
pub type Child = u32;
/// The bit that marks a [`Child`] as a leaf.
pub const LEAF: Child = 1 << 31;
/// A slot with no child. Its box is empty (lower corner +inf, upper -inf), so no ray ever enters it.
pub const NONE: Child = u32::MAX;

/// Slack on a box's far distance. A box is entered when its near distance is at most its far distance;
/// with each slab distance rounded, a ray that touches a box (or lies in a flat box's plane) could see
/// near a hair beyond far. Growing far by 1 + 2 gamma(3) (Ize, "Robust BVH Ray Traversal", 2013) keeps
/// every box a hit triangle lies in entered, so the tree never changes an answer.
const FAR_SLACK: f32 = 1.0 + 2.0 * (3.0 * f32::EPSILON / 2.0) / (1.0 - 3.0 * f32::EPSILON / 2.0);

/// Up to eight children's boxes: rows 0-2 the lower corner's x, y, z, rows 3-5 the upper corner's. The
/// children are in order of their centres along `axis`, so a ray can open them nearest first.
#[derive(Clone, Copy, Debug)]
#[cfg_attr(test, derive(PartialEq))]
#[repr(C, align(64))]
pub struct Node8 {
    pub bounds: [[f32; LANES]; 6],
    pub child: [Child; LANES],
    pub axis: u32,
}

impl Node8 {
    /// A node with no children.
    pub const EMPTY: Self = Self {
        bounds: [
            [f32::INFINITY; LANES],
            [f32::INFINITY; LANES],
            [f32::INFINITY; LANES],
            [f32::NEG_INFINITY; LANES],
            [f32::NEG_INFINITY; LANES],
            [f32::NEG_INFINITY; LANES],
        ],
        child: [NONE; LANES],
        axis: 0,
    };

    /// Puts a child and its box in lane `k`.
    pub fn set(&mut self, k: usize, child: Child, lo: Vec3A, hi: Vec3A) {
        for axis in 0..3 {
            self.bounds[axis][k] = lo[axis];
            self.bounds[axis + 3][k] = hi[axis];
        }
        self.child[k] = child;
    }

    /// The lanes whose box the ray enters within its interval, as bits.
    #[inline(always)]
    pub fn enter(&self, ray: &Ray) -> u32 {
        let mut near = [ray.tmin; LANES];
        let mut far = [ray.tmax; LANES];
        for axis in 0..3 {
            let (o, inv) = (ray.origin[axis], ray.inv_dir[axis]);
            let (n, f) = (&self.bounds[ray.near_row[axis]], &self.bounds[ray.far_row[axis]]);
            for k in 0..LANES {
                near[k] = max(near[k], (n[k] - o) * inv);
                far[k] = min(far[k], (f[k] - o) * inv);
            }
        }
        let mut mask = 0;
        for k in 0..LANES {
            mask |= u32::from(near[k] <= far[k] * FAR_SLACK) << k;
        }
        mask
    }

    /// [`Self::enter`] with every box grown by `pad` on each side: for a ray carried into another
    /// space, whose rounding there could otherwise pass a box by a hair.
    #[inline(always)]
    pub fn enter_grown(&self, ray: &Ray, pad: f32) -> u32 {
        let mut near = [ray.tmin; LANES];
        let mut far = [ray.tmax; LANES];
        for axis in 0..3 {
            let (o, inv) = (ray.origin[axis], ray.inv_dir[axis]);
            let (n, f) = (&self.bounds[ray.near_row[axis]], &self.bounds[ray.far_row[axis]]);
            // The side the ray enters through moves back towards its start, the other away from it.
            let back = if ray.near_row[axis] == axis { -pad } else { pad };
            for k in 0..LANES {
                near[k] = max(near[k], (n[k] + back - o) * inv);
                far[k] = min(far[k], (f[k] - back - o) * inv);
            }
        }
        let mut mask = 0;
        for k in 0..LANES {
            mask |= u32::from(near[k] <= far[k] * FAR_SLACK) << k;
        }
        mask
    }
}

/// Up to eight triangles, lane by lane: the first vertex, the edges `e1 = v0 - v1` and `e2 = v2 - v0`,
/// and the normal `e1 x e2`, each as x, y, z rows. A leaf with fewer triangles repeats its last one.
#[derive(Clone, Copy, Debug)]
#[cfg_attr(test, derive(PartialEq))]
#[repr(C, align(64))]
pub struct Tri8 {
    v0: [[f32; LANES]; 3],
    e1: [[f32; LANES]; 3],
    e2: [[f32; LANES]; 3],
    n: [[f32; LANES]; 3],
}

impl Tri8 {
    /// A block to be written over.
    pub const EMPTY: Self =
        Self { v0: [[0.0; LANES]; 3], e1: [[0.0; LANES]; 3], e2: [[0.0; LANES]; 3], n: [[0.0; LANES]; 3] };

    /// The block of the `count` triangles (one to eight) `corners` gives.
    pub fn new(count: usize, corners: impl Fn(usize) -> [Vec3A; 3]) -> Self {
        let mut block = Self::EMPTY;
        for k in 0..LANES {
            let [v0, v1, v2] = corners(k.min(count - 1));
            let (e1, e2) = (v0 - v1, v2 - v0);
            let n = e1.cross(e2);
            for axis in 0..3 {
                block.v0[axis][k] = v0[axis];
                block.e1[axis][k] = e1[axis];
                block.e2[axis][k] = e2[axis];
                block.n[axis][k] = n[axis];
            }
        }
        block
    }

    /// True when the ray meets one of the triangles at a distance in `tmin..tmax` (a blocker exactly at
    /// the light does not shadow it).
    ///
    /// Each lane is Möller and Trumbore's test ("Fast, Minimum Storage Ray/Triangle Intersection", 1997)
    /// in the same operations, in the same order, as `obvhs`' scalar `Triangle::intersect`, so each
    /// answer is that test's to the bit (the tests hold it to that): a point on an edge, where `u`, `v`
    /// or `w` is a signed zero, counts as inside only for `+0.0`, and a ray in the triangle's plane
    /// (zero determinant) never hits.
    #[inline(always)]
    pub fn hit(&self, ray: &Ray) -> bool {
        let mut any = false;
        for k in 0..LANES {
            any |= self.lane(ray, k).0;
        }
        any
    }

    /// The lanes [`Self::hit`] finds the ray meets, as bits, and where on each: its barycentric
    /// coordinates `u` and `v`, the point being `(1 - u - v) v0 + u v1 + v v2` of the corners the block
    /// was made from.
    #[inline(always)]
    pub fn hits(&self, ray: &Ray) -> Hits {
        let mut hits = Hits { lanes: 0, u: [0.0; LANES], v: [0.0; LANES] };
        for k in 0..LANES {
            let (hit, u, v) = self.lane(ray, k);
            hits.lanes |= u32::from(hit) << k;
            (hits.u[k], hits.v[k]) = (u, v);
        }
        hits
    }

    /// Lane `k`'s test: whether the ray meets its triangle, and where (see [`Self::hits`]).
    #[inline(always)]
    fn lane(&self, ray: &Ray, k: usize) -> (bool, f32, f32) {
        let d = ray.dir;
        let c = [self.v0[0][k] - ray.origin[0], self.v0[1][k] - ray.origin[1], self.v0[2][k] - ray.origin[2]];
        let r = [d[1] * c[2] - c[1] * d[2], d[2] * c[0] - c[2] * d[0], d[0] * c[1] - c[0] * d[1]];
        let n = [self.n[0][k], self.n[1][k], self.n[2][k]];
        let inv_det = 1.0 / dot(n, d);
        let u = dot(r, [self.e2[0][k], self.e2[1][k], self.e2[2][k]]) * inv_det;
        let v = dot(r, [self.e1[0][k], self.e1[1][k], self.e1[2][k]]) * inv_det;
        let w = 1.0 - u - v;
        let inside = (u.to_bits() | v.to_bits() | w.to_bits()) & 0x8000_0000 == 0;
        let t = dot(n, c) * inv_det;
        (inv_det != 0.0 && inside && t >= ray.tmin && t < ray.tmax, u, v)
    }
}

/// Up to eight triangles' corners, lane by lane (corner, then axis, then lane), in a space other than
/// the one they are tested in: [`Corners8::placed`] carries them there as a [`Tri8`].
#[derive(Clone, Copy, Debug)]
#[repr(C, align(64))]
pub struct Corners8 {
    corners: [[[f32; LANES]; 3]; 3],
}

impl Corners8 {
    /// The corners of the triangles `corners` gives for each lane (a leaf of fewer than eight repeats
    /// one).
    pub fn new(corners: impl Fn(usize) -> [Vec3A; 3]) -> Self {
        let mut block = Self { corners: [[[0.0; LANES]; 3]; 3] };
        for k in 0..LANES {
            for (c, corner) in corners(k).iter().enumerate() {
                for axis in 0..3 {
                    block.corners[c][axis][k] = corner[axis];
                }
            }
        }
        block
    }

    /// The block [`Tri8::new`] makes of these triangles with each corner carried by
    /// `m.transform_point3`, to the bit: the same products and sums in the same order (glam's
    /// `x p.x + y p.y + z p.z + w`, its cross product's `a.y b.z - a.z b.y`), lane by lane, so
    /// they run as eight-wide arithmetic.
    #[inline(always)]
    pub fn placed(&self, m: &Mat4) -> Tri8 {
        let cols = m.to_cols_array_2d();
        let mut v = [[[0.0; LANES]; 3]; 3];
        for (out, p) in v.iter_mut().zip(&self.corners) {
            for axis in 0..3 {
                let [x, y, z, w] = [cols[0][axis], cols[1][axis], cols[2][axis], cols[3][axis]];
                for k in 0..LANES {
                    out[axis][k] = x * p[0][k] + y * p[1][k] + z * p[2][k] + w;
                }
            }
        }
        let [v0, v1, v2] = v;
        let mut block = Tri8 { v0, ..Tri8::EMPTY };
        for axis in 0..3 {
            for k in 0..LANES {
                block.e1[axis][k] = v0[axis][k] - v1[axis][k];
                block.e2[axis][k] = v2[axis][k] - v0[axis][k];
            }
        }
        for k in 0..LANES {
            let (a, b) = ([0, 1, 2].map(|i| block.e1[i][k]), [0, 1, 2].map(|i| block.e2[i][k]));
            block.n[0][k] = a[1] * b[2] - a[2] * b[1];
            block.n[1][k] = a[2] * b[0] - a[0] * b[2];
            block.n[2][k] = a[0] * b[1] - a[1] * b[0];
        }
        block
    }
}

/// The lanes of a [`Tri8`] a ray meets (bit `k` for lane `k`), and each one's barycentric coordinates.
pub struct Hits {
    pub lanes: u32,
    pub u: [f32; LANES],
    pub v: [f32; LANES],
}

/// A shadow ray, set up for box tests: for each axis, the bounds rows its slab is entered and left
/// through (the lower corner's and the upper's when the ray runs up that axis).
pub struct Ray {
    pub origin: [f32; 3],
    pub dir: [f32; 3],
    pub inv_dir: [f32; 3],
    pub near_row: [usize; 3],
    pub far_row: [usize; 3],
    pub tmin: f32,
    pub tmax: f32,
}

impl Ray {
    /// The ray from `origin` along `dir`, over `tmin..=tmax`. A `-0.0` component of `dir` is taken as
    /// `+0.0`, so a ray's answer does not depend on the sign of a zero.
    pub fn new(origin: Vec3A, dir: Vec3A, tmin: f32, tmax: f32) -> Self {
        let dir = dir.to_array().map(|c| if c == 0.0 { 0.0 } else { c });
        // A component too small to invert finitely is taken as +-epsilon, so no slab distance is NaN
        // (0 * inf); such a ray's slab is then a little wider than exact, which only costs a box test.
        let inv_dir = dir.map(|c| if c.abs() <= f32::EPSILON { c.signum() / f32::EPSILON } else { 1.0 / c });
        let near_row: [usize; 3] = std::array::from_fn(|axis| if inv_dir[axis] >= 0.0 { axis } else { axis + 3 });
        let far_row = std::array::from_fn(|axis| if near_row[axis] == axis { axis + 3 } else { axis });
        Self { origin: origin.to_array(), dir, inv_dir, near_row, far_row, tmin, tmax }
    }
}

#[inline(always)]
fn dot(a: [f32; 3], b: [f32; 3]) -> f32 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}

/// The larger of two numbers, as one `maxps` lane (no NaN reaches it: see [`Ray::new`]).
#[inline(always)]
fn max(a: f32, b: f32) -> f32 {
    if a > b { a } else { b }
}

#[inline(always)]
fn min(a: f32, b: f32) -> f32 {
    if a < b { a } else { b }
}
