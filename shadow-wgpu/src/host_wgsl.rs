//! WGSL that a host application's own shaders import to read shadowlab's results: each light's
//! visibility as [`FrameRecorder`](crate::FrameRecorder) leaves it ([`VISIBILITY`]), and the depth maps
//! of the techniques that lend them, looked into with the technique's own filter ([`MAPS`]).
//!
//! Each module is plain WGSL without bindings of its own: the host binds the textures where it likes
//! and passes them to the functions. Paste a module before the host's shader, or compose it with
//! `naga_oil` under its import path ([`VISIBILITY_IMPORT_PATH`], [`MAPS_IMPORT_PATH`]). The visibility
//! module's functions:
//!
//! - `shadowlab_visibility(visibility, pixel: vec2<u32>, light: u32) -> f32`: a light's visibility at a
//!   pixel of the recorded view, 1 lit, 0 shadowed, in between in a penumbra;
//! - `shadowlab_visibility_at(visibility, frag_position: vec4<f32>, light: u32) -> f32`: the same at a
//!   fragment's `@builtin(position)`, for a pass drawn at the recorded view's size;
//! - `shadowlab_light_count(visibility) -> u32`: how many layers (lights) it holds.
//!
//! The maps module's: `shadowlab_map_visibility(maps, cmp, map: ShadowlabMap, p: vec3<f32>, pixel:
//! vec2<u32>) -> f32`, a light's visibility at any world point `p` (a forward pass's fragments, points
//! the G-buffer never held) through [`FrameRecorder::map`](crate::FrameRecorder::map)'s maps
//! ([`HostMap`](crate::HostMap)).
//!
//! ```
//! use shadow_wgpu::host_wgsl;
//!
//! // A host's shading pass, its own bindings first, the module pasted before it.
//! let host = "
//!     @group(0) @binding(0) var visibility: texture_2d_array<f32>;
//!     @fragment
//!     fn fs_main(@builtin(position) pos: vec4<f32>) -> @location(0) vec4<f32> {
//!         let lit = shadowlab_visibility_at(visibility, pos, 0u);
//!         return vec4<f32>(vec3<f32>(0.15 + 0.85 * lit), 1.0);
//!     }";
//! let source = format!("{}\n{host}", host_wgsl::VISIBILITY);
//! let module = naga::front::wgsl::parse_str(&source).expect("valid WGSL");
//! assert!(module.entry_points.iter().any(|e| e.name == "fs_main"));
//! ```

/// The visibility module's source (`src/shaders/host/visibility.wgsl` in this crate).
pub const VISIBILITY: &str = include_str!("shaders/host/visibility.wgsl");

/// Where the visibility module's file is, for hosts that load or watch shader files themselves: its path
/// in this crate's sources as they were built.
pub const VISIBILITY_PATH: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/src/shaders/host/visibility.wgsl");

/// The name to compose the visibility module under with `naga_oil` (its `ComposableModuleDescriptor`'s
/// `as_name`; the file has no `#define_import_path`, so it stays plain WGSL).
pub const VISIBILITY_IMPORT_PATH: &str = "shadowlab::visibility";

/// The maps module's source (`src/shaders/host/maps.wgsl` in this crate).
pub const MAPS: &str = include_str!("shaders/host/maps.wgsl");

/// Where the maps module's file is, as [`VISIBILITY_PATH`] for the visibility module.
pub const MAPS_PATH: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/src/shaders/host/maps.wgsl");

/// The name to compose the maps module under with `naga_oil`.
pub const MAPS_IMPORT_PATH: &str = "shadowlab::maps";

#[cfg(test)]
mod tests {
    use super::*;

    /// A host's fragment shader that reads every light's visibility, `prelude` in front of it.
    fn host_shader(prelude: &str) -> String {
        format!("{prelude}\n{}", include_str!("shaders/host/test_host.wgsl"))
    }

    fn validate(module: &naga::Module) {
        let flags = naga::valid::ValidationFlags::all();
        naga::valid::Validator::new(flags, naga::valid::Capabilities::empty())
            .validate(module)
            .unwrap_or_else(|e| panic!("{e:?}"));
    }

    fn parse(source: &str) -> naga::Module {
        naga::front::wgsl::parse_str(source).unwrap_or_else(|e| panic!("{}", e.emit_to_string(source)))
    }

    #[test]
    fn the_files_at_the_paths_are_the_modules() {
        assert_eq!(std::fs::read_to_string(VISIBILITY_PATH).expect("the file"), VISIBILITY);
        assert_eq!(std::fs::read_to_string(MAPS_PATH).expect("the file"), MAPS);
    }

    #[test]
    fn the_maps_module_validates_and_its_disk_is_the_backends() {
        validate(&parse(MAPS));
        let host = format!("{MAPS}\n{}", include_str!("shaders/host/test_host_maps.wgsl"));
        validate(&parse(&host));
        let disk = shadow_core::lookup::POISSON16.map(|p| format!("vec2<f32>({:?}, {:?})", p.x, p.y)).join(",\n    ");
        assert!(MAPS.contains(&format!("const SHADOWLAB_POISSON16 = array<vec2<f32>, 16>(\n    {disk}\n);")));
    }

    #[test]
    fn pasted_before_a_hosts_shader_it_validates() {
        let alone =
            naga::front::wgsl::parse_str(VISIBILITY).unwrap_or_else(|e| panic!("{}", e.emit_to_string(VISIBILITY)));
        validate(&alone);
        let source = host_shader(VISIBILITY);
        let module = naga::front::wgsl::parse_str(&source).unwrap_or_else(|e| panic!("{}", e.emit_to_string(&source)));
        validate(&module);
        assert!(module.entry_points.iter().any(|e| e.name == "fs_main"));
    }

    #[test]
    fn naga_oil_composes_them_under_their_import_paths() {
        use naga_oil::compose::{ComposableModuleDescriptor, Composer, NagaModuleDescriptor};
        let mut composer = Composer::default();
        for (source, file_path, name) in
            [(VISIBILITY, VISIBILITY_PATH, VISIBILITY_IMPORT_PATH), (MAPS, MAPS_PATH, MAPS_IMPORT_PATH)]
        {
            let descriptor =
                ComposableModuleDescriptor { source, file_path, as_name: Some(name.into()), ..Default::default() };
            if let Err(e) = composer.add_composable_module(descriptor) {
                panic!("{}", e.emit_to_string(&composer));
            }
        }
        let hosts = [
            (
                format!("#import {VISIBILITY_IMPORT_PATH}::{{shadowlab_visibility_at, shadowlab_light_count}}"),
                include_str!("shaders/host/test_host.wgsl"),
            ),
            (
                format!("#import {MAPS_IMPORT_PATH}::{{ShadowlabMap, shadowlab_map_visibility}}"),
                include_str!("shaders/host/test_host_maps.wgsl"),
            ),
        ];
        for (import, host) in hosts {
            let source = format!("{import}\n{host}");
            let module = composer
                .make_naga_module(NagaModuleDescriptor {
                    source: &source,
                    file_path: "host.wgsl",
                    ..Default::default()
                })
                .unwrap_or_else(|e| panic!("{}", e.emit_to_string(&composer)));
            validate(&module);
            assert!(module.entry_points.iter().any(|e| e.name == "fs_main"));
        }
    }
}
