// surface.wgsl — from a hit to a shading point: position, normals, uv, material with textures applied.

/// A triangle's shading attributes, decoded from its `TriShading` and three `ShadingVertex` entries (CPU twin:
/// src/render/shading_data.rs `decode`). A normal is unit, or zero where the vertex has none.
struct TriAttributes {
    n0: vec3<f32>,
    n1: vec3<f32>,
    n2: vec3<f32>,
    uv0: vec2<f32>,
    uv1: vec2<f32>,
    uv2: vec2<f32>,
    material: u32,
    light: u32,
    alpha_texture: u32,    // cut-out mask: 0 none, k + 1 texture k's alpha channel (alpha.wgsl)
}

fn scene_tri_shading(i: u32) -> TriAttributes {
    return tri_attributes(scene_tri_record(i));
}

fn tri_attributes(t: TriShading) -> TriAttributes {
    let a = scene_shading_vertex(t.corners.x);
    let b = scene_shading_vertex(t.corners.y);
    let c = scene_shading_vertex(t.corners.z);
    return TriAttributes(oct_decode(a.normal), oct_decode(b.normal), oct_decode(c.normal), a.uv, b.uv, c.uv,
        a.material & 0xffffu, t.light, a.material >> 16u);
}

/// A shading point. `ng`/`ns` are flipped to the side the ray came from; `front` says whether the ray
/// hit the front (emitting) face; `light` is the emitter's index in the light table or INVALID.
struct Surface {
    p: vec3<f32>,
    ng: vec3<f32>,
    ns: vec3<f32>,
    uv: vec2<f32>,
    material: u32,
    light: u32,
    front: bool,
}

/// Hit position, geometric normal (unflipped, the emitting side) etc. for any primitive kind.
fn surface_at(hit: Hit, o: vec3<f32>, d: vec3<f32>) -> Surface {
    var s: Surface;
    let kind = prim_kind(hit.prim);
    let i = prim_index(hit.prim);
    var ng: vec3<f32>;
    var ns: vec3<f32>;
    if (HAS_TRIANGLES && kind == PRIM_TRIANGLE) {
        let tp = scene_tri_positions(i);
        let v0 = tp.v0;
        let v1 = tp.v1;
        let v2 = tp.v2;
        let b0 = 1.0 - hit.b1 - hit.b2;
        // Barycentric interpolation keeps the point on the triangle's plane (o + t·d drifts off it).
        s.p = b0 * v0 + hit.b1 * v1 + hit.b2 * v2;
        ng = normalize(cross(v1 - v0, v2 - v0));
        let sh = tri_attributes(TriShading(tp.corners, scene_tri_light(i)));
        ns = b0 * sh.n0 + hit.b1 * sh.n1 + hit.b2 * sh.n2;
        s.uv = b0 * sh.uv0 + hit.b1 * sh.uv1 + hit.b2 * sh.uv2;
        s.material = sh.material;
        s.light = sh.light;
    } else if (HAS_SPHERES && kind == PRIM_SPHERE) {
        let sp = scene_sphere(i);
        let q = o + hit.t * d;
        ng = normalize(q - sp.center);
        s.p = sp.center + sp.radius * ng;   // re-projected onto the sphere
        ns = ng;
        s.uv = vec2<f32>(atan2(ng.z, ng.x) * INV_TWO_PI + 0.5, acos(clamp(ng.y, -1.0, 1.0)) * INV_PI);
        s.material = sp.material;
        s.light = sp.light;
    } else if (HAS_QUADS) {
        let q = scene_quad(i);
        s.p = q.corner + hit.b1 * q.edge_u + hit.b2 * q.edge_v;
        ng = normalize(cross(q.edge_u, q.edge_v));
        ns = ng;
        s.uv = vec2<f32>(hit.b1, hit.b2);
        s.material = q.material;
        s.light = q.light;
    }
    // A degenerate or non-finite interpolated normal falls back to the geometric one.
    let ns_len2 = dot(ns, ns);
    if (!(ns_len2 > 1e-12) || is_nonfinite(ns_len2)) { ns = ng; } else { ns = ns * inverseSqrt(ns_len2); }
    s.front = dot(d, ng) < 0.0;
    let flip = select(-1.0, 1.0, s.front);
    s.ng = ng * flip;
    s.ns = ns * flip;
    // A shading normal the ray grazes exactly gives no frame to shade in: the geometric one does. One that faces
    // away from the viewer is kept; shading_ctx decides with the BSDF.
    if (!(dot(s.ns, -d) != 0.0)) { s.ns = s.ng; }
    return s;
}

fn srgb_to_linear(c: f32) -> f32 {
    if (c <= 0.04045) { return c / 12.92; }
    return pow((c + 0.055) / 1.055, 2.4);
}

fn wrap_coord(x: i32, n: i32, mode: u32) -> i32 {
    if (mode == WRAP_CLAMP) { return clamp(x, 0, n - 1); }
    if (mode == WRAP_MIRROR) {
        let period = 2 * n;
        var m = x % period;
        if (m < 0) { m += period; }
        return select(m, period - 1 - m, m >= n);
    }
    var m = x % n;
    if (m < 0) { m += n; }
    return m;
}

/// Word `i` of the texture at `offset` (TEXEL_HI: in the second texel binding).
fn texel_word(offset: u32, i: u32) -> u32 {
    if (HAS_TEXEL_SPLIT && (offset & TEXEL_HI) != 0u) { return load_tex_texels_hi((offset & ~TEXEL_HI) + i); }
    return load_tex_texels(offset + i);
}

fn texel(info: TextureInfo, x: i32, y: i32) -> vec4<f32> {
    let xi = wrap_coord(x, i32(info.width), info.wrap_s);
    let yi = wrap_coord(y, i32(info.height), info.wrap_t);
    var c = unpack4x8unorm(texel_word(info.offset, u32(yi) * info.width + u32(xi)));
    if (info.srgb != 0u) {
        c = vec4<f32>(srgb_to_linear(c.x), srgb_to_linear(c.y), srgb_to_linear(c.z), c.w);
    }
    return c;
}

/// pbrt-v4's 2D checkerboard at (s, t), unfiltered: tex1 where ⌊s⌋ + ⌊t⌋ is even, tex2 where odd (the CPU twin
/// is scene::checkerboard). The colours are six f32 words at info.offset. Point sampling: the pixel's jittered
/// samples average the checks over its footprint, where pbrt filters them by ray differentials.
fn checkerboard_lookup(info: TextureInfo, st: vec2<f32>) -> vec4<f32> {
    // Clamped so the i32 conversion cannot overflow (±2^24 keeps the parity of exactly representable floors).
    let f = vec2<i32>(floor(clamp(st, vec2<f32>(-16777216.0), vec2<f32>(16777216.0))));
    let o = select(0u, 3u, ((f.x + f.y) & 1) != 0);
    let w = vec3<u32>(texel_word(info.offset, o), texel_word(info.offset, o + 1u), texel_word(info.offset, o + 2u));
    return vec4<f32>(bitcast<vec3<f32>>(w), 1.0);
}

/// Bilinear (or nearest) lookup with the texture's wrap modes, after the 2×3 uv transform; or a procedural
/// texture at the transformed uv.
fn texture_lookup(tex: u32, xf0: vec4<f32>, xf1: vec4<f32>, uv_in: vec2<f32>) -> vec4<f32> {
    let info = load_tex_info(tex);
    let uv = vec2<f32>(dot(xf0.xyz, vec3<f32>(uv_in, 1.0)), dot(xf1.xyz, vec3<f32>(uv_in, 1.0)));
    if (is_nonfinite(uv.x) || is_nonfinite(uv.y)) { return vec4<f32>(0.0); }
    if (HAS_CHECKERBOARD && info.tex_kind == TEX_CHECKERBOARD) { return checkerboard_lookup(info, uv); }
    let st = uv * vec2<f32>(f32(info.width), f32(info.height)) - 0.5;
    // Keep coordinates in i32 range before the wrap (huge uvs would overflow).
    let stc = clamp(st, vec2<f32>(-1e8), vec2<f32>(1e8));
    if (info.nearest != 0u) {
        return texel(info, i32(floor(stc.x + 0.5)), i32(floor(stc.y + 0.5)));
    }
    let f = floor(stc);
    let w = stc - f;
    let x = i32(f.x);
    let y = i32(f.y);
    let a = mix(texel(info, x, y), texel(info, x + 1, y), w.x);
    let b = mix(texel(info, x, y + 1), texel(info, x + 1, y + 1), w.x);
    return mix(a, b, w.y);
}

/// The material's BSDF parameters at `uv`, seen from the front or not: its words and the values of its textures (its
/// kind's `<kind>_params` decides what they multiply).
fn material_bsdf(m: Material, uv: vec2<f32>, front: bool) -> BsdfParams {
    var p = BsdfParams(m.bsdf_kind, m.params0, m.params1, m.params2, vec3<f32>(1.0), false, vec4<f32>(1.0), front);
    if (HAS_TEXTURES && m.base_tex != INVALID) {
        p.tex_base = texture_lookup(m.base_tex, m.base_xform0, m.base_xform1, uv).xyz;
    }
    if (HAS_TEXTURES && m.mr_tex != INVALID) {
        p.has_tex_mr = true;
        p.tex_mr = texture_lookup(m.mr_tex, m.mr_xform0, m.mr_xform1, uv);
    }
    return p;
}

/// Emitted radiance of the material at `uv` (front face only; callers check `front`).
fn material_emission(m: Material, uv: vec2<f32>) -> vec3<f32> {
    var e = m.emission;
    if (HAS_TEXTURES && m.emissive_tex != INVALID) {
        e *= texture_lookup(m.emissive_tex, m.em_xform0, m.em_xform1, uv).xyz;
    }
    return e;
}
