// light_tree_loads.wgsl — how the light tree's walks read a node: four 16-byte loads, the portable form. On a
// device with 64-bit integers light_tree_loads_int64.wgsl takes this file's place (src/render/shaders.rs
// `for_device`).

/// Light-tree node i.
fn light_node(i: u32) -> LightNode {
    return load_light_tree(i);
}
