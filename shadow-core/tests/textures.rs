//! Textured materials from files: glTF base-colour textures with their samplers, transforms and alpha
//! modes, OBJ `map_Kd`/`map_d`/`d`/`Tr`; bad images (missing, truncated, lying about their size, outside
//! the model's folder) refused or left out with one line; and export writing them back. Every file is
//! generated here.

use std::path::{Path, PathBuf};

use glam::Vec2;
use serde_json::json;
use shadow_core::assets::{self, AssetFault};
use shadow_core::material::{AlphaMode, Filter, Wrap};

/// A fresh folder for one test's files.
fn folder(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("shadowlab-textures-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).expect("temp folder");
    dir
}

/// An 8 x 8 checkerboard of 2 x 2 squares, opaque red and clear.
fn checker_png() -> Vec<u8> {
    let raw: Vec<u8> =
        (0..64).flat_map(|i| if ((i % 8) / 2 + (i / 16)) % 2 == 0 { [255, 0, 0, 255] } else { [0, 0, 0, 0] }).collect();
    png(8, 8, &raw)
}

fn png(width: u32, height: u32, rgba: &[u8]) -> Vec<u8> {
    let mut out = Vec::new();
    image::ImageEncoder::write_image(
        image::codecs::png::PngEncoder::new(&mut out),
        rgba,
        width,
        height,
        image::ExtendedColorType::Rgba8,
    )
    .expect("encode");
    out
}

/// A 1 x 1 PNG whose header claims `side` x `side`, its checksum mended so only the size lies.
fn lying_png(side: u32) -> Vec<u8> {
    let mut bytes = png(1, 1, &[0, 0, 0, 255]);
    bytes[16..20].copy_from_slice(&side.to_be_bytes());
    bytes[20..24].copy_from_slice(&side.to_be_bytes());
    let mut crc = flate2::Crc::new();
    crc.update(&bytes[12..29]);
    bytes[29..33].copy_from_slice(&crc.sum().to_be_bytes());
    bytes
}

/// A 64 x 64 JPEG of colour ramps: red across, green down.
fn jpeg() -> Vec<u8> {
    let rgb: Vec<u8> = (0..64 * 64).flat_map(|i| [(i % 64 * 4) as u8, (i / 64 * 4) as u8, 7]).collect();
    let mut out = Vec::new();
    let encoder = image::codecs::jpeg::JpegEncoder::new(&mut out);
    image::ImageEncoder::write_image(encoder, &rgb, 64, 64, image::ExtendedColorType::Rgb8).expect("encode");
    out
}

fn base64(bytes: &[u8]) -> String {
    const DIGITS: &[u8; 64] = b"ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
    let mut out = String::new();
    for chunk in bytes.chunks(3) {
        let b = [chunk[0], *chunk.get(1).unwrap_or(&0), *chunk.get(2).unwrap_or(&0)];
        let n = (u32::from(b[0]) << 16) | (u32::from(b[1]) << 8) | u32::from(b[2]);
        for i in 0..4 {
            out.push(if i <= chunk.len() { DIGITS[(n >> (18 - 6 * i) & 63) as usize] as char } else { '=' });
        }
    }
    out
}

/// A unit card in the XZ plane, facing up, with texture coordinates over it; its material reads image
/// `uri` as `alpha_mode` with `extra` merged into the base-colour texture's info.
fn card_gltf(dir: &Path, uri: &str, material: serde_json::Value, sampler: serde_json::Value) -> PathBuf {
    let positions: [[f32; 3]; 4] = [[-0.5, 0.0, 0.5], [0.5, 0.0, 0.5], [0.5, 0.0, -0.5], [-0.5, 0.0, -0.5]];
    let uvs: [[f32; 2]; 4] = [[0.0, 1.0], [1.0, 1.0], [1.0, 0.0], [0.0, 0.0]];
    let indices: [u16; 6] = [0, 1, 2, 0, 2, 3];
    let mut bin: Vec<u8> = bytemuck::cast_slice(&positions).to_vec();
    bin.extend_from_slice(bytemuck::cast_slice(&uvs));
    bin.extend_from_slice(bytemuck::cast_slice(&indices));
    let doc = json!({
        "asset": {"version": "2.0"},
        "scene": 0,
        "scenes": [{"nodes": [0]}],
        "nodes": [{"mesh": 0}],
        "meshes": [{"primitives": [{"attributes": {"POSITION": 0, "TEXCOORD_0": 1}, "indices": 2, "material": 0}]}],
        "materials": [material],
        "textures": [{"source": 0, "sampler": 0}],
        "samplers": [sampler],
        "images": [{"uri": uri}],
        "accessors": [
            {"bufferView": 0, "componentType": 5126, "count": 4, "type": "VEC3", "min": [-0.5, 0.0, -0.5], "max": [0.5, 0.0, 0.5]},
            {"bufferView": 1, "componentType": 5126, "count": 4, "type": "VEC2"},
            {"bufferView": 2, "componentType": 5123, "count": 6, "type": "SCALAR"},
        ],
        "bufferViews": [
            {"buffer": 0, "byteOffset": 0, "byteLength": 48},
            {"buffer": 0, "byteOffset": 48, "byteLength": 32},
            {"buffer": 0, "byteOffset": 80, "byteLength": 12},
        ],
        "buffers": [{"byteLength": bin.len(), "uri": format!("data:application/octet-stream;base64,{}", base64(&bin))}],
    });
    let path = dir.join("card.gltf");
    std::fs::write(&path, doc.to_string()).expect("write gltf");
    path
}

fn masked_material() -> serde_json::Value {
    json!({
        "name": "checker",
        "alphaMode": "MASK",
        "alphaCutoff": 0.4,
        "doubleSided": true,
        "pbrMetallicRoughness": {"baseColorFactor": [1.0, 1.0, 1.0, 0.9], "baseColorTexture": {
            "index": 0,
            "extensions": {"KHR_texture_transform": {"offset": [0.25, 0.0], "scale": [2.0, 2.0]}},
        }},
    })
}

fn nearest_clamp() -> serde_json::Value {
    json!({"magFilter": 9728, "minFilter": 9984, "wrapS": 33071, "wrapT": 33648})
}

/// glTF's `doubleSided` decides both sides' lighting and whether the camera sees back faces: a
/// double-sided material is lit from both sides and seen from both; a single-sided one (the default) is
/// culled from behind.
#[test]
fn double_sidedness_decides_back_face_culling() {
    let dir = folder("sides");
    std::fs::write(dir.join("checker.png"), checker_png()).unwrap();
    for (double_sided, material) in [(true, masked_material()), (false, json!({"name": "single"}))] {
        let scene = assets::load(card_gltf(&dir, "checker.png", material, nearest_clamp())).expect("card");
        let (_, _, _, material) = scene.drawables().next().expect("card");
        assert_eq!((material.two_sided, material.cull_back_faces), (double_sided, !double_sided), "{}", material.name);
    }
}

#[test]
fn a_masked_card_loads_its_texture_sampler_transform_and_coordinates() {
    let dir = folder("card");
    std::fs::write(dir.join("checker.png"), checker_png()).unwrap();
    let scene = assets::load(card_gltf(&dir, "checker.png", masked_material(), nearest_clamp())).expect("card");
    assert!(scene.warnings().is_empty(), "{:?}", scene.warnings());
    let (_, _, mesh, material) = scene.drawables().next().expect("card");
    assert_eq!(material.alpha_mode, AlphaMode::Mask { cutoff: 0.4 });
    assert!(material.two_sided);
    assert_eq!(material.alpha, 0.9);
    let r = material.base_color_texture.expect("texture");
    assert_eq!(
        (r.sampler.mag, r.sampler.min, r.sampler.mipmap),
        (Filter::Nearest, Filter::Nearest, Some(Filter::Nearest))
    );
    assert_eq!((r.sampler.wrap_u, r.sampler.wrap_v), (Wrap::ClampToEdge, Wrap::MirroredRepeat));
    assert_eq!((r.transform.offset, r.transform.scale), (Vec2::new(0.25, 0.0), Vec2::splat(2.0)));
    let texture = scene.texture(r.texture).expect("texture in the scene");
    assert_eq!((texture.width(), texture.height(), texture.levels().len()), (8, 8, 4));
    assert_eq!(*texture.levels()[0].get(0, 0), [255, 0, 0, 255]);
    assert_eq!(*texture.levels()[0].get(2, 0), [0, 0, 0, 0]);
    let uvs = scene.mesh(mesh).unwrap().uvs().expect("uvs");
    assert_eq!(uvs[0], Vec2::new(0.0, 1.0));
    // The same image through a data URI loads the same texels.
    let data_uri = format!("data:image/png;base64,{}", base64(&checker_png()));
    let again = assets::load(card_gltf(&dir, &data_uri, masked_material(), nearest_clamp())).expect("data URI");
    let (_, t) = again.textures().next().expect("texture");
    assert_eq!(t.levels()[0].data(), texture.levels()[0].data());
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn a_bad_image_is_left_out_with_one_line_naming_the_file_and_the_fault() {
    let dir = folder("bad-images");
    let good = checker_png();
    std::fs::write(dir.join("truncated.png"), &good[..good.len() / 2]).unwrap();
    std::fs::write(dir.join("huge.png"), lying_png(100_000)).unwrap();
    std::fs::write(dir.join("text.png"), b"not an image at all").unwrap();
    let jpeg = jpeg();
    // A Huffman table whose code counts add up to more codes than it holds.
    let mut corrupt = jpeg.clone();
    let dht = corrupt.windows(2).position(|w| w == [0xFF, 0xC4]).expect("a Huffman table");
    corrupt[dht + 5..dht + 21].fill(0xFF);
    std::fs::write(dir.join("corrupt.jpg"), corrupt).unwrap();
    std::fs::write(dir.join("cut.jpg"), &jpeg[..jpeg.len() / 2]).unwrap();
    std::fs::write(dir.join("basis.ktx2"), b"\xABKTX 20\xBB\r\n\x1A\n\0\0\0\0\0\0\0\0").unwrap();
    std::fs::write(
        dir.join("leaf.webp"),
        b"RIFF\x1a\0\0\0WEBPVP8L\x0d\0\0\0\x2f\0\0\0\x10\x07\x10\x11\x11\x88\x88\xfe\x07\0",
    )
    .unwrap();
    let cases = [
        ("missing.png", "file not found"),
        ("truncated.png", "cannot decode"),
        ("huge.png", "100000 x 100000 texels, beyond the limit of 16384 x 16384"),
        ("text.png", "not a PNG or JPEG"),
        ("corrupt.jpg", "cannot decode"),
        ("cut.jpg", "ends before its end-of-image marker"),
        ("basis.ktx2", "a KTX2 image; only PNG and JPEG are read"),
        ("leaf.webp", "a WebP image; only PNG and JPEG are read"),
    ];
    for (file, words) in cases {
        let path = card_gltf(&dir, file, masked_material(), nearest_clamp());
        let scene = assets::load(&path).unwrap_or_else(|e| panic!("{file}: {e}"));
        assert_eq!(scene.warnings().len(), 1, "{file}: {:?}", scene.warnings());
        let w = &scene.warnings()[0];
        assert!(w.starts_with(&path.display().to_string()), "{file}: the model is not named first: {w}");
        assert!(w.contains(file) && w.contains(words) && w.contains("material 'checker'"), "{file}: {w}");
        assert!(!w.contains('\n'), "{file}: more than one line: {w}");
        assert_eq!(scene.textures().count(), 0, "{file}");
        let (_, _, _, material) = scene.drawables().next().expect("card");
        assert_eq!(material.base_color_texture, None, "{file}");
    }
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn an_image_outside_the_model_folder_is_refused() {
    let dir = folder("outside");
    let inner = dir.join("model");
    std::fs::create_dir_all(&inner).unwrap();
    std::fs::write(dir.join("secret.png"), checker_png()).unwrap();
    for uri in ["../secret.png", "/etc/passwd", "file:///etc/passwd", "https://example.com/a.png"] {
        let path = card_gltf(&inner, uri, masked_material(), nearest_clamp());
        let err = match assets::load(&path) {
            Ok(_) => panic!("{uri} loaded"),
            Err(e) => e,
        };
        assert!(matches!(err.fault, AssetFault::OutsideFolder(_) | AssetFault::Access(_)), "{uri}: {err}");
        let msg = err.to_string();
        assert!(msg.starts_with(&path.display().to_string()) && msg.contains("image 0"), "{uri}: {msg}");
    }
    // With access anywhere the file beside the folder reads.
    let path = card_gltf(&inner, "../secret.png", masked_material(), nearest_clamp());
    let options = assets::LoadOptions { file_access: assets::FileAccess::Anywhere, ..Default::default() };
    assert_eq!(assets::load_with(&path, &options).expect("anywhere").textures().count(), 1);
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn obj_reads_map_kd_map_d_dissolve_and_flips_v() {
    let dir = folder("obj");
    std::fs::write(dir.join("leaf.png"), checker_png()).unwrap();
    let grey: Vec<u8> = (0..64).flat_map(|i| if i % 2 == 0 { [255, 255, 255, 255] } else { [0, 0, 0, 255] }).collect();
    std::fs::write(dir.join("mask.png"), png(8, 8, &grey)).unwrap();
    std::fs::write(
        dir.join("m.mtl"),
        "newmtl leaf\nKd 1 1 1\nmap_Kd -s 2 2 leaf.png\nmap_d leaf.png\n\
         newmtl glass\nKd 0.2 0.4 0.9\nTr 0.75\n\
         newmtl masked\nmap_d -imfchan m mask.png\n",
    )
    .unwrap();
    let obj = "mtllib m.mtl\nv 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nvt 0 0\nvt 1 0\nvt 1 1\nvt 0 1\n\
               o a\nusemtl leaf\nf 1/1 2/2 3/3 4/4\no b\nusemtl glass\nf 1/1 2/2 3/3\no c\nusemtl masked\nf 1/1 3/3 4/4\n";
    std::fs::write(dir.join("m.obj"), obj).unwrap();
    let scene = assets::load(dir.join("m.obj")).expect("obj");
    let path = dir.join("m.obj").display().to_string();
    assert_eq!(
        scene.warnings(),
        [format!("{path}: material 'masked' map_d: option -imfchan is not supported and is ignored")]
    );
    let by_name = |n: &str| scene.drawables().find(|d| d.3.name == n).map(|d| (d.2, d.3.clone())).expect(n);
    let (mesh, leaf) = by_name("leaf");
    assert_eq!(leaf.alpha_mode, AlphaMode::Mask { cutoff: 0.5 });
    let r = leaf.base_color_texture.expect("leaf texture");
    // uv * 2 in OBJ's v-up coordinates is v' * 2 - 1 in the mesh's v-down ones.
    assert_eq!((r.transform.scale, r.transform.offset), (Vec2::splat(2.0), Vec2::new(0.0, -1.0)));
    assert_eq!(scene.mesh(mesh).unwrap().uvs().expect("uvs")[0], Vec2::new(0.0, 1.0));
    let (_, glass) = by_name("glass");
    assert_eq!(glass.alpha_mode, AlphaMode::Blend);
    assert!((glass.alpha - 0.25).abs() < 1e-6 && glass.base_color_texture.is_none());
    // A grey map_d alone: white colour, alpha from its grey.
    let (_, masked) = by_name("masked");
    let t = scene.texture(masked.base_color_texture.expect("mask").texture).unwrap();
    assert_eq!(&t.levels()[0].data()[..2], &[[255, 255, 255, 255], [255, 255, 255, 0]]);
    assert_eq!(masked.alpha_mode, AlphaMode::Mask { cutoff: 0.5 });
    // leaf.png is decoded once, for map_Kd and map_d; mask.png once more.
    assert_eq!(scene.textures().count(), 2);
    let _ = std::fs::remove_dir_all(&dir);
}

/// The Khronos glTF validator's report on a file, where `SHADOWLAB_GLTF_VALIDATOR` names the
/// `node_modules` folder holding the npm package `gltf-validator` (CI installs it); `None` without it.
fn validate(path: &Path) -> Option<serde_json::Value> {
    let modules = std::env::var_os("SHADOWLAB_GLTF_VALIDATOR")?;
    let script = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/validate_gltf.cjs");
    let out = std::process::Command::new("node")
        .arg(script)
        .arg(path)
        .env("NODE_PATH", modules)
        .output()
        .expect("node runs (SHADOWLAB_GLTF_VALIDATOR is set)");
    assert!(
        out.status.success(),
        "the validator failed on {}: {}",
        path.display(),
        String::from_utf8_lossy(&out.stderr)
    );
    Some(serde_json::from_slice(&out.stdout).expect("the validator's report"))
}

#[test]
fn export_writes_textures_back_and_they_load_the_same() {
    let dir = folder("export");
    std::fs::write(dir.join("checker.png"), checker_png()).unwrap();
    let mut material = masked_material();
    material["pbrMetallicRoughness"]["baseColorTexture"]["extensions"]["KHR_texture_transform"]["rotation"] =
        json!(0.5);
    let scene = assets::load(card_gltf(&dir, "checker.png", material, nearest_clamp())).expect("card");
    let built_in = shadow_core::scenes::build("strike", &Default::default()).expect("strike");
    let mut validated = 0;
    for file in ["out.glb", "out.gltf", "my card.gltf"] {
        let out = dir.join(file);
        assets::export::export(&scene, &out).expect("export");
        let back = assets::load(&out).unwrap_or_else(|e| panic!("{file}: {e}"));
        assert!(back.warnings().is_empty(), "{file}: {:?}", back.warnings());
        let (_, _, mesh, m) = back.drawables().next().expect("card");
        let (_, _, mesh0, m0) = scene.drawables().next().expect("card");
        assert_eq!((&m.name, m.alpha_mode, m.alpha, m.two_sided), (&m0.name, m0.alpha_mode, m0.alpha, m0.two_sided));
        assert_eq!(m.base_color, m0.base_color, "{file}");
        let (r, r0) = (m.base_color_texture.expect("texture"), m0.base_color_texture.expect("texture"));
        assert_eq!((r.sampler, r.transform), (r0.sampler, r0.transform), "{file}");
        let (t, t0) = (back.texture(r.texture).unwrap(), scene.texture(r0.texture).unwrap());
        assert_eq!((t.name(), t.levels()), (t0.name(), t0.levels()), "{file}");
        assert_eq!(back.mesh(mesh).unwrap().uvs(), scene.mesh(mesh0).unwrap().uvs(), "{file}");
        let strike = dir.join(format!("strike-{file}"));
        assets::export::export(&built_in, &strike).expect("export strike");
        for path in [&out, &strike] {
            if let Some(report) = validate(path) {
                let counts = (&report["numErrors"], &report["numWarnings"], &report["numInfos"]);
                assert_eq!(counts, (&json!(0), &json!(0), &json!(0)), "{}: {report}", path.display());
                validated += 1;
            }
        }
    }
    if validated == 0 {
        eprintln!("glTF validator not run: set SHADOWLAB_GLTF_VALIDATOR to a node_modules folder with gltf-validator");
    }
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn a_jpeg_loads_as_a_texture() {
    let dir = folder("jpeg");
    std::fs::write(dir.join("ramp.jpg"), jpeg()).unwrap();
    let scene = assets::load(card_gltf(&dir, "ramp.jpg", masked_material(), nearest_clamp())).expect("card");
    assert!(scene.warnings().is_empty(), "{:?}", scene.warnings());
    let (_, t) = scene.textures().next().expect("texture");
    assert_eq!((t.width(), t.height(), t.levels().len()), (64, 64, 7));
    // Lossy, but close: red is four times the column, green four times the row.
    let [r, g, b, a] = *t.levels()[0].get(40, 3);
    assert!(r.abs_diff(160) <= 8 && g.abs_diff(12) <= 8 && b.abs_diff(7) <= 8 && a == 255, "{:?}", [r, g, b, a]);
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn the_texture_limits_are_checked_on_the_headers_in_the_order_the_model_names_them() {
    let dir = folder("limits");
    std::fs::write(dir.join("small.png"), checker_png()).unwrap();
    std::fs::write(dir.join("large.png"), png(16, 16, &[255; 16 * 16 * 4])).unwrap();
    std::fs::write(dir.join("m.mtl"), "newmtl a\nmap_Kd small.png\nnewmtl b\nmap_Kd large.png\n").unwrap();
    let obj = "mtllib m.mtl\nv 0 0 0\nv 1 0 0\nv 1 1 0\nvt 0 0\nvt 1 0\nvt 1 1\n\
               o a\nusemtl a\nf 1/1 2/2 3/3\no b\nusemtl b\nf 1/1 3/3 2/2\n";
    std::fs::write(dir.join("m.obj"), obj).unwrap();
    let with = |textures| assets::LoadOptions { textures, ..Default::default() };
    // The 8 x 8 chain holds 340 bytes, the 16 x 16 one 1364: a budget of 1000 takes the first only.
    let budget = assets::TextureLimits { max_scene_bytes: 1000, ..Default::default() };
    let scene = assets::load_with(dir.join("m.obj"), &with(budget)).expect("obj");
    assert_eq!(scene.textures().map(|(_, t)| t.name().to_string()).collect::<Vec<_>>(), ["small.png"]);
    assert_eq!(scene.warnings().len(), 1, "{:?}", scene.warnings());
    let w = &scene.warnings()[0];
    assert!(w.contains("'large.png'") && w.contains("past the scene's limit of 1000 bytes"), "{w}");
    // A side limit of 8 leaves the 16 x 16 image out by its header.
    let sides = assets::TextureLimits { max_side: 8, ..Default::default() };
    let scene = assets::load_with(dir.join("m.obj"), &with(sides)).expect("obj");
    assert_eq!(scene.textures().count(), 1);
    assert!(scene.warnings()[0].contains("16 x 16 texels, beyond the limit of 8 x 8"), "{:?}", scene.warnings());
    let _ = std::fs::remove_dir_all(&dir);
}
