//! The depth maps a map technique looked into for each light of a recorded frame, lent to a host that
//! samples them in its own shader (`host_wgsl::MAPS`'s `shadowlab_map_visibility`) instead of reading the
//! visibility: in a forward pass, say, at points the G-buffer never held.
//!
//! A technique lends its maps when its visibility is one lookup into them with its filter
//! ([`MapQuery::lent_to_hosts`](crate::passes::maps::MapQuery::lent_to_hosts)): `shadow-map`, cascades,
//! LiSPSM and perspective shadow maps. The rest (volumes, soft techniques' own lookups, several lookups
//! for one light) lend none, and the host reads their visibility.

use std::cell::RefCell;

use shadow_core::technique::settings::Filter;

/// One light's depth maps and how its technique looks into them.
#[derive(Clone, Debug)]
pub struct HostMap {
    /// The maps, one layer per projection of the light (a cube's six faces, each cascade): a depth
    /// `texture_depth_2d_array`. The technique renders into the same texture next frame: sample it in
    /// the frame it was recorded for.
    pub texture: wgpu::Texture,
    /// The lookup's parameters as `ShadowlabMap` in `host_wgsl::MAPS` lays them out: upload them to a
    /// uniform buffer ([`Self::params_bytes`]).
    pub params: crate::passes::maps::MapParams,
    /// The technique's filter.
    pub filter: Filter,
}

impl HostMap {
    /// The parameters' bytes, for a uniform buffer bound as `ShadowlabMap`.
    #[must_use]
    pub fn params_bytes(&self) -> &[u8] {
        bytemuck::bytes_of(&self.params)
    }

    /// The comparison sampler the lookup's bilinear taps need: linear, clamped to the edge, passing where
    /// the receiver's depth is at most the stored one.
    #[must_use]
    pub fn sampler_descriptor() -> wgpu::SamplerDescriptor<'static> {
        wgpu::SamplerDescriptor {
            label: Some("shadow comparison"),
            address_mode_u: wgpu::AddressMode::ClampToEdge,
            address_mode_v: wgpu::AddressMode::ClampToEdge,
            mag_filter: wgpu::FilterMode::Linear,
            min_filter: wgpu::FilterMode::Linear,
            compare: Some(wgpu::CompareFunction::LessEqual),
            ..Default::default()
        }
    }
}

/// What a light lent.
#[derive(Clone, Debug, Default)]
enum Lent {
    /// Nothing (yet).
    #[default]
    Nothing,
    /// One lookup's maps.
    One(Box<HostMap>),
    /// More than one lookup: no single map gives its visibility.
    Several,
}

/// The maps lent while a frame is recorded: a slot per light, and the light whose passes run.
#[derive(Debug, Default)]
pub(crate) struct Capture {
    slots: RefCell<Option<(usize, Vec<Lent>)>>,
}

impl Capture {
    /// Starts a frame of `lights` lights.
    pub(crate) fn begin(&self, lights: usize) {
        *self.slots.borrow_mut() = Some((0, vec![Lent::Nothing; lights]));
    }

    /// Light `k`'s passes run from now on.
    pub(crate) fn light(&self, k: usize) {
        if let Some((light, _)) = self.slots.borrow_mut().as_mut() {
            *light = k;
        }
    }

    /// The running light looked into `map` (no-op outside a recorded frame).
    pub(crate) fn lend(&self, map: impl FnOnce() -> HostMap) {
        if let Some((light, slots)) = self.slots.borrow_mut().as_mut()
            && let Some(slot) = slots.get_mut(*light)
        {
            *slot = match slot {
                Lent::Nothing => Lent::One(Box::new(map())),
                _ => Lent::Several,
            };
        }
    }

    /// Ends the frame: each light's map, where it lent one.
    pub(crate) fn end(&self) -> Vec<Option<HostMap>> {
        let (_, slots) = self.slots.borrow_mut().take().unwrap_or_default();
        slots.into_iter().map(|l| if let Lent::One(m) = l { Some(*m) } else { None }).collect()
    }
}
