//! `pcss` on the wgpu backend, through its public API: `shadow-map`'s light pass, then a query over the
//! G-buffer with `shadow-map`'s bindings and the geometric normals (query.wgsl).

use shadow_core::technique::{BuildReads, LightPass};
use shadow_core::technique::{DebugView, ShadowTechnique, TechniqueError};
use shadow_wgpu::passes::maps::{DepthMaps, LookupParams, MapQuery, QueryExtras};
use shadow_wgpu::pipelines::{FragmentEntry, attribute_entry};
use shadow_wgpu::{GpuGBuffer, GpuVisibility, WgpuBackend, WgpuContext, WgpuError, shaders};

use super::{Pcss, PcssLens};

/// Pipelines, the blockers' map and the lens of the last build.
pub struct State {
    map: DepthMaps,
    query: MapQuery,
    lens: Option<PcssLens>,
}

impl ShadowTechnique<WgpuBackend> for Pcss {
    type State = State;

    fn name(&self) -> &'static str {
        Self::NAME
    }

    /// Its build draws casters into the light's map and reads nothing else of the frame.
    fn build_reads(&self) -> BuildReads {
        BuildReads::LightViews
    }

    fn create_state(&self, cx: &mut WgpuContext) -> Result<State, WgpuError> {
        let map = DepthMaps::new(cx, &self.depth);
        cx.scoped("creating the pcss pipelines", |cx| {
            let module = cx.pipelines.module("pcss query", query_shader());
            let lookup = LookupParams { radius: 0.0, receiver_offset: self.depth.receiver_offset() };
            let query = MapQuery::with_entry(cx, &module, FragmentEntry::from("fs_pcss_query"), &[attribute_entry(4)])
                .with_lookup(lookup);
            State { map, query, lens: None }
        })
    }

    fn build(&self, cx: &mut WgpuContext, state: &mut State, pass: LightPass<'_>) -> Result<(), WgpuError> {
        let LightPass { frame, light, .. } = pass;
        state.lens = Some(Self::lens(light)?);
        state.map.render(cx, frame, light, self.depth.resolution)
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
        let (Some(maps), Some(lens)) = (state.map.maps(), &state.lens) else {
            return Err(TechniqueError::NotBuilt(Self::NAME.into()).into());
        };
        let entries =
            [wgpu::BindGroupEntry { binding: 4, resource: wgpu::BindingResource::TextureView(&g.geometric_normal) }];
        let extras = QueryExtras { settings: lens.uniform(), entries: &entries };
        state.query.run(cx, maps, light, g, out, &extras)
    }

    fn debug_views(&self, _: &mut WgpuContext, _: &State) -> Result<Vec<DebugView>, WgpuError> {
        Ok(Vec::new())
    }
}

/// The technique's shaders as compiled, by name (its registry entry's WGSL).
#[must_use]
pub fn shaders() -> Vec<(&'static str, String)> {
    vec![("pcss query", query_shader())]
}

/// The WGSL of the pcss query: the shadow-map shader, the blocker search, then the query.
#[must_use]
pub fn query_shader() -> String {
    with_search(include_str!("query.wgsl"))
}

/// The shadow-map shader, the blocker search (search.wgsl: the geometric normals at binding 4 and
/// `pcss_blockers`), then `query`: for a query that sizes its kernel as pcss does.
#[must_use]
pub fn with_search(query: &str) -> String {
    shaders::with_shadow_map(&format!("{}\n{query}", include_str!("search.wgsl")))
}
