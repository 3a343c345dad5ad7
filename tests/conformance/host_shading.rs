//! An engine that draws its own G-buffer and shades with its own WGSL (the `host_shading` example's),
//! reading each light's visibility through shadow-wgpu's host module after `record_visibility`: its
//! picture matches the one `FrameRecorder::record` shades within the suite's FLIP bound, and lies far
//! closer to it than the same engine's picture with the lights unshadowed (so the shadows came through).
//! Without a wgpu adapter this prints one line and passes, unless SHADOWLAB_REQUIRE_GPU=1.

#[path = "../../examples/host_shading/engine.rs"]
mod engine;

use shadow_core::FrameInputs;
use shadow_core::scenes::{self, SceneParams};

/// The suite's bound on the FLIP error between two renderers' shaded pictures.
const MAX_FLIP: f64 = 0.02;

#[test]
fn an_engine_shading_with_its_own_wgsl_matches_records_picture() {
    if crate::with_wgpu("an engine's own shading").is_none() {
        return;
    }
    for (scene, technique) in
        [("cubes", "shadow-map"), ("cubes", "shadow-volume-zfail"), ("cubes", "pcss"), ("room", "hybrid")]
    {
        let frame = FrameInputs::from_first_camera(&scenes::build(scene, &SceneParams::default()).expect("scene"))
            .expect("frame");
        let pictures = engine::Pictures::render(&frame, technique, 240, 180).unwrap_or_else(|e| panic!("{e}"));
        let flip = pictures.flip().expect("one size");
        let unshadowed = pictures.flip_of_the_shadows().expect("one size");
        assert!(
            flip <= MAX_FLIP && flip < 0.25 * unshadowed,
            "{scene} / {technique}: the engine's picture is {flip:.4} FLIP from record's ({unshadowed:.4} unshadowed)"
        );
    }
}

#[test]
fn the_engine_names_the_textured_material_it_cannot_draw() {
    if crate::with_wgpu("an engine's refusal").is_none() {
        return;
    }
    let frame = FrameInputs::from_first_camera(&scenes::build("foliage", &SceneParams::default()).expect("scene"))
        .expect("frame");
    let err = engine::Pictures::render(&frame, "shadow-map", 64, 48).err().expect("refused");
    assert!(err.to_string().contains("base-colour texture (material '"), "{err}");
}

/// Light 0's visibility as a host pass finds it in the maps its technique lent (`host_maps.wgsl`, with
/// the maps module), beside the visibility the technique recorded from the same depth: `-1` where the
/// engine drew nothing.
fn looked_up_and_recorded(frame: &FrameInputs, spec: &str, (width, height): (u32, u32)) -> (Vec<f32>, Vec<f32>) {
    use shadow_core::technique::TechniqueSpec;
    use shadow_wgpu::{FrameRecorder, HostMap, HostSurfaces, WgpuContext, host_wgsl, readback::read_f32};
    use wgpu::util::DeviceExt;
    let (adapter, device, queue) = engine::device().expect("a device");
    let mut cx = WgpuContext::from_host(&adapter, device.clone(), queue.clone()).expect("a context");
    let spec = TechniqueSpec::parse(spec).expect("spec");
    let mut technique = shadowlab::TechniqueRegistry::builtin().wgpu(&spec).expect("technique");
    let engine = engine::Engine::new(&device);
    let scene = engine::Engine::upload(&device, frame, width, height).expect("a scene the engine draws");
    let g = engine::GBuffer::new(&device, width, height);
    let mut encoder = device.create_command_encoder(&Default::default());
    engine.draw_gbuffer(&device, &mut encoder, &scene, &g);
    let (depth, normals) = (g.depth.create_view(&Default::default()), g.normals.create_view(&Default::default()));
    let surfaces = HostSurfaces { depth: &depth, normals: &normals, width, height };
    let mut recorder = FrameRecorder::new();
    recorder.record_visibility(&mut cx, &mut encoder, frame, technique.as_mut(), &surfaces).expect("recorded");
    let map = recorder.map(0).unwrap_or_else(|| panic!("{spec}: no maps lent")).clone();
    if frame.lights[0].range.is_some() {
        let atlas = shadow_core::frame::Savings::ATLAS_SIDE;
        assert_eq!(map.texture.width(), atlas, "{spec}: a ranged light's lent maps are the atlas");
    }

    let source = format!("{}\n{}", host_wgsl::MAPS, include_str!("host_maps.wgsl"));
    let module = device.create_shader_module(wgpu::ShaderModuleDescriptor {
        label: Some("host maps"),
        source: wgpu::ShaderSource::Wgsl(source.into()),
    });
    let target = shadow_wgpu::frame::layered(&cx, "looked up", width, height, 1, wgpu::TextureFormat::R32Float);
    let pipeline = device.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
        label: Some("host maps"),
        layout: None,
        vertex: wgpu::VertexState {
            module: &module,
            entry_point: Some("vs_full_screen"),
            compilation_options: Default::default(),
            buffers: &[],
        },
        primitive: Default::default(),
        depth_stencil: None,
        multisample: Default::default(),
        fragment: Some(wgpu::FragmentState {
            module: &module,
            entry_point: Some("fs_map_visibility"),
            compilation_options: Default::default(),
            targets: &[Some(wgpu::TextureFormat::R32Float.into())],
        }),
        multiview_mask: None,
        cache: None,
    });
    let uniform = |contents: &[u8]| {
        device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: None,
            contents,
            usage: wgpu::BufferUsages::UNIFORM,
        })
    };
    let params = uniform(map.params_bytes());
    let (w, h) = (width as f32, height as f32);
    let world_from_clip = frame.camera.clip_from_world(w / h).inverse();
    let camera: Vec<f32> = world_from_clip.to_cols_array().into_iter().chain([w, h, 1.0 / w, 1.0 / h]).collect();
    let camera = uniform(bytemuck::cast_slice(&camera));
    let maps = map.texture.create_view(&wgpu::TextureViewDescriptor {
        dimension: Some(wgpu::TextureViewDimension::D2Array),
        ..Default::default()
    });
    let sampler = device.create_sampler(&HostMap::sampler_descriptor());
    let depth_only = g
        .depth
        .create_view(&wgpu::TextureViewDescriptor { aspect: wgpu::TextureAspect::DepthOnly, ..Default::default() });
    let group = device.create_bind_group(&wgpu::BindGroupDescriptor {
        label: Some("host maps"),
        layout: &pipeline.get_bind_group_layout(0),
        entries: &[
            wgpu::BindGroupEntry { binding: 0, resource: wgpu::BindingResource::TextureView(&maps) },
            wgpu::BindGroupEntry { binding: 1, resource: wgpu::BindingResource::Sampler(&sampler) },
            wgpu::BindGroupEntry { binding: 2, resource: params.as_entire_binding() },
            wgpu::BindGroupEntry { binding: 3, resource: wgpu::BindingResource::TextureView(&depth_only) },
            wgpu::BindGroupEntry { binding: 4, resource: camera.as_entire_binding() },
        ],
    });
    engine::full_screen(&mut encoder, &target.create_view(&Default::default()), &pipeline, &group);
    queue.submit([encoder.finish()]);
    let looked_up = read_f32(&cx, &target, 0, wgpu::TextureAspect::All).expect("read back");
    let layers = recorder.visibility().expect("recorded visibility");
    let recorded = read_f32(&cx, layers, 0, wgpu::TextureAspect::All).expect("read back");
    (looked_up.data().to_vec(), recorded.data().to_vec())
}

#[test]
fn a_hosts_own_lookup_into_the_lent_maps_finds_the_techniques_visibility() {
    use shadow_core::scenes::LightType;
    if crate::with_wgpu("a host's own map lookup").is_none() {
        return;
    }
    // A light with a range gets tiles of the frame's shadow atlas: the lent maps are that atlas.
    let built = |scene: &str, light: Option<LightType>, range: Option<f32>| {
        let params = SceneParams { light, ..SceneParams::default() };
        let mut frame = FrameInputs::from_first_camera(&scenes::build(scene, &params).expect("scene")).expect("frame");
        frame.lights[0].range = range;
        frame
    };
    let ranged = Some(40.0);
    let cases = [
        ("cubes", None, None, "shadow-map"),
        ("cubes", None, None, "shadow-map:filter=bilinear"),
        ("cubes", None, None, "shadow-map:filter=pcf3x3"),
        ("cubes", None, None, "shadow-map:filter=pcf4x4-jitter,filter_radius=2"),
        ("cubes", None, None, "shadow-map:filter=poisson16,filter_radius=2,bias=world"),
        ("cubes", Some(LightType::Point), None, "shadow-map:filter=pcf3x3"),
        ("cubes", None, ranged, "shadow-map"),
        ("cubes", None, ranged, "shadow-map:filter=pcf3x3"),
        ("cubes", Some(LightType::Point), ranged, "shadow-map:filter=pcf3x3"),
        ("cubes", Some(LightType::Directional), None, "cascaded-shadow-map"),
        ("cubes", Some(LightType::Directional), None, "lispsm"),
        ("cubes", Some(LightType::Directional), None, "perspective-shadow-map"),
    ];
    let mut failures = Vec::new();
    for (scene, light, range, spec) in cases {
        let (looked_up, recorded) = looked_up_and_recorded(&built(scene, light, range), spec, (240, 180));
        let covered: Vec<(f32, f32)> =
            looked_up.iter().zip(&recorded).filter(|(l, _)| **l >= 0.0).map(|(l, r)| (*l, *r)).collect();
        let differ = covered.iter().filter(|(l, r)| (l - r).abs() > 0.01).count();
        let shadowed = covered.iter().filter(|(_, r)| *r < 0.5).count();
        eprintln!(
            "{scene} {light:?} {range:?} {spec}: {differ} of {} covered pixels differ, {shadowed} shadowed",
            covered.len()
        );
        if differ as f64 > 0.001 * covered.len() as f64 || shadowed == 0 {
            failures
                .push(format!("{scene} / {spec}: {differ} of {} pixels differ ({shadowed} shadowed)", covered.len()));
        }
    }
    assert!(failures.is_empty(), "{}", failures.join("\n"));
}

#[test]
fn techniques_that_are_no_one_lookup_lend_no_maps() {
    use shadow_core::technique::TechniqueSpec;
    use shadow_wgpu::{FrameRecorder, WgpuContext};
    if crate::with_wgpu("maps lent by no lookup").is_none() {
        return;
    }
    let (adapter, device, queue) = engine::device().expect("a device");
    let mut cx = WgpuContext::from_host(&adapter, device.clone(), queue.clone()).expect("a context");
    let frame = FrameInputs::from_first_camera(&scenes::build("cubes", &SceneParams::default()).expect("scene"))
        .expect("frame");
    let texture = shadow_wgpu::frame::layered(&cx, "target", 64, 48, 1, engine::COLOR);
    let view = texture.create_view(&Default::default());
    let target = shadow_wgpu::ColorTarget { view: &view, format: engine::COLOR, width: 64, height: 48 };
    let mut recorder = FrameRecorder::new();
    let registry = shadowlab::TechniqueRegistry::builtin();
    for (spec, lends) in [("shadow-map", true), ("shadow-volume-zfail", false), ("pcss", false), ("shadow-map", true)] {
        let mut technique = registry.wgpu(&TechniqueSpec::parse(spec).expect("spec")).expect("technique");
        let mut encoder = device.create_command_encoder(&Default::default());
        recorder.record(&mut cx, &mut encoder, &frame, technique.as_mut(), &target).expect("recorded");
        queue.submit([encoder.finish()]);
        assert_eq!(recorder.map(0).is_some(), lends, "{spec}");
        assert!(recorder.map(1).is_none(), "a light past the frame's");
    }
}
