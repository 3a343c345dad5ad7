//! Ray casting for the exact reference: an eight-wide BVH over every casting triangle in world space,
//! built by the surface area heuristic on every core (`build`) and traversed for any hit, eight boxes
//! or eight triangles per step (`wide`). A hit on an alpha-tested triangle counts only where its texel
//! passes ([`cutout`]); the walk goes on past a clear one.

mod build;
pub mod cutout;
mod instanced;
mod wide;

use std::hash::Hash;

use glam::{Vec3, Vec3A};
use rayon::prelude::*;
use shadow_core::{FrameInputs, Instance};

use self::build::STACK;
use self::cutout::{Cutouts, Table};
use self::instanced::{Instanced, Visit, walk_tree};
use self::wide::{Child, NONE, Node8, Ray, Tri8};
use shadow_core::frame::Coverage;

use crate::runs;

/// The casters of a frame, ready for shadow rays.
pub struct SceneBvh {
    /// The eight-wide nodes, the root first; empty when nothing casts.
    nodes: Vec<Node8>,
    /// The leaves, in the order a depth-first walk meets them.
    leaves: Vec<Tri8>,
    /// The leaves' alpha-tested triangles, where the frame casts any.
    cutouts: Option<Cutouts>,
    triangles: usize,
    /// The casters whose mesh another caster shares, each mesh kept once, where there are any.
    instanced: Option<Instanced>,
    /// Whether this CPU runs AVX2 (and the bit scans the walk uses).
    #[cfg_attr(not(target_arch = "x86_64"), allow(dead_code))]
    avx2: bool,
}

impl SceneBvh {
    /// A key that changes when any caster's mesh, transform or alpha test does.
    #[must_use]
    pub fn key(frame: &FrameInputs) -> u64 {
        shadow_core::hash::digest(0, &frame.instances, |_, inst, h| {
            if inst.casts_shadow {
                inst.mesh_version.hash(h);
                for v in inst.world_from_local.to_cols_array() {
                    v.to_bits().hash(h);
                }
                cutout::hash_alpha_test(inst, h);
            }
        })
    }

    /// Builds the BVH of every casting triangle: a mesh cast by more than one instance (and cut out by
    /// no texture) once in its own space under a tree of its instances, every other triangle in world
    /// space. Either way a ray gets the same answer (see `instanced`).
    #[must_use]
    pub fn build(frame: &FrameInputs) -> Self {
        let casters = casters(frame);
        let kept = instanced::kept(&casters.iter().map(|c| c.keepable_mesh).collect::<Vec<_>>());
        let (shared, flat): (Vec<_>, Vec<_>) = casters.into_iter().zip(kept).partition(|(_, k)| *k);
        let shared: Vec<&Instance> = shared.into_iter().map(|(c, _)| c.inst).collect();
        let flat: Vec<Caster> = flat.into_iter().map(|(c, _)| c).collect();
        let instanced = (!shared.is_empty()).then(|| Instanced::build(&shared));
        let Casters { tris, cutout, table } = casting_triangles(&flat);
        let (nodes, leaves, cutouts) = if tris.is_empty() {
            (Vec::new(), Vec::new(), None)
        } else {
            let (nodes, leaves, members) = build::build(&tris);
            (nodes, leaves, (!table.is_empty()).then(|| Cutouts::new(&members, &cutout, table)))
        };
        let triangles = tris.len() + instanced.as_ref().map_or(0, Instanced::triangle_count);
        Self { nodes, leaves, cutouts, triangles, instanced, avx2: avx2() }
    }

    /// Number of triangles (those of masked casters with no texture to read and an alpha below the
    /// cutoff left out: they are nowhere), counting each instance's.
    #[must_use]
    pub fn triangle_count(&self) -> usize {
        self.triangles
    }

    /// How many meshes are kept once for the instances that share them, and how many instances.
    #[must_use]
    pub fn instanced(&self) -> (usize, usize) {
        self.instanced.as_ref().map_or((0, 0), Instanced::counts)
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
        if self.nodes.is_empty() && self.instanced.is_none() {
            return false;
        }
        let ray = Ray::new(origin.into(), dir.into(), 0.0, tmax);
        #[cfg(target_arch = "x86_64")]
        if self.avx2 {
            // SAFETY: `avx2` is set only where `is_x86_feature_detected!` found every feature
            // `trace_avx2` enables (see [`avx2`]).
            #[allow(unsafe_code)]
            return unsafe {
                if self.cutouts.is_some() {
                    self.trace_avx2::<true>(&ray, walker)
                } else {
                    self.trace_avx2::<false>(&ray, walker)
                }
            };
        }
        if self.cutouts.is_some() {
            self.trace::<true, false>(&ray, walker)
        } else {
            self.trace::<false, false>(&ray, walker)
        }
    }

    /// [`Self::trace`] compiled for AVX2: each eight-lane test is one 256-bit operation instead of two
    /// 128-bit ones. The operations and their order are the same, so the answers are too.
    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx2,bmi1,bmi2,lzcnt")]
    fn trace_avx2<const CUTOUTS: bool>(&self, ray: &Ray, walker: &mut Walker) -> bool {
        self.trace::<CUTOUTS, true>(ray, walker)
    }

    /// Whether something blocks `ray`: the world tree, then the instances, each first trying the leaf
    /// that blocked the last ray `walker` saw blocked there, which it then remembers. `AVX2` says the
    /// walk runs where [`avx2`] found the features, so the instances are walked with them too.
    #[inline(always)]
    fn trace<const CUTOUTS: bool, const AVX2: bool>(&self, ray: &Ray, walker: &mut Walker) -> bool {
        if let (Some(instanced), Some(last)) = (&self.instanced, walker.last_instance)
            && instanced.blocks(last, ray)
        {
            return true;
        }
        if !self.nodes.is_empty()
            && let Some(leaf) = self.walk::<CUTOUTS>(ray, walker.last, &mut walker.stack)
        {
            walker.last = Some(leaf);
            return true;
        }
        let Some(instanced) = &self.instanced else { return false };
        let stacks = (&mut walker.stack, &mut walker.inner);
        #[cfg(target_arch = "x86_64")]
        let hit = if AVX2 {
            // SAFETY: `AVX2` is set only by `trace_avx2`, which runs only where `avx2` found every
            // feature `walk_avx2` enables.
            #[allow(unsafe_code)]
            unsafe {
                instanced.walk_avx2(ray, stacks)
            }
        } else {
            instanced.walk(ray, stacks)
        };
        #[cfg(not(target_arch = "x86_64"))]
        let hit = instanced.walk(ray, stacks);
        if let Some(hit) = hit {
            walker.last_instance = Some(hit);
            return true;
        }
        false
    }

    /// The leaf that blocks `ray`, trying leaf `first` before walking the tree (whose walk then passes it
    /// by); `None` when none does. The walk's stack is `stack`. `CUTOUTS` says whether the tree has
    /// alpha-tested triangles: a tree without walks as if the alpha test did not exist.
    #[inline(always)]
    fn walk<const CUTOUTS: bool>(&self, ray: &Ray, first: Option<Child>, stack: &mut [Child; STACK]) -> Option<Child> {
        let first = first.unwrap_or(NONE);
        if first != NONE && self.blocks::<CUTOUTS>(first, ray) {
            return Some(first);
        }
        walk_tree(&self.nodes, ray, stack, &mut WorldLeaves::<CUTOUTS> { bvh: self, ray, first })
    }

    /// Whether leaf `leaf` blocks `ray`: one of its triangles meets it, and where that one is
    /// alpha-tested, its texel there passes.
    #[inline(always)]
    fn blocks<const CUTOUTS: bool>(&self, leaf: Child, ray: &Ray) -> bool {
        let tris = &self.leaves[leaf as usize];
        match &self.cutouts {
            Some(cutouts) if CUTOUTS => cutouts.blocks(leaf as usize, || tris.hit(ray), || tris.hits(ray)),
            _ => tris.hit(ray),
        }
    }
}

/// The leaves of the world tree, but for `first`, which the walk has tried already.
struct WorldLeaves<'a, const CUTOUTS: bool> {
    bvh: &'a SceneBvh,
    ray: &'a Ray,
    first: Child,
}

impl<const CUTOUTS: bool> Visit for WorldLeaves<'_, CUTOUTS> {
    #[inline(always)]
    fn enter(&self, node: &Node8) -> u32 {
        node.enter(self.ray)
    }

    #[inline(always)]
    fn blocks(&mut self, leaf: Child) -> bool {
        leaf != self.first && self.bvh.blocks::<CUTOUTS>(leaf, self.ray)
    }
}

/// What a run of shadow rays carries from ray to ray ([`SceneBvh::occluded_after`]), one per thread, in
/// the order of their pixels: the leaf that blocked the last blocked ray (in the world tree and among
/// the instances), and the room the walks keep their stacks in. A stack of its own would be cleared at
/// every walk, and clearing its 2 KiB cost a sixth of a shadow ray's time.
#[derive(Clone, Debug)]
pub struct Walker {
    last: Option<Child>,
    /// An instance and a leaf of its mesh's tree.
    last_instance: Option<(u32, Child)>,
    stack: [Child; STACK],
    /// The stack of the walk through one instance's mesh, inside the walk through the instances.
    inner: [Child; STACK],
}

impl Default for Walker {
    fn default() -> Self {
        Self { last: None, last_instance: None, stack: [0; STACK], inner: [0; STACK] }
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

/// The casting triangles of a frame.
struct Casters {
    /// Each one in world space.
    tris: Vec<[Vec3A; 3]>,
    /// Where the frame casts alpha-tested triangles: each one's index in `table`, `u32::MAX` for a solid
    /// one. Empty when it casts none.
    cutout: Vec<u32>,
    /// The alpha-tested triangles.
    table: Table,
}

/// An instance that can block light, and what the build reads of it, read in one pass: a frame of many
/// small meshes waits on memory for each instance it reads.
#[derive(Clone, Copy)]
struct Caster<'a> {
    inst: &'a Instance,
    /// How much of it blocks light.
    coverage: Coverage,
    /// Its triangles.
    triangles: usize,
    /// Its mesh's address, where it may be kept as an instance of its mesh ([`instanced::keepable`]).
    keepable_mesh: Option<usize>,
}

/// The instances of the frame that can block light.
fn casters(frame: &FrameInputs) -> Vec<Caster<'_>> {
    frame
        .instances
        .par_iter()
        .with_min_len(1024)
        .filter(|i| i.casts_shadow)
        .map(|inst| {
            let coverage = inst.coverage();
            let keepable_mesh =
                instanced::keepable(inst, coverage).then_some(std::sync::Arc::as_ptr(&inst.mesh) as usize);
            Caster { inst, coverage, triangles: inst.mesh.triangles().len(), keepable_mesh }
        })
        .filter(|c| c.coverage != Coverage::Absent)
        .collect()
}

/// About how many triangles a thread carries to world space in one go: small casters a run of them to a
/// thread, a larger one alone, split among the threads by its vertices and triangles.
const JOB: usize = 4096;

/// Casters of at most this many triangles are carried corner by corner; larger ones vertex by vertex,
/// then gathered (the same positions either way, as the transform is the same).
const SMALL_MESH: usize = 64;

/// Every triangle of `casters` in world space, and the alpha-tested ones among them.
fn casting_triangles(casters: &[Caster]) -> Casters {
    let starts = runs::starts(&casters.iter().map(|c| c.triangles).collect::<Vec<_>>());
    let mut tris = vec![[Vec3A::ZERO; 3]; starts[casters.len()]];
    runs::for_each_run(&starts, &mut tris, JOB, |run, out| {
        let mut out = out;
        for Caster { inst, .. } in &casters[run] {
            let (m, positions, triangles) = (inst.world_from_local, inst.mesh.positions(), inst.mesh.triangles());
            let (mine, tail) = std::mem::take(&mut out).split_at_mut(triangles.len());
            if triangles.len() <= SMALL_MESH {
                for (o, t) in mine.iter_mut().zip(triangles) {
                    *o = t.map(|v| m.transform_point3(positions[v as usize]).into());
                }
            } else {
                let world: Vec<Vec3A> =
                    positions.par_iter().with_min_len(JOB).map(|&p| m.transform_point3(p).into()).collect();
                mine.par_iter_mut()
                    .zip(triangles)
                    .with_min_len(JOB)
                    .for_each(|(o, t)| *o = t.map(|v| world[v as usize]));
            }
            out = tail;
        }
    });
    let mut out = Casters { tris, cutout: Vec::new(), table: Table::default() };
    if casters.iter().any(|c| c.coverage == Coverage::Cutout) {
        out.cutout = vec![u32::MAX; out.tris.len()];
        for (&Caster { inst, coverage, .. }, w) in casters.iter().zip(starts.windows(2)) {
            if coverage == Coverage::Cutout {
                let first = out.table.add(inst);
                for (id, c) in (first..).zip(&mut out.cutout[w[0]..w[1]]) {
                    *c = id;
                }
            }
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use glam::{Vec2, Vec3};
    use shadow_core::scenes::{self, LightType, SceneParams};

    use obvhs::ray::Ray;
    use obvhs::triangle::Triangle;

    use super::*;

    /// Asserts that a tree and the same tree walked without AVX2 both answer a ray `expected`, from the
    /// root and after the last blocker each one's walker saw (which must change no answer).
    fn assert_answer(
        (bvh, portable): (&SceneBvh, &SceneBvh),
        walkers: &mut (Walker, Walker),
        (origin, dir, tmax): (Vec3, Vec3, f32),
        expected: bool,
        what: &str,
    ) {
        let ray = format!("{what} {origin} towards {dir}, to {tmax}");
        assert_eq!(bvh.occluded(origin, dir, tmax), expected, "{ray}");
        assert_eq!(portable.occluded(origin, dir, tmax), expected, "{ray}, without AVX2");
        assert_eq!(bvh.occluded_after(&mut walkers.0, origin, dir, tmax), expected, "{ray}, after the last blocker");
        assert_eq!(portable.occluded_after(&mut walkers.1, origin, dir, tmax), expected, "{ray}, after, without AVX2");
    }

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
        let tris = casting_triangles(&casters(&frame)).tris;
        let g = crate::gbuffer::render(&frame, 48, 36).unwrap();
        // The offset `ray-traced` uses by default (shadow-hard's `epsilon`).
        let origins = crate::passes::rays::RayOrigins::new(&g, &frame, 5e-7);
        let light = &frame.lights[0].kind;
        let (mut cast, mut blocked) = (0, 0);
        let mut walkers = (Walker::default(), Walker::default());
        for i in (0..g.receiver.data().len()).filter(|&i| g.receiver.data()[i]) {
            let (origin, n) = origins.at(i);
            let (dir, tmax) = crate::passes::rays::towards(light, origin);
            if n.dot(dir) <= 0.0 {
                continue;
            }
            let ray = Ray::new(origin.into(), dir.map(|c| if c == 0.0 { 0.0 } else { c }).into(), 0.0, tmax);
            let any = tris.iter().any(|&[v0, v1, v2]| Triangle { v0, v1, v2 }.intersect(&ray) < tmax);
            assert_answer((&bvh, &portable), &mut walkers, (origin, dir, tmax), any, &format!("pixel {i}"));
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
        let (nodes, leaves, _) = build::build(&tris);
        let bvh = SceneBvh { nodes, leaves, cutouts: None, triangles: tris.len(), instanced: None, avx2: avx2() };
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

    /// Meshes shared by many instances, turned, scaled unevenly, mirrored and placed far from the origin
    /// (so the rays carried into their space round as much as they can), among a mesh of its own: the
    /// shared meshes are kept once, and every ray gets the answer that testing every triangle in world
    /// space gives, with or without the last blocker tried first, with or without AVX2.
    #[test]
    fn instanced_meshes_are_kept_once_and_answer_as_their_triangles_do() {
        use shadow_core::procedural;
        let mut rng = scenes::Rng::new(17);
        let mut scene = shadow_core::Scene::new();
        let material = scene.add_material(shadow_core::scene::Material::default());
        let shapes = [
            procedural::cuboid(Vec3::new(1.0, 0.5, 0.3)).unwrap(),
            procedural::sphere(0.5, 12, 8).unwrap(),
            procedural::torus(0.6, 0.2, 16, 8).unwrap(),
        ];
        let meshes: Vec<_> = shapes.into_iter().map(|m| scene.add_mesh(m)).collect();
        let far = Vec3::new(3000.0, -20.0, 1500.0);
        for i in 0..300 {
            let axis = Vec3::new(rng.range(-1.0, 1.0), rng.range(-1.0, 1.0), rng.range(0.1, 1.0)).normalize();
            let mut scale = Vec3::new(rng.range(0.3, 2.0), rng.range(0.3, 2.0), rng.range(0.3, 2.0));
            if i % 7 == 0 {
                scale.x = -scale.x;
            }
            let at = far + Vec3::new(rng.range(-8.0, 8.0), rng.range(-8.0, 8.0), rng.range(-8.0, 8.0));
            let transform = glam::Mat4::from_scale_rotation_translation(
                scale,
                glam::Quat::from_axis_angle(axis, rng.range(0.0, 6.0)),
                at,
            );
            scene.add_instance(&format!("prop {i}"), meshes[i % 3], material, transform).unwrap();
        }
        let lone = scene.add_mesh(procedural::cuboid(Vec3::new(4.0, 0.2, 4.0)).unwrap());
        scene.add_instance("lone", lone, material, glam::Mat4::from_translation(far)).unwrap();
        scene.add_camera(shadow_core::scene::Camera::look_at(far + Vec3::new(0.0, 2.0, 30.0), far, 45.0));
        let frame = FrameInputs::from_first_camera(&scene).unwrap();
        let bvh = SceneBvh::build(&frame);
        assert_eq!(bvh.instanced(), (3, 300), "three meshes kept once for their 300 instances");
        let portable = SceneBvh { avx2: false, ..SceneBvh::build(&frame) };
        let tris = casting_triangles(&casters(&frame)).tris;
        assert_eq!(bvh.triangle_count(), tris.len());
        let mut walkers = (Walker::default(), Walker::default());
        let (mut cast, mut blocked) = (0, 0);
        for _ in 0..20_000 {
            // From near the props or from far off, aimed at a point of a triangle (or just past its
            // edge), stopping short of it a third of the time.
            let spread = if cast % 2 == 0 { 10.0 } else { 400.0 };
            let origin = far + Vec3::new(rng.range(-1.0, 1.0), rng.range(-1.0, 1.0), rng.range(-1.0, 1.0)) * spread;
            let [a, b, c] = tris[(rng.unit() * tris.len() as f32) as usize % tris.len()];
            let (u, v) = (rng.range(-0.01, 1.0), rng.range(-0.01, 1.0));
            let (u, v) = if u + v > 1.0 { (1.0 - u, 1.0 - v) } else { (u, v) };
            let target = Vec3::from(a + (b - a) * u + (c - a) * v);
            let dir = (target - origin).normalize();
            let tmax = (target - origin).length() * 1.5 * rng.unit();
            let ray = Ray::new(origin.into(), dir.map(|c| if c == 0.0 { 0.0 } else { c }).into(), 0.0, tmax);
            let any = tris.iter().any(|&[v0, v1, v2]| Triangle { v0, v1, v2 }.intersect(&ray) < tmax);
            assert_answer((&bvh, &portable), &mut walkers, (origin, dir, tmax), any, "");
            cast += 1;
            blocked += usize::from(any);
        }
        assert!(blocked > cast / 5 && blocked < cast * 4 / 5, "{blocked} of {cast} rays blocked");
    }

    /// Triangles carried into another space lane by lane make the block that carrying each corner with
    /// glam's `transform_point3` and building it with [`Tri8::new`] makes, bit for bit.
    #[test]
    fn triangles_carried_lane_by_lane_are_those_carried_one_by_one() {
        let mut rng = scenes::Rng::new(9);
        let point = |rng: &mut scenes::Rng, size: f32| {
            Vec3::new(rng.range(-size, size), rng.range(-size, size), rng.range(-size, size))
        };
        for _ in 0..200 {
            let m = glam::Mat4::from_scale_rotation_translation(
                point(&mut rng, 3.0),
                glam::Quat::from_axis_angle(point(&mut rng, 1.0).normalize(), rng.range(0.0, 6.0)),
                point(&mut rng, 5000.0),
            );
            let tris: Vec<[Vec3; 3]> = (0..8).map(|_| [(); 3].map(|()| point(&mut rng, 2.0))).collect();
            let local = wide::Corners8::new(|k| tris[k].map(Vec3A::from));
            let one_by_one = Tri8::new(8, |k| tris[k].map(|p| Vec3A::from(m.transform_point3(p))));
            assert!(local.placed(&m) == one_by_one, "{m}");
        }
    }

    /// A lane reports where the ray meets its triangle as `(1 - u - v) v0 + u v1 + v v2`, the weights the
    /// alpha test interpolates texture coordinates with.
    #[test]
    fn a_hit_says_where_it_meets_the_triangle() {
        let corners = [Vec3A::new(0.3, -0.2, 1.0), Vec3A::new(1.4, 0.1, 0.8), Vec3A::new(0.2, 1.3, 1.2)];
        let block = Tri8::new(1, |_| corners);
        let mut rng = scenes::Rng::new(3);
        for _ in 0..200 {
            let (u, v) = (rng.unit(), rng.unit());
            let (u, v) = if u + v > 1.0 { (1.0 - u, 1.0 - v) } else { (u, v) };
            let target = corners[0] * (1.0 - u - v) + corners[1] * u + corners[2] * v;
            let origin = Vec3A::new(rng.range(-1.0, 1.0), rng.range(-1.0, 1.0), -2.0);
            let hits = block.hits(&wide::Ray::new(origin, (target - origin).normalize(), 0.0, 10.0));
            assert_eq!(hits.lanes, 0xff, "every lane holds the one triangle");
            assert!(
                (hits.u[0] - u).abs() < 1e-4 && (hits.v[0] - v).abs() < 1e-4,
                "{u} {v}: {} {}",
                hits.u[0],
                hits.v[0]
            );
        }
    }

    /// Cards of random alpha textures (read through both filters, every wrap and a turned, scaled
    /// coordinate transform) among opaque ones: every ray is blocked exactly when testing every triangle,
    /// each hit's texel included, says so, with or without the last blocker tried first, with or without
    /// AVX2; and a fair share of the rays meet triangles only where their texels are clear.
    #[test]
    fn alpha_tested_rays_are_answered_as_all_triangles_answer_them() {
        let scene = cards(11, 200);
        let frame = FrameInputs::from_first_camera(&scene).unwrap();
        let bvh = SceneBvh::build(&frame);
        let portable = SceneBvh { avx2: false, ..SceneBvh::build(&frame) };
        let Casters { tris, cutout, table } = casting_triangles(&casters(&frame));
        assert!(bvh.cutouts.is_some() && !table.is_empty());
        // Testing every triangle: each one alone in a block, its texel read where it is met.
        let every = |ray: &wide::Ray| {
            let (mut met, mut blocked) = (false, false);
            for (i, &corners) in tris.iter().enumerate() {
                let hits = Tri8::new(1, |_| corners).hits(ray);
                if hits.lanes != 0 {
                    met = true;
                    blocked |= cutout[i] == u32::MAX || table.passes(cutout[i], hits.u[0], hits.v[0]);
                }
            }
            (met, blocked)
        };
        let mut rng = scenes::Rng::new(5);
        let mut walkers = (Walker::default(), Walker::default());
        let (mut cast, mut blocked, mut only_clear) = (0, 0, 0);
        for _ in 0..20_000 {
            let origin = Vec3::new(rng.range(-3.0, 3.0), rng.range(-3.0, 3.0), rng.range(-3.0, 3.0));
            let [a, b, c] = tris[(rng.unit() * tris.len() as f32) as usize % tris.len()];
            let (u, v) = (rng.unit(), rng.unit());
            let (u, v) = if u + v > 1.0 { (1.0 - u, 1.0 - v) } else { (u, v) };
            let target = Vec3::from(a + (b - a) * u + (c - a) * v);
            let dir = (target - origin).normalize();
            let tmax = (target - origin).length() * rng.range(0.6, 1.6);
            let (met, any) = every(&wide::Ray::new(origin.into(), dir.into(), 0.0, tmax));
            assert_answer((&bvh, &portable), &mut walkers, (origin, dir, tmax), any, "");
            cast += 1;
            blocked += usize::from(any);
            only_clear += usize::from(met && !any);
        }
        assert!(blocked > cast / 5 && blocked < cast * 4 / 5, "{blocked} of {cast} rays blocked");
        assert!(only_clear > cast / 20, "{only_clear} of {cast} rays met only clear texels");
    }

    /// A scene of `count` square cards scattered through a 5 m cube, most of them alpha-tested with one of
    /// four random alpha textures, read in turn through each filter and wrap and a coordinate transform.
    fn cards(seed: u64, count: usize) -> shadow_core::Scene {
        use shadow_core::material::{AlphaMode, Filter, Material, Sampler, Texture, TextureRef, UvTransform, Wrap};
        let mut rng = scenes::Rng::new(seed);
        let mut scene = shadow_core::Scene::new();
        let textures: Vec<_> = (0..4)
            .map(|k| {
                let texels = (0..16 * 16).map(|_| [200, 200, 200, (rng.unit() * 255.0) as u8]).collect();
                scene.add_texture(Texture::from_rgba8(&format!("noise {k}"), 16, 16, texels).unwrap())
            })
            .collect();
        let wraps = [Wrap::Repeat, Wrap::MirroredRepeat, Wrap::ClampToEdge];
        let materials: Vec<_> = (0..8)
            .map(|k| {
                let filter = if k % 2 == 0 { Filter::Nearest } else { Filter::Linear };
                let sampler = Sampler {
                    mag: filter,
                    min: filter,
                    mipmap: None,
                    wrap_u: wraps[k % 3],
                    wrap_v: wraps[(k + 1) % 3],
                };
                let transform = if k < 4 {
                    UvTransform::IDENTITY
                } else {
                    UvTransform { offset: Vec2::new(0.3, -0.1), rotation: 0.4, scale: Vec2::new(1.5, 0.8) }
                };
                scene.add_material(Material {
                    base_color_texture: Some(TextureRef { texture: textures[k % 4], sampler, transform }),
                    alpha: if k == 7 { 0.9 } else { 1.0 },
                    alpha_mode: AlphaMode::Mask { cutoff: 0.3 + 0.1 * (k % 4) as f32 },
                    two_sided: true,
                    ..Material::default()
                })
            })
            .collect();
        let opaque = scene.add_material(Material::default());
        for i in 0..count {
            let centre = Vec3::new(rng.range(-2.5, 2.5), rng.range(-2.5, 2.5), rng.range(-2.5, 2.5));
            let random =
                |rng: &mut scenes::Rng| Vec3::new(rng.range(-1.0, 1.0), rng.range(-1.0, 1.0), rng.range(-1.0, 1.0));
            let (e1, e2) = (random(&mut rng) * 0.3, random(&mut rng) * 0.3);
            let positions = vec![centre - e1 - e2, centre + e1 - e2, centre + e1 + e2, centre - e1 + e2];
            let s = rng.range(0.5, 3.0);
            let uvs = vec![Vec2::ZERO, Vec2::new(s, 0.0), Vec2::new(s, s), Vec2::new(0.0, s)];
            let mesh = shadow_core::Mesh::new(positions, vec![[0, 1, 2], [0, 2, 3]]).unwrap().with_uvs(uvs).unwrap();
            let mesh = scene.add_mesh(mesh);
            let material = if i % 5 == 0 { opaque } else { materials[i % 8] };
            scene.add_instance(&format!("card {i}"), mesh, material, glam::Mat4::IDENTITY).unwrap();
        }
        scene.add_camera(shadow_core::scene::Camera::look_at(Vec3::new(0.0, 0.0, 8.0), Vec3::ZERO, 45.0));
        scene
    }

    /// The build splits its work among the threads it has, and yet writes the same tree on any number
    /// of them: node for node, leaf for leaf, in the same places.
    #[test]
    fn the_tree_is_the_same_on_any_number_of_threads() {
        let scene = scenes::build("tree", &SceneParams::default()).expect("tree");
        let frame = FrameInputs::from_first_camera(&scene).expect("frame");
        let tris = casting_triangles(&casters(&frame)).tris;
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
