//! What `mislab info` says of the device and of a scene: its statistics, lights, BVH, memory, and the code paths
//! its specialised pipelines compile in.

use super::lab::Lab;
use super::scene::SceneHandle;
use crate::render::{features::Features, gpu_scene};
use crate::scene::Environment;

/// Every Vulkan adapter, one line each: name, type, driver.
pub fn adapters() -> Vec<String> {
    crate::gpu::list_adapters().iter().map(|a| format!("{} ({:?}, {})", a.name, a.device_type, a.driver)).collect()
}

impl Lab {
    /// The chosen adapter and its limits, several lines.
    pub fn describe(&self) -> String {
        crate::gpu::describe(self.gpu())
    }
}

impl SceneHandle {
    /// The scene's report for `mislab info`, one line each: the importer's report, counts, lights, BVH, memory,
    /// what the upload does on `lab`'s device, and the features compiled into its specialised pipelines.
    pub fn report(&self, lab: &Lab) -> Vec<String> {
        let (scene, data) = (self.scene(), self.data());
        let mut lines = scene.import_report.clone();
        lines.push(format!(
            "scene {}: {} triangles, {} spheres, {} quads, {} materials, {} textures, {} lights ({} delta), environment: {}",
            scene.name,
            scene.triangle_count(),
            scene.spheres.len(),
            scene.quads.len(),
            scene.materials.len(),
            scene.textures.len(),
            data.selectable_lights(),
            data.delta_lights,
            match &scene.environment {
                Environment::None => "none".to_string(),
                Environment::Constant(c) => format!("constant {c}"),
                Environment::Map { map, .. } => format!("map {} ({}x{})", map.path.display(), map.width, map.height),
            }
        ));
        let file = &scene.file_settings;
        let mut stated = Vec::new();
        if let Some([w, h]) = scene.film_size {
            stated.push(format!("image {w}x{h}"));
        }
        if let Some((depth, source)) = &file.max_depth {
            stated.push(format!("--mode path --max-depth {depth} ({source})"));
        }
        if let Some((spp, source)) = &file.spp {
            stated.push(format!("--spp {spp} ({source})"));
        }
        if let Some((sampler, source)) = &file.sampler {
            stated.push(format!("--sampler {sampler} ({source})"));
        }
        if let Some((f, source)) = &file.filter {
            stated.push(format!("{} ({source})", filter_flags(f)));
        }
        if !stated.is_empty() {
            lines.push(format!("render settings from the file (flags override them): {}", stated.join(", ")));
        }
        let lamps = data.convex_lamps();
        if lamps > 0 {
            lines.push(format!(
                "convex lamps: {lamps}, {} faces in all; each is one light, sampled through the cone of a sphere inside it",
                data.lamp_faces
            ));
        }
        let boxed: Vec<_> = data.lights.iter().filter(|l| l.shadow_box == 1).collect();
        if !boxed.is_empty() {
            let mut meshes: Vec<[u32; 6]> = boxed
                .iter()
                .map(|l| {
                    let [a, b, c] = l.position.map(f32::to_bits);
                    let [d, e, f] = l.direction.map(f32::to_bits);
                    [a, b, c, d, e, f]
                })
                .collect();
            meshes.sort_unstable();
            meshes.dedup();
            lines.push(format!(
                "isolated emitters: {} triangle lights in {} meshes; shadow rays towards them stop at the mesh's box",
                boxed.len() - lamps,
                meshes.len()
            ));
        }
        lines.push(format!(
            "BVH: {} nodes, {:.1} ms, SAH cost {:.2}, {} bytes",
            data.bvh_node_count(),
            data.bvh_seconds * 1e3,
            data.bvh_sah,
            data.bvh_bytes()
        ));
        let m = gpu_scene::memory_per_triangle(data);
        let every = gpu_scene::binding_sizes(data).iter().sum::<u64>();
        lines.push(format!(
            "memory per triangle: BVH {:.0} B, geometry {:.0} B, shading {:.0} B, total {:.0} B; every scene buffer {:.1} MiB",
            m.bvh,
            m.geometry,
            m.shading,
            m.total(),
            every as f64 / (1u64 << 20) as f64
        ));
        // What the upload does on this device: texels or vertices past one binding take a second, or it refuses.
        let mut uploaded = data.clone();
        if let Err(e) = gpu_scene::fit_to_binding_limit(&mut uploaded, lab.gpu().max_storage_binding()) {
            lines.push(format!("upload: {e}"));
        }
        let features = Features::of(&uploaded);
        lines.push(format!("features (code paths compiled into its specialised pipelines): {}", features.describe()));
        lines
    }
}

/// The flags that select a file's pixel filter.
pub fn filter_flags(f: &crate::scene::FileFilter) -> String {
    let sigma = if f.shape == "gaussian" { format!(" --filter-sigma {}", f.sigma) } else { String::new() };
    format!("--filter {} --filter-radius {}{sigma}", f.shape, f.radius)
}
