//! `lispsm` on the CPU (twin: [`super::gpu`]): the warped depth map, rendered and looked up through the
//! shared map passes (the warp is in the projection).

use super::Lispsm;

crate::view_maps::cpu::view_fitted_on_cpu!(Lispsm, "depth");
