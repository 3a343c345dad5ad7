//! glTF animations: each channel that moves a node of the loaded scene, read into the scene graph's
//! [`Animation`]s with its sampler's key times, values and interpolation.

use glam::{Quat, Vec3};
use gltf::accessor::Dimensions;
use gltf::animation::Property;

use super::Loader;
use super::bytes::read_floats;
use crate::assets::AssetFault as Fault;
use crate::scene::{Animation, Channel, Interpolation, Keyframes};

impl Loader<'_> {
    /// Adds the file's animations. A channel of a node outside the loaded scene moves nothing and is left
    /// out; one of morph weights moves the weights of every primitive the node draws.
    pub(super) fn animations(&mut self) -> Result<(), Fault> {
        for anim in self.doc.animations() {
            let name = anim.name().map_or_else(|| format!("animation {}", anim.index()), str::to_string);
            let mut channels = Vec::new();
            for (i, channel) in anim.channels().enumerate() {
                let target = channel.target();
                let index = target.node().index();
                let Some(node) = self.node_keys.get(index).copied().flatten() else { continue };
                let property = target.property();
                let name = &name;
                let fail = move |why: String| {
                    let property = format!("{property:?}").to_lowercase();
                    Fault::Malformed(format!("animation '{name}', channel {i} ({property} of node {index}): {why}"))
                };
                if property != Property::MorphTargetWeights
                    && matches!(target.node().transform(), gltf::scene::Transform::Matrix { .. })
                {
                    return Err(fail(
                        "the node is given by a matrix, and glTF animates only translation, rotation \
                                     and scale"
                            .into(),
                    ));
                }
                let sampler = channel.sampler();
                let times = read_floats(&sampler.input(), &self.buffers, "animation input", Dimensions::Scalar, false)
                    .map_err(|e| fail(e.to_string()))?;
                let output = sampler.output();
                let what = "animation output";
                let values = match property {
                    Property::Translation | Property::Scale => {
                        let v = read_floats(&output, &self.buffers, what, Dimensions::Vec3, false)
                            .map_err(|e| fail(e.to_string()))?;
                        let v: Vec<Vec3> = v.chunks_exact(3).map(Vec3::from_slice).collect();
                        if property == Property::Scale { Keyframes::Scale(v) } else { Keyframes::Translation(v) }
                    }
                    Property::Rotation => {
                        let v = read_floats(&output, &self.buffers, what, Dimensions::Vec4, true)
                            .map_err(|e| fail(e.to_string()))?;
                        Keyframes::Rotation(v.chunks_exact(4).map(Quat::from_slice).collect())
                    }
                    Property::MorphTargetWeights => {
                        let targets = target
                            .node()
                            .mesh()
                            .map_or(0, |m| m.primitives().map(|p| p.morph_targets().len()).max().unwrap_or(0));
                        if targets == 0 {
                            return Err(fail("the node draws no morph targets".into()));
                        }
                        let values = read_floats(&output, &self.buffers, what, Dimensions::Scalar, true)
                            .map_err(|e| fail(e.to_string()))?;
                        Keyframes::Weights { targets, values }
                    }
                };
                let interpolation = match sampler.interpolation() {
                    gltf::animation::Interpolation::Step => Interpolation::Step,
                    gltf::animation::Interpolation::Linear => Interpolation::Linear,
                    gltf::animation::Interpolation::CubicSpline => Interpolation::CubicSpline,
                };
                let mut channel = Channel { node, times, interpolation, values };
                channel.check().map_err(fail)?;
                if property == Property::MorphTargetWeights {
                    // Each primitive the node draws is a scene node of its own, with the node's weights.
                    for &p in &self.primitive_nodes[index] {
                        channels.push(Channel { node: p, ..channel.clone() });
                    }
                } else {
                    channels.push(channel);
                }
            }
            if channels.is_empty() {
                continue;
            }
            let animation = Animation::new(&name, channels).map_err(|e| Fault::Malformed(e.to_string()))?;
            self.scene.add_animation(animation).map_err(|e| Fault::Malformed(e.to_string()))?;
        }
        Ok(())
    }
}
