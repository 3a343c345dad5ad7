//! `cascaded-shadow-map` on the GPU (twin: [`super::cpu`]): the shared light pass renders one layer per
//! cascade; the shared query picks each receiver's cascade and blends at the seams (shadow_map.wgsl's
//! `cascade_pick`).

use super::CascadedShadowMap;

crate::view_maps::gpu::view_fitted_on_gpu!(CascadedShadowMap);
