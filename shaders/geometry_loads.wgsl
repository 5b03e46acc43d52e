// geometry_loads.wgsl — how traversal reads the first vertex binding and the wide BVH's nodes: 16 bytes a load
// (vec4<u32>), the portable form. On a device with 64-bit integers geometry_loads_int64.wgsl takes this file's
// place and both bindings are read 32 bytes a load (src/render/shaders.rs `for_device`). Needs bvh.wgsl
// (TriWords) and bvh_wide.wgsl (WideNode).

/// Vertex k of `tri_verts` as words (position bits, corner record index).
fn tri_verts_words(k: u32) -> vec4<u32> {
    return load_tri_verts(k);
}

/// How many vertices `tri_verts` holds (where the split path's further bindings begin).
fn tri_verts_len() -> u32 {
    return len_tri_verts();
}

/// Triangle i's vertices, all three in `tri_verts`: three loads.
fn tri_words(i: u32) -> TriWords {
    return TriWords(load_tri_verts(3u * i), load_tri_verts(3u * i + 1u), load_tri_verts(3u * i + 2u));
}

/// Wide BVH node i: five loads.
fn wide_node(i: u32) -> WideNode {
    return load_wide_nodes(i);
}

/// How many wide nodes the binding holds.
fn wide_node_count() -> u32 {
    return len_wide_nodes();
}
