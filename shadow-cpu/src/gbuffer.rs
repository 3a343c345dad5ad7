//! The camera G-buffer (DESIGN 5, step 2): one rasterization pass writing, per pixel, which triangle is
//! visible and its perspective-correct barycentrics; then a resolve that turns those into world position,
//! normals, albedo and the receiver mask.
//!
//! The clip-space vertices of every instance are kept: shadow-volume near caps are drawn from exactly
//! these, so a lit surface and its cap have bit-identical depths.

use glam::{Mat3, Mat4, Vec3, Vec4};
use rayon::prelude::*;
use shadow_core::scene::Camera;
use shadow_core::{FrameInputs, Image};

use crate::context::{CpuError, check_size};
use crate::raster::{DepthStencil, Indexed, RasterState, draw};

/// No instance at this pixel.
pub const NO_INSTANCE: u32 = u32::MAX;

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
    pub clip_vertices: Vec<Vec<Vec4>>,
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

#[derive(Clone, Copy)]
struct Sample {
    instance: u32,
    triangle: u32,
    bary: [f32; 3],
}

/// Clip-space vertices of an instance under `clip_from_world`: the one transform every pass shares.
#[must_use]
pub fn clip_vertices(positions: &[Vec3], clip_from_local: Mat4) -> Vec<Vec4> {
    positions.par_iter().with_min_len(4096).map(|&p| clip_from_local * p.extend(1.0)).collect()
}

/// Renders the G-buffer of a frame at `width x height`.
///
/// # Errors
/// A zero or oversized view.
pub fn render(frame: &FrameInputs, width: u32, height: u32) -> Result<GBuffer, CpuError> {
    check_size("view", u64::from(width), u64::from(height), u64::from(crate::context::MAX_TARGET_SIDE).pow(2))?;
    let camera = frame.camera;
    let clip_from_world = camera.clip_from_world(width as f32 / height as f32);
    let clip: Vec<Vec<Vec4>> = frame
        .instances
        .iter()
        .map(|inst| clip_vertices(inst.mesh.positions(), clip_from_world * inst.world_from_local))
        .collect();

    let mut ds = DepthStencil::new(width, height, 1.0, 0);
    let none = Sample { instance: NO_INSTANCE, triangle: 0, bary: [0.0; 3] };
    let mut samples = Image::new(width, height, none);
    let state = RasterState::default();
    for (i, inst) in frame.instances.iter().enumerate() {
        let src = Indexed { positions: &clip[i], triangles: inst.mesh.triangles(), prim_base: 0, flip: inst.mirrored };
        draw(
            &mut ds,
            &mut samples,
            &src,
            &state,
            |f| Some(Sample { instance: i as u32, triangle: f.prim, bary: f.bary }),
            |d, s| *d = s,
        );
    }

    // Resolve: one sample per pixel to the surface attributes.
    let normal_from_local: Vec<Mat3> =
        frame.instances.iter().map(|i| Mat3::from_mat4(i.world_from_local).inverse().transpose()).collect();
    let resolved: Vec<(Vec3, Vec3, Vec3, Vec3, bool)> = samples
        .data()
        .par_iter()
        .with_min_len(1024)
        .map(|s| {
            if s.instance == NO_INSTANCE {
                return (Vec3::ZERO, Vec3::Y, Vec3::Y, Vec3::ZERO, false);
            }
            let inst = &frame.instances[s.instance as usize];
            let t = inst.mesh.triangles()[s.triangle as usize];
            let (p, n) = (inst.mesh.positions(), inst.mesh.normals());
            let b = s.bary;
            let local = p[t[0] as usize] * b[0] + p[t[1] as usize] * b[1] + p[t[2] as usize] * b[2];
            let world = inst.world_from_local.transform_point3(local);
            let nm = normal_from_local[s.instance as usize];
            let mut shading = (nm * (n[t[0] as usize] * b[0] + n[t[1] as usize] * b[1] + n[t[2] as usize] * b[2]))
                .normalize_or(Vec3::Y);
            let face = shadow_core::mesh::face_normal(t.map(|k| p[k as usize]));
            let mut geometric = (nm * face).normalize_or(shading);
            if inst.mirrored {
                geometric = -geometric;
            }
            let to_eye = camera.eye - world;
            let seen_from_behind = geometric.dot(to_eye) < 0.0;
            if seen_from_behind {
                geometric = -geometric;
                if inst.two_sided {
                    shading = -shading;
                }
            }
            (world, shading, geometric, inst.base_color, inst.receives_shadow)
        })
        .collect();
    let take = |f: fn(&(Vec3, Vec3, Vec3, Vec3, bool)) -> Vec3| {
        Image::from_vec(width, height, resolved.iter().map(f).collect())
            .unwrap_or_else(|| unreachable!("one entry per pixel"))
    };
    Ok(GBuffer {
        camera,
        clip_from_world,
        position: take(|r| r.0),
        normal: take(|r| r.1),
        geometric_normal: take(|r| r.2),
        albedo: take(|r| r.3),
        receiver: Image::from_vec(width, height, resolved.iter().map(|r| r.4).collect())
            .unwrap_or_else(|| unreachable!("one entry per pixel")),
        instance: samples.map(|s| s.instance),
        depth: ds.into_depth_image(),
        clip_vertices: clip,
    })
}
