//! The order of the instance buffer, and the runs a pass draws with one instanced draw each.
//!
//! Instances that draw from the same buffers (one mesh: [`BuffersKey`]) with the same texture, coverage
//! and winding are a group (one draw in every pass fits them all), and a group's instances sit side by side in the instance buffer, so a pass draws every run of
//! them it keeps with one `draw_indexed`, wherever they stand in the frame. Groups keep the order of their
//! first instance in the frame and each group its instances' order: a frame whose every instance draws
//! from buffers of its own is laid out, and drawn, in its own order.
//!
//! The shaders index the instance buffer by slot (`instance_index`); what names an instance to the host
//! (an ID map's IDs) is its index in the frame, which its slot's `flags.z` holds.

use std::collections::HashMap;
use std::ops::Range;
use std::sync::Arc;

use shadow_core::frame::Coverage;
use shadow_core::{FrameInputs, Instance};

use crate::textures::read_texture;
use crate::upload::BuffersKey;

/// What the instances of a group share.
#[derive(PartialEq, Eq, Hash)]
struct Group {
    buffers: BuffersKey,
    /// The texture read (its address).
    texture: Option<usize>,
    coverage: Coverage,
    mirrored: bool,
}

impl Group {
    fn of(inst: &Instance) -> Self {
        Self {
            buffers: BuffersKey::of(inst),
            texture: read_texture(inst).map(|t| Arc::as_ptr(t) as usize),
            coverage: inst.coverage(),
            mirrored: inst.mirrored,
        }
    }
}

/// Where each of a frame's instances sits in the instance buffer ([`crate::upload::SceneCache::instances`]).
#[derive(Clone, Debug, Default)]
pub struct DrawOrder {
    /// Per slot, the frame's instance in it.
    instance: Vec<u32>,
    /// Per frame instance, its slot.
    slot: Vec<u32>,
    /// Per slot, its instance's group.
    group: Vec<u32>,
}

impl DrawOrder {
    /// The order of `frame`'s instances: grouped by buffers and texture, each group where its first
    /// instance is.
    #[must_use]
    pub fn of(frame: &FrameInputs) -> Self {
        let mut groups: HashMap<Group, u32> = HashMap::new();
        let group_of: Vec<u32> = frame
            .instances
            .iter()
            .map(|inst| {
                let next = groups.len() as u32;
                *groups.entry(Group::of(inst)).or_insert(next)
            })
            .collect();
        let mut instance: Vec<u32> = (0..group_of.len() as u32).collect();
        if groups.len() < group_of.len() {
            instance.sort_by_key(|&i| group_of[i as usize]);
        }
        let mut slot = vec![0; instance.len()];
        for (s, &i) in instance.iter().enumerate() {
            slot[i as usize] = s as u32;
        }
        let group = instance.iter().map(|&i| group_of[i as usize]).collect();
        Self { instance, slot, group }
    }

    /// The slot of the frame's instance `i`.
    #[must_use]
    pub fn slot(&self, i: usize) -> u32 {
        self.slot[i]
    }

    /// The frame's instances by slot.
    pub fn instances(&self) -> impl Iterator<Item = usize> + '_ {
        self.instance.iter().map(|&i| i as usize)
    }

    /// The runs of slots whose instances pass `keep`, each of one group: every run's first instance (in
    /// the frame) and its slots, the instance range of its draw.
    ///
    /// # Panics
    /// If the order is not `frame`'s (another count of instances).
    pub fn runs(&self, frame: &FrameInputs, keep: impl Fn(&Instance) -> bool) -> Vec<(usize, Range<u32>)> {
        assert_eq!(self.instance.len(), frame.instances.len(), "a draw order of another frame");
        let mut runs: Vec<(usize, Range<u32>)> = Vec::new();
        for (s, &i) in (0u32..).zip(&self.instance) {
            if !keep(&frame.instances[i as usize]) {
                continue;
            }
            match runs.last_mut() {
                Some((_, run)) if run.end == s && self.group[run.start as usize] == self.group[s as usize] => {
                    run.end += 1;
                }
                _ => runs.push((i as usize, s..s + 1)),
            }
        }
        runs
    }
}
