//! Alpha-tested casters for shadow rays: which triangles of the tree are cut out by their material, and
//! the test a ray's hit on one of them takes.
//!
//! A ray has no footprint, so a hit reads its texel as a point does ([`Footprint::POINT`]: level 0, the
//! sampler's magnification filter) through the material's own rule ([`Material::passes`]), which every
//! rasterized pass follows too. A hit on a clear texel does not block: the walk goes on past it, and
//! the ray is blocked only where some triangle is there.

use std::hash::{Hash, Hasher};
use std::sync::Arc;

use glam::Vec2;
use shadow_core::frame::Instance;
use shadow_core::material::{AlphaMode, Footprint, Material, Texture};

use super::wide::{Hits, LANES};

/// Feeds what decides an instance's coverage and its texel tests to `h`: the alpha mode and factor,
/// and for a masked material its texture (by address: a tree that tests texels holds the texture, so
/// no other one takes its place while the tree is cached) and how it is read.
pub fn hash_alpha_test(inst: &Instance, h: &mut impl Hasher) {
    let m = &inst.material;
    match m.alpha_mode {
        AlphaMode::Opaque | AlphaMode::Blend => 0u8.hash(h),
        AlphaMode::Mask { cutoff } => {
            1u8.hash(h);
            cutoff.to_bits().hash(h);
            m.alpha.to_bits().hash(h);
            if let Some(r) = &m.base_color_texture {
                inst.base_color_texture.as_ref().map(Arc::as_ptr).hash(h);
                r.sampler.hash(h);
                let t = r.transform;
                for x in [t.offset.x, t.offset.y, t.rotation, t.scale.x, t.scale.y] {
                    x.to_bits().hash(h);
                }
            }
        }
    }
}

/// The material and texture of one alpha-tested instance.
struct Surface {
    material: Arc<Material>,
    texture: Option<Arc<Texture>>,
}

/// An alpha-tested triangle: its corners' texture coordinates and its surface.
struct Triangle {
    uv: [Vec2; 3],
    surface: u32,
}

/// The alpha-tested triangles of a frame, as the tree gathers them.
#[derive(Default)]
pub struct Table {
    surfaces: Vec<Surface>,
    triangles: Vec<Triangle>,
}

impl Table {
    /// Adds the triangles of a [`shadow_core::frame::Coverage::Cutout`] instance; answers the index of its first one.
    ///
    /// # Panics
    /// Where the instance has no texture coordinates, which its coverage rules out.
    pub fn add(&mut self, inst: &Instance) -> u32 {
        let first = self.triangles.len() as u32;
        let surface = self.surfaces.len() as u32;
        self.surfaces.push(Surface { material: inst.material.clone(), texture: inst.base_color_texture.clone() });
        let uvs = inst.mesh.uvs().expect("a cutout instance has texture coordinates");
        self.triangles
            .extend(inst.mesh.triangles().iter().map(|t| Triangle { uv: t.map(|v| uvs[v as usize]), surface }));
        first
    }

    /// True when no triangle was added.
    pub fn is_empty(&self) -> bool {
        self.triangles.is_empty()
    }

    /// Whether triangle `id` is there at barycentric coordinates `u`, `v` (the point `(1 - u - v) p0
    /// + u p1 + v p2`).
    pub fn passes(&self, id: u32, u: f32, v: f32) -> bool {
        let t = &self.triangles[id as usize];
        let s = &self.surfaces[t.surface as usize];
        let uv = t.uv[0] * (1.0 - u - v) + t.uv[1] * u + t.uv[2] * v;
        s.material.passes(s.texture.as_deref(), Some(uv), Footprint::POINT)
    }
}

/// The alpha-tested lanes of a tree's leaves and their triangles.
pub struct Cutouts {
    /// Per leaf, bit `k` set when lane `k` holds an alpha-tested triangle.
    masked: Vec<u8>,
    /// Per leaf and lane, that triangle in `table` (where the lane's bit is set).
    ids: Vec<[u32; LANES]>,
    table: Table,
}

impl Cutouts {
    /// The cutouts of a tree whose leaves hold the triangles `members` (indices into the frame's
    /// casting triangles, lane by lane), `cutout` giving each casting triangle's index in `table`, or
    /// `u32::MAX` for a solid one.
    pub fn new(members: &[[u32; LANES]], cutout: &[u32], table: Table) -> Self {
        let ids: Vec<[u32; LANES]> = members.iter().map(|m| m.map(|t| cutout[t as usize])).collect();
        let masked = ids
            .iter()
            .map(|lanes| lanes.iter().enumerate().fold(0u8, |bits, (k, &id)| bits | u8::from(id != u32::MAX) << k))
            .collect();
        Self { masked, ids, table }
    }

    /// Whether leaf `leaf`'s triangles block a ray that `hits` says meets them: a solid one met, or an
    /// alpha-tested one met where its texel passes. `hits` is computed only for a leaf with
    /// alpha-tested lanes; `solid` answers for one without.
    #[inline(always)]
    pub fn blocks(&self, leaf: usize, solid: impl FnOnce() -> bool, hits: impl FnOnce() -> Hits) -> bool {
        let masked = u32::from(self.masked[leaf]);
        if masked == 0 {
            return solid();
        }
        let hits = hits();
        if hits.lanes & !masked != 0 {
            return true;
        }
        let mut tested = hits.lanes & masked;
        while tested != 0 {
            let k = tested.trailing_zeros() as usize;
            if self.table.passes(self.ids[leaf][k], hits.u[k], hits.v[k]) {
                return true;
            }
            tested &= tested - 1;
        }
        false
    }
}
