//! Depth maps fitted to the camera's view each frame (cascades, light-space perspective maps): the
//! projections a technique's [`MapLayout`](shadow_core::technique::maps::MapLayout) gives, rendered and
//! looked up through the shared map passes of each backend. The techniques built on them differ only in
//! their layout; this is the state and the two phases they share.

pub mod cpu;
pub mod gpu;
