//! Hard shadows: one folder per technique, written against the public APIs of shadow-core, shadow-cpu and
//! shadow-wgpu, as shadow-soft's are.
//!
//! Each folder reads top to bottom next to its paper: `mod.rs` says what the technique is, which section
//! it follows and where it departs, and declares its settings; `cpu.rs` and `gpu.rs` are its two backends
//! (the reference is CPU only); its WGSL sits beside them; maths only it uses lives in the folder too.
//!
//! - [`ray_traced`]: the exact reference.
//! - [`shadow_map`]: Williams' depth map with percentage-closer filtering.
//! - [`cascaded_shadow_map`]: a directional light's maps, one per slice of the camera's view depth.
//! - [`lispsm`]: Wimmer, Scherzer and Purgathofer's light-space perspective shadow map.
//! - [`perspective_shadow_map`]: Stamminger and Drettakis's map in post-perspective space.
//! - [`silhouette_map`]: Sen, Cammarano and Hanrahan's silhouette map.
//! - [`volume_reconstruction`]: McCool's shadow volumes rebuilt from a depth map.
//! - [`hybrid`]: Chan's shadow maps with shadow volumes at the silhouette pixels only.
//! - [`shadow_volume`]: stencil shadow volumes, z-pass and z-fail.
//! - [`depth_layers`]: Woo's midpoint, Wang and Molnar's second-depth and Weiskopf and Ertl's dual maps.

pub mod cascaded_shadow_map;
pub mod depth_layers;
pub mod hybrid;
pub mod lispsm;
pub mod perspective_shadow_map;
pub mod ray_traced;
pub mod shadow_map;
pub mod shadow_volume;
pub mod silhouette_map;
pub mod view_maps;
pub mod volume_reconstruction;

/// A registry entry of a technique on the two backends.
pub type Entry = shadow_core::technique::registry::Entry<shadow_cpu::CpuBackend, shadow_wgpu::WgpuBackend>;

pub use cascaded_shadow_map::CascadedShadowMap;
pub use depth_layers::{DepthLayers, DualShadowMap, MidpointShadowMap, SecondDepthShadowMap};
pub use hybrid::Hybrid;
pub use lispsm::Lispsm;
pub use perspective_shadow_map::PerspectiveShadowMap;
pub use ray_traced::RayTraced;
pub use shadow_map::ShadowMap;
pub use shadow_volume::ShadowVolume;
pub use silhouette_map::SilhouetteMap;
pub use volume_reconstruction::VolumeReconstruction;
