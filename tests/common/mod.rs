//! Helpers shared by the GPU integration tests. A missing adapter is a test FAILURE with a clear message.
#![allow(dead_code)]

use glam::Vec3;
use mislab::gpu::GpuContext;
use mislab::render::film::Film;
use mislab::render::settings::Settings;
use mislab::render::Renderer;
use mislab::render::{gpu_scene::GpuScene, scene_data::SceneData};
use mislab::scene::{self, LoadOptions, Scene};

/// The GPU context every test of this binary shares (renderers on one context share their compiled pipelines,
/// which take lavapipe seconds each), or a panic that says how to get one.
pub fn gpu() -> &'static GpuContext {
    static CTX: std::sync::OnceLock<GpuContext> = std::sync::OnceLock::new();
    CTX.get_or_init(|| {
        GpuContext::new().unwrap_or_else(|e| {
            panic!("GPU tests need a Vulkan adapter and found none ({e}). On Debian/Ubuntu without a GPU: apt-get install mesa-vulkan-drivers")
        })
    })
}

/// Loads a built-in scene or file.
pub fn scene(name: &str) -> Scene {
    scene::load(name, &LoadOptions::default()).unwrap_or_else(|e| panic!("loading {name}: {e}"))
}

/// The DamagedHelmet (a BVH, textures) under the noon_grass HDR map: a scene that reads every scene table.
pub fn helmet_under_sky() -> Scene {
    let helmet = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../shared/testdata/gltf/khronos/DamagedHelmet/glTF-Binary/DamagedHelmet.glb"
    );
    let hdr = concat!(env!("CARGO_MANIFEST_DIR"), "/../shared/testdata/env/hdr/noon_grass_1k.hdr");
    let mut scene = self::scene(helmet);
    let map = scene::envmap::load_envmap(std::path::Path::new(hdr)).unwrap_or_else(|e| panic!("{hdr}: {e}")).0;
    scene.environment = scene::Environment::Map { map: std::sync::Arc::new(map), scale: 1.0, rotation: 0.0 };
    scene
}

/// Renders `spp` samples of `scene` with `settings` and reads the film back.
pub fn render(ctx: &GpuContext, scene: &Scene, settings: &Settings, spp: u32) -> Film {
    let gs = GpuScene::upload(ctx, SceneData::build(scene)).expect("upload");
    let mut r = Renderer::new(ctx, &gs, scene.camera.clone(), settings.clone()).expect("renderer");
    r.render(ctx, spp).expect("render");
    r.film(ctx).expect("readback")
}

/// Small test settings.
pub fn small(width: u32, height: u32) -> Settings {
    Settings { width, height, ..Settings::default() }
}

/// Two-sided Šidák-corrected z threshold for `m` tests at family-wise level `alpha`.
pub fn sidak_z(alpha: f64, m: usize) -> f64 {
    let per_test = 1.0 - (1.0 - alpha).powf(1.0 / m as f64);
    inverse_normal_cdf(1.0 - per_test / 2.0)
}

/// Acklam's rational approximation of the standard normal quantile (relative error < 1.2e-9).
pub fn inverse_normal_cdf(p: f64) -> f64 {
    let a = [
        -3.969683028665376e+01,
        2.209460984245205e+02,
        -2.759285104469687e+02,
        1.383577518672690e+02,
        -3.066479806614716e+01,
        2.506628277459239e+00,
    ];
    let b = [
        -5.447609879822406e+01,
        1.615858368580409e+02,
        -1.556989798598866e+02,
        6.680131188771972e+01,
        -1.328068155288572e+01,
    ];
    let c = [
        -7.784894002430293e-03,
        -3.223964580411365e-01,
        -2.400758277161838e+00,
        -2.549671010279440e+00,
        4.374664141464968e+00,
        2.938163982698783e+00,
    ];
    let d = [7.784695709041462e-03, 3.224671290700398e-01, 2.445134137142996e+00, 3.754408661907416e+00];
    let pl = 0.02425;
    if p < pl {
        let q = (-2.0 * p.ln()).sqrt();
        (((((c[0] * q + c[1]) * q + c[2]) * q + c[3]) * q + c[4]) * q + c[5])
            / ((((d[0] * q + d[1]) * q + d[2]) * q + d[3]) * q + 1.0)
    } else if p <= 1.0 - pl {
        let q = p - 0.5;
        let r = q * q;
        (((((a[0] * r + a[1]) * r + a[2]) * r + a[3]) * r + a[4]) * r + a[5]) * q
            / (((((b[0] * r + b[1]) * r + b[2]) * r + b[3]) * r + b[4]) * r + 1.0)
    } else {
        -inverse_normal_cdf(1.0 - p)
    }
}

/// A UV sphere of `rings` × `segs` quads, wound outwards (or inwards), its poles fans. The seam's vertices at
/// φ = 2π are computed, not copied from φ = 0, so they differ from them in the last bits, as exported meshes' do.
pub fn uv_sphere(c: Vec3, r: f32, rings: u32, segs: u32, outward: bool) -> Vec<[Vec3; 3]> {
    let p = |i: u32, j: u32| {
        let (th, ph) = (std::f32::consts::PI * i as f32 / rings as f32, std::f32::consts::TAU * j as f32 / segs as f32);
        c + r * Vec3::new(th.sin() * ph.cos(), th.cos(), th.sin() * ph.sin())
    };
    let mut tris = vec![];
    for i in 0..rings {
        for j in 0..segs {
            let (a, b, cc, d) = (p(i, j), p(i + 1, j), p(i + 1, j + 1), p(i, j + 1));
            if i > 0 {
                tris.push([a, cc, d]);
            }
            if i + 1 < rings {
                tris.push([a, b, cc]);
            }
        }
    }
    for t in &mut tris {
        let n = (t[1] - t[0]).cross(t[2] - t[0]);
        if (n.dot(t[0] - c) > 0.0) != outward {
            t.swap(1, 2);
        }
    }
    tris
}

/// A mesh of separate triangles (no shared vertices) of material `material`.
pub fn mesh_of(name: &str, tris: &[[Vec3; 3]], material: u32) -> mislab::scene::Mesh {
    mislab::scene::Mesh {
        name: name.into(),
        positions: tris.iter().flatten().copied().collect(),
        indices: (0..tris.len() as u32).map(|t| [3 * t, 3 * t + 1, 3 * t + 2]).collect(),
        material,
        ..Default::default()
    }
}

/// The parallelogram c, c + u, c + u + v, c + v as two triangles (wound from u towards v).
pub fn rect(c: Vec3, u: Vec3, v: Vec3) -> [[Vec3; 3]; 2] {
    [[c, c + u, c + u + v], [c, c + u + v, c + v]]
}

/// Reads a child process's piped stderr on a thread, so that it never blocks on a full pipe: the receiver gets a
/// message once the text so far contains `needle` (a line that marks a moment of its run), and the thread returns
/// the whole text when the child closes the pipe.
pub fn watch_stderr(
    child: &mut std::process::Child,
    needle: &'static str,
) -> (std::sync::mpsc::Receiver<()>, std::thread::JoinHandle<String>) {
    use std::io::Read;
    let (tx, rx) = std::sync::mpsc::channel();
    let mut pipe = child.stderr.take().expect("the child's stderr is piped");
    let reader = std::thread::spawn(move || {
        let (mut all, mut buf, mut told) = (Vec::new(), [0u8; 256], false);
        while let Ok(n) = pipe.read(&mut buf) {
            if n == 0 {
                break;
            }
            all.extend_from_slice(&buf[..n]);
            if !told && String::from_utf8_lossy(&all).contains(needle) {
                let _ = tx.send(());
                told = true;
            }
        }
        String::from_utf8_lossy(&all).into_owned()
    });
    (rx, reader)
}
