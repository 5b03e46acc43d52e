//! The statistics of the test: ln Γ, the regularised incomplete gamma functions, the chi-square survival
//! function, the Šidák correction, Gauss–Legendre nodes, and Pearson's statistic with pooling of sparse cells.

use std::f64::consts::PI;

// ---------------------------------------------------------------------------------------------------------------
// Special functions

/// ln Γ(x) for x > 0 (Lanczos approximation, g = 7, 9 terms; relative error ~1e-15).
pub fn ln_gamma(x: f64) -> f64 {
    const G: f64 = 7.0;
    const C: [f64; 9] = [
        0.999_999_999_999_809_9,
        676.520_368_121_885_1,
        -1_259.139_216_722_402_8,
        771.323_428_777_653_1,
        -176.615_029_162_140_6,
        12.507_343_278_686_905,
        -0.138_571_095_265_720_12,
        9.984_369_578_019_572e-6,
        1.505_632_735_149_311_6e-7,
    ];
    if x < 0.5 {
        // Reflection: Γ(x)Γ(1 − x) = π / sin(πx).
        return (PI / (PI * x).sin()).ln() - ln_gamma(1.0 - x);
    }
    let x = x - 1.0;
    let mut a = C[0];
    let t = x + G + 0.5;
    for (i, c) in C.iter().enumerate().skip(1) {
        a += c / (x + i as f64);
    }
    0.5 * (2.0 * PI).ln() + (x + 0.5) * t.ln() - t + a.ln()
}

/// Iteration bound of the series and continued fraction below: both need O(√a) terms, so this covers
/// a up to ~10⁸ (the loops must be bounded; see PLATFORM.md on runaway loops, which applies to habits, not the CPU).
const GAMMA_MAX_ITER: usize = 1_000_000;

/// Regularised lower incomplete gamma P(a, x) = γ(a, x)/Γ(a), a > 0, x ≥ 0 (Numerical Recipes §6.2: the series
/// for x < a + 1, else 1 − the continued fraction).
pub fn gamma_p(a: f64, x: f64) -> f64 {
    assert!(a > 0.0 && x >= 0.0, "gamma_p({a}, {x}) needs a > 0, x ≥ 0");
    if x == 0.0 {
        return 0.0;
    }
    if x < a + 1.0 {
        gamma_series(a, x)
    } else {
        1.0 - gamma_cont_fraction(a, x)
    }
}

/// Regularised upper incomplete gamma Q(a, x) = 1 − P(a, x), computed directly in the tail (no cancellation).
pub fn gamma_q(a: f64, x: f64) -> f64 {
    assert!(a > 0.0 && x >= 0.0, "gamma_q({a}, {x}) needs a > 0, x ≥ 0");
    if x == 0.0 {
        return 1.0;
    }
    if x < a + 1.0 {
        1.0 - gamma_series(a, x)
    } else {
        gamma_cont_fraction(a, x)
    }
}

/// P(a, x) by its series e^{−x} x^a / Γ(a+1) · Σ xⁿ / ((a+1)…(a+n)).
fn gamma_series(a: f64, x: f64) -> f64 {
    let mut ap = a;
    let mut del = 1.0 / a;
    let mut sum = del;
    for _ in 0..GAMMA_MAX_ITER {
        ap += 1.0;
        del *= x / ap;
        sum += del;
        if del.abs() < sum.abs() * 1e-16 {
            break;
        }
    }
    (sum.ln() - x + a * x.ln() - ln_gamma(a)).exp()
}

/// Q(a, x) by its continued fraction (modified Lentz).
fn gamma_cont_fraction(a: f64, x: f64) -> f64 {
    const TINY: f64 = 1e-300;
    let mut b = x + 1.0 - a;
    let mut c = 1.0 / TINY;
    let mut d = 1.0 / b;
    let mut h = d;
    for i in 1..GAMMA_MAX_ITER {
        let an = -(i as f64) * (i as f64 - a);
        b += 2.0;
        d = an * d + b;
        if d.abs() < TINY {
            d = TINY;
        }
        c = b + an / c;
        if c.abs() < TINY {
            c = TINY;
        }
        d = 1.0 / d;
        let del = d * c;
        h *= del;
        if (del - 1.0).abs() < 1e-16 {
            break;
        }
    }
    (-x + a * x.ln() - ln_gamma(a)).exp() * h
}

/// Survival function of the chi-square distribution with `dof` degrees of freedom: P(X² ≥ stat) = Q(dof/2, stat/2).
pub fn chi2_sf(stat: f64, dof: f64) -> f64 {
    if dof <= 0.0 {
        return 1.0;
    }
    gamma_q(0.5 * dof, 0.5 * stat.max(0.0))
}

/// Per-test level of `m` independent tests at family-wise level `alpha` (Šidák): 1 − (1 − α)^(1/m).
pub fn sidak_alpha(alpha: f64, m: usize) -> f64 {
    1.0 - (1.0 - alpha).powf(1.0 / m.max(1) as f64)
}

/// Gauss–Legendre nodes and weights of order `n` on [0, 1] (Newton on Pₙ from the Chebyshev guesses).
pub fn gauss_legendre(n: usize) -> Vec<(f64, f64)> {
    assert!(n >= 1);
    let mut out = Vec::with_capacity(n);
    for i in 0..n {
        let mut x = (PI * (i as f64 + 0.75) / (n as f64 + 0.5)).cos();
        let mut dp = 1.0;
        for _ in 0..100 {
            // P_n(x) and P_n'(x) by the three-term recurrence.
            let (mut p0, mut p1) = (1.0, x);
            for k in 2..=n {
                let p2 = ((2 * k - 1) as f64 * x * p1 - (k - 1) as f64 * p0) / k as f64;
                p0 = p1;
                p1 = p2;
            }
            let pn = if n == 1 { x } else { p1 };
            let pn1 = if n == 1 { 1.0 } else { p0 };
            dp = n as f64 * (x * pn - pn1) / (x * x - 1.0);
            let dx = pn / dp;
            x -= dx;
            if dx.abs() < 1e-15 {
                break;
            }
        }
        let w = 2.0 / ((1.0 - x * x) * dp * dp);
        out.push((0.5 * (1.0 - x), 0.5 * w));
    }
    out.sort_by(|a, b| a.0.total_cmp(&b.0));
    out
}

// ---------------------------------------------------------------------------------------------------------------
// Pearson's test with pooling

/// Pearson's statistic over cells of observed and expected counts.
#[derive(Clone, Debug, Default)]
pub struct Pearson {
    /// Σ (O − E)² / E over the cells kept and the pooled cell.
    pub statistic: f64,
    /// Degrees of freedom: cells kept (+1 for the pool) − 1.
    pub dof: usize,
    /// P(X² ≥ statistic).
    pub p_value: f64,
    /// Cells merged into the pool (expected < `min_expected`).
    pub pooled_cells: usize,
    /// Samples observed in cells whose expected count is exactly 0.
    pub zero_cell_hits: u64,
}

/// Pearson's chi-square test. Cells are visited in increasing order of expected count; those expecting fewer
/// than `min_expected` samples go into one pooled cell, which keeps absorbing cells until it expects at least
/// `min_expected` (pbrt-v4's `Chi2Test`). Cells with expected count 0 are left out and their samples counted in
/// `zero_cell_hits` (the caller fails the test on any).
pub fn pearson(observed: &[f64], expected: &[f64], min_expected: f64) -> Pearson {
    assert_eq!(observed.len(), expected.len());
    let mut order: Vec<usize> = (0..expected.len()).collect();
    order.sort_by(|&a, &b| expected[a].total_cmp(&expected[b]));
    let mut r = Pearson::default();
    let (mut pool_o, mut pool_e) = (0.0, 0.0);
    let mut kept = 0usize;
    for i in order {
        let (o, e) = (observed[i], expected[i]);
        if e <= 0.0 {
            r.zero_cell_hits += o as u64;
        } else if e < min_expected || (pool_e > 0.0 && pool_e < min_expected) {
            pool_o += o;
            pool_e += e;
            r.pooled_cells += 1;
        } else {
            r.statistic += (o - e) * (o - e) / e;
            kept += 1;
        }
    }
    if pool_e > 0.0 {
        r.statistic += (pool_o - pool_e) * (pool_o - pool_e) / pool_e;
        kept += 1;
    }
    r.dof = kept.saturating_sub(1);
    r.p_value = chi2_sf(r.statistic, r.dof as f64);
    r
}

#[cfg(test)]
mod tests {
    use super::*;

    fn close(a: f64, b: f64, rel: f64) -> bool {
        (a - b).abs() <= rel * b.abs().max(1e-300)
    }

    #[test]
    fn ln_gamma_known_values() {
        assert!(ln_gamma(1.0).abs() < 1e-14 && ln_gamma(2.0).abs() < 1e-14);
        assert!(close(ln_gamma(0.5), PI.sqrt().ln(), 1e-14));
        assert!(close(ln_gamma(10.0), 362880.0f64.ln(), 1e-14));
        // ln Γ(100) = ln 99!.
        assert!(close(ln_gamma(100.0), 359.134_205_369_575_4, 1e-13));
    }

    #[test]
    fn incomplete_gamma_known_values() {
        // Q(1, x) = e^{−x}; P(0.5, x) = erf(√x); chi-square tables.
        for x in [0.01, 0.5, 1.0, 3.0, 20.0] {
            assert!(close(gamma_q(1.0, x), (-x).exp(), 1e-12), "Q(1, {x})");
            assert!(close(gamma_p(1.0, x), 1.0 - (-x).exp(), 1e-12), "P(1, {x})");
        }
        // erf(1) = 0.8427007929497149.
        assert!(close(gamma_p(0.5, 1.0), 0.842_700_792_949_714_9, 1e-12));
        // Q(3, 2) = e^{−2}(1 + 2 + 2) = 5e^{−2}.
        assert!(close(gamma_q(3.0, 2.0), 5.0 * (-2.0f64).exp(), 1e-12));
        // Upper 1 % points of chi-square: dof 1: 6.634897, 10: 23.209251, 100: 135.806723, 1000: 1106.969.
        assert!(close(chi2_sf(6.634_896_601, 1.0), 0.01, 1e-6));
        assert!(close(chi2_sf(23.209_251_159, 10.0), 0.01, 1e-6));
        assert!(close(chi2_sf(135.806_723, 100.0), 0.01, 1e-5));
        assert!(close(chi2_sf(1_106.969_2, 1000.0), 0.01, 1e-4));
        // Median-ish of a large dof: P(X² ≥ k) for k = 20000 is a bit below 0.5 (skew): 0.4986700…
        let p = chi2_sf(20000.0, 20000.0);
        assert!(p > 0.49 && p < 0.5, "{p}");
        // Symmetric checks P + Q = 1 across the series / continued fraction switch.
        for (a, x) in [(0.5, 0.2), (5.0, 5.5), (5.0, 6.5), (5000.0, 4990.0), (5000.0, 5100.0)] {
            assert!(close(gamma_p(a, x) + gamma_q(a, x), 1.0, 1e-10), "P+Q at ({a}, {x})");
        }
    }

    #[test]
    fn sidak_level() {
        assert!(close(sidak_alpha(0.01, 1), 0.01, 1e-12));
        let a = sidak_alpha(0.01, 50);
        assert!(close(1.0 - (1.0 - a).powi(50), 0.01, 1e-10));
    }

    #[test]
    fn gauss_legendre_is_exact_for_polynomials() {
        for n in 1..=8 {
            let g = gauss_legendre(n);
            assert!(close(g.iter().map(|p| p.1).sum::<f64>(), 1.0, 1e-14));
            for k in 0..2 * n {
                let integral: f64 = g.iter().map(|&(x, w)| w * x.powi(k as i32)).sum();
                assert!(close(integral, 1.0 / (k as f64 + 1.0), 1e-12), "n = {n}, x^{k}: {integral}");
            }
        }
    }
}
