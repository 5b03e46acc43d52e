//! An 8-wide BVH with child boxes quantised to 8 bits (Ylitie, Karras, Laine 2017, "Efficient Incoherent Ray
//! Traversal on GPUs Through Compressed Wide BVHs"), collapsed from the BVH2 of [`crate::accel::bvh`]. One node
//! is 80 bytes (five vec4 loads on the GPU) and tests eight boxes, so a ray makes fewer node steps; storage-buffer
//! loads dominate a BVH sample on lavapipe (docs/profile-bvh.md).
//!
//! Layout ([`GpuWideNode`], WGSL `WideNode` in `shaders/bvh_wide.wgsl`):
//! - `head`: the node's origin `p` (f32 bits, xyz) and, in w, the three biased exponents of the per-axis
//!   power-of-two scale `s = 2^(e − 127)` (bytes 0–2) and `imask` (byte 3: bit i set = slot i is an interior node);
//! - `links`: `child_base` (index of the first interior child; interior children follow in slot order),
//!   `tri_base` (index into `prim_refs` of the first primitive of the leaf children), and the eight `meta` bytes;
//! - `q_lo_xy`, `q_lo_z_hi_x`, `q_hi_yz`: per slot and axis, 8-bit `q` with the child's box edge at `p + s·q`
//!   (words hold slots 0–3, then 4–7, one byte each).
//!
//! `meta` of a slot: 0 = empty; `24 + slot` = interior; `count << 5 | offset` = a leaf over
//! `prim_refs[tri_base + offset ..][..count]` (count 1..=4, offset + count ≤ 24: the traversal keeps one hit bit per
//! primitive in bits 0–23 and one per interior slot in bits 24–31).
//!
//! Slots are ordered by position: bit k of a child's slot is set when the child lies on the + side of axis k of its
//! parent. A ray visits slot `rank ^ octant` at `rank` = 0, 1, …, 7, with bit k of `octant` set where the direction
//! is negative: near children first without sorting by distance.
//!
//! Quantisation is conservative: the decoded box, evaluated in f32 (`p + s·q`; `s·q` is exact, so an fma gives the
//! same bits), contains the child's box. The shader's slab test works in the node's frame instead (t = q·s/d +
//! (p − o)/d) and widens each plane by a bound on that form's roundings (`wide_node_hits`), so the wide tree finds
//! the same closest hits.

use glam::Vec3;

use crate::accel::aabb::Aabb;
use crate::accel::bvh::{self, Bvh, GpuBvhNode, Presplit, BVH_STACK_SIZE, EMPTY_CHILD, MAX_LEAF_PRIMS};
use crate::accel::quantise::{quantise, scale_exponent};
use crate::gpu::types::{GpuQuad, GpuSphere};

pub use crate::accel::wide_node::{GpuWideNode, WideChild, MAX_NODE_PRIMS, WIDTH};

/// Most wide levels: the traversal stack holds at most two entries per level (the rest of a node group and a
/// postponed leaf group), so `2 · depth ≤ BVH_STACK_SIZE`.
pub const MAX_WIDE_DEPTH: usize = BVH_STACK_SIZE / 2;

/// A BVH2 child: what the collapse moves between nodes. A leaf holds its primitive references themselves (up to
/// [`MAX_LEAF_PRIMS`]): a small BVH2 subtree becomes one leaf, whose references need not be contiguous there.
#[derive(Clone, Copy)]
enum Child {
    Leaf { refs: [u32; MAX_LEAF_PRIMS as usize], count: u32, bx: Aabb },
    Interior { node: u32, bx: Aabb },
}

impl Child {
    fn bx(&self) -> Aabb {
        match *self {
            Child::Leaf { bx, .. } | Child::Interior { bx, .. } => bx,
        }
    }
}

/// The BVH2 being collapsed, with the primitive count of every node's subtree.
struct Bvh2View<'a> {
    nodes: &'a [GpuBvhNode],
    prim_refs: &'a [u32],
    subtree_prims: Vec<u32>,
}

impl<'a> Bvh2View<'a> {
    fn new(bvh: &'a Bvh) -> Self {
        let nodes = &bvh.nodes;
        // The flattened BVH2 is in depth-first preorder (children after their parent), so a reverse sweep over the
        // indices sees every child before its parent.
        let mut subtree_prims = vec![0u32; nodes.len()];
        for i in (0..nodes.len()).rev() {
            let n = &nodes[i];
            let mut total = 0u32;
            for (first, count) in [(n.l_first, n.l_count), (n.r_first, n.r_count)] {
                total = total.saturating_add(if count > 0 {
                    count
                } else if first != EMPTY_CHILD {
                    subtree_prims[first as usize]
                } else {
                    0
                });
            }
            subtree_prims[i] = total;
        }
        Bvh2View { nodes, prim_refs: &bvh.prim_refs, subtree_prims }
    }

    /// Appends the primitive references of node `i`'s subtree to `out` from `at`; returns the new length.
    fn gather(&self, i: u32, out: &mut [u32], mut at: u32) -> u32 {
        let n = &self.nodes[i as usize];
        for (first, count) in [(n.l_first, n.l_count), (n.r_first, n.r_count)] {
            if count > 0 {
                out[at as usize..(at + count) as usize]
                    .copy_from_slice(&self.prim_refs[first as usize..(first + count) as usize]);
                at += count;
            } else if first != EMPTY_CHILD {
                at = self.gather(first, out, at);
            }
        }
        at
    }
}

/// Keeps the first of equal references in `refs[..count]` (two pieces of a pre-split triangle, from BVH2 leaves
/// merged into one, need one test); returns the new count.
fn distinct(refs: &mut [u32], count: u32) -> u32 {
    let mut n = 0;
    for k in 0..count as usize {
        if !refs[..n].contains(&refs[k]) {
            refs[n] = refs[k];
            n += 1;
        }
    }
    n as u32
}

/// SAH cost of a node step (Ylitie et al. 2017, §4.1)...
const C_NODE: f64 = 1.0;
/// ... and of one primitive test: on lavapipe a node step (three 32-byte loads, eight box tests) costs about two
/// triangle tests (two loads and the watertight test). 0.3 and 1.0 rendered within 2 % of 0.5
/// (docs/profile-bvh.md, "BVH quality").
const C_PRIM: f64 = 0.5;

/// One side of a BVH2 node, as the collapse sees it.
#[derive(Clone, Copy)]
enum Side {
    Empty,
    /// A BVH2 leaf: `prim_refs[first..first + count]`.
    Leaf {
        first: u32,
        count: u32,
        bx: Aabb,
    },
    /// A BVH2 interior node.
    Node {
        node: u32,
        bx: Aabb,
    },
}

impl Side {
    fn bx(&self) -> Aabb {
        match *self {
            Side::Empty => Aabb::EMPTY,
            Side::Leaf { bx, .. } | Side::Node { bx, .. } => bx,
        }
    }
}

/// Marks a slot count whose best form is the subtree as one child (a leaf or one wide node).
const ONE_CHILD: u8 = u8::MAX;

/// The SAH-optimal collapse of Ylitie et al. 2017 (§4.1), by dynamic programming over the BVH2: for every BVH2
/// node n and j = 1..=8, `cost[n][j − 1]` is the least SAH cost of n's subtree as at most j children of a wide node
/// — as one child (a leaf of its primitives, or a wide node of its own whose children are its sides spread over all
/// eight slots), or its two sides spread over the j slots; a leaf holds at most [`MAX_LEAF_PRIMS`] primitives.
/// (Until 2026-12-04 the collapse was greedy — the interior child of largest area opened while there was room,
/// and every subtree of at most 4 primitives merged into one leaf; the costs decide both now, and the trees render
/// in 0.84–0.99× the time, docs/profile-bvh.md, "BVH quality".)
struct Collapse<'a> {
    view: &'a Bvh2View<'a>,
    /// Least cost of n's subtree in at most j slots.
    cost: Vec<[f64; WIDTH]>,
    /// `ONE_CHILD`, or the slots that go to n's left side (the rest to its right).
    choice: Vec<[u8; WIDTH]>,
    /// Whether n as one child is a leaf (else a wide node).
    as_leaf: Vec<bool>,
}

impl<'a> Collapse<'a> {
    fn sides(&self, n: u32) -> [Side; 2] {
        let g = &self.view.nodes[n as usize];
        [(g.lmin, g.lmax, g.l_first, g.l_count), (g.rmin, g.rmax, g.r_first, g.r_count)].map(
            |(lo, hi, first, count)| {
                let bx = Aabb { min: lo.into(), max: hi.into() };
                if count > 0 {
                    Side::Leaf { first, count, bx }
                } else if first != EMPTY_CHILD {
                    Side::Node { node: first, bx }
                } else {
                    Side::Empty
                }
            },
        )
    }

    /// Least cost of a side in at most j ≥ 1 slots.
    fn side_cost(&self, side: Side, j: usize) -> f64 {
        match side {
            Side::Empty => 0.0,
            Side::Leaf { count, bx, .. } => bx.half_area() * count as f64 * C_PRIM,
            Side::Node { node, .. } => self.cost[node as usize][j - 1],
        }
    }

    /// The two sides of n spread over at most j slots: least cost and the left side's share.
    fn spread(&self, n: u32, j: usize) -> (f64, u8) {
        match self.sides(n) {
            [Side::Empty, Side::Empty] => (0.0, 0),
            [l, Side::Empty] => (self.side_cost(l, j), j as u8),
            [Side::Empty, r] => (self.side_cost(r, j), 0),
            [l, r] => (1..j)
                .map(|k| (self.side_cost(l, k) + self.side_cost(r, j - k), k as u8))
                .fold((f64::INFINITY, 0), |a, b| if b.0 < a.0 { b } else { a }),
        }
    }

    fn new(view: &'a Bvh2View<'a>) -> Self {
        let len = view.nodes.len();
        let mut c = Collapse {
            view,
            cost: vec![[0.0; WIDTH]; len],
            choice: vec![[ONE_CHILD; WIDTH]; len],
            as_leaf: vec![false; len],
        };
        // Depth-first preorder: a reverse sweep sees every child before its parent.
        for n in (0..len as u32).rev() {
            let area = c.sides(n).iter().fold(Aabb::EMPTY, |a, s| a.union(&s.bx())).half_area();
            let i = n as usize;
            let prims = view.subtree_prims[i];
            let as_node = area * C_NODE + c.spread(n, WIDTH).0;
            let as_leaf = area * prims as f64 * C_PRIM;
            c.as_leaf[i] = prims <= MAX_LEAF_PRIMS && as_leaf <= as_node;
            let one = if c.as_leaf[i] { as_leaf } else { as_node };
            for j in 1..=WIDTH {
                let (spread, k) = if j > 1 { c.spread(n, j) } else { (f64::INFINITY, 0) };
                let (cost, choice) = if spread < one { (spread, k) } else { (one, ONE_CHILD) };
                c.cost[i][j - 1] = cost;
                c.choice[i][j - 1] = choice;
            }
        }
        c
    }

    /// Appends n's subtree in at most j slots to `out`, as the costs chose.
    fn emit(&self, n: u32, j: usize, bx: Aabb, out: &mut Vec<Child>) {
        let i = n as usize;
        match self.choice[i][j - 1] {
            ONE_CHILD if self.as_leaf[i] => {
                let mut refs = [0; MAX_LEAF_PRIMS as usize];
                let gathered = self.view.gather(n, &mut refs, 0);
                let count = distinct(&mut refs, gathered);
                out.push(Child::Leaf { refs, count, bx });
            }
            ONE_CHILD => out.push(Child::Interior { node: n, bx }),
            k => self.emit_sides(n, j, k as usize, out),
        }
    }

    /// Appends n's two sides, k slots for the left and j − k for the right, to `out`.
    fn emit_sides(&self, n: u32, j: usize, k: usize, out: &mut Vec<Child>) {
        let [l, r] = self.sides(n);
        for (side, slots) in [(l, k), (r, j - k)] {
            match side {
                Side::Empty => {}
                Side::Leaf { first, count, bx } => {
                    let mut refs = [0; MAX_LEAF_PRIMS as usize];
                    refs[..count as usize]
                        .copy_from_slice(&self.view.prim_refs[first as usize..(first + count) as usize]);
                    out.push(Child::Leaf { refs, count, bx });
                }
                Side::Node { node, bx } => self.emit(node, slots, bx, out),
            }
        }
    }

    /// The children of the wide node made from BVH2 node n: its sides spread over the eight slots — or over fewer
    /// where the leaves' primitives would not fit the 24 hit bits (at most 4 a leaf, so 6 slots always fit).
    fn children(&self, n: u32) -> Vec<Child> {
        let prims =
            |k: &[Child]| k.iter().map(|c| if let Child::Leaf { count, .. } = c { *count } else { 0 }).sum::<u32>();
        let mut kids = Vec::with_capacity(WIDTH);
        for j in (2..=WIDTH).rev() {
            kids.clear();
            let (_, k) = self.spread(n, j);
            self.emit_sides(n, j, k as usize, &mut kids);
            if prims(&kids) <= MAX_NODE_PRIMS {
                break;
            }
        }
        kids
    }
}

/// Slot of each child: bit k set = the child lies on the + side of axis k (by centroid, against the parent's).
/// Greedy on the score Σₖ ±(cₖ − pₖ): the best-matching (child, slot) pair first.
fn assign_slots(kids: &[Child]) -> [Option<usize>; WIDTH] {
    let centre = |b: &Aabb| (b.min.as_dvec3() + b.max.as_dvec3()) * 0.5;
    let parent = kids.iter().fold(Aabb::EMPTY, |a, c| a.union(&c.bx()));
    let pc = centre(&parent);
    let mut pairs = Vec::with_capacity(kids.len() * WIDTH);
    for (c, k) in kids.iter().enumerate() {
        let off = centre(&k.bx()) - pc;
        for s in 0..WIDTH {
            let sign = |axis: usize| if s >> axis & 1 == 1 { 1.0 } else { -1.0 };
            pairs.push((sign(0) * off.x + sign(1) * off.y + sign(2) * off.z, c, s));
        }
    }
    pairs.sort_by(|a, b| b.0.total_cmp(&a.0).then((a.1, a.2).cmp(&(b.1, b.2))));
    let mut slots = [None; WIDTH];
    let mut placed = vec![false; kids.len()];
    for (_, c, s) in pairs {
        if slots[s].is_none() && !placed[c] {
            slots[s] = Some(c);
            placed[c] = true;
        }
    }
    slots
}

/// [`bvh::build`] collapsed to the 8-wide compressed layout ([`widen`]). Where the wide tree of
/// the PLOC build would be too deep for the traversal stack, the median split's tree (depth ≤ 31 for any input
/// size the references allow) is widened instead.
pub fn build(tri_verts: &[[Vec3; 3]], spheres: &[GpuSphere], quads: &[GpuQuad], presplit: Presplit) -> Bvh {
    widen(&bvh::build(tri_verts, spheres, quads, presplit)).unwrap_or_else(|| {
        widen(&bvh::build_with(tri_verts, spheres, quads, presplit, true))
            .expect("a median-split tree is shallow enough to widen")
    })
}

/// The one BVH2 node a wide tree's [`Bvh`] keeps in `nodes`: an empty root (the binary traversal is not compiled
/// into pipelines that use the wide tree).
pub fn empty_bvh2_root() -> GpuBvhNode {
    GpuBvhNode {
        lmin: Aabb::EMPTY.min.into(),
        l_first: EMPTY_CHILD,
        lmax: Aabb::EMPTY.max.into(),
        l_count: 0,
        rmin: Aabb::EMPTY.min.into(),
        r_first: EMPTY_CHILD,
        rmax: Aabb::EMPTY.max.into(),
        r_count: 0,
    }
}

/// Collapses a BVH2 into the wide layout. The result is a [`Bvh`] whose `wide` holds the nodes (root first) and
/// whose `prim_refs` are in the wide tree's leaf order; its `nodes` is a single empty BVH2 root (the binary
/// traversal is not compiled into pipelines that use the wide tree). `None` if the wide tree would be deeper than
/// [`MAX_WIDE_DEPTH`] (the caller keeps the BVH2).
pub fn widen(bvh: &Bvh) -> Option<Bvh> {
    let start = web_time::Instant::now();
    let mut wide: Vec<GpuWideNode> = vec![GpuWideNode::default()];
    let mut refs: Vec<u32> = Vec::with_capacity(bvh.prim_refs.len());
    // (BVH2 node, wide node index, depth)
    let view = Bvh2View::new(bvh);
    let collapse = Collapse::new(&view);
    let mut todo = vec![(0u32, 0usize, 1usize)];
    let mut depth = 1;
    while let Some((src, dst, d)) = todo.pop() {
        depth = depth.max(d);
        if depth > MAX_WIDE_DEPTH {
            return None;
        }
        let kids = collapse.children(src);
        let slots = assign_slots(&kids);
        let parent = kids.iter().fold(Aabb::EMPTY, |a, c| a.union(&c.bx()));
        let mut node = GpuWideNode::default();
        let mut e = [1u32; 3];
        if !kids.is_empty() {
            for k in 0..3 {
                node.head[k] = parent.min[k].to_bits();
                e[k] = scale_exponent(parent.min[k], parent.max[k]);
            }
        }
        let (p, _) = node.frame();
        let s = Vec3::from_array(e.map(|e| f32::from_bits(e << 23)));
        let mut imask = 0u32;
        let child_base = wide.len() as u32;
        let tri_base = refs.len() as u32;
        let mut bytes = [[0u32; WIDTH]; 7]; // meta, lo x/y/z, hi x/y/z
        for (slot, c) in slots.iter().enumerate() {
            let Some(c) = *c else { continue };
            let kid = kids[c];
            let bx = kid.bx();
            for k in 0..3 {
                let (lo, hi) = quantise(p[k], s[k], bx.min[k], bx.max[k]);
                bytes[1 + k][slot] = lo;
                bytes[4 + k][slot] = hi;
            }
            bytes[0][slot] = match kid {
                Child::Leaf { refs: prims, count, .. } => {
                    let offset = refs.len() as u32 - tri_base;
                    debug_assert!(count <= MAX_LEAF_PRIMS && offset + count <= MAX_NODE_PRIMS);
                    refs.extend_from_slice(&prims[..count as usize]);
                    count << 5 | offset
                }
                Child::Interior { node: n, .. } => {
                    imask |= 1 << slot;
                    let idx = wide.len();
                    wide.push(GpuWideNode::default());
                    todo.push((n, idx, d + 1));
                    24 + slot as u32
                }
            };
        }
        let pack = |b: &[u32; WIDTH], half: usize| (0..4).fold(0u32, |w, i| w | b[4 * half + i] << (8 * i));
        node.head[3] = e[0] | e[1] << 8 | e[2] << 16 | imask << 24;
        node.links = [child_base, tri_base, pack(&bytes[0], 0), pack(&bytes[0], 1)];
        node.q_lo_xy = [pack(&bytes[1], 0), pack(&bytes[1], 1), pack(&bytes[2], 0), pack(&bytes[2], 1)];
        node.q_lo_z_hi_x = [pack(&bytes[3], 0), pack(&bytes[3], 1), pack(&bytes[4], 0), pack(&bytes[4], 1)];
        node.q_hi_yz = [pack(&bytes[5], 0), pack(&bytes[5], 1), pack(&bytes[6], 0), pack(&bytes[6], 1)];
        wide[dst] = node;
    }
    Some(Bvh {
        nodes: vec![empty_bvh2_root()],
        prim_refs: refs,
        wide,
        build_seconds: bvh.build_seconds + start.elapsed().as_secs_f64(),
        sah_cost: bvh.sah_cost,
    })
}

/// Depth of a wide tree (root = 1).
pub fn depth(wide: &[GpuWideNode]) -> usize {
    let mut max = 0;
    let mut stack = vec![(0u32, 1usize)];
    while let Some((n, d)) = stack.pop() {
        max = max.max(d);
        for i in 0..WIDTH {
            if let WideChild::Interior(c) = wide[n as usize].child(i) {
                stack.push((c, d + 1));
            }
        }
    }
    max
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::accel::bvh;

    /// Triangles scattered in clusters of varied size, so that the BVH2 has unbalanced subtrees.
    fn scattered(n: usize) -> Vec<[Vec3; 3]> {
        let mut state = 0x9e3779b97f4a7c15u64;
        let mut next = || {
            state = state.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
            (state >> 40) as f32 / (1u64 << 24) as f32
        };
        (0..n)
            .map(|i| {
                let c = Vec3::new((i % 7) as f32 * 3.0, (i % 5) as f32 * 0.5, (i % 3) as f32 * 8.0);
                let p = c + Vec3::new(next(), next(), next()) * (1 + i % 4) as f32;
                [p, p + Vec3::new(next(), 0.1, 0.0), p + Vec3::new(0.0, next(), 0.2)]
            })
            .collect()
    }

    /// The SAH cost of the collapsed wide tree as built: C_NODE · area for every wide node below the root's
    /// children, C_PRIM · area · count for every leaf, from the same BVH2 boxes the collapse used.
    fn emitted_cost(c: &Collapse, n: u32) -> f64 {
        c.children(n)
            .iter()
            .map(|k| match *k {
                Child::Leaf { count, bx, .. } => bx.half_area() * count as f64 * C_PRIM,
                Child::Interior { node, bx } => bx.half_area() * C_NODE + emitted_cost(c, node),
            })
            .sum()
    }

    #[test]
    fn collapse_builds_the_tree_its_costs_describe() {
        let tris = scattered(600);
        let b2 = bvh::build(&tris, &[], &[], bvh::Presplit::Off);
        let view = Bvh2View::new(&b2);
        let c = Collapse::new(&view);
        for n in 0..b2.nodes.len() {
            // More slots never cost more; only a subtree that fits a leaf is one.
            assert!(c.cost[n].windows(2).all(|w| w[1] <= w[0]), "node {n}: {:?}", c.cost[n]);
            assert!(!c.as_leaf[n] || view.subtree_prims[n] <= MAX_LEAF_PRIMS);
        }
        let (optimum, _) = c.spread(0, WIDTH);
        let built = emitted_cost(&c, 0);
        assert!((built - optimum).abs() <= 1e-9 * optimum, "built {built} against the optimum {optimum}");
        // No wide node holds more leaf primitives than its hit bits, and every reference lands in one leaf.
        let wide = widen(&b2).expect("shallow enough");
        let mut refs = wide.prim_refs.clone();
        refs.sort_unstable();
        assert_eq!(refs, (0..tris.len() as u32).collect::<Vec<_>>());
    }

    /// Against an exhaustive search: every wide tree the BVH2 allows (each wide node's children a cut of its
    /// subtree of at most eight units, a unit a leaf of at most four primitives or a wide node of its own).
    #[test]
    fn collapse_is_optimal_on_a_small_tree() {
        /// A unit of a cut: a side as one leaf, or (`wide`) a BVH2 interior node as a wide node.
        type Unit = (Side, bool);
        fn unit_cost(c: &Collapse, (s, wide): Unit) -> f64 {
            match s {
                Side::Empty => 0.0,
                Side::Leaf { count, bx, .. } => bx.half_area() * count as f64 * C_PRIM,
                Side::Node { node, bx } if wide => bx.half_area() * C_NODE + best(c, node),
                Side::Node { node, bx } => bx.half_area() * c.view.subtree_prims[node as usize] as f64 * C_PRIM,
            }
        }
        // Every cut of a side's subtree into units.
        fn cuts(c: &Collapse, s: Side) -> Vec<Vec<Unit>> {
            match s {
                Side::Node { node, .. } => {
                    let mut out = vec![vec![(s, true)]];
                    if c.view.subtree_prims[node as usize] <= MAX_LEAF_PRIMS {
                        out.push(vec![(s, false)]);
                    }
                    out.extend(spreads(c, node));
                    out
                }
                _ => vec![vec![(s, false)]],
            }
        }
        fn spreads(c: &Collapse, n: u32) -> Vec<Vec<Unit>> {
            let [l, r] = c.sides(n);
            let mut out = Vec::new();
            for a in cuts(c, l) {
                for b in cuts(c, r) {
                    let u: Vec<Unit> = a.iter().chain(&b).copied().filter(|u| !matches!(u.0, Side::Empty)).collect();
                    if u.len() <= WIDTH {
                        out.push(u);
                    }
                }
            }
            out
        }
        // The least cost of the children of a wide node made from BVH2 node n.
        fn best(c: &Collapse, n: u32) -> f64 {
            spreads(c, n).iter().map(|u| u.iter().map(|&s| unit_cost(c, s)).sum::<f64>()).fold(f64::INFINITY, f64::min)
        }
        for (n, skip) in [(12, 0), (18, 3)] {
            let tris: Vec<_> = scattered(n + skip).into_iter().skip(skip).collect();
            let b2 = bvh::build(&tris, &[], &[], bvh::Presplit::Off);
            let view = Bvh2View::new(&b2);
            let c = Collapse::new(&view);
            let (dp, _) = c.spread(0, WIDTH);
            let exhaustive = best(&c, 0);
            assert!((dp - exhaustive).abs() <= 1e-9 * exhaustive, "{n} triangles: {dp} against {exhaustive}");
        }
    }
}
