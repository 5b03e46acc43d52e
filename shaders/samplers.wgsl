// samplers.wgsl — stateless sample sequences: (pixel, sample index, dimension) → u ∈ [0,1).
//
// Dimensions are allocated in a fixed, documented order so that every sampler sees the same meaning per
// dimension: 0–1 camera (pixel jitter); then for every path vertex (bounce b) a block of DIMS_PER_BOUNCE:
//   +0 light selection, +1..3 light sample (3D: the environment's alias table needs a third number),
//   +4 BSDF lobe, +5..6 BSDF/direction sample, +7 Russian roulette, +8 one-sample-MIS technique choice, +9 spare.
// The j-th extra light/BSDF sample of a vertex (multi-sample MIS) uses the block of bounce b + j·MAX_VERTICES.

const DIMS_CAMERA: u32 = 2u;
const DIMS_PER_BOUNCE: u32 = 10u;
const MAX_VERTICES: u32 = 64u;
const DIM_LIGHT_SELECT: u32 = 0u;
const DIM_LIGHT_UV: u32 = 1u;
const DIM_LIGHT_EXTRA: u32 = 3u;
const DIM_BSDF_LOBE: u32 = 4u;
const DIM_BSDF_UV: u32 = 5u;
const DIM_RR: u32 = 7u;
const DIM_MIS_CHOICE: u32 = 8u;

/// Identifies one sample of one pixel; `sample_dim` adds the dimension.
struct SampleId {
    pixel: u32,
    index: u32,
}

/// First dimension of the block for vertex `bounce`, repetition `j`.
fn dim_base(bounce: u32, j: u32) -> u32 {
    return DIMS_CAMERA + (bounce + j * MAX_VERTICES) * DIMS_PER_BOUNCE;
}

/// Independent sampler: a hash of (pixel, index, dimension, seed).
fn sample_independent(id: SampleId, dim: u32) -> f32 {
    return bits_to_unit(hash4(id.pixel, id.index, dim, params.seed));
}

/// One value of the active sequence.
fn sample_1d(id: SampleId, dim: u32) -> f32 {
    return sample_independent(id, dim);
}

/// Two consecutive dimensions of the active sequence.
fn sample_2d(id: SampleId, dim: u32) -> vec2<f32> {
    return vec2<f32>(sample_1d(id, dim), sample_1d(id, dim + 1u));
}
