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

/// Uniform on the upper hemisphere (z > 0). Measure: solid angle, pdf 1/2π. z = 1 − u.x ∈ (0, 1], so no sample
/// lies on the horizon, where the pdf below is 0.
fn square_to_uniform_hemisphere(u: vec2<f32>) -> vec3<f32> {
    let z = 1.0 - u.x;
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

// ---- accurate arctangent ----

/// atan2(y, x) to ~2 ulp. The driver's atan/atan2 may be far less accurate (Vulkan allows 4096 ulp; lavapipe's is
/// off by up to 2.1e-5 relative, 2e-6 absolute — measured in tests/sampling.rs), which the solid-angle code below
/// cannot afford. Cephes' atanf: reduction to [0, 1] by the octant, to |t| ≤ tan(π/8) by (t − 1)/(t + 1), and a
/// degree-9 odd polynomial. atan2(0, 0) = 0.
fn atan2_accurate(y: f32, x: f32) -> f32 {
    let ax = abs(x);
    let ay = abs(y);
    let hi = max(ax, ay);
    if (!(hi > 0.0)) { return 0.0; }
    var t = min(ax, ay) / hi;
    var base = 0.0;
    if (t > 0.41421356) {
        t = (t - 1.0) / (t + 1.0);
        base = 0.78539816;
    }
    let z = t * t;
    var a = base + (((0.0805374449538 * z - 0.138776856032) * z + 0.199777106478) * z - 0.333329491539) * z * t + t;
    if (ay > ax) { a = 1.57079633 - a; }
    if (x < 0.0) { a = PI - a; }
    return select(a, -a, y < 0.0);
}

// ---- spherical polygons (solid-angle sampling of triangle and rectangle lights) ----
//
// Both warps take the polygon's vertices RELATIVE TO THE SHADING POINT (unnormalised) and are written so that
// small and distant polygons keep their precision in f32: every quantity that shrinks with the polygon's
// angular size s is computed from edge vectors or by half-angle identities rather than as a difference of O(1)
// numbers, so relative errors grow like ε/s (ε = 2⁻²⁴) instead of ε/s². No compensated arithmetic (lavapipe
// reassociates it away). Where f32 still breaks down — measured in tests/sampling.rs, documented in
// docs/sampling.md — lights.wgsl falls back to area sampling.

/// Solid angle of the triangle with vertices a, b, c (relative to the viewpoint), Van Oosterom & Strackee 1983:
/// tan(Ω/2) = |â·(b̂×ĉ)| / (1 + â·b̂ + b̂·ĉ + ĉ·â). The triple product is a·((b − a)×(c − a)) / (|a||b||c|), from the
/// edges, so it keeps full relative precision for small triangles; the denominator is regrouped around the most
/// nearly opposite pair (x̂, ŷ) as |x̂ + ŷ|²/2 + ẑ·(x̂ + ŷ), which keeps it when the viewpoint is near an edge in the
/// triangle's plane (1 + x̂·ŷ alone would have no digits left). Range [0, 2π).
fn spherical_triangle_solid_angle(a: vec3<f32>, b: vec3<f32>, c: vec3<f32>) -> f32 {
    let la = length(a);
    let lb = length(b);
    let lc = length(c);
    let det = dot(a, cross(b - a, c - a)) / (la * lb * lc);
    let an = a / la;
    let bn = b / lb;
    let cn = c / lc;
    let sab = an + bn;
    let sbc = bn + cn;
    let sca = cn + an;
    var den = 0.5 * dot(sab, sab) + dot(cn, sab);
    if (dot(sbc, sbc) < dot(sab, sab) && dot(sbc, sbc) <= dot(sca, sca)) {
        den = 0.5 * dot(sbc, sbc) + dot(an, sbc);
    } else if (dot(sca, sca) < dot(sab, sab)) {
        den = 0.5 * dot(sca, sca) + dot(bn, sca);
    }
    return 2.0 * atan2_accurate(abs(det), den);
}

/// Uniform over the spherical triangle (a, b, c) seen from the origin (vertices relative to the viewpoint).
/// Measure: solid angle, pdf 1/Ω (`square_to_spherical_triangle_pdf`). Arvo 1995, "Stratified Sampling of
/// Spherical Triangles": u.x picks the sub-triangle (â, b̂, ĉ′) of area u.x·Ω with ĉ′ on the arc â→ĉ, u.y a
/// point on the arc b̂→ĉ′ uniform in cosθ. Step 1 is solved in closed form with the Van Oosterom–Strackee
/// formula instead of Arvo's spherical trigonometry: for ĉ′ = cosφ·â + sinφ·ŵ (ŵ ⊥ â in the plane of â, ĉ),
///   tan(Ω′/2)·[(1 + â·b̂)(1 + cosφ) + sinφ (b̂·ŵ)] = sinφ |[â, b̂, ŵ]|
/// ⇒ φ/2 = atan2((1 + â·b̂)·sin(Ω′/2), |[â, b̂, ŵ]|·cos(Ω′/2) − (b̂·ŵ)·sin(Ω′/2)),
/// which has no cancellation for small triangles (Arvo's and pbrt-v4's forms lose digits there). Step 2 works
/// from ĉ′ − b̂ or from ĉ′ + b̂, whichever is shorter, so arcs that end nearly opposite b̂ (viewpoints near the
/// triangle's plane) keep their precision too.
fn square_to_spherical_triangle(u: vec2<f32>, va: vec3<f32>, vb: vec3<f32>, vc: vec3<f32>) -> vec3<f32> {
    return spherical_triangle_warp(u, va, vb, vc, spherical_triangle_solid_angle(va, vb, vc));
}
fn square_to_spherical_triangle_pdf(a: vec3<f32>, b: vec3<f32>, c: vec3<f32>) -> f32 {
    return 1.0 / spherical_triangle_solid_angle(a, b, c);
}

/// `square_to_spherical_triangle` for a caller that already has Ω = `spherical_triangle_solid_angle(va, vb, vc)`.
fn spherical_triangle_warp(u: vec2<f32>, va: vec3<f32>, vb: vec3<f32>, vc: vec3<f32>, omega: f32) -> vec3<f32> {
    // Any labelling samples the same density. Take as the base a–c (the arc ĉ′ runs along) the shortest side:
    // a base of nearly 180° (a viewpoint near a vertex or an edge, close to the triangle's plane) would put ĉ′
    // where it moves fastest with φ.
    let cab = dot(va, vb) / (length(va) * length(vb));
    let cbc = dot(vb, vc) / (length(vb) * length(vc));
    let cca = dot(vc, va) / (length(vc) * length(va));
    var a = va;
    var b = vb;
    var c = vc;
    if (cab > cca && cab >= cbc) {
        b = vc;
        c = vb;
    } else if (cbc > cca) {
        a = vb;
        b = va;
    }
    let la = length(a);
    let lb = length(b);
    let e1 = b - a;
    let e2 = c - a;
    let an = a / la;
    let bn = b / lb;
    // ŵ ⊥ â towards ĉ: (a × c) × a with a × c = a × e2 (exact for nearby vertices).
    let w = normalize(cross(cross(a, e2), a));
    let d = abs(dot(cross(a, e1), w)) / (la * lb);     // |[â, b̂, ŵ]|
    let e = dot(e1, w) / lb;                          // b̂·ŵ (a·ŵ = 0)
    let k = 0.5 * dot(an + bn, an + bn);             // 1 + â·b̂, exact also for nearly opposite â, b̂
    let half = 0.5 * u.x * omega;
    let sh = sin(half);
    let half_phi = atan2_accurate(k * sh, d * cos(half) - e * sh);
    let s_half = sin(half_phi);
    // ĉ′ ∓ b̂ = (â ∓ b̂) + (cosφ − 1)·â + sinφ·ŵ, with cosφ − 1 = −2 sin²(φ/2).
    let rest = sin(2.0 * half_phi) * w - (2.0 * s_half * s_half) * an;
    let dm = (an - bn) + rest;                        // ĉ′ − b̂
    let dp = (an + bn) + rest;                        // ĉ′ + b̂
    // Step 2: 1 − cosθ uniform in [0, 1 − b̂·ĉ′], with 1 − b̂·ĉ′ = |ĉ′ − b̂|²/2 and 1 + b̂·ĉ′ = |ĉ′ + b̂|²/2.
    let omc = u.y * 0.5 * dot(dm, dm);
    let opc = 2.0 * (1.0 - u.y) + u.y * 0.5 * dot(dp, dp);     // 1 + cosθ = 2 − (1 − cosθ)
    let sin_theta = sqrt(max(omc * opc, 0.0));
    // The tangent at b̂ towards ĉ′: the part of ĉ′ ∓ b̂ perpendicular to b̂, from the shorter one.
    let dd = select(dm, dp, dot(dp, dp) < dot(dm, dm));
    let perp = normalize(dd - dot(dd, bn) * bn);
    return normalize((1.0 - omc) * bn + sin_theta * perp);
}

/// A rectangle prepared for solid-angle sampling, in its local frame: the viewpoint at the origin, the rectangle
/// [x0, x1] × [y0, y1] in the plane z = −h (h > 0). Sampling picks the coordinate along axis "a" first, then along
/// "b": (a, b) = (x, y), or (y, x) when `swap` (see `spherical_rect_setup`). With βi the elevation of the edge b = bi:
/// `cos_pair` holds what cos((Σ ± ψ)/2) (Σ = β0 + β1) needs, `beta_diff` = β1 − β0, `psi0`/`psi1` = ψ(a0), ψ(a1);
/// `omega` = Ω.
struct SphericalRect {
    x0: f32,
    y0: f32,
    a0: f32,
    a1: f32,
    b0: f32,
    b1: f32,
    h: f32,
    /// Σ = β0 + β1 when b0 < 0 < b1 (cos((Σ ± ψ)/2) directly); else Γ = atan(h/|b0|) + atan(h/|b1|), the
    /// complement of |Σ| (cos((Σ ± ψ)/2) = sin((Γ ∓ ψ)/2), no cancellation when h ≪ |bi|).
    cos_pair: f32,
    straddles: bool,
    beta_diff: f32,
    psi0: f32,
    psi1: f32,
    swap: bool,
    omega: f32,
}

/// ψ(A): the signed solid angle of the strip [0, A] × [b0, b1] at depth h,
/// atan(A·b1/(h·R1)) − atan(A·b0/(h·R0)) with Ri = |(A, bi, h)|, as one atan2 whose b1·R0 − b0·R1 is rationalised
/// when b0, b1 have the same sign (it cancels for small rectangles otherwise).
fn spherical_rect_psi(a: f32, b0: f32, b1: f32, h: f32) -> f32 {
    let r0 = sqrt(a * a + b0 * b0 + h * h);
    let r1 = sqrt(a * a + b1 * b1 + h * h);
    var m = b1 * r0 - b0 * r1;
    if (b0 * b1 > 0.0) { m = (a * a + h * h) * (b1 - b0) * (b1 + b0) / (b1 * r0 + b0 * r1); }
    return atan2_accurate(a * h * m, h * h * r0 * r1 + a * a * b0 * b1);
}

/// Prepares the rectangle [x0, x0 + w] × [y0, y0 + hgt] at depth h > 0 (the caller checks the side). The first
/// axis is the one whose range reaches less far from the foot of the perpendicular (x = y = 0): along an axis that
/// reaches far (≫ h; a rectangle seen edge-on from beside it, or the long side of a sliver seen from close by),
/// ψ(a0) and ψ(a1) approach the strip's limits ±Δ, where the inversion below has no digits left.
fn spherical_rect_setup(x0: f32, y0: f32, w: f32, hgt: f32, h: f32) -> SphericalRect {
    var r: SphericalRect;
    r.x0 = x0;
    r.y0 = y0;
    r.h = h;
    r.swap = max(abs(x0), abs(x0 + w)) > max(abs(y0), abs(y0 + hgt));
    var la = w;
    var lb = hgt;
    r.a0 = x0;
    r.b0 = y0;
    if (r.swap) {
        la = hgt;
        lb = w;
        r.a0 = y0;
        r.b0 = x0;
    }
    r.a1 = r.a0 + la;
    r.b1 = r.b0 + lb;
    r.straddles = r.b0 < 0.0 && r.b1 > 0.0;
    // Straddling: atan(b0/h) + atan(b1/h); else atan(h/|b0|) + atan(h/|b1|). One pair of atan2 calls with the
    // arguments selected (on lavapipe both sides of an if run).
    let s = r.straddles;
    r.cos_pair = atan2_accurate(select(h, r.b0, s), select(abs(r.b0), h, s))
        + atan2_accurate(select(h, r.b1, s), select(abs(r.b1), h, s));
    // β1 − β0: the angle between (b0, h) and (b1, h), from the edge length (no cancellation).
    r.beta_diff = atan2_accurate(h * lb, h * h + r.b0 * r.b1);
    r.psi0 = spherical_rect_psi(r.a0, r.b0, r.b1, h);
    r.psi1 = spherical_rect_psi(r.a1, r.b0, r.b1, h);
    // Ω: two spherical triangles (their triple products are exact in these coordinates).
    let v00 = vec3<f32>(x0, y0, -h);
    let v10 = vec3<f32>(x0 + w, y0, -h);
    let v11 = vec3<f32>(x0 + w, y0 + hgt, -h);
    let v01 = vec3<f32>(x0, y0 + hgt, -h);
    r.omega = spherical_triangle_solid_angle(v00, v10, v11) + spherical_triangle_solid_angle(v00, v11, v01);
    return r;
}

/// Uniform over the spherical rectangle `r` (from `spherical_rect_setup`), returned as the local point
/// (x, y) on the rectangle (the direction is normalize((x, y, −h))). Measure: solid angle, pdf 1/Ω.
/// Ureña, Fajardo & King 2013, "An Area-Preserving Parametrization for Spherical Rectangles": u.x picks the
/// sub-rectangle [a0, a] of solid angle u.x·Ω, u.y a point on the segment at a uniform in b/|(a, b, h)|.
/// Reformulated for f32: the paper's angle sum minus π at the edge a is ψ(a) (`spherical_rect_psi`), so
/// ψ = lerp(ψ(a0), ψ(a1), u.x) and, solving the paper's eqs. for a with half-angle identities,
///   a = h·sinψ / (2·sqrt(cos((Σ+ψ)/2)·cos((Σ−ψ)/2)·sin((Δ−ψ)/2)·sin((Δ+ψ)/2))),  Σ = β0 + β1, Δ = β1 − β0,
/// a product without cancellation; in step 2, 1 ∓ hv are interpolated from 1 ∓ hi computed without cancellation,
/// so grazing rectangles (hv → ±1) keep their precision.
fn square_to_spherical_rectangle(u: vec2<f32>, r: SphericalRect) -> vec2<f32> {
    let psi = mix(r.psi0, r.psi1, u.x);
    var cc: f32;
    if (r.straddles) {
        cc = cos(0.5 * (r.cos_pair + psi)) * cos(0.5 * (r.cos_pair - psi));
    } else {
        cc = sin(0.5 * (r.cos_pair + psi)) * sin(0.5 * (r.cos_pair - psi));
    }
    let q = cc * sin(0.5 * (r.beta_diff - psi)) * sin(0.5 * (r.beta_diff + psi));
    let a = clamp(r.h * sin(psi) / (2.0 * sqrt(max(q, 0.0))), r.a0, r.a1);
    let dd2 = a * a + r.h * r.h;
    let r0 = sqrt(dd2 + r.b0 * r.b0);
    let r1 = sqrt(dd2 + r.b1 * r.b1);
    let inv_r0 = 1.0 / r0;
    let inv_r1 = 1.0 / r1;
    // 1 ∓ hi = (ri ∓ bi)/ri without cancellation: ri + |bi| directly, ri − |bi| = dd²/(ri + |bi|).
    let far0 = r0 + abs(r.b0);
    let far1 = r1 + abs(r.b1);
    let near0 = dd2 / far0;
    let near1 = dd2 / far1;
    let om0 = select(far0, near0, r.b0 > 0.0) * inv_r0;
    let om1 = select(far1, near1, r.b1 > 0.0) * inv_r1;
    let op0 = select(far0, near0, r.b0 < 0.0) * inv_r0;
    let op1 = select(far1, near1, r.b1 < 0.0) * inv_r1;
    let hv = mix(r.b0 * inv_r0, r.b1 * inv_r1, u.y);
    let one_minus_hv2 = mix(om0, om1, u.y) * mix(op0, op1, u.y);
    let b = clamp(hv * sqrt(dd2 / one_minus_hv2), r.b0, r.b1);
    return select(vec2<f32>(a, b), vec2<f32>(b, a), r.swap);
}
fn square_to_spherical_rectangle_pdf(r: SphericalRect) -> f32 { return 1.0 / r.omega; }
