// The moment maps' maths (twin: moment_maps/moments.rs). The kind and its two parameters are pipeline
// constants: KIND 0 variance (Donnelly-Lauritzen), 1 exponential variance (PARAM_A = c+, PARAM_B = c-),
// 2 Hamburger 4MSM (PARAM_A = the moment bias; moments of 2d - 1). Depths d are normalized linear depths
// in [0, 1].

override KIND: u32 = 0u;
override PARAM_A: f32 = 0.0;
override PARAM_B: f32 = 0.0;

const MIN_VARIANCE: f32 = 1e-6;

fn chebyshev(mean: f32, mean_sq: f32, t: f32, min_variance: f32) -> f32 {
    if (t <= mean) {
        return 1.0;
    }
    let variance = max(mean_sq - mean * mean, min_variance);
    let d = t - mean;
    return variance / (variance + d * d);
}

fn linstep(lo: f32, hi: f32, v: f32) -> f32 {
    return clamp((v - lo) / (hi - lo), 0.0, 1.0);
}

// e^(c+ x) and -e^(-c- x), x = 2d - 1.
fn warp(d: f32) -> vec2<f32> {
    let x = 2.0 * d - 1.0;
    return vec2<f32>(exp(PARAM_A * x), -exp(-PARAM_B * x));
}

fn encode(d: f32) -> vec4<f32> {
    if (KIND == 1u) {
        let w = warp(d);
        return vec4<f32>(w.x, w.x * w.x, w.y, w.y * w.y);
    }
    if (KIND == 2u) {
        let x = 2.0 * d - 1.0;
        let x2 = x * x;
        return vec4<f32>(x, x2, x2 * x, x2 * x2);
    }
    return vec4<f32>(d, d * d, 0.0, 0.0);
}

fn hamburger_shadow(moments: vec4<f32>, z: f32, alpha: f32) -> f32 {
    let b = (1.0 - alpha) * moments + alpha * vec4<f32>(0.0, 0.63, 0.0, 0.63);
    let d22 = max(b.y - b.x * b.x, 1e-20);
    let l32 = (b.z - b.x * b.y) / d22;
    let d33 = max(b.w - b.y * b.y - l32 * l32 * d22, 1e-20);
    let w2 = z - b.x;
    let w3 = z * z - b.y - l32 * w2;
    let c3 = w3 / d33;
    let c2 = w2 / d22 - l32 * c3;
    let c1 = 1.0 - b.x * c2 - b.y * c3;
    // c3 kept from 0, as moments.rs explains.
    let least = 1e-7 * (abs(c1) + abs(c2));
    let c3_kept = select(min(c3, -least), max(c3, least), c3 >= 0.0);
    let p = c2 / c3_kept;
    let q = c1 / c3_kept;
    let r = sqrt(max(0.25 * p * p - q, 0.0));
    let z2 = -0.5 * p - r;
    let z3 = -0.5 * p + r;
    if (z <= z2) {
        return 0.0;
    } else if (z <= z3) {
        return clamp((z * z3 - b.x * (z + z3) + b.y) / ((z3 - z2) * (z - z2)), 0.0, 1.0);
    }
    return clamp(1.0 - (z2 * z3 - b.x * (z2 + z3) + b.y) / ((z - z2) * (z - z3)), 0.0, 1.0);
}

fn moment_visibility(m: vec4<f32>, t: f32) -> f32 {
    if (KIND == 1u) {
        let w = warp(t);
        let sp = 2.0 * PARAM_A * w.x;
        let sn = 2.0 * PARAM_B * w.y;
        return min(chebyshev(m.x, m.y, w.x, MIN_VARIANCE * sp * sp), chebyshev(m.z, m.w, w.y, MIN_VARIANCE * sn * sn));
    }
    if (KIND == 2u) {
        return 1.0 - hamburger_shadow(m, 2.0 * t - 1.0, PARAM_A);
    }
    return chebyshev(m.x, m.y, t, MIN_VARIANCE);
}
