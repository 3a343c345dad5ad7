//! Ray casting for the exact reference: a compressed wide BVH (obvhs' CWBVH, built with PLOC) over every
//! casting triangle in world space, traversed for any hit.

use std::hash::{Hash, Hasher};
use std::time::Duration;

use glam::{Vec3, Vec3A};
use obvhs::BvhBuildParams;
use obvhs::cwbvh::CwBvh;
use obvhs::cwbvh::builder::build_cwbvh_from_tris;
use obvhs::ray::Ray;
use obvhs::triangle::Triangle;
use rayon::prelude::*;
use shadow_core::FrameInputs;

/// The casters of a frame, ready for shadow rays.
pub struct SceneBvh {
    bvh: Option<CwBvh>,
    /// Triangles in the BVH's primitive order, so leaves read them sequentially.
    tris: Vec<Triangle>,
}

impl SceneBvh {
    /// A key that changes when any caster's mesh or transform does.
    #[must_use]
    pub fn key(frame: &FrameInputs) -> u64 {
        let mut h = std::collections::hash_map::DefaultHasher::new();
        for inst in frame.instances.iter().filter(|i| i.casts_shadow) {
            inst.mesh_version.hash(&mut h);
            for v in inst.world_from_local.to_cols_array() {
                v.to_bits().hash(&mut h);
            }
        }
        h.finish()
    }

    /// Builds the BVH of every casting triangle in world space.
    #[must_use]
    pub fn build(frame: &FrameInputs) -> Self {
        let tris: Vec<Triangle> = frame
            .instances
            .par_iter()
            .filter(|i| i.casts_shadow)
            .flat_map_iter(|inst| {
                let m = inst.world_from_local;
                let world: Vec<Vec3A> =
                    inst.mesh.positions().iter().map(|&p| Vec3A::from(m.transform_point3(p))).collect();
                inst.mesh
                    .triangles()
                    .iter()
                    .map(move |t| Triangle {
                        v0: world[t[0] as usize],
                        v1: world[t[1] as usize],
                        v2: world[t[2] as usize],
                    })
                    .collect::<Vec<_>>()
            })
            .collect();
        if tris.is_empty() {
            return Self { bvh: None, tris };
        }
        let bvh = build_cwbvh_from_tris(&tris, BvhBuildParams::medium_build(), &mut Duration::default());
        let ordered = bvh.primitive_indices.iter().map(|&i| tris[i as usize]).collect();
        Self { bvh: Some(bvh), tris: ordered }
    }

    /// Number of triangles.
    #[must_use]
    pub fn triangle_count(&self) -> usize {
        self.tris.len()
    }

    /// True when some triangle blocks the segment from `origin` along unit `dir` for `tmax`.
    #[must_use]
    pub fn occluded(&self, origin: Vec3, dir: Vec3, tmax: f32) -> bool {
        let Some(bvh) = &self.bvh else { return false };
        // obvhs picks the traversal octant from the sign bits, so a -0.0 component sends the ray down the
        // wrong children and it misses boxes it passes straight through: fold it into +0.0.
        let dir = dir.map(|c| if c == 0.0 { 0.0 } else { c });
        let ray = Ray::new(origin.into(), dir.into(), 0.0, tmax);
        !bvh.ray_traverse_miss(ray, |r, id| self.tris[id].intersect(r))
    }
}

#[cfg(test)]
mod tests {
    use glam::Vec3;
    use shadow_core::scenes::{self, LightType, SceneParams};

    use super::*;

    #[test]
    fn negative_zero_directions_still_hit() {
        let scene = scenes::build("room", &SceneParams { light: Some(LightType::Directional), seed: 1 }).unwrap();
        let cam = scene.cameras().next().unwrap().0;
        let frame = FrameInputs::from_scene(&scene, cam).unwrap();
        let bvh = SceneBvh::build(&frame);
        // Straight up through the beam hung at y 2.375..2.625 over x -0.7..0.7, z 0.8..1.7.
        for (origin, dir) in [
            (Vec3::new(0.0, 0.01, 1.25), Vec3::new(-0.0, 1.0, -0.0)),
            (Vec3::new(0.0, 0.01, 1.25), Vec3::new(0.0, 1.0, 0.0)),
            (Vec3::new(0.0, 0.01, 0.6), Vec3::new(-0.0, 0.96, 0.28).normalize()),
        ] {
            assert!(bvh.occluded(origin, dir, f32::INFINITY), "{origin} {dir}");
        }
    }

    /// Every shadow ray of a frame gets the answer that testing every triangle gives: the traversal never
    /// passes by a box that holds a hit, nor reports one that no triangle has.
    #[test]
    fn every_shadow_ray_is_answered_as_all_triangles_answer_it() {
        let scene = scenes::build("cubes", &SceneParams::default()).unwrap();
        let frame = FrameInputs::from_first_camera(&scene).unwrap();
        let bvh = SceneBvh::build(&frame);
        let g = crate::gbuffer::render(&frame, 48, 36).unwrap();
        // The offset `ray-traced` uses by default (shadow-hard's `epsilon`).
        let origins = crate::passes::rays::RayOrigins::new(&g, &frame, 5e-7);
        let light = &frame.lights[0].kind;
        let (mut cast, mut blocked) = (0, 0);
        for i in (0..g.receiver.data().len()).filter(|&i| g.receiver.data()[i]) {
            let (origin, n) = origins.at(i);
            let (dir, tmax) = crate::passes::rays::towards(light, origin);
            if n.dot(dir) <= 0.0 {
                continue;
            }
            let ray = Ray::new(origin.into(), dir.map(|c| if c == 0.0 { 0.0 } else { c }).into(), 0.0, tmax);
            let any = bvh.tris.iter().any(|t| t.intersect(&ray) < tmax);
            assert_eq!(bvh.occluded(origin, dir, tmax), any, "pixel {i}: {origin} towards {dir}");
            cast += 1;
            blocked += usize::from(any);
        }
        assert!(blocked > 0 && blocked < cast, "{blocked} of {cast} rays blocked: both answers are checked");
    }
}
