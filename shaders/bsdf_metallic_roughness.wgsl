// bsdf_metallic_roughness.wgsl — the glTF metallic-roughness BSDF (with KHR_materials_specular's specularFactor) as
// the technique triple metallic_roughness_eval / _sample / _pdf, under the contract of bsdf.wgsl (local shading
// frame, z = shading normal, wo and wi away from the surface, eval WITHOUT the cosine).
//
//   f = (1 − m)·[(1 − F_d)·base/π + F_d·S] + m·F_m·S,   S = D·G2 / (4 cosθo cosθi)   (glTF 2.0 appendix B)
//   F_d = f0 + (f90 − f0)(1 − |wo·h|)⁵ with f0 = 0.04·specular, f90 = specular;  F_m = base + (1 − base)(1 − |wo·h|)⁵
//   D: GGX (Trowbridge–Reitz); G2: height-correlated Smith (bsdf.wgsl's ggx_*).
// Lambert is {m = 0, specular = 0}; a GGX conductor with Fresnel 1 is {m = 1, base = 1}. Its lobes are compiled in
// by HAS_DIFFUSE and HAS_SPECULAR (src/render/materials.rs `metallic_roughness_lobes`), the kind by
// HAS_METALLIC_ROUGHNESS.
// Words (src/render/materials.rs `pack_metallic_roughness`): params0 = (base colour, metallic), params1.xy =
// (GGX α = roughness², specular). The base texture multiplies the base colour; the glTF metallic-roughness texture
// sets α from its G channel and scales metallic by its B channel.

struct MetallicRoughnessParams {
    base_color: vec3<f32>,
    metallic: f32,
    alpha: f32,
    specular: f32,
}

fn metallic_roughness_params(p: BsdfParams) -> MetallicRoughnessParams {
    var q = MetallicRoughnessParams(p.params0.xyz * p.tex_base, p.params0.w, p.params1.x, p.params1.y);
    if (p.has_tex_mr) {
        // glTF: roughness in G, metallic in B; α = roughness².
        let rough = sqrt(q.alpha) * p.tex_mr.y;
        q.alpha = max(rough * rough, 1e-4);
        q.metallic *= p.tex_mr.z;
    }
    return q;
}

fn metallic_roughness_is_delta(q: MetallicRoughnessParams) -> bool { return false; }

fn metallic_roughness_has_delta_lobe(q: MetallicRoughnessParams) -> bool { return false; }

/// Probability of choosing the specular lobe when sampling, from the lobes' approximate albedos at wo.
fn metallic_roughness_specular_probability(q: MetallicRoughnessParams, wo: vec3<f32>) -> f32 {
    if (!HAS_SPECULAR) { return 0.0; }
    if (!HAS_DIFFUSE) { return 1.0; }
    let fw = schlick_weight(wo.z);
    let f_d = 0.04 * q.specular + (q.specular - 0.04 * q.specular) * fw;
    let f_m = luminance(q.base_color + (vec3<f32>(1.0) - q.base_color) * fw);
    let w_spec = (1.0 - q.metallic) * f_d + q.metallic * f_m;
    let w_diff = (1.0 - q.metallic) * (1.0 - f_d) * luminance(q.base_color);
    if (w_spec <= 0.0) { return 0.0; }
    if (w_diff <= 0.0) { return 1.0; }
    return w_spec / (w_spec + w_diff);
}

/// f_r(wo, wi) without the cosine. Zero below either hemisphere.
fn metallic_roughness_eval(q: MetallicRoughnessParams, wo: vec3<f32>, wi: vec3<f32>) -> vec3<f32> {
    if (wo.z <= 0.0 || wi.z <= 0.0) { return vec3<f32>(0.0); }
    let h = normalize(wo + wi);
    let fw = schlick_weight(dot(wo, h));
    let f0_d = 0.04 * q.specular;
    let f_d = f0_d + (q.specular - f0_d) * fw;
    let f_m = q.base_color + (vec3<f32>(1.0) - q.base_color) * fw;
    var spec = 0.0;
    if (HAS_SPECULAR && (q.metallic > 0.0 || f_d > 0.0)) {
        spec = ggx_d(h, q.alpha) * ggx_g2(wo, wi, q.alpha) / (4.0 * wo.z * wi.z);
    }
    let dielectric = (1.0 - f_d) * q.base_color * INV_PI + vec3<f32>(f_d * spec);
    let metal = f_m * spec;
    return (1.0 - q.metallic) * dielectric + q.metallic * metal;
}

/// pdf (solid angle) of metallic_roughness_sample producing wi: the mixture of cosine and visible-normal sampling.
fn metallic_roughness_pdf(q: MetallicRoughnessParams, wo: vec3<f32>, wi: vec3<f32>) -> f32 {
    if (wo.z <= 0.0 || wi.z <= 0.0) { return 0.0; }
    let ps = metallic_roughness_specular_probability(q, wo);
    var pdf = (1.0 - ps) * square_to_cosine_hemisphere_pdf(wi);
    if (HAS_SPECULAR && ps > 0.0) { pdf += ps * ggx_reflection_pdf(wo, wi, q.alpha); }
    return pdf;
}

/// Samples wi: picks a lobe with u_lobe, then cosine (diffuse) or a reflected visible normal (specular).
/// pdf = 0 marks a failed sample (below the surface).
fn metallic_roughness_sample(q: MetallicRoughnessParams, wo: vec3<f32>, u_lobe: f32, u: vec2<f32>) -> BsdfSample {
    var s: BsdfSample;
    s.pdf = 0.0;
    s.f = vec3<f32>(0.0);
    s.delta = false;
    if (wo.z <= 0.0) { return s; }
    let ps = metallic_roughness_specular_probability(q, wo);
    if (HAS_SPECULAR && u_lobe < ps) {
        let h = ggx_sample_visible_normal(wo, q.alpha, u);
        s.wi = reflect(-wo, h);
    } else {
        s.wi = square_to_cosine_hemisphere(u);
    }
    if (s.wi.z <= 0.0) { return s; }
    s.pdf = metallic_roughness_pdf(q, wo, s.wi);
    s.f = metallic_roughness_eval(q, wo, s.wi);
    return s;
}
