//! What a technique tells the registry about itself: its name, paper, the lights it takes, its settings
//! keys and a constructor per backend. Each technique's folder builds its own [`Entry`]; the registry of
//! the `shadowlab` crate lists them, so adding a technique is its folder plus one line there.
//!
//! The entry is generic over the two backends it may be built on (`C` the CPU reference, `G` the GPU), so
//! this crate, which knows neither, can hold it.

use super::maps::{MapLayout, MapSampling};
use super::settings::{SettingKey, SettingsError, TechniqueSettings, TechniqueSpec};
use super::{Backend, DynShadowTechnique, ShadowTechnique, Stateful};
use crate::frame::FrameInputs;
use crate::light::LightView;
use crate::scene::{Light, LightKind};

/// The kinds of light a technique takes (`TechniqueSettings::LIGHTS`). A light of another kind is refused
/// before the technique's build runs ([`crate::technique::TechniqueError::UnsupportedLight`]), and
/// `compare` leaves the technique out of a scene lit by one.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct LightKinds {
    /// Spot lights.
    pub spot: bool,
    /// Directional lights.
    pub directional: bool,
    /// Point lights.
    pub point: bool,
}

impl LightKinds {
    /// Every kind.
    pub const ALL: Self = Self { spot: true, directional: true, point: true };
    /// Spot lights only.
    pub const SPOT: Self = Self { spot: true, directional: false, point: false };
    /// Directional lights only.
    pub const DIRECTIONAL: Self = Self { spot: false, directional: true, point: false };
    /// Lights with a position: spot and point.
    pub const POSITIONED: Self = Self { spot: true, directional: false, point: true };
    /// Lights with one projection: spot and directional.
    pub const ONE_PROJECTION: Self = Self { spot: true, directional: true, point: false };

    /// Whether `light` is of a kind taken.
    #[must_use]
    pub fn takes(self, light: &Light) -> bool {
        match light.kind {
            LightKind::Spot { .. } => self.spot,
            LightKind::Directional { .. } => self.directional,
            LightKind::Point { .. } => self.point,
        }
    }

    /// The kinds taken, by name (as `Light::type_name` has them).
    #[must_use]
    pub fn names(self) -> Vec<&'static str> {
        [(self.spot, "spot"), (self.directional, "directional"), (self.point, "point")]
            .into_iter()
            .filter_map(|(on, name)| on.then_some(name))
            .collect()
    }
}

/// How a technique shadows the casters of one alpha mode ([`crate::material::AlphaMode`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum CasterHandling {
    /// By its own method, exactly as the casters are: opaque ones whole, masked ones where their texels
    /// pass the alpha test (references: rays continue past clear texels; maps: light passes discard them).
    Exact,
    /// Through a depth map of those casters alone, cut out by their texture as every light pass cuts them
    /// ([`crate::technique::maps::CutoutMap`], its `cutout_res` and `cutout_filter`), a receiver lit only
    /// where both that map and the technique say lit: the way of the techniques that extrude silhouettes,
    /// as a card's outline is not its shadow's edge.
    CutoutMap,
    /// As opaque casters: the whole surface blocks light.
    AsOpaque,
    /// Not at all: `compare` leaves the technique out of a scene with such casters, and warns where it
    /// is named.
    LeftOut,
}

impl CasterHandling {
    /// A short name (`techniques --json`).
    #[must_use]
    pub fn name(self) -> &'static str {
        match self {
            Self::Exact => "exact",
            Self::CutoutMap => "cutout-map",
            Self::AsOpaque => "as-opaque",
            Self::LeftOut => "left-out",
        }
    }

    /// How it is done, as a clause after the kind of caster.
    #[must_use]
    pub fn clause(self) -> &'static str {
        match self {
            Self::Exact => "exactly, by its own method",
            Self::CutoutMap => {
                "through an alpha-tested depth map of them alone (the cutout_* settings), its visibility times the technique's"
            }
            Self::AsOpaque => "as opaque (the whole surface blocks light)",
            Self::LeftOut => "not at all (compare leaves it out of scenes with them)",
        }
    }
}

/// How a technique takes each kind of caster: opaque, masked (alpha-tested, cut out by a texture) and
/// blended. A blended caster blocks light as an opaque one in every technique and reference.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct CasterKinds {
    /// Opaque casters.
    pub opaque: CasterHandling,
    /// Masked casters cut out by their texture ([`crate::frame::Coverage::Cutout`]).
    pub masked: CasterHandling,
    /// Blended casters.
    pub blend: CasterHandling,
}

impl CasterKinds {
    /// Opaque and masked casters exactly, blended ones as opaque: every technique built on depth maps,
    /// and the references.
    pub const MAPS: Self =
        Self { opaque: CasterHandling::Exact, masked: CasterHandling::Exact, blend: CasterHandling::AsOpaque };

    /// Whether a frame whose casters a texture cuts out is taken.
    #[must_use]
    pub fn takes_cutouts(&self) -> bool {
        self.masked != CasterHandling::LeftOut
    }

    /// Each kind with its handling, in the order opaque, masked, blend (glTF's alpha modes).
    #[must_use]
    pub fn kinds(&self) -> [(&'static str, CasterHandling); 3] {
        [("opaque", self.opaque), ("masked", self.masked), ("blend", self.blend)]
    }

    /// What `shadowlab techniques` prints: the kinds it takes exactly, then how it takes each other one,
    /// e.g. "opaque exactly, by its own method; masked through an alpha-tested depth map ...; blend as
    /// opaque (the whole surface blocks light)".
    #[must_use]
    pub fn describe(&self) -> String {
        let exact: Vec<&str> =
            self.kinds().iter().filter(|(_, h)| *h == CasterHandling::Exact).map(|(k, _)| *k).collect();
        let mut parts = Vec::new();
        if !exact.is_empty() {
            parts.push(format!("{} {}", exact.join(" and "), CasterHandling::Exact.clause()));
        }
        for (kind, h) in self.kinds().into_iter().filter(|(_, h)| *h != CasterHandling::Exact) {
            parts.push(format!("{kind} {}", h.clause()));
        }
        parts.join("; ")
    }
}

/// Builds a technique for backend `B` from a spec.
pub type Constructor<B> = fn(&TechniqueSpec) -> Result<Box<dyn DynShadowTechnique<B>>, SettingsError>;

/// The maps a spec's technique renders for a light in a frame seen at an aspect ratio ([`MapLayout`]).
pub type Layout = fn(&TechniqueSpec, &FrameInputs, &LightView, f32) -> Result<MapSampling, SettingsError>;

/// One technique as the registry holds it.
pub struct Entry<C: Backend, G: Backend> {
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
    /// The lights it takes.
    pub lights: LightKinds,
    /// Settings keys with defaults.
    pub keys: fn() -> &'static [SettingKey],
    /// Canonical settings string of a spec (all keys, defaults filled in).
    pub canonical: fn(&TechniqueSpec) -> Result<String, SettingsError>,
    /// The CPU implementation, if any.
    pub cpu: Option<Constructor<C>>,
    /// The GPU implementation, if any.
    pub wgpu: Option<Constructor<G>>,
    /// The WGSL its GPU implementation compiles beyond the backend's own, each shader whole and named:
    /// every one is validated by the conformance suite.
    pub wgsl: fn() -> Vec<(&'static str, String)>,
    /// For a technique built on depth maps, where its texels fall ([`MapLayout`]).
    pub layout: Option<Layout>,
    /// How it takes each kind of caster; whether it takes those their texture cuts out
    /// ([`crate::frame::Coverage::Cutout`]) at all is [`CasterKinds::takes_cutouts`].
    pub casters: CasterKinds,
}

/// No WGSL of its own.
fn no_wgsl() -> Vec<(&'static str, String)> {
    Vec::new()
}

impl<C: Backend, G: Backend> Clone for Entry<C, G> {
    fn clone(&self) -> Self {
        Self { ..*self }
    }
}

impl<C: Backend, G: Backend> Entry<C, G> {
    /// The entry of a technique declared by the settings type `S` (its keys, canonical string and lights),
    /// made on each backend by the constructor given.
    #[must_use]
    pub fn new<S: TechniqueSettings>(
        name: &'static str,
        description: &'static str,
        paper: &'static str,
        cpu: Option<Constructor<C>>,
        wgpu: Option<Constructor<G>>,
    ) -> Self {
        Self {
            name,
            description,
            paper,
            reference: false,
            soft: false,
            lights: S::LIGHTS,
            keys: S::keys,
            canonical: canonical::<S>,
            cpu,
            wgpu,
            wgsl: no_wgsl,
            layout: None,
            casters: CasterKinds::MAPS,
        }
    }

    /// The entry of a technique whose settings type is itself the technique on both backends (the usual
    /// case: `S` implements `TechniqueSettings`, and `ShadowTechnique` for `C` and `G`).
    #[must_use]
    pub fn on_both<S>(name: &'static str, description: &'static str, paper: &'static str) -> Self
    where
        S: TechniqueSettings + ShadowTechnique<C> + ShadowTechnique<G>,
    {
        Self::new::<S>(name, description, paper, Some(plain::<C, S>), Some(plain::<G, S>))
    }

    /// The entry of a technique on the CPU backend only (the references).
    #[must_use]
    pub fn on_cpu<S>(name: &'static str, description: &'static str, paper: &'static str) -> Self
    where
        S: TechniqueSettings + ShadowTechnique<C>,
    {
        Self::new::<S>(name, description, paper, Some(plain::<C, S>), None)
    }

    /// The same entry, for a soft technique (measured against `area-light-reference`).
    #[must_use]
    pub fn soft(self) -> Self {
        Self { soft: true, ..self }
    }

    /// The same entry, with the WGSL its GPU implementation compiles.
    #[must_use]
    pub fn wgsl(self, shaders: fn() -> Vec<(&'static str, String)>) -> Self {
        Self { wgsl: shaders, ..self }
    }

    /// The same entry, with the layout of its maps, which its settings type `S` gives.
    #[must_use]
    pub fn with_layout<S: TechniqueSettings + MapLayout>(self) -> Self {
        Self { layout: Some(layout::<S>), ..self }
    }

    /// The same entry, for a technique that extrudes the casters' silhouettes and takes no casters cut
    /// out by their texture ([`CasterHandling::LeftOut`]).
    #[must_use]
    pub fn without_cutouts(self) -> Self {
        Self { casters: CasterKinds { masked: CasterHandling::LeftOut, ..self.casters }, ..self }
    }

    /// The same entry, for a technique that extrudes the casters' silhouettes and takes those their
    /// texture cuts out through their own map ([`CasterHandling::CutoutMap`]).
    #[must_use]
    pub fn cutouts_by_map(self) -> Self {
        Self { casters: CasterKinds { masked: CasterHandling::CutoutMap, ..self.casters }, ..self }
    }

    /// The same entry, for a reference.
    #[must_use]
    pub fn reference(self) -> Self {
        Self { reference: true, ..self }
    }
}

/// The canonical settings string of a spec for a settings type.
///
/// # Errors
/// Unknown keys or bad values.
pub fn canonical<S: TechniqueSettings>(spec: &TechniqueSpec) -> Result<String, SettingsError> {
    Ok(S::parse(&spec.name, &spec.values)?.settings_string())
}

/// The layout of a spec's maps, for a settings type that lays them out.
///
/// # Errors
/// Unknown keys or bad values.
pub fn layout<S: TechniqueSettings + MapLayout>(
    spec: &TechniqueSpec,
    frame: &FrameInputs,
    light: &LightView,
    aspect: f32,
) -> Result<MapSampling, SettingsError> {
    Ok(S::parse(&spec.name, &spec.values)?.sampling(frame, light, aspect))
}

/// A constructor for a settings type whose value alone is the technique, on backend `B`.
///
/// # Errors
/// Unknown keys or bad values.
pub fn plain<B, S>(spec: &TechniqueSpec) -> Result<Box<dyn DynShadowTechnique<B>>, SettingsError>
where
    B: Backend,
    S: TechniqueSettings + ShadowTechnique<B>,
{
    let s = S::parse(&spec.name, &spec.values)?;
    let text = s.settings_string();
    Ok(Box::new(Stateful::new(s, text).taking(S::LIGHTS)))
}

/// A constructor for a settings type that converts into the technique `T` it configures, on backend
/// `B`: one technique type behind several names, each name's settings type with its own keys and
/// defaults (the depth-layer maps, the moment maps).
///
/// # Errors
/// Unknown keys or bad values.
pub fn converted<B, S, T>(spec: &TechniqueSpec) -> Result<Box<dyn DynShadowTechnique<B>>, SettingsError>
where
    B: Backend,
    S: TechniqueSettings + Into<T>,
    T: ShadowTechnique<B> + 'static,
{
    let s = S::parse(&spec.name, &spec.values)?;
    let text = s.settings_string();
    Ok(Box::new(Stateful::new(s.into(), text).taking(S::LIGHTS)))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn casters_say_what_is_exact_and_how_the_others_are_taken() {
        assert_eq!(
            CasterKinds::MAPS.describe(),
            "opaque and masked exactly, by its own method; blend as opaque (the whole surface blocks light)"
        );
        let volumes = CasterKinds { masked: CasterHandling::CutoutMap, ..CasterKinds::MAPS };
        let text = volumes.describe();
        assert!(
            text.starts_with("opaque exactly, by its own method; masked through an alpha-tested depth map"),
            "{text}"
        );
        assert!(volumes.takes_cutouts() && CasterKinds::MAPS.takes_cutouts());
        assert!(!CasterKinds { masked: CasterHandling::LeftOut, ..CasterKinds::MAPS }.takes_cutouts());
    }
}
