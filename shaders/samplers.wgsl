// samplers.wgsl — stateless sample sequences: (pixel, sample index, dimension) → u ∈ [0,1). CPU twin and
// tables: src/render/samplers.rs (`sampler_data`, group 1 binding 3, declared in shading_bindings.wgsl).
//
// Dimension allocation. Every sampler sees the same meaning per dimension, in blocks of four (the padded Sobol
// sampler gives each block its own shuffled 4D Sobol pattern):
//   block 0, dims 0–3: camera (0–1 pixel jitter, 2–3 spare);
//   then per path vertex (bounce b) DIMS_PER_BOUNCE = 12 dimensions from dim_base(b, 0):
//     +0 light selection, +1..2 light sample, +3 light sample's third number (environment alias table),
//     +4 BSDF lobe, +5..6 BSDF/direction sample, +7 Russian roulette,
//     +8 one-sample-MIS technique choice, +9..11 spare.
// The j-th extra light/BSDF sample of a vertex (multi-sample MIS) uses the block of bounce b + j·MAX_VERTICES.
// 2D pairs (camera, light sample, BSDF sample) are read with sample_2d.
//
// Samplers (cfg_sampler(); a specialised pipeline folds the others away — lavapipe runs every branch a lane
// might take under a mask, so each sampler's code stays behind its own `cfg_sampler() == SAMPLER_X`):
//   independent  hash of (pixel, index, dim, seed);
//   stratified   jittered strata over a target count N = params.sampler_spp (1D: N strata; 2D: nx × ny),
//                strata visited in a random order, a fresh randomisation every N samples;
//   halton       Owen-scrambled Halton per pixel (prime bases in allocation order, spare dims skipped);
//   hammersley   (j/N jittered, Owen-scrambled radical inverses of j) over N = params.sampler_spp, j a random
//                permutation of the sample index, a fresh randomisation every N samples;
//   sobol        padded, shuffled, Owen-scrambled Sobol per pixel (Burley 2020);
//   blue-noise   one Owen-scrambled Sobol sequence for all pixels, rotated per pixel by a void-and-cluster
//                blue-noise mask (Georgiev & Fajardo 2016): low-spp error is distributed as blue noise.
// Every one is an unbiased estimator at any prefix of sample indices.

const DIMS_CAMERA: u32 = 4u;
const DIMS_PER_BOUNCE: u32 = 12u;
const DIMS_USED_PER_BOUNCE: u32 = 9u;
const MAX_VERTICES: u32 = 64u;
const DIM_LIGHT_SELECT: u32 = 0u;
const DIM_LIGHT_UV: u32 = 1u;
const DIM_LIGHT_EXTRA: u32 = 3u;
const DIM_BSDF_LOBE: u32 = 4u;
const DIM_BSDF_UV: u32 = 5u;
const DIM_RR: u32 = 7u;
const DIM_MIS_CHOICE: u32 = 8u;

// Layout of sampler_data (src/render/samplers.rs has the same constants; tests/samplers.rs compares them).
const SOBOL_OFFSET: u32 = 0u;
const SOBOL_TABLE_WORDS: u32 = 2048u;
const HALTON_OFFSET: u32 = 2048u;
const HALTON_DIMS: u32 = 256u;
const BLUE_NOISE_OFFSET: u32 = 3072u;
const BLUE_NOISE_LOG2: u32 = 6u;
const BLUE_NOISE_SIZE: u32 = 64u;
const DEFAULT_SAMPLER_SPP: u32 = 16u;
const MAX_SAMPLER_SPP: u32 = 1048576u;
const NO_HALTON_DIM: u32 = 0xffffffffu;

const SALT_SOBOL: u32 = 0x50b01du;
const SALT_BLUE_NOISE: u32 = 0xb10e5eu;
const SALT_BLUE_OFFSET: u32 = 0xb10ff5u;
const SALT_HALTON: u32 = 0x4a1707u;
const SALT_HAMMERSLEY: u32 = 0x4a33e5u;
const SALT_STRATIFIED: u32 = 0x57a71du;
const SALT_STRATIFIED_2D: u32 = 0x57a72du;

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

// ---- Owen scrambling (Burley 2020, "Practical Hash-based Owen Scrambling"; hash constants of Vegdahl 2021).

/// Every output bit depends only on input bits at or below it: on bit-reversed values, a nested uniform scramble.
fn laine_karras_permutation(x_in: u32, seed: u32) -> u32 {
    var x = x_in;
    x ^= x * 0x3d20adeau;
    x += seed;
    x *= (seed >> 16u) | 1u;
    x ^= x * 0x05526c56u;
    x ^= x * 0x53a22864u;
    return x;
}

/// Base-2 Owen scrambling of a 0.32 fixed-point value (Burley 2020, listing 3).
fn nested_uniform_scramble(x: u32, seed: u32) -> u32 {
    return reverseBits(laine_karras_permutation(reverseBits(x), seed));
}

/// Sobol dimension (0–3) of a dimension within its block: the camera keeps (0, 1); later blocks map their
/// 2D pair (components 1, 2) to (0, 1), the (0, 2)-sequence pair.
fn sobol_block_dim(dim: u32) -> u32 {
    let comp = dim & 3u;
    return select((comp + 3u) & 3u, comp, dim < 4u);
}

/// Sobol dimensions 2 and 3 (sd = 2, 3) without tables: the XOR of the generator-matrix columns (src/render/samplers.rs
/// `sobol_matrix`) of the index's set bits, unrolled. No loads (a storage-buffer read is a loop over the lanes on
/// lavapipe: the four byte-table reads this replaces cost more than these 32 masked XORs) and no loop (every loop
/// iteration counts against lavapipe's per-invocation budget).
fn sobol_matrix_bits(index: u32, sd: u32) -> u32 {
    let two = sd == 2u;
    var x = 0u;
    x ^= (0u - ((index >> 0u) & 1u)) & select(0x80000000u, 0x80000000u, two);
    x ^= (0u - ((index >> 1u) & 1u)) & select(0xc0000000u, 0xc0000000u, two);
    x ^= (0u - ((index >> 2u) & 1u)) & select(0x20000000u, 0x60000000u, two);
    x ^= (0u - ((index >> 3u) & 1u)) & select(0x50000000u, 0x90000000u, two);
    x ^= (0u - ((index >> 4u) & 1u)) & select(0xf8000000u, 0xe8000000u, two);
    x ^= (0u - ((index >> 5u) & 1u)) & select(0x74000000u, 0x5c000000u, two);
    x ^= (0u - ((index >> 6u) & 1u)) & select(0xa2000000u, 0x8e000000u, two);
    x ^= (0u - ((index >> 7u) & 1u)) & select(0x93000000u, 0xc5000000u, two);
    x ^= (0u - ((index >> 8u) & 1u)) & select(0xd8800000u, 0x68800000u, two);
    x ^= (0u - ((index >> 9u) & 1u)) & select(0x25400000u, 0x9cc00000u, two);
    x ^= (0u - ((index >> 10u) & 1u)) & select(0x59e00000u, 0xee600000u, two);
    x ^= (0u - ((index >> 11u) & 1u)) & select(0xe6d00000u, 0x55900000u, two);
    x ^= (0u - ((index >> 12u) & 1u)) & select(0x78080000u, 0x80680000u, two);
    x ^= (0u - ((index >> 13u) & 1u)) & select(0xb40c0000u, 0xc09c0000u, two);
    x ^= (0u - ((index >> 14u) & 1u)) & select(0x82020000u, 0x60ee0000u, two);
    x ^= (0u - ((index >> 15u) & 1u)) & select(0xc3050000u, 0x90550000u, two);
    x ^= (0u - ((index >> 16u) & 1u)) & select(0x208f8000u, 0xe8808000u, two);
    x ^= (0u - ((index >> 17u) & 1u)) & select(0x51474000u, 0x5cc0c000u, two);
    x ^= (0u - ((index >> 18u) & 1u)) & select(0xfbea2000u, 0x8e606000u, two);
    x ^= (0u - ((index >> 19u) & 1u)) & select(0x75d93000u, 0xc5909000u, two);
    x ^= (0u - ((index >> 20u) & 1u)) & select(0xa0858800u, 0x6868e800u, two);
    x ^= (0u - ((index >> 21u) & 1u)) & select(0x914e5400u, 0x9c9c5c00u, two);
    x ^= (0u - ((index >> 22u) & 1u)) & select(0xdbe79e00u, 0xeeee8e00u, two);
    x ^= (0u - ((index >> 23u) & 1u)) & select(0x25db6d00u, 0x5555c500u, two);
    x ^= (0u - ((index >> 24u) & 1u)) & select(0x58800080u, 0x8000e880u, two);
    x ^= (0u - ((index >> 25u) & 1u)) & select(0xe54000c0u, 0xc0005cc0u, two);
    x ^= (0u - ((index >> 26u) & 1u)) & select(0x79e00020u, 0x60008e60u, two);
    x ^= (0u - ((index >> 27u) & 1u)) & select(0xb6d00050u, 0x9000c590u, two);
    x ^= (0u - ((index >> 28u) & 1u)) & select(0x800800f8u, 0xe8006868u, two);
    x ^= (0u - ((index >> 29u) & 1u)) & select(0xc00c0074u, 0x5c009c9cu, two);
    x ^= (0u - ((index >> 30u) & 1u)) & select(0x200200a2u, 0x8e00eeeeu, two);
    x ^= (0u - ((index >> 31u) & 1u)) & select(0x50050093u, 0xc5005555u, two);
    return x;
}

/// Sobol dimension 1 before its final bit reversal: the index times Pascal's triangle mod 2.
fn sobol_pascal(index: u32) -> u32 {
    var x = index;
    x ^= (x & 0xaaaaaaaau) >> 1u;
    x ^= (x & 0xccccccccu) >> 2u;
    x ^= (x & 0xf0f0f0f0u) >> 4u;
    x ^= (x & 0xff00ff00u) >> 8u;
    x ^= (x & 0xffff0000u) >> 16u;
    return x;
}

/// Sobol coordinate `sd` of point `index` as 0.32 fixed point. Dimension 0 is the bit reversal; dimension 1
/// (Pascal's triangle mod 2) is a superset-sum transform; dimensions 2–3 are `sobol_matrix_bits` (the byte tables
/// in sampler_data serve the CPU twin). No loops: lavapipe counts every loop iteration of an invocation against one budget of 65535
/// and silently stops looping when it runs out.
fn sobol_bits(index: u32, sd: u32) -> u32 {
    if (sd == 0u) { return reverseBits(index); }
    if (sd == 1u) { return reverseBits(sobol_pascal(index)); }
    return sobol_matrix_bits(index, sd);
}

/// Padded, shuffled, Owen-scrambled Sobol (Burley 2020 §4): the index is shuffled by a nested uniform scramble
/// keyed by the block (so each pixel and block sees an aligned power-of-two run of the sequence), then the
/// coordinate is Owen-scrambled with a seed of its own.
fn sobol_owen_bits(index: u32, dim: u32, block_seed: u32) -> u32 {
    let sd = sobol_block_dim(dim);
    let i = nested_uniform_scramble(index, block_seed);
    let x = sobol_bits(i, sd);
    return nested_uniform_scramble(x, sobol_dim_seed(block_seed, sd));
}

fn sobol_dim_seed(block_seed: u32, sd: u32) -> u32 {
    return pcg_hash(block_seed ^ (sd * 0x9e3779b9u + 0x7f4a7c15u));
}

/// `sobol_owen_bits` for both dimensions of a block's 2D pair (Sobol dimensions 0 and 1), bit for bit, at less
/// than half the cost: one index shuffle for both, and since those dimensions are bit reversals (of the index
/// and of its Pascal transform), Owen-scrambling them is reverseBits(LK(y)) — one reversal instead of three.
fn sobol_owen_pair(index: u32, block_seed: u32) -> vec2<u32> {
    let i = nested_uniform_scramble(index, block_seed);
    return vec2<u32>(
        reverseBits(laine_karras_permutation(i, sobol_dim_seed(block_seed, 0u))),
        reverseBits(laine_karras_permutation(sobol_pascal(i), sobol_dim_seed(block_seed, 1u))),
    );
}

// ---- Random permutations of 0 … n − 1 (stratified, Hammersley).

/// A bijection of 0 … w (w = 2^k − 1) keyed by `seed` (Kensler 2013, "Correlated Multi-Jittered Sampling").
fn permute_bits(x_in: u32, w: u32, seed: u32) -> u32 {
    var x = x_in;
    x ^= seed;
    x = (x * 0xe170893du) & w;
    x ^= (seed >> 16u) & w;
    x ^= x >> 4u;
    x ^= (seed >> 8u) & w;
    x = (x * 0x0929eb3fu) & w;
    x ^= (seed >> 23u) & w;
    x ^= x >> 1u;
    x = (x * (1u | (seed >> 27u))) & w;
    x = (x * 0x6935fa69u) & w;
    x ^= x >> 11u;
    x = (x * 0x74dcb303u) & w;
    x ^= x >> 2u;
    x = (x * 0x9e501cc3u) & w;
    x ^= x >> 2u;
    x = (x * 0xc860a3dfu) & w;
    x ^= x >> 5u;
    return x & w;
}

/// Element i of a random permutation of 0 … n − 1: cycle-walking `permute_bits` (bounded at 64 rounds).
fn permute_index(i: u32, n: u32, seed: u32) -> u32 {
    if (n <= 1u) { return 0u; }
    let w = 0xffffffffu >> countLeadingZeros(n - 1u);
    var x = i;
    for (var k = 0u; k < 64u; k += 1u) {
        x = permute_bits(x, w, seed);
        if (x < n) { return x; }
    }
    return i;
}

/// The target count of the fixed-count samplers.
fn sampler_target() -> u32 {
    return select(min(params.sampler_spp, MAX_SAMPLER_SPP), DEFAULT_SAMPLER_SPP, params.sampler_spp == 0u);
}

// ---- Radical inverses (Halton, Hammersley).

/// Radical-inverse dimension of an allocation dimension (camera 0–1, then the 9 used dims of each vertex).
fn halton_dim(dim: u32) -> u32 {
    if (dim < 2u) { return dim; }
    if (dim < DIMS_CAMERA) { return NO_HALTON_DIM; }
    let rel = dim - DIMS_CAMERA;
    let vertex = rel / DIMS_PER_BOUNCE;
    let off = rel % DIMS_PER_BOUNCE;
    if (off >= DIMS_USED_PER_BOUNCE || vertex >= HALTON_DIMS) { return NO_HALTON_DIM; }
    let hd = 2u + vertex * DIMS_USED_PER_BOUNCE + off;
    return select(hd, NO_HALTON_DIM, hd >= HALTON_DIMS);
}

/// State of a scrambled radical inverse between digits: the index digits left, the scrambled digits so far,
/// and the hash of the digits above (which keys the next digit's permutation).
struct RadicalDigits {
    r: u32,
    acc: u32,
    h: u32,
}

/// One digit of a scrambled radical inverse in base b: d ↦ (a·d + c) mod b with a ≠ 0 and c hashed from the
/// digits above.
fn scramble_digit(s: RadicalDigits, b: u32) -> RadicalDigits {
    let q = s.r / b;
    let d = s.r - q * b;
    let h2 = pcg_hash(s.h);
    let a = 1u + (h2 >> 16u) % (b - 1u);
    let c = h2 % b;
    return RadicalDigits(q, s.acc * b + (a * d + c) % b, h2 ^ (d * 0x9e3779b9u + 0x632be5abu));
}

/// Owen-scrambled radical inverse of i in the base of prime-table entry hd: each digit goes through a random
/// affine permutation d ↦ (a·d + c) mod b, a ≠ 0, hashed from the digits above it (sharply 2-transitive over a
/// prime base, so pairs of digits scramble as under Owen's full permutations). Base 2 uses the bit scramble.
fn scrambled_radical_inverse(i: u32, hd: u32, seed: u32) -> f32 {
    let e = HALTON_OFFSET + 4u * hd;
    let b = sampler_data[e];
    if (b == 2u) { return bits_to_unit(nested_uniform_scramble(reverseBits(i), seed)); }
    let digits = sampler_data[e + 1u];
    let inv = bitcast<f32>(sampler_data[e + 2u]);
    // Unrolled rather than looped (see sobol_bits): bases 3 … 1619 need 3 … 16 digits for 24 bits.
    var s = RadicalDigits(i, 0u, seed);
    s = scramble_digit(s, b); s = scramble_digit(s, b); s = scramble_digit(s, b);
    if (digits > 3u) { s = scramble_digit(s, b); }
    if (digits > 4u) { s = scramble_digit(s, b); }
    if (digits > 5u) { s = scramble_digit(s, b); }
    if (digits > 6u) { s = scramble_digit(s, b); }
    if (digits > 7u) { s = scramble_digit(s, b); }
    if (digits > 8u) { s = scramble_digit(s, b); }
    if (digits > 9u) { s = scramble_digit(s, b); }
    if (digits > 10u) { s = scramble_digit(s, b); }
    if (digits > 11u) { s = scramble_digit(s, b); }
    if (digits > 12u) { s = scramble_digit(s, b); }
    if (digits > 13u) { s = scramble_digit(s, b); }
    if (digits > 14u) { s = scramble_digit(s, b); }
    if (digits > 15u) { s = scramble_digit(s, b); }
    return min(f32(s.acc) * inv, ONE_MINUS_EPSILON);
}

// ---- The samplers.

/// Jittered 1D strata: stratum = a random permutation of the index within its epoch of N.
fn sample_stratified(id: SampleId, dim: u32) -> f32 {
    let n = sampler_target();
    let epoch = id.index / n;
    let s = id.index - epoch * n;
    let h = hash4(id.pixel, dim, epoch, params.seed ^ SALT_STRATIFIED);
    let stratum = permute_index(s, n, h);
    let j = bits_to_unit(pcg_hash(h ^ pcg_hash(stratum)));
    return min((f32(stratum) + j) / f32(n), ONE_MINUS_EPSILON);
}

/// The nx × ny grid of 2D strata: ny the largest divisor of n not above √n.
fn stratified_grid(n_in: u32) -> vec2<u32> {
    let n = max(n_in, 1u);
    var ny = u32(sqrt(f32(n)));
    if (ny * ny > n) { ny -= 1u; }
    if ((ny + 1u) * (ny + 1u) <= n) { ny += 1u; }
    ny = max(ny, 1u);
    for (var k = 0u; k < 65536u; k += 1u) {
        if (n % ny == 0u) { break; }
        ny -= 1u;
    }
    return vec2<u32>(n / ny, ny);
}

/// Jittered 2D strata (nx × ny) for a pair of dimensions.
fn sample_stratified_2d(id: SampleId, dim: u32) -> vec2<f32> {
    let n = sampler_target();
    let epoch = id.index / n;
    let s = id.index - epoch * n;
    let h = hash4(id.pixel, dim, epoch, params.seed ^ SALT_STRATIFIED_2D);
    let stratum = permute_index(s, n, h);
    let g = stratified_grid(n);
    let cy = stratum / g.x;
    let cx = stratum - cy * g.x;
    let a = pcg_hash(h ^ pcg_hash(stratum));
    let jx = bits_to_unit(a);
    let jy = bits_to_unit(pcg_hash(a));
    return min(vec2<f32>((f32(cx) + jx) / f32(g.x), (f32(cy) + jy) / f32(g.y)), vec2<f32>(ONE_MINUS_EPSILON));
}

/// Owen-scrambled Halton, one randomisation per pixel; dimensions past the prime table are hashed.
fn sample_halton(id: SampleId, dim: u32) -> f32 {
    let hd = halton_dim(dim);
    if (hd == NO_HALTON_DIM) { return sample_independent(id, dim); }
    return scrambled_radical_inverse(id.index, hd, hash4(id.pixel, hd, params.seed, SALT_HALTON));
}

/// Hammersley over N: point j = π(index mod N) has (j + u)/N first, then Owen-scrambled radical inverses of j.
fn sample_hammersley(id: SampleId, dim: u32) -> f32 {
    let hd = halton_dim(dim);
    if (hd == NO_HALTON_DIM) { return sample_independent(id, dim); }
    let n = sampler_target();
    let epoch = id.index / n;
    let s = id.index - epoch * n;
    let hp = hash4(id.pixel, epoch, params.seed, SALT_HAMMERSLEY);
    let j = permute_index(s, n, hp);
    if (hd == 0u) {
        let u = bits_to_unit(pcg_hash(hp ^ pcg_hash(j)));
        return min((f32(j) + u) / f32(n), ONE_MINUS_EPSILON);
    }
    return scrambled_radical_inverse(j, hd - 1u, pcg_hash(hp ^ (hd * 0x9e3779b9u)));
}

/// Padded Owen-scrambled Sobol, one randomisation per pixel and block of four dimensions.
fn sample_sobol_bits(id: SampleId, dim: u32) -> u32 {
    return sobol_owen_bits(id.index, dim, hash4(id.pixel, dim >> 2u, params.seed, SALT_SOBOL));
}

/// One Owen-scrambled Sobol sequence for every pixel, rotated mod 1 by the blue-noise mask at the pixel
/// (offset per dimension so dimensions do not share a pattern).
fn sample_blue_noise_bits(id: SampleId, dim: u32) -> u32 {
    let x = sobol_owen_bits(id.index, dim, hash4(0u, dim >> 2u, params.seed, SALT_BLUE_NOISE));
    let w = max(params.width, 1u);
    let py = id.pixel / w;
    let px = id.pixel - py * w;
    let o = pcg_hash(pcg_hash(dim ^ SALT_BLUE_OFFSET) ^ params.seed);
    let m = BLUE_NOISE_SIZE - 1u;
    let mx = (px + o) & m;
    let my = (py + (o >> 8u)) & m;
    let rank = sampler_data[BLUE_NOISE_OFFSET + my * BLUE_NOISE_SIZE + mx];
    return x + (rank << (32u - 2u * BLUE_NOISE_LOG2));
}

/// One value of the active sequence.
fn sample_1d(id: SampleId, dim: u32) -> f32 {
    let k = cfg_sampler();
    if (k == SAMPLER_SOBOL) { return bits_to_unit(sample_sobol_bits(id, dim)); }
    if (k == SAMPLER_BLUE_NOISE) { return bits_to_unit(sample_blue_noise_bits(id, dim)); }
    if (k == SAMPLER_HALTON) { return sample_halton(id, dim); }
    if (k == SAMPLER_HAMMERSLEY) { return sample_hammersley(id, dim); }
    if (k == SAMPLER_STRATIFIED) { return sample_stratified(id, dim); }
    return sample_independent(id, dim);
}

/// Two consecutive dimensions of the active sequence (2D strata for the stratified sampler). `dim` must start a
/// block's 2D pair (dimension 0, or component 1 of a later block): the Sobol samplers read the pair together.
fn sample_2d(id: SampleId, dim: u32) -> vec2<f32> {
    let k = cfg_sampler();
    if (k == SAMPLER_STRATIFIED) { return sample_stratified_2d(id, dim); }
    if (k == SAMPLER_SOBOL) {
        let xy = sobol_owen_pair(id.index, hash4(id.pixel, dim >> 2u, params.seed, SALT_SOBOL));
        return vec2<f32>(bits_to_unit(xy.x), bits_to_unit(xy.y));
    }
    return vec2<f32>(sample_1d(id, dim), sample_1d(id, dim + 1u));
}
