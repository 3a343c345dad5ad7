//! `cascaded-shadow-map` on the GPU (twin: [`super::cpu`]): the shared light pass renders one layer per
//! cascade; the shared query picks each receiver's cascade and blends at the seams (shadow_map.wgsl's
//! `cascade_pick`).

use shadow_core::LightView;
use shadow_core::technique::maps::MapLayout;
use shadow_core::technique::{LightPass, ShadowTechnique, TechniqueError};
use shadow_wgpu::passes::maps::{DepthMaps, LookupParams, MapQuery, QueryExtras};
use shadow_wgpu::{GpuGBuffer, GpuVisibility, WgpuBackend, WgpuContext, WgpuError, shaders};

use super::CascadedShadowMap;

/// The light pass with the maps and cascades of the last build, and the query pipeline.
pub struct State {
    maps: DepthMaps,
    query: MapQuery,
    view: Option<LightView>,
}

impl ShadowTechnique<WgpuBackend> for CascadedShadowMap {
    type State = State;

    fn name(&self) -> &'static str {
        Self::NAME
    }

    fn create_state(&self, cx: &mut WgpuContext) -> Result<State, WgpuError> {
        cx.scoped("creating the cascaded-shadow-map pipelines", |cx| {
            let module = cx.pipelines.module("shadow_map", shaders::shadow_map());
            State {
                maps: DepthMaps::with_module(cx, &module, &self.map),
                query: MapQuery::new(cx, &module, self.filter).with_lookup(LookupParams {
                    radius: self.filter_radius,
                    receiver_offset: self.map.receiver_offset(),
                }),
                view: None,
            }
        })
    }

    fn build(&self, cx: &mut WgpuContext, state: &mut State, pass: LightPass<'_>) -> Result<(), WgpuError> {
        let sampling = self.sampling(pass.frame, pass.light, pass.aspect);
        state.view = None;
        state.maps.render(cx, pass.frame, &sampling.view, sampling.resolution)?;
        state.view = Some(sampling.view);
        Ok(())
    }

    fn query(
        &self,
        cx: &mut WgpuContext,
        state: &mut State,
        _: LightPass<'_>,
        g: &GpuGBuffer,
        out: &mut GpuVisibility,
    ) -> Result<(), WgpuError> {
        let not_built = || TechniqueError::NotBuilt(Self::NAME.into());
        let (maps, view) = state.maps.maps().zip(state.view.as_ref()).ok_or_else(not_built)?;
        state.query.run(cx, maps, view, g, out, &QueryExtras::NONE)
    }

    /// The cascades are fitted to the camera, which the build key does not hold.
    fn build_is_reusable(&self) -> bool {
        false
    }
}
