//! Meshes cast by several instances, kept once: a tree per mesh over its triangles in the mesh's own
//! space, under a tree over the instances' boxes in world space (a two-level BVH).
//!
//! The answers are the flattened tree's to the bit. Boxes only prune: a ray is carried into each
//! instance's mesh space to open that mesh's tree, whose boxes are grown there by more than the
//! carried ray's rounding can stray (see [`Placed::pad`]), so no box that holds a hit is passed by. A
//! leaf's triangles are then carried out to world space as the flattened tree carries them (the same
//! products and sums as its `transform_point3` of the same positions, [`Corners8::placed`]) and tested
//! against the world ray in the same lanes, so each triangle answers exactly what it answers there.

use std::sync::Arc;

use glam::{Mat4, Vec3, Vec3A};
use rayon::prelude::*;
use shadow_core::frame::Coverage;
use shadow_core::hash::WordMap;
use shadow_core::{Instance, Mesh};

use super::build::{self, STACK};
use super::wide::{Child, Corners8, LEAF, NONE, Node8, Ray};

/// Rounding steps the carried ray's error is bounded by, with room to spare: a transform of a point is
/// three products and three sums per coordinate, and normalizing the direction and scaling the
/// interval add a few more (see [`Placed::pad`]).
const PAD_ULPS: f32 = 64.0;

/// One mesh's tree, in its own space.
struct MeshTree {
    nodes: Vec<Node8>,
    /// Each leaf's triangles.
    leaves: Vec<Corners8>,
}

/// An instance of a kept mesh.
struct Placed {
    /// Its mesh's tree in [`Instanced::meshes`].
    mesh: u32,
    world_from_local: Mat4,
    local_from_world: Mat4,
    /// The largest row sum of `local_from_world`'s absolute linear part, and the largest magnitude of
    /// its translation: how much a world coordinate's rounding can grow when carried into mesh space.
    scale: f32,
    shift: f32,
}

impl Placed {
    /// How far the mesh's boxes are grown for a ray from `origin`: more than the error of any point of
    /// the ray carried into mesh space, out to where it could meet a triangle (within `reach` of the
    /// world origin on every axis). The point `o + t d` of a hit is at most `|o| + reach` from the
    /// origin per axis; carrying it costs a few roundings of `scale` times that plus the shift.
    fn pad(&self, origin: Vec3, reach: f32) -> f32 {
        PAD_ULPS * f32::EPSILON * (self.scale * (origin.abs().max_element() + reach) + self.shift)
    }
}

/// The instanced casters of a frame.
pub struct Instanced {
    /// The tree over the instances' world boxes; its leaves are nodes whose children are indices into
    /// `placed`, with their boxes, so a leaf opens only the instances the ray enters.
    top: Vec<Node8>,
    top_leaves: Vec<Node8>,
    placed: Vec<Placed>,
    meshes: Vec<MeshTree>,
    /// The largest magnitude of any coordinate of an instanced triangle in world space.
    reach: f32,
    /// Triangles cast, counting every instance's.
    triangles: usize,
}

/// Whether a caster may be kept as an instance of its mesh: it casts all of it (no texture cuts it
/// out), and its transform can carry a ray into the mesh's space (finite, with a finite inverse).
pub fn keepable(inst: &Instance, coverage: Coverage) -> bool {
    coverage == Coverage::Solid
        && inst.world_from_local.is_finite()
        && inst.local_from_world.is_finite()
        && inst.world_from_local.determinant() != 0.0
}

/// Which casters are kept as instances of their mesh, given the mesh of each [`keepable`] one (by
/// address): those whose mesh another keepable caster holds too (posed meshes, each its own, never
/// are).
pub fn kept(keepable_meshes: &[Option<usize>]) -> Vec<bool> {
    let mut uses: WordMap<usize, u32> = WordMap::with_capacity_and_hasher(keepable_meshes.len(), Default::default());
    for mesh in keepable_meshes.iter().flatten() {
        *uses.entry(*mesh).or_default() += 1;
    }
    keepable_meshes.par_iter().with_min_len(1024).map(|mesh| mesh.is_some_and(|m| uses[&m] > 1)).collect()
}

impl Instanced {
    /// The trees of `instances` (at least one), each mesh's built once.
    pub fn build(instances: &[&Instance]) -> Self {
        let mut index: WordMap<*const Mesh, u32> = WordMap::default();
        let mut unique: Vec<&Arc<Mesh>> = Vec::new();
        let placed_mesh: Vec<u32> = instances
            .iter()
            .map(|inst| {
                *index.entry(Arc::as_ptr(&inst.mesh)).or_insert_with(|| {
                    unique.push(&inst.mesh);
                    unique.len() as u32 - 1
                })
            })
            .collect();
        let meshes: Vec<MeshTree> = unique
            .par_iter()
            .map(|&mesh| {
                let p = mesh.positions();
                let tris: Vec<[Vec3A; 3]> =
                    mesh.triangles().iter().map(|t| t.map(|v| Vec3A::from(p[v as usize]))).collect();
                let (nodes, _, members) = build::build(&tris);
                let leaves = members.iter().map(|m| Corners8::new(|k| tris[m[k] as usize])).collect();
                MeshTree { nodes, leaves }
            })
            .collect();
        // Each instance's box: its vertices carried to world space as the flattened tree carries them,
        // so the box holds every triangle tested there exactly.
        let boxes: Vec<[Vec3A; 3]> = instances
            .par_iter()
            .map(|inst| {
                let m = inst.world_from_local;
                let (lo, hi) =
                    inst.mesh.positions().iter().fold((Vec3A::INFINITY, Vec3A::NEG_INFINITY), |(lo, hi), &p| {
                        let w = Vec3A::from(m.transform_point3(p));
                        (lo.min(w), hi.max(w))
                    });
                // A "triangle" whose box is the instance's, for the builder (it reads only boxes).
                [lo, hi, hi]
            })
            .collect();
        let reach = boxes.iter().map(|[lo, hi, _]| lo.abs().max(hi.abs()).max_element()).fold(0.0, f32::max);
        let (top, _, top_members) = build::build(&boxes);
        let top_leaves = top_members
            .iter()
            .map(|members| {
                let mut node = Node8::EMPTY;
                // A leaf of fewer than eight repeats its last member: its lanes stay empty.
                for (k, &p) in members.iter().enumerate() {
                    if k == 0 || members[k - 1] != p {
                        let [lo, hi, _] = boxes[p as usize];
                        node.set(k, p, lo, hi);
                    }
                }
                node
            })
            .collect();
        let placed = instances
            .iter()
            .zip(placed_mesh)
            .map(|(inst, mesh)| {
                let inv = inst.local_from_world;
                let linear = [inv.x_axis, inv.y_axis, inv.z_axis].map(|c| c.truncate().abs());
                let rows = linear[0] + linear[1] + linear[2];
                Placed {
                    mesh,
                    world_from_local: inst.world_from_local,
                    local_from_world: inv,
                    scale: rows.max_element(),
                    shift: inv.w_axis.truncate().abs().max_element(),
                }
            })
            .collect();
        let triangles = instances.iter().map(|i| i.mesh.triangle_count()).sum();
        Self { top, top_leaves, placed, meshes, reach, triangles }
    }

    /// Triangles cast, counting every instance's.
    pub fn triangle_count(&self) -> usize {
        self.triangles
    }

    /// Meshes kept once, and the instances that cast them.
    pub fn counts(&self) -> (usize, usize) {
        (self.meshes.len(), self.placed.len())
    }

    /// Whether leaf `leaf` of instance `p`'s mesh tree blocks `ray`.
    #[inline(always)]
    pub fn blocks(&self, (p, leaf): (u32, Child), ray: &Ray) -> bool {
        self.leaf_blocks(&self.placed[p as usize], leaf, ray)
    }

    /// The instance and the leaf of its mesh's tree that block `ray`, walking the instances' tree on the
    /// first of `stacks` and each mesh's on the second. A function of its own, not inlined into the
    /// walk of the world tree, which runs faster without it.
    #[inline(never)]
    pub fn walk(&self, ray: &Ray, stacks: (&mut [Child; STACK], &mut [Child; STACK])) -> Option<(u32, Child)> {
        self.walk_inline(ray, stacks)
    }

    /// [`Self::walk`] compiled for AVX2, as `SceneBvh`'s walk is.
    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx2,bmi1,bmi2,lzcnt")]
    #[inline(never)]
    pub fn walk_avx2(&self, ray: &Ray, stacks: (&mut [Child; STACK], &mut [Child; STACK])) -> Option<(u32, Child)> {
        self.walk_inline(ray, stacks)
    }

    #[inline(always)]
    fn walk_inline(&self, ray: &Ray, stacks: (&mut [Child; STACK], &mut [Child; STACK])) -> Option<(u32, Child)> {
        let (top_stack, mesh_stack) = stacks;
        let mut top = TopLeaves { instanced: self, ray, stack: mesh_stack, found: None };
        walk_tree(&self.top, ray, top_stack, &mut top);
        top.found
    }

    /// The leaf of instance `p`'s mesh tree that blocks the world `ray`.
    #[inline(always)]
    fn walk_instance(&self, p: u32, ray: &Ray, stack: &mut [Child; STACK]) -> Option<Child> {
        let placed = &self.placed[p as usize];
        let tree = &self.meshes[placed.mesh as usize];
        let origin = Vec3::from(ray.origin);
        let local_origin = placed.local_from_world.transform_point3(origin);
        let along = placed.local_from_world.transform_vector3(Vec3::from(ray.dir));
        let length = along.length();
        // The interval scaled to the unit direction, widened by a few roundings of the scaling.
        let (lo, hi) = (1.0 - 4.0 * f32::EPSILON, 1.0 + 4.0 * f32::EPSILON);
        let local =
            Ray::new(local_origin.into(), (along / length).into(), ray.tmin * length * lo, ray.tmax * length * hi);
        let pad = placed.pad(origin, self.reach);
        walk_tree(
            &tree.nodes,
            &local,
            stack,
            &mut MeshLeaves { instanced: self, placed, local: &local, world: ray, pad },
        )
    }

    /// Whether leaf `leaf` of `placed`'s mesh tree blocks the world `ray`: its triangles carried to world
    /// space as the flattened tree carries them, tested as it tests them.
    #[inline(always)]
    fn leaf_blocks(&self, placed: &Placed, leaf: Child, ray: &Ray) -> bool {
        let tree = &self.meshes[placed.mesh as usize];
        tree.leaves[leaf as usize].placed(&placed.world_from_local).hit(ray)
    }
}

/// What a walk does at each node and each leaf it meets: the children a node's ray enters, as bits,
/// and whether a leaf blocks it. Methods, not closures, so they are inlined into the walk wherever it is
/// compiled (a closure is a function of its own, built without the AVX2 the walk is built with).
pub trait Visit {
    /// The children of `node` the ray enters.
    fn enter(&self, node: &Node8) -> u32;
    /// Whether leaf `leaf` blocks the ray.
    fn blocks(&mut self, leaf: Child) -> bool;
}

/// The leaves of the instances' tree: each opens the instances whose boxes the ray enters.
struct TopLeaves<'a> {
    instanced: &'a Instanced,
    ray: &'a Ray,
    /// The stack of the walks through the instances' meshes.
    stack: &'a mut [Child; STACK],
    /// The instance and the leaf of its mesh's tree that blocked the ray.
    found: Option<(u32, Child)>,
}

impl Visit for TopLeaves<'_> {
    #[inline(always)]
    fn enter(&self, node: &Node8) -> u32 {
        node.enter(self.ray)
    }

    #[inline(always)]
    fn blocks(&mut self, leaf: Child) -> bool {
        let instances = &self.instanced.top_leaves[leaf as usize];
        let mut enter = instances.enter(self.ray);
        while enter != 0 {
            let p = instances.child[enter.trailing_zeros() as usize];
            enter &= enter - 1;
            if let Some(l) = self.instanced.walk_instance(p, self.ray, self.stack) {
                self.found = Some((p, l));
                return true;
            }
        }
        false
    }
}

/// The leaves of one instance's mesh tree, walked with the ray carried into its space (`local`) and
/// tested with the world one.
struct MeshLeaves<'a> {
    instanced: &'a Instanced,
    placed: &'a Placed,
    local: &'a Ray,
    world: &'a Ray,
    /// How far its boxes are grown ([`Placed::pad`]).
    pad: f32,
}

impl Visit for MeshLeaves<'_> {
    #[inline(always)]
    fn enter(&self, node: &Node8) -> u32 {
        node.enter_grown(self.local, self.pad)
    }

    #[inline(always)]
    fn blocks(&mut self, leaf: Child) -> bool {
        self.instanced.leaf_blocks(self.placed, leaf, self.world)
    }
}

/// Walks the tree `nodes` from its root for a leaf that blocks `ray` (`visit` says which nodes it
/// enters and which leaves block it), opening the children nearest first along each node's axis, on
/// `stack`. Returns that leaf.
#[inline(always)]
pub fn walk_tree(nodes: &[Node8], ray: &Ray, stack: &mut [Child; STACK], visit: &mut impl Visit) -> Option<Child> {
    let mut top = 0;
    let mut at = 0u32;
    loop {
        if at & LEAF != 0 {
            let leaf = at & !LEAF;
            if visit.blocks(leaf) {
                return Some(leaf);
            }
        } else {
            let node = &nodes[at as usize];
            let mut enter = visit.enter(node);
            // The child nearest along the node's axis is pushed last, so it is opened first: a blocked
            // ray is most likely blocked by what it meets first.
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
        debug_assert!(at != NONE, "an empty slot is never entered");
    }
}
