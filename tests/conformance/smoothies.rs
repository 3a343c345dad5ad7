//! Chan's claims for `smoothies` (thesis chapter 4) against the Monte Carlo
//! `area-light-reference` (CPU backend):
//!
//! - the alpha remap (Eq. 4.1, Fig. 4-10): on `stacked-boxes` the upper box's shadow has a sharper edge on
//!   the lower box than on the ground, measured as the 10%-90% width in pixels along a line across each
//!   edge; without the remap the ramp is as wide in the map on both.

use shadow_core::glam::Vec3;
use shadow_core::scenes::{self, SceneParams};
use shadow_core::technique::TechniqueSpec;
use shadow_core::{FrameInputs, Image};
use shadowlab::{Renderer, TechniqueRegistry};

/// The 10%-90% width, in image pixels, of `vis` along the world segment `from -> to` on a receiver at
/// height `y` (samples elsewhere are skipped): the image distance between where visibility first
/// passes 0.1 and where it first passes 0.9.
fn penumbra_width(frame: &FrameInputs, vis: &Image<f32>, position: &Image<Vec3>, from: Vec3, to: Vec3, y: f32) -> f32 {
    let (w, h) = (vis.width(), vis.height());
    let clip = frame.camera.clip_from_world(w as f32 / h as f32);
    let pixel = |p: Vec3| {
        let ndc = clip.project_point3(p);
        ((ndc.x * 0.5 + 0.5) * w as f32, (0.5 - ndc.y * 0.5) * h as f32)
    };
    let mut crossings = [None, None];
    for i in 0..=2000 {
        let p = from.lerp(to, i as f32 / 2000.0);
        let (px, py) = pixel(p);
        let (x, yy) = (px as u32, py as u32);
        if x >= w || yy >= h || (position.get(x, yy).y - y).abs() > 0.01 {
            continue;
        }
        let v = *vis.get(x, yy);
        for (k, level) in [0.1, 0.9].into_iter().enumerate() {
            if crossings[k].is_none() && v > level {
                crossings[k] = Some((px, py));
            }
        }
    }
    let (Some(a), Some(b)) = (crossings[0], crossings[1]) else {
        panic!("no full ramp from {from} to {to}: {crossings:?}")
    };
    ((a.0 - b.0).powi(2) + (a.1 - b.1).powi(2)).sqrt()
}

#[test]
fn the_remap_sharpens_the_shadow_on_the_nearer_receiver() {
    // A light of radius 0.2 (the scene's is 0.05), so the penumbrae span pixels enough to measure.
    let mut scene = scenes::build("stacked-boxes", &SceneParams::default()).expect("scene");
    let key = scene.lights().next().expect("a light").0;
    scene.light_mut(key).expect("the light").radius = 0.2;
    let cam = scene.cameras().next().expect("camera").0;
    let frame = FrameInputs::from_scene(&scene, cam).expect("frame");
    let light = frame.lights[0].position().expect("a spot light");
    // Lines outward from where the light projects the upper box's centre onto the lower box's top
    // (y 0.5, towards -x, staying on the top) and onto the ground (y 0, towards +x, clear of the lower box).
    let upper = Vec3::new(0.55, 1.4, 0.35);
    let onto = |y: f32| light + (upper - light) * ((light.y - y) / (light.y - upper.y));
    let top = (onto(0.5), onto(0.5) + Vec3::new(-0.95, 0.0, 0.0), 0.5);
    let ground = (onto(0.0), onto(0.0) + Vec3::new(0.9, 0.0, 0.0), 0.0);
    let mut renderer = Renderer::new(TechniqueRegistry::builtin());
    let mut rows = Vec::new();
    let mut widths = Vec::new();
    // The thesis's comparisons are measured alongside, for the record (no claim is tested for them).
    for spec in [
        "smoothies",
        "smoothies:remap=off",
        "area-light-reference",
        "pcss",
        "penumbra-map",
        "variance-shadow-map",
        "exponential-variance-shadow-map",
        "moment-shadow-map",
    ] {
        let (f, _) =
            renderer.run_cpu_frame(&frame, 512, 512, &TechniqueSpec::parse(spec).expect("spec")).expect("frame");
        let g = &f.gbuffer;
        let [on_top, on_ground] =
            [top, ground].map(|(a, b, y)| penumbra_width(&frame, &f.visibility[0], &g.position, a, b, y));
        rows.push(format!("{spec:<22} lower box {on_top:5.1} px, ground {on_ground:5.1} px"));
        widths.push((on_top, on_ground));
    }
    eprintln!("10%-90% penumbra width across the upper box's shadow edge, 512x512:\n{}", rows.join("\n"));
    let (remapped, fixed) = (widths[0], widths[1]);
    assert!(
        remapped.0 * 1.2 < remapped.1,
        "remapped: lower box {} px is not sharper than ground {} px",
        remapped.0,
        remapped.1
    );
    // Without the remap the ramp is as wide in the map on both receivers (Fig. 4-10, left): much wider on
    // the lower box, and no sharper there than on the ground.
    assert!(fixed.0 > remapped.0 * 2.0, "without the remap the lower box's edge should widen: {fixed:?}");
    assert!(fixed.0 * 1.2 > fixed.1, "without the remap the edges should be alike: {fixed:?}");
}
