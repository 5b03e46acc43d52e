// estimators.wgsl — the lecture's shade(x, V, brdf, N): direct illumination at a shading point, built
// from techniques that sample / pdf / eval. Two families of techniques:
//   * direction techniques (uniform hemisphere, cosine hemisphere, BSDF): sample w, trace, find emitters;
//   * light techniques (lights.wgsl): sample a point/direction on an emitter, test a shadow ray.
// `--strategy` picks which run; `mis` runs both and weights them (multi-sample or one-sample MIS).

/// What shade() returns: the estimate, and (for path tracing) the continuation ray it traced anyway.
struct Shaded {
    radiance: vec3<f32>,
    next_valid: bool,
    next_dir: vec3<f32>,
    next_weight: vec3<f32>,   // f·cos/pdf of the continuation direction
    next_hit: Hit,
    next_surface: Surface,  // surface_at(next_hit), when it hit something
}

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
    c.frame = frame_from_normal(x.ns);
    c.wo = to_local(c.frame, -d);
    c.brdf = material_bsdf(m, x.uv);
    c.id = id;
    c.bounce = bounce;
    return c;
}

/// The direction technique a strategy uses: uniform, cosine, or the BSDF (also for light / mis).
fn direction_technique() -> u32 {
    if (cfg_strategy() == STRATEGY_UNIFORM || cfg_strategy() == STRATEGY_COSINE) { return cfg_strategy(); }
    return STRATEGY_BSDF;
}

/// pdf (solid angle) of the direction technique producing local direction wi.
fn direction_pdf(c: ShadingCtx, wi: vec3<f32>) -> f32 {
    switch (direction_technique()) {
        case STRATEGY_UNIFORM: { return square_to_uniform_hemisphere_pdf(wi); }
        case STRATEGY_COSINE: { return square_to_cosine_hemisphere_pdf(wi); }
        default: { return bsdf_pdf(c.brdf, c.wo, wi); }
    }
}

/// Samples the direction technique: local wi and its pdf (0 = failed).
fn direction_sample(c: ShadingCtx, j: u32) -> vec4<f32> {
    let base = dim_base(c.bounce, j);
    let u = sample_2d(c.id, base + DIM_BSDF_UV);
    switch (direction_technique()) {
        case STRATEGY_UNIFORM: {
            let w = square_to_uniform_hemisphere(u);
            return vec4<f32>(w, square_to_uniform_hemisphere_pdf(w));
        }
        case STRATEGY_COSINE: {
            let w = square_to_cosine_hemisphere(u);
            return vec4<f32>(w, square_to_cosine_hemisphere_pdf(w));
        }
        default: {
            let s = bsdf_sample(c.brdf, c.wo, sample_1d(c.id, base + DIM_BSDF_LOBE), u);
            return vec4<f32>(s.wi, s.pdf);
        }
    }
}

/// Spawns a ray leaving the surface along world direction w (offset to the side w points to).
fn spawn_origin(x: Surface, w: vec3<f32>) -> vec3<f32> {
    return offset_ray_origin_scaled(x.p, select(-x.ng, x.ng, dot(w, x.ng) > 0.0), params.offset_scale);
}

/// What a light-technique sample found, and the sampled light's `omega` from the shading point (see LightSample).
struct LightEstimate {
    radiance: vec3<f32>,
    omega: f32,
}

/// One light-technique sample: choose a light, sample it, test visibility, weight against the
/// direction technique when `mis_n_dir` > 0 (its sample count; 0 = no MIS partner).
fn light_estimate(c: ShadingCtx, j: u32, n_light: f32, mis_n_dir: f32) -> LightEstimate {
    var out = LightEstimate(vec3<f32>(0.0), 0.0);
    if (params.num_lights == 0u) { return out; }
    let base = dim_base(c.bounce, j);
    let li = select_light(sample_1d(c.id, base + DIM_LIGHT_SELECT));
    let pmf = light_pmf(li);
    let u = vec3<f32>(sample_2d(c.id, base + DIM_LIGHT_UV), sample_1d(c.id, base + DIM_LIGHT_EXTRA));
    let ls = light_sample_li(li, c.x.p, u);
    out.omega = ls.omega;
    if (!(ls.pdf > 0.0) || !(pmf > 0.0)) { return out; }
    // Reflection only: the light must be above both the shading and the geometric hemisphere.
    let cos_s = dot(ls.wi, c.x.ns);
    if (cos_s <= 0.0 || dot(ls.wi, c.x.ng) <= 0.0) { return out; }
    let wi_local = to_local(c.frame, ls.wi);
    let f = bsdf_eval(c.brdf, c.wo, wi_local);
    if (all(f * ls.radiance == vec3<f32>(0.0))) { return out; }
    let o = spawn_origin(c.x, ls.wi);
    // The shadow ray runs from the offset origin o to the light point y and stops just short of y, so the
    // emitter itself is no occluder. Aim at y from o (not along wi from x.p): at grazing angles a ray
    // parallel to wi but offset by o − x.p reaches the light's plane well before distance |y − x.p|.
    var shadow_dir = ls.wi;
    var t_max = F32_MAX;
    if (ls.dist < F32_MAX) {
        let to_y = c.x.p + ls.wi * ls.dist - o;
        let len = length(to_y);
        shadow_dir = to_y / len;
        // Stop short of y by more than y's own rounding error (~2^-23·|y| per coordinate), which a relative
        // 1e-5 of a short shadow ray far from the origin is not.
        let y_err = 64.0 * 1.2e-7 * (max(max(abs(c.x.p.x), abs(c.x.p.y)), abs(c.x.p.z)) + len);
        t_max = len - max(len * 1e-5, y_err);
        if (t_max <= 0.0) { return out; }
    }
    rays_traced += 1u;
    if (trace_any_except(o, shadow_dir, t_max, light_prim_ref(li))) { return out; }
    let p_light = pmf * ls.pdf;
    var w = 1.0;
    if (mis_n_dir > 0.0 && !ls.delta) {
        w = mis_weight(n_light, p_light, mis_n_dir, direction_pdf(c, wi_local));
    }
    out.radiance = w * ls.radiance * f * cos_s / p_light;
    return out;
}

/// Emitted radiance found by a traced direction, and the light technique's pdf for it (with selection).
struct Found {
    le: vec3<f32>,
    p_light: f32,
    surface: Surface,   // the hit's shading point (reused as the path's next vertex)
}

/// What the ray o + t·w leaving the shading point at `from_p` found at `hit`. With `omega_known` (a constant at
/// each call site), a light hit there is the one sampled at from_p, whose `omega` from there is `omega`.
fn found_emission(from_p: vec3<f32>, o: vec3<f32>, w: vec3<f32>, hit: Hit, omega_known: bool, omega: f32) -> Found {
    var r: Found;
    r.le = vec3<f32>(0.0);
    r.p_light = 0.0;
    if (hit.prim == INVALID) {
        if (params.env_light != INVALID) {
            r.le = env_eval(w);
            r.p_light = light_pmf(params.env_light) * env_pdf(w);
        }
        return r;
    }
    let y = surface_at(hit, o, w);
    r.surface = y;
    if (!y.front) { return r; }
    r.le = material_emission(scene_material(y.material), y.uv);
    if (y.light != INVALID) {
        // y.ng was flipped towards the ray; |cos| is what the area conversion needs.
        if (omega_known) {
            r.p_light = light_pmf(y.light) * light_pdf_given_omega(y.light, from_p, w, y.p, y.ng, omega);
        } else {
            r.p_light = light_pmf(y.light) * light_pdf_li(y.light, from_p, w, y.p, y.ng);
        }
    }
    return r;
}

/// How the active strategy splits one shading point's work between the two technique families.
struct Plan {
    light_runs: u32,     // light-technique samples taken here
    light_n: f32,        // their count as MIS sees it
    light_partner: f32,  // direction samples weighed against them (0 = no MIS)
    light_div: f32,      // each light sample's estimate is divided by this
    n_dir: u32,          // direction-technique samples per shading point
    dir_count: u32,      // direction samples whose emission counts (0: light sampling, or one-sample MIS chose it)
    dir_scale: f32,      // factor on each counted direction sample
}

fn strategy_plan(c: ShadingCtx) -> Plan {
    var p: Plan;
    p.light_runs = 0u;
    p.n_dir = 0u;
    switch (cfg_strategy()) {
        case STRATEGY_LIGHT: { p.light_runs = params.light_samples; }
        case STRATEGY_MIS: {
            p.light_runs = params.light_samples;
            p.n_dir = params.bsdf_samples;
        }
        default: { p.n_dir = params.bsdf_samples; }
    }
    let mis = cfg_strategy() == STRATEGY_MIS;
    p.light_n = f32(params.light_samples);
    p.light_partner = select(0.0, f32(p.n_dir), mis);
    p.light_div = f32(p.light_runs);
    p.dir_count = p.n_dir;
    p.dir_scale = 1.0 / f32(max(p.n_dir, 1u));
    if (mis && cfg_mis_kind() == MIS_ONE) {
        // One-sample MIS: pick the light technique with probability c_l = n_l / (n_l + n_d); the
        // estimate is w_i·f/(c_i·p_i) for the chosen technique i (Veach §9.2.4).
        let c_l = f32(params.light_samples) / f32(params.light_samples + p.n_dir);
        let choose_light = sample_1d(c.id, dim_base(c.bounce, 0u) + DIM_MIS_CHOICE) < c_l;
        p.light_runs = select(0u, 1u, choose_light);
        p.light_div = c_l;
        p.dir_count = select(1u, 0u, choose_light);
        p.dir_scale = 1.0 / (1.0 - c_l);
    }
    return p;
}

/// The light-technique half of shade(): `plan.light_runs` samples of the lights, each weighed against the
/// direction technique under MIS. `omega` is the first sample's (see LightEstimate).
fn shade_lights(c: ShadingCtx, plan: Plan) -> LightEstimate {
    var out = LightEstimate(vec3<f32>(0.0), 0.0);
    for (var j = 0u; j < min(plan.light_runs, 64u); j += 1u) {
        let e = light_estimate(c, j, plan.light_n, plan.light_partner);
        out.radiance += e.radiance / plan.light_div;
        if (j == 0u) { out.omega = e.omega; }
    }
    return out;
}

/// Whether the `omega` of a vertex's first light sample serves the MIS pdf of whatever light its direction sample
/// hits, at every vertex: one light (the one sampled), and a light sample taken at every vertex (not one-sample
/// MIS). Fixed per pipeline.
fn light_omega_reusable() -> bool {
    return !MANY_LIGHTS && cfg_strategy() == STRATEGY_MIS && cfg_mis_kind() == MIS_MULTI;
}

/// The weight of emission found by a direction sample of pdf `dir_pdf`, whose light-technique pdf is `p_light`.
fn direction_emission_weight(plan_n_dir: u32, dir_pdf: f32, p_light: f32) -> f32 {
    if (cfg_strategy() != STRATEGY_MIS) { return 1.0; }
    return mis_weight(f32(plan_n_dir), dir_pdf, f32(params.light_samples), p_light);
}

/// shade(x, V, brdf, N): the direct-illumination estimate at one shading point, by the active strategy.
/// When `want_next`, also returns the path's continuation: the first direction sample, its hit and the
/// shading point there (traced for the continuation alone when the strategy counts no emission through it).
fn shade(c: ShadingCtx, want_next: bool) -> Shaded {
    var out: Shaded;
    out.next_valid = false;
    let plan = strategy_plan(c);
    out.radiance = shade_lights(c, plan).radiance;
    // Direction samples: trace, and count what they find (weighted against light sampling under MIS).
    // Sample 0 is also the path's continuation; a strategy that traces no direction here (light sampling,
    // or one-sample MIS that chose the light) still traces it, for the continuation only (its emission is
    // not counted: NEE already did). One trace site serves both — on lavapipe every call site's code runs
    // whether or not a lane needs it, so a separate continuation trace would cost a third traversal.
    let n_traced = max(plan.dir_count, select(0u, 1u, want_next));
    for (var j = 0u; j < min(n_traced, 64u); j += 1u) {
        let ds = direction_sample(c, j);
        let wl = ds.xyz;
        let pdf = ds.w;
        if (!(pdf > 0.0)) { continue; }
        let w = to_world(c.frame, wl);
        if (dot(w, c.x.ng) <= 0.0) { continue; }
        let f = bsdf_eval(c.brdf, c.wo, wl);
        let o = spawn_origin(c.x, w);
        rays_traced += 1u;
        let hit = trace_closest(o, w, F32_MAX);
        let found = found_emission(c.x.p, o, w, hit, false, 0.0);
        let weight = direction_emission_weight(plan.n_dir, pdf, found.p_light);
        if (j < plan.dir_count) { out.radiance += weight * found.le * f * wl.z / pdf * plan.dir_scale; }
        if (j == 0u && want_next) {
            out.next_valid = true;
            out.next_dir = w;
            out.next_weight = f * wl.z / pdf;
            out.next_hit = hit;
            out.next_surface = found.surface;
        }
    }
    return out;
}
