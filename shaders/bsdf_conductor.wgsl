// bsdf_conductor.wgsl — a conductor: complex Fresnel from RGB η + i·k over an anisotropic GGX microsurface,
// as the technique triple conductor_eval / conductor_sample / conductor_pdf (the contract of bsdf.wgsl: local
// shading frame, z = shading normal, wo and wi away from the surface, eval WITHOUT the cosine).
//
//   f = D(h)·G2(wo, wi)·F(wo·h) / (4 cosθo cosθi)
//   D: anisotropic GGX, α_u along the frame's tangent x and α_v along its bitangent y (Heitz 2014, eq. 85);
//   G2: height-correlated Smith; F: the unpolarised Fresnel reflectance of a conductor (pbrt-v4 FrComplex).
// Sampling: visible normals (Heitz 2018) by stretching wo into the isotropic configuration and sampling the
// spherical cap there (Dupuy & Benyoub 2023, as bsdf.wgsl), then un-stretching. pdf(wi) = G1(wo)·D(h)/(4 wo.z).
// Beckmann (p.specular = 1: Mitsuba 3's default microfacet distribution): D is the anisotropic Beckmann–
// Spizzichino distribution, G = G1(wo)·G1(wi) with Walter et al. 2007's rational fit of the Beckmann G1 (both as
// Mitsuba 3 evaluates them), and h is sampled from D(h)·cosθh (Walter et al. 2007, eqs. 28-29, anisotropic as
// pbrt-v3): pdf(wi) = D(h)·cosθh / (4 |wo·h|).
// Smooth (max α < DELTA_ALPHA): an exact mirror, a delta lobe that only conductor_sample reaches (eval, pdf 0).
// Reached only where the scene has a conductor (HAS_CONDUCTOR, src/render/features.rs).

/// Anisotropic GGX D(h). Written as the isotropic ggx_d with the stretched slope, without 1 − cos²θ.
fn aniso_ggx_d(h: vec3<f32>, au: f32, av: f32) -> f32 {
    let x = h.x / au;
    let y = h.y / av;
    let d = x * x + y * y + h.z * h.z;
    return 1.0 / (PI * au * av * d * d);
}

/// Smith Λ for anisotropic GGX: the isotropic Λ with α² tan²θ replaced by (α_u² x² + α_v² y²)/z².
fn aniso_ggx_lambda(w: vec3<f32>, au: f32, av: f32) -> f32 {
    let a2t2 = (au * au * w.x * w.x + av * av * w.y * w.y) / max(w.z * w.z, 1e-30);
    return 0.5 * (sqrt(1.0 + a2t2) - 1.0);
}

fn aniso_ggx_g1(w: vec3<f32>, au: f32, av: f32) -> f32 { return 1.0 / (1.0 + aniso_ggx_lambda(w, au, av)); }

/// Visible normal for wo (z > 0) of the anisotropic GGX: stretch, sample the isotropic cap, un-stretch.
fn aniso_ggx_sample_visible_normal(wo: vec3<f32>, au: f32, av: f32, u: vec2<f32>) -> vec3<f32> {
    let wi_std = normalize(vec3<f32>(wo.x * au, wo.y * av, wo.z));
    let phi = TWO_PI * u.x;
    let z = (1.0 - u.y) * (1.0 + wi_std.z) - wi_std.z;
    let sin_theta = safe_sqrt(1.0 - z * z);
    let h_std = vec3<f32>(sin_theta * cos(phi), sin_theta * sin(phi), z) + wi_std;
    return normalize(vec3<f32>(h_std.x * au, h_std.y * av, max(h_std.z, 0.0)));
}

/// Anisotropic Beckmann D(h).
fn beckmann_d(h: vec3<f32>, au: f32, av: f32) -> f32 {
    if (h.z <= 0.0) { return 0.0; }
    let c2 = h.z * h.z;
    let e = (h.x * h.x / (au * au) + h.y * h.y / (av * av)) / c2;
    return exp(-e) / (PI * au * av * c2 * c2);
}

/// Smith G1 of the anisotropic Beckmann distribution for direction w and microfacet normal h: Walter et al.
/// 2007's rational fit in a = 1/(α_w tanθ) (exact to about 0.35 %), 0 where w sees the back of h.
fn beckmann_g1(w: vec3<f32>, h: vec3<f32>, au: f32, av: f32) -> f32 {
    if (dot(w, h) * w.z <= 0.0) { return 0.0; }
    let xy2 = au * au * w.x * w.x + av * av * w.y * w.y;
    if (xy2 <= 0.0) { return 1.0; }
    let a = abs(w.z) / sqrt(xy2);
    if (a >= 1.6) { return 1.0; }
    return (3.535 * a + 2.181 * a * a) / (1.0 + 2.276 * a + 2.577 * a * a);
}

/// A microfacet normal drawn from D(h)·cosθh of the anisotropic Beckmann distribution.
fn beckmann_sample_normal(au: f32, av: f32, u: vec2<f32>) -> vec3<f32> {
    let phi = atan2(av * sin(TWO_PI * u.y), au * cos(TWO_PI * u.y));
    let c = cos(phi);
    let s = sin(phi);
    let inv_a2 = c * c / (au * au) + s * s / (av * av);
    let tan2 = -log(max(1.0 - u.x, 1e-30)) / inv_a2;
    let cos_t = 1.0 / sqrt(1.0 + tan2);
    let sin_t = safe_sqrt(1.0 - cos_t * cos_t);
    return vec3<f32>(sin_t * c, sin_t * s, cos_t);
}

fn conductor_is_beckmann(p: BsdfParams) -> bool { return p.specular == 1.0; }

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
fn conductor_eval(p: BsdfParams, wo: vec3<f32>, wi: vec3<f32>) -> vec3<f32> {
    if (wo.z <= 0.0 || wi.z <= 0.0 || max(p.alpha, p.alpha_v) < DELTA_ALPHA) { return vec3<f32>(0.0); }
    let h = normalize(wo + wi);
    let au = p.alpha;
    let av = p.alpha_v;
    var s: f32;
    if (conductor_is_beckmann(p)) {
        let g = beckmann_g1(wo, h, au, av) * beckmann_g1(wi, h, au, av);
        s = beckmann_d(h, au, av) * g / (4.0 * wo.z * wi.z);
    } else {
        let g2 = 1.0 / (1.0 + aniso_ggx_lambda(wo, au, av) + aniso_ggx_lambda(wi, au, av));
        s = aniso_ggx_d(h, au, av) * g2 / (4.0 * wo.z * wi.z);
    }
    return p.base_color * fresnel_complex3(dot(wo, h), p.eta, p.k) * s;
}

/// pdf (solid angle) of conductor_sample producing wi: G1(wo)·D(h)/(4 wo.z).
fn conductor_pdf(p: BsdfParams, wo: vec3<f32>, wi: vec3<f32>) -> f32 {
    if (wo.z <= 0.0 || wi.z <= 0.0 || max(p.alpha, p.alpha_v) < DELTA_ALPHA) { return 0.0; }
    let h = normalize(wo + wi);
    if (conductor_is_beckmann(p)) { return beckmann_d(h, p.alpha, p.alpha_v) * h.z / (4.0 * abs(dot(wo, h))); }
    return aniso_ggx_g1(wo, p.alpha, p.alpha_v) * aniso_ggx_d(h, p.alpha, p.alpha_v) / (4.0 * wo.z);
}

/// Reflects wo about a visible normal. pdf = 0 marks a failed sample (below the surface).
fn conductor_sample(p: BsdfParams, wo: vec3<f32>, u: vec2<f32>) -> BsdfSample {
    var s: BsdfSample;
    s.pdf = 0.0;
    s.f = vec3<f32>(0.0);
    s.delta = false;
    if (wo.z <= 0.0) { return s; }
    if (max(p.alpha, p.alpha_v) < DELTA_ALPHA) {
        // The mirror: weight F(cosθo), as f·cos/pdf with pdf 1.
        s.wi = vec3<f32>(-wo.x, -wo.y, wo.z);
        s.pdf = 1.0;
        s.delta = true;
        s.f = p.base_color * fresnel_complex3(wo.z, p.eta, p.k) / wo.z;
        return s;
    }
    var h: vec3<f32>;
    if (conductor_is_beckmann(p)) {
        h = beckmann_sample_normal(p.alpha, p.alpha_v, u);
    } else {
        h = aniso_ggx_sample_visible_normal(wo, p.alpha, p.alpha_v, u);
    }
    s.wi = reflect(-wo, h);
    if (s.wi.z <= 0.0) { return s; }
    s.pdf = conductor_pdf(p, wo, s.wi);
    s.f = conductor_eval(p, wo, s.wi);
    return s;
}
