//! What the benchmarks share: the device, the bench scenes (built-ins and DamagedHelmet under an HDR from
//! ../shared/testdata) and their environment variables.

use mislab::api::{self, Budget, RenderStats};
use mislab::gpu::GpuContext;
use mislab::render::Renderer;
use mislab::scene::{self, envmap, Environment, LoadOptions, Scene};
use std::sync::Arc;
use std::time::Duration;

/// `name` parsed from the environment, or `default`.
pub fn env_or<T: std::str::FromStr>(name: &str, default: T) -> T {
    std::env::var(name).ok().and_then(|s| s.parse().ok()).unwrap_or(default)
}

/// The device, or a panic that says how to get one.
pub fn gpu() -> GpuContext {
    GpuContext::new().expect("a Vulkan adapter (apt-get install mesa-vulkan-drivers)")
}

/// The DamagedHelmet scene name, for case lists.
pub const HELMET: &str = "DamagedHelmet + noon_grass";

/// Loads a bench scene by label: a built-in name, or `HELMET` (the glTF lit by noon_grass_1k.hdr).
pub fn load(label: &str) -> Scene {
    if label != HELMET {
        return scene::load(label, &LoadOptions::default()).expect("built-in scene");
    }
    let shared = concat!(env!("CARGO_MANIFEST_DIR"), "/../shared/testdata");
    let helmet = format!("{shared}/gltf/khronos/DamagedHelmet/glTF-Binary/DamagedHelmet.glb");
    let sky = format!("{shared}/env/hdr/noon_grass_1k.hdr");
    let mut s = scene::load(&helmet, &LoadOptions::default()).expect("DamagedHelmet");
    let (map, _) = envmap::load_envmap(std::path::Path::new(&sky)).expect("env map");
    s.environment = Environment::Map { map: Arc::new(map), scale: 1.0, rotation: 0.0 };
    s
}

/// Renders progressively for `seconds` (pipelines already built), as `mislab render --time` does.
pub fn render_for(ctx: &GpuContext, r: &mut Renderer, seconds: f64) -> RenderStats {
    api::drive(ctx, r, api::Plan::of(Budget::Time(Duration::from_secs_f64(seconds))), &mut api::Unobserved)
        .expect("render")
}
