//! The texel rule on the GPU (`texel.wgsl`) against shadow-core's: over random coordinates, footprints,
//! samplers and texture-coordinate transforms, on textures uploaded with their mip chains (square, odd
//! sides, one texel wide), a compute pass picks the same levels and texels as the CPU, reads the same
//! alpha and gives the alpha test the same answer. Cases within a rounding of a decision (a level's or a
//! texel's boundary, the cutoff) may go either way on two machines' arithmetic: they are counted apart
//! and must be rare.

use std::sync::Arc;

use bytemuck::{Pod, Zeroable};
use shadow_core::glam::Vec2;
use shadow_core::material::{Filter, Footprint, Sampler, Texture, TextureRef, UvTransform, Wrap};
use shadow_core::scene::TextureKey;
use shadow_wgpu::WgpuContext;
use shadow_wgpu::textures::{TexelRuleRaw, TextureGpu};

const CASES: usize = 6000;

/// How close to a decision a case may be and still count: a texel's edge, in texels; a level's boundary,
/// relative to rho^2 or in lambda; the cutoff, in alpha.
const NEAR_TEXEL_EDGE: f64 = 1e-3;
const NEAR_LEVEL: f64 = 1e-4;
const NEAR_CUTOFF: f32 = 2e-4;

/// How far the two filtered alphas may be apart: a texel coordinate of a few hundred texels (the
/// transform scales and repeats) rounded a unit in its last place apart on the two sides moves a
/// bilinear weight by 3e-5; a 20th of an 8-bit alpha's step.
const ALPHA_TOLERANCE: f32 = 2e-4;

const SHADER: &str = include_str!("texel_rule.wgsl");

#[repr(C)]
#[derive(Clone, Copy, Pod, Zeroable)]
struct CaseRaw {
    uv_dx: [f32; 4],
    dy: [f32; 4],
    rule: TexelRuleRaw,
}

#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, Zeroable)]
struct Pick {
    levels: [u32; 4],
    taps: [i32; 4],
    values: [f32; 4],
}

/// A case: where, over what footprint, through which read, with which alpha factor and cutoff.
struct Case {
    uv: Vec2,
    footprint: Footprint,
    read: TextureRef,
    factor: f32,
    cutoff: f32,
}

/// SplitMix64, for cases the same on every run.
struct Random(u64);

impl Random {
    fn next(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9e37_79b9_7f4a_7c15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
        z ^ (z >> 31)
    }

    /// Uniform in [lo, hi).
    fn range(&mut self, lo: f32, hi: f32) -> f32 {
        lo + (hi - lo) * ((self.next() >> 40) as f32 / (1u64 << 24) as f32)
    }

    fn pick<T: Copy>(&mut self, of: &[T]) -> T {
        of[(self.next() % of.len() as u64) as usize]
    }
}

/// A texture of random texels.
fn noise(name: &str, width: u32, height: u32, random: &mut Random) -> Arc<Texture> {
    let texels = (0..width * height).map(|_| random.next().to_le_bytes()[..4].try_into().expect("4 bytes")).collect();
    Arc::new(Texture::from_rgba8(name, width, height, texels).expect("texture"))
}

/// A footprint side of 1/32 to 64 texels of level 0, in a random direction.
fn side(random: &mut Random, size: Vec2) -> Vec2 {
    let length = random.range(-5.0, 6.0).exp2();
    let angle = random.range(0.0, std::f32::consts::TAU);
    Vec2::new(angle.cos(), angle.sin()) * length / size
}

fn cases(texture: &Texture, random: &mut Random) -> Vec<Case> {
    let size = Vec2::new(texture.width() as f32, texture.height() as f32);
    let filters = [Filter::Nearest, Filter::Linear];
    let wraps = [Wrap::Repeat, Wrap::ClampToEdge, Wrap::MirroredRepeat];
    (0..CASES)
        .map(|i| {
            let sampler = Sampler {
                mag: random.pick(&filters),
                min: random.pick(&filters),
                mipmap: random.pick(&[None, Some(Filter::Nearest), Some(Filter::Linear)]),
                wrap_u: random.pick(&wraps),
                wrap_v: random.pick(&wraps),
            };
            let transform = if i % 2 == 0 {
                UvTransform::IDENTITY
            } else {
                UvTransform {
                    offset: Vec2::new(random.range(-1.0, 1.0), random.range(-1.0, 1.0)),
                    rotation: random.range(-3.0, 3.0),
                    scale: Vec2::new(random.range(0.25, 3.0), random.range(0.25, 3.0)),
                }
            };
            Case {
                uv: Vec2::new(random.range(-1.5, 2.5), random.range(-1.5, 2.5)),
                footprint: Footprint { dx: side(random, size), dy: side(random, size) },
                read: TextureRef { texture: TextureKey::default(), sampler, transform },
                factor: random.range(0.5, 1.0),
                cutoff: random.range(0.2, 0.8),
            }
        })
        .collect()
}

/// The GPU's picks for `cases` on `texture`.
fn gpu_picks(cx: &WgpuContext, texture: &Arc<Texture>, cases: &[Case]) -> Vec<Pick> {
    use shadow_wgpu::pipelines::buffer_entry;
    let texture = TextureGpu::upload(cx, texture).expect("upload");
    let raw: Vec<CaseRaw> = cases
        .iter()
        .map(|c| CaseRaw {
            uv_dx: [c.uv.x, c.uv.y, c.footprint.dx.x, c.footprint.dx.y],
            dy: [c.footprint.dy.x, c.footprint.dy.y, 0.0, 0.0],
            rule: TexelRuleRaw::new(&c.read, c.factor, Some(c.cutoff)),
        })
        .collect();
    let storage = wgpu::BufferUsages::STORAGE;
    let input = cx.create_buffer_init(&wgpu::util::BufferInitDescriptor {
        label: Some("texel cases"),
        contents: bytemuck::cast_slice(&raw),
        usage: storage,
    });
    let size = (cases.len() * std::mem::size_of::<Pick>()) as u64;
    let output = cx.create_buffer(&wgpu::BufferDescriptor {
        label: Some("texel picks"),
        size,
        usage: storage | wgpu::BufferUsages::COPY_SRC,
        mapped_at_creation: false,
    });
    let read = cx.create_buffer(&wgpu::BufferDescriptor {
        label: Some("texel picks read"),
        size,
        usage: wgpu::BufferUsages::COPY_DST | wgpu::BufferUsages::MAP_READ,
        mapped_at_creation: false,
    });
    let layout = cx.pipelines.group_layout(
        "texel test",
        &[
            wgpu::BindGroupLayoutEntry {
                binding: 0,
                visibility: wgpu::ShaderStages::COMPUTE,
                ty: wgpu::BindingType::Texture {
                    sample_type: wgpu::TextureSampleType::Float { filterable: false },
                    view_dimension: wgpu::TextureViewDimension::D2,
                    multisampled: false,
                },
                count: None,
            },
            buffer_entry(1, wgpu::BufferBindingType::Storage { read_only: true }, wgpu::ShaderStages::COMPUTE),
            buffer_entry(2, wgpu::BufferBindingType::Storage { read_only: false }, wgpu::ShaderStages::COMPUTE),
        ],
    );
    let module = cx.pipelines.module("texel test", format!("{}\n{SHADER}", shadow_wgpu::shaders::TEXEL));
    let pipeline = cx.pipelines.compute(&wgpu::ComputePipelineDescriptor {
        label: Some("texel test"),
        layout: Some(&cx.pipelines.layout("texel test", &[Some(&layout)])),
        module: &module,
        entry_point: Some("cs_texel"),
        compilation_options: Default::default(),
        cache: None,
    });
    let group = cx.device.create_bind_group(&wgpu::BindGroupDescriptor {
        label: Some("texel test"),
        layout: &layout,
        entries: &[
            wgpu::BindGroupEntry { binding: 0, resource: wgpu::BindingResource::TextureView(&texture.view) },
            wgpu::BindGroupEntry { binding: 1, resource: input.as_entire_binding() },
            wgpu::BindGroupEntry { binding: 2, resource: output.as_entire_binding() },
        ],
    });
    let mut enc = cx.encoder("texel test");
    {
        let mut pass = enc.begin_compute_pass(&Default::default());
        pass.set_pipeline(&pipeline);
        pass.set_bind_group(0, &group, &[]);
        pass.dispatch_workgroups(cases.len().div_ceil(64) as u32, 1, 1);
    }
    enc.copy_buffer_to_buffer(&output, 0, &read, 0, size);
    cx.submit(enc);
    let bytes = shadow_wgpu::readback::map_read(cx, &read, "the texel test").expect("read back");
    bytemuck::cast_slice(&bytes).to_vec()
}

/// Whether `x` lies within `eps` of an integer.
fn near_integer(x: f64, eps: f64) -> bool {
    (x - x.round()).abs() < eps
}

/// Whether the CPU's decisions for `case` lie within a rounding of a boundary: the level (magnified or
/// not, which level) or the texel (which column or row) could go either way on other arithmetic.
fn near_a_decision(texture: &Texture, case: &Case, level: usize, filter: Filter) -> bool {
    let m = case.read.transform.matrix();
    let footprint =
        Footprint { dx: m.transform_vector2(case.footprint.dx), dy: m.transform_vector2(case.footprint.dy) };
    let rho_squared = f64::from(footprint.rho_squared(texture.width(), texture.height()));
    let lambda = 0.5 * rho_squared.log2();
    let near_level = (rho_squared - 1.0).abs() < NEAR_LEVEL
        || match case.read.sampler.mipmap {
            None => false,
            // 2^(2k+1): lambda at k + 1/2.
            Some(Filter::Nearest) => near_integer(lambda - 0.5, NEAR_LEVEL),
            Some(Filter::Linear) => near_integer(lambda, NEAR_LEVEL),
        };
    let at = m.transform_point2(case.uv);
    let chosen = &texture.levels()[level];
    let p = [f64::from(at.x) * f64::from(chosen.width()), f64::from(at.y) * f64::from(chosen.height())];
    let shift = if filter == Filter::Linear { 0.5 } else { 0.0 };
    near_level || p.iter().any(|&x| near_integer(x - shift, NEAR_TEXEL_EDGE))
}

#[test]
fn the_gpu_picks_the_cpus_levels_and_texels() {
    if crate::with_wgpu("the texel rule").is_none() {
        return;
    }
    let cx = WgpuContext::new(&shadow_wgpu::AdapterChoice { name: None, allow_software: true }).expect("context");
    let mut random = Random(0x7e3e1);
    let textures = [
        noise("64 x 64", 64, 64, &mut random),
        noise("37 x 23", 37, 23, &mut random),
        noise("1 x 16", 1, 16, &mut random),
    ];
    let (mut checked, mut near, mut blended, mut minified, mut passed) = (0, 0, 0, 0, 0);
    for texture in &textures {
        let cases = cases(texture, &mut random);
        let picks = gpu_picks(&cx, texture, &cases);
        for (i, (case, got)) in cases.iter().zip(&picks).enumerate() {
            let sampler = case.read.sampler;
            let m = case.read.transform.matrix();
            let footprint =
                Footprint { dx: m.transform_vector2(case.footprint.dx), dy: m.transform_vector2(case.footprint.dy) };
            let choice =
                sampler.levels(footprint.rho_squared(texture.width(), texture.height()), texture.levels().len());
            let filter = if choice.magnified { sampler.mag } else { sampler.min };
            if near_a_decision(texture, case, choice.first.0, filter) {
                near += 1;
                continue;
            }
            let what =
                || format!("{} case {i}: uv {} {:?} {:?}: GPU {got:?}", texture.name(), case.uv, case.read, choice);
            assert_eq!(got.levels[2] != 0, choice.magnified, "magnified: {}", what());
            assert_eq!(got.levels[0] as usize, choice.first.0, "first level: {}", what());
            let second = (got.values[0] > 0.0).then_some(got.levels[1] as usize);
            assert_eq!(second, choice.second.map(|s| s.0), "second level: {}", what());
            let taps = sampler.texels(&texture.levels()[choice.first.0], m.transform_point2(case.uv), filter);
            let (lo, hi) = (taps[0].0, if filter == Filter::Linear { taps[3].0 } else { taps[0].0 });
            let as_u32 = |x: i32| u32::try_from(x).expect("a wrapped index");
            let gpu = ((as_u32(got.taps[0]), as_u32(got.taps[1])), (as_u32(got.taps[2]), as_u32(got.taps[3])));
            assert_eq!(gpu, (lo, hi), "taps: {}", what());
            let alpha = sampler.sample_alpha(texture, m.transform_point2(case.uv), footprint);
            assert!((got.values[1] - alpha).abs() < ALPHA_TOLERANCE, "alpha {alpha}: {}", what());
            let cpu_passes = shadow_core::Material {
                alpha: case.factor,
                alpha_mode: shadow_core::material::AlphaMode::Mask { cutoff: case.cutoff },
                base_color_texture: Some(case.read),
                ..Default::default()
            }
            .passes(Some(texture), Some(case.uv), case.footprint);
            if (case.factor * alpha - case.cutoff).abs() >= NEAR_CUTOFF {
                assert_eq!(got.levels[3] != 0, cpu_passes, "alpha test: {}", what());
            }
            checked += 1;
            blended += usize::from(choice.second.is_some());
            minified += usize::from(!choice.magnified);
            passed += usize::from(cpu_passes);
        }
    }
    let all = checked + near;
    assert!(near * 100 < all, "{near} of {all} cases near a decision: too many to call the rule tested");
    // The cases reach every branch: magnified and minified, blended levels, both answers of the test.
    let magnified = checked - minified;
    assert!(blended > all / 20 && minified > all / 4 && magnified > all / 10, "{blended} {minified} {magnified}");
    assert!(passed > checked / 5 && checked - passed > checked / 5, "{passed} of {checked} pass");
    eprintln!(
        "{checked} cases equal on both backends ({magnified} magnified, {blended} blending two levels, {passed} \
         passing the alpha test; {near} near a decision left out)"
    );
}

/// A frame's textures go to the device once, one per texture however many instances read it, with their
/// mip chains (counted in the device's texture memory, as the viewer reports it), and are let go when a
/// frame reads them no more.
#[test]
fn textures_are_uploaded_once_and_shared() {
    use shadow_core::FrameInputs;
    use shadow_core::scenes::{self, SceneParams};
    if crate::with_wgpu("the textures on the device").is_none() {
        return;
    }
    let mut cx = WgpuContext::new(&shadow_wgpu::AdapterChoice { name: None, allow_software: true }).expect("context");
    let frame = |name: &str| {
        FrameInputs::from_first_camera(&scenes::build(name, &SceneParams::default()).expect("scene")).expect("frame")
    };
    // Foliage's leaves and fence's pickets, and the fences again beside them: three instances, two
    // textures.
    let mut textured = frame("foliage");
    let fence = frame("fence");
    let pickets = fence.instances.iter().find(|i| shadow_wgpu::textures::read_texture(i).is_some()).expect("pickets");
    textured.instances.extend([pickets.clone(), pickets.clone()]);
    let mut read: Vec<&Arc<Texture>> =
        textured.instances.iter().filter_map(shadow_wgpu::textures::read_texture).collect();
    assert_eq!(read.len(), 3, "textured instances");
    read.sort_by_key(|t| Arc::as_ptr(t));
    read.dedup_by_key(|t| Arc::as_ptr(t));
    assert_eq!(read.len(), 2, "textures");
    let bytes: u64 = read.iter().map(|t| t.memory_bytes() as u64).sum();
    let memory = |cx: &WgpuContext| cx.device.get_internal_counters().hal.texture_memory.read() as u64;
    let (made, held) = (cx.created().textures, memory(&cx));
    for _ in 0..3 {
        cx.upload_textures(&textured).expect("upload");
    }
    assert_eq!(cx.created().textures - made, read.len() as u64, "textures made for three frames");
    assert_eq!(cx.cache.textures.len(), read.len());
    for t in &read {
        let gpu = cx.cache.textures.get(t).expect("on the device");
        assert_eq!(gpu.texture.mip_level_count() as usize, t.levels().len(), "{}", t.name());
    }
    assert!(memory(&cx) >= held + bytes, "{} bytes of texture memory for {bytes} bytes of chains", memory(&cx) - held);
    cx.upload_textures(&frame("cubes")).expect("upload");
    assert!(cx.cache.textures.is_empty(), "a frame without textures keeps none");
}
