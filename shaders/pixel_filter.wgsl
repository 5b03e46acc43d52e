// pixel_filter.wgsl — the pixel filter as pbrt-v4 defines it (box, triangle, gaussian; separable): where around its
// pixel a camera sample goes and what it weighs. A pixel's value is ∫ f(x) L(x) dx / ∫ f; samples are drawn from
// the filter (filter importance sampling, as pbrt-v4), so the pixel's plain mean of weight × radiance estimates it.
// Box and triangle are sampled exactly (weight 1). The gaussian g(x) = G(x) − G(r) has no closed-form inverse: it is
// drawn from a logistic of scale min(0.6σ, 0.3r) truncated to [−r, r] and weighted g / (∫g · p): weights within
// [0, 1.33] and E[w²] ≤ 1.034 per axis for every r/σ (src/render/pixel_filter.rs computes ∫g and checks these).

const FILTER_BOX: u32 = 0u;
const FILTER_TRIANGLE: u32 = 1u;
const FILTER_GAUSSIAN: u32 = 2u;

struct FilterSample {
    jitter: vec2<f32>, // position in pixel units from the pixel's corner (0.5, 0.5 is its centre)
    weight: f32,
}

/// t in [−1, 1] with density 1 − |t|, by inverting its CDF.
fn filter_tent(u: f32) -> f32 {
    return select(sqrt(2.0 * u) - 1.0, 1.0 - sqrt(2.0 - 2.0 * u), u >= 0.5);
}

/// One axis of the gaussian: (offset in (−r, r), weight g(x) / (∫g · p(x))).
fn filter_gaussian_axis(u: f32) -> vec2<f32> {
    let r = params.filter_radius;
    let sigma = params.filter_sigma;
    let s = min(0.6 * sigma, 0.3 * r); // the logistic's scale nearest the gaussian's shape (pixel_filter.rs)
    let lo = 1.0 / (1.0 + exp(r / s)); // the logistic's CDF at −r; at r it is 1 − lo
    let mass = 1.0 - 2.0 * lo;
    let v = lo + u * mass;
    let x = clamp(s * log(v / (1.0 - v)), -r, r);
    let e = exp(-abs(x) / s);
    let pdf = e / (s * (1.0 + e) * (1.0 + e) * mass);
    let g = max(0.0, exp(-x * x / (2.0 * sigma * sigma)) - exp(-r * r / (2.0 * sigma * sigma)));
    return vec2<f32>(x, select(0.0, g * params.filter_norm / pdf, pdf > 0.0));
}

/// The camera sample of the unit-square point u for the pixel filter of the settings.
fn filter_sample(u: vec2<f32>) -> FilterSample {
    let r = params.filter_radius;
    switch cfg_filter() {
        case FILTER_TRIANGLE: {
            return FilterSample(vec2<f32>(0.5) + r * vec2<f32>(filter_tent(u.x), filter_tent(u.y)), 1.0);
        }
        case FILTER_GAUSSIAN: {
            let gx = filter_gaussian_axis(u.x);
            let gy = filter_gaussian_axis(u.y);
            return FilterSample(vec2<f32>(0.5 + gx.x, 0.5 + gy.x), gx.y * gy.y);
        }
        default: {
            // u · 2r + (0.5 − r): exactly u for the pixel-sized box (r = 0.5), the renders before filters existed.
            return FilterSample(u * (2.0 * r) + (0.5 - r), 1.0);
        }
    }
}
