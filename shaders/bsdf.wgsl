// bsdf.wgsl — the glTF metallic-roughness BSDF (with KHR_materials_specular's specularFactor) as the
// technique triple eval / sample / pdf. Everything is in the local shading frame (z = shading normal),
// wo and wi point away from the surface, and `eval` returns f_r WITHOUT the cosine (the lecture's
// brdf.eval: the estimator multiplies by dot(w, N)).
//
//   f = (1 − m)·[(1 − F_d)·base/π + F_d·S] + m·F_m·S,   S = D·G2 / (4 cosθo cosθi)   (glTF 2.0 appendix B)
//   F_d = f0 + (f90 − f0)(1 − |wo·h|)⁵ with f0 = 0.04·specular, f90 = specular;  F_m = base + (1 − base)(1 − |wo·h|)⁵
//   D: GGX (Trowbridge–Reitz); G2: height-correlated Smith.
// Lambert is {m = 0, specular = 0}; a GGX conductor with Fresnel 1 is {m = 1, base = 1}.
// bsdf_eval / bsdf_pdf / bsdf_sample are also the dispatch over material kinds: a kind the scene does not use
// is compiled out by its HAS_* constant, so metallic-roughness scenes run exactly the code they ran before.

/// What the BSDF needs at one shading point (textures already applied).
struct BsdfParams {
    base_color: vec3<f32>,
    metallic: f32,
    alpha: f32,
    specular: f32,
    bsdf_kind: u32,          // MATERIAL_* (common.wgsl); the fields above are metallic-roughness's
    eta: vec3<f32>,          // conductor: RGB η
    alpha_v: f32,            // conductor: GGX α along the bitangent (alpha: along the tangent)
    k: vec3<f32>,            // conductor: RGB k
}

/// A sampled direction: wi (local), the pdf of the sampling technique (solid angle), and f (no cosine).
/// `delta`: wi is a delta lobe's (smooth glass, mirror) — pdf is then the lobe's discrete probability, f·|cosθi|/pdf
/// the sample's weight, and neither bsdf_eval nor bsdf_pdf sees the lobe (its density is "infinite").
struct BsdfSample {
    wi: vec3<f32>,
    pdf: f32,
    f: vec3<f32>,
    delta: bool,
}

/// Whether the material is delta lobes only (light sampling cannot contribute: estimators.wgsl skips it).
fn bsdf_is_delta(p: BsdfParams) -> bool {
    if (HAS_DIELECTRIC && p.bsdf_kind == MATERIAL_DIELECTRIC) { return dielectric_is_smooth(p); }
    if (HAS_CONDUCTOR && p.bsdf_kind == MATERIAL_CONDUCTOR) { return max(p.alpha, p.alpha_v) < DELTA_ALPHA; }
    return false;
}

/// Whether the material has a delta lobe beside others (a smooth coat's mirror): light sampling still serves the
/// rest, but the hemisphere techniques (uniform, cosine) cannot reach the lobe.
fn bsdf_has_delta_lobe(p: BsdfParams) -> bool {
    return HAS_COATED_DIFFUSE && p.bsdf_kind == MATERIAL_COATED_DIFFUSE && coated_is_smooth(p);
}

/// Whether the material transmits (wi below the surface is allowed: two-sided light sampling, |cos|).
fn bsdf_transmits(p: BsdfParams) -> bool {
    return (HAS_DIELECTRIC && p.bsdf_kind == MATERIAL_DIELECTRIC)
        || (HAS_DIFFUSE_TRANSMISSION && p.bsdf_kind == MATERIAL_DIFFUSE_TRANSMISSION);
}

/// GGX normal distribution D(h), h local. Measure: projected solid angle of microfacet normals.
fn ggx_d(h: vec3<f32>, alpha: f32) -> f32 {
    let a2 = alpha * alpha;
    // sin²θ + α²·cos²θ, written without 1 − cos²θ: the textbook c2·(α² − 1) + 1 cancels near the normal
    // for small α (D was off by 1e-3 at α = 0.01 on lavapipe).
    let d = (h.x * h.x + h.y * h.y) + a2 * h.z * h.z;
    return a2 / (PI * d * d);
}

/// Smith Λ for GGX (Heitz 2014, eq. 72), written with tan²θ = (1 − cos²θ)/cos².
fn ggx_lambda(w: vec3<f32>, alpha: f32) -> f32 {
    let c2 = w.z * w.z;
    let t2 = max(1.0 - c2, 0.0) / max(c2, 1e-30);
    return 0.5 * (sqrt(1.0 + alpha * alpha * t2) - 1.0);
}

fn ggx_g1(w: vec3<f32>, alpha: f32) -> f32 { return 1.0 / (1.0 + ggx_lambda(w, alpha)); }

/// Height-correlated masking-shadowing G2(wo, wi).
fn ggx_g2(wo: vec3<f32>, wi: vec3<f32>, alpha: f32) -> f32 {
    return 1.0 / (1.0 + ggx_lambda(wo, alpha) + ggx_lambda(wi, alpha));
}

/// Samples a visible normal for wo (z > 0): Dupuy & Benyoub 2023, "Sampling Visible GGX Normals with
/// Spherical Caps", listing 3. The density of h is D_wo(h) = G1(wo)·max(0, wo·h)·D(h) / wo.z.
fn ggx_sample_visible_normal(wo: vec3<f32>, alpha: f32, u: vec2<f32>) -> vec3<f32> {
    let wi_std = normalize(vec3<f32>(wo.x * alpha, wo.y * alpha, wo.z));
    let phi = TWO_PI * u.x;
    let z = (1.0 - u.y) * (1.0 + wi_std.z) - wi_std.z;
    let sin_theta = safe_sqrt(1.0 - z * z);
    let c = vec3<f32>(sin_theta * cos(phi), sin_theta * sin(phi), z);
    let h_std = c + wi_std;
    return normalize(vec3<f32>(h_std.x * alpha, h_std.y * alpha, max(h_std.z, 0.0)));
}

/// pdf (solid angle of wi) of reflecting wo about a visible normal: G1(wo)·D(h) / (4·wo.z).
fn ggx_reflection_pdf(wo: vec3<f32>, wi: vec3<f32>, alpha: f32) -> f32 {
    if (wo.z <= 0.0 || wi.z <= 0.0) { return 0.0; }
    let h = normalize(wo + wi);
    return ggx_g1(wo, alpha) * ggx_d(h, alpha) / (4.0 * wo.z);
}

fn schlick_weight(c: f32) -> f32 {
    let m = clamp(1.0 - c, 0.0, 1.0);
    let m2 = m * m;
    return m2 * m2 * m;
}

/// Probability of choosing the specular lobe when sampling, from the lobes' approximate albedos at wo.
fn bsdf_specular_probability(p: BsdfParams, wo: vec3<f32>) -> f32 {
    if (!HAS_SPECULAR) { return 0.0; }
    if (!HAS_DIFFUSE) { return 1.0; }
    let fw = schlick_weight(wo.z);
    let f_d = 0.04 * p.specular + (p.specular - 0.04 * p.specular) * fw;
    let f_m = luminance(p.base_color + (vec3<f32>(1.0) - p.base_color) * fw);
    let w_spec = (1.0 - p.metallic) * f_d + p.metallic * f_m;
    let w_diff = (1.0 - p.metallic) * (1.0 - f_d) * luminance(p.base_color);
    if (w_spec <= 0.0) { return 0.0; }
    if (w_diff <= 0.0) { return 1.0; }
    return w_spec / (w_spec + w_diff);
}

/// f_r(wo, wi) without the cosine. Zero below either hemisphere.
fn bsdf_eval(p: BsdfParams, wo: vec3<f32>, wi: vec3<f32>) -> vec3<f32> {
    if (HAS_CONDUCTOR && p.bsdf_kind == MATERIAL_CONDUCTOR) { return conductor_eval(p, wo, wi); }
    if (HAS_COATED_DIFFUSE && p.bsdf_kind == MATERIAL_COATED_DIFFUSE) { return coated_eval(p, wo, wi); }
    if (HAS_DIELECTRIC && p.bsdf_kind == MATERIAL_DIELECTRIC) { return dielectric_eval(p, wo, wi); }
    if (HAS_DIFFUSE_TRANSMISSION && p.bsdf_kind == MATERIAL_DIFFUSE_TRANSMISSION) {
        return diffuse_transmission_eval(p, wo, wi);
    }
    if (wo.z <= 0.0 || wi.z <= 0.0) { return vec3<f32>(0.0); }
    let h = normalize(wo + wi);
    let fw = schlick_weight(dot(wo, h));
    let f0_d = 0.04 * p.specular;
    let f_d = f0_d + (p.specular - f0_d) * fw;
    let f_m = p.base_color + (vec3<f32>(1.0) - p.base_color) * fw;
    var spec = 0.0;
    if (HAS_SPECULAR && (p.metallic > 0.0 || f_d > 0.0)) {
        spec = ggx_d(h, p.alpha) * ggx_g2(wo, wi, p.alpha) / (4.0 * wo.z * wi.z);
    }
    let dielectric = (1.0 - f_d) * p.base_color * INV_PI + vec3<f32>(f_d * spec);
    let metal = f_m * spec;
    return (1.0 - p.metallic) * dielectric + p.metallic * metal;
}

/// pdf (solid angle) of `bsdf_sample` producing wi: the mixture of cosine and visible-normal sampling.
fn bsdf_pdf(p: BsdfParams, wo: vec3<f32>, wi: vec3<f32>) -> f32 {
    if (HAS_CONDUCTOR && p.bsdf_kind == MATERIAL_CONDUCTOR) { return conductor_pdf(p, wo, wi); }
    if (HAS_COATED_DIFFUSE && p.bsdf_kind == MATERIAL_COATED_DIFFUSE) { return coated_pdf(p, wo, wi); }
    if (HAS_DIELECTRIC && p.bsdf_kind == MATERIAL_DIELECTRIC) { return dielectric_pdf(p, wo, wi); }
    if (HAS_DIFFUSE_TRANSMISSION && p.bsdf_kind == MATERIAL_DIFFUSE_TRANSMISSION) {
        return diffuse_transmission_pdf(p, wo, wi);
    }
    if (wo.z <= 0.0 || wi.z <= 0.0) { return 0.0; }
    let ps = bsdf_specular_probability(p, wo);
    var pdf = (1.0 - ps) * square_to_cosine_hemisphere_pdf(wi);
    if (HAS_SPECULAR && ps > 0.0) { pdf += ps * ggx_reflection_pdf(wo, wi, p.alpha); }
    return pdf;
}

/// Samples wi: picks a lobe with u_lobe, then cosine (diffuse) or a reflected visible normal (specular).
/// pdf = 0 marks a failed sample (below the surface).
fn bsdf_sample(p: BsdfParams, wo: vec3<f32>, u_lobe: f32, u: vec2<f32>) -> BsdfSample {
    if (HAS_CONDUCTOR && p.bsdf_kind == MATERIAL_CONDUCTOR) { return conductor_sample(p, wo, u); }
    if (HAS_COATED_DIFFUSE && p.bsdf_kind == MATERIAL_COATED_DIFFUSE) { return coated_sample(p, wo, u_lobe, u); }
    if (HAS_DIELECTRIC && p.bsdf_kind == MATERIAL_DIELECTRIC) { return dielectric_sample(p, wo, u_lobe, u); }
    if (HAS_DIFFUSE_TRANSMISSION && p.bsdf_kind == MATERIAL_DIFFUSE_TRANSMISSION) {
        return diffuse_transmission_sample(p, wo, u_lobe, u);
    }
    var s: BsdfSample;
    s.pdf = 0.0;
    s.f = vec3<f32>(0.0);
    s.delta = false;
    if (wo.z <= 0.0) { return s; }
    let ps = bsdf_specular_probability(p, wo);
    if (HAS_SPECULAR && u_lobe < ps) {
        let h = ggx_sample_visible_normal(wo, p.alpha, u);
        s.wi = reflect(-wo, h);
    } else {
        s.wi = square_to_cosine_hemisphere(u);
    }
    if (s.wi.z <= 0.0) { return s; }
    s.pdf = bsdf_pdf(p, wo, s.wi);
    s.f = bsdf_eval(p, wo, s.wi);
    return s;
}
