//! Generators of structurally hostile model files: each builds a file that follows its format's shape
//! (so the loader gets past the first byte) with counts, indices, offsets, references, node graphs and
//! numbers drawn from the values a loader must guard, then sometimes damages the bytes as well.

use serde_json::{Value, json};

use crate::rng::Rng;

/// One generated input: the model's file name and every file of the case (the model first).
pub struct Case {
    /// Files to write into the case folder, the model first.
    pub files: Vec<(String, Vec<u8>)>,
    /// True when the model names a file outside its folder: it must not load under the default access.
    pub names_outside: bool,
}

/// Paths a model may name, inside and outside its folder. The case folder holds `side.bin`/`side.mtl`;
/// its parent holds `outside.bin`/`outside.mtl`.
const INSIDE: &[&str] = &["side", "./side", "sub/../side", "missing"];
const OUTSIDE: &[&str] = &["../outside", "%2e%2e/outside", "sub/../../outside", "/etc/hostname#", "/dev/zero#"];

/// A path (with `ext` appended unless the entry ends in '#') and whether it leaves the folder.
fn reference(r: &mut Rng, ext: &str) -> (String, bool) {
    if !r.hostile() {
        return (format!("side.{ext}"), false);
    }
    let outside = r.chance(0.5);
    let raw = *r.pick(if outside { OUTSIDE } else { INSIDE });
    let path = raw.strip_suffix('#').map_or_else(|| format!("{raw}.{ext}"), str::to_string);
    (path, outside)
}

fn floats(r: &mut Rng, n: usize) -> Vec<u8> {
    (0..n)
        .flat_map(|_| {
            let v: f32 = match if r.hostile() { r.below(4) } else { 4 } {
                0 => f32::NAN,
                1 => f32::INFINITY,
                2 => 1e38,
                3 => 1e-40,
                _ => (r.below(2000) as f32 - 1000.0) / 100.0,
            };
            v.to_le_bytes()
        })
        .collect()
}

// ---- OBJ with its material library ----

pub fn obj(r: &mut Rng) -> Case {
    let mut text = String::new();
    let vertices = r.count(40).min(3000);
    let (lib, _) = reference(r, "mtl");
    if r.chance(0.7) {
        text.push_str(&format!("mtllib {lib}\n"));
    }
    // The vertices the faces index, then every kind of line in any order.
    for _ in 0..vertices {
        text.push_str(&format!("v {} {} {}\n", r.number(), r.number(), r.number()));
    }
    let lines = r.count(80).min(6000);
    for _ in 0..lines {
        let line = match r.below(14) {
            0..=3 => {
                let n = if r.hostile() { *r.pick(&[4, 6, 2, 5, 7]) } else { 3 };
                format!("v {}", (0..n).map(|_| r.number()).collect::<Vec<_>>().join(" "))
            }
            4 => format!("vn {} {} {}", r.number(), r.number(), r.number()),
            5 => format!("vt {} {}", r.number(), r.number()),
            6..=8 => {
                let corners = if r.hostile() { *r.pick(&[2, 1, 12]) } else { *r.pick(&[3, 3, 4, 5]) };
                let c: Vec<String> = (0..corners)
                    .map(|_| match if r.hostile() { r.below(6) } else { 5 } {
                        0 => format!("{}/{}", r.index(vertices), r.index(vertices)),
                        1 => format!("{}//{}", r.index(vertices), r.index(vertices)),
                        2 => format!("{}/{}/{}", r.index(vertices), r.index(vertices), r.index(vertices)),
                        3 if r.chance(0.1) => "x/".into(),
                        _ => r.index(vertices).to_string(),
                    })
                    .collect();
                format!("f {}", c.join(" "))
            }
            9 => format!("l {} {}", r.index(vertices), r.index(vertices)),
            10 => format!("p {}", r.index(vertices)),
            11 => format!("{} part{}", r.pick(&["o", "g"]), r.below(100)),
            12 if r.hostile() => format!("usemtl {}", r.pick(&["", "nope"])),
            12 => format!("usemtl {}", r.pick(&["red", "blue"])),
            _ if r.hostile() => (*r.pick(&["vp 1 2", "mtllib", "usemtl", "f", "v"])).to_string(),
            _ => (*r.pick(&["# comment", "s off", ""])).to_string(),
        };
        text.push_str(&line);
        text.push('\n');
    }
    let mut model = text.into_bytes();
    r.damage(&mut model);
    Case { files: vec![("m.obj".into(), model), ("side.mtl".into(), mtl(r))], names_outside: false }
}

fn mtl(r: &mut Rng) -> Vec<u8> {
    let mut text = String::new();
    for _ in 0..r.count(12).min(200) {
        let line = match r.below(6) {
            0 => format!("newmtl {}", if r.hostile() { "" } else { r.pick(&["red", "blue"]) }),
            1..=3 => {
                let n = if r.hostile() { *r.pick(&[2, 1, 0, 4]) } else { 3 };
                format!(
                    "{} {}",
                    r.pick(&["Kd", "Ka", "Ks", "Ke"]),
                    (0..n).map(|_| r.number()).collect::<Vec<_>>().join(" ")
                )
            }
            4 => format!("{} {}", r.pick(&["Ns", "Ni", "d", "illum"]), r.number()),
            _ => (*r.pick(&["map_Kd", "map_Kd /etc/passwd", "bump", "# x"])).to_string(),
        };
        text.push_str(&line);
        text.push('\n');
    }
    let mut bytes = text.into_bytes();
    r.damage(&mut bytes);
    bytes
}

// ---- PLY, ASCII and binary, and gzipped ----

const PLY_TYPES: &[&str] = &["char", "uchar", "short", "ushort", "int", "uint", "float", "double", "int8", "float32"];

fn ply_size(t: &str) -> usize {
    match t {
        "char" | "uchar" | "int8" => 1,
        "short" | "ushort" => 2,
        "double" => 8,
        _ => 4,
    }
}

/// A value of a PLY type in the file's encoding.
fn ply_value(r: &mut Rng, t: &str, encoding: &str, value: f64, out: &mut Vec<u8>) {
    if encoding == "ascii" {
        let text = if r.chance(0.02) { r.number() } else { format!("{value}") };
        out.extend_from_slice(text.as_bytes());
        out.push(b' ');
        return;
    }
    let mut bytes: Vec<u8> = match t {
        "char" | "int8" => vec![value as i8 as u8],
        "uchar" => vec![value as u8],
        "short" => (value as i16).to_le_bytes().to_vec(),
        "ushort" => (value as u16).to_le_bytes().to_vec(),
        "int" => (value as i32).to_le_bytes().to_vec(),
        "uint" => (value as u32).to_le_bytes().to_vec(),
        "double" => value.to_le_bytes().to_vec(),
        _ => (value as f32).to_le_bytes().to_vec(),
    };
    debug_assert_eq!(bytes.len(), ply_size(t));
    if encoding == "binary_big_endian" {
        bytes.reverse();
    }
    out.extend_from_slice(&bytes);
}

pub fn ply(r: &mut Rng) -> Case {
    let encoding = if r.hostile() {
        "binary_middle_endian"
    } else {
        *r.pick(&["ascii", "binary_little_endian", "binary_big_endian"])
    };
    let vertices = r.count(30).min(3000);
    let faces = r.count(30).min(3000);
    let pos_t = if r.hostile() { *r.pick(PLY_TYPES) } else { *r.pick(&["float", "double", "float32"]) };
    let (count_t, item_t) = if r.hostile() {
        (*r.pick(&["char", "float", "short"]), *r.pick(&["short", "float", "uchar"]))
    } else {
        (*r.pick(&["uchar", "int", "uint"]), *r.pick(&["int", "uint"]))
    };
    let face_element = if r.hostile() { "edge" } else { *r.pick(&["face", "face", "tristrips"]) };
    let declared_v = if r.hostile() { r.count(1 << 20) } else { vertices };
    let declared_f = if r.hostile() { r.count(1 << 20) } else { faces };
    let normals = r.chance(0.3);
    let mut header = format!("ply\nformat {encoding} 1.0\ncomment fuzz\nelement vertex {declared_v}\n");
    for axis in ["x", "y", "z"] {
        if !r.hostile() {
            header.push_str(&format!("property {pos_t} {axis}\n"));
        }
    }
    if normals {
        for axis in ["nx", "ny", "nz"] {
            header.push_str(&format!("property float {axis}\n"));
        }
    }
    header.push_str(&format!(
        "element {face_element} {declared_f}\nproperty list {count_t} {item_t} {}\n",
        if r.hostile() { "indices" } else { *r.pick(&["vertex_indices", "vertex_index"]) }
    ));
    if r.hostile() {
        header.push_str(&format!("{}\n", r.pick(&["property", "element", "property list int", "end", "format ascii"])));
    }
    header.push_str("end_header\n");
    let mut bytes = header.into_bytes();
    for _ in 0..vertices {
        for _ in 0..3 + 3 * usize::from(normals) {
            let v = if r.hostile() { 1e30 } else { (r.below(2000) as f64 - 1000.0) / 100.0 };
            ply_value(r, pos_t, encoding, v, &mut bytes);
        }
        if encoding == "ascii" {
            bytes.push(b'\n');
        }
    }
    for _ in 0..faces {
        let n = match (face_element, r.hostile()) {
            ("tristrips", _) => 3 + r.below(10),
            (_, true) => *r.pick(&[0, 1, 2, 9, 300]),
            _ => *r.pick(&[3, 3, 4, 5]),
        };
        ply_value(r, count_t, encoding, n as f64, &mut bytes);
        for _ in 0..n {
            let i = if face_element == "tristrips" && r.chance(0.1) { -1 } else { r.index(vertices) - 1 };
            ply_value(r, item_t, encoding, i as f64, &mut bytes);
        }
        if encoding == "ascii" {
            bytes.push(b'\n');
        }
    }
    r.damage(&mut bytes);
    Case { files: vec![("m.ply".into(), bytes)], names_outside: false }
}

pub fn ply_gz(r: &mut Rng) -> Case {
    use std::io::Write;
    let mut case = ply(r);
    let mut gz = flate2::write::GzEncoder::new(Vec::new(), flate2::Compression::fast());
    let _ = gz.write_all(&case.files[0].1);
    let mut bytes = gz.finish().unwrap_or_default();
    r.damage(&mut bytes);
    case.files[0] = ("m.ply.gz".into(), bytes);
    case
}

// ---- glTF and GLB ----

fn json_number(r: &mut Rng) -> Value {
    match r.below(16) {
        0 => json!(*r.pick(&[1e38, -1e38, 3e38, 1e30, 1e-30, 0.0, 1e17])),
        _ => json!((r.below(400) as f64 - 200.0) / 50.0),
    }
}

/// The glTF document and its side buffer; `bin` buffers refer to a GLB BIN chunk.
fn gltf_document(r: &mut Rng, bin: bool) -> (Value, Vec<u8>, bool) {
    let n = 3 * r.count(40).min(4000) as usize + 9;
    let data = floats(r, n);
    let mut names_outside = false;
    let buffers = gltf_buffers(r, bin, &data, &mut names_outside);
    let views = gltf_views(r, &data, buffers.len() as u64);
    let accessors = gltf_accessors(r, &data, views.len() as u64);
    let meshes = gltf_meshes(r, accessors.len() as u64);
    let (nodes, shape) = gltf_nodes(r, meshes.len() as u64);
    let count = nodes.len() as u64;
    let mut doc = json!({
        "asset": {"version": "2.0"},
        "buffers": buffers, "bufferViews": views, "accessors": accessors, "meshes": meshes, "nodes": nodes,
        "extensions": {"KHR_lights_punctual": {"lights": [{"type": "spot", "spot": {"outerConeAngle": json_number(r)}, "intensity": json_number(r)}]}},
    });
    if r.chance(0.7) {
        let roots: Vec<i64> = if r.hostile() {
            (0..1 + r.below(3)).map(|_| r.index(count) - 1).collect()
        } else if shape <= 1 {
            vec![0]
        } else {
            (0..count as i64).collect()
        };
        doc["scenes"] = json!([{"nodes": roots}]);
        doc["scene"] = json!(0);
    }
    if r.hostile() && r.chance(0.2) {
        doc["extensionsRequired"] =
            json!([*r.pick(&["KHR_draco_mesh_compression", "EXT_unknown", "KHR_lights_punctual"])]);
    }
    (doc, data, names_outside)
}

/// One to three buffers: the GLB's BIN chunk first where `bin`, else data URIs, files beside the model
/// (or outside its folder: `names_outside`) and, when hostile, URLs and wrong lengths.
fn gltf_buffers(r: &mut Rng, bin: bool, data: &[u8], names_outside: &mut bool) -> Vec<Value> {
    (0..1 + r.below(3))
        .map(|i| {
            let len = if r.hostile() { r.count(1 << 16) } else { data.len() as u64 };
            if bin && i == 0 {
                return json!({"byteLength": len});
            }
            let uri = match if r.hostile() { r.below(6) } else { 2 * r.below(2) } {
                0 => format!("data:application/octet-stream;base64,{}", base64(&data[..data.len().min(512)])),
                1 => (*r.pick(&["https://example.invalid/b.bin", "file:///etc/hostname", "C:\\b.bin", ""])).into(),
                _ => {
                    let (path, outside) = reference(r, "bin");
                    *names_outside |= outside;
                    path
                }
            };
            json!({"uri": uri, "byteLength": len})
        })
        .collect()
}

/// Views into `nb` buffers, hostile ones out of range, offset or strided.
fn gltf_views(r: &mut Rng, data: &[u8], nb: u64) -> Vec<Value> {
    (0..1 + r.below(4))
        .map(|_| {
            if !r.hostile() {
                return json!({"buffer": 0, "byteLength": data.len().min(512)});
            }
            let mut v = json!({"buffer": r.index(nb) - 1, "byteLength": r.count(data.len() as u64)});
            if r.chance(0.5) {
                v["byteOffset"] = json!(r.count(64));
            }
            if r.chance(0.4) {
                v["byteStride"] = json!(r.count(64));
            }
            v
        })
        .collect()
}

/// Accessors of `nv` views, hostile ones of other types, counts, offsets or sparse.
fn gltf_accessors(r: &mut Rng, data: &[u8], nv: u64) -> Vec<Value> {
    (0..1 + r.below(6))
        .map(|_| {
            if !r.hostile() {
                let count = 3 * (1 + r.below(data.len().min(512) as u64 / 36));
                return json!({"bufferView": 0, "componentType": 5126, "count": count, "type": "VEC3",
                              "min": [0, 0, 0], "max": [1, 1, 1]});
            }
            let mut a = json!({
                "bufferView": r.index(nv) - 1,
                "componentType": *r.pick(&[5126, 5126, 5126, 5125, 5123, 5121, 5120, 5122, 1234]),
                "count": r.count(data.len() as u64 / 12),
                "type": *r.pick(&["VEC3", "VEC3", "SCALAR", "VEC2", "VEC4", "MAT4", "BAD"]),
            });
            if r.chance(0.3) {
                a["byteOffset"] = json!(r.count(64));
            }
            if r.chance(0.5) {
                a["min"] = json!([0, 0, 0]);
                a["max"] = json!([1, 1, 1]);
            }
            if r.chance(0.03) {
                a["sparse"] = json!({"count": 1, "indices": {"bufferView": 0, "componentType": 5125}, "values": {"bufferView": 0}});
            }
            a
        })
        .collect()
}

/// Meshes of primitives over `na` accessors, hostile ones of other modes or with indices.
fn gltf_meshes(r: &mut Rng, na: u64) -> Vec<Value> {
    (0..1 + r.below(3))
        .map(|_| {
            let prims: Vec<Value> = (0..1 + r.below(3))
                .map(|_| {
                    let mut attributes = json!({"POSITION": r.index(na) - 1});
                    if r.chance(0.3) {
                        attributes["NORMAL"] = json!(r.index(na) - 1);
                    }
                    let mode = if r.hostile() { *r.pick(&[0, 1, 2, 3, 9]) } else { *r.pick(&[4, 4, 5, 6]) };
                    let mut p = json!({"attributes": attributes, "mode": mode});
                    if r.hostile() {
                        p["indices"] = json!(r.index(na) - 1);
                    }
                    p
                })
                .collect();
            json!({"primitives": prims})
        })
        .collect()
}

/// The nodes, drawing `nm` meshes, and the graph's shape (0: a deep chain, 1: a wide hub, else random
/// children, cycles and two parents included).
fn gltf_nodes(r: &mut Rng, nm: u64) -> (Vec<Value>, u64) {
    let shape = r.below(10);
    let count = match shape {
        0 => 2000 + r.below(12_000),
        1 => 1000 + r.below(20_000),
        _ => 1 + r.count(12).min(400),
    };
    let nodes: Vec<Value> = (0..count)
        .map(|i| {
            let mut n = json!({});
            match shape {
                0 if i + 1 < count => n["children"] = json!([i + 1]),
                1 if i == 0 => n["children"] = json!((1..count).collect::<Vec<_>>()),
                0 | 1 => {}
                _ if r.hostile() => {
                    n["children"] = json!((0..r.below(4)).map(|_| r.index(count) - 1).collect::<Vec<_>>());
                }
                _ => {}
            }
            if r.chance(0.6) {
                n["mesh"] = json!(r.index(nm) - 1);
            }
            match if r.hostile() { r.below(5) } else { 3 } {
                0 => n["matrix"] = json!((0..16).map(|_| json_number(r)).collect::<Vec<_>>()),
                1 => n["scale"] = json!([json_number(r), json_number(r), json_number(r)]),
                2 => n["translation"] = json!([json_number(r), json_number(r), json_number(r)]),
                _ => {}
            }
            if r.chance(0.05) {
                n["extensions"] = json!({"KHR_lights_punctual": {"light": r.index(2) - 1}});
            }
            n
        })
        .collect();
    (nodes, shape)
}

fn base64(bytes: &[u8]) -> String {
    const A: &[u8; 64] = b"ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
    bytes
        .chunks(3)
        .flat_map(|c| {
            let n = (u32::from(c[0]) << 16)
                | (u32::from(*c.get(1).unwrap_or(&0)) << 8)
                | u32::from(*c.get(2).unwrap_or(&0));
            (0..4).map(move |k| if k <= c.len() { A[(n >> (18 - 6 * k)) as usize & 63] as char } else { '=' })
        })
        .collect()
}

pub fn gltf(r: &mut Rng) -> Case {
    let (doc, data, names_outside) = gltf_document(r, false);
    let mut bytes = doc.to_string().into_bytes();
    r.damage(&mut bytes);
    Case { files: vec![("m.gltf".into(), bytes), ("side.bin".into(), data)], names_outside }
}

pub fn glb(r: &mut Rng) -> Case {
    let (doc, data, names_outside) = gltf_document(r, true);
    let mut json = doc.to_string().into_bytes();
    while json.len() % 4 != 0 {
        json.push(b' ');
    }
    let mut bin = data.clone();
    while bin.len() % 4 != 0 {
        bin.push(0);
    }
    let chunk = |out: &mut Vec<u8>, kind: u32, body: &[u8], r: &mut Rng| {
        let len = if r.hostile() { r.next_u64() as u32 } else { body.len() as u32 };
        out.extend_from_slice(&len.to_le_bytes());
        out.extend_from_slice(&kind.to_le_bytes());
        out.extend_from_slice(body);
    };
    let mut body = Vec::new();
    chunk(&mut body, 0x4E4F_534A, &json, r);
    if !r.hostile() {
        chunk(&mut body, 0x004E_4942, &bin, r);
    }
    let version: u32 = if r.hostile() { r.below(4) as u32 } else { 2 };
    let total = if r.hostile() { r.next_u64() as u32 } else { 12 + body.len() as u32 };
    let mut bytes = b"glTF".to_vec();
    bytes.extend_from_slice(&version.to_le_bytes());
    bytes.extend_from_slice(&total.to_le_bytes());
    bytes.extend_from_slice(&body);
    r.damage(&mut bytes);
    Case { files: vec![("m.glb".into(), bytes), ("side.bin".into(), data)], names_outside }
}
