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
    /// out; channels of morph target weights are left out with one warning each animation.
    pub(super) fn animations(&mut self) -> Result<(), Fault> {
        for anim in self.doc.animations() {
            let name = anim.name().map_or_else(|| format!("animation {}", anim.index()), str::to_string);
            let mut channels = Vec::new();
            let mut weights = 0;
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
                if property == Property::MorphTargetWeights {
                    weights += 1;
                    continue;
                }
                if matches!(target.node().transform(), gltf::scene::Transform::Matrix { .. }) {
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
                    Property::MorphTargetWeights => unreachable!("left out above"),
                };
                let interpolation = match sampler.interpolation() {
                    gltf::animation::Interpolation::Step => Interpolation::Step,
                    gltf::animation::Interpolation::Linear => Interpolation::Linear,
                    gltf::animation::Interpolation::CubicSpline => Interpolation::CubicSpline,
                };
                let mut channel = Channel { node, times, interpolation, values };
                channel.check().map_err(fail)?;
                channels.push(channel);
            }
            if weights > 0 {
                self.scene.add_warning(format!(
                    "animation '{name}': {weights} channel(s) of morph target weights are not played"
                ));
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
