//! Unit vectors in one word: octahedral, 2 × 16-bit snorm (Cigolle et al. 2014, "A Survey of Efficient
//! Representations for Independent Unit Vectors"), encoded to the best of the four neighbouring codes, so that the
//! decoded direction is within 5e-5 rad (4.3e-5 the worst of 200,000 random and edge-case directions). Shading
//! normals (`render::shading_data`) and the light tree's cone axes (`accel::light_tree`) use it. The WGSL decode is
//! `oct_decode` in shaders/common.wgsl; `oct_decode` here is its CPU twin.

use glam::{Vec2, Vec3};

/// The normal code of a vertex without a usable normal (missing, zero or not finite): decodes to (0, 0, 0), so it
/// adds nothing to the interpolated normal (a triangle with none falls back to its geometric normal). The encoder
/// never writes -32768 (it clamps to ±32767), so this code is free.
pub const NO_NORMAL: u32 = 0x8000_8000;

fn sign_not_zero(x: f32) -> f32 {
    if x >= 0.0 {
        1.0
    } else {
        -1.0
    }
}

fn snorm16(x: f32) -> i32 {
    (x.clamp(-1.0, 1.0) * 32767.0).round() as i32
}

fn pack(x: i32, y: i32) -> u32 {
    (x as i16 as u16 as u32) | ((y as i16 as u16 as u32) << 16)
}

/// The octahedral code of direction `n` (any length > 0), or `NO_NORMAL` for a zero or non-finite vector.
pub fn oct_encode(n: Vec3) -> u32 {
    let l1 = n.x.abs() + n.y.abs() + n.z.abs();
    if !(l1 > 0.0 && l1.is_finite()) {
        return NO_NORMAL;
    }
    let mut p = Vec2::new(n.x, n.y) / l1;
    if n.z < 0.0 {
        // Fold the lower hemisphere over the octahedron's edges.
        p = Vec2::new((1.0 - p.y.abs()) * sign_not_zero(p.x), (1.0 - p.x.abs()) * sign_not_zero(p.y));
    }
    // Of the four codes around p, the one whose decoded direction is nearest n (rounding p alone can be off by
    // up to twice as much near the fold).
    let target = n.as_dvec3().normalize();
    // In f64: near 1, f32 dot products cannot tell the candidates apart (the errors are ~1e-5 rad).
    let err = |code: u32| (oct_decode(code).as_dvec3() - target).length_squared();
    let (fx, fy) = ((p.x.clamp(-1.0, 1.0) * 32767.0).floor() as i32, (p.y.clamp(-1.0, 1.0) * 32767.0).floor() as i32);
    let mut best = pack(snorm16(p.x), snorm16(p.y));
    let mut best_err = err(best);
    for (x, y) in [(fx, fy), (fx + 1, fy), (fx, fy + 1), (fx + 1, fy + 1)] {
        let code = pack(x.clamp(-32767, 32767), y.clamp(-32767, 32767));
        let e = err(code);
        if e < best_err {
            best = code;
            best_err = e;
        }
    }
    best
}

/// CPU twin of `oct_decode` (shaders/common.wgsl): WGSL's unpack2x16snorm, the sign fold, normalised.
pub fn oct_decode(code: u32) -> Vec3 {
    if code == NO_NORMAL {
        return Vec3::ZERO;
    }
    let e = |bits: u32| ((bits as u16 as i16) as f32 / 32767.0).max(-1.0);
    let (x, y) = (e(code & 0xffff), e(code >> 16));
    let z = 1.0 - x.abs() - y.abs();
    let (x, y) =
        if z < 0.0 { ((1.0 - y.abs()) * sign_not_zero(x), (1.0 - x.abs()) * sign_not_zero(y)) } else { (x, y) };
    Vec3::new(x, y, z).normalize()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Angle between two directions, f64.
    fn angle(a: Vec3, b: Vec3) -> f64 {
        let (a, b) = (a.as_dvec3().normalize(), b.as_dvec3().normalize());
        a.cross(b).length().atan2(a.dot(b))
    }

    /// Directions that stress the encoding: the ±axes, the fold edges (z = 0, and x = 0 or y = 0 below it where
    /// the fold's sign flips), the octahedron's edges |x| + |y| = 1, and points just either side of them.
    fn hard_directions() -> Vec<Vec3> {
        let mut v = vec![];
        for s in [1.0f32, -1.0] {
            v.extend([Vec3::X * s, Vec3::Y * s, Vec3::Z * s]);
        }
        for k in 0..=64 {
            let a = k as f32 / 64.0 * std::f32::consts::TAU;
            let (c, s) = (a.cos(), a.sin());
            for z in [0.0f32, 1e-7, -1e-7, 1e-3, -1e-3, -0.5, 0.5, -0.999] {
                let r = (1.0 - z * z).sqrt();
                v.push(Vec3::new(r * c, r * s, z));
            }
            // x = 0 and y = 0 in the lower hemisphere, with either sign of zero.
            v.push(Vec3::new(0.0, c, -s.abs()));
            v.push(Vec3::new(-0.0, c, -s.abs()));
            v.push(Vec3::new(c, 0.0, -s.abs()));
            v.push(Vec3::new(c, -0.0, -s.abs()));
        }
        v
    }

    #[test]
    fn octahedral_normals_round_trip_within_5e5_rad() {
        // Deterministic pseudo-random directions (uniform on the sphere) plus the hard cases.
        let mut state = 0x2545_f491_4f6c_dd1du64;
        let mut next = || {
            state ^= state << 13;
            state ^= state >> 7;
            state ^= state << 17;
            (state >> 40) as f32 / (1u64 << 24) as f32
        };
        let mut dirs = hard_directions();
        for _ in 0..200_000 {
            let z = 2.0 * next() - 1.0;
            let a = std::f32::consts::TAU * next();
            let r = (1.0 - z * z).max(0.0).sqrt();
            dirs.push(Vec3::new(r * a.cos(), r * a.sin(), z));
        }
        let mut worst = 0.0f64;
        for n in dirs {
            let code = oct_encode(n);
            assert_ne!(code, NO_NORMAL, "{n} encoded as no normal");
            let d = oct_decode(code);
            assert!((d.length() - 1.0).abs() < 1e-6, "{n}: decoded {d} is not unit");
            // A non-unit input encodes its direction as well (the code may differ by a rounding step).
            worst = worst.max(angle(n, d)).max(angle(n, oct_decode(oct_encode(n * 3.5))));
        }
        assert!(worst < 5e-5, "worst round-trip error {worst:e} rad");
        // The axes come back exactly.
        for n in [Vec3::X, Vec3::Y, Vec3::Z, -Vec3::X, -Vec3::Y, -Vec3::Z] {
            assert_eq!(oct_decode(oct_encode(n)), n);
        }
    }
}
