//! The viewer's timeline: a scene's animations played, paused and scrubbed. The scene is posed at the
//! timeline's time and its frame gathered again only when that time changes, so a paused pose is drawn
//! (and compared with its reference) as a still scene is.

use shadow_core::{FrameInputs, Scene};

use crate::Error;

/// A scene with animations, and where its timeline stands.
pub(super) struct Clip {
    scene: Scene,
    /// The clip's length in seconds (its longest animation's).
    duration: f32,
    time: f32,
    /// Whether the time runs with the wall clock.
    pub playing: bool,
}

impl Clip {
    /// The timeline of `scene`, where it has animations: paused at `time` where one is given (`--time`),
    /// else playing from the start.
    pub fn of(scene: Scene, time: Option<f32>) -> Option<Self> {
        scene.animations().next()?;
        let duration = scene.animation_duration();
        Some(Self { scene, duration, time: time.unwrap_or(0.0).clamp(0.0, duration), playing: time.is_none() })
    }

    /// The time shown, in seconds.
    pub fn time(&self) -> f32 {
        self.time
    }

    /// The clip's length in seconds.
    pub fn duration(&self) -> f32 {
        self.duration
    }

    /// Runs the time on by `dt` seconds while playing, from the end back to the start; whether it moved.
    pub fn advance(&mut self, dt: f32) -> bool {
        if !self.playing || dt <= 0.0 {
            return false;
        }
        self.time = if self.duration > 0.0 { (self.time + dt) % self.duration } else { 0.0 };
        true
    }

    /// Stops the time at `t` (held within the clip); whether it moved.
    pub fn scrub(&mut self, t: f32) -> bool {
        self.playing = false;
        let t = t.clamp(0.0, self.duration);
        std::mem::replace(&mut self.time, t) != t
    }

    /// The scene posed at the time, seen from its first camera under its own lights.
    ///
    /// # Errors
    /// A pose that fails (joint matrices that overflow: the error names the node).
    pub fn frame(&mut self) -> Result<FrameInputs, Error> {
        self.scene.pose(self.time).map_err(shadow_core::frame::FrameError::from)?;
        Ok(FrameInputs::from_first_camera(&self.scene)?)
    }
}
