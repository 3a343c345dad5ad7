//! `cascaded-shadow-map` on the CPU (twin: [`super::gpu`]): one depth map per cascade, looked up with the
//! cascades' blending (shadow-cpu's `passes::maps::MapLookup`).

use super::CascadedShadowMap;

crate::view_maps::cpu::view_fitted_on_cpu!(CascadedShadowMap, "cascade");
