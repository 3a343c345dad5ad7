//! `perspective-shadow-map` on the CPU (twin: [`super::gpu`]): the post-perspective map, rendered and looked
//! up through the shared map passes (the camera's and the light's projections in one matrix).

use super::PerspectiveShadowMap;

crate::view_maps::cpu::view_fitted_on_cpu!(PerspectiveShadowMap, "depth");
