//! `shadow-map` on the GPU (twin: [`super::cpu`]): the light pass of `passes::maps` renders depth with the
//! pipeline's depth bias into one layer per projection, or into the light's tiles of the frame's shadow
//! atlas; the query runs `shadow_lookup` of shadow_map.wgsl over the G-buffer, with the hardware
//! comparison sampler for bilinear taps.

use shadow_core::image::{Image, false_colour};
use shadow_core::technique::{BuildReads, DebugView, LightPass};
use shadow_core::technique::{ShadowTechnique, TechniqueError};
use shadow_wgpu::passes::maps::{DepthMaps, LookupParams, MapQuery, QueryExtras};
use shadow_wgpu::{GpuGBuffer, GpuVisibility, WgpuBackend, WgpuContext, WgpuError, readback, shaders};

use super::ShadowMap;

/// The light pass with the maps of the last build, and the query pipeline.
pub struct State {
    maps: DepthMaps,
    query: MapQuery,
}

impl ShadowTechnique<WgpuBackend> for ShadowMap {
    type State = State;

    fn name(&self) -> &'static str {
        Self::NAME
    }

    /// Its build draws casters into the light's map and reads nothing else of the frame.
    fn build_reads(&self) -> BuildReads {
        BuildReads::LightViews
    }

    /// A map of its resolution, or the side the frame's atlas grants.
    fn atlas_side(&self) -> Option<u32> {
        Some(self.map().resolution)
    }

    fn create_state(&self, cx: &mut WgpuContext) -> Result<State, WgpuError> {
        cx.scoped("creating the shadow-map pipelines", |cx| {
            let module = cx.pipelines.module("shadow_map", shaders::shadow_map());
            State {
                maps: DepthMaps::with_module(cx, &module, &self.map()),
                query: MapQuery::new(cx, &module, self.filter)
                    .with_lookup(LookupParams {
                        radius: self.filter_radius,
                        receiver_offset: self.map().receiver_offset(),
                    })
                    .lent_to_hosts(),
            }
        })
    }

    fn build(&self, cx: &mut WgpuContext, state: &mut State, pass: LightPass<'_>) -> Result<(), WgpuError> {
        let LightPass { frame, light, tiles, .. } = pass;
        match tiles {
            Some(tiles) => state.maps.render_tiles(cx, frame, light, tiles),
            None => state.maps.render(cx, frame, light, self.map().resolution),
        }
    }

    fn query(
        &self,
        cx: &mut WgpuContext,
        state: &mut State,
        pass: LightPass<'_>,
        g: &GpuGBuffer,
        out: &mut GpuVisibility,
    ) -> Result<(), WgpuError> {
        let LightPass { light, .. } = pass;
        let maps = state.maps.source().ok_or_else(|| TechniqueError::NotBuilt(Self::NAME.into()))?;
        state.query.run(cx, maps, light, g, out, &QueryExtras::NONE)
    }

    /// Each projection's map (`depth0`, ...), cut from the atlas where the light had tiles, and then the
    /// whole atlas (`atlas`, every light's tiles), false-coloured from the nearest depth drawn to the far
    /// plane.
    fn debug_views(&self, cx: &mut WgpuContext, state: &State) -> Result<Vec<DebugView>, WgpuError> {
        let Some(maps) = state.maps.source() else { return Ok(Vec::new()) };
        let layers = maps.texture.depth_or_array_layers();
        let mut depths = Vec::new();
        for k in 0..layers {
            depths.push(readback::read_f32(cx, maps.texture, k, wgpu::TextureAspect::DepthOnly)?);
        }
        // The nearest depth drawn: an atlas's texels no tile covers were never drawn, and hold 0.
        let picture = |depth: &Image<f32>| {
            let nearest = depth.data().iter().copied().filter(|&d| d > 0.0).fold(1.0f32, f32::min);
            false_colour(depth, nearest, 1.0)
        };
        let mut views = Vec::new();
        match maps.tiles {
            Some(tiles) => {
                let atlas = &depths[0];
                for (k, origin) in tiles.origins.iter().enumerate() {
                    let tile = Image::from_fn(tiles.side, tiles.side, |x, y| *atlas.get(origin.x + x, origin.y + y));
                    views.push(DebugView { name: format!("depth{k}"), image: picture(&tile) });
                }
                views.push(DebugView { name: "atlas".into(), image: picture(atlas) });
            }
            None => {
                for (k, depth) in depths.iter().enumerate() {
                    views.push(DebugView { name: format!("depth{k}"), image: picture(depth) });
                }
            }
        }
        Ok(views)
    }
}
