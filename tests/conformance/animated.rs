//! Animated scenes on the GPU: the compute pass poses skinned and morphed meshes as the CPU does (held
//! vertex for vertex), the two backends see the same shadows of a moving figure, and recorded frames of
//! a playing clip make no buffer or texture after the first. Without a wgpu adapter these print one
//! line and pass, unless SHADOWLAB_REQUIRE_GPU=1.

use shadow_core::deform::{Deformers, MorphTarget};
use shadow_core::glam::{Vec3, Vec4};
use shadow_core::mesh::{face_normal, power_of_two_unit};
use shadow_core::metrics::compare_visibility;
use shadow_core::scenes::{self, SceneParams};
use shadow_core::technique::TechniqueSpec;
use shadow_core::{FrameInputs, Image, Scene};
use shadow_wgpu::WgpuContext;
use shadowlab::BackendKind;

/// The times over a clip of `duration` seconds at which a test poses it: the middles of its tenths.
fn tenths(duration: f32) -> impl Iterator<Item = f32> {
    (0..10).map(move |k| (k as f32 + 0.5) * duration / 10.0)
}

/// `walker` with two morph targets added to its skinned body, so a pose runs both deformers: a swell
/// along the normals (with normal displacements that tilt them) and a lean that grows with height; their
/// weights are set per time by [`morph_weights`].
fn morphed_walker() -> (Scene, shadow_core::NodeKey) {
    let mut scene = scenes::build("walker", &SceneParams::default()).expect("walker");
    let (node, _, mesh_key, _) =
        scene.drawables().find(|(k, ..)| scene.node_skin(*k).is_some()).expect("a skinned node");
    let body = scene.mesh(mesh_key).expect("mesh").as_ref().clone();
    let skin = body.deformers().and_then(|d| d.skin.clone());
    let swell = MorphTarget {
        positions: body.normals().iter().map(|n| *n * 0.015).collect(),
        normals: Some(body.positions().iter().map(|p| Vec3::new(0.0, 0.0, 0.3 * p.y)).collect()),
    };
    let lean = MorphTarget {
        positions: body.positions().iter().map(|p| Vec3::new(0.05 * p.y, 0.0, 0.0)).collect(),
        normals: None,
    };
    let morphed = body.with_deformers(Deformers { skin, morph_targets: vec![swell, lean] }).expect("deformers");
    scene.replace_mesh(mesh_key, morphed).expect("mesh");
    (scene, node)
}

/// The morph weights at `t`: both move, one of them through zero (skipped, as the CPU skips it).
fn morph_weights(t: f32) -> Vec<f32> {
    vec![(2.0 * t).sin().max(0.0), 0.5 + 0.5 * (3.0 * t).cos()]
}

/// The GPU's pose of a skinned and morphed figure against the CPU's at ten times over its clip: posed
/// positions within 1e-5 of the figure's size, normals within 1e-5, welded positions where their mesh
/// vertices are, and each face's plane the CPU's rule over the GPU's welded positions.
#[test]
fn the_gpu_poses_meshes_as_the_cpu_does() {
    if crate::with_wgpu("GPU posing").is_none() {
        return;
    }
    let mut cx = WgpuContext::new(&shadow_wgpu::AdapterChoice { name: None, allow_software: true }).expect("context");
    let (mut scene, node) = morphed_walker();
    let duration = scene.animation_duration();
    assert!(duration > 1.0, "walker's clip lasts {duration} s");
    let mut worst = [0.0f32; 3];
    for t in tenths(duration) {
        scene.pose(t).expect("pose");
        scene.set_morph_weights(node, morph_weights(t)).expect("weights");
        let frame = FrameInputs::from_first_camera(&scene).expect("frame");
        cx.upload_meshes(&frame);
        let inst = frame.instances.iter().find(|i| i.node == node).expect("the figure");
        assert!(inst.pose.is_some(), "t = {t}: the figure is not posed");
        let gpu = cx.read_posed(inst).expect("read back").expect("posed on the GPU");
        let cpu = &inst.mesh;
        let size = cpu.bounds().size().length();
        let far = |a: &[Vec3], b: &[Vec3]| a.iter().zip(b).map(|(x, y)| (*x - *y).length()).fold(0.0, f32::max);
        assert_eq!(gpu.positions.len(), cpu.positions().len(), "t = {t}");
        let positions = far(&gpu.positions, cpu.positions()) / size;
        let normals = far(&gpu.normals, cpu.normals());
        let welded = far(&gpu.welded, inst.adjacency.positions()) / size;
        assert!(positions <= 1e-5, "t = {t}: a posed position {positions:e} of the size away from the CPU's");
        assert!(normals <= 1e-5, "t = {t}: a posed normal {normals:e} away from the CPU's");
        assert!(welded <= 1e-5, "t = {t}: a welded position {welded:e} of the size away from the CPU's");
        for (f, (plane, tri)) in gpu.planes.iter().zip(inst.adjacency.triangles()).enumerate() {
            let n = power_of_two_unit(face_normal(tri.map(|v| gpu.welded[v as usize])));
            let want = if n == Vec3::ZERO { Vec4::ZERO } else { n.extend(-n.dot(gpu.welded[tri[0] as usize])) };
            let off = (*plane - want).abs().max_element() / want.abs().max_element().max(1.0);
            assert!(off <= 1e-5, "t = {t}: face {f}'s plane {plane} is not {want}");
        }
        worst = [worst[0].max(positions), worst[1].max(normals), worst[2].max(welded)];
    }
    eprintln!(
        "GPU pose vs CPU over ten times: positions {:e}, normals {:e}, welded {:e}",
        worst[0], worst[1], worst[2]
    );
}

/// The share of pixels where two visibilities differ (lit against shadowed), over every pixel.
fn mismatch(a: &Image<f32>, b: &Image<f32>) -> f64 {
    let everywhere = Image::new(a.width(), a.height(), true);
    compare_visibility(a, b, &everywhere).expect("sizes").mismatch
}

/// The two backends on the moving scenes, `walker` (skinned) and `mill` (rigid parts turning), at three
/// times of their clips: visibility within 0.5% of each other for the shadow map, z-fail (the GPU
/// extruding the posed adjacency) and, under walker's spot light, penumbra wedges (built from the CPU's
/// pose, drawn over the GPU's).
#[test]
fn moving_scenes_agree_across_backends() {
    let Some(mut renderer) = crate::with_wgpu("animated cross-backend") else { return };
    const SIZE: u32 = 192;
    let mut rows = Vec::new();
    for name in ["walker", "mill"] {
        let mut scene = scenes::build(name, &SceneParams::default()).expect("scene");
        let duration = scene.animation_duration();
        for t in [0.13, 0.5, 0.81].map(|f| f * duration) {
            scene.pose(t).expect("pose");
            let frame = FrameInputs::from_first_camera(&scene).expect("frame");
            let wedges = (name == "walker").then_some("penumbra-wedges");
            for technique in ["shadow-map", "shadow-volume-zfail"].into_iter().chain(wedges) {
                let spec = TechniqueSpec::named(technique);
                let cpu = renderer.run(BackendKind::Cpu, &frame, SIZE, SIZE, &spec).expect("cpu");
                let gpu = renderer.run(BackendKind::Wgpu, &frame, SIZE, SIZE, &spec).expect("wgpu");
                let shadowed = gpu.visibility[0].data().iter().filter(|&&v| crate::shadowed(v)).count();
                assert!(shadowed > 200, "{name} at {t} s / {technique}: {shadowed} shadowed pixels");
                let m = mismatch(&cpu.visibility[0], &gpu.visibility[0]);
                rows.push(format!("{name} at {t:.2} s / {technique}: {:.3}%", 100.0 * m));
                assert!(m < 0.005, "{}", rows.last().map_or("", String::as_str));
            }
        }
    }
    eprintln!("{}", rows.join("\n"));
}

/// Techniques whose geometry the CPU still builds from its pose each frame and hands to the GPU in the
/// transient buffers: penumbra wedges' list grows and shrinks with the silhouette as the figure moves,
/// and the transient buffers grow with it.
const BUILT_ON_THE_CPU: [&str; 1] = ["penumbra-wedges"];

/// Recorded frames of `walker` as its clip plays, 100 of them a thirtieth of a second apart, for every
/// technique that can be recorded but [`BUILT_ON_THE_CPU`]: nothing is made after the first frame, and
/// the last frame's visibility is a fresh render's of that pose.
#[test]
fn a_playing_clip_allocates_nothing_after_the_first_frame() {
    use shadow_wgpu::{ColorTarget, FrameRecorder, readback};
    const FRAMES: u32 = 100;
    let Some(mut renderer) = crate::with_wgpu("animated recorded frames") else { return };
    let mut cx = WgpuContext::new(&shadow_wgpu::AdapterChoice { name: None, allow_software: true }).expect("context");
    let (w, h) = (128, 96);
    let target = shadow_wgpu::frame::layered(&cx, "host colour", w, h, 1, wgpu::TextureFormat::Rgba8UnormSrgb);
    let view = target.create_view(&Default::default());
    let color = ColorTarget { view: &view, format: target.format(), width: w, height: h };
    let mut failures = Vec::new();
    let mut checked = 0;
    let registry = renderer.registry().clone();
    let recordable = |name: &str| !crate::recorded::NOT_RECORDABLE.contains(&name) && !BUILT_ON_THE_CPU.contains(&name);
    for entry in registry.entries().iter().filter(|e| e.wgpu.is_some() && recordable(e.name)) {
        let mut scene = crate::scene_taken_by("walker", entry.lights);
        let spec = TechniqueSpec::named(entry.name);
        let mut technique = registry.wgpu(&spec).expect("technique");
        let mut recorder = FrameRecorder::new();
        let mut first = None;
        let mut last = None;
        for i in 0..FRAMES {
            scene.pose(i as f32 / 30.0).expect("pose");
            let frame = FrameInputs::from_first_camera(&scene).expect("frame");
            let mut encoder = cx.device.create_command_encoder(&Default::default());
            recorder
                .record(&mut cx, &mut encoder, &frame, technique.as_mut(), &color)
                .unwrap_or_else(|e| panic!("{}: {e}", entry.name));
            cx.queue.submit([encoder.finish()]);
            first.get_or_insert(cx.created());
            last = Some(frame);
        }
        let made = cx.created().since(first.unwrap_or_default());
        if made != shadow_wgpu::Created::default() {
            failures.push(format!("{}: {made:?}", entry.name));
        }
        let visibility = recorder.visibility().expect("a recorded frame");
        let visibility = readback::read_f32(&cx, visibility, 0, wgpu::TextureAspect::All).expect("read back");
        let fresh = renderer.run(BackendKind::Wgpu, &last.expect("a frame"), w, h, &spec).expect("a frame");
        failures.extend(crate::recorded::stale_or_unshadowed(entry.name, FRAMES, &visibility, &fresh.visibility[0]));
        checked += 1;
    }
    assert!(failures.is_empty(), "made after the first frame, or stale:\n{}", failures.join("\n"));
    assert!(checked >= 10, "only {checked} techniques checked");
}
