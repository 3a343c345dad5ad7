//! Scenes of many small meshes on the GPU: their adjacency is uploaded into a few shared buffers, not
//! four buffers a mesh (a device allocator's cost per buffer grows with the buffers it holds: a scene of
//! 20 000 one-triangle objects spent minutes there), and the volumes read each mesh's share right.

use shadow_core::glam::{Mat4, Vec3};
use shadow_core::technique::TechniqueSpec;
use shadow_core::{FrameInputs, Material, Mesh, Scene, scenes};
use shadow_wgpu::WgpuContext;
use shadowlab::BackendKind;
use shadowlab::compare::{CompareJob, run_compare};

/// `n` small tetrahedra, each a mesh of its own, in a grid over a ground, staged as a model file would be.
fn tetrahedra(n: usize) -> Scene {
    let corners = [Vec3::ZERO, Vec3::X, Vec3::Z, Vec3::new(0.2, 1.0, 0.2)];
    let triangles = vec![[0, 1, 2], [0, 3, 1], [1, 3, 2], [0, 2, 3]];
    let mut s = Scene::new();
    let material = s.add_material(Material::default());
    let side = (n as f32).sqrt().ceil() as usize;
    for i in 0..n {
        let at = Vec3::new((i % side) as f32 * 1.7, 0.3 * (i % 3) as f32, (i / side) as f32 * 1.7);
        let mesh = Mesh::new(corners.iter().map(|&c| c + at).collect(), triangles.clone()).expect("mesh");
        let mesh = s.add_mesh(mesh);
        s.add_instance(&format!("tetrahedron {i}"), mesh, material, Mat4::IDENTITY).expect("instance");
    }
    scenes::stage_model(&mut s, true);
    s
}

#[test]
fn many_meshes_share_their_adjacency_buffers_and_cast_right() {
    if crate::with_wgpu("many meshes' adjacency").is_none() {
        return;
    }
    let scene = tetrahedra(900);
    let frame = FrameInputs::from_first_camera(&scene).expect("frame");
    let mut cx = WgpuContext::new(&shadow_wgpu::AdapterChoice { name: None, allow_software: true }).expect("context");
    let before = cx.created();
    cx.upload_adjacency(&frame);
    let made = cx.created().since(before).buffers;
    assert!(made <= 1, "{made} buffers for the adjacency of {} meshes", frame.instances.len());

    let Some(mut renderer) = crate::with_wgpu("many meshes' volumes") else { return };
    let job = CompareJob {
        scene: "tetrahedra".into(),
        frame: &frame,
        width: 192,
        height: 192,
        techniques: ["shadow-volume-zpass", "shadow-volume-zfail"].map(TechniqueSpec::named).to_vec(),
        reference: TechniqueSpec::named("ray-traced"),
        soft_reference: None,
        backends: vec![BackendKind::Cpu, BackendKind::Wgpu],
        out_dir: None,
    };
    for r in run_compare(&mut renderer, &job, |_| {}).expect("compare").results {
        let mismatch = r.vs_reference["mismatch"];
        let what = format!("{} on {}", r.technique, r.backend);
        assert!(mismatch <= 0.0005, "{what}: mismatch {:.3}% against the reference", mismatch * 100.0);
    }
    let spec = TechniqueSpec::named("shadow-volume-zpass");
    let run = renderer.run(BackendKind::Wgpu, &frame, 192, 192, &spec).expect("a frame");
    let shadowed = run.visibility[0].data().iter().filter(|&&v| v == 0.0).count();
    assert!(shadowed > 500, "only {shadowed} pixels in the tetrahedra's shadows");
}

/// The `props` scene, whose three meshes are drawn by thousands of instances, casts what the same scene
/// with a copy of each mesh per instance casts: the references (whose ray casting keeps each shared
/// mesh once, under a tree of its instances) and the rasterized techniques, on each backend, for each
/// light, pixel for pixel.
#[test]
fn instances_cast_what_copies_of_their_meshes_cast() {
    let Some(mut renderer) = crate::with_wgpu("props against its unshared copy") else { return };
    let params = scenes::SceneParams::default();
    let shared = scenes::build("props", &params).expect("props");
    let mut unshared = scenes::build("props", &params).expect("props");
    assert!(unshared.unshare_meshes() > 3000, "every instance but the first of each mesh gets a copy");
    let frames = [&shared, &unshared].map(|s| FrameInputs::from_first_camera(s).expect("frame"));
    assert_eq!(frames[0].lights.len(), 2, "a sun and a spot light");
    let runs = [
        (BackendKind::Cpu, "ray-traced"),
        (BackendKind::Cpu, "shadow-map"),
        (BackendKind::Wgpu, "shadow-map"),
        (BackendKind::Cpu, "shadow-volume-zfail"),
        (BackendKind::Wgpu, "shadow-volume-zfail"),
        (BackendKind::Wgpu, "volume-reconstruction"),
        (BackendKind::Wgpu, "second-depth-shadow-map"),
    ];
    for (backend, technique) in runs {
        let spec = TechniqueSpec::named(technique);
        let [a, b] = frames.each_ref().map(|f| renderer.run(backend, f, 160, 120, &spec).expect("a frame"));
        for (light, (a, b)) in a.visibility.iter().zip(&b.visibility).enumerate() {
            let shadowed = a.data().iter().filter(|&&v| v == 0.0).count();
            let what = format!("{technique} on {}, light {light}", backend.name());
            assert!(shadowed > a.data().len() / 100, "{what}: {shadowed} pixels in shadow");
            assert!(a.data() == b.data(), "{what}: the pictures differ");
        }
    }
}

/// The GPU draws the instances of a mesh together, one draw a run of them, though the frame lists
/// `props`' rocks, crates and posts mixed: the instance buffer holds each mesh's instances side by side,
/// and names each instance by its index in the frame.
#[test]
fn instances_of_a_mesh_are_drawn_together() {
    if crate::with_wgpu("props' draws").is_none() {
        return;
    }
    let mut cx = WgpuContext::new(&shadow_wgpu::AdapterChoice { name: None, allow_software: true }).expect("context");
    let scene = scenes::build("props", &scenes::SceneParams::default()).expect("props");
    let frame = FrameInputs::from_first_camera(&scene).expect("frame");
    let meshes: std::collections::HashSet<_> = frame.instances.iter().map(|i| i.mesh_key).collect();
    let changes = frame.instances.windows(2).filter(|w| w[0].mesh_key != w[1].mesh_key).count();
    assert!(changes > 100, "the frame lists its instances mixed ({changes} changes of mesh)");
    cx.upload_meshes(&frame);
    cx.instances(&frame);
    let order = cx.cache.order();
    let runs = order.runs(&frame, |i| i.casts_shadow);
    assert_eq!(runs.len(), meshes.len(), "a draw a mesh, for {} instances", frame.instances.len());
    let mut slots: Vec<u32> = (0..frame.instances.len()).map(|i| order.slot(i)).collect();
    let listed: Vec<usize> = order.instances().collect();
    assert!(listed.iter().enumerate().all(|(s, &i)| slots[i] == s as u32), "slots and instances disagree");
    slots.sort_unstable();
    assert!(slots.iter().enumerate().all(|(s, &t)| t == s as u32), "every instance in a slot of its own");
    for (first, run) in runs {
        let mesh = frame.instances[first].mesh_key;
        assert!(listed[run.start as usize..run.end as usize].iter().all(|&i| frame.instances[i].mesh_key == mesh));
    }
}

/// z-pass draws no caps, so it keeps no room for them: a scene whose side and cap records together
/// (eight bytes each, three of each a face at most) would pass the device's largest storage binding
/// still casts its volumes on the GPU, as the CPU casts them.
#[test]
fn z_pass_keeps_no_room_for_caps_it_never_draws() {
    let Some(mut renderer) = crate::with_wgpu("z-pass over millions of faces") else { return };
    let cx = WgpuContext::new(&shadow_wgpu::AdapterChoice { name: None, allow_software: true }).expect("context");
    let limits = cx.device.limits();
    let most = limits.max_storage_buffer_binding_size.min(limits.max_buffer_size);
    let ball = shadow_core::procedural::sphere(0.3, 32, 16).expect("sphere");
    let faces = ball.triangle_count() as u64;
    // Enough balls that their caps would not fit beside their side records, while the side records do.
    let count = (most / (8 * 6 * faces) + 1) as usize;
    assert!(8 * 3 * faces * count as u64 <= most, "the side records fit");
    let mut s = Scene::new();
    let material = s.add_material(Material::default());
    let mesh = s.add_mesh(ball);
    let side = (count as f32).sqrt().ceil() as usize;
    for i in 0..count {
        let at = Vec3::new((i % side) as f32, 0.3, (i / side) as f32);
        s.add_instance(&format!("ball {i}"), mesh, material, Mat4::from_translation(at)).expect("instance");
    }
    scenes::stage_model(&mut s, true);
    let frame = FrameInputs::from_first_camera(&s).expect("frame");
    let spec = TechniqueSpec::named("shadow-volume-zpass");
    let gpu = renderer.run(BackendKind::Wgpu, &frame, 128, 128, &spec).expect("z-pass on the GPU");
    let cpu = renderer.run(BackendKind::Cpu, &frame, 128, 128, &spec).expect("z-pass on the CPU");
    let (gpu, cpu) = (gpu.visibility[0].data(), cpu.visibility[0].data());
    let shadowed = gpu.iter().filter(|&&v| v == 0.0).count();
    assert!(shadowed > gpu.len() / 100, "{shadowed} pixels in shadow");
    let differ = gpu.iter().zip(cpu).filter(|(a, b)| a != b).count();
    assert!(differ <= gpu.len() / 200, "{differ} of {} pixels differ from the CPU's", gpu.len());
}

/// Ten thousand instances of one thousand-triangle mesh: the GPU holds the mesh and its adjacency once
/// (a few buffers, not some per instance), and the CPU's ray-casting BVH keeps it once under a tree of
/// its instances.
#[test]
fn ten_thousand_instances_of_one_mesh_hold_one_copy() {
    if crate::with_wgpu("ten thousand instances' uploads").is_none() {
        return;
    }
    let ball = shadow_core::procedural::sphere(0.3, 32, 16).expect("sphere");
    assert!((900..1100).contains(&ball.triangle_count()), "{} triangles", ball.triangle_count());
    let mut s = Scene::new();
    let material = s.add_material(Material::default());
    let mesh = s.add_mesh(ball);
    for i in 0..10_000 {
        let at = Vec3::new((i % 100) as f32, 0.3, (i / 100) as f32);
        s.add_instance(&format!("ball {i}"), mesh, material, Mat4::from_translation(at)).expect("instance");
    }
    scenes::stage_model(&mut s, true);
    let frame = FrameInputs::from_first_camera(&s).expect("frame");
    let mut cx = WgpuContext::new(&shadow_wgpu::AdapterChoice { name: None, allow_software: true }).expect("context");
    let before = cx.created();
    let t0 = std::time::Instant::now();
    cx.upload_meshes(&frame);
    cx.upload_adjacency(&frame);
    let made = cx.created().since(before).buffers;
    println!("uploaded in {:.1} ms: {made} buffers", t0.elapsed().as_secs_f64() * 1e3);
    assert!(made <= 12, "{made} buffers for two meshes drawn by {} instances", frame.instances.len());
    let t0 = std::time::Instant::now();
    let bvh = shadow_cpu::bvh::SceneBvh::build(&frame);
    println!("BVH built in {:.1} ms", t0.elapsed().as_secs_f64() * 1e3);
    assert_eq!(bvh.instanced(), (1, 10_000), "the ball is kept once for its instances");
    assert_eq!(bvh.triangle_count(), frame.triangle_count(), "every instance's triangles cast");
}
