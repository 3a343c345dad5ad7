//! The depth maps of the casters their texture cuts out, alone, for the techniques built on silhouettes
//! (twin: shadow-cpu's `passes::maps::CutoutMaps`).

use shadow_core::FrameInputs;
use shadow_core::light::LightView;
use shadow_core::technique::maps::{Casters, CutoutMap};

use super::maps::{DepthMaps, LookupParams, MapQuery, QueryExtras};
use crate::context::{WgpuContext, WgpuError};
use crate::frame::GpuVisibility;
use crate::gbuffer::GpuGBuffer;
use crate::shaders;

/// The depth maps of the casters their texture cuts out, alone ([`Casters::CutOut`]), and their lookup
/// ([`CutoutMap`]): where the techniques built on silhouettes (which give such casters no volume or wedge)
/// take those casters' shadows from (twin: shadow-cpu's `passes::maps::CutoutMaps`). Its pipelines are
/// made by the first frame with such casters; a frame without them renders nothing.
#[derive(Default)]
pub struct CutoutMaps {
    passes: Option<CutoutPasses>,
    /// The view of the last render, when its frame had cut-out casters.
    rendered: Option<LightView>,
}

/// The light pass and the lookup of one [`CutoutMap`].
struct CutoutPasses {
    settings: CutoutMap,
    maps: DepthMaps,
    query: MapQuery,
}

impl CutoutMaps {
    /// Renders the maps of `frame`'s cut-out casters from every projection of `view` (the light's own, or
    /// its cascades over the camera's view) as `settings` asks; for a frame without such casters, nothing.
    ///
    /// # Errors
    /// As [`DepthMaps::render`].
    pub fn render(
        &mut self,
        cx: &mut WgpuContext,
        frame: &FrameInputs,
        view: &LightView,
        settings: &CutoutMap,
    ) -> Result<(), WgpuError> {
        self.rendered = None;
        if !frame.has_cutout_casters() {
            return Ok(());
        }
        let passes = match &mut self.passes {
            Some(p) if p.settings == *settings => p,
            _ => self.passes.insert(cx.scoped("creating the cut-out casters' map", |cx| {
                let module = cx.pipelines.module("shadow_map", shaders::shadow_map());
                let map = settings.map();
                let lookup = LookupParams { radius: settings.filter_radius(), receiver_offset: map.receiver_offset() };
                CutoutPasses {
                    settings: *settings,
                    maps: DepthMaps::with_module(cx, &module, &map).of(Casters::CutOut),
                    query: MapQuery::new(cx, &module, settings.filter).with_lookup(lookup),
                }
            })?),
        };
        passes.maps.render(cx, frame, view, settings.resolution)?;
        self.rendered = Some(view.clone());
        Ok(())
    }

    /// Whether the last render drew maps (its frame had cut-out casters).
    #[must_use]
    pub fn is_rendered(&self) -> bool {
        self.rendered.is_some()
    }

    /// Writes into `out` the share of the light the cut-out casters of the last render leave each receiver
    /// of `g`, and says so; says false and writes nothing when that frame had none.
    ///
    /// # Errors
    /// A GPU failure.
    pub fn query(&self, cx: &WgpuContext, g: &GpuGBuffer, out: &GpuVisibility) -> Result<bool, WgpuError> {
        let (Some(passes), Some(view)) = (&self.passes, &self.rendered) else { return Ok(false) };
        let Some(maps) = passes.maps.maps() else { return Ok(false) };
        passes.query.run(cx, maps, view, g, out, &QueryExtras::NONE)?;
        Ok(true)
    }
}
