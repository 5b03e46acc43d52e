// warps.wgsl — maps u ∈ [0,1)² to directions or points, each with its pdf (pbrt's SampleX / XPDF, Mitsuba's
// square_to_X / square_to_X_pdf). Directions are in a local frame with z along the normal unless stated.

/// An orthonormal basis around unit `n` (Duff et al. 2017, "Building an Orthonormal Basis, Revisited").
struct Frame {
    t: vec3<f32>,
    b: vec3<f32>,
    n: vec3<f32>,
}

fn frame_from_normal(n: vec3<f32>) -> Frame {
    let s = select(-1.0, 1.0, n.z >= 0.0);
    let a = -1.0 / (s + n.z);
    let b = n.x * n.y * a;
    return Frame(vec3<f32>(1.0 + s * n.x * n.x * a, s * b, -s * n.x), vec3<f32>(b, s + n.y * n.y * a, -n.y), n);
}

fn to_local(f: Frame, v: vec3<f32>) -> vec3<f32> { return vec3<f32>(dot(v, f.t), dot(v, f.b), dot(v, f.n)); }
fn to_world(f: Frame, v: vec3<f32>) -> vec3<f32> { return f.t * v.x + f.b * v.y + f.n * v.z; }

/// Uniform on the unit disk, concentric map (Shirley & Chiu 1997). Measure: area, pdf 1/π.
fn square_to_uniform_disk_concentric(u: vec2<f32>) -> vec2<f32> {
    let o = 2.0 * u - 1.0;
    if (o.x == 0.0 && o.y == 0.0) { return vec2<f32>(0.0); }
    var r: f32;
    var theta: f32;
    if (abs(o.x) > abs(o.y)) {
        r = o.x;
        theta = (PI / 4.0) * (o.y / o.x);
    } else {
        r = o.y;
        theta = (PI / 2.0) - (PI / 4.0) * (o.x / o.y);
    }
    return r * vec2<f32>(cos(theta), sin(theta));
}

/// Uniform on the upper hemisphere (z ≥ 0). Measure: solid angle, pdf 1/2π.
fn square_to_uniform_hemisphere(u: vec2<f32>) -> vec3<f32> {
    let z = u.x;
    let r = safe_sqrt(1.0 - z * z);
    let phi = TWO_PI * u.y;
    return vec3<f32>(r * cos(phi), r * sin(phi), z);
}
fn square_to_uniform_hemisphere_pdf(w: vec3<f32>) -> f32 { return select(0.0, INV_TWO_PI, w.z > 0.0); }

/// Cosine-weighted upper hemisphere (Malley's method). Measure: solid angle, pdf cosθ/π.
fn square_to_cosine_hemisphere(u: vec2<f32>) -> vec3<f32> {
    let d = square_to_uniform_disk_concentric(u);
    let z = safe_sqrt(1.0 - dot(d, d));
    return vec3<f32>(d.x, d.y, z);
}
fn square_to_cosine_hemisphere_pdf(w: vec3<f32>) -> f32 { return max(w.z, 0.0) * INV_PI; }

/// Uniform on the whole sphere. Measure: solid angle, pdf 1/4π.
fn square_to_uniform_sphere(u: vec2<f32>) -> vec3<f32> {
    let z = 1.0 - 2.0 * u.x;
    let r = safe_sqrt(1.0 - z * z);
    let phi = TWO_PI * u.y;
    return vec3<f32>(r * cos(phi), r * sin(phi), z);
}
fn square_to_uniform_sphere_pdf() -> f32 { return INV_FOUR_PI; }

/// Uniform in the cone around +z with 1 − cosθmax = `one_minus_cos_max` (passed directly so tiny cones
/// keep their precision: cosθ near 1 has only ~2⁻²⁴ resolution). Measure: solid angle,
/// pdf 1 / (2π (1 − cosθmax)).
fn square_to_uniform_cone(u: vec2<f32>, one_minus_cos_max: f32) -> vec3<f32> {
    let omc = u.x * one_minus_cos_max;             // 1 − cosθ, uniform in [0, 1 − cosθmax]
    let sin_theta = safe_sqrt(omc * (2.0 - omc));
    let phi = TWO_PI * u.y;
    return vec3<f32>(sin_theta * cos(phi), sin_theta * sin(phi), 1.0 - omc);
}
fn square_to_uniform_cone_pdf(one_minus_cos_max: f32) -> f32 { return 1.0 / (TWO_PI * one_minus_cos_max); }

/// Uniform barycentrics on a triangle (b1, b2), Heitz 2019 "A Low-Distortion Map Between Triangle and Square".
/// Measure: area, pdf 1/A.
fn square_to_uniform_triangle(u: vec2<f32>) -> vec2<f32> {
    var b0: f32;
    var b1: f32;
    if (u.x < u.y) {
        b0 = u.x / 2.0;
        b1 = u.y - b0;
    } else {
        b1 = u.y / 2.0;
        b0 = u.x - b1;
    }
    return vec2<f32>(b1, 1.0 - b0 - b1);
}
