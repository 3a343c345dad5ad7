//! Tests of the caster masks' CPU side: the split into pieces, their triangle layout and the shaft grids.

use std::collections::HashMap;

use crate::hybrid::shafts::{CasterShafts, Shaft, outline};
use shadow_core::geometry::volume::Caps;
use shadow_core::glam::{Vec2, Vec4};
use shadow_core::scenes::{self, SceneParams};

use super::pieces::{Split, flattened, grids};

/// The cell a light-space point looks in (casters.wgsl's `candidates`).
fn cell_of(frame: (Vec2, Vec2, usize), first: usize, xy: Vec2) -> usize {
    let (origin, scale, side) = frame;
    let c = ((xy - origin) * scale).floor();
    let clamp = |v: f32| (v.max(0.0) as usize).min(side - 1);
    first + clamp(c.y) * side + clamp(c.x)
}

#[test]
fn split_writes_closed_pieces_and_leaves_the_large_ones_to_rasterize() {
    // primitives: a sphere of more volume triangles than the limit, and smaller casters.
    let s = scenes::build("primitives", &SceneParams::default()).expect("scene");
    let frame = shadow_core::FrameInputs::from_scene(&s, s.cameras().next().expect("camera").0).expect("frame");
    let light = frame.light_view(&frame.lights[0]).expect("light view");
    let volumes = frame.shadow_volumes(&light, Caps::Both);
    let shafts = CasterShafts::new(&frame, &light, &volumes);
    let limit = 256;
    let split = Split::new(&frame, &volumes, &shafts, limit, usize::MAX);
    let sizes: Vec<usize> = volumes
        .iter()
        .flat_map(|iv| {
            iv.volume.pieces.iter().map(|p| p.sides.len() + 2 * (p.caps_forward.len() + p.caps_reversed.len()))
        })
        .collect();
    let (small, large): (Vec<usize>, Vec<usize>) = sizes.iter().partition(|&&n| n <= limit);
    assert!(!small.is_empty() && !large.is_empty(), "primitives has pieces on both sides of {limit}: {sizes:?}");
    assert_eq!(split.pieces.len(), small.len());
    assert_eq!(split.triangle_count() as usize, small.iter().sum::<usize>());
    let rasterized = |s: &Split| s.raster.iter().map(|v| v.volume.triangle_count()).sum::<usize>();
    assert_eq!(rasterized(&split), large.iter().sum::<usize>());
    // With room for half the small pieces' triangles, those that do not fit are rasterized too.
    let room = small.iter().sum::<usize>() / 2;
    let half = Split::new(&frame, &volumes, &shafts, limit, room);
    assert!(half.triangle_count() as usize <= room, "{} triangles in a room of {room}", half.triangle_count());
    assert!(!half.pieces.is_empty() && half.pieces.len() < small.len(), "{} pieces", half.pieces.len());
    assert_eq!(half.triangle_count() as usize + rasterized(&half), sizes.iter().sum::<usize>());
    // Each piece written out is closed and wound alike: every directed edge between two corners comes
    // with its reverse (far caps turned around, mirrored instances turned back).
    let key = |v: Vec4| v.to_array().map(f32::to_bits);
    for piece in &split.pieces {
        let (k, run, sides) = (piece.shaft, &piece.triangles, piece.sides as usize);
        // Sides, near caps, as many far caps, in runs.
        let groups: Vec<u32> = run.clone().map(|t| split.triangles[4 * t as usize + 3].z.to_bits()).collect();
        let caps = (groups.len() - sides) / 2;
        let runs = [(0, sides), (1, caps), (2, caps)];
        let expected: Vec<u32> = runs.iter().flat_map(|&(g, n)| std::iter::repeat_n(g, n)).collect();
        assert_eq!(groups, expected, "piece {k}: triangles out of their runs");
        let mut edges: HashMap<([u32; 4], [u32; 4]), i32> = HashMap::new();
        for t in run.clone() {
            let c = &split.triangles[4 * t as usize..4 * t as usize + 3];
            for (a, b) in [(c[0], c[1]), (c[1], c[2]), (c[2], c[0])] {
                *edges.entry((key(a), key(b))).or_default() += 1;
                *edges.entry((key(b), key(a))).or_default() -= 1;
            }
        }
        let open = edges.values().filter(|&&n| n != 0).count();
        assert_eq!(open, 0, "piece {k}: {open} directed edges without their reverse");
    }
}

#[test]
fn side_quads_keep_their_diagonal_in_the_rows_add_quads_leaves_out() {
    use shadow_core::glam::{Mat4, Vec3};
    use shadow_core::{Camera, Light, Material, Scene};

    // A cube as it is and a mirrored one (front faces wound the other way), under a spot light, which
    // sides come in quads for, and a directional light, which they do not.
    let mut s = Scene::new();
    let grey = s.add_material(Material::colored("grey", Vec3::splat(0.75)));
    let cube = s.add_mesh(shadow_core::procedural::cuboid(Vec3::splat(0.3)).expect("shape"));
    let tilt = Mat4::from_rotation_x(0.4) * Mat4::from_rotation_y(0.7);
    let at = |x: f32| Mat4::from_translation(Vec3::new(x, 0.5, 0.0)) * tilt;
    s.add_instance("cube", cube, grey, at(-0.4)).expect("cube");
    s.add_instance("mirrored", cube, grey, at(0.4) * Mat4::from_scale(Vec3::new(-1.0, 1.0, 1.0))).expect("cube");
    let camera = Camera::look_at(Vec3::new(0.0, 1.5, 2.5), Vec3::ZERO, 45.0);
    for (light, quads) in [
        (Light::spot(Vec3::new(0.5, 3.0, 1.0), Vec3::ZERO, 60.0), true),
        (Light::directional(Vec3::new(-0.3, -1.0, -0.2)), false),
    ] {
        let frame = shadow_core::FrameInputs::new(&s, camera, vec![light]).expect("frame");
        let light = frame.light_view(&frame.lights[0]).expect("light view");
        let volumes = frame.shadow_volumes(&light, Caps::Both);
        let shafts = CasterShafts::new(&frame, &light, &volumes);
        let split = Split::new(&frame, &volumes, &shafts, usize::MAX, usize::MAX);
        let mirrored: Vec<bool> = frame.instances.iter().map(|i| i.mirrored).collect();
        assert_eq!(mirrored, [false, true]);
        assert_eq!(split.pieces.len(), 2, "a piece per cube");
        for piece in &split.pieces {
            assert_eq!(piece.quads, quads);
            if !quads {
                continue;
            }
            let corners = |t: u32| &split.triangles[4 * t as usize..4 * t as usize + 3];
            let sides = piece.triangles.start..piece.triangles.start + piece.sides;
            for t in sides.step_by(2) {
                let (first, second) = (corners(t), corners(t + 1));
                // The diagonal, from b to a_inf, is each triangle's edge from its third corner to its
                // first, once each way; the corner off it is a (finite) in the first, b_inf in the second.
                assert_eq!((first[0], first[2]), (second[2], second[0]), "side quad at {t}");
                assert_eq!([first[0].w, first[2].w].iter().sum::<f32>(), 1.0, "one end at infinity");
                assert_eq!((first[1].w, second[1].w), (1.0, 0.0), "side quad at {t}");
            }
        }
    }
}

#[test]
fn every_point_a_shaft_holds_finds_its_piece_in_its_cell() {
    // Random shafts in two projections (a second view, shifted), some unbounded, some far outside the
    // view, and random points with tolerances no larger than the grids were widened for, looked up in
    // the flattened grids as the shader does.
    let mut seed = 0x2545_f491_u32;
    let mut next = move || {
        seed ^= seed << 13;
        seed ^= seed >> 17;
        seed ^= seed << 5;
        seed as f32 / u32::MAX as f32
    };
    let widest = 0.01;
    let mut shafts: Vec<Vec<Option<Shaft>>> = Vec::new();
    let windows = [(Vec2::splat(-1.0), Vec2::splat(1.0)), (Vec2::splat(-0.5), Vec2::splat(1.5))];
    for k in 0..300 {
        let mut shaft = || {
            let centre = Vec2::new(next() * 3.0 - 1.5, next() * 3.0 - 1.5) * if k % 10 == 0 { 8.0 } else { 1.0 };
            let half = Vec2::new(next(), next()) * 0.2;
            let (a, b) = (outline(centre - half), outline(centre + half));
            Shaft {
                lo: a.min(b).min(outline(centre + half * Vec2::new(1.0, -1.0))),
                hi: a.max(b).max(outline(centre + half * Vec2::new(-1.0, 1.0))),
                near: 0.5 + next(),
            }
        };
        let (first, second) = (shaft(), shaft());
        shafts.push(vec![(k % 37 != 0).then_some(first), (k % 23 != 0).then_some(second)]);
    }
    let refs: Vec<&[Option<Shaft>]> = shafts.iter().map(Vec::as_slice).collect();
    let per_projection = grids(&refs, &windows, widest, &[false, false]);
    let cells = flattened(&per_projection);
    let g = |j: usize| &per_projection[j];
    let first_cells = [0, g(0).side * g(0).side];
    let lists = first_cells[1] + g(1).side * g(1).side + 1;
    let (mut held, mut missed) = (0, Vec::new());
    for i in 0..40_000 {
        let j = i % 2;
        let xy = Vec2::new(next() * 4.0 - 2.0, next() * 4.0 - 2.0);
        let (tol, d) = (next() * widest, 0.3 + next() * 2.0);
        let side = 2.0 * tol / d;
        let c = cell_of((g(j).origin, g(j).scale, g(j).side), first_cells[j], xy);
        assert_eq!(c - first_cells[j], g(j).cell_of(xy), "the shader's cell is the grid's");
        let listed = &cells[lists + cells[c] as usize..lists + cells[c + 1] as usize];
        for (k, s) in shafts.iter().enumerate() {
            let holds = s[j].is_none_or(|s| s.holds(outline(xy), d, side, tol));
            if holds {
                held += 1;
                if !listed.contains(&(k as u32)) {
                    missed.push((k, xy));
                }
            }
        }
    }
    assert!(held > 40_000, "the points fall in some shafts: {held}");
    assert!(
        missed.is_empty(),
        "{} points held by a shaft not listed in their cell: {:?}",
        missed.len(),
        &missed[..missed.len().min(5)]
    );
}
