//! Pipelines and what they are built from (shader modules, bind group layouts, pipeline layouts), each
//! made once per description and shared from then on.
//!
//! Every light's state of a technique asks for the same pipelines, and a technique made again with other
//! settings asks for mostly the same ones: a setting the shader reads as a uniform changes none, one that
//! selects an entry point, an `override` constant or a fixed-function state (a depth bias, a target's
//! format) changes the pipelines that use it. Looking each description up before compiling it makes that
//! the whole cost of a change: the pipelines whose description did not change are found, not compiled.
//!
//! A description is keyed by what defines it: a module by its source, a bind group layout by its
//! entries, a pipeline layout by its groups, a pipeline by its layout and modules (wgpu's handles compare
//! by identity, which the cache makes equal for equal content) and the rest of its descriptor's fields as
//! their `Debug` text (the plain-data fields, constants and formats included). Labels are part of a
//! pipeline's key, so two call sites never share a pipeline by accident of equal states.

use std::cell::{Cell, RefCell};
use std::collections::HashMap;

/// How many pipelines and shader modules a cache has compiled.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub(crate) struct Compiled {
    /// Render and compute pipelines.
    pub pipelines: u64,
    /// Shader modules.
    pub shader_modules: u64,
}

/// A pipeline's key: its layout and modules by identity, everything else by its description.
#[derive(PartialEq, Eq, Hash)]
struct PipelineKey {
    layout: Option<wgpu::PipelineLayout>,
    modules: Vec<wgpu::ShaderModule>,
    described: String,
}

#[derive(Default)]
struct Kept {
    modules: HashMap<String, wgpu::ShaderModule>,
    group_layouts: HashMap<Vec<wgpu::BindGroupLayoutEntry>, wgpu::BindGroupLayout>,
    pipeline_layouts: HashMap<Vec<Option<wgpu::BindGroupLayout>>, wgpu::PipelineLayout>,
    render: HashMap<PipelineKey, wgpu::RenderPipeline>,
    compute: HashMap<PipelineKey, wgpu::ComputePipeline>,
}

/// The pipelines of a device, made once per description (see the module notes).
pub struct PipelineCache {
    device: wgpu::Device,
    kept: RefCell<Kept>,
    compiled: Cell<Compiled>,
}

// The one place wgpu's pipeline creation calls are made.
#[allow(clippy::disallowed_methods)]
impl PipelineCache {
    /// An empty cache on `device`.
    #[must_use]
    pub fn new(device: wgpu::Device) -> Self {
        Self { device, kept: RefCell::default(), compiled: Cell::default() }
    }

    /// How many pipelines and modules it has compiled.
    #[must_use]
    pub(crate) fn compiled(&self) -> Compiled {
        self.compiled.get()
    }

    /// The shader module of WGSL `source` (`label` names the first one made from it).
    #[must_use]
    pub fn module(&self, label: &str, source: String) -> wgpu::ShaderModule {
        let mut kept = self.kept.borrow_mut();
        if let Some(m) = kept.modules.get(&source) {
            return m.clone();
        }
        let module = self.device.create_shader_module(wgpu::ShaderModuleDescriptor {
            label: Some(label),
            source: wgpu::ShaderSource::Wgsl(source.as_str().into()),
        });
        let c = self.compiled.get();
        self.compiled.set(Compiled { shader_modules: c.shader_modules + 1, ..c });
        kept.modules.entry(source).or_insert(module).clone()
    }

    /// The bind group layout of `entries`.
    #[must_use]
    pub fn group_layout(&self, label: &str, entries: &[wgpu::BindGroupLayoutEntry]) -> wgpu::BindGroupLayout {
        let mut kept = self.kept.borrow_mut();
        let device = &self.device;
        let make = || device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor { label: Some(label), entries });
        kept.group_layouts.entry(entries.to_vec()).or_insert_with(make).clone()
    }

    /// The pipeline layout of `groups` (a group a pipeline does not use may be `None`; no immediate data).
    #[must_use]
    pub fn layout(&self, label: &str, groups: &[Option<&wgpu::BindGroupLayout>]) -> wgpu::PipelineLayout {
        let mut kept = self.kept.borrow_mut();
        let device = &self.device;
        let make = || {
            device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
                label: Some(label),
                bind_group_layouts: groups,
                immediate_size: 0,
            })
        };
        kept.pipeline_layouts.entry(groups.iter().map(|g| g.cloned()).collect()).or_insert_with(make).clone()
    }

    /// The render pipeline `desc` describes.
    #[must_use]
    pub fn render(&self, desc: &wgpu::RenderPipelineDescriptor<'_>) -> wgpu::RenderPipeline {
        let modules = std::iter::once(desc.vertex.module).chain(desc.fragment.as_ref().map(|f| f.module));
        let key = PipelineKey {
            layout: desc.layout.cloned(),
            modules: modules.cloned().collect(),
            described: format!("{desc:?}"),
        };
        self.pipeline(|k| &mut k.render, key, || self.device.create_render_pipeline(desc))
    }

    /// The compute pipeline `desc` describes.
    #[must_use]
    pub fn compute(&self, desc: &wgpu::ComputePipelineDescriptor<'_>) -> wgpu::ComputePipeline {
        let key = PipelineKey {
            layout: desc.layout.cloned(),
            modules: vec![desc.module.clone()],
            described: format!("{desc:?}"),
        };
        self.pipeline(|k| &mut k.compute, key, || self.device.create_compute_pipeline(desc))
    }

    /// The pipeline of `key` in the table `table` picks, made by `make` (and counted) the first time.
    fn pipeline<P: Clone>(
        &self,
        table: impl Fn(&mut Kept) -> &mut HashMap<PipelineKey, P>,
        key: PipelineKey,
        make: impl FnOnce() -> P,
    ) -> P {
        if let Some(p) = table(&mut self.kept.borrow_mut()).get(&key) {
            return p.clone();
        }
        let pipeline = make();
        let c = self.compiled.get();
        self.compiled.set(Compiled { pipelines: c.pipelines + 1, ..c });
        table(&mut self.kept.borrow_mut()).entry(key).or_insert(pipeline).clone()
    }
}
