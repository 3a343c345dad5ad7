//! Single-sided materials (glTF's `doubleSided: false`) in the camera's view: on both backends a card
//! seen from behind is not drawn (what lies past it shows), seen from the front it is; mirrored or not;
//! and a double-sided one is seen from both sides.

use shadow_core::glam::{Mat4, Vec3};
use shadow_core::{Camera, FrameInputs, Light, Material, Scene, procedural};
use shadowlab::BackendKind;

const SIZE: u32 = 64;

/// A level card a metre up, facing up (+y), seen from above or from below, drawn single- or double-sided,
/// mirrored or not; nothing else in the view.
fn card(from_below: bool, single_sided: bool, mirrored: bool) -> FrameInputs {
    let mut s = Scene::new();
    let material = s.add_material(Material { cull_back_faces: single_sided, ..Material::default() });
    let mesh = s.add_mesh(procedural::plane(4.0, 4.0).expect("plane"));
    let flip = if mirrored { Mat4::from_scale(Vec3::new(-1.0, 1.0, 1.0)) } else { Mat4::IDENTITY };
    s.add_instance("card", mesh, material, Mat4::from_translation(Vec3::Y) * flip).expect("card");
    s.add_light(Light::directional(Vec3::NEG_Y));
    let eye = Vec3::new(0.0, if from_below { -1.0 } else { 3.0 }, 0.01);
    FrameInputs::new(&s, Camera::look_at(eye, Vec3::Y, 40.0), s.lights().map(|(_, l)| l).collect()).expect("frame")
}

/// The share of the view the card covers on `backend`.
fn covered(renderer: &mut shadowlab::Renderer, backend: BackendKind, frame: &FrameInputs) -> f64 {
    let covered: Vec<bool> = match backend {
        BackendKind::Cpu => {
            let g = shadow_cpu::gbuffer::render(frame, SIZE, SIZE).expect("G-buffer");
            g.depth.data().iter().map(|&d| d < 1.0).collect()
        }
        BackendKind::Wgpu => {
            let cx = renderer.wgpu_context().expect("wgpu");
            shadow_wgpu::gbuffer::read(cx, frame, SIZE, SIZE).expect("G-buffer").covered.data().to_vec()
        }
    };
    covered.iter().filter(|&&c| c).count() as f64 / covered.len() as f64
}

#[test]
fn single_sided_cards_are_not_seen_from_behind() {
    let mut backends = vec![BackendKind::Cpu];
    let mut renderer = shadowlab::Renderer::new(shadowlab::TechniqueRegistry::builtin());
    if let Some(r) = crate::with_wgpu("single-sided cards on wgpu") {
        renderer = r;
        backends.push(BackendKind::Wgpu);
    }
    for backend in backends {
        for mirrored in [false, true] {
            for (from_below, single_sided, seen) in
                [(false, true, true), (true, true, false), (true, false, true), (false, false, true)]
            {
                let share = covered(&mut renderer, backend, &card(from_below, single_sided, mirrored));
                let what = format!("{backend:?}, below {from_below}, single-sided {single_sided}, mirrored {mirrored}");
                if seen {
                    assert!(share > 0.9, "{what}: the card covers {share}");
                } else {
                    assert_eq!(share, 0.0, "{what}: the card is seen from behind");
                }
            }
        }
    }
}
