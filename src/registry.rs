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
    /// not a reference and that takes every light of the frame, as do the references of its kind (hard or
    /// soft), in registration order; and the names of those left out.
    #[must_use]
    pub fn measurable(&self, frame: &FrameInputs) -> (Vec<TechniqueSpec>, Vec<&'static str>) {
        let lit = |e: &TechniqueEntry| frame.lights.iter().all(|l| e.lights.takes(l));
        let (taken, left): (Vec<_>, Vec<_>) = self
            .entries
            .iter()
            .filter(|e| !e.reference)
            .partition(|e| lit(e) && self.entries.iter().filter(|r| r.reference && r.soft == e.soft).all(lit));
        (taken.iter().map(|e| TechniqueSpec::named(e.name)).collect(), left.iter().map(|e| e.name).collect())
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
