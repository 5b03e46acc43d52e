//! The material kinds beyond metallic-roughness (docs/materials.md), rendered: a TOML scene of conductors loads
//! and renders without NaN/Inf, and a white furnace bounds each conductor's energy. The sampling routines'
//! chi-square tests are in tests/sampling.rs (`chi2_conductor`).

mod common;

use mislab::scene::{self, Environment, LoadOptions, MaterialKind};
use mislab::settings::{Mode, Settings, Strategy};

/// A row of conductors in a white furnace (constant radiance 1, nothing else): k = 10⁴ makes F ≈ 1, so each
/// sphere's pixels are the directional albedo of its single-scattering GGX surface (a convex sphere sees only the
/// environment after one bounce). With BSDF sampling every sample's weight is F·G2/G1 ≤ 1.
const FURNACE: &str = r#"
[camera]
position = [0, 0, 9]
look_at = [0, 0, 0]
vfov = 20

[materials.rough]
type = "conductor"
eta = 1.5
k = 1e4
alpha = 0.5

[materials.aniso]
type = "conductor"
eta = 1.5
k = 1e4
alpha_u = 0.05
alpha_v = 0.4

[materials.gold]
type = "conductor"
eta = [0.18, 0.42, 1.37]
k = [3.42, 2.35, 1.77]
alpha = 0.1

[[sphere]]
center = [-1.1, 0, 0]
radius = 0.5
material = "rough"

[[sphere]]
center = [0, 0, 0]
radius = 0.5
material = "aniso"

[[sphere]]
center = [1.1, 0, 0]
radius = 0.5
material = "gold"

[environment]
constant = 1
"#;

fn load(text: &str, name: &str) -> scene::Scene {
    let path = std::path::Path::new(env!("CARGO_TARGET_TMPDIR")).join(name);
    std::fs::write(&path, text).expect("write the test scene");
    scene::load(path.to_str().expect("utf-8 path"), &LoadOptions::default()).unwrap_or_else(|e| panic!("{e}"))
}

#[test]
fn toml_conductor_syntax() {
    let s = load(FURNACE, "furnace-conductors.toml");
    assert!(matches!(s.environment, Environment::Constant(_)));
    let kinds: Vec<&MaterialKind> = s.materials.iter().map(|m| &m.kind).collect();
    assert!(kinds.iter().all(|k| matches!(k, MaterialKind::Conductor { .. })), "{kinds:?}");
    let aniso = s.materials.iter().find(|m| m.name == "aniso").expect("aniso");
    assert!(
        matches!(aniso.kind, MaterialKind::Conductor { alpha_u, alpha_v, .. } if alpha_u == 0.05 && alpha_v == 0.4)
    );
    // Mixing the Fresnel-1 and complex-Fresnel keys is an error, not a silent choice.
    let path = std::path::Path::new(env!("CARGO_TARGET_TMPDIR")).join("bad-conductor.toml");
    std::fs::write(&path, "[materials.m]\ntype = \"conductor\"\nreflectance = 0.5\neta = 1.5\nalpha = 0.1\n").unwrap();
    let err = scene::load(path.to_str().unwrap(), &LoadOptions::default()).expect_err("must fail").to_string();
    assert!(err.contains("bad-conductor.toml") && err.contains("either 'reflectance' or 'eta'/'k'"), "{err}");
}

#[test]
fn conductor_white_furnace() {
    let ctx = common::gpu();
    let s = load(FURNACE, "furnace-conductors.toml");
    let (w, h) = (96u32, 32u32);
    let settings = Settings { max_depth: 8, strategy: Strategy::Bsdf, ..common::small(w, h) };
    let film = common::render(&ctx, &s, &settings, 64);
    let bad: u32 = film.nonfinite.iter().sum();
    assert_eq!(bad, 0, "NaN/Inf samples");
    // The same scene with the isotropic sphere as the metallic-roughness model's Fresnel-1 GGX conductor
    // (bsdf.wgsl, tested on its own): the two microfacet models are the same, so F ≈ 1 must give the same image.
    let mut mr = s.clone();
    let i = mr.materials.iter().position(|m| m.name == "rough").expect("rough");
    mr.materials[i] = mislab::scene::Material::conductor("rough", glam::Vec3::ONE, 0.5);
    let film_mr = common::render(&ctx, &mr, &settings, 64);
    // Pixels around each sphere's centre (the sphere spans ~±0.5/(9·tan 10°) ≈ 0.31 of the film height).
    for (i, cx) in [-1.1f32, 0.0, 1.1].iter().enumerate() {
        let px = (w as f32 * 0.5 + cx / (9.0 * 10f32.to_radians().tan()) * h as f32 * 0.5) as i32;
        let mut sum = [0f64; 3];
        let mut n = 0.0;
        for y in (h as i32 / 2 - 2)..(h as i32 / 2 + 2) {
            for x in (px - 2)..(px + 2) {
                let m = film.mean[(y as u32 * w + x as u32) as usize];
                for c in 0..3 {
                    sum[c] += m[c] as f64;
                }
                n += 1.0;
            }
        }
        let mean = sum.map(|v| v / n);
        eprintln!("sphere {i}: mean {mean:?}");
        if i == 0 {
            let mut r = 0.0;
            for y in (h as i32 / 2 - 2)..(h as i32 / 2 + 2) {
                for x in (px - 2)..(px + 2) {
                    r += film_mr.mean[(y as u32 * w + x as u32) as usize][0] as f64 / n;
                }
            }
            assert!((mean[0] - r).abs() < 2e-3 * r, "conductor k = 1e4: {} vs Fresnel-1 GGX {r}", mean[0]);
        }
        if i < 2 {
            // F ≈ 1: energy only lost to single scattering, never gained; and not all of it lost.
            for c in mean {
                assert!((0.5..=1.0 + 1e-4).contains(&c), "sphere {i}: furnace value {c} outside [0.5, 1]");
            }
        } else {
            // Gold: red above blue (its Fresnel), and below 1.
            assert!(mean[0] > mean[2] && mean[0] < 1.0, "gold: {mean:?}");
        }
    }
}

/// Mean of a 4×4 block of pixels around the centre of the sphere at x = cx (camera at z = 9, vfov 20°).
fn sphere_mean(film: &mislab::film::Film, w: u32, h: u32, cx: f32) -> [f64; 3] {
    let px = (w as f32 * 0.5 + cx / (9.0 * 10f32.to_radians().tan()) * h as f32 * 0.5) as i32;
    let mut sum = [0f64; 3];
    let mut n = 0.0;
    for y in (h as i32 / 2 - 2)..(h as i32 / 2 + 2) {
        for x in (px - 2)..(px + 2) {
            let m = film.mean[(y as u32 * w + x as u32) as usize];
            for c in 0..3 {
                sum[c] += m[c] as f64;
            }
            n += 1.0;
        }
    }
    sum.map(|v| v / n)
}

const GLASS_FURNACE: &str = r#"
[camera]
position = [0, 0, 9]
look_at = [0, 0, 0]
vfov = 20

[materials.glass]
type = "dielectric"
eta = 1.5

[materials.rough]
type = "dielectric"
eta = 1.5
alpha = 0.3

[materials.leaf]
type = "diffuse-transmission"
reflectance = 0.4
transmittance = 0.6

[[sphere]]
center = [-1.1, 0, 0]
radius = 0.5
material = "glass"

[[sphere]]
center = [0, 0, 0]
radius = 0.5
material = "rough"

[[sphere]]
center = [1.1, 0, 0]
radius = 0.5
material = "leaf"

[environment]
constant = 1
"#;

#[test]
fn dielectric_white_furnace() {
    let ctx = common::gpu();
    let s = load(GLASS_FURNACE, "furnace-glass.toml");
    let (w, h) = (96u32, 32u32);
    for (strategy, max_depth) in
        [(Strategy::Bsdf, 1), (Strategy::Bsdf, 2), (Strategy::Bsdf, 3), (Strategy::Bsdf, 32), (Strategy::Mis, 32)]
    {
        let settings = Settings { max_depth, strategy, mode: Mode::Path, ..common::small(w, h) };
        let film = common::render(&ctx, &s, &settings, 64);
        let bad: u32 = film.nonfinite.iter().sum();
        assert_eq!(bad, 0, "NaN/Inf samples");
        for cx in [-1.1f32, 0.0, 1.1] {
            eprintln!("{strategy:?} {max_depth} sphere at {cx}: {:?}", sphere_mean(&film, w, h, cx));
        }
    }
}
