//! The backend's WGSL: the frame bindings every pass shares (`common.wgsl`), the G-buffer and shading
//! passes, and the shared passes' shaders (`shadow_map.wgsl` for `passes::maps`, `shadow_volume.wgsl` for
//! `passes::volumes`). Each is `common.wgsl` and the full-screen triangle followed by its own file; the shadow-map shader also gets the
//! Poisson disk generated from shadow-core's constant, so the two backends share one table. A technique's
//! own WGSL lives in its folder and is appended to one of these.

use std::fmt::Write;

const COMMON: &str = include_str!("shaders/common.wgsl");
const FULL_SCREEN: &str = include_str!("shaders/full_screen.wgsl");

/// `common.wgsl` + `body`: for a technique's shader that reads the frame's bindings.
#[must_use]
pub fn with_common(body: &str) -> String {
    format!("{COMMON}\n{FULL_SCREEN}\n{body}")
}

/// The full-screen triangle (`vs_full_screen`) + `body`: for a pass over a texture's texels that reads
/// none of the frame's bindings (a technique's own build passes).
#[must_use]
pub fn with_full_screen(body: &str) -> String {
    format!("{FULL_SCREEN}\n{body}")
}

/// The Poisson disk of `shadow_core::lookup::POISSON16` as a WGSL constant.
fn poisson_constant() -> String {
    let mut s = String::from("const POISSON16 = array<vec2<f32>, 16>(");
    for (i, p) in shadow_core::lookup::POISSON16.iter().enumerate() {
        let _ = write!(s, "{}vec2<f32>({:?}, {:?})", if i == 0 { "" } else { ", " }, p.x, p.y);
    }
    s.push_str(");\n");
    s
}

/// The texel rule (`texel.wgsl`): how a material's texture is read, for the shaders that read one.
pub const TEXEL: &str = include_str!("shaders/texel.wgsl");

/// G-buffer pass, with the texel rule for textured surfaces.
#[must_use]
pub fn gbuffer() -> String {
    with_common(&format!("{TEXEL}\n{}", include_str!("shaders/gbuffer.wgsl")))
}

/// The G-buffer from a host's depth and normals.
#[must_use]
pub fn import() -> String {
    with_common(include_str!("shaders/import.wgsl"))
}

/// Shading pass.
#[must_use]
pub fn shade() -> String {
    with_common(include_str!("shaders/shade.wgsl"))
}

/// `common.wgsl`, the texel rule and the light-pass stages of casters a texture cuts out
/// (`cutout_casters.wgsl`: `vs_light_cutout` and `caster_there`, the texture in group 2) + `body`: for a
/// shader of light passes that draw casters.
#[must_use]
pub fn with_cutout_casters(body: &str) -> String {
    with_common(&format!("{TEXEL}\n{}\n{body}", include_str!("shaders/cutout_casters.wgsl")))
}

/// Shadow-map light pass (casters a texture cuts out included) and query.
#[must_use]
pub fn shadow_map() -> String {
    with_cutout_casters(&format!("{}{}", poisson_constant(), include_str!("shaders/shadow_map.wgsl")))
}

/// The shadow-map shader followed by `query`: a query written against `MapQuery`'s bindings and the
/// shadow-map shader's functions (the silhouette map's, hybrid's and the soft techniques' in shadow-soft).
#[must_use]
pub fn with_shadow_map(query: &str) -> String {
    format!("{}\n{query}", shadow_map())
}

/// Shadow-volume pass and resolve.
#[must_use]
pub fn shadow_volume() -> String {
    with_common(include_str!("shaders/shadow_volume.wgsl"))
}

/// The shadow-volume shader followed by the GPU extrusion's compute passes and the vertex shaders that
/// draw what they find (`passes::extrusion`).
#[must_use]
pub fn extrusion() -> String {
    format!("{}\n{}", shadow_volume(), include_str!("shaders/extrude.wgsl"))
}

/// The pose of skinned and morphed meshes (`crate::posing`).
#[must_use]
pub fn pose() -> String {
    include_str!("shaders/pose.wgsl").to_string()
}

/// Every shader of the backend, by name, for validation.
#[must_use]
pub fn all() -> Vec<(&'static str, String)> {
    vec![
        ("gbuffer", gbuffer()),
        ("import", import()),
        ("shade", shade()),
        ("shadow_map", shadow_map()),
        ("shadow_volume", shadow_volume()),
        ("extrusion", extrusion()),
        ("pose", pose()),
        ("texel", TEXEL.to_string()),
        // The host modules, each before a host's shader that uses it.
        (
            "host visibility",
            format!("{}\n{}", crate::host_wgsl::VISIBILITY, include_str!("shaders/host/test_host.wgsl")),
        ),
        ("host maps", format!("{}\n{}", crate::host_wgsl::MAPS, include_str!("shaders/host/test_host_maps.wgsl"))),
    ]
}
