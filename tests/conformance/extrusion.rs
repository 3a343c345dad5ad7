//! The GPU's shadow volumes, found and extruded in a compute pass, against shadow-core's extrusion (the
//! reference, drawn by the same GPU with `extrusion=cpu`): on every built-in scene, under spot, point and
//! parallel light, and on a scene of open, non-manifold and mirrored casters lit by two lights at once,
//! both countings give the same visibility, byte for byte, and the same counters (silhouette edges,
//! volume triangles, fragments, stencil updates).

use shadow_core::glam::{Mat4, Vec2, Vec3};
use shadow_core::scenes::{self, LightType, SceneParams};
use shadow_core::technique::TechniqueSpec;
use shadow_core::{FrameInputs, Light, Material, Mesh, Scene, procedural};
use shadowlab::BackendKind;

const SIZE: u32 = 256;
const COUNTERS: [&str; 4] = ["silhouette_edges", "volume_triangles", "volume_fragments", "stencil_updates"];

/// Three quads on one edge (a non-manifold fan), an open tube (whose silhouette edges, between faces
/// cast as wound and faces cast turned around, weigh 2), a ground plane, and a cube drawn mirrored,
/// under a spot light and a parallel one.
fn fins_and_a_mirrored_cube() -> Scene {
    let fan = Mesh::new(
        vec![
            Vec3::new(0.0, 0.2, 0.0),
            Vec3::new(0.0, 0.7, 0.0),
            Vec3::new(0.3, 0.2, 0.1),
            Vec3::new(0.3, 0.7, 0.1),
            Vec3::new(-0.3, 0.2, 0.1),
            Vec3::new(-0.3, 0.7, 0.1),
            Vec3::new(0.0, 0.2, -0.3),
            Vec3::new(0.0, 0.7, -0.3),
        ],
        vec![[0, 2, 1], [1, 2, 3], [0, 1, 4], [1, 5, 4], [0, 6, 1], [1, 6, 7]],
    )
    .expect("fan");
    let mut s = Scene::new();
    let mat = s.add_material(Material::default());
    let fan = s.add_mesh(fan);
    s.add_instance("fan", fan, mat, Mat4::from_translation(Vec3::new(-0.3, 0.0, 0.0))).expect("fan");
    let cube = s.add_mesh(procedural::cuboid(Vec3::splat(0.3)).expect("cube"));
    let mirrored = Mat4::from_translation(Vec3::new(0.35, 0.15, 0.1)) * Mat4::from_scale(Vec3::new(-1.0, 1.0, 1.0));
    s.add_instance("mirrored cube", cube, mat, mirrored).expect("cube");
    let tube = [Vec2::new(0.12, 0.0), Vec2::new(0.12, 0.35)];
    let tube = s.add_mesh(procedural::lathe(&tube, 16, false).expect("tube"));
    s.add_instance("tube", tube, mat, Mat4::from_translation(Vec3::new(0.0, 0.05, 0.45))).expect("tube");
    let ground = s.add_mesh(procedural::plane(3.0, 3.0).expect("plane"));
    s.add_instance("ground", ground, mat, Mat4::IDENTITY).expect("ground");
    s.add_light(Light::spot(Vec3::new(1.0, 2.0, 1.2), Vec3::ZERO, 70.0));
    s.add_light(Light::directional(Vec3::new(-0.4, -1.0, -0.3)));
    scenes::stage_model(&mut s, false);
    s
}

fn cases() -> Vec<(String, Scene)> {
    let mut v: Vec<(String, Scene)> = scenes::names()
        .iter()
        .map(|n| (n.to_string(), scenes::build(n, &SceneParams::default()).expect("built-in scene")))
        .collect();
    for (n, t) in [("room", LightType::Point), ("primitives", LightType::Point), ("cubes", LightType::Directional)] {
        let params = SceneParams { light: Some(t), ..SceneParams::default() };
        v.push((format!("{n}-{t}"), scenes::build(n, &params).expect("built-in scene")));
    }
    v.push(("fins and a mirrored cube".into(), fins_and_a_mirrored_cube()));
    v
}

#[test]
fn the_compute_extrusion_counts_what_the_reference_counts() {
    let Some(mut renderer) = super::with_wgpu("the GPU extrusion") else { return };
    let mut failures = Vec::new();
    for (name, scene) in cases() {
        let frame = FrameInputs::from_first_camera(&scene).expect("frame");
        for technique in ["shadow-volume-zfail", "shadow-volume-zpass"] {
            let mut run = |spec: &str| {
                let spec = TechniqueSpec::parse(spec).expect("spec");
                renderer.run(BackendKind::Wgpu, &frame, SIZE, SIZE, &spec).expect("a wgpu frame")
            };
            let (gpu, cpu) = (run(technique), run(&format!("{technique}:extrusion=cpu")));
            let what = format!("{name}, {technique}");
            let shadowed: usize = gpu.visibility.iter().map(|v| v.data().iter().filter(|&&x| x == 0.0).count()).sum();
            assert!(shadowed > 0, "{what}: nothing is shadowed, so nothing was compared");
            for (k, (g, c)) in gpu.visibility.iter().zip(&cpu.visibility).enumerate() {
                let differ = g.data().iter().zip(c.data()).filter(|(a, b)| a != b).count();
                if differ > 0 {
                    failures.push(format!("{what}: light {k}: {differ} pixels differ"));
                }
            }
            let (g_counters, c_counters) = (gpu.stats.counters.entries(), cpu.stats.counters.entries());
            let get = |entries: &[(String, f64)], name: &str| entries.iter().find(|(n, _)| n == name).map(|e| e.1);
            for counter in COUNTERS {
                let (g, c) = (get(&g_counters, counter), get(&c_counters, counter));
                if g != c || g.is_none() {
                    failures.push(format!("{what}: {counter} {g:?} on the GPU, {c:?} from the reference"));
                }
            }
        }
    }
    assert!(failures.is_empty(), "{}", failures.join("\n"));
}
