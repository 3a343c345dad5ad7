//! Instances' vertices in a view's clip space: the one transform every rasterized pass shares, so a
//! surface and what is drawn from the same vertices (a shadow volume's near cap) rasterize alike.

use std::ops::{Index, Range};

use glam::{Mat4, Vec3, Vec4};
use rayon::prelude::*;
use shadow_core::{FrameInputs, Instance};

use crate::runs;

/// Clip-space vertices of an instance under `clip_from_local` (its world transform under the view's).
#[must_use]
pub fn clip_vertices(positions: &[Vec3], clip_from_local: Mat4) -> Vec<Vec4> {
    positions.par_iter().with_min_len(JOB).map(|&p| to_clip(clip_from_local, p)).collect()
}

/// The transform itself, one vertex.
#[inline]
fn to_clip(clip_from_local: Mat4, p: Vec3) -> Vec4 {
    clip_from_local * p.extend(1.0)
}

/// Vertices a thread transforms in one go.
const JOB: usize = 4096;

/// The clip-space vertices of every instance of a frame ([`clip_vertices`]), one instance after another
/// in one buffer: a frame of many small meshes makes one allocation, not one a mesh. Indexed by the
/// instance's index in the frame.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct ClipVertices {
    vertices: Vec<Vec4>,
    /// Where each instance's vertices start, and the total at the end.
    starts: Vec<usize>,
}

impl ClipVertices {
    /// The vertices of `frame`'s instances under `clip_from_world`.
    #[must_use]
    pub fn of(frame: &FrameInputs, clip_from_world: Mat4) -> Self {
        Self::of_instances(&frame.instances.iter().collect::<Vec<_>>(), clip_from_world)
    }

    /// The vertices of `instances` under `clip_from_world`, indexed by their place in the list.
    #[must_use]
    pub fn of_instances(instances: &[&Instance], clip_from_world: Mat4) -> Self {
        // Counted side by side: reading many small meshes' lengths is a wait on memory each.
        let counts: Vec<usize> = instances.par_iter().with_min_len(1024).map(|i| i.mesh.positions().len()).collect();
        let starts = runs::starts(&counts);
        let mut vertices = vec![Vec4::ZERO; starts[counts.len()]];
        runs::for_each_run(&starts, &mut vertices, JOB, |run, out| {
            let mut out = out;
            for inst in &instances[run] {
                let (mine, tail) = std::mem::take(&mut out).split_at_mut(inst.mesh.positions().len());
                let m = clip_from_world * inst.world_from_local;
                let transform = |(v, &p): (&mut Vec4, &Vec3)| *v = to_clip(m, p);
                if mine.len() > JOB {
                    mine.par_iter_mut().zip(inst.mesh.positions()).with_min_len(JOB).for_each(transform);
                } else {
                    mine.iter_mut().zip(inst.mesh.positions()).for_each(transform);
                }
                out = tail;
            }
        });
        Self { vertices, starts }
    }

    /// The range of instance `i`'s vertices in the buffer.
    fn range(&self, i: usize) -> Range<usize> {
        self.starts[i]..self.starts[i + 1]
    }

    /// Number of instances.
    #[must_use]
    pub fn len(&self) -> usize {
        self.starts.len().saturating_sub(1)
    }

    /// True when there is no instance.
    #[must_use]
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }
}

impl Index<usize> for ClipVertices {
    type Output = [Vec4];

    fn index(&self, i: usize) -> &[Vec4] {
        &self.vertices[self.range(i)]
    }
}

#[cfg(test)]
mod tests {
    use glam::Mat4;
    use shadow_core::{Material, Scene, procedural, scenes};

    use super::*;

    /// Every instance's vertices are those [`clip_vertices`] gives it, to the bit, in a frame of small
    /// meshes around a large one.
    #[test]
    fn each_instance_has_its_own_vertices() {
        let mut s = Scene::new();
        let material = s.add_material(Material::default());
        let small = s.add_mesh(procedural::sphere(0.2, 8, 4).expect("sphere"));
        let large = s.add_mesh(procedural::sphere(1.0, 128, 64).expect("sphere"));
        for i in 0..300 {
            let mesh = if i == 150 { large } else { small };
            let at = Mat4::from_translation(Vec3::new((i % 20) as f32, 0.5, (i / 20) as f32));
            s.add_instance(&format!("ball {i}"), mesh, material, at).expect("instance");
        }
        scenes::stage_model(&mut s, true);
        let frame = FrameInputs::from_first_camera(&s).expect("frame");
        let view = frame.camera.clip_from_world(4.0 / 3.0);
        let all = ClipVertices::of(&frame, view);
        assert_eq!(all.len(), frame.instances.len());
        let sizes: Vec<usize> = frame.instances.iter().map(|i| i.mesh.positions().len()).collect();
        assert!(sizes.iter().any(|&n| n > JOB), "a mesh of more than a job's vertices");
        for (k, inst) in frame.instances.iter().enumerate() {
            let own = clip_vertices(inst.mesh.positions(), view * inst.world_from_local);
            assert_eq!(own.len(), all[k].len(), "instance {k}");
            let bits = |v: &Vec4| v.to_array().map(f32::to_bits);
            assert!(own.iter().zip(&all[k]).all(|(a, b)| bits(a) == bits(b)), "instance {k}");
        }
    }
}
