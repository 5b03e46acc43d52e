// bvh_wide.wgsl — traversal of the 8-wide compressed BVH (src/accel/wide_bvh.rs; Ylitie, Karras, Laine 2017).
// Needs bvh.wgsl (TraceRay, ray_box_entry, the primitive tests, the traversal stacks and the subgroup vote).

/// Whether this pipeline traverses the wide tree (`wide_nodes`) instead of the BVH2 (`bvh_nodes`): set per
/// pipeline from the scene (src/render/features.rs), so only one traversal is compiled in.
override WIDE_BVH: bool = false;

/// One 8-wide node, 80 bytes as five vec4 (mirrors `GpuWideNode` in src/accel/wide_bvh.rs, whose module docs give
/// the encoding): five 16-byte loads per node step, or three 32-byte ones (geometry_loads_int64.wgsl), each step
/// testing eight quantised boxes.
struct WideNode {
    head: vec4<u32>,
    links: vec4<u32>,
    q_lo_xy: vec4<u32>,
    q_lo_z_hi_x: vec4<u32>,
    q_hi_yz: vec4<u32>,
}

/// Bits 24–31 of a hit mask: interior children, by visiting rank. Bits 0–23: leaf primitives.
const WIDE_NODE_BITS: u32 = 0xff000000u;

/// The 8-bit values of slots 4·half .. 4·half + 3 from a (slots 0–3, slots 4–7) word pair.
fn wide_bytes(w: vec2<u32>, half: u32) -> u32 {
    return select(w.x, w.y, half == 1u);
}

/// Which children of `n` the ray enters within t: for an interior child in slot i the bit 24 + (i ^ oct) (its
/// visiting rank), for a leaf its primitives' bits offset .. offset + count − 1.
///
/// The slab test runs in the node's quantised frame (Ylitie et al. 2017, §3.2): the plane at p + s·q is crossed at
/// t = q·a + b with a = s/d and b = (p − o)/d, computed once per node, so a child's six planes cost a byte
/// extraction, a conversion and a multiply-add each, and the near and far planes are chosen once per node by the
/// direction's signs instead of a min and a max per plane. That form rounds differently from (p + s·q − o)/d —
/// and b can be far larger than t when the node's origin is far from the ray's — so each axis' planes are widened
/// by a bound on every rounding (of p + s·q, of b, of the product and the sum): pad = (|b| + |p/d| + 510·|a|)·2⁻²⁰,
/// several times the worst case of four roundings of 2⁻²⁴ each. The decoded boxes are conservative
/// (src/accel/wide_bvh.rs), so the widened test misses nothing the BVH2 would find. An axis whose terms overflow
/// (a direction component near 0 against huge coordinates) does not constrain: its planes become ±F32_MAX.
fn wide_node_hits(r: TraceRay, oct: u32, n: WideNode, t: f32) -> u32 {
    let p = bitcast<vec3<f32>>(n.head.xyz);
    let e = (vec3<u32>(n.head.w) >> vec3<u32>(0u, 8u, 16u)) & vec3<u32>(0xffu);
    let s = bitcast<vec3<f32>>(e << vec3<u32>(23u));
    let a = s * r.inv_d;
    let b = (p - r.o) * r.inv_d;
    let pad = (abs(b) + abs(p * r.inv_d) + 510.0 * abs(a)) * 9.5367431640625e-7;
    let finite = abs(b) + pad <= vec3<f32>(F32_MAX) & 255.0 * abs(a) <= vec3<f32>(F32_MAX);
    let a_f = select(vec3<f32>(0.0), a, finite);
    let b_near = select(vec3<f32>(-F32_MAX), b - pad, finite);
    let b_far = select(vec3<f32>(F32_MAX), b + pad, finite);
    // Along a negative direction component the upper edge is crossed first.
    let neg = r.inv_d < vec3<f32>(0.0);
    var hits = 0u;
    for (var half = 0u; half < 2u; half++) {
        let meta_w = wide_bytes(n.links.zw, half);
        let lo_w = vec3<u32>(wide_bytes(n.q_lo_xy.xy, half), wide_bytes(n.q_lo_xy.zw, half), wide_bytes(n.q_lo_z_hi_x.xy, half));
        let hi_w = vec3<u32>(wide_bytes(n.q_lo_z_hi_x.zw, half), wide_bytes(n.q_hi_yz.xy, half), wide_bytes(n.q_hi_yz.zw, half));
        let near_w = select(lo_w, hi_w, neg);
        let far_w = select(hi_w, lo_w, neg);
        for (var k = 0u; k < 4u; k++) {
            let sh = 8u * k;
            let m = (meta_w >> sh) & 0xffu;
            let tn = vec3<f32>((near_w >> vec3<u32>(sh)) & vec3<u32>(0xffu)) * a_f + b_near;
            let tf = vec3<f32>((far_w >> vec3<u32>(sh)) & vec3<u32>(0xffu)) * a_f + b_far;
            let enter = max(max(tn.x, tn.y), max(tn.z, 0.0));
            let leave = min(min(tf.x, tf.y), tf.z) * BVH_SLAB_FAR_SCALE;
            let entered = enter <= min(leave, t);
            let count = m >> 5u;
            let slot = 4u * half + k;
            let bits = select(((1u << count) - 1u) << (m & 31u), 1u << (24u + (slot ^ oct)), count == 0u);
            hits |= select(0u, bits, entered && m != 0u);
        }
    }
    return hits;
}

fn wide_push(base: u32, sp: ptr<function, u32>, e: vec2<u32>) {
    // src/accel/wide_bvh.rs keeps 2 · depth ≤ BVH_STACK_SIZE, so this never drops an entry.
    if *sp < BVH_STACK_SIZE {
        bvh_stack[base + *sp] = e;
        *sp += 1u;
    }
}

/// Closest or any hit in the wide tree: the paper's traversal with node groups and leaf groups. A node group is
/// (child_base, interior hit bits | imask): the next child is the lowest rank left, and the rest of the group is
/// pushed before descending. A leaf group is (tri_base, primitive hit bits). A lane that finds leaf primitives
/// postpones them and waits until every lane of its SIMD group has some or is done (Aila & Laine 2009's while-while
/// loop); then all test them together, one primitive per iteration. Stack entries carry no distance: a group's
/// boxes were tested against the closest hit when its node was loaded, and every primitive test uses the current one.
fn wide_traverse(r: TraceRay, t_max: f32, any_hit: bool, skip: u32) -> Hit {
    var hit = Hit(t_max, INVALID, 0.0, 0.0);
    let base = bvh_lane * BVH_STACK_SIZE;
    // Bit k set where the direction is negative: slot i is visited at rank i ^ oct.
    let oct = select(0u, 1u, r.d.x < 0.0) | select(0u, 2u, r.d.y < 0.0) | select(0u, 4u, r.d.z < 0.0);
    // The root as a node group of one: rank oct is slot 0, and imask 0 makes it child_base + 0.
    // A ray with a non-finite origin or direction hits nothing (wide_node_hits would let its NaN axes through).
    let finite_ray = all(abs(r.o) <= vec3<f32>(F32_MAX)) && all(abs(r.inv_d) <= vec3<f32>(F32_MAX));
    var g = vec2<u32>(0u, select(0u, 1u << (24u + oct), finite_ray));
    var tg = vec2<u32>(0u, 0u);
    if BAKED_ROOT {
        // The root's boxes are literals in a scene's own pipeline (baked_geometry.wgsl): a SIMD group whose rays
        // all stop at a baked occluder before the BVH's boxes, or miss them, never enters the loop below.
        let root = baked_wide_root();
        let hits = select(0u, baked_root_hits(r, oct, t_max), finite_ray);
        g = vec2<u32>(root.links.x, (hits & WIDE_NODE_BITS) | (root.head.w >> 24u));
        tg = vec2<u32>(root.links.y, hits & ~WIDE_NODE_BITS);
    }
    var sp = 0u;
    // The stack's top entry is held in registers (`top`, when `top_full`) and only the ones below it in workgroup
    // memory: lavapipe runs each workgroup-memory access as a loop over the SIMD lanes, and most pushed groups are
    // popped again before anything else is pushed (docs/profile-bvh.md, "The top entry in registers").
    var top = vec2<u32>(0u, 0u);
    var top_full = false;
    // Every node is loaded at most once and pushes at most one entry: these bound both loops.
    let bound = 3u * wide_node_count() + 1u;
    for (var round = 0u; round < bound && ((g.y & WIDE_NODE_BITS) != 0u || tg.y != 0u || sp > 0u || top_full); round++) {
        // A lane steps until it holds a leaf group, then waits for the others: each iteration loads one node, so
        // a lane finds at most one leaf group per iteration and never has to push one. (Speculating on, as the
        // BVH2 loop does, gained nothing on the wide tree and cost a second push in every step: lavapipe runs a
        // store as a loop over the SIMD lanes whether or not a lane stores; docs/profile-bvh.md.)
        for (var step = 0u; step < bound && tg.y == 0u && ((g.y & WIDE_NODE_BITS) != 0u || sp > 0u || top_full); step++) {
            // Pop and step in one iteration: lanes run in lockstep, so an iteration spent only popping idles the
            // lanes that have a node to visit (the BVH2 loop measured the same).
            if (g.y & WIDE_NODE_BITS) == 0u {
                var e = top;
                if top_full {
                    top_full = false;
                } else {
                    sp -= 1u;
                    e = bvh_stack[base + sp];
                }
                if (e.y & WIDE_NODE_BITS) != 0u {
                    g = e;
                } else {
                    tg = e;
                }
            }
            if (g.y & WIDE_NODE_BITS) != 0u {
                let bit = countTrailingZeros(g.y & WIDE_NODE_BITS);
                let slot = (bit - 24u) ^ oct;
                let idx = g.x + countOneBits(g.y & ((1u << slot) - 1u));
                g.y &= ~(1u << bit);
                if (g.y & WIDE_NODE_BITS) != 0u {
                    if top_full {
                        wide_push(base, &sp, top);
                    }
                    top = g;
                    top_full = true;
                }
                let node = wide_node(idx);
                let hits = wide_node_hits(r, oct, node, hit.t);
                g = vec2<u32>(node.links.x, (hits & WIDE_NODE_BITS) | (node.head.w >> 24u));
                tg = vec2<u32>(node.links.y, hits & ~WIDE_NODE_BITS);
            }
        }
        // The postponed leaf group's primitives.
        for (var k = 0u; k < 24u && tg.y != 0u; k++) {
            let lh = bvh_leaf_test(r, tg.x + countTrailingZeros(tg.y), hit.t, skip);
            tg.y &= tg.y - 1u;
            if lh.h.w != 0.0 {
                hit = Hit(lh.h.x, lh.prim, lh.h.y, lh.h.z);
                if any_hit {
                    return hit;
                }
            }
        }
    }
    return hit;
}
