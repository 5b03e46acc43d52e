// alpha.wgsl — cut-outs (pbrt `"float alpha"` textures: leaves): a triangle point whose mask coverage is below 0.5
// is a hole; traversal (bvh.wgsl) skips it for closest hits and shadow rays alike, so light and camera rays agree.
//
// A fixed threshold, not pbrt-v4's stochastic alpha (a hash decides per ray, with probability = coverage): the masks of
// these scenes are binary (0 or 1 nearly everywhere), where both give the same image, and a threshold adds no noise
// and keeps the shadow and closest-hit queries of one point consistent. Fractional coverage is rounded, not blended.

/// Coverage below this is a hole.
const ALPHA_CUTOFF: f32 = 0.5;

/// Whether the hit at barycentrics (b1, b2) of primitive `prim` lies in a cut-out. Triangles only.
fn alpha_cut_out(prim: u32, b1: f32, b2: f32) -> bool {
    if (prim_kind(prim) != PRIM_TRIANGLE) { return false; }
    // The first corner's material word says whether there is a mask; only then are the other two corners read.
    let i = prim_index(prim);
    let a = scene_shading_vertex(scene_tri_corner(i, 0u));
    let mask = a.material >> 16u;
    if (mask == 0u) { return false; }
    let v1 = scene_shading_vertex(scene_tri_corner(i, 1u));
    let v2 = scene_shading_vertex(scene_tri_corner(i, 2u));
    let uv = (1.0 - b1 - b2) * a.uv + b1 * v1.uv + b2 * v2.uv;
    // The mask's own uv: identity (the importer warns about uv scale/offset on a mask).
    let c = texture_lookup(mask - 1u, vec4<f32>(1.0, 0.0, 0.0, 0.0), vec4<f32>(0.0, 1.0, 0.0, 0.0), uv);
    return c.w < ALPHA_CUTOFF;
}
