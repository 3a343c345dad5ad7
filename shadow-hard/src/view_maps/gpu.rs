//! View-fitted maps on the GPU (twin: [`super::cpu`]).

use shadow_core::FrameInputs;
use shadow_core::LightView;
use shadow_core::technique::TechniqueError;
use shadow_core::technique::maps::{DepthMap, MapSampling};
use shadow_core::technique::settings::Filter;
use shadow_wgpu::passes::maps::{DepthMaps, LookupParams, MapQuery, QueryExtras};
use shadow_wgpu::{GpuGBuffer, GpuVisibility, WgpuContext, WgpuError, shaders};

/// The light pass, the query, and the projections of the last build with their maps.
pub struct ViewMaps {
    maps: DepthMaps,
    query: MapQuery,
    view: Option<LightView>,
}

impl ViewMaps {
    /// The pipelines for `map`'s bias and `filter` with `lookup`.
    #[must_use]
    pub fn new(cx: &WgpuContext, map: &DepthMap, filter: Filter, lookup: LookupParams) -> Self {
        let module = cx.pipelines.module("shadow_map", shaders::shadow_map());
        Self {
            maps: DepthMaps::with_module(cx, &module, map),
            query: MapQuery::new(cx, &module, filter).with_lookup(lookup).lent_to_hosts(),
            view: None,
        }
    }

    /// Renders the casters' depth from every projection of `sampling`, one layer each.
    ///
    /// # Errors
    /// Maps larger than the device allows, or a GPU failure.
    pub fn build(&mut self, cx: &mut WgpuContext, frame: &FrameInputs, sampling: MapSampling) -> Result<(), WgpuError> {
        self.view = None;
        self.maps.render(cx, frame, &sampling.view, sampling.resolution)?;
        self.view = Some(sampling.view);
        Ok(())
    }

    /// Looks every receiver up in the maps of the last build (`technique` names it for the error when
    /// there is none).
    ///
    /// # Errors
    /// [`TechniqueError::NotBuilt`] before a build, or a GPU failure.
    pub fn query(
        &self,
        cx: &WgpuContext,
        technique: &str,
        g: &GpuGBuffer,
        out: &GpuVisibility,
    ) -> Result<(), WgpuError> {
        let not_built = || TechniqueError::NotBuilt(technique.into());
        let (maps, view) = self.maps.maps().zip(self.view.as_ref()).ok_or_else(not_built)?;
        self.query.run(cx, maps, view, g, out, &QueryExtras::NONE)
    }
}

/// The GPU backend of a technique whose maps are [`ViewMaps`] (the settings type as for
/// `view_fitted_on_cpu`). Its build reads the camera, which the build key does not hold, so it is made
/// every frame.
macro_rules! view_fitted_on_gpu {
    ($technique:ty) => {
        impl shadow_core::technique::ShadowTechnique<shadow_wgpu::WgpuBackend> for $technique {
            type State = $crate::view_maps::gpu::ViewMaps;

            fn name(&self) -> &'static str {
                Self::NAME
            }

            fn create_state(&self, cx: &mut shadow_wgpu::WgpuContext) -> Result<Self::State, shadow_wgpu::WgpuError> {
                let what = format!("creating the {} pipelines", Self::NAME);
                cx.scoped(&what, |cx| {
                    let lookup = shadow_wgpu::passes::maps::LookupParams {
                        radius: self.filter_radius,
                        receiver_offset: self.map.receiver_offset(),
                    };
                    Self::State::new(cx, &self.map, self.filter, lookup)
                })
            }

            fn build(
                &self,
                cx: &mut shadow_wgpu::WgpuContext,
                state: &mut Self::State,
                pass: shadow_core::technique::LightPass<'_>,
            ) -> Result<(), shadow_wgpu::WgpuError> {
                use shadow_core::technique::maps::MapLayout;
                state.build(cx, pass.frame, self.sampling(pass.frame, pass.light, pass.aspect))
            }

            fn query(
                &self,
                cx: &mut shadow_wgpu::WgpuContext,
                state: &mut Self::State,
                _: shadow_core::technique::LightPass<'_>,
                g: &shadow_wgpu::GpuGBuffer,
                out: &mut shadow_wgpu::GpuVisibility,
            ) -> Result<(), shadow_wgpu::WgpuError> {
                state.query(cx, Self::NAME, g, out)
            }

            fn build_is_reusable(&self, _: &shadow_core::FrameInputs) -> bool {
                false
            }
        }
    };
}
pub(crate) use view_fitted_on_gpu;
