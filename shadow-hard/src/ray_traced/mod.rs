//! `ray-traced`: the exact reference hard shadows are measured against. One shadow ray per receiver
//! pixel, from the surface towards the light, against every caster through the CPU backend's BVH.
//!
//! A surface whose seen side faces away from the light cannot see it: the surface itself is in the way
//! (a closed mesh's own far side, or the back of a sheet). Those pixels are in shadow without a ray; a
//! ray there would only graze the surface and, offset, could slip past the silhouette.
//!
//! Other rays start off the surface by `epsilon` times the scene's bounding-box diagonal, along the face
//! normal turned towards the viewer (the side that is seen). The offset scales with the scene, so it is
//! as many f32 ulps at any scene size (see [`RayTraced::epsilon`] for how the default was measured).
//!
//! CPU only: a reference is computed once per scene, not per frame.

pub mod cpu;

use crate::Entry;
use shadow_core::technique::settings::SettingKey;

shadow_core::technique_settings! {
    /// `ray-traced`: one shadow ray per G-buffer pixel, the exact reference.
    pub struct RayTraced {
        /// Shadow-ray origin offset along the geometric normal, as a fraction of the scene's bounding-box
        /// diagonal (so the offset scales with the scene). The default, 5e-7, is a few f32 ulps of the
        /// scene's size: enough to clear the rounding of the surface position, small enough not to shift
        /// rays past sub-centimetre occluders (at 2e-5 the tree's thin branch shadows moved by a pixel in
        /// 0.1% of the image; from 2e-6 down the reference stops changing).
        pub epsilon: f32 = SettingKey::float(
            "epsilon",
            "0.0000005",
            0.0,
            0.1,
            "ray origin offset along the normal, as a fraction of the scene diagonal",
        ),
    }
}

impl RayTraced {
    /// The technique's name.
    pub const NAME: &'static str = "ray-traced";
}

/// The registry entry: the hard techniques' reference, on the CPU.
#[must_use]
pub fn entry() -> Entry {
    Entry::on_cpu::<RayTraced>(
        RayTraced::NAME,
        "exact hard shadows: one shadow ray per pixel through a BVH",
        "reference",
    )
    .reference()
}
