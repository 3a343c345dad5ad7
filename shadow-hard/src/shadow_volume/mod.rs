//! `shadow-volume-zpass` (Crow 1977, Heidmann 1991) and `shadow-volume-zfail` (Everitt-Kilgard 2002, after
//! Carmack): silhouettes from adjacency extruded to infinity, counted in an 8-bit stencil with two-sided
//! wrapping ops against the G-buffer's depth. A pixel is lit when its count is zero.
//!
//! Z-pass counts the volume faces in front of the surface (front faces +1, back faces -1 where the depth
//! test passes): right only while the eye is lit and no volume crosses the near plane. Z-fail counts the
//! faces behind it (back faces +1, front faces -1 where the depth test fails) and closes every volume with
//! a near and a far cap; with the camera's infinite far plane nothing is clipped behind, so it is right
//! with the eye in shadow too. Open meshes cast with Bergeron's weights (shared geometry), so the counts
//! stay right for the teapot and the Cornell box. The extrusion is shadow-core's, the counting each
//! backend's `passes::volumes`.

pub mod cpu;
pub mod gpu;

use shadow_core::geometry::volume::VolumeCounting;
use shadow_core::technique::settings::{SettingKey, SettingsError, TechniqueSettings, TechniqueSpec, Values};
use shadow_core::technique::{Backend, DynShadowTechnique, ShadowTechnique, Stateful};
use shadow_cpu::CpuBackend;
use shadow_wgpu::WgpuBackend;

use crate::Entry;

/// `shadow-volume-zpass` and `shadow-volume-zfail`: stencil shadow volumes from silhouette edges.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ShadowVolume {
    /// Which counting.
    pub counting: VolumeCounting,
}

impl ShadowVolume {
    /// Z-pass volumes.
    pub const ZPASS: Self = Self { counting: VolumeCounting::ZPass };
    /// Z-fail volumes.
    pub const ZFAIL: Self = Self { counting: VolumeCounting::ZFail };
}

impl TechniqueSettings for ShadowVolume {
    fn keys() -> &'static [SettingKey] {
        &[]
    }
    fn from_values(_: &Values<'_>) -> Result<Self, SettingsError> {
        Ok(Self::ZFAIL)
    }
    fn to_values(&self) -> Vec<String> {
        Vec::new()
    }
}

impl ShadowVolume {
    /// The name of the z-pass technique.
    pub const ZPASS_NAME: &'static str = "shadow-volume-zpass";
    /// The name of the z-fail technique.
    pub const ZFAIL_NAME: &'static str = "shadow-volume-zfail";

    /// The technique a name picks, `None` for other names.
    #[must_use]
    pub fn named(name: &str) -> Option<Self> {
        match name {
            Self::ZPASS_NAME => Some(Self::ZPASS),
            Self::ZFAIL_NAME => Some(Self::ZFAIL),
            _ => None,
        }
    }

    /// The registry name of this counting.
    #[must_use]
    pub fn name(&self) -> &'static str {
        match self.counting {
            VolumeCounting::ZPass => Self::ZPASS_NAME,
            VolumeCounting::ZFail => Self::ZFAIL_NAME,
        }
    }
}

/// The counting a spec's name picks, as a technique on backend `B`.
fn named<B: Backend>(spec: &TechniqueSpec) -> Result<Box<dyn DynShadowTechnique<B>>, SettingsError>
where
    ShadowVolume: ShadowTechnique<B>,
{
    ShadowVolume::parse(&spec.name, &spec.values)?;
    Ok(Stateful::boxed(ShadowVolume::named(&spec.name).unwrap_or(ShadowVolume::ZFAIL), String::new()))
}

fn entry(name: &'static str, description: &'static str, paper: &'static str) -> Entry {
    Entry::new::<ShadowVolume>(name, description, paper, Some(named::<CpuBackend>), Some(named::<WgpuBackend>))
}

/// The registry entry of z-pass volumes.
#[must_use]
pub fn zpass_entry() -> Entry {
    entry(
        ShadowVolume::ZPASS_NAME,
        "stencil shadow volumes counted from the eye: wrong when the eye is in shadow",
        "Crow 1977; Heidmann 1991",
    )
}

/// The registry entry of z-fail volumes.
#[must_use]
pub fn zfail_entry() -> Entry {
    entry(
        ShadowVolume::ZFAIL_NAME,
        "stencil shadow volumes counted from infinity, capped: right with the eye in shadow",
        "Everitt-Kilgard 2002",
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn takes_no_settings() {
        assert_eq!(ShadowVolume::defaults().settings_string(), "");
        let given = vec![("res".to_string(), "1".to_string())];
        let e = ShadowVolume::parse("shadow-volume-zfail", &given).unwrap_err();
        assert!(e.to_string().contains("settings: none"), "{e}");
    }
}
