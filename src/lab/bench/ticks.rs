//! Tick positions and labels for log axes: decades where the range spans several, 1-2-5 or 1…9 per decade where
//! it spans less (plotters' own log ticks leave a sub-decade axis unlabelled and repeat labels once rounded), and
//! integer ticks for sample counts.

/// Bold (labelled) and light (grid only) ticks of a log axis over `lo..hi` (both > 0).
pub fn log_ticks(lo: f64, hi: f64) -> (Vec<f64>, Vec<f64>) {
    if !(lo > 0.0 && hi > lo && hi.is_finite()) {
        return (vec![], vec![]);
    }
    let in_range = |v: &f64| *v >= lo * (1.0 - 1e-9) && *v <= hi * (1.0 + 1e-9);
    let (d0, d1) = (lo.log10().floor() as i32, hi.log10().ceil() as i32);
    let with = |mantissas: &[f64]| -> Vec<f64> {
        (d0..=d1).flat_map(|d| mantissas.iter().map(move |m| m * 10f64.powi(d))).filter(in_range).collect()
    };
    let decades = with(&[1.0]);
    if decades.len() >= 2 {
        // At most about 8 labels: every k-th decade.
        let k = decades.len().div_ceil(8);
        let bold: Vec<f64> =
            decades.iter().copied().filter(|v| (v.log10().round() as i32).rem_euclid(k as i32) == 0).collect();
        let bold = if bold.len() >= 2 { bold } else { decades };
        return (bold, with(&[1.0, 2.0, 3.0, 4.0, 5.0, 6.0, 7.0, 8.0, 9.0]));
    }
    let all = with(&[1.0, 2.0, 3.0, 4.0, 5.0, 6.0, 7.0, 8.0, 9.0]);
    let coarse = with(&[1.0, 2.0, 5.0]);
    if coarse.len() >= 3 {
        (coarse, all)
    } else if all.len() >= 2 {
        (all.clone(), all)
    } else {
        // Less than one step of 1…9 (e.g. 12 … 19): the ends as well.
        let mut bold = vec![lo, hi];
        bold.extend(&all);
        bold.sort_by(f64::total_cmp);
        (bold, all)
    }
}

/// Ticks of a sample-count axis over `lo..hi`: powers of two (every k-th so at most about 11), as integers.
pub fn spp_ticks(lo: f64, hi: f64) -> Vec<f64> {
    let p: Vec<f64> = (0..32).map(|k| (1u64 << k) as f64).filter(|v| *v >= lo && *v <= hi).collect();
    let k = p.len().div_ceil(11).max(1);
    p.into_iter().enumerate().filter(|(i, _)| i % k == 0).map(|(_, v)| v).collect()
}

/// A tick's label: plain decimals from 0.001 to 9999 ("0.05", "20"), otherwise "1e-5" / "2e6". Ticks from
/// `log_ticks` have one significant digit, so their labels never repeat.
pub fn label(v: f64) -> String {
    if !(v.is_finite() && v > 0.0) {
        return format!("{v}");
    }
    let e = v.log10().floor() as i32;
    let m = v / 10f64.powi(e);
    // Round the mantissa to what a one-digit tick is; fall back to three digits for other values.
    let m = if (m - m.round()).abs() < 1e-6 { m.round() } else { (m * 100.0).round() / 100.0 };
    if (-3..4).contains(&e) {
        let decimals = if e >= 0 { 0 } else { (-e) as usize + if m.fract() == 0.0 { 0 } else { 2 } };
        let s = format!("{:.*}", decimals, m * 10f64.powi(e));
        if s.contains('.') {
            s.trim_end_matches('0').trim_end_matches('.').to_string()
        } else {
            s
        }
    } else if m == 1.0 {
        format!("1e{e}")
    } else {
        format!("{}e{e}", format!("{m:.2}").trim_end_matches('0').trim_end_matches('.'))
    }
}

/// A value on a colour bar whose scale is log10: 10^x with two significant digits ("4e-3", "0.25").
pub fn label_log10(x: f64) -> String {
    let v = 10f64.powf(x);
    if !(v.is_finite() && v > 0.0) {
        return format!("{v}");
    }
    let e = v.log10().floor() as i32;
    label(((v / 10f64.powi(e)) * 10.0).round() / 10.0 * 10f64.powi(e))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sub_decade_ranges_get_labels_and_labels_never_repeat() {
        // error-vs-time often spans 0.03 … 0.09 s: under a decade.
        let (bold, _) = log_ticks(0.023, 0.117);
        assert!(bold.len() >= 3, "{bold:?}");
        let labels: Vec<String> = bold.iter().map(|&v| label(v)).collect();
        assert_eq!(labels, ["0.03", "0.04", "0.05", "0.06", "0.07", "0.08", "0.09", "0.1"]);
        for (lo, hi) in [(1e-5, 3e-1), (7.0, 40.0), (0.5, 1.6), (1e-9, 1e9), (12.0, 19.0)] {
            let (bold, light) = log_ticks(lo, hi);
            assert!(bold.len() >= 2 && bold.len() <= 10, "{lo}..{hi}: {bold:?}");
            assert!(bold.iter().chain(&light).all(|v| *v >= lo * 0.999 && *v <= hi * 1.001));
            let mut l: Vec<String> = bold.iter().map(|&v| label(v)).collect();
            l.dedup();
            assert_eq!(l.len(), bold.len(), "{lo}..{hi}: repeated labels {l:?}");
        }
        assert_eq!(
            log_ticks(1e-5, 3e-1).0.iter().map(|&v| label(v)).collect::<Vec<_>>(),
            ["1e-5", "1e-4", "0.001", "0.01", "0.1"]
        );
    }

    #[test]
    fn spp_ticks_are_integers_and_colour_bar_labels_are_values() {
        let t = spp_ticks(1.0 / 1.3, 64.0 * 1.3);
        assert_eq!(t.iter().map(|&v| label(v)).collect::<Vec<_>>(), ["1", "2", "4", "8", "16", "32", "64"]);
        assert!(spp_ticks(1.0, 1e9).len() <= 11);
        assert_eq!(label_log10(0.6), "4");
        assert_eq!(label_log10(-2.4), "0.004");
        assert_eq!(label_log10(-5.0), "1e-5");
        assert!(!label_log10(0.6).contains("e0."));
    }
}
