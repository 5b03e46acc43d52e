//! The material kinds beyond metallic-roughness (docs/materials.md), rendered: TOML scenes of conductors, glass and
//! diffuse transmission load and render without NaN/Inf, white furnaces bound each material's energy, and the
//! unreachable-light warning names light behind glass. The sampling routines' chi-square tests, the Fresnel
//! reference and the reciprocity checks are in tests/sampling.rs (`chi2_conductor`, `chi2_dielectric`,
//! `chi2_diffuse_transmission`, `smooth_dielectric_fresnel`, `bsdf_reciprocity`).

mod common;

use mislab::render::scene_data::SceneData;
use mislab::render::settings::{Mode, Settings, Strategy};
use mislab::scene::{self, Environment, LoadOptions, MaterialKind};

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

/// Mean (red) of a 4×4 block of pixels around the centre of the sphere at x = cx (camera at z = 9, vfov 20°),
/// and the standard error of that mean from the pixels' sample variances.
fn sphere_mean(film: &mislab::render::film::Film, w: u32, h: u32, cx: f32) -> (f64, f64) {
    let px = (w as f32 * 0.5 + cx / (9.0 * 10f32.to_radians().tan()) * h as f32 * 0.5) as i32;
    let (mut sum, mut var, mut n) = (0.0, 0.0, 0.0);
    for y in (h as i32 / 2 - 2)..(h as i32 / 2 + 2) {
        for x in (px - 2)..(px + 2) {
            let i = (y as u32 * w + x as u32) as usize;
            sum += film.mean[i][0] as f64;
            var += film.variance_of_mean(i).map_or(0.0, |v| v[0]);
            n += 1.0;
        }
    }
    (sum / n, var.sqrt() / n)
}

/// Closed non-absorbing objects in a white furnace (radiance 1 everywhere): smooth glass, a thin slab, nearly
/// smooth GGX glass, and a diffusely transmitting sphere with R + T = 1. Paths in and out of a sphere see 1/η² on
/// the way in and η² on the way out. (Lossless neighbours may exchange light: the furnace stays 1.)
const GLASS_FURNACE: &str = r#"
[camera]
position = [0, 0, 9]
look_at = [0, 0, 0]
vfov = 20

[materials.glass]
type = "dielectric"
eta = 1.5

[materials.thin]
type = "dielectric"
eta = 1.5
thin = true

[materials.nearly_smooth]
type = "dielectric"
eta = 1.5
alpha = 0.01

[materials.leaf]
type = "diffuse-transmission"
reflectance = 0.4
transmittance = 0.6

[[sphere]]
center = [-2.2, 0, 0]
radius = 0.5
material = "glass"

[[sphere]]
center = [-1.1, 0, 0]
radius = 0.5
material = "thin"

[[sphere]]
center = [0, 0, 0]
radius = 0.5
material = "nearly_smooth"

[[sphere]]
center = [1.1, 0, 0]
radius = 0.5
material = "leaf"

[environment]
constant = 1
"#;

/// Rough glass alone (a lossy neighbour would darken the others).
const ROUGH_FURNACE: &str = r#"
[camera]
position = [0, 0, 9]
look_at = [0, 0, 0]
vfov = 20

[materials.rough]
type = "dielectric"
eta = 1.5
alpha_u = 0.3
alpha_v = 0.3

[[sphere]]
center = [0, 0, 0]
radius = 0.5
material = "rough"

[environment]
constant = 1
"#;

/// Rough Beckmann glass alone (Mitsuba's roughdielectric default distribution).
const BECKMANN_FURNACE: &str = r#"
[camera]
position = [0, 0, 9]
look_at = [0, 0, 0]
vfov = 20

[materials.rough]
type = "dielectric"
eta = 1.5
alpha = 0.3
distribution = "beckmann"

[[sphere]]
center = [0, 0, 0]
radius = 0.5
material = "rough"

[environment]
constant = 1
"#;

#[test]
fn dielectric_white_furnace() {
    let ctx = common::gpu();
    let s = load(GLASS_FURNACE, "furnace-glass.toml");
    let rough_scene = load(ROUGH_FURNACE, "furnace-rough-glass.toml");
    let beckmann_scene = load(BECKMANN_FURNACE, "furnace-beckmann-glass.toml");
    let (w, h) = (128u32, 32u32);
    let mut rough = vec![];
    let mut beckmann = vec![];
    for strategy in [Strategy::Bsdf, Strategy::Mis] {
        // No Russian roulette (its weights are exact but noisy) and paths long enough that internal reflections
        // always leave: then every smooth-glass, thin and diffuse-transmission sample is 1 up to rounding.
        let settings = Settings { max_depth: 64, rr_depth: 64, strategy, mode: Mode::Path, ..common::small(w, h) };
        let film = common::render(&ctx, &s, &settings, 32);
        let film_rough = common::render(&ctx, &rough_scene, &settings, 32);
        let film_beckmann = common::render(&ctx, &beckmann_scene, &settings, 32);
        let bad: u32 = film.nonfinite.iter().chain(&film_rough.nonfinite).chain(&film_beckmann.nonfinite).sum();
        assert_eq!(bad, 0, "NaN/Inf samples");
        let mut m: Vec<(f64, f64)> = [-2.2f32, -1.1, 0.0, 1.1].iter().map(|&cx| sphere_mean(&film, w, h, cx)).collect();
        m.push(sphere_mean(&film_rough, w, h, 0.0));
        m.push(sphere_mean(&film_beckmann, w, h, 0.0));
        eprintln!(
            "{strategy:?}: (mean, standard error) smooth, thin, α 0.01, diffuse transmission, α 0.3, Beckmann α 0.3: {m:?}"
        );
        // With BSDF sampling every sample of the lossless objects is 1 up to rounding (σ = 0); MIS adds light
        // samples of the environment (unbiased, not constant): 5σ.
        for (name, (v, se)) in [("smooth glass", m[0]), ("thin glass", m[1]), ("diffuse transmission", m[3])] {
            assert!(
                (v - 1.0).abs() < 1e-3 + 5.0 * se,
                "{strategy:?}: {name} in a white furnace gives {v} ± {se}, not 1"
            );
        }
        // GGX single scattering only loses energy (to the light that would scatter again between microfacets):
        // little at α = 0.01, more at 0.3 — never a gain.
        let ((a1, se1), (a3, se3)) = (m[2], m[4]);
        assert!(a1 > 0.98 && a1 < 1.0 + 1e-3 + 5.0 * se1, "{strategy:?}: α = 0.01 glass gives {a1} ± {se1}");
        assert!(a3 > 0.7 && a3 < 1.0, "{strategy:?}: α = 0.3 glass gives {a3} ± {se3}");
        // Beckmann's single scattering loses energy too (its separable G masks more than the height-correlated one).
        let (b3, sb3) = m[5];
        assert!(b3 > 0.7 && b3 < 1.0, "{strategy:?}: Beckmann α = 0.3 glass gives {b3} ± {sb3}");
        rough.push(m[4]);
        beckmann.push(m[5]);
    }
    let ((b, sb), (l, sl)) = (beckmann[0], beckmann[1]);
    assert!(
        (b - l).abs() < 5.0 * (sb * sb + sl * sl).sqrt() + 1e-3,
        "Beckmann glass: BSDF {b} ± {sb} vs MIS {l} ± {sl}"
    );
    // BSDF sampling alone and MIS with light sampling (which uses eval and pdf) estimate the same rough sphere.
    let ((b, sb), (l, sl)) = (rough[0], rough[1]);
    assert!((b - l).abs() < 5.0 * (sb * sb + sl * sl).sqrt() + 1e-3, "rough glass: BSDF {b} ± {sb} vs MIS {l} ± {sl}");
}

/// Glass, a mirror and diffuse transmission, with a lamp seen only through a glass sphere and one seen only in the
/// mirror: MIS, BSDF and light sampling render without NaN/Inf; light sampling warns that it cannot reach them, and misses the
/// lamp behind the glass that MIS finds.
const GLASS_SCENE: &str = r#"
[camera]
position = [0, 1.2, 6]
look_at = [0, 0.6, 0]
vfov = 35

[materials.floor]
type = "lambert"
reflectance = 0.7

[materials.glass]
type = "dielectric"
eta = 1.5

[materials.rough_glass]
type = "dielectric"
eta = 1.5
alpha = 0.2

[materials.leaf]
type = "diffuse-transmission"
reflectance = [0.2, 0.45, 0.1]
transmittance = [0.25, 0.5, 0.1]

[materials.mirror]
type = "conductor"
eta = [0.2, 0.9, 1.1]
k = [3.9, 2.45, 2.14]
alpha = 0

[materials.lamp]
type = "emitter"
emission = [12, 10, 8]

[materials.backlamp]
type = "emitter"
emission = [30, 40, 60]

[[rectangle]]
center = [0, 0, 0]
normal = [0, 1, 0]
size = 20
material = "floor"

[[sphere]]
center = [-1.65, 0.5, 0]
radius = 0.5
material = "glass"

[[sphere]]
center = [-0.55, 0.5, 0]
radius = 0.5
material = "rough_glass"

[[rectangle]]
center = [0.55, 0.5, 0]
normal = [0, 0, 1]
size = 0.9
material = "leaf"

[[sphere]]
center = [1.65, 0.5, 0]
radius = 0.5
material = "mirror"

# On the line from the camera through the glass sphere's centre, behind it.
[[rectangle]]
center = [-1.87, 0.407, -0.8]
normal = [0, 0, 1]
size = 0.3
material = "backlamp"

[[rectangle]]
center = [0, 4, 1]
normal = [0, -1, 0]
size = 1.5
material = "lamp"

[environment]
constant = 0.1
"#;

#[test]
fn glass_scene_renders_and_warns() {
    let ctx = common::gpu();
    let s = load(GLASS_SCENE, "glass-scene.toml");
    let (w, h) = (64u32, 32u32);
    let data = SceneData::build(&s);
    let mut centre = vec![];
    for strategy in [Strategy::Mis, Strategy::Bsdf, Strategy::Light] {
        let settings = Settings { max_depth: 8, strategy, mode: Mode::Path, ..common::small(w, h) };
        let film = common::render(&ctx, &s, &settings, 16);
        let bad: u32 = film.nonfinite.iter().sum();
        assert_eq!(bad, 0, "{strategy:?}: NaN/Inf samples");
        let warning = mislab::render::reachability::unreachable_light_warning(&data, &settings);
        if strategy == Strategy::Light {
            let w = warning.expect("light sampling must warn about light behind glass");
            assert!(w.contains("--strategy light") && w.contains("glass"), "{w}");
        } else {
            assert!(warning.is_none(), "{strategy:?}: {warning:?}");
        }
        // The glass sphere's centre (the lamp behind it): the mean of a 3×3 block.
        let (cx, cy) = (w as f32 * (0.5 - 1.65 / (6.0 * 17.5f32.to_radians().tan() * 2.0 * 2.0)), 0.5 * h as f32);
        let mut sum = 0.0;
        for y in cy as u32 - 1..=cy as u32 + 1 {
            for x in cx as u32 - 1..=cx as u32 + 1 {
                sum += film.mean[(y * w + x) as usize][2] as f64 / 9.0;
            }
        }
        centre.push(sum);
    }
    eprintln!("glass sphere centre (blue), MIS / BSDF / light: {centre:?}");
    // The lamp behind the glass is reached by BSDF sampling (MIS, BSDF), not by light sampling.
    assert!(centre[0] > 2.0 * centre[2] && centre[1] > 2.0 * centre[2], "{centre:?}");
}

#[test]
fn toml_dielectric_syntax() {
    let s = load(GLASS_FURNACE, "furnace-glass-syntax.toml");
    let get = |n: &str| s.materials.iter().find(|m| m.name == n).map(|m| m.kind.clone()).expect(n);
    assert_eq!(
        get("glass"),
        MaterialKind::Dielectric {
            eta: 1.5,
            alpha_u: 0.0,
            alpha_v: 0.0,
            tint: glam::Vec3::ONE,
            thin: false,
            beckmann: false
        }
    );
    assert!(matches!(get("thin"), MaterialKind::Dielectric { thin: true, .. }));
    assert!(matches!(get("nearly_smooth"), MaterialKind::Dielectric { alpha_u, .. } if alpha_u == 0.01));
    let rough = load(ROUGH_FURNACE, "furnace-rough-syntax.toml");
    assert!(matches!(rough.materials[0].kind,
        MaterialKind::Dielectric { alpha_u, alpha_v, .. } if alpha_u == 0.3 && alpha_v == 0.3));
    assert!(matches!(
        get("leaf"),
        MaterialKind::DiffuseTransmission { reflectance, transmittance, .. }
            if reflectance == glam::Vec3::splat(0.4) && transmittance == glam::Vec3::splat(0.6)
    ));
    for (body, msg) in [
        ("type = \"dielectric\"\neta = [1.5, 1.6, 1.7]\n", "one positive number"),
        ("type = \"dielectric\"\nthin = true\nalpha = 0.1\n", "thin dielectric is smooth"),
        ("type = \"dielectric\"\nk = 1\n", "does not take 'k'"),
        ("type = \"diffuse-transmission\"\ntransmittance = -1\n", "transmittance must be finite"),
    ] {
        let path = std::path::Path::new(env!("CARGO_TARGET_TMPDIR")).join("bad-dielectric.toml");
        std::fs::write(&path, format!("[materials.m]\n{body}")).unwrap();
        let err = scene::load(path.to_str().unwrap(), &LoadOptions::default()).expect_err("must fail").to_string();
        assert!(err.contains("bad-dielectric.toml") && err.contains(msg), "{err}");
    }
}
