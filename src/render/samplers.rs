//! Sample sequences on the CPU: the tables the WGSL samplers read (`sampler_data`, group 1 binding 3: Sobol
//! generator matrices, the Halton/Hammersley prime table, a void-and-cluster blue-noise mask), the spp rules
//! of the fixed-count samplers (`check_spp`), and a CPU twin of every sampler in `shaders/samplers.wgsl`
//! (same integer operations; `tests/samplers.rs` compares the two on the device).
//!
//! Every sampler is stateless: (pixel, sample index, dimension, seed) → u ∈ [0, 1). Dimensions are allocated
//! as `shaders/samplers.wgsl` documents (4 for the camera, then 12 per path vertex, in blocks of 4).

use crate::render::error::InvalidSettings;
use crate::render::settings::SamplerKind;
use crate::render::void_and_cluster::void_and_cluster;
use std::sync::OnceLock;

// ---------------------------------------------------------------------------------------------------------------
// Dimension allocation and the layout of `sampler_data` (mirrored by WGSL constants of the same names; tested).

/// Dimensions of the camera block (0–1 pixel jitter, 2–3 spare).
pub const DIMS_CAMERA: u32 = 4;
/// Dimensions of each path vertex (three blocks of four).
pub const DIMS_PER_BOUNCE: u32 = 12;
/// Dimensions of a vertex that carry a sample (the rest of its block of 12 are spare).
pub const DIMS_USED_PER_BOUNCE: u32 = 9;
/// Sobol dimensions a padded block uses (dimensions 0 and 1 are computed; 2 and 3 come from tables).
pub const SOBOL_DIMS: u32 = 4;
/// Word offset of the Sobol byte tables of dimensions 2 and 3: for dimension 2 + t, byte k of the index and
/// value v, word `SOBOL_OFFSET + t·1024 + k·256 + v` is the XOR of the generator columns 8k … 8k + 7 selected
/// by v. Four lookups give a coordinate without a loop (lavapipe counts every loop iteration of an invocation
/// against one budget of 65535, so the samplers avoid loops).
pub const SOBOL_OFFSET: u32 = 0;
/// Words of the Sobol byte tables.
pub const SOBOL_TABLE_WORDS: u32 = 2 * 4 * 256;
/// Radical-inverse dimensions (Halton, Hammersley) with a prime of their own; later ones fall back to hashing.
pub const HALTON_DIMS: u32 = 256;
/// Word offset of the prime table: per dimension [prime, digits, bits of 1/prime^digits as f32, 0].
pub const HALTON_OFFSET: u32 = SOBOL_OFFSET + SOBOL_TABLE_WORDS;
/// log2 of the blue-noise mask's side.
pub const BLUE_NOISE_LOG2: u32 = 6;
/// Side of the (tileable) blue-noise mask.
pub const BLUE_NOISE_SIZE: u32 = 1 << BLUE_NOISE_LOG2;
/// Word offset of the blue-noise mask: ranks 0 .. BLUE_NOISE_SIZE² − 1, row-major.
pub const BLUE_NOISE_OFFSET: u32 = HALTON_OFFSET + 4 * HALTON_DIMS;
/// Total words of `sampler_data`.
pub const SAMPLER_DATA_WORDS: u32 = BLUE_NOISE_OFFSET + BLUE_NOISE_SIZE * BLUE_NOISE_SIZE;
/// Target sample count of the fixed-count samplers when none is given (time budgets, the viewer): the
/// sequence restarts with a fresh randomisation every this many samples.
pub const DEFAULT_SAMPLER_SPP: u32 = 16;
/// Largest target sample count of the fixed-count samplers.
pub const MAX_SAMPLER_SPP: u32 = 1 << 20;
/// Marks a dimension without a radical-inverse base (spare dimensions, or past `HALTON_DIMS`).
pub const NO_HALTON_DIM: u32 = u32::MAX;

// Hash salts, one per use, so that no two samplers or roles draw the same hash stream.
/// Salt of the Sobol sampler's per-block seeds.
pub const SALT_SOBOL: u32 = 0x50_b01d;
/// Salt of the blue-noise sampler's shared per-block seeds.
pub const SALT_BLUE_NOISE: u32 = 0xb1_0e5e;
/// Salt of the blue-noise mask offsets per dimension.
pub const SALT_BLUE_OFFSET: u32 = 0xb1_0ff5;
/// Salt of the Halton sampler's digit scrambles.
pub const SALT_HALTON: u32 = 0x4a_1707;
/// Salt of the Hammersley sampler's per-pass seeds.
pub const SALT_HAMMERSLEY: u32 = 0x4a_33e5;
/// Salt of the stratified sampler, 1D strata.
pub const SALT_STRATIFIED: u32 = 0x57_a71d;
/// Salt of the stratified sampler, 2D strata.
pub const SALT_STRATIFIED_2D: u32 = 0x57_a72d;

// ---------------------------------------------------------------------------------------------------------------
// Hashing (twins of shaders/rng.wgsl).

/// PCG-style permutation of one word (Jarzynski & Olano 2020), as `pcg_hash` in rng.wgsl.
pub fn pcg_hash(v: u32) -> u32 {
    let state = v.wrapping_mul(747796405).wrapping_add(2891336453);
    let word = ((state >> ((state >> 28) + 4)) ^ state).wrapping_mul(277803737);
    (word >> 22) ^ word
}

/// Hash of four words, as `hash4` in rng.wgsl.
pub fn hash4(a: u32, b: u32, c: u32, d: u32) -> u32 {
    pcg_hash(d ^ pcg_hash(c ^ pcg_hash(b ^ pcg_hash(a))))
}

/// Top 24 bits → [0, 1), as `bits_to_unit` in rng.wgsl.
pub fn bits_to_unit(bits: u32) -> f32 {
    (bits >> 8) as f32 * (1.0 / 16777216.0)
}

/// The largest f32 below 1.
pub const ONE_MINUS_EPSILON: f32 = 0.99999994;

// ---------------------------------------------------------------------------------------------------------------
// Sobol generator matrices.

/// A Sobol dimension's primitive polynomial x^s + a_1 x^(s−1) + … + a_(s−1) x + 1 (the inner coefficients packed
/// in `a`, a_1 most significant, as Joe & Kuo write them) and its initial direction numbers m_1 … m_s.
#[derive(Clone, Copy, Debug)]
pub struct SobolInit {
    /// Degree s.
    pub degree: u32,
    /// Inner coefficients a_1 … a_(s−1), a_1 in the highest of the s − 1 bits.
    pub a: u32,
    /// m_1 … m_s (m_k odd and < 2^k).
    pub m: &'static [u32],
}

/// Dimensions 1–3 (0-based; dimension 0 is the van der Corput sequence): the primitive polynomials x + 1,
/// x² + x + 1, x³ + x + 1 with the initial numbers Joe & Kuo (2008, "Constructing Sobol sequences with better
/// two-dimensional projections") list for them. `tests/samplers.rs` checks that these give the best possible
/// t-values for every 2D projection among the four dimensions.
pub const SOBOL_INIT: [SobolInit; 3] = [
    SobolInit { degree: 1, a: 0, m: &[1] },
    SobolInit { degree: 2, a: 1, m: &[1, 3] },
    SobolInit { degree: 3, a: 1, m: &[1, 3, 1] },
];

/// The 32 direction numbers v_k (left-aligned: v_k = m_k / 2^k as 0.32 fixed point) of one dimension, from its
/// polynomial and initial numbers by Bratley & Fox's recurrence
/// v_k = a_1 v_(k−1) ⊕ … ⊕ a_(s−1) v_(k−s+1) ⊕ v_(k−s) ⊕ (v_(k−s) >> s).
pub fn sobol_direction_numbers(init: &SobolInit) -> [u32; 32] {
    let s = init.degree as usize;
    assert!(s >= 1 && init.m.len() == s, "degree and initial numbers disagree");
    let mut v = [0u32; 32];
    for k in 0..32 {
        v[k] = if k < s {
            let m = init.m[k];
            assert!(m % 2 == 1 && m < (2 << k), "m_{} = {m} must be odd and below 2^{}", k + 1, k + 1);
            m << (31 - k)
        } else {
            let mut x = v[k - s] ^ (v[k - s] >> s);
            for i in 1..s {
                if (init.a >> (s - 1 - i)) & 1 == 1 {
                    x ^= v[k - i];
                }
            }
            x
        };
    }
    v
}

/// Generator matrix of Sobol dimension `dim` (0 … SOBOL_DIMS − 1) as 32 columns: column k is what index bit k
/// XORs into the result.
pub fn sobol_matrix(dim: u32) -> [u32; 32] {
    if dim == 0 {
        std::array::from_fn(|k| 1u32 << (31 - k))
    } else {
        sobol_direction_numbers(&SOBOL_INIT[dim as usize - 1])
    }
}

/// The Sobol point's coordinate `dim` for `index`, as 0.32 fixed point: XOR of the columns of the set bits.
pub fn sobol_bits_matrix(index: u32, matrix: &[u32; 32]) -> u32 {
    (0..32).filter(|k| (index >> k) & 1 == 1).fold(0, |r, k| r ^ matrix[k])
}

/// Sobol dimension 1 without a table: its matrix is Pascal's triangle mod 2, so bit b of the (bit-reversed)
/// result is the XOR of the index bits a ⊇ b (Lucas' theorem) — a superset-sum transform in five butterflies.
pub fn sobol_dim1(index: u32) -> u32 {
    let mut x = index;
    x ^= (x & 0xaaaa_aaaa) >> 1;
    x ^= (x & 0xcccc_cccc) >> 2;
    x ^= (x & 0xf0f0_f0f0) >> 4;
    x ^= (x & 0xff00_ff00) >> 8;
    x ^= (x & 0xffff_0000) >> 16;
    x.reverse_bits()
}

/// The t-value of the 2D projection of the first 2^m points of the digital sequence with generator matrices
/// `c1`, `c2`: the smallest t such that every elementary interval of area 2^(t−m) holds 2^t points, i.e. for
/// every d1 + d2 = m − t the first d1 rows of C1 and d2 rows of C2 (m columns) are linearly independent.
pub fn t_value_2d(c1: &[u32; 32], c2: &[u32; 32], m: u32) -> u32 {
    // Row r of a matrix restricted to the first m columns, as an m-bit word.
    let row = |c: &[u32; 32], r: u32| -> u32 { (0..m).fold(0, |w, k| w | (((c[k as usize] >> (31 - r)) & 1) << k)) };
    let independent = |rows: &[u32]| -> bool {
        let mut basis: Vec<u32> = Vec::new();
        for &r in rows {
            let mut x = r;
            for &b in &basis {
                x = x.min(x ^ b);
            }
            if x == 0 {
                return false;
            }
            basis.push(x);
            basis.sort_unstable_by(|a, b| b.cmp(a));
        }
        true
    };
    (0..=m)
        .find(|&t| {
            (0..=m - t).all(|d1| {
                let rows: Vec<u32> = (0..d1).map(|r| row(c1, r)).chain((0..m - t - d1).map(|r| row(c2, r))).collect();
                independent(&rows)
            })
        })
        .unwrap_or(m)
}

// ---------------------------------------------------------------------------------------------------------------
// Owen scrambling (Burley 2020, "Practical Hash-based Owen Scrambling", with Vegdahl's 2021 hash).

/// A hash in which every output bit depends only on input bits at or below it (so applied to bit-reversed
/// values it is a nested uniform scramble): Laine & Karras 2011's form with Vegdahl's constants.
pub fn laine_karras_permutation(mut x: u32, seed: u32) -> u32 {
    x ^= x.wrapping_mul(0x3d20_adea);
    x = x.wrapping_add(seed);
    x = x.wrapping_mul((seed >> 16) | 1);
    x ^= x.wrapping_mul(0x0552_6c56);
    x ^= x.wrapping_mul(0x53a2_2864);
    x
}

/// Base-2 Owen scrambling of a 0.32 fixed-point value (Burley 2020, listing 3).
pub fn nested_uniform_scramble(x: u32, seed: u32) -> u32 {
    laine_karras_permutation(x.reverse_bits(), seed).reverse_bits()
}

/// The Sobol dimension a dimension of the allocation draws from within its block of four. The camera block
/// keeps (0, 1) for the pixel jitter; later blocks start with a 1D number followed by a 2D pair (light
/// selection, light sample; BSDF lobe, BSDF sample), which gets Sobol (0, 1), the (0, 2)-sequence pair.
pub fn sobol_block_dim(dim: u32) -> u32 {
    let comp = dim & 3;
    if dim < 4 {
        comp
    } else {
        (comp + 3) & 3
    }
}

/// Sobol coordinate `sd` (0–3) of point `index`, as 0.32 fixed point, reading dimensions 2 and 3 from the
/// byte tables in `data`.
pub fn sobol_bits(index: u32, sd: u32, data: &[u32]) -> u32 {
    match sd {
        0 => index.reverse_bits(),
        1 => sobol_dim1(index),
        _ => {
            let base = (SOBOL_OFFSET + (sd - 2) * 1024) as usize;
            (0..4).fold(0, |r, k| r ^ data[base + k * 256 + ((index >> (8 * k)) & 255) as usize])
        }
    }
}

/// Padded, shuffled, Owen-scrambled Sobol (Burley 2020 §4): the index is shuffled by a nested uniform scramble
/// keyed by the block seed (so each pixel and block sees an aligned power-of-two run of the sequence), then the
/// coordinate is Owen-scrambled with a seed of its own.
pub fn sobol_owen_bits(index: u32, dim: u32, block_seed: u32, data: &[u32]) -> u32 {
    let sd = sobol_block_dim(dim);
    let i = nested_uniform_scramble(index, block_seed);
    let x = sobol_bits(i, sd, data);
    nested_uniform_scramble(x, pcg_hash(block_seed ^ sd.wrapping_mul(0x9e37_79b9).wrapping_add(0x7f4a_7c15)))
}

// ---------------------------------------------------------------------------------------------------------------
// Permutations of 0 … n − 1 (stratified, Hammersley).

/// A bijection of 0 … w (w = 2^k − 1) keyed by `seed`: multiplications by odd constants and xor-shifts, each
/// invertible modulo 2^k (the construction of Kensler 2013, "Correlated Multi-Jittered Sampling").
pub fn permute_bits(mut x: u32, w: u32, seed: u32) -> u32 {
    x ^= seed;
    x = x.wrapping_mul(0xe170_893d) & w;
    x ^= (seed >> 16) & w;
    x ^= x >> 4;
    x ^= (seed >> 8) & w;
    x = x.wrapping_mul(0x0929_eb3f) & w;
    x ^= (seed >> 23) & w;
    x ^= x >> 1;
    x = x.wrapping_mul(1 | (seed >> 27)) & w;
    x = x.wrapping_mul(0x6935_fa69) & w;
    x ^= x >> 11;
    x = x.wrapping_mul(0x74dc_b303) & w;
    x ^= x >> 2;
    x = x.wrapping_mul(0x9e50_1cc3) & w;
    x ^= x >> 2;
    x = x.wrapping_mul(0xc860_a3df) & w;
    x ^= x >> 5;
    x & w
}

/// Element i of a random permutation of 0 … n − 1 keyed by `seed`: `permute_bits` on the next power of two,
/// cycle-walking until the value falls below n (fewer than two rounds on average; bounded at 64).
pub fn permute_index(i: u32, n: u32, seed: u32) -> u32 {
    if n <= 1 {
        return 0;
    }
    let w = u32::MAX >> (n - 1).leading_zeros();
    let mut x = i;
    for _ in 0..64 {
        x = permute_bits(x, w, seed);
        if x < n {
            return x;
        }
    }
    i
}

// ---------------------------------------------------------------------------------------------------------------
// Radical inverses (Halton, Hammersley).

/// The first `n` primes.
pub fn primes(n: usize) -> Vec<u32> {
    let mut p: Vec<u32> = Vec::with_capacity(n);
    let mut k = 2u32;
    while p.len() < n {
        if p.iter().take_while(|&&q| q * q <= k).all(|&q| k % q != 0) {
            p.push(k);
        }
        k += 1;
    }
    p
}

/// Digits of a scrambled radical inverse in base b: the fewest with b^digits ≥ 2^24 (f32 resolution); b^digits
/// stays below 2^32 for every base of the table.
pub fn radical_inverse_digits(b: u32) -> u32 {
    let mut digits = 0;
    let mut p: u64 = 1;
    while p < (1 << 24) {
        p *= b as u64;
        digits += 1;
    }
    assert!(p <= u32::MAX as u64, "base {b} needs more than 32 bits");
    digits
}

/// The radical-inverse dimension (index into the prime table; Hammersley's 0 is i/N) a dimension of the
/// allocation uses: the camera's two, then the nine used dimensions of each vertex, skipping spare ones.
pub fn halton_dim(dim: u32) -> u32 {
    if dim < 2 {
        return dim;
    }
    if dim < DIMS_CAMERA {
        return NO_HALTON_DIM;
    }
    let rel = dim - DIMS_CAMERA;
    let vertex = rel / DIMS_PER_BOUNCE;
    let off = rel % DIMS_PER_BOUNCE;
    if off >= DIMS_USED_PER_BOUNCE || vertex >= HALTON_DIMS {
        return NO_HALTON_DIM;
    }
    let hd = 2 + vertex * DIMS_USED_PER_BOUNCE + off;
    if hd >= HALTON_DIMS {
        return NO_HALTON_DIM;
    }
    hd
}

/// Owen-scrambled radical inverse of `i` in the base of prime-table entry `hd`: digit k (from the most
/// significant) is mapped by a random affine permutation d ↦ (a·d + c) mod b, a ≠ 0, whose a and c are hashed
/// from the digits above it. Over a prime base affine maps are sharply 2-transitive, so any two digits of a
/// cell map to a uniformly random pair of distinct digits — the pairwise law Owen's variance analysis uses.
/// Base 2 takes the exact bit-level scramble.
pub fn scrambled_radical_inverse(i: u32, hd: u32, seed: u32, data: &[u32]) -> f32 {
    let e = (HALTON_OFFSET + 4 * hd) as usize;
    let b = data[e];
    if b == 2 {
        return bits_to_unit(nested_uniform_scramble(i.reverse_bits(), seed));
    }
    let digits = data[e + 1].min(32);
    let inv = f32::from_bits(data[e + 2]);
    let mut r = i;
    let mut acc = 0u32;
    let mut h = seed;
    for _ in 0..digits {
        let q = r / b;
        let d = r - q * b;
        r = q;
        let h2 = pcg_hash(h);
        let a = 1 + (h2 >> 16) % (b - 1);
        let c = h2 % b;
        acc = acc * b + (a * d + c) % b;
        h = h2 ^ (d.wrapping_mul(0x9e37_79b9).wrapping_add(0x632b_e5ab));
    }
    (acc as f32 * inv).min(ONE_MINUS_EPSILON)
}

// ---------------------------------------------------------------------------------------------------------------
// The table buffer.

/// Builds `sampler_data` (see the offsets above).
pub fn build_sampler_data() -> Vec<u32> {
    let mut data = vec![0u32; SAMPLER_DATA_WORDS as usize];
    for d in 2..SOBOL_DIMS {
        let m = sobol_matrix(d);
        for k in 0..4 {
            for v in 0..256u32 {
                let o = (SOBOL_OFFSET + (d - 2) * 1024 + k * 256 + v) as usize;
                data[o] = (0..8).filter(|b| (v >> b) & 1 == 1).fold(0, |r, b| r ^ m[(8 * k + b) as usize]);
            }
        }
    }
    for (hd, &p) in primes(HALTON_DIMS as usize).iter().enumerate() {
        let digits = radical_inverse_digits(p);
        let o = HALTON_OFFSET as usize + 4 * hd;
        data[o] = p;
        data[o + 1] = digits;
        data[o + 2] = ((p as f64).powi(digits as i32).recip() as f32).to_bits();
    }
    let mask = void_and_cluster(BLUE_NOISE_SIZE as usize, 1.5, 0x6d69_736c_6162);
    let o = BLUE_NOISE_OFFSET as usize;
    data[o..o + mask.len()].copy_from_slice(&mask);
    data
}

/// `sampler_data`, built once per process (the void-and-cluster mask takes a few tens of milliseconds).
pub fn sampler_data() -> &'static [u32] {
    static DATA: OnceLock<Vec<u32>> = OnceLock::new();
    DATA.get_or_init(build_sampler_data)
}

/// The blue-noise mask's ranks (a view into `sampler_data`).
pub fn blue_noise_mask() -> &'static [u32] {
    let o = BLUE_NOISE_OFFSET as usize;
    &sampler_data()[o..o + (BLUE_NOISE_SIZE * BLUE_NOISE_SIZE) as usize]
}

// ---------------------------------------------------------------------------------------------------------------
// Sample counts of the fixed-count samplers.

/// Whether the sampler's points are built for a target count (`FrameParams::sampler_spp`): stratified (one
/// sample per stratum) and Hammersley (i/N in the first coordinate). Both restart with a fresh randomisation
/// after N samples and permute their points randomly, so every prefix is still an unbiased estimate; only
/// multiples of N have the full stratification.
pub fn is_fixed_count(kind: SamplerKind) -> bool {
    matches!(kind, SamplerKind::Stratified | SamplerKind::Hammersley)
}

/// The grid of 2D strata for `n` samples: (nx, ny) with nx·ny = n and ny the largest divisor ≤ √n (the
/// same loop as `stratified_grid` in samplers.wgsl).
pub fn stratified_grid(n: u32) -> (u32, u32) {
    let n = n.max(1);
    let mut ny = (n as f32).sqrt() as u32;
    if ny * ny > n {
        ny -= 1;
    }
    if (ny + 1) * (ny + 1) <= n {
        ny += 1;
    }
    ny = ny.max(1);
    for _ in 0..65536 {
        if n % ny == 0 {
            break;
        }
        ny -= 1;
    }
    (n / ny, ny)
}

/// Whether `n` samples form a grid of strata no more than twice as wide as tall.
pub fn stratified_fits(n: u32) -> bool {
    let (nx, ny) = stratified_grid(n);
    n >= 1 && nx <= 2 * ny
}

/// The sample count a render with `kind` should use for a requested `spp`, or why none: the count-free
/// samplers take any spp; stratified rounds to the nearest count whose strata form an nx × ny grid with
/// ny ≤ nx ≤ 2·ny (ties round up); Hammersley takes any count up to `MAX_SAMPLER_SPP`. When the result differs
/// from `spp`, print `spp_message(kind, spp, used)`. Set the result as the renderer's `sampler_spp`.
pub fn check_spp(kind: SamplerKind, spp: u32) -> Result<u32, InvalidSettings> {
    if spp == 0 {
        return Err(InvalidSettings("--spp must be at least 1".into()));
    }
    if !is_fixed_count(kind) {
        return Ok(spp);
    }
    if spp > MAX_SAMPLER_SPP {
        return Err(InvalidSettings(format!(
            "--sampler {kind} builds its points for a fixed count, at most {MAX_SAMPLER_SPP}; {spp} is too many (use sobol or halton for more)"
        )));
    }
    if kind == SamplerKind::Stratified && !stratified_fits(spp) {
        let up = (spp..=MAX_SAMPLER_SPP).find(|&n| stratified_fits(n)).unwrap_or(MAX_SAMPLER_SPP);
        let down = (1..spp).rev().find(|&n| stratified_fits(n)).unwrap_or(1);
        return Ok(if spp - down < up - spp { down } else { up });
    }
    Ok(spp)
}

/// The message for a rounded sample count (empty when `used == requested`).
pub fn spp_message(kind: SamplerKind, requested: u32, used: u32) -> String {
    if requested == used {
        return String::new();
    }
    let (nx, ny) = stratified_grid(used);
    format!(
        "--sampler {kind}: {requested} spp do not form a grid of strata (nx × ny with ny ≤ nx ≤ 2·ny); using {used} spp ({nx} × {ny})"
    )
}

// ---------------------------------------------------------------------------------------------------------------
// CPU twins of the samplers.

/// What a sampler reads from `FrameParams` besides the sample id.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SamplerParams {
    /// Which sequence.
    pub kind: SamplerKind,
    /// `FrameParams::seed`.
    pub seed: u32,
    /// `FrameParams::sampler_spp` (0 = `DEFAULT_SAMPLER_SPP`).
    pub sampler_spp: u32,
    /// `FrameParams::width` (the blue-noise sampler finds the pixel's position from its index).
    pub width: u32,
}

impl SamplerParams {
    /// The target count the fixed-count samplers use.
    pub fn target(&self) -> u32 {
        if self.sampler_spp == 0 {
            DEFAULT_SAMPLER_SPP
        } else {
            self.sampler_spp.min(MAX_SAMPLER_SPP)
        }
    }
}

/// Independent sampler: a hash of (pixel, index, dimension, seed).
pub fn sample_independent(p: &SamplerParams, pixel: u32, index: u32, dim: u32) -> f32 {
    bits_to_unit(hash4(pixel, index, dim, p.seed))
}

fn sample_stratified(p: &SamplerParams, pixel: u32, index: u32, dim: u32) -> f32 {
    let n = p.target();
    let pass = index / n;
    let s = index - pass * n;
    let h = hash4(pixel, dim, pass, p.seed ^ SALT_STRATIFIED);
    let stratum = permute_index(s, n, h);
    let j = bits_to_unit(pcg_hash(h ^ pcg_hash(stratum)));
    ((stratum as f32 + j) / n as f32).min(ONE_MINUS_EPSILON)
}

fn sample_stratified_2d(p: &SamplerParams, pixel: u32, index: u32, dim: u32) -> [f32; 2] {
    let n = p.target();
    let pass = index / n;
    let s = index - pass * n;
    let h = hash4(pixel, dim, pass, p.seed ^ SALT_STRATIFIED_2D);
    let stratum = permute_index(s, n, h);
    let (nx, ny) = stratified_grid(n);
    let cy = stratum / nx;
    let cx = stratum - cy * nx;
    let a = pcg_hash(h ^ pcg_hash(stratum));
    let (jx, jy) = (bits_to_unit(a), bits_to_unit(pcg_hash(a)));
    [((cx as f32 + jx) / nx as f32).min(ONE_MINUS_EPSILON), ((cy as f32 + jy) / ny as f32).min(ONE_MINUS_EPSILON)]
}

fn sample_halton(p: &SamplerParams, pixel: u32, index: u32, dim: u32) -> f32 {
    let hd = halton_dim(dim);
    if hd == NO_HALTON_DIM {
        return sample_independent(p, pixel, index, dim);
    }
    scrambled_radical_inverse(index, hd, hash4(pixel, hd, p.seed, SALT_HALTON), sampler_data())
}

fn sample_hammersley(p: &SamplerParams, pixel: u32, index: u32, dim: u32) -> f32 {
    let hd = halton_dim(dim);
    if hd == NO_HALTON_DIM {
        return sample_independent(p, pixel, index, dim);
    }
    let n = p.target();
    let pass = index / n;
    let s = index - pass * n;
    let hp = hash4(pixel, pass, p.seed, SALT_HAMMERSLEY);
    let j = permute_index(s, n, hp);
    if hd == 0 {
        let u = bits_to_unit(pcg_hash(hp ^ pcg_hash(j)));
        return ((j as f32 + u) / n as f32).min(ONE_MINUS_EPSILON);
    }
    scrambled_radical_inverse(j, hd - 1, pcg_hash(hp ^ hd.wrapping_mul(0x9e37_79b9)), sampler_data())
}

fn sample_sobol_bits(p: &SamplerParams, pixel: u32, index: u32, dim: u32) -> u32 {
    let block_seed = hash4(pixel, dim >> 2, p.seed, SALT_SOBOL);
    sobol_owen_bits(index, dim, block_seed, sampler_data())
}

/// The blue-noise mask offset of a dimension: (x, y) in the low and next bits.
pub fn blue_noise_offset(dim: u32, seed: u32) -> u32 {
    pcg_hash(pcg_hash(dim ^ SALT_BLUE_OFFSET) ^ seed)
}

fn sample_blue_noise_bits(p: &SamplerParams, pixel: u32, index: u32, dim: u32) -> u32 {
    // One Owen-scrambled Sobol sequence for the whole image (the block seed leaves the pixel out) ...
    let block_seed = hash4(0, dim >> 2, p.seed, SALT_BLUE_NOISE);
    let x = sobol_owen_bits(index, dim, block_seed, sampler_data());
    // ... rotated (Cranley–Patterson, mod 1) per pixel by the blue-noise mask's value there.
    let w = p.width.max(1);
    let (px, py) = (pixel % w, pixel / w);
    let o = blue_noise_offset(dim, p.seed);
    let m = BLUE_NOISE_SIZE - 1;
    let mx = (px.wrapping_add(o)) & m;
    let my = (py.wrapping_add(o >> 8)) & m;
    let rank = sampler_data()[(BLUE_NOISE_OFFSET + my * BLUE_NOISE_SIZE + mx) as usize];
    x.wrapping_add(rank << (32 - 2 * BLUE_NOISE_LOG2))
}

/// One value of the sequence `p.kind` (twin of `sample_1d` in samplers.wgsl).
pub fn sample_1d(p: &SamplerParams, pixel: u32, index: u32, dim: u32) -> f32 {
    match p.kind {
        SamplerKind::Independent => sample_independent(p, pixel, index, dim),
        SamplerKind::Stratified => sample_stratified(p, pixel, index, dim),
        SamplerKind::Halton => sample_halton(p, pixel, index, dim),
        SamplerKind::Hammersley => sample_hammersley(p, pixel, index, dim),
        SamplerKind::Sobol => bits_to_unit(sample_sobol_bits(p, pixel, index, dim)),
        SamplerKind::BlueNoise => bits_to_unit(sample_blue_noise_bits(p, pixel, index, dim)),
    }
}

/// Two consecutive dimensions (twin of `sample_2d`): jittered 2D strata for the stratified sampler, the pair
/// of 1D values for the others.
pub fn sample_2d(p: &SamplerParams, pixel: u32, index: u32, dim: u32) -> [f32; 2] {
    match p.kind {
        SamplerKind::Stratified => sample_stratified_2d(p, pixel, index, dim),
        _ => [sample_1d(p, pixel, index, dim), sample_1d(p, pixel, index, dim + 1)],
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn dim1_butterflies_match_the_recurrence() {
        let m = sobol_matrix(1);
        for i in [0u32, 1, 2, 3, 5, 77, 1023, 0xdead_beef, u32::MAX] {
            assert_eq!(sobol_dim1(i), sobol_bits_matrix(i, &m), "index {i}");
        }
    }
}
