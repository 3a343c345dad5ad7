//! CPU backend speed: shadow rays per second on `tree`, and 1024x768 frames of `cubes` per technique.
//! `cargo bench -p shadow-hard --bench cpu_frame`.

use divan::Bencher;
use shadow_core::scenes::{self, SceneParams};
use shadow_core::technique::{FrameStats, LightPass, ShadowTechnique, TechniqueSettings};
use shadow_core::{FrameInputs, LightView};
use shadow_cpu::{CpuContext, gbuffer};
use shadow_hard::{RayTraced, ShadowMap, ShadowVolume};

fn main() {
    divan::main();
}

/// The pass of a frame's first light in a 1024x768 view, fitted as `view`.
fn first_light<'a>(f: &'a FrameInputs, view: &'a LightView, stats: &'a mut FrameStats) -> LightPass<'a> {
    let reach = f.reach(&f.lights[0], 1024, 768);
    LightPass { frame: f, light: view, reach, tiles: None, update: Default::default(), slot: 0, aspect: 1.0, stats }
}

fn frame(name: &str) -> FrameInputs {
    let scene = scenes::build(name, &SceneParams::default()).expect("built-in scene");
    let cam = scene.cameras().next().expect("a camera").0;
    FrameInputs::from_scene(&scene, cam).expect("a valid frame")
}

/// Shadow rays on `tree` at 1024x768, BVH built once: divan's throughput is rays per second.
#[divan::bench(sample_count = 10)]
fn ray_traced_tree(b: Bencher) {
    let f = frame("tree");
    let g = gbuffer::render(&f, 1024, 768).expect("gbuffer");
    let view = f.light_view(&f.lights[0]).expect("light view");
    let mut cx = CpuContext::new();
    let t = RayTraced::defaults();
    let mut state = t.create_state(&mut cx).expect("state");
    let mut stats = FrameStats::default();
    let mut pass = first_light(&f, &view, &mut stats);
    t.build(&mut cx, &mut state, pass.reborrow()).expect("build");
    let mut out = shadow_core::Image::new(1024, 768, 1.0f32);
    b.counter(divan::counter::ItemsCount::new(g.covered_pixels())).bench_local(|| {
        t.query(&mut cx, &mut state, pass.reborrow(), &g, &mut out).expect("query");
    });
}

fn whole_frame<T: ShadowTechnique<shadow_cpu::CpuBackend>>(b: Bencher, t: T) {
    let f = frame("cubes");
    let view = f.light_view(&f.lights[0]).expect("light view");
    let mut cx = CpuContext::new();
    let mut state = t.create_state(&mut cx).expect("state");
    let mut spare = None;
    b.bench_local(|| {
        let mut stats = FrameStats::default();
        let mut pass = first_light(&f, &view, &mut stats);
        let g = gbuffer::render_reusing(&f, 1024, 768, spare.take()).expect("gbuffer");
        t.build(&mut cx, &mut state, pass.reborrow()).expect("build");
        let mut out = shadow_core::Image::new(1024, 768, 1.0f32);
        t.query(&mut cx, &mut state, pass.reborrow(), &g, &mut out).expect("query");
        let color = shadow_cpu::shade::shade(&g, (&f.lights, &[f.reach(&f.lights[0], 1024, 768)]), &[&out]);
        spare = Some(g);
        color
    });
}

/// A 1024x768 frame of `cubes` (G-buffer, build, query, shade) with a 2048^2 shadow map.
#[divan::bench(sample_count = 10)]
fn cubes_shadow_map_2048(b: Bencher) {
    whole_frame(b, {
        let mut s = ShadowMap::defaults();
        s.resolution = 2048;
        s
    });
}

/// A 1024x768 frame of `cubes` with z-fail shadow volumes.
#[divan::bench(sample_count = 10)]
fn cubes_shadow_volume_zfail(b: Bencher) {
    whole_frame(b, ShadowVolume::ZFAIL);
}

/// The G-buffer of a 1024x768 `cubes` frame.
#[divan::bench(sample_count = 10)]
fn cubes_gbuffer(b: Bencher) {
    let f = frame("cubes");
    let mut spare = None;
    b.bench_local(|| spare = Some(gbuffer::render_reusing(&f, 1024, 768, spare.take()).expect("gbuffer")));
}
