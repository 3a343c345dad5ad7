//! shadowlab on the host application's own device: a device and queue the application made, with
//! WebGPU's default limits, render every technique as shadowlab's own device does; one without
//! Depth32FloatStencil8 falls back to Depth24PlusStencil8 and renders them within its rounding; one short
//! of the limits is refused with what it lacks. An engine's own depth
//! and normals stand in for the G-buffer; timed frames report their GPU time a few frames later. Without
//! a wgpu adapter these print one line and pass, unless SHADOWLAB_REQUIRE_GPU=1.

use shadow_core::FrameInputs;
use shadow_core::scenes::{self, SceneParams};
use shadow_core::technique::TechniqueSpec;
use shadow_wgpu::WgpuContext;
use shadowlab::{BackendKind, TechniqueRegistry};

/// The adapter named `name`, on an instance of the host's, with a device as a host would ask for one:
/// `features`, WebGPU's default limits.
fn host_device(name: &str, features: wgpu::Features) -> (wgpu::Adapter, wgpu::Device, wgpu::Queue) {
    let instance = wgpu::Instance::new(wgpu::InstanceDescriptor::new_without_display_handle());
    let adapter = pollster::block_on(instance.enumerate_adapters(wgpu::Backends::all()))
        .into_iter()
        .find(|a| a.get_info().name == name && WgpuContext::can_use(a))
        .unwrap_or_else(|| panic!("the host's instance has no adapter '{name}'"));
    let desc = wgpu::DeviceDescriptor { required_features: features, ..WgpuContext::device_descriptor() };
    let (device, queue) = pollster::block_on(adapter.request_device(&desc)).expect("a host device");
    (adapter, device, queue)
}

#[test]
fn a_host_device_renders_every_technique_as_shadowlabs_own() {
    let Some(mut renderer) = crate::with_wgpu("host device") else { return };
    let name = renderer.adapter().expect("an adapter").name.clone();
    let (adapter, device, queue) = host_device(&name, WgpuContext::REQUIRED_FEATURES);
    let mut host = WgpuContext::from_host(&adapter, device, queue).expect("the host's device is enough");
    let registry = TechniqueRegistry::builtin();
    let mut compared = 0;
    for scene in ["cubes", "room"] {
        for entry in registry.entries().iter().filter(|e| e.wgpu.is_some()) {
            let frame = crate::frame_taken_by(scene, entry.lights);
            let spec = TechniqueSpec::named(entry.name);
            let own = renderer.run(BackendKind::Wgpu, &frame, 160, 120, &spec).expect("own device");
            let mut technique = registry.wgpu(&spec).expect("technique");
            let hosted =
                shadow_wgpu::render_frame(&mut host, &frame, 160, 120, technique.as_mut()).expect("host device");
            assert!(
                own.visibility[0].data().iter().any(|&v| crate::shadowed(v)),
                "{scene} / {}: nothing in shadow",
                entry.name
            );
            assert!(
                own.visibility[0].data() == hosted.visibility[0].data(),
                "{scene} / {}: the host's device renders another visibility",
                entry.name
            );
            assert_eq!(own.color.data(), hosted.color.data(), "{scene} / {}", entry.name);
            compared += 1;
        }
    }
    assert!(compared >= 20, "only {compared} techniques compared");
}

#[test]
fn a_host_device_short_of_the_limits_is_refused_by_name() {
    let Some(renderer) = crate::with_wgpu("host device refusal") else { return };
    let name = renderer.adapter().expect("an adapter").name.clone();
    let instance = wgpu::Instance::new(wgpu::InstanceDescriptor::new_without_display_handle());
    let adapter = pollster::block_on(instance.enumerate_adapters(wgpu::Backends::all()))
        .into_iter()
        .find(|a| a.get_info().name == name)
        .expect("the adapter");
    let desc = wgpu::DeviceDescriptor { required_limits: wgpu::Limits::downlevel_defaults(), ..Default::default() };
    let (device, queue) = pollster::block_on(adapter.request_device(&desc)).expect("a small device");
    let err = WgpuContext::from_host(&adapter, device, queue).err().expect("refused");
    let msg = err.to_string();
    assert!(msg.contains(&name) && msg.contains("max_color_attachment_bytes_per_sample"), "{msg}");
}

#[test]
fn a_host_device_without_f32_depth_stencil_falls_back_to_depth24() {
    let Some(mut renderer) = crate::with_wgpu("the depth-stencil fallback") else { return };
    let name = renderer.adapter().expect("an adapter").name.clone();
    let (adapter, device, queue) = host_device(&name, wgpu::Features::empty());
    let mut host = WgpuContext::from_host(&adapter, device, queue).expect("no feature is required");
    assert_eq!(host.depth_stencil, wgpu::TextureFormat::Depth24PlusStencil8);
    let registry = TechniqueRegistry::builtin();
    let mut failures = Vec::new();
    for entry in registry.entries().iter().filter(|e| e.wgpu.is_some()) {
        let frame = crate::frame_taken_by("cubes", entry.lights);
        let spec = TechniqueSpec::named(entry.name);
        let own = renderer.run(BackendKind::Wgpu, &frame, 160, 120, &spec).expect("own device");
        let mut technique = registry.wgpu(&spec).expect("technique");
        let hosted = shadow_wgpu::render_frame(&mut host, &frame, 160, 120, technique.as_mut()).expect("host device");
        let (a, b) = (own.visibility[0].data(), hosted.visibility[0].data());
        let differ = a.iter().zip(b).filter(|(x, y)| (*x - *y).abs() > 0.01).count();
        // Volumes count against a 24-bit depth: a side that meets its receiver within that depth's
        // rounding may land on the other side of it.
        if differ as f64 > 0.001 * a.len() as f64 || !b.iter().any(|&v| crate::shadowed(v)) {
            failures.push(format!("{}: {differ} pixels differ", entry.name));
        }
    }
    assert!(failures.is_empty(), "{}", failures.join("\n"));
    let frame = crate::frame_taken_by("cubes", shadow_core::technique::LightKinds::ALL);
    let mut depth_mask = registry.wgpu(&TechniqueSpec::parse("hybrid:gpu_mask=depth").expect("spec")).expect("hybrid");
    let err = shadow_wgpu::render_frame(&mut host, &frame, 160, 120, depth_mask.as_mut()).err().expect("refused");
    assert!(err.to_string().contains("DEPTH32FLOAT_STENCIL8"), "{err}");
}

#[test]
fn realtime_shadows_switch_techniques_and_keep_theirs_on_a_refusal() {
    use shadowlab::realtime::RealtimeShadows;
    let Some(renderer) = crate::with_wgpu("realtime shadows") else { return };
    let name = renderer.adapter().expect("an adapter").name.clone();
    let (adapter, device, queue) = host_device(&name, WgpuContext::REQUIRED_FEATURES);
    let registry = TechniqueRegistry::builtin();
    let mut shadows = RealtimeShadows::new(&adapter, device.clone(), queue.clone(), registry, "shadow-map")
        .unwrap_or_else(|e| panic!("{e}"));
    let err = shadows.set_technique("ray-traced").expect_err("the reference has no GPU side");
    assert!(err.to_string().contains("not implemented on the wgpu backend"), "{err}");
    assert!(shadows.set_technique("shadow-map:res=3").is_err(), "a map of side 3 taken");
    assert_eq!(shadows.technique().to_string(), "shadow-map");
    shadows.set_technique("shadow-volume-zfail").unwrap_or_else(|e| panic!("{e}"));
    let s = scenes::build("cubes", &SceneParams::default()).expect("scene");
    let frame = FrameInputs::from_first_camera(&s).expect("frame");
    let texture = shadow_wgpu::frame::layered(shadows.context(), "target", 64, 48, 1, wgpu::TextureFormat::Rgba8Unorm);
    let view = texture.create_view(&Default::default());
    let target = shadow_wgpu::ColorTarget { view: &view, format: texture.format(), width: 64, height: 48 };
    let mut encoder = device.create_command_encoder(&Default::default());
    let views = shadows.record(&mut encoder, &frame, &target).unwrap_or_else(|e| panic!("{e}"));
    queue.submit([encoder.finish()]);
    assert_eq!(views.len(), frame.lights.len());
    let vis = shadows.visibility().expect("a visibility target");
    let vis = shadow_wgpu::readback::read_f32(shadows.context(), vis, 0, wgpu::TextureAspect::All).expect("read back");
    assert!(vis.data().contains(&0.0) && vis.data().contains(&1.0), "no shadow edge in the recorded frame");
}

#[test]
fn timed_realtime_frames_report_their_gpu_time_by_phase_frames_later() {
    use shadowlab::realtime::RealtimeShadows;
    let Some(renderer) = crate::with_wgpu("timed realtime frames") else { return };
    let name = renderer.adapter().expect("an adapter").name.clone();
    let (adapter, device, queue) = host_device(&name, WgpuContext::REQUIRED_FEATURES | wgpu::Features::TIMESTAMP_QUERY);
    let registry = TechniqueRegistry::builtin();
    let mut shadows = RealtimeShadows::new(&adapter, device.clone(), queue.clone(), registry, "shadow-volume-zfail")
        .unwrap_or_else(|e| panic!("{e}"));
    assert!(shadows.time_frames(true), "the device has timestamps, the timer none");
    let s = scenes::build("cubes", &SceneParams::default()).expect("scene");
    let frame = FrameInputs::from_first_camera(&s).expect("frame");
    let texture = shadow_wgpu::frame::layered(shadows.context(), "target", 64, 48, 1, wgpu::TextureFormat::Rgba8Unorm);
    let view = texture.create_view(&Default::default());
    let target = shadow_wgpu::ColorTarget { view: &view, format: texture.format(), width: 64, height: 48 };
    // The host waits for each frame here, so each step of the read-back lands by the next frame: the map
    // is asked for when frame 2 is recorded, and frame 3 reads frame 1's time.
    let mut times = Vec::new();
    for _ in 0..3 {
        let mut encoder = device.create_command_encoder(&Default::default());
        shadows.record(&mut encoder, &frame, &target).unwrap_or_else(|e| panic!("{e}"));
        queue.submit([encoder.finish()]);
        times.push(shadows.gpu_times().cloned());
        device.poll(wgpu::PollType::wait_indefinitely()).expect("the frame done");
    }
    assert_eq!(&times[..2], &[None, None], "a time before its frame was read back");
    let first = times[2].as_ref().unwrap_or_else(|| panic!("no GPU time for frame 1"));
    assert!(first.total_ms > 0.0 && first.total_ms < 60_000.0, "frame 1's GPU time: {first:?}");
    let names: Vec<&str> = first.phases.iter().map(|(n, _)| *n).collect();
    assert_eq!(names, ["G-buffer", "shadows", "shading"], "{first:?}");
    let sum: f64 = first.phases.iter().map(|(_, ms)| ms).sum();
    assert!((sum - first.total_ms).abs() < 1e-9 && first.phases.iter().all(|(_, ms)| *ms >= 0.0), "{first:?}");
    assert!(!shadows.time_frames(false) && shadows.gpu_times().is_none(), "still timing");
}

#[test]
fn an_engines_own_depth_and_normals_stand_in_for_the_gbuffer() {
    let Some(mut renderer) = crate::with_wgpu("host surfaces") else { return };
    let name = renderer.adapter().expect("an adapter").name.clone();
    let f32_depth = wgpu::Features::DEPTH32FLOAT_STENCIL8;
    let (adapter, device, queue) = host_device(&name, WgpuContext::REQUIRED_FEATURES | f32_depth);
    let s = scenes::build("cubes", &SceneParams::default()).expect("scene");
    let frame = FrameInputs::from_first_camera(&s).expect("frame");
    let (w, h) = (160, 120);
    // The engine's depth and normals: here, a G-buffer drawn on a context of the engine's own.
    let mut engine = WgpuContext::from_host(&adapter, device.clone(), queue.clone()).expect("a context");
    let surfaces = shadow_wgpu::gbuffer::render(&mut engine, &frame, w, h).expect("the engine's surfaces");
    let depth = surfaces
        .depth
        .create_view(&wgpu::TextureViewDescriptor { aspect: wgpu::TextureAspect::DepthOnly, ..Default::default() });
    let host = shadow_wgpu::HostSurfaces { depth: &depth, normals: &surfaces.normal, width: w, height: h };
    let mut cx = WgpuContext::from_host(&adapter, device.clone(), queue.clone()).expect("a context");
    let registry = TechniqueRegistry::builtin();
    let mut recorder = shadow_wgpu::FrameRecorder::new();
    for (spec, most) in
        [("shadow-volume-zfail", 0.0), ("silhouette-map", 0.001), ("shadow-map", 0.001), ("pcss", 0.001)]
    {
        let spec = TechniqueSpec::parse(spec).expect("spec");
        let mut technique = registry.wgpu(&spec).expect("technique");
        let mut encoder = device.create_command_encoder(&Default::default());
        recorder.record_visibility(&mut cx, &mut encoder, &frame, technique.as_mut(), &host).expect("recorded");
        queue.submit([encoder.finish()]);
        let layers = recorder.visibility().expect("visibility");
        let vis = shadow_wgpu::readback::read_f32(&cx, layers, 0, wgpu::TextureAspect::All).expect("read back");
        let own = renderer.run(BackendKind::Wgpu, &frame, w, h, &spec).expect("own frame");
        let differ = vis.data().iter().zip(own.visibility[0].data()).filter(|(a, b)| (*a - *b).abs() > 0.01).count();
        let share = differ as f64 / vis.data().len() as f64;
        assert!(own.visibility[0].data().contains(&0.0), "{spec}: nothing in shadow");
        // Positions found from the depth differ from the rasterized ones by rounding, which moves a map's
        // depth test at the odd pixel; volumes count against the very same depth.
        assert!(share <= most, "{spec}: {differ} pixels ({:.3}%) differ from the G-buffer's", share * 100.0);
    }
}
