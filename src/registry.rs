//! The technique registry: name -> description, paper, lights, settings keys with defaults, and a
//! constructor per backend. Built-in, shadow-soft and user techniques register the same way (each
//! technique's folder makes its own entry); the CLI, the reports and the conformance tests enumerate it, so
//! a new technique gets all of them for free.

use shadow_core::FrameInputs;
use shadow_core::technique::DynShadowTechnique;
use shadow_core::technique::settings::{SettingsError, TechniqueSpec};
use shadow_cpu::CpuBackend;
use shadow_wgpu::WgpuBackend;

/// One registered technique, on the two backends (see [`shadow_core::technique::registry::Entry`]).
pub type TechniqueEntry = shadow_core::technique::registry::Entry<CpuBackend, WgpuBackend>;

/// Why a technique could not be made.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum RegistryError {
    /// No technique of that name.
    #[error("unknown technique '{name}' (techniques: {known})")]
    Unknown {
        /// The name asked for.
        name: String,
        /// The names registered.
        known: String,
    },
    /// The technique has no implementation on that backend.
    #[error("technique '{name}' is not implemented on the {backend} backend")]
    NotOnBackend {
        /// The technique.
        name: String,
        /// The backend.
        backend: &'static str,
    },
    /// Bad settings.
    #[error(transparent)]
    Settings(#[from] SettingsError),
}

/// A technique [`TechniqueRegistry::measurable`] leaves out of a frame, and why.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct LeftOut {
    /// The technique.
    pub name: &'static str,
    /// Why, as a clause: "as ...".
    pub why: &'static str,
}

impl LeftOut {
    /// It or its reference takes none of the frame's kinds of light.
    pub const LIGHTS: &'static str = "as they or their reference take no light of this scene's kinds";
    /// It takes no masked casters, and the frame has casters cut out by their texture.
    pub const CUTOUTS: &'static str =
        "as they take no masked casters and this scene's casters are cut out by their textures";
}

/// Every technique, by name.
#[derive(Clone, Default)]
pub struct TechniqueRegistry {
    entries: Vec<TechniqueEntry>,
}

impl TechniqueRegistry {
    /// The built-in techniques, in the order `shadowlab techniques` lists them: the references first.
    #[must_use]
    pub fn builtin() -> Self {
        let mut r = Self::default();
        for entry in [
            shadow_hard::ray_traced::entry(),
            shadow_soft::area_light::entry(),
            shadow_hard::shadow_map::entry(),
            shadow_hard::silhouette_map::entry(),
            shadow_hard::volume_reconstruction::entry(),
            shadow_hard::hybrid::entry(),
            shadow_soft::smoothies::entry(),
            shadow_soft::pcss::entry(),
            shadow_soft::penumbra_map::entry(),
            shadow_soft::moment_maps::variance_entry(),
            shadow_soft::moment_maps::exponential_variance_entry(),
            shadow_soft::moment_maps::moment_entry(),
            shadow_soft::penumbra_wedges::entry(),
            shadow_hard::shadow_volume::zpass_entry(),
            shadow_hard::shadow_volume::zfail_entry(),
            shadow_hard::depth_layers::midpoint_entry(),
            shadow_hard::depth_layers::second_depth_entry(),
            shadow_hard::depth_layers::dual_entry(),
            shadow_hard::cascaded_shadow_map::entry(),
            shadow_hard::lispsm::entry(),
            shadow_hard::perspective_shadow_map::entry(),
        ] {
            r.register(entry);
        }
        r
    }

    /// The techniques `compare` and `results` measure on `frame` when none is named: every one that is
    /// not a reference, that takes every light of the frame, as do the references of its kind (hard or
    /// soft), and that takes its casters (a frame with casters cut out by their texture leaves out the
    /// techniques that take no masked casters), in registration order; and those left out, each with why.
    #[must_use]
    pub fn measurable(&self, frame: &FrameInputs) -> (Vec<TechniqueSpec>, Vec<LeftOut>) {
        let lit = |e: &TechniqueEntry| frame.lights.iter().all(|l| e.lights.takes(l));
        let cutouts = frame.has_cutout_casters();
        let mut taken = Vec::new();
        let mut left = Vec::new();
        for e in self.entries.iter().filter(|e| !e.reference) {
            if !(lit(e) && self.entries.iter().filter(|r| r.reference && r.soft == e.soft).all(lit)) {
                left.push(LeftOut { name: e.name, why: LeftOut::LIGHTS });
            } else if cutouts && !e.casters.takes_cutouts() {
                left.push(LeftOut { name: e.name, why: LeftOut::CUTOUTS });
            } else {
                taken.push(TechniqueSpec::named(e.name));
            }
        }
        (taken, left)
    }

    /// Adds (or replaces) a technique.
    pub fn register(&mut self, entry: TechniqueEntry) {
        self.entries.retain(|e| e.name != entry.name);
        self.entries.push(entry);
    }

    /// Every entry, in registration order.
    #[must_use]
    pub fn entries(&self) -> &[TechniqueEntry] {
        &self.entries
    }

    /// The entry for a name.
    ///
    /// # Errors
    /// [`RegistryError::Unknown`].
    pub fn get(&self, name: &str) -> Result<&TechniqueEntry, RegistryError> {
        self.entries.iter().find(|e| e.name == name).ok_or_else(|| RegistryError::Unknown {
            name: name.into(),
            known: self.entries.iter().map(|e| e.name).collect::<Vec<_>>().join(", "),
        })
    }

    /// Checks a spec (name and settings) and returns its canonical settings string.
    ///
    /// # Errors
    /// Unknown name or bad settings.
    pub fn canonical(&self, spec: &TechniqueSpec) -> Result<String, RegistryError> {
        Ok((self.get(&spec.name)?.canonical)(spec)?)
    }

    /// The wgpu implementation of a spec.
    ///
    /// # Errors
    /// Unknown name, bad settings, or no wgpu implementation.
    pub fn wgpu(&self, spec: &TechniqueSpec) -> Result<Box<dyn DynShadowTechnique<WgpuBackend>>, RegistryError> {
        let e = self.get(&spec.name)?;
        let make = e.wgpu.ok_or_else(|| RegistryError::NotOnBackend { name: spec.name.clone(), backend: "wgpu" })?;
        Ok(make(spec)?)
    }

    /// The CPU implementation of a spec.
    ///
    /// # Errors
    /// Unknown name, bad settings, or no CPU implementation.
    pub fn cpu(&self, spec: &TechniqueSpec) -> Result<Box<dyn DynShadowTechnique<CpuBackend>>, RegistryError> {
        let e = self.get(&spec.name)?;
        let make = e.cpu.ok_or_else(|| RegistryError::NotOnBackend { name: spec.name.clone(), backend: "cpu" })?;
        Ok(make(spec)?)
    }
}

#[cfg(test)]
mod tests {
    use shadow_core::material::AlphaMode;
    use shadow_core::scenes::{self, SceneParams};

    use super::*;

    /// Every built-in technique takes casters cut out by their texture. One that takes none
    /// (`Entry::without_cutouts`, as a user's technique on silhouettes may say) is left out of a scene
    /// whose card is cut out, saying why; the same card made opaque or blended leaves it in.
    #[test]
    fn cutouts_leave_out_the_techniques_that_take_no_masked_casters() {
        let mut registry = TechniqueRegistry::builtin();
        let refusing: Vec<&str> =
            registry.entries().iter().filter(|e| !e.casters.takes_cutouts()).map(|e| e.name).collect();
        assert!(refusing.is_empty(), "{refusing:?}");
        let zfail = registry.get("shadow-volume-zfail").expect("z-fail").clone();
        registry.register(zfail.without_cutouts());
        let mut scene = scenes::build("cutout", &SceneParams::default()).expect("cutout");
        let left_for_cutouts = |scene: &shadow_core::Scene| {
            let frame = FrameInputs::from_first_camera(scene).expect("frame");
            let (taken, left) = registry.measurable(&frame);
            assert!(taken.iter().any(|t| t.name == "shadow-map"), "the map techniques are measured");
            left.iter().filter(|l| l.why == LeftOut::CUTOUTS).map(|l| l.name).collect::<Vec<_>>()
        };
        assert_eq!(left_for_cutouts(&scene), ["shadow-volume-zfail"]);
        let card = scene.materials().find(|(_, m)| m.name == "checkerboard").expect("the card").0;
        for mode in [AlphaMode::Opaque, AlphaMode::Blend] {
            scene.material_mut(card).expect("material").alpha_mode = mode;
            assert!(left_for_cutouts(&scene).is_empty(), "{mode:?}");
        }
    }
}
