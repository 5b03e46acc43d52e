//! The sample sequences: tables and spp rules on the CPU; on the device (probe kernels running the WGSL
//! samplers themselves) agreement with the CPU twins, chi-square uniformity of the 2D projections of the first
//! dimensions, unbiasedness over seeds at a non-power-of-two prefix, (0,m,2)-net structure of Sobol prefixes,
//! and measured RMSE convergence slopes on smooth analytic pixel integrands; and one render per sampler.

mod common;
mod scratch;
use common::*;
use mislab::render::samplers::{self, *};
use mislab::render::settings::{SamplerKind, Settings};
use mislab::render::shaders;
use mislab::testkit::chi2;
use mislab::testkit::metrics::loglog_slope;
use mislab::testkit::probe::{Probe, ProbeJob};
use scratch::Scratch;

// ---------------------------------------------------------------------------------------------------------------
// CPU: tables, constants, spp rules.

#[test]
fn wgsl_constants_match_rust() {
    let module = shaders::validate(&shaders::compose(mislab::render::RENDER_FILES, "")).expect("render module");
    let value = |name: &str| -> u32 {
        let (_, c) = module
            .constants
            .iter()
            .find(|(_, c)| c.name.as_deref() == Some(name))
            .unwrap_or_else(|| panic!("no WGSL const {name}"));
        match module.global_expressions[c.init] {
            naga::Expression::Literal(naga::Literal::U32(v)) => v,
            ref e => panic!("{name}: unexpected initializer {e:?}"),
        }
    };
    let pairs: &[(&str, u32)] = &[
        ("DIMS_CAMERA", DIMS_CAMERA),
        ("DIMS_PER_BOUNCE", DIMS_PER_BOUNCE),
        ("DIMS_USED_PER_BOUNCE", DIMS_USED_PER_BOUNCE),
        ("SOBOL_OFFSET", SOBOL_OFFSET),
        ("SOBOL_TABLE_WORDS", SOBOL_TABLE_WORDS),
        ("HALTON_OFFSET", HALTON_OFFSET),
        ("HALTON_DIMS", HALTON_DIMS),
        ("BLUE_NOISE_OFFSET", BLUE_NOISE_OFFSET),
        ("BLUE_NOISE_LOG2", BLUE_NOISE_LOG2),
        ("BLUE_NOISE_SIZE", BLUE_NOISE_SIZE),
        ("DEFAULT_SAMPLER_SPP", DEFAULT_SAMPLER_SPP),
        ("MAX_SAMPLER_SPP", MAX_SAMPLER_SPP),
        ("NO_HALTON_DIM", NO_HALTON_DIM),
        ("SALT_SOBOL", SALT_SOBOL),
        ("SALT_BLUE_NOISE", SALT_BLUE_NOISE),
        ("SALT_BLUE_OFFSET", SALT_BLUE_OFFSET),
        ("SALT_HALTON", SALT_HALTON),
        ("SALT_HAMMERSLEY", SALT_HAMMERSLEY),
        ("SALT_STRATIFIED", SALT_STRATIFIED),
        ("SALT_STRATIFIED_2D", SALT_STRATIFIED_2D),
    ];
    for (name, v) in pairs {
        assert_eq!(value(name), *v, "WGSL {name} differs from src/render/samplers.rs");
    }
    assert_eq!(sampler_data().len() as u32, SAMPLER_DATA_WORDS);
    // The 2D pairs of a vertex must fall inside one block of four (the padded Sobol sampler shuffles per block).
    for d in [value("DIM_LIGHT_UV"), value("DIM_BSDF_UV")] {
        assert_eq!((DIMS_CAMERA + d) / 4, (DIMS_CAMERA + d + 1) / 4, "2D pair at +{d} straddles two blocks");
    }
    assert_eq!(DIMS_PER_BOUNCE % 4, 0);
}

#[test]
fn sobol_matrices_have_optimal_2d_projections() {
    let m: Vec<[u32; 32]> = (0..SOBOL_DIMS).map(samplers::sobol_matrix).collect();
    // Dimensions 0 and 1 form a (0,2)-sequence: every prefix of 2^k points is a (0,k,2)-net.
    for k in 1..=20 {
        assert_eq!(t_value_2d(&m[0], &m[1], k), 0, "(0,1) at m = {k}");
    }
    // Every 2D projection among the four dimensions stays within t ≤ 2 for every power-of-two prefix up to 2^16
    // (Joe & Kuo chose the initial numbers to keep the t-values of 2D projections small).
    for a in 0..SOBOL_DIMS as usize {
        for b in a + 1..SOBOL_DIMS as usize {
            let ts: Vec<u32> = (1..=16).map(|k| t_value_2d(&m[a], &m[b], k)).collect();
            println!("t-values of Sobol dims ({a}, {b}) for m = 1…16: {ts:?}");
            assert!(ts.iter().all(|&t| t <= 2), "dims ({a}, {b}): t-values {ts:?}");
        }
    }
    for d in 0..SOBOL_DIMS {
        for i in [0u32, 1, 6, 1000, 0x8000_0001, u32::MAX] {
            assert_eq!(sobol_bits(i, d, sampler_data()), sobol_bits_matrix(i, &m[d as usize]), "dim {d} index {i}");
        }
    }
    println!(
        "Sobol t-values at m = 10: (0,2) {}, (1,2) {}, (0,3) {}, (1,3) {}, (2,3) {}",
        t_value_2d(&m[0], &m[2], 10),
        t_value_2d(&m[1], &m[2], 10),
        t_value_2d(&m[0], &m[3], 10),
        t_value_2d(&m[1], &m[3], 10),
        t_value_2d(&m[2], &m[3], 10)
    );
}

#[test]
fn permutations_are_bijections() {
    for n in [1u32, 2, 3, 5, 7, 16, 100, 257] {
        for seed in [0u32, 1, 0xdead_beef] {
            let mut seen = vec![false; n as usize];
            for i in 0..n {
                let j = permute_index(i, n, seed) as usize;
                assert!(j < n as usize && !seen[j], "n = {n}, seed = {seed}: not a permutation");
                seen[j] = true;
            }
        }
    }
}

#[test]
fn blue_noise_mask_is_a_blue_permutation() {
    let mask = blue_noise_mask();
    let n = (BLUE_NOISE_SIZE * BLUE_NOISE_SIZE) as usize;
    let mut seen = vec![false; n];
    for &r in mask {
        assert!(!seen[r as usize], "rank {r} twice");
        seen[r as usize] = true;
    }
    // Power at low frequencies (radius ≤ size/8, DC excluded) relative to white noise's expectation: blue noise
    // has almost none there. White noise of variance σ² has expected power n·σ² at every frequency.
    let s = BLUE_NOISE_SIZE as usize;
    let mean = (n as f64 - 1.0) / 2.0;
    let var = (n as f64 * n as f64 - 1.0) / 12.0;
    let (mut low, mut count) = (0.0, 0);
    for fy in 0..s {
        for fx in 0..s {
            let (kx, ky) = (fx.min(s - fx) as f64, fy.min(s - fy) as f64);
            let r = (kx * kx + ky * ky).sqrt();
            if r == 0.0 || r > s as f64 / 8.0 {
                continue;
            }
            let (mut re, mut im) = (0.0, 0.0);
            for y in 0..s {
                for x in 0..s {
                    let a = -2.0 * std::f64::consts::PI * (fx * x + fy * y) as f64 / s as f64;
                    let v = mask[y * s + x] as f64 - mean;
                    re += v * a.cos();
                    im += v * a.sin();
                }
            }
            low += (re * re + im * im) / (n as f64 * var);
            count += 1;
        }
    }
    let ratio = low / count as f64;
    println!("blue-noise mask: low-frequency power {ratio:.4} of white noise's");
    assert!(ratio < 0.05, "low-frequency power {ratio} of white noise's: not blue");
}

#[test]
fn spp_rules() {
    for k in SamplerKind::ALL {
        assert!(check_spp(*k, 0).is_err());
    }
    assert_eq!(check_spp(SamplerKind::Sobol, 7), Ok(7));
    assert_eq!(check_spp(SamplerKind::Hammersley, 7), Ok(7));
    assert!(check_spp(SamplerKind::Hammersley, MAX_SAMPLER_SPP + 1).is_err());
    for n in [1u32, 2, 4, 8, 16, 32, 64, 128, 256, 512, 1024, 9, 6, 12] {
        assert_eq!(check_spp(SamplerKind::Stratified, n), Ok(n), "{n} forms a grid");
    }
    assert_eq!(check_spp(SamplerKind::Stratified, 7), Ok(8));
    assert_eq!(check_spp(SamplerKind::Stratified, 5), Ok(6));
    assert_eq!(check_spp(SamplerKind::Stratified, 11), Ok(12));
    assert_eq!(stratified_grid(32), (8, 4));
    assert!(spp_message(SamplerKind::Stratified, 7, 8).contains("4 × 2"));
    assert!(spp_message(SamplerKind::Stratified, 8, 8).is_empty());
}

// ---------------------------------------------------------------------------------------------------------------
// The device: probe kernels over the WGSL samplers.

/// Dimensions read with sample_1d by the point probe: the camera block and the first vertex's block.
const DIMS_1D: u32 = 16;
/// sample_2d pairs read by the point probe: camera, first light sample, first BSDF sample.
const PAIRS_2D: [u32; 3] = [0, DIMS_CAMERA + 1, DIMS_CAMERA + 5];
const PER_POINT: usize = DIMS_1D as usize + 2 * PAIRS_2D.len();

/// Probe configuration, one u32 array: [seed, sampler_spp, width, samples, pixels, first pixel, kernel-specific].
fn probe_source(kernel: &str) -> String {
    let decls = "
@group(1) @binding(0) var<storage, read_write> probe_out: array<f32>;
@group(1) @binding(1) var<storage, read> probe_cfg: array<u32>;
@group(1) @binding(2) var<storage, read> sampler_data: array<u32>;
var<private> params: FrameParams;
fn probe_setup() {
    params.seed = probe_cfg[0];
    params.sampler_spp = probe_cfg[1];
    params.width = probe_cfg[2];
    params.height = probe_cfg[2];
}
";
    let mut s = shaders::compose(&["common.wgsl"], decls);
    s += &shaders::compose(&["specialize.wgsl", "rng.wgsl", "samplers.wgsl"], kernel);
    s
}

const POINTS_KERNEL: &str = "
@compute @workgroup_size(64)
fn probe_points(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) nwg: vec3<u32>) {
    probe_setup();
    let t = gid.x + gid.y * nwg.x * 64u;
    let samples = probe_cfg[3];
    if (t >= samples * probe_cfg[4]) { return; }
    let id = SampleId(probe_cfg[5] + t / samples, t % samples);
    let o = t * 22u;
    for (var d = 0u; d < 16u; d += 1u) { probe_out[o + d] = sample_1d(id, d); }
    let a = sample_2d(id, 0u);
    let b = sample_2d(id, DIMS_CAMERA + 1u);
    let c = sample_2d(id, DIMS_CAMERA + 5u);
    probe_out[o + 16u] = a.x; probe_out[o + 17u] = a.y;
    probe_out[o + 18u] = b.x; probe_out[o + 19u] = b.y;
    probe_out[o + 20u] = c.x; probe_out[o + 21u] = c.y;
}
";

fn workgroups(threads: u32) -> [u32; 3] {
    let g = threads.div_ceil(64);
    [g.min(65535), g.div_ceil(65535), 1]
}

/// Points of `pixels` consecutive pixels from `first_pixel`, `samples` each, on the device.
fn device_points(
    ctx: &mislab::gpu::GpuContext,
    kind: SamplerKind,
    seed: u32,
    spp_target: u32,
    width: u32,
    first_pixel: u32,
    pixels: u32,
    samples: u32,
) -> Vec<f32> {
    let cfg = [seed, spp_target, width, samples, pixels, first_pixel];
    let n = (pixels * samples) as usize;
    let bytes = Probe::new(ctx)
        .run(&ProbeJob {
            source: &probe_source(POINTS_KERNEL),
            entry: "probe_points",
            inputs: &[bytemuck::cast_slice(&cfg), bytemuck::cast_slice(sampler_data())],
            output_bytes: (n * PER_POINT * 4) as u64,
            workgroups: workgroups(n as u32),
            constants: &[("SPEC_SAMPLER", kind.tag() as f64)],
            geometry: None,
        })
        .unwrap_or_else(|e| panic!("{kind}: {e}"));
    bytemuck::pod_collect_to_vec(&bytes)
}

/// The same points from the CPU twins.
fn cpu_points(
    kind: SamplerKind,
    seed: u32,
    spp_target: u32,
    width: u32,
    first_pixel: u32,
    pixels: u32,
    samples: u32,
) -> Vec<f32> {
    let p = SamplerParams { kind, seed, sampler_spp: spp_target, width };
    let mut out = Vec::with_capacity((pixels * samples) as usize * PER_POINT);
    for px in first_pixel..first_pixel + pixels {
        for i in 0..samples {
            for d in 0..DIMS_1D {
                out.push(samplers::sample_1d(&p, px, i, d));
            }
            for d in PAIRS_2D {
                out.extend(samplers::sample_2d(&p, px, i, d));
            }
        }
    }
    out
}

/// Pearson's statistic of a 2D histogram with `bins`² equal cells, and its p-value.
fn chi2_2d(xs: impl Iterator<Item = (f32, f32)>, bins: usize) -> (f64, f64) {
    let mut h = vec![0f64; bins * bins];
    let mut n = 0usize;
    for (x, y) in xs {
        assert!((0.0..1.0).contains(&x) && (0.0..1.0).contains(&y), "sample ({x}, {y}) outside [0,1)²");
        h[(y * bins as f32) as usize * bins + (x * bins as f32) as usize] += 1.0;
        n += 1;
    }
    let e = n as f64 / (bins * bins) as f64;
    let stat: f64 = h.iter().map(|o| (o - e) * (o - e) / e).sum();
    (stat, chi2::chi2_sf(stat, (bins * bins - 1) as f64))
}

/// The device's samples equal the CPU twins' (integer work bit for bit; the final float divisions may round
/// differently on the device, hence 2⁻²⁰), and every 2D projection of the first 12 dimensions, and every
/// sample_2d pair, passes a chi-square test of uniformity — both over many samples of a few pixels and over
/// few samples of many pixels (which also catches pixels that share patterns). Šidák-corrected α = 0.01.
#[test]
fn device_matches_cpu_and_projections_are_uniform() {
    let ctx = gpu();
    // (pixels, samples, target spp, first pixel): few pixels × many samples; many pixels × few samples.
    let layouts = [(16u32, 1024u32, 1024u32, 1000u32), (4096, 4, 4, 0)];
    let pairs: Vec<(usize, usize)> = (0..12).flat_map(|a| (a + 1..12).map(move |b| (a, b))).collect();
    let tests = SamplerKind::ALL.len() * layouts.len() * (pairs.len() + PAIRS_2D.len());
    let alpha = chi2::sidak_alpha(0.01, tests);
    let mut worst = (1.0f64, String::new());
    for kind in SamplerKind::ALL {
        for (pixels, samples, target, first) in layouts {
            let seed = 12345;
            let dev = device_points(&ctx, *kind, seed, target, 64, first, pixels, samples);
            let cpu = cpu_points(*kind, seed, target, 64, first, pixels, samples);
            assert_eq!(dev.len(), cpu.len());
            let mismatches = dev.iter().zip(&cpu).filter(|(a, b)| (**a - **b).abs() > 1.0 / (1 << 20) as f32).count();
            let first_bad = dev.iter().zip(&cpu).position(|(a, b)| (*a - *b).abs() > 1.0 / (1 << 20) as f32);
            assert_eq!(
                mismatches,
                0,
                "{kind}: {mismatches} device values differ from the CPU twin (first at {first_bad:?}: {:?})",
                first_bad.map(|i| (dev[i], cpu[i], i / PER_POINT, i % PER_POINT))
            );
            let point = |t: usize, k: usize| dev[t * PER_POINT + k];
            let n = (pixels * samples) as usize;
            let mut check = |name: String, a: usize, b: usize| {
                let (stat, p) = chi2_2d((0..n).map(|t| (point(t, a), point(t, b))), 16);
                if p < worst.0 {
                    worst = (p, format!("{name}: χ² = {stat:.1}, p = {p:.2e}"));
                }
                assert!(
                    p > alpha,
                    "{kind} ({pixels} px × {samples} spp) {name}: χ² = {stat:.1} (255 dof), p = {p:.2e} < {alpha:.1e}"
                );
            };
            for &(a, b) in &pairs {
                check(format!("dims ({a}, {b})"), a, b);
            }
            for (k, d) in PAIRS_2D.iter().enumerate() {
                check(format!("sample_2d at {d}"), DIMS_1D as usize + 2 * k, DIMS_1D as usize + 2 * k + 1);
            }
        }
    }
    println!("smallest p-value of {tests} projections: {}", worst.1);
}

/// Sobol prefixes of 2^k samples are (0,k,2)-nets in the camera pair and the light-sample pair: every
/// elementary interval of area 2^−k holds exactly one point (checked on the device's samples).
#[test]
fn sobol_prefixes_are_nets_on_the_device() {
    let ctx = gpu();
    let dev = device_points(&ctx, SamplerKind::Sobol, 99, 0, 64, 0, 8, 1024);
    for pixel in 0..8usize {
        for (xk, yk) in [(16usize, 17usize), (18, 19)] {
            for k in [2u32, 4, 7, 10] {
                let n = 1usize << k;
                for a in 0..=k {
                    let mut seen = vec![false; n];
                    for i in 0..n {
                        let t = pixel * 1024 + i;
                        let (x, y) = (dev[t * PER_POINT + xk], dev[t * PER_POINT + yk]);
                        let cx = (x * (1u32 << a) as f32) as usize;
                        let cy = (y * (1u32 << (k - a)) as f32) as usize;
                        let cell = cy * (1 << a) + cx;
                        assert!(!seen[cell], "pixel {pixel}, pair {xk}: the first {n} points are not a (0,{k},2)-net ({a} bits × {} bits)", k - a);
                        seen[cell] = true;
                    }
                }
            }
        }
    }
}

/// Per seed: estimates, from the first 5 samples of one pixel (not a power of two, and below the fixed-count
/// samplers' target of 8), of ∫(x² + y) over the pixel jitter pair, ∫[u + v < 1] over the light-sample pair,
/// and ∫u·w over the light selection and extra dimensions.
const SEEDS_KERNEL: &str = "
@compute @workgroup_size(64)
fn probe_seeds(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) nwg: vec3<u32>) {
    probe_setup();
    let s = gid.x + gid.y * nwg.x * 64u;
    if (s >= probe_cfg[4]) { return; }
    params.seed = probe_cfg[0] + s * 7919u;
    var acc = vec3<f32>(0.0);
    let n = probe_cfg[3];
    for (var i = 0u; i < n; i += 1u) {
        let id = SampleId(probe_cfg[5], i);
        let a = sample_2d(id, 0u);
        let b = sample_2d(id, DIMS_CAMERA + DIM_LIGHT_UV);
        let u = sample_1d(id, DIMS_CAMERA + DIM_LIGHT_SELECT);
        let w = sample_1d(id, DIMS_CAMERA + DIM_LIGHT_EXTRA);
        acc += vec3<f32>(a.x * a.x + a.y, select(0.0, 1.0, b.x + b.y < 1.0), u * w);
    }
    acc /= f32(n);
    probe_out[3u * s] = acc.x; probe_out[3u * s + 1u] = acc.y; probe_out[3u * s + 2u] = acc.z;
}
";

#[test]
fn randomized_sequences_are_unbiased_over_seeds() {
    let ctx = gpu();
    let seeds = 16384u32;
    let exact = [5.0 / 6.0, 0.5, 0.25];
    let z_max = sidak_z(0.01, SamplerKind::ALL.len() * exact.len());
    for kind in SamplerKind::ALL {
        let cfg = [777u32, 8, 64, 5, seeds, 1234];
        let bytes = Probe::new(&ctx)
            .run(&ProbeJob {
                source: &probe_source(SEEDS_KERNEL),
                entry: "probe_seeds",
                inputs: &[bytemuck::cast_slice(&cfg), bytemuck::cast_slice(sampler_data())],
                output_bytes: seeds as u64 * 12,
                workgroups: workgroups(seeds),
                constants: &[("SPEC_SAMPLER", kind.tag() as f64)],
                geometry: None,
            })
            .unwrap_or_else(|e| panic!("{kind}: {e}"));
        let est: Vec<f32> = bytemuck::pod_collect_to_vec(&bytes);
        for (k, truth) in exact.iter().enumerate() {
            let v: Vec<f64> = est.iter().skip(k).step_by(3).map(|&x| x as f64).collect();
            let mean = v.iter().sum::<f64>() / v.len() as f64;
            let var = v.iter().map(|x| (x - mean) * (x - mean)).sum::<f64>() / (v.len() - 1) as f64;
            let se = (var / v.len() as f64).sqrt().max(1e-9);
            let z = (mean - truth) / se;
            println!("{kind:>12} integrand {k}: mean over {seeds} seeds {mean:.6} (exact {truth:.6}, z = {z:+.2})");
            assert!(
                z.abs() < z_max,
                "{kind}: integrand {k} has mean {mean} over seeds, exact {truth} (z = {z:.2}, limit {z_max:.2})"
            );
        }
    }
}

/// Ladder of sample counts for the convergence slopes.
const LADDER: [u32; 9] = [4, 8, 16, 32, 64, 128, 256, 512, 1024];

/// Per pixel and ladder step: the estimate of ∫∫ exp(x·y) from N samples of the camera pair and of the first
/// light-sample pair, with the fixed-count samplers' target set to N.
const SLOPES_KERNEL: &str = "
@compute @workgroup_size(64)
fn probe_slopes(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) nwg: vec3<u32>) {
    probe_setup();
    let t = gid.x + gid.y * nwg.x * 64u;
    let steps = probe_cfg[6];
    if (t >= probe_cfg[4] * steps) { return; }
    // One invocation per (pixel, step): lavapipe stops an invocation's loops after 65535 iterations in all.
    let p = t / steps;
    let l = t % steps;
    let n = probe_cfg[7u + l];
    params.sampler_spp = n;
    var acc = vec2<f32>(0.0);
    for (var i = 0u; i < n; i += 1u) {
        let id = SampleId(probe_cfg[5] + p, i);
        let a = sample_2d(id, 0u);
        let b = sample_2d(id, DIMS_CAMERA + DIM_LIGHT_UV);
        acc += vec2<f32>(exp(a.x * a.y), exp(b.x * b.y));
    }
    acc /= f32(n);
    probe_out[2u * t] = acc.x;
    probe_out[2u * t + 1u] = acc.y;
}
";

/// ∫₀¹∫₀¹ exp(xy) dx dy = Σ 1 / (n! (n + 1)²).
fn exp_xy_integral() -> f64 {
    let mut s = 0.0;
    let mut fact = 1.0;
    for n in 0..30 {
        if n > 0 {
            fact *= n as f64;
        }
        s += 1.0 / (fact * ((n + 1) * (n + 1)) as f64);
    }
    s
}

/// RMSE over 1024 independently randomised pixels against N, fitted as N^slope over N = 4 … 1024. Owen-scrambled
/// Sobol must converge clearly faster than Monte Carlo's N^−1/2 (smooth integrands: about N^−1.5); independent
/// sampling must sit at −1/2. Every slope is printed; docs/samplers.md records them.
#[test]
fn convergence_slopes_on_smooth_pixel_integrands() {
    let ctx = gpu();
    let pixels = 1024u32;
    let exact = exp_xy_integral();
    let mut cfg = vec![4242u32, 0, 64, 0, pixels, 0, LADDER.len() as u32];
    cfg.extend(LADDER);
    let mut report = String::new();
    for kind in SamplerKind::ALL {
        let bytes = Probe::new(&ctx)
            .run(&ProbeJob {
                source: &probe_source(SLOPES_KERNEL),
                entry: "probe_slopes",
                inputs: &[bytemuck::cast_slice(&cfg), bytemuck::cast_slice(sampler_data())],
                output_bytes: (pixels as usize * LADDER.len() * 8) as u64,
                workgroups: workgroups(pixels * LADDER.len() as u32),
                constants: &[("SPEC_SAMPLER", kind.tag() as f64)],
                geometry: None,
            })
            .unwrap_or_else(|e| panic!("{kind}: {e}"));
        let est: Vec<f32> = bytemuck::pod_collect_to_vec(&bytes);
        // The device's estimates agree with the CPU twins' (a few pixels; f32 sums in a different order).
        let sp = SamplerParams { kind: *kind, seed: cfg[0], sampler_spp: 0, width: cfg[2] };
        for p in 0..8u32 {
            for (l, &n) in LADDER.iter().enumerate() {
                let sp = SamplerParams { sampler_spp: n, ..sp };
                let (mut a, mut b) = (0.0f64, 0.0f64);
                for i in 0..n {
                    let u = samplers::sample_2d(&sp, p, i, 0);
                    let v = samplers::sample_2d(&sp, p, i, DIMS_CAMERA + 1);
                    a += ((u[0] * u[1]) as f64).exp();
                    b += ((v[0] * v[1]) as f64).exp();
                }
                let k = 2 * (p as usize * LADDER.len() + l);
                assert!(
                    (est[k] as f64 - a / n as f64).abs() < 1e-4 && (est[k + 1] as f64 - b / n as f64).abs() < 1e-4,
                    "{kind}: pixel {p}, N = {n}: device ({}, {}) vs CPU ({}, {})",
                    est[k],
                    est[k + 1],
                    a / n as f64,
                    b / n as f64
                );
            }
        }
        let mut slopes = [0.0; 2];
        let mut rmse_line = String::new();
        for (k, slope) in slopes.iter_mut().enumerate() {
            let rmse: Vec<f64> = (0..LADDER.len())
                .map(|l| {
                    let se: f64 = (0..pixels as usize)
                        .map(|p| (est[2 * (p * LADDER.len() + l) + k] as f64 - exact).powi(2))
                        .sum();
                    (se / pixels as f64).sqrt()
                })
                .collect();
            let ns: Vec<f64> = LADDER.iter().map(|&n| n as f64).collect();
            *slope = loglog_slope(&ns, &rmse).expect("a slope");
            if k == 0 {
                rmse_line = rmse.iter().map(|r| format!("{r:.2e}")).collect::<Vec<_>>().join(" ");
            }
        }
        println!("{:>12}: slopes {:.2} {:.2}; camera RMSE {rmse_line}", kind.name(), slopes[0], slopes[1]);
        report += &format!("{:>12}: RMSE ∝ N^{:.2} (camera pair), N^{:.2} (light-sample pair); camera RMSE at N = 4…1024: {rmse_line}\n", kind.name(), slopes[0], slopes[1]);
        match kind {
            SamplerKind::Independent => {
                for s in slopes {
                    assert!((-0.6..-0.4).contains(&s), "independent sampling's slope {s:.2} is not Monte Carlo's −1/2");
                }
            }
            SamplerKind::Sobol => {
                for s in slopes {
                    assert!(s < -1.0, "Owen-scrambled Sobol's RMSE slope {s:.2} is not clearly faster than N^−1/2");
                }
            }
            _ => {
                for s in slopes {
                    assert!(s < -0.7, "{kind}: slope {s:.2} is not faster than Monte Carlo");
                }
            }
        }
    }
    println!("{report}");
}

// ---------------------------------------------------------------------------------------------------------------
// Renders.

/// Each sampler through the whole renderer (binding 3, specialised pipeline, dimension allocation): the white
/// furnace gives 1 in every pixel, so the image mean must be 1 within its standard error.
#[test]
fn every_sampler_renders_the_furnace() {
    let ctx = gpu();
    let scene = scene("furnace");
    for kind in SamplerKind::ALL {
        let settings =
            Settings { sampler: *kind, mode: mislab::render::settings::Mode::Path, max_depth: 4, ..small(16, 16) };
        let film = render(&ctx, &scene, &settings, 16);
        assert_eq!(film.nonfinite_total, 0, "{kind}: NaN/Inf samples");
        let n = film.mean.len();
        let mean = film.mean_value();
        let var: f64 = (0..n).map(|i| film.variance_of_mean(i).map(|v| v.iter().sum::<f64>()).unwrap_or(0.0)).sum();
        let sigma = var.sqrt() / (3 * n) as f64;
        assert!((mean - 1.0).abs() < 4.0 * sigma.max(1e-4), "{kind}: furnace mean {mean} (σ {sigma:.1e})");
    }
}

/// lavapipe (Mesa 22.3 gallivm) gives each invocation one budget of 65535 loop iterations, shared by every
/// loop it runs, and silently stops looping when it is spent. The samplers therefore avoid loops (table
/// lookups, unrolled digits); what remains (cycle-walking permutations, the strata grid) must stay small.
/// A kernel that draws one vertex's worth of samples (every 1D and 2D dimension of a vertex and the camera)
/// 2048 times in one loop must complete all 2048 iterations: under 32 loop iterations per vertex.
const BUDGET_KERNEL: &str = "
@compute @workgroup_size(1)
fn probe_budget() {
    probe_setup();
    var count = 0u;
    var acc = 0.0;
    for (var i = 0u; i < 2048u; i += 1u) {
        let id = SampleId(7u, i);
        let b = dim_base(0u, 0u);
        acc += sample_2d(id, 0u).x + sample_1d(id, b + DIM_LIGHT_SELECT) + sample_2d(id, b + DIM_LIGHT_UV).y
            + sample_1d(id, b + DIM_LIGHT_EXTRA) + sample_1d(id, b + DIM_BSDF_LOBE) + sample_2d(id, b + DIM_BSDF_UV).x
            + sample_1d(id, b + DIM_RR) + sample_1d(id, b + DIM_MIS_CHOICE);
        count += 1u;
    }
    probe_out[0] = f32(count);
    probe_out[1] = acc;
}
";

#[test]
fn samplers_fit_lavapipes_loop_budget() {
    let ctx = gpu();
    for kind in SamplerKind::ALL {
        for target in [0u32, 7, 1024] {
            let cfg = [5u32, target, 64, 0, 1, 0];
            let bytes = Probe::new(&ctx)
                .run(&ProbeJob {
                    source: &probe_source(BUDGET_KERNEL),
                    entry: "probe_budget",
                    inputs: &[bytemuck::cast_slice(&cfg), bytemuck::cast_slice(sampler_data())],
                    output_bytes: 8,
                    workgroups: [1, 1, 1],
                    constants: &[("SPEC_SAMPLER", kind.tag() as f64)],
                    geometry: None,
                })
                .unwrap_or_else(|e| panic!("{kind}: {e}"));
            let out: Vec<f32> = bytemuck::pod_collect_to_vec(&bytes);
            assert_eq!(out[0], 2048.0, "{kind} (target {target}): the loop stopped after {} iterations", out[0]);
        }
    }
}

// ---------------------------------------------------------------------------------------------------------------
// The figure, references and the benchmark, end to end (small).

fn scratch(name: &str) -> Scratch {
    Scratch::new("samplers", name)
}

/// The figure is written in both formats, and its spectra tell blue noise from white noise: at 1 spp the
/// blue-noise sampler's error has much less low-frequency power than high, independent sampling's is flat.
#[test]
fn sampler_figure_and_spectra() {
    use mislab::lab::sampler_figure::*;
    let (white, _) = error_spectrum(SamplerKind::Independent, 1);
    let (blue, _) = error_spectrum(SamplerKind::BlueNoise, 1);
    let (w, b) = (low_frequency_ratio(&white, SPECTRUM_SIZE), low_frequency_ratio(&blue, SPECTRUM_SIZE));
    println!("low-frequency error power at 1 spp: independent {w:.2}, blue-noise {b:.2} (× the mean over frequencies)");
    assert!((0.8..1.2).contains(&w), "independent sampling's error is not white: {w}");
    // Each dimension is rotated by its own offset of a scalar mask, so a 2D integrand's error is less blue than
    // the mask itself (tested above at < 0.05): about a third of white noise's low-frequency power remains.
    assert!(b < 0.5, "blue-noise sampling's error keeps {b} of the low-frequency power");
    let dir = scratch("figure");
    run(&dir.join("samplers.png"), 1500, 1000).unwrap();
    run(&dir.join("samplers.svg"), 1500, 1000).unwrap();
    let img = image::open(dir.join("samplers.png")).unwrap();
    assert_eq!((img.width(), img.height()), (1500, 1000));
    assert!(std::fs::metadata(dir.join("samplers.svg")).unwrap().len() > 10_000);
    assert!(run(&dir.join("samplers.jpg"), 1500, 1000).is_err());
}

/// `mislab figure samplers` follows --spp and --seed (a different figure for each) and says what it wrote.
#[test]
fn figure_samplers_follows_spp_and_seed_and_reports() {
    let dir = scratch("figure-cli");
    let figure = |spp: &str, seed: &str, name: &str| {
        let out = dir.join(name);
        let o = std::process::Command::new(env!("CARGO_BIN_EXE_mislab"))
            .args(["figure", "samplers", "--width", "40", "--height", "50", "--spp", spp, "--seed", seed, "-o"])
            .arg(&out)
            .output()
            .unwrap();
        let err = String::from_utf8_lossy(&o.stderr).into_owned();
        (o.status.code(), err, out)
    };
    let (code, err, a) = figure("16", "0", "a.png");
    assert_eq!(code, Some(0), "{err}");
    assert!(err.contains("wrote") && err.contains("16 points per sampler") && err.contains("seed 0"), "{err}");
    let (_, _, b) = figure("16", "3", "b.png");
    let (_, _, c) = figure("4", "0", "c.png");
    let img = |p: &std::path::Path| image::open(p).unwrap().into_rgb8();
    assert_eq!(img(&a).dimensions(), (240, 200));
    assert_ne!(img(&a), img(&b), "--seed must change the figure");
    assert_ne!(img(&a), img(&c), "--spp must change the figure");
    let (code, err, _) = figure("5000", "0", "d.png");
    assert_eq!(code, Some(2), "{err}");
    assert!(err.contains("1 to 1024"), "{err}");
}

/// A reference's EXR header records its sample count and settings, and the pixels survive the round trip.
#[test]
fn reference_exr_records_spp_and_settings() {
    use mislab::lab::reference::*;
    let ctx = gpu();
    let scene = scene("veach-mis");
    let settings = reference_settings(&small(24, 16));
    let (film, stats) = render_reference(&ctx, &scene, &settings, mislab::api::Budget::Samples(40), 0).unwrap();
    assert_eq!(stats.spp, 40);
    assert_eq!(film.spp(), 40);
    let dir = scratch("reference");
    let path = dir.join("ref.exr");
    let spec = mislab::scene::SceneSpec::named("veach-mis");
    write_exr(&path, &film, &header_attributes(&spec, &settings, &stats)).unwrap();
    let back = read_exr(&path).unwrap();
    assert_eq!((back.width, back.height), (24, 16));
    assert_eq!(back.pixels, film.mean);
    assert_eq!(back.attributes.get("spp").map(String::as_str), Some("40"));
    let s: Settings = serde_json::from_str(&back.attributes["mislabSettings"]).unwrap();
    assert_eq!(
        (s.sampler, s.strategy, s.seed),
        (SamplerKind::Sobol, mislab::render::settings::Strategy::Mis, REFERENCE_SEED)
    );
    assert_eq!(back.attributes.get("scene").map(String::as_str), Some("veach-mis"));
}

#[derive(clap::Parser)]
struct BenchCli {
    #[command(flatten)]
    args: mislab::lab::bench::BenchArgs,
}

/// `mislab bench` from flags: every configuration × spp × seed is a row with the columns; JSON, summary
/// and plots are written; a fixed-count sampler is rendered per point; errors fall with spp.
#[test]
fn bench_end_to_end_from_flags() {
    use clap::Parser;
    let dir = scratch("bench");
    let out = dir.to_string_lossy().into_owned();
    let cli = BenchCli::parse_from([
        "bench",
        "veach-mis",
        "--width",
        "24",
        "--height",
        "16",
        "--samplers",
        "independent,stratified",
        "--spp",
        "1,4,16",
        "--seeds",
        "2",
        "--ref-spp",
        "256",
        "--out",
        &out,
    ]);
    mislab::lab::bench::run(&cli.args).unwrap();
    let csv = std::fs::read_to_string(dir.join("results.csv")).unwrap();
    let mut lines = csv.lines();
    let header: Vec<&str> = lines.next().unwrap().split(',').collect();
    for col in [
        "scene",
        "mode",
        "strategy",
        "sampler",
        "heuristic",
        "spp",
        "seed",
        "seconds_gpu",
        "seconds_wall",
        "rmse",
        "relmse",
        "mae",
        "efficiency",
    ] {
        assert!(header.contains(&col), "results.csv lacks column {col}");
    }
    let rows: Vec<Vec<&str>> = lines.map(|l| l.split(',').collect()).collect();
    assert_eq!(rows.len(), 2 * 3 * 2, "2 samplers × 3 spp × 2 seeds");
    let col = |name: &str| header.iter().position(|c| *c == name).unwrap();
    for r in &rows {
        let rel: f64 = r[col("relmse")].parse().unwrap();
        let t: f64 = r[col("seconds_gpu")].parse().unwrap();
        assert!(rel > 0.0 && rel.is_finite() && t > 0.0, "row {r:?}");
    }
    let mean_rel = |spp: &str| {
        let v: Vec<f64> =
            rows.iter().filter(|r| r[col("spp")] == spp).map(|r| r[col("relmse")].parse::<f64>().unwrap()).collect();
        v.iter().sum::<f64>() / v.len() as f64
    };
    assert!(mean_rel("16") < mean_rel("1"), "error must fall with spp");
    let json: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(dir.join("results.json")).unwrap()).unwrap();
    assert_eq!(json["rows"].as_array().unwrap().len(), 12);
    for f in [
        "summary.md",
        "veach-mis-direct-error-vs-time.png",
        "veach-mis-direct-error-vs-time.svg",
        "veach-mis-direct-error-vs-spp.png",
        "veach-mis-direct-heatmaps.png",
        "veach-mis-direct-heatmaps.svg",
    ] {
        assert!(dir.join(f).exists(), "{f} missing");
    }
    assert!(std::fs::read_dir(dir.join("refs")).unwrap().count() == 1, "the reference is cached");
    // Every row counts its NaN/Inf samples; the reference's spp is the real one.
    assert!(rows.iter().all(|r| r[col("nonfinite_samples")] == "0"), "NaN/Inf counts per row");
    assert_eq!(json["groups"][0]["reference_spp"], 256);
    assert_eq!(json["groups"][0]["group"]["reference_spp"], 256);
    assert!(std::fs::read_to_string(dir.join("summary.md")).unwrap().contains("(256 spp)"));
    // A given reference: its header's spp is reported, whatever --ref-spp says; an 8-bit PNG is refused.
    let cached = std::fs::read_dir(dir.join("refs")).unwrap().next().unwrap().unwrap().path();
    let again = dir.join("again").to_string_lossy().into_owned();
    let with_ref = |r: &std::path::Path, out: &str| {
        let r = r.to_string_lossy().into_owned();
        let args = ["bench", "veach-mis", "--width", "24", "--height", "16", "--spp", "2", "--seeds", "1"];
        BenchCli::parse_from(args.into_iter().chain(["--ref", &r, "--ref-spp", "4096", "--out", out]))
    };
    mislab::lab::bench::run(&with_ref(&cached, &again).args).unwrap();
    let json: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(dir.join("again/results.json")).unwrap()).unwrap();
    assert_eq!(json["groups"][0]["reference_spp"], 256, "the given file's spp, not --ref-spp");
    let png = dir.join("ref.png");
    image::RgbImage::new(24, 16).save(&png).unwrap();
    let e = mislab::lab::bench::run(&with_ref(&png, &again).args).unwrap_err();
    assert!(e.to_string().contains("not an OpenEXR file"), "{e}");
}

/// A TOML configuration with two groups, one reading the reference the other wrote.
#[test]
fn bench_from_toml() {
    use clap::Parser;
    let dir = scratch("toml");
    std::fs::write(
        dir.join("bench.toml"),
        "[[group]]\nname = \"heuristics\"\nscene = \"veach-mis\"\nwidth = 16\nheight = 16\nspp = [2, 8]\nseeds = 1\nreference_spp = 64\nheuristics = [\"balance\", \"power\"]\n\n[[group]]\nname = \"cornell path\"\nscene = \"cornell-box\"\nmode = \"path\"\nmax_depth = 4\nwidth = 16\nheight = 16\nspp = [2]\nseeds = 1\nreference_spp = 32\nsamplers = [\"sobol\", \"halton\"]\n",
    )
    .unwrap();
    let out = dir.join("out").to_string_lossy().into_owned();
    let cfg = dir.join("bench.toml").to_string_lossy().into_owned();
    let cli = BenchCli::parse_from(["bench", "--config", &cfg, "--out", &out]);
    mislab::lab::bench::run(&cli.args).unwrap();
    let csv = std::fs::read_to_string(dir.join("out/results.csv")).unwrap();
    assert_eq!(csv.lines().count(), 1 + 2 * 2 + 2, "{csv}");
    assert!(csv.contains("heuristics,balance") && csv.contains("cornell path,sobol"));
    assert!(BenchCli::try_parse_from(["bench", "--suite", "lecture", "--config", &cfg])
        .map(|c| c.args.groups().is_err())
        .unwrap_or(true));
}

/// The lecture suite, end to end (about half an hour on a loaded 2-core lavapipe machine;
/// `cargo test --release --test samplers -- --ignored`). MISLAB_SUITE_OUT sets the output directory (default: a
/// scratch directory); MISLAB_BENCH_ARGS, if set, replaces `--suite lecture` with other `mislab bench` arguments
/// (whitespace-separated), e.g. `--config bench.toml`.
#[test]
#[ignore]
fn lecture_suite_end_to_end() {
    use clap::Parser;
    let suite_dir = scratch("suite");
    let out = std::env::var("MISLAB_SUITE_OUT").unwrap_or_else(|_| suite_dir.to_string_lossy().into_owned());
    let extra = std::env::var("MISLAB_BENCH_ARGS").unwrap_or_else(|_| "--suite lecture".into());
    let args: Vec<String> = ["bench".to_string()]
        .into_iter()
        .chain(extra.split_whitespace().map(String::from))
        .chain(["--out".into(), out.clone()])
        .collect();
    let cli = BenchCli::parse_from(args);
    mislab::lab::bench::run(&cli.args).unwrap();
    assert!(std::path::Path::new(&out).join("results.csv").exists());
}
