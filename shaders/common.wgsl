// common.wgsl — constants and the structs shared with Rust (mirrored in src/gpu/types.rs, layout-tested).

const PI: f32 = 3.14159265358979323846;
const INV_PI: f32 = 0.31830988618379067154;
const TWO_PI: f32 = 6.28318530717958647692;
const INV_TWO_PI: f32 = 0.15915494309189533577;
const INV_FOUR_PI: f32 = 0.07957747154594766788;
const F32_MAX: f32 = 3.40282347e38;
const INVALID: u32 = 0xffffffffu;
const ONE_MINUS_EPSILON: f32 = 0.99999994;

// Primitive references (BVH leaves): kind in the top two bits, index in the rest.
const PRIM_TRIANGLE: u32 = 0u;
const PRIM_SPHERE: u32 = 1u;
const PRIM_QUAD: u32 = 2u;
const PRIM_KIND_SHIFT: u32 = 30u;
const PRIM_INDEX_MASK: u32 = 0x3fffffffu;

// Light kinds (Light.kind).
const LIGHT_TRIANGLE: u32 = 0u;
const LIGHT_SPHERE: u32 = 1u;
const LIGHT_QUAD: u32 = 2u;
const LIGHT_POINT: u32 = 3u;
const LIGHT_SPOT: u32 = 4u;
const LIGHT_DIRECTIONAL: u32 = 5u;
const LIGHT_ENVIRONMENT: u32 = 6u;
const LIGHT_CONVEX_LAMP: u32 = 7u;   // a closed convex emitter mesh sampled as one light (lights.wgsl)
const LIGHT_LAMP_FACE: u32 = 8u;     // one face of a convex lamp: found by rays, never chosen (tree_trail: its lamp)

// Settings tags (mirrored by the Rust enums in src/render/settings.rs).
const MODE_DIRECT: u32 = 0u;
const MODE_PATH: u32 = 1u;

const STRATEGY_UNIFORM: u32 = 0u;
const STRATEGY_COSINE: u32 = 1u;
const STRATEGY_BSDF: u32 = 2u;
const STRATEGY_LIGHT: u32 = 3u;
const STRATEGY_MIS: u32 = 4u;

const LIGHT_SAMPLING_AREA: u32 = 0u;
const LIGHT_SAMPLING_SOLID_ANGLE: u32 = 1u;

const ENV_SAMPLING_UNIFORM: u32 = 0u;
const ENV_SAMPLING_IMPORTANCE: u32 = 1u;
const ENV_SAMPLING_GUIDED: u32 = 2u;
// Resolved on the host to guided or importance (src/render/sky_probe.rs): no kernel sees it.
const ENV_SAMPLING_AUTO: u32 = 3u;

const LIGHT_SELECT_UNIFORM: u32 = 0u;
const LIGHT_SELECT_POWER: u32 = 1u;
const LIGHT_SELECT_TREE: u32 = 2u;
const LIGHT_SELECT_RIS: u32 = 3u;
const LIGHT_SELECT_TREE_RIS: u32 = 4u;

const HEURISTIC_BALANCE: u32 = 0u;
const HEURISTIC_POWER: u32 = 1u;

const MIS_MULTI: u32 = 0u;
const MIS_ONE: u32 = 1u;

const SAMPLER_INDEPENDENT: u32 = 0u;
const SAMPLER_STRATIFIED: u32 = 1u;
const SAMPLER_HALTON: u32 = 2u;
const SAMPLER_HAMMERSLEY: u32 = 3u;
const SAMPLER_SOBOL: u32 = 4u;
const SAMPLER_BLUE_NOISE: u32 = 5u;

// Texture wrap modes (TextureInfo.wrap_s / wrap_t).
const WRAP_REPEAT: u32 = 0u;
const WRAP_CLAMP: u32 = 1u;
const WRAP_MIRROR: u32 = 2u;
const TEX_IMAGE: u32 = 0u;
const TEX_CHECKERBOARD: u32 = 1u;
const TEXEL_HI: u32 = 0x80000000u;

/// An analytic sphere. Emission, if any, comes from its material; `light` indexes the light table.
struct Sphere {
    center: vec3<f32>,
    radius: f32,
    material: u32,
    light: u32,
    _pad0: u32,
    _pad1: u32,
}

/// An analytic parallelogram: corner + s·edge_u + t·edge_v, s,t ∈ [0,1]; front face along cross(edge_u, edge_v).
struct Quad {
    corner: vec3<f32>,
    material: u32,
    edge_u: vec3<f32>,
    light: u32,
    edge_v: vec3<f32>,
    _pad0: u32,
}

/// Per-triangle shading data: its three shading vertices (indices into `shading_verts`, stored in the w of its three
/// `tri_verts`) and its light (INVALID: none; stored in `tri_lights`). Read through `scene_tri_record`.
struct TriShading {
    corners: vec3<u32>,
    light: u32,
}

/// A shading vertex, shared between triangles (src/render/shading_data.rs): octahedral normal (oct_decode), material
/// index (low 16 bits) and cut-out mask (high 16: 0 none, k + 1 texture k's alpha channel), uv.
struct ShadingVertex {
    normal: u32,
    material: u32,
    uv: vec2<f32>,
}

/// The code of "no usable normal" (shading_data::NO_NORMAL): decodes to zero.
const NO_NORMAL: u32 = 0x80008000u;

/// Octahedral normal (2 × snorm16, Cigolle et al. 2014): the upper half of the octahedron maps to itself, the
/// lower half is folded over its edges; normalised. Branch-free (a select), so lanes stay together.
fn oct_decode(code: u32) -> vec3<f32> {
    let e = unpack2x16snorm(code);
    let z = 1.0 - abs(e.x) - abs(e.y);
    let folded = (vec2<f32>(1.0) - abs(e.yx)) * select(vec2<f32>(-1.0), vec2<f32>(1.0), e >= vec2<f32>(0.0));
    let n = normalize(vec3<f32>(select(e, folded, z < 0.0), z));
    return select(n, vec3<f32>(0.0), code == NO_NORMAL);
}

/// A material: what every kind shares (emission, textures, its kind) and its kind's parameter words, whose layout
/// the kind's registry entry writes (src/render/materials.rs `pack_*`) and its shader file reads (`<kind>_params` in
/// shaders/bsdf_<kind>.wgsl). The MATERIAL_* tags are generated from the registry (src/render/materials.rs).
/// Texture slots hold an index into `tex_info` or INVALID; uv transforms are 2×3 affine (rows xform_*0, xform_*1).
struct Material {
    emission: vec3<f32>,
    bsdf_kind: u32,         // MATERIAL_* tag
    base_tex: u32,          // the base-colour texture (each kind says what it multiplies)
    mr_tex: u32,            // glTF's metallic-roughness texture (metallic-roughness reads it)
    emissive_tex: u32,
    _pad0: u32,
    base_xform0: vec4<f32>, // (a, b, c, texcoord): u' = a·u + b·v + c
    base_xform1: vec4<f32>, // (d, e, f, 0):        v' = d·u + e·v + f
    mr_xform0: vec4<f32>,
    mr_xform1: vec4<f32>,
    em_xform0: vec4<f32>,
    em_xform1: vec4<f32>,
    params0: vec4<f32>,     // the kind's parameter words
    params1: vec4<f32>,
    params2: vec4<f32>,
}

/// GGX α below which conductors and dielectrics are delta lobes (scene::DELTA_ALPHA).
const DELTA_ALPHA: f32 = 1e-3;

/// One entry of the light table. For area lights `prim` indexes triangles/spheres/quads; for
/// punctual lights `position`/`direction` are used. `pmf` is this light's selection probability under
/// the active light-selection scheme (power or uniform), so MIS can evaluate it in O(1).
struct Light {
    position: vec3<f32>,
    kind: u32,
    direction: vec3<f32>,
    prim: u32,
    radiance: vec3<f32>,   // emitted radiance (area), intensity (point/spot), irradiance (directional), scale (env)
    pmf_power: f32,
    cos_inner: f32,
    cos_outer: f32,
    area: f32,
    pmf_uniform: f32,
    tree_trail: u32,       // the light's root-to-leaf path in light_tree (bit k: second child at depth k); a lamp face's lamp
    two_sided: u32,        // 1: an area light emitting from both faces (triangles, quads)
    shadow_box: u32,       // 1: a triangle of an isolated emitter; position/direction hold its stop box (lo/hi)
    _pad2: u32,
}

/// One child's bounds in a light-tree node, decoded (light_tree.wgsl `light_node_child`): bounds, power φ,
/// orientation cone (axis, cos θo) and emission spread cos θe of the lights below it.
struct LightChild {
    lo: vec3<f32>,
    hi: vec3<f32>,
    phi: f32,
    axis: vec3<f32>,
    cos_o: f32,
    cos_e: f32,
}

/// A light-tree node, both children's bounds compressed to four vec4 (src/accel/light_tree.rs `GpuLightNode` gives
/// the layout): `head` the box origin and scale exponents, two-sided bits; `boxes` the children's 8-bit box edges
/// and the count of lights below; `power_axes` their φ and octahedral cone axes; `spread_next` their cone
/// cosines (snorm16 pairs) and where they are: a node index, or LIGHT_LEAF_BIT | a light index, or INVALID.
struct LightNode {
    head: vec4<u32>,
    boxes: vec4<u32>,
    power_axes: vec4<u32>,
    spread_next: vec4<u32>,
}

/// Alias-table entry: take `index` with probability `prob`, else `alias`.
struct AliasEntry {
    prob: f32,
    alias_index: u32,
}

/// Where a texture's texels start in `tex_texels` (RGBA8, one u32 per texel) and how to read them.
struct TextureInfo {
    offset: u32,
    width: u32,
    height: u32,
    wrap_s: u32,
    wrap_t: u32,
    srgb: u32,
    nearest: u32,
    /// TEX_IMAGE, or TEX_CHECKERBOARD (tex1.rgb, tex2.rgb as f32 bits at `offset`).
    tex_kind: u32,
}

/// Per-pixel accumulation: running mean and sum of squared deviations (Welford/Chan), sample count,
/// and the number of non-finite samples that were counted and left out.
struct Accum {
    mean: vec3<f32>,
    count: u32,
    m2: vec3<f32>,
    nonfinite: u32,
}

/// Everything a dispatch needs to know that is not scene data: camera, film, settings.
struct FrameParams {
    width: u32,
    height: u32,
    sample_base: u32,
    samples_per_dispatch: u32,
    seed: u32,
    mode: u32,
    max_depth: u32,
    strategy: u32,
    light_sampling: u32,
    env_sampling: u32,
    light_select: u32,
    heuristic: u32,
    power_beta: f32,
    light_samples: u32,
    bsdf_samples: u32,
    mis_kind: u32,
    sampler: u32,
    num_lights: u32,
    rr_depth: u32,
    env_light: u32,
    cam_origin: vec3<f32>,
    tan_half_fov: f32,
    cam_right: vec3<f32>,
    aspect: f32,
    cam_up: vec3<f32>,
    env_scale: f32,
    cam_forward: vec3<f32>,
    env_rotation: f32,
    env_constant: vec3<f32>,
    env_width: u32,
    env_height: u32,
    sampler_spp: u32,
    /// First film row this dispatch renders (the viewer renders bands of rows to bound its frame time).
    row_offset: u32,
    /// Rows this dispatch renders from `row_offset` (the dispatch covers ceil(row_count / 8) workgroup rows).
    row_count: u32,
    /// Length scale of the scene around the render origin (≤ 1); see offset_ray_origin_scaled.
    offset_scale: f32,
    /// Candidates per light sample under `--light-select ris`.
    ris_candidates: u32,
    /// Workgroup row j of the dispatch renders tile row (j · stride) mod rows (src/render/tile_order.rs).
    tile_row_stride: u32,
    /// Path mode: the light technique's samples at a first vertex where the environment guide applies are
    /// light_samples × this (estimators.wgsl strategy_plan).
    first_hit_light_split: u32,
    /// The environment guide's grid (src/render/env_guide.rs): its lower corner, 1 / cell size, cells per axis.
    guide_min: vec3<f32>,
    /// The guide's learning pass (GUIDE_LEARN: also accumulated; GUIDE_LEARN_ONLY: counts only), over the learner
    /// tiles only, or the rest of sample 0 after it (GUIDE_COMPLETE); 0: neither.
    guide_train: u32,
    guide_inv_cell: vec3<f32>,
    /// The guide's slots (cells × 6 normal classes).
    guide_slots: u32,
    guide_dims: vec3<u32>,
    /// 1 once a guide has been learned (guide_cdf holds it).
    guide_on: u32,
    /// One 8×8 tile in this many learns the guide (1, 2 or 4; env_guide_learner_tile).
    guide_learner_period: u32,
    lamp_first: u32,       // the convex lamps: lamp_count entries of the light table from lamp_first
    lamp_count: u32,
    lamps_only: u32,       // 1: they are the scene's only emitters
    occluder_first: u32,   // the triangles outside the BVH (src/render/scene_data.rs occluder_split)
    occluder_count: u32,
    /// The pixel filter (FILTER_*), its radius and gaussian σ in pixels, and 1 / ∫ of its gaussian over [−r, r]
    /// (shaders/pixel_filter.wgsl).
    pixel_filter: u32,
    filter_radius: f32,
    filter_sigma: f32,
    filter_norm: f32,
    _pad_filter: vec2<u32>,
}

/// The result of a closest-hit query. `prim` is a primitive reference or INVALID for a miss;
/// (b1, b2) are barycentrics of v1, v2 for triangles, (s, t) for quads, unused for spheres.
struct Hit {
    t: f32,
    prim: u32,
    b1: f32,
    b2: f32,
}

fn prim_kind(prim: u32) -> u32 { return prim >> PRIM_KIND_SHIFT; }
fn prim_index(prim: u32) -> u32 { return prim & PRIM_INDEX_MASK; }
fn make_prim(kind: u32, index: u32) -> u32 { return (kind << PRIM_KIND_SHIFT) | index; }

/// True for NaN and ±Inf. Tests the exponent bits: `x != x` is compiled as an ordered compare and misses NaN.
fn is_nonfinite(x: f32) -> bool { return (bitcast<u32>(x) & 0x7f800000u) == 0x7f800000u; }
fn any_nonfinite3(v: vec3<f32>) -> bool { return is_nonfinite(v.x) || is_nonfinite(v.y) || is_nonfinite(v.z); }

fn luminance(c: vec3<f32>) -> f32 { return dot(c, vec3<f32>(0.2126, 0.7152, 0.0722)); }
fn sqr(x: f32) -> f32 { return x * x; }
fn safe_sqrt(x: f32) -> f32 { return sqrt(max(x, 0.0)); }

// ---- Scene features: pipeline-overridable constants (src/render/features.rs sets them). The default (true)
// compiles every path; a specialised pipeline sets the ones a scene does not need to false, and the
// driver removes that code. On lavapipe this matters: it runs SIMD lanes under masks, so code in a
// branch that no lane takes still costs time unless it is compiled out.
override HAS_TRIANGLES: bool = true;
override HAS_SPHERES: bool = true;
override HAS_QUADS: bool = true;
override HAS_TRIANGLE_LIGHTS: bool = true;
override HAS_SPHERE_LIGHTS: bool = true;
override HAS_QUAD_LIGHTS: bool = true;
override HAS_CONVEX_LAMPS: bool = true;
override HAS_DELTA_LIGHTS: bool = true;
/// 0: no environment, 1: constant, 2: equirectangular map, 3: either (generic).
override ENV_KIND: u32 = 3u;
override HAS_TEXTURES: bool = true;
/// Any pbrt checkerboard texture (TEX_CHECKERBOARD).
override HAS_CHECKERBOARD: bool = true;
/// Texels over two bindings (src/render/gpu_scene.rs split_texels): a TextureInfo offset with TEXEL_HI set
/// counts into tex_texels_hi. False: that read is compiled out.
override HAS_TEXEL_SPLIT: bool = true;
/// Vertices over two to four bindings (src/render/gpu_scene.rs split_vertices): vertex k past tri_verts' length is
/// in tri_verts_hi, tri_verts_hi2 or tri_verts_hi3. False: those reads are compiled out.
override HAS_GEOMETRY_SPLIT: bool = true;
/// Whether any metallic-roughness material has a GGX lobe (metallic > 0 or specular > 0); false = Lambert only.
/// (Each material kind's own HAS_* is generated from src/render/materials.rs.)
override HAS_SPECULAR: bool = true;
/// Any triangle with a cut-out mask (alpha.wgsl); false = no alpha test in traversal.
override HAS_ALPHA: bool = true;
/// Whether any metallic-roughness material has a diffuse lobe.
override HAS_DIFFUSE: bool = true;
/// More than one light: false skips light selection entirely.
override MANY_LIGHTS: bool = true;
/// Scenes of a few primitives, baked into the shader: traversal is the generated `baked_traverse` (src/render/baked.rs).
override FLAT_SCENE: bool = false;
/// A few occluder triangles outside the BVH, tested before it (`baked_traverse`, `baked_occluded`): as literals in
/// a scene's own pipeline, in a loop over `occluder_range()` in the generic one (src/render/scene_data.rs
/// `occluder_split`).
override BAKED_OCCLUDERS: bool = false;
/// The wide BVH's root children tested against their exact boxes, as literals, before the traversal loop
/// (bvh_wide.wgsl; src/render/baked.rs `baked_root`): in a scene's own pipeline, not in the generic one (which
/// would only read the root node outside the loop instead of in it).
override BAKED_ROOT: bool = false;
/// Rays traced only for their emission stop at a convex lamp's box where they meet its inner sphere
/// (lights.wgsl `lamp_in_sight`): in a scene's own pipeline.
override LAMP_SIGHTING: bool = false;
