//! The light tree (`--light-select tree`): a BVH over every emitter with a position — triangles, spheres, quads,
//! point and spot lights — whose nodes carry their lights' total power, bounds and an orientation cone, so that
//! the probability of choosing a light depends on the shading point (Conty Estevez & Kulla 2018, as pbrt-v4's
//! `BVHLightSampler` uses it). Built here on the CPU; shaders/light_tree.wgsl descends it. The infinite lights
//! (directional, environment) have no position: each is chosen with the same probability as the whole tree.
//!
//! The importance of a node seen from p with normal n has pbrt-v4's angular part (`LightBounds::Importance`):
//! φ · cos θ' · cos θ'ᵢ, where θ' is the angle between the cone's axis and the direction to p less the cone's
//! spread θo and the angle θb the bounds' bounding sphere subtends (0 past the emission spread θe), and θ'ᵢ the
//! angle between n and the direction to the bounds less θb. It is 0 only where every light below emits nothing
//! towards p, so no light that can reach p gets probability 0. The distance part differs: pbrt-v4 divides by the
//! squared distance to the box's centre (at least its radius²), which cannot tell apart two siblings whose boxes
//! are about as large as their distance to p — near the floor of a field of lights every step down the upper
//! levels is then close to a power split. Here each child has two importances, the angular part over the squared
//! distance to the box's closest point (`near`) and to its farthest corner (`far`), and a child is chosen with the
//! mean of the two normalised probabilities, after Blender Cycles' light tree (a maximal and a minimal importance,
//! averaged). On the many-lights scene this
//! cut the variance of the pick 5× (examples/light_tree_variance.rs measures it without a GPU).
//!
//! The pmf of one light from p is the product of the child probabilities on its root-to-leaf path; each light
//! stores that path as bits (`tree_trail`, bit k = the second child at depth k), so the pmf of a light found by a
//! BSDF sample costs one walk down, as the sampling did. The split is by a surface-area-orientation heuristic
//! over 12 buckets (pbrt-v4), falling back to the median where a deeper split could overflow the 32 trail bits.

use bytemuck::{Pod, Zeroable};
use glam::Vec3;

use crate::accel::quantise::{decode_frame, quantise, scale_exponent};
use crate::gpu::octahedral::{oct_decode, oct_encode};

/// In a child reference (`GpuLightNode::next`): the child is a leaf and the low bits are its light-table index.
pub const LEAF_BIT: u32 = 0x8000_0000;
/// A child reference that refers to nothing: the second child of a root over a single light.
pub const EMPTY: u32 = 0xffff_ffff;
/// Trail bits: a leaf is at most this deep. The heuristic splits a node only while its lights still fit below it
/// when split at the median from there on (depth + ⌈log2 n⌉ < 32).
const MAX_DEPTH: u32 = 32;
/// The closest distance² to a box that contains p is this fraction of its radius²: finite, and large enough
/// that a box around p does not take every sample from its sibling.
const NEAR_CLAMP: f32 = 1e-3;
/// Buckets per axis of the split heuristic.
const BUCKETS: usize = 12;

/// Where a light is and where it emits: bounds, power, and a cone of normals (axis, cos θo) widened by the emission
/// spread about each normal (cos θe: 0 for area emitters' hemispheres).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LightBounds {
    pub lo: Vec3,
    pub hi: Vec3,
    /// Emitted power (any consistent unit: only ratios matter).
    pub phi: f32,
    pub axis: Vec3,
    pub cos_o: f32,
    pub cos_e: f32,
    pub two_sided: bool,
}

/// One child's bounds as the importance reads them (WGSL `LightChild`, decoded from its parent's node by
/// [`GpuLightNode::child`] on the CPU and `light_node_child` in shaders/light_tree.wgsl).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct LightChild {
    pub lo: Vec3,
    pub hi: Vec3,
    pub phi: f32,
    pub axis: Vec3,
    pub cos_o: f32,
    pub cos_e: f32,
}

/// One interior node as the GPU reads it (WGSL `LightNode`): both children's bounds, compressed to 64 bytes so that
/// a step down is four vec4 loads (lavapipe pays per storage load: docs/profile-bvh.md; the f32 layout took seven).
/// Every field is rounded so that the decoded bounds contain the exact ones: boxes outwards, cones wider.
/// - `head`: the children's common box origin (f32 bits, xyz) and, in w, the biased exponents of the per-axis
///   power-of-two scales (bytes 0–2, [`crate::accel::quantise`]) and the two-sided bits (bit 24 + c: child c emits
///   from both faces);
/// - `boxes`: xyz hold 12 box bytes, child 0's lo xyz and hi xyz, then child 1's; w: lights below this node (the
///   root's: how many lights of the table the tree covers);
/// - `power_axes`: φ of child 0 and 1 (f32 bits), then their cone axes (octahedral, `crate::gpu::octahedral`);
/// - `spread_next`: per child cos θo (low 16 bits) and cos θe (high 16), snorm16 rounded down; then `next0`,
///   `next1`: a node index, or [`LEAF_BIT`] | the light's index in the light table, or [`EMPTY`].
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct GpuLightNode {
    pub head: [u32; 4],
    pub boxes: [u32; 4],
    pub power_axes: [u32; 4],
    pub spread_next: [u32; 4],
}

/// Widening of a cone for its axis' octahedral rounding beyond the measured angle: the GPU's normalize may differ
/// from the CPU's by a few ulps (~1e-7 rad).
const AXIS_MARGIN: f64 = 1e-5;

/// snorm16 code of a cosine, rounded down (one more step unless exact, so that a decode that differs from the
/// CPU's by an ulp is still ≤ the exact cosine): a wider cone.
fn cos_code_down(c: f64) -> u32 {
    let x = c.clamp(-1.0, 1.0) * 32767.0;
    let q = if x == x.floor() { x as i32 } else { x.floor() as i32 - 1 };
    q.clamp(-32767, 32767) as i16 as u16 as u32
}

/// CPU twin of WGSL's unpack2x16snorm for one half.
fn snorm16_decode(bits: u32) -> f32 {
    ((bits as u16 as i16) as f32 / 32767.0).max(-1.0)
}

impl GpuLightNode {
    /// Packs two children (child 1 absent for a root over a single light) and where they are.
    fn pack(c0: &LightBounds, c1: Option<&LightBounds>, next: [u32; 2], count: u32) -> GpuLightNode {
        let (lo, hi) = match c1 {
            Some(c1) => (c0.lo.min(c1.lo), c0.hi.max(c1.hi)),
            None => (c0.lo, c0.hi),
        };
        let e = [0, 1, 2].map(|k| scale_exponent(lo[k], hi[k]));
        let s = Vec3::from_array(e.map(|e| f32::from_bits(e << 23)));
        let mut bytes = [0u32; 12];
        let mut node = GpuLightNode::default();
        for (c, b) in [Some(c0), c1].into_iter().enumerate() {
            let Some(b) = b else { continue };
            for k in 0..3 {
                let (ql, qh) = quantise(lo[k], s[k], b.lo[k], b.hi[k]);
                (bytes[6 * c + k], bytes[6 * c + 3 + k]) = (ql, qh);
            }
            let axis = oct_encode(b.axis);
            // The cone about the decoded axis that contains the cone about the exact one.
            let err = oct_decode(axis).as_dvec3().angle_between(b.axis.as_dvec3().normalize());
            let theta_o = (b.cos_o.clamp(-1.0, 1.0) as f64).acos() + err + AXIS_MARGIN;
            // A full sphere of directions, or an axis that does not encode (never for a union of unit normals).
            let full = b.cos_o <= -1.0 || !(theta_o < std::f64::consts::PI);
            // In f64: a cone widened by ~1e-5 rad has a cosine that rounds to 1 in f32.
            let cos_o = if full { -1.0 } else { theta_o.cos() };
            node.power_axes[c] = b.phi.to_bits();
            node.power_axes[2 + c] = axis;
            node.spread_next[c] = cos_code_down(cos_o) | cos_code_down(b.cos_e as f64) << 16;
            node.head[3] |= (b.two_sided as u32) << (24 + c);
        }
        for k in 0..3 {
            node.head[k] = lo[k].to_bits();
            node.head[3] |= e[k] << (8 * k);
        }
        for (i, q) in bytes.iter().enumerate() {
            node.boxes[i / 4] |= q << (8 * (i % 4));
        }
        node.boxes[3] = count;
        (node.spread_next[2], node.spread_next[3]) = (next[0], next[1]);
        node
    }

    /// Child c's bounds, decoded as the shader decodes them.
    pub fn child(&self, c: usize) -> LightChild {
        let (o, s) = decode_frame(&self.head);
        let byte = |i: usize| ((self.boxes[i / 4] >> (8 * (i % 4))) & 0xff) as f32;
        let q = |first: usize| Vec3::new(byte(first), byte(first + 1), byte(first + 2));
        let spread = self.spread_next[c];
        LightChild {
            lo: o + s * q(6 * c),
            hi: o + s * q(6 * c + 3),
            phi: f32::from_bits(self.power_axes[c]),
            axis: oct_decode(self.power_axes[2 + c]),
            cos_o: snorm16_decode(spread & 0xffff),
            cos_e: snorm16_decode(spread >> 16),
        }
    }

    /// Whether child c emits from both faces.
    pub fn two_sided(&self, c: usize) -> bool {
        self.head[3] & (1 << (24 + c)) != 0
    }

    /// Where child c is: a node index, [`LEAF_BIT`] | a light index, or [`EMPTY`].
    pub fn next(&self, c: usize) -> u32 {
        self.spread_next[2 + c]
    }

    /// Lights below this node.
    pub fn count(&self) -> u32 {
        self.boxes[3]
    }
}

/// A built tree: nodes depth-first from the root, and each light's root-to-leaf trail.
#[derive(Clone, Debug, Default)]
pub struct LightTree {
    pub nodes: Vec<GpuLightNode>,
    /// For input light k (in the order given to [`LightTree::build`]): its trail bits.
    pub trails: Vec<u32>,
}

impl LightBounds {
    /// The union of two bounds: boxes and power add; the cones merge into the smallest cone containing both
    /// (pbrt-v4's `DirectionCone` union), the spread is the wider one.
    pub fn union(&self, o: &LightBounds) -> LightBounds {
        if self.phi == 0.0 {
            return *o;
        }
        if o.phi == 0.0 {
            return *self;
        }
        let (axis, cos_o) = cone_union(self.axis, self.cos_o, o.axis, o.cos_o);
        LightBounds {
            lo: self.lo.min(o.lo),
            hi: self.hi.max(o.hi),
            phi: self.phi + o.phi,
            axis,
            cos_o,
            cos_e: self.cos_e.min(o.cos_e),
            two_sided: self.two_sided || o.two_sided,
        }
    }

    fn centroid(&self) -> Vec3 {
        0.5 * (self.lo + self.hi)
    }
}

/// The smallest cone containing cones (a, cos θa) and (b, cos θb).
fn cone_union(a: Vec3, cos_a: f32, b: Vec3, cos_b: f32) -> (Vec3, f32) {
    let (theta_a, theta_b) = (cos_a.clamp(-1.0, 1.0).acos(), cos_b.clamp(-1.0, 1.0).acos());
    let theta_d = a.dot(b).clamp(-1.0, 1.0).acos();
    if (theta_d + theta_b).min(std::f32::consts::PI) <= theta_a {
        return (a, cos_a);
    }
    if (theta_d + theta_a).min(std::f32::consts::PI) <= theta_b {
        return (b, cos_b);
    }
    let theta_o = 0.5 * (theta_a + theta_d + theta_b);
    if theta_o >= std::f32::consts::PI {
        return (a, -1.0);
    }
    // Rotate a towards b by θo − θa about a × b.
    let theta_r = theta_o - theta_a;
    let w = a.cross(b);
    if w.length_squared() < 1e-12 {
        return (a, -1.0);
    }
    let axis = glam::Quat::from_axis_angle(w.normalize(), theta_r) * a;
    (axis.normalize(), theta_o.cos())
}

/// cos(max(0, A − B)) from the sines and cosines of A and B.
fn cos_sub_clamped(sin_a: f32, cos_a: f32, sin_b: f32, cos_b: f32) -> f32 {
    if cos_a > cos_b {
        return 1.0;
    }
    cos_a * cos_b + sin_a * sin_b
}

/// sin(max(0, A − B)).
fn sin_sub_clamped(sin_a: f32, cos_a: f32, sin_b: f32, cos_b: f32) -> f32 {
    if cos_a > cos_b {
        return 0.0;
    }
    sin_a * cos_b - cos_a * sin_b
}

fn safe_sqrt(x: f32) -> f32 {
    x.max(0.0).sqrt()
}

/// Squared distances below this are this (a shading point on a point light).
const MIN_DIST2: f32 = 1e-12;

/// The importance of a child seen from p with surface normal n (module docs): (near, far), with the closest and
/// the farthest distance to its box. The same arithmetic, in the same order, as `light_node_importance` in
/// shaders/light_tree.wgsl (f32 both), so CPU and GPU pmfs agree closely.
pub fn importance(node: &LightChild, two_sided: bool, p: Vec3, n: Vec3) -> (f32, f32) {
    let (lo, hi) = (node.lo, node.hi);
    let pc = 0.5 * (lo + hi);
    let r2 = 0.25 * (hi - lo).length_squared();
    let to_p = p - pc;
    let dist2 = to_p.length_squared();
    let wi = if dist2 > 0.0 { to_p / dist2.sqrt() } else { Vec3::Z };
    let mut cos_w = node.axis.dot(wi);
    if two_sided {
        cos_w = cos_w.abs();
    }
    let sin_w = safe_sqrt(1.0 - cos_w * cos_w);
    // The cone of directions from p to the bounds' bounding sphere.
    let (sin_b, cos_b) = if dist2 < r2 {
        (0.0, -1.0)
    } else {
        let s2 = r2 / dist2;
        (safe_sqrt(s2), safe_sqrt(1.0 - s2))
    };
    let sin_o = safe_sqrt(1.0 - node.cos_o * node.cos_o);
    let cos_x = cos_sub_clamped(sin_w, cos_w, sin_o, node.cos_o);
    let sin_x = sin_sub_clamped(sin_w, cos_w, sin_o, node.cos_o);
    let cos_p = cos_sub_clamped(sin_x, cos_x, sin_b, cos_b);
    if cos_p <= node.cos_e {
        return (0.0, 0.0);
    }
    let mut a = node.phi * cos_p;
    if n != Vec3::ZERO {
        let cos_i = wi.dot(n).abs();
        let sin_i = safe_sqrt(1.0 - cos_i * cos_i);
        a *= cos_sub_clamped(sin_i, cos_i, sin_b, cos_b);
    }
    let a = a.max(0.0);
    let floor = (NEAR_CLAMP * r2).max(MIN_DIST2);
    let near = (p - p.clamp(lo, hi)).length_squared().max(floor);
    let far = (p - Vec3::select(p.cmplt(pc), hi, lo)).length_squared().max(floor);
    (a / near, a / far)
}

/// The probability of descending into the first child of `node`: by importance, or by power where neither has
/// any (conservative bounds can give a node importance whose children both have none: descending by power
/// there keeps Σ pmf = 1 at every point, at the cost of a wasted sample where no light reaches p anyway).
pub fn first_child_probability(node: &GpuLightNode, p: Vec3, n: Vec3) -> f32 {
    if node.next(1) == EMPTY {
        return 1.0;
    }
    let (c0, c1) = (node.child(0), node.child(1));
    let (n0, f0) = importance(&c0, node.two_sided(0), p, n);
    let (n1, f1) = importance(&c1, node.two_sided(1), p, n);
    if n0 + n1 > 0.0 && f0 + f1 > 0.0 {
        return 0.5 * (n0 / (n0 + n1) + f0 / (f0 + f1));
    }
    if c0.phi + c1.phi > 0.0 {
        return c0.phi / (c0.phi + c1.phi);
    }
    0.5
}

impl LightTree {
    /// Builds the tree over `lights` (index k of the input = `light_index[k]` in the light table), every one of
    /// them: the root's `count` is how many lights of the table the tree covers. A single light gets a root
    /// whose second child is [`EMPTY`].
    pub fn build(lights: &[LightBounds], light_index: &[u32]) -> LightTree {
        let mut tree = LightTree { nodes: vec![], trails: vec![0; lights.len()] };
        let mut items: Vec<usize> = (0..lights.len()).collect();
        match items.len() {
            0 => {}
            1 => {
                tree.nodes.push(GpuLightNode::pack(&lights[0], None, [LEAF_BIT | light_index[0], EMPTY], 1));
            }
            _ => {
                tree.build_node(lights, light_index, &mut items, 0, 0);
            }
        }
        tree
    }

    /// Builds the subtree over `items` at `depth` and returns its bounds and its reference (a node index, or a
    /// leaf's [`LEAF_BIT`] | light index).
    fn build_node(
        &mut self,
        lights: &[LightBounds],
        index: &[u32],
        items: &mut [usize],
        depth: u32,
        trail: u32,
    ) -> (LightBounds, u32) {
        if items.len() == 1 {
            let k = items[0];
            self.trails[k] = trail;
            return (lights[k], LEAF_BIT | index[k]);
        }
        let bounds = items.iter().skip(1).fold(lights[items[0]], |b, &k| b.union(&lights[k]));
        let me = self.nodes.len();
        self.nodes.push(GpuLightNode::default());
        let fits = depth + items.len().next_power_of_two().trailing_zeros() < MAX_DEPTH;
        let mid = if fits { split_saoh(lights, items, &bounds) } else { None };
        let mid = mid.unwrap_or_else(|| split_median(lights, items, &bounds));
        let (a, b) = items.split_at_mut(mid);
        let (b0, r0) = self.build_node(lights, index, a, depth + 1, trail);
        let (b1, r1) = self.build_node(lights, index, b, depth + 1, trail | (1u32 << depth));
        self.nodes[me] = GpuLightNode::pack(&b0, Some(&b1), [r0, r1], items.len() as u32);
        (bounds, me as u32)
    }

    /// The probability that the tree picks its light with input index k from (p, n). f32 like the GPU.
    pub fn pmf(&self, k: usize, p: Vec3, n: Vec3) -> f32 {
        pmf(&self.nodes, self.trails[k], p, n)
    }

    /// Every leaf's light-table index, for tests.
    pub fn leaves(&self) -> Vec<u32> {
        let refs = self.nodes.iter().flat_map(|n| [n.next(0), n.next(1)]);
        refs.filter(|&r| r != EMPTY && r & LEAF_BIT != 0).map(|r| r & !LEAF_BIT).collect()
    }

    /// Depth of the deepest leaf (the number of steps down to it).
    pub fn depth(&self) -> u32 {
        fn walk(t: &LightTree, r: u32) -> u32 {
            if r == EMPTY || r & LEAF_BIT != 0 {
                return 0;
            }
            let n = &t.nodes[r as usize];
            1 + walk(t, n.next(0)).max(walk(t, n.next(1)))
        }
        if self.nodes.is_empty() {
            0
        } else {
            walk(self, 0)
        }
    }
}

/// The probability that a walk down `nodes` from (p, n) ends at the leaf with root-to-leaf path `trail`: the
/// product of the child probabilities on the way (0 for an empty tree). The same walk as `tree_light_pmf` in
/// shaders/light_tree.wgsl, which also includes the probability of choosing the tree over the infinite lights.
pub fn pmf(nodes: &[GpuLightNode], mut trail: u32, p: Vec3, n: Vec3) -> f32 {
    if nodes.is_empty() {
        return 0.0;
    }
    let mut r = 0u32;
    let mut pmf = 1.0f32;
    for _ in 0..MAX_DEPTH {
        let node = &nodes[r as usize];
        let p0 = first_child_probability(node, p, n);
        if trail & 1 == 0 {
            pmf *= p0;
            r = node.next(0);
        } else {
            pmf *= 1.0 - p0;
            r = node.next(1);
        }
        trail >>= 1;
        if r == EMPTY || r & LEAF_BIT != 0 {
            break;
        }
    }
    pmf
}

/// The cost of a cluster in the split heuristic: power × surface area × orientation measure (pbrt-v4's `EvaluateCost`).
fn saoh_cost(b: &LightBounds, extent: Vec3, axis: usize) -> f32 {
    use std::f32::consts::PI;
    let theta_o = b.cos_o.clamp(-1.0, 1.0).acos();
    let theta_e = b.cos_e.clamp(-1.0, 1.0).acos();
    let theta_w = (theta_o + theta_e).min(PI);
    let sin_o = theta_o.sin();
    let m_omega = 2.0 * PI * (1.0 - b.cos_o)
        + PI / 2.0 * (2.0 * theta_w * sin_o - (theta_o - 2.0 * theta_w).cos() - 2.0 * theta_o * sin_o + b.cos_o);
    let d = b.hi - b.lo;
    let area = 2.0 * (d.x * d.y + d.y * d.z + d.z * d.x);
    // Long thin clusters cost more along their long axis (pbrt-v4's Kr).
    let kr = extent.max_element() / extent[axis].max(1e-20);
    b.phi * m_omega * area.max(1e-20) * kr
}

/// The best bucket split over the three axes, or None (all centroids equal, or no split is better than a leaf
/// chain): items are partitioned in place and the first part's length returned.
fn split_saoh(lights: &[LightBounds], items: &mut [usize], bounds: &LightBounds) -> Option<usize> {
    let nb = BUCKETS;
    let key = |k: usize, dim: usize| lights[k].centroid()[dim];
    let extent = bounds.hi - bounds.lo;
    let mut best: Option<(f32, usize, usize, f32, f32)> = None;
    for dim in 0..3 {
        let (klo, khi) =
            items.iter().fold((f32::MAX, f32::MIN), |(lo, hi), &k| (lo.min(key(k, dim)), hi.max(key(k, dim))));
        let span = khi - klo;
        if !(span > 0.0) {
            continue;
        }
        let bucket_of = |k: usize| (((key(k, dim) - klo) / span * nb as f32) as usize).min(nb - 1);
        let mut buckets: Vec<Option<LightBounds>> = vec![None; nb];
        for &k in items.iter() {
            let b = bucket_of(k);
            buckets[b] = Some(buckets[b].map_or(lights[k], |x| x.union(&lights[k])));
        }
        for split in 1..nb {
            let merge = |r: std::ops::Range<usize>| r.filter_map(|i| buckets[i]).reduce(|a, b| a.union(&b));
            let (Some(a), Some(b)) = (merge(0..split), merge(split..nb)) else { continue };
            let cost = saoh_cost(&a, extent, dim) + saoh_cost(&b, extent, dim);
            if best.is_none_or(|(c, ..)| cost < c) {
                best = Some((cost, dim, split, klo, span));
            }
        }
    }
    let (_, dim, split, klo, span) = best?;
    let left = |k: &usize| ((((key(*k, dim) - klo) / span * nb as f32) as usize).min(nb - 1)) < split;
    let mid = partition_in_place(items, left);
    (mid > 0 && mid < items.len()).then_some(mid)
}

/// Splits at the median centroid along the widest centroid axis (always two non-empty halves).
fn split_median(lights: &[LightBounds], items: &mut [usize], _bounds: &LightBounds) -> usize {
    let (clo, chi) = items.iter().fold((Vec3::splat(f32::MAX), Vec3::splat(f32::MIN)), |(lo, hi), &k| {
        let c = lights[k].centroid();
        (lo.min(c), hi.max(c))
    });
    let axis = (chi - clo).max_position();
    let mid = items.len() / 2;
    items.select_nth_unstable_by(mid, |&a, &b| {
        lights[a].centroid()[axis].total_cmp(&lights[b].centroid()[axis]).then(a.cmp(&b))
    });
    mid
}

fn partition_in_place(items: &mut [usize], pred: impl Fn(&usize) -> bool) -> usize {
    let mut i = 0;
    for j in 0..items.len() {
        if pred(&items[j]) {
            items.swap(i, j);
            i += 1;
        }
    }
    i
}

#[cfg(test)]
mod tests {
    use super::*;

    fn tri_light(c: Vec3, n: Vec3, phi: f32) -> LightBounds {
        LightBounds { lo: c - 0.05, hi: c + 0.05, phi, axis: n, cos_o: 1.0, cos_e: 0.0, two_sided: false }
    }

    fn scatter(count: usize) -> Vec<LightBounds> {
        // A deterministic scatter of small emitters of varied power and orientation.
        (0..count)
            .map(|i| {
                let f = i as f32;
                let c = Vec3::new(
                    (f * 0.618).fract() * 10.0 - 5.0,
                    (f * 0.414).fract() * 2.0,
                    (f * 0.732).fract() * 10.0 - 5.0,
                );
                let n = Vec3::new((f * 1.3).sin(), (f * 0.7).cos().abs() + 0.1, (f * 2.1).cos()).normalize();
                tri_light(c, n, 0.1 + (f * 0.37).fract() * 10.0)
            })
            .collect()
    }

    #[test]
    fn pmf_sums_to_one_and_every_visible_light_has_a_chance() {
        let lights = scatter(500);
        let idx: Vec<u32> = (0..lights.len() as u32).collect();
        let t = LightTree::build(&lights, &idx);
        assert_eq!(t.leaves().len(), 500);
        assert!(t.depth() <= 32, "depth {}", t.depth());
        for (p, n) in
            [(Vec3::new(0.0, 3.0, 0.0), Vec3::NEG_Y), (Vec3::new(4.0, 0.5, -4.0), Vec3::Y), (Vec3::ZERO, Vec3::ZERO)]
        {
            let sum: f64 = (0..lights.len()).map(|k| t.pmf(k, p, n) as f64).sum();
            assert!((sum - 1.0).abs() < 1e-4, "Σ pmf = {sum} at {p}");
            // A light that faces p and lies above the surface must have pmf > 0.
            for (k, l) in lights.iter().enumerate() {
                let to_p = p - l.centroid();
                if to_p.dot(l.axis) > 0.1 * to_p.length() && (n == Vec3::ZERO || (-to_p).dot(n) > 0.1 * to_p.length()) {
                    assert!(t.pmf(k, p, n) > 0.0, "light {k} visible from {p} has pmf 0");
                }
            }
        }
    }

    /// Every light below a child lies inside the child's decoded bounds: box, cone (its normals within θo of the
    /// decoded axis), spread; the compression only widens (scatter lights, and cones of every width).
    #[test]
    fn decoded_children_contain_their_lights() {
        let mut lights = scatter(700);
        for (i, l) in lights.iter_mut().enumerate().step_by(3) {
            // Spot-like cones and spreads of varied widths, and some full spheres.
            l.cos_o = [1.0, 0.9, 0.0, -0.5, -1.0][i % 5];
            l.cos_e = [0.0, 0.7, -1.0, 0.95][i % 4];
        }
        let idx: Vec<u32> = (0..lights.len() as u32).collect();
        let t = LightTree::build(&lights, &idx);
        fn below(t: &LightTree, r: u32, out: &mut Vec<u32>) {
            if r == EMPTY {
            } else if r & LEAF_BIT != 0 {
                out.push(r & !LEAF_BIT);
            } else {
                let n = &t.nodes[r as usize];
                below(t, n.next(0), out);
                below(t, n.next(1), out);
            }
        }
        let mut checked = 0;
        for node in &t.nodes {
            for c in 0..2 {
                let mut ks = vec![];
                below(&t, node.next(c), &mut ks);
                let ch = node.child(c);
                let phi: f64 = ks.iter().map(|&k| lights[k as usize].phi as f64).sum();
                assert!((ch.phi as f64 - phi).abs() <= 1e-4 * phi, "φ {} against {phi}", ch.phi);
                let theta_o = (ch.cos_o as f64).clamp(-1.0, 1.0).acos();
                for &k in &ks {
                    let l = &lights[k as usize];
                    assert!(ch.lo.cmple(l.lo).all() && ch.hi.cmpge(l.hi).all(), "box of light {k} outside");
                    assert!(ch.cos_e <= l.cos_e, "spread of light {k}: {} > {}", ch.cos_e, l.cos_e);
                    assert_eq!(node.two_sided(c), node.two_sided(c) || l.two_sided);
                    if ch.cos_o > -1.0 {
                        let a = ch.axis.as_dvec3().angle_between(l.axis.as_dvec3());
                        let spread = (l.cos_o as f64).clamp(-1.0, 1.0).acos();
                        assert!(a + spread <= theta_o, "cone of light {k}: {a} + {spread} > {theta_o}");
                    }
                    checked += 1;
                }
            }
        }
        assert!(checked > 700 * 5, "{checked} containments checked");
    }

    #[test]
    fn lights_behind_a_one_sided_emitter_get_nothing() {
        let lights = vec![tri_light(Vec3::ZERO, Vec3::Y, 1.0), tri_light(Vec3::new(3.0, 0.0, 0.0), Vec3::NEG_Y, 1.0)];
        let t = LightTree::build(&lights, &[0, 1]);
        let p = Vec3::new(0.0, 2.0, 0.0);
        assert_eq!(t.pmf(1, p, Vec3::ZERO), 0.0);
        assert_eq!(t.pmf(0, p, Vec3::ZERO), 1.0);
    }

    #[test]
    fn deep_trees_fall_back_to_the_median_and_fit_the_trail() {
        // Exponentially spaced powers along a line drive the heuristic to unbalanced splits.
        let lights: Vec<LightBounds> = (0..5000)
            .map(|i| tri_light(Vec3::new(i as f32 * 1e-3, 0.0, 0.0), Vec3::Y, (i as f32 * 0.01).exp()))
            .collect();
        let idx: Vec<u32> = (0..lights.len() as u32).collect();
        let t = LightTree::build(&lights, &idx);
        assert!(t.depth() <= 32, "depth {}", t.depth());
        let sum: f64 = (0..lights.len()).map(|k| t.pmf(k, Vec3::new(2.5, 1.0, 0.0), Vec3::NEG_Y) as f64).sum();
        assert!((sum - 1.0).abs() < 1e-3, "Σ pmf = {sum}");
    }
}
