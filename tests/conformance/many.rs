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
