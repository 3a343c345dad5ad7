//! WGSL that a host application's own shaders import to read shadowlab's results: each light's
//! visibility as [`FrameRecorder`](crate::FrameRecorder) leaves it ([`VISIBILITY`]).
//!
//! The module is plain WGSL without bindings of its own: the host binds the texture where it likes and
//! passes it to the functions. Paste it before the host's shader, or compose it with `naga_oil` under
//! [`VISIBILITY_IMPORT_PATH`]. Its functions:
//!
//! - `shadowlab_visibility(visibility, pixel: vec2<u32>, light: u32) -> f32`: a light's visibility at a
//!   pixel of the recorded view, 1 lit, 0 shadowed, in between in a penumbra;
//! - `shadowlab_visibility_at(visibility, frag_position: vec4<f32>, light: u32) -> f32`: the same at a
//!   fragment's `@builtin(position)`, for a pass drawn at the recorded view's size;
//! - `shadowlab_light_count(visibility) -> u32`: how many layers (lights) it holds.
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

    #[test]
    fn the_file_at_the_path_is_the_module() {
        assert_eq!(std::fs::read_to_string(VISIBILITY_PATH).expect("the file"), VISIBILITY);
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
    fn naga_oil_composes_it_under_its_import_path() {
        use naga_oil::compose::{ComposableModuleDescriptor, Composer, NagaModuleDescriptor};
        let mut composer = Composer::default();
        let added = composer.add_composable_module(ComposableModuleDescriptor {
            source: VISIBILITY,
            file_path: VISIBILITY_PATH,
            as_name: Some(VISIBILITY_IMPORT_PATH.into()),
            ..Default::default()
        });
        if let Err(e) = added {
            panic!("{}", e.emit_to_string(&composer));
        }
        let import = format!("#import {VISIBILITY_IMPORT_PATH}::{{shadowlab_visibility_at, shadowlab_light_count}}");
        let source = host_shader(&import);
        let module = composer
            .make_naga_module(NagaModuleDescriptor { source: &source, file_path: "host.wgsl", ..Default::default() })
            .unwrap_or_else(|e| panic!("{}", e.emit_to_string(&composer)));
        validate(&module);
        assert!(module.entry_points.iter().any(|e| e.name == "fs_main"));
    }
}
