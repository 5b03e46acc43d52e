//! Alpha cut-outs (pbrt `"texture alpha"`): a 2 × 2 checkerboard-masked black quad between a square light and
//! the camera or a Lambert floor. The checkerboard has a cell corner on the symmetry axis, so a 90° turn about it
//! swaps holes and cells while leaving the views, the light and the floor unchanged: exactly half of what would
//! arrive unmasked gets through — for camera rays (the image mean is 0.5 of the light's radiance) and for shadow
//! and BSDF rays (the floor gets half the analytic irradiance of the square light).

mod common;
mod scratch;

use mislab::render::features::Features;
use mislab::render::scene_data::SceneData;
use mislab::render::settings::{Mode, Settings, Strategy};
use mislab::scene::{self, LoadOptions, Scene};
use std::f64::consts::PI;
use std::path::{Path, PathBuf};

/// 256² checkerboard of 4-pixel cells (64 × 64 cells): alpha 0 (a hole) or 255, RGB white, in `dir`.
fn write_mask(dir: &Path) -> PathBuf {
    let path = dir.join("checker.png");
    let img = image::RgbaImage::from_fn(256, 256, |x, y| {
        let a = if (x / 4 + y / 4) % 2 == 0 { 255 } else { 0 };
        image::Rgba([255, 255, 255, a])
    });
    img.save(&path).unwrap();
    path
}

/// The masked quad at y = 0.5 (x, z ∈ [-1, 1], uv over [0, 1]: a cell corner at the origin), the square light
/// (half-side 1, radiance 1) at y = 1 facing down, a Lambert 0.5 floor at y = 0; the camera at y = 0.25 looks up
/// (at the light through the mask, 60°) or down (at the floor, 1°).
fn load(camera_up: bool, masked: bool) -> Scene {
    let dir = scratch::unique("alpha");
    write_mask(&dir); // beside the scene file, named relative to it (scene files may not reach outside their folder)
    let look = if camera_up {
        "LookAt 0 0.25 0  0 1 0  0 0 1\nCamera \"perspective\" \"float fov\" [ 60 ]"
    } else {
        "LookAt 0 0.25 0  0 0 0  0 0 -1\nCamera \"perspective\" \"float fov\" [ 1 ]"
    };
    let alpha = if masked { r#""texture alpha" "mask""# } else { "" };
    let text = format!(
        r#"{look}
Film "rgb" "integer xresolution" [ 16 ] "integer yresolution" [ 16 ]
WorldBegin
Texture "mask" "float" "imagemap" "string filename" [ "checker.png" ] "string encoding" "linear"
AttributeBegin
  Material "diffuse" "rgb reflectance" [ 0.5 0.5 0.5 ]
  Shape "trianglemesh" "point3 P" [ -10 0 -10  10 0 -10  10 0 10  -10 0 10 ] "integer indices" [ 0 2 1 0 3 2 ]
AttributeEnd
AttributeBegin
  Material "diffuse" "rgb reflectance" [ 0 0 0 ]
  Shape "trianglemesh" "point3 P" [ -1 0.5 -1  1 0.5 -1  1 0.5 1  -1 0.5 1 ] "point2 uv" [ 0 0  1 0  1 1  0 1 ]
    "integer indices" [ 0 1 2 0 2 3 ] {alpha}
AttributeEnd
AttributeBegin
  AreaLightSource "diffuse" "rgb L" [ 1 1 1 ]
  Material "diffuse" "rgb reflectance" [ 0 0 0 ]
  Shape "trianglemesh" "point3 P" [ -1 1 -1  1 1 -1  1 1 1  -1 1 1 ] "integer indices" [ 0 1 2 0 2 3 ]
AttributeEnd
"#
    );
    let path = dir.join(format!("alpha-{camera_up}-{masked}.pbrt"));
    std::fs::write(&path, text).unwrap();
    let s = scene::load(path.to_str().unwrap(), &LoadOptions::default()).unwrap_or_else(|e| panic!("{e}"));
    assert!(s.warnings.iter().all(|w| !w.contains("alpha")), "alpha is imported: {:?}", s.warnings);
    s
}

fn mean(ctx: &mislab::gpu::GpuContext, s: &Scene, strategy: Strategy, spp: u32) -> f64 {
    let settings = Settings { mode: Mode::Direct, strategy, ..common::small(16, 16) };
    let film = common::render(ctx, s, &settings, spp);
    assert_eq!(film.nonfinite_total, 0);
    film.mean.iter().map(|p| p[1] as f64).sum::<f64>() / film.mean.len() as f64
}

/// ρ/π · E under the centre of the square light (half-side 1 at height 1): ρ · 4 · the corner form factor.
fn floor_unmasked() -> f64 {
    let x = 1.0f64;
    let corner = 2.0 * (x / (1.0 + x * x).sqrt() * (x / (1.0 + x * x).sqrt()).atan()) / (2.0 * PI);
    0.5 * 4.0 * corner
}

#[test]
fn checkerboard_cut_out_passes_half_the_light() {
    let ctx = common::gpu();
    // Scenes without masks compile the alpha test out; the masked ones take the BVH (no baked traversal).
    let plain = Features::of(&SceneData::build(&load(true, false)));
    assert!(!plain.alpha);
    let masked_up = load(true, true);
    let f = Features::of(&SceneData::build(&masked_up));
    assert!(f.alpha && f.flat.is_none());
    // Camera rays: the light (radiance 1) through the holes, the black quad elsewhere.
    let up = mean(&ctx, &masked_up, Strategy::Mis, 16);
    assert!((up - 0.5).abs() < 0.01, "camera through the mask: mean {up}, expected 0.5");
    assert!(mean(&ctx, &load(true, false), Strategy::Mis, 4) < 1e-6, "unmasked, the quad hides the light");
    // Shadow rays (light sampling) and BSDF rays: half the unmasked irradiance.
    let expected = 0.5 * floor_unmasked();
    let masked_down = load(false, true);
    for (strategy, tol) in [(Strategy::Light, 0.01), (Strategy::Bsdf, 0.03)] {
        let m = mean(&ctx, &masked_down, strategy, 256);
        assert!((m / expected - 1.0).abs() < tol, "floor under the mask, {strategy:?}: {m} vs {expected}");
    }
}
