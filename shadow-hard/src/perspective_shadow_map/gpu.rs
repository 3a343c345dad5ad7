//! `perspective-shadow-map` on the GPU (twin: [`super::cpu`]): the post-perspective map, rendered and looked
//! up through the shared map passes (the camera's and the light's projections in one matrix; the
//! clipper drops what lies behind either).

use super::PerspectiveShadowMap;

crate::view_maps::gpu::view_fitted_on_gpu!(PerspectiveShadowMap);
