//! Hard techniques on the CPU backend against the exact reference, at 512x512 with each scene's default
//! light. Every number is computed here; nothing is compared with stored pictures.

use std::path::Path;

use shadow_core::metrics::{VisibilityMetrics, compare_visibility, measured_pixels};
use shadow_core::scenes::{self, SceneParams};
use shadow_core::technique::{DynShadowTechnique, Stateful, TechniqueSettings};
use shadow_core::{FrameInputs, Scene};
use shadow_cpu::{CpuBackend, CpuContext, CpuError, render_frame};
use shadow_hard::{RayTraced, ShadowMap, ShadowVolume};

const SIZE: u32 = 512;

fn frame(scene: &Scene) -> FrameInputs {
    let cam = scene.cameras().next().expect("camera").0;
    FrameInputs::from_scene(scene, cam).expect("frame")
}

/// Errors of each technique against `ray-traced`.
fn measure(scene: &Scene, techniques: Vec<Box<dyn DynShadowTechnique<CpuBackend>>>) -> Vec<VisibilityMetrics> {
    let f = frame(scene);
    let mut cx = CpuContext::new();
    let mut reference = Stateful::<CpuBackend, _>::new(RayTraced::defaults(), String::new());
    let r = render_frame(&mut cx, &f, SIZE, SIZE, &mut reference).expect("reference");
    let g = &r.gbuffer;
    let mask = measured_pixels(&g.receiver, &g.position, &g.geometric_normal, &r.light_views[0]);
    assert!(mask.data().iter().filter(|&&m| m).count() > 10_000, "too few measured pixels");
    // A reference with no shadow at all would make every test below pass: make sure there is one.
    assert!(r.visibility[0].data().iter().zip(mask.data()).any(|(&v, &m)| m && v < 0.5), "no shadow in view");
    techniques
        .into_iter()
        .map(|mut t| {
            let out = render_frame(&mut cx, &f, SIZE, SIZE, t.as_mut()).expect("technique");
            compare_visibility(&out.visibility[0], &r.visibility[0], &mask).expect("same size")
        })
        .collect()
}

fn volume(v: ShadowVolume) -> Box<dyn DynShadowTechnique<CpuBackend>> {
    Stateful::boxed(v, String::new())
}

fn spot_on_a_plane() -> Option<Scene> {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../shared/models/spot.obj");
    if !path.exists() {
        eprintln!("skipping spot.obj: {} not found", path.display());
        return None;
    }
    let mut s = shadow_core::assets::load(&path).expect("spot.obj loads");
    scenes::stage_model(&mut s, true);
    Some(s)
}

#[test]
fn zfail_is_exact_on_every_scene() {
    let mut cases: Vec<(String, Scene)> = scenes::ALL
        .iter()
        .map(|i| (i.name.to_string(), scenes::build(i.name, &SceneParams::default()).expect("scene")))
        .collect();
    cases.extend(spot_on_a_plane().map(|s| ("spot.obj".to_string(), s)));
    for (name, scene) in cases {
        let lit_eye = name != "room";
        let mut ts = vec![volume(ShadowVolume::ZFAIL)];
        if lit_eye {
            ts.push(volume(ShadowVolume::ZPASS));
        }
        let m = measure(&scene, ts);
        assert!(m[0].mismatch <= 0.0005, "{name}: z-fail mismatch {:.4}%", m[0].mismatch * 100.0);
        if lit_eye {
            assert!(m[1].mismatch <= 0.0005, "{name}: z-pass mismatch {:.4}%", m[1].mismatch * 100.0);
        }
    }
}

#[test]
fn zpass_fails_with_the_eye_in_shadow() {
    let room = scenes::build("room", &SceneParams::default()).expect("room");
    let m = measure(&room, vec![volume(ShadowVolume::ZPASS), volume(ShadowVolume::ZFAIL)]);
    assert!(m[0].mismatch > 0.5, "z-pass should invert the view: {:.2}%", m[0].mismatch * 100.0);
    assert!(m[1].mismatch <= 0.0005);
}

#[test]
fn shadow_map_mismatch_falls_with_resolution() {
    let cyl = scenes::build("cylinder", &SceneParams::default()).expect("cylinder");
    let map = |res| {
        Stateful::boxed(
            {
                let mut s = ShadowMap::defaults();
                s.resolution = res;
                s
            },
            String::new(),
        ) as Box<dyn DynShadowTechnique<CpuBackend>>
    };
    let m = measure(&cyl, vec![map(256), map(1024), map(2048), map(4096)]);
    let at_2048 = &m[2];
    assert!(at_2048.mismatch <= 0.02, "2048: {:.3}%", at_2048.mismatch * 100.0);
    assert!(at_2048.interior_false_shadow <= 0.001, "acne at 2048: {:.3}%", at_2048.interior_false_shadow * 100.0);
    assert!(
        m[0].mismatch > m[1].mismatch && m[1].mismatch > m[3].mismatch,
        "{:?}",
        m.iter().map(|x| x.mismatch).collect::<Vec<_>>()
    );
}

#[test]
fn bad_requests_are_refused_before_allocating() {
    let scene = scenes::build("cylinder", &SceneParams::default()).expect("cylinder");
    let f = frame(&scene);
    let mut cx = CpuContext::new();
    let mut t = Stateful::<CpuBackend, _>::new(ShadowVolume::ZFAIL, String::new());
    for (w, h) in [(0, 512), (512, 0), (20_000, 20_000)] {
        assert!(matches!(render_frame(&mut cx, &f, w, h, &mut t), Err(CpuError::BadSize { .. })), "{w}x{h}");
    }
    // Six 16384^2 cube faces (6 GiB) for a point light are refused; one such map for a spot light is not.
    let mut point = scene;
    scenes::retype_lights(&mut point, scenes::LightType::Point);
    let f = frame(&point);
    let mut huge = Stateful::<CpuBackend, _>::new(
        {
            let mut s = ShadowMap::defaults();
            s.resolution = 16384;
            s
        },
        String::new(),
    );
    let err = render_frame(&mut cx, &f, 64, 64, &mut huge).err().expect("refused");
    assert!(err.to_string().contains("shadow maps") && err.to_string().contains("over the limit"), "{err}");
    // A NaN transform never reaches a frame: the scene refuses it.
    let mut s = Scene::new();
    let n = s.add_node("n", None, glam::Mat4::IDENTITY).expect("node");
    assert!(s.set_local_transform(n, glam::Mat4::from_scale(glam::Vec3::splat(f32::NAN))).is_err());
}

/// A tetrahedron of side `size` standing on a staged ground, as a model file of that size would load.
fn tetrahedron_staged(size: f32) -> Scene {
    use shadow_core::glam::{Mat4, Vec3};
    let p = [Vec3::ZERO, Vec3::X, Vec3::Z, Vec3::new(0.2, 1.0, 0.2)].map(|v| v * size);
    let mesh =
        shadow_core::Mesh::new(p.to_vec(), vec![[0, 1, 2], [0, 3, 1], [1, 3, 2], [0, 2, 3]]).expect("tetrahedron");
    let mut s = Scene::new();
    let m = s.add_mesh(mesh);
    let mat = s.add_material(shadow_core::Material::default());
    s.add_instance("tetrahedron", m, mat, Mat4::IDENTITY).expect("instance");
    scenes::stage_model(&mut s, true);
    s
}

#[test]
fn volumes_are_exact_at_every_scale_the_loaders_accept() {
    // Staged to one unit, a model of side 1e13 and up has face planes whose offsets pass f32's range and a
    // staging scale whose determinant is below f32's normal numbers.
    for size in [1.0, 1e13, shadow_core::mesh::MAX_COORDINATE] {
        let scene = tetrahedron_staged(size);
        let m = measure(&scene, vec![volume(ShadowVolume::ZFAIL), volume(ShadowVolume::ZPASS)]);
        for (name, m) in ["z-fail", "z-pass"].iter().zip(&m) {
            assert!(m.mismatch <= 0.0005, "side {size:e}: {name} mismatch {:.4}%", m.mismatch * 100.0);
        }
    }
}

/// The reference through `cutout`'s checkerboard card lights half of the ground under it, as the board
/// is half clear; the same card made opaque shadows all of it.
#[test]
fn the_reference_sees_through_clear_texels() {
    use shadow_core::material::AlphaMode;
    use shadow_core::scenes::cutouts::card_shadow_lit_share;
    let lit_share = |scene: &Scene| {
        let mut reference = Stateful::<CpuBackend, _>::new(RayTraced::defaults(), String::new());
        let r = render_frame(&mut CpuContext::new(), &frame(scene), SIZE, SIZE, &mut reference).expect("reference");
        card_shadow_lit_share(r.receiver_points(0))
    };
    let mut scene = scenes::build("cutout", &SceneParams::default()).expect("cutout");
    let (share, pixels) = lit_share(&scene);
    assert!(pixels > 20_000, "{pixels} pixels under the card");
    assert!((share - 0.5).abs() <= 0.005, "the reference lights {:.2}% of the card's shadow", share * 100.0);
    let card = scene.materials().find(|(_, m)| m.name == "checkerboard").expect("the card's material").0;
    scene.material_mut(card).expect("material").alpha_mode = AlphaMode::Opaque;
    let (solid, _) = lit_share(&scene);
    assert!(solid < 0.001, "an opaque card's shadow is {:.2}% lit", solid * 100.0);
}
