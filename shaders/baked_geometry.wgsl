// baked_geometry.wgsl — traversal of a scene baked into the shader (Features::flat). src/render/baked.rs generates the
// real one per scene, every primitive's intersection test unrolled with its data as literals; this stub stands in
// for modules built without a scene (the generic pipeline, probes), where FLAT_SCENE is false.

/// Closest hit of a baked scene (FLAT_SCENE) up to start.t, ignoring primitive `skip`.
fn baked_traverse(r: TraceRay, start: Hit, skip: u32) -> Hit {
    return start;
}

/// Shadow-ray test of a baked scene: whether anything but `skip` is hit with t in (0, t_max).
fn baked_occluded(r: TraceRay, t_max: f32, skip: u32) -> bool {
    return false;
}
