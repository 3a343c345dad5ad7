//! The one integration-test binary (DESIGN 9): the command line, and cross-backend conformance of every
//! registered technique, the example's runtime-registered one included.

mod animated;
mod cache;
mod cli;
mod cutouts;
mod depth_layers;
mod extrusion;
mod gpu_clock;
mod head_on;
mod host;
mod host_shading;
mod hybrid;
mod many;
mod moment_maps;
mod own_pixels;
mod penumbra_wedges;
mod per_light;
mod pipelines;
mod reach;
mod settings;
mod silhouette_map;
mod single_sided;
mod smoothies;
mod sources;
// The technique of examples/custom_technique.rs, registered at runtime like a user's would be.
#[path = "../../examples/planar/mod.rs"]
#[allow(dead_code)]
mod planar;
mod recorded;
mod scale;
mod suite;
mod texel_rule;
mod view_fitted;
#[cfg(feature = "viewer")]
mod viewer;
mod volume_reconstruction;
mod wgsl;

/// Whether visibility `v` is shadowed, as every metric splits lit from shadowed (below one half): a
/// test that a frame is not all lit asks for this, not for an exact 0, which a filterable map's bound
/// leaves a trace above even in the umbra.
fn shadowed(v: f32) -> bool {
    v < 0.5
}

/// Built-in scene `name` under a light of a kind `lights` takes: its own light, or for the techniques of
/// directional lights alone (cascades, the perspective warps), a directional light in its place.
fn scene_taken_by(name: &str, lights: shadow_core::technique::LightKinds) -> shadow_core::Scene {
    use shadow_core::scenes::{self, LightType, SceneParams};
    let own = scenes::build(name, &SceneParams::default()).expect("built-in scene");
    if own.lights().all(|(_, l)| lights.takes(&l)) {
        return own;
    }
    let params = SceneParams { light: Some(LightType::Directional), ..SceneParams::default() };
    scenes::build(name, &params).expect("built-in scene")
}

/// The first camera's frame of [`scene_taken_by`].
fn frame_taken_by(name: &str, lights: shadow_core::technique::LightKinds) -> shadow_core::FrameInputs {
    shadow_core::FrameInputs::from_first_camera(&scene_taken_by(name, lights)).expect("frame")
}

/// A renderer of the built-in techniques with a wgpu adapter resolved, or `None` (and a line saying that
/// `what` is skipped) without one, which `SHADOWLAB_REQUIRE_GPU=1` turns into a failure.
fn with_wgpu(what: &str) -> Option<shadowlab::Renderer> {
    let mut renderer = shadowlab::Renderer::new(shadowlab::TechniqueRegistry::builtin());
    if let Err(e) = renderer.resolve(shadowlab::BackendChoice::Wgpu) {
        let require = std::env::var("SHADOWLAB_REQUIRE_GPU").is_ok_and(|v| v == "1");
        assert!(!require, "SHADOWLAB_REQUIRE_GPU=1 but no wgpu adapter: {e}");
        eprintln!("{what} skipped: no wgpu adapter ({e})");
        return None;
    }
    Some(renderer)
}
