// baked_geometry.wgsl — traversal of what a scene has baked into the shader: all of it (Features::flat) or the
// occluders outside its BVH (BAKED_OCCLUDERS). src/render/baked.rs generates the real one per scene, every
// primitive's intersection test unrolled with its data as literals. This one stands in for modules built without
// a scene (the generic pipeline, probes): FLAT_SCENE is false there, and the occluders' triangles, if any, are
// read from their buffer slots in a loop (`occluder_range()`).

/// Closest hit among the baked primitives up to start.t, ignoring primitive `skip`.
fn baked_traverse(r: TraceRay, start: Hit, skip: u32) -> Hit {
    var hit = start;
    let range = occluder_range();
    for (var i = range.x; i < range.x + range.y; i++) {
        let h = intersect_triangle_at(r, i, hit.t); // triangle i's reference is i (PRIM_TRIANGLE = 0)
        if h.w != 0.0 && i != skip {
            hit = Hit(h.x, i, h.y, h.z);
        }
    }
    return hit;
}

/// The wide BVH's root node: a literal where the scene's occluders are baked, read here otherwise.
fn baked_wide_root() -> WideNode {
    return wide_node(0u);
}

/// Which of the root's children a ray enters within t (bits as `wide_node_hits` gives them): where the scene's
/// occluders are baked, a test of their exact boxes as literals.
fn baked_root_hits(r: TraceRay, oct: u32, t: f32) -> u32 {
    return wide_node_hits(r, oct, wide_node(0u), t);
}

/// Shadow-ray test of the baked primitives: whether anything but `skip` is hit with t in (0, t_max).
fn baked_occluded(r: TraceRay, t_max: f32, skip: u32) -> bool {
    return baked_traverse(r, Hit(t_max, INVALID, 0.0, 0.0), skip).prim != INVALID;
}
