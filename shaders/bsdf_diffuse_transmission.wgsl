// bsdf_diffuse_transmission.wgsl — Lambert reflection and Lambert transmission (pbrt-v4 DiffuseTransmissionBxDF),
// as the technique triple diffuse_transmission_eval / _sample / _pdf. The contract of bsdf.wgsl (local shading
// frame, z = shading normal, wo and wi away from the surface, eval WITHOUT the cosine), except that wi may lie
// below the surface; the estimator's cosine is |wi.z|.
//   f = R/π where wo and wi are on the same side, T/π where they are on opposite sides.
// Sampling: a lobe by its largest channel (pbrt-v4), then a cosine-weighted direction on that lobe's side.
// Compiled in where the scene has such a material (HAS_DIFFUSE_TRANSMISSION).
// Words (src/render/materials.rs `pack_diffuse_transmission`): params0 = (R, 1 where the base texture tints T too),
// params1.xyz = T. The base texture multiplies R.

struct DiffuseTransmissionParams {
    reflectance: vec3<f32>,
    transmittance: vec3<f32>,
}

fn diffuse_transmission_params(p: BsdfParams) -> DiffuseTransmissionParams {
    let t = select(vec3<f32>(1.0), p.tex_base, p.params0.w > 0.0);
    return DiffuseTransmissionParams(p.params0.xyz * p.tex_base, p.params1.xyz * t);
}

fn diffuse_transmission_is_delta(q: DiffuseTransmissionParams) -> bool { return false; }

fn diffuse_transmission_has_delta_lobe(q: DiffuseTransmissionParams) -> bool { return false; }

/// Probability of sampling the reflection lobe: max(R) / (max(R) + max(T)); 0.5 for a black surface.
fn diffuse_transmission_reflect_probability(q: DiffuseTransmissionParams) -> f32 {
    let pr = max(q.reflectance.x, max(q.reflectance.y, q.reflectance.z));
    let pt = max(q.transmittance.x, max(q.transmittance.y, q.transmittance.z));
    if (!(pr + pt > 0.0)) { return 0.5; }
    return pr / (pr + pt);
}

/// f(wo, wi) without the cosine.
fn diffuse_transmission_eval(q: DiffuseTransmissionParams, wo: vec3<f32>, wi: vec3<f32>) -> vec3<f32> {
    if (wo.z == 0.0 || wi.z == 0.0) { return vec3<f32>(0.0); }
    if (wo.z * wi.z > 0.0) { return q.reflectance * INV_PI; }
    return q.transmittance * INV_PI;
}

/// pdf (solid angle) of diffuse_transmission_sample producing wi.
fn diffuse_transmission_pdf(q: DiffuseTransmissionParams, wo: vec3<f32>, wi: vec3<f32>) -> f32 {
    if (wo.z == 0.0 || wi.z == 0.0) { return 0.0; }
    let pr = diffuse_transmission_reflect_probability(q);
    let lobe = select(1.0 - pr, pr, wo.z * wi.z > 0.0);
    return lobe * abs(wi.z) * INV_PI;
}

/// Samples wi: the lobe with u_lobe, a cosine-weighted direction with u, on wo's side (reflection) or the other
/// (transmission). pdf = 0 marks a failed sample.
fn diffuse_transmission_sample(q: DiffuseTransmissionParams, wo: vec3<f32>, u_lobe: f32, u: vec2<f32>) -> BsdfSample {
    var s: BsdfSample;
    s.pdf = 0.0;
    s.f = vec3<f32>(0.0);
    s.delta = false;
    if (wo.z == 0.0) { return s; }
    var w = square_to_cosine_hemisphere(u);
    let side = select(-1.0, 1.0, wo.z > 0.0);
    let reflect_lobe = u_lobe < diffuse_transmission_reflect_probability(q);
    s.wi = vec3<f32>(w.x, w.y, w.z * select(-side, side, reflect_lobe));
    if (s.wi.z == 0.0) { return s; }
    s.pdf = diffuse_transmission_pdf(q, wo, s.wi);
    s.f = diffuse_transmission_eval(q, wo, s.wi);
    return s;
}
