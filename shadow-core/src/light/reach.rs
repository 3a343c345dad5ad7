//! A light's reach in a view: the part of space its direct term can light, and the pixels that part covers.
//!
//! A point or spot light with a range lights nothing beyond it (glTF's window reaches 0 there), and a spot
//! nothing outside its cone (the falloff is 0 at the rim), so a pixel whose surface lies outside both is
//! shaded the same whatever its visibility. A frame asks a light's query for the pixels within its reach
//! only, and skips a light whose reach covers no pixel of the view. A light without a range, and a
//! directional light, reach everything.
//!
//! The bounds are widened by a hair over the zeros of the shading terms ([`crate::shading`]), so every
//! pixel whose direct term is not exactly 0 is inside; the pixels inside are answered exactly as a query
//! over the whole view answers them.

use std::ops::Range;

use glam::{Mat4, Vec3, Vec4, Vec4Swizzles};

use crate::bounds::Aabb;
use crate::scene::{Camera, Light, LightKind};
use crate::shading::cone_cosines;

/// Relative widening of a range: the window is 0 from the range on, so this only takes in surfaces a
/// few millionths beyond it.
const RANGE_MARGIN: f32 = 1e-3;

/// Widening of a cone's cosine: the falloff is 0 wherever the cosine to the axis is at most the rim's.
const CONE_MARGIN: f32 = 1e-3;

/// A rectangle of pixels: columns `x0..x1` and rows `y0..y1`, empty when either is.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct PixelRect {
    /// First column.
    pub x0: u32,
    /// First row.
    pub y0: u32,
    /// One past the last column.
    pub x1: u32,
    /// One past the last row.
    pub y1: u32,
}

impl PixelRect {
    /// Every pixel of a `width x height` view.
    #[must_use]
    pub fn full(width: u32, height: u32) -> Self {
        Self { x0: 0, y0: 0, x1: width, y1: height }
    }

    /// True when it holds no pixel.
    #[must_use]
    pub fn is_empty(&self) -> bool {
        self.x0 >= self.x1 || self.y0 >= self.y1
    }

    /// Its columns.
    #[must_use]
    pub fn columns(&self) -> Range<u32> {
        self.x0..self.x1
    }

    /// Its rows.
    #[must_use]
    pub fn rows(&self) -> Range<u32> {
        self.y0..self.y1
    }

    /// Its pixel count.
    #[must_use]
    pub fn area(&self) -> u64 {
        if self.is_empty() { 0 } else { u64::from(self.x1 - self.x0) * u64::from(self.y1 - self.y0) }
    }

    /// Whether pixel (x, y) is in it.
    #[must_use]
    #[inline]
    pub fn contains(&self, x: u32, y: u32) -> bool {
        (self.x0..self.x1).contains(&x) && (self.y0..self.y1).contains(&y)
    }
}

/// The solid a bounded light reaches: a ball about the light, cut to a cone for a spot.
#[derive(Clone, Copy, Debug, PartialEq)]
struct Sector {
    apex: Vec3,
    /// The range, widened, squared.
    radius_squared: f32,
    /// A spot's unit axis and the cosine of its rim's half-angle, widened.
    cone: Option<(Vec3, f32)>,
}

impl Sector {
    fn of(light: &Light) -> Option<Self> {
        let (range, apex) = (light.range?, light.position()?);
        let radius = range * (1.0 + RANGE_MARGIN);
        let cone = match light.kind {
            LightKind::Spot { direction, .. } => {
                cone_cosines(light).map(|(rim, _)| (direction.normalize_or_zero(), rim - CONE_MARGIN))
            }
            _ => None,
        };
        Some(Self { apex, radius_squared: radius * radius, cone })
    }

    fn radius(&self) -> f32 {
        self.radius_squared.sqrt()
    }

    #[inline]
    fn holds(&self, p: Vec3) -> bool {
        let d = p - self.apex;
        let far = d.length_squared();
        far <= self.radius_squared && self.cone.is_none_or(|(axis, rim)| far == 0.0 || d.dot(axis) >= rim * far.sqrt())
    }

    /// The smallest box around it: along each axis direction `e`, the farthest it gets is the radius
    /// times the largest cosine between `e` and a direction of the cone (1 where `e` is inside it, else
    /// the cosine of `e`'s angle past the rim), or the apex itself.
    fn bounds(&self) -> Aabb {
        let r = self.radius();
        let Some((axis, rim)) = self.cone else {
            return Aabb::new(self.apex - Vec3::splat(r), self.apex + Vec3::splat(r));
        };
        let half = rim.clamp(-1.0, 1.0).acos();
        let reach_along = |e: Vec3| {
            let off_axis = axis.dot(e).clamp(-1.0, 1.0).acos();
            let cosine = if off_axis <= half { 1.0 } else { (off_axis - half).cos() };
            r * cosine.max(0.0)
        };
        let max = Vec3::new(reach_along(Vec3::X), reach_along(Vec3::Y), reach_along(Vec3::Z));
        let min = Vec3::new(reach_along(Vec3::NEG_X), reach_along(Vec3::NEG_Y), reach_along(Vec3::NEG_Z));
        Aabb::new(self.apex - min, self.apex + max)
    }
}

/// Where a light can light anything in one view ([module docs](self)).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Reach {
    /// The pixels whose surfaces it may reach; none outside.
    pub rect: PixelRect,
    sector: Option<Sector>,
}

impl Reach {
    /// Every pixel of a `width x height` view and all of space: a light without bounds, or a frame that
    /// does not bound its lights.
    #[must_use]
    pub fn everywhere(width: u32, height: u32) -> Self {
        Self { rect: PixelRect::full(width, height), sector: None }
    }

    /// The reach of `light` in a `width x height` view through `camera`.
    #[must_use]
    pub fn of(light: &Light, camera: &Camera, width: u32, height: u32) -> Self {
        let Some(sector) = Sector::of(light) else { return Self::everywhere(width, height) };
        let aspect = width as f32 / height.max(1) as f32;
        let rect = screen_rect(&sector.bounds(), camera.clip_from_world(aspect), width, height);
        Self { rect, sector: Some(sector) }
    }

    /// True when it lights no pixel of the view.
    #[must_use]
    pub fn is_empty(&self) -> bool {
        self.rect.is_empty()
    }

    /// True when it is all of space (a light without a range, or a directional one).
    #[must_use]
    pub fn is_everywhere(&self) -> bool {
        self.sector.is_none()
    }

    /// Whether the light may light world point `p` (seen at a pixel of [`Self::rect`]).
    #[must_use]
    #[inline]
    pub fn holds(&self, p: Vec3) -> bool {
        self.sector.is_none_or(|s| s.holds(p))
    }

    /// The box its solid fits in, `None` for one that is everywhere.
    #[must_use]
    pub fn bounds(&self) -> Option<Aabb> {
        self.sector.map(|s| s.bounds())
    }
}

/// The pixels of a `width x height` view that box `b` may cover seen through `clip_from_world`, with a
/// pixel's margin against rounding: its corners in front of the near plane and the points where its edges
/// cross that plane, projected (the box's outline in the view is their hull).
fn screen_rect(b: &Aabb, clip_from_world: Mat4, width: u32, height: u32) -> PixelRect {
    let corners = b.corners().map(|c| clip_from_world * c.extend(1.0));
    // Edges join corners whose indices differ in one bit (x = 1, y = 2, z = 4).
    let crossings = (0..8usize).flat_map(|i| [1usize, 2, 4].map(move |bit| (i, i | bit))).filter(|(i, j)| i != j);
    let crossing = |(i, j): (usize, usize)| -> Option<Vec4> {
        let (a, c) = (corners[i], corners[j]);
        ((a.z < 0.0) != (c.z < 0.0)).then(|| a + (c - a) * (a.z / (a.z - c.z)))
    };
    let points = corners.iter().copied().filter(|c| c.z >= 0.0).chain(crossings.filter_map(crossing));
    let (mut lo, mut hi) = (glam::Vec2::splat(f32::INFINITY), glam::Vec2::splat(f32::NEG_INFINITY));
    for c in points {
        let ndc = c.xy() / c.w.max(f32::MIN_POSITIVE);
        let pixel = glam::Vec2::new((ndc.x * 0.5 + 0.5) * width as f32, (0.5 - ndc.y * 0.5) * height as f32);
        lo = lo.min(pixel);
        hi = hi.max(pixel);
    }
    if !(lo.x <= hi.x && lo.y <= hi.y) {
        return PixelRect { x0: 0, y0: 0, x1: 0, y1: 0 };
    }
    let clamp = |v: f32, n: u32| v.clamp(0.0, n as f32) as u32;
    PixelRect {
        x0: clamp(lo.x.floor() - 1.0, width),
        y0: clamp(lo.y.floor() - 1.0, height),
        x1: clamp(hi.x.ceil() + 1.0, width),
        y1: clamp(hi.y.ceil() + 1.0, height),
    }
}

#[cfg(test)]
mod tests {
    use glam::Vec3;

    use super::{Reach, Sector};
    use crate::scene::{Camera, Light};
    use crate::shading::{cone_falloff, range_window};

    fn lights() -> Vec<Light> {
        let spot = |deg: f32| Light { range: Some(4.0), ..Light::spot(Vec3::new(1.0, 3.0, -1.0), Vec3::ZERO, deg) };
        vec![
            Light { range: Some(2.5), ..Light::point(Vec3::new(-1.0, 1.5, 0.5)) },
            spot(40.0),
            spot(100.0),
            spot(170.0),
            Light { range: Some(3.0), ..Light::spot(Vec3::new(0.0, 2.0, 0.0), Vec3::new(0.0, 2.0, 5.0), 60.0) },
        ]
    }

    /// Points on a grid through and around every light's solid.
    fn grid() -> impl Iterator<Item = Vec3> {
        let steps = (-40..=40).map(|i| i as f32 * 0.125);
        steps.clone().flat_map(move |x| {
            let steps = steps.clone();
            steps.clone().flat_map(move |y| steps.clone().map(move |z| Vec3::new(x, y, z)))
        })
    }

    #[test]
    fn every_point_a_light_shades_is_in_its_reach_and_its_box() {
        for light in lights() {
            let sector = Sector::of(&light).expect("a bounded light");
            let bounds = sector.bounds();
            let (mut lit, mut beyond) = (0, 0);
            for p in grid() {
                let shaded = range_window(&light, p) > 0.0 && cone_falloff(&light, p) > 0.0;
                if shaded {
                    lit += 1;
                    assert!(sector.holds(p), "{light:?} lights {p} outside its reach");
                    assert!(bounds.min.cmple(p).all() && p.cmple(bounds.max).all(), "{p} outside {bounds:?}");
                } else if !sector.holds(p) {
                    beyond += 1;
                }
            }
            assert!(lit > 100 && beyond > 100, "{light:?}: {lit} lit, {beyond} beyond its reach");
        }
    }

    #[test]
    fn a_sectors_box_is_tight() {
        // A cone of 90 degrees along -Y from the origin, range 2: down to -2, out to 2 sin 45 sideways.
        let light = Light { range: Some(2.0), ..Light::spot(Vec3::ZERO, Vec3::NEG_Y, 90.0) };
        let b = Sector::of(&light).expect("bounded").bounds();
        let side = 2.0 * std::f32::consts::FRAC_1_SQRT_2 * 1.001;
        assert!((b.min.y + 2.002).abs() < 1e-2 && b.max.y.abs() < 1e-6, "{b:?}");
        assert!((b.max.x - side).abs() < 1e-2 && (b.min.z + side).abs() < 1e-2, "{b:?}");
    }

    #[test]
    fn the_rect_holds_every_pixel_of_a_reached_surface() {
        let camera = Camera::look_at(Vec3::new(6.0, 7.0, 10.0), Vec3::ZERO, 50.0);
        let (width, height) = (160, 120);
        let clip = camera.clip_from_world(width as f32 / height as f32);
        let mut partial = 0;
        for light in lights() {
            let reach = Reach::of(&light, &camera, width, height);
            let mut inside = 0;
            for p in grid().filter(|&p| reach.holds(p)) {
                let c = clip * p.extend(1.0);
                if c.z < 0.0 || c.x.abs() > c.w || c.y.abs() > c.w {
                    continue;
                }
                let x = ((c.x / c.w * 0.5 + 0.5) * width as f32) as u32;
                let y = ((0.5 - c.y / c.w * 0.5) * height as f32) as u32;
                assert!(
                    reach.rect.contains(x.min(width - 1), y.min(height - 1)),
                    "{p} at ({x}, {y}) outside {reach:?}"
                );
                inside += 1;
            }
            assert!(inside > 0, "{light:?} reaches no point in view");
            partial += usize::from(reach.rect.area() < u64::from(width * height) / 2);
        }
        assert!(partial >= 3, "only {partial} lights reach under half the view");
    }

    #[test]
    fn a_light_behind_the_camera_or_without_range_reaches_as_it_should() {
        let camera = Camera::look_at(Vec3::new(0.0, 1.0, 5.0), Vec3::new(0.0, 1.0, 0.0), 45.0);
        let behind = Light { range: Some(1.0), ..Light::point(Vec3::new(0.0, 1.0, 8.0)) };
        assert!(Reach::of(&behind, &camera, 64, 64).is_empty());
        // Around the eye: the box crosses the near plane, and the whole view is reached.
        let around = Light { range: Some(3.0), ..Light::point(Vec3::new(0.0, 1.0, 5.5)) };
        assert_eq!(Reach::of(&around, &camera, 64, 64).rect.area(), 64 * 64);
        let unbounded = Reach::of(&Light::point(Vec3::new(0.0, 1.0, 8.0)), &camera, 64, 64);
        assert!(unbounded.is_everywhere() && unbounded.rect.area() == 64 * 64 && unbounded.holds(Vec3::splat(1e6)));
        let sun = Light { range: Some(1.0), ..Light::directional(Vec3::NEG_Y) };
        assert!(Reach::of(&sun, &camera, 64, 64).is_everywhere());
    }
}
