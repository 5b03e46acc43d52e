// mis.wgsl — multiple importance sampling weights (Veach 1997, ch. 9), in ratio form so that huge or
// infinite pdfs give 0 or 1 instead of NaN (f²/(f²+g²) is NaN at f = 1e20; 1/(1 + (g/f)²) is not).

/// Weight of technique a (n_a samples, pdf p_a) against technique b (n_b samples, pdf p_b) under the
/// active heuristic: balance n_a p_a / Σ, power (n_a p_a)^β / Σ (n p)^β.
fn mis_weight(n_a: f32, p_a: f32, n_b: f32, p_b: f32) -> f32 {
    let fa = n_a * p_a;
    let fb = n_b * p_b;
    if (!(fa > 0.0)) { return 0.0; }
    if (!(fb > 0.0)) { return 1.0; }
    let r = fb / fa;
    if (is_nonfinite(r)) { return select(1.0, 0.0, r > 1.0); }
    if (cfg_heuristic() == HEURISTIC_BALANCE) { return 1.0 / (1.0 + r); }
    let rb = pow(r, params.power_beta);
    if (is_nonfinite(rb)) { return 0.0; }
    return 1.0 / (1.0 + rb);
}
