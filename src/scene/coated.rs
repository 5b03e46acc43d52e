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

/// Unpolarised Fresnel reflectance of a dielectric interface of relative index `eta` (either side of 1: total
/// internal reflection gives 1), incidence cosine `c` in [0, 1].
fn fresnel_dielectric(c: f64, eta: f64) -> f64 {
    let c = c.clamp(0.0, 1.0);
    let sin2_t = (1.0 - c * c) / (eta * eta);
    if sin2_t >= 1.0 {
        return 1.0;
    }
    let cos_t = (1.0 - sin2_t).sqrt();
    let r_s = (c - eta * cos_t) / (c + eta * cos_t);
    let r_p = (eta * c - cos_t) / (eta * c + cos_t);
    0.5 * (r_s * r_s + r_p * r_p)
}

/// Isotropic microfacet D(m) (m in the upper hemisphere), Beckmann or GGX, as Mitsuba 3 evaluates them.
fn microfacet_d(m: [f64; 3], alpha: f64, beckmann: bool) -> f64 {
    let c2 = m[2] * m[2];
    let t2 = (1.0 - c2).max(0.0) / c2;
    let a2 = alpha * alpha;
    if beckmann {
        (-t2 / a2).exp() / (std::f64::consts::PI * a2 * c2 * c2)
    } else {
        let d = 1.0 + t2 / a2;
        1.0 / (std::f64::consts::PI * a2 * c2 * c2 * d * d)
    }
}

/// Mitsuba 3's Smith G1 of w for the microfacet normal m: Beckmann by Walter et al.'s rational fit, GGX exact;
/// 0 where w sees the back of m.
fn microfacet_g1(w: [f64; 3], m: [f64; 3], alpha: f64, beckmann: bool) -> f64 {
    let dot = w[0] * m[0] + w[1] * m[1] + w[2] * m[2];
    if dot * w[2] <= 0.0 {
        return 0.0;
    }
    let xy2 = alpha * alpha * (w[0] * w[0] + w[1] * w[1]);
    if xy2 <= 0.0 {
        return 1.0;
    }
    let t2 = xy2 / (w[2] * w[2]);
    if beckmann {
        let a = 1.0 / t2.sqrt();
        if a >= 1.6 {
            1.0
        } else {
            (3.535 * a + 2.181 * a * a) / (1.0 + 2.276 * a + 2.577 * a * a)
        }
    } else {
        2.0 / (1.0 + (1.0 + t2).sqrt())
    }
}

/// The directional reflectance of a rough dielectric interface of relative index `eta` (η < 1: seen from the dense
/// side) at incidence cosine `mu`, single scattering with Smith masking, E over the visible normals m of wi of
/// F(wi·m)·G1(wr, m), as Mitsuba 3's `eval_reflectance`. A product quadrature over m in slope space
/// (tanθm = α·tan(v·π/2)), normalised by the quadrature of the visible normals' density itself.
pub fn rough_directional_reflectance(mu: f64, eta: f64, alpha: f64, beckmann: bool) -> f64 {
    use std::f64::consts::PI;
    let mu = mu.clamp(1e-6, 1.0);
    let wi = [(1.0 - mu * mu).sqrt(), 0.0, mu];
    let (nv, nphi) = (192, 96);
    let (mut sum, mut norm) = (0.0, 0.0);
    for i in 0..nv {
        let v = (i as f64 + 0.5) / nv as f64;
        let x = (v * PI / 2.0).tan();
        let theta = (alpha * x).atan();
        // dθ/dv = α (1 + x²)(π/2) / (1 + α² x²)
        let dtheta = alpha * (1.0 + x * x) * (PI / 2.0) / (1.0 + alpha * alpha * x * x) / nv as f64;
        let (st, ct) = theta.sin_cos();
        if ct <= 0.0 {
            continue;
        }
        for j in 0..nphi {
            // φ over [0, π], doubled: wi lies in the xz plane, so the integrand is even in φ.
            let phi = (j as f64 + 0.5) / nphi as f64 * PI;
            let m = [st * phi.cos(), st * phi.sin(), ct];
            let c = wi[0] * m[0] + wi[2] * m[2];
            if c <= 0.0 {
                continue;
            }
            let dm = st * dtheta * (PI / nphi as f64) * 2.0;
            let p = microfacet_g1(wi, m, alpha, beckmann) * c * microfacet_d(m, alpha, beckmann) / mu * dm;
            norm += p;
            let wr = [2.0 * c * m[0] - wi[0], 2.0 * c * m[1] - wi[1], 2.0 * c * m[2] - wi[2]];
            if wr[2] > 0.0 {
                sum += p * fresnel_dielectric(c, eta) * microfacet_g1(wr, m, alpha, beckmann);
            }
        }
    }
    if norm > 0.0 {
        sum / norm
    } else {
        0.0
    }
}

/// The internal diffuse reflectance of Mitsuba 3's `roughplastic` coat (relative index `eta` > 1, isotropic
/// `alpha`): 2·mean over μ = max(10⁻⁶, i/63), i = 0..63, of μ·R(μ) with R the rough interface's directional
/// reflectance from inside (1/η, total internal reflection included) — Mitsuba's own estimate of ∫ R(μ) 2μ dμ.
/// Rough masking makes it smaller than the smooth F̄ᵢ (0.524 against 0.590 for Beckmann α 0.3, η 1.49).
pub fn mitsuba_rough_internal_reflectance(eta: f32, alpha: f32, beckmann: bool) -> f32 {
    let (eta, alpha) = (eta as f64, (alpha as f64).max(1e-4));
    let n = 64;
    let s: f64 = (0..n)
        .map(|i| {
            let mu = (i as f64 / (n - 1) as f64).max(1e-6);
            mu * rough_directional_reflectance(mu, 1.0 / eta, alpha, beckmann)
        })
        .sum();
    (2.0 * s / n as f64) as f32
}

/// The base reflectance R' for which this model's diffuse term R'/(1 − R'·F̄ᵢ) equals `target` (a diffuse term
/// another model computes, e.g. Mitsuba's r/(1 − F̄ᵢ,rough)): R' = T/(1 + T·F̄ᵢ).
pub fn reflectance_for_diffuse_term(target: f32, fi: f32) -> f32 {
    let t = target.max(0.0);
    (t / (1.0 + t * fi)).clamp(0.0, 1.0)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Mitsuba-style rough internal reflectance against values from an independent quadrature (numpy, a
    /// tan-θ grid over D·cos-weighted visible normals): Beckmann, η = 1.49/1.000277.
    #[test]
    fn rough_internal_reflectance_matches_an_independent_quadrature() {
        let eta = 1.49 / 1.000277;
        for (alpha, want) in [(0.1f32, 0.57471f32), (0.3, 0.52364)] {
            let fi = mitsuba_rough_internal_reflectance(eta, alpha, true);
            assert!((fi - want).abs() < 2e-3, "α {alpha}: {fi} vs {want}");
        }
        // Nearly smooth: the smooth F̄ᵢ as Mitsuba's 64-point mean over μ = i/63 estimates it (≈ 63/64 of the
        // integral, as 2μR(μ) vanishes at μ = 0 and is small at 1).
        let smooth = coated_internal_reflectance(eta);
        let fi = mitsuba_rough_internal_reflectance(eta, 0.002, true);
        assert!((fi - smooth * 63.0 / 64.0).abs() < 3e-3, "α 0.002: {fi} vs smooth {smooth} · 63/64");
        // Directional reflectance from outside at normal incidence: the smooth Fresnel term.
        let r = rough_directional_reflectance(1.0, eta as f64, 0.1, true);
        assert!((r - coat_fresnel(1.0, eta as f64)).abs() < 1e-3, "R(1) {r}");
    }
}
