//! Error metrics against a reference (DESIGN 8), over the pixels where a light's visibility shows in the
//! picture: receiver pixels inside the light's reach whose seen side faces the light ([`measured_pixels`]).
//!
//! Surfaces turned away from a light get none of it whatever their visibility (Lambert's max(n.l, 0)), and
//! there every technique's answer is a precision race: at a closed mesh's terminator, and on whole
//! sub-pixel branches, the point lies within f32 depth resolution of its own silhouette's volume side or
//! map texel. Measuring there would rank techniques by rounding, so those pixels are left out, as pixels
//! showing no receiver are (DESIGN 4). The reference still calls them shadowed.
//!
//! Every fraction has the number of masked pixels as its denominator, so the parts add up:
//! `mismatch = edge_band_mismatch + interior_mismatch = false_shadow + false_light`.

use crate::image::{Image, Rgb8};
use crate::scene::Camera;
use crate::technique::maps::MapSampling;
use glam::Vec3;

/// Half-width in pixels of the band around reference shadow boundaries.
pub const EDGE_BAND_RADIUS: i32 = 2;

/// Why two images could not be compared.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[error("cannot compare a {0}x{1} image with a {2}x{3} one")]
pub struct SizeMismatch(pub u32, pub u32, pub u32, pub u32);

/// Visibility error of a technique against a reference.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct VisibilityMetrics {
    /// Masked pixels compared.
    pub pixels: u64,
    /// Fraction where lit (v >= 0.5) differs from the reference.
    pub mismatch: f64,
    /// Mismatch within [`EDGE_BAND_RADIUS`] pixels of a reference shadow boundary.
    pub edge_band_mismatch: f64,
    /// Mismatch elsewhere.
    pub interior_mismatch: f64,
    /// Shadowed here, lit in the reference (acne).
    pub false_shadow: f64,
    /// Lit here, shadowed in the reference (leaks, peter-panning).
    pub false_light: f64,
    /// False shadow away from reference shadow boundaries: surface acne.
    pub interior_false_shadow: f64,
    /// Root mean square visibility difference.
    pub rmse: f64,
    /// Mean absolute visibility difference.
    pub mean_abs: f64,
}

/// False light on receiver pixels turned away from the light (the self-unshadowing of Weiskopf-Ertl
/// Fig. 2a and 4), as a fraction of `reach` (receivers in the light's reach); `measured` marks the pixels
/// facing the light, which are left out.
///
/// # Errors
/// When the images differ in size.
pub fn back_false_light(
    test: &Image<f32>,
    reference: &Image<f32>,
    measured: &Image<bool>,
    reach: &Image<bool>,
) -> Result<f64, SizeMismatch> {
    check(test, reference)?;
    check(test, measured)?;
    check(test, reach)?;
    let (mut n, mut k) = (0u64, 0u64);
    for i in 0..test.data().len() {
        if !reach.data()[i] {
            continue;
        }
        n += 1;
        k += u64::from(!measured.data()[i] && test.data()[i] >= 0.5 && reference.data()[i] < 0.5);
    }
    Ok(if n == 0 { 0.0 } else { k as f64 / n as f64 })
}

/// Largest reference visibility counted as umbra by [`light_bleeding`] (the area-light reference's 256
/// rays: at most two reach the light).
pub const UMBRA: f32 = 0.01;

/// Smallest visibility [`light_bleeding`] counts as light in the umbra: a tenth of the light, well clear
/// of filtering noise, plainly visible on a dark shadow.
pub const BLEEDING: f32 = 0.1;

/// Light bleeding: the fraction of `measured` pixels where `reference` is in umbra (at most [`UMBRA`])
/// and `test` lets at least [`BLEEDING`] of the light through. The failure of filterable maps, whose
/// bounds let light through a blocker when a second one lies behind it.
///
/// # Errors
/// When the images differ in size.
pub fn light_bleeding(test: &Image<f32>, reference: &Image<f32>, measured: &Image<bool>) -> Result<f64, SizeMismatch> {
    check(test, reference)?;
    check(test, measured)?;
    let (mut n, mut k) = (0u64, 0u64);
    for ((&t, &r), &m) in test.data().iter().zip(reference.data()).zip(measured.data()) {
        if m {
            n += 1;
            k += u64::from(r <= UMBRA && t >= BLEEDING);
        }
    }
    Ok(if n == 0 { 0.0 } else { k as f64 / n as f64 })
}

/// A straight shadow edge to measure a penumbra across: a world segment on a horizontal receiver at
/// height `y`, from inside the shadow outwards.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct EdgeLine {
    /// Where the segment starts, in the shadow.
    pub from: Vec3,
    /// Where it ends, in the light.
    pub to: Vec3,
    /// The receiver's height: samples on other surfaces are skipped.
    pub y: f32,
}

/// The 10%-90% width, in image pixels, of the penumbra `vis` shows along `line`: the image distance
/// between where visibility first passes 0.1 and where it first passes 0.9, sampled at 2001 points
/// where the G-buffer's `position` is on the receiver. `None` without a full ramp from 0.1 to 0.9.
#[must_use]
pub fn penumbra_width(camera: &Camera, vis: &Image<f32>, position: &Image<Vec3>, line: EdgeLine) -> Option<f32> {
    let (w, h) = (vis.width(), vis.height());
    let clip = camera.clip_from_world(w as f32 / h as f32);
    let pixel = |p: Vec3| {
        let ndc = clip.project_point3(p);
        ((ndc.x * 0.5 + 0.5) * w as f32, (0.5 - ndc.y * 0.5) * h as f32)
    };
    let mut crossings = [None, None];
    for i in 0..=2000 {
        let p = line.from.lerp(line.to, i as f32 / 2000.0);
        let (px, py) = pixel(p);
        if px < 0.0 || py < 0.0 {
            continue;
        }
        let (x, y) = (px as u32, py as u32);
        if x >= w || y >= h || (position.get(x, y).y - line.y).abs() > 0.01 {
            continue;
        }
        let v = *vis.get(x, y);
        for (k, level) in [0.1, 0.9].into_iter().enumerate() {
            if crossings[k].is_none() && v > level {
                crossings[k] = Some((px, py));
            }
        }
    }
    let (a, b) = (crossings[0]?, crossings[1]?);
    Some(((a.0 - b.0).powi(2) + (a.1 - b.1).powi(2)).sqrt())
}

/// The pixels every metric is taken over: receivers inside the light's reach whose seen side faces it.
/// `position` and `normal` are the world position and the face normal turned towards the viewer.
#[must_use]
pub fn measured_pixels(
    receiver: &Image<bool>,
    position: &Image<Vec3>,
    normal: &Image<Vec3>,
    light: &crate::light::LightView,
) -> Image<bool> {
    Image::from_fn(receiver.width(), receiver.height(), |x, y| {
        let p = *position.get(x, y);
        *receiver.get(x, y) && light.in_domain(p) && normal.get(x, y).dot(light.light.to_light(p)) > 0.0
    })
}

/// The pixels of `mask` in the nearest third of the view's depth range, where perspective aliasing is
/// worst: view depth (along the camera's axis) at most a third of the way from the nearest measured
/// receiver to the farthest.
#[must_use]
pub fn near_field(mask: &Image<bool>, position: &Image<Vec3>, camera: &Camera) -> Image<bool> {
    let axis = (camera.target - camera.eye).normalize_or_zero();
    let depth = |i: usize| (position.data()[i] - camera.eye).dot(axis);
    let measured = (0..mask.data().len()).filter(|&i| mask.data()[i]);
    let (lo, hi) = measured.map(depth).fold((f32::INFINITY, f32::NEG_INFINITY), |(lo, hi), d| (lo.min(d), hi.max(d)));
    let limit = lo + (hi - lo) / 3.0;
    Image::from_fn(mask.width(), mask.height(), |x, y| {
        let i = (y * mask.width() + x) as usize;
        mask.data()[i] && depth(i) <= limit
    })
}

/// Light-map texels per screen pixel at each pixel of `mask` (NaN where it cannot be measured): the area of
/// the pixel's footprint on its surface in the texels of the map the receiver reads. Below 1, one texel
/// covers several pixels and its square edges show (undersampling); the survey's `d / d_i` is one over the
/// square root of this. Measured from the pixel's right or left and lower or upper neighbour on the same
/// plane, so pixels at depth discontinuities and on sub-pixel detail have none.
#[must_use]
pub fn texel_density(
    sampling: &MapSampling,
    position: &Image<Vec3>,
    normal: &Image<Vec3>,
    mask: &Image<bool>,
) -> Image<f32> {
    let (w, h) = (mask.width() as i32, mask.height() as i32);
    let res = sampling.resolution as f32;
    let same_plane = |p: Vec3, n: Vec3, x: i32, y: i32| -> Option<Vec3> {
        if x < 0 || y < 0 || x >= w || y >= h || !*mask.get(x as u32, y as u32) {
            return None;
        }
        let (q, m) = (*position.get(x as u32, y as u32), *normal.get(x as u32, y as u32));
        let step = (q - p).length();
        (m.dot(n) > 0.9999 && n.dot(q - p).abs() <= 1e-3 * step).then_some(q)
    };
    Image::from_fn(w as u32, h as u32, |x, y| {
        if !*mask.get(x, y) {
            return f32::NAN;
        }
        let (p, n) = (*position.get(x, y), *normal.get(x, y));
        let (x, y) = (x as i32, y as i32);
        let along = |dx: i32, dy: i32| {
            same_plane(p, n, x + dx, y + dy).map(|q| q - p).or_else(|| same_plane(p, n, x - dx, y - dy).map(|q| p - q))
        };
        let (Some(du), Some(dv)) = (along(1, 0), along(0, 1)) else { return f32::NAN };
        let proj = &sampling.view.projections[sampling.view.projection_index(p)];
        let (uv, _) = proj.uv_depth(p);
        let (a, _) = proj.uv_depth(p + du);
        let (b, _) = proj.uv_depth(p + dv);
        let (a, b) = ((a - uv) * res, (b - uv) * res);
        (a.x * b.y - a.y * b.x).abs()
    })
}

/// The smallest and the median of the measured (not NaN) values of `values` over `mask`, or `None` when
/// there are none.
#[must_use]
pub fn min_median(values: &Image<f32>, mask: &Image<bool>) -> Option<(f64, f64)> {
    let mut v: Vec<f32> =
        values.data().iter().zip(mask.data()).filter(|&(v, &m)| m && !v.is_nan()).map(|(v, _)| *v).collect();
    if v.is_empty() {
        return None;
    }
    v.sort_by(f32::total_cmp);
    Some((f64::from(v[0]), f64::from(v[v.len() / 2])))
}

fn check<A, B>(a: &Image<A>, b: &Image<B>) -> Result<(), SizeMismatch> {
    if a.same_size(b) { Ok(()) } else { Err(SizeMismatch(a.width(), a.height(), b.width(), b.height())) }
}

/// Pixels within [`EDGE_BAND_RADIUS`] (Euclidean) of a reference shadow boundary: a masked pixel whose
/// binary reference visibility differs from a masked 4-neighbour's.
#[must_use]
pub fn edge_band(reference: &Image<f32>, mask: &Image<bool>) -> Image<bool> {
    let (w, h) = (reference.width() as i32, reference.height() as i32);
    let lit = |x: i32, y: i32| *reference.get(x as u32, y as u32) >= 0.5;
    let inside = |x: i32, y: i32| x >= 0 && y >= 0 && x < w && y < h && *mask.get(x as u32, y as u32);
    let boundary = Image::from_fn(w as u32, h as u32, |x, y| {
        let (x, y) = (x as i32, y as i32);
        inside(x, y)
            && [(1, 0), (-1, 0), (0, 1), (0, -1)]
                .iter()
                .any(|&(dx, dy)| inside(x + dx, y + dy) && lit(x + dx, y + dy) != lit(x, y))
    });
    let r = EDGE_BAND_RADIUS;
    Image::from_fn(w as u32, h as u32, |x, y| {
        let (x, y) = (x as i32, y as i32);
        (-r..=r).any(|dy| {
            (-r..=r).any(|dx| {
                dx * dx + dy * dy <= r * r && inside(x + dx, y + dy) && *boundary.get((x + dx) as u32, (y + dy) as u32)
            })
        })
    })
}

/// Compares a visibility image with a reference over `mask`.
///
/// # Errors
/// When the three images differ in size.
pub fn compare_visibility(
    test: &Image<f32>,
    reference: &Image<f32>,
    mask: &Image<bool>,
) -> Result<VisibilityMetrics, SizeMismatch> {
    check(test, reference)?;
    check(test, mask)?;
    let band = edge_band(reference, mask);
    let (mut n, mut band_miss, mut interior_miss, mut fs, mut fl, mut acne) = (0u64, 0u64, 0u64, 0u64, 0u64, 0u64);
    let (mut sq, mut abs) = (0.0f64, 0.0f64);
    for i in 0..test.data().len() {
        if !mask.data()[i] {
            continue;
        }
        n += 1;
        let (t, r) = (test.data()[i], reference.data()[i]);
        let d = f64::from(t - r);
        sq += d * d;
        abs += d.abs();
        let (tl, rl) = (t >= 0.5, r >= 0.5);
        if tl != rl {
            if band.data()[i] {
                band_miss += 1;
            } else {
                interior_miss += 1;
                if rl {
                    acne += 1;
                }
            }
            if rl {
                fs += 1;
            } else {
                fl += 1;
            }
        }
    }
    let frac = |k: u64| if n == 0 { 0.0 } else { k as f64 / n as f64 };
    Ok(VisibilityMetrics {
        pixels: n,
        mismatch: frac(band_miss + interior_miss),
        edge_band_mismatch: frac(band_miss),
        interior_mismatch: frac(interior_miss),
        false_shadow: frac(fs),
        false_light: frac(fl),
        interior_false_shadow: frac(acne),
        rmse: if n == 0 { 0.0 } else { (sq / n as f64).sqrt() },
        mean_abs: if n == 0 { 0.0 } else { abs / n as f64 },
    })
}

/// Mean FLIP error (NVIDIA's perceptual metric, as in wgpu's image tests) of two shaded images, averaged
/// over `mask`. FLIP sees the whole image (its filters need the surroundings); only the average is masked.
///
/// # Errors
/// When the images differ in size.
pub fn flip_mean(test: &Image<Rgb8>, reference: &Image<Rgb8>, mask: &Image<bool>) -> Result<f64, SizeMismatch> {
    check(test, reference)?;
    check(test, mask)?;
    let bytes = |img: &Image<Rgb8>| img.data().iter().flatten().copied().collect::<Vec<u8>>();
    let (w, h) = (test.width(), test.height());
    let r = nv_flip::FlipImageRgb8::with_data(w, h, &bytes(reference));
    let t = nv_flip::FlipImageRgb8::with_data(w, h, &bytes(test));
    let err = nv_flip::flip(r, t, nv_flip::DEFAULT_PIXELS_PER_DEGREE).to_vec();
    let (sum, n) = err
        .iter()
        .zip(mask.data())
        .filter(|(_, m)| **m)
        .fold((0.0f64, 0u64), |(s, n), (e, _)| (s + f64::from(*e), n + 1));
    Ok(if n == 0 { 0.0 } else { sum / n as f64 })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A 20x20 reference, shadowed for x < 10; the test shadows x < 12 (two columns of false shadow) and
    /// leaks one interior pixel.
    #[test]
    fn known_answers() {
        let reference = Image::from_fn(20, 20, |x, _| if x < 10 { 0.0 } else { 1.0 });
        let test = Image::from_fn(20, 20, |x, y| {
            if (x, y) == (2, 5) {
                1.0
            } else if x < 12 {
                0.0
            } else {
                1.0
            }
        });
        let mask = Image::new(20, 20, true);
        let m = compare_visibility(&test, &reference, &mask).unwrap();
        assert_eq!(m.pixels, 400);
        assert!((m.mismatch - 41.0 / 400.0).abs() < 1e-12);
        assert!((m.false_shadow - 40.0 / 400.0).abs() < 1e-12);
        assert!((m.false_light - 1.0 / 400.0).abs() < 1e-12);
        // Columns 10 and 11 are within 2 px of the boundary (between columns 9 and 10); (2, 5) is not.
        assert!((m.edge_band_mismatch - 40.0 / 400.0).abs() < 1e-12);
        assert!((m.interior_mismatch - 1.0 / 400.0).abs() < 1e-12);
        // The interior miss is a leak, not acne.
        assert_eq!(m.interior_false_shadow, 0.0);
        assert!((m.mean_abs - 41.0 / 400.0).abs() < 1e-12);
        assert!((m.rmse - (41.0f64 / 400.0).sqrt()).abs() < 1e-12);
    }

    #[test]
    fn bleeding_counts_light_in_the_umbra_only() {
        // Umbra for x < 5, penumbra at 5 (0.4), lit beyond; the test lets 0.2 through at x = 1 and 3
        // (bleeding), 0.05 at x = 2 (below the threshold), and brightens the penumbra (not umbra).
        let reference = Image::from_fn(10, 1, |x, _| match x {
            0..5 => 0.0,
            5 => 0.4,
            _ => 1.0,
        });
        let test = Image::from_fn(10, 1, |x, _| match x {
            1 | 3 => 0.2,
            2 => 0.05,
            5 => 0.9,
            0..5 => 0.0,
            _ => 1.0,
        });
        let all = Image::new(10, 1, true);
        assert!((light_bleeding(&test, &reference, &all).unwrap() - 0.2).abs() < 1e-12);
        let left = Image::from_fn(10, 1, |x, _| x < 2);
        assert!((light_bleeding(&test, &reference, &left).unwrap() - 0.5).abs() < 1e-12);
    }

    #[test]
    fn band_is_two_pixels_wide_each_side() {
        let reference = Image::from_fn(20, 1, |x, _| if x < 10 { 0.0 } else { 1.0 });
        let band = edge_band(&reference, &Image::new(20, 1, true));
        let cols: Vec<u32> = (0..20).filter(|&x| *band.get(x, 0)).collect();
        assert_eq!(cols, vec![7, 8, 9, 10, 11, 12]);
    }

    #[test]
    fn mask_excludes_pixels() {
        let reference = Image::new(4, 4, 1.0f32);
        let test = Image::new(4, 4, 0.0f32);
        let mask = Image::from_fn(4, 4, |x, _| x == 0);
        let m = compare_visibility(&test, &reference, &mask).unwrap();
        assert_eq!(m.pixels, 4);
        assert_eq!(m.mismatch, 1.0);
        assert!(compare_visibility(&test, &Image::new(3, 4, 1.0), &mask).is_err());
    }

    #[test]
    fn near_field_is_the_nearest_third_of_the_depths_seen() {
        // Receivers at depths 1 to 10 along -Z from the eye: the nearest third is up to 4.
        let camera = Camera::look_at(Vec3::ZERO, Vec3::NEG_Z, 60.0);
        let position = Image::from_fn(10, 1, |x, _| Vec3::new(0.0, 0.0, -1.0 - x as f32));
        let near = near_field(&Image::new(10, 1, true), &position, &camera);
        let cols: Vec<u32> = (0..10).filter(|&x| *near.get(x, 0)).collect();
        assert_eq!(cols, vec![0, 1, 2, 3]);
    }

    #[test]
    fn texel_density_counts_texels_per_pixel() {
        // A plane facing a directional light straight on, its pixels 0.01 apart, a map of 1000 texels
        // over 10 units: each pixel spans one texel each way.
        let light = crate::light::LightView::fit(
            &crate::scene::Light::directional(Vec3::NEG_Y),
            &[crate::bounds::Aabb::new(Vec3::new(-5.0, 0.0, -5.0), Vec3::new(5.0, 0.0, 5.0))],
        )
        .unwrap();
        let size = light.projections[0].world_from_uv_depth(glam::Vec2::ONE, 0.5)
            - light.projections[0].world_from_uv_depth(glam::Vec2::ZERO, 0.5);
        let res = 1000;
        let texel = size.abs().max_element() / res as f32;
        let sampling = MapSampling { view: light, resolution: res };
        let position = Image::from_fn(8, 8, |x, y| Vec3::new(x as f32 * texel * 2.0, 0.0, y as f32 * texel));
        let normal = Image::new(8, 8, Vec3::Y);
        let mask = Image::from_fn(8, 8, |x, _| x != 3);
        let d = texel_density(&sampling, &position, &normal, &mask);
        // Two texels across, one down: 2 texels per pixel, from either neighbour, none off the mask.
        assert!((d.get(0, 0) - 2.0).abs() < 1e-2, "{}", d.get(0, 0));
        assert!((d.get(7, 7) - 2.0).abs() < 1e-2, "{}", d.get(7, 7));
        assert!(d.get(3, 0).is_nan());
        let (lo, median) = min_median(&d, &mask).unwrap();
        assert!((lo - 2.0).abs() < 1e-2 && (median - 2.0).abs() < 1e-2);
    }

    #[test]
    fn flip_is_zero_for_equal_and_positive_for_different() {
        let a = Image::from_fn(32, 32, |x, y| [(x * 8) as u8, (y * 8) as u8, 128]);
        let mask = Image::new(32, 32, true);
        assert!(flip_mean(&a, &a, &mask).unwrap() < 1e-6);
        let b = a.map(|p| [255 - p[0], p[1], p[2]]);
        assert!(flip_mean(&b, &a, &mask).unwrap() > 0.1);
    }
}
