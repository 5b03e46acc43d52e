// env_guide.wgsl — the environment guide (src/render/env_guide.rs): where a constant environment is visible from,
// learned from the render's first sample; `env_sample` and `env_pdf` (lights.wgsl) draw from it and weigh by it.
//
// Inside a room a constant sky is seen through the windows only, so most cosine-distributed shadow rays are
// blocked. The render's first sample (a learning pass, guide_train > 0) counts, per slot — a cell of a grid over
// the scene and the dominant axis of the receiver's normal — its cosine-sampled shadow rays, those that reached
// the sky, and the directions (GUIDE_BINS equal-area bins) in which they and its paths' continuations reached it;
// the host turns the counts into one CDF per slot and a probability alpha. `--env-sampling guided` then draws from
// alpha·guide + (1 − alpha)·cosine: the cosine share keeps every direction the integrand can use reachable, so
// the estimate stays unbiased whatever the guide learned.

// The constants below are src/render/env_guide.rs's (tests/layout.rs checks them).
/// guide_train: a learning pass that also accumulates its samples (a render's sample 0).
const GUIDE_LEARN: u32 = 1u;
/// guide_train: a learning pass that only counts (sample 0 again, for a render resumed past it).
const GUIDE_LEARN_ONLY: u32 = 2u;
/// guide_train: the rest of sample 0 after a learning pass (the pixels outside the learner tiles), guided.
const GUIDE_COMPLETE: u32 = 3u;

/// Whether the 8×8 tile (tx, ty) learns the guide: every guide_learner_period-th diagonal (src/render/env_guide.rs
/// `learner_tile`, which tests/estimators.rs checks against this).
fn env_guide_learner_tile(tx: u32, ty: u32) -> bool {
    return (tx + ty) % max(params.guide_learner_period, 1u) == 0u;
}

/// Whether this dispatch leaves pixel px alone: a learning pass renders the learner tiles' pixels only, the
/// pass completing sample 0 after it the others only.
fn env_guide_skips(px: vec2<u32>) -> bool {
    let t = params.guide_train;
    if (t == 0u) { return false; }
    let learner = env_guide_learner_tile(px.x / 8u, px.y / 8u);
    return select(!learner, learner, t == GUIDE_COMPLETE);
}

const GUIDE_Z_BINS: u32 = 8u;
const GUIDE_PHI_BINS: u32 = 16u;
const GUIDE_BINS: u32 = 128u;
/// The solid angle of one bin (4π / GUIDE_BINS: bins are equal in z = w.y and in φ).
const GUIDE_BIN_SOLID_ANGLE: f32 = 0.09817477;

/// The guide's slot for a receiver at p (clamped into the grid) with normal n.
fn env_guide_slot(p: vec3<f32>, n: vec3<f32>) -> u32 {
    let dims = params.guide_dims;
    let c = min(vec3<u32>(max(floor((p - params.guide_min) * params.guide_inv_cell), vec3<f32>(0.0))), dims - 1u);
    let a = abs(n);
    var axis = 2u;
    if (a.x >= a.y && a.x >= a.z) { axis = 0u; } else if (a.y >= a.z) { axis = 1u; }
    let side = 2u * axis + select(0u, 1u, n[axis] < 0.0);
    return ((c.z * dims.y + c.y) * dims.x + c.x) * 6u + side;
}

/// The equal-area bin of direction w: 8 bands of w.y, 16 sectors of φ = atan2(w.z, w.x).
fn env_guide_bin(w: vec3<f32>) -> u32 {
    let iz = min(u32(max((w.y + 1.0) * 0.5 * f32(GUIDE_Z_BINS), 0.0)), GUIDE_Z_BINS - 1u);
    let phi = atan2(w.z, w.x) * INV_TWO_PI + 0.5;
    let ip = min(u32(max(phi * f32(GUIDE_PHI_BINS), 0.0)), GUIDE_PHI_BINS - 1u);
    return iz * GUIDE_PHI_BINS + ip;
}

/// The probability of drawing from the guide rather than the cosine in `slot`, which the host stores in place of
/// the CDF's last entry (always 1): higher where the sky was seen by fewer of the learning pass's shadow rays, 0
/// where the slot has no guide (too few counts, or the sky seen almost everywhere, where the cosine is best).
fn env_guide_alpha(slot: u32) -> f32 {
    return guide_cdf[slot * GUIDE_BINS + GUIDE_BINS - 1u];
}

/// The guide at a receiver: its slot and the slot's guide probability alpha (`env_guide_alpha`), read once.
struct GuideAt {
    slot: u32,
    alpha: f32,
}

/// The guide at a receiver at p with normal n; slot INVALID (alpha 0) where the cosine alone is used (not guided,
/// no guide learned yet, no normal, or a slot without counts).
fn env_guide_at(p: vec3<f32>, n: vec3<f32>) -> GuideAt {
    let none = GuideAt(INVALID, 0.0);
    if (cfg_env_sampling() != ENV_SAMPLING_GUIDED || params.guide_on == 0u || !env_cosine(n)) { return none; }
    let slot = env_guide_slot(p, n);
    let alpha = env_guide_alpha(slot);
    if (!(alpha > 0.0)) { return none; }
    return GuideAt(slot, alpha);
}

/// The guide's density (solid angle) of direction bin b in `slot` (the last bin's CDF entry is 1).
fn env_guide_pdf(slot: u32, b: u32) -> f32 {
    let base = slot * GUIDE_BINS;
    let lo = select(0.0, guide_cdf[base + max(b, 1u) - 1u], b > 0u);
    let hi = select(guide_cdf[base + b], 1.0, b == GUIDE_BINS - 1u);
    return (hi - lo) * (1.0 / GUIDE_BIN_SOLID_ANGLE);
}

/// The guided mixture's density of w (cosine density `cosine` about the receiver's normal) in `slot`, its bin b,
/// with the slot's guide probability alpha.
fn env_guided_pdf(slot: u32, alpha: f32, b: u32, cosine: f32) -> f32 {
    return alpha * env_guide_pdf(slot, b) + (1.0 - alpha) * cosine;
}

/// The bin of `slot` whose CDF interval holds u0 (binary search; it never reads the last entry, which holds alpha).
fn env_guide_pick(slot: u32, u0: f32) -> u32 {
    let base = slot * GUIDE_BINS;
    var lo = 0u;
    var hi = GUIDE_BINS - 1u;
    while (lo < hi) {
        let mid = (lo + hi) / 2u;
        if (guide_cdf[base + mid] > u0) { hi = mid; } else { lo = mid + 1u; }
    }
    return lo;
}

/// The direction at uv inside direction bin b (uniform in z and φ is uniform in solid angle).
fn env_guide_bin_direction(b: u32, uv: vec2<f32>) -> vec3<f32> {
    let iz = b / GUIDE_PHI_BINS;
    let ip = b % GUIDE_PHI_BINS;
    let z = clamp(-1.0 + 2.0 * (f32(iz) + uv.x) / f32(GUIDE_Z_BINS), -1.0, 1.0);
    let phi = TWO_PI * ((f32(ip) + uv.y) / f32(GUIDE_PHI_BINS) - 0.5);
    let r = safe_sqrt(1.0 - z * z);
    return vec3<f32>(r * cos(phi), z, r * sin(phi));
}

/// Whether this pass learns the guide at a receiver with normal n (`env_receiver`).
fn env_guide_learning(n: vec3<f32>) -> bool {
    let learning = params.guide_train == GUIDE_LEARN || params.guide_train == GUIDE_LEARN_ONLY;
    return cfg_env_sampling() == ENV_SAMPLING_GUIDED && learning && env_cosine(n);
}

/// Learning: a cosine-sampled shadow ray towards the sky from a receiver at p with normal n along w, `visible` or
/// not. The slot counts its shadow rays and those that reached the sky (their ratio sets its alpha), and the bin
/// of each that did: such a ray's weight L·cos/pdf is the same (π·L) for all, so a count per ray estimates ∫ V·cos
/// over the bin. The slot's counts follow its GUIDE_BINS bin counts (src/render/env_guide.rs `counts_words`).
fn env_guide_learn_shadow_ray(p: vec3<f32>, n: vec3<f32>, w: vec3<f32>, visible: bool) {
    if (!env_guide_learning(n)) { return; }
    let slot = env_guide_slot(p, n);
    let tallies = params.guide_slots * GUIDE_BINS + 2u * slot;
    atomicAdd(&guide_counts[tallies], 1u);
    if (visible) {
        atomicAdd(&guide_counts[tallies + 1u], 1u);
        atomicAdd(&guide_counts[slot * GUIDE_BINS + env_guide_bin(w)], 1u);
    }
}

/// Learning: a path's continuation from a receiver at p with normal n that reached the sky along w counts in its
/// bin too (its weight is the shadow ray's for a Lambert surface; for others an approximation, which only the
/// guide's quality depends on).
fn env_guide_learn_escape(p: vec3<f32>, n: vec3<f32>, w: vec3<f32>) {
    if (!env_guide_learning(n)) { return; }
    atomicAdd(&guide_counts[env_guide_slot(p, n) * GUIDE_BINS + env_guide_bin(w)], 1u);
}
