//! What a draw rasterizes: triangles by index, from indexed meshes ([`Indexed`], several as one
//! [`Batch`]) or given corner by corner ([`Soup`]).

use std::ops::Range;

use glam::Vec4;
use shadow_core::frame::{FrameError, Instance, MAX_FRAME_TRIANGLES};

/// One triangle as a draw sees it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SourceTriangle {
    /// Clip-space corners.
    pub v: [Vec4; 3],
    /// Primitive id handed to the fragment closure.
    pub prim: u32,
    /// Swap front and back for this triangle (a face drawn turned around).
    pub flip: bool,
    /// Not drawn where its back faces the view, whatever the draw's culling.
    pub cull_back: bool,
}

/// Anything that yields triangles by index.
pub trait TriangleSource: Sync {
    /// Number of triangles.
    fn len(&self) -> usize;
    /// Triangle `i`.
    fn get(&self, i: usize) -> SourceTriangle;
    /// Triangles `range` in order, each as [`Self::get`] gives it, to `f` (a source whose `get` searches
    /// walks instead).
    fn each(&self, range: Range<usize>, f: &mut dyn FnMut(SourceTriangle)) {
        for i in range {
            f(self.get(i));
        }
    }
    /// True when there are none.
    fn is_empty(&self) -> bool {
        self.len() == 0
    }
}

/// Indexed triangles over shared clip-space vertices.
pub struct Indexed<'a> {
    /// Clip-space vertices.
    pub positions: &'a [Vec4],
    /// Corner indices.
    pub triangles: &'a [[u32; 3]],
    /// Added to the triangle index to make the primitive id.
    pub prim_base: u32,
    /// Swap front and back for every triangle.
    pub flip: bool,
    /// Draw none of its back faces, whatever the draw's culling (a single-sided surface in the camera's
    /// view).
    pub cull_back: bool,
}

impl<'a> Indexed<'a> {
    /// An instance's triangles over its clip-space vertices `clip` (as [`crate::gbuffer::clip_vertices`]
    /// makes them), turned around where the instance is mirrored.
    #[must_use]
    pub fn instance(inst: &'a Instance, clip: &'a [Vec4]) -> Self {
        Self { positions: clip, triangles: inst.mesh.triangles(), prim_base: 0, flip: inst.mirrored, cull_back: false }
    }

    /// An instance's triangles as the camera sees them: [`Self::instance`], with its back faces left out
    /// where its material is single-sided ([`Instance::cull_back_faces`]).
    #[must_use]
    pub fn seen(inst: &'a Instance, clip: &'a [Vec4]) -> Self {
        Self { cull_back: inst.cull_back_faces, ..Self::instance(inst, clip) }
    }
}

impl TriangleSource for Indexed<'_> {
    fn len(&self) -> usize {
        self.triangles.len()
    }
    #[inline]
    fn get(&self, i: usize) -> SourceTriangle {
        let t = self.triangles[i];
        SourceTriangle {
            v: t.map(|k| self.positions[k as usize]),
            prim: self.prim_base + i as u32,
            flip: self.flip,
            cull_back: self.cull_back,
        }
    }
}

/// Several indexed meshes drawn as one source, in order, under one numbering: primitive ids run on from one
/// part to the next, so a visibility buffer of a whole frame ([`draw_flat`](super::draw_flat)) holds one
/// id per pixel, which [`Batch::part_of`] turns back into the mesh and its triangle. Each part keeps its
/// own `flip`; the fragments, and so the pictures, are those of the parts drawn in turn. (A draw's fixed
/// cost per mesh is not what it saves: on cubes' thousand boxes, one draw and a thousand took the same
/// time.)
pub struct Batch<'a> {
    parts: Vec<Indexed<'a>>,
    /// The id of each part's first triangle, and the total at the end.
    starts: Vec<u32>,
}

impl<'a> Batch<'a> {
    /// The parts, drawn in this order (their `prim_base` is not used).
    ///
    /// # Errors
    /// [`FrameError::TooManyTriangles`] past [`MAX_FRAME_TRIANGLES`] in all, more than a draw can number.
    pub fn new(parts: Vec<Indexed<'a>>) -> Result<Self, FrameError> {
        let mut starts = Vec::with_capacity(parts.len() + 1);
        let mut n = 0u64;
        starts.push(0);
        for p in &parts {
            n += p.triangles.len() as u64;
            match u32::try_from(n) {
                Ok(end) if n <= MAX_FRAME_TRIANGLES => starts.push(end),
                _ => {
                    let triangles = parts.iter().map(|p| p.triangles.len() as u64).sum();
                    return Err(FrameError::TooManyTriangles { triangles });
                }
            }
        }
        Ok(Self { parts, starts })
    }

    /// The primitive id of part `part`'s first triangle.
    #[must_use]
    pub fn start(&self, part: usize) -> u32 {
        self.starts[part]
    }

    /// The part a primitive id of this source is in, and its triangle there.
    #[must_use]
    pub fn part_of(&self, prim: u32) -> (usize, u32) {
        let part = self.starts.partition_point(|&s| s <= prim) - 1;
        (part, prim - self.starts[part])
    }
}

impl TriangleSource for Batch<'_> {
    fn len(&self) -> usize {
        self.starts.last().map_or(0, |&n| n as usize)
    }
    #[inline]
    fn get(&self, i: usize) -> SourceTriangle {
        let (part, local) = self.part_of(i as u32);
        SourceTriangle { prim: i as u32, ..self.parts[part].get(local as usize) }
    }
    /// Searches for the first triangle's part only: a frame of many small meshes would otherwise pay a
    /// search of its parts per triangle.
    fn each(&self, range: Range<usize>, f: &mut dyn FnMut(SourceTriangle)) {
        let Some(first) = range.clone().next() else { return };
        let (mut part, _) = self.part_of(first as u32);
        for i in range {
            while self.starts[part + 1] as usize <= i {
                part += 1;
            }
            let local = i - self.starts[part] as usize;
            f(SourceTriangle { prim: i as u32, ..self.parts[part].get(local) });
        }
    }
}

/// Triangles given corner by corner.
pub struct Soup<'a> {
    /// Clip-space corners.
    pub triangles: &'a [[Vec4; 3]],
    /// Added to the triangle index to make the primitive id.
    pub prim_base: u32,
    /// Swap front and back for every triangle.
    pub flip: bool,
}

impl TriangleSource for Soup<'_> {
    fn len(&self) -> usize {
        self.triangles.len()
    }
    #[inline]
    fn get(&self, i: usize) -> SourceTriangle {
        SourceTriangle { v: self.triangles[i], prim: self.prim_base + i as u32, flip: self.flip, cull_back: false }
    }
}
