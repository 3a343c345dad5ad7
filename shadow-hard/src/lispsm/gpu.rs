//! `lispsm` on the GPU (twin: [`super::cpu`]): the warped depth map, rendered and looked up through the
//! shared map passes (the warp is in the projection; the hardware clips casters behind its centre).

use super::Lispsm;

crate::view_maps::gpu::view_fitted_on_gpu!(Lispsm);
