//! Models at the extremes of the coordinates the loaders accept, on both backends: a tetrahedron of side
//! 1e13 and one of side 1e17 (the limit), staged to one unit as a model file of that size would be. Face
//! planes and the staging transform's inverse pass f32's range there unless computed with care; the
//! volumes must still match the ray-traced reference and the GPU's shading normals must stay finite.

use shadow_core::glam::{Mat4, Vec3};
use shadow_core::technique::TechniqueSpec;
use shadow_core::{FrameInputs, Material, Mesh, Scene, scenes};
use shadowlab::BackendKind;
use shadowlab::compare::{CompareJob, run_compare};

fn tetrahedron(size: f32) -> Scene {
    let p = [Vec3::ZERO, Vec3::X, Vec3::Z, Vec3::new(0.2, 1.0, 0.2)].map(|v| v * size);
    let mesh = Mesh::new(p.to_vec(), vec![[0, 1, 2], [0, 3, 1], [1, 3, 2], [0, 2, 3]]).expect("tetrahedron");
    let mut s = Scene::new();
    let m = s.add_mesh(mesh);
    let mat = s.add_material(Material::default());
    s.add_instance("tetrahedron", m, mat, Mat4::IDENTITY).expect("instance");
    scenes::stage_model(&mut s, true);
    s
}

#[test]
fn volumes_and_shading_hold_at_the_largest_accepted_coordinates() {
    let Some(mut renderer) = super::with_wgpu("the large-coordinate volumes") else { return };
    for size in [1e13, shadow_core::mesh::MAX_COORDINATE] {
        let scene = tetrahedron(size);
        let frame = FrameInputs::from_scene(&scene, scene.cameras().next().expect("camera").0).expect("frame");
        let job = CompareJob {
            scene: format!("tetrahedron {size:e}"),
            frame: &frame,
            width: 256,
            height: 256,
            techniques: ["shadow-volume-zfail", "shadow-volume-zpass", "hybrid"].map(TechniqueSpec::named).to_vec(),
            reference: TechniqueSpec::named("ray-traced"),
            soft_reference: None,
            backends: vec![BackendKind::Cpu, BackendKind::Wgpu],
            out_dir: None,
        };
        for r in run_compare(&mut renderer, &job, |_| {}).expect("compare").results {
            let (mismatch, flip) = (r.vs_reference["mismatch"], r.vs_reference["flip_mean"]);
            let what = format!("side {size:e}: {} on {}", r.technique, r.backend);
            assert!(mismatch <= 0.0005, "{what}: mismatch {:.3}%", mismatch * 100.0);
            // NaN normals shade black: FLIP 0.2 where the G-buffer lost them.
            assert!(flip <= 0.01, "{what}: FLIP {flip:.4}");
        }
    }
}
