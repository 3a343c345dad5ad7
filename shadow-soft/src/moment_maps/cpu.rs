//! The moment maps on the CPU backend, through its public depth-map API; the reference of the build and
//! the lookup, which build.wgsl and query.wgsl mirror. The blocker search is `pcss`'s.

use shadow_core::Image;
use shadow_core::glam::Vec2;
use shadow_core::light::LightProjection;
use shadow_core::lookup::on_map;
use shadow_core::technique::{BuildReads, DebugView, LightPass, ShadowTechnique, TechniqueError};
use shadow_cpu::passes::maps::{map_position, render_depth_maps};
use shadow_cpu::passes::per_receiver;
use shadow_cpu::{CpuBackend, CpuContext, CpuError, GBuffer};

use super::{MomentKind, MomentMap};
use crate::pcss::PcssLens;
use crate::pcss::cpu::blocker_depth;

/// Moments of each texel, a level of the mip chain.
pub type MomentImage = Image<[f32; 4]>;

/// The depth map, the mip chain of its moments and the lens of the last build.
#[derive(Default)]
pub struct State {
    depth: Vec<Image<f32>>,
    mips: Vec<MomentImage>,
    lens: Option<PcssLens>,
}

/// Normalized linear depth in [0, 1] of NDC depth `ndc` (twin: `normalized_depth` in build.wgsl).
#[must_use]
pub fn normalized_depth(proj: &LightProjection, ndc: f32) -> f32 {
    ((proj.linear_depth(ndc) - proj.near) / (proj.far - proj.near)).clamp(0.0, 1.0)
}

/// Adds `v` to `sum`, moment by moment.
fn accumulate(sum: &mut [f32; 4], v: &[f32; 4]) {
    for (s, v) in sum.iter_mut().zip(v) {
        *s += v;
    }
}

/// The mean of `2 radius + 1` texels of `src` along x (`horizontal`) or y, centred on each texel and
/// clamped to the edge (twin: `blur` in build.wgsl, summed in the same order).
fn box_blur(src: &MomentImage, radius: u32, horizontal: bool) -> MomentImage {
    let r = radius as i32;
    let scale = 1.0 / (2 * r + 1) as f32;
    Image::from_fn(src.width(), src.height(), |x, y| {
        let mut sum = [0.0f32; 4];
        for k in -r..=r {
            let (sx, sy) = if horizontal { (x as i32 + k, y as i32) } else { (x as i32, y as i32 + k) };
            accumulate(&mut sum, src.get_clamped(sx, sy));
        }
        sum.map(|s| s * scale)
    })
}

/// The next mip level: each texel the mean of the 2x2 it covers, the last row or column of an odd side
/// repeated (twin: `fs_downsample`).
fn downsample(src: &MomentImage) -> MomentImage {
    let (w, h) = ((src.width() / 2).max(1), (src.height() / 2).max(1));
    Image::from_fn(w, h, |x, y| {
        let (x0, y0) = (2 * x as i32, 2 * y as i32);
        let taps = [(x0, y0), (x0 + 1, y0), (x0, y0 + 1), (x0 + 1, y0 + 1)];
        let mut sum = [0.0f32; 4];
        for (tx, ty) in taps {
            accumulate(&mut sum, src.get_clamped(tx, ty));
        }
        sum.map(|s| s * 0.25)
    })
}

/// The mip chain of the moments of `depth` (NDC depths of projection `proj`), blurred by `blur` texels.
#[must_use]
pub fn moment_mips(depth: &Image<f32>, proj: &LightProjection, kind: MomentKind, blur: u32) -> Vec<MomentImage> {
    let moments = depth.map(|&d| kind.encode(normalized_depth(proj, d)));
    let mut level = if blur == 0 { moments } else { box_blur(&box_blur(&moments, blur, true), blur, false) };
    let mut mips = Vec::new();
    while level.width() > 1 || level.height() > 1 {
        let next = downsample(&level);
        mips.push(level);
        level = next;
    }
    mips.push(level);
    mips
}

/// Bilinear moments of `level` at `uv`, between texel centres, clamped to the edge (twin: `bilinear`).
fn bilinear(level: &MomentImage, uv: Vec2) -> [f32; 4] {
    let p = uv * Vec2::new(level.width() as f32, level.height() as f32) - 0.5;
    let i = p.floor();
    let f = p - i;
    let (x, y) = (i.x as i32, i.y as i32);
    let at = |dx, dy| *level.get_clamped(x + dx, y + dy);
    let (a, b, c, d) = (at(0, 0), at(1, 0), at(0, 1), at(1, 1));
    std::array::from_fn(|k| {
        let top = a[k] + f.x * (b[k] - a[k]);
        let bottom = c[k] + f.x * (d[k] - c[k]);
        top + f.y * (bottom - top)
    })
}

/// Taps per side of the grid [`average`] reads.
pub const GRID: usize = 4;

/// Trilinear moments at `uv` from the mip levels whose texels are nearest `footprint` (map coordinates).
fn trilinear(mips: &[MomentImage], uv: Vec2, footprint: f32) -> [f32; 4] {
    let top = (mips.len() - 1) as f32;
    let level = (footprint * mips[0].width() as f32).max(1.0).log2().min(top);
    let l0 = level.floor();
    let a = bilinear(&mips[l0 as usize], uv);
    if level == l0 {
        return a;
    }
    let b = bilinear(&mips[l0 as usize + 1], uv);
    let f = level - l0;
    std::array::from_fn(|k| a[k] + f * (b[k] - a[k]))
}

/// The moments averaged over a square of side `side` (map coordinates) around `uv`: a [`GRID`]^2 grid of
/// trilinear taps, each from the level whose texels are a grid cell wide. One tap of the level as wide
/// as the square would be a box snapped to that level's texel grid, up to twice as wide and off centre;
/// a grid of finer ones centres it, and keeps a straight edge's penumbra straight (twin: `moment_average`
/// in query.wgsl, summed in the same order).
#[must_use]
pub fn average(mips: &[MomentImage], uv: Vec2, side: f32) -> [f32; 4] {
    let cell = side / GRID as f32;
    let mut sum = [0.0f32; 4];
    for j in 0..GRID {
        for i in 0..GRID {
            let offset = Vec2::new(i as f32 + 0.5, j as f32 + 0.5) * cell - 0.5 * side;
            accumulate(&mut sum, &trilinear(mips, uv + offset, cell));
        }
    }
    sum.map(|s| s * (1.0 / (GRID * GRID) as f32))
}

impl ShadowTechnique<CpuBackend> for MomentMap {
    type State = State;

    fn name(&self) -> &'static str {
        MomentMap::name(self)
    }

    /// Its build draws casters into the light's map and reads nothing else of the frame.
    fn build_reads(&self) -> BuildReads {
        BuildReads::LightViews
    }

    fn create_state(&self, _: &mut CpuContext) -> Result<State, CpuError> {
        Ok(State::default())
    }

    fn build(&self, _: &mut CpuContext, state: &mut State, pass: LightPass<'_>) -> Result<(), CpuError> {
        let LightPass { frame, light, .. } = pass;
        let lens = self.lens(light)?;
        render_depth_maps(frame, light, self.depth.resolution, self.depth.depth_bias(), &mut state.depth)?;
        state.mips = moment_mips(&state.depth[0], &lens.proj, self.kind, self.blur);
        state.lens = Some(lens);
        Ok(())
    }

    fn query(
        &self,
        _: &mut CpuContext,
        state: &mut State,
        pass: LightPass<'_>,
        g: &GBuffer,
        out: &mut Image<f32>,
    ) -> Result<(), CpuError> {
        let LightPass { light, reach, .. } = pass;
        let (Some(lens), false) = (&state.lens, state.mips.is_empty()) else {
            return Err(TechniqueError::NotBuilt(self.name().into()).into());
        };
        let (proj, depth, offset) = (&lens.proj, &state.depth[0], self.depth.receiver_offset());
        per_receiver(g, &reach, out, |x, y, i| {
            let m = map_position(light, g.position.data()[i], offset);
            if !on_map(m.uv) {
                return 1.0;
            }
            let gradient = proj.depth_gradient(m.world, g.geometric_normal.data()[i]);
            let Some(z_b) = blocker_depth(depth, lens, m.uv, m.depth, gradient, (x, y)) else {
                return 1.0;
            };
            let t = normalized_depth(proj, m.depth);
            self.visibility(lens, t, proj.linear_depth(m.depth), z_b, |side| average(&state.mips, m.uv, side))
        });
        Ok(())
    }

    fn debug_views(&self, _: &mut CpuContext, _: &State) -> Result<Vec<DebugView>, CpuError> {
        Ok(Vec::new())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use shadow_core::bounds::Aabb;
    use shadow_core::glam::Vec3;
    use shadow_core::light::LightView;
    use shadow_core::scene::Light;

    /// A spot light's projection: NDC depth 0 at its near plane, 1 at its far plane.
    fn spot_projection() -> LightProjection {
        let light = Light::spot(Vec3::new(0.0, 10.0, 0.0), Vec3::ZERO, 90.0);
        let boxes = [Aabb { min: Vec3::new(-5.0, 0.0, -5.0), max: Vec3::new(5.0, 8.0, 5.0) }];
        LightView::fit(&light, &boxes).expect("a light view").projections[0]
    }

    #[test]
    fn the_mip_chain_keeps_the_mean_and_averages_squares() {
        let depth = Image::from_fn(8, 8, |x, _| if x < 4 { 0.0 } else { 1.0 });
        let proj = spot_projection();
        let mips = moment_mips(&depth, &proj, MomentKind::Variance, 0);
        assert_eq!(mips.iter().map(|m| m.width()).collect::<Vec<_>>(), [8, 4, 2, 1]);
        let top = mips[3].get(0, 0);
        assert!((top[0] - 0.5).abs() < 1e-6 && (top[1] - 0.5).abs() < 1e-6, "{top:?}");
        // Half the region at depth 0, half at 1: the mean 0.5, and Chebyshev's bound at 1 is 0.5.
        let m = average(&mips, Vec2::splat(0.5), 1.0);
        assert!((MomentKind::Variance.visibility(m, 1.0) - 0.5).abs() < 1e-4);
        // A blur keeps a constant map constant, edges included.
        let flat = moment_mips(&Image::new(5, 3, 0.25), &proj, MomentKind::Variance, 2);
        let d = normalized_depth(&proj, 0.25);
        assert!(flat[0].data().iter().all(|m| (m[0] - d).abs() < 1e-6));
    }
}
