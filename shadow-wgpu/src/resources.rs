//! Where the backend's buffers and textures come from: every one is made through the context
//! ([`WgpuContext::create_buffer`] and its siblings), which counts them, so a test can hold a frame loop
//! to making none after its first frame (the library crates' `clippy.toml` forbids wgpu's own creation
//! calls outside this module; pipelines come from [`crate::PipelineCache`], counted with them).
//!
//! Data the GPU reads in one frame only (a light view's uniform, a map query's parameters, the segments
//! a pass draws) goes into [`Transient`] slices of one buffer the context keeps, at offsets handed out in
//! order since the frame began. A frame recorded into one command buffer sees all its writes land before
//! its first command, so each piece needs a place of its own. Consecutive frames write different buffers,
//! a few in turn, so a frame's writes do not wait for the frames still in flight to finish reading. The
//! buffers are made again, twice as large, only when a frame needs more than one holds. A pass whose data
//! grows and shrinks from frame to frame (geometry around a moving figure's silhouette) keeps a
//! [`TransientRing`] of its own, sized by its own frames, not by what else the frame holds.

use std::cell::{Cell, RefCell};

use crate::context::WgpuContext;

/// How many buffers, textures, pipelines and shader modules a context has made since it was opened.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Created {
    /// Buffers.
    pub buffers: u64,
    /// Textures.
    pub textures: u64,
    /// Render and compute pipelines ([`crate::PipelineCache`]).
    pub pipelines: u64,
    /// Shader modules.
    pub shader_modules: u64,
}

impl Created {
    /// What was made between `earlier` and these counts.
    #[must_use]
    pub fn since(self, earlier: Self) -> Self {
        Self {
            buffers: self.buffers - earlier.buffers,
            textures: self.textures - earlier.textures,
            pipelines: self.pipelines - earlier.pipelines,
            shader_modules: self.shader_modules - earlier.shader_modules,
        }
    }
}

/// The counters and the transient buffer a context keeps.
#[derive(Default)]
pub(crate) struct Resources {
    created: Cell<Created>,
    transient: RefCell<Arena>,
}

/// The transient buffers, [`FRAMES`] of `size` bytes used in turn, the frame under way and how much of
/// its buffer it has used; with the device's offset alignment and largest buffer, read once.
#[derive(Default)]
struct Arena {
    buffers: Vec<wgpu::Buffer>,
    size: u64,
    frame: u64,
    used: u64,
    align: u64,
    max_size: u64,
}

/// A slice of the transient buffer holding one piece of this frame's data.
#[derive(Clone, Debug)]
pub struct Transient {
    buffer: wgpu::Buffer,
    offset: u64,
    size: u64,
}

impl Transient {
    /// The slice as a vertex or index buffer.
    #[must_use]
    pub fn slice(&self) -> wgpu::BufferSlice<'_> {
        self.buffer.slice(self.offset..self.offset + self.size)
    }

    /// The slice as a binding (uniform or read-only storage).
    #[must_use]
    pub fn binding(&self) -> wgpu::BindingResource<'_> {
        wgpu::BindingResource::Buffer(wgpu::BufferBinding {
            buffer: &self.buffer,
            offset: self.offset,
            size: wgpu::BufferSize::new(self.size),
        })
    }
}

/// The smallest transient buffer: room for every uniform of a frame of a few lights without growing.
const MIN_TRANSIENT: u64 = 1 << 16;

/// Frames whose transient data may be in use at once: each writes a buffer of its own, so a frame's
/// writes never land in a buffer a frame still on the GPU reads (the copy would wait for that frame to
/// finish: the GPU tracks a buffer's use whole, not by range).
pub(crate) const FRAMES: usize = 3;

// The one place wgpu's creation calls are made.
#[allow(clippy::disallowed_methods)]
impl WgpuContext {
    fn count(&self, buffers: u64, textures: u64) {
        let c = self.resources.created.get();
        self.resources.created.set(Created { buffers: c.buffers + buffers, textures: c.textures + textures, ..c });
    }

    /// How many buffers, textures, pipelines and shader modules this context has made.
    #[must_use]
    pub fn created(&self) -> Created {
        let compiled = self.pipelines.compiled();
        Created {
            pipelines: compiled.pipelines,
            shader_modules: compiled.shader_modules,
            ..self.resources.created.get()
        }
    }

    /// Makes a buffer (counted).
    #[must_use]
    pub fn create_buffer(&self, desc: &wgpu::BufferDescriptor<'_>) -> wgpu::Buffer {
        self.count(1, 0);
        self.device.create_buffer(desc)
    }

    /// Makes a buffer holding `desc`'s contents (counted).
    #[must_use]
    pub fn create_buffer_init(&self, desc: &wgpu::util::BufferInitDescriptor<'_>) -> wgpu::Buffer {
        use wgpu::util::DeviceExt;
        self.count(1, 0);
        self.device.create_buffer_init(desc)
    }

    /// Makes a texture (counted).
    #[must_use]
    pub fn create_texture(&self, desc: &wgpu::TextureDescriptor<'_>) -> wgpu::Texture {
        self.count(0, 1);
        self.device.create_texture(desc)
    }

    /// Makes a texture holding `data` in `order` (counted).
    #[must_use]
    pub fn create_texture_with_data(
        &self,
        desc: &wgpu::TextureDescriptor<'_>,
        order: wgpu::util::TextureDataOrder,
        data: &[u8],
    ) -> wgpu::Texture {
        use wgpu::util::DeviceExt;
        self.count(0, 1);
        self.device.create_texture_with_data(&self.queue, desc, order, data)
    }

    /// Starts a frame's transient data over at the start of the buffer.
    /// Which of the [`FRAMES`] buffers kept in turn this frame uses.
    pub(crate) fn frame_turn(&self) -> usize {
        self.resources.transient.borrow().frame as usize % FRAMES
    }

    pub(crate) fn begin_transient(&self) {
        let mut arena = self.resources.transient.borrow_mut();
        arena.frame += 1;
        arena.used = 0;
    }

    /// `bytes` in a slice of the transient buffer of its own for this frame (see the module notes), to
    /// bind as a uniform or read-only storage, or to draw as vertices or indices.
    #[must_use]
    pub fn transient(&self, bytes: &[u8]) -> Transient {
        // Bindings and writes are whole words; an empty storage binding is not allowed.
        let size = (bytes.len() as u64).max(4).next_multiple_of(4);
        // Reads the device's alignment and largest buffer on the first use.
        self.transient_frame();
        let mut arena = self.resources.transient.borrow_mut();
        let local = arena.used.next_multiple_of(arena.align);
        let offset = if !arena.buffers.is_empty() && local + size <= arena.size {
            local
        } else {
            arena.size = (2 * (local + size)).max(MIN_TRANSIENT).min(arena.max_size);
            arena.buffers = self.transient_buffers("transient", arena.size);
            0
        };
        arena.used = offset + size;
        let buffer = arena.buffers[arena.frame as usize % FRAMES].clone();
        self.write_transient(buffer, offset, bytes)
    }

    /// The frame under way (counted from the context's first), the offset alignment of transient
    /// slices (the device's for uniform and storage bindings) and the largest buffer the device makes.
    fn transient_frame(&self) -> (u64, u64, u64) {
        let mut arena = self.resources.transient.borrow_mut();
        if arena.align == 0 {
            let limits = self.device.limits();
            arena.align =
                u64::from(limits.min_uniform_buffer_offset_alignment.max(limits.min_storage_buffer_offset_alignment));
            arena.max_size = limits.max_buffer_size;
        }
        (arena.frame, arena.align, arena.max_size)
    }

    /// [`FRAMES`] buffers of `size` bytes for transient slices of every use.
    fn transient_buffers(&self, label: &str, size: u64) -> Vec<wgpu::Buffer> {
        let usage = wgpu::BufferUsages::UNIFORM
            | wgpu::BufferUsages::STORAGE
            | wgpu::BufferUsages::VERTEX
            | wgpu::BufferUsages::INDEX
            | wgpu::BufferUsages::COPY_DST;
        let desc = wgpu::BufferDescriptor { label: Some(label), size, usage, mapped_at_creation: false };
        (0..FRAMES).map(|_| self.create_buffer(&desc)).collect()
    }

    /// `bytes`, padded to whole words, written at `offset` of `buffer`: the slice there.
    fn write_transient(&self, buffer: wgpu::Buffer, offset: u64, bytes: &[u8]) -> Transient {
        let size = (bytes.len() as u64).max(4).next_multiple_of(4);
        let mut padded = bytes.to_vec();
        padded.resize(size as usize, 0);
        self.queue.write_buffer(&buffer, offset, &padded);
        Transient { buffer, offset, size }
    }
}

/// Transient buffers a pass keeps for itself (a few used in turn, like the context's): each frame's
/// data is written into that frame's buffer, and when a frame's data outgrows it the buffers are made
/// again at twice the frame's size so far. Data that varies from frame to frame (a moving silhouette's
/// geometry) so costs an allocation only when a frame needs more than twice what the frame that last
/// grew the buffers had written, whatever else the frame holds.
pub struct TransientRing {
    label: &'static str,
    buffers: Vec<wgpu::Buffer>,
    size: u64,
    frame: u64,
    used: u64,
}

impl TransientRing {
    /// An empty ring, its buffers labelled `label`; nothing is made until the first write.
    #[must_use]
    pub fn new(label: &'static str) -> Self {
        Self { label, buffers: Vec::new(), size: 0, frame: 0, used: 0 }
    }

    /// `parts`, each in a slice of its own (to bind as uniform or read-only storage, or to draw as
    /// vertices or indices), after what this frame wrote before.
    pub fn write<const N: usize>(&mut self, cx: &WgpuContext, parts: [&[u8]; N]) -> [Transient; N] {
        let (frame, align, max_size) = cx.transient_frame();
        if frame != self.frame {
            (self.frame, self.used) = (frame, 0);
        }
        let sizes = parts.map(|p| (p.len() as u64).max(4).next_multiple_of(align));
        let need: u64 = sizes.iter().sum();
        if self.buffers.is_empty() || self.used + need > self.size {
            // Slices written before this frame's growth stay in the buffers they were written to; the
            // new ones have room for twice the frame so far.
            self.size = (2 * (self.used + need)).min(max_size.max(need));
            self.buffers = cx.transient_buffers(self.label, self.size);
            self.used = 0;
        }
        let buffer = &self.buffers[frame as usize % FRAMES];
        std::array::from_fn(|i| {
            let slice = cx.write_transient(buffer.clone(), self.used, parts[i]);
            self.used += sizes[i];
            slice
        })
    }
}
