//! BVH over triangles, spheres and quads: built on the CPU with obvhs (PLOC + reinsertion), flattened to the
//! two-boxes-per-node layout that `shaders/bvh.wgsl` traverses; `crate::accel::wide_bvh::build` collapses it further into
//! the 8-wide compressed layout (the renderer's default).
//!
//! Layout ([`GpuBvhNode`], WGSL `BvhNode`): every node stores the boxes of *both* children, so a traversal step
//! tests two boxes from one 64-byte load and never fetches a child just to reject it. For each child:
//! - `count > 0`: a leaf over `prim_refs[first .. first + count]`;
//! - `count == 0 && first != EMPTY_CHILD`: an interior node `nodes[first]`;
//! - `count == 0 && first == EMPTY_CHILD` (= `0xffffffff`): no child. Its box is inverted (min = +MAX,
//!   max = -MAX); traversal skips it by the flag, not the box. Only the root uses it: a single-leaf tree is a root
//!   whose left child is that leaf and whose right child is empty, and an empty scene is a root with two empty
//!   children (so the node buffer is never empty).
//!
//! The root is `nodes[0]`; nodes are in depth-first preorder (a left child directly follows its parent).
//! Primitive references are `kind << 30 | index` ([`crate::gpu::types::make_prim`]).

use web_time::Instant;

use bytemuck::{Pod, Zeroable};
use glam::{DVec3, Vec3, Vec3A};

pub use crate::accel::aabb::{quad_aabb, sphere_aabb, triangle_aabb, Aabb};
use crate::accel::presplit::{self, Piece};
use crate::accel::wide_node::GpuWideNode;
use crate::gpu::types::{
    make_prim, GpuQuad, GpuSphere, INVALID, PRIM_INDEX_MASK, PRIM_KIND_SHIFT, PRIM_QUAD, PRIM_SPHERE, PRIM_TRIANGLE,
};

/// A BVH2 node with both children's boxes (WGSL `BvhNode`, same field names). See the module docs for the
/// meaning of `*_first` / `*_count`.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct GpuBvhNode {
    pub lmin: [f32; 3],
    pub l_first: u32,
    pub lmax: [f32; 3],
    pub l_count: u32,
    pub rmin: [f32; 3],
    pub r_first: u32,
    pub rmax: [f32; 3],
    pub r_count: u32,
}

/// `first` of an absent child (with `count == 0`).
pub const EMPTY_CHILD: u32 = INVALID;

/// Entries of the fixed traversal stack in `bvh.wgsl` (`BVH_STACK_SIZE`). [`build`] guarantees that the tree
/// depth (root = 1) never exceeds it, so the stack cannot overflow.
pub const BVH_STACK_SIZE: usize = 64;

/// Most primitives in one leaf (the leaf collapse of obvhs stops there).
pub const MAX_LEAF_PRIMS: u32 = 4;
// The traversal packs a leaf into one word with 3 bits of count (shaders/bvh.wgsl `bvh_child_ref`).
const _: () = assert!(MAX_LEAF_PRIMS <= 8);

/// A built, flattened BVH, ready to upload (`nodes` → binding 0, `prim_refs` → binding 1 of
/// `geometry_bindings.wgsl`).
#[derive(Clone, Debug, Default)]
pub struct Bvh {
    /// Nodes, root first; never empty.
    pub nodes: Vec<GpuBvhNode>,
    /// Primitive references (`kind << 30 | index`) in leaf order; excluded primitives are absent.
    pub prim_refs: Vec<u32>,
    /// The 8-wide compressed nodes ([`crate::accel::wide_bvh::widen`]), root first; empty for the binary layout.
    /// When not empty, they are the tree (`nodes` is then one empty root) and `prim_refs` are in their leaf order.
    pub wide: Vec<GpuWideNode>,
    /// Wall-clock time of [`build`] (boxes, obvhs, flattening).
    pub build_seconds: f64,
    /// SAH cost (traversal cost 1, intersection cost 1, areas relative to the root box); 0 for an empty tree.
    pub sah_cost: f32,
}

impl Bvh {
    /// Node count.
    pub fn node_count(&self) -> usize {
        self.nodes.len()
    }

    /// Bytes of `nodes` + `prim_refs` + `wide` per triangle in the tree (0 if it holds no triangles).
    pub fn bytes_per_triangle(&self) -> f64 {
        let tris = self.prim_refs.iter().filter(|&&r| r >> PRIM_KIND_SHIFT == PRIM_TRIANGLE).count();
        if tris == 0 {
            return 0.0;
        }
        let bytes = std::mem::size_of_val(self.nodes.as_slice())
            + std::mem::size_of_val(self.prim_refs.as_slice())
            + std::mem::size_of_val(self.wide.as_slice());
        bytes as f64 / tris as f64
    }

    /// Depth of the node tree (root = 1): the traversal stack needs at most `depth - 1` entries.
    pub fn depth(&self) -> usize {
        let mut max = 0;
        let mut stack = vec![(0u32, 1usize)];
        while let Some((n, d)) = stack.pop() {
            max = max.max(d);
            let node = &self.nodes[n as usize];
            for (first, count) in [(node.l_first, node.l_count), (node.r_first, node.r_count)] {
                if count == 0 && first != EMPTY_CHILD {
                    stack.push((first, d + 1));
                }
            }
        }
        max
    }
}

/// Renumbers the triangles in the order the leaves reference them, one new triangle per reference: a pre-split
/// triangle ([`crate::accel::presplit`]) referenced from several leaves becomes as many copies. Returns `order`
/// with `order[new] = old`: every reference's triangle, then those the tree excludes (degenerate ones); each old
/// triangle appears at least once. The caller permutes every per-triangle array by it. In a triangle-only scene
/// `prim_refs[j] == j` afterwards, so traversal reads a leaf's triangles directly (`shaders/bvh.wgsl`: three vertex
/// loads per test instead of four); in mixed scenes the triangle references are rewritten to the new indices.
pub fn into_leaf_order(bvh: &mut Bvh, tri_count: usize) -> Vec<u32> {
    let mut referenced = vec![false; tri_count];
    let mut order = Vec::with_capacity(tri_count);
    for r in bvh.prim_refs.iter_mut() {
        if *r >> PRIM_KIND_SHIFT == PRIM_TRIANGLE {
            let old = (*r & PRIM_INDEX_MASK) as usize;
            referenced[old] = true;
            *r = make_prim(PRIM_TRIANGLE, order.len() as u32);
            order.push(old as u32);
        }
    }
    order.extend((0..tri_count as u32).filter(|&old| !referenced[old as usize]));
    order
}

/// obvhs build settings: its "slow" preset's PLOC search (24 neighbours), without obvhs's own pre-splits (mislab
/// splits before, with conservative boxes: [`crate::accel::presplit`]), with leaves of at most 4 primitives
/// collapsed by the SAH with traversal cost 1 (our node tests two boxes per fetch; an intersection costs about as
/// much). Reinsertion (moving subtrees to where they lower the SAH) starts from every node, before and after the
/// leaf collapse, not the preset's 20 %: the build takes 2.5–3× as long (1M triangles: 2.3 → 6.9 s) and the trees
/// render 0.86–1.0× the time (docs/profile-bvh.md, "BVH quality").
/// obvhs's `build_bvh2` (PLOC, reinsertion, leaf collapse, reinsertion) without its timer: std's clock does not
/// exist in a browser (wasm32), and the caller times the build itself.
fn build_bvh2(aabbs: &[obvhs::aabb::Aabb], config: obvhs::BvhBuildParams) -> obvhs::bvh2::Bvh2 {
    use obvhs::bvh2::{leaf_collapser::collapse, reinsertion::ReinsertionOptimizer};
    let indices = (0..aabbs.len() as u32).collect();
    let mut bvh2 = obvhs::ploc::PlocBuilder::with_capacity(aabbs.len()).build(
        config.ploc_search_distance,
        aabbs,
        indices,
        config.sort_precision,
        config.search_depth_threshold,
    );
    let mut reinsertion = ReinsertionOptimizer::default();
    reinsertion.run(&mut bvh2, config.reinsertion_batch_ratio, None);
    collapse(&mut bvh2, config.max_prims_per_leaf.clamp(1, 255), config.collapse_traversal_cost);
    let ratio = config.reinsertion_batch_ratio * config.post_collapse_reinsertion_batch_ratio_multiplier;
    reinsertion.run(&mut bvh2, ratio, None);
    bvh2
}

fn build_params() -> obvhs::BvhBuildParams {
    obvhs::BvhBuildParams {
        pre_split: false,
        ploc_search_distance: obvhs::ploc::PlocSearchDistance::High,
        search_depth_threshold: 2,
        reinsertion_batch_ratio: 1.0,
        post_collapse_reinsertion_batch_ratio_multiplier: 1.0,
        sort_precision: obvhs::ploc::SortPrecision::U64,
        max_prims_per_leaf: MAX_LEAF_PRIMS,
        collapse_traversal_cost: 1.0,
    }
}

/// A builder-independent binary tree: `count > 0` is a leaf over `order[first..first + count]`, otherwise an
/// interior node with children `left`, `right` (indices into the same list). Root at 0.
#[derive(Clone, Copy)]
struct TmpNode {
    left: u32,
    right: u32,
    first: u32,
    count: u32,
}

/// Which triangles [`build`] may reference in pieces ([`crate::accel::presplit`]).
#[derive(Clone, Copy, Debug)]
pub enum Presplit<'a> {
    /// None: one reference per triangle.
    Off,
    /// The large ones, except where `keep_whole[i]` is true (emitters: a shadow ray towards a point on an
    /// emissive triangle skips that triangle by its index, which a copy would not have). `&[]`: any.
    Large { keep_whole: &'a [bool] },
}

/// Builds the BVH over all primitives. Triangles are given by their three vertices (the same values, and order,
/// as in the `tri_verts` buffer); excluded primitives (see [`triangle_aabb`], [`sphere_aabb`], [`quad_aabb`]) are
/// not in the tree and can never be hit. With [`Presplit::Large`], large triangles are referenced in pieces
/// (docs/profile-bvh.md, "Large triangles in pieces", has its measurement): a triangle may then be in several leaves, never twice in one.
/// Panics if a kind has more than 2^30 primitives.
pub fn build(tri_verts: &[[Vec3; 3]], spheres: &[GpuSphere], quads: &[GpuQuad], presplit: Presplit) -> Bvh {
    build_with(tri_verts, spheres, quads, presplit, false)
}

/// [`build`], or with `median` the median split's tree (shallow for any input: `wide_bvh::build` falls back to it).
pub(crate) fn build_with(
    tri_verts: &[[Vec3; 3]],
    spheres: &[GpuSphere],
    quads: &[GpuQuad],
    presplit: Presplit,
    median: bool,
) -> Bvh {
    let start = Instant::now();
    for n in [tri_verts.len(), spheres.len(), quads.len()] {
        assert!(n as u64 <= PRIM_INDEX_MASK as u64 + 1, "a BVH holds at most 2^30 primitives of each kind");
    }
    // Included triangles, large ones in pieces (more references to the same triangle, each with a smaller box).
    let mut tris: Vec<Piece> = (0..tri_verts.len())
        .filter_map(|i| triangle_aabb(&tri_verts[i]).map(|bx| Piece { tri: i as u32, bx }))
        .collect();
    if let Presplit::Large { keep_whole } = presplit {
        let budget = (presplit::BUDGET * tris.len() as f64) as usize;
        let (split, mut kept): (Vec<Piece>, Vec<Piece>) =
            tris.into_iter().partition(|p| !keep_whole.get(p.tri as usize).is_some_and(|&k| k));
        kept.extend(presplit::split(&split, tri_verts, budget));
        tris = kept;
    }
    // Included primitives: their references and boxes.
    let mut refs: Vec<u32> = tris.iter().map(|p| make_prim(PRIM_TRIANGLE, p.tri)).collect();
    let mut boxes: Vec<Aabb> = tris.iter().map(|p| p.bx).collect();
    let mut add = |kind: u32, i: usize, b: Option<Aabb>| {
        if let Some(b) = b {
            refs.push(make_prim(kind, i as u32));
            boxes.push(b);
        }
    };
    spheres.iter().enumerate().for_each(|(i, s)| add(PRIM_SPHERE, i, sphere_aabb(s)));
    quads.iter().enumerate().for_each(|(i, q)| add(PRIM_QUAD, i, quad_aabb(q)));

    let (mut tmp, order) = if boxes.is_empty() {
        (Vec::new(), Vec::new())
    } else {
        let (tmp, order) = if median { build_median(&boxes) } else { build_obvhs(&boxes) };
        if tree_depth(&tmp) <= BVH_STACK_SIZE {
            (tmp, order)
        } else {
            // PLOC can make deep trees from pathological input (e.g. thousands of coincident primitives); a
            // median split has depth ~log2(n / 4) + 1, so the fixed GPU stack always suffices.
            build_median(&boxes)
        }
    };
    let order = distinct_in_leaves(&mut tmp, order, &refs);
    let mut bvh = flatten(&tmp, &order, &refs, &boxes);
    bvh.build_seconds = start.elapsed().as_secs_f64();
    bvh
}

/// Removes the second and later pieces of one triangle from each leaf (two pieces of a triangle may land in the
/// same leaf; one test finds it). Returns the new `order`; leaves' `first` and `count` are rewritten.
fn distinct_in_leaves(tmp: &mut [TmpNode], order: Vec<u32>, refs: &[u32]) -> Vec<u32> {
    let mut out = Vec::with_capacity(order.len());
    for t in tmp.iter_mut().filter(|t| t.count > 0) {
        let first = out.len();
        for &p in &order[t.first as usize..(t.first + t.count) as usize] {
            if !out[first..].iter().any(|&q: &u32| refs[q as usize] == refs[p as usize]) {
                out.push(p);
            }
        }
        (t.first, t.count) = (first as u32, (out.len() - first) as u32);
    }
    out
}

/// PLOC + reinsertion + SAH leaf collapse by obvhs, on boxes normalised to the scene's bounds (so that huge
/// coordinates cannot overflow its f32 cost sums). Only the topology is kept: boxes are recomputed exactly.
fn build_obvhs(boxes: &[Aabb]) -> (Vec<TmpNode>, Vec<u32>) {
    let scene = boxes.iter().fold(Aabb::EMPTY, |a, b| a.union(b));
    let (lo, hi) = (scene.min.as_dvec3(), scene.max.as_dvec3());
    let center = (lo + hi) * 0.5;
    let extent = (hi - lo).max_element();
    let scale = if extent > 0.0 && extent.is_finite() { 2.0 / extent } else { 1.0 };
    let norm = |p: Vec3| Vec3A::from(((p.as_dvec3() - center) * scale).as_vec3());
    let aabbs: Vec<obvhs::aabb::Aabb> =
        boxes.iter().map(|b| obvhs::aabb::Aabb::new(norm(b.min), norm(b.max))).collect();
    let bvh2 = build_bvh2(&aabbs, build_params());

    let mut tmp = Vec::with_capacity(bvh2.nodes.len());
    // obvhs: inner node children at first_index and first_index + 1; leaves index primitive_indices.
    // Renumber depth-first from the root (obvhs' node 0) into `tmp`.
    tmp.push(TmpNode { left: 0, right: 0, first: 0, count: 0 });
    let mut stack = vec![(0usize, 0usize)]; // (obvhs index, tmp index)
    while let Some((src, dst)) = stack.pop() {
        let n = &bvh2.nodes[src];
        if n.is_leaf() {
            tmp[dst] = TmpNode { left: 0, right: 0, first: n.first_index, count: n.prim_count };
        } else {
            let (l, r) = (tmp.len(), tmp.len() + 1);
            tmp.push(TmpNode { left: 0, right: 0, first: 0, count: 0 });
            tmp.push(TmpNode { left: 0, right: 0, first: 0, count: 0 });
            tmp[dst] = TmpNode { left: l as u32, right: r as u32, first: 0, count: 0 };
            stack.push((n.first_index as usize, l));
            stack.push((n.first_index as usize + 1, r));
        }
    }
    (tmp, bvh2.primitive_indices)
}

/// Top-down median split on the longest centroid axis; leaves of at most [`MAX_LEAF_PRIMS`]. The fallback
/// when the PLOC tree is too deep for the traversal stack.
fn build_median(boxes: &[Aabb]) -> (Vec<TmpNode>, Vec<u32>) {
    let mut order: Vec<u32> = (0..boxes.len() as u32).collect();
    let centroid = |i: u32| (boxes[i as usize].min.as_dvec3() + boxes[i as usize].max.as_dvec3()) * 0.5;
    let mut tmp = vec![TmpNode { left: 0, right: 0, first: 0, count: 0 }];
    let mut stack = vec![(0usize, 0usize, boxes.len())]; // (tmp index, range start, range end)
    while let Some((dst, a, b)) = stack.pop() {
        let n = b - a;
        if n <= MAX_LEAF_PRIMS as usize {
            tmp[dst] = TmpNode { left: 0, right: 0, first: a as u32, count: n as u32 };
            continue;
        }
        let (mut lo, mut hi) = (DVec3::splat(f64::MAX), DVec3::splat(f64::MIN));
        for &i in &order[a..b] {
            lo = lo.min(centroid(i));
            hi = hi.max(centroid(i));
        }
        let e = hi - lo;
        let axis = if e.x >= e.y && e.x >= e.z {
            0
        } else if e.y >= e.z {
            1
        } else {
            2
        };
        let mid = a + n / 2;
        order[a..b].select_nth_unstable_by(n / 2, |&i, &j| centroid(i)[axis].total_cmp(&centroid(j)[axis]));
        let (l, r) = (tmp.len(), tmp.len() + 1);
        tmp.push(TmpNode { left: 0, right: 0, first: 0, count: 0 });
        tmp.push(TmpNode { left: 0, right: 0, first: 0, count: 0 });
        tmp[dst] = TmpNode { left: l as u32, right: r as u32, first: 0, count: 0 };
        stack.push((l, a, mid));
        stack.push((r, mid, b));
    }
    (tmp, order)
}

/// Depth of the flattened tree a `TmpNode` tree becomes: interior nodes only (leaves live in their parent), and a
/// single-leaf tree still has its one root node.
fn tree_depth(tmp: &[TmpNode]) -> usize {
    let mut max = 1;
    let mut stack = vec![(0usize, 1usize)];
    while let Some((n, d)) = stack.pop() {
        max = max.max(d);
        let t = tmp[n];
        if t.count == 0 {
            for c in [t.left as usize, t.right as usize] {
                if tmp[c].count == 0 {
                    stack.push((c, d + 1));
                }
            }
        }
    }
    max
}

fn empty_child() -> ([f32; 3], [f32; 3]) {
    (Aabb::EMPTY.min.into(), Aabb::EMPTY.max.into())
}

/// Converts a `TmpNode` tree to the GPU layout, computing every box exactly from the primitives' boxes, and the
/// SAH cost on the way.
fn flatten(tmp: &[TmpNode], order: &[u32], refs: &[u32], boxes: &[Aabb]) -> Bvh {
    let (emin, emax) = empty_child();
    let empty_node = GpuBvhNode {
        lmin: emin,
        l_first: EMPTY_CHILD,
        lmax: emax,
        l_count: 0,
        rmin: emin,
        r_first: EMPTY_CHILD,
        rmax: emax,
        r_count: 0,
    };
    if tmp.is_empty() {
        return Bvh { nodes: vec![empty_node], ..Default::default() };
    }

    // Boxes bottom-up: children always have larger tmp indices than their parent, so a reverse sweep works.
    let mut tbox = vec![Aabb::EMPTY; tmp.len()];
    for i in (0..tmp.len()).rev() {
        let t = tmp[i];
        tbox[i] = if t.count > 0 {
            order[t.first as usize..(t.first + t.count) as usize]
                .iter()
                .fold(Aabb::EMPTY, |a, &p| a.union(&boxes[p as usize]))
        } else {
            tbox[t.left as usize].union(&tbox[t.right as usize])
        };
    }

    let mut nodes = Vec::with_capacity(tmp.len() / 2 + 1);
    let mut prim_refs = Vec::with_capacity(order.len());
    let root_area = tbox[0].half_area();
    let rel = |b: &Aabb| if root_area > 0.0 { b.half_area() / root_area } else { 1.0 };
    let mut sah = 0.0f64;

    if tmp[0].count > 0 {
        // Single leaf: the root's left child is the leaf, the right child empty.
        let t = tmp[0];
        let b = tbox[0];
        prim_refs.extend(order[t.first as usize..(t.first + t.count) as usize].iter().map(|&p| refs[p as usize]));
        nodes.push(GpuBvhNode { lmin: b.min.into(), l_first: 0, lmax: b.max.into(), l_count: t.count, ..empty_node });
        return Bvh { nodes, prim_refs, sah_cost: t.count as f32, ..Default::default() };
    }

    // Preorder: pop a tmp interior node, give it the next output index, patch its parent's link.
    let mut stack: Vec<(usize, usize, bool)> = vec![(0, usize::MAX, false)]; // (tmp index, parent out index, is right)
    while let Some((ti, parent, is_right)) = stack.pop() {
        let out = nodes.len() as u32;
        if parent != usize::MAX {
            let p = &mut nodes[parent];
            if is_right {
                p.r_first = out
            } else {
                p.l_first = out
            }
        }
        let t = tmp[ti];
        sah += rel(&tbox[ti]); // traversal cost 1
        let mut node = empty_node;
        let mut interior = Vec::with_capacity(2);
        for (side, c) in [(false, t.left as usize), (true, t.right as usize)] {
            let ct = tmp[c];
            let b = tbox[c];
            let (first, count) = if ct.count > 0 {
                let first = prim_refs.len() as u32;
                prim_refs
                    .extend(order[ct.first as usize..(ct.first + ct.count) as usize].iter().map(|&p| refs[p as usize]));
                sah += rel(&b) * ct.count as f64; // intersection cost 1 per primitive
                (first, ct.count)
            } else {
                interior.push((c, side));
                (EMPTY_CHILD, 0) // patched when the child is emitted
            };
            if side {
                (node.rmin, node.rmax, node.r_first, node.r_count) = (b.min.into(), b.max.into(), first, count);
            } else {
                (node.lmin, node.lmax, node.l_first, node.l_count) = (b.min.into(), b.max.into(), first, count);
            }
        }
        nodes.push(node);
        // Push right first so the left child is emitted right after its parent.
        for &(c, side) in interior.iter().rev() {
            stack.push((c, out as usize, side));
        }
    }
    Bvh { nodes, prim_refs, sah_cost: sah as f32, ..Default::default() }
}

/// CPU reference intersection in f64: every primitive, no acceleration structure. For tests (the thing under test
/// is always the WGSL); the formulas are textbook ones, independent of the shader's.
pub mod reference {
    use super::*;

    /// A ray in f64.
    #[derive(Clone, Copy, Debug)]
    pub struct Ray {
        pub o: DVec3,
        pub d: DVec3,
        pub t_max: f64,
    }

    /// A reference hit. `margin` is a dimensionless distance to the primitive's boundary (min barycentric for
    /// triangles, min(s, 1-s, t, 1-t) for quads, (r² − dist²)/r² for spheres): negative when only a padded test hit.
    #[derive(Clone, Copy, Debug, PartialEq)]
    pub struct RefHit {
        pub t: f64,
        pub prim: u32,
        pub b1: f64,
        pub b2: f64,
        pub margin: f64,
    }

    /// The primitives the reference intersects (the same inputs as [`build`]).
    pub struct Scene<'a> {
        pub tris: &'a [[Vec3; 3]],
        pub spheres: &'a [GpuSphere],
        pub quads: &'a [GpuQuad],
    }

    /// Möller–Trumbore in f64; `pad` widens the barycentric domain (hit if every barycentric ≥ −pad).
    pub fn triangle(ray: &Ray, v: &[Vec3; 3], pad: f64) -> Option<(f64, f64, f64, f64)> {
        let (v0, v1, v2) = (v[0].as_dvec3(), v[1].as_dvec3(), v[2].as_dvec3());
        let (e1, e2) = (v1 - v0, v2 - v0);
        let p = ray.d.cross(e2);
        let det = e1.dot(p);
        if det == 0.0 || !det.is_finite() {
            return None;
        }
        let inv = 1.0 / det;
        let s = ray.o - v0;
        let b1 = s.dot(p) * inv;
        let q = s.cross(e1);
        let b2 = ray.d.dot(q) * inv;
        let t = e2.dot(q) * inv;
        let margin = b1.min(b2).min(1.0 - b1 - b2);
        (margin >= -pad && t > 0.0 && t < ray.t_max).then_some((t, b1, b2, margin))
    }

    /// Ray–sphere in f64 (the numerically careful form of Haines et al., Ray Tracing Gems ch. 7); `pad` grows
    /// the accepted discriminant to −pad·r².
    pub fn sphere(ray: &Ray, s: &GpuSphere, pad: f64) -> Option<(f64, f64)> {
        let c = Vec3::from(s.center).as_dvec3();
        let r = s.radius as f64;
        let f = ray.o - c;
        let a = ray.d.dot(ray.d);
        let b = -f.dot(ray.d);
        let l = f + (b / a) * ray.d;
        let disc = r * r - l.dot(l);
        let margin = disc / (r * r);
        if margin < -pad {
            return None;
        }
        let q = b + b.signum() * (a * disc.max(0.0)).sqrt();
        let cc = f.dot(f) - r * r;
        let (t0, t1) = (cc / q, q / a);
        let (tn, tf) = (t0.min(t1), t0.max(t1));
        for t in [tn, tf] {
            if t > 0.0 && t < ray.t_max {
                return Some((t, margin));
            }
        }
        None
    }

    /// Ray–parallelogram in f64; `pad` widens the (s, t) domain to [−pad, 1 + pad]².
    pub fn quad(ray: &Ray, q: &GpuQuad, pad: f64) -> Option<(f64, f64, f64, f64)> {
        let (p, u, v) =
            (Vec3::from(q.corner).as_dvec3(), Vec3::from(q.edge_u).as_dvec3(), Vec3::from(q.edge_v).as_dvec3());
        let n = u.cross(v);
        let denom = n.dot(ray.d);
        if denom == 0.0 {
            return None;
        }
        let t = n.dot(p - ray.o) / denom;
        let rel = ray.o + t * ray.d - p;
        let nn = n.dot(n);
        let s = rel.cross(v).dot(n) / nn;
        let tt = u.cross(rel).dot(n) / nn;
        let margin = s.min(1.0 - s).min(tt).min(1.0 - tt);
        (margin >= -pad && t > 0.0 && t < ray.t_max).then_some((t, s, tt, margin))
    }

    /// One primitive by reference (`None` for excluded primitives, like the BVH).
    pub fn intersect(scene: &Scene, ray: &Ray, prim: u32, pad: f64) -> Option<RefHit> {
        let i = (prim & PRIM_INDEX_MASK) as usize;
        match prim >> PRIM_KIND_SHIFT {
            PRIM_TRIANGLE => {
                let v = &scene.tris[i];
                triangle_aabb(v)?;
                triangle(ray, v, pad).map(|(t, b1, b2, margin)| RefHit { t, prim, b1, b2, margin })
            }
            PRIM_SPHERE => {
                let s = &scene.spheres[i];
                sphere_aabb(s)?;
                sphere(ray, s, pad).map(|(t, margin)| RefHit { t, prim, b1: 0.0, b2: 0.0, margin })
            }
            PRIM_QUAD => {
                let q = &scene.quads[i];
                quad_aabb(q)?;
                quad(ray, q, pad).map(|(t, b1, b2, margin)| RefHit { t, prim, b1, b2, margin })
            }
            _ => None,
        }
    }

    /// Every primitive reference of a scene, included or not.
    pub fn all_prims(scene: &Scene) -> impl Iterator<Item = u32> {
        (0..scene.tris.len() as u32)
            .map(|i| make_prim(PRIM_TRIANGLE, i))
            .chain((0..scene.spheres.len() as u32).map(|i| make_prim(PRIM_SPHERE, i)))
            .chain((0..scene.quads.len() as u32).map(|i| make_prim(PRIM_QUAD, i)))
    }

    /// Closest hit over all primitives (brute force), exact (unpadded) tests.
    pub fn closest(scene: &Scene, ray: &Ray) -> Option<RefHit> {
        let mut best: Option<RefHit> = None;
        for p in all_prims(scene) {
            let r = Ray { t_max: best.map_or(ray.t_max, |b| b.t), ..*ray };
            if let Some(h) = intersect(scene, &r, p, 0.0) {
                best = Some(h);
            }
        }
        best
    }
}
