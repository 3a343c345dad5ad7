//! Alpha-tested instances in the rasterized passes (the camera's G-buffer, the lights' maps): a fragment
//! of an instance whose texture cuts it out ([`Coverage::Cutout`]) is kept where its texel passes the
//! material's alpha test and discarded elsewhere, before it writes depth, so what lies behind a clear
//! texel shows through. The texel is read at the fragment's texture coordinates over the footprint of its
//! pixel (or map texel): how the coordinates change one pixel across and one down, which picks the mip
//! level ([`shadow_core::material::Sampler::sample`]).
//!
//! Solid instances keep the passes' own loops; only the cut-out ones take the per-fragment path, drawn
//! after them. Instances with nothing there ([`Coverage::Absent`]) are not drawn at all.

use rayon::prelude::*;
use shadow_core::frame::{Coverage, Instance};
use shadow_core::glam::Vec2;
use shadow_core::material::Footprint;
use shadow_core::{FrameInputs, Image};

use crate::raster::{Batch, DepthStencil, Fragment, RasterCounters, RasterState, draw};

/// A frame's instances for a rasterized pass, sorted by their coverage, each list in frame order.
#[derive(Default)]
pub struct Drawn<'a> {
    /// Drawn whole.
    pub solid: Vec<usize>,
    /// Drawn through the alpha test.
    pub cutout: Vec<usize>,
    /// The alpha test of each of `cutout`, in its order.
    pub tests: Vec<Cutout<'a>>,
}

impl<'a> Drawn<'a> {
    /// The instances of `frame` that `keep` takes (every one for the camera, the casters for a light),
    /// sorted.
    #[must_use]
    pub fn sort(frame: &'a FrameInputs, keep: impl Fn(&Instance) -> bool + Sync) -> Self {
        // Read side by side: a frame of many small meshes waits on memory for each instance.
        let coverage: Vec<Option<Coverage>> =
            frame.instances.par_iter().with_min_len(1024).map(|i| keep(i).then(|| i.coverage())).collect();
        let mut drawn = Self::default();
        for (k, (inst, coverage)) in frame.instances.iter().zip(coverage).enumerate() {
            let Some(coverage) = coverage else { continue };
            match coverage {
                Coverage::Solid => drawn.solid.push(k),
                Coverage::Cutout => {
                    if let Some(test) = Cutout::of(inst) {
                        drawn.cutout.push(k);
                        drawn.tests.push(test);
                    }
                }
                Coverage::Absent => {}
            }
        }
        drawn
    }
}

/// The alpha test of one cut-out instance's fragments.
pub struct Cutout<'a> {
    test: shadow_core::material::AlphaTest<'a>,
    uvs: &'a [Vec2],
    triangles: &'a [[u32; 3]],
}

impl<'a> Cutout<'a> {
    /// The test of a [`Coverage::Cutout`] instance; `None` for any other.
    #[must_use]
    pub fn of(inst: &'a Instance) -> Option<Self> {
        (inst.coverage() == Coverage::Cutout).then_some(())?;
        Some(Self {
            test: inst.material.alpha_test(inst.base_color_texture.as_deref())?,
            uvs: inst.mesh.uvs()?,
            triangles: inst.mesh.triangles(),
        })
    }

    /// Whether fragment `f` of the instance's triangle `triangle` is there: its texel, at the
    /// texture coordinates interpolated at the fragment over the footprint of its pixel, passes.
    #[must_use]
    #[inline]
    pub fn passes(&self, triangle: u32, f: &Fragment) -> bool {
        let corners = self.triangles[triangle as usize].map(|v| self.uvs[v as usize]);
        let uv = |b: [f32; 3]| corners[0] * b[0] + corners[1] * b[1] + corners[2] * b[2];
        let at = uv(f.bary());
        let [right, down] = f.bary_beside().map(uv);
        self.test.passes(Some(at), Footprint { dx: right - at, dy: down - at })
    }
}

/// Draws the cut-out instances of `batch` (its parts, in the order of `tests`) into `ds` and `color`
/// under `st`: a fragment that passes its instance's alpha test writes what `shade` gives it, and is
/// discarded before it writes anything where the test fails or `shade` answers `None`.
pub fn draw_alpha_tested<T, F>(
    ds: &mut DepthStencil,
    color: &mut Image<T>,
    (batch, tests): (&Batch<'_>, &[Cutout<'_>]),
    st: &RasterState,
    shade: F,
) -> RasterCounters
where
    T: Copy + Send,
    F: Fn(&Fragment) -> Option<T> + Sync,
{
    let shader = |f: &Fragment| {
        let (part, triangle) = batch.part_of(f.prim);
        if tests[part].passes(triangle, f) { shade(f) } else { None }
    };
    draw(ds, color, batch, st, shader, |stored, v| *stored = v)
}
