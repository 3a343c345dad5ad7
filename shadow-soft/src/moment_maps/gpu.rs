//! The moment maps on the wgpu backend, through its public API: `shadow-map`'s light pass for the depth,
//! three full-screen passes per build (moments blurred along x, then y, then each mip level from the one
//! above; build.wgsl), copied into one texture side by side, and a query over the G-buffer with
//! `shadow-map`'s bindings, the geometric normals for `pcss`'s blocker search, and that texture
//! (query.wgsl). The kind is a pipeline constant, so each map compiles only
//! its own maths.

use bytemuck::{Pod, Zeroable};
use shadow_core::technique::{BuildReads, DebugView, LightPass, ShadowTechnique, TechniqueError};
use shadow_wgpu::passes::full_screen;
use shadow_wgpu::passes::maps::{DepthMaps, LookupParams, MapQuery, QueryExtras};
use shadow_wgpu::pipelines::{
    ATTRIBUTE, FragmentEntry, attribute_entry, buffer_entry, depth_array_entry, full_screen_pipeline,
};
use shadow_wgpu::{GpuGBuffer, GpuVisibility, WgpuBackend, WgpuContext, WgpuError, shaders};

use super::MomentMap;
use crate::pcss::PcssLens;

/// GPU twin of `BuildParams` in build.wgsl.
#[repr(C)]
#[derive(Clone, Copy, Pod, Zeroable)]
struct BuildParams {
    depth: [f32; 4],
}

/// The build's pipelines and the layouts of their two kinds of input.
struct BuildPasses {
    from_depth: wgpu::BindGroupLayout,
    from_moments: wgpu::BindGroupLayout,
    moments_x: wgpu::RenderPipeline,
    blur_y: wgpu::RenderPipeline,
    downsample: wgpu::RenderPipeline,
}

/// Pipelines, the depth map, the moments (with their mip chain) and the lens of the last build.
pub struct State {
    map: DepthMaps,
    build: BuildPasses,
    query: MapQuery,
    /// The x pass's output, the moments' mip chain, and the chain laid out in one level (query.wgsl).
    targets: Option<Targets>,
    lens: Option<PcssLens>,
}

/// The build's textures.
#[derive(Clone)]
struct Targets {
    scratch: wgpu::Texture,
    mips: wgpu::Texture,
    atlas: wgpu::Texture,
}

impl Targets {
    fn new(cx: &WgpuContext, res: u32) -> Self {
        let levels = res.ilog2() + 1;
        let usage = wgpu::TextureUsages::RENDER_ATTACHMENT | wgpu::TextureUsages::TEXTURE_BINDING;
        Self {
            scratch: moments_texture(cx, "moments along x", (res, res), 1, usage),
            mips: moments_texture(cx, "moments", (res, res), levels, usage | wgpu::TextureUsages::COPY_SRC),
            atlas: moments_texture(
                cx,
                "moment atlas",
                (res + res / 2, res),
                1,
                wgpu::TextureUsages::TEXTURE_BINDING | wgpu::TextureUsages::COPY_DST,
            ),
        }
    }

    /// Copies every mip level to its place in the atlas: level 0 at the origin, the others in a column
    /// to its right, top down (twin: `level_origin` in query.wgsl).
    fn lay_out(&self, cx: &WgpuContext) {
        let mut enc = cx.encoder("moment atlas");
        let res = self.mips.width();
        let mut y = 0;
        for level in 0..self.mips.mip_level_count() {
            let size = (res >> level).max(1);
            let origin = if level == 0 { wgpu::Origin3d::ZERO } else { wgpu::Origin3d { x: res, y, z: 0 } };
            enc.copy_texture_to_texture(
                wgpu::TexelCopyTextureInfo {
                    texture: &self.mips,
                    mip_level: level,
                    origin: wgpu::Origin3d::ZERO,
                    aspect: wgpu::TextureAspect::All,
                },
                wgpu::TexelCopyTextureInfo {
                    texture: &self.atlas,
                    mip_level: 0,
                    origin,
                    aspect: wgpu::TextureAspect::All,
                },
                wgpu::Extent3d { width: size, height: size, depth_or_array_layers: 1 },
            );
            if level > 0 {
                y += size;
            }
        }
        cx.submit(enc);
    }
}

/// A view of one mip level.
fn level_view(texture: &wgpu::Texture, level: u32) -> wgpu::TextureView {
    texture.create_view(&wgpu::TextureViewDescriptor {
        base_mip_level: level,
        mip_level_count: Some(1),
        ..Default::default()
    })
}

/// A moments texture `(width, height)` with `levels` mip levels.
fn moments_texture(
    cx: &WgpuContext,
    label: &str,
    (width, height): (u32, u32),
    levels: u32,
    usage: wgpu::TextureUsages,
) -> wgpu::Texture {
    cx.create_texture(&wgpu::TextureDescriptor {
        label: Some(label),
        size: wgpu::Extent3d { width, height, depth_or_array_layers: 1 },
        mip_level_count: levels,
        sample_count: 1,
        dimension: wgpu::TextureDimension::D2,
        format: ATTRIBUTE,
        usage,
        view_formats: &[],
    })
}

/// The pipeline constants of `map`'s kind (moments.wgsl).
fn constants(map: &MomentMap) -> [(&'static str, f64); 3] {
    let (code, a, b) = map.kind.code();
    [("KIND", f64::from(code)), ("PARAM_A", f64::from(a)), ("PARAM_B", f64::from(b))]
}

impl BuildPasses {
    fn new(cx: &WgpuContext, map: &MomentMap) -> Self {
        let module = cx.pipelines.module("moment map build", build_shader());
        let uniform = buffer_entry(0, wgpu::BufferBindingType::Uniform, wgpu::ShaderStages::FRAGMENT);
        let from_depth = cx.pipelines.group_layout("moments from depth", &[uniform, depth_array_entry(1)]);
        let from_moments = cx.pipelines.group_layout("moments from moments", &[uniform, attribute_entry(2)]);
        let constants = constants(map);
        let pipeline = |name: &str, layout: &wgpu::BindGroupLayout| {
            let entry = FragmentEntry { name, constants: &constants };
            full_screen_pipeline(&cx.pipelines, name, &module, entry, &[layout], Some(ATTRIBUTE), None)
        };
        Self {
            moments_x: pipeline("fs_moments_x", &from_depth),
            blur_y: pipeline("fs_blur_y", &from_moments),
            downsample: pipeline("fs_downsample", &from_moments),
            from_depth,
            from_moments,
        }
    }

    /// A group of `layout`: the build's uniform and `view` at `binding`.
    fn group(
        cx: &WgpuContext,
        layout: &wgpu::BindGroupLayout,
        params: &BuildParams,
        binding: u32,
        view: &wgpu::TextureView,
    ) -> wgpu::BindGroup {
        let uniform = cx.transient(bytemuck::bytes_of(params));
        cx.device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("moment map build"),
            layout,
            entries: &[
                wgpu::BindGroupEntry { binding: 0, resource: uniform.binding() },
                wgpu::BindGroupEntry { binding, resource: wgpu::BindingResource::TextureView(view) },
            ],
        })
    }

    /// The moments of `depth` into level 0 of `moments` through `scratch`, then every level below.
    fn run(
        &self,
        cx: &WgpuContext,
        params: &BuildParams,
        depth: &wgpu::Texture,
        (scratch, moments): (&wgpu::Texture, &wgpu::Texture),
    ) {
        let depth_view = depth.create_view(&wgpu::TextureViewDescriptor {
            dimension: Some(wgpu::TextureViewDimension::D2Array),
            ..Default::default()
        });
        let group = Self::group(cx, &self.from_depth, params, 1, &depth_view);
        full_screen(cx, "moments along x", &level_view(scratch, 0), &self.moments_x, &[&group], None);
        let group = Self::group(cx, &self.from_moments, params, 2, &level_view(scratch, 0));
        full_screen(cx, "moments along y", &level_view(moments, 0), &self.blur_y, &[&group], None);
        for level in 1..moments.mip_level_count() {
            let group = Self::group(cx, &self.from_moments, params, 2, &level_view(moments, level - 1));
            full_screen(cx, "moment mip level", &level_view(moments, level), &self.downsample, &[&group], None);
        }
    }
}

impl ShadowTechnique<WgpuBackend> for MomentMap {
    type State = State;

    fn name(&self) -> &'static str {
        MomentMap::name(self)
    }

    /// Its build draws casters into the light's map and reads nothing else of the frame.
    fn build_reads(&self) -> BuildReads {
        BuildReads::LightViews
    }

    fn create_state(&self, cx: &mut WgpuContext) -> Result<State, WgpuError> {
        let map = DepthMaps::new(cx, &self.depth);
        cx.scoped("creating the moment-map pipelines", |cx| {
            let build = BuildPasses::new(cx, self);
            let module = cx.pipelines.module("moment map query", query_shader());
            let constants = constants(self);
            let entry = FragmentEntry { name: "fs_moment_query", constants: &constants };
            let lookup = LookupParams { radius: 0.0, receiver_offset: self.depth.receiver_offset() };
            let query =
                MapQuery::with_entry(cx, &module, entry, &[attribute_entry(4), attribute_entry(5)]).with_lookup(lookup);
            State { map, build, query, targets: None, lens: None }
        })
    }

    fn build(&self, cx: &mut WgpuContext, state: &mut State, pass: LightPass<'_>) -> Result<(), WgpuError> {
        let LightPass { frame, light, .. } = pass;
        let lens = self.lens(light)?;
        let res = self.depth.resolution;
        state.map.render(cx, frame, light, res)?;
        let depth = state.map.maps().ok_or_else(|| TechniqueError::NotBuilt(self.name().into()))?.clone();
        let targets = match &state.targets {
            Some(t) if t.mips.width() == res => t.clone(),
            _ => state.targets.insert(cx.scoped("allocating the moment maps", |cx| Targets::new(cx, res))?).clone(),
        };
        let params = BuildParams { depth: [lens.proj.near, lens.proj.far, self.blur as f32, 0.0] };
        cx.scoped("the moment maps", |cx| {
            state.build.run(cx, &params, &depth, (&targets.scratch, &targets.mips));
            targets.lay_out(cx);
        })?;
        state.lens = Some(lens);
        Ok(())
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
        let (Some(maps), Some(lens), Some(targets)) = (state.map.maps(), &state.lens, &state.targets) else {
            return Err(TechniqueError::NotBuilt(self.name().into()).into());
        };
        let moments_view = targets.atlas.create_view(&wgpu::TextureViewDescriptor::default());
        let entries = [
            wgpu::BindGroupEntry { binding: 4, resource: wgpu::BindingResource::TextureView(&g.geometric_normal) },
            wgpu::BindGroupEntry { binding: 5, resource: wgpu::BindingResource::TextureView(&moments_view) },
        ];
        let extras = QueryExtras { settings: self.uniform(lens), entries: &entries };
        state.query.run(cx, maps, light, g, out, &extras)
    }

    fn debug_views(&self, _: &mut WgpuContext, _: &State) -> Result<Vec<DebugView>, WgpuError> {
        Ok(Vec::new())
    }
}

/// The technique's shaders as compiled, by name (its registry entry's WGSL).
#[must_use]
pub fn shaders() -> Vec<(&'static str, String)> {
    vec![("moment map build", build_shader()), ("moment map query", query_shader())]
}

/// The WGSL of the build: the full-screen triangle, the moments' maths, then the passes.
#[must_use]
pub fn build_shader() -> String {
    shaders::with_full_screen(&format!("{}\n{}", include_str!("moments.wgsl"), include_str!("build.wgsl")))
}

/// The WGSL of the query: the shadow-map shader, pcss's blocker search, the moments' maths, then the
/// query.
#[must_use]
pub fn query_shader() -> String {
    crate::pcss::gpu::with_search(&format!("{}\n{}", include_str!("moments.wgsl"), include_str!("query.wgsl")))
}
