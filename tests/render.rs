//! Whole-render tests on the device: the furnace renders 1, renders are bit-for-bit repeatable, and
//! the accumulation statistics are what the shader claims.

mod common;
use common::*;
use mislab::render::settings::*;

/// Furnace: a sphere of albedo 1 under a constant white sky reflects exactly 1 in every direction, so
/// every pixel's expected value is 1 — in direct mode (one bounce, nothing occludes a convex sphere)
/// and in path mode. Checked by the image mean within 3σ and per-pixel z-tests (Šidák over pixels).
fn furnace_is_one(mode: Mode, strategy: Strategy) {
    let ctx = gpu();
    let scene = scene("furnace");
    let settings = Settings { mode, strategy, max_depth: 16, ..small(32, 32) };
    let film = render(&ctx, &scene, &settings, 256);
    assert_eq!(film.nonfinite_total, 0, "NaN/Inf samples in the furnace");
    let n = film.mean.len();
    let z_max = sidak_z(0.01, n * 3);
    let (mut sum, mut var_sum) = (0.0, 0.0);
    for i in 0..n {
        let var = film.variance_of_mean(i).expect("≥ 2 samples");
        for c in 0..3 {
            let x = film.mean[i][c] as f64;
            sum += x;
            var_sum += var[c];
            // A zero-variance pixel must be exactly right (up to f32 rounding of the mean).
            let sd = var[c].sqrt().max(1e-6);
            let z = (x - 1.0) / sd;
            assert!(
                z.abs() < z_max,
                "{mode:?}/{strategy:?}: pixel {i} channel {c} = {x} (z = {z:.2}, limit {z_max:.2})"
            );
        }
    }
    let mean = sum / (3 * n) as f64;
    let sigma = var_sum.sqrt() / (3 * n) as f64;
    assert!(
        (mean - 1.0).abs() < 3.0 * sigma.max(1e-6),
        "{mode:?}/{strategy:?}: image mean {mean} vs 1 (σ = {sigma:e})"
    );
}

#[test]
fn furnace_direct_every_strategy() {
    for s in Strategy::ALL {
        furnace_is_one(Mode::Direct, *s);
    }
}

#[test]
fn furnace_path() {
    furnace_is_one(Mode::Path, Strategy::Mis);
    furnace_is_one(Mode::Path, Strategy::Bsdf);
}

#[test]
fn same_seed_same_bits_other_seed_other_bits() {
    let ctx = gpu();
    let scene = scene("veach-mis");
    let s = small(48, 48);
    let a = render(&ctx, &scene, &s, 8);
    let b = render(&ctx, &scene, &s, 8);
    let bits = |f: &mislab::render::film::Film| f.mean.iter().flat_map(|c| c.map(f32::to_bits)).collect::<Vec<_>>();
    assert_eq!(bits(&a), bits(&b), "the same seed and settings must give the same image bit for bit");
    let c = render(&ctx, &scene, &Settings { seed: 7, ..s }, 8);
    assert_ne!(bits(&a), bits(&c), "a different seed must change the image");
}

#[test]
fn sample_counts_and_variance_are_consistent() {
    let ctx = gpu();
    let scene = scene("cornell-box");
    let film = render(&ctx, &scene, &Settings { mode: Mode::Path, ..small(16, 16) }, 20);
    assert_eq!(film.spp(), 20);
    assert!(film.count.iter().all(|&c| c == 20), "every pixel must hold 20 samples");
    assert!(film.m2.iter().flatten().all(|&m| m >= 0.0 && m.is_finite()));
}

/// The device counts non-finite samples (by their bits: `x != x` misses NaN on lavapipe) and leaves them
/// out of the mean. A light of radiance 3e38 overflows f32 in the estimator, so some
/// samples are +Inf: they must be counted, per pixel and in total, and the image must stay finite.
#[test]
fn nonfinite_samples_are_counted_and_excluded() {
    let ctx = gpu();
    let mut scene = scene("furnace");
    scene.environment = mislab::scene::Environment::None;
    scene.materials.push(mislab::scene::Material::emitter("huge", glam::Vec3::splat(3.0e38)));
    let m = (scene.materials.len() - 1) as u32;
    scene.spheres.push(mislab::scene::Sphere { center: glam::Vec3::new(0.0, 3.0, 0.0), radius: 1.0, material: m });
    let film = render(&ctx, &scene, &Settings { strategy: Strategy::Uniform, ..small(16, 16) }, 4);
    assert!(film.nonfinite_total > 0, "overflowing samples must be counted");
    let per_pixel: u64 = film.nonfinite.iter().map(|&n| n as u64).sum();
    assert_eq!(per_pixel, film.nonfinite_total, "per-pixel and total counters must agree");
    assert!(film.mean.iter().flatten().all(|v| v.is_finite()), "non-finite samples must not reach the mean");
    for i in 0..film.count.len() {
        assert_eq!(film.count[i] + film.nonfinite[i], 4, "every sample is either accumulated or counted");
    }
}

/// A pipeline specialised to the scene and settings computes the same estimate as the generic one that
/// reads everything at run time: same seed → equal images up to float rounding (the compiler may
/// reassociate differently once branches fold away).
#[test]
fn specialised_and_generic_pipelines_agree() {
    let ctx = gpu();
    for (name, mode) in [("veach-mis", Mode::Direct), ("cornell-box", Mode::Path)] {
        let scene = scene(name);
        // Russian roulette from depth 2, so the 4-vertex paths take it: baked and BVH pipelines share one path loop
        // (shaders/integrator.wgsl) and one roulette rule, so they agree sample by sample with it too.
        let settings = Settings { mode, max_depth: 4, rr_depth: 2, ..small(24, 24) };
        let gs =
            mislab::render::gpu_scene::GpuScene::upload(&ctx, mislab::render::scene_data::SceneData::build(&scene))
                .unwrap();
        let mut r = mislab::render::Renderer::new(&ctx, &gs, scene.camera.clone(), settings.clone()).unwrap();
        r.render(&ctx, 4).unwrap();
        let special = r.film(&ctx).unwrap();
        r.reset();
        r.set_specialize(false).unwrap();
        r.render(&ctx, 4).unwrap();
        let generic = r.film(&ctx).unwrap();
        let mut worst = 0.0f32;
        for (a, b) in special.mean.iter().zip(&generic.mean) {
            for c in 0..3 {
                let rel = (a[c] - b[c]).abs() / (a[c].abs().max(b[c].abs()).max(1e-3));
                worst = worst.max(rel);
            }
        }
        assert!(worst < 1e-4, "{name}: specialised and generic images differ by {worst} (relative)");
    }
}

/// Every requested sample reaches the film even when one call asks for many (lavapipe silently stops
/// a shader's loops after 65535 iterations per invocation, so large dispatches used to drop samples).
#[test]
fn large_requests_keep_every_sample() {
    let ctx = gpu();
    let scene = scene("cornell-box");
    let gs = mislab::render::gpu_scene::GpuScene::upload(&ctx, mislab::render::scene_data::SceneData::build(&scene))
        .unwrap();
    let mut r =
        mislab::render::Renderer::new(&ctx, &gs, scene.camera.clone(), Settings { mode: Mode::Path, ..small(8, 8) })
            .unwrap();
    r.render(&ctx, 512).unwrap();
    let film = r.film(&ctx).unwrap();
    assert!(
        film.count.iter().zip(&film.nonfinite).all(|(c, b)| c + b == 512),
        "samples were dropped: {:?}",
        &film.count[..4]
    );
}
