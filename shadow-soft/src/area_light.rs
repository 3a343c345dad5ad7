//! `area-light-reference`: the reference for soft shadows (DESIGN 8). At every receiver pixel, the
//! fraction of a spherical light (the scene light's `radius` about its position) that the receiver sees,
//! estimated with stratified Monte Carlo shadow rays through the CPU backend's BVH.
//!
//! Visibility here is the unoccluded fraction of the solid angle the sphere subtends, sampled uniformly
//! in that cone: the same quantity a fake soft-shadow technique's `v` stands for, since shading multiplies
//! it with the Lambert term towards the light's centre. Directions below the receiver's own horizon count
//! as blocked (the surface is in the way), as `ray-traced` counts a surface facing away. Rays leave the
//! surface as `ray-traced`'s do: offset along the face normal turned towards the viewer.

use crate::Entry;
use shadow_core::Image;
use shadow_core::glam::Vec3;
use shadow_core::lookup::{hash_unit, pixel_hash};
use shadow_core::technique::LightKinds;
use shadow_core::technique::LightPass;
use shadow_core::technique::settings::{SettingKey, SettingsError, Values};
use shadow_core::technique::{ShadowTechnique, TechniqueError};
use shadow_cpu::bvh::{SceneBvh, Walker};
use shadow_cpu::passes::per_receiver_casting;
use shadow_cpu::passes::rays::{RayOrigins, State as RayState};
use shadow_cpu::{CpuBackend, CpuContext, CpuError, GBuffer};

/// The largest sample count, per pixel.
pub const MAX_SAMPLES: u32 = 4096;

shadow_core::technique_settings! {
    /// `area-light-reference` settings.
    pub struct AreaLightReference {
        /// Shadow rays per pixel: a square number, for a `sqrt(n) x sqrt(n)` grid of strata over the light's
        /// cone of directions, one jittered ray in each.
        pub samples: u32 = SettingKey::int(
            "samples",
            "256",
            1,
            MAX_SAMPLES,
            "shadow rays per pixel, a square number (1, 4, 9, ... 4096): one per stratum of the light's cone",
        ),
        /// Ray origin offset along the normal, as a fraction of the scene's diagonal (as `ray-traced`'s).
        pub epsilon: f32 = SettingKey::float(
            "epsilon",
            "0.0000005",
            0.0,
            0.1,
            "ray origin offset along the normal, as a fraction of the scene diagonal",
        ),
    }
    lights = LightKinds::POSITIONED;
    check = AreaLightReference::check;
}

impl AreaLightReference {
    /// The technique's name.
    pub const NAME: &'static str = "area-light-reference";

    /// The strata make a square grid.
    fn check(&self, v: &Values<'_>) -> Result<(), SettingsError> {
        let side = self.samples.isqrt();
        if side * side != self.samples {
            return Err(v.bad("samples", "a square number (1, 4, 9, 16, ..., 4096)"));
        }
        Ok(())
    }
}

/// The spherical light a receiver looks at: centre and radius.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Sphere {
    /// Centre.
    pub centre: Vec3,
    /// Radius (0: a point).
    pub radius: f32,
}

/// The fraction of `light` visible from `origin` (already off the surface) on a surface of unit normal
/// `n`, and the number of rays cast for it: `samples` stratified directions (a square number) uniform in
/// the cone the sphere subtends, each below the surface's horizon counted blocked without a ray, the
/// others tested up to where they enter the sphere (each after the last blocker `walker` saw: see
/// [`SceneBvh::occluded_after`]); `seed` picks the jitter. A receiver inside the sphere sees all of it.
#[must_use]
pub fn sphere_visibility(
    bvh: &SceneBvh,
    walker: &mut Walker,
    origin: Vec3,
    n: Vec3,
    light: Sphere,
    samples: u32,
    seed: u32,
) -> (f32, u32) {
    let to_centre = light.centre - origin;
    let dist = to_centre.length();
    if dist <= light.radius {
        return (1.0, 0);
    }
    let w = to_centre / dist;
    let (u, v) = w.any_orthonormal_pair();
    // The cone of the sphere's directions: cos of its half-angle, sampled uniformly in solid angle.
    let cos_max = (1.0 - (light.radius / dist).powi(2)).max(0.0).sqrt();
    let side = samples.isqrt().max(1);
    let (mut seen, mut cast) = (0u32, 0u32);
    for j in 0..side {
        for i in 0..side {
            let h = pixel_hash(seed, j * side + i);
            let s1 = (j as f32 + hash_unit(h)) / side as f32;
            let s2 = (i as f32 + hash_unit(h.rotate_left(12))) / side as f32;
            let cos = 1.0 - s1 * (1.0 - cos_max);
            let sin = (1.0 - cos * cos).max(0.0).sqrt();
            let (sp, cp) = (s2 * std::f32::consts::TAU).sin_cos();
            let dir = w * cos + (u * cp + v * sp) * sin;
            if n.dot(dir) <= 0.0 {
                continue;
            }
            // Up to the sphere's near surface: the ray's closest approach to the centre, back by the chord.
            let along = to_centre.dot(dir);
            let miss2 = (to_centre.length_squared() - along * along).max(0.0);
            let tmax = along - (light.radius * light.radius - miss2).max(0.0).sqrt();
            cast += 1;
            if !bvh.occluded_after(walker, origin, dir, tmax) {
                seen += 1;
            }
        }
    }
    (seen as f32 / (side * side) as f32, cast)
}

impl ShadowTechnique<CpuBackend> for AreaLightReference {
    type State = RayState;

    fn name(&self) -> &'static str {
        Self::NAME
    }

    fn create_state(&self, _: &mut CpuContext) -> Result<RayState, CpuError> {
        Ok(RayState::default())
    }

    fn build(&self, cx: &mut CpuContext, state: &mut RayState, pass: LightPass<'_>) -> Result<(), CpuError> {
        let LightPass { frame, light, .. } = pass;
        if light.light.position().is_none() {
            return Err(TechniqueError::unsupported_light(self.name(), &light.light).into());
        }
        state.build(cx, frame);
        Ok(())
    }

    fn query(
        &self,
        _: &mut CpuContext,
        state: &mut RayState,
        pass: LightPass<'_>,
        g: &GBuffer,
        out: &mut Image<f32>,
    ) -> Result<(), CpuError> {
        let LightPass { frame, light, stats, reach, .. } = pass;
        let bvh = state.bvh(self.name())?;
        let Some(centre) = light.light.position() else {
            return Err(TechniqueError::NotBuilt(self.name().into()).into());
        };
        let sphere = Sphere { centre, radius: light.light.radius };
        let origins = RayOrigins::new(g, frame, self.epsilon);
        let rays = per_receiver_casting(g, &reach, out, |walker, x, y, i| {
            let (origin, n) = origins.at(i);
            let (visible, cast) = sphere_visibility(bvh, walker, origin, n, sphere, self.samples, pixel_hash(x, y));
            (visible, u64::from(cast))
        });
        stats.counters.extra.insert("rays_cast".into(), rays as f64);
        Ok(())
    }
}

/// The registry entry: the soft techniques' reference, on the CPU.
#[must_use]
pub fn entry() -> Entry {
    Entry::on_cpu::<AreaLightReference>(
        AreaLightReference::NAME,
        "soft shadows of a spherical light: stratified Monte Carlo shadow rays per pixel through a BVH",
        "reference (shadow-soft)",
    )
    .reference()
    .soft()
}

#[cfg(test)]
mod tests {
    use shadow_core::FrameInputs;
    use shadow_core::glam::{Mat4, Vec3};
    use shadow_core::procedural;
    use shadow_core::scene::{Camera, Light, Material, Scene};

    use super::*;

    /// A BVH over one square occluder, 4 wide, at height 1 with its near edge at `x0` (the square covers
    /// x in x0..x0 + 4, z in -2..2).
    fn occluder_from(x0: f32) -> SceneBvh {
        let mut scene = Scene::new();
        let mesh = scene.add_mesh(procedural::plane(4.0, 4.0).expect("shape"));
        let material = scene.add_material(Material::colored("grey", Vec3::splat(0.5)));
        scene.add_instance("occluder", mesh, material, Mat4::from_translation(Vec3::new(x0 + 2.0, 1.0, 0.0))).unwrap();
        let camera = scene.add_camera(Camera::look_at(Vec3::new(0.0, 5.0, 5.0), Vec3::ZERO, 45.0));
        scene.add_light(Light::point(Vec3::new(0.0, 2.0, 0.0)));
        SceneBvh::build(&FrameInputs::from_scene(&scene, camera).unwrap())
    }

    const LIGHT: Sphere = Sphere { centre: Vec3::new(0.0, 2.0, 0.0), radius: 0.5 };

    #[test]
    fn visibility_is_the_unblocked_fraction_of_the_sphere() {
        let up = Vec3::Y;
        let fraction = |bvh: &SceneBvh, origin: Vec3, n: Vec3, light: Sphere, samples: u32| {
            sphere_visibility(bvh, &mut Walker::default(), origin, n, light, samples, 7).0
        };
        // Far off to the side: nothing in the way, and every sample cast.
        let clear = occluder_from(50.0);
        assert_eq!(sphere_visibility(&clear, &mut Walker::default(), Vec3::ZERO, up, LIGHT, 256, 7), (1.0, 256));
        // Under the middle of the square: every ray blocked.
        let covered = occluder_from(-2.0);
        assert_eq!(sphere_visibility(&covered, &mut Walker::default(), Vec3::ZERO, up, LIGHT, 256, 7), (0.0, 256));
        // The square's edge right over the receiver, under the light's centre: half the cone, by symmetry
        // (stratified, so within a stratum row's worth).
        let half = occluder_from(0.0);
        let v = fraction(&half, Vec3::ZERO, up, LIGHT, 256);
        assert!((v - 0.5).abs() < 0.04, "half-covered: {v}");
        // A receiver whose horizon passes through the light's centre sees the upper half of it, and casts
        // rays only there.
        let (v, cast) =
            sphere_visibility(&clear, &mut Walker::default(), Vec3::new(0.0, 2.0, 3.0), Vec3::Y, LIGHT, 256, 7);
        assert!((v - 0.5).abs() < 0.04, "half below the horizon: {v}");
        assert_eq!(cast as f32, v * 256.0, "rays cast over the horizon");
        // A point light is all or nothing, and the receiver inside the sphere sees it all without a ray.
        let point = Sphere { radius: 0.0, ..LIGHT };
        assert_eq!(fraction(&half, Vec3::new(-0.01, 0.0, 0.0), up, point, 16), 1.0);
        assert_eq!(fraction(&half, Vec3::new(0.01, 0.0, 0.0), up, point, 16), 0.0);
        assert_eq!(
            sphere_visibility(&covered, &mut Walker::default(), Vec3::new(0.0, 1.9, 0.0), up, LIGHT, 16, 7),
            (1.0, 0)
        );
    }

    #[test]
    fn the_penumbra_widens_with_the_radius() {
        // Receivers along x under the square's edge: lit on the left, shadowed on the right, a ramp
        // between whose width grows with the light's radius (Chan Fig. 4-5: the ratio b / r).
        let half = occluder_from(0.0);
        let width = |radius: f32| {
            let light = Sphere { radius, ..LIGHT };
            let xs: Vec<f32> = (0..200).map(|i| -1.0 + i as f32 * 0.01).collect();
            let v: Vec<f32> = xs
                .iter()
                .map(|&x| {
                    sphere_visibility(&half, &mut Walker::default(), Vec3::new(x, 0.0, 0.0), Vec3::Y, light, 256, 3).0
                })
                .collect();
            let first = |t: f32| xs[v.iter().position(|&v| v < t).unwrap()];
            first(0.1) - first(0.9)
        };
        let (narrow, wide) = (width(0.2), width(0.6));
        // Similar triangles, the blocker halfway: the whole penumbra is 2 * radius wide at the receiver.
        assert!(narrow > 0.2 && narrow < 0.5, "radius 0.2: {narrow}");
        assert!(wide > 2.5 * narrow, "radius 0.6: {wide} against {narrow}");
    }

    #[test]
    fn samples_must_be_a_square_number() {
        use shadow_core::technique::TechniqueSettings;
        let parse = |s: &str| AreaLightReference::parse("area-light-reference", &[("samples".into(), s.into())]);
        assert_eq!(parse("64").unwrap().samples, 64);
        let e = parse("200").unwrap_err().to_string();
        assert!(e.contains("samples") && e.contains("square"), "{e}");
        assert!(parse("0").is_err() && parse("9000").is_err());
    }
}
