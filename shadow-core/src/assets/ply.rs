//! PLY (Stanford polygon format): ASCII, binary little endian and binary big endian, optionally gzipped
//! (recognized by its magic bytes). Vertex `x y z` and optional `nx ny nz`; faces from the list property
//! `vertex_indices` (or `vertex_index`) of a `face` element, polygons fanned into triangles, or of a
//! `tristrips` element, strips split at each -1 (as classic range scans ship them). Other elements and
//! properties are read past. Errors in an ASCII body name the line, in a binary body the byte.

use std::io::Read;
use std::path::Path;

use glam::{Mat4, Vec3};

use super::{AssetError, AssetFault, read_model};
use crate::mesh::Mesh;
use crate::scene::{Material, Scene};

/// Decompressed size beyond which a gzipped PLY is refused (a guard against compression bombs).
const MAX_DECOMPRESSED: u64 = 4 << 30;

#[derive(Clone, Copy, Debug, PartialEq)]
enum Scalar {
    I8,
    U8,
    I16,
    U16,
    I32,
    U32,
    F32,
    F64,
}

impl Scalar {
    fn parse(s: &str) -> Option<Self> {
        Some(match s {
            "char" | "int8" => Self::I8,
            "uchar" | "uint8" => Self::U8,
            "short" | "int16" => Self::I16,
            "ushort" | "uint16" => Self::U16,
            "int" | "int32" => Self::I32,
            "uint" | "uint32" => Self::U32,
            "float" | "float32" => Self::F32,
            "double" | "float64" => Self::F64,
            _ => return None,
        })
    }
    fn size(self) -> usize {
        match self {
            Self::I8 | Self::U8 => 1,
            Self::I16 | Self::U16 => 2,
            Self::I32 | Self::U32 | Self::F32 => 4,
            Self::F64 => 8,
        }
    }
}

#[derive(Debug)]
enum Property {
    Scalar(String, Scalar),
    List(String, Scalar, Scalar),
}

#[derive(Debug)]
struct Element {
    name: String,
    count: usize,
    properties: Vec<Property>,
}

#[derive(Clone, Copy, PartialEq)]
enum Encoding {
    Ascii,
    Little,
    Big,
}

/// A cursor over the body that reads values in the file's encoding.
struct Body<'a> {
    bytes: &'a [u8],
    pos: usize,
    encoding: Encoding,
    /// The file line `pos` is on (ASCII bodies).
    line: usize,
    /// The file byte `bytes` starts at (binary bodies).
    offset: usize,
}

impl<'a> Body<'a> {
    /// Where the cursor is, for messages: the line of an ASCII body, the byte of a binary one.
    fn place(&self) -> String {
        match self.encoding {
            Encoding::Ascii => format!("line {}", self.line),
            _ => format!("byte {}", self.offset + self.pos),
        }
    }

    fn token(&mut self) -> Result<&'a str, AssetFault> {
        let b: &'a [u8] = self.bytes;
        while self.pos < b.len() && b[self.pos].is_ascii_whitespace() {
            self.line += usize::from(b[self.pos] == b'\n');
            self.pos += 1;
        }
        let start = self.pos;
        while self.pos < b.len() && !b[self.pos].is_ascii_whitespace() {
            self.pos += 1;
        }
        if start == self.pos {
            return Err(AssetFault::Truncated(format!(
                "the data ends at {} before every element was read",
                self.place()
            )));
        }
        std::str::from_utf8(&b[start..self.pos])
            .map_err(|_| AssetFault::Malformed(format!("line {}: non-text bytes in an ASCII body", self.line)))
    }

    fn value(&mut self, t: Scalar) -> Result<f64, AssetFault> {
        if self.encoding == Encoding::Ascii {
            let tok = self.token()?;
            return tok
                .parse::<f64>()
                .map_err(|_| AssetFault::Malformed(format!("line {}: '{tok}' is not a number", self.line)));
        }
        let n = t.size();
        let place = self.place();
        let raw = self
            .bytes
            .get(self.pos..self.pos + n)
            .ok_or_else(|| AssetFault::Truncated(format!("the data ends at {place} before every element was read")))?;
        self.pos += n;
        let mut buf = [0u8; 8];
        buf[..n].copy_from_slice(raw);
        if self.encoding == Encoding::Big {
            buf[..n].reverse();
        }
        Ok(match t {
            Scalar::I8 => f64::from(buf[0] as i8),
            Scalar::U8 => f64::from(buf[0]),
            Scalar::I16 => f64::from(i16::from_le_bytes([buf[0], buf[1]])),
            Scalar::U16 => f64::from(u16::from_le_bytes([buf[0], buf[1]])),
            Scalar::I32 => f64::from(i32::from_le_bytes([buf[0], buf[1], buf[2], buf[3]])),
            Scalar::U32 => f64::from(u32::from_le_bytes([buf[0], buf[1], buf[2], buf[3]])),
            Scalar::F32 => f64::from(f32::from_le_bytes([buf[0], buf[1], buf[2], buf[3]])),
            Scalar::F64 => f64::from_le_bytes(buf),
        })
    }

    fn remaining(&self) -> usize {
        self.bytes.len() - self.pos
    }
}

fn parse_header(text: &str) -> Result<(Encoding, Vec<Element>), AssetFault> {
    let bad = |m: String| AssetFault::Malformed(m);
    let mut lines = text.lines();
    if lines.next().map(str::trim) != Some("ply") {
        return Err(bad("the file does not start with 'ply'".into()));
    }
    let mut encoding = None;
    let mut elements: Vec<Element> = Vec::new();
    for (n, line) in lines.enumerate() {
        let bad = |m: String| AssetFault::Malformed(format!("header line {}: {m}", n + 2));
        let words: Vec<&str> = line.split_whitespace().collect();
        match words.as_slice() {
            [] | ["comment", ..] | ["obj_info", ..] => {}
            ["format", f, _version] => {
                encoding = Some(match *f {
                    "ascii" => Encoding::Ascii,
                    "binary_little_endian" => Encoding::Little,
                    "binary_big_endian" => Encoding::Big,
                    other => return Err(bad(format!("unknown format '{other}'"))),
                });
            }
            ["element", name, count] => {
                let count = count.parse().map_err(|_| bad(format!("element '{name}' has a bad count '{count}'")))?;
                elements.push(Element { name: (*name).into(), count, properties: Vec::new() });
            }
            ["property", "list", count_t, item_t, name] => {
                let (c, i) = (Scalar::parse(count_t), Scalar::parse(item_t));
                let (Some(c), Some(i)) = (c, i) else {
                    return Err(bad(format!("unknown type in list property '{name}'")));
                };
                let e = elements.last_mut().ok_or_else(|| bad("a property before any element".into()))?;
                e.properties.push(Property::List((*name).into(), c, i));
            }
            ["property", t, name] => {
                let t = Scalar::parse(t).ok_or_else(|| bad(format!("unknown type '{t}' of property '{name}'")))?;
                let e = elements.last_mut().ok_or_else(|| bad("a property before any element".into()))?;
                e.properties.push(Property::Scalar((*name).into(), t));
            }
            _ => return Err(bad(format!("unexpected header line '{line}'"))),
        }
    }
    Ok((encoding.ok_or_else(|| bad("no format line".into()))?, elements))
}

fn decompress(bytes: Vec<u8>) -> Result<Vec<u8>, AssetFault> {
    if !bytes.starts_with(&[0x1f, 0x8b]) {
        return Ok(bytes);
    }
    let mut out = Vec::new();
    flate2::read::GzDecoder::new(bytes.as_slice())
        .take(MAX_DECOMPRESSED + 1)
        .read_to_end(&mut out)
        .map_err(|e| AssetFault::Truncated(format!("gzip stream: {e}")))?;
    if out.len() as u64 > MAX_DECOMPRESSED {
        return Err(AssetFault::Unsupported(format!("decompresses to more than {} GiB", MAX_DECOMPRESSED >> 30)));
    }
    Ok(out)
}

pub(super) fn load(path: &Path) -> Result<Scene, AssetError> {
    parse(path).map_err(|f| AssetError::new(path, f))
}

/// The header's encoding and elements, and the body after the `end_header` line.
fn split_header(bytes: &[u8]) -> Result<(Vec<Element>, Body<'_>), AssetFault> {
    if !bytes.starts_with(b"ply") {
        return Err(AssetFault::Malformed("the file does not start with 'ply'".into()));
    }
    const END: &[u8] = b"end_header";
    let end = bytes
        .windows(END.len())
        .position(|w| w == END)
        .ok_or_else(|| AssetFault::Malformed("no 'end_header' line".into()))?;
    let header =
        std::str::from_utf8(&bytes[..end]).map_err(|_| AssetFault::Malformed("the header is not text".into()))?;
    let (encoding, elements) = parse_header(header)?;
    // The body starts after the end_header line's newline (\n or \r\n).
    let mut start = end + END.len();
    while start < bytes.len() && bytes[start] != b'\n' {
        start += 1;
    }
    let body_start = (start + 1).min(bytes.len());
    let first_line = 1 + bytes[..body_start].iter().filter(|&&b| b == b'\n').count();
    Ok((elements, Body { bytes: &bytes[body_start..], pos: 0, encoding, line: first_line, offset: body_start }))
}

/// Refuses an element whose count the rest of the data cannot hold, before anything is reserved: every
/// instance takes at least one byte (binary) or one token (ASCII, two bytes with a separator).
fn check_count(e: &Element, body: &Body<'_>) -> Result<(), AssetFault> {
    let min_size: usize = match body.encoding {
        Encoding::Ascii => 2 * e.properties.len().max(1),
        _ => e
            .properties
            .iter()
            .map(|p| match p {
                Property::Scalar(_, t) => t.size(),
                Property::List(_, c, _) => c.size(),
            })
            .sum::<usize>()
            .max(1),
    };
    if e.count.checked_mul(min_size).is_none_or(|need| need > body.remaining()) {
        return Err(AssetFault::Truncated(format!(
            "element '{}' claims {} entries, more than the data holds",
            e.name, e.count
        )));
    }
    Ok(())
}

fn parse(path: &Path) -> Result<Scene, AssetFault> {
    let bytes = decompress(read_model(path)?)?;
    let (elements, mut body) = split_header(&bytes)?;
    let mut positions: Vec<Vec3> = Vec::new();
    let mut normals: Vec<Vec3> = Vec::new();
    let mut triangles: Vec<[u32; 3]> = Vec::new();
    let mut faces_seen = 0usize;
    for e in &elements {
        check_count(e, &body)?;
        let is_vertex = e.name == "vertex";
        let is_face = e.name == "face";
        let is_strips = e.name == "tristrips";
        let find = |n: &str| e.properties.iter().position(|p| matches!(p, Property::Scalar(name, _) if name == n));
        let xyz = [find("x"), find("y"), find("z")];
        let nxyz = [find("nx"), find("ny"), find("nz")];
        if is_vertex && xyz.iter().any(Option::is_none) {
            return Err(AssetFault::Malformed("the vertex element lacks x, y or z".into()));
        }
        if is_vertex {
            positions.reserve(e.count);
        }
        let mut scalars = vec![0.0f64; e.properties.len()];
        let mut list: Vec<f64> = Vec::new();
        for _ in 0..e.count {
            for (k, p) in e.properties.iter().enumerate() {
                match p {
                    Property::Scalar(_, t) => scalars[k] = body.value(*t)?,
                    Property::List(name, ct, it) => {
                        let n = body.value(*ct)?;
                        if !(0.0..=1e6).contains(&n) {
                            return Err(AssetFault::Malformed(format!("list '{name}' has length {n}")));
                        }
                        list.clear();
                        for _ in 0..n as usize {
                            list.push(body.value(*it)?);
                        }
                        if (is_face || is_strips) && (name == "vertex_indices" || name == "vertex_index") {
                            faces_seen += 1;
                            let place = body.place();
                            if is_face {
                                fan(&list, faces_seen - 1, &mut triangles)
                            } else {
                                strips(&list, faces_seen - 1, &mut triangles)
                            }
                            .map_err(|why| AssetFault::Malformed(format!("{place}: {why}")))?;
                        }
                    }
                }
            }
            if is_vertex {
                let get = |i: Option<usize>| i.map_or(0.0, |i| scalars[i] as f32);
                positions.push(Vec3::new(get(xyz[0]), get(xyz[1]), get(xyz[2])));
                if nxyz.iter().all(Option::is_some) {
                    normals.push(Vec3::new(get(nxyz[0]), get(nxyz[1]), get(nxyz[2])));
                }
            }
        }
    }
    if triangles.is_empty() {
        return Err(AssetFault::Unsupported(
            "no faces with three or more vertices (only points or lines, or nothing at all)".into(),
        ));
    }
    let mesh = if normals.len() == positions.len() {
        Mesh::with_normals(positions, normals, triangles)
    } else {
        Mesh::new(positions, triangles)
    }
    .map_err(|e| AssetFault::Mesh("mesh".into(), e))?;
    let mut scene = Scene::new();
    let mat = scene.add_material(Material::default());
    let key = scene.add_mesh(mesh);
    let name = path.file_stem().and_then(|s| s.to_str()).unwrap_or("ply");
    scene.add_instance(name, key, mat, Mat4::IDENTITY).map_err(|e| AssetFault::Malformed(e.to_string()))?;
    Ok(scene)
}

/// A list entry as a vertex index: a whole number in u32's range.
fn vertex_index(i: f64) -> Option<u32> {
    (i >= 0.0 && i.fract() == 0.0 && i <= f64::from(u32::MAX)).then_some(i as u32)
}

/// Fans a polygon into triangles, checking that every index is a non-negative integer.
fn fan(indices: &[f64], face: usize, out: &mut Vec<[u32; 3]>) -> Result<(), String> {
    let idx: Vec<u32> = indices
        .iter()
        .map(|&i| vertex_index(i).ok_or_else(|| format!("face {face} has vertex index {i}")))
        .collect::<Result<_, _>>()?;
    for k in 1..idx.len().saturating_sub(1) {
        out.push([idx[0], idx[k], idx[k + 1]]);
    }
    Ok(())
}

/// Triangles of a `tristrips` entry: strips separated by -1. Every other triangle of a strip swaps its
/// first two corners so all keep the first one's winding; triangles with a repeated corner (the joins
/// strippers insert) are left out.
fn strips(indices: &[f64], entry: usize, out: &mut Vec<[u32; 3]>) -> Result<(), String> {
    for strip in indices.split(|&i| i == -1.0) {
        let idx: Vec<u32> = strip
            .iter()
            .map(|&i| vertex_index(i).ok_or_else(|| format!("strip entry {entry} has vertex index {i}")))
            .collect::<Result<_, _>>()?;
        for k in 2..idx.len() {
            let t = if k % 2 == 0 { [idx[k - 2], idx[k - 1], idx[k]] } else { [idx[k - 1], idx[k - 2], idx[k]] };
            if t[0] != t[1] && t[1] != t[2] && t[0] != t[2] {
                out.push(t);
            }
        }
    }
    Ok(())
}
