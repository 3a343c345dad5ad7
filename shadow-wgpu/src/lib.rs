//! shadow-wgpu: the GPU backend, through wgpu.
//!
//! A headless context ([`context`]), scene upload cached per mesh ([`upload`]), the G-buffer
//! ([`gbuffer`]), the frame driver with shading and readback ([`frame`]), and the GPU versions of the
//! techniques ([`techniques`]), each a folder-like module with its WGSL next to it in `shaders/`.

pub mod clock;
pub mod context;
pub mod frame;
pub mod gbuffer;
pub mod pipelines;
pub mod readback;
pub mod shaders;
pub mod techniques;
pub mod upload;

pub use context::{AdapterChoice, AdapterSummary, WgpuBackend, WgpuContext, WgpuError, list_adapters};
pub use frame::{GpuVisibility, WgpuFrame, render_frame};
pub use gbuffer::GpuGBuffer;
