// scene_data.wgsl — how shading code reads the scene: one accessor per table. This file reads the storage
// buffers; for scenes small enough to bake (Features::flat) src/render/baked.rs generates a replacement with the same
// functions returning literals, (its `baked_geometry.wgsl` replacement has every intersection test unrolled). lavapipe runs a
// storage-buffer read as a loop over the SIMD lanes (each lane's bounds check and load in turn), so in the
// bounce loop one read costs about as much as a hundred arithmetic operations; a literal costs nothing and a
// short select chain little.

/// A triangle's three positions.
struct TriPositions {
    v0: vec3<f32>,
    v1: vec3<f32>,
    v2: vec3<f32>,
}

fn scene_tri_positions(i: u32) -> TriPositions {
    return TriPositions(tri_verts[3u * i].xyz, tri_verts[3u * i + 1u].xyz, tri_verts[3u * i + 2u].xyz);
}
fn scene_tri_record(i: u32) -> TriShading { return tri_shading[i]; }
fn scene_shading_vertex(i: u32) -> ShadingVertex { return shading_verts[i]; }
fn scene_sphere(i: u32) -> Sphere { return spheres[i]; }
fn scene_quad(i: u32) -> Quad { return quads[i]; }
fn scene_material(i: u32) -> Material { return materials[i]; }
fn scene_light(i: u32) -> Light { return lights[i]; }
