//! Box edges in 8 bits: an edge is `p + s·q` with an f32 origin `p`, a power-of-two scale `s = 2^(e − 127)` and a
//! byte `q`, rounded outwards so that the decoded box contains the exact one. `s·q` is exact (a power of two times
//! a byte), so `p + s·q` rounds once and an fma gives the same bits: the CPU decodes exactly as the shaders do.
//! The wide BVH's child boxes (`accel::wide_bvh`) and the light tree's (`accel::light_tree`) use it.

use glam::Vec3;

/// f32 `p + s·q`, as the shader decodes a box edge.
pub fn decode(p: f32, s: f32, q: u32) -> f32 {
    p + s * q as f32
}

/// A quantisation frame stored in four words: the origin's f32 bits in xyz and the three biased exponents in bytes
/// 0–2 of w (the wide BVH's and the light tree's node heads). Returns the origin `p` and the per-axis scale `s`.
pub fn decode_frame(head: &[u32; 4]) -> (Vec3, Vec3) {
    let p = Vec3::new(f32::from_bits(head[0]), f32::from_bits(head[1]), f32::from_bits(head[2]));
    let e = |k: u32| f32::from_bits(((head[3] >> (8 * k)) & 0xff) << 23);
    (p, Vec3::new(e(0), e(1), e(2)))
}

/// The biased exponent of the smallest power-of-two scale with `p + 255·s ≥ hi` in f32.
pub fn scale_exponent(p: f32, hi: f32) -> u32 {
    let ext = hi as f64 - p as f64;
    let mut e = if ext > 0.0 { ((ext / 255.0).log2().ceil() as i32 + 127).clamp(1, 254) as u32 } else { 1 };
    while e < 254 && decode(p, f32::from_bits(e << 23), 255) < hi {
        e += 1;
    }
    e
}

/// Conservative 8-bit edges of `[lo, hi]` against origin `p` and scale `s`: `decode(q_lo) ≤ lo`,
/// `decode(q_hi) ≥ hi`. Needs `p ≤ lo` and `decode(255) ≥ hi`.
pub fn quantise(p: f32, s: f32, lo: f32, hi: f32) -> (u32, u32) {
    let mut qlo = (((lo as f64 - p as f64) / s as f64).floor().max(0.0) as u32).min(255);
    while qlo > 0 && decode(p, s, qlo) > lo {
        qlo -= 1;
    }
    let mut qhi = (((hi as f64 - p as f64) / s as f64).ceil().max(0.0) as u32).min(255);
    while qhi < 255 && decode(p, s, qhi) < hi {
        qhi += 1;
    }
    (qlo, qhi)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Decoded edges contain the input interval for awkward origins, scales and magnitudes.
    #[test]
    fn quantised_edges_are_conservative() {
        let mut x = 0x9e3779b97f4a7c15u64;
        let mut rnd = || {
            x ^= x << 13;
            x ^= x >> 7;
            x ^= x << 17;
            (x >> 11) as f64 / (1u64 << 53) as f64
        };
        for i in 0..20000 {
            let mag = 10f64.powf(rnd() * 60.0 - 30.0) as f32;
            let (a, b) = ((rnd() * 2.0 - 1.0) as f32 * mag, (rnd() * 2.0 - 1.0) as f32 * mag);
            let (p, top) = (a.min(b), a.max(b));
            let top = if i % 7 == 0 { p } else { top };
            let e = scale_exponent(p, top);
            let s = f32::from_bits(e << 23);
            assert!(decode(p, s, 255) >= top, "scale too small for [{p}, {top}]");
            let (c0, c1) = (p + (top - p) * rnd() as f32, p + (top - p) * rnd() as f32);
            let (lo, hi) = (c0.min(c1).max(p), c0.max(c1).min(top));
            let (ql, qh) = quantise(p, s, lo, hi);
            assert!(decode(p, s, ql) <= lo && decode(p, s, qh) >= hi, "[{lo}, {hi}] in [{p}, {top}]: {ql} {qh}");
        }
    }
}
