//! Small meshes' adjacencies built on one thread, many into one store: the lists [`super::build`] gives
//! each mesh, in the same order, with no step split over threads and the scratch space (a weld table,
//! the edges' sort) reused from mesh to mesh.

use std::sync::Arc;

use super::build::{self, COMPONENT_RUN};
use super::{Adjacency, FaceUse, Part, SMALL, Store};
use crate::bounds::Aabb;
use crate::geometry::facing::{self, EDGES, FACES};
use crate::geometry::weld::{WeldTable, weld_alone_into};
use crate::mesh::Mesh;

// One run of component bounds covers every face of a small mesh, as one thread's chunk does in the
// build on all threads, so the bounds are merged in the same order.
const _: () = assert!(SMALL <= COMPONENT_RUN);

/// Space a batch reuses from mesh to mesh.
#[derive(Default)]
struct Scratch {
    table: WeldTable,
    /// Each edge use of the mesh's faces, as `(lower, higher << 32 | use)`: the words the build on all
    /// threads sorts per lower vertex.
    uses: Vec<(u32, u64)>,
    /// One edge's uses.
    edge: Vec<u64>,
    /// Runs of faces of one component and their bounds.
    runs: Vec<(u32, Aabb)>,
}

/// The adjacencies of `meshes` (each [`super::is_small`]), built on this thread into one store.
pub(super) fn build_batch(meshes: &[&Mesh]) -> Vec<Adjacency> {
    let mut store = Store::default();
    let (vertices, faces) = meshes.iter().fold((0, 0), |(v, f), m| (v + m.positions().len(), f + m.triangle_count()));
    store.positions.reserve(vertices);
    store.remap.reserve_exact(vertices);
    store.triangles.reserve_exact(faces);
    store.planes.reserve_exact(faces);
    store.degenerate.reserve_exact(faces);
    store.component.reserve_exact(faces);
    let mut scratch = Scratch::default();
    let parts: Vec<Part> = meshes
        .iter()
        .map(|mesh| {
            let before = store.whole_part();
            add(&mut store, &mut scratch, mesh);
            store.part_since(&before)
        })
        .collect();
    let store = Arc::new(store);
    parts.into_iter().map(|part| Adjacency { store: Arc::clone(&store), part }).collect()
}

/// Appends one mesh's adjacency to the store's lists.
fn add(store: &mut Store, scratch: &mut Scratch, mesh: &Mesh) {
    let (v0, r0, f0) = (store.positions.len(), store.remap.len(), store.triangles.len());
    weld_alone_into(mesh.positions(), &mut scratch.table, &mut store.positions, &mut store.remap);
    let (positions, remap) = (&store.positions[v0..], &store.remap[r0..]);
    for &m in mesh.triangles() {
        let (t, d, plane) = build::face(m, remap, positions);
        store.triangles.push(t);
        store.degenerate.push(d);
        store.planes.push(plane);
    }
    let (triangles, degenerate) = (&store.triangles[f0..], &store.degenerate[f0..]);

    // Edges, by lower endpoint, then higher, then use.
    let (m0, x0) = (store.manifold.len(), store.lists.complex.len());
    let uses = &mut scratch.uses;
    uses.clear();
    for (f, (t, &d)) in triangles.iter().zip(degenerate).enumerate() {
        if d {
            continue;
        }
        for k in 0..3 {
            // The face runs from corner k up to the corner after it, and down to k from the one before.
            let (lower, after, before) = (t[k], t[(k + 1) % 3], t[(k + 2) % 3]);
            if after > lower {
                uses.push((lower, u64::from(after) << 32 | u64::from(FaceUse::new(f as u32, false).0)));
            }
            if before > lower {
                uses.push((lower, u64::from(before) << 32 | u64::from(FaceUse::new(f as u32, true).0)));
            }
        }
    }
    uses.sort_unstable();
    for run in uses.chunk_by(|a, b| a.0 == b.0 && a.1 >> 32 == b.1 >> 32) {
        let v = [run[0].0, (run[0].1 >> 32) as u32];
        scratch.edge.clear();
        scratch.edge.extend(run.iter().map(|u| u.1));
        match build::manifold_faces_of(&scratch.edge) {
            Some(pair) => {
                store.manifold.push(v);
                store.manifold_faces.push(pair);
            }
            None => store.lists.add(v, &scratch.edge),
        }
    }

    // Components and their bounds.
    store.component.extend(0..triangles.len() as u32);
    let count =
        build::number_components(&mut store.component[f0..], &store.manifold_faces[m0..], &store.lists.complex[x0..]);
    scratch.runs.clear();
    build::component_runs(triangles, &store.component[f0..], positions, &mut scratch.runs);
    let b0 = store.component_bounds.len();
    store.component_bounds.resize(b0 + count as usize, Aabb::EMPTY);
    let bounds = &mut store.component_bounds[b0..];
    for &(c, b) in &scratch.runs {
        bounds[c as usize] = bounds[c as usize].union(b);
    }

    store.face_runs.extend(store.planes[f0..].chunks(FACES).map(facing::face_run));
    store.edge_runs.extend(store.manifold_faces[m0..].chunks(EDGES).map(facing::edge_run));
}
