// The texel rule (twin: shadow_core::material::sampler, with the transform of `TextureRef::sample` and the
// alpha test of `Material::passes`): a material's base-colour texture read by index over the mip chain
// shadow-core built, never through a hardware sampler, so both backends pick the same levels and texels.
// The texture is Rgba8UnormSrgb: a load decodes the colour to linear light and leaves alpha as it is,
// as shadow-core's `decode` does before it filters.

// How a material reads its texture (twin: shadow-wgpu's `TexelRuleRaw`).
struct TexelRule {
    // The texture-coordinate transform (KHR_texture_transform) as two rows on (u, v, 1).
    row_u: vec4<f32>,
    row_v: vec4<f32>,
    // x: magnification filter, y: minification filter (TEXEL_NEAREST, TEXEL_LINEAR); z: between levels
    // (MIP_NONE: level 0 alone, MIP_NEAREST, MIP_LINEAR); w: the wrap along u | the wrap along v << 4
    // (WRAP_REPEAT, WRAP_CLAMP, WRAP_MIRROR).
    sampler: vec4<u32>,
    // x: the base colour's alpha factor, y: the alpha cutoff of a masked material.
    alpha: vec4<f32>,
};

const TEXEL_NEAREST: u32 = 0u;
const TEXEL_LINEAR: u32 = 1u;
const MIP_NONE: u32 = 0u;
const MIP_NEAREST: u32 = 1u;
const MIP_LINEAR: u32 = 2u;
const WRAP_REPEAT: u32 = 0u;
const WRAP_CLAMP: u32 = 1u;
const WRAP_MIRROR: u32 = 2u;

// The levels a footprint reads (twin: `LevelChoice`): `first`, and `second` by the weight `blend` where
// two are blended (`first` alone where `blend` is 0).
struct TexelLevels {
    first: u32,
    second: u32,
    blend: f32,
    magnified: bool,
};

// The texels a filter reads in one level (twin: `Sampler::texels`): columns `lo.x`, `hi.x` and rows
// `lo.y`, `hi.y`, wrapped, the second column and row weighing `f` (nearest: one texel, `lo`).
struct TexelTaps {
    lo: vec2<i32>,
    hi: vec2<i32>,
    f: vec2<f32>,
};

// Twin: `UvTransform::apply` (glam's `transform_point2`: the columns times u and v, then the offset).
fn texel_transform_point(rule: TexelRule, uv: vec2<f32>) -> vec2<f32> {
    let m = vec2<f32>(rule.row_u.x, rule.row_v.x) * uv.x + vec2<f32>(rule.row_u.y, rule.row_v.y) * uv.y;
    return m + vec2<f32>(rule.row_u.z, rule.row_v.z);
}

// A footprint's side through the transform (glam's `transform_vector2`).
fn texel_transform_vector(rule: TexelRule, d: vec2<f32>) -> vec2<f32> {
    return vec2<f32>(rule.row_u.x, rule.row_v.x) * d.x + vec2<f32>(rule.row_u.y, rule.row_v.y) * d.y;
}

// Twin: `Footprint::rho_squared`: the footprint's larger side squared, in texels of level 0.
fn texel_rho_squared(dx: vec2<f32>, dy: vec2<f32>, size: vec2<f32>) -> f32 {
    let a = dx * size;
    let b = dy * size;
    return max(a.x * a.x + a.y * a.y, b.x * b.x + b.y * b.y);
}

// Twin: `Sampler::levels`: magnified at rho^2 <= 1 (and for a NaN footprint); nearest mips compare rho^2
// with the exact powers of two 2^(2k+1); linear mips blend floor(lambda) and the level above.
fn texel_levels(rule: TexelRule, rho_squared: f32, levels: u32) -> TexelLevels {
    let top = levels - 1u;
    var out = TexelLevels(0u, 0u, 0.0, true);
    if (!(rho_squared > 1.0)) {
        return out;
    }
    out.magnified = false;
    let mip = rule.sampler.z;
    if (mip == MIP_NEAREST) {
        var k = 0u;
        var bound = 2.0;
        while (k < top && rho_squared >= bound) {
            k = k + 1u;
            bound = bound * 4.0;
        }
        out.first = k;
        out.second = k;
    } else if (mip == MIP_LINEAR) {
        let lambda = min(0.5 * log2(rho_squared), f32(top));
        let k = u32(floor(lambda));
        let t = lambda - f32(k);
        if (k >= top || t == 0.0) {
            out.first = min(k, top);
            out.second = out.first;
        } else {
            out.first = k;
            out.second = k + 1u;
            out.blend = t;
        }
    }
    return out;
}

// Twin: `Wrap::index`.
fn texel_wrap(i: i32, n: i32, mode: u32) -> i32 {
    if (mode == WRAP_CLAMP) {
        return clamp(i, 0, n - 1);
    }
    if (mode == WRAP_MIRROR) {
        var m = i % (2 * n);
        if (m < 0) {
            m = m + 2 * n;
        }
        return select(m, 2 * n - 1 - m, m >= n);
    }
    var r = i % n;
    if (r < 0) {
        r = r + n;
    }
    return r;
}

fn texel_wrap2(i: vec2<i32>, size: vec2<i32>, rule: TexelRule) -> vec2<i32> {
    let wraps = rule.sampler.w;
    return vec2<i32>(texel_wrap(i.x, size.x, wraps & 15u), texel_wrap(i.y, size.y, wraps >> 4u));
}

// Twin: `Sampler::texels`: the nearest texel, or the 2 x 2 around `uv * size - 1/2`.
fn texel_taps(rule: TexelRule, size: vec2<i32>, uv: vec2<f32>, kind: u32) -> TexelTaps {
    let p = uv * vec2<f32>(size);
    if (kind == TEXEL_NEAREST) {
        let at = texel_wrap2(vec2<i32>(floor(p)), size, rule);
        return TexelTaps(at, at, vec2<f32>(0.0));
    }
    let q = p - 0.5;
    let base = floor(q);
    let i = vec2<i32>(base);
    return TexelTaps(texel_wrap2(i, size, rule), texel_wrap2(i + vec2<i32>(1), size, rule), q - base);
}

// The size of `t`'s level `level`: level 0's halved `level` times, down to one texel (as the chain is
// built; the level's size as textureDimensions would give it, without a query per level).
fn texel_level_size(t: texture_2d<f32>, level: u32) -> vec2<i32> {
    return vec2<i32>(max(textureDimensions(t, 0u) >> vec2<u32>(level), vec2<u32>(1u)));
}

// One level's filtered texels (twin: the level sum of `Sampler::filtered`, in its order of taps).
fn texel_level(t: texture_2d<f32>, rule: TexelRule, level: u32, uv: vec2<f32>, kind: u32) -> vec4<f32> {
    let taps = texel_taps(rule, texel_level_size(t, level), uv, kind);
    if (kind == TEXEL_NEAREST) {
        return textureLoad(t, taps.lo, level);
    }
    let f = taps.f;
    var sum = textureLoad(t, taps.lo, level) * ((1.0 - f.x) * (1.0 - f.y));
    sum = sum + textureLoad(t, vec2<i32>(taps.hi.x, taps.lo.y), level) * (f.x * (1.0 - f.y));
    sum = sum + textureLoad(t, vec2<i32>(taps.lo.x, taps.hi.y), level) * ((1.0 - f.x) * f.y);
    return sum + textureLoad(t, taps.hi, level) * (f.x * f.y);
}

// The levels the transformed footprint `(dx, dy)` reads in `t`.
fn texel_levels_of(t: texture_2d<f32>, rule: TexelRule, dx: vec2<f32>, dy: vec2<f32>) -> TexelLevels {
    let size = vec2<f32>(textureDimensions(t, 0u));
    return texel_levels(rule, texel_rho_squared(dx, dy, size), textureNumLevels(t));
}

// Twin: `TextureRef::sample`: linear colour and alpha at mesh coordinate `uv` over the footprint `(dx, dy)`
// (how `uv` changes a pixel, or a map texel, to the right and down), in mesh coordinates.
fn texel_sample(t: texture_2d<f32>, rule: TexelRule, uv: vec2<f32>, dx: vec2<f32>, dy: vec2<f32>) -> vec4<f32> {
    let at = texel_transform_point(rule, uv);
    let levels = texel_levels_of(t, rule, texel_transform_vector(rule, dx), texel_transform_vector(rule, dy));
    let kind = select(rule.sampler.y, rule.sampler.x, levels.magnified);
    var out = texel_level(t, rule, levels.first, at, kind);
    if (levels.blend > 0.0) {
        out = out * (1.0 - levels.blend) + texel_level(t, rule, levels.second, at, kind) * levels.blend;
    }
    return out;
}

// Twin: `Material::passes` of a masked material with a texture: the factor's alpha times the texture's,
// at least the cutoff.
fn texel_alpha_passes(t: texture_2d<f32>, rule: TexelRule, uv: vec2<f32>, dx: vec2<f32>, dy: vec2<f32>) -> bool {
    return rule.alpha.x * texel_sample(t, rule, uv, dx, dy).w >= rule.alpha.y;
}
