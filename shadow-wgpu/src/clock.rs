//! GPU time per phase from timestamp queries, where the adapter has them: a marker (an empty compute
//! pass that writes a timestamp) is submitted between phases; as the queue runs in order, the difference
//! between two markers is the GPU's time for the work submitted between them.
//!
//! A technique whose query also runs counter passes (occlusion queries read back on the CPU) calls
//! [`WgpuContext::end_of_work`] once its own work is submitted: the frame driver then reports the GPU time
//! up to that marker as the phase's and the rest as `gpu_counters`, so the waits and passes of the
//! counters do not land in the technique's time.
//!
//! A technique may also end named steps of its phase with [`WgpuContext::step`] after submitting each
//! one's work: the driver reports the GPU time from the phase's start or the step before as
//! `gpu_<phase>.<name>` (per-pass times for a profile; their sum is the phase's own time).

use std::cell::{Cell, RefCell};

use crate::context::{WgpuContext, WgpuError};

/// Markers of one frame.
pub struct PhaseClock {
    set: wgpu::QuerySet,
    /// Markers written so far (a cell, so a step can be marked through a shared context).
    count: Cell<u32>,
    work_end: Option<u32>,
    steps: RefCell<Vec<(&'static str, u32)>>,
}

/// Most markers a frame writes.
const CAPACITY: u32 = 64;

impl PhaseClock {
    /// A clock, or `None` on an adapter without timestamp queries.
    #[must_use]
    pub fn new(cx: &WgpuContext) -> Option<Self> {
        cx.timestamps.then(|| Self {
            set: cx.device.create_query_set(&wgpu::QuerySetDescriptor {
                label: Some("phase clock"),
                ty: wgpu::QueryType::Timestamp,
                count: CAPACITY,
            }),
            count: Cell::new(0),
            work_end: None,
            steps: RefCell::new(Vec::new()),
        })
    }

    /// Submits a marker; returns its index.
    pub fn mark(&mut self, cx: &WgpuContext) -> Option<u32> {
        self.mark_on(&cx.device, &cx.queue)
    }

    /// Submits the end-of-work marker of the phase under way (see the module docs).
    pub(crate) fn mark_work_end(&mut self, device: &wgpu::Device, queue: &wgpu::Queue) {
        self.work_end = self.mark_on(device, queue);
    }

    /// The end-of-work marker submitted since the last call, if any.
    pub fn take_work_end(&mut self) -> Option<u32> {
        self.work_end.take()
    }

    /// Submits the marker that ends the named step of the phase under way (see the module docs).
    pub(crate) fn mark_step(&self, device: &wgpu::Device, queue: &wgpu::Queue, name: &'static str) {
        if let Some(index) = self.mark_on(device, queue) {
            self.steps.borrow_mut().push((name, index));
        }
    }

    /// The named steps' end markers submitted since the last call, in order.
    pub fn take_steps(&mut self) -> Vec<(&'static str, u32)> {
        self.steps.take()
    }

    fn mark_on(&self, device: &wgpu::Device, queue: &wgpu::Queue) -> Option<u32> {
        if self.count.get() >= CAPACITY {
            return None;
        }
        let index = self.count.get();
        let mut enc = device.create_command_encoder(&wgpu::CommandEncoderDescriptor { label: Some("phase marker") });
        write_mark(&mut enc, &self.set, index);
        queue.submit([enc.finish()]);
        self.count.set(index + 1);
        Some(index)
    }

    /// Every marker's time in milliseconds since the first.
    ///
    /// # Errors
    /// A GPU failure while reading the queries back.
    pub fn read(&self, cx: &WgpuContext) -> Result<Vec<f64>, WgpuError> {
        let count = self.count.get();
        if count == 0 {
            return Ok(Vec::new());
        }
        let ticks = read_ticks(cx, &self.set, count)?;
        let period = f64::from(cx.queue.get_timestamp_period());
        Ok(ticks.iter().map(|&t| t.saturating_sub(ticks[0]) as f64 * period * 1e-6).collect())
    }
}

/// Writes timestamp `index` of `set` where `encoder` stands: an empty compute pass that writes it as it
/// begins.
pub fn write_mark(encoder: &mut wgpu::CommandEncoder, set: &wgpu::QuerySet, index: u32) {
    drop(encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
        label: Some("timestamp"),
        timestamp_writes: Some(wgpu::ComputePassTimestampWrites {
            query_set: set,
            beginning_of_pass_write_index: Some(index),
            end_of_pass_write_index: None,
        }),
    }));
}

/// The first `count` timestamps of `set`, in ticks of the queue's timestamp period, read back once the
/// work that wrote them is done.
///
/// # Errors
/// A GPU failure while reading them back, or a read-back inside a recorded frame.
pub fn read_ticks(cx: &WgpuContext, set: &wgpu::QuerySet, count: u32) -> Result<Vec<u64>, WgpuError> {
    let size = u64::from(count) * 8;
    let buffer = |label, usage| {
        cx.create_buffer(&wgpu::BufferDescriptor { label: Some(label), size, usage, mapped_at_creation: false })
    };
    let resolve = buffer("timestamps", wgpu::BufferUsages::QUERY_RESOLVE | wgpu::BufferUsages::COPY_SRC);
    let staging = buffer("timestamps readback", wgpu::BufferUsages::COPY_DST | wgpu::BufferUsages::MAP_READ);
    let mut enc = cx.encoder("timestamps");
    enc.resolve_query_set(set, 0..count, &resolve, 0);
    enc.copy_buffer_to_buffer(&resolve, 0, &staging, 0, size);
    cx.submit(enc);
    let bytes = crate::readback::map_read(cx, &staging, "reading timestamps")?;
    Ok(bytes.chunks_exact(8).map(|c| u64::from_le_bytes([c[0], c[1], c[2], c[3], c[4], c[5], c[6], c[7]])).collect())
}
