//! Ray casting for the exact reference: an eight-wide BVH over every casting triangle in world space,
//! built by the surface area heuristic on every core ([`build`]) and traversed for any hit, eight boxes
//! or eight triangles per step ([`wide`]).

mod build;
mod wide;

use std::hash::{Hash, Hasher};

use glam::{Vec3, Vec3A};
use rayon::prelude::*;
use shadow_core::FrameInputs;

use self::build::STACK;
use self::wide::{Child, LEAF, NONE, Node8, Ray, Tri8};

/// The casters of a frame, ready for shadow rays.
pub struct SceneBvh {
    /// The eight-wide nodes, the root first; empty when nothing casts.
    nodes: Vec<Node8>,
    /// The leaves, in the order a depth-first walk meets them.
    leaves: Vec<Tri8>,
    triangles: usize,
    /// Whether this CPU runs AVX2 (and the bit scans the walk uses).
    #[cfg_attr(not(target_arch = "x86_64"), allow(dead_code))]
    avx2: bool,
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
        let tris = casting_triangles(frame);
        if tris.is_empty() {
            return Self { nodes: Vec::new(), leaves: Vec::new(), triangles: 0, avx2: false };
        }
        let (nodes, leaves) = build::build(&tris);
        Self { nodes, leaves, triangles: tris.len(), avx2: avx2() }
    }

    /// Number of triangles.
    #[must_use]
    pub fn triangle_count(&self) -> usize {
        self.triangles
    }

    /// True when some triangle blocks the segment from `origin` along unit `dir` for `tmax`.
    #[must_use]
    pub fn occluded(&self, origin: Vec3, dir: Vec3, tmax: f32) -> bool {
        self.occluded_after(&mut Walker::default(), origin, dir, tmax)
    }

    /// [`Self::occluded`], trying first the leaf that blocked the last blocked ray `walker` saw, and
    /// remembering the leaf that blocks this one. The answer is the same; only the work differs.
    ///
    /// Shadow rays of neighbouring pixels towards one light run side by side, so a ray is often blocked
    /// by the very triangles that blocked the one before it: then one leaf test answers it, where the
    /// walk from the root opens a node on every level. A ray the leaf does not block costs one leaf test
    /// more (the walk passes that leaf by).
    #[must_use]
    pub fn occluded_after(&self, walker: &mut Walker, origin: Vec3, dir: Vec3, tmax: f32) -> bool {
        if self.nodes.is_empty() {
            return false;
        }
        let ray = Ray::new(origin.into(), dir.into(), 0.0, tmax);
        let blocker = 'walk: {
            #[cfg(target_arch = "x86_64")]
            if self.avx2 {
                // SAFETY: `avx2` is set only where `is_x86_feature_detected!` found every feature
                // `walk_avx2` enables (see [`avx2`]).
                #[allow(unsafe_code)]
                break 'walk unsafe { self.walk_avx2(&ray, walker.last, &mut walker.stack) };
            }
            self.walk(&ray, walker.last, &mut walker.stack)
        };
        if blocker.is_some() {
            walker.last = blocker;
        }
        blocker.is_some()
    }

    /// [`Self::walk`] compiled for AVX2: each eight-lane test is one 256-bit operation instead of two
    /// 128-bit ones. The operations and their order are the same, so the answers are too.
    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx2,bmi1,bmi2,lzcnt")]
    fn walk_avx2(&self, ray: &Ray, first: Option<Child>, stack: &mut [Child; STACK]) -> Option<Child> {
        self.walk(ray, first, stack)
    }

    /// The leaf that blocks `ray`, trying leaf `first` before walking the tree (whose walk then passes it
    /// by); `None` when none does. The walk's stack is `stack`.
    #[inline(always)]
    fn walk(&self, ray: &Ray, first: Option<Child>, stack: &mut [Child; STACK]) -> Option<Child> {
        let first = first.unwrap_or(NONE);
        if first != NONE && self.leaves[first as usize].hit(ray) {
            return Some(first);
        }
        let mut top = 0;
        let mut at = 0u32;
        loop {
            if at & LEAF != 0 {
                let leaf = at & !LEAF;
                if leaf != first && self.leaves[leaf as usize].hit(ray) {
                    return Some(leaf);
                }
            } else {
                let node = &self.nodes[at as usize];
                let mut enter = node.enter(ray);
                // The child nearest along the node's axis is pushed last, so it is opened first: a
                // blocked ray is most likely blocked by what it meets first.
                if ray.dir[node.axis as usize] < 0.0 {
                    while enter != 0 {
                        stack[top] = node.child[enter.trailing_zeros() as usize];
                        top += 1;
                        enter &= enter - 1;
                    }
                } else {
                    while enter != 0 {
                        let k = 31 - enter.leading_zeros() as usize;
                        stack[top] = node.child[k];
                        top += 1;
                        enter &= !(1 << k);
                    }
                }
            }
            if top == 0 {
                return None;
            }
            top -= 1;
            at = stack[top];
        }
    }
}

/// What a run of shadow rays carries from ray to ray ([`SceneBvh::occluded_after`]), one per thread, in
/// the order of their pixels: the leaf that blocked the last blocked ray, and the room the walks keep
/// their stack in. A stack of its own would be cleared at every walk, and clearing its 2 KiB cost a
/// sixth of a shadow ray's time.
#[derive(Clone, Debug)]
pub struct Walker {
    last: Option<Child>,
    stack: [Child; STACK],
}

impl Default for Walker {
    fn default() -> Self {
        Self { last: None, stack: [0; STACK] }
    }
}

/// Whether this CPU runs AVX2 and the bit scans the walk uses.
fn avx2() -> bool {
    #[cfg(target_arch = "x86_64")]
    {
        is_x86_feature_detected!("avx2")
            && is_x86_feature_detected!("bmi1")
            && is_x86_feature_detected!("bmi2")
            && is_x86_feature_detected!("lzcnt")
    }
    #[cfg(not(target_arch = "x86_64"))]
    false
}

/// Every casting triangle of the frame, in world space.
fn casting_triangles(frame: &FrameInputs) -> Vec<[Vec3A; 3]> {
    // Instance by instance, each one's vertices and triangles split among the threads: a scene is
    // often one large mesh and a few small ones.
    let mut tris = Vec::new();
    for inst in frame.instances.iter().filter(|i| i.casts_shadow) {
        let m = inst.world_from_local;
        let world: Vec<Vec3A> =
            inst.mesh.positions().par_iter().with_min_len(4096).map(|&p| m.transform_point3(p).into()).collect();
        tris.par_extend(inst.mesh.triangles().par_iter().with_min_len(4096).map(|t| t.map(|v| world[v as usize])));
    }
    tris
}

#[cfg(test)]
mod tests {
    use glam::Vec3;
    use shadow_core::scenes::{self, LightType, SceneParams};

    use obvhs::ray::Ray;
    use obvhs::triangle::Triangle;

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
    /// passes by a box that holds a hit, nor reports one that no triangle has, whether or not it starts
    /// from the leaf that blocked the ray before.
    #[test]
    fn every_shadow_ray_is_answered_as_all_triangles_answer_it() {
        let scene = scenes::build("cubes", &SceneParams::default()).unwrap();
        let frame = FrameInputs::from_first_camera(&scene).unwrap();
        let bvh = SceneBvh::build(&frame);
        // The same tree walked without AVX2, as CPUs without it walk it.
        let portable = SceneBvh { avx2: false, ..SceneBvh::build(&frame) };
        let tris = casting_triangles(&frame);
        let g = crate::gbuffer::render(&frame, 48, 36).unwrap();
        // The offset `ray-traced` uses by default (shadow-hard's `epsilon`).
        let origins = crate::passes::rays::RayOrigins::new(&g, &frame, 5e-7);
        let light = &frame.lights[0].kind;
        let (mut cast, mut blocked) = (0, 0);
        let (mut walker, mut walker_portable) = (Walker::default(), Walker::default());
        for i in (0..g.receiver.data().len()).filter(|&i| g.receiver.data()[i]) {
            let (origin, n) = origins.at(i);
            let (dir, tmax) = crate::passes::rays::towards(light, origin);
            if n.dot(dir) <= 0.0 {
                continue;
            }
            let ray = Ray::new(origin.into(), dir.map(|c| if c == 0.0 { 0.0 } else { c }).into(), 0.0, tmax);
            let any = tris.iter().any(|&[v0, v1, v2]| Triangle { v0, v1, v2 }.intersect(&ray) < tmax);
            assert_eq!(bvh.occluded(origin, dir, tmax), any, "pixel {i}: {origin} towards {dir}");
            assert_eq!(portable.occluded(origin, dir, tmax), any, "pixel {i} without AVX2");
            // Trying first the leaf that blocked the last blocked ray changes no answer.
            assert_eq!(bvh.occluded_after(&mut walker, origin, dir, tmax), any, "pixel {i} after the last blocker");
            assert_eq!(
                portable.occluded_after(&mut walker_portable, origin, dir, tmax),
                any,
                "pixel {i} after, portable"
            );
            cast += 1;
            blocked += usize::from(any);
        }
        assert!(blocked > 0 && blocked < cast, "{blocked} of {cast} rays blocked: both answers are checked");
    }

    /// A tree over triangles whose centres coincide (no binned cut separates them: the builder halves
    /// them at the median), among a cloud of scattered ones and a degenerate one, answers every ray as
    /// testing every triangle does.
    #[test]
    fn triangles_sharing_a_centre_are_all_found() {
        let mut rng = scenes::Rng::new(7);
        let mut rand = move || rng.unit();
        let mut tris = Vec::new();
        // Eighty triangles through the origin, turned about the z axis and growing: each spans -p..p,
        // its third corner inside that box, so every box is symmetric about the origin and every
        // centre is the origin.
        for k in 0..80 {
            let (s, c) = (k as f32 * 0.078).sin_cos();
            let p = Vec3A::new(c, s, 0.1) * (0.2 + 0.02 * k as f32);
            tris.push([p, -p, p * Vec3A::new(0.3, -0.6, 0.5)]);
        }
        for _ in 0..300 {
            let centre = Vec3A::new(rand() * 4.0 - 2.0, rand() * 4.0 - 2.0, rand() * 4.0 - 2.0);
            let corner = |rand: &mut dyn FnMut() -> f32| centre + Vec3A::new(rand(), rand(), rand()) * 0.3;
            tris.push([corner(&mut rand), corner(&mut rand), corner(&mut rand)]);
        }
        tris.push([Vec3A::ONE; 3]);
        let (nodes, leaves) = build::build(&tris);
        let bvh = SceneBvh { nodes, leaves, triangles: tris.len(), avx2: avx2() };
        let (mut cast, mut blocked) = (0, 0);
        for _ in 0..8000 {
            let origin = Vec3::new(rand() * 6.0 - 3.0, rand() * 6.0 - 3.0, rand() * 6.0 - 3.0);
            // Aimed at a point of a triangle (most often one through the origin), and stopping short
            // of it a third of the time.
            let [a, b, c] = tris[if cast % 4 == 0 { 80 + (rand() * 300.0) as usize } else { (rand() * 79.9) as usize }];
            let (u, v) = (rand(), rand());
            let (u, v) = if u + v > 1.0 { (1.0 - u, 1.0 - v) } else { (u, v) };
            let target = Vec3::from(a + (b - a) * u + (c - a) * v);
            let dir = (target - origin).normalize();
            let tmax = (target - origin).length() * 1.5 * rand();
            let ray = Ray::new(origin.into(), dir.into(), 0.0, tmax);
            let any = tris.iter().any(|&[v0, v1, v2]| Triangle { v0, v1, v2 }.intersect(&ray) < tmax);
            assert_eq!(bvh.occluded(origin, dir, tmax), any, "{origin} towards {dir}, to {tmax}");
            cast += 1;
            blocked += usize::from(any);
        }
        assert!(
            blocked > cast / 4 && blocked < cast * 3 / 4,
            "{blocked} of {cast} rays blocked: both answers are checked"
        );
    }

    /// The build splits its work among the threads it has, and yet writes the same tree on any number
    /// of them: node for node, leaf for leaf, in the same places.
    #[test]
    fn the_tree_is_the_same_on_any_number_of_threads() {
        let scene = scenes::build("tree", &SceneParams::default()).expect("tree");
        let frame = FrameInputs::from_first_camera(&scene).expect("frame");
        let tris = casting_triangles(&frame);
        let on = |threads| {
            let pool = rayon::ThreadPoolBuilder::new().num_threads(threads).build().expect("a pool");
            pool.install(|| build::build(&tris))
        };
        let (one, three) = (on(1), on(3));
        assert!(one.0.len() > 1000, "{} nodes: the build has pieces to share out", one.0.len());
        assert!(one.0 == three.0, "the nodes differ");
        assert!(one.1 == three.1, "the leaves differ");
    }
}
