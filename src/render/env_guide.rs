//! The environment guide (`--env-sampling guided`, the default): where a constant environment is visible from,
//! learned from the render's first sample, for the light technique's sky samples.
//!
//! Inside a room a constant sky is seen through the windows only: most cosine-distributed shadow rays towards it
//! are blocked, and that is most of the interiors' error (docs/estimators.md, "Environment guide"). Sample 0 of
//! the learner tiles (its *learning pass*, rendered with the cosine alone; one 8×8 tile in [`learner_period`])
//! counts, per *slot* — a cell of a grid over the
//! scene × the dominant axis of the receiver's normal — its shadow rays towards the sky, those that reached it,
//! and the direction bins in which they and the paths' continuations reached it. Each slot's counts, pooled with
//! its neighbours', become a CDF over [`BINS`] equal-area direction bins and a probability alpha of using it; the
//! light technique then samples `alpha · guide + (1 − alpha) · cosine` (shaders/env_guide.wgsl; `env_sample` in lights.wgsl), so
//! every direction the integrand needs keeps a density and the estimate stays unbiased whatever the guide learned.
//! The other pixels' sample 0 follows with the guide ([`COMPLETE`]). The guide is a function of the scene, camera, settings and seed only (integer counts of sample 0), so renders
//! stay repeatable, and resumed or split ones learn the same guide (`Renderer::ensure_guide`).

use glam::{UVec3, Vec2, Vec3};

use crate::render::scene_data::SceneData;

/// `FrameParams::guide_train` of the learning pass: its samples also accumulate (a render's sample 0).
pub const LEARN: u32 = 1;
/// `FrameParams::guide_train` of a learning pass that only counts (sample 0 again, for a render resumed past it).
pub const LEARN_ONLY: u32 = 2;
/// `FrameParams::guide_train` of the rest of sample 0 after a learning pass: the pixels outside the learner tiles,
/// rendered with the guide just learned.
pub const COMPLETE: u32 = 3;

/// Fewest learning paths (pixels of learner tiles) a film of at least this many pixels keeps (`learner_period`).
pub const MIN_LEARNING_PATHS: u64 = 1 << 14;

/// One 8×8 tile in this many learns the guide (1, 2 or 4) for a film of `pixels`: as few as keep at least
/// [`MIN_LEARNING_PATHS`] learning paths, and at least one in four (one in eight learned too little for the living
/// room at 640×360: relMSE at 4 spp 3.5e-2 → 3.8e-2). The learning pass samples by the cosine alone, and its samples are the
/// learner pixels' sample 0, about twice as noisy as a guided sample inside a room (staircase2: relMSE per sample
/// 0.54 against 0.28); the other pixels' sample 0 is rendered after the guide is learned, with it.
pub fn learner_period(pixels: u64) -> u32 {
    match pixels / MIN_LEARNING_PATHS {
        0 | 1 => 1,
        2 | 3 => 2,
        _ => 4,
    }
}

/// Whether the 8×8 tile `(tx, ty)` learns the guide, one in `period` (shaders/env_guide.wgsl
/// `env_guide_learner_tile`): the tiles on every `period`-th diagonal, (tx + ty) mod period = 0 — one in `period`
/// in every row and every column of tiles, so that the learners spread evenly over the image and over every run of
/// tile rows a thread renders.
pub fn learner_tile(tx: u32, ty: u32, period: u32) -> bool {
    (tx + ty).is_multiple_of(period.max(1))
}

/// Bands of w.y in a slot's direction bins.
pub const Z_BINS: usize = 8;
/// Sectors of φ = atan2(w.z, w.x) in a slot's direction bins.
pub const PHI_BINS: usize = 16;
/// Direction bins per slot (equal solid angle, 4π / BINS each).
pub const BINS: usize = Z_BINS * PHI_BINS;
/// Normal classes per cell: ±x, ±y, ±z by the normal's largest component.
pub const NORMAL_CLASSES: usize = 6;
/// Most cells along the grid's longest axis (the others in proportion, at least one).
pub const MAX_CELLS_LONGEST_AXIS: u32 = 16;
/// Film pixels (learning-pass paths) per cell of a cube of cells: the grid is as fine as the learning pass can fill
/// (16 cells along the longest axis from 640×360 on, measured best on the living room; 3 at 48×48).
pub const PIXELS_PER_CUBE_CELL: f64 = 56.0;

/// Cells along the grid's longest axis for a film of `pixels`.
pub fn cells_longest_axis(pixels: u64) -> u32 {
    ((pixels as f64 / PIXELS_PER_CUBE_CELL).cbrt().round() as u32).clamp(1, MAX_CELLS_LONGEST_AXIS)
}
/// The largest probability of drawing a sky sample from the guide rather than the cosine.
pub const ALPHA_MAX: f32 = 0.9;
/// Where at most this fraction of a slot's cosine-sampled shadow rays reached the sky, it draws from the guide with
/// probability [`ALPHA_MAX`]...
pub const SKY_SEEN_GUIDED: f32 = 0.1;
/// ... and where at least this fraction did, never: the cosine alone (with a low-discrepancy sampler it is hard to
/// beat where the sky is mostly visible; measured, docs/estimators.md "Environment guide").
pub const SKY_SEEN_COSINE: f32 = 0.3;

/// A slot's probability of drawing from the guide, given the fraction v of its cosine-sampled shadow rays that
/// reached the sky: [`ALPHA_MAX`] up to [`SKY_SEEN_GUIDED`], falling linearly to 0 at [`SKY_SEEN_COSINE`].
pub fn guide_share(v: f32) -> f32 {
    ALPHA_MAX * ((SKY_SEEN_COSINE - v) / (SKY_SEEN_COSINE - SKY_SEEN_GUIDED)).clamp(0.0, 1.0)
}
/// Cells within this many cells of a slot's own lend it their counts (`cdfs`).
pub const POOL_RADIUS: u32 = 1;
/// Fewest counts for a slot to get a guide (fewer: the cosine alone).
pub const MIN_COUNTS: u64 = 8;

/// The grid of cells over the scene's bounds (render-origin space, as the shader's points).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct GuideGrid {
    /// Lower corner.
    pub min: Vec3,
    /// 1 / cell size per axis.
    pub inv_cell: Vec3,
    /// Cells per axis.
    pub dims: UVec3,
}

impl GuideGrid {
    /// Cells of one size (cubes, as near as whole counts allow) over the box `lo..hi`, `cells` along its longest
    /// side.
    pub fn over(lo: Vec3, hi: Vec3, cells: u32) -> GuideGrid {
        let ext = (hi - lo).max(Vec3::splat(1e-6));
        let cell = ext.max_element() / cells as f32;
        let dims = (ext / cell).ceil().as_uvec3().clamp(UVec3::ONE, UVec3::splat(cells));
        GuideGrid { min: lo, inv_cell: dims.as_vec3() / ext, dims }
    }

    /// The grid over a scene's geometry (triangles, spheres and quads) for a film of `pixels`.
    pub fn of_scene(d: &SceneData, pixels: u64) -> GuideGrid {
        let cells = cells_longest_axis(pixels);
        let mut lo = Vec3::splat(f32::MAX);
        let mut hi = Vec3::splat(f32::MIN);
        let mut add = |p: Vec3| {
            lo = lo.min(p);
            hi = hi.max(p);
        };
        for v in d.tri_verts.iter().chain(d.tri_verts_hi.iter().flatten()) {
            add(Vec3::new(v[0], v[1], v[2]));
        }
        for s in &d.spheres {
            add(Vec3::from(s.center) - s.radius);
            add(Vec3::from(s.center) + s.radius);
        }
        for q in &d.quads {
            let (c, u, v) = (Vec3::from(q.corner), Vec3::from(q.edge_u), Vec3::from(q.edge_v));
            for p in [c, c + u, c + v, c + u + v] {
                add(p);
            }
        }
        if lo.x > hi.x {
            return GuideGrid::over(Vec3::ZERO, Vec3::ONE, cells);
        }
        GuideGrid::over(lo, hi, cells)
    }

    /// Slots: cells × normal classes.
    pub fn slots(&self) -> usize {
        (self.dims.x * self.dims.y * self.dims.z) as usize * NORMAL_CLASSES
    }

    /// The slot of a receiver at p (clamped into the grid) with normal n: the CPU twin of `env_guide_slot`.
    pub fn slot(&self, p: Vec3, n: Vec3) -> usize {
        let c = ((p - self.min) * self.inv_cell).floor().max(Vec3::ZERO).as_uvec3().min(self.dims - 1);
        let a = n.abs();
        let axis = if a.x >= a.y && a.x >= a.z {
            0
        } else if a.y >= a.z {
            1
        } else {
            2
        };
        let class = 2 * axis + usize::from(n[axis] < 0.0);
        ((c.z * self.dims.y + c.y) * self.dims.x + c.x) as usize * NORMAL_CLASSES + class
    }
}

/// The direction bin of w: the CPU twin of `env_guide_bin`.
pub fn bin(w: Vec3) -> usize {
    let iz = (((w.y + 1.0) * 0.5 * Z_BINS as f32).max(0.0) as usize).min(Z_BINS - 1);
    let phi = w.z.atan2(w.x) / std::f32::consts::TAU + 0.5;
    let ip = ((phi * PHI_BINS as f32).max(0.0) as usize).min(PHI_BINS - 1);
    iz * PHI_BINS + ip
}

/// The direction at (u, v) ∈ [0, 1)² inside bin b (uniform in solid angle): the CPU twin of the end of
/// `env_guide_sample`.
pub fn bin_direction(b: usize, uv: Vec2) -> Vec3 {
    let (iz, ip) = (b / PHI_BINS, b % PHI_BINS);
    let z = (-1.0 + 2.0 * (iz as f32 + uv.x) / Z_BINS as f32).clamp(-1.0, 1.0);
    let phi = std::f32::consts::TAU * ((ip as f32 + uv.y) / PHI_BINS as f32 - 0.5);
    let r = (1.0 - z * z).max(0.0).sqrt();
    Vec3::new(r * phi.cos(), z, r * phi.sin())
}

/// Words of the learning pass's counts: per slot its [`BINS`] bin counts, then per slot two tallies (shadow rays
/// towards the sky, and those that reached it).
pub fn counts_words(slots: usize) -> usize {
    slots * BINS + 2 * slots
}

/// Sums `per`-word records over the cells within `radius` of each cell along one axis (a box filter, separable:
/// three passes make the cube), for every normal class. `stride`: cells between neighbours along the axis.
fn pool_axis(v: &[u64], per: usize, dims: UVec3, axis: usize, radius: u32) -> Vec<u64> {
    let n = dims[axis] as i64;
    let stride = match axis {
        0 => 1,
        1 => dims.x as usize,
        _ => (dims.x * dims.y) as usize,
    };
    let cells = (dims.x * dims.y * dims.z) as usize;
    let rec = NORMAL_CLASSES * per;
    let mut out = vec![0u64; v.len()];
    for cell in 0..cells {
        let i = ((cell / stride) as i64) % n;
        for d in -(radius as i64)..=radius as i64 {
            let j = i + d;
            if j < 0 || j >= n {
                continue;
            }
            let other = (cell as i64 + d * stride as i64) as usize;
            let (dst, src) = (&mut out[cell * rec..(cell + 1) * rec], &v[other * rec..(other + 1) * rec]);
            for (a, b) in dst.iter_mut().zip(src) {
                *a += b;
            }
        }
    }
    out
}

/// Sums each slot's `per`-word records over the cells within `radius` cells of its own (a box), class by class.
fn pool(v: &[u64], per: usize, grid: &GuideGrid, radius: u32) -> Vec<u64> {
    (0..3).fold(v.to_vec(), |acc, axis| pool_axis(&acc, per, grid.dims, axis, radius))
}

/// The guide from the learning pass's counts (`counts_words` of them): per slot, the normalised CDF over its bins
/// of the bin counts of its normal class in the cells within `radius` cells of its own (a box: the sky's
/// directions change slowly across a room, and one cell's counts are few), with its last entry (always 1) replaced
/// by the slot's probability of drawing from the guide, [`guide_share`] of the fraction of its pooled shadow rays
/// that reached the sky: the guide pays where the sky is seen through small openings. A slot whose pooled counts
/// are fewer than [`MIN_COUNTS`], or whose share is 0, stays all zero: the cosine alone.
pub fn cdfs(counts: &[u32], grid: &GuideGrid, radius: u32) -> Vec<f32> {
    let slots = grid.slots();
    assert_eq!(counts.len(), counts_words(slots), "the learning pass's counts");
    let wide = |w: &[u32]| w.iter().map(|&k| k as u64).collect::<Vec<u64>>();
    let bins = pool(&wide(&counts[..slots * BINS]), BINS, grid, radius);
    let tallies = pool(&wide(&counts[slots * BINS..]), 2, grid, radius);
    let mut out = vec![0f32; slots * BINS];
    for (slot, (b, o)) in bins.chunks_exact(BINS).zip(out.chunks_exact_mut(BINS)).enumerate() {
        let total: u64 = b.iter().sum();
        let (rays, reached) = (tallies[2 * slot], tallies[2 * slot + 1]);
        if total < MIN_COUNTS || rays == 0 {
            continue;
        }
        let alpha = guide_share((reached as f64 / rays as f64) as f32);
        if alpha == 0.0 {
            continue;
        }
        let mut run = 0u64;
        for (k, c) in b.iter().zip(o.iter_mut()) {
            run += k;
            *c = (run as f64 / total as f64) as f32;
        }
        o[BINS - 1] = alpha;
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    /// One tile in `period` learns, in every row of tiles and every column (so in every thread's run of rows, and
    /// on films of one tile column as on wide ones), and films keep at least MIN_LEARNING_PATHS learners.
    #[test]
    fn learner_tiles_are_one_in_period_in_every_row_and_column() {
        for period in [1, 2, 4] {
            for t in 0..64 {
                let in_row = (0..period).filter(|&tx| learner_tile(tx + 8 * t, t, period)).count();
                let in_column = (0..period).filter(|&ty| learner_tile(t, ty + 4 * t, period)).count();
                assert_eq!((in_row, in_column), (1, 1), "period {period}, tile row/column {t}");
            }
        }
        for (w, h, period) in
            [(64, 64, 1), (128, 128, 1), (200, 200, 2), (320, 180, 2), (256, 256, 4), (640, 360, 4), (4096, 4096, 4)]
        {
            let pixels = w as u64 * h as u64;
            assert_eq!(learner_period(pixels), period, "{w}×{h}");
            assert!(pixels / period as u64 >= MIN_LEARNING_PATHS.min(pixels), "{w}×{h}");
        }
    }

    /// Every bin's directions fall in that bin (`bin` inverts `bin_direction`), and the bins are equal in solid
    /// angle: uniform directions land in each bin 1/BINS of the time.
    #[test]
    fn bins_invert_their_directions_and_share_the_sphere_equally() {
        for b in 0..BINS {
            for uv in [Vec2::new(0.5, 0.5), Vec2::new(0.01, 0.99), Vec2::new(0.99, 0.02)] {
                let w = bin_direction(b, uv);
                assert!((w.length() - 1.0).abs() < 1e-5, "bin {b} {uv}: |w| = {}", w.length());
                assert_eq!(bin(w), b, "bin {b} at {uv}: {w}");
            }
        }
        let mut hits = vec![0u32; BINS];
        let n = 256u32;
        for i in 0..n {
            for j in 0..n {
                // A stratified grid of uniform sphere directions (z uniform in [−1, 1], φ uniform).
                let z = -1.0 + 2.0 * (i as f32 + 0.5) / n as f32;
                let phi = std::f32::consts::TAU * (j as f32 + 0.5) / n as f32;
                let r = (1.0 - z * z).sqrt();
                hits[bin(Vec3::new(r * phi.cos(), z, r * phi.sin()))] += 1;
            }
        }
        let each = (n * n) as usize / BINS;
        assert!(hits.iter().all(|&h| h as usize == each), "bins are not equal-area: {hits:?}");
    }

    #[test]
    fn slots_follow_the_cell_and_the_normals_dominant_axis() {
        let g = GuideGrid::over(Vec3::ZERO, Vec3::new(8.0, 2.0, 4.0), 16);
        assert_eq!(g.dims, UVec3::new(16, 4, 8));
        assert_eq!(g.slots(), 16 * 4 * 8 * NORMAL_CLASSES);
        assert_eq!(g.slot(Vec3::new(0.1, 0.1, 0.1), Vec3::X), 0);
        assert_eq!(g.slot(Vec3::new(0.1, 0.1, 0.1), Vec3::NEG_Y), 3);
        assert_eq!(g.slot(Vec3::new(0.6, 0.1, 0.1), Vec3::new(0.1, 0.2, -0.9)), NORMAL_CLASSES + 5);
        // Points outside are clamped into the edge cells.
        assert_eq!(g.slot(Vec3::new(-5.0, 9.0, 99.0), Vec3::Z), g.slot(Vec3::new(0.0, 1.99, 3.99), Vec3::Z));
    }

    #[test]
    fn the_grid_is_as_fine_as_the_learning_pass_can_fill() {
        assert_eq!(cells_longest_axis(640 * 360), 16);
        assert_eq!(cells_longest_axis(1920 * 1080), MAX_CELLS_LONGEST_AXIS);
        assert_eq!(cells_longest_axis(48 * 48), 3);
        assert_eq!(cells_longest_axis(1), 1);
    }

    #[test]
    fn the_guides_share_falls_from_its_most_to_none_as_more_of_the_sky_is_seen() {
        assert_eq!(guide_share(0.0), ALPHA_MAX);
        assert_eq!(guide_share(SKY_SEEN_GUIDED), ALPHA_MAX);
        assert!((guide_share(0.2) - 0.5 * ALPHA_MAX).abs() < 1e-6);
        assert_eq!(guide_share(SKY_SEEN_COSINE), 0.0);
        assert_eq!(guide_share(1.0), 0.0);
    }

    /// The pooled CDFs against a direct sum over each slot's neighbourhood: normalised, the learned share in place
    /// of the last entry, zero where too little was counted or the sky was mostly seen.
    #[test]
    fn cdfs_pool_the_neighbouring_cells_counts() {
        let g = GuideGrid::over(Vec3::ZERO, Vec3::new(3.0, 1.0, 2.0), 6);
        let slots = g.slots();
        let mut counts = vec![0u32; counts_words(slots)];
        let mut rng = 12345u64;
        let mut next = || {
            rng = rng.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
            (rng >> 33) as u32
        };
        for slot in 0..slots {
            if next() % 3 == 0 {
                continue;
            }
            let rays = 20 + next() % 200;
            let reached = next() % (rays / 2);
            counts[slots * BINS + 2 * slot] = rays;
            counts[slots * BINS + 2 * slot + 1] = reached;
            for _ in 0..reached {
                counts[slot * BINS + (next() as usize % 40)] += 1;
            }
        }
        let out = cdfs(&counts, &g, 1);
        let d = g.dims.as_ivec3();
        let mut guided = 0;
        for z in 0..d.z {
            for y in 0..d.y {
                for x in 0..d.x {
                    for class in 0..NORMAL_CLASSES {
                        let (mut bins, mut rays, mut reached) = (vec![0u64; BINS], 0u64, 0u64);
                        for (xx, yy, zz) in (x - 1..=x + 1)
                            .flat_map(|a| (y - 1..=y + 1).flat_map(move |b| (z - 1..=z + 1).map(move |c| (a, b, c))))
                        {
                            if xx < 0 || yy < 0 || zz < 0 || xx >= d.x || yy >= d.y || zz >= d.z {
                                continue;
                            }
                            let s = ((zz * d.y + yy) * d.x + xx) as usize * NORMAL_CLASSES + class;
                            for (acc, &k) in bins.iter_mut().zip(&counts[s * BINS..(s + 1) * BINS]) {
                                *acc += k as u64;
                            }
                            rays += counts[slots * BINS + 2 * s] as u64;
                            reached += counts[slots * BINS + 2 * s + 1] as u64;
                        }
                        let slot = ((z * d.y + y) * d.x + x) as usize * NORMAL_CLASSES + class;
                        let o = &out[slot * BINS..(slot + 1) * BINS];
                        let total: u64 = bins.iter().sum();
                        let share = if rays > 0 { guide_share(reached as f32 / rays as f32) } else { 0.0 };
                        if total < MIN_COUNTS || share == 0.0 {
                            assert!(o.iter().all(|&c| c == 0.0), "slot {slot} should keep the cosine");
                            continue;
                        }
                        guided += 1;
                        assert!((o[BINS - 1] - share).abs() < 1e-6, "slot {slot}: share {} vs {share}", o[BINS - 1]);
                        let mut run = 0u64;
                        for b in 0..BINS - 1 {
                            run += bins[b];
                            let want = run as f64 / total as f64;
                            assert!((o[b] as f64 - want).abs() < 1e-6, "slot {slot} bin {b}: {} vs {want}", o[b]);
                        }
                    }
                }
            }
        }
        assert!(guided > 10, "the test exercised only {guided} guided slots");
    }
}
