// bsdf_dielectric.wgsl — a dielectric interface (glass, water) as the technique triple dielectric_eval /
// dielectric_sample / dielectric_pdf. The contract of bsdf.wgsl (local shading frame, z = shading normal, wo and
// wi away from the surface, eval WITHOUT the cosine), except that wi may lie below the surface (transmission),
// and the cosine the estimator multiplies by is |wi.z|.
//
// η = q.eta is the index of the side below (z < 0) over the side above: dielectric_params gives 1/η when the ray
// arrives from inside (the back face; not for the thin slab, which has no inside). wo below the surface is handled too (η then inverts here), as chi-square
// tests and reciprocity checks evaluate both sides.
//   Smooth (max α < DELTA_ALPHA): delta reflection with probability F and refraction with 1 − F (exact Fresnel,
//     total internal reflection), the BTDF scaled by 1/η'² (radiance, not importance: pbrt-v4 §9.5.2).
//   Rough: anisotropic GGX (bsdf.wgsl's aniso_ggx_*) with Walter et al. 2007's BTDF (eq. 21) and the generalized
//     half vector wm = normalize(η'·wi + wo) (eq. 16); a visible normal of wo is sampled, then reflection with
//     probability F(wo·wm), else refraction about wm; pdf from the Jacobians of eq. 14 and 17.
//     Beckmann (q.beckmann, Mitsuba 3's default): D and the separable G = G1(wo)·G1(wi) of Walter et al.'s
//     rational fit (bsdf.wgsl's beckmann_*, as Mitsuba 3 evaluates them); wm drawn from D(wm)·cosθm.
//   Thin (q.thin, Mitsuba's thindielectric): a slab of two parallel smooth interfaces; its internal bounces
//     sum to R' = R + T²R/(1 − R²), and transmission continues straight through (wi = −wo, no 1/η² scaling).
// q.tint is the tint on both lobes. Compiled in where the scene has a dielectric (HAS_DIELECTRIC).
// Words (src/render/materials.rs `pack_dielectric`): params0 = (tint, η), params1 = (α along the tangent, α along the
// bitangent, 1 for thin, 1 for Beckmann). The base texture multiplies the tint.

struct DielectricParams {
    tint: vec3<f32>,
    eta: f32,
    alpha_u: f32,
    alpha_v: f32,
    thin: bool,
    beckmann: bool,
}

fn dielectric_params(p: BsdfParams) -> DielectricParams {
    var q = DielectricParams(p.params0.xyz * p.tex_base, p.params0.w, p.params1.x, p.params1.y, p.params1.z != 0.0,
                             p.params1.w == 1.0);
    // η is inside over outside; a ray arriving from inside (the back face) sees 1/η.
    if (!p.front && !q.thin) { q.eta = 1.0 / q.eta; }
    return q;
}

fn dielectric_is_delta(q: DielectricParams) -> bool { return dielectric_is_smooth(q); }

fn dielectric_has_delta_lobe(q: DielectricParams) -> bool { return false; }

/// Unpolarised Fresnel reflectance of a dielectric interface, incidence cosine c (negative: arriving from the
/// side below, η inverted), relative index η (pbrt-v4 FrDielectric). 1 under total internal reflection.
fn fresnel_dielectric(c_in: f32, eta_in: f32) -> f32 {
    var c = clamp(c_in, -1.0, 1.0);
    var eta = eta_in;
    if (c < 0.0) {
        eta = 1.0 / eta;
        c = -c;
    }
    let sin2_t = max(1.0 - c * c, 0.0) / (eta * eta);
    if (sin2_t >= 1.0) { return 1.0; }
    let cos_t = safe_sqrt(1.0 - sin2_t);
    let r_parl = (eta * c - cos_t) / (eta * c + cos_t);
    let r_perp = (c - eta * cos_t) / (c + eta * cos_t);
    return 0.5 * (r_parl * r_parl + r_perp * r_perp);
}

/// Refraction of wo about the normal n (either side) with relative index η: (wt, η') where η' is the index
/// ratio the ray crosses (η from above, 1/η from below); η' = 0 marks total internal reflection.
fn refract_dielectric(wo: vec3<f32>, n_in: vec3<f32>, eta_in: f32) -> vec4<f32> {
    var n = n_in;
    var eta = eta_in;
    var c = dot(n, wo);
    if (c < 0.0) {
        eta = 1.0 / eta;
        c = -c;
        n = -n;
    }
    let sin2_t = max(1.0 - c * c, 0.0) / (eta * eta);
    if (sin2_t >= 1.0) { return vec4<f32>(0.0); }
    let cos_t = safe_sqrt(1.0 - sin2_t);
    return vec4<f32>(normalize(-wo / eta + (c / eta - cos_t) * n), eta);
}

fn dielectric_is_smooth(q: DielectricParams) -> bool {
    return max(q.alpha_u, q.alpha_v) < DELTA_ALPHA || q.thin;
}

/// The generalized half vector of (wo, wi) on the upper side (Walter eq. 16), and η' of the pair; w = 0: none.
fn dielectric_half_vector(wo: vec3<f32>, wi: vec3<f32>, eta: f32) -> vec4<f32> {
    var etap = 1.0;
    if (wo.z * wi.z < 0.0) { etap = select(1.0 / eta, eta, wo.z > 0.0); }
    var wm = wi * etap + wo;
    if (wi.z == 0.0 || wo.z == 0.0 || dot(wm, wm) == 0.0) { return vec4<f32>(0.0); }
    wm = normalize(wm);
    if (wm.z < 0.0) { wm = -wm; }
    // Microfacets seen from behind by either direction contribute nothing.
    if (dot(wm, wi) * wi.z < 0.0 || dot(wm, wo) * wo.z < 0.0) { return vec4<f32>(0.0); }
    return vec4<f32>(wm, etap);
}

/// f(wo, wi) without the cosine; 0 for the smooth (delta) interface, whose lobes only dielectric_sample reaches.
fn dielectric_eval(q: DielectricParams, wo: vec3<f32>, wi: vec3<f32>) -> vec3<f32> {
    if (dielectric_is_smooth(q)) { return vec3<f32>(0.0); }
    let hv = dielectric_half_vector(wo, wi, q.eta);
    if (hv.w == 0.0) { return vec3<f32>(0.0); }
    let wm = hv.xyz;
    let au = q.alpha_u;
    let av = q.alpha_v;
    var d: f32;
    var g: f32;
    if (q.beckmann) {
        d = beckmann_d(wm, au, av);
        g = beckmann_g1(wo, wm, au, av) * beckmann_g1(wi, wm, au, av);
    } else {
        d = aniso_ggx_d(wm, au, av);
        g = 1.0 / (1.0 + aniso_ggx_lambda(wo, au, av) + aniso_ggx_lambda(wi, au, av));
    }
    let f = fresnel_dielectric(dot(wo, wm), q.eta);
    if (wo.z * wi.z > 0.0) {
        return q.tint * (d * g * f / abs(4.0 * wo.z * wi.z));
    }
    let etap = hv.w;
    let denom = dot(wi, wm) + dot(wo, wm) / etap;
    let ft = d * (1.0 - f) * g * abs(dot(wi, wm) * dot(wo, wm) / (denom * denom * wi.z * wo.z));
    return q.tint * (ft / (etap * etap));
}

/// pdf (solid angle) of dielectric_sample producing wi; 0 for the smooth interface (a delta: no density).
fn dielectric_pdf(q: DielectricParams, wo: vec3<f32>, wi: vec3<f32>) -> f32 {
    if (dielectric_is_smooth(q)) { return 0.0; }
    let hv = dielectric_half_vector(wo, wi, q.eta);
    if (hv.w == 0.0) { return 0.0; }
    let wm = hv.xyz;
    let au = q.alpha_u;
    let av = q.alpha_v;
    let f = fresnel_dielectric(dot(wo, wm), q.eta);
    // Density of wm: GGX's visible normal seen from wo, G1(wo)·D(wm)·|wo·wm| / |wo.z|; Beckmann's D(wm)·cosθm.
    var d_vis: f32;
    if (q.beckmann) {
        d_vis = beckmann_d(wm, au, av) * wm.z;
    } else {
        d_vis = aniso_ggx_g1(wo, au, av) * aniso_ggx_d(wm, au, av) * abs(dot(wo, wm)) / abs(wo.z);
    }
    if (wo.z * wi.z > 0.0) {
        return d_vis / (4.0 * abs(dot(wo, wm))) * f;
    }
    let etap = hv.w;
    let denom = dot(wi, wm) + dot(wo, wm) / etap;
    return d_vis * abs(dot(wi, wm)) / (denom * denom) * (1.0 - f);
}

/// Samples wi: a delta lobe for the smooth interface (s.delta, s.pdf = the lobe's probability, f·|cos|/pdf the
/// weight), else a visible normal and a Fresnel-weighted choice of reflection or refraction. pdf = 0: failed.
fn dielectric_sample(q: DielectricParams, wo: vec3<f32>, u_lobe: f32, u: vec2<f32>) -> BsdfSample {
    var s: BsdfSample;
    s.pdf = 0.0;
    s.f = vec3<f32>(0.0);
    s.delta = false;
    if (wo.z == 0.0) { return s; }
    let eta = q.eta;
    if (dielectric_is_smooth(q)) {
        var r = fresnel_dielectric(wo.z, eta);
        var t = 1.0 - r;
        let thin = q.thin;
        if (thin && r < 1.0) {
            // The slab's multiple internal reflections, summed (Mitsuba's thindielectric).
            r += t * t * r / (1.0 - r * r);
            t = 1.0 - r;
        }
        s.delta = true;
        if (u_lobe < r || t <= 0.0) {
            s.wi = vec3<f32>(-wo.x, -wo.y, wo.z);
            s.pdf = r;
            s.f = q.tint * (r / abs(s.wi.z));
            return s;
        }
        if (thin) {
            s.wi = -wo;
            s.pdf = t;
            s.f = q.tint * (t / abs(s.wi.z));
            return s;
        }
        let rt = refract_dielectric(wo, vec3<f32>(0.0, 0.0, 1.0), eta);
        if (rt.w == 0.0 || rt.z == 0.0) { s.delta = false; return s; }
        s.wi = rt.xyz;
        s.pdf = t;
        s.f = q.tint * (t / (abs(s.wi.z) * rt.w * rt.w));
        return s;
    }
    // Visible normals of the side wo is on (the distribution is symmetric under z → −z); Beckmann's wm, drawn
    // from D·cos alone, may face away from wo: a failed sample.
    var wm: vec3<f32>;
    if (q.beckmann) {
        wm = beckmann_sample_normal(q.alpha_u, q.alpha_v, u);
        if (dot(wo, wm) * wo.z <= 0.0) { return s; }
    } else {
        let side = select(-1.0, 1.0, wo.z > 0.0);
        wm = aniso_ggx_sample_visible_normal(wo * side, q.alpha_u, q.alpha_v, u);
    }
    let f = fresnel_dielectric(dot(wo, wm), eta);
    if (u_lobe < f) {
        s.wi = reflect(-wo, wm);
        if (s.wi.z * wo.z <= 0.0) { return s; }
    } else {
        let rt = refract_dielectric(wo, wm, eta);
        if (rt.w == 0.0) { return s; }
        s.wi = rt.xyz;
        if (s.wi.z * wo.z >= 0.0) { return s; }
    }
    s.pdf = dielectric_pdf(q, wo, s.wi);
    s.f = dielectric_eval(q, wo, s.wi);
    return s;
}
