//! Structs shared with WGSL (`shaders/common.wgsl`), byte for byte. `tests/layout.rs` asks naga for the
//! WGSL layout of each and compares it with `size_of` / `offset_of!`.

use bytemuck::{Pod, Zeroable};

/// Marks "no index" in every u32 index field (texture slots, light of a primitive, ...).
pub const INVALID: u32 = u32::MAX;

/// Primitive kinds stored in the top two bits of a BVH primitive reference.
pub const PRIM_TRIANGLE: u32 = 0;
pub const PRIM_SPHERE: u32 = 1;
pub const PRIM_QUAD: u32 = 2;
pub const PRIM_KIND_SHIFT: u32 = 30;
pub const PRIM_INDEX_MASK: u32 = (1 << PRIM_KIND_SHIFT) - 1;

/// Packs a primitive kind and index into one reference (as WGSL `make_prim`).
pub fn make_prim(kind: u32, index: u32) -> u32 {
    debug_assert!(index <= PRIM_INDEX_MASK);
    (kind << PRIM_KIND_SHIFT) | index
}

/// Light kinds (`Light::kind`).
pub const LIGHT_TRIANGLE: u32 = 0;
pub const LIGHT_SPHERE: u32 = 1;
pub const LIGHT_QUAD: u32 = 2;
pub const LIGHT_POINT: u32 = 3;
pub const LIGHT_SPOT: u32 = 4;
pub const LIGHT_DIRECTIONAL: u32 = 5;
pub const LIGHT_ENVIRONMENT: u32 = 6;
/// A convex lamp (`accel::convex_lamps`): a closed convex emitter mesh sampled as one light.
pub const LIGHT_CONVEX_LAMP: u32 = 7;
/// One face of a convex lamp: found by rays, never chosen itself (its lamp is).
pub const LIGHT_LAMP_FACE: u32 = 8;

/// Texture wrap modes (`TextureInfo::wrap_s`/`wrap_t`).
pub const WRAP_REPEAT: u32 = 0;
pub const WRAP_CLAMP: u32 = 1;
pub const WRAP_MIRROR: u32 = 2;

/// Texture kinds (`TextureInfo::tex_kind`): texels, or pbrt's checkerboard (two linear RGB colours as six f32 words
/// at `offset`, no texels).
pub const TEX_IMAGE: u32 = 0;
/// Set in `GpuTextureInfo::offset` of a texture whose texels are in the second texel binding (`tex_texels_hi`,
/// src/render/gpu_scene.rs `split_texels`); the rest of the offset counts from that binding's start.
pub const TEXEL_HI: u32 = 1 << 31;
pub const TEX_CHECKERBOARD: u32 = 1;

/// An analytic sphere (WGSL `Sphere`).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct GpuSphere {
    pub center: [f32; 3],
    pub radius: f32,
    pub material: u32,
    pub light: u32,
    pub _pad0: u32,
    pub _pad1: u32,
}

/// An analytic parallelogram (WGSL `Quad`).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct GpuQuad {
    pub corner: [f32; 3],
    pub material: u32,
    pub edge_u: [f32; 3],
    pub light: u32,
    pub edge_v: [f32; 3],
    pub _pad0: u32,
}

/// Per-triangle shading data (WGSL `TriShading`): its three shading vertices (`GpuShadingVertex`, in the
/// `shading_verts` table) and its light. Uploaded split: the indices in the w of the triangle's `tri_verts`, the light
/// in `tri_lights` (`SceneData::pack_triangle_records`). Encoding and decoding: src/render/shading_data.rs.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct GpuTriShading {
    pub corners: [u32; 3],
    /// Index in the light table, or INVALID.
    pub light: u32,
}

/// A shading vertex (WGSL `ShadingVertex`), shared by the triangles whose corners have the same contents.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct GpuShadingVertex {
    /// Octahedral normal, 2 × snorm16 (`shading_data::oct_encode`; `NO_NORMAL` = none).
    pub normal: u32,
    /// Material index (low 16 bits) and cut-out mask (high 16: 0 none, k + 1 texture k's alpha channel).
    pub material: u32,
    pub uv: [f32; 2],
}

/// A material (WGSL `Material`): what every kind shares, its kind's tag (`render::materials::MATERIALS`) and that
/// kind's parameter words (its own layout: `render::materials::pack`, and `<kind>_params` in its shader file).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct GpuMaterial {
    pub emission: [f32; 3],
    pub bsdf_kind: u32,
    pub base_tex: u32,
    pub mr_tex: u32,
    pub emissive_tex: u32,
    pub _pad0: u32,
    pub base_xform0: [f32; 4],
    pub base_xform1: [f32; 4],
    pub mr_xform0: [f32; 4],
    pub mr_xform1: [f32; 4],
    pub em_xform0: [f32; 4],
    pub em_xform1: [f32; 4],
    pub params0: [f32; 4],
    pub params1: [f32; 4],
    pub params2: [f32; 4],
}

/// One entry of the light table (WGSL `Light`).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct GpuLight {
    pub position: [f32; 3],
    pub kind: u32,
    pub direction: [f32; 3],
    pub prim: u32,
    pub radiance: [f32; 3],
    pub pmf_power: f32,
    pub cos_inner: f32,
    pub cos_outer: f32,
    pub area: f32,
    pub pmf_uniform: f32,
    /// Its path in the light tree (`light_tree::LightTree::trails`; 0 for lights outside it).
    pub tree_trail: u32,
    /// 1: an area light emitting from both faces (triangles and quads).
    pub two_sided: u32,
    /// 1: a triangle of an isolated emitter mesh (`accel::isolated_emitters`), whose stop box `position`
    /// (lower corner) and `direction` (upper corner) hold: a shadow ray towards it may end where it enters that box.
    pub shadow_box: u32,
    pub _pad2: u32,
}

/// Alias-table entry (WGSL `AliasEntry`).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct GpuAliasEntry {
    pub prob: f32,
    pub alias_index: u32,
}

/// Where a texture lives in the texel buffer and how it is read (WGSL `TextureInfo`).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct GpuTextureInfo {
    pub offset: u32,
    pub width: u32,
    pub height: u32,
    pub wrap_s: u32,
    pub wrap_t: u32,
    pub srgb: u32,
    pub nearest: u32,
    pub tex_kind: u32,
}

/// Per-pixel accumulator (WGSL `Accum`).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct GpuAccum {
    pub mean: [f32; 3],
    pub count: u32,
    pub m2: [f32; 3],
    pub nonfinite: u32,
}

/// Per-dispatch parameters (WGSL `FrameParams`).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct GpuFrameParams {
    pub width: u32,
    pub height: u32,
    pub sample_base: u32,
    pub samples_per_dispatch: u32,
    pub seed: u32,
    pub mode: u32,
    pub max_depth: u32,
    pub strategy: u32,
    pub light_sampling: u32,
    pub env_sampling: u32,
    pub light_select: u32,
    pub heuristic: u32,
    pub power_beta: f32,
    pub light_samples: u32,
    pub bsdf_samples: u32,
    pub mis_kind: u32,
    pub sampler: u32,
    pub num_lights: u32,
    pub rr_depth: u32,
    pub env_light: u32,
    pub cam_origin: [f32; 3],
    pub tan_half_fov: f32,
    pub cam_right: [f32; 3],
    pub aspect: f32,
    pub cam_up: [f32; 3],
    pub env_scale: f32,
    pub cam_forward: [f32; 3],
    pub env_rotation: f32,
    pub env_constant: [f32; 3],
    pub env_width: u32,
    pub env_height: u32,
    pub sampler_spp: u32,
    /// First film row of the dispatch.
    pub row_offset: u32,
    /// Rows rendered from `row_offset`.
    pub row_count: u32,
    /// Length scale of the scene around the render origin (≤ 1): ray-origin offsets near the origin are
    /// proportional to it, so tiny scenes do not jump out of themselves.
    pub offset_scale: f32,
    /// Candidates per light sample under resampled importance sampling.
    pub ris_candidates: u32,
    /// Workgroup row j of the dispatch renders tile row (j · stride) mod rows (`render::tile_order`).
    pub tile_row_stride: u32,
    /// Path mode: the light technique's samples at a first vertex where the environment guide applies are
    /// `light_samples` × this (`Settings::first_hit_light_split`).
    pub first_hit_light_split: u32,
    /// The environment guide's grid: lower corner (render-origin space), 1 / cell size, cells per axis
    /// (`render::env_guide`).
    pub guide_min: [f32; 3],
    /// > 0: the guide's learning pass (1: its samples also accumulate; 2: it only counts) or, 3, the rest of
    /// sample 0 after a learning pass over the learner tiles only (`render::env_guide`).
    pub guide_train: u32,
    pub guide_inv_cell: [f32; 3],
    /// The guide's slots (cells × 6 normal classes).
    pub guide_slots: u32,
    pub guide_dims: [u32; 3],
    /// 1 once a guide is learned.
    pub guide_on: u32,
    /// One 8×8 tile in this many learns the guide (1, 2 or 4; `env_guide::learner_period`).
    pub guide_learner_period: u32,
    /// The convex lamps' entries in the light table: `lamp_count` of them from `lamp_first` (they follow each
    /// other; `accel::convex_lamps`).
    pub lamp_first: u32,
    pub lamp_count: u32,
    /// 1: the lamps are the scene's only emitters (no other light, no environment).
    pub lamps_only: u32,
    /// The triangles outside the BVH (`SceneData::occluders`): `occluder_count` slots from `occluder_first`, which
    /// the generic pipeline tests in a loop (a scene's own pipeline has them as literals).
    pub occluder_first: u32,
    pub occluder_count: u32,
    /// The pixel filter (`PixelFilter` tag), its radius and gaussian σ in pixels, and 1 / ∫ of its gaussian over
    /// [−r, r] (`render::pixel_filter`).
    pub pixel_filter: u32,
    pub filter_radius: f32,
    pub filter_sigma: f32,
    pub filter_norm: f32,
    pub _pad_filter: [u32; 2],
}

/// A closest-hit result (WGSL `Hit`), used by probe kernels.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct GpuHit {
    pub t: f32,
    pub prim: u32,
    pub b1: f32,
    pub b2: f32,
}
