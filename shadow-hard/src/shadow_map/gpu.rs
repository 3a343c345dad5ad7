//! `shadow-map` on the GPU (twin: [`super::cpu`]): the light pass of `passes::maps` renders depth with the
//! pipeline's depth bias into one layer per projection; the query runs `shadow_lookup` of shadow_map.wgsl
//! over the G-buffer, with the hardware comparison sampler for bilinear taps.

use shadow_core::technique::{BuildReads, LightPass};
use shadow_core::technique::{ShadowTechnique, TechniqueError};
use shadow_wgpu::passes::maps::{DepthMaps, LookupParams, MapQuery, QueryExtras};
use shadow_wgpu::{GpuGBuffer, GpuVisibility, WgpuBackend, WgpuContext, WgpuError, shaders};

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
        state.maps.render(cx, frame, light, tiles.map_or(self.map().resolution, |t| t.side))
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
        let maps = state.maps.maps().ok_or_else(|| TechniqueError::NotBuilt(Self::NAME.into()))?;
        state.query.run(cx, maps, light, g, out, &QueryExtras::NONE)
    }
}
