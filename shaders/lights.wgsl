// lights.wgsl — the light techniques, one section per light kind, and light selection.
//
// Contract (pbrt-v4's Light::SampleLi / PDF_Li / L, plus the measure they share). Every kind K (`LIGHT_K` in
// common.wgsl) has one section with:
//   K_measure(l, p) -> LightMeasure       how K_sample_li draws directions from p (by area, uniformly in the solid
//                                         angle the light subtends, a delta, none): decided once, so that sample_li
//                                         and pdf_li agree, and kept by a caller that needs the pdf again;
//   K_sample_li(l, p, u) -> LightSample   a direction wi from p towards light l, drawn with u ∈ [0,1)³: the
//                                         distance to the light point, the radiance arriving along wi unoccluded
//                                         (delta lights: intensity/d² or irradiance), its pdf per unit solid angle
//                                         at p (0 = no sample), and K_measure(l, p) (also when the sample failed);
//   K_pdf_li(l, m, p, wi, y, n_y) -> f32  the pdf per unit solid angle that K_sample_li draws wi, which meets the
//                                         light at y with geometric normal n_y (either orientation), given
//                                         m = K_measure(l, p); 0 for delta lights;
//   K_eval(l, y, wi) -> vec3<f32>         the radiance the light emits along wi from the point y a ray found (the
//                                         environment ignores y); 0 for delta lights, which no ray finds.
// No pdf here includes the selection probability (`light_pmf`). Emitters are one-sided unless `l.two_sided`: from
// behind a one-sided triangle or quad, p gets no light (MEASURE_NONE) and pdf_li is 0; a two-sided one seen from
// behind is sampled as its mirror twin (the same points, winding reversed), so the one-sided code applies. The dispatchers light_measure / light_sample_li /
// light_pdf_li / light_eval (last section) have one `case` per kind; tests/shaders.rs checks that and that nothing
// else switches on the kind.

/// How a light's sampler draws directions from a point p. MEASURE_SOLID_ANGLE: uniformly in the solid angle
/// `omega` the light subtends (spherical triangle, spherical rectangle, cone), so pdf = 1/omega for every
/// direction that meets it; the environment draws per texel, in solid angle too (`omega` unused). MEASURE_AREA:
/// uniformly by area, converted per direction by d²/cos. MEASURE_DISCRETE: a delta light. MEASURE_NONE: p gets no
/// light from it.
const MEASURE_NONE: u32 = 0u;
const MEASURE_SOLID_ANGLE: u32 = 1u;
const MEASURE_AREA: u32 = 2u;
const MEASURE_DISCRETE: u32 = 3u;

struct LightMeasure {
    measure: u32,
    omega: f32,
}

/// A sampled direction towards a light (see the contract above). `prim` is the light's own primitive reference,
/// which a shadow ray towards it must not count as an occluder (INVALID for delta and environment lights).
struct LightSample {
    wi: vec3<f32>,
    dist: f32,
    radiance: vec3<f32>,
    pdf: f32,
    m: LightMeasure,
    prim: u32,
}

fn no_light_sample() -> LightSample {
    return LightSample(vec3<f32>(0.0, 0.0, 1.0), 0.0, vec3<f32>(0.0), 0.0, LightMeasure(MEASURE_NONE, 0.0), INVALID);
}

/// A failed sample that keeps the measure decided at p.
fn no_light_sample_in(m: LightMeasure) -> LightSample {
    var s = no_light_sample();
    s.m = m;
    return s;
}

// ---- light selection ----

/// Whether lights are chosen by the light tree: `tree`, and `tree-ris`'s candidates.
fn light_select_by_tree() -> bool {
    return cfg_light_select() == LIGHT_SELECT_TREE || cfg_light_select() == LIGHT_SELECT_TREE_RIS;
}

/// Probability of choosing light `i` from the shading point p with normal n (zero: none) under the active scheme.
fn light_pmf(i: u32, p: vec3<f32>, n: vec3<f32>) -> f32 {
    if (MANY_LIGHTS && light_select_by_tree()) { return tree_light_pmf(i, p, n); }
    let l = scene_light(i);
    // RIS draws its candidates by power (tree-ris: by the tree): the MIS weights of both techniques use that
    // source density (estimators.wgsl).
    let by_power = cfg_light_select() == LIGHT_SELECT_POWER || cfg_light_select() == LIGHT_SELECT_RIS;
    return select(l.pmf_uniform, l.pmf_power, by_power);
}

/// Samples an index from an alias table of `n` entries starting at `base` with one number u: the column from
/// u·n, the coin from its fractional part. NOTE: u has 24 random bits (samplers.wgsl), so the coin keeps only
/// 24 − log2(n) of them; use `alias_sample2` where a second number is available (large tables).
fn alias_sample(base: u32, n: u32, u: f32, table_is_env: bool) -> u32 {
    let x = u * f32(n);
    let i = min(u32(x), n - 1u);
    let r = x - f32(i);
    var e: AliasEntry;
    if (table_is_env) { e = load_env_alias(base + i); } else { e = load_light_alias(base + i); }
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
    if (table_is_env) { e = load_env_alias(base + i); } else { e = load_light_alias(base + i); }
    if (u_coin < e.prob) { return AliasPick(i, min(u_coin / e.prob, ONE_MINUS_EPSILON)); }
    return AliasPick(e.alias_index, min((u_coin - e.prob) / (1.0 - e.prob), ONE_MINUS_EPSILON));
}

/// A chosen light and its probability, `light_pmf(index, p, n)`.
struct LightPick {
    index: u32,
    pmf: f32,
}

/// Chooses one light with probability `light_pmf(·, p, n)`, and returns that probability (bit for bit: the tree
/// multiplies it up on its way down instead of walking twice).
fn select_light(u: f32, p: vec3<f32>, n: vec3<f32>) -> LightPick {
    if (!MANY_LIGHTS) { return LightPick(0u, light_pmf(0u, p, n)); }
    let count = params.num_lights;
    if (light_select_by_tree()) { return tree_select_light(u, p, n); }
    let by_power = cfg_light_select() == LIGHT_SELECT_POWER || cfg_light_select() == LIGHT_SELECT_RIS;
    var i = min(u32(u * f32(count)), count - 1u);
    if (by_power) { i = alias_sample(0u, count, u, false); }
    return LightPick(i, light_pmf(i, p, n));
}

// ---- area lights in common ----
//
// By area: uniform on the surface, converted to solid angle by d²/cos. By solid angle (spherical triangle,
// spherical rectangle, cone) where the warp is accurate, else by area: that choice is a deterministic function
// of (light, p), made by the kind's `*_measure`, which sample_li and pdf_li share. The spherical warps
// are used only where their f32 error on this platform stays below 1e-4 — sample positions in units of the
// light's size and Ω relative, against f64 twins, over far / close (above the centre, an edge, a vertex) /
// grazing viewpoints of regular and 100:1 sliver shapes (tests/sampling.rs `spherical_warps_precision`; the table
// is in docs/sampling.md). Measured: triangles break down below ~6e-6 sr (slivers; regular ones hold to ~1e-7 sr)
// and above ~5.8 sr (a viewpoint within ~1/1000 of the light's size of its plane, near an edge); rectangles below
// ~2e-5 sr (slivers) and above ~5.8 sr (near a corner). Below the minimum the light is small and area sampling is
// nearly as good (its pdf is nearly constant over the light); above the maximum p almost touches the light.

/// Spherical-triangle sampling is used for triangles subtending [SPHERICAL_TRIANGLE_MIN_SR, SPHERICAL_TRIANGLE_MAX_SR].
const SPHERICAL_TRIANGLE_MIN_SR: f32 = 1e-5;
const SPHERICAL_TRIANGLE_MAX_SR: f32 = 5.5;
/// Spherical-rectangle sampling is used for rectangles subtending [SPHERICAL_RECT_MIN_SR, SPHERICAL_RECT_MAX_SR].
const SPHERICAL_RECT_MIN_SR: f32 = 5e-5;
const SPHERICAL_RECT_MAX_SR: f32 = 5.5;
/// A quad is a rectangle when |cos| of the angle between its edges is at most this; other parallelograms are
/// sampled by area in either mode.
const RECT_COS_TOLERANCE: f32 = 1e-5;

/// Area-to-solid-angle conversion for a sampled light point y with normal n_y, seen from p.
/// One-sided: a point seen from behind has pdf 0 (it emits nothing towards p).
fn area_to_solid_angle(p: vec3<f32>, y: vec3<f32>, n_y: vec3<f32>, pdf_area: f32, emitted: vec3<f32>, prim: u32) -> LightSample {
    let v = y - p;
    let d2 = dot(v, v);
    let dist = sqrt(d2);
    let wi = v / dist;
    let cos_l = dot(-wi, n_y);
    if (!(cos_l > 0.0) || !(d2 > 0.0)) { return no_light_sample(); }
    return LightSample(wi, dist, emitted, pdf_area * d2 / cos_l, LightMeasure(MEASURE_AREA, 0.0), prim);
}

/// The emission of an area light at the point y a ray found: its material's, on the front face only unless the
/// light is two-sided.
fn area_eval(l: Light, y: Surface) -> vec3<f32> {
    if (!y.front && l.two_sided == 0u) { return vec3<f32>(0.0); }
    return material_emission(scene_material(y.material), y.uv);
}

// ---- LIGHT_TRIANGLE: a mesh triangle of an emissive material ----

/// Spherical-triangle sampling where accurate (solid-angle mode), else by area; NONE when p sees the back.
fn triangle_measure_of(v0: vec3<f32>, v1: vec3<f32>, v2: vec3<f32>, p: vec3<f32>) -> LightMeasure {
    let n = cross(v1 - v0, v2 - v0);
    if (!(dot(p - v0, n) > 0.0)) { return LightMeasure(MEASURE_NONE, 0.0); }
    if (cfg_light_sampling() == LIGHT_SAMPLING_SOLID_ANGLE) {
        let omega = spherical_triangle_solid_angle(v0 - p, v1 - p, v2 - p);
        if (omega >= SPHERICAL_TRIANGLE_MIN_SR && omega <= SPHERICAL_TRIANGLE_MAX_SR) {
            return LightMeasure(MEASURE_SOLID_ANGLE, omega);
        }
    }
    return LightMeasure(MEASURE_AREA, 0.0);
}

/// A light triangle's vertices as p sees them: a two-sided light seen from behind has v1 and v2 swapped (`swapped`),
/// so that p is in front of the same triangle.
struct TriFromP {
    v0: vec3<f32>,
    v1: vec3<f32>,
    v2: vec3<f32>,
    swapped: bool,
}

fn triangle_from(l: Light, p: vec3<f32>) -> TriFromP {
    let tp = scene_tri_positions(l.prim);
    let behind = dot(p - tp.v0, cross(tp.v1 - tp.v0, tp.v2 - tp.v0)) < 0.0;
    if (l.two_sided != 0u && behind) { return TriFromP(tp.v0, tp.v2, tp.v1, true); }
    return TriFromP(tp.v0, tp.v1, tp.v2, false);
}

/// The uv at barycentrics (b1, b2) of `triangle_from`'s vertices.
fn triangle_light_uv(prim: u32, b1: f32, b2: f32, swapped: bool) -> vec2<f32> {
    let sh = scene_tri_shading(prim);
    return (1.0 - b1 - b2) * sh.uv0 + select(b1, b2, swapped) * sh.uv1 + select(b2, b1, swapped) * sh.uv2;
}

fn triangle_measure(l: Light, p: vec3<f32>) -> LightMeasure {
    let t = triangle_from(l, p);
    return triangle_measure_of(t.v0, t.v1, t.v2, p);
}

/// Uniform by area (barycentrics by Heitz's low-distortion map). Measure: area → solid angle.
fn triangle_sample_area(l: Light, p: vec3<f32>, u: vec2<f32>) -> LightSample {
    let t = triangle_from(l, p);
    let c = cross(t.v1 - t.v0, t.v2 - t.v0);
    let area2 = length(c);
    if (!(area2 > 0.0)) { return no_light_sample(); }
    let b = square_to_uniform_triangle(u);
    let y = (1.0 - b.x - b.y) * t.v0 + b.x * t.v1 + b.y * t.v2;
    let sh = scene_tri_shading(l.prim);
    let emitted = material_emission(scene_material(sh.material), triangle_light_uv(l.prim, b.x, b.y, t.swapped));
    return area_to_solid_angle(p, y, c / area2, 2.0 / area2, emitted, make_prim(PRIM_TRIANGLE, l.prim));
}

/// Uniform in solid angle (spherical triangle, Arvo 1995) where `triangle_measure` allows, else by area.
fn triangle_sample_li(l: Light, p: vec3<f32>, u: vec3<f32>) -> LightSample {
    let tp = triangle_from(l, p);
    let v0 = tp.v0;
    let v1 = tp.v1;
    let v2 = tp.v2;
    let m = triangle_measure_of(v0, v1, v2, p);
    if (m.measure != MEASURE_SOLID_ANGLE) {
        var s = triangle_sample_area(l, p, u.xy);
        s.m = m;
        return s;
    }
    let wi = spherical_triangle_warp(u.xy, v0 - p, v1 - p, v2 - p, m.omega);
    // The light point: wi meets the triangle's plane at t = (v0 − p)·n / (wi·n).
    let n = cross(v1 - v0, v2 - v0);
    let t = dot(v0 - p, n) / dot(wi, n);
    if (!(t > 0.0) || is_nonfinite(t)) { return no_light_sample_in(m); }
    let y = p + t * wi;
    let inv_nn = 1.0 / dot(n, n);
    let b1 = clamp(dot(cross(y - v0, v2 - v0), n) * inv_nn, 0.0, 1.0);
    let b2 = clamp(dot(cross(v1 - v0, y - v0), n) * inv_nn, 0.0, 1.0);
    let sh = scene_tri_shading(l.prim);
    let emitted = material_emission(scene_material(sh.material), triangle_light_uv(l.prim, b1, b2, tp.swapped));
    return LightSample(wi, t, emitted, 1.0 / m.omega, m, make_prim(PRIM_TRIANGLE, l.prim));
}

fn triangle_pdf_li(l: Light, m: LightMeasure, p: vec3<f32>, wi: vec3<f32>, y: vec3<f32>, n_y: vec3<f32>) -> f32 {
    if (m.measure == MEASURE_SOLID_ANGLE) { return 1.0 / m.omega; }
    if (m.measure != MEASURE_AREA) { return 0.0; }
    // By area: (2/|n|)·d² / cos_l with cos_l = |wi·n|/|n|.
    let tp = scene_tri_positions(l.prim);
    let v = y - p;
    let c = abs(dot(wi, cross(tp.v1 - tp.v0, tp.v2 - tp.v0)));
    if (!(c > 0.0)) { return 0.0; }
    return 2.0 * dot(v, v) / c;
}

fn triangle_eval(l: Light, y: Surface, wi: vec3<f32>) -> vec3<f32> { return area_eval(l, y); }

// ---- LIGHT_QUAD: an emissive parallelogram ----

/// A quad light seen from p: how it is sampled (`m`, and for solid angle the spherical rectangle `rect`), with
/// its unit edges x, y, front normal z and edge lengths.
struct QuadLightFrame {
    m: LightMeasure,
    x: vec3<f32>,
    y: vec3<f32>,
    z: vec3<f32>,
    lu: f32,
    lv: f32,
    rect: SphericalRect,
}

/// Spherical-rectangle sampling where accurate (a rectangle, solid-angle mode), else by area; NONE when p sees the
/// back. The frame is set up only for solid angle.
fn quad_frame(q: Quad, p: vec3<f32>) -> QuadLightFrame {
    var f: QuadLightFrame;
    f.m = LightMeasure(MEASURE_NONE, 0.0);
    let c = cross(q.edge_u, q.edge_v);
    let d = q.corner - p;
    if (!(dot(-d, c) > 0.0)) { return f; }
    f.m.measure = MEASURE_AREA;
    if (cfg_light_sampling() != LIGHT_SAMPLING_SOLID_ANGLE) { return f; }
    f.lu = length(q.edge_u);
    f.lv = length(q.edge_v);
    if (!(abs(dot(q.edge_u, q.edge_v)) <= RECT_COS_TOLERANCE * f.lu * f.lv)) { return f; }
    f.x = q.edge_u / f.lu;
    f.y = q.edge_v / f.lv;
    f.z = normalize(c);
    let r = spherical_rect_setup(dot(d, f.x), dot(d, f.y), f.lu, f.lv, -dot(d, f.z));
    if (r.omega >= SPHERICAL_RECT_MIN_SR && r.omega <= SPHERICAL_RECT_MAX_SR) {
        f.m = LightMeasure(MEASURE_SOLID_ANGLE, r.omega);
        f.rect = r;
    }
    return f;
}

/// A light quad as p sees it: a two-sided light seen from behind has its edges swapped (`swapped`; the same
/// points, front facing p), so its uv is (v, u).
struct QuadFromP {
    q: Quad,
    swapped: bool,
}

fn quad_from(l: Light, p: vec3<f32>) -> QuadFromP {
    var q = scene_quad(l.prim);
    if (l.two_sided != 0u && dot(p - q.corner, cross(q.edge_u, q.edge_v)) < 0.0) {
        let e = q.edge_u;
        q.edge_u = q.edge_v;
        q.edge_v = e;
        return QuadFromP(q, true);
    }
    return QuadFromP(q, false);
}

fn quad_measure(l: Light, p: vec3<f32>) -> LightMeasure { return quad_frame(quad_from(l, p).q, p).m; }

/// Uniform by area. Measure: area → solid angle.
fn quad_sample_area(l: Light, p: vec3<f32>, u: vec2<f32>) -> LightSample {
    let qp = quad_from(l, p);
    let q = qp.q;
    let c = cross(q.edge_u, q.edge_v);
    let area = length(c);
    if (!(area > 0.0)) { return no_light_sample(); }
    let y = q.corner + u.x * q.edge_u + u.y * q.edge_v;
    let emitted = material_emission(scene_material(q.material), select(u, u.yx, qp.swapped));
    return area_to_solid_angle(p, y, c / area, 1.0 / area, emitted, make_prim(PRIM_QUAD, l.prim));
}

/// Uniform in solid angle (spherical rectangle, Ureña et al. 2013) where `quad_frame` allows, else by area.
fn quad_sample_li(l: Light, p: vec3<f32>, u: vec3<f32>) -> LightSample {
    let qp = quad_from(l, p);
    let q = qp.q;
    let f = quad_frame(q, p);
    if (f.m.measure != MEASURE_SOLID_ANGLE) {
        var s = quad_sample_area(l, p, u.xy);
        s.m = f.m;
        return s;
    }
    let xy = square_to_spherical_rectangle(u.xy, f.rect);
    let v = xy.x * f.x + xy.y * f.y - f.rect.h * f.z;
    let dist = length(v);
    let st = vec2<f32>((xy.x - f.rect.x0) / f.lu, (xy.y - f.rect.y0) / f.lv);
    let emitted = material_emission(scene_material(q.material), select(st, st.yx, qp.swapped));
    return LightSample(v / dist, dist, emitted, 1.0 / f.rect.omega, f.m, make_prim(PRIM_QUAD, l.prim));
}

fn quad_pdf_li(l: Light, m: LightMeasure, p: vec3<f32>, wi: vec3<f32>, y: vec3<f32>, n_y: vec3<f32>) -> f32 {
    if (m.measure == MEASURE_SOLID_ANGLE) { return 1.0 / m.omega; }
    if (m.measure != MEASURE_AREA) { return 0.0; }
    // By area: d² / (A·cos_l) = d² / |wi·(edge_u × edge_v)|.
    let q = scene_quad(l.prim);
    let v = y - p;
    let c = abs(dot(wi, cross(q.edge_u, q.edge_v)));
    if (!(c > 0.0)) { return 0.0; }
    return dot(v, v) / c;
}

fn quad_eval(l: Light, y: Surface, wi: vec3<f32>) -> vec3<f32> { return area_eval(l, y); }

// ---- LIGHT_SPHERE: an emissive sphere ----

/// 1 − cosθmax of the cone a sphere subtends from p, or a negative value when p is inside (or so close
/// to the surface that the cone is numerically a hemisphere): then the sphere is sampled by area.
/// Written via sin²θmax/(1 + cosθmax) so tiny spheres keep their precision.
fn sphere_cone_one_minus_cos(s: Sphere, p: vec3<f32>) -> f32 {
    let d2 = dot(s.center - p, s.center - p);
    let r2 = s.radius * s.radius;
    if (!(d2 > r2 * 1.0001)) { return -1.0; }
    let sin2 = r2 / d2;
    return sin2 / (1.0 + sqrt(1.0 - sin2));
}

/// Uniform by area over the whole sphere. Points on the far side face away from p and come back as failed
/// samples (pdf 0), so the pdf of the successful ones integrates to the visible fraction of the area.
/// Measure: area → solid angle.
fn sphere_sample_area(prim: u32, p: vec3<f32>, u: vec2<f32>) -> LightSample {
    let s = scene_sphere(prim);
    let n = square_to_uniform_sphere(u);
    let y = s.center + s.radius * n;
    let uv = vec2<f32>(atan2(n.z, n.x) * INV_TWO_PI + 0.5, acos(clamp(n.y, -1.0, 1.0)) * INV_PI);
    let emitted = material_emission(scene_material(s.material), uv);
    return area_to_solid_angle(p, y, n, 1.0 / (4.0 * PI * s.radius * s.radius), emitted, make_prim(PRIM_SPHERE, prim));
}

/// Uniform in the subtended cone (solid-angle mode, p outside), else by area.
fn sphere_measure(l: Light, p: vec3<f32>) -> LightMeasure {
    let omc = sphere_cone_one_minus_cos(scene_sphere(l.prim), p);
    if (cfg_light_sampling() == LIGHT_SAMPLING_SOLID_ANGLE && omc > 0.0) {
        return LightMeasure(MEASURE_SOLID_ANGLE, TWO_PI * omc);
    }
    return LightMeasure(MEASURE_AREA, 0.0);
}

fn sphere_sample_li(l: Light, p: vec3<f32>, u: vec3<f32>) -> LightSample {
    // A far-side point of the area sampler fails, but keeps the measure: other directions from p do meet the light.
    if (cfg_light_sampling() != LIGHT_SAMPLING_SOLID_ANGLE) {
        var a = sphere_sample_area(l.prim, p, u.xy);
        a.m = LightMeasure(MEASURE_AREA, 0.0);
        return a;
    }
    let s = scene_sphere(l.prim);
    let omc = sphere_cone_one_minus_cos(s, p);
    if (omc <= 0.0) {
        var a = sphere_sample_area(l.prim, p, u.xy);
        a.m = LightMeasure(MEASURE_AREA, 0.0);
        return a;
    }
    let to_c = s.center - p;
    let d = length(to_c);
    let f = frame_from_normal(to_c / d);
    let wl = square_to_uniform_cone(u.xy, omc);
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
    let m = LightMeasure(MEASURE_SOLID_ANGLE, TWO_PI * omc);
    return LightSample(wi, t, emitted, square_to_uniform_cone_pdf(omc), m, make_prim(PRIM_SPHERE, l.prim));
}

fn sphere_pdf_li(l: Light, m: LightMeasure, p: vec3<f32>, wi: vec3<f32>, y: vec3<f32>, n_y: vec3<f32>) -> f32 {
    if (m.measure == MEASURE_SOLID_ANGLE) { return 1.0 / m.omega; }
    // By area: d² / (A·cos_l).
    let v = y - p;
    let cos_l = abs(dot(wi, n_y));
    if (!(cos_l > 0.0)) { return 0.0; }
    return dot(v, v) / (l.area * cos_l);
}

fn sphere_eval(l: Light, y: Surface, wi: vec3<f32>) -> vec3<f32> { return area_eval(l, y); }

// ---- LIGHT_CONVEX_LAMP: a closed, convex, round emitter mesh as one light (src/accel/convex_lamps.rs) ----
//
// A lamp's fields: position / direction its stop box (lo / hi, shadow_box = 1), whose centre is the centre of the
// sphere inside the mesh; cos_inner that sphere's radius; cos_outer the rim probability; prim the light index of its
// first face (LIGHT_LAMP_FACE, the faces follow each other); area the number of faces; radiance the emission.
// A LIGHT_LAMP_FACE is a face's triangle light (prim, area, stop box) with tree_trail = its lamp. Rays find faces;
// light samples choose lamps.

fn lamp_center(l: Light) -> vec3<f32> { return 0.5 * (l.position + l.direction); }

/// 1 − cosθmax of the cone of the lamp's inner sphere from p, or a negative value where p is not outside it.
fn lamp_cone_one_minus_cos(l: Light, p: vec3<f32>) -> f32 {
    let v = lamp_center(l) - p;
    let d2 = dot(v, v);
    let r2 = l.cos_inner * l.cos_inner;
    if (!(d2 > r2 * 1.0001)) { return -1.0; }
    let sin2 = r2 / d2;
    return sin2 / (1.0 + sqrt(1.0 - sin2));
}

/// Whether direction w from p meets the lamp's inner sphere.
fn lamp_in_cone(l: Light, p: vec3<f32>, w: vec3<f32>) -> bool {
    let v = lamp_center(l) - p;
    let t = dot(v, w);
    return t > 0.0 && dot(v, v) - t * t <= l.cos_inner * l.cos_inner;
}

/// Solid-angle mode (p outside the inner sphere): the cone, omega its solid angle, and the rim; else by area.
fn convex_lamp_measure(l: Light, p: vec3<f32>) -> LightMeasure {
    let omc = lamp_cone_one_minus_cos(l, p);
    if (cfg_light_sampling() == LIGHT_SAMPLING_SOLID_ANGLE && omc > 0.0) {
        return LightMeasure(MEASURE_SOLID_ANGLE, TWO_PI * omc);
    }
    return LightMeasure(MEASURE_AREA, 0.0);
}

/// Probability of drawing a face by area: the rim's in solid-angle mode, every sample by area.
fn lamp_by_area_share(l: Light, m: LightMeasure) -> f32 {
    return select(1.0, l.cos_outer, m.measure == MEASURE_SOLID_ANGLE);
}

/// With probability 1 − rim a direction uniformly in the inner sphere's cone (it meets the mesh; the shadow ray
/// stops at the stop box, so the point aimed at is the inner sphere's); else a face uniformly and a point on it by
/// area, kept only outside the cone (the rim). By area (area mode): every sample a face and a point, none dropped.
fn convex_lamp_sample_li(l: Light, p: vec3<f32>, u: vec3<f32>) -> LightSample {
    let m = convex_lamp_measure(l, p);
    let by_area = lamp_by_area_share(l, m);
    let faces = u32(l.area);
    if (u.z < by_area) {
        let k = min(u32(u.z / by_area * f32(faces)), faces - 1u);
        var s = triangle_sample_area(scene_light(l.prim + k), p, u.xy);
        if (!(s.pdf > 0.0) || (m.measure == MEASURE_SOLID_ANGLE && lamp_in_cone(l, p, s.wi))) {
            return no_light_sample_in(m);
        }
        s.pdf *= by_area / f32(faces);
        s.m = m;
        return s;
    }
    let omc = m.omega * INV_TWO_PI;
    let to_c = lamp_center(l) - p;
    let d = length(to_c);
    let wl = square_to_uniform_cone(u.xy, omc);
    let wi = normalize(to_world(frame_from_normal(to_c / d), wl));
    let sin2 = wl.x * wl.x + wl.y * wl.y;
    let t = max(d * wl.z - safe_sqrt(l.cos_inner * l.cos_inner - d * d * sin2), 0.0);
    // Any face's triangle leads the shadow ray to the stop box (estimators.wgsl `stop_box_entry`).
    let prim = make_prim(PRIM_TRIANGLE, scene_light(l.prim).prim);
    return LightSample(wi, t, l.radiance, (1.0 - by_area) / m.omega, m, prim);
}

/// Rays find a lamp's faces, not the lamp: no pdf of its own (its faces' is the lamp's), no emission.
fn convex_lamp_pdf_li(l: Light, m: LightMeasure, p: vec3<f32>, wi: vec3<f32>, y: vec3<f32>, n_y: vec3<f32>) -> f32 { return 0.0; }
fn convex_lamp_eval(l: Light, y: Surface, wi: vec3<f32>) -> vec3<f32> { return vec3<f32>(0.0); }

// ---- LIGHT_LAMP_FACE: one face of a convex lamp (never chosen: its lamp is) ----

fn lamp_face_measure(l: Light, p: vec3<f32>) -> LightMeasure { return convex_lamp_measure(scene_light(l.tree_trail), p); }
fn lamp_face_sample_li(l: Light, p: vec3<f32>, u: vec3<f32>) -> LightSample { return no_light_sample(); }
fn lamp_face_eval(l: Light, y: Surface, wi: vec3<f32>) -> vec3<f32> { return area_eval(l, y); }

/// pdf that the lamp of `face` draws wi from p, meeting `face` at y (n_y), given m = its lamp's measure from p.
fn lamp_face_pdf_li(face: Light, m: LightMeasure, p: vec3<f32>, wi: vec3<f32>, y: vec3<f32>, n_y: vec3<f32>) -> f32 {
    if (m.measure != MEASURE_SOLID_ANGLE && m.measure != MEASURE_AREA) { return 0.0; }
    let l = scene_light(face.tree_trail);
    let by_area = lamp_by_area_share(l, m);
    if (m.measure == MEASURE_SOLID_ANGLE && lamp_in_cone(l, p, wi)) { return (1.0 - by_area) / m.omega; }
    return by_area / l.area * triangle_pdf_li(face, LightMeasure(MEASURE_AREA, 0.0), p, wi, y, n_y);
}

/// Whether a ray from o along d certainly finds no emission without being traced: the scene's only emitters are a
/// few convex lamps (`params.lamps_only`) and the ray enters none of their stop boxes (nor starts in one).
const MAX_LAMPS_TESTED: u32 = 8u;
fn finds_no_emission(o: vec3<f32>, d: vec3<f32>) -> bool {
    if (!HAS_CONVEX_LAMPS || params.lamps_only == 0u || params.lamp_count > MAX_LAMPS_TESTED) { return false; }
    return !ray_may_meet_a_lamp(o, d);
}
fn ray_may_meet_a_lamp(o: vec3<f32>, d: vec3<f32>) -> bool {
    for (var k = 0u; k < params.lamp_count; k += 1u) {
        let l = scene_light(params.lamp_first + k);
        if (ray_meets_box(l.position, l.direction, o, d)) { return true; }
    }
    return false;
}

/// A convex lamp that a ray traced only for its emission meets for certain unless something comes before the lamp's
/// stop box: its first face's light, the lamp's radiance and where the ray enters that box (`stop_box_entry`'s
/// rounding), or INVALID and F32_MAX. The ray from o along d meets the lamp's inner sphere, so it meets the lamp's
/// faces; nothing else is in the box (src/accel/isolated_emitters.rs); so if nothing is hit before the box, the
/// first hit is a front face of the lamp, whose emission is the lamp's everywhere. Only in solid-angle mode and
/// where d is in the cone from the shading point p as well: there the light technique's pdf of d does not depend
/// on the face (`lamp_face_pdf_li`), so the face need not be found — a walk into the lamp's own thousands of
/// triangles saved.
struct LampSighting {
    face: u32,
    le: vec3<f32>,
    t_box: f32,
}
fn lamp_in_sight(o: vec3<f32>, d: vec3<f32>, p: vec3<f32>) -> LampSighting {
    var s = LampSighting(INVALID, vec3<f32>(0.0), F32_MAX);
    if (!LAMP_SIGHTING || params.lamp_count > MAX_LAMPS_TESTED || cfg_light_sampling() != LIGHT_SAMPLING_SOLID_ANGLE) { return s; }
    for (var k = 0u; k < params.lamp_count; k += 1u) {
        let l = scene_light(params.lamp_first + k);
        if (!lamp_in_cone(l, o, d) || !lamp_in_cone(l, p, d)) { continue; }
        let b = box_slabs(l.position, l.direction, o, d);
        let entry = max(max(b.near.x, b.near.y), b.near.z) * (1.0 + 1e-5);
        if (entry > 0.0 && entry < s.t_box) { s = LampSighting(l.prim, l.radiance, entry); }
    }
    return s;
}

/// The light a light found by a ray counts as when chosen: a lamp's face (the entries from num_lights on) its lamp.
fn chosen_light(i: u32) -> u32 {
    if (!HAS_CONVEX_LAMPS || i == INVALID || i < params.num_lights) { return i; }
    return scene_light(i).tree_trail;
}

// ---- LIGHT_POINT, LIGHT_SPOT, LIGHT_DIRECTIONAL: delta lights (light sampling alone finds them) ----

/// Point light: irradiance-like radiance I/d², pdf 1 (delta).
fn point_sample_li(l: Light, p: vec3<f32>, u: vec3<f32>) -> LightSample {
    let v = l.position - p;
    let d2 = dot(v, v);
    if (!(d2 > 0.0)) { return no_light_sample(); }
    let dist = sqrt(d2);
    return LightSample(v / dist, dist, l.radiance / d2, 1.0, LightMeasure(MEASURE_DISCRETE, 0.0), INVALID);
}
fn point_measure(l: Light, p: vec3<f32>) -> LightMeasure { return LightMeasure(MEASURE_DISCRETE, 0.0); }
fn point_pdf_li(l: Light, m: LightMeasure, p: vec3<f32>, wi: vec3<f32>, y: vec3<f32>, n_y: vec3<f32>) -> f32 { return 0.0; }
fn point_eval(l: Light, y: Surface, wi: vec3<f32>) -> vec3<f32> { return vec3<f32>(0.0); }

/// Spot light: a point light times a smooth falloff between the outer and inner cone.
fn spot_sample_li(l: Light, p: vec3<f32>, u: vec3<f32>) -> LightSample {
    var s = point_sample_li(l, p, u);
    let c = dot(-s.wi, l.direction);
    s.radiance *= smoothstep(l.cos_outer, l.cos_inner, c);
    return s;
}
fn spot_measure(l: Light, p: vec3<f32>) -> LightMeasure { return LightMeasure(MEASURE_DISCRETE, 0.0); }
fn spot_pdf_li(l: Light, m: LightMeasure, p: vec3<f32>, wi: vec3<f32>, y: vec3<f32>, n_y: vec3<f32>) -> f32 { return 0.0; }
fn spot_eval(l: Light, y: Surface, wi: vec3<f32>) -> vec3<f32> { return vec3<f32>(0.0); }

/// Directional light: light travelling along `direction`, irradiance in `radiance`.
fn directional_sample_li(l: Light, p: vec3<f32>, u: vec3<f32>) -> LightSample {
    return LightSample(-l.direction, F32_MAX, l.radiance, 1.0, LightMeasure(MEASURE_DISCRETE, 0.0), INVALID);
}
fn directional_measure(l: Light, p: vec3<f32>) -> LightMeasure { return LightMeasure(MEASURE_DISCRETE, 0.0); }
fn directional_pdf_li(l: Light, m: LightMeasure, p: vec3<f32>, wi: vec3<f32>, y: vec3<f32>, n_y: vec3<f32>) -> f32 { return 0.0; }
fn directional_eval(l: Light, y: Surface, wi: vec3<f32>) -> vec3<f32> { return vec3<f32>(0.0); }

// ---- LIGHT_ENVIRONMENT: constant or equirectangular, at infinity (a ray that misses everything finds it) ----

/// Direction → equirectangular (u, v) in map space: u = 0.5 looks down −Z, v = 0 is +Y;
/// the map is rotated by `env_rotation` radians about +Y. θ from atan2 (acos(w.y) loses digits at the poles), and
/// the accurate atan2 so that directions map to the texels `env_sample` sampled them in.
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

/// Whether the environment's radiance is one constant (no map).
fn env_constant() -> bool {
    return ENV_KIND == 1u || (ENV_KIND == 3u && params.env_width == 0u);
}

/// Whether the environment is sampled uniformly on the sphere (a constant one seen from no particular surface, or by
/// the setting).
fn env_uniform() -> bool {
    return env_constant() || cfg_env_sampling() == ENV_SAMPLING_UNIFORM;
}

/// Whether a constant environment is sampled by the cosine about the receiver's normal `n` (0: no normal, as for
/// surfaces that transmit): L·cos is then ∝ cos, so this is importance sampling of the light times the cosine —
/// no sample is spent below the surface, where uniform sampling puts half of them. `--env-sampling uniform` keeps
/// the uniform sphere; `guided` mixes the cosine with the learned guide (`env_guide_slot`).
fn env_cosine(n: vec3<f32>) -> bool {
    return env_constant() && cfg_env_sampling() != ENV_SAMPLING_UNIFORM && any(n != vec3<f32>(0.0));
}

/// Radiance arriving from direction w (piecewise constant over texels, matching the sampling density).
fn env_radiance(w: vec3<f32>) -> vec3<f32> {
    if (ENV_KIND == 0u) { return vec3<f32>(0.0); }
    if (ENV_KIND == 1u || (ENV_KIND == 3u && params.env_width == 0u)) { return params.env_constant * params.env_scale; }
    return load_env_texels(env_texel_index(env_direction_to_uv(w))).xyz * params.env_scale;
}

/// pdf (solid angle) of `env_sample(·, p, n)` producing w: max(w·n, 0)/π (a constant map, cosine about n; guided:
/// mixed with the guide of p's slot), 1/4π
/// (uniform), or density_uv / (2π² sinθ) (importance). sinθ = |w.xz| (1 − w.y² loses its digits near the poles).
fn env_pdf(w: vec3<f32>, p: vec3<f32>, n: vec3<f32>) -> f32 {
    if (ENV_KIND == 0u) { return 0.0; }
    if (env_cosine(n)) {
        // Below the surface the density is 0 whatever the guide holds: `env_sample` drops the guide's samples there.
        let cosine = max(dot(w, n), 0.0) * INV_PI;
        let g = env_guide_at(p, n);
        if (g.slot == INVALID || !(cosine > 0.0)) { return cosine; }
        return env_guided_pdf(g.slot, g.alpha, env_guide_bin(w), cosine);
    }
    if (env_uniform()) { return INV_FOUR_PI; }
    let uv = env_direction_to_uv(w);
    let density_uv = load_env_texels(env_texel_index(uv)).w;
    let sin_theta = length(w.xz);
    return density_uv / (2.0 * PI * PI * max(sin_theta, 1e-7));
}

/// Cosine-weighted about the receiver's normal n (a constant map: `env_cosine`), uniform on the sphere, or a texel
/// ∝ luminance·sinθ by the alias table (column from u.z, coin from u.y, which is then reused) and uniform in (u, v)
/// inside the texel, so pdf_ω = density_uv / (2π² sinθ). The pdf returned is the chosen texel's: at a texel edge,
/// f32 rounding may map the direction into the neighbour, where `env_pdf` (and a black neighbour's radiance) would
/// differ on that measure-zero set. Measure: solid angle.
fn env_sample(u: vec3<f32>, p: vec3<f32>, n: vec3<f32>) -> LightSample {
    if (env_cosine(n)) {
        let g = env_guide_at(p, n);
        var wi: vec3<f32>;
        var b: u32;
        if (u.z < g.alpha) {
            // The guide's share: its bins cover the whole sphere, so a direction below the surface is a lost sample.
            b = env_guide_pick(g.slot, u.z / g.alpha);
            wi = env_guide_bin_direction(b, u.xy);
        } else {
            let local = square_to_cosine_hemisphere(u.xy);
            if (!(local.z > 0.0)) { return no_light_sample(); }
            wi = to_world(frame_from_normal(n), local);
            if (g.slot != INVALID) { b = env_guide_bin(wi); }
        }
        // One density for both shares (one guide lookup compiled, not two: lavapipe's start-up is its code's size).
        let cosine = dot(wi, n);
        if (!(cosine > 0.0)) { return no_light_sample(); }
        var pdf = cosine * INV_PI;
        if (g.slot != INVALID) { pdf = env_guided_pdf(g.slot, g.alpha, b, pdf); }
        if (!(pdf > 0.0)) { return no_light_sample(); }
        return LightSample(wi, F32_MAX, env_radiance(wi), pdf, LightMeasure(MEASURE_SOLID_ANGLE, 0.0), INVALID);
    }
    if (env_uniform()) {
        let wi = square_to_uniform_sphere(u.xy);
        return LightSample(wi, F32_MAX, env_radiance(wi), INV_FOUR_PI, LightMeasure(MEASURE_SOLID_ANGLE, 0.0), INVALID);
    }
    let texels = params.env_width * params.env_height;
    let pick = alias_sample2(0u, texels, u.z, u.y, true);
    let x = pick.index % params.env_width;
    let y = pick.index / params.env_width;
    let uv = vec2<f32>((f32(x) + u.x) / f32(params.env_width), (f32(y) + pick.u) / f32(params.env_height));
    let wi = env_uv_to_direction(uv);
    let texel = load_env_texels(pick.index);
    let pdf = texel.w / (2.0 * PI * PI * max(length(wi.xz), 1e-7));
    if (!(pdf > 0.0)) { return no_light_sample(); }
    return LightSample(wi, F32_MAX, texel.xyz * params.env_scale, pdf, LightMeasure(MEASURE_SOLID_ANGLE, 0.0), INVALID);
}

// The environment alone depends on the receiver's normal n (`env_cosine`); the other kinds ignore it.
fn environment_sample_li(l: Light, p: vec3<f32>, n: vec3<f32>, u: vec3<f32>) -> LightSample { return env_sample(u, p, n); }
fn environment_measure(l: Light, p: vec3<f32>) -> LightMeasure { return LightMeasure(MEASURE_SOLID_ANGLE, 0.0); }
fn environment_pdf_li(l: Light, m: LightMeasure, p: vec3<f32>, n: vec3<f32>, wi: vec3<f32>) -> f32 {
    return env_pdf(wi, p, n);
}
fn environment_eval(l: Light, y: Surface, wi: vec3<f32>) -> vec3<f32> { return env_radiance(wi); }

// ---- the dispatchers: one case per kind; a kind the scene lacks is compiled out by its HAS_* constant ----

/// Samples light i as seen from p (without the selection probability). n: the receiver's normal where it reflects
/// only, else 0 (`env_receiver`): a constant environment is then sampled by the cosine about it.
fn light_sample_li(i: u32, p: vec3<f32>, n: vec3<f32>, u: vec3<f32>) -> LightSample {
    let l = scene_light(i);
    switch (l.kind) {
        case LIGHT_TRIANGLE: { if (HAS_TRIANGLE_LIGHTS) { return triangle_sample_li(l, p, u); } }
        case LIGHT_SPHERE: { if (HAS_SPHERE_LIGHTS) { return sphere_sample_li(l, p, u); } }
        case LIGHT_QUAD: { if (HAS_QUAD_LIGHTS) { return quad_sample_li(l, p, u); } }
        case LIGHT_POINT: { if (HAS_DELTA_LIGHTS) { return point_sample_li(l, p, u); } }
        case LIGHT_SPOT: { if (HAS_DELTA_LIGHTS) { return spot_sample_li(l, p, u); } }
        case LIGHT_DIRECTIONAL: { if (HAS_DELTA_LIGHTS) { return directional_sample_li(l, p, u); } }
        case LIGHT_ENVIRONMENT: { if (ENV_KIND != 0u) { return environment_sample_li(l, p, n, u); } }
        case LIGHT_CONVEX_LAMP: { if (HAS_CONVEX_LAMPS) { return convex_lamp_sample_li(l, p, u); } }
        case LIGHT_LAMP_FACE: { if (HAS_CONVEX_LAMPS) { return lamp_face_sample_li(l, p, u); } }
        default: {}
    }
    return no_light_sample();
}

/// How light i is sampled from p.
fn light_measure(i: u32, p: vec3<f32>) -> LightMeasure {
    let l = scene_light(i);
    switch (l.kind) {
        case LIGHT_TRIANGLE: { if (HAS_TRIANGLE_LIGHTS) { return triangle_measure(l, p); } }
        case LIGHT_SPHERE: { if (HAS_SPHERE_LIGHTS) { return sphere_measure(l, p); } }
        case LIGHT_QUAD: { if (HAS_QUAD_LIGHTS) { return quad_measure(l, p); } }
        case LIGHT_POINT: { if (HAS_DELTA_LIGHTS) { return point_measure(l, p); } }
        case LIGHT_SPOT: { if (HAS_DELTA_LIGHTS) { return spot_measure(l, p); } }
        case LIGHT_DIRECTIONAL: { if (HAS_DELTA_LIGHTS) { return directional_measure(l, p); } }
        case LIGHT_ENVIRONMENT: { if (ENV_KIND != 0u) { return environment_measure(l, p); } }
        case LIGHT_CONVEX_LAMP: { if (HAS_CONVEX_LAMPS) { return convex_lamp_measure(l, p); } }
        case LIGHT_LAMP_FACE: { if (HAS_CONVEX_LAMPS) { return lamp_face_measure(l, p); } }
        default: {}
    }
    return LightMeasure(MEASURE_NONE, 0.0);
}

/// pdf (solid angle, without selection) that `light_sample_li(i, p, n, ·)` draws wi, meeting the light at y (n_y),
/// given m = light_measure(i, p).
fn light_pdf_li(i: u32, m: LightMeasure, p: vec3<f32>, n: vec3<f32>, wi: vec3<f32>, y: vec3<f32>, n_y: vec3<f32>) -> f32 {
    let l = scene_light(i);
    switch (l.kind) {
        case LIGHT_TRIANGLE: { if (HAS_TRIANGLE_LIGHTS) { return triangle_pdf_li(l, m, p, wi, y, n_y); } }
        case LIGHT_SPHERE: { if (HAS_SPHERE_LIGHTS) { return sphere_pdf_li(l, m, p, wi, y, n_y); } }
        case LIGHT_QUAD: { if (HAS_QUAD_LIGHTS) { return quad_pdf_li(l, m, p, wi, y, n_y); } }
        case LIGHT_POINT: { if (HAS_DELTA_LIGHTS) { return point_pdf_li(l, m, p, wi, y, n_y); } }
        case LIGHT_SPOT: { if (HAS_DELTA_LIGHTS) { return spot_pdf_li(l, m, p, wi, y, n_y); } }
        case LIGHT_DIRECTIONAL: { if (HAS_DELTA_LIGHTS) { return directional_pdf_li(l, m, p, wi, y, n_y); } }
        case LIGHT_ENVIRONMENT: { if (ENV_KIND != 0u) { return environment_pdf_li(l, m, p, n, wi); } }
        case LIGHT_CONVEX_LAMP: { if (HAS_CONVEX_LAMPS) { return convex_lamp_pdf_li(l, m, p, wi, y, n_y); } }
        case LIGHT_LAMP_FACE: { if (HAS_CONVEX_LAMPS) { return lamp_face_pdf_li(l, m, p, wi, y, n_y); } }
        default: {}
    }
    return 0.0;
}

/// Radiance light i emits along wi from the point y a ray found.
fn light_eval(i: u32, y: Surface, wi: vec3<f32>) -> vec3<f32> {
    let l = scene_light(i);
    switch (l.kind) {
        case LIGHT_TRIANGLE: { if (HAS_TRIANGLE_LIGHTS) { return triangle_eval(l, y, wi); } }
        case LIGHT_SPHERE: { if (HAS_SPHERE_LIGHTS) { return sphere_eval(l, y, wi); } }
        case LIGHT_QUAD: { if (HAS_QUAD_LIGHTS) { return quad_eval(l, y, wi); } }
        case LIGHT_POINT: { if (HAS_DELTA_LIGHTS) { return point_eval(l, y, wi); } }
        case LIGHT_SPOT: { if (HAS_DELTA_LIGHTS) { return spot_eval(l, y, wi); } }
        case LIGHT_DIRECTIONAL: { if (HAS_DELTA_LIGHTS) { return directional_eval(l, y, wi); } }
        case LIGHT_ENVIRONMENT: { if (ENV_KIND != 0u) { return environment_eval(l, y, wi); } }
        case LIGHT_CONVEX_LAMP: { if (HAS_CONVEX_LAMPS) { return convex_lamp_eval(l, y, wi); } }
        case LIGHT_LAMP_FACE: { if (HAS_CONVEX_LAMPS) { return lamp_face_eval(l, y, wi); } }
        default: {}
    }
    return vec3<f32>(0.0);
}
