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
//! 5e-5 rad (4.3e-5 the worst of 200,000 random and edge-case directions): `crate::gpu::octahedral`.

use crate::gpu::types::{GpuShadingVertex, GpuTriShading, INVALID};
use glam::{Vec2, Vec3};

pub use crate::gpu::octahedral::{oct_decode, oct_encode, NO_NORMAL};
use std::collections::HashMap;
use std::hash::{BuildHasherDefault, Hasher};

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
    index: HashMap<[u32; 4], u32, BuildHasherDefault<WordHasher>>,
}

/// A multiply-rotate hash of machine words (the Fx hash's step: rotate, xor the word in, multiply by an odd
/// constant) for the table's keys of four words, which no one chooses adversarially: std's SipHash made the table
/// a third of a 270k-triangle scene's flattening.
#[derive(Default)]
pub struct WordHasher(u64);

impl Hasher for WordHasher {
    fn write(&mut self, bytes: &[u8]) {
        for chunk in bytes.chunks(8) {
            let mut word = [0u8; 8];
            word[..chunk.len()].copy_from_slice(chunk);
            self.write_u64(u64::from_le_bytes(word));
        }
    }

    fn write_u64(&mut self, word: u64) {
        self.0 = (self.0.rotate_left(5) ^ word).wrapping_mul(0x51_7c_c1_b7_27_22_0a_95);
    }

    fn write_usize(&mut self, word: usize) {
        self.write_u64(word as u64);
    }

    fn finish(&self) -> u64 {
        self.0
    }
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
