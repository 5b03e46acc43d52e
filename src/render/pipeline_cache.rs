//! The render pipelines built so far, by `PipelineKey`: the one cache the renderer and the viewer's engine share
//! the shape of (building one takes seconds on lavapipe, so nothing is built twice).

use crate::render::features::PipelineKey;
use std::collections::HashMap;

/// Compute pipelines by key.
#[derive(Default)]
pub struct PipelineCache {
    map: HashMap<PipelineKey, wgpu::ComputePipeline>,
}

impl PipelineCache {
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

    /// Forgets the pipelines for which `keep` is false.
    pub fn retain(&mut self, mut keep: impl FnMut(&PipelineKey) -> bool) {
        self.map.retain(|k, _| keep(k));
    }

    /// Forgets every pipeline.
    pub fn clear(&mut self) {
        self.map.clear();
    }
}
