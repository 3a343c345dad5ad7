//! Shadow rays for the ray-traced references (`ray-traced` in shadow-hard, `area-light-reference` in
//! shadow-soft): the scene BVH, built once per frame, and each receiver's ray origin, offset off the
//! surface by a fraction of the scene's diagonal along the face normal turned towards the viewer.

use rayon::prelude::*;
use shadow_core::FrameInputs;
use shadow_core::glam::Vec3;
use shadow_core::scene::LightKind;
use shadow_core::technique::TechniqueError;

use crate::bvh::{SceneBvh, Walker};
use crate::context::CpuContext;
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

/// The shadow ray from `origin` to a light: its unit direction and how far it runs (to the light's
/// position, or without end against a directional light's direction).
#[must_use]
pub fn towards(light: &LightKind, origin: Vec3) -> (Vec3, f32) {
    match *light {
        LightKind::Spot { position, .. } | LightKind::Point { position } => {
            let d = position - origin;
            let len = d.length();
            (d / len, len)
        }
        LightKind::Directional { direction } => (-direction.normalize(), f32::INFINITY),
    }
}

/// A shadow ray: origin, unit direction, and how far it runs.
pub type ShadowRay = (Vec3, Vec3, f32);

/// The rays `ray-traced` casts over `g`: from each receiver whose seen side faces the frame's first
/// light, towards it (see [`towards`]), leaving the surface as [`RayOrigins`] places it. None without a
/// light.
#[must_use]
pub fn shadow_rays(g: &GBuffer, frame: &FrameInputs, epsilon: f32) -> Vec<ShadowRay> {
    let Some(light) = frame.lights.first() else { return Vec::new() };
    let origins = RayOrigins::new(g, frame, epsilon);
    (0..g.receiver.data().len())
        .filter(|&i| g.receiver.data()[i])
        .filter_map(|i| {
            let (origin, n) = origins.at(i);
            let (dir, far) = towards(&light.kind, origin);
            (n.dot(dir) > 0.0).then_some((origin, dir, far))
        })
        .collect()
}

/// How many of `rays` some triangle blocks, traced in order on this thread, each after the last blocker
/// of those before it (as a technique traces a row of pixels: [`SceneBvh::occluded_after`]).
#[must_use]
pub fn count_blocked(bvh: &SceneBvh, rays: &[ShadowRay]) -> usize {
    let mut walker = Walker::default();
    rays.iter().filter(|&&(origin, dir, far)| bvh.occluded_after(&mut walker, origin, dir, far)).count()
}

/// [`count_blocked`] on every thread, each taking runs of neighbouring rays in turn.
#[must_use]
pub fn count_blocked_on_every_thread(bvh: &SceneBvh, rays: &[ShadowRay]) -> usize {
    rays.par_chunks(4096).map(|run| count_blocked(bvh, run)).sum()
}
