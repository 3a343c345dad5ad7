//! glTF 2.0: `.gltf` with external or data-URI buffers, and `.glb`. The node hierarchy with matrices or
//! TRS; every triangle primitive (lists, strips, fans) with u8, u16, u32 or no indices; the base colour
//! factor and texture (PNG or JPEG, from a buffer view, a data URI or a file beside the model) with its
//! sampler, texture coordinates and `KHR_texture_transform`; the alpha mode and cutoff;
//! double-sidedness; perspective cameras and KHR_lights_punctual lights.
//!
//! The gltf crate parses and validates the JSON (index ranges, enum values). Everything that touches
//! bytes is done here, with bounds checks: the GLB container, buffer sources, and accessor reads (offsets,
//! strides, component types), so a short or lying file gives an error instead of a panic.

use std::collections::HashMap;
use std::path::Path;

use glam::{Mat4, Vec2, Vec3};
use gltf::accessor::{DataType, Dimensions};
use gltf::mesh::{Mode, Semantic};

use super::images::{self, ImageSource};
use super::{AssetError, AssetFault, LoadOptions, read_model, read_referenced};
use crate::material::{AlphaMode, Filter, Sampler, TextureRef, UvTransform, Wrap};
use crate::mesh::{MAX_COORDINATE, Mesh};
use crate::scene::{Camera, Light, LightKind, Material, MaterialKey, MeshKey, NodeKey, Scene};

type Fault = AssetFault;

pub(super) fn load(path: &Path, options: &LoadOptions) -> Result<Scene, AssetError> {
    parse(path, options).map_err(|f| AssetError::new(path, f))
}

/// The JSON and BIN chunks of a GLB container.
fn split_glb(bytes: &[u8]) -> Result<(&[u8], Option<&[u8]>), Fault> {
    let u32_at = |o: usize| -> Result<u32, Fault> {
        bytes
            .get(o..o + 4)
            .map(|b| u32::from_le_bytes([b[0], b[1], b[2], b[3]]))
            .ok_or_else(|| Fault::Truncated("GLB header or chunk header cut short".into()))
    };
    if u32_at(4)? != 2 {
        return Err(Fault::Unsupported(format!("GLB container version {}", u32_at(4)?)));
    }
    let total = u32_at(8)? as usize;
    if total > bytes.len() {
        return Err(Fault::Truncated(format!("GLB header says {total} bytes, the file has {}", bytes.len())));
    }
    let (mut json, mut bin, mut at) = (None, None, 12usize);
    while at + 8 <= total {
        let (len, kind) = (u32_at(at)? as usize, u32_at(at + 4)?);
        let data = bytes
            .get(at + 8..at + 8 + len)
            .ok_or_else(|| Fault::Truncated(format!("GLB chunk at byte {at} runs past the end")))?;
        match kind {
            0x4E4F_534A if json.is_none() => json = Some(data),
            0x004E_4942 if bin.is_none() => bin = Some(data),
            _ => {}
        }
        at += 8 + len;
    }
    Ok((json.ok_or_else(|| Fault::Malformed("GLB has no JSON chunk".into()))?, bin))
}

fn base64_decode(s: &str) -> Result<Vec<u8>, Fault> {
    let value = |c: u8| -> Result<u32, Fault> {
        Ok(match c {
            b'A'..=b'Z' => u32::from(c - b'A'),
            b'a'..=b'z' => u32::from(c - b'a') + 26,
            b'0'..=b'9' => u32::from(c - b'0') + 52,
            b'+' | b'-' => 62,
            b'/' | b'_' => 63,
            _ => return Err(Fault::Malformed(format!("'{}' in a base64 data URI", c as char))),
        })
    };
    let digits: Vec<u8> = s.bytes().filter(|&c| c != b'=' && !c.is_ascii_whitespace()).collect();
    let mut out = Vec::with_capacity(digits.len() * 3 / 4);
    for chunk in digits.chunks(4) {
        let mut acc = 0u32;
        for (i, &c) in chunk.iter().enumerate() {
            acc |= value(c)? << (18 - 6 * i);
        }
        let bytes = acc.to_be_bytes();
        out.extend_from_slice(&bytes[1..chunk.len()]);
    }
    Ok(out)
}

fn percent_decode(s: &str) -> String {
    let b = s.as_bytes();
    let hex = |c: u8| (c as char).to_digit(16);
    let mut out = Vec::with_capacity(b.len());
    let mut i = 0;
    while i < b.len() {
        if b[i] == b'%'
            && i + 2 < b.len()
            && let (Some(h), Some(l)) = (hex(b[i + 1]), hex(b[i + 2]))
        {
            out.push((h * 16 + l) as u8);
            i += 3;
            continue;
        }
        out.push(b[i]);
        i += 1;
    }
    String::from_utf8_lossy(&out).into_owned()
}

fn load_buffers(
    doc: &gltf::Document,
    dir: &Path,
    bin: Option<&[u8]>,
    options: &LoadOptions,
) -> Result<Vec<Vec<u8>>, Fault> {
    doc.buffers()
        .map(|b| {
            let what = format!("buffer {}", b.index());
            let data = match b.source() {
                gltf::buffer::Source::Bin => bin
                    .ok_or_else(|| Fault::Malformed(format!("{what} refers to a GLB BIN chunk that is missing")))?
                    .to_vec(),
                gltf::buffer::Source::Uri(uri) if uri.starts_with("data:") => {
                    let (_, payload) = uri
                        .split_once(";base64,")
                        .ok_or_else(|| Fault::Unsupported(format!("{what}: a data URI that is not base64")))?;
                    base64_decode(payload)?
                }
                // Never more than the buffer declares: a file may be longer (or endless) behind it.
                gltf::buffer::Source::Uri(uri) => {
                    read_referenced(dir, &percent_decode(uri), &what, Some(b.length() as u64), options)?
                }
            };
            if data.len() < b.length() {
                return Err(Fault::Truncated(format!(
                    "{what} holds {} bytes, the file declares {}",
                    data.len(),
                    b.length()
                )));
            }
            Ok(data)
        })
        .collect()
}

/// An accessor's elements as f64 components, bounds-checked against its view and buffer.
fn read_accessor(acc: &gltf::Accessor, buffers: &[Vec<u8>], what: &str) -> Result<Vec<[f64; 3]>, Fault> {
    if acc.sparse().is_some() {
        return Err(Fault::Unsupported(format!("sparse accessor {} ({what})", acc.index())));
    }
    let view = acc
        .view()
        .ok_or_else(|| Fault::Unsupported(format!("accessor {} ({what}) has no buffer view", acc.index())))?;
    let buffer = &buffers[view.buffer().index()];
    let view_end = view.offset().checked_add(view.length()).filter(|&e| e <= buffer.len()).ok_or_else(|| {
        Fault::Truncated(format!("buffer view {} runs past the end of buffer {}", view.index(), view.buffer().index()))
    })?;
    let view_bytes = &buffer[view.offset()..view_end];
    let comps = acc.dimensions().multiplicity();
    let csize = acc.data_type().size();
    let elem = comps * csize;
    let stride = view.stride().unwrap_or(elem);
    if stride < elem {
        return Err(Fault::Malformed(format!(
            "buffer view {} has stride {stride} below its element size {elem}",
            view.index()
        )));
    }
    let count = acc.count();
    if count > 0 {
        // Every later offset is below `need`, so once it fits nothing below can overflow.
        let need =
            (count - 1).checked_mul(stride).and_then(|n| n.checked_add(acc.offset())).and_then(|n| n.checked_add(elem));
        if need.is_none_or(|n| n > view_bytes.len()) {
            return Err(Fault::Truncated(format!(
                "accessor {} ({what}) reads past the end of buffer view {}",
                acc.index(),
                view.index()
            )));
        }
    }
    let norm = acc.normalized();
    let read = |o: usize| -> f64 {
        let b = &view_bytes[o..o + csize];
        match acc.data_type() {
            DataType::I8 => {
                let v = f64::from(b[0] as i8);
                if norm { (v / 127.0).max(-1.0) } else { v }
            }
            DataType::U8 => {
                let v = f64::from(b[0]);
                if norm { v / 255.0 } else { v }
            }
            DataType::I16 => {
                let v = f64::from(i16::from_le_bytes([b[0], b[1]]));
                if norm { (v / 32767.0).max(-1.0) } else { v }
            }
            DataType::U16 => {
                let v = f64::from(u16::from_le_bytes([b[0], b[1]]));
                if norm { v / 65535.0 } else { v }
            }
            DataType::U32 => f64::from(u32::from_le_bytes([b[0], b[1], b[2], b[3]])),
            DataType::F32 => f64::from(f32::from_le_bytes([b[0], b[1], b[2], b[3]])),
        }
    };
    Ok((0..count)
        .map(|i| {
            let base = acc.offset() + i * stride;
            let mut e = [0.0; 3];
            for (c, slot) in e.iter_mut().enumerate().take(comps.min(3)) {
                *slot = read(base + c * csize);
            }
            e
        })
        .collect())
}

fn read_vec3(acc: &gltf::Accessor, buffers: &[Vec<u8>], what: &str) -> Result<Vec<Vec3>, Fault> {
    if acc.dimensions() != Dimensions::Vec3 || acc.data_type() != DataType::F32 {
        return Err(Fault::WrongAccessor(format!(
            "{what} accessor {} is {:?} of {:?}, expected Vec3 of F32",
            acc.index(),
            acc.dimensions(),
            acc.data_type()
        )));
    }
    Ok(read_accessor(acc, buffers, what)?.iter().map(|e| Vec3::new(e[0] as f32, e[1] as f32, e[2] as f32)).collect())
}

/// Texture coordinates: float pairs, or normalized unsigned bytes or shorts (glTF 2.0 3.7.2.1).
fn read_uvs(acc: &gltf::Accessor, buffers: &[Vec<u8>], what: &str) -> Result<Vec<Vec2>, Fault> {
    let float = acc.data_type() == DataType::F32;
    let normalized = acc.normalized() && matches!(acc.data_type(), DataType::U8 | DataType::U16);
    if acc.dimensions() != Dimensions::Vec2 || !(float || normalized) {
        return Err(Fault::WrongAccessor(format!(
            "{what} accessor {} is {:?} of {:?}{}, expected Vec2 of F32 or of normalized U8 or U16",
            acc.index(),
            acc.dimensions(),
            acc.data_type(),
            if acc.normalized() { " (normalized)" } else { "" }
        )));
    }
    Ok(read_accessor(acc, buffers, what)?.iter().map(|e| Vec2::new(e[0] as f32, e[1] as f32)).collect())
}

fn read_indices(acc: &gltf::Accessor, buffers: &[Vec<u8>]) -> Result<Vec<u32>, Fault> {
    if acc.dimensions() != Dimensions::Scalar
        || !matches!(acc.data_type(), DataType::U8 | DataType::U16 | DataType::U32)
    {
        return Err(Fault::WrongAccessor(format!(
            "index accessor {} is {:?} of {:?}, expected Scalar of U8, U16 or U32",
            acc.index(),
            acc.dimensions(),
            acc.data_type()
        )));
    }
    Ok(read_accessor(acc, buffers, "indices")?.iter().map(|e| e[0] as u32).collect())
}

/// Triangles of a primitive from its index list (or 0..n without indices).
fn assemble(mode: Mode, idx: &[u32]) -> Vec<[u32; 3]> {
    match mode {
        Mode::Triangles => idx.chunks_exact(3).map(|t| [t[0], t[1], t[2]]).collect(),
        // Strips alternate winding so every triangle keeps the first one's orientation.
        Mode::TriangleStrip => (2..idx.len())
            .map(|i| if i % 2 == 0 { [idx[i - 2], idx[i - 1], idx[i]] } else { [idx[i - 1], idx[i - 2], idx[i]] })
            .filter(|t| t[0] != t[1] && t[1] != t[2] && t[0] != t[2])
            .collect(),
        Mode::TriangleFan => (2..idx.len()).map(|i| [idx[0], idx[i - 1], idx[i]]).collect(),
        Mode::Points | Mode::Lines | Mode::LineLoop | Mode::LineStrip => Vec::new(),
    }
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
                m = m.with_uvs(uvs).map_err(|e| Fault::Mesh(what, e))?;
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
