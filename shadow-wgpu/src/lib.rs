//! shadow-wgpu: the GPU backend, through wgpu.
//!
//! A context on its own device or the host application's ([`context`]), scene upload cached per mesh
//! ([`upload`]), the G-buffer ([`gbuffer`]), the instrumented frame with shading and read-backs
//! ([`frame`]), the frame recorded into a host's encoder ([`record`]), pipelines and WGSL every technique
//! uses ([`pipelines`], [`shaders`]), materials' textures ([`textures`]), the passes techniques are built from ([`passes`]), and where
//! buffers and textures come from ([`resources`]).

pub mod clock;
pub mod context;
pub mod draw_order;
pub mod frame;
pub mod gbuffer;
pub mod host_maps;
pub mod host_wgsl;
pub mod passes;
pub mod pipeline_cache;
pub mod pipelines;
pub mod posing;
pub mod readback;
pub mod record;
pub mod resources;
pub mod shaders;
pub mod textures;
pub mod timer;
pub mod upload;

pub use context::{AdapterChoice, AdapterSummary, WgpuBackend, WgpuContext, WgpuError, list_adapters};
pub use frame::{GpuVisibility, WgpuFrame, render_frame};
pub use gbuffer::{GpuGBuffer, HostSurfaces};
pub use host_maps::HostMap;
pub use pipeline_cache::PipelineCache;
pub use record::{ColorTarget, FrameRecorder};
pub use resources::{Created, Transient, TransientRing};
pub use timer::{FrameTimer, FrameTimes};
