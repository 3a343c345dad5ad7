//! `shadowlab inspect`: a scene's or model file's meshes, materials and textures, as text or JSON.

use std::path::Path;

use serde_json::json;
use shadow_core::assets::FileAccess;
use shadow_core::inspect::{Inspection, MaterialStats};
use shadow_core::material::{AlphaMode, Filter, Wrap};
use shadow_core::scenes;
use shadowlab::Error;
use shadowlab::setup::SceneSetup;

use super::{args, print_json, stdout_error};

pub(crate) fn inspect(target: &str, json: bool, allow_outside_files: bool) -> Result<(), Error> {
    let path = Path::new(target);
    let is_file = shadow_core::assets::is_model_path(path) || path.exists();
    let file_access = if allow_outside_files { FileAccess::Anywhere } else { FileAccess::ModelFolder };
    let i = if is_file {
        // The file's own numbers; the silhouette from the default staged light.
        let options = shadow_core::assets::LoadOptions { file_access, ..Default::default() };
        let raw = shadow_core::assets::load_with(path, &options)
            .map_err(|e| Error::Setup(shadowlab::SceneSourceError::Asset(e).into()))?;
        args::print_warnings(&raw);
        let of_file = Inspection::of(&raw);
        // Staged in place rather than loaded again: its images are decoded once.
        let mut staged = raw;
        scenes::stage_model(&mut staged, false);
        Inspection { silhouette_edges: Inspection::silhouette_edges_of(&staged), ..of_file }
    } else {
        Inspection::of(&SceneSetup::new(target).build()?)
    };
    if json {
        return print_json(&json!({
            "triangles": i.triangles,
            "vertices": i.vertices,
            "closed": i.closed,
            "components": i.components,
            "boundary_edges": i.boundary_edges,
            "non_manifold_edges": i.non_manifold_edges,
            "inconsistent_edges": i.inconsistent_edges,
            "bounds": {"min": i.bounds.min.to_array(), "max": i.bounds.max.to_array()},
            "silhouette_edges": i.silhouette_edges,
            "meshes": i.meshes,
            "instances": i.instances,
            "mesh_bytes": i.mesh_bytes,
            "unshared_mesh_bytes": i.unshared_mesh_bytes,
            "meshes_with_texture_coordinates": i.meshes_with_uvs,
            "materials": i.materials.iter().map(material_json).collect::<Vec<_>>(),
            "textures": i.textures.iter().map(|t| json!({
                "name": t.name, "width": t.width, "height": t.height, "bytes_with_mips": t.bytes,
            })).collect::<Vec<_>>(),
            "animations": i.animations.iter().map(|a| json!({
                "name": a.name, "duration_s": a.duration, "channels": a.channels, "nodes": a.nodes,
                "interpolations": a.interpolations,
            })).collect::<Vec<_>>(),
            "skins": i.skins.iter().map(|(name, joints)| json!({"name": name, "joints": joints})).collect::<Vec<_>>(),
            "meshes_with_morph_targets": i.morphed_meshes.0,
            "most_morph_targets": i.morphed_meshes.1,
        }));
    }
    out!("{target}");
    out!("  triangles           {}", i.triangles);
    out!("  vertices (welded)   {}", i.vertices);
    out!("  closed              {}", i.closed);
    out!("  components          {}", i.components);
    out!("  boundary edges      {}", i.boundary_edges);
    out!("  non-manifold edges  {}", i.non_manifold_edges);
    out!("  inconsistent edges  {}", i.inconsistent_edges);
    out!("  bounds              {} .. {}", i.bounds.min, i.bounds.max);
    match i.silhouette_edges {
        Some(n) => out!("  silhouette edges    {n} (default light)"),
        None => out!("  silhouette edges    - (no light)"),
    }
    out!(
        "  meshes              {} drawn by {} instance{} ({} of geometry; {} saved by sharing)",
        i.meshes,
        i.instances,
        if i.instances == 1 { "" } else { "s" },
        in_units(i.mesh_bytes),
        in_units(i.unshared_mesh_bytes - i.mesh_bytes)
    );
    out!("  texture coordinates {} of {} meshes", i.meshes_with_uvs, i.meshes);
    let count = |mode: &str| i.materials.iter().filter(|m| m.alpha_mode.name() == mode).count();
    let sides = i.materials.iter().filter(|m| m.double_sided).count();
    out!(
        "  materials           {} ({} opaque, {} masked, {} blended; {sides} double-sided)",
        i.materials.len(),
        count("OPAQUE"),
        count("MASK"),
        count("BLEND")
    );
    for m in &i.materials {
        let mode = match m.alpha_mode {
            AlphaMode::Mask { cutoff } => format!("MASK {cutoff}"),
            other => other.name().to_string(),
        };
        let texture = m.texture.map_or(String::new(), |t| format!("  texture {t}"));
        let sides = if m.double_sided { "double-sided" } else { "single-sided" };
        out!("    {:<20} {mode:<10} {sides}{texture}", m.name);
    }
    let bytes: usize = i.textures.iter().map(|t| t.bytes).sum();
    out!("  textures            {} ({:.1} MiB with mip chains)", i.textures.len(), bytes as f64 / f64::from(1 << 20));
    for (n, t) in i.textures.iter().enumerate() {
        out!("    {n:<3} {} x {}  {}", t.width, t.height, t.name);
    }
    let joints: usize = i.skins.iter().map(|s| s.1).sum();
    out!("  skins               {} ({joints} joints)", i.skins.len());
    out!("  morph targets       {} meshes, up to {} targets", i.morphed_meshes.0, i.morphed_meshes.1);
    out!("  animations          {}", i.animations.len());
    for a in &i.animations {
        out!(
            "    {:<20} {:.3} s, {} channel(s) on {} node(s), {}",
            a.name,
            a.duration,
            a.channels,
            a.nodes,
            a.interpolations.join(", ")
        );
    }
    Ok(())
}

/// A material as `inspect --json` lists it.
fn material_json(m: &MaterialStats) -> serde_json::Value {
    let mut j = json!({
        "name": m.name, "alpha_mode": m.alpha_mode.name(), "double_sided": m.double_sided,
        "base_color_texture": m.texture,
    });
    if let AlphaMode::Mask { cutoff } = m.alpha_mode {
        j["alpha_cutoff"] = json!(cutoff);
    }
    if let Some(s) = m.sampler {
        let filter = |f: Option<Filter>| match f {
            None => "none",
            Some(Filter::Nearest) => "nearest",
            Some(Filter::Linear) => "linear",
        };
        let wrap = |w: Wrap| match w {
            Wrap::Repeat => "repeat",
            Wrap::ClampToEdge => "clamp_to_edge",
            Wrap::MirroredRepeat => "mirrored_repeat",
        };
        j["sampler"] = json!({
            "mag": filter(Some(s.mag)), "min": filter(Some(s.min)), "mipmap": filter(s.mipmap),
            "wrap_u": wrap(s.wrap_u), "wrap_v": wrap(s.wrap_v),
        });
    }
    j
}

/// A number of bytes in KiB or MiB, one decimal.
fn in_units(bytes: usize) -> String {
    let kib = bytes as f64 / 1024.0;
    if kib < 1024.0 { format!("{kib:.1} KiB") } else { format!("{:.1} MiB", kib / 1024.0) }
}
