//! Soft shadows, written only against the public APIs of shadow-core, shadow-cpu and shadow-wgpu (DESIGN
//! 2): the proof that a technique can live outside the backends. Where a backend lacked something a
//! technique here needed, it was added to that backend's public API, documented.
//!
//! - [`area_light::AreaLightReference`] (`area-light-reference`): the reference soft techniques are
//!   measured against, Monte Carlo visibility of a spherical light through the CPU backend's BVH.
//! - [`smoothies::Smoothies`] (`smoothies`): Chan and Durand's fake soft shadows.
//! - [`pcss::Pcss`] (`pcss`): Fernando's percentage-closer soft shadows.

pub mod area_light;
pub mod pcss;
pub mod smoothies;

pub use area_light::AreaLightReference;
pub use pcss::Pcss;
pub use smoothies::Smoothies;
