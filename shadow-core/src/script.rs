//! The frame script (DESIGN 5), written once for every backend: the camera's G-buffer, then per light a
//! build and a query into that light's visibility, then shading. Each light is shadowed by the frame's
//! technique or by one of its own ([`LightTechniques`]); a light that casts no shadow is lit everywhere, and so
//! is one that reaches no pixel of the view ([`crate::light::Reach`]), which is neither built nor queried.
//!
//! A backend supplies the steps ([`FrameSteps`]) and [`run_frame`] puts them in order, times each phase
//! and gathers the lights' stats. How the steps run is theirs to decide: the instrumented frame of each
//! backend waits after every phase (so a phase's wall-clock time is the device's) and reads its targets
//! back; steps that only record work into a host's frame and never wait run under the same script.

use std::time::Instant;

use crate::frame::FrameInputs;
use crate::light::{AtlasPlan, LightView, Reach, TileRequest};
use crate::scene::LightKind;
use crate::stats::{Phase, ms};
use crate::technique::settings::TechniqueSpec;
use crate::technique::{Backend, DynShadowTechnique, FrameStats, LightPass, TechniqueError};

/// The counter of lights that reach no pixel of the view, which a frame neither builds nor queries.
pub const OUT_OF_VIEW: &str = "lights_out_of_view";

/// The steps of one frame on backend `B`, in the order [`run_frame`] calls them.
pub trait FrameSteps<B: Backend> {
    /// What shading leaves for [`FrameSteps::finish`] (the shaded image, or the target it was drawn into).
    type Shaded;
    /// What the frame leaves its caller (images read back, say).
    type Output;

    /// Renders the camera's G-buffer.
    ///
    /// # Errors
    /// Backend failures, or a view size the backend cannot render.
    fn gbuffer(&mut self, cx: &mut B::Context, frame: &FrameInputs) -> Result<B::GBuffer, B::Error>;

    /// The target light `k`'s visibility is queried into, over the pixels of its `reach`.
    ///
    /// # Errors
    /// Backend failures.
    fn visibility(&mut self, cx: &mut B::Context, k: usize, reach: &Reach) -> Result<B::Visibility, B::Error>;

    /// Takes light `k`'s visibility once its query is issued.
    fn keep(&mut self, k: usize, visibility: B::Visibility);

    /// Fills a visibility with 1 (lit everywhere), for a light that casts no shadow or reaches no pixel.
    ///
    /// # Errors
    /// Backend failures.
    fn lit(&mut self, cx: &mut B::Context, visibility: &mut B::Visibility) -> Result<(), B::Error>;

    /// Shades the G-buffer with every light's visibility: `lights` holds the frame and each light's reach
    /// in the view, in the frame's light order; a light adds nothing to a pixel outside its reach's
    /// rectangle.
    ///
    /// # Errors
    /// Backend failures.
    fn shade(
        &mut self,
        cx: &mut B::Context,
        lights: (&FrameInputs, &[Reach]),
        gbuffer: &B::GBuffer,
    ) -> Result<Self::Shaded, B::Error>;

    /// The frame's output, after the last phase; `stats` holds every phase's time, and counters the steps
    /// read (covered pixels, device times) are added to it here.
    ///
    /// # Errors
    /// Backend failures (a read-back).
    fn finish(
        self,
        cx: &mut B::Context,
        gbuffer: B::GBuffer,
        shaded: Self::Shaded,
        stats: &mut FrameStats,
    ) -> Result<Self::Output, B::Error>;

    /// Called before each phase's work (a device clock marks the phase's start here).
    fn begin(&mut self, _cx: &mut B::Context, _phase: Phase) {}

    /// Called once a phase's work is issued. Instrumented steps wait here for the device to finish it.
    ///
    /// # Errors
    /// A device failure while waiting.
    fn end(&mut self, _cx: &mut B::Context, _phase: Phase) -> Result<(), B::Error> {
        Ok(())
    }
}

/// What [`run_frame`] returns: the steps' output, the fitted view of each light, the shadow atlas, and
/// the stats.
pub struct FrameRun<O> {
    /// The steps' output.
    pub output: O,
    /// The fitted view of each light, in the frame's light order.
    pub light_views: Vec<LightView>,
    /// The frame's shadow atlas ([`crate::frame::Savings::atlas`]): each light's tiles and their side.
    pub atlas: Option<AtlasPlan>,
    /// Counters summed over the lights, and phase times.
    pub stats: FrameStats,
}

/// The techniques that shadow a frame's lights: the frame's own, and those lights name for themselves
/// ([`crate::LightShadow::technique`]), each made once for its spec by the caller (who has the registry).
pub struct LightTechniques<'a, 'o: 'a, B: Backend> {
    /// The frame's technique.
    pub frame: &'a mut (dyn DynShadowTechnique<B> + 'o),
    /// The techniques lights name, by their specs.
    pub named: &'a mut [(TechniqueSpec, Box<dyn DynShadowTechnique<B>>)],
}

impl<'a, 'o: 'a, B: Backend> From<&'a mut (dyn DynShadowTechnique<B> + 'o)> for LightTechniques<'a, 'o, B> {
    /// The frame's technique alone.
    fn from(frame: &'a mut (dyn DynShadowTechnique<B> + 'o)) -> Self {
        Self { frame, named: &mut [] }
    }
}

impl<'a, B: Backend, T: DynShadowTechnique<B> + 'a> From<&'a mut T> for LightTechniques<'a, 'a, B> {
    /// The frame's technique alone.
    fn from(frame: &'a mut T) -> Self {
        Self { frame, named: &mut [] }
    }
}

impl<B: Backend> LightTechniques<'_, '_, B> {
    /// The technique for a light that names `spec`, or the frame's.
    fn pick(&mut self, spec: Option<&TechniqueSpec>) -> Result<&mut dyn DynShadowTechnique<B>, TechniqueError> {
        let Some(spec) = spec else { return Ok(&mut *self.frame) };
        match self.named.iter_mut().find(|(s, _)| s == spec) {
            Some((_, t)) => Ok(t.as_mut()),
            None => Err(TechniqueError::Unprepared(spec.to_string())),
        }
    }
}

/// Runs one frame: `steps` supply the backend's passes and `techniques` shadow the lights.
///
/// # Errors
/// A light whose view cannot be fitted, a light its technique does not take, a light naming a technique
/// `techniques` lacks, or a failure of a step or of a technique.
pub fn run_frame<'t, 'o: 't, B: Backend, S: FrameSteps<B>>(
    cx: &mut B::Context,
    frame: &FrameInputs,
    mut steps: S,
    techniques: impl Into<LightTechniques<'t, 'o, B>>,
) -> Result<FrameRun<S::Output>, B::Error> {
    let mut techniques = techniques.into();
    let start = Instant::now();
    let mut stats = FrameStats::default();
    let mut phases = Phases { steps: &mut steps, stats: &mut stats };

    let gbuffer = phases.run(cx, Phase::GBuffer, |cx, steps| steps.gbuffer(cx, frame))?;
    let (width, height) = B::view_size(&gbuffer);
    let aspect = width as f32 / height.max(1) as f32;
    let reaches: Vec<Reach> = frame.lights.iter().map(|l| frame.reach(l, width, height)).collect();
    let atlas = match frame.savings.atlas {
        Some(side) => Some(plan_atlas(frame, &reaches, (side, width * height), &mut techniques)?),
        None => None,
    };
    let mut light_views = Vec::with_capacity(frame.lights.len());
    for (k, (light, &reach)) in frame.lights.iter().zip(&reaches).enumerate() {
        let view = frame.light_view(light)?;
        let shadow = frame.shadow(k);
        let tiles = atlas.as_ref().and_then(|a| a.lights[k].as_ref());
        let mut vis = phases.steps.visibility(cx, k, &reach)?;
        if reach.is_empty() {
            *phases.stats.counters.extra.entry(OUT_OF_VIEW.into()).or_insert(0.0) += 1.0;
        }
        if !shadow.casts || reach.is_empty() {
            if let Ok(technique) = techniques.pick(shadow.technique.as_ref()) {
                technique.release_tiles(k);
            }
            phases.steps.lit(cx, &mut vis)?;
            phases.steps.keep(k, vis);
            light_views.push(view);
            continue;
        }
        let technique = techniques.pick(shadow.technique.as_ref())?;
        let mut light_stats = FrameStats::default();
        let mut pass = LightPass {
            frame,
            light: &view,
            reach,
            tiles,
            update: shadow.update,
            slot: k,
            aspect,
            stats: &mut light_stats,
        };
        phases.run(cx, Phase::Build, |cx, _| technique.build(cx, pass.reborrow()))?;
        phases.run(cx, Phase::Query, |cx, _| technique.query(cx, pass, &gbuffer, &mut vis))?;
        phases.steps.keep(k, vis);
        phases.stats.add_light(light_stats);
        light_views.push(view);
    }
    let shaded = phases.run(cx, Phase::Shade, |cx, steps| steps.shade(cx, (frame, &reaches), &gbuffer))?;

    stats.timings.total = ms(start.elapsed());
    let output = steps.finish(cx, gbuffer, shaded, &mut stats)?;
    Ok(FrameRun { output, light_views, atlas, stats })
}

/// The frame's shadow atlas of `side` texels for a view of `pixels`: a tile for each face of each spot and point light with a
/// range that casts with a technique asking for one ([`crate::technique::ShadowTechnique::atlas_side`])
/// and reaches some of the view, sized by the share of the view its reach's rectangle covers, and keeping
/// the tiles its technique's last build lies in where it can ([`DynShadowTechnique::held_tiles`]). A light
/// without a range lights the whole scene: its maps stay its own, of its technique's size.
fn plan_atlas<B: Backend>(
    frame: &FrameInputs,
    reaches: &[Reach],
    (side, pixels): (u32, u32),
    techniques: &mut LightTechniques<'_, '_, B>,
) -> Result<AtlasPlan, TechniqueError> {
    let view = pixels.max(1) as f32;
    let mut requests = Vec::with_capacity(frame.lights.len());
    for (k, (light, reach)) in frame.lights.iter().zip(reaches).enumerate() {
        let shadow = frame.shadow(k);
        let faces = match light.kind {
            LightKind::Spot { .. } => 1,
            LightKind::Point { .. } => 6,
            LightKind::Directional { .. } => 0,
        };
        let coverage = reach.rect.area() as f32 / view;
        let mut request = TileRequest { faces: 0, side: 0, coverage, held: None };
        if shadow.casts && !reach.is_empty() && !reach.is_everywhere() {
            let technique = techniques.pick(shadow.technique.as_ref())?;
            if let Some(side) = technique.atlas_side() {
                request = TileRequest { faces, side, coverage, held: technique.held_tiles(k) };
            }
        }
        requests.push(request);
    }
    Ok(AtlasPlan::new(side, &requests)?)
}

/// The steps and the stats their phases are timed into.
struct Phases<'a, S> {
    steps: &'a mut S,
    stats: &'a mut FrameStats,
}

impl<S> Phases<'_, S> {
    /// Runs one phase between the steps' `begin` and `end`, adding its wall-clock time to the stats.
    fn run<B: Backend, R>(
        &mut self,
        cx: &mut B::Context,
        phase: Phase,
        work: impl FnOnce(&mut B::Context, &mut S) -> Result<R, B::Error>,
    ) -> Result<R, B::Error>
    where
        S: FrameSteps<B>,
    {
        let t = Instant::now();
        self.steps.begin(cx, phase);
        let result = work(cx, self.steps)?;
        self.steps.end(cx, phase)?;
        self.stats.timings.add(phase, ms(t.elapsed()));
        Ok(result)
    }
}
