//! The GPU time of frames recorded into a host's encoder, phase by phase, read back frames later without
//! ever waiting.
//!
//! Each timed frame gets a slot of a small ring: timestamps at its start, between its phases and at its
//! end, resolved and copied into a buffer the CPU can map. A buffer can only be mapped once the frame holding its copy is
//! submitted, which the host does after recording, so the map is asked for when the next frame is
//! recorded; it completes whenever the host's device next polls (a present, a submit, an explicit poll),
//! and the frame after that reads it. A frame that finds every slot still on its way is not timed: the
//! timer drops a measurement rather than stall.

use std::sync::{Arc, Mutex};

use crate::clock::write_mark;
use crate::context::WgpuContext;

/// Slots in the ring: frames whose times may be on their way at once.
const SLOTS: usize = 4;
/// Timestamps a frame may write: its start, the ends of up to three phases.
const MARKS: u32 = 4;

/// One frame's GPU time, whole and per phase, in milliseconds.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct FrameTimes {
    /// From the frame's start to its end.
    pub total_ms: f64,
    /// Each phase, named, in order.
    pub phases: Vec<(&'static str, f64)>,
}

/// The GPU times of recorded frames (see the module notes).
pub struct FrameTimer {
    slots: Vec<Slot>,
    period_ns: f64,
    last: Option<FrameTimes>,
    /// The slot the frame being recorded writes, between [`Self::begin`] and [`Self::end`].
    open: Option<usize>,
}

struct Slot {
    set: wgpu::QuerySet,
    resolve: wgpu::Buffer,
    staging: wgpu::Buffer,
    state: State,
    /// The names of the phases that end at its second, third, ... timestamp.
    phases: Vec<&'static str>,
}

enum State {
    Free,
    /// Its copy is recorded into a frame the host has not necessarily submitted yet.
    Recorded,
    /// Its map was asked for; the callback leaves whether it succeeded.
    Mapping(Arc<Mutex<Option<bool>>>),
}

impl FrameTimer {
    /// A timer on `cx`'s device, or `None` where the device has no timestamp queries.
    #[must_use]
    pub fn new(cx: &WgpuContext) -> Option<Self> {
        if !cx.timestamps {
            return None;
        }
        let buffer = |label, usage| {
            let size = 8 * u64::from(MARKS);
            cx.create_buffer(&wgpu::BufferDescriptor { label: Some(label), size, usage, mapped_at_creation: false })
        };
        let slots = (0..SLOTS)
            .map(|_| Slot {
                set: cx.device.create_query_set(&wgpu::QuerySetDescriptor {
                    label: Some("frame time"),
                    ty: wgpu::QueryType::Timestamp,
                    count: MARKS,
                }),
                resolve: buffer("frame time", wgpu::BufferUsages::QUERY_RESOLVE | wgpu::BufferUsages::COPY_SRC),
                staging: buffer("frame time readback", wgpu::BufferUsages::COPY_DST | wgpu::BufferUsages::MAP_READ),
                state: State::Free,
                phases: Vec::new(),
            })
            .collect();
        Some(Self { slots, period_ns: f64::from(cx.queue.get_timestamp_period()), last: None, open: None })
    }

    /// The GPU times of the latest frame whose times have come back.
    #[must_use]
    pub fn last(&self) -> Option<&FrameTimes> {
        self.last.as_ref()
    }

    /// Gathers what has come back, asks for the maps of the frames recorded since, and marks the start of
    /// the frame about to be recorded into `encoder` (unless every slot is still on its way).
    pub fn begin(&mut self, encoder: &mut wgpu::CommandEncoder) {
        for slot in &mut self.slots {
            if let Some(times) = slot.advance(self.period_ns) {
                self.last = Some(times);
            }
        }
        self.open = self.slots.iter().position(|s| matches!(s.state, State::Free));
        if let Some(k) = self.open {
            let slot = &mut self.slots[k];
            slot.phases.clear();
            write_mark(encoder, &slot.set, 0);
        }
    }

    /// Marks the end of the phase `name` of the frame being timed (the first phase starts at
    /// [`Self::begin`], each next one at the mark before); a frame has room for three.
    pub fn mark(&mut self, encoder: &mut wgpu::CommandEncoder, name: &'static str) {
        let Some(slot) = self.open.map(|k| &mut self.slots[k]) else { return };
        let index = slot.phases.len() as u32 + 1;
        if index < MARKS {
            write_mark(encoder, &slot.set, index);
            slot.phases.push(name);
        }
    }

    /// Marks the end of the frame recorded into `encoder` since [`Self::begin`] (the end of its last
    /// phase, `name`), and copies its times out.
    pub fn end(&mut self, encoder: &mut wgpu::CommandEncoder, name: &'static str) {
        let Some(k) = self.open.take() else { return };
        let slot = &mut self.slots[k];
        // Every mark taken: the phase before runs on into this last one.
        if slot.phases.len() as u32 + 1 == MARKS {
            slot.phases.pop();
        }
        let index = slot.phases.len() as u32 + 1;
        write_mark(encoder, &slot.set, index);
        slot.phases.push(name);
        encoder.resolve_query_set(&slot.set, 0..index + 1, &slot.resolve, 0);
        encoder.copy_buffer_to_buffer(&slot.resolve, 0, &slot.staging, 0, 8 * u64::from(index + 1));
        slot.state = State::Recorded;
    }
}

impl Slot {
    /// Moves the slot on: asks for the map of a recorded frame's times (the host has submitted it by
    /// now), and frees a mapped one, returning its time.
    fn advance(&mut self, period_ns: f64) -> Option<FrameTimes> {
        let mapped = match &self.state {
            State::Free => return None,
            State::Recorded => {
                let done = Arc::new(Mutex::new(None));
                let flag = done.clone();
                self.staging.slice(..).map_async(wgpu::MapMode::Read, move |r| {
                    if let Ok(mut f) = flag.lock() {
                        *f = Some(r.is_ok());
                    }
                });
                self.state = State::Mapping(done);
                return None;
            }
            State::Mapping(done) => done.lock().ok().and_then(|d| *d)?,
        };
        let times = if mapped { self.read(period_ns) } else { None };
        if mapped {
            self.staging.unmap();
        }
        self.state = State::Free;
        times
    }

    /// The times of a mapped slot: between its first and last timestamps, and between each two.
    fn read(&self, period_ns: f64) -> Option<FrameTimes> {
        let bytes = self.staging.slice(..).get_mapped_range().ok()?;
        let tick = |i: usize| u64::from_le_bytes(bytes[8 * i..8 * i + 8].try_into().unwrap_or_default());
        let ticks: Vec<u64> = (0..=self.phases.len()).map(tick).collect();
        // A pair out of order (a clock that wrapped, a reset) gives no times rather than wrong ones.
        let ms = |a: u64, b: u64| (b >= a).then(|| (b - a) as f64 * period_ns / 1e6);
        let phases: Option<Vec<_>> =
            self.phases.iter().zip(ticks.windows(2)).map(|(name, w)| Some((*name, ms(w[0], w[1])?))).collect();
        Some(FrameTimes { total_ms: ms(ticks[0], *ticks.last()?)?, phases: phases? })
    }
}
