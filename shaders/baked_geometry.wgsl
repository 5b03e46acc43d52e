// baked_geometry.wgsl — traversal of a scene baked into the shader (Features::flat). src/baked.rs generates the
// real one per scene, every primitive's intersection test unrolled with its data as literals; this stub stands in
// for modules built without a scene (the generic pipeline, probes), where FLAT_SCENE is false.

/// Traversal of a baked scene (FLAT_SCENE): never called for a scene that was not baked.
fn baked_traverse(r: TraceRay, start: Hit, any_hit: bool, skip: u32) -> Hit {
    return start;
}
