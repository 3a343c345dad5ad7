//! Procedural meshes: plane, box, sphere, cylinder, cone, torus, capsule, lathe, prism, and implicit
//! surfaces by marching tetrahedra.
//!
//! Every solid is closed and wound counter-clockwise outside; its creases are made of duplicated vertices
//! (same position, separate normals), which adjacency welds back together.

use std::collections::HashMap;
use std::f32::consts::{PI, TAU};

use glam::{Vec2, Vec3};

use crate::mesh::{Mesh, MeshError};

/// The most vertices a procedural mesh may have: 2^26 (some 2.3 GB with its triangles), so that a
/// mistaken parameter is refused before it is allocated.
pub const MAX_SHAPE_VERTICES: u64 = 1 << 26;

/// Why a procedural mesh could not be built.
#[derive(Debug, thiserror::Error)]
pub enum ShapeError {
    /// A parameter out of its range.
    #[error("{shape}: {what} = {value}: {why}")]
    Parameter {
        /// The shape asked for.
        shape: &'static str,
        /// The parameter.
        what: &'static str,
        /// Its value, printed.
        value: String,
        /// What it must be.
        why: &'static str,
    },
    /// The parameters ask for more than [`MAX_SHAPE_VERTICES`].
    #[error("{shape}: {vertices} vertices, over the limit of {}", MAX_SHAPE_VERTICES)]
    TooManyVertices {
        /// The shape asked for.
        shape: &'static str,
        /// The vertices it would have.
        vertices: u64,
    },
    /// The mesh made is refused (an implicit surface with no triangles, say).
    #[error("{shape}: {source}")]
    Mesh {
        /// The shape asked for.
        shape: &'static str,
        /// Why.
        source: MeshError,
    },
}

/// `value` for `what` of `shape`, refused unless finite and above zero.
fn positive(shape: &'static str, what: &'static str, value: f32) -> Result<f32, ShapeError> {
    if value.is_finite() && value > 0.0 {
        return Ok(value);
    }
    Err(ShapeError::Parameter { shape, what, value: value.to_string(), why: "must be finite and above 0" })
}

/// Refuses `vertices` over [`MAX_SHAPE_VERTICES`].
fn within_limit(shape: &'static str, vertices: u64) -> Result<(), ShapeError> {
    if vertices > MAX_SHAPE_VERTICES {
        return Err(ShapeError::TooManyVertices { shape, vertices });
    }
    Ok(())
}

fn build(shape: &'static str, positions: Vec<Vec3>, triangles: Vec<[u32; 3]>) -> Result<Mesh, ShapeError> {
    Mesh::new(positions, triangles).map_err(|source| ShapeError::Mesh { shape, source })
}

/// A `width x depth` rectangle in the XZ plane, centred at the origin, facing +Y. Open: two triangles.
///
/// # Errors
/// [`ShapeError::Parameter`] for a side not finite and above 0.
pub fn plane(width: f32, depth: f32) -> Result<Mesh, ShapeError> {
    let (w, d) = (positive("plane", "width", width)? * 0.5, positive("plane", "depth", depth)? * 0.5);
    let p = vec![Vec3::new(-w, 0.0, -d), Vec3::new(-w, 0.0, d), Vec3::new(w, 0.0, d), Vec3::new(w, 0.0, -d)];
    build("plane", p, vec![[0, 1, 2], [0, 2, 3]])
}

/// An axis-aligned box of the given size centred at the origin, flat-shaded (24 vertices, 12 triangles).
///
/// # Errors
/// [`ShapeError::Parameter`] for a side not finite and above 0.
pub fn cuboid(size: Vec3) -> Result<Mesh, ShapeError> {
    for (what, v) in [("size.x", size.x), ("size.y", size.y), ("size.z", size.z)] {
        positive("cuboid", what, v)?;
    }
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
    build("cuboid", positions, triangles)
}

/// A solid of revolution about +Y. `profile` lists (radius, height) points; the solid lies to the left of
/// the profile's direction in the (radius, height) plane (so run it bottom to top on the outside). A point
/// with radius 0 becomes a pole; a point repeated makes a crease (duplicated vertices, separate normals).
/// With `closed_profile` the last point connects back to the first (a torus). At least 3 segments.
///
/// # Errors
/// [`ShapeError::Parameter`] for fewer than two profile points, or one not finite or of a negative
/// radius; [`ShapeError::TooManyVertices`] past [`MAX_SHAPE_VERTICES`]; [`ShapeError::Mesh`] for a
/// profile that sweeps no area.
pub fn lathe(profile: &[Vec2], segments: u32, closed_profile: bool) -> Result<Mesh, ShapeError> {
    lathed("lathe", profile, segments, closed_profile)
}

/// [`lathe`], its errors naming `shape`.
fn lathed(shape: &'static str, profile: &[Vec2], segments: u32, closed_profile: bool) -> Result<Mesh, ShapeError> {
    let segments = segments.max(3);
    let point = |what, value: String, why| Err(ShapeError::Parameter { shape, what, value, why });
    if profile.len() < 2 {
        return point("profile", format!("{} points", profile.len()), "needs at least 2");
    }
    if let Some(p) = profile.iter().find(|p| !p.is_finite() || p.x < 0.0) {
        return point("profile point", format!("{p}"), "must be finite with a radius of 0 or more");
    }
    within_limit(shape, profile.iter().map(|p| if p.x == 0.0 { 1 } else { u64::from(segments) }).sum())?;
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
    build(shape, positions, triangles)
}

/// A UV sphere centred at the origin; at least 3 segments and 2 rings.
///
/// # Errors
/// [`ShapeError::Parameter`] for a radius not finite and above 0, [`ShapeError::TooManyVertices`] past
/// [`MAX_SHAPE_VERTICES`].
pub fn sphere(radius: f32, segments: u32, rings: u32) -> Result<Mesh, ShapeError> {
    let radius = positive("sphere", "radius", radius)?;
    let rings = rings.max(2);
    // Checked before the profile is made: its rings alone could exhaust memory (lathe checks again, exactly).
    within_limit("sphere", u64::from(rings) * u64::from(segments.max(3)))?;
    let profile: Vec<Vec2> = (0..=rings)
        .map(|i| {
            let phi = PI * i as f32 / rings as f32;
            let r = if i == 0 || i == rings { 0.0 } else { radius * phi.sin() };
            Vec2::new(r, -radius * phi.cos())
        })
        .collect();
    lathed("sphere", &profile, segments, false)
}

/// A capped cylinder standing on y = 0, flat caps; at least 3 segments.
///
/// # Errors
/// [`ShapeError::Parameter`] for a radius or height not finite and above 0,
/// [`ShapeError::TooManyVertices`] past [`MAX_SHAPE_VERTICES`].
pub fn cylinder(radius: f32, height: f32, segments: u32) -> Result<Mesh, ShapeError> {
    let (r, h) = (positive("cylinder", "radius", radius)?, positive("cylinder", "height", height)?);
    let profile = [(0.0, 0.0), (r, 0.0), (r, 0.0), (r, h), (r, h), (0.0, h)].map(Vec2::from);
    lathed("cylinder", &profile, segments, false)
}

/// A cone standing on y = 0 with its apex at y = height; at least 3 segments.
///
/// # Errors
/// As [`cylinder`].
pub fn cone(radius: f32, height: f32, segments: u32) -> Result<Mesh, ShapeError> {
    let (r, h) = (positive("cone", "radius", radius)?, positive("cone", "height", height)?);
    let profile = [(0.0, 0.0), (r, 0.0), (r, 0.0), (0.0, h)].map(Vec2::from);
    lathed("cone", &profile, segments, false)
}

/// A torus about +Y centred at the origin: ring radius `major`, tube radius `minor`; at least 3 segments
/// and 3 sides.
///
/// # Errors
/// [`ShapeError::Parameter`] for radii not finite and above 0, or a tube as wide as the ring or wider
/// (it would cross the axis); [`ShapeError::TooManyVertices`] past [`MAX_SHAPE_VERTICES`].
pub fn torus(major: f32, minor: f32, segments: u32, sides: u32) -> Result<Mesh, ShapeError> {
    let (major, minor) = (positive("torus", "major", major)?, positive("torus", "minor", minor)?);
    if minor >= major {
        let why = "must be below the ring radius (major)";
        return Err(ShapeError::Parameter { shape: "torus", what: "minor", value: minor.to_string(), why });
    }
    let sides = sides.max(3);
    // As sphere's: before the profile is made.
    within_limit("torus", u64::from(sides) * u64::from(segments.max(3)))?;
    let profile: Vec<Vec2> = (0..sides)
        .map(|i| {
            let t = TAU * i as f32 / sides as f32;
            Vec2::new(major + minor * t.cos(), minor * t.sin())
        })
        .collect();
    lathed("torus", &profile, segments, true)
}

/// A capsule along +Y from y = 0 to y = `height` (caps included; the body is `height - 2 radius`, none
/// when that is not above 0); at least 3 segments and 2 rings a cap.
///
/// # Errors
/// [`ShapeError::Parameter`] for a radius or height not finite and above 0,
/// [`ShapeError::TooManyVertices`] past [`MAX_SHAPE_VERTICES`].
pub fn capsule(radius: f32, height: f32, segments: u32, cap_rings: u32) -> Result<Mesh, ShapeError> {
    let (radius, height) = (positive("capsule", "radius", radius)?, positive("capsule", "height", height)?);
    let cap_rings = cap_rings.max(2);
    // As sphere's: before the profile is made.
    within_limit("capsule", 2 * (u64::from(cap_rings) + 1) * u64::from(segments.max(3)))?;
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
    lathed("capsule", &profile, segments, false)
}

/// A prism: a polygon in the XZ plane (counter-clockwise seen from +Y) extruded from y = 0 to `height`.
/// The caps are fanned from vertex `fan_from`, which must see the whole polygon (any vertex of a convex
/// polygon; the reflex vertex of an L).
///
/// # Errors
/// [`ShapeError::Parameter`] for fewer than 3 outline points or one not finite, `fan_from` not one of
/// them, or a height not finite and above 0; [`ShapeError::TooManyVertices`] past
/// [`MAX_SHAPE_VERTICES`].
pub fn prism(outline: &[Vec2], fan_from: usize, height: f32) -> Result<Mesh, ShapeError> {
    let n = outline.len();
    let bad = |what, value: String, why| Err(ShapeError::Parameter { shape: "prism", what, value, why });
    if n < 3 {
        return bad("outline", format!("{n} points"), "needs at least 3");
    }
    if let Some(p) = outline.iter().find(|p| !p.is_finite()) {
        return bad("outline point", format!("{p}"), "must be finite");
    }
    if fan_from >= n {
        return bad("fan_from", fan_from.to_string(), "must be the index of an outline point");
    }
    let height = positive("prism", "height", height)?;
    within_limit("prism", 6 * n as u64)?;
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
    build("prism", positions, triangles)
}

/// The isosurface f = 0 of an implicit solid (f < 0 inside) over a box, by marching tetrahedra on a grid
/// of `cells` cubes along the longest side, each cut into six tetrahedra around its main diagonal (the cut
/// agrees across shared faces, so the surface is watertight). Normals are the normalized gradient of f.
///
/// # Errors
/// [`ShapeError::Parameter`] for a box not finite or empty along an axis, or no cells;
/// [`ShapeError::TooManyVertices`] for a grid of more nodes than [`MAX_SHAPE_VERTICES`];
/// [`ShapeError::Mesh`] ([`MeshError::Empty`]) where the surface does not cross the box.
pub fn implicit(f: impl Fn(Vec3) -> f32, lo: Vec3, hi: Vec3, cells: u32) -> Result<Mesh, ShapeError> {
    let bad = |what, value: String, why| Err(ShapeError::Parameter { shape: "implicit", what, value, why });
    if !lo.is_finite() || !hi.is_finite() || lo.cmpge(hi).any() {
        return bad("box", format!("{lo} to {hi}"), "must be finite, its high corner above its low one on every axis");
    }
    if cells == 0 {
        return bad("cells", "0".into(), "must be at least 1");
    }
    let size = hi - lo;
    let h = size.max_element() / cells as f32;
    let dims = (size / h).ceil().as_uvec3().max(glam::UVec3::ONE);
    within_limit("implicit", (dims.as_u64vec3() + 1).element_product())?;
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
        return Err(ShapeError::Mesh { shape: "implicit", source: MeshError::Empty });
    }
    let normals = positions.iter().map(|&p| gradient_direction(&f, p, h * 0.25)).collect();
    Mesh::with_normals(positions, normals, triangles).map_err(|source| ShapeError::Mesh { shape: "implicit", source })
}

/// The direction of `f`'s gradient at `p`, by central differences `e` apart (zero where it vanishes).
fn gradient_direction(f: &impl Fn(Vec3) -> f32, p: Vec3, e: f32) -> Vec3 {
    let g = Vec3::new(
        f(p + Vec3::X * e) - f(p - Vec3::X * e),
        f(p + Vec3::Y * e) - f(p - Vec3::Y * e),
        f(p + Vec3::Z * e) - f(p - Vec3::Z * e),
    );
    g.normalize_or_zero()
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
            (cuboid(Vec3::new(1.0, 2.0, 3.0)).expect("shape"), 6.0, 1e-5),
            (sphere(1.0, 64, 32).expect("shape"), 4.0 / 3.0 * PI, 0.01),
            (cylinder(0.5, 2.0, 64).expect("shape"), PI * 0.25 * 2.0, 0.01),
            (cone(1.0, 3.0, 64).expect("shape"), PI / 3.0 * 3.0, 0.01),
            (torus(1.0, 0.25, 64, 32).expect("shape"), 2.0 * PI * PI * 0.0625, 0.01),
            (capsule(0.5, 3.0, 48, 12).expect("shape"), PI * 0.25 * 2.0 + 4.0 / 3.0 * PI * 0.125, 0.01),
        ];
        for (i, (mesh, expected, tol)) in cases.iter().enumerate() {
            let adj = Adjacency::build(mesh);
            assert!(adj.closed(), "case {i} not closed");
            let v = volume(mesh);
            assert!((v - expected).abs() / expected < *tol, "case {i}: volume {v}, expected {expected}");
        }
    }

    #[test]
    fn bad_parameters_are_refused_naming_the_shape_and_the_value() {
        let l = [Vec2::ZERO, Vec2::X, Vec2::ONE];
        let tilted = |f: &dyn Fn(Vec3) -> f32| implicit(f, Vec3::splat(-1.0), Vec3::splat(1.0), 8);
        let cases: [(Result<Mesh, ShapeError>, &str); 14] = [
            (plane(0.0, 1.0), "plane: width = 0: must be finite and above 0"),
            (plane(1.0, f32::NAN), "plane: depth = NaN"),
            (cuboid(Vec3::new(1.0, -1.0, 1.0)), "cuboid: size.y = -1"),
            (sphere(f32::INFINITY, 8, 4), "sphere: radius = inf"),
            (cylinder(0.5, 0.0, 8), "cylinder: height = 0"),
            (cone(-1.0, 1.0, 8), "cone: radius = -1"),
            (torus(0.2, 0.3, 8, 8), "torus: minor = 0.3: must be below the ring radius"),
            (capsule(0.0, 1.0, 8, 2), "capsule: radius = 0"),
            (lathe(&[Vec2::Y], 8, false), "lathe: profile = 1 points: needs at least 2"),
            (lathe(&[Vec2::ZERO, Vec2::new(-1.0, 1.0)], 8, false), "lathe: profile point = [-1, 1]"),
            (prism(&l[..2], 0, 1.0), "prism: outline = 2 points: needs at least 3"),
            (prism(&l, 3, 1.0), "prism: fan_from = 3: must be the index of an outline point"),
            (tilted(&|p| p.length() + 1.0), "implicit: mesh has no triangles"),
            (implicit(|p| p.length() - 0.5, Vec3::ONE, Vec3::ONE, 8), "implicit: box = [1, 1, 1] to [1, 1, 1]"),
        ];
        for (shape, words) in cases {
            let e = shape.expect_err(words).to_string();
            assert!(e.starts_with(words), "'{e}' does not start with '{words}'");
        }
    }

    #[test]
    fn shapes_past_the_vertex_limit_are_refused_before_they_are_made() {
        // Each would take gigabytes: the test runs out of memory if the limit is not checked first.
        let huge = 1 << 20;
        for (shape, name) in [
            (sphere(1.0, huge, huge), "sphere"),
            (torus(1.0, 0.5, huge, huge), "torus"),
            (capsule(1.0, 4.0, huge, huge), "capsule"),
            (implicit(|p| p.length() - 1.0, Vec3::splat(-1.0), Vec3::splat(1.0), 1 << 12), "implicit"),
        ] {
            match shape {
                Err(ShapeError::TooManyVertices { shape, vertices }) => {
                    assert_eq!(shape, name);
                    assert!(vertices > MAX_SHAPE_VERTICES, "{name}: {vertices}");
                }
                other => panic!("{name}: {other:?}"),
            }
        }
        // The limit itself is allowed, one vertex more is not.
        assert!(within_limit("sphere", MAX_SHAPE_VERTICES).is_ok());
        assert!(within_limit("sphere", MAX_SHAPE_VERTICES + 1).is_err());
    }

    #[test]
    fn l_prism_is_closed() {
        let l = [(0.0, 0.0), (2.0, 0.0), (2.0, -1.0), (1.0, -1.0), (1.0, -2.0), (0.0, -2.0)].map(Vec2::from);
        let m = prism(&l, 3, 1.0).expect("shape");
        assert!(Adjacency::build(&m).closed());
        assert!((volume(&m) - 3.0).abs() < 1e-5);
    }

    #[test]
    fn implicit_sphere_is_closed() {
        let m = implicit(|p| p.length() - 1.0, Vec3::splat(-1.3), Vec3::splat(1.3), 20).expect("shape");
        let adj = Adjacency::build(&m);
        assert!(adj.closed(), "boundary {} complex {}", adj.boundary_edge_count(), adj.complex_edges().len());
        assert!((volume(&m) - 4.0 / 3.0 * PI).abs() < 0.1);
    }
}
