//! The `Renderer`'s frame parameters (`GpuFrameParams`, WGSL `FrameParams`): what one dispatch tells the kernel —
//! the film, the settings, the camera, the scene's lights and environment, the guide's grid and state.

use super::Renderer;
use crate::gpu::types::GpuFrameParams;
use crate::render::env_guide;
use crate::render::pixel_filter;
use crate::render::settings::Mode;
use crate::render::tile_order::tile_row_stride;

impl Renderer {
    /// The frame parameters of a dispatch of `spp` samples starting at the current sample count.
    pub fn frame_params(&self, spp: u32) -> GpuFrameParams {
        let s = &self.settings;
        let (right, up, forward) = self.camera.frame();
        let (forward, tan_half_fov) = self.camera.cropped_view(forward, right, up, s.width, s.height);
        GpuFrameParams {
            width: s.width,
            height: s.height,
            // The guide's learning pass is the learners' sample 0, wherever the render stands (`ensure_guide`).
            sample_base: if self.guide_train == env_guide::LEARN_ONLY { 0 } else { self.samples },
            samples_per_dispatch: spp,
            seed: s.seed,
            mode: s.mode.tag(),
            max_depth: if s.mode == Mode::Direct { 1 } else { s.max_depth },
            strategy: s.strategy.tag(),
            light_sampling: s.light_sampling.tag(),
            env_sampling: s.env_sampling.tag(),
            light_select: s.light_select.tag(),
            heuristic: s.heuristic.tag(),
            power_beta: s.power_beta,
            light_samples: s.light_samples,
            bsdf_samples: s.bsdf_samples,
            mis_kind: s.mis.tag(),
            sampler: s.sampler.tag(),
            num_lights: self.num_lights,
            rr_depth: s.rr_depth,
            env_light: self.env_light,
            cam_origin: (self.camera.position - self.origin).into(),
            tan_half_fov,
            cam_right: right.into(),
            aspect: s.width as f32 / s.height as f32,
            cam_up: up.into(),
            env_scale: self.env_scale,
            cam_forward: forward.into(),
            env_rotation: self.env_rotation,
            env_constant: self.env_constant,
            env_width: self.env_size.0,
            env_height: self.env_size.1,
            sampler_spp: self.sampler_spp,
            row_offset: 0,
            row_count: s.height,
            offset_scale: self.offset_scale,
            ris_candidates: s.ris_candidates,
            tile_row_stride: tile_row_stride(s.height.div_ceil(8)),
            first_hit_light_split: s.first_hit_light_split,
            guide_min: self.guide_grid.min.into(),
            guide_train: self.guide_train,
            guide_inv_cell: self.guide_grid.inv_cell.into(),
            guide_slots: self.guide_grid.slots() as u32,
            guide_dims: self.guide_grid.dims.into(),
            guide_on: self.guide_on as u32,
            guide_learner_period: self.guide_learner_period(),
            lamp_first: self.lamps.0,
            lamp_count: self.lamps.1,
            lamps_only: self.lamps.2 as u32,
            occluder_first: self.occluders.0,
            occluder_count: self.occluders.1,
            pixel_filter: s.filter.tag(),
            filter_radius: s.filter_radius(),
            filter_sigma: s.filter_sigma,
            filter_norm: pixel_filter::shader_norm(s.filter, s.filter_radius(), s.filter_sigma),
            _pad_filter: [0; 2],
        }
    }
}
