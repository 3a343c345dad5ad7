//! Cascaded shadow maps for a directional light: the camera's view depth range cut into slices by the
//! practical split scheme (Zhang et al. 2006: a blend of the logarithmic split, which keeps texels per
//! pixel constant in depth, and the uniform one), and one orthographic map fitted to each slice.
//!
//! A uniform map spreads its texels over the whole scene, so a receiver at the viewer's feet gets as few as
//! one on the horizon (perspective aliasing, the survey's `d_s r_s / r_i`). Each cascade covers only its
//! slice, so near slices get small texels and far ones large texels.
//!
//! A map whose texels slide or change size as the camera moves makes its shadow edges shimmer. Three fits
//! ([`Stabilize`]):
//! - `sphere`: each slice bounded by a sphere whose radius depends only on the slice's depths and the
//!   field of view (so it is the same whatever way the camera turns), and the map window moved in whole
//!   texels of a light-space grid anchored at the world origin (so a caster lands on the same texels from
//!   frame to frame). Never shimmers; the price is texels, for the sphere holds more than the slice.
//! - `snapped`: the slice's corners fitted tightly, the window's side rounded up to the next step of a
//!   ladder of sizes an eighth of an octave apart and moved in whole texels: the texel size holds until
//!   the tight fit crosses a step, so the shadows stand still but for a jump now and then, with most of the
//!   tight fit's texels.
//! - `off`: the slice's corners fitted tightly, every frame anew: the most texels, sliding and changing
//!   size as the camera moves.

use glam::camera::rh::proj::directx;
use glam::camera::rh::view::look_to_mat4;
use glam::{Vec3, Vec3Swizzles};

use super::{LightProjection, LightView, safe_up};
use crate::bounds::Aabb;
use crate::scene::{Camera, LightKind};

/// The most cascades a light view holds (a shader's split vector has four lanes).
pub const MAX_CASCADES: usize = 4;

/// How a light view's projections split the camera's view depth: receivers at view depth up to `far[k]`
/// read cascade `k` (the last also takes anything deeper).
#[derive(Clone, Debug, PartialEq)]
pub struct Cascades {
    /// The camera's eye.
    pub eye: Vec3,
    /// The camera's unit view axis: a point's view depth is `(p - eye) . axis`.
    pub axis: Vec3,
    /// The near end of the first cascade.
    pub near: f32,
    /// The far end of each cascade, increasing; the last is the far end of the view.
    pub far: Vec<f32>,
    /// The fraction of each cascade's depth range, at its far end, over which it fades into the next.
    pub blend: f32,
}

/// The cascade a receiver reads, and where it fades into the next, that one and the next's weight.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CascadePick {
    /// The cascade.
    pub cascade: usize,
    /// The next cascade and its weight in (0, 1], inside the blend band at the cascade's far end.
    pub next: Option<(usize, f32)>,
}

impl Cascades {
    /// A point's view depth.
    #[must_use]
    #[inline]
    pub fn depth(&self, p: Vec3) -> f32 {
        (p - self.eye).dot(self.axis)
    }

    /// The near end of cascade `k`.
    #[must_use]
    pub fn near_of(&self, k: usize) -> f32 {
        if k == 0 { self.near } else { self.far[k - 1] }
    }

    /// Where cascade `k` starts fading into the next: `blend` of its depth range before its far end.
    #[must_use]
    pub fn blend_start(&self, k: usize) -> f32 {
        self.far[k] - self.blend * (self.far[k] - self.near_of(k))
    }

    /// The cascade for view depth `depth`, with the next one's weight in the blend band. WGSL twin:
    /// `cascade_pick` in shadow_map.wgsl.
    #[must_use]
    pub fn pick(&self, depth: f32) -> CascadePick {
        let last = self.far.len() - 1;
        let cascade = self.far.iter().position(|&f| depth <= f).unwrap_or(last);
        let start = self.blend_start(cascade);
        let next = (cascade < last && depth > start && self.far[cascade] > start)
            .then(|| (cascade + 1, ((depth - start) / (self.far[cascade] - start)).min(1.0)));
        CascadePick { cascade, next }
    }
}

/// The far end of each of `count` slices of `[near, far]` by the practical split scheme: `lambda` of the
/// logarithmic split `near (far / near)^(i / count)` plus `1 - lambda` of the uniform one. The last is
/// `far` exactly.
#[must_use]
pub fn practical_splits(near: f32, far: f32, count: usize, lambda: f32) -> Vec<f32> {
    (1..=count)
        .map(|i| {
            if i == count {
                return far;
            }
            let s = i as f32 / count as f32;
            lambda * near * (far / near).powf(s) + (1.0 - lambda) * (near + (far - near) * s)
        })
        .collect()
}

crate::named_enum! {
    /// How a cascade's window follows the camera (see the module docs).
    pub enum Stabilize {
        /// A bounding sphere of fixed size on a world texel grid.
        Sphere = "sphere",
        /// A tight fit, its size on a ladder, on a world texel grid.
        Snapped = "snapped",
        /// A tight fit, every frame anew.
        Off = "off",
    }
}

/// Steps per octave of the ladder of window sizes of a snapped fit.
const LADDER: f32 = 8.0;

/// How cascades are split and fitted.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CascadeFit {
    /// Number of cascades, 1 to [`MAX_CASCADES`].
    pub count: usize,
    /// The practical scheme's weight of the logarithmic split (0 uniform, 1 logarithmic).
    pub lambda: f32,
    /// The fraction of each cascade's range over which it fades into the next.
    pub blend: f32,
    /// How each cascade's window follows the camera.
    pub stabilize: Stabilize,
    /// Map side in texels (the texel grid of a stabilised fit).
    pub resolution: u32,
    /// The view depth the last cascade ends at; 0 fits it to the scene.
    pub distance: f32,
}

/// The radius of the smallest sphere centred on the view axis around the slice `[n, f]` of a frustum
/// whose corner rays leave the axis at `tan^2 = k` (`tan_x^2 + tan_y^2`), and the centre's depth. Only
/// the slice's depths and the field of view enter, so a turning camera keeps the radius to the last bit.
fn slice_sphere(n: f32, f: f32, k: f32) -> (f32, f32) {
    // Equal distance to a near and a far corner: (c - n)^2 + n^2 k = (f - c)^2 + f^2 k.
    let c = ((n + f) * (1.0 + k) * 0.5).clamp(n, f);
    let to_near = ((c - n) * (c - n) + n * n * k).sqrt();
    let to_far = ((f - c) * (f - c) + f * f * k).sqrt();
    (to_near.max(to_far), c)
}

impl LightView {
    /// The view of a directional light as [`CascadeFit::count`] cascades over the view of `camera` (whose
    /// picture is `aspect` wide per unit of height) into a scene bounded by `bounds`; any other light's
    /// view is returned unchanged. The view's depth range runs from the camera's near plane to
    /// [`CascadeFit::distance`], or when that is 0 to the deepest corner of `bounds` (the camera has no far
    /// plane: nothing lies beyond the scene); stabilised, to the farthest corner's distance, rounded up.
    #[must_use]
    pub fn cascaded(&self, camera: &Camera, aspect: f32, bounds: &Aabb, fit: &CascadeFit) -> Self {
        let LightKind::Directional { direction } = self.light.kind else { return self.clone() };
        let count = fit.count.clamp(1, MAX_CASCADES);
        let dir = direction.normalize();
        let axis = (camera.target - camera.eye).normalize();
        let world_from_camera = camera.view_from_world().inverse();
        let near = camera.near;
        let far_end = if fit.distance > 0.0 {
            fit.distance.max(near * 2.0)
        } else if fit.stabilize != Stabilize::Off {
            // The distance to the farthest corner, which does not change as the camera turns, rounded up
            // to an eighth of an octave, so that moving changes it (and every radius) only now and then.
            let reach = bounds.corners().iter().map(|&c| (c - camera.eye).length()).fold(0.0f32, f32::max);
            ((reach.max(near * 2.0).log2() * 8.0).ceil() / 8.0).exp2()
        } else {
            let deepest = bounds.corners().iter().map(|&c| (c - camera.eye).dot(axis)).fold(0.0f32, f32::max);
            deepest.max(near * 2.0)
        };
        let cascades = Cascades {
            eye: camera.eye,
            axis,
            near,
            far: practical_splits(near, far_end, count, fit.lambda),
            blend: fit.blend.clamp(0.0, 1.0),
        };
        // Light space anchored at the world origin, so a stabilised window's texel grid is the world's.
        let light_from_world = look_to_mat4(Vec3::ZERO, dir, safe_up(dir));
        let scene = bounds.transformed(light_from_world);
        let pad = (scene.max.z - scene.min.z) * 0.01 + 1e-4;
        let (z_near, z_far) = super::orthographic_range(-scene.max.z - pad, -scene.min.z + pad);
        let tan_y = (camera.fov_y * 0.5).tan();
        let tan_x = tan_y * aspect;
        let res = fit.resolution.max(4) as f32;
        let projections = (0..count)
            .map(|k| {
                // A cascade also covers the blend band of the one before, where the two are mixed.
                let n = if k == 0 { near } else { cascades.blend_start(k - 1) };
                let f = cascades.far[k];
                let tight = || {
                    let corners = [n, f].into_iter().flat_map(|d| {
                        [(-1.0, -1.0), (1.0, -1.0), (-1.0, 1.0), (1.0, 1.0)].map(|(sx, sy)| {
                            world_from_camera.transform_point3(Vec3::new(sx * tan_x * d, sy * tan_y * d, -d))
                        })
                    });
                    Aabb::from_points(corners.map(|p| light_from_world.transform_point3(p)))
                };
                // A window of side `side` texels `res - 2` wide (one texel of slack each side) around
                // `centre`, moved in whole texels: snapping moves it less than a texel, so it still holds
                // what `side` held.
                let snapped = |centre: glam::Vec2, side: f32| {
                    let texel = side / (res - 2.0);
                    let half = texel * res * 0.5;
                    let c = (centre / texel).floor() * texel;
                    (c.x - half, c.x + half, c.y - half, c.y + half)
                };
                let (x0, x1, y0, y1) = match fit.stabilize {
                    Stabilize::Sphere => {
                        let (radius, c) = slice_sphere(n, f, tan_x * tan_x + tan_y * tan_y);
                        snapped(light_from_world.transform_point3(camera.eye + axis * c).xy(), 2.0 * radius)
                    }
                    Stabilize::Snapped => {
                        let b = tight();
                        let side = (b.max - b.min).xy().max_element();
                        let on_ladder = ((side.log2() * LADDER).ceil() / LADDER).exp2();
                        snapped(((b.min + b.max) * 0.5).xy(), on_ladder)
                    }
                    Stabilize::Off => {
                        let b = tight();
                        // A texel of margin, so that corners on the window's edge stay inside it.
                        let margin = (b.max - b.min).xy() / res;
                        (b.min.x - margin.x, b.max.x + margin.x, b.min.y - margin.y, b.max.y + margin.y)
                    }
                };
                let proj = directx::orthographic(x0, x1, y0, y1, z_near, z_far);
                LightProjection::new(light_from_world, proj, z_near, z_far, true)
            })
            .collect();
        Self { light: self.light, projections, cascades: Some(cascades) }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::Light;
    use glam::Mat4;

    fn scene() -> (LightView, Aabb) {
        let bounds = Aabb::new(Vec3::new(-100.0, 0.0, -100.0), Vec3::new(100.0, 20.0, 100.0));
        (LightView::fit(&Light::directional(Vec3::new(0.5, -0.35, 0.2)), &[bounds]).unwrap(), bounds)
    }

    fn fit(stabilize: Stabilize) -> CascadeFit {
        CascadeFit { count: 4, lambda: 0.5, blend: 0.1, stabilize, resolution: 2048, distance: 0.0 }
    }

    #[test]
    fn practical_splits_blend_log_and_uniform() {
        let log = practical_splits(1.0, 16.0, 4, 1.0);
        assert!(log.iter().zip([2.0, 4.0, 8.0, 16.0]).all(|(a, b)| (a - b).abs() < 1e-4), "{log:?}");
        let uniform = practical_splits(1.0, 17.0, 4, 0.0);
        assert!(uniform.iter().zip([5.0, 9.0, 13.0, 17.0]).all(|(a, b)| (a - b).abs() < 1e-4), "{uniform:?}");
        let half = practical_splits(1.0, 16.0, 4, 0.5);
        assert!((half[0] - 0.5 * (2.0 + 4.75)).abs() < 1e-4, "{half:?}");
    }

    #[test]
    fn every_receiver_in_view_lies_in_the_maps_it_reads() {
        let (view, bounds) = scene();
        let camera = Camera::look_at(Vec3::new(3.0, 1.7, 40.0), Vec3::new(-20.0, 1.0, -60.0), 60.0);
        let aspect = 16.0 / 9.0;
        for stabilize in [Stabilize::Sphere, Stabilize::Snapped, Stabilize::Off] {
            let v = view.cascaded(&camera, aspect, &bounds, &fit(stabilize));
            let c = v.cascades.as_ref().unwrap();
            assert_eq!(v.projections.len(), 4);
            // Points through the view's corners and centre at many depths.
            let world_from_camera = camera.view_from_world().inverse();
            let t = (camera.fov_y * 0.5).tan();
            for i in 0..200 {
                let d = c.near + (c.far[3] - c.near) * (i as f32 / 199.0).powi(3);
                for (sx, sy) in [(-1.0, -1.0), (1.0, 1.0), (0.0, 0.0), (1.0, -1.0), (-0.99, 0.4)] {
                    let p = world_from_camera.transform_point3(Vec3::new(sx * t * aspect * d, sy * t * d, -d));
                    let pick = c.pick(c.depth(p));
                    for k in std::iter::once(pick.cascade).chain(pick.next.map(|n| n.0)) {
                        let ndc = v.projections[k].ndc(p);
                        assert!(ndc.x.abs() <= 1.0 && ndc.y.abs() <= 1.0, "stabilize {stabilize}: {p} in {k}: {ndc}");
                    }
                }
            }
        }
    }

    #[test]
    fn stabilised_texels_stay_on_the_grid_as_the_camera_turns_and_moves() {
        let (view, bounds) = scene();
        let texel_origin = |camera: &Camera, stabilize| {
            let v = view.cascaded(camera, 1.5, &bounds, &CascadeFit { distance: 150.0, ..fit(stabilize) });
            let p = &v.projections[1];
            // The world origin's map coordinates in texels, and the texel size in world units.
            let (uv, _) = p.uv_depth(Vec3::ZERO);
            // Measured across the whole map, so the rounding of the two world points is a 2048th of it.
            let size = (p.world_from_uv_depth(glam::Vec2::new(1.0, 0.0), 0.75)
                - p.world_from_uv_depth(glam::Vec2::ZERO, 0.75))
            .length()
                / 2048.0;
            (uv * 2048.0, size)
        };
        let camera = Camera::look_at(Vec3::new(3.0, 1.7, 40.0), Vec3::new(-20.0, 1.0, -60.0), 60.0);
        // Any turn and move for the sphere; a walker's small ones for the snapped fit, within a step
        // of its ladder.
        let moves = [
            (Stabilize::Sphere, Mat4::from_rotation_y(0.3)),
            (Stabilize::Sphere, Mat4::from_translation(Vec3::new(0.37, 0.0, -1.21))),
            (Stabilize::Sphere, Mat4::from_rotation_y(-1.1) * Mat4::from_translation(Vec3::new(5.0, 0.2, 0.0))),
            (Stabilize::Snapped, Mat4::from_translation(Vec3::new(0.05, 0.0, -0.05))),
            (Stabilize::Snapped, Mat4::from_rotation_y(0.002)),
        ];
        for (stabilize, m) in moves {
            let (o0, s0) = texel_origin(&camera, stabilize);
            let (o, s) = texel_origin(&camera.transformed(m), stabilize);
            assert!((s - s0).abs() < 1e-5 * s0, "texel size changed: {s0} -> {s}");
            // The origin stays on a texel corner: whole texels from where it was.
            let shift = o - o0;
            assert!((shift - shift.round()).abs().max_element() < 2e-2, "moved {shift} texels");
        }
    }

    #[test]
    fn picks_blend_into_the_next_cascade_at_the_far_end() {
        let c = Cascades { eye: Vec3::ZERO, axis: Vec3::NEG_Z, near: 1.0, far: vec![11.0, 31.0], blend: 0.1 };
        assert_eq!(c.pick(5.0), CascadePick { cascade: 0, next: None });
        let p = c.pick(10.5);
        assert_eq!(p.cascade, 0);
        assert!((p.next.unwrap().1 - 0.5).abs() < 1e-5);
        assert_eq!(c.pick(30.9).next, None);
        assert_eq!(c.pick(50.0).cascade, 1);
    }
}
