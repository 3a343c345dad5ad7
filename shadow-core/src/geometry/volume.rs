//! Shadow-volume extrusion to infinity with front and back caps (Crow 1977; Everitt-Kilgard 2002 for the
//! caps and the infinite extrusion; Bergeron 1986 for open meshes).
//!
//! The volume of a mesh is the set of faces that cast (the near cap), the sides swept by its silhouette
//! edges, and the near cap projected to infinity with its orientation reversed (the far cap). Vertices at
//! infinity are homogeneous with w = 0: `(p - light, 0)` for a point light, `(direction, 0)` for a
//! directional one, so nothing is far-clipped by a camera with an infinite far plane. Every triangle faces
//! out of the volume, so a ray entering the volume crosses a front face.
//!
//! The far cap is the reversed projection of the near cap rather than the projection of the faces turned
//! away from the light (Everitt-Kilgard's choice). The two are the same surface when the light is outside
//! every closed caster; ours stays right with the light inside a closed mesh (a room lit from within),
//! where the other choice leaves a cap at infinity that shadows everything.
//!
//! Caps are lists of the mesh's own triangles, not copies: backends draw near caps from the vertex and
//! index data the G-buffer pass used, so a lit surface and its near cap rasterize to bit-identical depths
//! (the invariance z-fail relies on). Faces cast turned around (Bergeron) are drawn with front and back
//! swapped instead of re-wound, for the same reason.
//!
//! Sides and caps come grouped by the mesh's connected components ([`VolumePiece`]): each group is a
//! closed volume of its own, the shadow of that component alone, whose count is zero wherever that
//! shadow is not. Counting draws may skip a piece where its bounds' shadow cannot reach.

use std::ops::Range;

use glam::Vec4;

use super::LightSource;
use super::adjacency::Adjacency;
use super::silhouette::Silhouette;
use crate::bounds::Aabb;

/// How stencil shadow volumes count (DESIGN 4).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum VolumeCounting {
    /// Crow / Heidmann: count volume faces in front of the surface; sides only. Wrong where the eye is in
    /// shadow or a volume crosses the near plane.
    ZPass,
    /// Everitt-Kilgard / Carmack: count faces behind the surface; needs both caps; right everywhere with an
    /// infinite far plane.
    ZFail,
}

/// Whether a volume needs caps: z-pass counts only the sides, z-fail needs both caps.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Caps {
    /// Sides only.
    None,
    /// Sides, near cap and far cap.
    Both,
}

/// One mesh's shadow volume for one light, in the mesh's space.
#[derive(Clone, Debug, PartialEq)]
pub struct ShadowVolume {
    /// Side triangles, outward-facing, with homogeneous vertices (w = 1 on the mesh, w = 0 at infinity).
    /// A silhouette edge of weight k contributes its quad k times.
    pub sides: Vec<[Vec4; 3]>,
    /// Faces that cast as wound: near caps as they are; far caps projected and reversed.
    pub caps_forward: Vec<u32>,
    /// Faces that cast turned around (Bergeron): near caps reversed; far caps projected as they are.
    pub caps_reversed: Vec<u32>,
    /// The light, in the mesh's space.
    pub light: LightSource,
    /// The connected components that cast, each with its runs of `sides`, `caps_forward` and
    /// `caps_reversed`: together they cover all three.
    pub pieces: Vec<VolumePiece>,
}

/// The part of a [`ShadowVolume`] one connected component of the mesh casts: a closed volume by itself.
#[derive(Clone, Debug, PartialEq)]
pub struct VolumePiece {
    /// Its run of [`ShadowVolume::sides`].
    pub sides: Range<u32>,
    /// Its run of [`ShadowVolume::caps_forward`].
    pub caps_forward: Range<u32>,
    /// Its run of [`ShadowVolume::caps_reversed`].
    pub caps_reversed: Range<u32>,
    /// The bounds of the component's vertices, in mesh space: the piece is the shadow of what lies in
    /// them, so it holds only points the light reaches through them.
    pub bounds: Aabb,
}

impl ShadowVolume {
    /// Triangles the rasterizer will see: sides plus a near and a far cap per casting face.
    #[must_use]
    pub fn triangle_count(&self) -> usize {
        self.sides.len() + 2 * (self.caps_forward.len() + self.caps_reversed.len())
    }

    /// Near-cap triangles, outward-facing, as homogeneous points (for tests and simple backends; real
    /// backends draw the mesh's own triangles, see the module notes).
    pub fn near_caps<'a>(&'a self, adj: &'a Adjacency) -> impl Iterator<Item = [Vec4; 3]> + 'a {
        let corner = |f: u32| adj.triangles()[f as usize].map(|i| adj.positions()[i as usize].extend(1.0));
        let fwd = self.caps_forward.iter().map(move |&f| corner(f));
        let rev = self.caps_reversed.iter().map(move |&f| {
            let [a, b, c] = corner(f);
            [a, c, b]
        });
        fwd.chain(rev)
    }

    /// Far-cap triangles at infinity, outward-facing.
    pub fn far_caps<'a>(&'a self, adj: &'a Adjacency) -> impl Iterator<Item = [Vec4; 3]> + 'a {
        let light = self.light;
        let corner = move |f: u32| adj.triangles()[f as usize].map(|i| light.extrude(adj.positions()[i as usize]));
        let fwd = self.caps_forward.iter().map(move |&f| {
            let [a, b, c] = corner(f);
            [a, c, b]
        });
        let rev = self.caps_reversed.iter().map(move |&f| corner(f));
        fwd.chain(rev)
    }
}

/// Extrudes a silhouette into a shadow volume, grouped by connected component. `silhouette` must come
/// from [`super::silhouette::silhouette`] with the same adjacency and light.
#[must_use]
pub fn extrude(adj: &Adjacency, silhouette: &Silhouette, light: LightSource, caps: Caps) -> ShadowVolume {
    let p = adj.positions();
    let directional = matches!(light, LightSource::Directional(_));
    let mut sides = Vec::with_capacity(silhouette.weighted_len() * if directional { 1 } else { 2 });
    // The face each side comes from, for the grouping below (meshes of one component need none).
    let grouped = adj.component_bounds().len() > 1;
    let mut side_faces = Vec::with_capacity(if grouped { sides.capacity() } else { 0 });
    for e in &silhouette.edges {
        let (a, b) = (p[e.a as usize], p[e.b as usize]);
        let (a4, b4, a_inf, b_inf) = (a.extend(1.0), b.extend(1.0), light.extrude(a), light.extrude(b));
        for _ in 0..e.weight {
            // The outward quad (b, a, a_inf, b_inf); with parallel light a_inf = b_inf and it is one triangle.
            sides.push([b4, a4, a_inf]);
            if !directional {
                sides.push([b4, a_inf, b_inf]);
            }
        }
        if grouped {
            side_faces.resize(sides.len(), e.face);
        }
    }
    let (mut caps_forward, mut caps_reversed) = (Vec::new(), Vec::new());
    if caps == Caps::Both {
        for (f, &w) in silhouette.face_weights.iter().enumerate() {
            match w {
                1 => caps_forward.push(f as u32),
                -1 => caps_reversed.push(f as u32),
                _ => {}
            }
        }
    }
    let bounds = adj.component_bounds();
    let whole = |n: usize| 0..n as u32;
    if !grouped {
        let anything = !sides.is_empty() || !caps_forward.is_empty() || !caps_reversed.is_empty();
        let pieces = anything
            .then(|| VolumePiece {
                sides: whole(sides.len()),
                caps_forward: whole(caps_forward.len()),
                caps_reversed: whole(caps_reversed.len()),
                bounds: bounds.first().copied().unwrap_or_default(),
            })
            .into_iter()
            .collect();
        return ShadowVolume { sides, caps_forward, caps_reversed, light, pieces };
    }
    let component = |f: u32| adj.components()[f as usize] as usize;
    let (sides, side_runs) = by_component(&sides, bounds.len(), |i, _| component(side_faces[i]));
    let (caps_forward, forward_runs) = by_component(&caps_forward, bounds.len(), |_, &f| component(f));
    let (caps_reversed, reversed_runs) = by_component(&caps_reversed, bounds.len(), |_, &f| component(f));
    let pieces = (0..bounds.len())
        .map(|k| VolumePiece {
            sides: side_runs[k]..side_runs[k + 1],
            caps_forward: forward_runs[k]..forward_runs[k + 1],
            caps_reversed: reversed_runs[k]..reversed_runs[k + 1],
            bounds: bounds[k],
        })
        .filter(|p| !p.sides.is_empty() || !p.caps_forward.is_empty() || !p.caps_reversed.is_empty())
        .collect();
    ShadowVolume { sides, caps_forward, caps_reversed, light, pieces }
}

/// `items` grouped by their component (`component(index, item)`, below `n`), each group in input order
/// (a counting sort), with where each component's run starts (`n + 1` entries).
fn by_component<T: Copy + Default>(
    items: &[T],
    n: usize,
    component: impl Fn(usize, &T) -> usize,
) -> (Vec<T>, Vec<u32>) {
    let mut starts = vec![0u32; n + 1];
    for (i, t) in items.iter().enumerate() {
        starts[component(i, t) + 1] += 1;
    }
    for k in 0..n {
        starts[k + 1] += starts[k];
    }
    let mut next = starts.clone();
    let mut out = vec![T::default(); items.len()];
    for (i, t) in items.iter().enumerate() {
        let at = &mut next[component(i, t)];
        out[*at as usize] = *t;
        *at += 1;
    }
    (out, starts)
}

#[cfg(test)]
pub(crate) mod tests {
    use std::collections::HashMap;

    use glam::Vec3;

    use super::*;
    use crate::geometry::silhouette::{CastMode, silhouette};
    use crate::procedural;

    /// Directed-edge balance of a triangle set: a closed, consistently oriented surface uses every edge
    /// once in each direction, so every entry is zero.
    pub(crate) fn edge_balance(tris: &[[Vec4; 3]]) -> HashMap<([u32; 4], [u32; 4]), i32> {
        let key = |v: Vec4| v.to_array().map(|c| if c == 0.0 { 0 } else { c.to_bits() });
        let mut bal = HashMap::new();
        for t in tris {
            for (u, v) in [(t[0], t[1]), (t[1], t[2]), (t[2], t[0])] {
                let (ku, kv) = (key(u), key(v));
                if ku == kv {
                    continue;
                }
                if ku < kv {
                    *bal.entry((ku, kv)).or_insert(0) += 1;
                } else {
                    *bal.entry((kv, ku)).or_insert(0) -= 1;
                }
            }
        }
        bal.retain(|_, v| *v != 0);
        bal
    }

    pub(crate) fn all_triangles(adj: &Adjacency, vol: &ShadowVolume) -> Vec<[Vec4; 3]> {
        vol.sides.iter().copied().chain(vol.near_caps(adj)).chain(vol.far_caps(adj)).collect()
    }

    #[test]
    fn closed_volumes_are_closed_and_outward() {
        for mesh in [
            procedural::cuboid(Vec3::ONE).expect("shape"),
            procedural::sphere(0.7, 12, 8).expect("shape"),
            procedural::torus(1.0, 0.3, 16, 8).expect("shape"),
        ] {
            let adj = Adjacency::build(&mesh);
            for light in
                [LightSource::Point(Vec3::new(2.0, 3.0, 1.5)), LightSource::Directional(Vec3::new(-0.3, -1.0, 0.2))]
            {
                let s = silhouette(&adj, light, CastMode::Closed);
                let vol = extrude(&adj, &s, light, Caps::Both);
                assert!(edge_balance(&all_triangles(&adj, &vol)).is_empty(), "volume not closed");
                // Outward: the near cap faces the light.
                for t in vol.near_caps(&adj) {
                    let n = (t[1] - t[0]).truncate().cross((t[2] - t[0]).truncate());
                    let to_light = match light {
                        LightSource::Point(l) => l - t[0].truncate(),
                        LightSource::Directional(d) => -d,
                    };
                    assert!(n.dot(to_light) > 0.0);
                }
            }
        }
    }

    #[test]
    fn each_component_casts_a_closed_piece() {
        // Two boxes, a torus and an open plane in one mesh; a point and a directional light.
        let parts = [
            procedural::cuboid(Vec3::ONE).expect("shape"),
            procedural::cuboid(Vec3::splat(0.5))
                .expect("shape")
                .transformed(glam::Mat4::from_translation(Vec3::new(3.0, 0.5, 0.0))),
            procedural::torus(1.0, 0.3, 16, 8)
                .expect("shape")
                .transformed(glam::Mat4::from_translation(Vec3::new(-3.0, 0.0, 1.0))),
            procedural::plane(2.0, 2.0)
                .expect("shape")
                .transformed(glam::Mat4::from_translation(Vec3::new(0.0, -2.0, 0.0))),
        ];
        let adj = Adjacency::build(&crate::mesh::Mesh::merged(&parts).expect("four parts"));
        assert_eq!(adj.component_bounds().len(), 4);
        for light in
            [LightSource::Point(Vec3::new(0.5, 4.0, 1.5)), LightSource::Directional(Vec3::new(-0.3, -1.0, 0.2))]
        {
            let vol = extrude(&adj, &silhouette(&adj, light, CastMode::Bergeron), light, Caps::Both);
            assert_eq!(vol.pieces.len(), 4);
            let covered = |f: fn(&VolumePiece) -> &Range<u32>| vol.pieces.iter().map(|p| f(p).len()).sum::<usize>();
            assert_eq!(covered(|p| &p.sides), vol.sides.len());
            assert_eq!(covered(|p| &p.caps_forward), vol.caps_forward.len());
            assert_eq!(covered(|p| &p.caps_reversed), vol.caps_reversed.len());
            for piece in &vol.pieces {
                let part = ShadowVolume {
                    sides: vol.sides[piece.sides.start as usize..piece.sides.end as usize].to_vec(),
                    caps_forward: vol.caps_forward[piece.caps_forward.start as usize..piece.caps_forward.end as usize]
                        .to_vec(),
                    caps_reversed: vol.caps_reversed
                        [piece.caps_reversed.start as usize..piece.caps_reversed.end as usize]
                        .to_vec(),
                    light,
                    pieces: Vec::new(),
                };
                let tris = all_triangles(&adj, &part);
                assert!(!tris.is_empty());
                assert!(edge_balance(&tris).is_empty(), "piece not closed");
                // Every finite corner lies in the piece's bounds.
                for v in tris.iter().flatten().filter(|v| v.w == 1.0) {
                    assert!(v.truncate().cmpge(piece.bounds.min).all() && v.truncate().cmple(piece.bounds.max).all());
                }
            }
        }
    }

    #[test]
    fn side_quads_face_out_of_the_shadow() {
        // Cube lit from straight above by a point light: a point just outside a side quad, away from the
        // cube's shadow, lies on the side the quad's normal points to.
        let adj = Adjacency::build(&procedural::cuboid(Vec3::splat(2.0)).expect("shape"));
        let light = LightSource::Point(Vec3::new(0.0, 5.0, 0.0));
        let vol = extrude(&adj, &silhouette(&adj, light, CastMode::Closed), light, Caps::None);
        assert_eq!(vol.sides.len(), 8);
        for t in &vol.sides {
            let (a, b) = (t[0].truncate(), t[1].truncate());
            let n = (b - a).cross(t[2].truncate());
            let mid = (a + b) * 0.5;
            // Outward from the volume is outward from the cube's vertical axis.
            assert!(n.dot(Vec3::new(mid.x, 0.0, mid.z)) > 0.0);
        }
    }
}
