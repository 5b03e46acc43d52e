//! Triangle pre-splitting before the BVH build (Dammertz & Keller 2008, "Edge volume heuristic"/"early split
//! clipping"; Karras & Aila 2013, "Fast parallel construction of high-quality bounding volume hierarchies", §4):
//! a long or diagonal triangle — a wall, a floor, a stair's stringer — has a box far larger than itself, so every
//! ray that passes near it enters nodes whose boxes it inflates. Splitting the *reference* (not the triangle) into
//! pieces, each with the box of the part of the triangle inside it, lets the builder place the pieces like small
//! triangles. A triangle then sits in several leaves; traversal may test it more than once, which is harmless
//! for closest and any hits.
//!
//! The largest boxes are split first, until a budget of extra references is spent: the memory per triangle stays
//! bounded (docs/profile-bvh.md, "Memory per triangle"), and the few huge triangles of an interior take nearly
//! all of it. A piece's box is computed in f64 by clipping the triangle to the piece's slab and rounded outwards to
//! f32, so the pieces together cover the whole triangle (no ray that hits it can miss every piece).

use std::collections::BinaryHeap;

use glam::{DVec3, Vec3};

use crate::accel::aabb::{next_down, next_up, Aabb};

/// Extra references allowed, as a fraction of the triangles (each costs a vertex copy of 48 bytes and a share
/// of a node).
pub const BUDGET: f64 = 0.1;
/// A piece is split only if it is more than this many times the mean triangle box (half area).
const MIN_AREA_FACTOR: f64 = 2.0;
/// ... and only if its two halves' areas sum to less than its own divided by this.
const MIN_GAIN: f64 = 1.8;
/// Candidate split planes along the longest axis (at i / PLANES of the extent, i = 1 .. PLANES − 1).
const PLANES: usize = 8;

/// A piece of a triangle: the triangle's index in the input and the box of its part.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Piece {
    pub tri: u32,
    pub bx: Aabb,
}

/// Max-heap entry: the largest box first.
struct Entry {
    area: f64,
    piece: Piece,
}

impl PartialEq for Entry {
    fn eq(&self, o: &Self) -> bool {
        self.area == o.area
    }
}
impl Eq for Entry {}
impl PartialOrd for Entry {
    fn partial_cmp(&self, o: &Self) -> Option<std::cmp::Ordering> {
        Some(self.cmp(o))
    }
}
impl Ord for Entry {
    fn cmp(&self, o: &Self) -> std::cmp::Ordering {
        self.area.total_cmp(&o.area).then(o.piece.tri.cmp(&self.piece.tri))
    }
}

/// Splits the references `(tri, box)` (the boxes of whole triangles `verts[tri]`) into pieces; returns every
/// piece, the unsplit ones included, at most `budget` more than given. Deterministic.
pub fn split(refs: &[Piece], verts: &[[Vec3; 3]], budget: usize) -> Vec<Piece> {
    if refs.is_empty() || budget == 0 {
        return refs.to_vec();
    }
    let mean = refs.iter().map(|p| p.bx.half_area()).sum::<f64>() / refs.len() as f64;
    let threshold = mean * MIN_AREA_FACTOR;
    if !(threshold > 0.0 && threshold.is_finite()) {
        return refs.to_vec();
    }
    let mut out = Vec::with_capacity(refs.len() + budget);
    let mut heap = BinaryHeap::new();
    for p in refs {
        let area = p.bx.half_area();
        if area > threshold {
            heap.push(Entry { area, piece: *p });
        } else {
            out.push(*p);
        }
    }
    let mut extra = 0;
    while let Some(Entry { area, piece }) = heap.pop() {
        let halves =
            if extra < budget && area > threshold { best_split(&piece, &verts[piece.tri as usize]) } else { None };
        match halves {
            Some((l, r)) if (l.half_area() + r.half_area()) * MIN_GAIN < area => {
                extra += 1;
                for bx in [l, r] {
                    heap.push(Entry { area: bx.half_area(), piece: Piece { tri: piece.tri, bx } });
                }
            }
            _ => out.push(piece),
        }
    }
    out
}

/// The split of `p` along its box's longest axis that leaves the least total area, as the boxes of the
/// triangle's parts on either side; `None` if no plane leaves both sides non-empty.
fn best_split(p: &Piece, v: &[Vec3; 3]) -> Option<(Aabb, Aabb)> {
    let (lo, hi) = (p.bx.min.as_dvec3(), p.bx.max.as_dvec3());
    let e = hi - lo;
    let axis = if e.x >= e.y && e.x >= e.z {
        0
    } else if e.y >= e.z {
        1
    } else {
        2
    };
    let mut best: Option<(f64, Aabb, Aabb)> = None;
    for i in 1..PLANES {
        let pos = lo[axis] + e[axis] * i as f64 / PLANES as f64;
        let (mut lmax, mut rmin) = (hi, lo);
        lmax[axis] = pos;
        rmin[axis] = pos;
        let (Some(l), Some(r)) = (clipped_box(v, lo, lmax), clipped_box(v, rmin, hi)) else { continue };
        let cost = l.half_area() + r.half_area();
        if best.as_ref().is_none_or(|b| cost < b.0) {
            best = Some((cost, l, r));
        }
    }
    best.map(|(_, l, r)| (l, r))
}

/// The box of the part of triangle `v` inside `[lo, hi]`, rounded outwards to f32 and kept inside the f32 box
/// `[lo, hi]` rounded outwards; `None` if the part is empty.
fn clipped_box(v: &[Vec3; 3], lo: DVec3, hi: DVec3) -> Option<Aabb> {
    let mut poly: Vec<DVec3> = v.iter().map(|p| p.as_dvec3()).collect();
    for axis in 0..3 {
        poly = clip(&poly, axis, lo[axis], 1.0);
        poly = clip(&poly, axis, hi[axis], -1.0);
        if poly.is_empty() {
            return None;
        }
    }
    let (mut a, mut b) = (DVec3::splat(f64::MAX), DVec3::splat(f64::MIN));
    for p in &poly {
        a = a.min(*p);
        b = b.max(*p);
    }
    // The clip's f64 roundings are far below one f32 ulp: one ulp beyond the f32 below (above) covers them.
    let down = |x: f64| {
        let f = x as f32;
        next_down(if f as f64 > x { next_down(f) } else { f })
    };
    let up = |x: f64| {
        let f = x as f32;
        next_up(if (f as f64) < x { next_up(f) } else { f })
    };
    let tri = Aabb { min: v[0].min(v[1]).min(v[2]), max: v[0].max(v[1]).max(v[2]) };
    let min = Vec3::new(down(a.x), down(a.y), down(a.z)).max(tri.min);
    let max = Vec3::new(up(b.x), up(b.y), up(b.z)).min(tri.max);
    Some(Aabb { min, max })
}

/// Sutherland–Hodgman: the part of the convex polygon where `sign · (p[axis] − plane) ≥ 0`.
fn clip(poly: &[DVec3], axis: usize, plane: f64, sign: f64) -> Vec<DVec3> {
    let mut out = Vec::with_capacity(poly.len() + 1);
    for i in 0..poly.len() {
        let (a, b) = (poly[i], poly[(i + 1) % poly.len()]);
        let (da, db) = (sign * (a[axis] - plane), sign * (b[axis] - plane));
        if da >= 0.0 {
            out.push(a);
        }
        if (da >= 0.0) != (db >= 0.0) {
            let t = da / (da - db);
            let mut p = a + (b - a) * t;
            p[axis] = plane; // exactly on the plane
            out.push(p);
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    fn whole(v: &[[Vec3; 3]]) -> Vec<Piece> {
        v.iter()
            .enumerate()
            .map(|(i, t)| Piece {
                tri: i as u32,
                bx: Aabb { min: t[0].min(t[1]).min(t[2]), max: t[0].max(t[1]).max(t[2]) },
            })
            .collect()
    }

    /// A long diagonal triangle among small ones is split; the pieces' boxes are smaller in total, lie in the
    /// triangle's box, and cover every point of the triangle.
    #[test]
    fn a_diagonal_sliver_is_split_into_covering_pieces() {
        let mut tris = vec![[Vec3::ZERO, Vec3::new(10.0, 10.0, 10.0), Vec3::new(10.0, 10.5, 10.0)]];
        for i in 0..99 {
            let o = Vec3::new(i as f32 * 0.1, 0.0, 0.0);
            tris.push([o, o + Vec3::X * 0.1, o + Vec3::Y * 0.1]);
        }
        let refs = whole(&tris);
        let pieces = split(&refs, &tris, 10);
        let sliver: Vec<&Piece> = pieces.iter().filter(|p| p.tri == 0).collect();
        assert_eq!(pieces.len(), 100 + sliver.len() - 1);
        assert!(sliver.len() > 2 && sliver.len() <= 11, "{} pieces", sliver.len());
        let total: f64 = sliver.iter().map(|p| p.bx.half_area()).sum();
        assert!(total < 0.5 * refs[0].bx.half_area(), "{total} vs {}", refs[0].bx.half_area());
        for p in &sliver {
            assert!(refs[0].bx.contains(&p.bx));
        }
        // Points on the triangle (including its edges and corners) lie in some piece.
        let t = tris[0];
        for i in 0..=40 {
            for j in 0..=(40 - i) {
                let (u, w) = (i as f32 / 40.0, j as f32 / 40.0);
                let q = t[0] + (t[1] - t[0]) * u + (t[2] - t[0]) * w;
                let inside = |b: &Aabb| b.min.cmple(q).all() && b.max.cmpge(q).all();
                assert!(sliver.iter().any(|p| inside(&p.bx)), "{q} in no piece");
            }
        }
    }

    /// Small triangles and an axis-aligned square's halves (no larger than twice the mean box) are left alone, and a
    /// zero budget splits nothing.
    #[test]
    fn tight_boxes_and_a_zero_budget_split_nothing() {
        let tris = vec![
            [Vec3::ZERO, Vec3::X, Vec3::Y],
            [Vec3::X, Vec3::X + Vec3::Y, Vec3::Y],
            [Vec3::ZERO, Vec3::new(0.01, 0.0, 0.0), Vec3::new(0.0, 0.01, 0.0)],
        ];
        let refs = whole(&tris);
        assert_eq!(split(&refs, &tris, 100).len(), 3);
        let sliver = vec![[Vec3::ZERO, Vec3::splat(10.0), Vec3::new(10.0, 10.5, 10.0)], tris[2]];
        assert_eq!(split(&whole(&sliver), &sliver, 0), whole(&sliver));
    }
}
