//! The order in which a dispatch's rows of 8×8 tiles are handed out. Mesa's lavapipe splits a dispatch
//! statically: with T threads, thread k runs workgroups k·N/T … (k+1)·N/T − 1 in linear order (x fastest), so on
//! two cores one thread renders the top half of the image and the other the bottom half, and the thread with the
//! cheaper half (sky, say) then idles until the other is done — measured on scaling_100k at 256², 64 spp: one
//! worker busy 99 % of the time, the other 55 %. So workgroup row j renders tile row (j · stride) mod rows, with a
//! stride near rows / φ and coprime to rows: a bijection (every tile row once), and any run of consecutive
//! workgroup rows — one thread's share, whatever the thread count — is spread over the whole image (a Kronecker
//! sequence: its gaps take at most three sizes). A GPU schedules workgroups dynamically and does not care.

/// The stride for a dispatch of `rows` workgroup rows (≥ 1; 1 for 0 or 1 rows): coprime to `rows`, near
/// `rows / φ`. Row j of the dispatch renders tile row `(j · stride) mod rows` (shaders/integrator.wgsl).
pub fn tile_row_stride(rows: u32) -> u32 {
    if rows <= 2 {
        return 1;
    }
    let target = (rows as f64 * 0.618_033_988_749_895).round() as u32;
    // The nearest coprime value at or around the target (1 always is).
    (0..rows)
        .flat_map(|d| [target.saturating_sub(d), target + d])
        .find(|&s| s >= 1 && s < rows && gcd(s, rows) == 1)
        .unwrap_or(1)
}

fn gcd(mut a: u32, mut b: u32) -> u32 {
    while b != 0 {
        (a, b) = (b, a % b);
    }
    a
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_tile_row_is_rendered_once() {
        for rows in 0..=2000u32 {
            let s = tile_row_stride(rows);
            let mut seen = vec![false; rows as usize];
            for j in 0..rows {
                // The shader's arithmetic is u32: (j · s) must not overflow for any row count a device allows.
                let t = (j as u64 * s as u64 % rows as u64) as usize;
                assert!(!seen[t], "rows {rows}, stride {s}: tile row {t} twice");
                seen[t] = true;
            }
        }
        assert!(16384u64 / 8 * 16384 / 8 < u32::MAX as u64);
    }

    #[test]
    fn each_thread_share_spans_the_image() {
        // For 2, 3, 4 and 16 threads taking equal runs of workgroup rows, each run's tile rows reach into every
        // quarter of the image (for images of at least 8 tile rows per run).
        for rows in [32u32, 45, 64, 90, 135, 270] {
            let s = tile_row_stride(rows);
            for threads in [2u32, 3, 4, 16] {
                let per = rows / threads;
                if per < 8 {
                    continue;
                }
                for k in 0..threads {
                    let mut quarters = [0; 4];
                    for j in k * per..(k + 1) * per {
                        quarters[(4 * (j * s % rows) / rows) as usize] += 1;
                    }
                    assert!(quarters.iter().all(|&q| q > 0), "rows {rows}, {threads} threads, run {k}: {quarters:?}");
                }
            }
        }
    }
}
