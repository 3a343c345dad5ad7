//! One frame on the GPU: the frame script of shadow-core ([`shadow_core::script`]) with the GPU's
//! instrumented steps. Each light's visibility is a layer of one array texture; shading reads them all.
//! Every phase ends with the queue drained, so its wall-clock time is the GPU's time for it, and the
//! results are read back into images.

use shadow_core::image::Rgb8;
use shadow_core::light::{LightView, Reach};
use shadow_core::script::{FrameRun, FrameSteps, LightTechniques, run_frame};
use shadow_core::stats::Phase;
use shadow_core::technique::FrameStats;
use shadow_core::{FrameInputs, Image};

use crate::clock::PhaseClock;
use crate::context::{WgpuBackend, WgpuContext, WgpuError};
use crate::gbuffer::{self, GpuGBuffer};
use crate::pipelines::{COLOR, LightRaw, VISIBILITY};
use crate::readback;

/// One light's visibility on the GPU: a render target layer (R32Float, 1 lit, 0 shadowed).
pub struct GpuVisibility {
    /// The layer to render into.
    pub view: wgpu::TextureView,
    /// Width.
    pub width: u32,
    /// Height.
    pub height: u32,
    /// The pixels its light may reach ([`shadow_core::light::Reach::rect`]): a query need answer only
    /// these ([`crate::passes::answer`]), the rest are 1.
    pub rect: shadow_core::light::PixelRect,
}

/// Everything a GPU frame produced, read back.
pub struct WgpuFrame {
    /// The fitted view of each light.
    pub light_views: Vec<LightView>,
    /// The shadow atlas: each light's tiles and their side.
    pub atlas: Option<shadow_core::light::AtlasPlan>,
    /// Visibility per light.
    pub visibility: Vec<Image<f32>>,
    /// The shaded image.
    pub color: Image<Rgb8>,
    /// Counters (summed over lights) and phase times.
    pub stats: FrameStats,
}

/// The most lights a frame may have on this backend (fewer where the device has fewer texture array
/// layers, one per light's visibility): the shading pass reads them from one uniform buffer.
pub const MAX_LIGHTS: usize = 256;

/// shade.wgsl's `Lights`: the count, then the lights. A uniform buffer rather than a storage one: lavapipe
/// (Mesa 22.3) loads from a storage buffer lane by lane, and the shading pass reads every light at every
/// pixel.
#[repr(C)]
#[derive(Clone, Copy, bytemuck::Pod, bytemuck::Zeroable)]
struct LightTable {
    count: [u32; 4],
    lights: [LightRaw; MAX_LIGHTS],
}

/// A 2D array texture to render into, sample and copy from.
#[must_use]
pub fn layered(
    cx: &WgpuContext,
    label: &str,
    w: u32,
    h: u32,
    layers: u32,
    format: wgpu::TextureFormat,
) -> wgpu::Texture {
    cx.create_texture(&wgpu::TextureDescriptor {
        label: Some(label),
        size: wgpu::Extent3d { width: w, height: h, depth_or_array_layers: layers },
        mip_level_count: 1,
        sample_count: 1,
        dimension: wgpu::TextureDimension::D2,
        format,
        usage: wgpu::TextureUsages::RENDER_ATTACHMENT
            | wgpu::TextureUsages::TEXTURE_BINDING
            | wgpu::TextureUsages::COPY_SRC,
        view_formats: &[],
    })
}

/// A view of one layer of a 2D array texture.
#[must_use]
pub fn layer_view(tex: &wgpu::Texture, layer: u32) -> wgpu::TextureView {
    tex.create_view(&wgpu::TextureViewDescriptor {
        dimension: Some(wgpu::TextureViewDimension::D2),
        base_array_layer: layer,
        array_layer_count: Some(1),
        ..Default::default()
    })
}

/// Renders a frame, each light shadowed by the frame's technique or its own (`techniques`; a single
/// technique converts into them), waiting after each phase and reading every target back.
///
/// # Errors
/// A bad view size, an unsupported light, or a GPU failure.
pub fn render_frame<'t, 'o: 't>(
    cx: &mut WgpuContext,
    frame: &FrameInputs,
    width: u32,
    height: u32,
    techniques: impl Into<LightTechniques<'t, 'o, WgpuBackend>>,
) -> Result<WgpuFrame, WgpuError> {
    check_lights(cx, frame)?;
    cx.clock = PhaseClock::new(cx);
    let steps = MeasuredSteps::new(cx, frame, width, height);
    let result = run_frame(cx, frame, steps, techniques);
    cx.clock = None;
    let FrameRun { output: (visibility, color), light_views, atlas, stats } = result?;
    Ok(WgpuFrame { light_views, atlas, visibility, color, stats })
}

/// The GPU's instrumented steps: each phase ends with the queue drained, so its wall-clock time is the
/// GPU's, and between timestamp markers where the adapter has them; the targets are read back at the end.
struct MeasuredSteps {
    width: u32,
    height: u32,
    lights: u32,
    /// One layer per light's visibility.
    visibility: wgpu::Texture,
    /// The marker that began the phase under way.
    start: Option<u32>,
    spans: Vec<Span>,
}

/// A phase's clock markers: its start, the end of the technique's own work (see
/// [`WgpuContext::end_of_work`]), its end, and the ends of its named steps.
struct Span {
    phase: Phase,
    start: Option<u32>,
    work_end: Option<u32>,
    end: Option<u32>,
    steps: Vec<(&'static str, u32)>,
}

impl MeasuredSteps {
    fn new(cx: &WgpuContext, frame: &FrameInputs, width: u32, height: u32) -> Self {
        let lights = frame.lights.len() as u32;
        let visibility = layered(cx, "visibility", width, height, lights.max(1), VISIBILITY);
        Self { width, height, lights, visibility, start: None, spans: Vec::new() }
    }
}

/// Submits a clock marker, where the frame has a clock.
fn mark(cx: &mut WgpuContext) -> Option<u32> {
    let mut clock = cx.clock.take()?;
    let index = clock.mark(cx);
    cx.clock = Some(clock);
    index
}

impl FrameSteps<WgpuBackend> for MeasuredSteps {
    /// The shaded texture and the receiver count's resolve buffer.
    type Shaded = (wgpu::Texture, wgpu::Buffer);
    /// Visibility per light and the shaded image, read back.
    type Output = (Vec<Image<f32>>, Image<Rgb8>);

    fn gbuffer(&mut self, cx: &mut WgpuContext, frame: &FrameInputs) -> Result<GpuGBuffer, WgpuError> {
        gbuffer::render(cx, frame, self.width, self.height)
    }

    fn visibility(&mut self, _cx: &mut WgpuContext, k: usize, reach: &Reach) -> Result<GpuVisibility, WgpuError> {
        let view = layer_view(&self.visibility, k as u32);
        Ok(GpuVisibility { view, width: self.width, height: self.height, rect: reach.rect })
    }

    fn keep(&mut self, _k: usize, _visibility: GpuVisibility) {}

    fn lit(&mut self, cx: &mut WgpuContext, visibility: &mut GpuVisibility) -> Result<(), WgpuError> {
        clear_lit(cx, visibility);
        Ok(())
    }

    fn shade(
        &mut self,
        cx: &mut WgpuContext,
        lights: (&FrameInputs, &[Reach]),
        g: &GpuGBuffer,
    ) -> Result<Self::Shaded, WgpuError> {
        shade(cx, lights, g, &self.visibility)
    }

    fn finish(
        self,
        cx: &mut WgpuContext,
        _gbuffer: GpuGBuffer,
        (color, covered): Self::Shaded,
        stats: &mut FrameStats,
    ) -> Result<Self::Output, WgpuError> {
        stats.counters.covered_pixels = Some(read_count(cx, &covered)?);
        if let Some(clock) = &cx.clock {
            add_gpu_times(&clock.read(cx)?, self.spans, stats);
        }
        let color = readback::read_rgb8(cx, &color)?;
        let visibility = (0..self.lights)
            .map(|k| readback::read_f32(cx, &self.visibility, k, wgpu::TextureAspect::All))
            .collect::<Result<_, _>>()?;
        Ok((visibility, color))
    }

    fn begin(&mut self, cx: &mut WgpuContext, _phase: Phase) {
        self.start = mark(cx);
    }

    fn end(&mut self, cx: &mut WgpuContext, phase: Phase) -> Result<(), WgpuError> {
        let work_end = cx.clock.as_mut().and_then(PhaseClock::take_work_end);
        let end = mark(cx);
        let steps = cx.clock.as_mut().map(PhaseClock::take_steps).unwrap_or_default();
        self.spans.push(Span { phase, start: self.start.take(), work_end, end, steps });
        cx.wait()
    }
}

/// Adds each span's GPU time from the clock's readings `at`: per phase `gpu_PHASE` (the technique's own
/// work, up to its end-of-work marker), its named steps `gpu_PHASE.STEP`, and `gpu_counters`, the rest of
/// a phase after its end of work (the counters' passes and read-backs).
fn add_gpu_times(at: &[f64], spans: Vec<Span>, stats: &mut FrameStats) {
    let mut add = |key: String, a: u32, b: u32| {
        *stats.timings.extra.entry(key).or_insert(0.0) += at[b as usize] - at[a as usize];
    };
    for span in spans {
        let (Some(a), Some(b)) = (span.start, span.end) else { continue };
        let key = format!("gpu_{}", span.phase.key());
        let mut from = a;
        for (name, end) in span.steps {
            add(format!("{key}.{name}"), from, end);
            from = end;
        }
        match span.work_end {
            Some(w) => {
                add(key, a, w);
                add("gpu_counters".into(), w, b);
            }
            None => add(key, a, b),
        }
    }
}

/// The receiver count of [`shade`]'s occlusion query.
fn read_count(cx: &WgpuContext, q: &wgpu::Buffer) -> Result<u64, WgpuError> {
    let staging = cx.create_buffer(&wgpu::BufferDescriptor {
        label: Some("receivers readback"),
        size: 8,
        usage: wgpu::BufferUsages::COPY_DST | wgpu::BufferUsages::MAP_READ,
        mapped_at_creation: false,
    });
    let mut enc = cx.encoder("readback");
    enc.copy_buffer_to_buffer(q, 0, &staging, 0, 8);
    cx.submit(enc);
    let d = readback::map_read(cx, &staging, "counting receivers")?;
    Ok(u64::from_le_bytes([d[0], d[1], d[2], d[3], d[4], d[5], d[6], d[7]]))
}

/// Refuses a frame of more lights than one frame can shade on `cx`'s device.
///
/// # Errors
/// [`WgpuError::TooManyLights`].
pub(crate) fn check_lights(cx: &WgpuContext, frame: &FrameInputs) -> Result<(), WgpuError> {
    let most = MAX_LIGHTS.min(cx.device.limits().max_texture_array_layers as usize);
    if frame.lights.len() > most {
        return Err(WgpuError::TooManyLights { lights: frame.lights.len(), most });
    }
    Ok(())
}

/// Clears a visibility target to 1: lit everywhere (a light that casts no shadow).
pub(crate) fn clear_lit(cx: &WgpuContext, visibility: &GpuVisibility) {
    let mut enc = cx.encoder("unshadowed light");
    enc.begin_render_pass(&wgpu::RenderPassDescriptor {
        label: Some("unshadowed light"),
        color_attachments: &[Some(wgpu::RenderPassColorAttachment {
            view: &visibility.view,
            depth_slice: None,
            resolve_target: None,
            ops: wgpu::Operations { load: wgpu::LoadOp::Clear(wgpu::Color::WHITE), store: wgpu::StoreOp::Store },
        })],
        depth_stencil_attachment: None,
        timestamp_writes: None,
        occlusion_query_set: None,
        multiview_mask: None,
    });
    cx.submit(enc);
}

/// The shading pass's inputs: the G-buffer's position, normal and albedo, every light's visibility (a
/// layer each of `vis`) and the frame's lights with their reaches' rectangles (in the frame's transient
/// buffer).
pub(crate) fn shade_group(
    cx: &WgpuContext,
    (frame, reaches): (&FrameInputs, &[Reach]),
    g: &GpuGBuffer,
    vis: &wgpu::Texture,
) -> wgpu::BindGroup {
    let mut table: LightTable = bytemuck::Zeroable::zeroed();
    table.count[0] = frame.lights.len() as u32;
    for ((slot, l), reach) in table.lights.iter_mut().zip(&frame.lights).zip(reaches) {
        *slot = LightRaw::from(l).within(reach.rect);
    }
    let lights = cx.transient(bytemuck::bytes_of(&table));
    let vis_view = vis.create_view(&wgpu::TextureViewDescriptor {
        dimension: Some(wgpu::TextureViewDimension::D2Array),
        ..Default::default()
    });
    cx.device.create_bind_group(&wgpu::BindGroupDescriptor {
        label: Some("shade"),
        layout: &cx.shared.shade_layout,
        entries: &[
            wgpu::BindGroupEntry { binding: 0, resource: wgpu::BindingResource::TextureView(&g.position) },
            wgpu::BindGroupEntry { binding: 1, resource: wgpu::BindingResource::TextureView(&g.normal) },
            wgpu::BindGroupEntry { binding: 2, resource: wgpu::BindingResource::TextureView(&g.albedo) },
            wgpu::BindGroupEntry { binding: 3, resource: wgpu::BindingResource::TextureView(&vis_view) },
            wgpu::BindGroupEntry { binding: 4, resource: lights.binding() },
        ],
    })
}

/// One full-screen pass of `pipeline` over the G-buffer into `view` (cleared to black first), with the
/// shading inputs `group`; with a `query`, counting the samples that pass in its one occlusion query.
pub(crate) fn full_screen_shade(
    enc: &mut wgpu::CommandEncoder,
    view: &wgpu::TextureView,
    pipeline: &wgpu::RenderPipeline,
    g: &GpuGBuffer,
    group: &wgpu::BindGroup,
    query: Option<&wgpu::QuerySet>,
) {
    let mut pass = enc.begin_render_pass(&wgpu::RenderPassDescriptor {
        label: Some(if query.is_some() { "count receivers" } else { "shade" }),
        color_attachments: &[Some(wgpu::RenderPassColorAttachment {
            view,
            depth_slice: None,
            resolve_target: None,
            ops: wgpu::Operations { load: wgpu::LoadOp::Clear(wgpu::Color::BLACK), store: wgpu::StoreOp::Store },
        })],
        depth_stencil_attachment: None,
        timestamp_writes: None,
        occlusion_query_set: query,
        multiview_mask: None,
    });
    pass.set_pipeline(pipeline);
    pass.set_bind_group(0, &g.frame_group, &[]);
    pass.set_bind_group(1, group, &[]);
    if query.is_some() {
        pass.begin_occlusion_query(0);
    }
    pass.draw(0..3, 0..1);
    if query.is_some() {
        pass.end_occlusion_query();
    }
}

/// Counts the receiver pixels (an occlusion query over a pass that discards everything else), then
/// shades. Returns the shaded texture and the query's resolve buffer.
fn shade(
    cx: &WgpuContext,
    lights: (&FrameInputs, &[Reach]),
    g: &GpuGBuffer,
    vis: &wgpu::Texture,
) -> Result<(wgpu::Texture, wgpu::Buffer), WgpuError> {
    cx.scoped("the shading pass", |cx| {
        let color = layered(cx, "color", g.width, g.height, 1, COLOR);
        let group = shade_group(cx, lights, g, vis);
        let view = color.create_view(&Default::default());
        let query = cx.device.create_query_set(&wgpu::QuerySetDescriptor {
            label: Some("receivers"),
            ty: wgpu::QueryType::Occlusion,
            count: 1,
        });
        let resolved = cx.create_buffer(&wgpu::BufferDescriptor {
            label: Some("receivers"),
            size: 8,
            usage: wgpu::BufferUsages::QUERY_RESOLVE | wgpu::BufferUsages::COPY_SRC,
            mapped_at_creation: false,
        });
        let mut enc = cx.encoder("shade");
        full_screen_shade(&mut enc, &view, &cx.shared.receivers, g, &group, Some(&query));
        full_screen_shade(&mut enc, &view, &cx.shared.shade, g, &group, None);
        enc.resolve_query_set(&query, 0..1, &resolved, 0);
        cx.submit(enc);
        (color, resolved)
    })
}
