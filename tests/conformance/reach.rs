//! Each light queried only where it reaches: on `yard` (64 lights with ranges, spots and points), a frame
//! that saves by reach gives every light the visibility of a frame that does not, at every receiver within
//! the light's reach, and 1 elsewhere; a light that reaches no pixel is neither built nor queried; and the
//! shaded picture is the same to the byte. A light whose maps are tiles of the frame's shadow atlas sees
//! what maps of their side of its own show.

use shadow_core::frame::Savings;
use shadow_core::scenes::{self, SceneParams};
use shadow_core::script::OUT_OF_VIEW;
use shadow_core::technique::TechniqueSpec;
use shadow_core::{FrameInputs, Image, LightShadow};
use shadowlab::{BackendKind, Renderer, TechniqueRegistry};

const WIDTH: u32 = 200;
const HEIGHT: u32 = 150;

fn yard() -> FrameInputs {
    let scene = scenes::build("yard", &SceneParams::default()).expect("yard");
    FrameInputs::from_first_camera(&scene).expect("frame")
}

/// Light `k`'s pixels: receivers within its reach, those where `saved` differs from `full`, pixels beyond
/// it where `saved` is not 1 (of them, those outside its reach's rectangle), and pixels beyond it that
/// `full` shadows (what the saving leaves out).
#[derive(Default)]
struct Counts {
    inside: usize,
    differ: usize,
    not_lit: usize,
    not_lit_outside_rect: usize,
    left_out: usize,
    /// Of the pixels within, those where the two differ by more than 1/100.
    apart: usize,
}

fn compare_light(
    frame: &FrameInputs,
    g: &shadow_cpu::GBuffer,
    k: usize,
    saved: &Image<f32>,
    full: &Image<f32>,
) -> Counts {
    let reach = frame.reach(&frame.lights[k], WIDTH, HEIGHT);
    let mut c = Counts::default();
    for (i, (&s, &f)) in saved.data().iter().zip(full.data()).enumerate() {
        let (x, y) = (i as u32 % WIDTH, i as u32 / WIDTH);
        if g.receiver.data()[i] && reach.rect.contains(x, y) && reach.holds(g.position.data()[i]) {
            c.inside += 1;
            c.differ += usize::from(s.to_bits() != f.to_bits());
            c.apart += usize::from((s - f).abs() > 0.01);
        } else {
            c.not_lit += usize::from(s != 1.0);
            c.not_lit_outside_rect += usize::from(s != 1.0 && !reach.rect.contains(x, y));
            c.left_out += usize::from(f < 1.0);
        }
    }
    c
}

#[test]
fn a_light_is_answered_within_its_reach_as_over_the_whole_view() {
    // Reach alone: every map at its technique's size (the atlas's tiles are held to maps of their own
    // size below).
    let mut saving = yard();
    saving.savings.atlas = None;
    let full = FrameInputs { savings: Savings::NONE, ..saving.clone() };
    let g = shadow_cpu::gbuffer::render(&saving, WIDTH, HEIGHT).expect("G-buffer");
    let mut renderer = Renderer::new(TechniqueRegistry::builtin());
    let mut backends = vec![BackendKind::Cpu];
    if super::with_wgpu("reach").is_some() {
        backends.push(BackendKind::Wgpu);
    }
    for backend in backends {
        let references: &[&str] = if backend == BackendKind::Cpu { &["ray-traced"] } else { &[] };
        let techniques = ["shadow-map:res=256,filter=pcf3x3", "shadow-volume-zfail", "penumbra-wedges"];
        for spec in techniques.iter().chain(references) {
            let spec = TechniqueSpec::parse(spec).expect("spec");
            let saved = renderer.run(backend, &saving, WIDTH, HEIGHT, &spec).expect("frame saving by reach");
            let whole = renderer.run(backend, &full, WIDTH, HEIGHT, &spec).expect("frame over the whole view");
            let out_of_view = saved.stats.counters.extra.get(OUT_OF_VIEW).copied().unwrap_or(0.0);
            assert!(out_of_view >= 4.0, "{backend:?} {spec}: only {out_of_view} lights out of view");
            assert!(!whole.stats.counters.extra.contains_key(OUT_OF_VIEW), "{backend:?} {spec}: lights skipped");
            let (mut reached, mut left_out) = (0, 0);
            for k in 0..saving.lights.len() {
                let c = compare_light(&saving, &g, k, &saved.visibility[k], &whole.visibility[k]);
                let Counts { inside, differ, not_lit, .. } = c;
                assert_eq!(
                    differ, 0,
                    "{backend:?} {spec}: light {k} differs at {differ} of {inside} pixels it reaches"
                );
                // The CPU answers within the reach itself, the GPU within its rectangle (a scissor).
                let beyond = if backend == BackendKind::Cpu { not_lit } else { c.not_lit_outside_rect };
                assert_eq!(beyond, 0, "{backend:?} {spec}: light {k} is not 1 at {beyond} pixels beyond it");
                reached += usize::from(inside > 0);
                left_out += c.left_out;
            }
            assert!(reached >= 8, "{backend:?} {spec}: only {reached} lights reach the view");
            assert!(left_out > 1000, "{backend:?} {spec}: only {left_out} shadowed pixels beyond the lights' reach");
            assert!(saved.color.data() == whole.color.data(), "{backend:?} {spec}: the shaded pictures differ");
        }
    }
}

/// On `yard`, each light's shadow-map tile in the atlas (sized by the share of the view it reaches) gives
/// the visibility a map of that side of its own gives, within its reach: to the bit on the CPU (whose
/// tiles are maps of their own), within the device's precision on the GPU (whose tiles share one
/// texture); the tiles differ in size, below the side the technique asks for.
#[test]
fn a_light_given_a_tile_sees_what_a_map_of_that_side_shows() {
    let saving = yard();
    let g = shadow_cpu::gbuffer::render(&saving, WIDTH, HEIGHT).expect("G-buffer");
    let mut renderer = Renderer::new(TechniqueRegistry::builtin());
    let mut backends = vec![BackendKind::Cpu];
    if super::with_wgpu("shadow atlas").is_some() {
        backends.push(BackendKind::Wgpu);
    }
    let asked = 2048;
    let spec = |res: u32| TechniqueSpec::parse(&format!("shadow-map:res={res},filter=pcf3x3")).expect("spec");
    for backend in backends {
        let saved = renderer.run(backend, &saving, WIDTH, HEIGHT, &spec(asked)).expect("frame with an atlas");
        let atlas = saved.atlas.as_ref().expect("an atlas");
        let sides: Vec<Option<u32>> = atlas.lights.iter().map(|t| t.as_ref().map(|t| t.side)).collect();
        // The same lights, each with a map of its own of the side its tile had, over the whole view.
        let mut own = FrameInputs { savings: Savings::NONE, ..saving.clone() };
        own.shadows = sides.iter().map(|s| s.map_or_else(Default::default, |s| LightShadow::with(spec(s)))).collect();
        let whole = renderer.run(backend, &own, WIDTH, HEIGHT, &spec(asked)).expect("frame of own maps");
        let (mut inside, mut apart) = (0, 0);
        for (k, side) in sides.iter().enumerate().filter(|(_, s)| s.is_some()) {
            let c = compare_light(&saving, &g, k, &saved.visibility[k], &whole.visibility[k]);
            if backend == BackendKind::Cpu {
                assert_eq!(c.differ, 0, "cpu: light {k} ({side:?}) differs at {} of {} pixels", c.differ, c.inside);
            }
            inside += c.inside;
            apart += c.apart;
        }
        // The GPU's tiles lie at an offset in one texture: its rasterizer and sampler work that offset in
        // at their own precision (a vertex snapped a 256th of a texel aside, a filter weight off by 1e-5),
        // so a shadow edge may fall a texel aside at a rare pixel.
        let share = apart as f64 / inside.max(1) as f64;
        assert!(inside > 10_000 && share < 5e-4, "{backend:?}: {apart} of {inside} pixels differ by over 1/100");
        let mut granted: Vec<u32> = sides.iter().flatten().copied().collect();
        granted.sort_unstable();
        granted.dedup();
        assert!(granted.len() >= 3 && granted.iter().all(|&s| s < asked), "{backend:?}: tiles of {granted:?}");
    }
}

/// On `yard` with the camera turning a few degrees a frame about the point it looks at, the lights (all
/// still) keep their atlas tiles and their builds (`cached_builds`), and a kept build shows what building
/// again in the same tiles shows, to the bit: no other light drew into a kept tile. On both backends.
#[test]
fn still_lights_keep_their_tiles_and_builds_while_the_camera_turns() {
    use shadow_core::glam::Mat3;
    use shadow_core::scene::ShadowUpdate;
    let start = yard();
    let turned = |degrees: f32| {
        let mut f = start.clone();
        let c = &mut f.camera;
        c.eye = c.target + Mat3::from_rotation_y(degrees.to_radians()) * (c.eye - c.target);
        f
    };
    let every = |f: &FrameInputs| FrameInputs {
        shadows: vec![LightShadow { update: ShadowUpdate::EveryFrame, ..LightShadow::default() }; f.lights.len()],
        ..f.clone()
    };
    let mut renderer = Renderer::new(TechniqueRegistry::builtin());
    let mut backends = vec![BackendKind::Cpu];
    if super::with_wgpu("tiles kept while the camera turns").is_some() {
        backends.push(BackendKind::Wgpu);
    }
    let spec = TechniqueSpec::parse("shadow-map:res=1024").expect("spec");
    for backend in backends {
        let mut kept = renderer.prepare(backend, &spec).expect("technique");
        let mut built = renderer.prepare(backend, &spec).expect("technique");
        let mut moved_by = Vec::new();
        for (i, frame) in [0.0f32, 2.0, 4.0, 6.0, 8.0].map(turned).iter().enumerate() {
            let a = renderer.run_prepared(&mut kept, frame, WIDTH, HEIGHT).expect("frame keeping builds");
            let b = renderer.run_prepared(&mut built, &every(frame), WIDTH, HEIGHT).expect("frame building all");
            assert_eq!(a.atlas, b.atlas, "{backend:?} frame {i}: the plans differ");
            for (k, (va, vb)) in a.visibility.iter().zip(&b.visibility).enumerate() {
                assert!(va.data() == vb.data(), "{backend:?} frame {i}: light {k}'s kept build differs");
            }
            let reused = a.stats.counters.extra.get("cached_builds").copied().unwrap_or(0.0);
            let built_now = b.stats.counters.extra.get("cached_builds").copied().unwrap_or(0.0);
            assert_eq!(built_now, 0.0, "{backend:?}: every-frame lights kept a build");
            if i > 0 {
                moved_by.push(reused);
            }
        }
        // 46 to 49 of the lights in view here; 3 to 22 with every plan laid afresh.
        assert!(moved_by.iter().all(|&n| n >= 30.0), "{backend:?}: builds kept per frame {moved_by:?}");
    }
}
