// rng.wgsl — stateless hashing: (pixel, sample index, dimension, seed) → 32 random bits.

/// PCG-style output permutation of one 32-bit word (Jarzynski & Olano 2020, "Hash Functions for GPU Rendering").
fn pcg_hash(v: u32) -> u32 {
    let state = v * 747796405u + 2891336453u;
    let word = ((state >> ((state >> 28u) + 4u)) ^ state) * 277803737u;
    return (word >> 22u) ^ word;
}

/// Hash of four words, each folded in through a full PCG permutation so nearby inputs decorrelate.
fn hash4(a: u32, b: u32, c: u32, d: u32) -> u32 {
    return pcg_hash(d ^ pcg_hash(c ^ pcg_hash(b ^ pcg_hash(a))));
}

/// Maps 32 random bits to [0, 1) using the top 24 bits (exactly representable, never 1.0).
fn bits_to_unit(bits: u32) -> f32 {
    return f32(bits >> 8u) * (1.0 / 16777216.0);
}
