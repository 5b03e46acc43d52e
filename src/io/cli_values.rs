//! Value parsers for numeric command-line flags: each refuses what its TOML twin refuses (NaN, infinities,
//! out-of-range values) at parse time, so a bad flag is a usage error (exit 2) naming the flag, before any
//! work starts, and `--spp 0` and `--spp 4294967296` get the same kind of message.

/// A finite f32, or the reason it is not one (f32 overflow included: "1e39" parses to infinity).
fn finite(s: &str) -> Result<f32, String> {
    let v: f32 = s.trim().parse().map_err(|_| format!("'{}' is not a number", crate::io::input_file::clip(s, 40)))?;
    if !v.is_finite() {
        return Err(format!("{} is not a finite number", crate::io::input_file::clip(s, 40)));
    }
    Ok(v)
}

/// Largest |exposure| in stops: 2^64 times any radiance an image holds is still a finite f32.
pub const MAX_EXPOSURE: f32 = 64.0;

/// `--exposure`: finite, in [-64, 64] stops.
pub fn exposure(s: &str) -> Result<f32, String> {
    let v = finite(s)?;
    if v.abs() > MAX_EXPOSURE {
        return Err(format!("{v} stops is out of range (-{MAX_EXPOSURE}..={MAX_EXPOSURE})"));
    }
    Ok(v)
}

/// `--env-scale`: finite, in [0, 1e30] (as the TOML environment's `scale`).
pub fn env_scale(s: &str) -> Result<f32, String> {
    let v = finite(s)?;
    if !(0.0..=1e30).contains(&v) {
        return Err(format!("{v} is out of range (a scale in [0, 1e30])"));
    }
    Ok(v)
}

/// `--env-rotation` and other angles in degrees: finite.
pub fn degrees(s: &str) -> Result<f32, String> {
    finite(s)
}

/// `--time`: a positive, finite number of seconds (at most a week).
pub fn seconds(s: &str) -> Result<f64, String> {
    let v: f64 = s.trim().parse().map_err(|_| format!("'{}' is not a number", crate::io::input_file::clip(s, 40)))?;
    if !(v.is_finite() && v > 0.0 && v <= 7.0 * 86400.0) {
        return Err(format!("{v} is not a positive number of seconds (at most a week, 604800)"));
    }
    Ok(v)
}

/// `--spp`: an integer from 1 to 4294967295.
pub fn spp(s: &str) -> Result<u32, String> {
    match s.trim().parse::<u64>() {
        Ok(n) if (1..=u32::MAX as u64).contains(&n) => Ok(n as u32),
        _ => Err(format!(
            "'{}' is not a sample count (an integer from 1 to {})",
            crate::io::input_file::clip(s, 40),
            u32::MAX
        )),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn refuse_what_the_toml_twins_refuse() {
        for bad in ["nan", "inf", "-inf", "1e39", "128", "x"] {
            assert!(exposure(bad).is_err(), "{bad}");
        }
        assert_eq!(exposure("-3.5"), Ok(-3.5));
        for bad in ["nan", "inf", "-1", "1e39", "1e31"] {
            assert!(env_scale(bad).is_err(), "{bad}");
        }
        assert!(degrees("nan").is_err() && degrees("inf").is_err());
        assert_eq!(degrees("-90"), Ok(-90.0));
        assert!(spp("0").is_err() && spp("4294967296").is_err() && spp("-1").is_err());
        assert_eq!(spp("4294967295"), Ok(u32::MAX));
        assert!(seconds("0").is_err() && seconds("nan").is_err() && seconds("inf").is_err());
    }
}
