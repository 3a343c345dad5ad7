//! The CPU backend type, its context and its errors.

use std::sync::Arc;

use shadow_core::frame::FrameError;
use shadow_core::light::LightViewError;
use shadow_core::technique::{Backend, TechniqueError};
use shadow_core::{FrameInputs, Image};

use crate::bvh::SceneBvh;
use crate::gbuffer::GBuffer;

/// Largest view or map side the CPU backend renders.
pub const MAX_TARGET_SIDE: u32 = 16384;
/// Largest total of texels a single map-based build may allocate (2^30: 4 GiB of f32 depth).
pub const MAX_MAP_TEXELS: u64 = 1 << 30;

/// Errors of the CPU backend.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum CpuError {
    /// A shared technique error (unsupported light, bad settings).
    #[error(transparent)]
    Technique(#[from] TechniqueError),
    /// The frame could not be assembled (bad camera or light, empty scene).
    #[error(transparent)]
    Frame(#[from] FrameError),
    /// No light view could be fitted.
    #[error(transparent)]
    LightView(#[from] LightViewError),
    /// A view or map size that cannot be rendered.
    #[error("{what} of {width}x{height} cannot be rendered: {why}")]
    BadSize {
        /// What was being sized.
        what: &'static str,
        /// Width asked for.
        width: u64,
        /// Height asked for.
        height: u64,
        /// Why not.
        why: String,
    },
}

/// Checks a target size before anything is allocated.
///
/// # Errors
/// [`CpuError::BadSize`] for a zero side, a side over [`MAX_TARGET_SIDE`] or more than `max_texels`.
pub fn check_size(what: &'static str, width: u64, height: u64, max_texels: u64) -> Result<(), CpuError> {
    let why = if width == 0 || height == 0 {
        "a side is zero".to_string()
    } else if width > u64::from(MAX_TARGET_SIDE) || height > u64::from(MAX_TARGET_SIDE) {
        format!("a side is over the limit of {MAX_TARGET_SIDE}")
    } else if width * height > max_texels {
        format!("{} texels is over the limit of {max_texels}", width * height)
    } else {
        return Ok(());
    };
    Err(CpuError::BadSize { what, width, height, why })
}

/// The CPU reference backend.
#[derive(Clone, Copy, Debug, Default)]
pub struct CpuBackend;

impl Backend for CpuBackend {
    type Context = CpuContext;
    type GBuffer = GBuffer;
    type Visibility = Image<f32>;
    type Error = CpuError;
    const NAME: &'static str = "cpu";

    fn view_size(g: &GBuffer) -> (u32, u32) {
        (g.depth.width(), g.depth.height())
    }
}

/// What the CPU backend keeps between frames: the ray-casting BVH of the casters (it does not depend on
/// the light, so it survives a moving light; it is rebuilt when a caster moves or changes).
///
/// A technique of one's own on the CPU backend, here hard shadows by one ray per pixel through the
/// context's BVH, rendered in a frame:
///
/// ```
/// use shadow_core::scenes::{self, SceneParams};
/// use shadow_core::technique::{LightPass, ShadowTechnique, Stateful};
/// use shadow_core::{FrameInputs, Image};
/// use shadow_cpu::{CpuBackend, CpuContext, CpuError, GBuffer};
///
/// struct Rays;
///
/// impl ShadowTechnique<CpuBackend> for Rays {
///     type State = ();
///
///     fn name(&self) -> &'static str {
///         "rays"
///     }
///
///     fn create_state(&self, _: &mut CpuContext) -> Result<(), CpuError> {
///         Ok(())
///     }
///
///     fn build(&self, _: &mut CpuContext, _: &mut (), _: LightPass<'_>) -> Result<(), CpuError> {
///         Ok(())
///     }
///
///     fn query(&self, cx: &mut CpuContext, _: &mut (), pass: LightPass<'_>, g: &GBuffer, out: &mut Image<f32>) -> Result<(), CpuError> {
///         let (bvh, light) = (cx.bvh(pass.frame), &pass.light.light);
///         for (i, v) in out.data_mut().iter_mut().enumerate() {
///             if g.receiver.data()[i] {
///                 // Off the surface a little, towards its seen side, so it does not shadow itself.
///                 let p = g.position.data()[i] + g.geometric_normal.data()[i] * 1e-3;
///                 let reach = light.position().map_or(f32::INFINITY, |l| l.distance(p));
///                 *v = f32::from(u8::from(!bvh.occluded(p, light.to_light(p), reach)));
///             }
///         }
///         Ok(())
///     }
/// }
///
/// let frame = FrameInputs::from_first_camera(&scenes::build("cubes", &SceneParams::default())?)?;
/// let mut cx = CpuContext::new();
/// let rendered = shadow_cpu::frame::render_frame(&mut cx, &frame, 160, 120, &mut Stateful::new(Rays, String::new()))?;
/// let visibility = rendered.visibility[0].data();
/// assert!(visibility.contains(&0.0) && visibility.contains(&1.0));
/// # Ok::<(), Box<dyn std::error::Error>>(())
/// ```
#[derive(Default)]
pub struct CpuContext {
    bvh: Option<(u64, Arc<SceneBvh>)>,
    spare: Option<GBuffer>,
}

impl CpuContext {
    /// A fresh context.
    #[must_use]
    pub fn new() -> Self {
        Self::default()
    }

    /// Hands a finished frame's G-buffer back, so the next frame reuses its storage.
    pub fn recycle(&mut self, gbuffer: GBuffer) {
        self.spare = Some(gbuffer);
    }

    /// The recycled G-buffer, if any.
    pub(crate) fn take_spare(&mut self) -> Option<GBuffer> {
        self.spare.take()
    }

    /// Drops what the context keeps from frame to frame (the BVH), so the next frame builds it again:
    /// for measuring what that costs.
    pub fn forget(&mut self) {
        self.bvh = None;
    }

    /// The BVH of the frame's casters, built on first use and reused while they stay put.
    pub fn bvh(&mut self, frame: &FrameInputs) -> Arc<SceneBvh> {
        let key = SceneBvh::key(frame);
        match &self.bvh {
            Some((k, b)) if *k == key => b.clone(),
            _ => {
                let b = Arc::new(SceneBvh::build(frame));
                self.bvh = Some((key, b.clone()));
                b
            }
        }
    }
}
