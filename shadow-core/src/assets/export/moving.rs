//! Writing a scene that moves: its node hierarchy with each animated node's rest translation, rotation
//! and scale, its skins (joints and inverse bind matrices) and skinned meshes' `JOINTS_0`/`WEIGHTS_0`,
//! its morph targets and weights, and its animations, so that it plays again where it is loaded.
//!
//! glTF ignores a skinned mesh's own transform, and its validator asks that such a node be a root with
//! none: each skinned mesh is written on a root node of its own, and the node that drew it keeps its
//! place (and its children) without it.

use std::collections::HashMap;

use glam::{Mat4, Vec3};
use serde_json::{Value, json};

use super::MeshParts;
use crate::bounds::Aabb;
use crate::deform::Deformers;
use crate::scene::{Keyframes, NodeKey, Scene};

/// The nodes of a moving scene, the roots among them, its skins and its animations, as glTF arrays.
pub(super) struct Moving {
    pub(super) nodes: Vec<Value>,
    pub(super) roots: Vec<usize>,
    pub(super) skins: Vec<Value>,
    pub(super) animations: Vec<Value>,
}

pub(super) fn hierarchy(scene: &Scene, parts: &mut MeshParts) -> Moving {
    let order = scene.depth_first();
    let index: HashMap<NodeKey, usize> = order.iter().enumerate().map(|(i, k)| (*k, i)).collect();
    let mut nodes = Vec::with_capacity(order.len());
    let mut skinned = Vec::new();
    // The glTF node holding each scene node's mesh: itself, or the root its skinned mesh moved to.
    let mut mesh_node: HashMap<NodeKey, usize> = HashMap::new();
    let mut skins: Vec<(crate::scene::SkinKey, Value)> = Vec::new();
    for &key in &order {
        let Some(node) = scene.node(key) else { continue };
        let mut n = json!({"name": node.name()});
        match scene.rest_pose(key) {
            Some(trs) => {
                n["translation"] = json!(trs.translation.to_array());
                n["rotation"] = json!(trs.rotation.to_array());
                n["scale"] = json!(trs.scale.to_array());
            }
            None if node.local_transform() != Mat4::IDENTITY => {
                n["matrix"] = json!(node.local_transform().to_cols_array());
            }
            None => {}
        }
        let children: Vec<usize> = node.children().iter().filter_map(|c| index.get(c).copied()).collect();
        if !children.is_empty() {
            n["children"] = json!(children);
        }
        if let Some((mesh_key, material_key)) = node.mesh()
            && let (Some(mesh), Some(material)) = (scene.mesh(mesh_key), scene.material(material_key))
        {
            let mi = parts.mesh(scene, mesh, material);
            let mut holder = json!({"mesh": mi});
            let targets = mesh.deformers().map_or(0, |d| d.morph_targets.len());
            if targets > 0 {
                let mut weights = scene.rest_morph_weights(key).to_vec();
                weights.resize(targets, 0.0);
                holder["weights"] = json!(weights);
            }
            // A root with no transform of its own and no children may keep its skinned mesh.
            let bare =
                node.parent().is_none() && node.children().is_empty() && n.as_object().is_some_and(|o| o.len() == 1);
            match scene.node_skin(key) {
                Some(skin) if !bare => {
                    let si = skin_index(&mut skins, skin, |parts| skin_json(scene, skin, &index, parts), parts);
                    holder["skin"] = json!(si);
                    holder["name"] = json!(node.name());
                    mesh_node.insert(key, order.len() + skinned.len());
                    skinned.push(holder);
                }
                skin => {
                    if let Some(skin) = skin {
                        holder["skin"] =
                            json!(skin_index(&mut skins, skin, |parts| skin_json(scene, skin, &index, parts), parts));
                    }
                    for (k, v) in holder.as_object().into_iter().flatten() {
                        n[k] = v.clone();
                    }
                    mesh_node.insert(key, nodes.len());
                }
            }
        }
        nodes.push(n);
    }
    let mut roots: Vec<usize> = scene.roots().iter().filter_map(|r| index.get(r).copied()).collect();
    roots.extend(order.len()..order.len() + skinned.len());
    nodes.extend(skinned);
    let animations = scene
        .animations()
        .map(|(_, a)| {
            let (mut samplers, mut channels) = (Vec::new(), Vec::new());
            for c in a.channels() {
                let (path, output, kind) = match &c.values {
                    Keyframes::Translation(v) => ("translation", flat(v.iter().map(|x| x.to_array())), "VEC3"),
                    Keyframes::Scale(v) => ("scale", flat(v.iter().map(|x| x.to_array())), "VEC3"),
                    Keyframes::Rotation(v) => ("rotation", flat(v.iter().map(|x| x.to_array())), "VEC4"),
                    Keyframes::Weights { values, .. } => ("weights", values.clone(), "SCALAR"),
                };
                let node = if path == "weights" { mesh_node.get(&c.node) } else { index.get(&c.node) };
                let Some(&node) = node else { continue };
                let input = parts.floats(&c.times, "SCALAR", true);
                let output = parts.floats(&output, kind, false);
                samplers.push(json!({"input": input, "output": output, "interpolation": c.interpolation.name()}));
                channels.push(json!({"sampler": samplers.len() - 1, "target": {"node": node, "path": path}}));
            }
            json!({"name": a.name(), "samplers": samplers, "channels": channels})
        })
        .collect();
    Moving { nodes, roots, skins: skins.into_iter().map(|(_, s)| s).collect(), animations }
}

/// The index of a skin among those written, writing it on first use.
fn skin_index(
    skins: &mut Vec<(crate::scene::SkinKey, Value)>,
    skin: crate::scene::SkinKey,
    write: impl FnOnce(&mut MeshParts) -> Value,
    parts: &mut MeshParts,
) -> usize {
    if let Some(i) = skins.iter().position(|(k, _)| *k == skin) {
        return i;
    }
    skins.push((skin, write(parts)));
    skins.len() - 1
}

/// A skin's joints (as node indices) and inverse bind matrices.
fn skin_json(
    scene: &Scene,
    skin: crate::scene::SkinKey,
    index: &HashMap<NodeKey, usize>,
    parts: &mut MeshParts,
) -> Value {
    let Some(s) = scene.skin(skin) else { return json!({}) };
    let joints: Vec<usize> = s.joints.iter().map(|j| index.get(j).copied().unwrap_or(0)).collect();
    let matrices = flat(s.inverse_bind_matrices.iter().map(Mat4::to_cols_array));
    let ibm = parts.floats(&matrices, "MAT4", false);
    json!({"name": s.name, "joints": joints, "inverseBindMatrices": ibm})
}

fn flat<const N: usize>(v: impl Iterator<Item = [f32; N]>) -> Vec<f32> {
    v.flatten().collect()
}

impl MeshParts {
    /// Appends floats as an accessor of `kind` in a view of its own with no target (animation and skin
    /// data); with `bounds`, its min and max (which animation inputs must have). Returns its index.
    pub(super) fn floats(&mut self, values: &[f32], kind: &str, bounds: bool) -> usize {
        let per = match kind {
            "SCALAR" => 1,
            "VEC3" => 3,
            "VEC4" => 4,
            _ => 16,
        };
        super::pad4(&mut self.bin, 0);
        self.views.push(json!({"buffer": 0, "byteOffset": self.bin.len(), "byteLength": values.len() * 4}));
        self.bin.extend_from_slice(bytemuck::cast_slice(values));
        let mut a = json!({"bufferView": self.views.len() - 1, "componentType": 5126, "count": values.len() / per, "type": kind});
        if bounds {
            let (lo, hi) = values.iter().fold((f32::MAX, f32::MIN), |(l, h), &v| (l.min(v), h.max(v)));
            a["min"] = json!([lo]);
            a["max"] = json!([hi]);
        }
        self.accessors.push(a);
        self.accessors.len() - 1
    }

    /// Adds a mesh's skin weights and morph targets to its primitive's `attributes` and `targets`.
    pub(super) fn deformers(&mut self, d: &Deformers, attributes: &mut Value) -> Option<Value> {
        if let Some(skin) = &d.skin {
            let n = skin.len();
            let jv = self.view(bytemuck::cast_slice(skin.joints()), 34962);
            self.accessors.push(json!({"bufferView": jv, "componentType": 5123, "count": n, "type": "VEC4"}));
            attributes["JOINTS_0"] = json!(self.accessors.len() - 1);
            let wv = self.view(bytemuck::cast_slice(skin.weights()), 34962);
            self.accessors.push(json!({"bufferView": wv, "componentType": 5126, "count": n, "type": "VEC4"}));
            attributes["WEIGHTS_0"] = json!(self.accessors.len() - 1);
        }
        if d.morph_targets.is_empty() {
            return None;
        }
        let targets = d.morph_targets.iter().map(|t| {
            let b = Aabb::from_points(t.positions.iter().copied());
            let pv = self.view(bytemuck::cast_slice(&t.positions), 34962);
            let n = t.positions.len();
            let (min, max) = (b.min.to_array(), b.max.to_array());
            self.accessors.push(
                json!({"bufferView": pv, "componentType": 5126, "count": n, "type": "VEC3", "min": min, "max": max}),
            );
            let mut target = json!({"POSITION": self.accessors.len() - 1});
            if let Some(normals) = &t.normals {
                let nv = self.view(bytemuck::cast_slice::<Vec3, u8>(normals), 34962);
                self.accessors.push(json!({"bufferView": nv, "componentType": 5126, "count": n, "type": "VEC3"}));
                target["NORMAL"] = json!(self.accessors.len() - 1);
            }
            target
        });
        Some(json!(targets.collect::<Vec<_>>()))
    }
}
