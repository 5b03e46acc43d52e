// lights.wgsl — light techniques: sample_li / pdf_li for area lights (triangle, quad, sphere), delta lights
// (point, spot, directional) and the environment, plus light selection. All pdfs are per unit solid angle
// at the shading point and do NOT include the selection probability (see `light_pmf`).

/// A sampled direction towards a light: unit wi, distance to the light point (F32_MAX for distant
/// lights), the radiance arriving along wi (for delta lights: intensity/d² or irradiance), the pdf in
/// solid angle (0 = no sample), whether the technique is a delta distribution, and `omega`: for an area light,
/// what its pdf at any point depends on, as `light_pdf_given_omega` takes it (Ω > 0 when sampled uniformly in
/// solid angle, −1 when by area, 0 when p sees no light from it).
struct LightSample {
    wi: vec3<f32>,
    dist: f32,
    radiance: vec3<f32>,
    pdf: f32,
    delta: bool,
    omega: f32,
}

fn no_light_sample() -> LightSample {
    return LightSample(vec3<f32>(0.0, 0.0, 1.0), 0.0, vec3<f32>(0.0), 0.0, false, 0.0);
}

/// The primitive an area light is (a primitive reference), or INVALID for delta and environment lights.
fn light_prim_ref(i: u32) -> u32 {
    let l = scene_light(i);
    switch l.kind {
        case LIGHT_TRIANGLE: { return make_prim(PRIM_TRIANGLE, l.prim); }
        case LIGHT_SPHERE: { return make_prim(PRIM_SPHERE, l.prim); }
        case LIGHT_QUAD: { return make_prim(PRIM_QUAD, l.prim); }
        default: { return INVALID; }
    }
}

/// Probability of choosing light `i` under the active selection scheme.
fn light_pmf(i: u32) -> f32 {
    let l = scene_light(i);
    return select(l.pmf_uniform, l.pmf_power, cfg_light_select() == LIGHT_SELECT_POWER);
}

/// Samples an index from an alias table of `n` entries starting at `base` with one number u: the column from
/// u·n, the coin from its fractional part. NOTE: u has 24 random bits (samplers.wgsl), so the coin keeps only
/// 24 − log2(n) of them; use `alias_sample2` where a second number is available (large tables).
fn alias_sample(base: u32, n: u32, u: f32, table_is_env: bool) -> u32 {
    let x = u * f32(n);
    let i = min(u32(x), n - 1u);
    let r = x - f32(i);
    var e: AliasEntry;
    if (table_is_env) { e = env_alias[base + i]; } else { e = light_alias[base + i]; }
    return select(e.alias_index, i, r < e.prob);
}

/// Alias-table sampling with separate numbers for the column (`u_col`) and the coin (`u_coin`), so the coin has
/// full precision for any table size. Returns the index and `u_coin` rescaled to [0, 1) within the branch taken,
/// for reuse (Vose 1991; the rescaling is pbrt-v4's AliasTable::Sample).
struct AliasPick {
    index: u32,
    u: f32,
}
fn alias_sample2(base: u32, n: u32, u_col: f32, u_coin: f32, table_is_env: bool) -> AliasPick {
    let i = min(u32(u_col * f32(n)), n - 1u);
    var e: AliasEntry;
    if (table_is_env) { e = env_alias[base + i]; } else { e = light_alias[base + i]; }
    if (u_coin < e.prob) { return AliasPick(i, min(u_coin / e.prob, ONE_MINUS_EPSILON)); }
    return AliasPick(e.alias_index, min((u_coin - e.prob) / (1.0 - e.prob), ONE_MINUS_EPSILON));
}

/// Chooses one light with probability `light_pmf`.
fn select_light(u: f32) -> u32 {
    if (!MANY_LIGHTS) { return 0u; }
    let n = params.num_lights;
    if (cfg_light_select() == LIGHT_SELECT_POWER) { return alias_sample(0u, n, u, false); }
    return min(u32(u * f32(n)), n - 1u);
}

// ---- area lights: uniform by area, converted to solid angle by distance² / cos ----

/// Area-to-solid-angle conversion for a sampled light point y with normal n_y, seen from p.
/// One-sided: a point seen from behind has pdf 0 (it emits nothing towards p).
fn area_to_solid_angle(p: vec3<f32>, y: vec3<f32>, n_y: vec3<f32>, pdf_area: f32, emitted: vec3<f32>) -> LightSample {
    let v = y - p;
    let d2 = dot(v, v);
    let dist = sqrt(d2);
    let wi = v / dist;
    let cos_l = dot(-wi, n_y);
    if (!(cos_l > 0.0) || !(d2 > 0.0)) { return no_light_sample(); }
    return LightSample(wi, dist, emitted, pdf_area * d2 / cos_l, false, -1.0);
}

/// Triangle light, uniform by area (barycentrics by Heitz's low-distortion map). Measure: area → solid angle.
fn triangle_sample_li(prim: u32, p: vec3<f32>, u: vec2<f32>) -> LightSample {
    let tp = scene_tri_positions(prim);
    let v0 = tp.v0;
    let v1 = tp.v1;
    let v2 = tp.v2;
    let c = cross(v1 - v0, v2 - v0);
    let area2 = length(c);
    if (!(area2 > 0.0)) { return no_light_sample(); }
    let b = square_to_uniform_triangle(u);
    let y = (1.0 - b.x - b.y) * v0 + b.x * v1 + b.y * v2;
    let sh = scene_tri_shading(prim);
    let uv = (1.0 - b.x - b.y) * sh.uv0 + b.x * sh.uv1 + b.y * sh.uv2;
    let emitted = material_emission(scene_material(sh.material), uv);
    return area_to_solid_angle(p, y, c / area2, 2.0 / area2, emitted);
}

/// Quad light, uniform by area. Measure: area → solid angle.
fn quad_sample_li(prim: u32, p: vec3<f32>, u: vec2<f32>) -> LightSample {
    let q = scene_quad(prim);
    let c = cross(q.edge_u, q.edge_v);
    let area = length(c);
    if (!(area > 0.0)) { return no_light_sample(); }
    let y = q.corner + u.x * q.edge_u + u.y * q.edge_v;
    let emitted = material_emission(scene_material(q.material), u);
    return area_to_solid_angle(p, y, c / area, 1.0 / area, emitted);
}

/// Sphere light, uniform by area over the whole sphere. Points on the far side face away from p and come back
/// as failed samples (pdf 0), so the pdf of the successful ones integrates to the visible fraction of the area.
/// Measure: area → solid angle.
fn sphere_sample_li_area(prim: u32, p: vec3<f32>, u: vec2<f32>) -> LightSample {
    let s = scene_sphere(prim);
    let n = square_to_uniform_sphere(u);
    let y = s.center + s.radius * n;
    let uv = vec2<f32>(atan2(n.z, n.x) * INV_TWO_PI + 0.5, acos(clamp(n.y, -1.0, 1.0)) * INV_PI);
    let emitted = material_emission(scene_material(s.material), uv);
    return area_to_solid_angle(p, y, n, 1.0 / (4.0 * PI * s.radius * s.radius), emitted);
}

/// 1 − cosθmax of the cone a sphere subtends from p, or a negative value when p is inside (or so close
/// to the surface that the cone is numerically a hemisphere): then callers fall back to area sampling.
/// Written via sin²θmax/(1 + cosθmax) so tiny spheres keep their precision.
fn sphere_cone_one_minus_cos(s: Sphere, p: vec3<f32>) -> f32 {
    let d2 = dot(s.center - p, s.center - p);
    let r2 = s.radius * s.radius;
    if (!(d2 > r2 * 1.0001)) { return -1.0; }
    let sin2 = r2 / d2;
    return sin2 / (1.0 + sqrt(1.0 - sin2));
}

/// Sphere light, uniform in the subtended cone (solid angle). Measure: solid angle.
fn sphere_sample_li_cone(prim: u32, p: vec3<f32>, u: vec2<f32>) -> LightSample {
    let s = scene_sphere(prim);
    let omc = sphere_cone_one_minus_cos(s, p);
    if (omc <= 0.0) { return sphere_sample_li_area(prim, p, u); }
    let to_c = s.center - p;
    let d = length(to_c);
    let f = frame_from_normal(to_c / d);
    let wl = square_to_uniform_cone(u, omc);
    let wi = normalize(to_world(f, wl));
    // Distance along wi to the near intersection: t = d·cosθ − sqrt(r² − d²·sin²θ). sin²θ from the transverse
    // components (1 − z² has no digits left in a tiny cone).
    let sin2 = wl.x * wl.x + wl.y * wl.y;
    let cos_t = wl.z;
    let t = max(d * cos_t - safe_sqrt(s.radius * s.radius - d * d * sin2), 0.0);
    let y = p + t * wi;
    let n = normalize(y - s.center);
    let uv = vec2<f32>(atan2(n.z, n.x) * INV_TWO_PI + 0.5, acos(clamp(n.y, -1.0, 1.0)) * INV_PI);
    let emitted = material_emission(scene_material(s.material), uv);
    return LightSample(wi, t, emitted, square_to_uniform_cone_pdf(omc), false, TWO_PI * omc);
}

// ---- triangle and quad lights by solid angle (spherical triangle / spherical rectangle) ----
//
// Fallback to area sampling, a deterministic function of (light, shading point) shared by sample_li and pdf_li:
// the spherical warps are used only where their f32 error on this platform stays below 1e-4 — sample positions
// in units of the light's size and Ω relative, against f64 twins, over far / close (above the centre, an edge, a
// vertex) / grazing viewpoints of regular and 100:1 sliver shapes (tests/sampling.rs `spherical_warps_precision`;
// the table is in docs/sampling.md). Measured: triangles break down below ~6e-6 sr (slivers; regular ones hold to
// ~1e-7 sr) and above ~5.8 sr (a viewpoint within ~1/1000 of the light's size of its plane, near an edge);
// rectangles below ~2e-5 sr (slivers) and above ~5.8 sr (near a corner). Below the minimum the light is small and
// area sampling is nearly as good (its pdf is nearly constant over the light); above the maximum the viewpoint
// almost touches the light.

/// Spherical-triangle sampling is used for triangles subtending [SPHERICAL_TRIANGLE_MIN_SR, SPHERICAL_TRIANGLE_MAX_SR].
const SPHERICAL_TRIANGLE_MIN_SR: f32 = 1e-5;
const SPHERICAL_TRIANGLE_MAX_SR: f32 = 5.5;
/// Spherical-rectangle sampling is used for rectangles subtending [SPHERICAL_RECT_MIN_SR, SPHERICAL_RECT_MAX_SR].
const SPHERICAL_RECT_MIN_SR: f32 = 5e-5;
const SPHERICAL_RECT_MAX_SR: f32 = 5.5;
/// A quad is a rectangle when |cos| of the angle between its edges is at most this; other parallelograms are
/// sampled by area in either mode.
const RECT_COS_TOLERANCE: f32 = 1e-5;

/// Solid angle of triangle light `prim` as its solid-angle sampler uses it: Ω > 0 when spherical sampling
/// applies, −1 when p is in front but area sampling is used (Ω out of range), 0 when p sees its back or lies in
/// its plane (no light reaches p).
fn triangle_light_omega(v0: vec3<f32>, v1: vec3<f32>, v2: vec3<f32>, p: vec3<f32>) -> f32 {
    let n = cross(v1 - v0, v2 - v0);
    if (!(dot(p - v0, n) > 0.0)) { return 0.0; }
    let omega = spherical_triangle_solid_angle(v0 - p, v1 - p, v2 - p);
    if (omega >= SPHERICAL_TRIANGLE_MIN_SR && omega <= SPHERICAL_TRIANGLE_MAX_SR) { return omega; }
    return -1.0;
}

/// Triangle light, uniform in solid angle (spherical triangle), else by area. Measure: solid angle.
fn triangle_sample_li_solid_angle(prim: u32, p: vec3<f32>, u: vec2<f32>) -> LightSample {
    let tp = scene_tri_positions(prim);
    let v0 = tp.v0;
    let v1 = tp.v1;
    let v2 = tp.v2;
    let omega = triangle_light_omega(v0, v1, v2, p);
    if (omega == 0.0) { return no_light_sample(); }
    if (omega < 0.0) { return triangle_sample_li(prim, p, u); }
    let wi = spherical_triangle_warp(u, v0 - p, v1 - p, v2 - p, omega);
    // The light point: wi meets the triangle's plane at t = (v0 − p)·n / (wi·n).
    let n = cross(v1 - v0, v2 - v0);
    let t = dot(v0 - p, n) / dot(wi, n);
    if (!(t > 0.0) || is_nonfinite(t)) { return no_light_sample(); }
    let y = p + t * wi;
    let inv_nn = 1.0 / dot(n, n);
    let b1 = clamp(dot(cross(y - v0, v2 - v0), n) * inv_nn, 0.0, 1.0);
    let b2 = clamp(dot(cross(v1 - v0, y - v0), n) * inv_nn, 0.0, 1.0);
    let sh = scene_tri_shading(prim);
    let uv = (1.0 - b1 - b2) * sh.uv0 + b1 * sh.uv1 + b2 * sh.uv2;
    let emitted = material_emission(scene_material(sh.material), uv);
    return LightSample(wi, t, emitted, 1.0 / omega, false, omega);
}

/// A quad light's frame for spherical-rectangle sampling: unit edges x, y, front normal z, edge lengths, and
/// the spherical rectangle seen from p (`rect.omega` ≤ 0: see `quad_light_frame`).
struct QuadLightFrame {
    x: vec3<f32>,
    y: vec3<f32>,
    z: vec3<f32>,
    lu: f32,
    lv: f32,
    rect: SphericalRect,
}

/// Like `triangle_light_omega` for quads: `rect.omega` > 0 when spherical-rectangle sampling applies, −1 when p
/// is in front but area sampling is used (not a rectangle, or Ω out of range), 0 when p sees its back.
fn quad_light_frame(q: Quad, p: vec3<f32>) -> QuadLightFrame {
    var f: QuadLightFrame;
    f.rect.omega = 0.0;
    let c = cross(q.edge_u, q.edge_v);
    let d = q.corner - p;
    if (!(dot(-d, c) > 0.0)) { return f; }
    f.rect.omega = -1.0;
    f.lu = length(q.edge_u);
    f.lv = length(q.edge_v);
    if (!(abs(dot(q.edge_u, q.edge_v)) <= RECT_COS_TOLERANCE * f.lu * f.lv)) { return f; }
    f.x = q.edge_u / f.lu;
    f.y = q.edge_v / f.lv;
    f.z = normalize(c);
    let r = spherical_rect_setup(dot(d, f.x), dot(d, f.y), f.lu, f.lv, -dot(d, f.z));
    if (r.omega >= SPHERICAL_RECT_MIN_SR && r.omega <= SPHERICAL_RECT_MAX_SR) { f.rect = r; }
    return f;
}

/// Quad light, uniform in solid angle (spherical rectangle) when it is a rectangle, else by area.
/// Measure: solid angle.
fn quad_sample_li_solid_angle(prim: u32, p: vec3<f32>, u: vec2<f32>) -> LightSample {
    let q = scene_quad(prim);
    let f = quad_light_frame(q, p);
    if (f.rect.omega == 0.0) { return no_light_sample(); }
    if (f.rect.omega < 0.0) { return quad_sample_li(prim, p, u); }
    let xy = square_to_spherical_rectangle(u, f.rect);
    let v = xy.x * f.x + xy.y * f.y - f.rect.h * f.z;
    let dist = length(v);
    let st = vec2<f32>((xy.x - f.rect.x0) / f.lu, (xy.y - f.rect.y0) / f.lv);
    let emitted = material_emission(scene_material(q.material), st);
    return LightSample(v / dist, dist, emitted, 1.0 / f.rect.omega, false, f.rect.omega);
}

// ---- delta lights ----

/// Point light: irradiance-like radiance I/d², pdf 1 (delta).
fn point_sample_li(l: Light, p: vec3<f32>) -> LightSample {
    let v = l.position - p;
    let d2 = dot(v, v);
    if (!(d2 > 0.0)) { return no_light_sample(); }
    let dist = sqrt(d2);
    return LightSample(v / dist, dist, l.radiance / d2, 1.0, true, -1.0);
}

/// Spot light: a point light times a smooth falloff between the outer and inner cone.
fn spot_sample_li(l: Light, p: vec3<f32>) -> LightSample {
    var s = point_sample_li(l, p);
    let c = dot(-s.wi, l.direction);
    s.radiance *= smoothstep(l.cos_outer, l.cos_inner, c);
    return s;
}

/// Directional light: light travelling along `direction`, irradiance in `radiance`.
fn directional_sample_li(l: Light) -> LightSample {
    return LightSample(-l.direction, F32_MAX, l.radiance, 1.0, true, -1.0);
}

// ---- environment ----

/// Direction → equirectangular (u, v) in map space: u = 0.5 looks down −Z, v = 0 is +Y;
/// the map is rotated by `env_rotation` radians about +Y. θ from atan2 (acos(w.y) loses digits at the poles), and
/// the accurate atan2 so that directions map to the texels `env_sample_li` sampled them in.
fn env_direction_to_uv(w: vec3<f32>) -> vec2<f32> {
    let u = atan2_accurate(w.x, -w.z) * INV_TWO_PI + 0.5 - params.env_rotation * INV_TWO_PI;
    return vec2<f32>(fract(u), atan2_accurate(length(w.xz), w.y) * INV_PI);
}

fn env_uv_to_direction(uv: vec2<f32>) -> vec3<f32> {
    let phi = TWO_PI * (uv.x - 0.5) + params.env_rotation;
    let theta = PI * uv.y;
    let st = sin(theta);
    return vec3<f32>(st * sin(phi), cos(theta), -st * cos(phi));
}

fn env_texel_index(uv: vec2<f32>) -> u32 {
    let x = min(u32(uv.x * f32(params.env_width)), params.env_width - 1u);
    let y = min(u32(uv.y * f32(params.env_height)), params.env_height - 1u);
    return y * params.env_width + x;
}

/// Radiance arriving from direction w (piecewise constant over texels, matching the sampling density).
fn env_eval(w: vec3<f32>) -> vec3<f32> {
    if (ENV_KIND == 0u) { return vec3<f32>(0.0); }
    if (ENV_KIND == 1u || (ENV_KIND == 3u && params.env_width == 0u)) { return params.env_constant * params.env_scale; }
    return env_texels[env_texel_index(env_direction_to_uv(w))].xyz * params.env_scale;
}

/// pdf (solid angle) of `env_sample_li` producing w: 1/4π (uniform), or density_uv / (2π² sinθ) (importance).
/// sinθ = |w.xz| (1 − w.y² loses its digits near the poles).
fn env_pdf(w: vec3<f32>) -> f32 {
    if (ENV_KIND == 0u) { return 0.0; }
    if (ENV_KIND == 1u || (ENV_KIND == 3u && params.env_width == 0u) || cfg_env_sampling() == ENV_SAMPLING_UNIFORM) { return INV_FOUR_PI; }
    let uv = env_direction_to_uv(w);
    let density_uv = env_texels[env_texel_index(uv)].w;
    let sin_theta = length(w.xz);
    return density_uv / (2.0 * PI * PI * max(sin_theta, 1e-7));
}

/// Environment: uniform on the sphere, or a texel ∝ luminance·sinθ by the alias table (column from u.z, coin
/// from u.y, which is then reused) and uniform in (u, v) inside the texel, so pdf_ω = density_uv / (2π² sinθ).
/// The pdf returned is the chosen texel's: at a texel edge, f32 rounding may map the direction into the
/// neighbour, where `env_pdf` (and a black neighbour's radiance) would differ on that measure-zero set.
/// Measure: solid angle.
fn env_sample_li(u: vec3<f32>) -> LightSample {
    if (ENV_KIND == 1u || (ENV_KIND == 3u && params.env_width == 0u) || cfg_env_sampling() == ENV_SAMPLING_UNIFORM) {
        let wi = square_to_uniform_sphere(u.xy);
        return LightSample(wi, F32_MAX, env_eval(wi), INV_FOUR_PI, false, -1.0);
    }
    let n = params.env_width * params.env_height;
    let pick = alias_sample2(0u, n, u.z, u.y, true);
    let x = pick.index % params.env_width;
    let y = pick.index / params.env_width;
    let uv = vec2<f32>((f32(x) + u.x) / f32(params.env_width), (f32(y) + pick.u) / f32(params.env_height));
    let wi = env_uv_to_direction(uv);
    let texel = env_texels[pick.index];
    let pdf = texel.w / (2.0 * PI * PI * max(length(wi.xz), 1e-7));
    if (!(pdf > 0.0)) { return no_light_sample(); }
    return LightSample(wi, F32_MAX, texel.xyz * params.env_scale, pdf, false, -1.0);
}

// ---- the light technique as a whole ----

/// Samples a point or direction on light `i` as seen from p (without the selection probability).
fn light_sample_li(i: u32, p: vec3<f32>, u: vec3<f32>) -> LightSample {
    let l = scene_light(i);
    let solid_angle = cfg_light_sampling() == LIGHT_SAMPLING_SOLID_ANGLE;
    switch (l.kind) {
        case LIGHT_TRIANGLE: {
            if (!HAS_TRIANGLE_LIGHTS) { return no_light_sample(); }
            if (solid_angle) { return triangle_sample_li_solid_angle(l.prim, p, u.xy); }
            return triangle_sample_li(l.prim, p, u.xy);
        }
        case LIGHT_QUAD: {
            if (!HAS_QUAD_LIGHTS) { return no_light_sample(); }
            if (solid_angle) { return quad_sample_li_solid_angle(l.prim, p, u.xy); }
            return quad_sample_li(l.prim, p, u.xy);
        }
        case LIGHT_SPHERE: {
            if (!HAS_SPHERE_LIGHTS) { return no_light_sample(); }
            if (solid_angle) { return sphere_sample_li_cone(l.prim, p, u.xy); }
            return sphere_sample_li_area(l.prim, p, u.xy);
        }
        case LIGHT_POINT: { if (HAS_DELTA_LIGHTS) { return point_sample_li(l, p); } }
        case LIGHT_SPOT: { if (HAS_DELTA_LIGHTS) { return spot_sample_li(l, p); } }
        case LIGHT_DIRECTIONAL: { if (HAS_DELTA_LIGHTS) { return directional_sample_li(l); } }
        case LIGHT_ENVIRONMENT: { if (ENV_KIND != 0u) { return env_sample_li(u); } }
        default: {}
    }
    return no_light_sample();
}

/// pdf (solid angle, without selection) that `light_sample_li` for light i produces the point y
/// (normal n_y, either orientation) seen from p along wi. For the environment y is unused. The fallback
/// decisions are the samplers' own (`triangle_light_omega`, `quad_light_frame`, `sphere_cone_one_minus_cos`);
/// a triangle or quad seen from behind has pdf 0 (one-sided emitters).
fn light_pdf_li(i: u32, p: vec3<f32>, wi: vec3<f32>, y: vec3<f32>, n_y: vec3<f32>) -> f32 {
    let l = scene_light(i);
    if (l.kind == LIGHT_ENVIRONMENT) { return env_pdf(wi); }
    if (l.kind > LIGHT_QUAD) { return 0.0; }
    return light_pdf_given_omega(i, p, wi, y, n_y, light_omega(i, p));
}

/// The `omega` of `LightSample` for area light i seen from p: what its sampler decides there.
fn light_omega(i: u32, p: vec3<f32>) -> f32 {
    let l = scene_light(i);
    let solid_angle = cfg_light_sampling() == LIGHT_SAMPLING_SOLID_ANGLE;
    if (HAS_TRIANGLE_LIGHTS && l.kind == LIGHT_TRIANGLE) {
        let tp = scene_tri_positions(l.prim);
        if (solid_angle) { return triangle_light_omega(tp.v0, tp.v1, tp.v2, p); }
        return select(0.0, -1.0, dot(p - tp.v0, cross(tp.v1 - tp.v0, tp.v2 - tp.v0)) > 0.0);
    }
    if (HAS_QUAD_LIGHTS && l.kind == LIGHT_QUAD) {
        let q = scene_quad(l.prim);
        if (solid_angle) { return quad_light_frame(q, p).rect.omega; }
        return select(0.0, -1.0, dot(p - q.corner, cross(q.edge_u, q.edge_v)) > 0.0);
    }
    if (HAS_SPHERE_LIGHTS && l.kind == LIGHT_SPHERE) {
        let omc = sphere_cone_one_minus_cos(scene_sphere(l.prim), p);
        return select(-1.0, TWO_PI * omc, solid_angle && omc > 0.0);
    }
    return 0.0;
}

/// `light_pdf_li` for an area light whose `omega` from p is known (a light sample taken at p returns it: the
/// pdf of a direction that hits the same light from the same point needs no second spherical-polygon setup).
fn light_pdf_given_omega(i: u32, p: vec3<f32>, wi: vec3<f32>, y: vec3<f32>, n_y: vec3<f32>, omega: f32) -> f32 {
    if (omega > 0.0) { return 1.0 / omega; }
    if (!(omega < 0.0)) { return 0.0; }
    // By area: d² / (A·cos_l).
    let l = scene_light(i);
    let v = y - p;
    let d2 = dot(v, v);
    if (HAS_TRIANGLE_LIGHTS && l.kind == LIGHT_TRIANGLE) {
        let tp = scene_tri_positions(l.prim);
        // (2/|n|)·d² / cos_l with cos_l = |wi·n|/|n|.
        let c = abs(dot(wi, cross(tp.v1 - tp.v0, tp.v2 - tp.v0)));
        if (!(c > 0.0)) { return 0.0; }
        return 2.0 * d2 / c;
    }
    if (HAS_QUAD_LIGHTS && l.kind == LIGHT_QUAD) {
        let q = scene_quad(l.prim);
        let c = abs(dot(wi, cross(q.edge_u, q.edge_v)));
        if (!(c > 0.0)) { return 0.0; }
        return d2 / c;
    }
    if (HAS_SPHERE_LIGHTS && l.kind == LIGHT_SPHERE) {
        let cos_l = abs(dot(wi, n_y));
        if (!(cos_l > 0.0)) { return 0.0; }
        return d2 / (l.area * cos_l);
    }
    return 0.0;
}
