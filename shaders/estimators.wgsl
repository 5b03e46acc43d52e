// estimators.wgsl — the lecture's shade(x, V, brdf, N): direct illumination at a shading point, built
// from techniques that sample / pdf / eval. Two families of techniques:
//   * direction techniques (uniform hemisphere, cosine hemisphere, BSDF): sample w, trace, find emitters;
//   * light techniques (lights.wgsl): sample a point/direction on an emitter, test a shadow ray.
// `--strategy` picks which run; `mis` runs both and weights them (multi-sample or one-sample MIS). The first
// direction sample is also the path's continuation: in path mode shade() returns it untraced, and the path loop
// (integrator.wgsl) traces it once, for the next vertex and the emission it finds there alike.

/// The shading point as the techniques see it.
struct ShadingCtx {
    x: Surface,
    frame: Frame,
    wo: vec3<f32>,        // V in the local frame
    brdf: BsdfParams,
    id: SampleId,
    bounce: u32,
}

/// The shading point x, with material m, seen along the ray direction d that found it.
fn shading_ctx(x: Surface, m: Material, d: vec3<f32>, id: SampleId, bounce: u32) -> ShadingCtx {
    var c: ShadingCtx;
    c.x = x;
    c.brdf = material_bsdf(m, x.uv, x.front);
    // Seen from behind its shading normal (the geometric normal faces the viewer, the interpolated one does not),
    // an opaque surface is shaded as its back side: in the frame of −ns, as pbrt-v4's two-sided BxDFs and
    // Mitsuba 3's `twosided` do, so that such pixels (creases, silhouettes of smooth-shaded meshes) converge to
    // what their references show. A transmitting BSDF keeps the geometric normal: its inside is the geometric
    // back (docs/materials.md, "Which side is inside").
    if (dot(x.ns, -d) < 0.0) { c.x.ns = select(-x.ns, x.ng, bsdf_transmits(c.brdf)); }
    c.frame = frame_from_normal(c.x.ns);
    c.wo = to_local(c.frame, -d);
    c.id = id;
    c.bounce = bounce;
    return c;
}

// ---- direction techniques ----

/// The direction technique a strategy uses at c: uniform, cosine, or the BSDF (also for light / mis). Surfaces
/// that transmit or have delta lobes always use the BSDF: the hemisphere techniques cannot reach those directions.
fn direction_kind(c: ShadingCtx) -> u32 {
    if (bsdf_transmits(c.brdf) || bsdf_is_delta(c.brdf) || bsdf_has_delta_lobe(c.brdf)) { return STRATEGY_BSDF; }
    if (cfg_strategy() == STRATEGY_UNIFORM || cfg_strategy() == STRATEGY_COSINE) { return cfg_strategy(); }
    return STRATEGY_BSDF;
}

/// The normal a light sample may use to skip directions a shading point cannot receive from (`light_sample_li`):
/// its shading normal n where its BSDF only reflects, 0 where it transmits (light arrives from both sides).
fn env_receiver(n: vec3<f32>, transmits: bool) -> vec3<f32> {
    return select(n, vec3<f32>(0.0), transmits);
}

/// Whether world direction w (local wi) leaves c on a side its BSDF does not allow. Where the BSDF transmits, the
/// geometric surface decides: a reflection leaves above it and a transmission below it (a shading normal must not
/// turn one into the other). An opaque BSDF is judged in its shading frame alone, as pbrt-v4's BxDFs and Mitsuba 3's
/// are: a reflection may leave below the geometric surface where the shading normal leans past it, and its ray then
/// starts on that side (`spawn_origin`). A closed mesh blocks such rays itself; an open one lets the sky in there,
/// as both references do (docs/materials.md, "A shading normal that faces away from the viewer").
fn wrong_side(c: ShadingCtx, w: vec3<f32>, wi: vec3<f32>) -> bool {
    return bsdf_transmits(c.brdf) && ((dot(w, c.x.ng) > 0.0) != (wi.z > 0.0) || wi.z == 0.0);
}

/// pdf (solid angle) of the direction technique producing local direction wi.
fn direction_pdf(c: ShadingCtx, wi: vec3<f32>) -> f32 {
    switch (direction_kind(c)) {
        case STRATEGY_UNIFORM: { return square_to_uniform_hemisphere_pdf(wi); }
        case STRATEGY_COSINE: { return square_to_cosine_hemisphere_pdf(wi); }
        default: { return bsdf_pdf(c.brdf, c.wo, wi); }
    }
}

/// Samples the direction technique: local wi and its pdf (0 = failed). f is set (and meant) only for a delta
/// sample (`delta`): the others take bsdf_eval at wi.
fn direction_sample(c: ShadingCtx, j: u32) -> BsdfSample {
    let base = dim_base(c.bounce, j);
    let u = sample_2d(c.id, base + DIM_BSDF_UV);
    var s: BsdfSample;
    s.f = vec3<f32>(0.0);
    s.delta = false;
    switch (direction_kind(c)) {
        case STRATEGY_UNIFORM: {
            s.wi = square_to_uniform_hemisphere(u);
            s.pdf = square_to_uniform_hemisphere_pdf(s.wi);
        }
        case STRATEGY_COSINE: {
            s.wi = square_to_cosine_hemisphere(u);
            s.pdf = square_to_cosine_hemisphere_pdf(s.wi);
        }
        default: {
            s = bsdf_sample(c.brdf, c.wo, sample_1d(c.id, base + DIM_BSDF_LOBE), u);
        }
    }
    return s;
}

/// f at a direction sample: the sample's own for a delta lobe, bsdf_eval otherwise.
fn direction_f(c: ShadingCtx, ds: BsdfSample) -> vec3<f32> {
    if (ds.delta) { return ds.f; }
    return bsdf_eval(c.brdf, c.wo, ds.wi);
}

/// Spawns a ray leaving the surface along world direction w (offset to the side w points to).
fn spawn_origin(x: Surface, w: vec3<f32>) -> vec3<f32> {
    return offset_ray_origin_scaled(x.p, select(-x.ng, x.ng, dot(w, x.ng) > 0.0), params.offset_scale);
}

/// Where a shadow ray from o along d enters the stop box of the isolated emitter that light primitive `prim` belongs
/// to (src/accel/isolated_emitters.rs: nothing else is in that box, and no part of the emitter can hide a point of
/// it that a light sample aims at), or F32_MAX: no such box, or o inside it. Rounding may only move the stop later
/// (further into the box, which is empty but for the emitter), never earlier.
fn stop_box_entry(prim: u32, o: vec3<f32>, d: vec3<f32>) -> f32 {
    if !HAS_TRIANGLE_LIGHTS || prim_kind(prim) != PRIM_TRIANGLE {
        return F32_MAX;
    }
    let li = scene_tri_light(prim & PRIM_INDEX_MASK);
    if li == INVALID || load_lights(li).shadow_box == 0u {
        return F32_MAX;
    }
    let lamp = load_lights(li);
    let s = box_slabs(lamp.position, lamp.direction, o, d);
    let entry = max(max(s.near.x, s.near.y), s.near.z);
    if !(entry > 0.0) {
        return F32_MAX;
    }
    // Each plane's t is (lo − o) · (1/d) with three roundings, each relative to its own result (a float
    // subtraction is exact but for the rounding of the difference), so within 3 · 2⁻²⁴ of t: 1e-5 of t is far beyond.
    return entry * (1.0 + 1e-5);
}

/// The t at which the ray from o along d crosses the box lo..hi's near and far plane of each axis.
struct BoxSlabs {
    near: vec3<f32>,
    far: vec3<f32>,
}
fn box_slabs(lo: vec3<f32>, hi: vec3<f32>, o: vec3<f32>, d: vec3<f32>) -> BoxSlabs {
    // A direction component near 0 takes a tiny stand-in of its sign: that slab's planes then lie at ±huge t,
    // as they should (never NaN from 0 · ∞).
    let sgn = select(vec3<f32>(1.0), vec3<f32>(-1.0), d < vec3<f32>(0.0));
    let inv = 1.0 / select(d, sgn * 1e-30, abs(d) < vec3<f32>(1e-30));
    let t0 = (lo - o) * inv;
    let t1 = (hi - o) * inv;
    return BoxSlabs(min(t0, t1), max(t0, t1));
}

/// Whether the ray from o along d (t > 0) meets the box lo..hi or starts in it; rounding errs towards yes.
fn ray_meets_box(lo: vec3<f32>, hi: vec3<f32>, o: vec3<f32>, d: vec3<f32>) -> bool {
    let s = box_slabs(lo, hi, o, d);
    let near = max(max(s.near.x, s.near.y), s.near.z);
    let far = min(min(s.far.x, s.far.y), s.far.z);
    return far * (1.0 + 1e-5) >= max(near, 0.0) * (1.0 - 1e-5);
}

/// Whether nothing blocks the segment from x to the light sample's point (or direction, for distant lights).
fn unoccluded(x: Surface, ls: LightSample) -> bool {
    let o = spawn_origin(x, ls.wi);
    // The shadow ray runs from the offset origin o to the light point y and stops just short of y, so the
    // emitter itself is no occluder. Aim at y from o (not along wi from x.p): at grazing angles a ray
    // parallel to wi but offset by o − x.p reaches the light's plane well before distance |y − x.p|.
    var shadow_dir = ls.wi;
    var t_max = F32_MAX;
    if (ls.dist < F32_MAX) {
        let to_y = x.p + ls.wi * ls.dist - o;
        let len = length(to_y);
        shadow_dir = to_y / len;
        // Stop short of y by more than y's own rounding error (~2^-23·|y| per coordinate), which a relative
        // 1e-5 of a short shadow ray far from the origin is not.
        let y_err = 64.0 * 1.2e-7 * (max(max(abs(x.p.x), abs(x.p.y)), abs(x.p.z)) + len);
        t_max = len - max(len * 1e-5, y_err);
        if (t_max <= 0.0) { return false; }
        t_max = min(t_max, stop_box_entry(ls.prim, o, shadow_dir));
    }
    rays_traced += 1u;
    return !trace_any_except(o, shadow_dir, t_max, ls.prim);
}

fn mis_on() -> bool { return cfg_strategy() == STRATEGY_MIS; }

// ---- the lecture's two MIS blocks (Veach §9.2; pbrt-v4's SampleLd, and PathIntegrator::Li for the second).
// Each technique's sample is weighted against the other's pdf of the same direction, with the sample counts
// n_l = --light-samples and n_d = --bsdf-samples.

/// A light-technique sample's estimate, and how its light is sampled from the shading point.
struct LightEstimate {
    radiance: vec3<f32>,
    m: LightMeasure,
}

/// Block 1, the light technique: choose a light, sample it, test visibility, weight against the direction
/// technique's pdf. L·f·cos / (pmf·pdf).
fn light_technique(c: ShadingCtx, j: u32) -> LightEstimate {
    var out = LightEstimate(vec3<f32>(0.0), LightMeasure(MEASURE_NONE, 0.0));
    if (params.num_lights == 0u) { return out; }
    // A delta-only BSDF is zero in every direction a light sample can take: no shadow ray.
    if (bsdf_is_delta(c.brdf)) { return out; }
    if (cfg_light_select() == LIGHT_SELECT_RIS || cfg_light_select() == LIGHT_SELECT_TREE_RIS) {
        return ris_light_technique(c, j);
    }
    let base = dim_base(c.bounce, j);
    let pick = select_light(sample_1d(c.id, base + DIM_LIGHT_SELECT), c.x.p, c.x.ns);
    let li = pick.index;
    let pmf = pick.pmf;
    let u = vec3<f32>(sample_2d(c.id, base + DIM_LIGHT_UV), sample_1d(c.id, base + DIM_LIGHT_EXTRA));
    let ls = light_sample_li(li, c.x.p, env_receiver(c.x.ns, bsdf_transmits(c.brdf)), u);
    out.m = ls.m;
    if (!(ls.pdf > 0.0) || !(pmf > 0.0)) { return out; }
    // The light must be on a side the BSDF allows, by both the shading and the geometric normal.
    let cos_s = dot(ls.wi, c.x.ns);
    let wi = to_local(c.frame, ls.wi);
    if (cos_s == 0.0 || (cos_s < 0.0 && !bsdf_transmits(c.brdf)) || wrong_side(c, ls.wi, wi)) { return out; }
    let f = bsdf_eval(c.brdf, c.wo, wi);
    if (all(f * ls.radiance == vec3<f32>(0.0))) { return out; }
    let visible = unoccluded(c.x, ls);
    if (ENV_KIND != 0u && li == params.env_light) {
        env_guide_learn_shadow_ray(c.x.p, env_receiver(c.x.ns, bsdf_transmits(c.brdf)), ls.wi, visible);
    }
    if (!visible) { return out; }
    let p_light = pmf * ls.pdf;
    var w = 1.0;
    if (mis_on() && ls.m.measure != MEASURE_DISCRETE) {
        w = mis_weight(f32(params.light_samples), p_light, f32(params.bsdf_samples), direction_pdf(c, wi));
    }
    out.radiance = w * ls.radiance * f * abs(cos_s) / p_light;
    return out;
}

/// One light-sample candidate of RIS: the sample, f at its direction, and its target value p̂ = lum(f·L·cos).
struct RisCandidate {
    ls: LightSample,
    f_cos: vec3<f32>,
    p_hat: f32,
}

/// A candidate drawn with u = (selection, uv, extra): a light by power (tree-ris: by the tree), a point on it; p̂ = 0 where it cannot
/// contribute (below either hemisphere, no sample).
fn ris_candidate(c: ShadingCtx, u: vec4<f32>) -> RisCandidate {
    var r = RisCandidate(no_light_sample(), vec3<f32>(0.0), 0.0);
    let pick = select_light(u.x, c.x.p, c.x.ns);
    r.ls = light_sample_li(pick.index, c.x.p, env_receiver(c.x.ns, bsdf_transmits(c.brdf)), u.yzw);
    r.ls.pdf *= pick.pmf;
    let cos_s = dot(r.ls.wi, c.x.ns);
    let wi = to_local(c.frame, r.ls.wi);
    if (!(r.ls.pdf > 0.0) || cos_s == 0.0 || (cos_s < 0.0 && !bsdf_transmits(c.brdf)) || wrong_side(c, r.ls.wi, wi)) {
        return r;
    }
    r.f_cos = bsdf_eval(c.brdf, c.wo, wi) * abs(cos_s);
    r.p_hat = luminance(r.f_cos * r.ls.radiance);
    return r;
}

/// Block 1 by resampled importance sampling (Talbot et al. 2005): M = --ris-candidates candidates from the source
/// density p_src = pmf · pdf_li (pmf by power for `ris`, by the light tree for `tree-ris`), one kept with probability ∝ w = p̂/p_src (a one-slot reservoir), then one
/// shadow ray. The kept y counts f·L·cos · W with W = (Σw / M) / p̂(y), whose expectation given y is 1/p(y) of the
/// resampled density, so the estimate is unbiased wherever p̂ > 0 where f·L·cos ≠ 0 (luminance of positive rgb).
/// MIS: RIS's own density has no closed form, so both techniques weigh with p_src standing in for it. Any weights
/// that sum to one at each direction keep the sum of the two techniques unbiased (Veach 1997, §9.2): the choice
/// moves variance only. Candidate 0 takes the sampler's dimensions; the others and the reservoir's coin are hashed.
fn ris_light_technique(c: ShadingCtx, j: u32) -> LightEstimate {
    var out = LightEstimate(vec3<f32>(0.0), LightMeasure(MEASURE_NONE, 0.0));
    let base = dim_base(c.bounce, j);
    let m = max(params.ris_candidates, 1u);
    var kept = RisCandidate(no_light_sample(), vec3<f32>(0.0), 0.0);
    var w_sum = 0.0;
    for (var k = 0u; k < m; k += 1u) {
        var u = vec4<f32>(sample_1d(c.id, base + DIM_LIGHT_SELECT), sample_2d(c.id, base + DIM_LIGHT_UV),
                          sample_1d(c.id, base + DIM_LIGHT_EXTRA));
        let stream = hash4(c.id.pixel, c.id.index, base ^ (params.seed * 0x9e3779b9u), k);
        if (k > 0u) {
            u = vec4<f32>(bits_to_unit(pcg_hash(stream)), bits_to_unit(pcg_hash(stream + 1u)),
                          bits_to_unit(pcg_hash(stream + 2u)), bits_to_unit(pcg_hash(stream + 3u)));
        }
        let cand = ris_candidate(c, u);
        if (k == 0u) { out.m = cand.ls.m; }
        if (!(cand.p_hat > 0.0)) { continue; }
        let w = cand.p_hat / cand.ls.pdf;
        w_sum += w;
        if (bits_to_unit(pcg_hash(stream + 4u)) * w_sum < w) { kept = cand; }
    }
    if (!(kept.p_hat > 0.0) || !(w_sum > 0.0) || !unoccluded(c.x, kept.ls)) { return out; }
    var weight = 1.0;
    if (mis_on() && kept.ls.m.measure != MEASURE_DISCRETE) {
        let wi = to_local(c.frame, kept.ls.wi);
        weight = mis_weight(f32(params.light_samples), kept.ls.pdf, f32(params.bsdf_samples), direction_pdf(c, wi));
    }
    out.radiance = weight * kept.ls.radiance * kept.f_cos * (w_sum / f32(m) / kept.p_hat);
    return out;
}

/// What a traced direction found: the emitted radiance arriving along it, the light that emits it (INVALID: none),
/// and whether it hit a surface (`surface`: the path's next vertex) or escaped to the environment. A sighted lamp
/// (`lamp_in_sight`) is neither.
struct Found {
    le: vec3<f32>,
    light: u32,
    surface: Surface,
    at_surface: bool,
    escaped: bool,
}

/// What the ray o + t·w found at `hit`: a surface (an area light's eval there) or, for a miss, the environment.
fn found_emission(o: vec3<f32>, w: vec3<f32>, hit: Hit) -> Found {
    var r: Found;
    r.le = vec3<f32>(0.0);
    r.light = INVALID;
    if (hit.prim == INVALID) {
        r.escaped = true;
        r.light = params.env_light;
        if (r.light != INVALID) { r.le = env_radiance(w); }
        return r;
    }
    r.at_surface = true;
    r.surface = surface_at(hit, o, w);
    r.light = r.surface.light;
    if (r.light != INVALID) { r.le = light_eval(r.light, r.surface, w); }
    return r;
}

/// Traces direction sample s from o (counted in `rays_traced`). `emission_only`: traced only for the emission it
/// finds (every direction sample in direct mode, a path's last): towards a convex lamp's inner sphere it then stops
/// at the lamp's stop box, and if nothing is hit before it, it finds the lamp (`lamp_in_sight`).
fn trace_found(o: vec3<f32>, s: DirectionSample, emission_only: bool) -> Found {
    rays_traced += 1u;
    var sight = LampSighting(INVALID, vec3<f32>(0.0), F32_MAX);
    if (emission_only) { sight = lamp_in_sight(o, s.w, s.p); }
    let hit = trace_closest(o, s.w, sight.t_box);
    if (lamp_sighted(sight, hit)) { return lamp_found(sight); }
    return found_emission(o, s.w, hit);
}

/// Whether a ray traced up to `sight`'s stop box found its lamp: nothing hit before the box.
fn lamp_sighted(sight: LampSighting, hit: Hit) -> bool {
    return sight.face != INVALID && hit.prim == INVALID;
}

/// The emission of a sighted lamp: found on one of its faces (which one is not needed: `lamp_in_sight`).
fn lamp_found(sight: LampSighting) -> Found {
    var r: Found;
    r.light = sight.face;
    r.le = sight.le;
    return r;
}

/// Whether the measure of the first light sample at a shading point is that of any light its direction samples
/// hit: one light (the one sampled), sampled at every vertex (not one-sample MIS). Saves a second
/// spherical-polygon setup per vertex. Fixed per pipeline.
fn light_measure_known() -> bool {
    return !MANY_LIGHTS && cfg_mis_kind() == MIS_MULTI;
}

/// A direction technique's sample, as the emission it finds is weighted: the shading point it leaves (p, shading
/// normal n; `transmits`: its BSDF does), its direction w and pdf, and the measure of the first light sample taken
/// at p. `delta`: a delta lobe's sample, or the camera ray: no light technique competes, its emission counts in full.
struct DirectionSample {
    p: vec3<f32>,
    n: vec3<f32>,
    transmits: bool,
    w: vec3<f32>,
    pdf: f32,
    delta: bool,
    light: LightMeasure,
}

/// The MIS weight of emission `found` along direction sample s against the light technique's pdf of s.w (selection
/// included).
fn direction_mis_weight(s: DirectionSample, found: Found) -> f32 {
    if (!mis_on()) { return 1.0; }
    var m = s.light;
    if (!light_measure_known() && found.light != params.env_light) { m = light_measure(found.light, s.p); }
    // One light_pdf_li for every kind, the environment included: each call site is compiled with all it reaches.
    // y.ng was flipped towards the ray; |cos| is what the area conversion needs.
    let p_light = light_pdf_li(found.light, m, s.p, env_receiver(s.n, s.transmits), s.w, found.surface.p,
                               found.surface.ng);
    // A convex lamp's face was found: the lamp is what light sampling chooses.
    let chosen = chosen_light(found.light);
    return mis_weight(f32(params.bsdf_samples), s.pdf, f32(params.light_samples), light_pmf(chosen, s.p, s.n) * p_light);
}

/// The emission `found` by direction sample s, × scale, × its MIS weight. The one place where emission a direction
/// sample finds is weighted: for the samples shade() traces and for the path's continuation (integrator.wgsl).
fn weighted_emission(s: DirectionSample, found: Found, scale: f32) -> vec3<f32> {
    var w = scale;
    if (w > 0.0 && !s.delta && any(found.le != vec3<f32>(0.0))) { w *= direction_mis_weight(s, found); }
    return w * found.le;
}

/// Block 2, the direction technique: sample a direction, trace it, weight the emission it finds against the light
/// technique's pdf. L·f·cos / pdf. `known`: the measure of the first light sample taken at c.
fn direction_technique(c: ShadingCtx, j: u32, known: LightMeasure) -> vec3<f32> {
    let ds = direction_sample(c, j);
    if (!(ds.pdf > 0.0)) { return vec3<f32>(0.0); }
    let w = to_world(c.frame, ds.wi);
    if (wrong_side(c, w, ds.wi)) { return vec3<f32>(0.0); }
    let o = spawn_origin(c.x, w);
    if (finds_no_emission(o, w)) { return vec3<f32>(0.0); }
    let s = DirectionSample(c.x.p, c.x.ns, bsdf_transmits(c.brdf), w, ds.pdf, ds.delta, known);
    let found = trace_found(o, s, true);
    if (all(found.le == vec3<f32>(0.0))) { return vec3<f32>(0.0); }
    return weighted_emission(s, found, 1.0) * direction_f(c, ds) * abs(ds.wi.z) / ds.pdf;
}

/// The environment guide learns where the sky is seen from: direction sample s escaped to it.
fn env_guide_learn_found(s: DirectionSample, found: Found) {
    if (found.escaped && !s.delta) { env_guide_learn_escape(s.p, env_receiver(s.n, s.transmits), s.w); }
}

// ---- shade() ----

/// How the active strategy splits one shading point's work: light samples taken (each estimate divided by
/// light_div) and direction samples whose emission counts (each scaled by dir_scale).
struct Plan {
    light_runs: u32,
    light_div: f32,
    dir_runs: u32,
    dir_scale: f32,
}

/// Whether the environment guide draws the sky samples at c (a constant sky, guided, and c's slot learned).
fn first_hit_guided(c: ShadingCtx) -> bool {
    if (ENV_KIND == 0u) { return false; }
    return env_guide_at(c.x.p, env_receiver(c.x.ns, bsdf_transmits(c.brdf))).slot != INVALID;
}

fn strategy_plan(c: ShadingCtx) -> Plan {
    let s = cfg_strategy();
    var p = Plan(0u, 1.0, 0u, 1.0);
    if (s == STRATEGY_LIGHT || s == STRATEGY_MIS) {
        p.light_runs = params.light_samples;
        // Splitting at a path's first vertex where the environment guide applies (the sky seldom seen from there:
        // a light sample is a rare success, and a blocked shadow ray ends early): the light technique's estimate
        // is the mean of more samples, each with the MIS weight of --light-samples (any weights that sum to one
        // with the direction technique's keep the sum unbiased). Counting them in the weights (n_l · p_l) would
        // shift weight off the path's continuation, whose light and the indirect light behind it vary together;
        // that raised the helmet's error (docs/estimators.md, "Light samples split at the first vertex").
        if (c.bounce == 0u && cfg_mode() == MODE_PATH && first_hit_guided(c)) {
            p.light_runs = min(p.light_runs * params.first_hit_light_split, 64u);
        }
    }
    if (s != STRATEGY_LIGHT) { p.dir_runs = params.bsdf_samples; }
    p.light_div = f32(p.light_runs);
    p.dir_scale = 1.0 / f32(max(p.dir_runs, 1u));
    // Delta lobes: light samples cannot contribute, so MIS gives the whole weight to the direction samples (their
    // emission counts with weight 1). Light-only sampling stays without them (the warning says what it misses).
    if (bsdf_is_delta(c.brdf)) {
        p.light_runs = 0u;
        p.light_div = 1.0;
        return p;
    }
    if (s == STRATEGY_MIS && cfg_mis_kind() == MIS_ONE) {
        // One-sample MIS: pick the light technique with probability c_l = n_l / (n_l + n_d); the
        // estimate is w_i·f/(c_i·p_i) for the chosen technique i (Veach §9.2.4).
        let c_l = f32(params.light_samples) / f32(params.light_samples + params.bsdf_samples);
        let choose_light = sample_1d(c.id, dim_base(c.bounce, 0u) + DIM_MIS_CHOICE) < c_l;
        p.light_runs = select(0u, 1u, choose_light);
        p.light_div = c_l;
        p.dir_runs = select(1u, 0u, choose_light);
        p.dir_scale = 1.0 / (1.0 - c_l);
    }
    return p;
}

/// What shade() returns: the estimate it completed, and (path mode) direction sample 0 untraced — the path's
/// continuation, whose emission the path loop weights where its trace finds it (`weighted_emission` × next_scale).
struct Shaded {
    radiance: vec3<f32>,      // light samples and the direction samples traced here, weighted
    next_valid: bool,
    next_origin: vec3<f32>,
    next: DirectionSample,
    next_weight: vec3<f32>,   // f·cos/pdf of next.w
    next_scale: f32,          // 0 where the strategy counts no direction sample here (light sampling, or one-sample
                              // MIS chose the light): then the direction only continues the path
}

/// shade(x, V, brdf, N): the direct light at c by the active strategy. `want_next`: the path goes on from here,
/// so direction sample 0 is wanted even when its emission does not count.
fn shade(c: ShadingCtx, want_next: bool) -> Shaded {
    var out: Shaded;
    let plan = strategy_plan(c);
    out.radiance = vec3<f32>(0.0);
    var known = LightMeasure(MEASURE_NONE, 0.0);
    for (var j = 0u; j < min(plan.light_runs, 64u); j += 1u) {
        let e = light_technique(c, j);
        out.radiance += e.radiance / plan.light_div;
        if (j == 0u) { known = e.m; }
    }
    // Direction samples 1.. are traced here (a pipeline for one sample compiles none), and sample 0 too in direct
    // mode: no path continues, and one trace site per sample keeps a direct sample to one pass of the path loop.
    let all_here = cfg_mode() == MODE_DIRECT;
    if (SPEC_ONE_DIRECTION != 1u || all_here) {
        for (var j = select(1u, 0u, all_here); j < min(plan.dir_runs, 64u); j += 1u) {
            out.radiance += direction_technique(c, j, known) * plan.dir_scale;
        }
    }
    out.next_valid = false;
    if (all_here || (!want_next && plan.dir_runs == 0u)) { return out; }
    let ds = direction_sample(c, 0u);
    if (!(ds.pdf > 0.0)) { return out; }
    let w = to_world(c.frame, ds.wi);
    if (wrong_side(c, w, ds.wi)) { return out; }
    out.next_valid = true;
    out.next_origin = spawn_origin(c.x, w);
    out.next = DirectionSample(c.x.p, c.x.ns, bsdf_transmits(c.brdf), w, ds.pdf, ds.delta, known);
    out.next_weight = direction_f(c, ds) * abs(ds.wi.z) / ds.pdf;
    out.next_scale = select(0.0, plan.dir_scale, plan.dir_runs > 0u);
    return out;
}
