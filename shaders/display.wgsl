// display.wgsl — the viewer's display pass: per-pixel accumulators → what is shown (tonemapped image,
// standard error, relMSE against a reference, NaN/Inf mask; error views in false colour) as packed
// sRGB8, plus per-column sums of the statistics the panel prints. Twin: src/viewer/display.rs.

/// Same layout as `Accum` in common.wgsl (tests/viewer.rs checks both against `GpuAccum`).
struct Accum {
    mean: vec3<f32>,
    count: u32,
    m2: vec3<f32>,
    nonfinite: u32,
}

/// What to show and how (Rust twin: `DisplayParams` in src/viewer/display.rs).
struct DisplayParams {
    width: u32,
    height: u32,
    /// VIEW_* tag (informative: the pipeline's `VIEW` constant decides).
    view: u32,
    /// TONEMAP_* tag.
    tonemap: u32,
    /// 2^exposure.
    exposure_scale: f32,
    /// Pixels with x < split_x show side A, the others side B (split_x = width without a comparison).
    split_x: u32,
    /// 1 when side B is rendered (its statistics are summed), 0 otherwise.
    compare: u32,
    /// 1 when `reference` holds a reference image of the film's size.
    has_reference: u32,
    /// The preview films are width / preview_scale × height / preview_scale.
    preview_scale: u32,
    preview_width: u32,
    preview_height: u32,
    /// log10 of the values at the bottom and top of the false-colour scale.
    log_min: f32,
    log_max: f32,
    /// Film rows this dispatch redraws (the rows the renderer changed; all of them after a restart).
    row_offset: u32,
    row_count: u32,
    _pad0: u32,
}

/// Sums over one column's pixels for one side (Rust twin: `SideSums`).
struct SideSums {
    /// Σ relative standard error (standard error of the mean / mean) over pixels with ≥ 2 samples and mean > 0.
    rel_se: f32,
    rel_se_n: f32,
    /// Σ over channels of (mean − reference)², and of (mean − reference)² / (reference² + 0.01).
    sq_err: f32,
    rel_mse: f32,
    /// Pixels that entered the error sums (finite reference, at least one sample).
    err_n: f32,
    /// Pixels with at least one NaN/Inf sample.
    nonfinite_px: f32,
    /// Pixels with at least one sample.
    sampled_px: f32,
    _pad0: f32,
}

struct Partial {
    a: SideSums,
    b: SideSums,
}

/// The view (a VIEW_* tag) is a pipeline constant: lavapipe runs every case of a switch under masks,
/// so a run-time choice would pay for all four views at every pixel.
override VIEW: u32 = 0u;

const VIEW_IMAGE: u32 = 0u;
const VIEW_STDERR: u32 = 1u;
const VIEW_RELMSE: u32 = 2u;
const VIEW_NONFINITE: u32 = 3u;

const TONEMAP_CLAMP: u32 = 0u;
const TONEMAP_ACES: u32 = 1u;

/// ε in relMSE = (x − ref)² / (ref² + ε): keeps black reference pixels from dominating (Rousselle et al. 2011).
const REL_MSE_EPSILON: f32 = 0.01;

@group(0) @binding(0) var<uniform> dp: DisplayParams;
@group(0) @binding(1) var<storage, read> accum_a: array<Accum>;
@group(0) @binding(2) var<storage, read> accum_b: array<Accum>;
@group(0) @binding(3) var<storage, read> preview_a: array<Accum>;
@group(0) @binding(4) var<storage, read> preview_b: array<Accum>;
@group(0) @binding(5) var<storage, read> reference: array<vec4<f32>>;
@group(0) @binding(6) var<storage, read_write> out_rgba: array<u32>;
@group(0) @binding(7) var<storage, read_write> partials: array<Partial>;

fn display_is_nonfinite(x: f32) -> bool { return (bitcast<u32>(x) & 0x7f800000u) == 0x7f800000u; }

/// Exposure and tonemapper: linear radiance → [0, 1] linear display value (as `film::tonemap`). NaN
/// cannot reach here (accumulators hold finite samples only), and `max` maps anything negative to 0.
fn tonemap(x: vec3<f32>) -> vec3<f32> {
    let v = max(x * dp.exposure_scale, vec3<f32>(0.0));
    if (dp.tonemap == TONEMAP_ACES) {
        // ACES filmic fit (Narkowicz 2015).
        return clamp((v * (2.51 * v + 0.03)) / (v * (2.43 * v + 0.59) + 0.14), vec3<f32>(0.0), vec3<f32>(1.0));
    }
    return min(v, vec3<f32>(1.0));
}

/// Linear → sRGB transfer function (as `film::linear_to_srgb`).
fn linear_to_srgb(x: vec3<f32>) -> vec3<f32> {
    let lo = 12.92 * x;
    let hi = 1.055 * pow(max(x, vec3<f32>(0.0031308)), vec3<f32>(1.0 / 2.4)) - 0.055;
    return select(hi, lo, x <= vec3<f32>(0.0031308));
}

/// The false-colour scale ("Turbo", polynomial fit by Mikhailov 2019): t ∈ [0, 1] → sRGB display colour.
/// Rust twin: `false_colour` in src/viewer/display.rs (the legend).
fn false_colour(t_in: f32) -> vec3<f32> {
    let t = clamp(t_in, 0.0, 1.0);
    let v4 = vec4<f32>(1.0, t, t * t, t * t * t);
    let v2 = v4.zw * v4.z;
    let r = dot(v4, vec4<f32>(0.13572138, 4.61539260, -42.66032258, 132.13108234)) + dot(v2, vec2<f32>(-152.94239396, 59.28637943));
    let g = dot(v4, vec4<f32>(0.09140261, 2.19418839, 4.84296658, -14.18503333)) + dot(v2, vec2<f32>(4.27729857, 2.82956604));
    let b = dot(v4, vec4<f32>(0.10667330, 12.64194608, -60.58204836, 110.36276771)) + dot(v2, vec2<f32>(-89.90310912, 27.34824973));
    return clamp(vec3<f32>(r, g, b), vec3<f32>(0.0), vec3<f32>(1.0));
}

/// A positive value on the log scale [10^log_min, 10^log_max] in false colour.
fn log_colour(v: f32) -> vec3<f32> {
    let l = log2(max(v, 1e-30)) * 0.30103;
    return false_colour((l - dp.log_min) / max(dp.log_max - dp.log_min, 1e-6));
}

/// Standard error of the pixel mean, averaged over channels (None-like −1 with fewer than 2 samples).
fn standard_error(a: Accum) -> f32 {
    if (a.count < 2u) { return -1.0; }
    let n = f32(a.count);
    let var_mean = max((a.m2.x + a.m2.y + a.m2.z) / 3.0, 0.0) / ((n - 1.0) * n);
    return sqrt(var_mean);
}

/// The accumulator shown at `px` for one side: the full-resolution one once it has samples there,
/// else the low-resolution preview (the first image after a reset), else nothing.
fn shown(full: Accum, px: vec2<u32>, side_b: bool) -> Accum {
    if (full.count + full.nonfinite > 0u || dp.preview_scale == 0u) { return full; }
    let q = min(px / dp.preview_scale, vec2<u32>(dp.preview_width - 1u, dp.preview_height - 1u));
    let j = q.y * dp.preview_width + q.x;
    if (side_b) { return preview_b[j]; }
    return preview_a[j];
}

/// The display colour (sRGB) of an accumulator.
fn colour_of(a: Accum, ref_value: vec4<f32>, ref_ok: bool) -> vec3<f32> {
    let has = a.count + a.nonfinite > 0u;
    let no_data = vec3<f32>(0.18);
    switch VIEW {
        case VIEW_STDERR: {
            let se = standard_error(a);
            if (se < 0.0) { return no_data; }
            return log_colour(se);
        }
        case VIEW_RELMSE: {
            if (!ref_ok || a.count == 0u) { return no_data; }
            let d = a.mean - ref_value.xyz;
            let r = d * d / (ref_value.xyz * ref_value.xyz + vec3<f32>(REL_MSE_EPSILON));
            return log_colour((r.x + r.y + r.z) / 3.0);
        }
        case VIEW_NONFINITE: {
            if (a.nonfinite > 0u) { return vec3<f32>(1.0, 0.0, 1.0); }
            let img = linear_to_srgb(tonemap(a.mean));
            return vec3<f32>(0.35 * dot(img, vec3<f32>(0.2126, 0.7152, 0.0722)));
        }
        default: {
            if (!has) { return vec3<f32>(0.0); }
            return linear_to_srgb(tonemap(a.mean));
        }
    }
}

/// This pixel's contribution to one side's statistics (full-resolution accumulator only).
fn side_sums(a: Accum, ref_value: vec4<f32>, ref_ok: bool) -> SideSums {
    var s: SideSums;
    let se = standard_error(a);
    let m = (a.mean.x + a.mean.y + a.mean.z) / 3.0;
    if (se >= 0.0 && m > 1e-6) {
        s.rel_se = se / m;
        s.rel_se_n = 1.0;
    }
    if (ref_ok && a.count > 0u) {
        let d = a.mean - ref_value.xyz;
        s.sq_err = dot(d, d);
        let r = d * d / (ref_value.xyz * ref_value.xyz + vec3<f32>(REL_MSE_EPSILON));
        s.rel_mse = r.x + r.y + r.z;
        s.err_n = 1.0;
    }
    s.nonfinite_px = select(0.0, 1.0, a.nonfinite > 0u);
    s.sampled_px = select(0.0, 1.0, a.count + a.nonfinite > 0u);
    return s;
}

fn add_sums(x: SideSums, y: SideSums) -> SideSums {
    var s: SideSums;
    s.rel_se = x.rel_se + y.rel_se;
    s.rel_se_n = x.rel_se_n + y.rel_se_n;
    s.sq_err = x.sq_err + y.sq_err;
    s.rel_mse = x.rel_mse + y.rel_mse;
    s.err_n = x.err_n + y.err_n;
    s.nonfinite_px = x.nonfinite_px + y.nonfinite_px;
    s.sampled_px = x.sampled_px + y.sampled_px;
    return s;
}

/// One pixel of the shown image. No statistics here: a workgroup reduction needs barriers, which
/// lavapipe runs as coroutines (it made this pass ~30× slower); `stats_main` sums columns instead.
@compute @workgroup_size(8, 8, 1)
fn display_main(@builtin(global_invocation_id) gid3: vec3<u32>) {
    let gid = vec2<u32>(gid3.x, gid3.y + dp.row_offset);
    if (gid.x >= dp.width || gid3.y >= dp.row_count || gid.y >= dp.height) { return; }
    let i = gid.y * dp.width + gid.x;
    var ref_value = vec4<f32>(0.0);
    var ref_ok = false;
    if (dp.has_reference != 0u) {
        ref_value = reference[i];
        ref_ok = !(display_is_nonfinite(ref_value.x) || display_is_nonfinite(ref_value.y) || display_is_nonfinite(ref_value.z));
    }
    var colour: vec3<f32>;
    if (dp.compare != 0u && gid.x >= dp.split_x) {
        colour = colour_of(shown(accum_b[i], gid.xy, true), ref_value, ref_ok);
    } else {
        colour = colour_of(shown(accum_a[i], gid.xy, false), ref_value, ref_ok);
    }
    out_rgba[i] = pack4x8unorm(vec4<f32>(colour, 1.0));
}

/// The statistics sums of one film column (one invocation per column, so neighbouring invocations
/// read neighbouring pixels), for both sides.
@compute @workgroup_size(64, 1, 1)
fn stats_main(@builtin(global_invocation_id) gid: vec3<u32>) {
    let x = gid.x;
    if (x >= dp.width) { return; }
    var total: Partial;
    for (var y = 0u; y < dp.height; y += 1u) {
        let i = y * dp.width + x;
        var ref_value = vec4<f32>(0.0);
        var ref_ok = false;
        if (dp.has_reference != 0u) {
            ref_value = reference[i];
            ref_ok = !(display_is_nonfinite(ref_value.x) || display_is_nonfinite(ref_value.y) || display_is_nonfinite(ref_value.z));
        }
        total.a = add_sums(total.a, side_sums(accum_a[i], ref_value, ref_ok));
        if (dp.compare != 0u) {
            total.b = add_sums(total.b, side_sums(accum_b[i], ref_value, ref_ok));
        }
    }
    partials[x] = total;
}
