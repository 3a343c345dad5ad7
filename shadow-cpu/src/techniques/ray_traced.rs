//! `ray-traced`: the exact reference. One shadow ray per receiver pixel, from the surface towards the
//! light, against every caster.
//!
//! A surface whose seen side faces away from the light cannot see it: the surface itself is in the way
//! (a closed mesh's own far side, or the back of a sheet). Those pixels are in shadow without a ray; a
//! ray there would only graze the surface and, offset, could slip past the silhouette.
//!
//! Other rays start off the surface by `epsilon` times the scene's bounding-box diagonal, along the face
//! normal turned towards the viewer (the side that is seen). The offset scales with the scene, so it is
//! as many f32 ulps at any scene size (see [`RayTraced::epsilon`] for how the default was measured).

use shadow_core::glam::Vec3;
use shadow_core::light::LightView;
use shadow_core::scene::LightKind;
use shadow_core::technique::hard::RayTraced;
use shadow_core::technique::{FrameStats, ShadowTechnique, TechniqueError};
use shadow_core::{FrameInputs, Image};

use super::per_receiver;
use crate::bvh::SceneBvh;
use crate::context::{CpuBackend, CpuContext, CpuError};
use crate::gbuffer::GBuffer;

/// What a ray-traced technique keeps: the BVH of the last build (shared with `area-light-reference`).
#[derive(Default)]
pub struct State {
    bvh: Option<std::sync::Arc<SceneBvh>>,
}

impl State {
    /// Builds (or takes the context's cached) BVH of the frame's casters.
    pub fn build(&mut self, cx: &mut CpuContext, frame: &FrameInputs) {
        self.bvh = Some(cx.bvh(frame));
    }

    /// The BVH of the last build.
    ///
    /// # Errors
    /// [`TechniqueError::NotBuilt`] naming `technique` before any build.
    pub fn bvh(&self, technique: &str) -> Result<&SceneBvh, TechniqueError> {
        self.bvh.as_deref().ok_or_else(|| TechniqueError::NotBuilt(technique.into()))
    }
}

/// Where shadow rays leave the receivers of a G-buffer: each position moved `epsilon` times the scene's
/// bounding-box diagonal along its geometric normal (turned towards the viewer, the side that is seen), so
/// the offset is as many f32 ulps at any scene size.
pub struct RayOrigins<'a> {
    g: &'a GBuffer,
    offset: f32,
}

impl<'a> RayOrigins<'a> {
    /// The origins over `g` for a frame, `epsilon` a fraction of its diagonal.
    #[must_use]
    pub fn new(g: &'a GBuffer, frame: &FrameInputs, epsilon: f32) -> Self {
        Self { g, offset: epsilon * frame.bounds.size().length() }
    }

    /// Pixel `i`'s ray origin and its geometric normal.
    #[must_use]
    pub fn at(&self, i: usize) -> (Vec3, Vec3) {
        let n = self.g.geometric_normal.data()[i];
        (self.g.position.data()[i] + n * self.offset, n)
    }
}

impl ShadowTechnique<CpuBackend> for RayTraced {
    type State = State;

    fn name(&self) -> &'static str {
        "ray-traced"
    }

    fn create_state(&self, _: &mut CpuContext) -> Result<State, CpuError> {
        Ok(State::default())
    }

    fn build(
        &self,
        cx: &mut CpuContext,
        state: &mut State,
        frame: &FrameInputs,
        _: &LightView,
        _: &mut FrameStats,
    ) -> Result<(), CpuError> {
        state.build(cx, frame);
        Ok(())
    }

    fn query(
        &self,
        _: &mut CpuContext,
        state: &mut State,
        frame: &FrameInputs,
        light: &LightView,
        g: &GBuffer,
        out: &mut Image<f32>,
        stats: &mut FrameStats,
    ) -> Result<(), CpuError> {
        let bvh = state.bvh(self.name())?;
        let origins = RayOrigins::new(g, frame, self.epsilon);
        per_receiver(g, out, |_, _, i| {
            let (origin, n) = origins.at(i);
            let (dir, tmax) = match light.light.kind {
                LightKind::Spot { position, .. } | LightKind::Point { position } => {
                    let d = position - origin;
                    let len = d.length();
                    (d / len, len)
                }
                LightKind::Directional { direction } => (-direction.normalize(), f32::INFINITY),
            };
            if n.dot(dir) <= 0.0 || bvh.occluded(origin, dir, tmax) { 0.0 } else { 1.0 }
        });
        stats.counters.extra.insert("shadow_rays".into(), g.covered_pixels() as f64);
        Ok(())
    }
}
