//! One light projection's reconstruction, as both backends run it: the GPU backend reads its maps back
//! and hands them here, as the paper does (section 2, step 1).

use glam::{Mat4, Vec4};

use super::caps::near_plane_cap;
use super::edges::{EdgeMap, depth_and_id_edges, depth_edges};
use super::mesh::{border_walls, reconstruct};
use super::{HomTriangle, SampleGrid, texel_square_grid};
use crate::volume_reconstruction::{MeshVertices, VolumeReconstruction};
use shadow_core::Image;
use shadow_core::image::{Rgb8, false_colour};
use shadow_core::light::{LightProjection, LightView};
use shadow_core::scene::LightKind;
use shadow_core::technique::FrameStats;

/// One light projection's map, edges and boundary.
pub struct Projection {
    /// The projection the map was rendered with.
    pub view: LightProjection,
    /// Where the mesh's samples are.
    pub grid: SampleGrid,
    /// NDC depths at the grid's samples, bias included.
    pub samples: Vec<f32>,
    /// Linear depths at the samples (what the edge detector and the split rule compare).
    pub linear: Vec<f32>,
    /// The map's edge flags.
    pub edges: EdgeMap,
    /// The flags between the grid's samples (the map's own for the paper's grid).
    pub mesh_edges: EdgeMap,
    /// The reconstructed boundary.
    pub triangles: Vec<HomTriangle>,
}

/// Where the light's rays start, as the mesh's `bias=world` offset needs it.
#[must_use]
pub fn light_origin(view: &LightView) -> Vec4 {
    match view.light.kind {
        LightKind::Spot { position, .. } | LightKind::Point { position } => position.extend(1.0),
        LightKind::Directional { direction } => direction.extend(0.0),
    }
}

/// Edges and boundary of one rendered map (shared by both backends: the GPU reads its maps back first),
/// with the object IDs of its texels when the light pass rendered them (`ids` other than `off`).
///
/// # Panics
/// When `ids` is not the size of `map`: a caller bug.
#[must_use]
pub fn reconstruct_projection(
    s: &VolumeReconstruction,
    view: &LightView,
    proj: LightProjection,
    map: &Image<f32>,
    ids: Option<&Image<u32>>,
) -> Projection {
    let n = map.width();
    let point = matches!(view.light.kind, LightKind::Point { .. });
    let texels: Vec<f32> = map.data().iter().map(|&z| proj.linear_depth(z.min(1.0))).collect();
    let thresholds = s.edge_settings(proj.far - proj.near);
    let edges = match ids {
        Some(ids) => depth_and_id_edges(&texels, ids.data(), n, n, &thresholds, s.ids),
        None => depth_edges(&texels, n, n, &thresholds),
    };
    let (grid, samples, linear, mesh_edges) = match s.vertices {
        MeshVertices::Texel => {
            let ring = u32::from(point);
            let (linear, flags) = texel_square_grid(&texels, n, &edges, ring);
            let ndc = linear.iter().map(|&d| proj.ndc_depth(d)).collect();
            (SampleGrid::texel_squares(&proj, n, ring), ndc, linear, flags)
        }
        MeshVertices::Centre => (SampleGrid::centres(&proj, n), map.data().to_vec(), texels, edges.clone()),
    };
    let offset = s.depth.receiver_offset();
    let origin = light_origin(view);
    let mut triangles = reconstruct(&samples, &linear, &mesh_edges, &grid, offset, origin).triangles;
    if !point {
        triangles.extend(border_walls(&samples, &grid, offset, origin));
    }
    Projection { view: proj, grid, samples, linear, edges, mesh_edges, triangles }
}

/// The caps of every projection for a view: the stencil's starting bit (global inversions) and the cap
/// triangles.
#[must_use]
pub fn caps_for_view(projections: &[Projection], eye_clip_from_world: Mat4) -> (bool, Vec<HomTriangle>) {
    let mut invert = false;
    let mut triangles = Vec::new();
    for p in projections {
        let cap = near_plane_cap(eye_clip_from_world, &p.view, &p.grid, &p.samples, &p.linear);
        invert ^= cap.invert_all;
        triangles.extend(cap.triangles);
    }
    (invert, triangles)
}

/// The build's counters: the edge-flag fraction (mean over the maps) and the boundary's triangles.
pub fn record_build(projections: &[Projection], stats: &mut FrameStats) {
    let fraction = projections.iter().map(|p| p.edges.flag_fraction()).sum::<f64>() / projections.len().max(1) as f64;
    stats.counters.extra.insert("edge_flag_fraction".into(), fraction);
    stats
        .counters
        .extra
        .insert("boundary_triangles".into(), projections.iter().map(|p| p.triangles.len()).sum::<usize>() as f64);
}

/// The edge map over the mesh's sample depths (light view): samples with a flagged side red.
#[must_use]
pub fn edge_view(samples: &[f32], edges: &EdgeMap) -> Image<Rgb8> {
    let (w, h) = edges.size();
    let depths = Image::from_fn(w, h, |x, y| samples[(y * w + x) as usize]);
    let lo = samples.iter().copied().fold(1.0f32, f32::min);
    let mut img = false_colour(&depths, lo, 1.0);
    for y in 0..h {
        for x in 0..w {
            let flagged = (x + 1 < w && edges.u(x, y))
                || (x > 0 && edges.u(x - 1, y))
                || (y + 1 < h && edges.v(x, y))
                || (y > 0 && edges.v(x, y - 1));
            if flagged {
                *img.get_mut(x, y) = [235, 30, 30];
            }
        }
    }
    img
}

/// The reconstructed volume's debug view from per-pixel counts of the boundary and cap triangles covering
/// each pixel (no depth test): a false-colour ramp up to the largest count, black where none.
#[must_use]
pub fn coverage_view(counts: &Image<u8>) -> Image<Rgb8> {
    let top = counts.data().iter().copied().max().unwrap_or(0).max(1);
    let ramp = false_colour(
        &Image::from_fn(counts.width(), counts.height(), |x, y| f32::from(*counts.get(x, y))),
        0.0,
        f32::from(top),
    );
    Image::from_fn(
        counts.width(),
        counts.height(),
        |x, y| if *counts.get(x, y) == 0 { [0, 0, 0] } else { *ramp.get(x, y) },
    )
}
