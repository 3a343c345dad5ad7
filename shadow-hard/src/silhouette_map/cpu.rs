//! `silhouette-map` (Sen, Cammarano, Hanrahan 2003). Pass 1 renders the depth map as `shadow-map` does
//! (same bias); pass 2 stores one silhouette point per texel of a map shifted half a texel
//! (`super::points::PointMap::store`, the reference both backends follow); the query runs the
//! four corner tests and, where they disagree, the skewed-quadrant reconstruction of Fig. 5. With
//! `corner_depth=receiver-plane` (the default) each corner is compared with the receiver plane's depth
//! there, from the G-buffer's face normal.
//!
//! The silhouettes come from the shared extraction (`FrameInputs::silhouette_segments`). Pass 2 is not a
//! rasterizer here: each segment visits the texels whose enlarged squares it may touch, in edge order,
//! so a texel keeps the last point written to it, as on the GPU. Counters: `silhouette_edges`,
//! `silhouette_texels` (non-empty texels, all projections) and `silhouette_pixels` (pixels whose corner
//! tests disagreed: Sen's P is this over `covered_pixels`).

use shadow_core::technique::LightPass;
use std::sync::atomic::{AtomicU64, Ordering};

use super::SilhouetteMap;
use super::points::CornerDepth;
use super::points::{PointMap, overlay, project_segments, silhouette_lookup};
use shadow_core::Image;
use shadow_core::glam::Vec2;
use shadow_core::technique::{DebugView, ShadowTechnique, TechniqueError};

use shadow_cpu::GBuffer;
use shadow_cpu::passes::maps::depth_views;
use shadow_cpu::passes::maps::{map_position, render_depth_maps};
use shadow_cpu::passes::per_receiver;
use shadow_cpu::{CpuBackend, CpuContext, CpuError};

/// The depth and silhouette maps of the last build, one of each per light projection.
#[derive(Default)]
pub struct State {
    maps: Vec<Image<f32>>,
    points: Vec<PointMap>,
}

impl ShadowTechnique<CpuBackend> for SilhouetteMap {
    type State = State;

    fn name(&self) -> &'static str {
        Self::NAME
    }

    fn create_state(&self, _: &mut CpuContext) -> Result<State, CpuError> {
        Ok(State::default())
    }

    fn build(&self, _: &mut CpuContext, state: &mut State, pass: LightPass<'_>) -> Result<(), CpuError> {
        let LightPass { frame, light, stats, aspect, .. } = pass;
        let view = self.view(frame, light, aspect);
        let light = &*view;
        let res = self.depth.resolution;
        render_depth_maps(frame, light, res, self.depth.depth_bias(), &mut state.maps)?;
        let edges = frame.silhouette_segments(light);
        state.points.resize_with(light.projections.len(), PointMap::default);
        let mut texels = 0;
        for ((p, map), points) in light.projections.iter().zip(&state.maps).zip(&mut state.points) {
            points.store(&project_segments(&edges, p, res), map, self.corner_margin, self.keep);
            texels += points.texels();
        }
        let c = &mut stats.counters;
        c.silhouette_edges = Some(edges.len() as u64);
        c.extra.insert("silhouette_texels".into(), texels as f64);
        Ok(())
    }

    fn query(
        &self,
        _: &mut CpuContext,
        state: &mut State,
        pass: LightPass<'_>,
        g: &GBuffer,
        out: &mut Image<f32>,
    ) -> Result<(), CpuError> {
        let LightPass { frame, light, stats, aspect, reach, .. } = pass;
        let view = self.view(frame, light, aspect);
        let light = &*view;
        if state.maps.len() != light.projections.len() || state.points.len() != state.maps.len() {
            return Err(TechniqueError::NotBuilt(Self::NAME.into()).into());
        }
        let offset = self.depth.receiver_offset();
        let silhouette_pixels = AtomicU64::new(0);
        per_receiver(g, &reach, out, |_, _, i| {
            let m = map_position(light, g.position.data()[i], offset);
            let k = m.projection;
            let gradient = match self.corner_depth {
                CornerDepth::ReceiverPlane => {
                    light.projections[k].depth_gradient(m.world, g.geometric_normal.data()[i])
                }
                CornerDepth::Fragment => Vec2::ZERO,
            };
            let r = silhouette_lookup(&state.maps[k], state.points[k].points(), m.uv, m.depth, gradient);
            if r.silhouette {
                silhouette_pixels.fetch_add(1, Ordering::Relaxed);
            }
            r.visibility
        });
        stats.counters.silhouette_pixels = Some(silhouette_pixels.into_inner());
        Ok(())
    }

    /// With cascades the maps follow the camera, which the build key does not hold.
    fn build_is_reusable(&self, _: &shadow_core::FrameInputs) -> bool {
        self.cascades == 0
    }

    fn debug_views(&self, _: &mut CpuContext, state: &State) -> Result<Vec<DebugView>, CpuError> {
        let mut views = depth_views("depth", &state.maps);
        views.extend(
            state
                .maps
                .iter()
                .zip(&state.points)
                .enumerate()
                .map(|(k, (m, p))| DebugView { name: format!("silhouette{k}"), image: overlay(m, p.points()) }),
        );
        Ok(views)
    }
}
