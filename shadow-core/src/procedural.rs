//! Procedural meshes: plane, box, sphere, cylinder, cone, torus, capsule, lathe, prism, and implicit
//! surfaces by marching tetrahedra.
//!
//! Every solid is closed and wound counter-clockwise outside; its creases are made of duplicated vertices
//! (same position, separate normals), which adjacency welds back together.

use std::collections::HashMap;
use std::f32::consts::{PI, TAU};

use glam::{Vec2, Vec3};

use crate::mesh::Mesh;

/// Builders only produce valid meshes; a failure here is a bug in this module.
fn build(positions: Vec<Vec3>, triangles: Vec<[u32; 3]>) -> Mesh {
    match Mesh::new(positions, triangles) {
        Ok(m) => m,
        Err(e) => panic!("procedural mesh is invalid: {e}"),
    }
}

/// A `width x depth` rectangle in the XZ plane, centred at the origin, facing +Y. Open: two triangles.
#[must_use]
pub fn plane(width: f32, depth: f32) -> Mesh {
    let (w, d) = (width * 0.5, depth * 0.5);
    let p = vec![Vec3::new(-w, 0.0, -d), Vec3::new(-w, 0.0, d), Vec3::new(w, 0.0, d), Vec3::new(w, 0.0, -d)];
    build(p, vec![[0, 1, 2], [0, 2, 3]])
}

/// An axis-aligned box of the given size centred at the origin, flat-shaded (24 vertices, 12 triangles).
#[must_use]
pub fn cuboid(size: Vec3) -> Mesh {
    let h = size * 0.5;
    let mut positions = Vec::with_capacity(24);
    let mut triangles = Vec::with_capacity(12);
    // Each face: its normal axis and two in-plane axes (u x v = normal) so the quad winds outward.
    for (n, u, v) in [
        (Vec3::X, Vec3::NEG_Z, Vec3::Y),
        (Vec3::NEG_X, Vec3::Z, Vec3::Y),
        (Vec3::Y, Vec3::X, Vec3::NEG_Z),
        (Vec3::NEG_Y, Vec3::X, Vec3::Z),
        (Vec3::Z, Vec3::X, Vec3::Y),
        (Vec3::NEG_Z, Vec3::NEG_X, Vec3::Y),
    ] {
        let base = positions.len() as u32;
        for (su, sv) in [(-1.0, -1.0), (1.0, -1.0), (1.0, 1.0), (-1.0, 1.0)] {
            positions.push((n + u * su + v * sv) * h);
        }
        triangles.push([base, base + 1, base + 2]);
        triangles.push([base, base + 2, base + 3]);
    }
    build(positions, triangles)
}

/// A solid of revolution about +Y. `profile` lists (radius, height) points; the solid lies to the left of
/// the profile's direction in the (radius, height) plane (so run it bottom to top on the outside). A point
/// with radius 0 becomes a pole; a point repeated makes a crease (duplicated vertices, separate normals).
/// With `closed_profile` the last point connects back to the first (a torus).
#[must_use]
pub fn lathe(profile: &[Vec2], segments: u32, closed_profile: bool) -> Mesh {
    let segments = segments.max(3);
    let mut positions = Vec::new();
    // Ring i: its first vertex, and whether it is a single pole vertex.
    let mut rings: Vec<(u32, bool)> = Vec::with_capacity(profile.len());
    for p in profile {
        let start = positions.len() as u32;
        if p.x == 0.0 {
            positions.push(Vec3::new(0.0, p.y, 0.0));
            rings.push((start, true));
        } else {
            for j in 0..segments {
                let t = TAU * j as f32 / segments as f32;
                positions.push(Vec3::new(p.x * t.cos(), p.y, -p.x * t.sin()));
            }
            rings.push((start, false));
        }
    }
    let vertex = |ring: (u32, bool), j: u32| if ring.1 { ring.0 } else { ring.0 + j % segments };
    let mut triangles = Vec::new();
    let n = profile.len();
    let spans = if closed_profile { n } else { n - 1 };
    for i in 0..spans {
        let (lo, hi) = (i, (i + 1) % n);
        if profile[lo] == profile[hi] || (rings[lo].1 && rings[hi].1) {
            continue; // crease or pole-to-pole: no faces
        }
        for j in 0..segments {
            let (a, b) = (vertex(rings[lo], j), vertex(rings[lo], j + 1));
            let (c, d) = (vertex(rings[hi], j + 1), vertex(rings[hi], j));
            if !rings[lo].1 {
                triangles.push([a, b, c]);
            }
            if !rings[hi].1 {
                triangles.push([a, c, d]);
            }
        }
    }
    build(positions, triangles)
}

/// A UV sphere centred at the origin.
#[must_use]
pub fn sphere(radius: f32, segments: u32, rings: u32) -> Mesh {
    let rings = rings.max(2);
    let profile: Vec<Vec2> = (0..=rings)
        .map(|i| {
            let phi = PI * i as f32 / rings as f32;
            let r = if i == 0 || i == rings { 0.0 } else { radius * phi.sin() };
            Vec2::new(r, -radius * phi.cos())
        })
        .collect();
    lathe(&profile, segments, false)
}

/// A capped cylinder standing on y = 0, flat caps.
#[must_use]
pub fn cylinder(radius: f32, height: f32, segments: u32) -> Mesh {
    let (r, h) = (radius, height);
    let profile = [(0.0, 0.0), (r, 0.0), (r, 0.0), (r, h), (r, h), (0.0, h)].map(Vec2::from);
    lathe(&profile, segments, false)
}

/// A cone standing on y = 0 with its apex at y = height.
#[must_use]
pub fn cone(radius: f32, height: f32, segments: u32) -> Mesh {
    let profile = [(0.0, 0.0), (radius, 0.0), (radius, 0.0), (0.0, height)].map(Vec2::from);
    lathe(&profile, segments, false)
}

/// A torus about +Y centred at the origin: ring radius `major`, tube radius `minor`.
#[must_use]
pub fn torus(major: f32, minor: f32, segments: u32, sides: u32) -> Mesh {
    let sides = sides.max(3);
    let profile: Vec<Vec2> = (0..sides)
        .map(|i| {
            let t = TAU * i as f32 / sides as f32;
            Vec2::new(major + minor * t.cos(), minor * t.sin())
        })
        .collect();
    lathe(&profile, segments, true)
}

/// A capsule along +Y from y = 0 to y = `height` (caps included).
#[must_use]
pub fn capsule(radius: f32, height: f32, segments: u32, cap_rings: u32) -> Mesh {
    let cap_rings = cap_rings.max(2);
    let body = (height - 2.0 * radius).max(0.0);
    let mut profile = Vec::new();
    for i in 0..=cap_rings {
        let phi = 0.5 * PI * i as f32 / cap_rings as f32;
        let r = if i == 0 { 0.0 } else { radius * phi.sin() };
        profile.push(Vec2::new(r, radius - radius * phi.cos()));
    }
    for i in 0..=cap_rings {
        let phi = 0.5 * PI * i as f32 / cap_rings as f32;
        let r = if i == cap_rings { 0.0 } else { radius * phi.cos() };
        profile.push(Vec2::new(r, radius + body + radius * phi.sin()));
    }
    lathe(&profile, segments, false)
}

/// A prism: a polygon in the XZ plane (counter-clockwise seen from +Y) extruded from y = 0 to `height`.
/// The caps are fanned from vertex `fan_from`, which must see the whole polygon (any vertex of a convex
/// polygon; the reflex vertex of an L).
#[must_use]
pub fn prism(outline: &[Vec2], fan_from: usize, height: f32) -> Mesh {
    let n = outline.len();
    let mut positions = Vec::new();
    let mut triangles = Vec::new();
    // Caps: bottom faces -Y (reverse order), top faces +Y.
    for (y, top) in [(0.0, false), (height, true)] {
        let base = positions.len() as u32;
        positions.extend(outline.iter().map(|p| Vec3::new(p.x, y, p.y)));
        for k in 1..n - 1 {
            let (i, j) = ((fan_from + k) % n, (fan_from + k + 1) % n);
            let (a, b, c) = (base + fan_from as u32, base + i as u32, base + j as u32);
            // Counter-clockwise seen from +Y means (b - a) x (c - a) points up: the top cap as is.
            triangles.push(if top { [a, b, c] } else { [a, c, b] });
        }
    }
    // Sides: one flat quad per outline edge.
    for i in 0..n {
        let (p, q) = (outline[i], outline[(i + 1) % n]);
        let base = positions.len() as u32;
        positions.extend([
            Vec3::new(p.x, 0.0, p.y),
            Vec3::new(q.x, 0.0, q.y),
            Vec3::new(q.x, height, q.y),
            Vec3::new(p.x, height, p.y),
        ]);
        triangles.push([base, base + 1, base + 2]);
        triangles.push([base, base + 2, base + 3]);
    }
    build(positions, triangles)
}

/// The isosurface f = 0 of an implicit solid (f < 0 inside) over a box, by marching tetrahedra on a grid
/// of `cells` cubes along the longest side, each cut into six tetrahedra around its main diagonal (the cut
/// agrees across shared faces, so the surface is watertight). Returns `None` if the surface is empty.
/// Normals are the normalized gradient of f.
pub fn implicit(f: impl Fn(Vec3) -> f32, lo: Vec3, hi: Vec3, cells: u32) -> Option<Mesh> {
    let size = hi - lo;
    let h = size.max_element() / cells.max(1) as f32;
    let dims = (size / h).ceil().as_uvec3().max(glam::UVec3::ONE);
    let (nx, ny) = (dims.x + 1, dims.y + 1);
    let node = |x: u32, y: u32, z: u32| -> u32 { x + nx * (y + ny * z) };
    let node_pos = |i: u32| {
        let (x, y, z) = (i % nx, (i / nx) % ny, i / (nx * ny));
        lo + Vec3::new(x as f32, y as f32, z as f32) * h
    };
    let mut values = vec![0.0f32; (nx * ny * (dims.z + 1)) as usize];
    for (i, v) in values.iter_mut().enumerate() {
        *v = f(node_pos(i as u32));
    }
    // Zero counts as outside so no surface vertex lands on a grid node.
    let inside = |i: u32| values[i as usize] < 0.0;
    let mut positions: Vec<Vec3> = Vec::new();
    let mut on_edge: HashMap<(u32, u32), u32> = HashMap::new();
    let mut edge_vertex = |a: u32, b: u32, positions: &mut Vec<Vec3>| -> u32 {
        let key = (a.min(b), a.max(b));
        *on_edge.entry(key).or_insert_with(|| {
            let (fa, fb) = (values[key.0 as usize], values[key.1 as usize]);
            let t = (fa / (fa - fb)).clamp(0.01, 0.99);
            positions.push(node_pos(key.0).lerp(node_pos(key.1), t));
            positions.len() as u32 - 1
        })
    };
    // Kuhn's six tetrahedra of a cube with corners numbered by bits (x = 1, y = 2, z = 4).
    const TETS: [[usize; 4]; 6] = [[0, 1, 3, 7], [0, 3, 2, 7], [0, 2, 6, 7], [0, 6, 4, 7], [0, 4, 5, 7], [0, 5, 1, 7]];
    let mut triangles: Vec<[u32; 3]> = Vec::new();
    for z in 0..dims.z {
        for y in 0..dims.y {
            for x in 0..dims.x {
                let corner = |c: usize| node(x + (c as u32 & 1), y + ((c as u32 >> 1) & 1), z + ((c as u32 >> 2) & 1));
                for tet in TETS {
                    let v = tet.map(corner);
                    let (ins, outs): (Vec<u32>, Vec<u32>) = v.iter().partition(|&&i| inside(i));
                    if ins.is_empty() || outs.is_empty() {
                        continue;
                    }
                    let polygon: Vec<u32> = match (ins.len(), outs.len()) {
                        (1, 3) => outs.iter().map(|&o| edge_vertex(ins[0], o, &mut positions)).collect(),
                        (3, 1) => ins.iter().map(|&i| edge_vertex(i, outs[0], &mut positions)).collect(),
                        _ => [(ins[0], outs[0]), (ins[0], outs[1]), (ins[1], outs[1]), (ins[1], outs[0])]
                            .iter()
                            .map(|&(i, o)| edge_vertex(i, o, &mut positions))
                            .collect(),
                    };
                    // Orient outward: along the direction from the inside corners to the outside ones.
                    let centroid = |s: &[u32]| s.iter().map(|&i| node_pos(i)).sum::<Vec3>() / s.len() as f32;
                    let out_dir = centroid(&outs) - centroid(&ins);
                    for k in 1..polygon.len() - 1 {
                        let t = [polygon[0], polygon[k], polygon[k + 1]];
                        let n = crate::mesh::face_normal(t.map(|i| positions[i as usize]));
                        triangles.push(if n.dot(out_dir) >= 0.0 { t } else { [t[0], t[2], t[1]] });
                    }
                }
            }
        }
    }
    if triangles.is_empty() {
        return None;
    }
    let e = h * 0.25;
    let normals = positions
        .iter()
        .map(|&p| {
            let g = Vec3::new(
                f(p + Vec3::X * e) - f(p - Vec3::X * e),
                f(p + Vec3::Y * e) - f(p - Vec3::Y * e),
                f(p + Vec3::Z * e) - f(p - Vec3::Z * e),
            );
            g.normalize_or_zero()
        })
        .collect();
    Mesh::with_normals(positions, normals, triangles).ok()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geometry::adjacency::Adjacency;

    /// Signed volume by the divergence theorem: positive for outward winding.
    fn volume(m: &Mesh) -> f32 {
        (0..m.triangle_count())
            .map(|t| {
                let [a, b, c] = m.triangle_positions(t);
                a.dot(b.cross(c)) / 6.0
            })
            .sum()
    }

    #[test]
    fn solids_are_closed_with_the_right_volume() {
        let cases: [(Mesh, f32, f32); 6] = [
            (cuboid(Vec3::new(1.0, 2.0, 3.0)), 6.0, 1e-5),
            (sphere(1.0, 64, 32), 4.0 / 3.0 * PI, 0.01),
            (cylinder(0.5, 2.0, 64), PI * 0.25 * 2.0, 0.01),
            (cone(1.0, 3.0, 64), PI / 3.0 * 3.0, 0.01),
            (torus(1.0, 0.25, 64, 32), 2.0 * PI * PI * 0.0625, 0.01),
            (capsule(0.5, 3.0, 48, 12), PI * 0.25 * 2.0 + 4.0 / 3.0 * PI * 0.125, 0.01),
        ];
        for (i, (mesh, expected, tol)) in cases.iter().enumerate() {
            let adj = Adjacency::build(mesh);
            assert!(adj.closed(), "case {i} not closed");
            let v = volume(mesh);
            assert!((v - expected).abs() / expected < *tol, "case {i}: volume {v}, expected {expected}");
        }
    }

    #[test]
    fn l_prism_is_closed() {
        let l = [(0.0, 0.0), (2.0, 0.0), (2.0, -1.0), (1.0, -1.0), (1.0, -2.0), (0.0, -2.0)].map(Vec2::from);
        let m = prism(&l, 3, 1.0);
        assert!(Adjacency::build(&m).closed());
        assert!((volume(&m) - 3.0).abs() < 1e-5);
    }

    #[test]
    fn implicit_sphere_is_closed() {
        let m = implicit(|p| p.length() - 1.0, Vec3::splat(-1.3), Vec3::splat(1.3), 20).unwrap();
        let adj = Adjacency::build(&m);
        assert!(adj.closed(), "boundary {} complex {}", adj.boundary_edge_count(), adj.complex_edges().len());
        assert!((volume(&m) - 4.0 / 3.0 * PI).abs() < 0.1);
    }
}
