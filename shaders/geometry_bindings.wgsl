// geometry_bindings.wgsl — the scene's geometry as storage buffers (group 0, bindings 0–4).

@group(0) @binding(0) var<storage, read> bvh_nodes: array<BvhNode>;
@group(0) @binding(1) var<storage, read> prim_refs: array<u32>;
@group(0) @binding(2) var<storage, read> tri_verts: array<vec4<f32>>;
@group(0) @binding(3) var<storage, read> spheres: array<Sphere>;
@group(0) @binding(4) var<storage, read> quads: array<Quad>;
