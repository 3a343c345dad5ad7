//! Temporal flicker (`shadowlab flicker`): the camera walks a path, and at every step the technique is
//! built for the moved camera and asked about the same receivers: the points the camera saw at the start
//! of the walk. The reference's answer at a fixed point of a still scene never changes, so a point
//! flickers between two consecutive frames when the technique's lit/shadowed state there changes at all:
//! the shadow edge crawling or shimmering over a surface as the maps fitted to the view move under it.
//! Flicker is the fraction of measured points (receivers facing the light) and consecutive frame pairs
//! that do.
//!
//! Holding the points still is what isolates the maps' motion. Following pixels from frame to frame
//! instead (as temporal anti-aliasing reprojects them) compares samples that lie a fraction of a pixel
//! apart on the surface, and a map's stair-steps lie between such samples as often when the steps stand
//! still as when they move: every map flickers by that measure, a uniform map that never moves included.
//! The CPU backend runs it, since it can query a frame over another view's receivers; the maps' fit is
//! the same code on both backends.
//!
//! A walk may step through an animation too ([`FlickerWalk::through`]): the scene posed a little later
//! at every frame. Then the casters move and the reference's own answer changes where the shadow truly
//! moves, so a point flickers between two frames when the technique's state changes there and the
//! reference's does not, or the reference's changes and the technique's does not. Only the receivers
//! that stand still and stay in view are measured: a point on a moving caster does not stay on it, and
//! one a caster walks in front of is not seen.

use shadow_core::metrics::measured_pixels;
use shadow_core::technique::TechniqueSpec;
use shadow_core::{Camera, FrameInputs, Image};

use crate::Error;
use crate::renderer::{BackendKind, Renderer};

/// A walk from `start`: `frames` cameras, each `step` scene units further along the view's level
/// direction and turned `turn` radians left about the vertical, as a walker looking about would be.
#[must_use]
pub fn walk(start: &Camera, frames: usize, step: f32, turn: f32) -> Vec<Camera> {
    let forward = (start.target - start.eye) * glam::Vec3::new(1.0, 0.0, 1.0);
    let forward = forward.try_normalize().unwrap_or(glam::Vec3::NEG_Z);
    (0..frames)
        .map(|k| {
            let k = k as f32;
            let moved = glam::Mat4::from_translation(forward * step * k);
            let turned = glam::Mat4::from_translation(start.eye)
                * glam::Mat4::from_rotation_y(turn * k)
                * glam::Mat4::from_translation(-start.eye);
            start.transformed(moved * turned)
        })
        .collect()
}

/// A walk and the receivers it is measured at: the first camera's view, with the pixels measured there
/// (receivers facing the light, in the reference's frame).
pub struct FlickerWalk {
    frames: Vec<FrameInputs>,
    receivers: shadow_cpu::GBuffer,
    mask: Image<bool>,
    /// Where the scene moves, the reference's lit state at the receivers in each frame.
    reference: Option<Vec<Image<bool>>>,
}

impl FlickerWalk {
    /// The frames of `frame` (its scene and lights) seen from each camera of `path`, measured at the
    /// receivers of the first, rendered at `width x height`.
    ///
    /// # Errors
    /// A camera that cannot be used; fewer than two; a frame that cannot be rendered.
    pub fn new(
        renderer: &mut Renderer,
        frame: &FrameInputs,
        path: &[Camera],
        (width, height): (u32, u32),
    ) -> Result<Self, Error> {
        if path.len() < 2 {
            return Err(Error::Usage(format!("flicker needs at least 2 frames, not {}", path.len())));
        }
        let mut frames = Vec::with_capacity(path.len());
        for (k, camera) in path.iter().enumerate() {
            camera.validate().map_err(|e| Error::Usage(format!("camera {k} of the walk: {e}")))?;
            frames.push(FrameInputs { camera: *camera, ..frame.clone() });
        }
        let (receivers, mask) = Self::receivers(renderer, &frames[0], (width, height))?;
        Ok(Self { frames, receivers, mask, reference: None })
    }

    /// A walk through frames of a moving scene (each posed at its own time, seen from its own camera),
    /// measured at the receivers of the first that stand still (on instances placed and posed alike in
    /// every frame) and that no caster hides from the camera in any frame, against the reference's
    /// answer at each.
    ///
    /// # Errors
    /// Fewer than two frames; a frame that cannot be rendered.
    pub fn through(renderer: &mut Renderer, frames: Vec<FrameInputs>, size: (u32, u32)) -> Result<Self, Error> {
        if frames.len() < 2 {
            return Err(Error::Usage(format!("flicker needs at least 2 frames, not {}", frames.len())));
        }
        let (receivers, mask) = Self::receivers(renderer, &frames[0], size)?;
        let placed = |f: &FrameInputs, i: usize| f.instances.get(i).map(|x| (x.mesh_version, x.world_from_local));
        let still: Vec<bool> = (0..frames[0].instances.len())
            .map(|i| frames.iter().all(|f| placed(f, i) == placed(&frames[0], i)))
            .collect();
        let on_still = |i: &u32| still.get(*i as usize).copied().unwrap_or(false);
        // A point a moving caster hides from the camera in some frame is left out too: the techniques
        // that count along the eye's ray (z-pass volumes) answer only for points the eye sees.
        let bvhs: Vec<shadow_cpu::bvh::SceneBvh> = frames.iter().map(shadow_cpu::bvh::SceneBvh::build).collect();
        let seen = |p: glam::Vec3| {
            frames.iter().zip(&bvhs).all(|(f, bvh)| {
                let to = p - f.camera.eye;
                let d = to.length();
                // Short of the point by a little, so its own surface does not hide it.
                d <= 0.0 || !bvh.occluded(f.camera.eye, to / d, d * (1.0 - 1e-4))
            })
        };
        let mask = Image::from_fn(mask.width(), mask.height(), |x, y| {
            *mask.get(x, y) && on_still(receivers.instance.get(x, y)) && seen(*receivers.position.get(x, y))
        });
        let mut walk = Self { frames, receivers, mask, reference: None };
        let reference = TechniqueSpec::named(shadow_hard::RayTraced::NAME);
        walk.reference = Some(walk.lit_states(renderer, &reference, |_| {})?);
        Ok(walk)
    }

    /// The first frame's G-buffer and its measured pixels (receivers facing the light).
    fn receivers(
        renderer: &mut Renderer,
        first: &FrameInputs,
        (width, height): (u32, u32),
    ) -> Result<(shadow_cpu::GBuffer, Image<bool>), Error> {
        let reference = TechniqueSpec::named(shadow_hard::RayTraced::NAME);
        let (first, _) = renderer.run_cpu_frame(first, width, height, &reference)?;
        let view = first.light_views.first().ok_or_else(|| Error::Usage("the scene has no light".into()))?;
        let g = &first.gbuffer;
        let mask = measured_pixels(&g.receiver, &g.position, &g.geometric_normal, view);
        Ok((first.gbuffer, mask))
    }

    /// Where `spec` says lit at the receivers, frame by frame. The technique keeps its state from frame
    /// to frame, as an application's would.
    fn lit_states(
        &self,
        renderer: &mut Renderer,
        spec: &TechniqueSpec,
        mut progress: impl FnMut(usize),
    ) -> Result<Vec<Image<bool>>, Error> {
        let mut prepared = renderer.prepare(BackendKind::Cpu, spec)?;
        let mut states = Vec::with_capacity(self.frames.len());
        for (k, frame) in self.frames.iter().enumerate() {
            progress(k);
            let run = renderer.run_cpu_over(&mut prepared, frame, &self.receivers)?;
            states.push(run.visibility[0].map(|&v| v >= 0.5));
        }
        Ok(states)
    }

    /// The flicker of `spec` (on the CPU) along the walk. The technique keeps its state from frame to
    /// frame, as an application's would.
    ///
    /// # Errors
    /// An unknown technique, bad settings, or a frame that cannot be rendered.
    pub fn flicker(
        &self,
        renderer: &mut Renderer,
        spec: &TechniqueSpec,
        progress: impl FnMut(usize),
    ) -> Result<f64, Error> {
        let states = self.lit_states(renderer, spec, progress)?;
        let (mut flickered, mut pairs) = (0u64, 0u64);
        for k in 1..states.len() {
            let (f, n) = match &self.reference {
                None => changed(&states[k - 1], &states[k], &self.mask),
                Some(truth) => {
                    // Where the technique changes and the truth does not, or the other way round.
                    let moved = |s: &[Image<bool>], i: usize| s[k - 1].data()[i] != s[k].data()[i];
                    let measured = self.mask.data().iter().enumerate().filter(|(_, m)| **m).map(|(i, _)| i);
                    let wrong = measured.clone().filter(|&i| moved(&states, i) != moved(truth, i)).count();
                    (wrong as u64, measured.count() as u64)
                }
            };
            flickered += f;
            pairs += n;
        }
        Ok(if pairs == 0 { 0.0 } else { flickered as f64 / pairs as f64 })
    }
}

/// Of the pixels of `mask`, how many differ between `a` and `b`, and how many there are.
fn changed(a: &Image<bool>, b: &Image<bool>, mask: &Image<bool>) -> (u64, u64) {
    let measured = || a.data().iter().zip(b.data()).zip(mask.data()).filter(|(_, m)| **m);
    (measured().filter(|((x, y), _)| x != y).count() as u64, measured().count() as u64)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn only_measured_changes_count() {
        let img = |v: &[bool]| Image::from_fn(4, 1, |x, _| v[x as usize]);
        let (a, b) = (img(&[true, true, false, false]), img(&[false, true, true, true]));
        assert_eq!(changed(&a, &b, &img(&[true, true, true, false])), (2, 3));
    }

    #[test]
    fn the_walk_moves_and_turns_at_head_height() {
        let start = Camera::look_at(glam::Vec3::new(0.0, 1.7, 0.0), glam::Vec3::new(0.0, 1.7, -10.0), 60.0);
        let path = walk(&start, 11, 0.1, 0.01);
        assert_eq!(path.len(), 11);
        assert!((path[10].eye - glam::Vec3::new(0.0, 1.7, -1.0)).length() < 1e-5, "{}", path[10].eye);
        let dir = (path[10].target - path[10].eye).normalize();
        assert!((dir.x + 0.1f32.sin()).abs() < 1e-4 && dir.y.abs() < 1e-6, "{dir}");
    }
}
