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

/// The "white-furnace shortfall" (a white Lambert sphere read 0.99886 ± 0.00018 in the coated-diffuse test's
/// three-sphere furnace) is direct mode, not lost paths: `--mode direct` (the default `Settings`) counts light after
/// one bounce, so a BSDF ray from one sphere that hits a neighbour adds that neighbour's emission, 0. The loss is
/// the cosine-weighted fraction of directions that see a neighbour, which this test computes on the CPU (f64,
/// stratified) for the pixels inside the middle sphere: direct mode must equal 1 − that fraction within 4σ, and
/// path mode (the neighbours' own reflection counted) must be 1.
#[test]
fn furnace_shortfall_is_direct_modes_missing_bounce() {
    let ctx = gpu();
    let path = std::path::Path::new(env!("CARGO_TARGET_TMPDIR")).join("furnace-neighbours.toml");
    let (gap, dist, vfov) = (1.05f64, 6.0f64, 12.0f64);
    let mut text = format!("[camera]\nposition = [0, 0, {dist}]\nlook_at = [0, 0, 0]\nvfov = {vfov}\n");
    text += "[materials.w]\ntype = \"lambert\"\nreflectance = 1\n[environment]\nconstant = 1\n";
    for x in [-gap, 0.0, gap] {
        text += &format!("[[sphere]]\ncenter = [{x}, 0, 0]\nradius = 0.5\nmaterial = \"w\"\n");
    }
    std::fs::write(&path, text).unwrap();
    let scene = scene(path.to_str().unwrap());
    let n = 24u32;
    let tan_half = (vfov / 2.0).to_radians().tan();
    // The camera ray through film point (fx, fy) ∈ [0, n]² (box-filter jitter, as camera_direction does).
    let ray = |fx: f64, fy: f64| {
        let d = [(2.0 * fx / n as f64 - 1.0) * tan_half, (1.0 - 2.0 * fy / n as f64) * tan_half, -1.0];
        let l = (d[0] * d[0] + d[1] * d[1] + 1.0).sqrt();
        [d[0] / l, d[1] / l, d[2] / l]
    };
    // The nearest positive hit of a ray o + t·d (unit d) with the sphere of radius 0.5 at (cx, 0, 0).
    let hit = |o: [f64; 3], d: [f64; 3], cx: f64| -> Option<f64> {
        let f = [o[0] - cx, o[1], o[2]];
        let b = f[0] * d[0] + f[1] * d[1] + f[2] * d[2];
        let disc = b * b - (f[0] * f[0] + f[1] * f[1] + f[2] * f[2] - 0.25);
        let t = -b - disc.max(0.0).sqrt();
        (disc >= 0.0 && t > 1e-9).then_some(t)
    };
    // Pixels whose whole footprint lies on the middle sphere (all four corners hit it).
    let inside = |x: u32, y: u32| {
        [(0.0, 0.0), (1.0, 0.0), (0.0, 1.0), (1.0, 1.0)]
            .iter()
            .all(|(a, b)| hit([0.0, 0.0, dist], ray(x as f64 + a, y as f64 + b), 0.0).is_some())
    };
    let pixels: Vec<(u32, u32)> =
        (0..n).flat_map(|y| (0..n).map(move |x| (x, y))).filter(|&(x, y)| inside(x, y)).collect();
    assert!(pixels.len() > 200, "{} pixels", pixels.len());

    // CPU: the fraction of cosine-weighted directions from each shaded point that hit a neighbour (4 jittered
    // points per pixel, 48² stratified directions each), averaged over the pixels.
    let m = 48usize;
    let mut lost = 0.0;
    for &(x, y) in &pixels {
        for (jx, jy) in [(0.25, 0.25), (0.75, 0.25), (0.25, 0.75), (0.75, 0.75)] {
            let d = ray(x as f64 + jx, y as f64 + jy);
            let t = hit([0.0, 0.0, dist], d, 0.0).expect("inside");
            let p = [t * d[0], t * d[1], dist + t * d[2]];
            let nrm = [p[0] * 2.0, p[1] * 2.0, p[2] * 2.0];
            let a = if nrm[0].abs() > 0.9 { [0.0, 1.0, 0.0] } else { [1.0, 0.0, 0.0] };
            let cross = |u: [f64; 3], v: [f64; 3]| {
                [u[1] * v[2] - u[2] * v[1], u[2] * v[0] - u[0] * v[2], u[0] * v[1] - u[1] * v[0]]
            };
            let t1 = cross(nrm, a);
            let l1 = (t1[0] * t1[0] + t1[1] * t1[1] + t1[2] * t1[2]).sqrt();
            let t1 = [t1[0] / l1, t1[1] / l1, t1[2] / l1];
            let t2 = cross(nrm, t1);
            let mut seen = 0usize;
            for i in 0..m {
                for j in 0..m {
                    let (u1, u2) = ((i as f64 + 0.5) / m as f64, (j as f64 + 0.5) / m as f64);
                    let (r, phi) = (u1.sqrt(), 2.0 * std::f64::consts::PI * u2);
                    let (lx, ly, lz) = (r * phi.cos(), r * phi.sin(), (1.0 - u1).sqrt());
                    let w: Vec<f64> = (0..3).map(|k| lx * t1[k] + ly * t2[k] + lz * nrm[k]).collect();
                    let w = [w[0], w[1], w[2]];
                    seen += (hit(p, w, -gap).is_some() || hit(p, w, gap).is_some()) as usize;
                }
            }
            lost += seen as f64 / (m * m) as f64 / (4 * pixels.len()) as f64;
        }
    }

    let block = |film: &mislab::render::film::Film| {
        let (mut mean, mut var) = (0.0, 0.0);
        let k = pixels.len() as f64;
        for &(x, y) in &pixels {
            let i = (y * n + x) as usize;
            let c = film.count[i] as f64;
            mean += film.mean[i][1] as f64 / k;
            var += film.m2[i][1] as f64 / (c - 1.0) / c / (k * k);
        }
        (mean, var.sqrt())
    };
    let direct = render(&ctx, &scene, &Settings { mode: Mode::Direct, strategy: Strategy::Bsdf, ..small(n, n) }, 64);
    let (d, sd) = block(&direct);
    let path_film = render(
        &ctx,
        &scene,
        &Settings { mode: Mode::Path, strategy: Strategy::Bsdf, max_depth: 16, ..small(n, n) },
        16,
    );
    let (p, sp) = block(&path_film);
    eprintln!("{} pixels: direct {d:.6} ± {sd:.6}, CPU 1 − {lost:.6}; path {p:.6} ± {sp:.6}", pixels.len());
    assert_eq!(direct.nonfinite_total + path_film.nonfinite_total, 0);
    assert!(lost > 10.0 * sd, "the neighbours hide {lost}: too little to resolve at ± {sd}");
    assert!((d - (1.0 - lost)).abs() < 4.0 * sd + 2e-4, "direct {d} ± {sd} vs 1 − {lost} (CPU)");
    assert!((p - 1.0).abs() < 4.0 * sp + 1e-6, "path {p} ± {sp}: light is lost");
}

/// Also the device's pipeline memo (`GpuContext::pipelines`): renderers of one scene and settings share one build,
/// the seed is not compiled in, and another baked scene gets its own pipeline (its primitives are in the source).
#[test]
fn same_seed_same_bits_other_seed_other_bits() {
    // A context of its own, so that no other test's pipelines are counted.
    let ctx = mislab::gpu::GpuContext::new().expect("a Vulkan adapter");
    let scene = scene("veach-mis");
    let s = small(48, 48);
    let a = render(&ctx, &scene, &s, 8);
    assert_eq!(ctx.pipelines.len(), 1);
    let b = render(&ctx, &scene, &s, 8);
    assert_eq!(ctx.pipelines.len(), 1, "a second renderer of the same pipeline must not build it again");
    let bits = |f: &mislab::render::film::Film| f.mean.iter().flat_map(|c| c.map(f32::to_bits)).collect::<Vec<_>>();
    assert_eq!(bits(&a), bits(&b), "the same seed and settings must give the same image bit for bit");
    let c = render(&ctx, &scene, &Settings { seed: 7, ..s.clone() }, 8);
    assert_ne!(bits(&a), bits(&c), "a different seed must change the image");
    assert_eq!(ctx.pipelines.len(), 1, "the seed is a run-time parameter");
    let mut moved = scene.clone();
    moved.spheres[0].radius *= 1.5;
    let d = render(&ctx, &moved, &s, 8);
    assert_eq!(ctx.pipelines.len(), 2, "another baked scene needs its own pipeline");
    assert_ne!(bits(&a), bits(&d), "a pipeline of the other scene was reused");
}

#[test]
fn sample_counts_and_variance_are_consistent() {
    let ctx = gpu();
    let scene = scene("cornell-box");
    // 9 tile rows, the last one partial: workgroup rows take tile rows in a spread order (render::tile_order),
    // and every pixel must still be rendered exactly once per sample.
    let film = render(&ctx, &scene, &Settings { mode: Mode::Path, ..small(20, 70) }, 20);
    assert_eq!(film.spp(), 20);
    let missed: Vec<usize> = (0..film.count.len()).filter(|&i| film.count[i] != 20).collect();
    assert!(missed.is_empty(), "{} pixels without 20 samples, the first {:?}", missed.len(), missed.first());
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
