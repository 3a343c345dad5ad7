//! glTF 2.0: `.gltf` with external or data-URI buffers, and `.glb`. The node hierarchy with matrices or
//! TRS; every triangle primitive (lists, strips, fans) with u8, u16, u32 or no indices; the base colour
//! factor and texture (PNG or JPEG, from a buffer view, a data URI or a file beside the model) with its
//! sampler, texture coordinates and `KHR_texture_transform`; the alpha mode and cutoff;
//! double-sidedness; perspective cameras and KHR_lights_punctual lights; skins (`JOINTS_0`/`WEIGHTS_0`,
//! joints and inverse bind matrices) and morph targets (positions and normals) with their weights; and
//! animations of nodes' translation, rotation, scale and morph weights.
//!
//! The gltf crate parses and validates the JSON (index ranges, enum values). Everything that touches
//! bytes is done here, with bounds checks: the GLB container, buffer sources, and accessor reads (offsets,
//! strides, component types), so a short or lying file gives an error instead of a panic.

use std::collections::HashMap;
use std::path::Path;

use glam::{Mat4, Vec2, Vec3};
use gltf::mesh::{Mode, Semantic};

use super::images::{self, ImageSource};
use super::{AssetError, AssetFault, LoadOptions, read_model};
use crate::material::{AlphaMode, Filter, Sampler, TextureRef, UvTransform, Wrap};
use crate::mesh::{MAX_COORDINATE, Mesh};
use crate::scene::{Camera, Light, LightKind, Material, MaterialKey, MeshKey, NodeKey, Scene};

mod animation;
mod bytes;
mod skin;

use bytes::{assemble, base64_decode, load_buffers, percent_decode, read_indices, read_uvs, read_vec3, split_glb};

type Fault = AssetFault;

pub(super) fn load(path: &Path, options: &LoadOptions) -> Result<Scene, AssetError> {
    parse(path, options).map_err(|f| AssetError::new(path, f))
}

fn check_required_extensions(root: &gltf::json::Root) -> Result<(), Fault> {
    for ext in &root.extensions_required {
        let what = match ext.as_str() {
            "KHR_draco_mesh_compression" => "Draco mesh compression (KHR_draco_mesh_compression)".to_string(),
            "EXT_meshopt_compression" | "KHR_meshopt_compression" => format!("meshopt compression ({ext})"),
            "KHR_lights_punctual"
            | "KHR_materials_unlit"
            | "KHR_texture_transform"
            | "KHR_materials_emissive_strength" => continue,
            other => format!("required extension {other}"),
        };
        return Err(Fault::Unsupported(what));
    }
    Ok(())
}

/// A scene material and the texture-coordinate set its texture reads, if it has one.
#[derive(Clone, Copy)]
struct LoadedMaterial {
    key: MaterialKey,
    uv_set: Option<u32>,
}

/// A material's base-colour texture, waiting for its image to be decoded with all the others.
struct PendingTexture {
    material: MaterialKey,
    image: usize,
    sampler: Sampler,
    transform: UvTransform,
}

struct Loader<'a> {
    buffers: Vec<Vec<u8>>,
    scene: Scene,
    meshes: HashMap<(usize, usize), (MeshKey, MaterialKey)>,
    materials: HashMap<Option<usize>, LoadedMaterial>,
    /// Textures of the materials made so far, in the order they were made.
    pending: Vec<PendingTexture>,
    doc: &'a gltf::Document,
    dir: &'a Path,
    options: &'a LoadOptions,
    triangles: usize,
    /// The scene node of each glTF node the scene holds.
    node_keys: Vec<Option<NodeKey>>,
    /// The scene nodes that draw each glTF node's mesh primitives, in order.
    primitive_nodes: Vec<Vec<NodeKey>>,
}

impl Loader<'_> {
    fn material(&mut self, m: &gltf::Material) -> Result<LoadedMaterial, Fault> {
        if let Some(&loaded) = self.materials.get(&m.index()) {
            return Ok(loaded);
        }
        let pbr = m.pbr_metallic_roughness();
        let c = pbr.base_color_factor();
        let name =
            m.name().map_or_else(|| m.index().map_or("default".into(), |i| format!("material {i}")), str::to_string);
        let alpha_mode = match m.alpha_mode() {
            gltf::material::AlphaMode::Opaque => AlphaMode::Opaque,
            gltf::material::AlphaMode::Mask => {
                AlphaMode::Mask { cutoff: m.alpha_cutoff().unwrap_or(AlphaMode::DEFAULT_CUTOFF) }
            }
            gltf::material::AlphaMode::Blend => AlphaMode::Blend,
        };
        if let AlphaMode::Mask { cutoff } = alpha_mode
            && !(cutoff >= 0.0 && cutoff.is_finite())
        {
            return Err(Fault::Malformed(format!("material '{name}' has alphaCutoff {cutoff}, expected 0 or more")));
        }
        let key = self.scene.add_material(Material {
            alpha: c[3],
            alpha_mode,
            two_sided: m.double_sided(),
            cull_back_faces: !m.double_sided(),
            ..Material::colored(&name, Vec3::new(c[0], c[1], c[2]))
        });
        let mut uv_set = None;
        if let Some(info) = pbr.base_color_texture() {
            let transform = info.texture_transform();
            let texture = info.texture();
            uv_set = Some(transform.as_ref().and_then(|t| t.tex_coord()).unwrap_or(info.tex_coord()));
            self.pending.push(PendingTexture {
                material: key,
                image: texture.source().index(),
                sampler: sampler(&texture.sampler()),
                transform: transform.map_or(UvTransform::IDENTITY, |t| UvTransform {
                    offset: Vec2::from(t.offset()),
                    rotation: t.rotation(),
                    scale: Vec2::from(t.scale()),
                }),
            });
        }
        let loaded = LoadedMaterial { key, uv_set };
        self.materials.insert(m.index(), loaded);
        Ok(loaded)
    }

    /// Decodes the images the materials read, each once and all in parallel, and gives each material
    /// its texture. An image that cannot be used leaves its materials untextured, with one warning that
    /// names the image, the materials and what is wrong.
    fn finish_textures(&mut self) -> Result<(), Fault> {
        let mut images: Vec<usize> = Vec::new();
        for p in &self.pending {
            if !images.contains(&p.image) {
                images.push(p.image);
            }
        }
        let doc_images: Vec<gltf::Image> = self.doc.images().collect();
        let sources = images.iter().map(|&i| self.image_source(&doc_images[i])).collect::<Result<Vec<_>, Fault>>()?;
        let labels: Vec<String> = sources.iter().map(|s| s.label.clone()).collect();
        let decoded = images::decode_all(sources, &self.options.textures);
        for ((image, label), texture) in images.iter().zip(labels).zip(decoded) {
            let users = self.pending.iter().filter(|p| p.image == *image);
            match texture {
                Ok(texture) => {
                    let key = self.scene.add_texture(texture);
                    for p in users {
                        let r = TextureRef { texture: key, sampler: p.sampler, transform: p.transform };
                        if let Some(m) = self.scene.material_mut(p.material) {
                            m.base_color_texture = Some(r);
                        }
                    }
                }
                Err(why) => {
                    let names: Vec<String> = users
                        .filter_map(|p| self.scene.material(p.material))
                        .map(|m| format!("'{}'", m.name))
                        .collect();
                    let (noun, verb) = if names.len() == 1 { ("material", "is") } else { ("materials", "are") };
                    let names = names.join(", ");
                    self.scene.add_warning(format!("{label}: {why}; {noun} {names} {verb} drawn without it"));
                }
            }
        }
        Ok(())
    }

    /// An image's bytes: from a buffer view, a data URI, or a file the model may read. A file it may not
    /// read refuses the model, as a buffer would; one that cannot be read is a bad image like any other.
    fn image_source(&self, image: &gltf::Image) -> Result<ImageSource, Fault> {
        // Told by its index, and by its name where the model gives one (a file also by its path).
        let what = format!("image {}", image.index());
        let (label, name) = match image.name() {
            Some(name) => (format!("{what} '{name}'"), name.to_string()),
            None => (what.clone(), what.clone()),
        };
        Ok(match image.source() {
            gltf::image::Source::View { view, .. } => {
                let buffer = &self.buffers[view.buffer().index()];
                let bytes = view.offset().checked_add(view.length()).and_then(|end| buffer.get(view.offset()..end));
                let bytes = bytes.ok_or_else(|| {
                    Fault::Truncated(format!("{what}: buffer view {} runs past the end of its buffer", view.index()))
                })?;
                ImageSource { label, name, bytes: Ok(bytes.to_vec()) }
            }
            gltf::image::Source::Uri { uri, .. } if uri.starts_with("data:") => {
                let bytes = match uri.split_once(";base64,") {
                    Some((_, payload)) => base64_decode(payload).map_err(|f| f.to_string()),
                    None => Err("a data URI that is not base64".to_string()),
                };
                ImageSource { label, name, bytes }
            }
            gltf::image::Source::Uri { uri, .. } => {
                let file = percent_decode(uri);
                let bytes = images::read_image_file(self.dir, &file, &what, self.options)?;
                let name = image.name().map_or_else(|| file.clone(), str::to_string);
                ImageSource { label: format!("{label} ('{file}')"), name, bytes }
            }
        })
    }

    /// The scene meshes of a glTF mesh: one per triangle primitive, shared by every node that uses it.
    fn primitives(&mut self, mesh: &gltf::Mesh) -> Result<Vec<(MeshKey, MaterialKey)>, Fault> {
        let mut out = Vec::new();
        for prim in mesh.primitives() {
            let id = (mesh.index(), prim.index());
            if let Some(&k) = self.meshes.get(&id) {
                out.push(k);
                continue;
            }
            if matches!(prim.mode(), Mode::Points | Mode::Lines | Mode::LineLoop | Mode::LineStrip) {
                continue;
            }
            let what = format!("mesh {} primitive {}", mesh.index(), prim.index());
            let pos_acc =
                prim.get(&Semantic::Positions).ok_or_else(|| Fault::Malformed(format!("{what} has no POSITION")))?;
            let positions = read_vec3(&pos_acc, &self.buffers, "POSITION")?;
            let idx = match prim.indices() {
                Some(a) => read_indices(&a, &self.buffers)?,
                None => (0..positions.len() as u32).collect(),
            };
            let triangles = assemble(prim.mode(), &idx);
            self.triangles += triangles.len();
            let mesh_result = match prim.get(&Semantic::Normals) {
                Some(n) => {
                    let normals = read_vec3(&n, &self.buffers, "NORMAL")?;
                    Mesh::with_normals(positions, normals, triangles)
                }
                None => Mesh::new(positions, triangles),
            };
            let mut m = mesh_result.map_err(|e| Fault::Mesh(what.clone(), e))?;
            let mat = self.material(&prim.material())?;
            if let Some(set) = mat.uv_set {
                let acc = prim.get(&Semantic::TexCoords(set)).ok_or_else(|| {
                    Fault::Malformed(format!(
                        "{what}: its material's texture reads TEXCOORD_{set}, which it does not have"
                    ))
                })?;
                let uvs = read_uvs(&acc, &self.buffers, &format!("TEXCOORD_{set}"))?;
                m = m.with_uvs(uvs).map_err(|e| Fault::Mesh(what.clone(), e))?;
            }
            if let Some(deformers) = self.deformers(&prim, &what)? {
                m = m.with_deformers(deformers).map_err(|e| Fault::Mesh(what, e))?;
            }
            let key = (self.scene.add_mesh(m), mat.key);
            self.meshes.insert(id, key);
            out.push(key);
        }
        Ok(out)
    }

    /// Adds the scene's nodes depth-first from `roots`, without recursion (a chain of nodes may be as deep
    /// as the file is long). A node met again is a cycle when it is on the path from its root, and a node
    /// with two parents otherwise.
    fn walk(&mut self, roots: &[usize]) -> Result<(), Fault> {
        enum Step {
            Enter(usize, Option<NodeKey>, Mat4),
            Leave(usize),
        }
        let nodes: Vec<gltf::Node> = self.doc.nodes().collect();
        let count = nodes.len();
        let (mut seen, mut on_path) = (vec![false; count], vec![false; count]);
        let mut stack: Vec<Step> = roots.iter().rev().map(|&r| Step::Enter(r, None, Mat4::IDENTITY)).collect();
        while let Some(step) = stack.pop() {
            let (index, parent, parent_world) = match step {
                Step::Enter(i, p, w) => (i, p, w),
                Step::Leave(i) => {
                    on_path[i] = false;
                    continue;
                }
            };
            if on_path[index] {
                return Err(Fault::Cycle(format!("node {index} is its own ancestor")));
            }
            if std::mem::replace(&mut seen[index], true) {
                return Err(Fault::Cycle(format!("node {index} has more than one parent")));
            }
            let node = nodes.get(index).ok_or_else(|| Fault::Malformed(format!("node {index} does not exist")))?;
            let (key, world) = self.node(node, parent, parent_world)?;
            self.node_keys[index] = Some(key);
            on_path[index] = true;
            stack.push(Step::Leave(index));
            let children: Vec<usize> = node.children().map(|c| c.index()).collect();
            stack.extend(children.into_iter().rev().map(|c| Step::Enter(c, Some(key), world)));
        }
        Ok(())
    }

    /// Adds one node under `parent`: its mesh's primitives, camera and light. Returns its key and world
    /// transform.
    fn node(
        &mut self,
        node: &gltf::Node,
        parent: Option<NodeKey>,
        parent_world: Mat4,
    ) -> Result<(NodeKey, Mat4), Fault> {
        let index = node.index();
        let local = Mat4::from_cols_array_2d(&node.transform().matrix());
        if !local.is_finite() {
            return Err(Fault::Malformed(format!("node {index} has a non-finite transform")));
        }
        // glTF node matrices are decomposable into translation, rotation and scale, so affine.
        if local.row(3) != glam::Vec4::W {
            return Err(Fault::Malformed(format!("node {index} has a matrix whose last row is not 0 0 0 1")));
        }
        let name = node.name().map_or_else(|| format!("node {index}"), str::to_string);
        let key = self.scene.add_node(&name, parent, local).map_err(|e| Fault::Malformed(e.to_string()))?;
        let world = parent_world * local;
        if let Some(mesh) = node.mesh() {
            let prims = self.primitives(&mesh)?;
            for (i, p) in prims.into_iter().enumerate() {
                let what = format!("mesh {} primitive {i}", mesh.index());
                check_world(&self.scene, p.0, world)
                    .map_err(|why| Fault::Malformed(format!("node {index}: {what} {why}")))?;
                // A node holds one mesh; extra primitives hang below it as children at the same place.
                let target = if i == 0 {
                    key
                } else {
                    self.scene
                        .add_node(&format!("{name} #{i}"), Some(key), Mat4::IDENTITY)
                        .map_err(|e| Fault::Malformed(e.to_string()))?
                };
                self.scene.set_mesh(target, Some(p)).map_err(|e| Fault::Malformed(e.to_string()))?;
                self.primitive_nodes[index].push(target);
            }
        }
        self.camera_and_light(node, key, world);
        Ok((key, world))
    }

    /// The node's perspective camera and KHR punctual light, following the node: both look down the node's
    /// -Z with +Y up, from its origin. Placed by `world`, they are checked once where the file puts them.
    fn camera_and_light(&mut self, node: &gltf::Node, key: NodeKey, world: Mat4) {
        let (origin, forward) = (Vec3::ZERO, Vec3::NEG_Z);
        if let Some(cam) = node.camera()
            && let gltf::camera::Projection::Perspective(p) = cam.projection()
        {
            let camera =
                Camera { eye: origin, target: forward, up: Vec3::Y, fov_y: p.yfov(), near: p.znear().max(1e-4) };
            if camera.transformed(world).validate().is_ok() {
                let _ = self.scene.add_camera_to(key, camera);
            }
        }
        if let Some(l) = node.light() {
            use gltf::khr_lights_punctual::Kind;
            // glTF cone angles are half-angles; ours are full apex angles.
            let (kind, inner_cone_angle) = match l.kind() {
                Kind::Directional => (LightKind::Directional { direction: forward }, None),
                Kind::Point => (LightKind::Point { position: origin }, None),
                Kind::Spot { inner_cone_angle, outer_cone_angle } => {
                    let cone_angle = (2.0 * outer_cone_angle).clamp(1e-3, 3.1);
                    let inner = (2.0 * inner_cone_angle).clamp(0.0, cone_angle * 0.999);
                    (LightKind::Spot { position: origin, direction: forward, cone_angle }, Some(inner))
                }
            };
            // The light's radius is for soft shadows, which glTF does not describe: the default.
            let range = l.range().filter(|_| !matches!(kind, LightKind::Directional { .. }));
            let light = Light {
                kind,
                color: Vec3::from(l.color()),
                intensity: l.intensity(),
                inner_cone_angle,
                range,
                ..Light::point(origin)
            };
            if light.transformed(world).validate().is_ok() {
                let _ = self.scene.add_light_to(key, light);
            }
        }
    }
}

/// A glTF sampler as ours. Without a minification filter glTF leaves the choice to the renderer:
/// trilinear, as without a sampler.
fn sampler(s: &gltf::texture::Sampler) -> Sampler {
    use gltf::texture::{MagFilter, MinFilter, WrappingMode};
    let wrap = |w| match w {
        WrappingMode::ClampToEdge => Wrap::ClampToEdge,
        WrappingMode::MirroredRepeat => Wrap::MirroredRepeat,
        WrappingMode::Repeat => Wrap::Repeat,
    };
    let mag = if s.mag_filter() == Some(MagFilter::Nearest) { Filter::Nearest } else { Filter::Linear };
    let (min, mipmap) = match s.min_filter() {
        None | Some(MinFilter::LinearMipmapLinear) => (Filter::Linear, Some(Filter::Linear)),
        Some(MinFilter::Nearest) => (Filter::Nearest, None),
        Some(MinFilter::Linear) => (Filter::Linear, None),
        Some(MinFilter::NearestMipmapNearest) => (Filter::Nearest, Some(Filter::Nearest)),
        Some(MinFilter::LinearMipmapNearest) => (Filter::Linear, Some(Filter::Nearest)),
        Some(MinFilter::NearestMipmapLinear) => (Filter::Nearest, Some(Filter::Linear)),
    };
    Sampler { mag, min, mipmap, wrap_u: wrap(s.wrap_s()), wrap_v: wrap(s.wrap_t()) }
}

/// Checks that a mesh placed by `world` stays inside f32 geometry and keeps some area: the mesh's own
/// checks ran on its local positions, and a transform can overflow them (a huge translation, nested
/// huge scales) or flatten every triangle (a zero scale). The corners of the local bounds bound the
/// placed positions, since the transform is affine.
fn check_world(scene: &Scene, mesh: MeshKey, world: Mat4) -> Result<(), String> {
    let Some(mesh) = scene.mesh(mesh) else { return Ok(()) };
    if !world.is_finite() {
        return Err("has a world transform that overflows f32".into());
    }
    let b = mesh.bounds();
    let reach = (0..8)
        .map(|i| {
            let corner = Vec3::new(
                if i & 1 == 0 { b.min.x } else { b.max.x },
                if i & 2 == 0 { b.min.y } else { b.max.y },
                if i & 4 == 0 { b.min.z } else { b.max.z },
            );
            world.transform_point3(corner).abs().max_element()
        })
        .fold(0.0f32, |m, r| if r.is_nan() { f32::INFINITY } else { m.max(r) });
    if reach > MAX_COORDINATE {
        return Err(format!("reaches {reach:e} in world space, beyond +-{MAX_COORDINATE:e}"));
    }
    let p = |i: u32| world.transform_point3(mesh.positions()[i as usize]);
    let has_area = mesh.triangles().iter().any(|&[a, b, c]| (p(b) - p(a)).cross(p(c) - p(a)).length_squared() > 0.0);
    if !has_area {
        return Err(format!("has zero area in world space (all {} triangles degenerate)", mesh.triangle_count()));
    }
    Ok(())
}

/// Refuses attributes and indices that name accessors the file does not have, before the gltf crate
/// validates (it indexes the POSITION accessor unchecked to look at its bounds).
fn check_accessor_indices(root: &gltf::json::Root) -> Result<(), Fault> {
    let n = root.accessors.len();
    for (m, mesh) in root.meshes.iter().enumerate() {
        for (p, prim) in mesh.primitives.iter().enumerate() {
            let named = prim.attributes.iter().map(|(semantic, a)| (format!("{semantic:?}"), a.value()));
            let indices = prim.indices.iter().map(|a| ("indices".to_string(), a.value()));
            if let Some((what, a)) = named.chain(indices).find(|&(_, a)| a >= n) {
                return Err(Fault::Malformed(format!(
                    "mesh {m} primitive {p}: {what} names accessor {a}, but the file has {n}"
                )));
            }
        }
    }
    Ok(())
}

fn parse(path: &Path, options: &LoadOptions) -> Result<Scene, Fault> {
    let bytes = read_model(path)?;
    let (json, bin) = if bytes.starts_with(b"glTF") { split_glb(&bytes)? } else { (bytes.as_slice(), None) };
    let root: gltf::json::Root =
        gltf::json::deserialize::from_slice(json).map_err(|e| Fault::Malformed(format!("JSON: {e}")))?;
    check_required_extensions(&root)?;
    check_accessor_indices(&root)?;
    let doc = match gltf::Document::from_json(root.clone()) {
        Ok(doc) => doc,
        Err(gltf::Error::Validation(errs)) => {
            // POSITION min/max are required by the spec but many exporters leave them out; the loader
            // computes bounds itself, so only that omission is forgiven.
            let errs: Vec<_> = errs
                .into_iter()
                .filter(|(p, _)| {
                    !(p.as_str().contains("POSITION") && (p.as_str().ends_with(".min") || p.as_str().ends_with(".max")))
                })
                .collect();
            if let Some((p, e)) = errs.first() {
                return Err(Fault::Malformed(format!("{} validation error(s), first: {p}: {e}", errs.len())));
            }
            gltf::Document::from_json_without_validation(root)
        }
        Err(other) => return Err(Fault::Malformed(other.to_string())),
    };
    let dir = path.parent().unwrap_or(Path::new("."));
    let buffers = load_buffers(&doc, dir, bin, options)?;
    let mut loader = Loader {
        buffers,
        scene: Scene::new(),
        meshes: HashMap::new(),
        materials: HashMap::new(),
        pending: Vec::new(),
        doc: &doc,
        dir,
        options,
        triangles: 0,
        node_keys: vec![None; doc.nodes().len()],
        primitive_nodes: vec![Vec::new(); doc.nodes().len()],
    };
    let roots: Vec<usize> = match doc.default_scene().or_else(|| doc.scenes().next()) {
        Some(s) => s.nodes().map(|n| n.index()).collect(),
        None => {
            // No scene: every node that is nobody's child is a root.
            let mut is_child = vec![false; doc.nodes().len()];
            for c in doc.nodes().flat_map(|n| n.children()) {
                is_child[c.index()] = true;
            }
            (0..is_child.len()).filter(|&i| !is_child[i]).collect()
        }
    };
    if roots.is_empty() && doc.nodes().len() > 0 {
        return Err(Fault::Cycle("every node is some node's child, so there is no root".into()));
    }
    loader.walk(&roots)?;
    loader.skins_and_weights()?;
    loader.animations()?;
    loader.finish_textures()?;
    if loader.triangles == 0 {
        let any_prims = doc.meshes().any(|m| m.primitives().len() > 0);
        return Err(if any_prims {
            Fault::Unsupported("only points or lines primitives, no triangles".into())
        } else {
            Fault::Unsupported("no meshes in the default scene".into())
        });
    }
    Ok(loader.scene)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn base64_and_percent() {
        assert_eq!(base64_decode("SGVsbG8=").unwrap(), b"Hello");
        assert_eq!(base64_decode("AAEC").unwrap(), vec![0, 1, 2]);
        assert!(base64_decode("A*").is_err());
        assert_eq!(percent_decode("a%20b.bin"), "a b.bin");
    }

    #[test]
    fn strips_keep_winding() {
        let t = assemble(Mode::TriangleStrip, &[0, 1, 2, 3]);
        assert_eq!(t, vec![[0, 1, 2], [2, 1, 3]]);
        assert_eq!(assemble(Mode::TriangleFan, &[0, 1, 2, 3]), vec![[0, 1, 2], [0, 2, 3]]);
    }
}
