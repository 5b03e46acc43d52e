//! Compact shading data: per triangle its three shading-vertex indices, which travel in the w words of its three
//! `tri_verts` (free: a vertex is a vec4 for alignment; `SceneData::pack_triangle_records`), and its light, in
//! `tri_lights` only where some triangle emits; per distinct shading vertex 16 bytes (an octahedral normal, the
//! material word, the uv as two f32), or 8 in a scene without textures, where nothing reads a uv and none is kept
//! (`SceneData::shading_records`). `GpuTriShading` is the CPU's view of a triangle's record.
//!
//! Why indexed rather than packed per triangle: 32 bytes per triangle leave no room for f32 uvs next to three
//! normals, and f16 uvs (or f16 uv deltas) fail where tiling needs the range: a 100-tile floor triangle's corner
//! at u = 100 would move by 0.03 tiles, differently in each of the two triangles sharing an edge (a seam). Indexed,
//! the uvs stay the file's f32 values bit for bit. Shading vertices are deduplicated by their encoded contents
//! (normal, uv, material), so a smooth mesh needs about one per triangle or fewer, and a mesh without uvs and
//! normals one per material.
//!
//! Normals: octahedral, 2 × 16-bit snorm (Cigolle et al. 2014, "A Survey of Efficient Representations for
//! Independent Unit Vectors"), encoded to the best of the four neighbouring codes: the decoded direction is within
//! 5e-5 rad (4.3e-5 the worst of 200,000 random and edge-case directions). The WGSL decode is `oct_decode` in
//! shaders/common.wgsl; `oct_decode` here is its CPU twin.

use crate::gpu::types::{GpuShadingVertex, GpuTriShading, INVALID};
use glam::{Vec2, Vec3};
use std::collections::HashMap;

/// The normal code of a vertex without a usable normal (missing, zero or not finite): decodes to (0, 0, 0), so it
/// adds nothing to the interpolated normal (a triangle with none falls back to its geometric normal). The encoder
/// never writes -32768 (it clamps to ±32767), so this code is free.
pub const NO_NORMAL: u32 = 0x8000_8000;

/// The material word of a shading vertex: the material index in the low 16 bits, the cut-out mask (0 none, k + 1
/// texture k's alpha channel, shaders/alpha.wgsl) in the high 16. Scenes beyond these are refused at load
/// (`crate::scene::MAX_MATERIALS`, `MAX_MASK_TEXTURE`); here a value out of range maps to material 0 / no mask.
pub fn material_word(material: u32, alpha_texture: u32) -> u32 {
    let m = if material <= 0xffff { material } else { 0 };
    let a = if alpha_texture <= 0xffff { alpha_texture } else { 0 };
    m | (a << 16)
}

/// The material index of a material word.
pub fn word_material(word: u32) -> u32 {
    word & 0xffff
}

/// The cut-out mask of a material word (0 none, k + 1 texture k).
pub fn word_alpha_texture(word: u32) -> u32 {
    word >> 16
}

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

/// A triangle's shading attributes as the shader sees them (CPU twin of `scene_tri_shading`).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TriAttributes {
    /// Vertex normals, unit or zero (no usable normal).
    pub n: [Vec3; 3],
    /// Vertex uvs.
    pub uv: [Vec2; 3],
    /// Material index.
    pub material: u32,
    /// Cut-out mask: 0 none, k + 1 texture k.
    pub alpha_texture: u32,
    /// Light-table index, or INVALID.
    pub light: u32,
}

/// Decodes triangle `t` against the shading-vertex table.
pub fn decode(t: &GpuTriShading, verts: &[GpuShadingVertex]) -> TriAttributes {
    let v = t.corners.map(|c| verts[c as usize]);
    TriAttributes {
        n: v.map(|v| oct_decode(v.normal)),
        uv: v.map(|v| Vec2::from(v.uv)),
        material: word_material(v[0].material),
        alpha_texture: word_alpha_texture(v[0].material),
        light: t.light,
    }
}

/// Builds the shading-vertex table while triangles are added, sharing equal vertices.
#[derive(Default)]
pub struct ShadingTable {
    /// Per triangle, in the order added.
    pub tris: Vec<GpuTriShading>,
    /// Distinct shading vertices.
    pub verts: Vec<GpuShadingVertex>,
    index: HashMap<[u32; 4], u32>,
}

impl ShadingTable {
    /// The index of a shading vertex with these contents (added if new).
    pub fn vertex(&mut self, normal: Vec3, uv: Vec2, material_word: u32) -> u32 {
        let v = GpuShadingVertex { normal: oct_encode(normal), material: material_word, uv: uv.into() };
        let key = [v.normal, v.material, v.uv[0].to_bits(), v.uv[1].to_bits()];
        let verts = &mut self.verts;
        *self.index.entry(key).or_insert_with(|| {
            verts.push(v);
            (verts.len() - 1) as u32
        })
    }

    /// Adds a triangle of three shading vertices (no light yet).
    pub fn triangle(&mut self, corners: [u32; 3]) {
        self.tris.push(GpuTriShading { corners, light: INVALID });
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn material_words_round_trip_and_refuse_to_wrap() {
        let w = material_word(65535, 65535);
        assert_eq!((word_material(w), word_alpha_texture(w)), (65535, 65535));
        let w = material_word(65536, 70000);
        assert_eq!((word_material(w), word_alpha_texture(w)), (0, 0));
    }

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

    #[test]
    fn equal_vertices_are_shared() {
        let mut t = ShadingTable::default();
        let a = t.vertex(Vec3::Z, Vec2::new(0.25, 100.0), 3);
        let b = t.vertex(Vec3::Z * 2.0, Vec2::new(0.25, 100.0), 3);
        let c = t.vertex(Vec3::Z, Vec2::new(0.25, 100.0), 4);
        assert_eq!((a, b, c), (0, 0, 1));
        t.triangle([a, b, c]);
        let d = decode(&t.tris[0], &t.verts);
        // uvs are kept bit for bit.
        assert_eq!(d.uv[0], Vec2::new(0.25, 100.0));
        assert_eq!((d.material, d.alpha_texture, d.light), (3, 0, INVALID));
    }

    #[test]
    fn no_normal_is_zero_and_bad_normals_map_to_it() {
        assert_eq!(oct_decode(NO_NORMAL), Vec3::ZERO);
        for n in [Vec3::ZERO, Vec3::NAN, Vec3::new(f32::INFINITY, 0.0, 0.0)] {
            assert_eq!(oct_encode(n), NO_NORMAL);
        }
    }
}
