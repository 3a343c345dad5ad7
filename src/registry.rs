//! The technique registry: name -> description, paper, settings keys with defaults, and a constructor per
//! backend. Built-in, shadow-soft and user techniques register the same way; the CLI, the reports and the
//! conformance tests enumerate it, so a new technique gets all of them for free.

use shadow_core::technique::settings::{SettingKey, SettingsError, TechniqueSettings, TechniqueSpec};
use shadow_core::technique::{DynShadowTechnique, ShadowTechnique, Stateful};
use shadow_cpu::CpuBackend;
use shadow_hard::{
    DepthLayers, DualShadowMap, Hybrid, MidpointShadowMap, RayTraced, SecondDepthShadowMap, ShadowMap, ShadowVolume,
    SilhouetteMap, VolumeReconstruction,
};
use shadow_soft::{AreaLightReference, Pcss, PenumbraMap, Smoothies};
use shadow_wgpu::WgpuBackend;

/// Builds a technique for the CPU backend from a spec.
pub type CpuConstructor = fn(&TechniqueSpec) -> Result<Box<dyn DynShadowTechnique<CpuBackend>>, SettingsError>;

/// Builds a technique for the wgpu backend from a spec.
pub type WgpuConstructor = fn(&TechniqueSpec) -> Result<Box<dyn DynShadowTechnique<WgpuBackend>>, SettingsError>;

type LayerFns = (
    fn() -> &'static [SettingKey],
    fn(&TechniqueSpec) -> Result<String, SettingsError>,
    CpuConstructor,
    WgpuConstructor,
);

/// One registered technique.
#[derive(Clone)]
pub struct TechniqueEntry {
    /// Registry name.
    pub name: &'static str,
    /// One line on what it does.
    pub description: &'static str,
    /// The paper it follows.
    pub paper: &'static str,
    /// Whether it is a reference (measured against, not measured).
    pub reference: bool,
    /// Whether it renders soft shadows: measured against `area-light-reference` (hard techniques against
    /// `ray-traced`).
    pub soft: bool,
    /// Settings keys with defaults.
    pub keys: fn() -> &'static [SettingKey],
    /// Canonical settings string of a spec (all keys, defaults filled in).
    pub canonical: fn(&TechniqueSpec) -> Result<String, SettingsError>,
    /// The CPU implementation, if any.
    pub cpu: Option<CpuConstructor>,
    /// The wgpu implementation, if any.
    pub wgpu: Option<WgpuConstructor>,
}

impl TechniqueEntry {
    /// The entry of a technique whose settings type is itself the technique on both backends (the usual
    /// case: `S` implements `TechniqueSettings`, and `ShadowTechnique` for `CpuBackend` and `WgpuBackend`).
    #[must_use]
    pub fn on_both<S>(name: &'static str, description: &'static str, paper: &'static str) -> Self
    where
        S: TechniqueSettings + ShadowTechnique<CpuBackend> + ShadowTechnique<WgpuBackend> + 'static,
    {
        Self {
            name,
            description,
            paper,
            reference: false,
            soft: false,
            keys: S::keys,
            canonical: canonical::<S>,
            cpu: Some(plain::<CpuBackend, S>),
            wgpu: Some(plain::<WgpuBackend, S>),
        }
    }

    /// The same entry, for a soft technique (measured against `area-light-reference`).
    #[must_use]
    pub fn soft(self) -> Self {
        Self { soft: true, ..self }
    }
}

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

fn canonical<S: TechniqueSettings>(spec: &TechniqueSpec) -> Result<String, SettingsError> {
    Ok(S::parse(&spec.name, &spec.values)?.settings_string())
}

/// A constructor for a settings type whose value alone is the technique, on backend `B`.
fn plain<B, S>(spec: &TechniqueSpec) -> Result<Box<dyn DynShadowTechnique<B>>, SettingsError>
where
    B: shadow_core::technique::Backend,
    S: TechniqueSettings + shadow_core::technique::ShadowTechnique<B>,
{
    let s = S::parse(&spec.name, &spec.values)?;
    let text = s.settings_string();
    Ok(Stateful::boxed(s, text))
}

/// A depth-layer map: the settings type (one per name, for its defaults) wraps the shared technique.
fn layers<B, S>(spec: &TechniqueSpec) -> Result<Box<dyn DynShadowTechnique<B>>, SettingsError>
where
    B: shadow_core::technique::Backend,
    S: TechniqueSettings + Into<DepthLayers>,
    DepthLayers: shadow_core::technique::ShadowTechnique<B>,
{
    let s = S::parse(&spec.name, &spec.values)?;
    let text = s.settings_string();
    Ok(Stateful::boxed(s.into(), text))
}

/// Shadow volumes: the name picks the counting.
fn volume<B>(spec: &TechniqueSpec) -> Result<Box<dyn DynShadowTechnique<B>>, SettingsError>
where
    B: shadow_core::technique::Backend,
    ShadowVolume: shadow_core::technique::ShadowTechnique<B>,
{
    ShadowVolume::parse(&spec.name, &spec.values)?;
    let v = ShadowVolume::named(&spec.name).unwrap_or(ShadowVolume::ZFAIL);
    Ok(Stateful::boxed(v, String::new()))
}

impl TechniqueRegistry {
    /// The built-in techniques.
    #[must_use]
    pub fn builtin() -> Self {
        let mut r = Self::default();
        r.register(TechniqueEntry {
            name: "ray-traced",
            description: "exact hard shadows: one shadow ray per pixel through a BVH",
            paper: "reference",
            reference: true,
            soft: false,
            keys: RayTraced::keys,
            canonical: canonical::<RayTraced>,
            cpu: Some(plain::<CpuBackend, RayTraced>),
            wgpu: None,
        });
        r.register(TechniqueEntry {
            name: "area-light-reference",
            description: "soft shadows of a spherical light: stratified Monte Carlo shadow rays per pixel through a BVH",
            paper: "reference (shadow-soft)",
            reference: true,
            soft: true,
            keys: AreaLightReference::keys,
            canonical: canonical::<AreaLightReference>,
            cpu: Some(plain::<CpuBackend, AreaLightReference>),
            wgpu: None,
        });
        r.register(TechniqueEntry::on_both::<ShadowMap>(
            "shadow-map",
            "depth map from the light with Vulkan depth bias and percentage-closer filtering",
            "Williams 1978; Reeves et al. 1987 (survey: Nealen 2005)",
        ));
        r.register(TechniqueEntry::on_both::<SilhouetteMap>(
            "silhouette-map",
            "a shadow map plus silhouette points half a texel off: piecewise-linear shadow edges",
            "Sen, Cammarano, Hanrahan 2003",
        ));
        r.register(TechniqueEntry::on_both::<VolumeReconstruction>(
            "volume-reconstruction",
            "a shadow volume rebuilt from the light's depth map, resolved with one stencil bit",
            "McCool 2000",
        ));
        r.register(TechniqueEntry::on_both::<Hybrid>(
            "hybrid",
            "a shadow map, with z-fail shadow volumes at its silhouette pixels only (a computation mask)",
            "Chan 2004 (thesis, chapter 3)",
        ));
        r.register(
            TechniqueEntry::on_both::<Smoothies>(
                "smoothies",
                "fake soft shadows: a shadow map plus alpha ramps hung outward from the silhouettes (smoothies)",
                "Chan-Durand 2003; Chan 2004 (thesis, chapter 4)",
            )
            .soft(),
        );
        r.register(
            TechniqueEntry::on_both::<Pcss>(
                "pcss",
                "percentage-closer soft shadows: a blocker search sizes a PCF kernel to the penumbra",
                "Fernando 2005",
            )
            .soft(),
        );
        r.register(
            TechniqueEntry::on_both::<PenumbraMap>(
                "penumbra-map",
                "fake soft shadows: a shadow map plus cones and sheets at the silhouettes drawn into a penumbra map",
                "Wyman-Hansen 2003 (compared in Chan 2004, thesis 4.5.1)",
            )
            .soft(),
        );
        r.register(TechniqueEntry {
            name: "shadow-volume-zpass",
            description: "stencil shadow volumes counted from the eye: wrong when the eye is in shadow",
            paper: "Crow 1977; Heidmann 1991",
            reference: false,
            soft: false,
            keys: ShadowVolume::keys,
            canonical: canonical::<ShadowVolume>,
            cpu: Some(volume::<CpuBackend>),
            wgpu: Some(volume::<WgpuBackend>),
        });
        r.register(TechniqueEntry {
            name: "shadow-volume-zfail",
            description: "stencil shadow volumes counted from infinity, capped: right with the eye in shadow",
            paper: "Everitt-Kilgard 2002",
            reference: false,
            soft: false,
            keys: ShadowVolume::keys,
            canonical: canonical::<ShadowVolume>,
            cpu: Some(volume::<CpuBackend>),
            wgpu: Some(volume::<WgpuBackend>),
        });
        let layer_entries: [(&'static str, &'static str, &'static str, LayerFns); 3] = [
            (
                "midpoint-shadow-map",
                "a map of the midpoint between the two layers nearest the light (depth peeling)",
                "Woo 1992 (in Weiskopf-Ertl 2003, section 3)",
                (
                    MidpointShadowMap::keys,
                    canonical::<MidpointShadowMap>,
                    layers::<CpuBackend, MidpointShadowMap>,
                    layers::<WgpuBackend, MidpointShadowMap>,
                ),
            ),
            (
                "second-depth-shadow-map",
                "a map of the second-nearest layer; meant for closed meshes",
                "Wang-Molnar 1994 (in Weiskopf-Ertl 2003, section 2)",
                (
                    SecondDepthShadowMap::keys,
                    canonical::<SecondDepthShadowMap>,
                    layers::<CpuBackend, SecondDepthShadowMap>,
                    layers::<WgpuBackend, SecondDepthShadowMap>,
                ),
            ),
            (
                "dual-shadow-map",
                "nearest layer plus min(half the gap to the second, z_offset): an adaptive bias",
                "Weiskopf-Ertl 2003",
                (
                    DualShadowMap::keys,
                    canonical::<DualShadowMap>,
                    layers::<CpuBackend, DualShadowMap>,
                    layers::<WgpuBackend, DualShadowMap>,
                ),
            ),
        ];
        for (name, description, paper, (keys, canonical, cpu, wgpu)) in layer_entries {
            r.register(TechniqueEntry {
                name,
                description,
                paper,
                reference: false,
                soft: false,
                keys,
                canonical,
                cpu: Some(cpu),
                wgpu: Some(wgpu),
            });
        }
        r
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
