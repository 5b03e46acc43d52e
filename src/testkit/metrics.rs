//! Error metrics of an image against a reference: RMSE, relMSE, mean absolute error, per-pixel relMSE, the
//! efficiency 1 / (relMSE · time), and least-squares log-log slopes (convergence rates).

/// Added to r² in the relMSE denominator so black reference pixels do not dominate.
pub const RELMSE_EPSILON: f64 = 0.01;

/// The error of one image against a reference, over all pixels and channels.
#[derive(Clone, Copy, Debug, Default, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct ErrorMetrics {
    /// √(mean of (x − r)²).
    pub rmse: f64,
    /// Mean of (x − r)² / (r² + 0.01).
    pub relmse: f64,
    /// Mean of |x − r|.
    pub mae: f64,
}

/// Why two images cannot be compared.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum MetricsError {
    #[error("the image has {image} pixels, the reference {reference}")]
    SizeMismatch { image: usize, reference: usize },
    #[error("empty image")]
    Empty,
}
fn check(image: &[[f32; 3]], reference: &[[f32; 3]]) -> Result<(), MetricsError> {
    if image.len() != reference.len() {
        return Err(MetricsError::SizeMismatch { image: image.len(), reference: reference.len() });
    }
    if image.is_empty() {
        return Err(MetricsError::Empty);
    }
    Ok(())
}

/// RMSE, relMSE and MAE of `image` against `reference` (row-major RGB, the same size). Non-finite pixels
/// make the metrics non-finite (they are errors, not something to skip).
pub fn compare(image: &[[f32; 3]], reference: &[[f32; 3]]) -> Result<ErrorMetrics, MetricsError> {
    check(image, reference)?;
    let (mut se, mut rel, mut ae) = (0.0f64, 0.0f64, 0.0f64);
    for (x, r) in image.iter().zip(reference) {
        for c in 0..3 {
            let (x, r) = (x[c] as f64, r[c] as f64);
            let d = x - r;
            se += d * d;
            rel += d * d / (r * r + RELMSE_EPSILON);
            ae += d.abs();
        }
    }
    let n = 3.0 * image.len() as f64;
    Ok(ErrorMetrics { rmse: (se / n).sqrt(), relmse: rel / n, mae: ae / n })
}

/// RMSE of `image` against `reference`.
pub fn rmse(image: &[[f32; 3]], reference: &[[f32; 3]]) -> Result<f64, MetricsError> {
    Ok(compare(image, reference)?.rmse)
}

/// relMSE = mean over pixels and channels of (x − r)² / (r² + 0.01).
pub fn relmse(image: &[[f32; 3]], reference: &[[f32; 3]]) -> Result<f64, MetricsError> {
    Ok(compare(image, reference)?.relmse)
}

/// Mean absolute error.
pub fn mae(image: &[[f32; 3]], reference: &[[f32; 3]]) -> Result<f64, MetricsError> {
    Ok(compare(image, reference)?.mae)
}

/// relMSE of each pixel (mean over its three channels), for heatmaps.
pub fn per_pixel_relmse(image: &[[f32; 3]], reference: &[[f32; 3]]) -> Result<Vec<f64>, MetricsError> {
    check(image, reference)?;
    Ok(image
        .iter()
        .zip(reference)
        .map(|(x, r)| {
            (0..3)
                .map(|c| {
                    let d = x[c] as f64 - r[c] as f64;
                    d * d / (r[c] as f64 * r[c] as f64 + RELMSE_EPSILON)
                })
                .sum::<f64>()
                / 3.0
        })
        .collect())
}

/// Efficiency 1 / (relMSE · seconds): halving the error at equal time or the time at equal error doubles it.
pub fn efficiency(relmse: f64, seconds: f64) -> f64 {
    1.0 / (relmse * seconds)
}

/// Least-squares slope of log y against log x over the points where both are positive and finite (the
/// exponent of a power law y ∝ x^slope), or None with fewer than two such points.
pub fn loglog_slope(xs: &[f64], ys: &[f64]) -> Option<f64> {
    let pts: Vec<(f64, f64)> = xs
        .iter()
        .zip(ys)
        .filter(|(x, y)| **x > 0.0 && **y > 0.0 && x.is_finite() && y.is_finite())
        .map(|(x, y)| (x.ln(), y.ln()))
        .collect();
    if pts.len() < 2 {
        return None;
    }
    let n = pts.len() as f64;
    let (mx, my) = (pts.iter().map(|p| p.0).sum::<f64>() / n, pts.iter().map(|p| p.1).sum::<f64>() / n);
    let sxx: f64 = pts.iter().map(|p| (p.0 - mx) * (p.0 - mx)).sum();
    let sxy: f64 = pts.iter().map(|p| (p.0 - mx) * (p.1 - my)).sum();
    (sxx > 0.0).then(|| sxy / sxx)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn metrics_of_a_known_difference() {
        let r = vec![[1.0f32, 0.0, 2.0]; 4];
        let x = vec![[1.5f32, 0.0, 2.0]; 4];
        let m = compare(&x, &r).unwrap();
        assert!((m.rmse - (0.25f64 / 3.0).sqrt()).abs() < 1e-12);
        assert!((m.relmse - 0.25 / 1.01 / 3.0).abs() < 1e-12);
        assert!((m.mae - 0.5 / 3.0).abs() < 1e-12);
        assert!(compare(&x[..3], &r).is_err());
        assert_eq!(loglog_slope(&[1.0, 10.0, 100.0], &[1.0, 0.1, 0.01]).map(|s| (s * 1e9).round() / 1e9), Some(-1.0));
        assert!((efficiency(0.01, 2.0) - 50.0).abs() < 1e-12);
    }
}
