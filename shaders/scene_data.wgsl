// scene_data.wgsl — how shading code reads the scene: one accessor per table. This file reads the storage
// buffers; for scenes small enough to bake (Features::flat) src/render/baked.rs generates a replacement with the same
// functions returning literals, (its `baked_geometry.wgsl` replacement has every intersection test unrolled). lavapipe runs a
// storage-buffer read as a loop over the SIMD lanes (each lane's bounds check and load in turn), so in the
// bounce loop one read costs about as much as a hundred arithmetic operations; a literal costs nothing and a
// short select chain little.

/// A triangle's three positions and its corners' shading-vertex indices (the w of each vertex: one set of loads
/// gives both; `tri_verts` is read as u32 words, see bvh.wgsl `triangle_words`).
struct TriPositions {
    v0: vec3<f32>,
    v1: vec3<f32>,
    v2: vec3<f32>,
    corners: vec3<u32>,
}

fn scene_tri_positions(i: u32) -> TriPositions {
    let w = triangle_words(i);
    return TriPositions(bitcast<vec3<f32>>(w.a.xyz), bitcast<vec3<f32>>(w.b.xyz), bitcast<vec3<f32>>(w.c.xyz), vec3<u32>(w.a.w, w.b.w, w.c.w));
}
/// Corner k's shading-vertex index alone (one load).
fn scene_tri_corner(i: u32, k: u32) -> u32 { return tri_vertex_words(3u * i + k).w; }
/// The triangle's light, or INVALID. Where no triangle emits, `tri_lights` is a few INVALID words
/// (src/render/scene_data.rs `NO_TRI_LIGHTS`), and the clamped index reads one of them.
fn scene_tri_light(i: u32) -> u32 {
    return load_tri_lights(min(i, len_tri_lights() - 1u));
}
fn scene_tri_record(i: u32) -> TriShading { return TriShading(scene_tri_positions(i).corners, scene_tri_light(i)); }
/// The shading vertex whose records start at `r` (a corner's w): (normal, material) and, in a scene with textures
/// (HAS_TEXTURES), the uv's bits in the next record. Without textures no uv is stored and nothing reads one.
fn scene_shading_vertex(r: u32) -> ShadingVertex {
    let a = load_shading_verts(r);
    var uv = vec2<f32>(0.0);
    if HAS_TEXTURES {
        uv = bitcast<vec2<f32>>(load_shading_verts(r + 1u));
    }
    return ShadingVertex(a.x, a.y, uv);
}
fn scene_sphere(i: u32) -> Sphere { return load_spheres(i); }
fn scene_quad(i: u32) -> Quad { return load_quads(i); }
fn scene_material(i: u32) -> Material { return load_materials(i); }
fn scene_light(i: u32) -> Light { return load_lights(i); }
/// The triangles outside the BVH as (first slot, count): what the generic pipeline's `baked_traverse` loops over.
fn occluder_range() -> vec2<u32> { return vec2<u32>(params.occluder_first, params.occluder_count); }
