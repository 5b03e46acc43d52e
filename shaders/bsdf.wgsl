// bsdf.wgsl — the material contract, and the microfacet functions the materials share.
//
// Every material kind K (src/render/materials.rs `MATERIALS`: its tag, name and file) is one file,
// shaders/bsdf_K.wgsl, with its own parameter struct and these functions, in the local shading frame (z = shading
// normal, wo and wi pointing away from the surface):
//
//   K_params(p: BsdfParams) -> KParams             its parameters at the shading point, read from its words p.params*
//                                                  (the layout its registry entry's `pack` writes), with the textures
//                                                  it uses applied (p.tex_base, p.tex_mr) and, where it cares, the side
//                                                  the ray arrived from (p.front)
//   K_eval(q, wo, wi) -> vec3<f32>                 f (BRDF or BTDF) WITHOUT the cosine (the lecture's brdf.eval: the
//                                                  estimator multiplies by |wi.z|); 0 for delta lobes
//   K_pdf(q, wo, wi) -> f32                        the solid-angle density of K_sample producing wi; 0 for delta lobes
//   K_sample(q, wo, u_lobe, u: vec2) -> BsdfSample a direction, its pdf and f (pdf = 0: failed)
//   K_is_delta(q) -> bool                          delta lobes only (light sampling cannot contribute)
//   K_has_delta_lobe(q) -> bool                    a delta lobe beside others (a smooth coat's mirror)
//
// A kind whose registry entry says it transmits lets wi lie below the surface. The dispatchers bsdf_eval /
// bsdf_pdf / bsdf_sample / bsdf_is_delta / bsdf_has_delta_lobe / bsdf_transmits are generated from the registry
// (src/render/materials.rs `dispatch_wgsl`), one `if (HAS_K && p.bsdf_kind == MATERIAL_K)` line per kind each, so a
// kind the scene does not use is compiled out; the tags and HAS_* overrides are generated there too.

/// What a material's BSDF needs at one shading point: its kind, its parameter words (the kind's own layout, as
/// stored in `Material`), the texture values at the point and the side the ray arrived from.
struct BsdfParams {
    bsdf_kind: u32,          // MATERIAL_* (generated from src/render/materials.rs)
    params0: vec4<f32>,
    params1: vec4<f32>,
    params2: vec4<f32>,
    tex_base: vec3<f32>,     // the base-colour texture at the point; 1 without one
    has_tex_mr: bool,        // a glTF metallic-roughness texture is bound (tex_mr holds its value)
    tex_mr: vec4<f32>,
    front: bool,             // the ray arrived from the side the geometric normal points to
}

/// The BsdfParams of a kind's words, untextured and seen from the front (probe kernels build them so).
fn bsdf_params(kind: u32, params0: vec4<f32>, params1: vec4<f32>, params2: vec4<f32>) -> BsdfParams {
    return BsdfParams(kind, params0, params1, params2, vec3<f32>(1.0), false, vec4<f32>(1.0), true);
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

// ---- isotropic GGX (Trowbridge–Reitz) ----

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

// ---- anisotropic GGX, α_u along the frame's tangent x and α_v along its bitangent y (Heitz 2014, eq. 85) ----

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

// ---- anisotropic Beckmann–Spizzichino (Walter et al. 2007; as Mitsuba 3 evaluates it) ----

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
