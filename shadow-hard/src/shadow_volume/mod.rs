//! `shadow-volume-zpass` (Crow 1977, Heidmann 1991) and `shadow-volume-zfail` (Everitt-Kilgard 2002, after
//! Carmack): silhouettes from adjacency extruded to infinity, counted in an 8-bit stencil with two-sided
//! wrapping ops against the G-buffer's depth. A pixel is lit when its count is zero.
//!
//! Z-pass counts the volume faces in front of the surface (front faces +1, back faces -1 where the depth
//! test passes): right only while the eye is lit and no volume crosses the near plane. Z-fail counts the
//! faces behind it (back faces +1, front faces -1 where the depth test fails) and closes every volume with
//! a near and a far cap; with the camera's infinite far plane nothing is clipped behind, so it is right
//! with the eye in shadow too. Open meshes cast with Bergeron's weights (shared geometry), so the counts
//! stay right for the teapot and the Cornell box. The CPU extrudes with shadow-core's geometry and counts
//! with its `passes::volumes`; the GPU finds and extrudes the volumes itself in a compute pass
//! (`passes::extrusion`, the cost Sen, Chan and Nealen each name for volumes), or, with `extrusion=cpu`,
//! draws shadow-core's extrusion uploaded each frame, the reference the compute pass is held to.
//!
//! Casters their texture cuts out get no volume (a card's outline is not its shadow's edge): their
//! shadows come from a depth map of them alone, alpha-tested as every light pass is (`passes::maps`'
//! `CutoutMaps` on each backend, [`CutoutMap`] its settings), and a receiver is lit only where its count
//! is zero and that map says lit. A frame without such casters renders no map and runs as before.

pub mod cpu;
pub mod gpu;

use shadow_core::geometry::volume::VolumeCounting;
use shadow_core::technique::maps::CutoutMap;
use shadow_core::technique::settings::{
    Filter, SettingField, SettingKey, SettingsError, TechniqueSettings, TechniqueSpec, Values,
};
use shadow_core::technique::{Backend, DynShadowTechnique, ShadowTechnique, Stateful};
use shadow_cpu::CpuBackend;
use shadow_wgpu::WgpuBackend;

use crate::Entry;

/// `shadow-volume-zpass` and `shadow-volume-zfail`: stencil shadow volumes from silhouette edges.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ShadowVolume {
    /// Which counting (from the technique's name).
    pub counting: VolumeCounting,
    /// The map of the casters their texture cuts out.
    pub cutouts: CutoutMap,
    /// What the GPU backend alone reads.
    pub gpu: GpuOptions,
}

impl ShadowVolume {
    /// Z-pass volumes.
    pub const ZPASS: Self = Self {
        counting: VolumeCounting::ZPass,
        cutouts: CutoutMap { resolution: 2048, filter: Filter::None, cascades: 4 },
        gpu: GpuOptions { extrusion: Extrusion::Gpu },
    };
    /// Z-fail volumes.
    pub const ZFAIL: Self = Self { counting: VolumeCounting::ZFail, ..Self::ZPASS };
}

shadow_core::setting_group! {
    /// The shadow volumes' settings for the GPU backend alone.
    pub struct GpuOptions {
        /// Where the GPU's volumes are found and extruded.
        pub extrusion: Extrusion = SettingKey::choice(
            "extrusion",
            "gpu",
            Extrusion::NAMES,
            "GPU: gpu (silhouettes found and extruded in a compute pass) or cpu (shadow-core's extrusion, uploaded each frame: the reference)",
        ),
    }
}

shadow_core::named_enum! {
    /// Where the GPU backend's shadow volumes are found and extruded.
    pub enum Extrusion {
        /// In a compute pass over each mesh's adjacency, uploaded once: the host records a few commands
        /// per light and never sees a vertex.
        Gpu = "gpu",
        /// On the host with shadow-core's geometry, uploaded every frame (what the CPU backend draws).
        Cpu = "cpu",
    }
}

/// The cut-out casters' map's keys, then the GPU's.
const KEYS: [SettingKey; 4] = [CutoutMap::KEYS[0], CutoutMap::KEYS[1], CutoutMap::KEYS[2], GpuOptions::KEYS[0]];

impl TechniqueSettings for ShadowVolume {
    fn keys() -> &'static [SettingKey] {
        &KEYS
    }
    fn from_values(v: &Values<'_>) -> Result<Self, SettingsError> {
        Ok(Self {
            cutouts: CutoutMap::read(v, &CutoutMap::KEYS)?,
            gpu: GpuOptions::read(v, GpuOptions::KEYS)?,
            ..Self::ZFAIL
        })
    }
    fn to_values(&self) -> Vec<String> {
        let mut out = Vec::new();
        self.cutouts.write(&mut out);
        self.gpu.write(&mut out);
        out
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
    let settings = ShadowVolume::parse(&spec.name, &spec.values)?;
    let counting = ShadowVolume::named(&spec.name).unwrap_or(ShadowVolume::ZFAIL).counting;
    Ok(Stateful::boxed(ShadowVolume { counting, ..settings }, settings.settings_string()))
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
    .cutouts_by_map()
}

/// The registry entry of z-fail volumes.
#[must_use]
pub fn zfail_entry() -> Entry {
    entry(
        ShadowVolume::ZFAIL_NAME,
        "stencil shadow volumes counted from infinity, capped: right with the eye in shadow",
        "Everitt-Kilgard 2002",
    )
    .cutouts_by_map()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn takes_the_cutout_map_and_the_extrusion() {
        assert_eq!(
            ShadowVolume::defaults().settings_string(),
            "cutout_res=2048,cutout_filter=none,cutout_cascades=4,extrusion=gpu"
        );
        assert_eq!(ShadowVolume::defaults().cutouts, ShadowVolume::ZPASS.cutouts, "the constants' map is the keys'");
        let cpu = vec![("extrusion".to_string(), "cpu".to_string())];
        assert_eq!(ShadowVolume::parse("shadow-volume-zpass", &cpu).expect("valid").gpu.extrusion, Extrusion::Cpu);
        let given = vec![("res".to_string(), "1".to_string())];
        let e = ShadowVolume::parse("shadow-volume-zfail", &given).unwrap_err();
        assert!(e.to_string().contains("extrusion"), "{e}");
    }
}
