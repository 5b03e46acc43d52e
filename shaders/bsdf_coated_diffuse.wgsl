// bsdf_coated_diffuse.wgsl — a rough dielectric coat over a Lambertian base (pbrt-v4 `coateddiffuse`, Mitsuba
// `plastic` / `roughplastic`), as the technique triple coated_diffuse_eval / _sample / _pdf (the contract of
// bsdf.wgsl: local shading frame, z = shading normal, wo and wi away from the surface, eval WITHOUT the cosine).
//
// An analytic model (as Tungsten's RoughPlastic and Mitsuba's plastic; docs/materials.md measures how it differs
// from pbrt-v4's stochastic layered evaluation):
//   f = F(wo·h)·D(h)·G2(wo, wi) / (4 cosθo cosθi)                               the coat's specular reflection
//     + (1 − F(cosθo))·(1 − F(cosθi)) · R / (π η² (1 − R·F̄ᵢ))                  the base, seen through the coat
// F: the unpolarised Fresnel reflectance of a dielectric of relative index η (outside → coat); D, G2: anisotropic
// GGX with height-correlated Smith shadowing (bsdf.wgsl's aniso_ggx_*); R: the base's reflectance;
// F̄ᵢ: the coat's diffuse (cosine-averaged) reflectance seen from inside, so that R/(1 − R·F̄ᵢ) sums the light
// bouncing between base and coat. The base's transmission uses the smooth Fresnel term at the macro normal.
// For R = 1 and a smooth coat the base returns exactly 1 − F(cosθo) (as 1 − F̄ᵢ = (1 − F̄ₑ)/η²).
// Beckmann coat (q.beckmann, Mitsuba 3's roughplastic default): D and the separable G = G1(wo)·G1(wi) of
// Walter et al.'s rational fit (bsdf.wgsl's beckmann_*, as Mitsuba 3), h sampled from D(h)·cosθh.
// Sampling: the coat's visible normals with probability ps (its Fresnel weight against the base's albedo), else
// cosine-weighted. A smooth coat (max α < DELTA_ALPHA) is an exact mirror lobe of weight F(cosθo): a delta sample
// (BsdfSample.delta, pdf ps) that eval and pdf do not see; they are the base's alone. Compiled in where the scene
// has a coated diffuse material (HAS_COATED_DIFFUSE).
// Words (src/render/materials.rs `pack_coated_diffuse`): params0 = (R, η), params1.xyz = (α along the tangent, α
// along the bitangent, 1 for Beckmann). The base texture multiplies R.

struct CoatedDiffuseParams {
    reflectance: vec3<f32>,
    eta: f32,
    alpha_u: f32,
    alpha_v: f32,
    beckmann: bool,
}

fn coated_diffuse_params(p: BsdfParams) -> CoatedDiffuseParams {
    return CoatedDiffuseParams(p.params0.xyz * p.tex_base, p.params0.w, p.params1.x, p.params1.y, p.params1.z == 1.0);
}

fn coated_diffuse_is_delta(q: CoatedDiffuseParams) -> bool { return false; }

fn coated_diffuse_has_delta_lobe(q: CoatedDiffuseParams) -> bool { return coated_is_smooth(q); }

/// Unpolarised Fresnel reflectance of a dielectric interface for light arriving from the side of index 1 at
/// incidence cosine c (η > 1: no total internal reflection from this side).
fn coated_fresnel(c_in: f32, eta: f32) -> f32 {
    let c = clamp(c_in, 0.0, 1.0);
    let sin2_t = (1.0 - c * c) / (eta * eta);
    let cos_t = safe_sqrt(1.0 - sin2_t);
    let r_s = (c - eta * cos_t) / (c + eta * cos_t);
    let r_p = (eta * c - cos_t) / (eta * c + cos_t);
    return 0.5 * (r_s * r_s + r_p * r_p);
}

/// F̄ᵢ, the cosine-weighted hemispherical reflectance of the coat seen from inside: 1 − (1 − F̄ₑ)/η², with F̄ₑ the
/// outside's, ∫₀¹ F(c)·2c dc by 8-point Gauss–Legendre (F is smooth from outside: within 2e-7 for η ≤ 3). The
/// relation keeps a white base exact: it returns 1 − F(cosθo) whatever the quadrature's error.
/// The CPU side is `scene::coated_internal_reflectance` (tests/bsdf_coated.rs compares them).
fn coated_internal_reflectance(eta: f32) -> f32 {
    var x = array<f32, 4>(0.48014492824876814, 0.39833323870681336, 0.2627662049581645, 0.0917173212478249);
    var w = array<f32, 4>(0.05061426814518815, 0.11119051722668725, 0.15685332293894366, 0.181341891689181);
    var fe = 0.0;
    for (var i = 0u; i < 4u; i++) {
        let lo = 0.5 - x[i];
        let hi = 0.5 + x[i];
        fe += w[i] * 2.0 * (lo * coated_fresnel(lo, eta) + hi * coated_fresnel(hi, eta));
    }
    return 1.0 - (1.0 - fe) / (eta * eta);
}

fn coated_is_smooth(q: CoatedDiffuseParams) -> bool { return max(q.alpha_u, q.alpha_v) < DELTA_ALPHA; }

/// The base's reflectance, capped at 1 (a texture times a factor may exceed it; 1 − R·F̄ᵢ must stay positive).
fn coated_base(q: CoatedDiffuseParams) -> vec3<f32> {
    return clamp(q.reflectance, vec3<f32>(0.0), vec3<f32>(1.0));
}

/// Probability of sampling the coat: its Fresnel reflectance at wo against the base's directional albedo.
fn coated_coat_probability(q: CoatedDiffuseParams, wo: vec3<f32>) -> f32 {
    let eta = q.eta;
    let fo = coated_fresnel(wo.z, eta);
    let r = luminance(coated_base(q));
    let fi = coated_internal_reflectance(eta);
    let w_base = (1.0 - fo) * r * (1.0 - fi) / (1.0 - r * fi);
    if (w_base <= 0.0) { return 1.0; }
    return fo / (fo + w_base);
}

/// f_r(wo, wi) without the cosine. Zero below either hemisphere.
fn coated_diffuse_eval(q: CoatedDiffuseParams, wo: vec3<f32>, wi: vec3<f32>) -> vec3<f32> {
    if (wo.z <= 0.0 || wi.z <= 0.0) { return vec3<f32>(0.0); }
    let eta = q.eta;
    let h = normalize(wo + wi);
    let au = q.alpha_u;
    let av = q.alpha_v;
    var coat = 0.0;
    if (coated_is_smooth(q)) {
        // The mirror lobe is a delta: only coated_diffuse_sample reaches it.
    } else if (q.beckmann) {
        let g = beckmann_g1(wo, h, au, av) * beckmann_g1(wi, h, au, av);
        coat = coated_fresnel(dot(wo, h), eta) * beckmann_d(h, au, av) * g / (4.0 * wo.z * wi.z);
    } else {
        let g2 = 1.0 / (1.0 + aniso_ggx_lambda(wo, au, av) + aniso_ggx_lambda(wi, au, av));
        coat = coated_fresnel(dot(wo, h), eta) * aniso_ggx_d(h, au, av) * g2 / (4.0 * wo.z * wi.z);
    }
    let r = coated_base(q);
    let fi = coated_internal_reflectance(eta);
    let t = (1.0 - coated_fresnel(wo.z, eta)) * (1.0 - coated_fresnel(wi.z, eta)) / (PI * eta * eta);
    return vec3<f32>(coat) + t * r / (vec3<f32>(1.0) - r * fi);
}

/// pdf (solid angle) of coated_diffuse_sample producing wi: ps·G1(wo)·D(h)/(4 wo.z) + (1 − ps)·cosθi/π (Beckmann:
/// ps·D(h)·cosθh/(4 |wo·h|) for the coat).
fn coated_diffuse_pdf(q: CoatedDiffuseParams, wo: vec3<f32>, wi: vec3<f32>) -> f32 {
    if (wo.z <= 0.0 || wi.z <= 0.0) { return 0.0; }
    let ps = coated_coat_probability(q, wo);
    let h = normalize(wo + wi);
    var coat = 0.0;
    if (coated_is_smooth(q)) {
        // A delta lobe has no density.
    } else if (q.beckmann) {
        coat = beckmann_d(h, q.alpha_u, q.alpha_v) * h.z / (4.0 * abs(dot(wo, h)));
    } else {
        coat = aniso_ggx_g1(wo, q.alpha_u, q.alpha_v) * aniso_ggx_d(h, q.alpha_u, q.alpha_v) / (4.0 * wo.z);
    }
    return ps * coat + (1.0 - ps) * square_to_cosine_hemisphere_pdf(wi);
}

/// Picks the coat (a reflected visible normal) or the base (cosine) with u_lobe. pdf = 0 marks a failed sample.
fn coated_diffuse_sample(q: CoatedDiffuseParams, wo: vec3<f32>, u_lobe: f32, u: vec2<f32>) -> BsdfSample {
    var s: BsdfSample;
    s.pdf = 0.0;
    s.f = vec3<f32>(0.0);
    s.delta = false;
    if (wo.z <= 0.0) { return s; }
    let ps = coated_coat_probability(q, wo);
    if (u_lobe < ps && coated_is_smooth(q)) {
        // The smooth coat's mirror: weight f·cosθi/pdf = F(cosθo)/ps.
        s.wi = vec3<f32>(-wo.x, -wo.y, wo.z);
        s.pdf = ps;
        s.delta = true;
        s.f = vec3<f32>(coated_fresnel(wo.z, q.eta) / wo.z);
        return s;
    }
    if (u_lobe < ps) {
        var h: vec3<f32>;
        if (q.beckmann) {
            h = beckmann_sample_normal(q.alpha_u, q.alpha_v, u);
        } else {
            h = aniso_ggx_sample_visible_normal(wo, q.alpha_u, q.alpha_v, u);
        }
        s.wi = reflect(-wo, h);
    } else {
        s.wi = square_to_cosine_hemisphere(u);
    }
    if (s.wi.z <= 0.0) { return s; }
    s.pdf = coated_diffuse_pdf(q, wo, s.wi);
    s.f = coated_diffuse_eval(q, wo, s.wi);
    return s;
}
