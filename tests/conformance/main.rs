//! The one integration-test binary (DESIGN 9): the command line, and cross-backend conformance of every
//! registered technique, the example's runtime-registered one included.

mod cli;
mod depth_layers;
mod gpu_clock;
mod hybrid;
mod silhouette_map;
mod smoothies;
// The technique of examples/custom_technique.rs, registered at runtime like a user's would be.
#[path = "../../examples/planar/mod.rs"]
#[allow(dead_code)]
mod planar;
mod suite;
mod volume_reconstruction;
