use glam::Vec4;

use super::spans::span;
use super::*;

fn count_state() -> RasterState {
    RasterState { depth: None, ..RasterState::default() }
}

/// A jittered grid of triangles spanning beyond the screen, in NDC with varying w (so perspective and
/// clipping are exercised). Returns clip-space triangles.
fn jittered_grid(n: usize, seed: u64, w_scale: f32) -> Vec<[Vec4; 3]> {
    let mut rng = shadow_core::scenes::Rng::new(seed);
    let mut pts = vec![vec![Vec4::ZERO; n + 1]; n + 1];
    for (j, row) in pts.iter_mut().enumerate() {
        for (i, p) in row.iter_mut().enumerate() {
            let jit =
                |r: &mut shadow_core::scenes::Rng, k: usize| if k == 0 || k == n { 0.0 } else { r.range(-0.3, 0.3) };
            let x = -1.3 + 2.6 * (i as f32 + jit(&mut rng, i)) / n as f32;
            let y = -1.3 + 2.6 * (j as f32 + jit(&mut rng, j)) / n as f32;
            let w = 1.0 + w_scale * rng.unit();
            *p = Vec4::new(x * w, y * w, 0.5 * w, w);
        }
    }
    let mut tris = Vec::new();
    for j in 0..n {
        for i in 0..n {
            let (a, b, c, d) = (pts[j][i], pts[j][i + 1], pts[j + 1][i + 1], pts[j + 1][i]);
            tris.push([a, b, c]);
            tris.push([a, c, d]);
        }
    }
    tris
}

#[test]
fn a_mesh_covers_every_pixel_exactly_once() {
    for (seed, w_scale) in [(1, 0.0), (2, 3.0), (3, 0.5)] {
        let tris = jittered_grid(13, seed, w_scale);
        let mut ds = DepthStencil::new(97, 61, 1.0, 0);
        let mut hits = Image::new(97, 61, 0u32);
        let src = Soup { triangles: &tris, prim_base: 0, flip: false };
        draw(&mut ds, &mut hits, &src, &count_state(), |_| Some(1), |d, s| *d += s);
        assert!(
            hits.data().iter().all(|&h| h == 1),
            "seed {seed}: {:?}",
            hits.data().iter().filter(|&&h| h != 1).count()
        );
    }
}

#[test]
fn clipped_fans_stay_watertight() {
    // A fan around a vertex behind the near plane: every triangle is clipped, and the clipped pieces must
    // still tile the covered area exactly once.
    let centre = Vec4::new(0.1, -0.05, -0.5, 0.2);
    let ring: Vec<Vec4> = (0..11)
        .map(|k| {
            let a = std::f32::consts::TAU * k as f32 / 11.0;
            Vec4::new(0.9 * a.cos(), 0.9 * a.sin(), 0.5, 1.0)
        })
        .collect();
    let tris: Vec<[Vec4; 3]> = (0..11).map(|k| [centre, ring[k], ring[(k + 1) % 11]]).collect();
    let mut ds = DepthStencil::new(64, 64, 1.0, 0);
    let mut hits = Image::new(64, 64, 0u32);
    draw(
        &mut ds,
        &mut hits,
        &Soup { triangles: &tris, prim_base: 0, flip: false },
        &count_state(),
        |_| Some(1),
        |d, s| *d += s,
    );
    assert!(hits.data().iter().all(|&h| h <= 1));
    assert!(hits.data().iter().filter(|&&h| h == 1).count() > 100);
}

#[test]
fn top_left_rule() {
    // A 4x4 pixel square from two triangles whose edges pass exactly through pixel centres: the left and
    // top edges own their samples, the right and bottom ones do not.
    let ndc = |x: f32, y: f32| Vec4::new(x / 4.0 - 1.0, 1.0 - y / 4.0, 0.5, 1.0);
    let (a, b, c, d) = (ndc(1.5, 1.5), ndc(5.5, 1.5), ndc(5.5, 5.5), ndc(1.5, 5.5));
    let tris = [[a, d, c], [a, c, b]];
    let mut ds = DepthStencil::new(8, 8, 1.0, 0);
    let mut hits = Image::new(8, 8, 0u32);
    draw(
        &mut ds,
        &mut hits,
        &Soup { triangles: &tris, prim_base: 0, flip: false },
        &count_state(),
        |_| Some(1),
        |d, s| *d += s,
    );
    for y in 0..8 {
        for x in 0..8 {
            let inside = (1..5).contains(&x) && (1..5).contains(&y);
            assert_eq!(*hits.get(x, y), u32::from(inside), "pixel ({x}, {y})");
        }
    }
}

#[test]
fn barycentrics_are_perspective_correct() {
    // A triangle with very different w: the attribute at a pixel must equal the one found by casting the
    // pixel's ray onto the triangle in clip space.
    let v = [Vec4::new(-1.0, -1.0, 0.1, 1.0), Vec4::new(3.0, -3.0, 1.5, 3.0), Vec4::new(-0.5, 2.0, 1.0, 2.0)];
    let mut ds = DepthStencil::new(32, 32, 1.0, 0);
    let mut out = Image::new(32, 32, [f32::NAN; 3]);
    let st = RasterState { depth: None, ..RasterState::default() };
    draw(
        &mut ds,
        &mut out,
        &Soup { triangles: &[v], prim_base: 0, flip: false },
        &st,
        |f| Some(f.bary()),
        |d, s| *d = s,
    );
    let mut checked = 0;
    for y in 0..32 {
        for x in 0..32 {
            let b = *out.get(x, y);
            if b[0].is_nan() {
                continue;
            }
            let p = v[0] * b[0] + v[1] * b[1] + v[2] * b[2];
            let (nx, ny) = (p.x / p.w, p.y / p.w);
            let (sx, sy) = ((nx * 0.5 + 0.5) * 32.0, (0.5 - ny * 0.5) * 32.0);
            assert!(
                (sx - (x as f32 + 0.5)).abs() < 2e-3 && (sy - (y as f32 + 0.5)).abs() < 2e-3,
                "({x}, {y}) -> ({sx}, {sy})"
            );
            checked += 1;
        }
    }
    assert!(checked > 100);
}

/// The barycentrics beside a fragment are those of the fragments one to the right and one down, and
/// past the triangle's edge they go on along its plane (the footprint of a pixel on an edge).
#[test]
fn barycentrics_beside_a_fragment_are_its_neighbours() {
    let v = [Vec4::new(-1.0, -1.0, 0.1, 1.0), Vec4::new(3.0, -3.0, 1.5, 3.0), Vec4::new(-0.5, 2.0, 1.0, 2.0)];
    let mut ds = DepthStencil::new(32, 32, 1.0, 0);
    let mut out = Image::new(32, 32, [[f32::NAN; 3]; 3]);
    let st = RasterState { depth: None, ..RasterState::default() };
    let soup = Soup { triangles: &[v], prim_base: 0, flip: false };
    draw(&mut ds, &mut out, &soup, &st, |f| Some([f.bary(), f.bary_beside()[0], f.bary_beside()[1]]), |d, s| *d = s);
    let (mut neighbours, mut past_the_edge) = (0, 0);
    let close = |a: [f32; 3], b: [f32; 3]| a.iter().zip(b).all(|(a, b)| (a - b).abs() < 1e-5);
    for y in 0..31 {
        for x in 0..31 {
            let [_, right, down] = *out.get(x, y);
            if right[0].is_nan() {
                continue;
            }
            for (beside, (bx, by)) in [(right, (x + 1, y)), (down, (x, y + 1))] {
                let theirs = out.get(bx, by)[0];
                if theirs[0].is_nan() {
                    // Outside the triangle: a point of its plane, one weight negative.
                    assert!(beside.iter().any(|&w| w < 0.0) && (beside.iter().sum::<f32>() - 1.0).abs() < 1e-5);
                    past_the_edge += 1;
                } else {
                    assert!(close(beside, theirs), "({x}, {y}) beside ({bx}, {by}): {beside:?} {theirs:?}");
                    neighbours += 1;
                }
            }
        }
    }
    assert!(neighbours > 100 && past_the_edge > 10, "{neighbours} {past_the_edge}");
}

#[test]
fn depth_test_keeps_the_nearest_and_bias_follows_vulkan() {
    let quad = |z: f32| [[Vec4::new(-1.0, -1.0, z, 1.0), Vec4::new(3.0, -1.0, z, 1.0), Vec4::new(-1.0, 3.0, z, 1.0)]];
    let mut ds = DepthStencil::new(8, 8, 1.0, 0);
    for z in [0.7, 0.25, 0.5] {
        draw_depth(&mut ds, &Soup { triangles: &quad(z), prim_base: 0, flip: false }, &RasterState::default());
    }
    assert!(ds.depth.iter().all(|&d| d == 0.25));
    // Constant bias of 4 at z = 0.75 (exponent -1): 4 * 2^-24.
    let mut ds = DepthStencil::new(8, 8, 1.0, 0);
    let bias = DepthBias { constant: 4.0, slope: 0.0, clamp: 0.0 };
    let st = RasterState { depth: Some(DepthState { bias, ..DepthState::LESS_WRITE }), ..RasterState::default() };
    draw_depth(&mut ds, &Soup { triangles: &quad(0.75), prim_base: 0, flip: false }, &st);
    assert!(ds.depth.iter().all(|&d| d == 0.75 + 4.0 * 2f32.powi(-24)));
    // Slope bias on a plane rising 0.1 per pixel in x: offset 2 * 0.1.
    let tilted = [[Vec4::new(-1.0, -1.0, 0.2, 1.0), Vec4::new(1.0, -1.0, 1.0, 1.0), Vec4::new(-1.0, 1.0, 0.2, 1.0)]];
    let mut plain = DepthStencil::new(8, 8, 1.0, 0);
    draw_depth(&mut plain, &Soup { triangles: &tilted, prim_base: 0, flip: false }, &RasterState::default());
    let mut biased = DepthStencil::new(8, 8, 1.0, 0);
    let bias = DepthBias { constant: 0.0, slope: 2.0, clamp: 0.0 };
    let st = RasterState { depth: Some(DepthState { bias, ..DepthState::LESS_WRITE }), ..RasterState::default() };
    draw_depth(&mut biased, &Soup { triangles: &tilted, prim_base: 0, flip: false }, &st);
    let (p, b) = (plain.depth[56], biased.depth[56]);
    assert!((b - p - 0.2).abs() < 1e-5, "{p} {b}");
}

#[test]
fn culling_and_facing() {
    let ccw = [Vec4::new(-1.0, -1.0, 0.5, 1.0), Vec4::new(1.0, -1.0, 0.5, 1.0), Vec4::new(-1.0, 1.0, 0.5, 1.0)];
    let cw = [ccw[0], ccw[2], ccw[1]];
    for (tri, flip, front) in [(ccw, false, true), (cw, false, false), (cw, true, true)] {
        let mut ds = DepthStencil::new(4, 4, 1.0, 0);
        let mut out = Image::new(4, 4, 0u8);
        let st = RasterState { depth: None, ..RasterState::default() };
        draw(
            &mut ds,
            &mut out,
            &Soup { triangles: &[tri], prim_base: 0, flip },
            &st,
            |f| Some(if f.front_facing { 1 } else { 2 }),
            |d, s| *d = s,
        );
        assert_eq!(*out.get(0, 3), if front { 1 } else { 2 });
        let st = RasterState { cull: CullMode::Back, depth: None, ..RasterState::default() };
        let mut ds = DepthStencil::new(4, 4, 1.0, 0);
        let n = draw_depth(&mut ds, &Soup { triangles: &[tri], prim_base: 0, flip }, &st).fragments;
        assert_eq!(n > 0, front);
    }
}

#[test]
fn every_stencil_op() {
    let cases = [
        (StencilOp::Keep, 7, 7),
        (StencilOp::Zero, 7, 0),
        (StencilOp::Replace, 7, 42),
        (StencilOp::IncrementClamp, 255, 255),
        (StencilOp::DecrementClamp, 0, 0),
        (StencilOp::Invert, 0b1010_0000, 0b0101_1111),
        (StencilOp::IncrementWrap, 255, 0),
        (StencilOp::DecrementWrap, 0, 255),
    ];
    let tri = [[Vec4::new(-1.0, -1.0, 0.5, 1.0), Vec4::new(3.0, -1.0, 0.5, 1.0), Vec4::new(-1.0, 3.0, 0.5, 1.0)]];
    for (op, before, after) in cases {
        let face =
            StencilFace { compare: CompareFn::Always, fail: StencilOp::Keep, depth_fail: StencilOp::Keep, pass: op };
        let st = RasterState {
            depth: None,
            stencil: Some(StencilState {
                front: face,
                back: StencilFace::KEEP,
                read_mask: 0xff,
                write_mask: 0xff,
                reference: 42,
            }),
            ..RasterState::default()
        };
        let mut ds = DepthStencil::new(2, 2, 1.0, before);
        draw_depth(&mut ds, &Soup { triangles: &tri, prim_base: 0, flip: false }, &st);
        assert_eq!(ds.stencil[0], after, "{op:?}");
    }
    // Write mask keeps the other bits; depth-fail and fail ops; back-face state for back faces.
    let face = StencilFace {
        compare: CompareFn::Equal,
        fail: StencilOp::Zero,
        depth_fail: StencilOp::Invert,
        pass: StencilOp::Keep,
    };
    let st = RasterState {
        depth: Some(DepthState::LESS_READ),
        stencil: Some(StencilState {
            front: StencilFace::KEEP,
            back: face,
            read_mask: 0x0f,
            write_mask: 0x01,
            reference: 3,
        }),
        ..RasterState::default()
    };
    let back = [[tri[0][0], tri[0][2], tri[0][1]]];
    let mut ds = DepthStencil::new(2, 2, 0.25, 0xf3); // reference 3 == 0xf3 & 0x0f; depth fails
    draw_depth(&mut ds, &Soup { triangles: &back, prim_base: 0, flip: false }, &st);
    assert_eq!(ds.stencil[0], 0xf2);
    let mut ds = DepthStencil::new(2, 2, 0.25, 0xf1); // stencil test fails: Zero through write mask 1
    draw_depth(&mut ds, &Soup { triangles: &back, prim_base: 0, flip: false }, &st);
    assert_eq!(ds.stencil[0], 0xf0);
}

#[test]
fn output_does_not_depend_on_the_thread_count() {
    let tris = jittered_grid(40, 7, 2.0);
    let mut rng = shadow_core::scenes::Rng::new(9);
    // Overlapping layers at random depths, with stencil counting and a colour write.
    let mut all = Vec::new();
    for _ in 0..3 {
        let dz = rng.range(-0.3, 0.3);
        all.extend(tris.iter().map(|t| t.map(|v| Vec4::new(v.x, v.y, v.z + dz * v.w, v.w))));
    }
    let run = || {
        let face = StencilFace {
            compare: CompareFn::Always,
            fail: StencilOp::Keep,
            depth_fail: StencilOp::IncrementWrap,
            pass: StencilOp::DecrementWrap,
        };
        let st = RasterState {
            stencil: Some(StencilState { front: face, back: face, read_mask: 0xff, write_mask: 0xff, reference: 0 }),
            ..RasterState::default()
        };
        let mut ds = DepthStencil::new(301, 207, 1.0, 0);
        let mut col = Image::new(301, 207, 0u32);
        let c = draw(
            &mut ds,
            &mut col,
            &Soup { triangles: &all, prim_base: 0, flip: false },
            &st,
            |f| Some(f.prim),
            |d, s| *d = s,
        );
        (ds, col, c)
    };
    let one = rayon::ThreadPoolBuilder::new().num_threads(1).build().unwrap().install(run);
    let many = rayon::ThreadPoolBuilder::new().num_threads(4).build().unwrap().install(run);
    assert_eq!(one.0, many.0);
    assert_eq!(one.1, many.1);
    assert_eq!(one.2, many.2);
    assert!(one.2.stencil_updates > 0);
}

#[test]
fn fast_kernels_match_the_general_loop() {
    let tris = jittered_grid(30, 11, 2.0);
    let mut rng = shadow_core::scenes::Rng::new(5);
    let mut all = Vec::new();
    for k in 0..4 {
        let dz = rng.range(-0.3, 0.3);
        // Every other layer turned around, so both stencil faces are exercised.
        all.extend(tris.iter().map(|t| {
            let t = t.map(|v| Vec4::new(v.x, v.y, v.z + dz * v.w, v.w));
            if k % 2 == 0 { t } else { [t[0], t[2], t[1]] }
        }));
    }
    let src = Soup { triangles: &all, prim_base: 0, flip: false };
    let volume = {
        let face =
            |pass, depth_fail| StencilFace { compare: CompareFn::Always, fail: StencilOp::Keep, depth_fail, pass };
        StencilState {
            front: face(StencilOp::IncrementWrap, StencilOp::Keep),
            back: face(StencilOp::Keep, StencilOp::DecrementWrap),
            read_mask: 0xff,
            write_mask: 0xff,
            reference: 0,
        }
    };
    let bias = DepthBias { constant: 3.0, slope: 1.5, clamp: 0.0 };
    for st in [
        RasterState { depth: Some(DepthState { bias, ..DepthState::LESS_WRITE }), ..RasterState::default() },
        RasterState { depth: Some(DepthState::LESS_READ), stencil: Some(volume), ..RasterState::default() },
    ] {
        let mut base = DepthStencil::new(123, 77, 1.0, 0);
        // A non-trivial starting depth so tests go both ways.
        for (i, d) in base.depth.iter_mut().enumerate() {
            *d = 0.3 + 0.5 * ((i * 7919) % 101) as f32 / 101.0;
        }
        let (mut a, mut b) = (base.clone(), base);
        assert!(DepthKernel::for_state(&st).is_some());
        let fast = draw_depth(&mut a, &src, &st);
        let mut none = Image::new(123, 77, ());
        let general = draw(&mut b, &mut none, &src, &st, |_| Some(()), |_, _| {});
        assert_eq!(a, b);
        assert_eq!(fast, general);
    }
}

#[test]
fn a_peeling_draw_leaves_what_the_general_loop_leaves() {
    // Four overlapping layers; the first is drawn, then all are peeled behind it, once through the
    // peeling kernel and once through the general loop with the peel as the fragment closure. The
    // second layer lies within epsilon behind the first, so it must be peeled too. Depth clamping on,
    // and a bias, so every part of the fragment depth is the one the closure sees.
    let tris = jittered_grid(24, 9, 2.0);
    let mut rng = shadow_core::scenes::Rng::new(3);
    let mut all = Vec::new();
    let first_dz = rng.range(-0.4, 0.4);
    for dz in [first_dz, first_dz + 5e-4, rng.range(-0.4, 0.4), rng.range(-0.4, 0.4)] {
        all.extend(tris.iter().map(|t| t.map(|v| Vec4::new(v.x, v.y, v.z + dz * v.w, v.w))));
    }
    let src = Soup { triangles: &all, prim_base: 0, flip: false };
    let bias = DepthBias { constant: 2.0, slope: 1.0, clamp: 0.0 };
    let st = RasterState {
        depth: Some(DepthState { bias, clamp: true, ..DepthState::LESS_WRITE }),
        ..RasterState::default()
    };
    let mut first = DepthStencil::new(97, 71, 1.0, 0);
    draw_depth(&mut first, &Soup { triangles: &all[..tris.len()], ..src }, &st);
    let under = first.into_depth_image();
    let epsilon = 1e-3;
    let (mut a, mut b) = (DepthStencil::new(97, 71, 1.0, 0), DepthStencil::new(97, 71, 1.0, 0));
    let peeled = draw_depth_peeled(&mut a, &src, &st, &under, epsilon);
    let mut none = Image::new(97, 71, ());
    let late = RasterState { early_tests: false, ..st };
    let general =
        draw(&mut b, &mut none, &src, &late, |f| (f.depth > *under.get(f.x, f.y) + epsilon).then_some(()), |_, _| {});
    assert_eq!(a, b);
    assert_eq!(peeled, general);
    // Both some fragments peeled away and some kept, so both outcomes were compared.
    assert!(peeled.passed > 0 && peeled.passed < peeled.fragments, "{peeled:?}");
}

#[test]
fn a_batch_draws_what_its_parts_draw_in_turn_and_flat_draws_what_the_general_loop_does() {
    // Three overlapping layers as three meshes, the middle one turned around: drawn one after the other
    // with the general loop (each fragment's colour its layer and triangle), then as one batch through the
    // flat path (the colour from the batch's primitive id).
    let grid = jittered_grid(17, 4, 1.5);
    let positions: Vec<Vec4> = grid.iter().flatten().copied().collect();
    // Tilted differently, so each layer is nearest somewhere.
    let tilts = [Vec4::new(0.2, 0.0, 0.0, 0.0), Vec4::new(-0.2, 0.0, 0.0, 0.0), Vec4::new(0.0, 0.25, 0.0, 0.0)];
    let layers: Vec<Vec<Vec4>> =
        tilts.iter().map(|t| positions.iter().map(|v| Vec4::new(v.x, v.y, v.z + t.dot(*v), v.w)).collect()).collect();
    let triangles: Vec<[u32; 3]> = (0..grid.len() as u32).map(|t| [3 * t, 3 * t + 1, 3 * t + 2]).collect();
    let part = |k: usize| Indexed {
        positions: &layers[k],
        triangles: &triangles,
        prim_base: 0,
        flip: k == 1,
        cull_back: false,
    };
    let bias = DepthBias { constant: 2.0, slope: 1.0, clamp: 0.0 };
    let st = RasterState { depth: Some(DepthState { bias, ..DepthState::LESS_WRITE }), ..RasterState::default() };
    let none = (u32::MAX, u32::MAX);

    let mut a = DepthStencil::new(101, 67, 1.0, 0);
    let mut by_parts = Image::new(101, 67, none);
    let mut general = RasterCounters::default();
    for k in 0..3 {
        general += draw(&mut a, &mut by_parts, &part(k), &st, |f| Some((k as u32, f.prim)), |d, s| *d = s);
    }

    let batch = Batch::new((0..3).map(part).collect()).expect("three small parts");
    assert_eq!(batch.len(), 3 * triangles.len());
    assert_eq!(batch.part_of(triangles.len() as u32 + 5), (1, 5));
    let mut b = DepthStencil::new(101, 67, 1.0, 0);
    let mut flat = Image::new(101, 67, none);
    let counters = draw_flat(&mut b, &mut flat, &batch, &st, |prim| {
        let (k, t) = batch.part_of(prim);
        (k as u32, t)
    });
    assert_eq!(a, b);
    assert_eq!(by_parts, flat);
    assert_eq!(general, counters);
    // Every layer shows somewhere, so the comparison saw every part and the order they are drawn in.
    for k in 0..3 {
        assert!(flat.data().iter().any(|&(layer, _)| layer == k), "layer {k} shows nowhere");
    }
}

#[test]
fn a_computation_mask_confines_stencil_work_to_its_pixels() {
    // Counting volumes (both ops incrementing) over a jittered mesh with perspective and clipping, once
    // unmasked and once under a mask of scattered pixels and a block, in tiles of several sides: ones
    // that divide the rasterizer's bands, and ones whose tile rows straddle them.
    let tris = jittered_grid(9, 7, 2.0);
    let (w, h) = (83, 57);
    let face = StencilFace {
        compare: CompareFn::Always,
        fail: StencilOp::Keep,
        depth_fail: StencilOp::IncrementWrap,
        pass: StencilOp::IncrementWrap,
    };
    let st = RasterState {
        depth: Some(DepthState::LESS_READ),
        stencil: Some(StencilState { front: face, back: face, read_mask: 0xff, write_mask: 0xff, reference: 0 }),
        ..RasterState::default()
    };
    let src = Soup { triangles: &tris, prim_base: 0, flip: false };
    let mut all = DepthStencil::new(w, h, 0.5, 0);
    let unmasked = draw_depth(&mut all, &src, &st);
    let on = |x: u32, y: u32| (x * 7 + y * 13).is_multiple_of(29) || (40..52).contains(&x) && (10..30).contains(&y);
    for tile in [1, 3, 4, 8, 24] {
        let mask = ComputationMask::from_fn(w, h, tile, on);
        let mut ds = DepthStencil::new(w, h, 0.5, 0);
        let c = draw_depth_masked(&mut ds, &src, &st, Some(&mask));
        for y in 0..h {
            for x in 0..w {
                let i = (y * w + x) as usize;
                let want = if on(x, y) { all.stencil[i] } else { 0 };
                assert_eq!(ds.stencil[i], want, "tile {tile}, pixel ({x}, {y})");
            }
        }
        // Every triangle covers each pixel of the mesh once, so the masked fragments are the mask's pixels.
        assert_eq!(c.fragments, mask.count() as u64, "tile {tile}");
        assert!(c.fragments < unmasked.fragments / 4);
    }
}

#[test]
fn the_edge_walk_steps_to_the_divided_spans() {
    // The jittered grid, and long slivers from well outside the screen (shadow-volume sides, clipped to
    // the guard band), walked from their first row and from every band start, against `span`.
    let mut rng = shadow_core::scenes::Rng::new(3);
    let mut tris = jittered_grid(12, 9, 3.0);
    let grid = tris.len() as u32;
    for _ in 0..300 {
        let mut corner = || {
            let w = rng.range(0.05, 3.0);
            Vec4::new(rng.range(-4.0, 4.0) * w, rng.range(-4.0, 4.0) * w, 0.5 * w, w)
        };
        let (a, b) = (corner(), corner());
        let c = a + (b - a) * 0.5 + Vec4::new(rng.range(-0.05, 0.05), rng.range(-0.05, 0.05), 0.0, 0.0);
        tris.push([a, b, c]);
    }
    let (w, h) = (301, 217);
    let st = RasterState { cull: CullMode::None, ..count_state() };
    let mut setups = Vec::new();
    for (i, v) in tris.iter().enumerate() {
        setup(
            SourceTriangle { v: *v, prim: i as u32, flip: false, cull_back: false },
            &st,
            w,
            h,
            guard_band(w, h),
            &mut setups,
        );
    }
    let slivers = setups.iter().filter(|t| t.prim >= grid).count();
    assert!(slivers > 40, "{slivers} slivers set up");
    let mut rows = 0;
    for t in &setups {
        let starts = std::iter::once(t.min_y).chain((0..t.max_y).step_by(BAND_ROWS as usize).filter(|&y| y > t.min_y));
        for start in starts {
            let mut walk = EdgeWalk::new(t, start);
            for y in start..=t.max_y {
                assert_eq!(walk.next_row(), span(t, i64::from(y) * ONE + HALF), "row {y} of {t:?} from {start}");
                rows += 1;
            }
        }
    }
    assert!(rows > 10_000, "{rows} rows walked");
}

/// Z-fail counting: depth test "less", back faces +1 and front faces -1 where it fails.
fn zfail_state() -> RasterState {
    RasterState {
        cull: CullMode::None,
        depth: Some(DepthState::LESS_READ),
        stencil: Some(StencilState {
            front: StencilFace { depth_fail: StencilOp::DecrementWrap, ..StencilFace::KEEP },
            back: StencilFace { depth_fail: StencilOp::IncrementWrap, ..StencilFace::KEEP },
            read_mask: 0xff,
            write_mask: 0xff,
            reference: 0,
        }),
        ..RasterState::default()
    }
}

/// A stored depth rising across the target with a small ripple, for counting draws to cross.
fn slanted_depth(w: u32, h: u32) -> Vec<f32> {
    (0..w * h).map(|i| 0.3 + 0.4 * ((i % w) as f32 / w as f32) + 0.01 * (i % 7) as f32).collect()
}

/// A fan around an apex at a pixel centre (returned, in pixels), from a chain of edges with corners at
/// pixel centres and sides ending at pixel centres too: the sides' long edges are shared by neighbours
/// and pass through pixel centres, where the top-left rule decides which side counts.
fn pixel_centre_fan(w: u32, h: u32) -> ((f32, f32), Vec<[Vec4; 3]>) {
    let ndc = |x: f32, y: f32, z: f32| Vec4::new(2.0 * x / w as f32 - 1.0, 1.0 - 2.0 * y / h as f32, z, 1.0);
    let centre = (75.5, 56.5);
    let chain = [(10, -3), (12, 2), (9, 7), (3, 11), (-4, 9), (-9, 4), (-11, -2), (-7, -8), (0, -10), (10, -3)];
    let mut fan = Vec::new();
    for pair in chain.windows(2) {
        let at = |(dx, dy): (i32, i32), k: f32| ndc(centre.0 + k * dx as f32, centre.1 + k * dy as f32, 0.45 + 0.1 * k);
        let (a, b, a_far, b_far) = (at(pair[0], 1.0), at(pair[1], 1.0), at(pair[0], 4.0), at(pair[1], 4.0));
        fan.push([a, b, b_far]);
        fan.push([a, b_far, a_far]);
    }
    (centre, fan)
}

#[test]
fn listed_draws_count_what_masked_walks_count() {
    // Three counting draws (slivers extruded to infinity, clipped, and a jittered grid) each confined to
    // its own list of pixels, overlapping the others', one of them a fan whose edges run through pixel
    // centres: the same stencil and counters as walking each under a mask of just its pixels.
    let (w, h) = (151, 113);
    let (st, depth) = (zfail_state(), slanted_depth(w, h));
    let mut rng = shadow_core::scenes::Rng::new(7);
    let apex = Vec4::new(0.1, 0.2, 0.4, 1.0);
    let mut tris = pixel_centre_fan(w, h).1;
    tris.extend(jittered_grid(6, 7, 1.0));
    for _ in 0..300 {
        let mut corner = || {
            let w = rng.range(0.5, 2.0);
            Vec4::new(rng.range(-1.2, 1.2) * w, rng.range(-1.2, 1.2) * w, rng.range(0.2, 0.8) * w, w)
        };
        let (a, b) = (corner(), corner());
        tris.push([a, b, b - apex]);
        tris.push([a, b - apex, a - apex]);
    }
    let parts: Vec<&[[Vec4; 3]]> = tris.chunks(tris.len().div_ceil(3)).collect();
    let lists: Vec<Vec<u32>> = (0..3u32)
        .map(|k| (0..w * h).filter(|&i| (i % w * (3 + k) + i / w * (5 + 2 * k)) % (7 + k) < 2 + k).collect())
        .collect();
    let sources: Vec<Soup> = parts.iter().map(|t| Soup { triangles: t, prim_base: 0, flip: false }).collect();
    let draws: Vec<ListedDraw> =
        sources.iter().zip(&lists).map(|(s, pixels)| ListedDraw { sources: vec![s], pixels }).collect();
    let mut ds = DepthStencil::from_parts(w, h, depth.clone(), vec![0; (w * h) as usize]);
    let got = count_listed(&mut ds, &draws, &st);
    let mut walked = DepthStencil::from_parts(w, h, depth, vec![0; (w * h) as usize]);
    let mut want = RasterCounters::default();
    for (src, pixels) in sources.iter().zip(&lists) {
        let mask = ComputationMask::from_fn(w, h, 8, |x, y| pixels.binary_search(&(y * w + x)).is_ok());
        want += draw_depth_masked(&mut walked, src, &st, Some(&mask));
    }
    let differ = (0..ds.stencil.len()).find(|&i| ds.stencil[i] != walked.stencil[i]);
    assert!(differ.is_none(), "pixel {differ:?} counted {:?}", differ.map(|i| (ds.stencil[i], walked.stencil[i])));
    assert_eq!(got, want);
    assert!(want.fragments > 5_000 && want.stencil_updates > 1_000, "{want:?}");
}
