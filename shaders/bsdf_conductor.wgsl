// bsdf_conductor.wgsl — a conductor: complex Fresnel from RGB η + i·k over an anisotropic GGX microsurface,
// as the technique triple conductor_eval / conductor_sample / conductor_pdf (the contract of bsdf.wgsl: local
// shading frame, z = shading normal, wo and wi away from the surface, eval WITHOUT the cosine).
//
//   f = D(h)·G2(wo, wi)·F(wo·h) / (4 cosθo cosθi)
//   D: anisotropic GGX, α_u along the frame's tangent x and α_v along its bitangent y (Heitz 2014, eq. 85);
//   G2: height-correlated Smith; F: the unpolarised Fresnel reflectance of a conductor (pbrt-v4 FrComplex).
// Sampling: visible normals (Heitz 2018) by stretching wo into the isotropic configuration and sampling the
// spherical cap there (Dupuy & Benyoub 2023, bsdf.wgsl's aniso_ggx_sample_visible_normal), then un-stretching.
// pdf(wi) = G1(wo)·D(h)/(4 wo.z).
// Beckmann (q.beckmann: Mitsuba 3's default microfacet distribution): D is the anisotropic Beckmann–
// Spizzichino distribution, G = G1(wo)·G1(wi) with Walter et al. 2007's rational fit of the Beckmann G1 (both as
// Mitsuba 3 evaluates them), and h is sampled from D(h)·cosθh (Walter et al. 2007, eqs. 28-29, anisotropic as
// pbrt-v3): pdf(wi) = D(h)·cosθh / (4 |wo·h|).
// Smooth (max α < DELTA_ALPHA): an exact mirror, a delta lobe that only conductor_sample reaches (eval, pdf 0).
// Compiled in where the scene has a conductor (HAS_CONDUCTOR).
// Words (src/render/materials.rs `pack_conductor`): params0 = (tint, α_u), params1 = (η, α_v), params2 = (k, 1 for
// Beckmann). The tint multiplies the Fresnel term (Mitsuba's specular_reflectance) and the base texture multiplies it.

struct ConductorParams {
    tint: vec3<f32>,
    eta: vec3<f32>,
    k: vec3<f32>,
    alpha_u: f32,
    alpha_v: f32,
    beckmann: bool,
}

fn conductor_params(p: BsdfParams) -> ConductorParams {
    return ConductorParams(p.params0.xyz * p.tex_base, p.params1.xyz, p.params2.xyz, p.params0.w, p.params1.w,
                           p.params2.w == 1.0);
}

fn conductor_is_delta(q: ConductorParams) -> bool { return max(q.alpha_u, q.alpha_v) < DELTA_ALPHA; }

fn conductor_has_delta_lobe(q: ConductorParams) -> bool { return false; }

fn cmul(a: vec2<f32>, b: vec2<f32>) -> vec2<f32> { return vec2<f32>(a.x * b.x - a.y * b.y, a.x * b.y + a.y * b.x); }
fn cdiv(a: vec2<f32>, b: vec2<f32>) -> vec2<f32> {
    let s = 1.0 / dot(b, b);
    return vec2<f32>(a.x * b.x + a.y * b.y, a.y * b.x - a.x * b.y) * s;
}
/// Principal square root of a complex number (the branch with a non-negative real part).
fn csqrt(z: vec2<f32>) -> vec2<f32> {
    let n = length(z);
    if (n == 0.0) { return vec2<f32>(0.0); }
    let t1 = sqrt(0.5 * (n + abs(z.x)));
    let t2 = 0.5 * z.y / t1;
    if (z.x >= 0.0) { return vec2<f32>(t1, t2); }
    return vec2<f32>(abs(t2), select(-t1, t1, z.y >= 0.0));
}

/// Unpolarised Fresnel reflectance of one channel, incidence cosine c, relative index η + i·k (pbrt-v4 FrComplex).
fn fresnel_complex(c_in: f32, eta: f32, k: f32) -> f32 {
    let c = clamp(c_in, 0.0, 1.0);
    let n = vec2<f32>(eta, k);
    let sin2_i = 1.0 - c * c;
    let sin2_t = cdiv(vec2<f32>(sin2_i, 0.0), cmul(n, n));
    let cos_t = csqrt(vec2<f32>(1.0, 0.0) - sin2_t);
    let ci = vec2<f32>(c, 0.0);
    let r_parl = cdiv(cmul(n, ci) - cos_t, cmul(n, ci) + cos_t);
    let r_perp = cdiv(ci - cmul(n, cos_t), ci + cmul(n, cos_t));
    return 0.5 * (dot(r_parl, r_parl) + dot(r_perp, r_perp));
}

fn fresnel_complex3(c: f32, eta: vec3<f32>, k: vec3<f32>) -> vec3<f32> {
    return vec3<f32>(fresnel_complex(c, eta.x, k.x), fresnel_complex(c, eta.y, k.y), fresnel_complex(c, eta.z, k.z));
}

/// f_r(wo, wi) without the cosine. Zero below either hemisphere.
fn conductor_eval(q: ConductorParams, wo: vec3<f32>, wi: vec3<f32>) -> vec3<f32> {
    if (wo.z <= 0.0 || wi.z <= 0.0 || conductor_is_delta(q)) { return vec3<f32>(0.0); }
    let h = normalize(wo + wi);
    let au = q.alpha_u;
    let av = q.alpha_v;
    var s: f32;
    if (q.beckmann) {
        let g = beckmann_g1(wo, h, au, av) * beckmann_g1(wi, h, au, av);
        s = beckmann_d(h, au, av) * g / (4.0 * wo.z * wi.z);
    } else {
        let g2 = 1.0 / (1.0 + aniso_ggx_lambda(wo, au, av) + aniso_ggx_lambda(wi, au, av));
        s = aniso_ggx_d(h, au, av) * g2 / (4.0 * wo.z * wi.z);
    }
    return q.tint * fresnel_complex3(dot(wo, h), q.eta, q.k) * s;
}

/// pdf (solid angle) of conductor_sample producing wi: G1(wo)·D(h)/(4 wo.z).
fn conductor_pdf(q: ConductorParams, wo: vec3<f32>, wi: vec3<f32>) -> f32 {
    if (wo.z <= 0.0 || wi.z <= 0.0 || conductor_is_delta(q)) { return 0.0; }
    let h = normalize(wo + wi);
    if (q.beckmann) { return beckmann_d(h, q.alpha_u, q.alpha_v) * h.z / (4.0 * abs(dot(wo, h))); }
    return aniso_ggx_g1(wo, q.alpha_u, q.alpha_v) * aniso_ggx_d(h, q.alpha_u, q.alpha_v) / (4.0 * wo.z);
}

/// Reflects wo about a visible normal. pdf = 0 marks a failed sample (below the surface).
fn conductor_sample(q: ConductorParams, wo: vec3<f32>, u_lobe: f32, u: vec2<f32>) -> BsdfSample {
    var s: BsdfSample;
    s.pdf = 0.0;
    s.f = vec3<f32>(0.0);
    s.delta = false;
    if (wo.z <= 0.0) { return s; }
    if (conductor_is_delta(q)) {
        // The mirror: weight F(cosθo), as f·cos/pdf with pdf 1.
        s.wi = vec3<f32>(-wo.x, -wo.y, wo.z);
        s.pdf = 1.0;
        s.delta = true;
        s.f = q.tint * fresnel_complex3(wo.z, q.eta, q.k) / wo.z;
        return s;
    }
    var h: vec3<f32>;
    if (q.beckmann) {
        h = beckmann_sample_normal(q.alpha_u, q.alpha_v, u);
    } else {
        h = aniso_ggx_sample_visible_normal(wo, q.alpha_u, q.alpha_v, u);
    }
    s.wi = reflect(-wo, h);
    if (s.wi.z <= 0.0) { return s; }
    s.pdf = conductor_pdf(q, wo, s.wi);
    s.f = conductor_eval(q, wo, s.wi);
    return s;
}
