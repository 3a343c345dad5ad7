//! Per-frame geometry on closed spheres of about 10k, 100k and 1M triangles: adjacency (once per mesh),
//! silhouette extraction and volume extrusion (every frame). `cargo bench -p shadow-core`.

use divan::Bencher;
use glam::Vec3;
use shadow_core::Mesh;
use shadow_core::geometry::LightSource;
use shadow_core::geometry::adjacency::Adjacency;
use shadow_core::geometry::silhouette::{CastMode, silhouette};
use shadow_core::geometry::volume::{Caps, extrude};
use shadow_core::procedural;

fn main() {
    divan::main();
}

const SIZES: [u32; 3] = [10_000, 100_000, 1_000_000];

/// A closed UV sphere with about `tris` triangles (segments x (2 rings - 2)).
fn sphere(tris: u32) -> Mesh {
    let segments = (tris as f32).sqrt().round() as u32;
    let rings = (tris / segments).div_ceil(2) + 1;
    procedural::sphere(1.0, segments, rings).expect("a sphere of the bench sizes")
}

/// `mesh` with its triangles in a fixed pseudo-random order (a multiplicative step coprime to the count).
fn scrambled(mesh: &Mesh) -> Mesh {
    let tris = mesh.triangles();
    let n = tris.len() as u64;
    let step = (0x9e37_79b9u64..).find(|s| gcd(*s, n) == 1).expect("a step coprime to the count");
    let order = (0..n).map(|i| tris[(i * step % n) as usize]).collect();
    Mesh::new(mesh.positions().to_vec(), order).expect("the same triangles")
}

fn gcd(a: u64, b: u64) -> u64 {
    if b == 0 { a } else { gcd(b, a % b) }
}

const LIGHT: LightSource = LightSource::Point(Vec3::new(2.0, 4.0, 1.5));

#[divan::bench(args = SIZES, sample_count = 10)]
fn adjacency(b: Bencher, tris: u32) {
    let mesh = sphere(tris);
    b.bench(|| Adjacency::build(divan::black_box(&mesh)));
}

#[divan::bench(args = SIZES, sample_count = 50)]
fn silhouette_extraction(b: Bencher, tris: u32) {
    let adj = Adjacency::build(&sphere(tris));
    b.bench(|| silhouette(divan::black_box(&adj), LIGHT, CastMode::Closed));
}

/// The same sphere with its faces in a scrambled order: no run of consecutive faces lies together, so
/// the silhouette pass decides no run at once and tests every face and edge (its worst case).
#[divan::bench(args = SIZES, sample_count = 50)]
fn silhouette_extraction_scrambled(b: Bencher, tris: u32) {
    let adj = Adjacency::build(&scrambled(&sphere(tris)));
    b.bench(|| silhouette(divan::black_box(&adj), LIGHT, CastMode::Closed));
}

#[divan::bench(args = SIZES, sample_count = 50)]
fn volume_extrusion(b: Bencher, tris: u32) {
    let adj = Adjacency::build(&sphere(tris));
    let sil = silhouette(&adj, LIGHT, CastMode::Closed);
    b.bench(|| extrude(divan::black_box(&adj), &sil, LIGHT, Caps::Both));
}
