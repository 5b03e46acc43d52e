//! Blue noise: the void-and-cluster dither array (Ulichney 1993, "The void-and-cluster method for dither array
//! generation") behind the blue-noise sampler's mask (`samplers::blue_noise_mask`). Built once on the CPU.

/// A `size`×`size` tileable dither array by void and cluster: every pixel gets a distinct rank 0 … size² − 1 such
/// that for every k the pixels ranked below k are evenly spread (their energy under a toroidal Gaussian of
/// σ = `sigma` is as flat as the greedy steps can make it). Deterministic for a given `seed`.
pub fn void_and_cluster(size: usize, sigma: f64, seed: u64) -> Vec<u32> {
    let n = size * size;
    // Toroidal Gaussian kernel indexed by the wrapped offset.
    let kernel: Vec<f64> = (0..n)
        .map(|k| {
            let (dx, dy) = ((k % size) as f64, (k / size) as f64);
            let (dx, dy) = (dx.min(size as f64 - dx), dy.min(size as f64 - dy));
            (-(dx * dx + dy * dy) / (2.0 * sigma * sigma)).exp()
        })
        .collect();
    let update = |energy: &mut [f64], q: usize, sign: f64| add_kernel(energy, &kernel, size, q, sign);
    let tightest_cluster = |bits: &[bool], energy: &[f64]| extreme(bits, energy, true).expect("a one");
    let largest_void = |bits: &[bool], energy: &[f64]| extreme(bits, energy, false).expect("a zero");

    // Initial binary pattern: a tenth of the pixels, at random (splitmix64).
    let mut state = seed;
    let mut next = || {
        state = state.wrapping_add(0x9e37_79b9_7f4a_7c15);
        let mut z = state;
        z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
        z ^ (z >> 31)
    };
    let ones = (n / 10).max(1);
    let mut bits = vec![false; n];
    let mut placed = 0;
    while placed < ones {
        let p = (next() % n as u64) as usize;
        if !bits[p] {
            bits[p] = true;
            placed += 1;
        }
    }
    let mut energy = vec![0.0; n];
    for q in (0..n).filter(|&q| bits[q]) {
        update(&mut energy, q, 1.0);
    }
    // Relax the initial pattern: move the tightest cluster into the largest void until that changes nothing.
    for _ in 0..n {
        let c = tightest_cluster(&bits, &energy);
        bits[c] = false;
        update(&mut energy, c, -1.0);
        let v = largest_void(&bits, &energy);
        bits[v] = true;
        update(&mut energy, v, 1.0);
        if v == c {
            break;
        }
    }
    let prototype = (bits.clone(), energy.clone());
    let mut rank = vec![0u32; n];
    // Phase 1: rank the prototype's ones by removing tightest clusters.
    let mut count = ones;
    while count > 0 {
        let c = tightest_cluster(&bits, &energy);
        bits[c] = false;
        update(&mut energy, c, -1.0);
        count -= 1;
        rank[c] = count as u32;
    }
    // Phases 2 and 3: fill the largest voids. Past half full, the tightest cluster of zeros (Ulichney's phase 3)
    // is the zero with the most energy from zeros, which is the zero with the least energy from ones: the same
    // choice, since the two energies sum to a constant.
    let (mut bits, mut energy) = prototype;
    for count in ones..n {
        let v = largest_void(&bits, &energy);
        bits[v] = true;
        update(&mut energy, v, 1.0);
        rank[v] = count as u32;
    }
    rank
}

/// Adds `sign` × the toroidal `kernel` (indexed by wrapped offset) centred on pixel `q` to every pixel's energy.
/// Row by row, the kernel's x index is the pixel's shifted by q's with one wrap, so a row is two contiguous runs
/// and no pixel needs a division: the same additions, in the same order, as indexing the kernel by each pixel's
/// wrapped offset from `q` (the tests compare the two bit for bit).
fn add_kernel(energy: &mut [f64], kernel: &[f64], size: usize, q: usize, sign: f64) {
    let (qx, qy) = (q % size, q / size);
    for (py, row) in energy.chunks_exact_mut(size).enumerate() {
        let k = &kernel[((py + size - qy) % size) * size..][..size];
        let (left, right) = row.split_at_mut(qx);
        for (e, k) in left.iter_mut().zip(&k[size - qx..]) {
            *e += sign * k;
        }
        for (e, k) in right.iter_mut().zip(&k[..size - qx]) {
            *e += sign * k;
        }
    }
}

/// Among the pixels whose bit is `ones`: for ones the one with the most energy (the tightest cluster), for zeros
/// the one with the least (the largest void); the first such pixel on ties.
fn extreme(bits: &[bool], energy: &[f64], ones: bool) -> Option<usize> {
    let want = if ones { std::cmp::Ordering::Greater } else { std::cmp::Ordering::Less };
    let mut best: Option<usize> = None;
    for p in (0..bits.len()).filter(|&p| bits[p] == ones) {
        if best.is_none_or(|b| energy[p].total_cmp(&energy[b]) == want) {
            best = Some(p);
        }
    }
    best
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The definitions the fast forms must equal: the kernel indexed by each pixel's wrapped offset from q, and
    /// the extreme pixel by a comparison that breaks ties towards the lower index.
    fn add_kernel_by_offset(energy: &mut [f64], kernel: &[f64], size: usize, q: usize, sign: f64) {
        let (qx, qy) = (q % size, q / size);
        for (p, e) in energy.iter_mut().enumerate() {
            let (px, py) = (p % size, p / size);
            *e += sign * kernel[((py + size - qy) % size) * size + (px + size - qx) % size];
        }
    }

    fn extreme_by_iterator(bits: &[bool], energy: &[f64], ones: bool) -> Option<usize> {
        let candidates = (0..bits.len()).filter(|&p| bits[p] == ones);
        if ones {
            candidates.max_by(|&a, &b| energy[a].total_cmp(&energy[b]).then(b.cmp(&a)))
        } else {
            candidates.min_by(|&a, &b| energy[a].total_cmp(&energy[b]).then(a.cmp(&b)))
        }
    }

    #[test]
    fn row_wise_kernel_addition_is_the_offset_indexed_one_bit_for_bit() {
        for size in [1usize, 2, 5, 8] {
            let n = size * size;
            let kernel: Vec<f64> = (0..n).map(|k| 1.0 / (1.0 + k as f64 * 0.37)).collect();
            let (mut fast, mut slow) = (vec![0.0; n], vec![0.0; n]);
            for (i, q) in (0..n).chain((0..n).rev()).enumerate() {
                let sign = if i % 3 == 0 { -1.0 } else { 1.0 };
                add_kernel(&mut fast, &kernel, size, q, sign);
                add_kernel_by_offset(&mut slow, &kernel, size, q, sign);
                assert!(fast.iter().zip(&slow).all(|(a, b)| a.to_bits() == b.to_bits()), "size {size}, q {q}");
            }
        }
    }

    #[test]
    fn extremes_break_ties_as_the_definition_does() {
        // Energies with many ties, and every pattern of bits over 8 pixels.
        let energy = [0.5, 0.25, 0.5, 0.75, 0.25, 0.75, 0.5, 0.25];
        for pattern in 0u32..256 {
            let bits: Vec<bool> = (0..8).map(|i| (pattern >> i) & 1 == 1).collect();
            for ones in [true, false] {
                assert_eq!(extreme(&bits, &energy, ones), extreme_by_iterator(&bits, &energy, ones), "{bits:?}");
            }
        }
    }
}
