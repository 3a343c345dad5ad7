//! `pcss` on the CPU backend, through its public depth-map API; the reference of the lookup, which
//! query.wgsl mirrors.

use shadow_core::Image;
use shadow_core::glam::Vec2;
use shadow_core::lookup::{POISSON16, compare_bilinear, floor_vec2, hash_unit, on_map, pixel_hash};
use shadow_core::technique::{BuildReads, LightPass};
use shadow_core::technique::{DebugView, ShadowTechnique, TechniqueError};
use shadow_cpu::passes::maps::{map_position, render_depth_maps};
use shadow_cpu::passes::per_receiver;
use shadow_cpu::{CpuBackend, CpuContext, CpuError, GBuffer};

use super::{Pcss, PcssLens};

/// The depth map of the last build and its lens.
#[derive(Default)]
pub struct State {
    maps: Vec<Image<f32>>,
    lens: Option<PcssLens>,
}

/// The NDC depth of the texel holding `uv`, clamped to the map's edge.
fn texel_depth(map: &Image<f32>, uv: Vec2) -> f32 {
    let t = floor_vec2(uv * map.width() as f32);
    *map.get_clamped(t.x as i32, t.y as i32)
}

/// The Poisson disc turned by `pixel`'s hash.
fn turned_disc(pixel: (u32, u32)) -> [Vec2; 16] {
    let angle = hash_unit(pixel_hash(pixel.0, pixel.1)) * std::f32::consts::TAU;
    let (s, c) = angle.sin_cos();
    POISSON16.map(|p| Vec2::new(c * p.x - s * p.y, s * p.x + c * p.y))
}

/// The blocker search (step 1): the mean linear depth of the blockers of a receiver at map point `uv`,
/// NDC depth `depth`, whose plane's depth changes by `gradient` per unit of `uv`; `None` when there are
/// none. `pixel` turns the Poisson disc. Twin: `pcss_blockers` in search.wgsl.
#[must_use]
pub fn blocker_depth(
    map: &Image<f32>,
    lens: &PcssLens,
    uv: Vec2,
    depth: f32,
    gradient: Vec2,
    pixel: (u32, u32),
) -> Option<f32> {
    let search = lens.search_radius(lens.proj.linear_depth(depth));
    let (mut sum, mut blockers) = (0.0, 0u32);
    for p in turned_disc(pixel) {
        let o = p * search;
        let d = texel_depth(map, uv + o);
        if d < depth + gradient.dot(o) {
            sum += lens.proj.linear_depth(d);
            blockers += 1;
        }
    }
    (blockers > 0).then(|| sum / blockers as f32)
}

/// PCSS visibility of a receiver at map point `uv`, NDC depth `depth`, whose plane's depth changes by
/// `gradient` per unit of `uv`; `pixel` turns the Poisson disc. 1 outside the map.
#[must_use]
pub fn pcss_lookup(map: &Image<f32>, lens: &PcssLens, uv: Vec2, depth: f32, gradient: Vec2, pixel: (u32, u32)) -> f32 {
    if !on_map(uv) {
        return 1.0;
    }
    let Some(z_b) = blocker_depth(map, lens, uv, depth, gradient, pixel) else {
        return 1.0;
    };
    let radius = lens.filter_radius(lens.proj.linear_depth(depth), z_b);
    let disc = turned_disc(pixel);
    disc.iter().map(|&p| p * radius).map(|o| compare_bilinear(map, uv + o, depth + gradient.dot(o))).sum::<f32>() / 16.0
}

impl ShadowTechnique<CpuBackend> for Pcss {
    type State = State;

    fn name(&self) -> &'static str {
        Self::NAME
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
        state.lens = Some(Self::lens(light)?);
        render_depth_maps(frame, light, self.depth.resolution, self.depth.depth_bias(), &mut state.maps)
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
        let (Some(lens), Some(map)) = (&state.lens, state.maps.first()) else {
            return Err(TechniqueError::NotBuilt(Self::NAME.into()).into());
        };
        let offset = self.depth.receiver_offset();
        per_receiver(g, &reach, out, |x, y, i| {
            let m = map_position(light, g.position.data()[i], offset);
            let gradient = lens.proj.depth_gradient(m.world, g.geometric_normal.data()[i]);
            pcss_lookup(map, lens, m.uv, m.depth, gradient, (x, y))
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

    /// A spot light of radius 0.5 at height 10 looking straight down with a 90-degree cone (the map's
    /// P00 is 1, so k = 0.25), fitted to a box from the ground to height 8.
    fn lens() -> (PcssLens, Vec3) {
        let position = Vec3::new(0.0, 10.0, 0.0);
        let mut light = Light::spot(position, Vec3::ZERO, 90.0);
        light.radius = 0.5;
        let boxes = [Aabb { min: Vec3::new(-5.0, 0.0, -5.0), max: Vec3::new(5.0, 8.0, 5.0) }];
        let view = LightView::fit(&light, &boxes).expect("a light view");
        let lens = Pcss::lens(&view).expect("a spot light");
        assert!((lens.k - 0.25).abs() < 1e-5);
        (lens, position)
    }

    #[test]
    fn the_sizes_follow_similar_triangles() {
        let (l, light) = lens();
        // A receiver 4 below the light behind blockers 2 below it: the penumbra's half-width is
        // 0.5 (4 - 2) / 2 = 0.5 world units, which at distance 4 spans 0.5 / (2 * 4) of the map.
        assert!((l.filter_radius(4.0, 2.0) - 0.0625).abs() < 1e-6);
        assert_eq!(l.filter_radius(4.0, 4.0), 0.0);
        // The search reaches the map point of the nearest possible blocker: on the near plane, on the line
        // from the receiver to the light's rim.
        let receiver = light - Vec3::Y * 6.0;
        let rim = light + Vec3::X * 0.5;
        let near = receiver.lerp(rim, (6.0 - l.proj.near) / 6.0);
        let reach = (l.proj.uv_depth(near).0 - l.proj.uv_depth(receiver).0).length();
        assert!((l.search_radius(6.0) - reach).abs() < 1e-5, "{} vs {reach}", l.search_radius(6.0));
    }

    #[test]
    fn an_edge_gets_a_penumbra_as_wide_as_the_estimate() {
        let (l, _) = lens();
        // Blockers at linear depth 4 over the left half of a 256^2 map, the receiver plane at 6 behind.
        let (zb, zr) = (l.proj.ndc_depth(4.0), l.proj.ndc_depth(6.0));
        let map = Image::from_fn(256, 256, |x, _| if x < 128 { zb } else { zr });
        let at = |u: f32| pcss_lookup(&map, &l, Vec2::new(u, 0.5), zr, Vec2::ZERO, (7, 11));
        let half = l.filter_radius(6.0, 4.0);
        assert_eq!(at(0.2), 0.0, "deep in the umbra");
        assert_eq!(at(0.5 + l.search_radius(6.0) + 0.01), 1.0, "no blocker within the search");
        assert!((at(0.5) - 0.5).abs() < 0.15, "half lit on the hard edge: {}", at(0.5));
        assert!(at(0.5 - half * 0.6) < 0.25 && at(0.5 + half * 0.6) > 0.75);
        assert!(at(0.5 - half * 1.1) == 0.0 && at(0.5 + half * 1.1) == 1.0, "nothing beyond the penumbra");
    }

    #[test]
    fn other_lights_are_refused_by_name() {
        let light = Light::directional(Vec3::NEG_Y);
        let boxes = [Aabb { min: Vec3::splat(-1.0), max: Vec3::splat(1.0) }];
        let view = LightView::fit(&light, &boxes).expect("a light view");
        assert!(matches!(Pcss::lens(&view), Err(TechniqueError::UnsupportedLight { .. })));
    }
}
