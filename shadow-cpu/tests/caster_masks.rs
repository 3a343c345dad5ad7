//! `hybrid`'s caster masks (each connected component's volume counted only at the silhouette pixels its
//! shadow's bounds hold) change no pixel: the visibility is bit-identical to the whole mask's on every
//! built-in scene and under point, spot and directional lights, some among the casters, with far fewer
//! fragments where many casters' volumes cross each other's shadows.

use shadow_core::glam::Vec3;
use shadow_core::scenes::{self, SceneParams};
use shadow_core::technique::hard::Hybrid;
use shadow_core::technique::settings::OnOff;
use shadow_core::technique::{Stateful, TechniqueSettings};
use shadow_core::{FrameInputs, Light};
use shadow_cpu::{CpuBackend, CpuContext, render_frame};

const SIZE: u32 = 512;

/// The visibility and the processed volume fragments of `hybrid` with caster masks on or off.
fn render(frame: &FrameInputs, caster_masks: OnOff) -> (Vec<f32>, u64, u64) {
    let mut cx = CpuContext::new();
    let hybrid = Hybrid { caster_masks, ..Hybrid::defaults() };
    let mut t = Stateful::<CpuBackend, _>::new(hybrid, String::new());
    let out = render_frame(&mut cx, frame, SIZE, SIZE, &mut t).expect("hybrid renders");
    let c = &out.stats.counters;
    (out.visibility[0].data().to_vec(), c.volume_fragments.expect("fragments"), c.silhouette_pixels.expect("pixels"))
}

#[test]
fn caster_masks_change_no_pixel() {
    let mut cases: Vec<(String, FrameInputs)> = Vec::new();
    for name in scenes::names() {
        let s = scenes::build(name, &SceneParams::default()).expect("scene");
        let cam = *s.camera(s.cameras().next().expect("camera").0).expect("camera");
        cases.push((
            name.to_string(),
            FrameInputs::from_scene(&s, s.cameras().next().expect("camera").0).expect("frame"),
        ));
        // Lights inside the casters (six cube faces, pieces across their planes; a spot light's plane
        // through the cloud), and a directional light over the tree.
        let inside = Vec3::new(0.3, 2.2, 0.4);
        let extra = match name {
            "cubes" => vec![
                ("point light inside", Light::point(inside)),
                ("spot light inside", Light::spot(inside, inside - Vec3::Y, 120.0)),
            ],
            "tree" => vec![
                ("directional light", Light::directional(Vec3::new(-1.0, -3.0, -2.0))),
                ("point light in the branches", Light::point(Vec3::new(0.0, 1.8, 0.0))),
            ],
            _ => Vec::new(),
        };
        for (what, light) in extra {
            cases.push((format!("{name}, {what}"), FrameInputs::new(&s, cam, vec![light]).expect("frame")));
        }
    }
    let mut failures = Vec::new();
    for (name, frame) in &cases {
        let (on, on_fragments, pixels) = render(frame, OnOff::On);
        let (off, off_fragments, _) = render(frame, OnOff::Off);
        let differ = on.iter().zip(&off).filter(|(a, b)| a != b).count();
        eprintln!(
            "{name}: {pixels} silhouette pixels, fragments {on_fragments} with caster masks, {off_fragments} without"
        );
        if differ != 0 {
            failures.push(format!("{name}: {differ} pixels differ"));
        }
        // Nothing shadowed, nothing to test: every case has shadows at the silhouette pixels.
        if pixels == 0 || !on.contains(&0.0) {
            failures.push(format!("{name}: no silhouette pixel or no shadow"));
        }
        if on_fragments > off_fragments {
            failures.push(format!("{name}: more fragments with caster masks ({on_fragments} > {off_fragments})"));
        }
        // Many casters crossing each other's shadows: most fragments go.
        if (name == "cubes" || name == "tree") && on_fragments * 4 > off_fragments {
            failures.push(format!("{name}: caster masks keep {on_fragments} of {off_fragments} fragments"));
        }
    }
    assert!(failures.is_empty(), "{}", failures.join("\n"));
}
