//! Each backend is measured at its own pixels: the reference is traced over the G-buffer that backend
//! renders. On the outdoor street's fence pickets and thin branches the two backends' pixel samples land
//! on either side of a shadow edge, which one shared reference would count as the technique's error.

use shadow_core::FrameInputs;
use shadow_core::metrics::{compare_visibility, measured_pixels};
use shadow_core::scenes::{self, SceneParams};
use shadow_core::technique::TechniqueSpec;
use shadowlab::BackendKind;
use shadowlab::compare::{CompareJob, run_compare};

#[test]
fn each_backend_is_measured_at_its_own_pixels() {
    let Some(mut renderer) = crate::with_wgpu("measuring at each backend's pixels") else { return };
    let scene = scenes::build("outdoor", &SceneParams::default()).expect("outdoor scene");
    let frame = FrameInputs::from_first_camera(&scene).expect("frame");
    let (w, h) = (480, 270);

    // The GPU's G-buffer, read back, shows the CPU's surfaces but for a few pixels at their edges.
    let cpu = renderer.gbuffer_of(BackendKind::Cpu, &frame, w, h).expect("cpu G-buffer");
    let gpu = renderer.gbuffer_of(BackendKind::Wgpu, &frame, w, h).expect("wgpu G-buffer");
    let differ = cpu.receiver.data().iter().zip(gpu.receiver.data()).filter(|(a, b)| a != b).count();
    let n = cpu.receiver.data().len();
    assert!(differ * 100 <= n, "receivers differ on {differ} of {n} pixels");
    assert!(cpu.covered_pixels() * 2 > n as u64, "the view shows little: {} receivers", cpu.covered_pixels());

    // The exact shadow volume on the GPU, against the reference at its own pixels and at the CPU's.
    let exact = TechniqueSpec::named("shadow-volume-zfail");
    let job = CompareJob {
        scene: "outdoor".into(),
        frame: &frame,
        width: w,
        height: h,
        techniques: vec![exact.clone()],
        reference: TechniqueSpec::named("ray-traced"),
        soft_reference: None,
        backends: vec![BackendKind::Cpu, BackendKind::Wgpu],
        out_dir: None,
    };
    let report = run_compare(&mut renderer, &job, |_| {}).expect("compare");
    let own = report.results.iter().find(|e| e.backend == "wgpu").expect("the wgpu row").metrics.mismatch;
    let on_gpu = renderer.run(BackendKind::Wgpu, &frame, w, h, &exact).expect("wgpu run");
    let (cpu_reference, _) =
        renderer.run_cpu_frame(&frame, w, h, &TechniqueSpec::named("ray-traced")).expect("reference");
    let light = &cpu_reference.light_views[0];
    let mask = measured_pixels(&cpu.receiver, &cpu.position, &cpu.geometric_normal, light);
    let shared = compare_visibility(&on_gpu.visibility[0], &cpu_reference.visibility[0], &mask).expect("metrics");
    assert!(
        own <= 0.5 * shared.mismatch,
        "wgpu's exact volume is off on {:.3}% at its own pixels, {:.3}% at the CPU's",
        own * 100.0,
        shared.mismatch * 100.0
    );
}
