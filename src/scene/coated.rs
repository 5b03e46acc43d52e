//! The coated diffuse model's CPU side (shaders/bsdf_coated_diffuse.wgsl): the coat's Fresnel term, its internal
//! diffuse reflectance F̄ᵢ, and the conversion of Mitsuba's linear reflectance parameterisation onto the model.

/// F̄ᵢ, the cosine-weighted hemispherical reflectance of a smooth dielectric coat of relative index `eta` seen from
/// inside: 1 − (1 − F̄ₑ)/η² with F̄ₑ = ∫₀¹ F(c)·2c dc from outside, by the same 8-point Gauss–Legendre rule as
/// shaders/bsdf_coated_diffuse.wgsl (so the importers' conversions match the GPU model).
pub fn coated_internal_reflectance(eta: f32) -> f32 {
    const X: [f64; 4] = [0.48014492824876814, 0.39833323870681336, 0.2627662049581645, 0.0917173212478249];
    const W: [f64; 4] = [0.05061426814518815, 0.11119051722668725, 0.15685332293894366, 0.181341891689181];
    let eta = eta as f64;
    let fe: f64 = X
        .iter()
        .zip(W)
        .map(|(x, w)| w * 2.0 * ((0.5 - x) * coat_fresnel(0.5 - x, eta) + (0.5 + x) * coat_fresnel(0.5 + x, eta)))
        .sum();
    (1.0 - (1.0 - fe) / (eta * eta)) as f32
}

/// Unpolarised Fresnel reflectance of a dielectric of relative index `eta` ≥ 1, light from the outside at
/// incidence cosine `c`.
pub fn coat_fresnel(c: f64, eta: f64) -> f64 {
    let c = c.clamp(0.0, 1.0);
    let cos_t = (1.0 - (1.0 - c * c) / (eta * eta)).max(0.0).sqrt();
    let r_s = (c - eta * cos_t) / (c + eta * cos_t);
    let r_p = (eta * c - cos_t) / (eta * c + cos_t);
    0.5 * (r_s * r_s + r_p * r_p)
}

/// The base reflectance R' for which this model's diffuse term R'/(1 − R'·F̄ᵢ) equals that of Mitsuba's default
/// `nonlinear = false` parameterisation, r/(1 − F̄ᵢ) (there `r` is the base's share of the albedo, not the base's
/// reflectance): R' = r / (1 − F̄ᵢ + r·F̄ᵢ), per channel. Exact for constant colours; textures are scaled by the
/// ratio at their mean factor (docs/materials.md).
pub fn reflectance_from_linear(r: f32, fi: f32) -> f32 {
    let r = r.clamp(0.0, 1.0);
    r / (1.0 - fi + r * fi)
}
