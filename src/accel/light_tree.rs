//! The light tree (`--light-select tree`): a BVH over every emitter with a position — triangles, spheres, quads,
//! point and spot lights — whose nodes carry their lights' total power, bounds and an orientation cone, so that
//! the probability of choosing a light depends on the shading point (Conty Estevez & Kulla 2018, as pbrt-v4's
//! `BVHLightSampler` uses it). Built here on the CPU; shaders/lights.wgsl descends it. The infinite lights
//! (directional, environment) have no position: each is chosen with the same probability as the whole tree.
//!
//! The importance of a node seen from p with normal n (pbrt-v4's `LightBounds::Importance`):
//! φ · cos θ' / d² · cos θ'ᵢ, where d is the distance to the bounds' centre (at least their radius), θ' the angle
//! between the cone's axis and the direction to p less the cone's spread θo and the angle θb the bounds subtend
//! (0 past the emission spread θe), and θ'ᵢ the angle between n and the direction to the bounds less θb. It
//! bounds the light's contribution from above up to a factor, and is 0 only where every light below emits
//! nothing towards p, so no light that can reach p gets probability 0.
//!
//! The pmf of one light from p is the product of the child probabilities on its root-to-leaf path; each light
//! stores that path as bits (`tree_trail`, bit k = the second child at depth k), so the pmf of a light found by a
//! BSDF sample costs one walk down, as the sampling did. The split is by a surface-area-orientation heuristic
//! over 12 buckets (pbrt-v4), falling back to the median where a deeper split could overflow the 32 trail bits.

use bytemuck::{Pod, Zeroable};
use glam::Vec3;

/// Marks a leaf in `GpuLightNode::second`.
pub const LEAF: u32 = 0xffff_ffff;
/// Trail bits: a leaf is at most this deep. The heuristic splits a node only while its lights still fit below it
/// when split at the median from there on (depth + ⌈log2 n⌉ < 32).
const MAX_DEPTH: u32 = 32;
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

/// One node as the GPU reads it (WGSL `LightNode`). Interior nodes: the first child is the next node, the second at
/// `second`. Leaves: `second` = [`LEAF`] and `light` is the light's index in the light table.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct GpuLightNode {
    pub lo: [f32; 3],
    pub phi: f32,
    pub hi: [f32; 3],
    pub second: u32,
    pub axis: [f32; 3],
    pub cos_o: f32,
    pub cos_e: f32,
    pub light: u32,
    pub two_sided: u32,
    /// Lights below this node.
    pub count: u32,
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

    fn to_gpu(self, second: u32, light: u32, count: u32) -> GpuLightNode {
        GpuLightNode {
            lo: self.lo.into(),
            phi: self.phi,
            hi: self.hi.into(),
            second,
            axis: self.axis.into(),
            cos_o: self.cos_o,
            cos_e: self.cos_e,
            light,
            two_sided: self.two_sided as u32,
            count,
        }
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

/// The importance of a node seen from p with surface normal n (module docs). The same arithmetic, in the same
/// order, as `light_node_importance` in shaders/lights.wgsl (f32 both), so CPU and GPU pmfs agree closely.
pub fn importance(node: &GpuLightNode, p: Vec3, n: Vec3) -> f32 {
    let (lo, hi) = (Vec3::from(node.lo), Vec3::from(node.hi));
    let pc = 0.5 * (lo + hi);
    let r2 = 0.25 * (hi - lo).length_squared();
    let d2 = (p - pc).length_squared().max(r2);
    let to_p = p - pc;
    let wi = if to_p.length_squared() > 0.0 { to_p.normalize() } else { Vec3::Z };
    let mut cos_w = Vec3::from(node.axis).dot(wi);
    if node.two_sided != 0 {
        cos_w = cos_w.abs();
    }
    let sin_w = safe_sqrt(1.0 - cos_w * cos_w);
    // The cone of directions from p to the bounds' bounding sphere.
    let (sin_b, cos_b) = if (p - pc).length_squared() < r2 {
        (0.0, -1.0)
    } else {
        let s2 = r2 / (p - pc).length_squared();
        (safe_sqrt(s2), safe_sqrt(1.0 - s2))
    };
    let sin_o = safe_sqrt(1.0 - node.cos_o * node.cos_o);
    let cos_x = cos_sub_clamped(sin_w, cos_w, sin_o, node.cos_o);
    let sin_x = sin_sub_clamped(sin_w, cos_w, sin_o, node.cos_o);
    let cos_p = cos_sub_clamped(sin_x, cos_x, sin_b, cos_b);
    if cos_p <= node.cos_e {
        return 0.0;
    }
    let mut imp = node.phi * cos_p / d2;
    if n != Vec3::ZERO {
        let cos_i = wi.dot(n).abs();
        let sin_i = safe_sqrt(1.0 - cos_i * cos_i);
        imp *= cos_sub_clamped(sin_i, cos_i, sin_b, cos_b);
    }
    imp.max(0.0)
}

/// The probability of descending into the first of two children: by importance, or by power where neither has
/// any (conservative bounds can give a node importance whose children both have none: descending by power
/// there keeps Σ pmf = 1 at every point, at the cost of a wasted sample where no light reaches p anyway).
pub fn first_child_probability(c0: &GpuLightNode, c1: &GpuLightNode, p: Vec3, n: Vec3) -> f32 {
    let (i0, i1) = (importance(c0, p, n), importance(c1, p, n));
    if i0 + i1 > 0.0 {
        return i0 / (i0 + i1);
    }
    if c0.phi + c1.phi > 0.0 {
        return c0.phi / (c0.phi + c1.phi);
    }
    0.5
}

impl LightTree {
    /// Builds the tree over `lights` (index k of the input = `light_index[k]` in the light table), every one of
    /// them: the root's `count` is how many lights of the table the tree covers.
    pub fn build(lights: &[LightBounds], light_index: &[u32]) -> LightTree {
        let mut tree = LightTree { nodes: vec![], trails: vec![0; lights.len()] };
        let mut items: Vec<usize> = (0..lights.len()).collect();
        if !items.is_empty() {
            tree.build_node(lights, light_index, &mut items, 0, 0);
        }
        tree
    }

    fn build_node(&mut self, lights: &[LightBounds], index: &[u32], items: &mut [usize], depth: u32, trail: u32) {
        let bounds = items.iter().skip(1).fold(lights[items[0]], |b, &k| b.union(&lights[k]));
        let me = self.nodes.len();
        if items.len() == 1 {
            let k = items[0];
            self.trails[k] = trail;
            self.nodes.push(bounds.to_gpu(LEAF, index[k], 1));
            return;
        }
        self.nodes.push(bounds.to_gpu(0, 0, items.len() as u32));
        let fits = depth + items.len().next_power_of_two().trailing_zeros() < MAX_DEPTH;
        let mid = if fits { split_saoh(lights, items, &bounds) } else { None };
        let mid = mid.unwrap_or_else(|| split_median(lights, items, &bounds));
        let (a, b) = items.split_at_mut(mid);
        self.build_node(lights, index, a, depth + 1, trail);
        self.nodes[me].second = self.nodes.len() as u32;
        self.build_node(lights, index, b, depth + 1, trail | (1u32 << depth));
    }

    /// The probability that the tree picks its light with input index k from (p, n). f32 like the GPU.
    pub fn pmf(&self, k: usize, p: Vec3, n: Vec3) -> f32 {
        pmf(&self.nodes, self.trails[k], p, n)
    }

    /// Every leaf's light-table index, with its input index, for tests.
    pub fn leaves(&self) -> Vec<u32> {
        self.nodes.iter().filter(|n| n.second == LEAF).map(|n| n.light).collect()
    }

    /// Depth of the deepest leaf.
    pub fn depth(&self) -> u32 {
        fn walk(t: &LightTree, i: usize) -> u32 {
            let n = &t.nodes[i];
            if n.second == LEAF {
                return 0;
            }
            1 + walk(t, i + 1).max(walk(t, n.second as usize))
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
/// shaders/lights.wgsl, which also includes the probability of choosing the tree over the infinite lights.
pub fn pmf(nodes: &[GpuLightNode], mut trail: u32, p: Vec3, n: Vec3) -> f32 {
    if nodes.is_empty() {
        return 0.0;
    }
    let mut i = 0usize;
    let mut pmf = 1.0f32;
    while nodes[i].second != LEAF {
        let p0 = first_child_probability(&nodes[i + 1], &nodes[nodes[i].second as usize], p, n);
        if trail & 1 == 0 {
            pmf *= p0;
            i += 1;
        } else {
            pmf *= 1.0 - p0;
            i = nodes[i].second as usize;
        }
        trail >>= 1;
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
    let (clo, chi) = items.iter().fold((Vec3::splat(f32::MAX), Vec3::splat(f32::MIN)), |(lo, hi), &k| {
        let c = lights[k].centroid();
        (lo.min(c), hi.max(c))
    });
    let extent = bounds.hi - bounds.lo;
    let mut best: Option<(f32, usize, usize)> = None;
    for axis in 0..3 {
        let span = chi[axis] - clo[axis];
        if !(span > 0.0) {
            continue;
        }
        let bucket_of = |k: usize| {
            let t = (lights[k].centroid()[axis] - clo[axis]) / span;
            ((t * BUCKETS as f32) as usize).min(BUCKETS - 1)
        };
        let mut buckets: [Option<LightBounds>; BUCKETS] = [None; BUCKETS];
        for &k in items.iter() {
            let b = bucket_of(k);
            buckets[b] = Some(buckets[b].map_or(lights[k], |x| x.union(&lights[k])));
        }
        for split in 1..BUCKETS {
            let merge = |r: std::ops::Range<usize>| r.filter_map(|i| buckets[i]).reduce(|a, b| a.union(&b));
            let (Some(a), Some(b)) = (merge(0..split), merge(split..BUCKETS)) else { continue };
            let cost = saoh_cost(&a, extent, axis) + saoh_cost(&b, extent, axis);
            if best.is_none_or(|(c, _, _)| cost < c) {
                best = Some((cost, axis, split));
            }
        }
    }
    let (_, axis, split) = best?;
    let span = chi[axis] - clo[axis];
    let left = |k: &usize| {
        let t = (lights[*k].centroid()[axis] - clo[axis]) / span;
        ((t * BUCKETS as f32) as usize).min(BUCKETS - 1) < split
    };
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
