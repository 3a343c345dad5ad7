//! Animated scenes on the GPU: the compute pass poses skinned and morphed meshes as the CPU does (held
//! vertex for vertex), the two backends see the same shadows of a moving figure, and recorded frames of
//! a playing clip make no buffer or texture after the first. Without a wgpu adapter these print one
//! line and pass, unless SHADOWLAB_REQUIRE_GPU=1.

use shadow_core::deform::{Deformers, MorphTarget};
use shadow_core::glam::{Mat4, Quat, Vec3, Vec4};
use shadow_core::mesh::{face_normal, power_of_two_unit};
use shadow_core::metrics::compare_visibility;
use shadow_core::scene::Skin;
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
/// weights are set per time by [`morph_weights`]. Beside it, a twin drawing the same mesh through a skin
/// of its own (the same joints, bound a step to the side) and a morphed ball that is not skinned, placed
/// by its node: three nodes posed in three ways, two of them sharing one mesh.
fn morphed_walker() -> (Scene, [shadow_core::NodeKey; 3]) {
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
    let material = scene.node(node).and_then(|n| n.mesh()).expect("a drawn node").1;
    let twin = scene.add_instance("twin", mesh_key, material, Mat4::IDENTITY).expect("twin");
    let skin = scene.node_skin(node).and_then(|k| scene.skin(k)).expect("the figure's skin").clone();
    let aside = Mat4::from_translation(Vec3::new(-0.6, 0.0, 0.2));
    let inverse_bind_matrices = skin.inverse_bind_matrices.iter().map(|m| *m * aside).collect();
    let skin = scene.add_skin(Skin { name: "twin".into(), inverse_bind_matrices, ..skin }).expect("skin");
    scene.set_skin(twin, Some(skin)).expect("bound");
    let ball = shadow_core::procedural::sphere(0.2, 24, 12).expect("a ball");
    let bulge = MorphTarget {
        positions: ball.positions().iter().map(|p| Vec3::new(p.x * 0.8, 0.0, 0.0)).collect(),
        normals: Some(ball.normals().iter().map(|n| Vec3::new(-0.5 * n.x, 0.0, 0.0)).collect()),
    };
    let ball = ball.with_deformers(Deformers { skin: None, morph_targets: vec![bulge] }).expect("deformers");
    let ball = scene.add_mesh(ball);
    let place = Mat4::from_rotation_translation(Quat::from_rotation_y(0.7), Vec3::new(0.8, 0.4, 0.3));
    let ball = scene.add_instance("ball", ball, material, place).expect("ball");
    (scene, [node, twin, ball])
}

/// The morph weights of the three nodes at `t`: the figure's two move, one of them through zero
/// (skipped, as the CPU skips it); the twin's stand still; the ball's swells and shrinks, never to zero
/// (at zero it would stand unposed).
fn morph_weights(t: f32) -> [Vec<f32>; 3] {
    [vec![(2.0 * t).sin().max(0.0), 0.5 + 0.5 * (3.0 * t).cos()], vec![0.3, 0.0], vec![1.1 + t.sin()]]
}

/// The GPU's pose of a skinned and morphed figure, its twin and a morphed ball ([`morphed_walker`])
/// against the CPU's at ten times over the clip: posed positions within 1e-5 of the mesh's size, normals
/// within 1e-5, welded positions where their mesh vertices are, and each face's plane the CPU's rule over
/// the GPU's welded positions.
#[test]
fn the_gpu_poses_meshes_as_the_cpu_does() {
    if crate::with_wgpu("GPU posing").is_none() {
        return;
    }
    let mut cx = WgpuContext::new(&shadow_wgpu::AdapterChoice { name: None, allow_software: true }).expect("context");
    let (mut scene, nodes) = morphed_walker();
    let duration = scene.animation_duration();
    assert!(duration > 1.0, "walker's clip lasts {duration} s");
    let mut worst = [0.0f32; 3];
    for t in tenths(duration) {
        scene.pose(t).expect("pose");
        for (node, weights) in nodes.iter().zip(morph_weights(t)) {
            scene.set_morph_weights(*node, weights).expect("weights");
        }
        let frame = FrameInputs::from_first_camera(&scene).expect("frame");
        cx.upload_meshes(&frame);
        for node in nodes {
            let inst = frame.instances.iter().find(|i| i.node == node).expect("a posed node");
            let name = scene.node(node).expect("node").name();
            let case = format!("{name} at {t} s");
            assert!(inst.pose.is_some(), "{case}: not posed");
            let gpu = cx.read_posed(inst).expect("read back").expect("posed on the GPU");
            let cpu = &inst.mesh;
            let size = cpu.bounds().size().length();
            let far = |a: &[Vec3], b: &[Vec3]| a.iter().zip(b).map(|(x, y)| (*x - *y).length()).fold(0.0, f32::max);
            assert_eq!(gpu.positions.len(), cpu.positions().len(), "{case}");
            let positions = far(&gpu.positions, cpu.positions()) / size;
            let normals = far(&gpu.normals, cpu.normals());
            let welded = far(&gpu.welded, inst.adjacency.positions()) / size;
            assert!(positions <= 1e-5, "{case}: a posed position {positions:e} of the size away from the CPU's");
            assert!(normals <= 1e-5, "{case}: a posed normal {normals:e} away from the CPU's");
            assert!(welded <= 1e-5, "{case}: a welded position {welded:e} of the size away from the CPU's");
            for (f, (plane, tri)) in gpu.planes.iter().zip(inst.adjacency.triangles()).enumerate() {
                let n = power_of_two_unit(face_normal(tri.map(|v| gpu.welded[v as usize])));
                let want = if n == Vec3::ZERO { Vec4::ZERO } else { n.extend(-n.dot(gpu.welded[tri[0] as usize])) };
                let off = (*plane - want).abs().max_element() / want.abs().max_element().max(1.0);
                assert!(off <= 1e-5, "{case}: face {f}'s plane {plane} is not {want}");
            }
            worst = [worst[0].max(positions), worst[1].max(normals), worst[2].max(welded)];
        }
        // The two nodes of one mesh stand apart: each was posed into buffers of its own.
        let [figure, twin] = [nodes[0], nodes[1]].map(|n| frame.instances.iter().find(|i| i.node == n).expect("node"));
        let apart = figure.mesh.positions().iter().zip(twin.mesh.positions()).map(|(a, b)| (*a - *b).length());
        assert!(apart.fold(0.0, f32::max) > 0.3, "at {t} s the twin stands where the figure does");
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

/// Recorded frames of `walker` as its clip plays, 100 of them a thirtieth of a second apart, for every
/// technique that can be recorded: nothing is made after the first frame, and
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
    let recordable = |name: &str| !crate::recorded::NOT_RECORDABLE.contains(&name);
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
