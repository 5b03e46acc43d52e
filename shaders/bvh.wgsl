// bvh.wgsl — BVH2 traversal (closest hit, any hit), ray–triangle/sphere/quad intersection and ray-origin offsetting.
// Needs common.wgsl and geometry_bindings.wgsl. Every loop has an explicit bound: lavapipe has no watchdog.

/// A BVH2 node holding both children's boxes (mirrors `GpuBvhNode` in src/accel/bvh.rs, same field names). Per child:
/// count > 0: leaf over prim_refs[first .. first + count]; count == 0 && first != INVALID: interior node
/// bvh_nodes[first]; count == 0 && first == INVALID: no child (single-leaf and empty trees), skipped by the flag.
struct BvhNode {
    lmin: vec3<f32>,
    l_first: u32,
    lmax: vec3<f32>,
    l_count: u32,
    rmin: vec3<f32>,
    r_first: u32,
    rmax: vec3<f32>,
    r_count: u32,
}

/// Traversal stack entries; src/accel/bvh.rs (BVH_STACK_SIZE) guarantees tree depth ≤ this, so pushes never overflow.
const BVH_STACK_SIZE: u32 = 64u;
/// Invocations per workgroup that may trace rays (every tracing entry point has at most this many).
const BVH_LANES: u32 = 64u;
// Traversal stacks live in workgroup memory, one BVH_STACK_SIZE slice per invocation: lavapipe lowers
// dynamic indexing of a private (function-scope) array to chains of selects over every element, and a
// 64-entry private stack made path tracing 1.7× slower than an 8-entry one; workgroup memory is plain
// addressed memory (and needs no zero-initialisation per call). 64 × 64 × 8 B = 32 KiB. An entry is two
// words in one vec2 — the BVH2 keeps a reference and its entry distance (f32 bits), the wide tree
// (bvh_wide.wgsl) a group — because Mesa 22's lavapipe runs every workgroup-memory access as a loop over the
// SIMD lanes, one loop per load or store instruction whatever its width: one vec2 is half the loops of two u32
// arrays (docs/profile-bvh.md, "The JIT code").
var<workgroup> bvh_stack: array<vec2<u32>, 4096>;
/// This invocation's index in its workgroup; entry points that trace call `bvh_set_lane` first.
var<private> bvh_lane: u32;

/// Tells traversal which stack slice is this invocation's (its local_invocation_index, < BVH_LANES).
fn bvh_set_lane(local_index: u32) {
    bvh_lane = min(local_index, BVH_LANES - 1u);
}
/// Conservative far-distance scale for the slab test, 1 + 2γ₃ rounded up (Ize 2013, "Robust BVH Ray Traversal",
/// JCGT 2(2)): the rounded slab distances then never reject a box the exact ray passes through.
const BVH_SLAB_FAR_SCALE: f32 = 1.0000004;
/// Direction components smaller than this are replaced by ±this before inverting, so 1/d is finite and the slab
/// products (b − o)·(1/d) are never 0·∞ = NaN.
const BVH_TINY_DIR: f32 = 1e-30;

/// Per-ray constants: origin, direction, safe inverse direction, and the shear/permutation of the watertight
/// triangle test (Woop, Benthin, Wald 2013, "Watertight Ray/Triangle Intersection", JCGT 2(1), §3).
struct TraceRay {
    o: vec3<f32>,
    d: vec3<f32>,
    inv_d: vec3<f32>,
    kx: u32,
    ky: u32,
    kz: u32,
    shear: vec3<f32>, // (Sx, Sy, Sz)
}

fn trace_ray_setup(o: vec3<f32>, d: vec3<f32>) -> TraceRay {
    let sgn = select(vec3<f32>(1.0), vec3<f32>(-1.0), d < vec3<f32>(0.0));
    let d_safe = select(d, sgn * BVH_TINY_DIR, abs(d) < vec3<f32>(BVH_TINY_DIR));
    // kz: the dominant axis of d; swap kx, ky when d[kz] < 0 to keep the winding (paper, Fig. 2).
    let ad = abs(d);
    var kz = 2u;
    if ad.x >= ad.y && ad.x >= ad.z { kz = 0u; } else if ad.y >= ad.z { kz = 1u; }
    var kx = (kz + 1u) % 3u;
    var ky = (kx + 1u) % 3u;
    if d[kz] < 0.0 { let tmp = kx; kx = ky; ky = tmp; }
    let shear = vec3<f32>(d[kx] / d[kz], d[ky] / d[kz], 1.0 / d[kz]);
    return TraceRay(o, d, 1.0 / d_safe, kx, ky, kz, shear);
}

/// Entry distance of the ray into [bmin, bmax] within [0, t_far], or F32_MAX for a miss (robust slab test with
/// min/max, so a negative inverse direction needs no swap).
fn ray_box_entry(r: TraceRay, bmin: vec3<f32>, bmax: vec3<f32>, t_far: f32) -> f32 {
    let t0 = (bmin - r.o) * r.inv_d;
    let t1 = (bmax - r.o) * r.inv_d;
    let tn = min(t0, t1);
    let tf = max(t0, t1);
    let enter = max(max(tn.x, tn.y), max(tn.z, 0.0));
    let leave = min(min(tf.x, tf.y), tf.z) * BVH_SLAB_FAR_SCALE;
    return select(F32_MAX, enter, enter <= min(leave, t_far));
}

/// One edge function of the watertight test, U/V/W = p.x·q.y − p.y·q.x in the sheared 2D frame. The paper
/// re-evaluates an exact 0 in double precision so that adjacent triangles agree on its sign; we instead evaluate
/// every edge with its endpoints in a canonical (lexicographic) order and negate afterwards. WGSL lets a compiler
/// reassociate or contract a·b − c·d into an fma, after which e(p,q) = −e(q,p) no longer holds bit for bit; with
/// the canonical order the two triangles sharing an edge compute the same bits with opposite signs whatever the
/// compiler does, so a ray through the edge hits at least one of them. A value of exactly 0 counts as inside for
/// both (a tie, never a hole). No f64 needed.
fn tri_edge(p: vec2<f32>, q: vec2<f32>) -> f32 {
    let swap = q.x < p.x || (q.x == p.x && q.y < p.y);
    let a = select(p, q, swap);
    let b = select(q, p, swap);
    let e = a.x * b.y - a.y * b.x;
    return select(e, -e, swap);
}

/// A vertex relative to the ray origin, permuted and sheared (paper, Fig. 2). Shared vertices give identical bits
/// in every triangle because the same code runs on the same values.
fn tri_vertex(r: TraceRay, v: vec3<f32>) -> vec3<f32> {
    let a = v - r.o;
    let az = a[r.kz];
    return vec3<f32>(a[r.kx] - r.shear.x * az, a[r.ky] - r.shear.y * az, r.shear.z * az);
}

/// Watertight ray–triangle test (Woop, Benthin, Wald 2013). Returns (t, b1, b2, 1) for a hit with t in (0, t_max),
/// (b1, b2) the barycentrics of v1, v2; w = 0 for a miss. Both faces; NaN inputs miss (ordered compares).
fn intersect_triangle(r: TraceRay, v0: vec3<f32>, v1: vec3<f32>, v2: vec3<f32>, t_max: f32) -> vec4<f32> {
    let a = tri_vertex(r, v0);
    let b = tri_vertex(r, v1);
    let c = tri_vertex(r, v2);
    return tri_hit(tri_edge(c.xy, b.xy), tri_edge(a.xy, c.xy), tri_edge(b.xy, a.xy), a.z, b.z, c.z, t_max);
}

/// The end of the watertight test, from the edge functions u, v, w (opposite v0, v1, v2) and the sheared z of the
/// vertices. Baked meshes (src/render/baked.rs) compute each shared vertex and edge once per ray and call this per
/// triangle: the same values, bit for bit, as `intersect_triangle`.
fn tri_hit(u: f32, v: f32, w: f32, az: f32, bz: f32, cz: f32, t_max: f32) -> vec4<f32> {
    // Branch-free: lavapipe runs both sides of every branch anyway, and selects are cheaper than its masks.
    let outside = (u < 0.0 || v < 0.0 || w < 0.0) && (u > 0.0 || v > 0.0 || w > 0.0);
    let det = u + v + w;
    let inv_det = 1.0 / det;
    let t = (u * az + v * bz + w * cz) * inv_det;
    let hit = !outside && det != 0.0 && t > 0.0 && t < t_max;
    return select(vec4<f32>(0.0), vec4<f32>(t, v * inv_det, w * inv_det, 1.0), hit);
}

/// Clips the ray parameter interval `span` to the half-space n·x ≤ dist (unit n): one face of a convex solid
/// (src/accel/convex_solids.rs; Haines 1991). The interval is empty (x ≥ y) once the ray misses the solid.
fn clip_to_half_space(span: vec2<f32>, r: TraceRay, n: vec3<f32>, dist: f32) -> vec2<f32> {
    let dn = dot(n, r.d);
    let s = dist - dot(n, r.o);   // ≥ 0 when the origin is inside
    let t = s / dn;
    let enter = select(span.x, max(span.x, t), dn < 0.0);
    let exit = select(span.y, min(span.y, t), dn > 0.0);
    // Parallel to the face: all or nothing.
    return select(vec2<f32>(enter, exit), vec2<f32>(1.0, 0.0), dn == 0.0 && s < 0.0);
}

/// Ray–sphere test, the cancellation-free form of Haines et al. 2019, "Precision Improvements for Ray/Sphere
/// Intersection" (Ray Tracing Gems ch. 7, eqs. 7.9–7.14): the discriminant from the distance of the centre to the
/// ray's line (accurate for far/small spheres), the roots as c/q and q/a. Returns (t, 0, 0, 1) for the nearest
/// root in (0, t_max) (the far one from inside), w = 0 for a miss. `d` need not be normalised.
fn intersect_sphere(o: vec3<f32>, d: vec3<f32>, center: vec3<f32>, radius: f32, t_max: f32) -> vec4<f32> {
    let f = o - center;
    let a = dot(d, d);
    let b = -dot(f, d);
    let l = f + (b / a) * d;
    let r2 = radius * radius;
    let disc = r2 - dot(l, l);
    // Branch-free (see tri_hit): for disc < 0 the square root is NaN and every comparison below fails.
    let q = b + select(1.0, -1.0, b < 0.0) * sqrt(a * disc);
    let c = dot(f, f) - r2;
    let t0 = c / q;
    let t1 = q / a;
    // select(), not min/max: min(NaN, x) = x on lavapipe would turn a NaN root into a hit.
    let near = select(t1, t0, t0 < t1);
    let far = select(t0, t1, t0 < t1);
    let near_ok = near > 0.0 && near < t_max;
    let far_ok = far > 0.0 && far < t_max;
    let hit = disc >= 0.0 && (near_ok || far_ok);
    return select(vec4<f32>(0.0), vec4<f32>(select(far, near, near_ok), 0.0, 0.0, 1.0), hit);
}

/// Ray–parallelogram test: the plane of corner + s·edge_u + t·edge_v, then (s, t) from cross products with the
/// normal n = edge_u × edge_v. Returns (t, s, t_param, 1) for a hit with s, t_param ∈ [0, 1], w = 0 for a miss.
fn intersect_quad(o: vec3<f32>, d: vec3<f32>, q: Quad, t_max: f32) -> vec4<f32> {
    let n = cross(q.edge_u, q.edge_v);
    let inv_nn = 1.0 / dot(n, n);
    return intersect_parallelogram(o, d, q.corner, n, cross(q.edge_v, n) * inv_nn, cross(n, q.edge_u) * inv_nn, t_max);
}

/// `intersect_quad` with the per-quad vectors precomputed (baked scenes write them as literals): the normal n and
/// the dual axes s_axis = (edge_v × n)/|n|², t_axis = (n × edge_u)/|n|², so that for a point p on the plane
/// (relative to the corner) s = p·s_axis and t = p·t_axis (the triple products (p × edge_v)·n/|n|² and
/// (edge_u × p)·n/|n|²).
fn intersect_parallelogram(o: vec3<f32>, d: vec3<f32>, corner: vec3<f32>, n: vec3<f32>, s_axis: vec3<f32>, t_axis: vec3<f32>, t_max: f32) -> vec4<f32> {
    let denom = dot(n, d);
    let rel_o = o - corner;
    let t = -dot(n, rel_o) / denom;
    let p = rel_o + t * d;
    let s = dot(p, s_axis);
    let tt = dot(p, t_axis);
    // Branch-free (see tri_hit); ordered comparisons fail for the NaN/∞ of denom = 0.
    let hit = t > 0.0 && t < t_max && denom != 0.0 && s >= 0.0 && s <= 1.0 && tt >= 0.0 && tt <= 1.0;
    return select(vec4<f32>(0.0), vec4<f32>(t, s, tt, 1.0), hit);
}

/// Intersects one primitive reference (kind << 30 | index); (t, b1, b2, 1) for a hit in (0, t_max), w = 0 for a miss.
fn intersect_prim(r: TraceRay, prim: u32, t_max: f32) -> vec4<f32> {
    let i = prim_index(prim);
    switch prim_kind(prim) {
        case PRIM_TRIANGLE: {
            if (!HAS_TRIANGLES) { return vec4<f32>(0.0); }
            return intersect_triangle_at(r, i, t_max);
        }
        case PRIM_SPHERE: {
            if (!HAS_SPHERES) { return vec4<f32>(0.0); }
            let s = load_spheres(i);
            return intersect_sphere(r.o, r.d, s.center, s.radius, t_max);
        }
        case PRIM_QUAD: {
            if (!HAS_QUADS) { return vec4<f32>(0.0); }
            return intersect_quad(r.o, r.d, load_quads(i), t_max);
        }
        default: {
            return vec4<f32>(0.0);
        }
    }
}

/// Vertex k of `tri_verts` (three per triangle). The buffer is read as u32 words: w holds a shading-vertex index
/// (src/render/scene_data.rs `pack_triangle_records`), whose bits as an f32 are a denormal, and lavapipe runs
/// shaders with denormals flushed to zero, so it must never pass through a float register.
fn tri_position(k: u32) -> vec3<f32> {
    return bitcast<vec3<f32>>(tri_vertex_words(k).xyz);
}

/// Vertex k of `tri_verts` as words (position bits, corner record index). In a scene whose vertices exceed one
/// binding, those past the first binding's length continue in `tri_verts_hi`, then `tri_verts_hi2` and
/// `tri_verts_hi3` (src/render/gpu_scene.rs split_vertices; an unused part is one zero vertex, never reached).
fn tri_vertex_words(k: u32) -> vec4<u32> {
    if HAS_GEOMETRY_SPLIT {
        let n0 = tri_verts_len();
        if k >= n0 {
            let k1 = k - n0;
            let n1 = len_tri_verts_hi();
            if k1 < n1 {
                return load_tri_verts_hi(k1);
            }
            let k2 = k1 - n1;
            let n2 = len_tri_verts_hi2();
            if k2 < n2 {
                return load_tri_verts_hi2(k2);
            }
            return load_tri_verts_hi3(k2 - n2);
        }
    }
    return tri_verts_words(k);
}

/// A triangle's three vertices as words (position bits, corner record index), as `tri_words`
/// (geometry_loads.wgsl) reads them in one go.
struct TriWords {
    a: vec4<u32>,
    b: vec4<u32>,
    c: vec4<u32>,
}

/// Triangle i's vertices: from `tri_verts` in as few loads as the device allows, or vertex by vertex where the
/// scene's vertices take further bindings (HAS_GEOMETRY_SPLIT; a triangle never straddles two).
fn triangle_words(i: u32) -> TriWords {
    if HAS_GEOMETRY_SPLIT {
        return TriWords(tri_vertex_words(3u * i), tri_vertex_words(3u * i + 1u), tri_vertex_words(3u * i + 2u));
    }
    return tri_words(i);
}

/// Intersects triangle i (its vertices' position bits as floats only here: w holds integer records).
fn intersect_triangle_at(r: TraceRay, i: u32, t_max: f32) -> vec4<f32> {
    let w = triangle_words(i);
    return intersect_triangle(r, bitcast<vec3<f32>>(w.a.xyz), bitcast<vec3<f32>>(w.b.xyz), bitcast<vec3<f32>>(w.c.xyz), t_max);
}

/// A child reference in one word, as the traversal stack and the leaf queue hold it: an interior node's index
/// (bit 31 clear), or BVH_LEAF | (count − 1) << 28 | first for a leaf of 1..=8 primitives (src/accel/bvh.rs makes ≤ 4;
/// `first` < 2^28 always holds: the node and vertex bindings cannot hold that many). INVALID = none.
const BVH_LEAF: u32 = 0x80000000u;
const BVH_LEAF_COUNT_ONE: u32 = 0x10000000u;
const BVH_LEAF_FIRST_MASK: u32 = 0x0fffffffu;

fn bvh_child_ref(first: u32, count: u32) -> u32 {
    return select(first, BVH_LEAF | ((min(count, 8u) - 1u) << 28u) | (first & BVH_LEAF_FIRST_MASK), count > 0u);
}

fn bvh_is_interior(r: u32) -> bool {
    return (r & BVH_LEAF) == 0u;
}

fn bvh_is_leaf(r: u32) -> bool {
    return (r & BVH_LEAF) != 0u && r != INVALID;
}

/// Whether `b` holds on every active lane of this SIMD group: the vote of speculative traversal. Devices with
/// subgroup operations get `subgroupAll` here (src/render/shaders.rs `for_device`); without them each lane votes alone,
/// which makes the traversal a plain while-while loop.
fn bvh_all_lanes(b: bool) -> bool {
    return b; // BVH_VOTE
}

/// Pops the top stack entry: its reference, or INVALID where it was entered beyond `t` (a closer hit has been
/// found since; the next step pops again). One pop per call, no loop: on lavapipe every loop in a step's body
/// costs at least one pass whether or not a lane needs it.
fn bvh_pop(base: u32, sp: ptr<function, u32>, t: f32) -> u32 {
    if *sp == 0u {
        return INVALID;
    }
    *sp -= 1u;
    let e = bvh_stack[base + *sp];
    return select(INVALID, e.x, bitcast<f32>(e.y) <= t);
}

/// A leaf primitive's test: its reference and hit (w = 0: a miss, a cut-out point, or `skip`).
struct LeafHit {
    prim: u32,
    h: vec4<f32>,
}

/// Tests entry j of the leaf order (`prim_refs[j]`) within t; both trees' traversals call it. In a triangle-only
/// scene prim_refs[j] == j (src/accel/bvh.rs into_leaf_order): the triangle is read directly, with no prim_refs
/// load and no switch on the kind; storage loads dominate a BVH sample on lavapipe (docs/profile-bvh.md). Chosen
/// per pipeline, not per leaf: a branch between the two paths costs lavapipe both (measured 13 % slower than
/// always reading prim_refs).
fn bvh_leaf_test(r: TraceRay, j: u32, t: f32, skip: u32) -> LeafHit {
    var prim: u32;
    var h = vec4<f32>(0.0);
    if HAS_TRIANGLES && !HAS_SPHERES && !HAS_QUADS {
        prim = j; // PRIM_TRIANGLE << 30 | index
        if prim != skip {
            h = intersect_triangle_at(r, prim, t);
        }
    } else {
        // A triangle-only scene uploads no references (src/render/scene_data.rs IDENTITY_PRIM_REFS): INVALID = j.
        prim = load_prim_refs(min(j, len_prim_refs() - 1u));
        if prim == INVALID {
            prim = j;
        }
        if prim != skip {
            h = intersect_prim(r, prim, t);
        }
    }
    // A cut-out point is no hit (HAS_ALPHA is false, and this test gone, in scenes without masks).
    if h.w != 0.0 && HAS_ALPHA && alpha_cut_out(prim, h.y, h.z) {
        h.w = 0.0;
    }
    return LeafHit(prim, h);
}

/// Stack-based BVH2 traversal shared by trace_closest and trace_any: Aila & Laine 2009's while-while loop with
/// speculative traversal. Lavapipe (and a GPU) runs a SIMD group's lanes in lockstep, executes a loop until its
/// last lane is done and a branch for any lane that takes it; in a loop that did a node step and a leaf's
/// primitive tests in the same iteration, every step paid for the leaf loop whenever one lane of 8 had a leaf.
/// Here an inner loop only visits interior nodes (near child first by entry distance, the far one pushed) and a
/// lane that reaches a leaf postpones it and keeps traversing until every lane has one; then a second loop tests
/// the postponed leaves' primitives, one per iteration, with all lanes busy. Node visits bound both loops.
fn bvh_traverse(o: vec3<f32>, d: vec3<f32>, t_max: f32, any_hit: bool, skip: u32) -> Hit {
    var hit = Hit(t_max, INVALID, 0.0, 0.0);
    // NaN/Inf rays, a zero direction or a NaN or non-positive t_max can hit nothing.
    if any_nonfinite3(o) || any_nonfinite3(d) || all(d == vec3<f32>(0.0)) || !(t_max > 0.0) {
        return hit;
    }
    let r = trace_ray_setup(o, d);
    if FLAT_SCENE {
        // (any_hit is a constant at every call site: only one of these survives inlining.)
        if any_hit {
            return Hit(t_max, select(INVALID, 0u, baked_occluded(r, t_max, skip)), 0.0, 0.0);
        }
        return baked_traverse(r, hit, skip);
    }
    if BAKED_OCCLUDERS {
        // A few large occluders first: their hit shortens the BVH walk, and a shadow ray they block ends here.
        if any_hit {
            if baked_occluded(r, t_max, skip) {
                return Hit(t_max, 0u, 0.0, 0.0);
            }
        } else {
            hit = baked_traverse(r, hit, skip);
        }
    }
    if WIDE_BVH {
        let h = wide_traverse(r, hit.t, any_hit, skip);
        if h.prim != INVALID {
            hit = h;
        }
        return hit;
    }
    // This invocation's slice of the workgroup stacks.
    let base = bvh_lane * BVH_STACK_SIZE;
    var sp = 0u;
    var cur = 0u;        // the next interior node to visit, a leaf waiting behind `leaf`, or INVALID: pop
    var leaf = INVALID;  // the postponed leaf: its next primitive and how many follow
    let max_steps = len_bvh_nodes() + 1u;
    for (var round = 0u; round < max_steps && (cur != INVALID || leaf != INVALID || sp > 0u); round++) {
        for (var step = 0u; step < 2u * max_steps && (bvh_is_interior(cur) || (cur == INVALID && sp > 0u)); step++) {
            var next = INVALID;
            if cur != INVALID {
                let node = load_bvh_nodes(cur);
                let l_valid = node.l_count > 0u || node.l_first != INVALID;
                let r_valid = node.r_count > 0u || node.r_first != INVALID;
                let tl = select(F32_MAX, ray_box_entry(r, node.lmin, node.lmax, hit.t), l_valid);
                let tr = select(F32_MAX, ray_box_entry(r, node.rmin, node.rmax, hit.t), r_valid);
                let lref = bvh_child_ref(node.l_first, node.l_count);
                let rref = bvh_child_ref(node.r_first, node.r_count);
                let right_first = tr < tl;
                let near_t = select(tl, tr, right_first);
                let far_t = select(tr, tl, right_first);
                if far_t != F32_MAX && sp < BVH_STACK_SIZE {
                    bvh_stack[base + sp] = vec2<u32>(select(rref, lref, right_first), bitcast<u32>(far_t));
                    sp += 1u;
                }
                next = select(INVALID, select(lref, rref, right_first), near_t != F32_MAX);
                if bvh_is_leaf(next) && leaf == INVALID {
                    leaf = next;
                    next = INVALID;
                }
            }
            if next == INVALID {
                next = bvh_pop(base, &sp, hit.t);
                if bvh_is_leaf(next) && leaf == INVALID {
                    leaf = next;
                    next = INVALID;
                }
            }
            cur = next;
            if bvh_all_lanes(leaf != INVALID) {
                break;
            }
        }
        // The postponed leaf's primitives, then the leaf `cur` holds if it is one (and so on).
        for (var k = 0u; k < 8u * max_steps && leaf != INVALID; k++) {
            let lh = bvh_leaf_test(r, leaf & BVH_LEAF_FIRST_MASK, hit.t, skip);
            if lh.h.w != 0.0 {
                hit = Hit(lh.h.x, lh.prim, lh.h.y, lh.h.z);
                if any_hit {
                    return hit;
                }
            }
            if leaf >= BVH_LEAF + BVH_LEAF_COUNT_ONE {
                leaf += 1u - BVH_LEAF_COUNT_ONE;
            } else if bvh_is_leaf(cur) {
                leaf = cur;
                cur = INVALID;
            } else {
                leaf = INVALID;
            }
        }
    }
    return hit;
}

/// Closest hit with t in (0, t_max). On a miss prim = INVALID and t = t_max. Triangles: (b1, b2) = barycentrics of
/// v1, v2; quads: (s, t) along edge_u, edge_v; spheres: unused (0). Both faces of everything are hit.
fn trace_closest(o: vec3<f32>, d: vec3<f32>, t_max: f32) -> Hit {
    return bvh_traverse(o, d, t_max, false, INVALID);
}

/// Whether anything is hit with t in (0, t_max) (shadow rays); returns at the first hit found.
fn trace_any(o: vec3<f32>, d: vec3<f32>, t_max: f32) -> bool {
    return bvh_traverse(o, d, t_max, true, INVALID).prim != INVALID;
}

/// `trace_any` that ignores primitive `skip`: a shadow ray towards a point sampled on an area light never
/// counts that light as its own occluder (a planar or convex emitter cannot hide its own visible points, and
/// the ill-conditioned plane crossing of a grazing ray would otherwise report one).
fn trace_any_except(o: vec3<f32>, d: vec3<f32>, t_max: f32, skip: u32) -> bool {
    return bvh_traverse(o, d, t_max, true, skip).prim != INVALID;
}

/// Spawn point for a ray leaving a surface at p, offset along the geometric normal `ng` (unit length, oriented
/// to the side the new ray leaves from). Wächter & Binder 2019, "A Fast and Robust Method for Avoiding
/// Self-Intersection" (Ray Tracing Gems ch. 6, listing 6-1): an offset of 256·ng integer ULPs, which scales with
/// the magnitude of p, and a fixed float offset of ng/65536 near the origin (|p| < 1/32) where ULPs get tiny.
fn offset_ray_origin(p: vec3<f32>, ng: vec3<f32>) -> vec3<f32> {
    return offset_ray_origin_scaled(p, ng, 1.0);
}

/// `offset_ray_origin` for a scene whose extent around the origin is `scale` (≤ 1): the near-origin threshold
/// and float offset shrink with it. With the fixed 1/65536 a sphere of radius 3e-7 lost 40% of its light
/// (rays spawned outside it); W–B's constants assume scenes of unit size.
fn offset_ray_origin_scaled(p: vec3<f32>, ng: vec3<f32>, scale: f32) -> vec3<f32> {
    let of_i = vec3<i32>(256.0 * ng);
    let p_i = bitcast<vec3<f32>>(bitcast<vec3<i32>>(p) + select(of_i, -of_i, p < vec3<f32>(0.0)));
    let p_f = p + (scale / 65536.0) * ng;
    return select(p_i, p_f, abs(p) < vec3<f32>(scale / 32.0));
}
