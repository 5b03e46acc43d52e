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
    let offset = |p: usize, q: usize| -> usize {
        let (px, py, qx, qy) = (p % size, p / size, q % size, q / size);
        ((py + size - qy) % size) * size + (px + size - qx) % size
    };
    let update = |energy: &mut [f64], q: usize, sign: f64| {
        for (p, e) in energy.iter_mut().enumerate() {
            *e += sign * kernel[offset(p, q)];
        }
    };
    let tightest_cluster = |bits: &[bool], energy: &[f64]| -> usize {
        (0..n).filter(|&p| bits[p]).max_by(|&a, &b| energy[a].total_cmp(&energy[b]).then(b.cmp(&a))).expect("a one")
    };
    let largest_void = |bits: &[bool], energy: &[f64]| -> usize {
        (0..n).filter(|&p| !bits[p]).min_by(|&a, &b| energy[a].total_cmp(&energy[b]).then(a.cmp(&b))).expect("a zero")
    };

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
