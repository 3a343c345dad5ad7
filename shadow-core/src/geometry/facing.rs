//! The facing of whole runs of faces at once, so the silhouette pass reads only the faces near the
//! silhouette.
//!
//! Most meshes list their faces in spatial order (strip by strip, cluster by cluster), so long runs of
//! consecutive faces all face the light or all face away from it, and only the runs the silhouette
//! crosses are mixed. Once per mesh, the planes of each run of [`FACES`] faces are bounded component by
//! component; per light, interval arithmetic on those bounds tells in four products whether the light
//! is in front of every plane of the run, behind every one, or neither. Only runs of the third kind are
//! tested face by face.
//!
//! Each run of [`EDGES`] manifold edges records the face runs its faces lie in. When all of those have
//! one decided facing, every face of every edge in the run has the same weight, and none of the edges is
//! on the silhouette: the run is skipped without reading its faces.
//!
//! The shortcut changes no answer. A run is decided only when its bound clears the rounding error of the
//! per-face test (a four-term dot product in f32: at most gamma_4 = 4u / (1 - 4u) times the sum of the
//! terms' magnitudes, Higham 2002 section 3.1, with u = 2^-24) with room to spare; the bound itself is
//! taken in f64, where the products of two f32 values are exact. So every face of a decided run gets the
//! sign the per-face test gives it. Runs with a plane or a light that is not finite are never decided.

use glam::{DVec4, Vec4};
use rayon::prelude::*;

use super::LightSource;

/// Faces per run.
pub(crate) const FACES: usize = 64;
/// Manifold edges per run.
pub(crate) const EDGES: usize = 64;
/// The most face runs an edge run keeps track of; an edge run whose faces spread over more is always
/// read edge by edge.
const SPREAD: usize = 8;

/// Where a light lies for every plane of a run of faces.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum Facing {
    /// In front of every plane: each face's facing value is positive.
    Front,
    /// Behind every plane: each face's facing value is negative.
    Back,
    /// Not decided by the bounds: the faces are tested one by one.
    Mixed,
}

/// The face runs of one run of manifold edges, the unused slots repeating the first (so all of them
/// can be checked without a count); `None` when they are more than [`SPREAD`].
pub(crate) type EdgeRun = Option<[u32; SPREAD]>;

/// The least and the greatest value of each plane component over one run of faces.
pub(crate) fn face_run(run: &[Vec4]) -> [Vec4; 2] {
    let (lo, hi) = run.iter().fold((Vec4::INFINITY, Vec4::NEG_INFINITY), |(lo, hi), &p| (lo.min(p), hi.max(p)));
    // A plane with an infinite or NaN component has a NaN facing value wherever a light component it
    // meets is zero, and `min` and `max` pass NaN over: its run stays undecided.
    if run.iter().all(|p| p.is_finite()) { [lo, hi] } else { [Vec4::NAN; 2] }
}

/// The face runs of the faces of one run of manifold edges.
pub(crate) fn edge_run(run: &[[u32; 2]]) -> EdgeRun {
    let mut runs = [(run[0][0] as usize / FACES) as u32; SPREAD];
    let mut len = 1;
    for f in run.iter().flatten() {
        let r = (*f as usize / FACES) as u32;
        if !runs[..len].contains(&r) {
            if len == SPREAD {
                return None;
            }
            runs[len] = r;
            len += 1;
        }
    }
    Some(runs)
}

/// One mesh's bounds for [`Facing`] decisions over runs of faces and of manifold edges: per run of
/// [`FACES`] faces, [`face_run`]; per run of [`EDGES`] manifold edges, [`edge_run`].
#[derive(Clone, Copy, Debug)]
pub(crate) struct FacingRuns<'a> {
    pub(crate) planes: &'a [[Vec4; 2]],
    pub(crate) edges: &'a [EdgeRun],
}

impl FacingRuns<'_> {
    /// The facing of every run of faces towards `light`.
    pub(crate) fn facing(&self, light: LightSource) -> Vec<Facing> {
        // The facing value of a plane as a dot product with the light in homogeneous form: (l, 1) for a
        // point light; (-d, 0) for parallel light along d.
        let h = match light {
            LightSource::Point(l) => l.as_dvec3().extend(1.0),
            LightSource::Directional(d) => (-d.as_dvec3()).extend(0.0),
        };
        self.planes.par_iter().with_min_len(256).map(|&[lo, hi]| run_facing(lo.as_dvec4(), hi.as_dvec4(), h)).collect()
    }

    /// True when every face of every edge in edge run `run` lies in a face run of one decided facing, so
    /// every such face has the same weight.
    pub(crate) fn edges_uniform(&self, run: usize, facing: &[Facing]) -> bool {
        self.edges[run].is_some_and(|runs| {
            let first = facing[runs[0] as usize];
            first != Facing::Mixed && runs.iter().all(|&r| facing[r as usize] == first)
        })
    }
}

/// The facing of planes bounded componentwise by `lo` and `hi` towards the homogeneous light `h`.
fn run_facing(lo: DVec4, hi: DVec4, h: DVec4) -> Facing {
    if !(lo.is_finite() && hi.is_finite() && h.is_finite()) {
        return Facing::Mixed;
    }
    // Each term's interval; products of f32 values are exact in f64.
    let (a, b) = (lo * h, hi * h);
    let (least, most) = (a.min(b).element_sum(), a.max(b).element_sum());
    let magnitude = (lo.abs().max(hi.abs()) * h.abs()).element_sum();
    // gamma_4 is 2.4e-7; 2^-20 (9.5e-7) covers it and the f64 sums' own rounding many times over. The
    // absolute term covers products that underflow into subnormals, each off by at most 2^-150.
    let margin = magnitude * 2f64.powi(-20) + 2f64.powi(-120);
    if least > margin {
        Facing::Front
    } else if most < -margin {
        Facing::Back
    } else {
        Facing::Mixed
    }
}
