//! Two-sided area lights (pbrt `AreaLightSource "diffuse" "bool twosided" true`): a square emitter above a
//! Lambert floor, its front facing away from the floor, gives the floor exactly the irradiance of the square seen
//! from below (closed form) when two-sided, and none when one-sided — by light sampling (solid angle and area), BSDF
//! sampling and MIS. The light table counts both faces' power.

mod common;
mod scratch;

use mislab::render::scene_data::SceneData;
use mislab::render::settings::{LightSampling, Mode, Settings, Strategy};
use mislab::scene::{self, LoadOptions, Scene};
use std::f64::consts::PI;

const ALBEDO: f64 = 0.5;
/// Half the side of the square light, and its height above the floor point the camera sees.
const HALF: f64 = 1.0;
const HEIGHT: f64 = 1.0;

/// The floor (y = 0, 20 × 20, Lambert 0.5) and a square light of radiance 1 at y = HEIGHT whose front faces up
/// (`up`) or down; the camera at y = 0.5 looks straight down with a 1° field of view.
fn scene_text(two_sided: bool, up: bool) -> String {
    // Counter-clockwise seen from above (0 2 1 …) faces +y in mislab's convention; the test does not rely on
    // pbrt's rule for the sign: it checks that exactly one orientation lights the floor when one-sided.
    let indices = if up { "0 2 1 0 3 2" } else { "0 1 2 0 2 3" };
    format!(
        r#"LookAt 0 0.5 0  0 0 0  0 0 -1
Camera "perspective" "float fov" [ 1 ]
Film "rgb" "integer xresolution" [ 16 ] "integer yresolution" [ 16 ]
WorldBegin
AttributeBegin
  Material "diffuse" "rgb reflectance" [ {ALBEDO} {ALBEDO} {ALBEDO} ]
  Shape "trianglemesh" "point3 P" [ -10 0 -10  10 0 -10  10 0 10  -10 0 10 ] "integer indices" [ 0 2 1 0 3 2 ]
AttributeEnd
AttributeBegin
  AreaLightSource "diffuse" "rgb L" [ 1 1 1 ] "bool twosided" {two_sided}
  Material "diffuse" "rgb reflectance" [ 0 0 0 ]
  Shape "trianglemesh" "point3 P" [ -{HALF} {HEIGHT} -{HALF}  {HALF} {HEIGHT} -{HALF}  {HALF} {HEIGHT} {HALF}  -{HALF} {HEIGHT} {HALF} ]
    "integer indices" [ {indices} ]
AttributeEnd
"#
    )
}

fn load(two_sided: bool, up: bool) -> Scene {
    let dir = scratch::unique("two-sided");
    let path = dir.join(format!("light-{two_sided}-{up}.pbrt"));
    std::fs::write(&path, scene_text(two_sided, up)).unwrap();
    let s = scene::load(path.to_str().unwrap(), &LoadOptions::default()).unwrap_or_else(|e| panic!("{e}"));
    assert!(s.warnings.iter().all(|w| !w.contains("twosided")), "twosided is imported, not ignored: {:?}", s.warnings);
    s
}

/// Radiance leaving the floor under the light's centre: ρ/π · E, with E = π·L·F for the point-to-rectangle form
/// factor F of the four HALF × HALF quarters (each corner-aligned above the point).
fn analytic() -> f64 {
    let (x, y) = (HALF / HEIGHT, HALF / HEIGHT);
    let corner = (x / (1.0 + x * x).sqrt() * (y / (1.0 + x * x).sqrt()).atan()
        + y / (1.0 + y * y).sqrt() * (x / (1.0 + y * y).sqrt()).atan())
        / (2.0 * PI);
    ALBEDO * 4.0 * corner
}

fn mean(ctx: &mislab::gpu::GpuContext, s: &Scene, strategy: Strategy, light_sampling: LightSampling) -> (f64, u64) {
    let settings = Settings { mode: Mode::Direct, strategy, light_sampling, ..common::small(16, 16) };
    let film = common::render(ctx, s, &settings, 512);
    (film.mean.iter().map(|p| p[1] as f64).sum::<f64>() / film.mean.len() as f64, film.nonfinite_total)
}

#[test]
fn two_sided_light_matches_the_analytic_irradiance_from_behind() {
    let ctx = common::gpu();
    let expected = analytic();
    assert!((expected - 0.27706).abs() < 1e-4, "{expected}");
    // One-sided: exactly one orientation lights the floor, with the analytic value; the other gives black.
    let (down, _) = mean(&ctx, &load(false, false), Strategy::Mis, LightSampling::SolidAngle);
    let (up, _) = mean(&ctx, &load(false, true), Strategy::Mis, LightSampling::SolidAngle);
    let (front, back) = if down > up { (down, up) } else { (up, down) };
    assert!((front / expected - 1.0).abs() < 0.01, "one-sided, facing the floor: {front} vs {expected}");
    assert!(back < 1e-6, "one-sided, facing away: {back} (no light expected)");
    let away = down < up; // which orientation faces away from the floor
                          // Two-sided, facing away: the back face lights the floor, by every technique. 131,072 samples: the BSDF
                          // estimator (a hit with probability F ≈ 0.55) has a relative standard error of 0.25 %; the others far less.
    let s = load(true, !away);
    for (strategy, ls) in [
        (Strategy::Mis, LightSampling::SolidAngle),
        (Strategy::Light, LightSampling::SolidAngle),
        (Strategy::Light, LightSampling::Area),
        (Strategy::Bsdf, LightSampling::SolidAngle),
    ] {
        let (m, nonfinite) = mean(&ctx, &s, strategy, ls);
        assert_eq!(nonfinite, 0);
        let tol = if strategy == Strategy::Bsdf { 0.01 } else { 0.005 };
        assert!((m / expected - 1.0).abs() < tol, "two-sided {strategy:?}/{ls:?}: {m} vs analytic {expected}");
    }
}

#[test]
fn two_sided_light_has_twice_the_power_in_light_selection() {
    // A two-sided and a one-sided square of the same size and radiance: power-proportional selection 2 : 1.
    let mut s = load(true, true);
    let one = load(false, true);
    let m = one.meshes.last().unwrap().clone();
    let lm = s.materials.len() as u32;
    s.materials.push(one.materials[m.material as usize].clone());
    s.meshes.push(scene::Mesh { material: lm, ..m });
    let data = SceneData::build(&s);
    let two: f64 = data.lights.iter().filter(|l| l.two_sided == 1).map(|l| l.pmf_power as f64).sum();
    let single: f64 = data.lights.iter().filter(|l| l.two_sided == 0).map(|l| l.pmf_power as f64).sum();
    assert_eq!(data.lights.len(), 4, "two triangles per square");
    assert!((two - 2.0 / 3.0).abs() < 1e-6 && (single - 1.0 / 3.0).abs() < 1e-6, "{two} {single}");
}
