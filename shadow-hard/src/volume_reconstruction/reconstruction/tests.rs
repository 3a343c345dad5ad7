//! Reconstruction checked by geometry: depth maps of an analytic scene (a square slab over the ground),
//! shadows found by counting crossings of the reconstructed triangles along eye rays, as the one-bit
//! stencil does, and compared with the exact shadow.

use glam::{Mat4, Vec2, Vec3, Vec4};

use super::caps::near_plane_cap;
use super::edges::{EdgeMap, EdgeSettings, dangling, depth_and_id_edges, depth_edges, id_edges};
use super::mesh::reconstruct;
use super::{HomTriangle, SampleGrid, Split, texel_square_grid};
use crate::volume_reconstruction::ObjectIds;
use shadow_core::bounds::Aabb;
use shadow_core::light::{LightProjection, LightView};
use shadow_core::scene::{Camera, Light};

const N: u32 = 64;
const SLAB: f32 = 0.5; // half-width of the slab, at height 1 over the ground y = 0

fn settings() -> EdgeSettings {
    EdgeSettings { low: 0.05, high: 0.3, second: Some(0.01), dangling: 0.005, dangling_steps: 4 }
}

/// The slab's shadow on the ground, exactly.
fn shadowed(light_dir: Vec3, q: Vec3) -> bool {
    // Where the ray towards the light crosses y = 1.
    let t = (1.0 - q.y) / -light_dir.y;
    let p = q - light_dir * t;
    p.x.abs() < SLAB && p.z.abs() < SLAB
}

struct Setup {
    dir: Vec3,
    proj: LightProjection,
    grid: SampleGrid,
    ndc: Vec<f32>,
    linear: Vec<f32>,
}

/// A directional light's map of the slab over a 4 x 4 ground, by casting each sample's ray.
fn setup() -> Setup {
    let dir = Vec3::new(0.3, -1.0, 0.2).normalize();
    let boxes = [
        Aabb::new(Vec3::new(-2.0, -0.01, -2.0), Vec3::new(2.0, 0.0, 2.0)),
        Aabb::new(Vec3::new(-SLAB, 0.99, -SLAB), Vec3::new(SLAB, 1.0, SLAB)),
    ];
    let view = LightView::fit(&Light::directional(dir), &boxes).unwrap();
    let proj = view.projections[0];
    let grid = SampleGrid::centres(&proj, N);
    let mut ndc = Vec::new();
    for y in 0..N {
        for x in 0..N {
            let s = Vec2::new(x as f32, y as f32);
            let (a, b) = (grid.world(s, 0.0), grid.world(s, 1.0));
            let (a, b) = (a.truncate() / a.w, b.truncate() / b.w);
            let hit = |h: f32| a + (b - a) * ((a.y - h) / (a.y - b.y));
            let top = hit(1.0);
            let p = if top.x.abs() < SLAB && top.z.abs() < SLAB { top } else { hit(0.0) };
            // A little bias, as the map would have.
            ndc.push(proj.ndc(p).z + 1e-5);
        }
    }
    let linear = ndc.iter().map(|&z| proj.linear_depth(z)).collect();
    Setup { dir, proj, grid, ndc, linear }
}

/// Whether the eye sees ground point q (the slab, at y = 1, is not in the way).
fn visible(eye: Vec3, q: Vec3) -> bool {
    if (eye.y - 1.0) * (q.y - 1.0) > 0.0 {
        return true;
    }
    let p = eye + (q - eye) * ((eye.y - 1.0) / (eye.y - q.y));
    !(p.x.abs() < SLAB && p.z.abs() < SLAB)
}

fn hom(p: Vec4) -> Vec3 {
    p.truncate() / p.w
}

/// Where segment a-b crosses triangle t (Moller-Trumbore on the divided points): the smallest of the
/// crossing's barycentric coordinates, its distance from the triangle's border.
fn crossing(a: Vec3, b: Vec3, t: &HomTriangle) -> Option<f32> {
    let (p0, p1, p2) = (hom(t[0]), hom(t[1]), hom(t[2]));
    let (e1, e2, d) = (p1 - p0, p2 - p0, b - a);
    let h = d.cross(e2);
    let det = e1.dot(h);
    if det.abs() < 1e-12 {
        return None;
    }
    let s = a - p0;
    let u = s.dot(h) / det;
    let q = s.cross(e1);
    let v = d.dot(q) / det;
    let t = e2.dot(q) / det;
    let border = u.min(v).min(1.0 - u - v);
    (border >= 0.0 && t > 0.0 && t < 1.0).then_some(border)
}

fn crosses(a: Vec3, b: Vec3, t: &HomTriangle) -> bool {
    crossing(a, b, t).is_some()
}

/// The parity of segment a-b's crossings of `tris`, or `None` where the segment passes within rounding
/// of a triangle's border: there the two triangles sharing that edge both count it under this inclusive
/// test, where the stencil's rasterization rule counts it once.
fn parity(a: Vec3, b: Vec3, tris: &[HomTriangle]) -> Option<bool> {
    let mut count = 0;
    for t in tris {
        match crossing(a, b, t) {
            Some(border) if border < 1e-4 => return None,
            Some(_) => count += 1,
            None => {}
        }
    }
    Some(count % 2 == 1)
}

/// Ground points on a grid, away from the shadow's edge by more than `band` (in world units).
fn ground_points(dir: Vec3, band: f32) -> Vec<Vec3> {
    let mut pts = Vec::new();
    for i in 0..60 {
        for j in 0..60 {
            let q = Vec3::new(-1.5 + i as f32 * 0.05 + 0.013, 0.0, -1.5 + j as f32 * 0.05 + 0.007);
            let near_edge = [Vec3::X, Vec3::NEG_X, Vec3::Z, Vec3::NEG_Z]
                .iter()
                .any(|&o| shadowed(dir, q + o * band) != shadowed(dir, q));
            if !near_edge {
                pts.push(q);
            }
        }
    }
    pts
}

#[test]
fn steps_are_edges_and_steep_ramps_are_thinned() {
    let (w, h) = (8, 3);
    let step: Vec<f32> = (0..w * h).map(|i| if i % w < 4 { 1.0 } else { 2.0 }).collect();
    let e = depth_edges(&step, w, h, &settings());
    for y in 0..h {
        for x in 0..w - 1 {
            assert_eq!(e.u(x, y), x == 3, "u({x}, {y})");
        }
    }
    assert_eq!(e.flag_count(), 3);
    // A ramp 0.1 per sample: over theta_L everywhere, but the differences have no extremum.
    let ramp: Vec<f32> = (0..w * h).map(|i| (i % w) as f32 * 0.1).collect();
    assert_eq!(depth_edges(&ramp, w, h, &settings()).flag_count(), 0);
    let plain = EdgeSettings { second: None, ..settings() };
    assert_eq!(depth_edges(&ramp, w, h, &plain).flag_count(), 7 * 3);
    // A step on a ramp stands out of the ramp's differences on both sides.
    let stepped: Vec<f32> = (0..w * h).map(|i| (i % w) as f32 * 0.1 + if i % w >= 4 { 0.2 } else { 0.0 }).collect();
    let e = depth_edges(&stepped, w, h, &settings());
    assert_eq!(e.flag_count(), 3);
    assert!(e.u(3, 1));
}

#[test]
fn dangling_edges_are_followed_into_fading_contrast() {
    // A step between columns 4 and 5 whose height fades to nothing down the rows, as an object's side
    // meeting the ground: 0.25, 0.2, 0.15, 0.1, 0.045, 0.
    let heights = [0.25, 0.2, 0.15, 0.1, 0.045, 0.0];
    let (w, h) = (10, heights.len() as u32);
    let depth: Vec<f32> = (0..w * h).map(|i| if i % w >= 5 { 1.0 - heights[(i / w) as usize] } else { 1.0 }).collect();
    let no_follow = EdgeSettings { dangling_steps: 0, ..settings() };
    let e = depth_edges(&depth, w, h, &no_follow);
    let rows = |e: &EdgeMap| (0..h).filter(|&y| e.u(4, y)).collect::<Vec<_>>();
    // Over theta_L = 0.05 down to 0.1; the ramp of the object's side (0.05 a row) is thinned away.
    assert_eq!(rows(&e), vec![0, 1, 2, 3]);
    assert!(dangling(e.code(4, 3)), "the contour dangles in cell (4, 3): code {:04b}", e.code(4, 3));
    // Followed under theta_D = 0.005 through the 0.045 step, and not past the contact.
    let e = depth_edges(&depth, w, h, &settings());
    assert_eq!(rows(&e), vec![0, 1, 2, 3, 4]);
}

#[test]
fn id_boundaries_close_contours_the_depth_test_loses() {
    // An object (ID 2, columns 5 on) on the ground (ID 1) whose height over it fades to nothing three rows
    // before the last, and a second object boundary (columns 0 and 1) with no depth contrast at all.
    let heights = [0.25, 0.2, 0.15, 0.1, 0.045, 0.0, 0.0, 0.0];
    let (w, h) = (10, heights.len() as u32);
    let depth: Vec<f32> = (0..w * h).map(|i| if i % w >= 5 { 1.0 - heights[(i / w) as usize] } else { 1.0 }).collect();
    let ids: Vec<u32> = (0..w * h)
        .map(|i| {
            if i % w >= 5 {
                2
            } else if i % w == 0 {
                3
            } else {
                1
            }
        })
        .collect();
    let rows = |e: &EdgeMap, x: u32| (0..h).filter(|&y| e.u(x, y)).collect::<Vec<_>>();
    let depth_only = depth_and_id_edges(&depth, &ids, w, h, &settings(), ObjectIds::Off);
    assert_eq!(depth_only, depth_edges(&depth, w, h, &settings()));
    assert_eq!(rows(&depth_only, 4), vec![0, 1, 2, 3, 4], "no depth contrast below row 4");
    // Dangling: the contour goes on along the ID boundary (up to 4 steps); the far boundary, with no
    // dangling edge near it, is left alone.
    let dangling = depth_and_id_edges(&depth, &ids, w, h, &settings(), ObjectIds::Dangling);
    assert_eq!(rows(&dangling, 4), vec![0, 1, 2, 3, 4, 5, 6, 7]);
    assert!(rows(&dangling, 0).is_empty());
    // All: every ID boundary is an edge.
    let all = depth_and_id_edges(&depth, &ids, w, h, &settings(), ObjectIds::All);
    assert_eq!(rows(&all, 4), vec![0, 1, 2, 3, 4, 5, 6, 7]);
    assert_eq!(rows(&all, 0), (0..h).collect::<Vec<_>>());
    let plain = id_edges(&ids, w, h);
    assert_eq!(plain.flag_count(), 2 * h as usize);
}

#[test]
fn the_split_cuts_across_the_larger_diagonal() {
    // One occluder corner sample: the split edge joins the other two, which differ least.
    assert_eq!(Split::of([0.2, 1.0, 1.0, 1.0]), Split::AlongBD);
    assert_eq!(Split::of([1.0, 0.2, 1.0, 1.0]), Split::AlongAC);
}

/// The map's samples on the paper's grid (texel centres) or the texel-square grid, with their flags.
fn on_grid(s: &Setup, texel_squares: bool) -> (SampleGrid, Vec<f32>, Vec<f32>, EdgeMap) {
    let edges = depth_edges(&s.linear, N, N, &settings());
    if !texel_squares {
        return (s.grid, s.ndc.clone(), s.linear.clone(), edges);
    }
    let (linear, flags) = texel_square_grid(&s.linear, N, &edges, 0);
    let ndc = linear.iter().map(|&d| s.proj.ndc_depth(d)).collect();
    (SampleGrid::texel_squares(&s.proj, N, 0), ndc, linear, flags)
}

#[test]
fn the_texel_square_grid_keeps_a_texel_wide_occluder_and_puts_edges_on_texel_borders() {
    let n = 5;
    let far = 2.0;
    let settings = EdgeSettings { low: 0.1, high: 0.5, second: Some(0.05), dangling: 0.01, dangling_steps: 0 };
    // One occluder texel: a pyramid on its centre, every other sample far.
    let mut spike = vec![far; 25];
    spike[2 * 5 + 2] = 1.0;
    let (depth, flags) = texel_square_grid(&spike, n, &depth_edges(&spike, n, n, &settings), 0);
    let m = 2 * n + 1;
    for i in 0..m * m {
        assert_eq!(depth[i as usize], if i == 5 * m + 5 { 1.0 } else { far }, "sample ({}, {})", i % m, i / m);
    }
    assert!(flags.u(4, 5) && flags.u(5, 5) && flags.v(5, 4) && flags.v(5, 5));
    assert_eq!(flags.flag_count(), 4);
    // A step between texel columns 1 and 2: the border samples (x = 4) take the far side, so the jump is
    // between x = 3 and 4, inside the occluder's texel, and a ramp's border samples are its mean.
    let step: Vec<f32> = (0..25).map(|i| if i % 5 < 2 { 1.0 } else { far + 0.01 * (i % 5) as f32 }).collect();
    let (depth, flags) = texel_square_grid(&step, n, &depth_edges(&step, n, n, &settings), 0);
    for y in 0..m {
        for x in 0..m - 1 {
            assert_eq!(flags.u(x, y), x == 3, "u({x}, {y})");
        }
    }
    assert_eq!(depth[4], far + 0.02);
    assert!((depth[6] - (far + 0.025)).abs() < 1e-6);
    assert_eq!(flags.flag_count(), m as usize);
}

#[test]
fn parity_of_the_reconstructed_boundary_is_the_shadow() {
    let s = setup();
    for texel_squares in [false, true] {
        let (grid, ndc, linear, edges) = on_grid(&s, texel_squares);
        let rec = reconstruct(&ndc, &linear, &edges, &grid, 0.0, Vec4::ZERO);
        assert!(!rec.triangles.is_empty());
        // O(n) cells: the slab's outline is about 4 x 0.25 of the map's side (twice as many samples a side
        // on the texel-square grid).
        let side = if texel_squares { 2 * N } else { N };
        assert!(rec.cells < 4 * side as usize, "{} cells", rec.cells);
        let eye = Vec3::new(2.5, 3.0, 3.0);
        let texel = 4.2 / N as f32;
        let pts: Vec<Vec3> = ground_points(s.dir, 2.0 * texel).into_iter().filter(|&q| visible(eye, q)).collect();
        let parities: Vec<(Vec3, bool)> =
            pts.iter().filter_map(|&q| parity(eye, q, &rec.triangles).map(|p| (q, p))).collect();
        assert!(
            parities.len() * 100 > pts.len() * 99,
            "{} of {} points on a border",
            pts.len() - parities.len(),
            pts.len()
        );
        let wrong = parities.iter().filter(|&&(q, p)| p != shadowed(s.dir, q)).count();
        assert_eq!(wrong, 0, "{wrong} of {} ground points (texel squares: {texel_squares})", parities.len());
        assert!(pts.iter().filter(|&&q| shadowed(s.dir, q)).count() > 100);
    }
}

#[test]
fn a_cap_restores_parity_where_the_near_plane_cuts_the_volume() {
    let s = setup();
    for texel_squares in [false, true] {
        cap_restores_parity(&s, texel_squares);
    }
}

fn cap_restores_parity(s: &Setup, texel_squares: bool) {
    let (grid, ndc, linear, edges) = on_grid(s, texel_squares);
    let rec = reconstruct(&ndc, &linear, &edges, &grid, 0.0, Vec4::ZERO);
    // An eye just under the slab's edge, in its shadow, looking out along x past it: its near plane cuts
    // the volume's boundary.
    let eye = Vec3::new(0.45, 0.5, 0.0);
    let target = Vec3::new(2.0, 0.0, 0.3);
    let camera = Camera { near: 0.3, ..Camera::look_at(eye, target, 70.0) };
    let eye_clip: Mat4 = camera.clip_from_world(1.0);
    let cap = near_plane_cap(eye_clip, &s.proj, &grid, &ndc, &linear);
    assert!(!cap.invert_all && !cap.triangles.is_empty(), "a mixed cap is expected");
    let near_point = |q: Vec3| {
        // Where the eye's ray to q crosses the near plane (clip z = 0).
        let (ce, cq) = (eye_clip * eye.extend(1.0), eye_clip * q.extend(1.0));
        let t = -ce.z / (cq.z - ce.z);
        eye + (q - eye) * t
    };
    let in_cap =
        |f: Vec3| cap.triangles.iter().any(|t| crosses(f - (q_dir(eye, f) * 1e-3), f + q_dir(eye, f) * 1e-3, t));
    let texel = 4.2 / N as f32;
    let pts: Vec<Vec3> = ground_points(s.dir, 2.0 * texel)
        .into_iter()
        .filter(|q| {
            let c = eye_clip * q.extend(1.0);
            visible(eye, *q) && c.w > 0.0 && c.x.abs() < c.w && c.y.abs() < c.w && c.z > 0.0
        })
        .collect();
    assert!(pts.len() > 100, "{} visible points", pts.len());
    let (mut uncapped, mut capped) = (0, 0);
    for &q in &pts {
        let f = near_point(q);
        let Some(p) = parity(f, q, &rec.triangles) else { continue };
        uncapped += usize::from(p != shadowed(s.dir, q));
        capped += usize::from((p != in_cap(f)) != shadowed(s.dir, q));
    }
    assert!(uncapped > 20, "without the cap the clipped parity should invert part of the view ({uncapped})");
    assert_eq!(capped, 0, "{capped} of {} points wrong with the cap (texel squares: {texel_squares})", pts.len());
}

fn q_dir(eye: Vec3, f: Vec3) -> Vec3 {
    (f - eye).normalize()
}
