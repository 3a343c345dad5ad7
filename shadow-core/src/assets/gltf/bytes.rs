//! The bytes of a glTF file, each read with bounds checks: the GLB container, the buffers (from the
//! container, a data URI or a file beside the model) and the accessors (offsets, strides, component
//! types, normalisation), and the triangles a primitive's indices make.

use std::path::Path;

use glam::{Vec2, Vec3};
use gltf::accessor::{DataType, Dimensions};
use gltf::mesh::Mode;

use super::Fault;
use crate::assets::{LoadOptions, read_referenced};

/// The JSON and BIN chunks of a GLB container.
pub(super) fn split_glb(bytes: &[u8]) -> Result<(&[u8], Option<&[u8]>), Fault> {
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

pub(super) fn base64_decode(s: &str) -> Result<Vec<u8>, Fault> {
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

pub(super) fn percent_decode(s: &str) -> String {
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

pub(super) fn load_buffers(
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

/// An accessor's components as f64, element after element, bounds-checked against its view and buffer.
pub(super) fn read_accessor(acc: &gltf::Accessor, buffers: &[Vec<u8>], what: &str) -> Result<Vec<f64>, Fault> {
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
        .flat_map(|i| {
            let base = acc.offset() + i * stride;
            (0..comps).map(move |c| base + c * csize)
        })
        .map(read)
        .collect())
}

pub(super) fn read_vec3(acc: &gltf::Accessor, buffers: &[Vec<u8>], what: &str) -> Result<Vec<Vec3>, Fault> {
    if acc.dimensions() != Dimensions::Vec3 || acc.data_type() != DataType::F32 {
        return Err(Fault::WrongAccessor(format!(
            "{what} accessor {} is {:?} of {:?}, expected Vec3 of F32",
            acc.index(),
            acc.dimensions(),
            acc.data_type()
        )));
    }
    let floats = read_accessor(acc, buffers, what)?;
    Ok(floats.chunks_exact(3).map(|e| Vec3::new(e[0] as f32, e[1] as f32, e[2] as f32)).collect())
}

/// Texture coordinates: float pairs, or normalized unsigned bytes or shorts (glTF 2.0 3.7.2.1).
pub(super) fn read_uvs(acc: &gltf::Accessor, buffers: &[Vec<u8>], what: &str) -> Result<Vec<Vec2>, Fault> {
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
    Ok(read_accessor(acc, buffers, what)?.chunks_exact(2).map(|e| Vec2::new(e[0] as f32, e[1] as f32)).collect())
}

pub(super) fn read_indices(acc: &gltf::Accessor, buffers: &[Vec<u8>]) -> Result<Vec<u32>, Fault> {
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
    Ok(read_accessor(acc, buffers, "indices")?.iter().map(|&e| e as u32).collect())
}

/// Floats of the given shape, element after element: F32, or where `normalized` allows it the normalized
/// integers glTF allows for rotations and morph weights (signed and unsigned bytes and shorts).
pub(super) fn read_floats(
    acc: &gltf::Accessor,
    buffers: &[Vec<u8>],
    what: &str,
    dimensions: Dimensions,
    normalized: bool,
) -> Result<Vec<f32>, Fault> {
    let integer = matches!(acc.data_type(), DataType::I8 | DataType::U8 | DataType::I16 | DataType::U16);
    let allowed = acc.data_type() == DataType::F32 || (normalized && acc.normalized() && integer);
    if acc.dimensions() != dimensions || !allowed {
        return Err(Fault::WrongAccessor(format!(
            "{what} accessor {} is {:?} of {:?}{}, expected {dimensions:?} of F32{}",
            acc.index(),
            acc.dimensions(),
            acc.data_type(),
            if acc.normalized() { " (normalized)" } else { "" },
            if normalized { " or of normalized bytes or shorts" } else { "" }
        )));
    }
    Ok(read_accessor(acc, buffers, what)?.iter().map(|&e| e as f32).collect())
}

/// Triangles of a primitive from its index list (or 0..n without indices).
pub(super) fn assemble(mode: Mode, idx: &[u32]) -> Vec<[u32; 3]> {
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
