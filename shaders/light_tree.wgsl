// light_tree.wgsl — `--light-select tree`: the descent of the light tree src/accel/light_tree.rs builds (its module docs
// give the importance), and the pmf of a given light from a shading point, for MIS. Called by select_light /
// light_pmf in lights.wgsl.
//
// The lights with a position come first in the light table, `light_node(0u).boxes.w` of them; the infinite ones
// (directional, environment) follow. Each infinite light is chosen with the probability of the whole tree:
// 1 / (infinite + 1), or 1 / infinite without a tree. Each node holds both children's bounds, so a step down is
// one node load (four vec4, or two 32-byte loads: light_tree_loads.wgsl).

/// In a LightNode's next words (spread_next.zw): the child is a leaf, the low bits its light index (light_tree::LEAF_BIT).
const LIGHT_LEAF_BIT: u32 = 0x80000000u;

fn cos_sub_clamped(sin_a: f32, cos_a: f32, sin_b: f32, cos_b: f32) -> f32 {
    if (cos_a > cos_b) { return 1.0; }
    return cos_a * cos_b + sin_a * sin_b;
}

fn sin_sub_clamped(sin_a: f32, cos_a: f32, sin_b: f32, cos_b: f32) -> f32 {
    if (cos_a > cos_b) { return 0.0; }
    return sin_a * cos_b - cos_a * sin_b;
}

/// Squared distances below this are this (light_tree::MIN_DIST2), and a box's closest distance² at least
/// LIGHT_NEAR_CLAMP of its radius² (light_tree::NEAR_CLAMP).
const LIGHT_MIN_DIST2: f32 = 1e-12;
const LIGHT_NEAR_CLAMP: f32 = 1e-3;

/// The importance of a child seen from p with normal n: (near, far), over the squared distance to its box's
/// closest point and farthest corner; the same arithmetic as light_tree::importance.
fn light_node_importance(node: LightChild, two_sided: bool, p: vec3<f32>, n: vec3<f32>) -> vec2<f32> {
    let pc = 0.5 * (node.lo + node.hi);
    let half = node.hi - node.lo;
    let r2 = 0.25 * dot(half, half);
    let to_p = p - pc;
    let dist2 = dot(to_p, to_p);
    var wi = vec3<f32>(0.0, 0.0, 1.0);
    if (dist2 > 0.0) { wi = to_p / sqrt(dist2); }
    var cos_w = dot(node.axis, wi);
    if (two_sided) { cos_w = abs(cos_w); }
    let sin_w = sqrt(max(1.0 - cos_w * cos_w, 0.0));
    var sin_b = 0.0;
    var cos_b = -1.0;
    if (!(dist2 < r2)) {
        let s2 = r2 / dist2;
        sin_b = sqrt(max(s2, 0.0));
        cos_b = sqrt(max(1.0 - s2, 0.0));
    }
    let sin_o = sqrt(max(1.0 - node.cos_o * node.cos_o, 0.0));
    let cos_x = cos_sub_clamped(sin_w, cos_w, sin_o, node.cos_o);
    let sin_x = sin_sub_clamped(sin_w, cos_w, sin_o, node.cos_o);
    let cos_p = cos_sub_clamped(sin_x, cos_x, sin_b, cos_b);
    if (cos_p <= node.cos_e) { return vec2<f32>(0.0); }
    var a = node.phi * cos_p;
    if (any(n != vec3<f32>(0.0))) {
        let cos_i = abs(dot(wi, n));
        let sin_i = sqrt(max(1.0 - cos_i * cos_i, 0.0));
        a *= cos_sub_clamped(sin_i, cos_i, sin_b, cos_b);
    }
    a = max(a, 0.0);
    let floor_d2 = max(LIGHT_NEAR_CLAMP * r2, LIGHT_MIN_DIST2);
    let dn = p - clamp(p, node.lo, node.hi);
    let df = p - select(node.lo, node.hi, p < pc);
    return vec2<f32>(a / max(dot(dn, dn), floor_d2), a / max(dot(df, df), floor_d2));
}

/// Child c (0 or 1) of `node`, decoded as light_tree::GpuLightNode::child does: box edges p + s·q (s·q is exact,
/// so this rounds once, as on the CPU), φ, the octahedral axis and the snorm16 cosines.
fn light_node_child(node: LightNode, c: u32) -> LightChild {
    let o = bitcast<vec3<f32>>(node.head.xyz);
    let e = (vec3<u32>(node.head.w) >> vec3<u32>(0u, 8u, 16u)) & vec3<u32>(0xffu);
    let s = bitcast<vec3<f32>>(e << vec3<u32>(23u));
    // Bytes 6c .. 6c + 5 of boxes.xyz (lo xyz, hi xyz): w0 holds the first four, w1 the last two.
    let w0 = select(node.boxes.x, (node.boxes.y >> 16u) | (node.boxes.z << 16u), c == 1u);
    let w1 = select(node.boxes.y, node.boxes.z >> 16u, c == 1u);
    let lo = vec3<f32>((vec3<u32>(w0) >> vec3<u32>(0u, 8u, 16u)) & vec3<u32>(0xffu));
    let hi = vec3<f32>(vec3<u32>(w0 >> 24u, w1 & 0xffu, (w1 >> 8u) & 0xffu));
    let spread = unpack2x16snorm(node.spread_next[c]);
    return LightChild(o + s * lo, o + s * hi,
        bitcast<f32>(node.power_axes[c]), oct_decode(node.power_axes[2u + c]), spread.x, spread.y);
}

/// The probability of descending into the first child of `node`: the mean of the near and far importances'
/// shares, by power where neither child has importance (as light_tree::first_child_probability).
fn tree_first_child_probability(node: LightNode, p: vec3<f32>, n: vec3<f32>) -> f32 {
    if (node.spread_next.w == INVALID) { return 1.0; }
    let c0 = light_node_child(node, 0u);
    let c1 = light_node_child(node, 1u);
    let i0 = light_node_importance(c0, (node.head.w & (1u << 24u)) != 0u, p, n);
    let i1 = light_node_importance(c1, (node.head.w & (1u << 25u)) != 0u, p, n);
    let sum = i0 + i1;
    if (sum.x > 0.0 && sum.y > 0.0) { return 0.5 * (i0.x / sum.x + i0.y / sum.y); }
    if (c0.phi + c1.phi > 0.0) { return c0.phi / (c0.phi + c1.phi); }
    return 0.5;
}

/// The probability of choosing the tree (not one of the infinite lights), and how many infinite lights follow it.
struct TreeSplit {
    p_tree: f32,
    bounded: u32,
    infinite: u32,
}
fn tree_split() -> TreeSplit {
    let bounded = light_node(0u).boxes.w;
    let infinite = params.num_lights - bounded;
    let choices = infinite + select(0u, 1u, bounded > 0u);
    return TreeSplit(select(0.0, 1.0 / f32(choices), bounded > 0u), bounded, infinite);
}

/// A light drawn by the tree and its pmf, multiplied up on the way down: the same factors in the same order as
/// tree_light_pmf, so equal to it bit for bit, without a second walk.
fn tree_select_light(u_in: f32, p: vec3<f32>, n: vec3<f32>) -> LightPick {
    let t = tree_split();
    var u = u_in;
    if (u >= t.p_tree) {
        // One of the infinite lights, uniformly.
        let k = min(u32((u - t.p_tree) / (1.0 - t.p_tree) * f32(t.infinite)), t.infinite - 1u);
        return LightPick(t.bounded + k, (1.0 - t.p_tree) / f32(t.infinite));
    }
    u = min(u / t.p_tree, ONE_MINUS_EPSILON);
    var pmf = t.p_tree;
    var next = 0u;
    for (var depth = 0u; depth < 32u; depth += 1u) {
        let node = light_node(next);
        let p0 = tree_first_child_probability(node, p, n);
        if (u < p0) {
            u = min(u / p0, ONE_MINUS_EPSILON);
            pmf *= p0;
            next = node.spread_next.z;
        } else {
            u = min((u - p0) / (1.0 - p0), ONE_MINUS_EPSILON);
            pmf *= 1.0 - p0;
            next = node.spread_next.w;
        }
        if ((next & LIGHT_LEAF_BIT) != 0u) { break; }
    }
    return LightPick(next & ~LIGHT_LEAF_BIT, pmf);
}

fn tree_light_pmf(light: u32, p: vec3<f32>, n: vec3<f32>) -> f32 {
    let t = tree_split();
    if (light >= t.bounded) { return (1.0 - t.p_tree) / f32(t.infinite); }
    var trail = scene_light(light).tree_trail;
    var pmf = t.p_tree;
    var next = 0u;
    for (var depth = 0u; depth < 32u; depth += 1u) {
        let node = light_node(next);
        let p0 = tree_first_child_probability(node, p, n);
        if ((trail & 1u) == 0u) {
            pmf *= p0;
            next = node.spread_next.z;
        } else {
            pmf *= 1.0 - p0;
            next = node.spread_next.w;
        }
        trail = trail >> 1u;
        if ((next & LIGHT_LEAF_BIT) != 0u) { break; }
    }
    return pmf;
}
