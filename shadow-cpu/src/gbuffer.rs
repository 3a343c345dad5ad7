//! The camera G-buffer (DESIGN 5, step 2): a visibility buffer, then a resolve. The rasterization pass
//! writes only which triangle is visible at each pixel; the resolve intersects the pixel's camera ray with
//! that one triangle, which gives exact world position and perspective-correct barycentrics for the
//! normal, once per pixel instead of once per overdrawn fragment.
//!
//! The clip-space vertices of every instance are kept: shadow-volume near caps are drawn from exactly
//! these, so a lit surface and its cap have bit-identical depths.

use glam::{BVec4A, Mat3, Mat4, Vec2, Vec3, Vec4};
use rayon::prelude::*;
use shadow_core::material::Footprint;
use shadow_core::mesh::{face_normal, power_of_two_unit};
use shadow_core::scene::Camera;
use shadow_core::{FrameInputs, Image};

use crate::alpha_test::{Drawn, draw_alpha_tested};
pub use crate::clip_space::{ClipVertices, clip_vertices};
use crate::context::{CpuError, check_size};
use crate::raster::{Batch, DepthStencil, Fragment, Indexed, RasterState, draw_flat};

/// No instance at this pixel.
pub const NO_INSTANCE: u32 = u32::MAX;

/// Some instance at this pixel, which one not known: a covered pixel of a G-buffer made from another
/// backend's surfaces ([`GBuffer::from_surfaces`]).
pub const SOME_INSTANCE: u32 = u32::MAX - 1;

/// The camera view of a frame.
#[derive(Clone, Debug)]
pub struct GBuffer {
    /// The camera.
    pub camera: Camera,
    /// World to clip for this view's aspect ratio.
    pub clip_from_world: Mat4,
    /// NDC depth, 1 where nothing is drawn.
    pub depth: Image<f32>,
    /// World position of the visible surface.
    pub position: Image<Vec3>,
    /// Unit shading normal (turned towards the viewer for two-sided materials).
    pub normal: Image<Vec3>,
    /// Unit face normal, turned towards the viewer (the side that is seen).
    pub geometric_normal: Image<Vec3>,
    /// Linear albedo.
    pub albedo: Image<Vec3>,
    /// Index of the visible instance in the frame, [`NO_INSTANCE`] for none.
    pub instance: Image<u32>,
    /// Pixels that show a surface receiving shadows.
    pub receiver: Image<bool>,
    /// Clip-space vertices of every instance, exactly as rasterized.
    pub clip_vertices: ClipVertices,
    /// The visibility buffer (each pixel's primitive in the frame's one draw, [`NO_INSTANCE`] for none),
    /// kept so a recycled G-buffer reuses its storage.
    visible: Vec<u32>,
}

impl GBuffer {
    /// Width in pixels.
    #[must_use]
    pub fn width(&self) -> u32 {
        self.depth.width()
    }
    /// Height in pixels.
    #[must_use]
    pub fn height(&self) -> u32 {
        self.depth.height()
    }
    /// Number of receiver pixels.
    #[must_use]
    pub fn covered_pixels(&self) -> u64 {
        self.receiver.data().iter().filter(|&&r| r).count() as u64
    }
}

impl GBuffer {
    /// The G-buffer of the surfaces another backend saw in `frame`'s view (its G-buffer read back), so the
    /// CPU can shade and measure at exactly those points: the depth is found from the positions, every
    /// covered pixel shows [`SOME_INSTANCE`], and the clip-space vertices are the frame's own.
    #[must_use]
    pub fn from_surfaces(frame: &FrameInputs, s: shadow_core::frame::Surfaces) -> Self {
        let (width, height) = (s.position.width(), s.position.height());
        let clip_from_world = frame.camera.clip_from_world(width as f32 / height as f32);
        let depth = Image::from_fn(width, height, |x, y| {
            if *s.covered.get(x, y) { clip_from_world.project_point3(*s.position.get(x, y)).z } else { 1.0 }
        });
        let instance = s.covered.map(|&c| if c { SOME_INSTANCE } else { NO_INSTANCE });
        Self {
            camera: frame.camera,
            clip_from_world,
            depth,
            position: s.position,
            normal: s.normal,
            geometric_normal: s.geometric_normal,
            albedo: s.albedo,
            instance,
            receiver: s.receiver,
            clip_vertices: ClipVertices::of(frame, clip_from_world),
            visible: Vec::new(),
        }
    }
}

/// The storage of a G-buffer, taken apart for reuse.
#[derive(Default)]
struct Storage {
    vec3: [Option<Vec<Vec3>>; 4],
    depth: Option<Vec<f32>>,
    receiver: Option<Vec<bool>>,
    visible: Option<Vec<u32>>,
    instance: Option<Vec<u32>>,
}

impl GBuffer {
    fn into_storage(self) -> Storage {
        Storage {
            vec3: [
                Some(self.position.into_vec()),
                Some(self.normal.into_vec()),
                Some(self.geometric_normal.into_vec()),
                Some(self.albedo.into_vec()),
            ],
            depth: Some(self.depth.into_vec()),
            receiver: Some(self.receiver.into_vec()),
            visible: Some(self.visible),
            instance: Some(self.instance.into_vec()),
        }
    }
}

/// Where the ray `origin + t dir` meets the plane of triangle `c`, with that point's barycentrics. The
/// ray is known to hit the triangle (the rasterizer found it at this pixel), so no bounds are checked;
/// a ray parallel to the plane (a triangle seen edge-on) falls back to the centroid.
fn ray_triangle(origin: Vec3, dir: Vec3, c: [Vec3; 3]) -> (Vec3, [f32; 3]) {
    let (e1, e2) = (c[1] - c[0], c[2] - c[0]);
    let h = dir.cross(e2);
    let det = e1.dot(h);
    if det.abs() <= f32::MIN_POSITIVE {
        return ((c[0] + c[1] + c[2]) / 3.0, [1.0 / 3.0; 3]);
    }
    let s = origin - c[0];
    let u = s.dot(h) / det;
    let q = s.cross(e1);
    let v = dir.dot(q) / det;
    (c[0] + e1 * u + e2 * v, [1.0 - u - v, u, v])
}

/// What the resolve needs of a visible triangle, the same for all its pixels.
#[derive(Clone, Copy)]
struct Triangle {
    instance: usize,
    /// World-space corners.
    corners: [Vec3; 3],
    /// Object-space vertex normals.
    normals: [Vec3; 3],
    normal_from_local: Mat3,
    /// Unit world-space face normal, `None` for a degenerate triangle.
    face: Option<Vec3>,
    /// The corners' texture coordinates, where the instance's base colour has a texture to read.
    uvs: Option<[Vec2; 3]>,
}

impl Triangle {
    fn new(frame: &FrameInputs, instance: usize, triangle: usize, normal_from_local: Mat3) -> Self {
        let inst = &frame.instances[instance];
        let t = inst.mesh.triangles()[triangle];
        let (p, nn) = (inst.mesh.positions(), inst.mesh.normals());
        let textured = inst.material.base_color_texture.is_some() && inst.base_color_texture.is_some();
        Self {
            instance,
            corners: t.map(|k| inst.world_from_local.transform_point3(p[k as usize])),
            normals: t.map(|k| nn[k as usize]),
            normal_from_local,
            // Scaled first: a model staged from large coordinates has a normal matrix that would multiply
            // the raw face normal past f32's range.
            face: (normal_from_local * power_of_two_unit(face_normal(t.map(|k| p[k as usize])))).try_normalize(),
            uvs: inst.mesh.uvs().filter(|_| textured).map(|uv| t.map(|k| uv[k as usize])),
        }
    }

    /// The albedo where the ray from `eye` along `dir` meets the triangle: the material's base colour
    /// times its texture's, read at the point's texture coordinates over the footprint of the pixel
    /// (how they change to where the rays `right` and `down` of the pixels beside it meet the
    /// triangle's plane). `None` for an untextured triangle, whose albedo is the instance's.
    fn albedo(&self, inst: &shadow_core::Instance, eye: Vec3, [dir, right, down]: [Vec3; 3]) -> Option<Vec3> {
        let uvs = self.uvs?;
        let uv = |dir: Vec3| {
            let b = ray_triangle(eye, dir, self.corners).1;
            uvs[0] * b[0] + uvs[1] * b[1] + uvs[2] * b[2]
        };
        let at = uv(dir);
        let footprint = Footprint { dx: uv(right) - at, dy: uv(down) - at };
        Some(inst.material.base_color_at(inst.base_color_texture.as_deref(), Some(at), footprint).truncate())
    }
}

/// Renders the G-buffer of a frame at `width x height`.
///
/// # Errors
/// A zero or oversized view, or a frame of more triangles than a draw can number.
pub fn render(frame: &FrameInputs, width: u32, height: u32) -> Result<GBuffer, CpuError> {
    render_reusing(frame, width, height, None)
}

/// A vector of `n` copies of `value`, in `old`'s storage when there is one: a recycled buffer's pages are
/// already mapped, so a frame does not pay the kernel to fault fresh ones in.
fn refill<T: Clone>(old: Option<Vec<T>>, n: usize, value: T) -> Vec<T> {
    let mut v = old.unwrap_or_default();
    v.clear();
    v.resize(n, value);
    v
}

/// A vector of `n` entries for a pass that writes every one of them, `old` as it is when it has that length
/// (no pass over it first), else `n` copies of `value`.
fn overwritten<T: Clone>(old: Option<Vec<T>>, n: usize, value: T) -> Vec<T> {
    old.filter(|v| v.len() == n).unwrap_or_else(|| vec![value; n])
}

/// The camera's rays through pixel centres.
struct EyeRays {
    eye: Vec3,
    world_from_clip: Mat4,
    width: u32,
    height: u32,
}

impl EyeRays {
    /// The direction (not normalized) of the ray through pixel `(x, y)`'s centre.
    #[inline]
    fn dir(&self, x: usize, y: usize) -> Vec3 {
        let ndc = glam::Vec2::new(
            (x as f32 + 0.5) / self.width as f32 * 2.0 - 1.0,
            1.0 - (y as f32 + 0.5) / self.height as f32 * 2.0,
        );
        self.world_from_clip.project_point3(ndc.extend(0.5)) - self.eye
    }
}

/// Where the ray from `eye` along `dir` meets triangle `t` of instance `inst`: the world point, the
/// interpolated shading normal and the face normal, both turned to the side that is seen (the shading
/// normal only for two-sided materials).
#[inline]
fn surface(t: &Triangle, inst: &shadow_core::Instance, eye: Vec3, dir: Vec3) -> (Vec3, Vec3, Vec3) {
    let (world, b) = ray_triangle(eye, dir, t.corners);
    let interp = t.normals[0] * b[0] + t.normals[1] * b[1] + t.normals[2] * b[2];
    let mut shading = (t.normal_from_local * interp).normalize_or(Vec3::Y);
    let mut geometric = t.face.unwrap_or(shading);
    if inst.mirrored {
        geometric = -geometric;
    }
    if geometric.dot(eye - world) < 0.0 {
        geometric = -geometric;
        if inst.two_sided {
            shading = -shading;
        }
    }
    (world, shading, geometric)
}

/// Four vectors, one a lane: the operands of [`surface_x4`].
#[derive(Clone, Copy)]
struct Lanes3 {
    x: Vec4,
    y: Vec4,
    z: Vec4,
}

impl Lanes3 {
    fn of(v: [Vec3; 4]) -> Self {
        Self { x: Vec4::from(v.map(|v| v.x)), y: Vec4::from(v.map(|v| v.y)), z: Vec4::from(v.map(|v| v.z)) }
    }

    fn splat(v: Vec3) -> Self {
        Self { x: Vec4::splat(v.x), y: Vec4::splat(v.y), z: Vec4::splat(v.z) }
    }

    fn lane(&self, k: usize) -> Vec3 {
        Vec3::new(self.x[k], self.y[k], self.z[k])
    }

    /// `Vec3::dot`'s sum, in its order.
    fn dot(self, o: Self) -> Vec4 {
        self.x * o.x + self.y * o.y + self.z * o.z
    }

    /// `Vec3::cross`'s terms, in its order.
    fn cross(self, o: Self) -> Self {
        Self { x: self.y * o.z - o.y * self.z, y: self.z * o.x - o.z * self.x, z: self.x * o.y - o.x * self.y }
    }

    /// `Mat3 * Vec3` as glam sums it: column by column.
    fn transformed(self, m: &Mat3) -> Self {
        let (c0, c1, c2) = (Self::splat(m.x_axis), Self::splat(m.y_axis), Self::splat(m.z_axis));
        c0 * self.x + c1 * self.y + c2 * self.z
    }

    /// `Vec3::normalize_or`: times the reciprocal length where that is finite and positive.
    fn normalize_or(self, fallback: Vec3) -> Self {
        let rcp = Vec4::ONE / self.dot(self).sqrt();
        let ok = rcp.cmpgt(Vec4::ZERO) & rcp.is_finite_mask();
        (self * rcp).select(ok, Self::splat(fallback))
    }

    /// `self` in the lanes of `mask`, `other` elsewhere.
    fn select(self, mask: BVec4A, other: Self) -> Self {
        Self {
            x: Vec4::select(mask, self.x, other.x),
            y: Vec4::select(mask, self.y, other.y),
            z: Vec4::select(mask, self.z, other.z),
        }
    }
}

impl std::ops::Add for Lanes3 {
    type Output = Self;
    fn add(self, o: Self) -> Self {
        Self { x: self.x + o.x, y: self.y + o.y, z: self.z + o.z }
    }
}

impl std::ops::Sub for Lanes3 {
    type Output = Self;
    fn sub(self, o: Self) -> Self {
        Self { x: self.x - o.x, y: self.y - o.y, z: self.z - o.z }
    }
}

impl std::ops::Neg for Lanes3 {
    type Output = Self;
    fn neg(self) -> Self {
        Self { x: -self.x, y: -self.y, z: -self.z }
    }
}

/// Each lane times its own scalar.
impl std::ops::Mul<Vec4> for Lanes3 {
    type Output = Self;
    fn mul(self, s: Vec4) -> Self {
        Self { x: self.x * s, y: self.y * s, z: self.z * s }
    }
}

/// [`surface`] for four rays into the same triangle: each lane the same operations in the same order, so
/// the same bits (a test holds them equal), with four pixels' divisions and roots in one instruction
/// each and four chains of them in flight.
fn surface_x4(t: &Triangle, inst: &shadow_core::Instance, eye: Vec3, dirs: [Vec3; 4]) -> [(Vec3, Vec3, Vec3); 4] {
    let c = t.corners;
    let dir = Lanes3::of(dirs);
    // ray_triangle, lane by lane.
    let (e1, e2) = (c[1] - c[0], c[2] - c[0]);
    let h = dir.cross(Lanes3::splat(e2));
    let det = Lanes3::splat(e1).dot(h);
    let s = eye - c[0];
    let u = Lanes3::splat(s).dot(h) / det;
    let v = dir.dot(Lanes3::splat(s.cross(e1))) / det;
    let hit = Lanes3::splat(c[0]) + Lanes3::splat(e1) * u + Lanes3::splat(e2) * v;
    let edge_on = det.abs().cmple(Vec4::splat(f32::MIN_POSITIVE));
    let world = Lanes3::splat((c[0] + c[1] + c[2]) / 3.0).select(edge_on, hit);
    let third = Vec4::splat(1.0 / 3.0);
    let b = [
        Vec4::select(edge_on, third, Vec4::ONE - u - v),
        Vec4::select(edge_on, third, u),
        Vec4::select(edge_on, third, v),
    ];
    // The rest of surface.
    let n = t.normals.map(Lanes3::splat);
    let interp = n[0] * b[0] + n[1] * b[1] + n[2] * b[2];
    let mut shading = interp.transformed(&t.normal_from_local).normalize_or(Vec3::Y);
    let mut geometric = t.face.map_or(shading, Lanes3::splat);
    if inst.mirrored {
        geometric = -geometric;
    }
    let away = geometric.dot(Lanes3::splat(eye) - world).cmplt(Vec4::ZERO);
    geometric = (-geometric).select(away, geometric);
    if inst.two_sided {
        shading = (-shading).select(away, shading);
    }
    std::array::from_fn(|k| (world.lane(k), shading.lane(k), geometric.lane(k)))
}

/// The surface attributes of every pixel, row after row.
struct Surfaces {
    position: Vec<Vec3>,
    normal: Vec<Vec3>,
    geometric_normal: Vec<Vec3>,
    albedo: Vec<Vec3>,
    receiver: Vec<bool>,
    instance: Vec<u32>,
}

/// Resolves each pixel's visible primitive (its id in `all`, [`NO_INSTANCE`] for none) to the surface
/// attributes, writing every pixel of every image in one pass (the background's too: the buffers are not
/// cleared first). The triangle's world corners and face normal are those of the pixel before on most
/// pixels of a row, and four pixels in a row on one triangle are resolved together ([`surface_x4`]).
fn resolve(frame: &FrameInputs, all: &Batch<'_>, visible: &[u32], eye_rays: &EyeRays, s: &mut Surfaces) {
    let w = eye_rays.width as usize;
    s.position
        .par_chunks_mut(w)
        .zip(s.normal.par_chunks_mut(w))
        .zip(s.geometric_normal.par_chunks_mut(w))
        .zip(s.albedo.par_chunks_mut(w))
        .zip(s.receiver.par_chunks_mut(w))
        .zip(s.instance.par_chunks_mut(w))
        .zip(visible.par_chunks(w))
        .enumerate()
        .for_each_init(Vec::new, |dirs, (y, ((((((pos, nrm), geo), alb), rec), ins), vis))| {
            // The row's ray directions first, in a loop of their own: the surface work after them is a
            // long chain of dependent divisions and roots, and short loops keep more pixels in flight.
            dirs.clear();
            dirs.extend((0..w).map(|x| eye_rays.dir(x, y)));
            let mut last: Option<(u32, Triangle)> = None;
            let mut x = 0;
            while x < w {
                let prim = vis[x];
                if prim == NO_INSTANCE {
                    (pos[x], nrm[x], geo[x], alb[x], rec[x], ins[x]) =
                        (Vec3::ZERO, Vec3::Y, Vec3::Y, Vec3::ZERO, false, NO_INSTANCE);
                    x += 1;
                    continue;
                }
                let t = match last {
                    Some((p, t)) if p == prim => t,
                    _ => {
                        let (k, triangle) = all.part_of(prim);
                        // Made as the row meets an instance: only those of instances in view are made.
                        let m = match last {
                            Some((_, t)) if t.instance == k => t.normal_from_local,
                            _ => shadow_core::affine::normal_matrix(frame.instances[k].world_from_local),
                        };
                        let t = Triangle::new(frame, k, triangle as usize, m);
                        last = Some((prim, t));
                        t
                    }
                };
                let inst = &frame.instances[t.instance];
                let mut put = |x: usize, (world, shading, geometric): (Vec3, Vec3, Vec3)| {
                    (pos[x], nrm[x], geo[x], alb[x], rec[x], ins[x]) =
                        (world, shading, geometric, inst.base_color, inst.receives_shadow, t.instance as u32);
                };
                // Four pixels at once where the next four show this triangle, else this one.
                let next = if vis.get(x..x + 4).is_some_and(|four| four.iter().all(|&p| p == prim)) {
                    let four = surface_x4(&t, inst, eye_rays.eye, std::array::from_fn(|k| dirs[x + k]));
                    for (k, surface) in four.into_iter().enumerate() {
                        put(x + k, surface);
                    }
                    x + 4
                } else {
                    put(x, surface(&t, inst, eye_rays.eye, dirs[x]));
                    x + 1
                };
                if t.uvs.is_some() {
                    for x in x..next {
                        let beside = [dirs[x], eye_rays.dir(x + 1, y), eye_rays.dir(x, y + 1)];
                        alb[x] = t.albedo(inst, eye_rays.eye, beside).unwrap_or(alb[x]);
                    }
                }
                x = next;
            }
        });
}

/// [`render`], reusing the storage of a previous frame's G-buffer.
///
/// # Errors
/// A zero or oversized view, or a frame of more triangles than a draw can number.
pub fn render_reusing(
    frame: &FrameInputs,
    width: u32,
    height: u32,
    spare: Option<GBuffer>,
) -> Result<GBuffer, CpuError> {
    check_size("view", u64::from(width), u64::from(height), u64::from(crate::context::MAX_TARGET_SIDE).pow(2))?;
    let camera = frame.camera;
    let clip_from_world = camera.clip_from_world(width as f32 / height as f32);
    let clip = ClipVertices::of(frame, clip_from_world);

    let n = width as usize * height as usize;
    let mut old = spare.map(GBuffer::into_storage);
    let mut take = |k: usize| old.as_mut().and_then(|o: &mut Storage| o.vec3[k].take());
    let (position, normal, geometric_normal, albedo) = (
        overwritten(take(0), n, Vec3::ZERO),
        overwritten(take(1), n, Vec3::Y),
        overwritten(take(2), n, Vec3::Y),
        overwritten(take(3), n, Vec3::ZERO),
    );
    let old = old.unwrap_or_default();
    let mut ds = DepthStencil::from_parts(width, height, refill(old.depth, n, 1.0), vec![0; n]);
    let mut visible =
        Image::from_vec(width, height, refill(old.visible, n, NO_INSTANCE)).unwrap_or_else(|| unreachable!("n pixels"));
    let receiver = overwritten(old.receiver, n, false);
    // Every instance in one draw, in order (the same fragments as a draw each), each pixel left with the id
    // of its primitive in the batch; the back faces of single-sided materials not drawn.
    let all = Batch::new(
        frame
            .instances
            .par_iter()
            .enumerate()
            .with_min_len(1024)
            .map(|(k, inst)| Indexed::seen(inst, &clip[k]))
            .collect(),
    )?;
    let drawn = Drawn::sort(frame, |_| true);
    if drawn.solid.len() == frame.instances.len() {
        draw_flat(&mut ds, &mut visible, &all, &RasterState::default(), |prim| prim);
    } else {
        // The solid instances in one draw, then the cut-out ones through their alpha test, each pixel
        // left with its primitive's id in `all`.
        let part = |k: usize| Indexed::seen(&frame.instances[k], &clip[k]);
        let solid = Batch::new(drawn.solid.iter().map(|&k| part(k)).collect())?;
        let in_all = |list: &[usize], batch: &Batch<'_>, prim: u32| {
            let (part, triangle) = batch.part_of(prim);
            all.start(list[part]) + triangle
        };
        draw_flat(&mut ds, &mut visible, &solid, &RasterState::default(), |p| in_all(&drawn.solid, &solid, p));
        let cutout = Batch::new(drawn.cutout.iter().map(|&k| part(k)).collect())?;
        let value = |f: &Fragment| Some(in_all(&drawn.cutout, &cutout, f.prim));
        draw_alpha_tested(&mut ds, &mut visible, (&cutout, &drawn.tests), &RasterState::default(), value);
    }

    let eye_rays = EyeRays { eye: camera.eye, world_from_clip: clip_from_world.inverse(), width, height };
    let mut surfaces = Surfaces {
        position,
        normal,
        geometric_normal,
        albedo,
        receiver,
        instance: overwritten(old.instance, n, NO_INSTANCE),
    };
    resolve(frame, &all, visible.data(), &eye_rays, &mut surfaces);
    let Surfaces { position, normal, geometric_normal, albedo, receiver, instance } = surfaces;
    fn image<T>(w: u32, h: u32, data: Vec<T>) -> Image<T> {
        Image::from_vec(w, h, data).unwrap_or_else(|| unreachable!("one entry per pixel"))
    }
    Ok(GBuffer {
        camera,
        clip_from_world,
        position: image(width, height, position),
        normal: image(width, height, normal),
        geometric_normal: image(width, height, geometric_normal),
        albedo: image(width, height, albedo),
        receiver: image(width, height, receiver),
        instance: image(width, height, instance),
        depth: ds.into_depth_image(),
        clip_vertices: clip,
        visible: visible.into_vec(),
    })
}

#[cfg(test)]
mod tests {
    use shadow_core::scenes::{self, SceneParams};

    use super::*;

    fn frame(name: &str) -> FrameInputs {
        let scene = scenes::build(name, &SceneParams::default()).expect("built-in scene");
        let camera = scene.cameras().next().expect("a camera").0;
        FrameInputs::from_scene(&scene, camera).expect("a valid frame")
    }

    /// Four rays at once give the bits one ray at a time gives: over random triangles and rays, a
    /// degenerate triangle, one seen edge-on, zero and overflowing normals, mirrored and two-sided
    /// instances, rays from either side.
    #[test]
    fn four_rays_at_once_are_four_rays_one_at_a_time() {
        let f = frame("primitives");
        let seed = std::cell::Cell::new(0x9e37_79b9u32);
        let next = || {
            let mut x = seed.get();
            x ^= x << 13;
            x ^= x >> 17;
            x ^= x << 5;
            seed.set(x);
            (x >> 8) as f32 / (1 << 24) as f32 * 4.0 - 2.0
        };
        let v3 = || Vec3::new(next(), next(), next());
        let mut checked = 0;
        for case in 0..400 {
            let mut inst = f.instances[0].clone();
            (inst.mirrored, inst.two_sided) = (case % 2 == 1, case % 4 >= 2);
            let mut corners = [v3(), v3(), v3()];
            match case % 25 {
                0 => corners[2] = corners[0] + (corners[1] - corners[0]) * 0.5,
                1 => corners = [Vec3::ZERO, Vec3::X, Vec3::Y],
                _ => {}
            }
            let normals = match case % 25 {
                2 => [Vec3::ZERO; 3],
                // Lengths past f32's range: the reciprocal length is 0.
                3 => [Vec3::splat(3e38); 3],
                _ => [v3(), v3(), v3()],
            };
            let face = (corners[1] - corners[0]).cross(corners[2] - corners[0]).try_normalize();
            let normal_from_local = Mat3::from_cols(v3(), v3(), v3());
            let t = Triangle { instance: 0, corners, normals, normal_from_local, face, uvs: None };
            let eye = v3() * 3.0;
            // Rays towards points of the triangle's plane, and along it for the one seen edge-on.
            let dirs: [Vec3; 4] = std::array::from_fn(|_| {
                if case % 25 == 1 { Vec3::new(next(), next(), 0.0) - eye.with_z(0.0) } else { corners[0] + v3() - eye }
            });
            let eye = if case % 25 == 1 { eye.with_z(0.0) } else { eye };
            let four = surface_x4(&t, &inst, eye, dirs);
            for (k, &dir) in dirs.iter().enumerate() {
                let one = surface(&t, &inst, eye, dir);
                let bits = |(a, b, c): (Vec3, Vec3, Vec3)| [a, b, c].map(|v| v.to_array().map(f32::to_bits));
                assert_eq!(bits(four[k]), bits(one), "case {case}, lane {k}");
                checked += 1;
            }
        }
        assert_eq!(checked, 1600);
    }

    /// Through the clear squares of `cutout`'s checkerboard card the camera sees the ground; on its
    /// opaque ones, the card in the texture's colour.
    #[test]
    fn clear_texels_show_what_lies_behind_them() {
        use shadow_core::scenes::cutouts::{CARD_HEIGHT, CARD_SIDE, CHECKER_SQUARES};
        let f = frame("cutout");
        let card = f.instances.iter().position(|i| i.material.name == "checkerboard").expect("the card");
        let (w, h) = (320, 240);
        let g = render(&f, w, h).expect("G-buffer");
        let eye = f.camera.eye;
        let world_from_clip = g.clip_from_world.inverse();
        let rays = EyeRays { eye, world_from_clip, width: w, height: h };
        // Each pixel's ray through the card's plane, where it meets the card: the square it crosses, and
        // whether it lies a hundredth of a square or more from the square's sides.
        let crossing = |x: usize, y: usize| {
            let dir = rays.dir(x, y);
            let p = eye + dir * ((CARD_HEIGHT - eye.y) / dir.y);
            let uv = (Vec2::new(p.x, p.z) / CARD_SIDE + 0.5) * CHECKER_SQUARES as f32;
            let inside = uv.cmpge(Vec2::ZERO).all() && uv.cmplt(Vec2::splat(CHECKER_SQUARES as f32)).all();
            let clear_of_sides = (uv - uv.round()).abs().min_element() > 0.01;
            inside.then(|| (((uv.x.floor() + uv.y.floor()) as u32).is_multiple_of(2), clear_of_sides))
        };
        let colour = shadow_core::material::sampler::decode([224, 150, 80, 255]).truncate();
        let (mut opaque, mut clear) = (0, 0);
        for y in 0..h as usize {
            for x in 0..w as usize {
                let Some((solid, true)) = crossing(x, y) else { continue };
                let shows = *g.instance.get(x as u32, y as u32);
                if solid {
                    assert_eq!(shows, card as u32, "pixel {x}, {y} on an opaque square");
                    assert!((*g.albedo.get(x as u32, y as u32) - colour).abs().max_element() < 1e-6);
                    opaque += 1;
                } else {
                    assert_ne!(shows, card as u32, "pixel {x}, {y} on a clear square");
                    assert!(g.position.get(x as u32, y as u32).y.abs() < 1e-4, "the ground through a clear square");
                    clear += 1;
                }
            }
        }
        assert!(opaque > 1000 && clear > 1000, "{opaque} pixels on opaque squares, {clear} on clear ones");
    }

    /// The buffers of a recycled G-buffer are overwritten, not cleared: whatever another scene left in
    /// them, at the same size or another, must not show through.
    #[test]
    fn a_recycled_g_buffer_is_a_fresh_one() {
        let (cubes, cylinder) = (frame("cubes"), frame("cylinder"));
        for (w, h) in [(96, 64), (80, 80)] {
            let fresh = render(&cylinder, w, h).expect("G-buffer");
            let spare = render(&cubes, 96, 64).expect("G-buffer");
            let reused = render_reusing(&cylinder, w, h, Some(spare)).expect("G-buffer");
            assert_eq!(fresh.depth, reused.depth);
            assert_eq!(fresh.position, reused.position);
            assert_eq!(fresh.normal, reused.normal);
            assert_eq!(fresh.geometric_normal, reused.geometric_normal);
            assert_eq!(fresh.albedo, reused.albedo);
            assert_eq!(fresh.instance, reused.instance);
            assert_eq!(fresh.receiver, reused.receiver);
            // Background and surface both in view, so both branches of the resolve were compared.
            assert!(fresh.instance.data().contains(&NO_INSTANCE) && fresh.covered_pixels() > 0);
        }
    }

    /// A G-buffer made from the surfaces of a rendered one keeps its points and normals, finds the same
    /// depth from the positions, and tells covered pixels from background.
    #[test]
    fn a_g_buffer_from_surfaces_is_the_one_they_came_from() {
        let f = frame("primitives");
        let g = render(&f, 80, 60).expect("G-buffer");
        let covered = g.instance.map(|&i| i != NO_INSTANCE);
        let surfaces = shadow_core::frame::Surfaces {
            position: g.position.clone(),
            normal: g.normal.clone(),
            geometric_normal: g.geometric_normal.clone(),
            albedo: g.albedo.clone(),
            receiver: g.receiver.clone(),
            covered: covered.clone(),
        };
        let made = GBuffer::from_surfaces(&f, surfaces);
        assert_eq!((made.position, made.receiver, made.clip_vertices), (g.position, g.receiver, g.clip_vertices));
        assert_eq!(made.instance.map(|&i| i == SOME_INSTANCE), covered);
        for (a, b) in made.depth.data().iter().zip(g.depth.data()) {
            assert!((a - b).abs() <= 1e-5, "depth {a} found from the position, {b} rasterized");
        }
        assert!(covered.data().contains(&false) && covered.data().contains(&true));
    }
}
