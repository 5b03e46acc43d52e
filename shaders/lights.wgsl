// lights.wgsl — light techniques: sample_li / pdf_li for area lights (triangle, quad, sphere), delta lights
// (point, spot, directional) and the environment, plus light selection. All pdfs are per unit solid angle
// at the shading point and do NOT include the selection probability (see `light_pmf`).

/// A sampled direction towards a light: unit wi, distance to the light point (F32_MAX for distant
/// lights), the radiance arriving along wi (for delta lights: intensity/d² or irradiance), the pdf in
/// solid angle (0 = no sample), and whether the technique is a delta distribution.
struct LightSample {
    wi: vec3<f32>,
    dist: f32,
    radiance: vec3<f32>,
    pdf: f32,
    delta: bool,
}

fn no_light_sample() -> LightSample {
    return LightSample(vec3<f32>(0.0, 0.0, 1.0), 0.0, vec3<f32>(0.0), 0.0, false);
}

/// Probability of choosing light `i` under the active selection scheme.
fn light_pmf(i: u32) -> f32 {
    let l = lights[i];
    return select(l.pmf_uniform, l.pmf_power, cfg_light_select() == LIGHT_SELECT_POWER);
}

/// Samples an index from an alias table of `n` entries starting at `base` with one number u.
fn alias_sample(base: u32, n: u32, u: f32, table_is_env: bool) -> u32 {
    let x = u * f32(n);
    let i = min(u32(x), n - 1u);
    let r = x - f32(i);
    var e: AliasEntry;
    if (table_is_env) { e = env_alias[base + i]; } else { e = light_alias[base + i]; }
    return select(e.alias_index, i, r < e.prob);
}

/// Chooses one light with probability `light_pmf`.
fn select_light(u: f32) -> u32 {
    if (!MANY_LIGHTS) { return 0u; }
    let n = params.num_lights;
    if (cfg_light_select() == LIGHT_SELECT_POWER) { return alias_sample(0u, n, u, false); }
    return min(u32(u * f32(n)), n - 1u);
}

// ---- area lights: uniform by area, converted to solid angle by distance² / cos ----

/// Area-to-solid-angle conversion for a sampled light point y with normal n_y, seen from p.
/// One-sided: a point seen from behind has pdf 0 (it emits nothing towards p).
fn area_to_solid_angle(p: vec3<f32>, y: vec3<f32>, n_y: vec3<f32>, pdf_area: f32, emitted: vec3<f32>) -> LightSample {
    let v = y - p;
    let d2 = dot(v, v);
    let dist = sqrt(d2);
    let wi = v / dist;
    let cos_l = dot(-wi, n_y);
    if (!(cos_l > 0.0) || !(d2 > 0.0)) { return no_light_sample(); }
    return LightSample(wi, dist, emitted, pdf_area * d2 / cos_l, false);
}

/// Triangle light, uniform by area (barycentrics by Heitz's low-distortion map). Measure: area → solid angle.
fn triangle_sample_li(prim: u32, p: vec3<f32>, u: vec2<f32>) -> LightSample {
    let v0 = tri_verts[3u * prim].xyz;
    let v1 = tri_verts[3u * prim + 1u].xyz;
    let v2 = tri_verts[3u * prim + 2u].xyz;
    let c = cross(v1 - v0, v2 - v0);
    let area2 = length(c);
    if (!(area2 > 0.0)) { return no_light_sample(); }
    let b = square_to_uniform_triangle(u);
    let y = (1.0 - b.x - b.y) * v0 + b.x * v1 + b.y * v2;
    let sh = tri_shading[prim];
    let uv = (1.0 - b.x - b.y) * sh.uv0 + b.x * sh.uv1 + b.y * sh.uv2;
    let emitted = material_emission(materials[sh.material], uv);
    return area_to_solid_angle(p, y, c / area2, 2.0 / area2, emitted);
}

/// Quad light, uniform by area. Measure: area → solid angle.
fn quad_sample_li(prim: u32, p: vec3<f32>, u: vec2<f32>) -> LightSample {
    let q = quads[prim];
    let c = cross(q.edge_u, q.edge_v);
    let area = length(c);
    if (!(area > 0.0)) { return no_light_sample(); }
    let y = q.corner + u.x * q.edge_u + u.y * q.edge_v;
    let emitted = material_emission(materials[q.material], u);
    return area_to_solid_angle(p, y, c / area, 1.0 / area, emitted);
}

/// Sphere light, uniform by area over the whole sphere (points on the far side are occluded by the
/// sphere itself, which the shadow ray finds). Measure: area → solid angle.
fn sphere_sample_li_area(prim: u32, p: vec3<f32>, u: vec2<f32>) -> LightSample {
    let s = spheres[prim];
    let n = square_to_uniform_sphere(u);
    let y = s.center + s.radius * n;
    let uv = vec2<f32>(atan2(n.z, n.x) * INV_TWO_PI + 0.5, acos(clamp(n.y, -1.0, 1.0)) * INV_PI);
    let emitted = material_emission(materials[s.material], uv);
    return area_to_solid_angle(p, y, n, 1.0 / (4.0 * PI * s.radius * s.radius), emitted);
}

/// 1 − cosθmax of the cone a sphere subtends from p, or a negative value when p is inside (or so close
/// to the surface that the cone is numerically a hemisphere): then callers fall back to area sampling.
/// Written via sin²θmax/(1 + cosθmax) so tiny spheres keep their precision.
fn sphere_cone_one_minus_cos(s: Sphere, p: vec3<f32>) -> f32 {
    let d2 = dot(s.center - p, s.center - p);
    let r2 = s.radius * s.radius;
    if (!(d2 > r2 * 1.0001)) { return -1.0; }
    let sin2 = r2 / d2;
    return sin2 / (1.0 + sqrt(1.0 - sin2));
}

/// Sphere light, uniform in the subtended cone (solid angle). Measure: solid angle.
fn sphere_sample_li_cone(prim: u32, p: vec3<f32>, u: vec2<f32>) -> LightSample {
    let s = spheres[prim];
    let omc = sphere_cone_one_minus_cos(s, p);
    if (omc <= 0.0) { return sphere_sample_li_area(prim, p, u); }
    let to_c = s.center - p;
    let d = length(to_c);
    let f = frame_from_normal(to_c / d);
    let wl = square_to_uniform_cone(u, omc);
    let wi = normalize(to_world(f, wl));
    // Distance along wi to the near intersection: t = d·cosθ − sqrt(r² − d²·sin²θ).
    let sin2 = max(1.0 - wl.z * wl.z, 0.0);
    let cos_t = wl.z;
    let t = max(d * cos_t - safe_sqrt(s.radius * s.radius - d * d * sin2), 0.0);
    let y = p + t * wi;
    let n = normalize(y - s.center);
    let uv = vec2<f32>(atan2(n.z, n.x) * INV_TWO_PI + 0.5, acos(clamp(n.y, -1.0, 1.0)) * INV_PI);
    let emitted = material_emission(materials[s.material], uv);
    return LightSample(wi, t, emitted, square_to_uniform_cone_pdf(omc), false);
}

// ---- delta lights ----

/// Point light: irradiance-like radiance I/d², pdf 1 (delta).
fn point_sample_li(l: Light, p: vec3<f32>) -> LightSample {
    let v = l.position - p;
    let d2 = dot(v, v);
    if (!(d2 > 0.0)) { return no_light_sample(); }
    let dist = sqrt(d2);
    return LightSample(v / dist, dist, l.radiance / d2, 1.0, true);
}

/// Spot light: a point light times a smooth falloff between the outer and inner cone.
fn spot_sample_li(l: Light, p: vec3<f32>) -> LightSample {
    var s = point_sample_li(l, p);
    let c = dot(-s.wi, l.direction);
    s.radiance *= smoothstep(l.cos_outer, l.cos_inner, c);
    return s;
}

/// Directional light: light travelling along `direction`, irradiance in `radiance`.
fn directional_sample_li(l: Light) -> LightSample {
    return LightSample(-l.direction, F32_MAX, l.radiance, 1.0, true);
}

// ---- environment ----

/// Direction → equirectangular (u, v) in map space: u = 0.5 looks down −Z, v = 0 is +Y;
/// the map is rotated by `env_rotation` radians about +Y.
fn env_direction_to_uv(w: vec3<f32>) -> vec2<f32> {
    let u = atan2(w.x, -w.z) * INV_TWO_PI + 0.5 - params.env_rotation * INV_TWO_PI;
    return vec2<f32>(fract(u), acos(clamp(w.y, -1.0, 1.0)) * INV_PI);
}

fn env_uv_to_direction(uv: vec2<f32>) -> vec3<f32> {
    let phi = TWO_PI * (uv.x - 0.5) + params.env_rotation;
    let theta = PI * uv.y;
    let st = sin(theta);
    return vec3<f32>(st * sin(phi), cos(theta), -st * cos(phi));
}

fn env_texel_index(uv: vec2<f32>) -> u32 {
    let x = min(u32(uv.x * f32(params.env_width)), params.env_width - 1u);
    let y = min(u32(uv.y * f32(params.env_height)), params.env_height - 1u);
    return y * params.env_width + x;
}

/// Radiance arriving from direction w (piecewise constant over texels, matching the sampling density).
fn env_eval(w: vec3<f32>) -> vec3<f32> {
    if (ENV_KIND == 0u) { return vec3<f32>(0.0); }
    if (ENV_KIND == 1u || (ENV_KIND == 3u && params.env_width == 0u)) { return params.env_constant * params.env_scale; }
    return env_texels[env_texel_index(env_direction_to_uv(w))].xyz * params.env_scale;
}

/// pdf (solid angle) of `env_sample_li` producing w.
fn env_pdf(w: vec3<f32>) -> f32 {
    if (ENV_KIND == 0u) { return 0.0; }
    if (ENV_KIND == 1u || (ENV_KIND == 3u && params.env_width == 0u) || cfg_env_sampling() == ENV_SAMPLING_UNIFORM) { return INV_FOUR_PI; }
    let uv = env_direction_to_uv(w);
    let density_uv = env_texels[env_texel_index(uv)].w;
    let sin_theta = safe_sqrt(1.0 - w.y * w.y);
    return density_uv / (2.0 * PI * PI * max(sin_theta, 1e-7));
}

/// Environment: uniform on the sphere, or texel ∝ luminance·sinθ by the alias table then uniform in (u, v)
/// inside the texel (so pdf_ω = density_uv / (2π² sinθ)).
fn env_sample_li(u: vec3<f32>) -> LightSample {
    var wi: vec3<f32>;
    if (ENV_KIND == 1u || (ENV_KIND == 3u && params.env_width == 0u) || cfg_env_sampling() == ENV_SAMPLING_UNIFORM) {
        wi = square_to_uniform_sphere(u.xy);
    } else {
        let n = params.env_width * params.env_height;
        let t = alias_sample(0u, n, u.z, true);
        let x = t % params.env_width;
        let y = t / params.env_width;
        let uv = vec2<f32>((f32(x) + u.x) / f32(params.env_width), (f32(y) + u.y) / f32(params.env_height));
        wi = env_uv_to_direction(uv);
    }
    let pdf = env_pdf(wi);
    if (!(pdf > 0.0)) { return no_light_sample(); }
    return LightSample(wi, F32_MAX, env_eval(wi), pdf, false);
}

// ---- the light technique as a whole ----

/// Samples a point or direction on light `i` as seen from p (without the selection probability).
fn light_sample_li(i: u32, p: vec3<f32>, u: vec3<f32>) -> LightSample {
    let l = lights[i];
    switch (l.kind) {
        case LIGHT_TRIANGLE: { if (HAS_TRIANGLE_LIGHTS) { return triangle_sample_li(l.prim, p, u.xy); } }
        case LIGHT_QUAD: { if (HAS_QUAD_LIGHTS) { return quad_sample_li(l.prim, p, u.xy); } }
        case LIGHT_SPHERE: {
            if (!HAS_SPHERE_LIGHTS) { return no_light_sample(); }
            if (cfg_light_sampling() == LIGHT_SAMPLING_SOLID_ANGLE) { return sphere_sample_li_cone(l.prim, p, u.xy); }
            return sphere_sample_li_area(l.prim, p, u.xy);
        }
        case LIGHT_POINT: { if (HAS_DELTA_LIGHTS) { return point_sample_li(l, p); } }
        case LIGHT_SPOT: { if (HAS_DELTA_LIGHTS) { return spot_sample_li(l, p); } }
        case LIGHT_DIRECTIONAL: { if (HAS_DELTA_LIGHTS) { return directional_sample_li(l); } }
        case LIGHT_ENVIRONMENT: { if (ENV_KIND != 0u) { return env_sample_li(u); } }
        default: {}
    }
    return no_light_sample();
}

/// pdf (solid angle, without selection) that `light_sample_li` for light i produces the point y
/// (normal n_y, outward/front) seen from p along wi. For the environment y is unused.
fn light_pdf_li(i: u32, p: vec3<f32>, wi: vec3<f32>, y: vec3<f32>, n_y: vec3<f32>) -> f32 {
    let l = lights[i];
    if (l.kind == LIGHT_ENVIRONMENT) { return env_pdf(wi); }
    if (HAS_SPHERE_LIGHTS && l.kind == LIGHT_SPHERE && cfg_light_sampling() == LIGHT_SAMPLING_SOLID_ANGLE) {
        let omc = sphere_cone_one_minus_cos(spheres[l.prim], p);
        if (omc > 0.0) { return square_to_uniform_cone_pdf(omc); }
    }
    if (l.kind > LIGHT_QUAD) { return 0.0; }
    let v = y - p;
    let d2 = dot(v, v);
    let cos_l = abs(dot(wi, n_y));
    if (!(cos_l > 0.0)) { return 0.0; }
    return d2 / (l.area * cos_l);
}
