//! `perspective-shadow-map` on the GPU (twin: [`super::cpu`]): the post-perspective map, rendered and looked
//! up through the shared map passes (the camera's and the light's projections in one matrix; the
//! clipper drops what lies behind either).

use shadow_core::technique::maps::MapLayout;
use shadow_core::technique::{LightPass, ShadowTechnique};
use shadow_wgpu::passes::maps::LookupParams;
use shadow_wgpu::{GpuGBuffer, GpuVisibility, WgpuBackend, WgpuContext, WgpuError};

use super::PerspectiveShadowMap;
use crate::view_maps::gpu::ViewMaps;

impl ShadowTechnique<WgpuBackend> for PerspectiveShadowMap {
    type State = ViewMaps;

    fn name(&self) -> &'static str {
        Self::NAME
    }

    fn create_state(&self, cx: &mut WgpuContext) -> Result<ViewMaps, WgpuError> {
        cx.scoped("creating the perspective-shadow-map pipelines", |cx| {
            let lookup = LookupParams { radius: self.filter_radius, receiver_offset: self.map.receiver_offset() };
            ViewMaps::new(cx, &self.map, self.filter, lookup)
        })
    }

    fn build(&self, cx: &mut WgpuContext, state: &mut ViewMaps, pass: LightPass<'_>) -> Result<(), WgpuError> {
        state.build(cx, pass.frame, self.sampling(pass.frame, pass.light, pass.aspect))
    }

    fn query(
        &self,
        cx: &mut WgpuContext,
        state: &mut ViewMaps,
        _: LightPass<'_>,
        g: &GpuGBuffer,
        out: &mut GpuVisibility,
    ) -> Result<(), WgpuError> {
        state.query(cx, Self::NAME, g, out)
    }

    /// The map is fitted to the camera, which the build key does not hold.
    fn build_is_reusable(&self) -> bool {
        false
    }
}
