//! The GPU time of frames recorded into a host's encoder, read back frames later without ever waiting.
//!
//! Each timed frame gets a slot of a small ring: timestamps at its start and end, resolved and copied
//! into a buffer the CPU can map. A buffer can only be mapped once the frame holding its copy is
//! submitted, which the host does after recording, so the map is asked for when the next frame is
//! recorded; it completes whenever the host's device next polls (a present, a submit, an explicit poll),
//! and the frame after that reads it. A frame that finds every slot still on its way is not timed: the
//! timer drops a measurement rather than stall.

use std::sync::{Arc, Mutex};

use crate::clock::write_mark;
use crate::context::WgpuContext;

/// Slots in the ring: frames whose times may be on their way at once.
const SLOTS: usize = 4;

/// The GPU times of recorded frames (see the module notes).
pub struct FrameTimer {
    slots: Vec<Slot>,
    period_ns: f64,
    last_ms: Option<f64>,
    /// The slot the frame being recorded writes, between [`Self::begin`] and [`Self::end`].
    open: Option<usize>,
}

struct Slot {
    set: wgpu::QuerySet,
    resolve: wgpu::Buffer,
    staging: wgpu::Buffer,
    state: State,
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
            cx.create_buffer(&wgpu::BufferDescriptor { label: Some(label), size: 16, usage, mapped_at_creation: false })
        };
        let slots = (0..SLOTS)
            .map(|_| Slot {
                set: cx.device.create_query_set(&wgpu::QuerySetDescriptor {
                    label: Some("frame time"),
                    ty: wgpu::QueryType::Timestamp,
                    count: 2,
                }),
                resolve: buffer("frame time", wgpu::BufferUsages::QUERY_RESOLVE | wgpu::BufferUsages::COPY_SRC),
                staging: buffer("frame time readback", wgpu::BufferUsages::COPY_DST | wgpu::BufferUsages::MAP_READ),
                state: State::Free,
            })
            .collect();
        Some(Self { slots, period_ns: f64::from(cx.queue.get_timestamp_period()), last_ms: None, open: None })
    }

    /// The GPU time of the latest frame whose times have come back, in milliseconds.
    #[must_use]
    pub fn last_ms(&self) -> Option<f64> {
        self.last_ms
    }

    /// Gathers what has come back, asks for the maps of the frames recorded since, and marks the start of
    /// the frame about to be recorded into `encoder` (unless every slot is still on its way).
    pub fn begin(&mut self, encoder: &mut wgpu::CommandEncoder) {
        for slot in &mut self.slots {
            if let Some(ms) = slot.advance(self.period_ns) {
                self.last_ms = Some(ms);
            }
        }
        self.open = self.slots.iter().position(|s| matches!(s.state, State::Free));
        if let Some(k) = self.open {
            write_mark(encoder, &self.slots[k].set, 0);
        }
    }

    /// Marks the end of the frame recorded into `encoder` since [`Self::begin`], and copies its times out.
    pub fn end(&mut self, encoder: &mut wgpu::CommandEncoder) {
        let Some(k) = self.open.take() else { return };
        let slot = &mut self.slots[k];
        write_mark(encoder, &slot.set, 1);
        encoder.resolve_query_set(&slot.set, 0..2, &slot.resolve, 0);
        encoder.copy_buffer_to_buffer(&slot.resolve, 0, &slot.staging, 0, 16);
        slot.state = State::Recorded;
    }
}

impl Slot {
    /// Moves the slot on: asks for the map of a recorded frame's times (the host has submitted it by
    /// now), and frees a mapped one, returning its time.
    fn advance(&mut self, period_ns: f64) -> Option<f64> {
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
        let ms = if mapped { read_ms(&self.staging, period_ns) } else { None };
        if mapped {
            self.staging.unmap();
        }
        self.state = State::Free;
        ms
    }
}

/// The milliseconds between a mapped slot's two timestamps.
fn read_ms(staging: &wgpu::Buffer, period_ns: f64) -> Option<f64> {
    let bytes = staging.slice(..).get_mapped_range().ok()?;
    let tick = |i: usize| u64::from_le_bytes(bytes[8 * i..8 * i + 8].try_into().unwrap_or_default());
    let (start, end) = (tick(0), tick(1));
    (end >= start).then(|| (end - start) as f64 * period_ns / 1e6)
}
