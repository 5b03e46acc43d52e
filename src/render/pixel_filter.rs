//! The pixel filter's numbers on the CPU: the gaussian's normalisation that the shader's weights divide by, and the
//! shader's sampling of each filter written again in Rust (`sample_axis`), so tests check its distribution against
//! the filter's shape (shaders/pixel_filter.wgsl says how and why).

use crate::render::settings::PixelFilter;

/// The scale of the logistic the gaussian is drawn from: 0.6σ where the radius is wide (r ≥ 2σ), 0.3r where the
/// filter is a cap cut from the gaussian's top; within 0.01 of the E[w²]-minimising scale for r/σ from 0.01 to 32.
pub fn gaussian_proposal_scale(radius: f64, sigma: f64) -> f64 {
    (0.6 * sigma).min(0.3 * radius)
}

/// pbrt-v4's gaussian filter along one axis: a normal density's shape of deviation σ less its value at r, so it
/// falls to zero there (up to a constant factor, which the normalisation removes).
pub fn gaussian(x: f64, radius: f64, sigma: f64) -> f64 {
    let g = |t: f64| (-t * t / (2.0 * sigma * sigma)).exp();
    if x.abs() >= radius {
        0.0
    } else {
        (g(x) - g(radius)).max(0.0)
    }
}

/// The filter's value along one axis (unnormalised).
pub fn value(filter: PixelFilter, radius: f64, sigma: f64, x: f64) -> f64 {
    match filter {
        _ if x.abs() > radius => 0.0,
        PixelFilter::Box => 1.0,
        PixelFilter::Triangle => radius - x.abs(),
        PixelFilter::Gaussian => gaussian(x, radius, sigma),
    }
}

/// ∫ of `gaussian` over [−r, r] by composite Simpson (the integrand is smooth; 4096 panels give ~1e-12).
pub fn gaussian_integral(radius: f64, sigma: f64) -> f64 {
    let n = 4096;
    let h = 2.0 * radius / n as f64;
    let mut sum = gaussian(-radius, radius, sigma) + gaussian(radius, radius, sigma);
    for i in 1..n {
        let x = -radius + i as f64 * h;
        sum += if i % 2 == 1 { 4.0 } else { 2.0 } * gaussian(x, radius, sigma);
    }
    sum * h / 3.0
}

/// The shader's `filter_norm`: 1 / `gaussian_integral` for the gaussian, which alone weighs its samples (0 for the
/// others, and where the integral vanishes, which validation rules out). A quadrature: not worth doing per dispatch
/// for filters that do not use it.
pub fn shader_norm(filter: PixelFilter, radius: f32, sigma: f32) -> f32 {
    if filter != PixelFilter::Gaussian {
        return 0.0;
    }
    let g = gaussian_integral(radius as f64, sigma as f64);
    if g > 0.0 {
        (1.0 / g) as f32
    } else {
        0.0
    }
}

/// The shader's sample along one axis of the unit interval's `u`: (offset from the pixel's centre, weight); `norm`
/// is 1 / `gaussian_integral(radius, sigma)`.
pub fn sample_axis(filter: PixelFilter, radius: f64, sigma: f64, norm: f64, u: f64) -> (f64, f64) {
    match filter {
        PixelFilter::Box => ((2.0 * u - 1.0) * radius, 1.0),
        PixelFilter::Triangle => {
            let t = if u >= 0.5 { 1.0 - (2.0 - 2.0 * u).sqrt() } else { (2.0 * u).sqrt() - 1.0 };
            (radius * t, 1.0)
        }
        PixelFilter::Gaussian => {
            let s = gaussian_proposal_scale(radius, sigma);
            let lo = 1.0 / (1.0 + (radius / s).exp());
            let mass = 1.0 - 2.0 * lo;
            let v = lo + u * mass;
            let x = (s * (v / (1.0 - v)).ln()).clamp(-radius, radius);
            let e = (-x.abs() / s).exp();
            let pdf = e / (s * (1.0 + e) * (1.0 + e) * mass);
            let w = if pdf > 0.0 { gaussian(x, radius, sigma) * norm / pdf } else { 0.0 };
            (x, w)
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Over a fine grid of u, the weighted samples of each filter fall into bins in proportion to the filter's
    /// integral over each bin: the sampling and its weights realise the filter's shape, normalised.
    #[test]
    fn each_filter_is_sampled_in_proportion_to_its_shape() {
        for (filter, radius, sigma) in [
            (PixelFilter::Box, 0.5, 0.5),
            (PixelFilter::Box, 1.5, 0.5),
            (PixelFilter::Triangle, 1.0, 0.5),
            (PixelFilter::Triangle, 2.0, 0.5),
            (PixelFilter::Gaussian, 1.5, 0.5),
            (PixelFilter::Gaussian, 2.0, 0.5),
            (PixelFilter::Gaussian, 0.5, 2.0),
            (PixelFilter::Gaussian, 3.0, 1.0),
            (PixelFilter::Gaussian, 0.1, 1.0),
            (PixelFilter::Gaussian, 16.0, 0.5),
        ] {
            let bins = 24;
            let n = 400_000;
            let mut got = vec![0.0; bins];
            let norm = 1.0 / gaussian_integral(radius, sigma);
            let (mut w_sum, mut w2_sum, mut w_max) = (0.0, 0.0, 0.0f64);
            for i in 0..n {
                let u = (i as f64 + 0.5) / n as f64;
                let (x, w) = sample_axis(filter, radius, sigma, norm, u);
                assert!(x.abs() <= radius && w.is_finite() && w >= 0.0, "{filter} r {radius}: x {x} w {w}");
                let b = (((x + radius) / (2.0 * radius)) * bins as f64).min(bins as f64 - 1.0) as usize;
                got[b] += w / n as f64;
                (w_sum, w2_sum, w_max) = (w_sum + w, w2_sum + w * w, w_max.max(w));
            }
            let integral = |a: f64, z: f64| -> f64 {
                (0..1024).map(|k| value(filter, radius, sigma, a + (k as f64 + 0.5) * (z - a) / 1024.0)).sum::<f64>()
                    * (z - a)
                    / 1024.0
            };
            let total = integral(-radius, radius);
            for (b, g) in got.iter().enumerate() {
                let (a, z) = (
                    -radius + b as f64 * 2.0 * radius / bins as f64,
                    -radius + (b + 1) as f64 * 2.0 * radius / bins as f64,
                );
                let want = integral(a, z) / total;
                assert!((g - want).abs() < 2e-4, "{filter} r {radius} σ {sigma}: bin {b} has {g}, the filter {want}");
            }
            assert!((w_sum / n as f64 - 1.0).abs() < 1e-4, "{filter}: weights average {}", w_sum / n as f64);
            if filter == PixelFilter::Gaussian {
                let second = w2_sum / n as f64;
                assert!(second < 1.04 && w_max < 1.35, "gaussian r {radius} σ {sigma}: E[w²] {second}, max {w_max}");
            } else {
                assert_eq!(w_max, 1.0);
            }
        }
    }

    #[test]
    fn the_gaussian_integral_is_the_closed_form() {
        // ∫_{−r}^{r} e^{−x²/2σ²} dx − 2r e^{−r²/2σ²}, with erf(1.5/(0.5√2)) = erf(3/√2) = 0.997300203936740.
        let (r, s) = (1.5f64, 0.5f64);
        let want =
            s * (2.0 * std::f64::consts::PI).sqrt() * 0.997_300_203_936_740 - 2.0 * r * (-r * r / (2.0 * s * s)).exp();
        assert!((gaussian_integral(r, s) - want).abs() < 1e-10, "{} vs {want}", gaussian_integral(r, s));
    }
}
