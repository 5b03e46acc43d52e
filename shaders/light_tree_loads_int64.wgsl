// light_tree_loads_int64.wgsl — light_tree_loads.wgsl for a device with 64-bit integers: `light_tree` bound as
// array<vec4<u64>>, a 64-byte node in two 32-byte loads instead of four (see geometry_loads_int64.wgsl, whose
// `u64_words` this uses).

/// Light-tree node i.
fn light_node(i: u32) -> LightNode {
    let a = light_tree[2u * i];
    let b = light_tree[2u * i + 1u];
    return LightNode(u64_words(a.xy), u64_words(a.zw), u64_words(b.xy), u64_words(b.zw));
}
