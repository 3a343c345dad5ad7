//! Models at the extremes of the coordinates the loaders accept, on both backends: a tetrahedron of side
//! 1e13 and one of side 1e17 (the limit), staged to one unit as a model file of that size would be. Face
//! planes and the staging transform's inverse pass f32's range there unless computed with care; the
//! volumes must still match the ray-traced reference and the GPU's shading normals must stay finite.
//! And a lone triangle of side 1e14 standing upright: its normals, from a face normal whose squared length
//! passes f32's range, must still say which way it faces, or the reference at the CPU's pixels shadows it.

use shadow_core::glam::{Mat4, Vec3};
use shadow_core::technique::TechniqueSpec;
use shadow_core::{FrameInputs, Material, Mesh, Scene, scenes};
use shadowlab::BackendKind;
use shadowlab::compare::{CompareJob, run_compare};

/// A model of `triangles` over `corners` scaled by `size`, staged on a ground as a model file would be.
fn staged(corners: &[Vec3], triangles: Vec<[u32; 3]>, size: f32) -> Scene {
    let mesh = Mesh::new(corners.iter().map(|&v| v * size).collect(), triangles).expect("mesh");
    let mut s = Scene::new();
    let m = s.add_mesh(mesh);
    let mat = s.add_material(Material::default());
    s.add_instance("model", m, mat, Mat4::IDENTITY).expect("instance");
    scenes::stage_model(&mut s, true);
    s
}

fn tetrahedron(size: f32) -> Scene {
    let corners = [Vec3::ZERO, Vec3::X, Vec3::Z, Vec3::new(0.2, 1.0, 0.2)];
    staged(&corners, vec![[0, 1, 2], [0, 3, 1], [1, 3, 2], [0, 2, 3]], size)
}

/// `techniques` on both backends against the ray-traced reference of `scene`, each at most 0.05% off and
/// shaded without NaN normals.
fn holds(renderer: &mut shadowlab::Renderer, scene: &Scene, name: &str, techniques: &[&str]) {
    let frame = FrameInputs::from_scene(scene, scene.cameras().next().expect("camera").0).expect("frame");
    let job = CompareJob {
        scene: name.into(),
        frame: &frame,
        width: 256,
        height: 256,
        techniques: techniques.iter().copied().map(TechniqueSpec::named).collect(),
        reference: TechniqueSpec::named("ray-traced"),
        soft_reference: None,
        backends: vec![BackendKind::Cpu, BackendKind::Wgpu],
        out_dir: None,
    };
    for r in run_compare(renderer, &job, |_| {}).expect("compare").results {
        let (mismatch, flip) = (r.vs_reference["mismatch"], r.vs_reference["flip_mean"]);
        let what = format!("{name}: {} on {}", r.technique, r.backend);
        assert!(mismatch <= 0.0005, "{what}: mismatch {:.3}%", mismatch * 100.0);
        // NaN normals shade black: FLIP 0.2 where the G-buffer lost them.
        assert!(flip <= 0.01, "{what}: FLIP {flip:.4}");
    }
}

#[test]
fn volumes_and_shading_hold_at_the_largest_accepted_coordinates() {
    let Some(mut renderer) = super::with_wgpu("the large-coordinate volumes") else { return };
    for size in [1e13, shadow_core::mesh::MAX_COORDINATE] {
        let techniques = ["shadow-volume-zfail", "shadow-volume-zpass", "hybrid"];
        holds(&mut renderer, &tetrahedron(size), &format!("tetrahedron {size:e}"), &techniques);
    }
}

#[test]
fn an_upright_triangle_of_side_1e14_is_lit_in_the_reference_at_every_backends_pixels() {
    let Some(mut renderer) = super::with_wgpu("the large upright triangle") else { return };
    let triangle = staged(&[Vec3::ZERO, Vec3::X, Vec3::Y], vec![[0, 1, 2]], 1e14);
    holds(&mut renderer, &triangle, "upright triangle 1e14", &["shadow-volume-zfail", "shadow-map"]);
}
