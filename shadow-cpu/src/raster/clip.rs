//! Homogeneous clipping (Sutherland-Hodgman in clip space).
//!
//! Near (z >= 0) always; far (z <= w) unless depth clamp; and a guard band |x|, |y| <= G w that keeps
//! screen coordinates inside the fixed-point range without changing which pixels are covered. The
//! intersection on an edge is always computed from its inside end towards its outside end, so two
//! triangles sharing an edge get bit-identical new vertices and stay watertight.

use glam::Vec4;

/// A clip-space vertex with its barycentric coordinates in the original triangle.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ClipVertex {
    /// Clip-space position.
    pub pos: Vec4,
    /// Weights of the original triangle's three corners.
    pub bary: [f32; 3],
}

/// A clipped polygon: at most 3 + 6 vertices.
pub type Polygon = arrayvec_lite::ArrayVec<ClipVertex, 9>;

/// A minimal fixed-capacity vector, enough for clipping without allocation.
pub mod arrayvec_lite {
    /// A vector of at most `N` copyable items on the stack.
    #[derive(Clone, Copy, Debug)]
    pub struct ArrayVec<T: Copy + Default, const N: usize> {
        items: [T; N],
        len: usize,
    }

    impl<T: Copy + Default, const N: usize> Default for ArrayVec<T, N> {
        fn default() -> Self {
            Self { items: [T::default(); N], len: 0 }
        }
    }

    impl<T: Copy + Default, const N: usize> ArrayVec<T, N> {
        /// Appends; items beyond capacity are dropped (clipping a triangle by six planes never needs
        /// more than nine vertices).
        pub fn push(&mut self, t: T) {
            if self.len < N {
                self.items[self.len] = t;
                self.len += 1;
            }
        }
        /// The items.
        pub fn as_slice(&self) -> &[T] {
            &self.items[..self.len]
        }
        /// Number of items.
        pub fn len(&self) -> usize {
            self.len
        }
        /// True when empty.
        pub fn is_empty(&self) -> bool {
            self.len == 0
        }
    }
}

impl Default for ClipVertex {
    fn default() -> Self {
        Self { pos: Vec4::ZERO, bary: [0.0; 3] }
    }
}

/// Signed distances to the clip planes; inside when >= 0.
#[inline(always)]
fn distances(p: Vec4, guard: f32, far: bool) -> [f32; 6] {
    [p.z, if far { p.w - p.z } else { 1.0 }, guard * p.w + p.x, guard * p.w - p.x, guard * p.w + p.y, guard * p.w - p.y]
}

/// True when the triangle needs no clipping at all (the common case).
#[inline]
pub fn inside_all(v: &[Vec4; 3], guard: f32, far: bool) -> bool {
    v.iter().all(|&p| distances(p, guard, far).iter().all(|&d| d >= 0.0))
}

/// True when all three vertices are outside one plane: nothing to draw.
#[inline]
pub fn trivially_out(v: &[Vec4; 3], guard: f32, far: bool) -> bool {
    let d = v.map(|p| distances(p, guard, far));
    (0..6).any(|k| d.iter().all(|d| d[k] < 0.0))
}

/// Clips a triangle against the planes; the result is a convex polygon (possibly empty).
pub fn clip_triangle(v: &[Vec4; 3], guard: f32, far: bool) -> Polygon {
    let mut poly = Polygon::default();
    let ident = [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]];
    for (p, b) in v.iter().zip(ident) {
        poly.push(ClipVertex { pos: *p, bary: b });
    }
    for plane in 0..6 {
        if !far && plane == 1 {
            continue;
        }
        let src = poly;
        let s = src.as_slice();
        if s.is_empty() {
            break;
        }
        let mut out = Polygon::default();
        for i in 0..s.len() {
            let (a, b) = (s[i], s[(i + 1) % s.len()]);
            let (da, db) = (distances(a.pos, guard, far)[plane], distances(b.pos, guard, far)[plane]);
            if da >= 0.0 {
                out.push(a);
            }
            if (da >= 0.0) != (db >= 0.0) {
                // From the inside end towards the outside end, whichever way the edge is walked.
                let (inn, outv, di, dout) = if da >= 0.0 { (a, b, da, db) } else { (b, a, db, da) };
                let t = di / (di - dout);
                let lerp = |x: f32, y: f32| x + t * (y - x);
                out.push(ClipVertex {
                    pos: inn.pos + t * (outv.pos - inn.pos),
                    bary: [
                        lerp(inn.bary[0], outv.bary[0]),
                        lerp(inn.bary[1], outv.bary[1]),
                        lerp(inn.bary[2], outv.bary[2]),
                    ],
                });
            }
        }
        poly = out;
    }
    poly
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn near_plane_cut_keeps_the_inside() {
        let v = [Vec4::new(0.0, 0.0, -1.0, 1.0), Vec4::new(0.5, 0.0, 0.5, 1.0), Vec4::new(0.0, 0.5, 0.5, 1.0)];
        let p = clip_triangle(&v, 4.0, true);
        assert_eq!(p.len(), 4);
        assert!(p.as_slice().iter().all(|c| c.pos.z >= 0.0));
        // Barycentrics still sum to one and reproduce the position.
        for c in p.as_slice() {
            assert!((c.bary.iter().sum::<f32>() - 1.0).abs() < 1e-6);
            let back = v[0] * c.bary[0] + v[1] * c.bary[1] + v[2] * c.bary[2];
            assert!((back - c.pos).length() < 1e-6);
        }
    }

    #[test]
    fn shared_edge_intersections_match() {
        let a = Vec4::new(0.0, 0.0, -1.0, 1.0);
        let b = Vec4::new(0.3, 0.1, 0.7, 1.0);
        let t1 = clip_triangle(&[a, b, Vec4::new(0.0, 0.5, 0.5, 1.0)], 4.0, true);
        let t2 = clip_triangle(&[b, a, Vec4::new(0.0, -0.5, 0.5, 1.0)], 4.0, true);
        let on_edge =
            |p: &Polygon| p.as_slice().iter().map(|c| c.pos).filter(|q| q.z == 0.0 && q.x != 0.0).collect::<Vec<_>>();
        let (e1, e2) = (on_edge(&t1), on_edge(&t2));
        assert!(e1.iter().any(|p| e2.contains(p)), "{e1:?} vs {e2:?}");
    }
}
