//! Triangle setup: a source triangle clipped against the guard band (and the near plane, and the far one
//! unless depth clamps), snapped to fixed point, with its edge functions, top-left rule, bounds, depth
//! plane and perspective-correct barycentrics ready for the walk.

use super::{CullMode, FrontFace, HALF, ONE, RasterState, SourceTriangle, clip};

/// A triangle after clipping, projection and setup.
#[derive(Clone, Copy, Debug)]
pub(super) struct Setup {
    /// Edge functions `E_k = a px + b py + c` (fixed point), positive inside; edge k faces corner k.
    pub(super) a: [i64; 3],
    pub(super) b: [i64; 3],
    pub(super) c: [i64; 3],
    /// -1 for edges that are not top or left (a sample exactly on them is outside), else 0.
    pub(super) tl: [i64; 3],
    pub(super) min_x: i32,
    pub(super) max_x: i32,
    pub(super) min_y: i32,
    pub(super) max_y: i32,
    /// Where each edge with `a != 0` crosses a row: `px = x_at[k].0 + x_at[k].1 * py` (fixed point), for
    /// [`slab_columns`].
    pub(super) x_at: [(f64, f64); 3],
    /// The corners in fixed point, in edge order; the depth plane is anchored at corner 0.
    pub(super) fx: [i64; 3],
    pub(super) fy: [i64; 3],
    /// Depth plane: z = z0 + dzdx (x - x0) + dzdy (y - y0), in pixels.
    pub(super) z0: f32,
    pub(super) dzdx: f32,
    pub(super) dzdy: f32,
    pub(super) offset: f32,
    pub(super) inv_area: f32,
    pub(super) inv_w: [f32; 3],
    pub(super) bary: [[f32; 3]; 3],
    pub(super) prim: u32,
    pub(super) front: bool,
}

pub(super) fn floor_div(a: i64, b: i64) -> i64 {
    if b > 0 { a.div_euclid(b) } else { (-a).div_euclid(-b) }
}

pub(super) fn ceil_div(a: i64, b: i64) -> i64 {
    -floor_div(-a, b)
}

/// Screen setup of one (clipped) triangle; `None` when it covers no sample or is culled.
pub(super) fn setup_one(
    v: [clip::ClipVertex; 3],
    src: &SourceTriangle,
    st: &RasterState,
    w: u32,
    h: u32,
) -> Option<Setup> {
    let Snapped { fx, fy, z, inv_w } = snap(&v, w, h)?;
    let area = (fx[1] - fx[0]) * (fy[2] - fy[0]) - (fx[2] - fx[0]) * (fy[1] - fy[0]);
    if area == 0 {
        return None;
    }
    // Counter-clockwise in NDC (y up) is clockwise on screen (y down): negative screen area.
    let ccw = area < 0;
    let front = (ccw == (st.front_face == FrontFace::Ccw)) != src.flip;
    if src.cull_back && !front {
        return None;
    }
    match st.cull {
        CullMode::Back if !front => return None,
        CullMode::Front if front => return None,
        _ => {}
    }
    // Order the corners so the edge functions are positive inside.
    let order = if area < 0 { [0usize, 2, 1] } else { [0, 1, 2] };
    let (fx, fy, z, inv_w) = (order.map(|k| fx[k]), order.map(|k| fy[k]), order.map(|k| z[k]), order.map(|k| inv_w[k]));
    let bary = order.map(|k| v[k].bary);
    let area = area.abs();

    let [min_x, max_x, min_y, max_y] = pixel_bounds(&fx, &fy, w, h)?;
    let Edges { a, b, c, tl } = edges(&fx, &fy);
    let (dzdx, dzdy) = depth_slopes(&fx, &fy, &z);
    let offset = st.depth.map_or(0.0, |d| {
        let max_z = z.iter().fold(0.0f32, |m, v| m.max(v.abs()));
        d.bias.offset(dzdx.abs().max(dzdy.abs()), max_z)
    });

    Some(Setup {
        a,
        b,
        c,
        tl,
        min_x,
        max_x,
        min_y,
        max_y,
        x_at: [0, 1, 2]
            .map(|k| if a[k] == 0 { (0.0, 0.0) } else { (-(c[k] as f64) / a[k] as f64, -(b[k] as f64) / a[k] as f64) }),
        fx,
        fy,
        z0: z[0],
        dzdx,
        dzdy,
        offset,
        inv_area: 1.0 / area as f32,
        inv_w,
        bary,
        prim: src.prim,
        front,
    })
}

/// The corners on screen: fixed-point position, depth and `1/w`.
struct Snapped {
    fx: [i64; 3],
    fy: [i64; 3],
    z: [f32; 3],
    inv_w: [f32; 3],
}

/// Projects the corners to screen space, top-left origin, y down (DESIGN 4), snapped to 8 subpixel bits;
/// `None` when a corner is behind the eye.
fn snap(v: &[clip::ClipVertex; 3], w: u32, h: u32) -> Option<Snapped> {
    let mut out = Snapped { fx: [0; 3], fy: [0; 3], z: [0.0; 3], inv_w: [0.0; 3] };
    for (k, corner) in v.iter().enumerate() {
        let p = corner.pos;
        if p.w <= 0.0 {
            return None;
        }
        let iw = 1.0 / p.w;
        let (nx, ny) = (p.x * iw, p.y * iw);
        out.fx[k] = ((nx * 0.5 + 0.5) * w as f32 * ONE as f32).round() as i64;
        out.fy[k] = ((0.5 - ny * 0.5) * h as f32 * ONE as f32).round() as i64;
        out.z[k] = p.z * iw;
        out.inv_w[k] = iw;
    }
    Some(out)
}

/// The pixels whose centres lie inside the corners' bounding box, clamped to the target, as
/// `[min_x, max_x, min_y, max_y]`; `None` when there are none.
fn pixel_bounds(fx: &[i64; 3], fy: &[i64; 3], w: u32, h: u32) -> Option<[i32; 4]> {
    let min_fx = fx.iter().min().copied().unwrap_or(0);
    let max_fx = fx.iter().max().copied().unwrap_or(0);
    let min_fy = fy.iter().min().copied().unwrap_or(0);
    let max_fy = fy.iter().max().copied().unwrap_or(0);
    let min_x = ceil_div(min_fx - HALF, ONE).max(0);
    let max_x = floor_div(max_fx - HALF, ONE).min(i64::from(w) - 1);
    let min_y = ceil_div(min_fy - HALF, ONE).max(0);
    let max_y = floor_div(max_fy - HALF, ONE).min(i64::from(h) - 1);
    (min_x <= max_x && min_y <= max_y).then_some([min_x as i32, max_x as i32, min_y as i32, max_y as i32])
}

/// The edge functions of corners ordered positive inside, and their top-left adjustments.
struct Edges {
    a: [i64; 3],
    b: [i64; 3],
    c: [i64; 3],
    tl: [i64; 3],
}

/// Edge k runs between the two corners other than k, so `E_k` vanishes on it and grows toward corner k.
fn edges(fx: &[i64; 3], fy: &[i64; 3]) -> Edges {
    let mut e = Edges { a: [0; 3], b: [0; 3], c: [0; 3], tl: [0; 3] };
    for k in 0..3 {
        let (i, j) = ((k + 1) % 3, (k + 2) % 3);
        let (dx, dy) = (fx[j] - fx[i], fy[j] - fy[i]);
        e.a[k] = -dy;
        e.b[k] = dx;
        e.c[k] = dy * fx[i] - dx * fy[i];
        // Inside is to the side of grad E = (-dy, dx): a left edge has the inside to its right
        // (dy < 0), a top edge is horizontal with the inside below it (dy == 0, dx > 0).
        let top_left = dy < 0 || (dy == 0 && dx > 0);
        e.tl[k] = if top_left { 0 } else { -1 };
    }
    e
}

/// The depth plane's slopes `(dz/dx, dz/dy)` in pixel units, from the snapped corners.
fn depth_slopes(fx: &[i64; 3], fy: &[i64; 3], z: &[f32; 3]) -> (f32, f32) {
    let (x0, y0) = (fx[0] as f64 / ONE as f64, fy[0] as f64 / ONE as f64);
    let (x1, y1) = (fx[1] as f64 / ONE as f64 - x0, fy[1] as f64 / ONE as f64 - y0);
    let (x2, y2) = (fx[2] as f64 / ONE as f64 - x0, fy[2] as f64 / ONE as f64 - y0);
    let det = x1 * y2 - x2 * y1;
    let (z1, z2) = (f64::from(z[1]) - f64::from(z[0]), f64::from(z[2]) - f64::from(z[0]));
    (((z1 * y2 - z2 * y1) / det) as f32, ((z2 * x1 - z1 * x2) / det) as f32)
}

/// Clips and sets up a source triangle into up to seven screen triangles.
pub(super) fn setup(src: SourceTriangle, st: &RasterState, w: u32, h: u32, guard: f32, out: &mut Vec<Setup>) {
    let far = !st.depth.is_some_and(|d| d.clamp);
    if clip::trivially_out(&src.v, guard, far) {
        return;
    }
    let ident = [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]];
    if clip::inside_all(&src.v, guard, far) {
        let v = [0, 1, 2].map(|k| clip::ClipVertex { pos: src.v[k], bary: ident[k] });
        out.extend(setup_one(v, &src, st, w, h));
        return;
    }
    let poly = clip::clip_triangle(&src.v, guard, far);
    let p = poly.as_slice();
    for k in 1..p.len().saturating_sub(1) {
        out.extend(setup_one([p[0], p[k], p[k + 1]], &src, st, w, h));
    }
}

/// Guard band: how far beyond the viewport (in viewport widths) geometry may reach before it is clipped,
/// chosen so fixed-point coordinates stay far inside i32 range for any target up to 16384 pixels.
pub(super) fn guard_band(w: u32, h: u32) -> f32 {
    let side = w.max(h).max(1) as f32;
    ((1u32 << 22) as f32 / (side * ONE as f32)).clamp(1.0, 64.0)
}
