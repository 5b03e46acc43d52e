//! The render pipelines built so far, by `PipelineKey`: the one cache the renderer and the viewer's engine share
//! the shape of (building one takes seconds on lavapipe, so nothing is built twice).

use crate::gpu::PipelineMemo;
use crate::render::features::PipelineKey;
use std::collections::HashMap;
use std::hash::{Hash, Hasher};

/// Compute pipelines by key, and the device's memo they are shared through (`get_or_share`; a default cache has a
/// memo of its own).
#[derive(Default)]
pub struct PipelineCache {
    map: HashMap<PipelineKey, wgpu::ComputePipeline>,
    device: PipelineMemo,
}

impl PipelineCache {
    /// An empty cache that shares pipelines through the device's `memo` (`GpuContext::pipelines`).
    pub fn on_device(memo: &PipelineMemo) -> PipelineCache {
        PipelineCache { map: HashMap::new(), device: memo.clone() }
    }

    /// The device's memo this cache shares through.
    pub fn memo(&self) -> &PipelineMemo {
        &self.device
    }

    /// The pipeline for `key`, if built.
    pub fn get(&self, key: &PipelineKey) -> Option<&wgpu::ComputePipeline> {
        self.map.get(key)
    }

    /// Whether the pipeline for `key` is built.
    pub fn contains(&self, key: &PipelineKey) -> bool {
        self.map.contains_key(key)
    }

    /// Adds (or replaces) the pipeline for `key`.
    pub fn insert(&mut self, key: PipelineKey, pipeline: wgpu::ComputePipeline) {
        self.map.insert(key, pipeline);
    }

    /// Makes sure the pipeline for `key` is here: from this cache, else from the device's memo (another renderer
    /// built it: same `source` and key), else built by `build` (through the device's on-disk store, if any) and remembered in both. Every render pipeline has the
    /// same layout, so the source and the key tell them apart.
    pub fn get_or_share<E>(
        &mut self,
        key: PipelineKey,
        source: &str,
        build: impl FnOnce(Option<&crate::gpu::PipelineStore>) -> Result<wgpu::ComputePipeline, E>,
    ) -> Result<(), E> {
        if self.map.contains_key(&key) {
            return Ok(());
        }
        let mut h = std::collections::hash_map::DefaultHasher::new();
        ("render_main", source, key).hash(&mut h);
        let fingerprint = h.finish();
        let pipeline = match self.device.get(fingerprint) {
            Some(p) => p,
            None => {
                let p = build(self.device.store())?;
                self.device.insert(fingerprint, &p);
                p
            }
        };
        self.map.insert(key, pipeline);
        Ok(())
    }

    /// Forgets the pipelines for which `keep` is false.
    pub fn retain(&mut self, mut keep: impl FnMut(&PipelineKey) -> bool) {
        self.map.retain(|k, _| keep(k));
    }

    /// Forgets every pipeline.
    pub fn clear(&mut self) {
        self.map.clear();
    }
}
