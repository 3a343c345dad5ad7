//! shadow-cpu: the CPU reference backend.
//!
//! A software rasterizer that follows DESIGN 4 exactly ([`raster`]), BVH ray casting for the exact
//! reference ([`bvh`]), the G-buffer ([`gbuffer`]), shading ([`shade`]) and frame assembly ([`frame`]),
//! and the passes techniques are built from ([`passes`]); the rasterized passes cut out what a masked
//! material's texture clears ([`alpha_test`]).

pub mod acne;
pub mod alpha_test;
pub mod bvh;
pub mod clip_space;
pub mod context;
pub mod frame;
pub mod gbuffer;
pub mod passes;
pub mod raster;
pub mod runs;
pub mod shade;

pub use context::{CpuBackend, CpuContext, CpuError};
pub use frame::{CpuFrame, render_frame, render_frame_over};
pub use gbuffer::GBuffer;
