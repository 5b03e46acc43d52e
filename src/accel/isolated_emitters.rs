//! Emitters that nothing else comes near: a shadow ray towards a point on one may stop where it enters the box that
//! only that emitter occupies.
//!
//! A shadow ray from x to a point y on an emitting triangle tests everything in between. Where y lies on a
//! connected emitter mesh that is planar, or closed and convex with its faces wound outwards and emitting from the
//! front only, no other triangle of that mesh can block the ray: light samples come only from points x in front of
//! y's face (behind a one-sided face there is no light; a two-sided one is sampled from behind as its mirror twin,
//! which only a planar mesh allows here), and from there the segment meets the mesh's plane, or its convex solid,
//! only at y. If, in addition, no other primitive's bounding box meets the mesh's padded box, nothing inside that
//! box can block either, so the ray can stop where it enters the box. For a finely tessellated emitter — the Veach
//! glTF's sphere lights, 20,160 triangles each — that saves the descent into the emitter's own subtree next to y,
//! where most of a shadow ray's node and triangle tests were spent (docs/estimators.md, "Shadow rays that stop at
//! an isolated emitter").

use crate::accel::mesh_components::mesh_components;
use glam::{DVec3, Vec3};
use std::collections::{HashMap, HashSet};

/// One isolated emitter mesh: its triangles and the box a shadow ray towards it may stop at.
#[derive(Clone, Debug, PartialEq)]
pub struct IsolatedEmitter {
    /// Indices into the scene's triangle list, ascending.
    pub triangles: Vec<usize>,
    /// The mesh's bounding box, padded by half the margin that no other primitive's box may enter.
    pub lo: Vec3,
    pub hi: Vec3,
}

/// Relative tolerance (of the mesh's size) for "on the plane" and "behind the plane": vertices given in f32.
const PLANE_TOLERANCE: f64 = 1e-6;

/// Margin (relative to the mesh's largest extent) that no other primitive's box may enter; the stop box is padded by
/// half of it. Slack only: the shader already moves its stop past the box's entry by more than the entry's rounding.
const MARGIN: f32 = 1e-3;

/// The isolated emitter meshes among `tris`. `emitter(i)`: None if triangle i does not emit, else whether it emits
/// from both faces. `others`: the bounding boxes of every primitive that is not one of `tris` (spheres, quads).
pub fn isolated_emitters(
    tris: &[[Vec3; 3]],
    emitter: impl Fn(usize) -> Option<bool>,
    others: &[(Vec3, Vec3)],
) -> Vec<IsolatedEmitter> {
    let candidates: Vec<IsolatedEmitter> =
        emitter_meshes(tris, &emitter).into_iter().filter_map(|m| shadow_safe(tris, &emitter, m)).collect();
    if candidates.is_empty() {
        return candidates;
    }
    let mut group = vec![u32::MAX; tris.len()];
    for (g, c) in candidates.iter().enumerate() {
        for &t in &c.triangles {
            group[t] = g as u32;
        }
    }
    let grid = BoxGrid::new(&candidates);
    let mut crowded = vec![false; candidates.len()];
    for (i, t) in tris.iter().enumerate() {
        let (lo, hi) = (t[0].min(t[1]).min(t[2]), t[0].max(t[1]).max(t[2]));
        grid.overlapping(lo, hi, |g| crowded[g] |= group[i] != g as u32);
    }
    for &(lo, hi) in others {
        grid.overlapping(lo, hi, |g| crowded[g] = true);
    }
    candidates.into_iter().zip(crowded).filter(|(_, c)| !c).map(|(m, _)| m).collect()
}

/// Connected components of the emitting triangles (sharing a vertex, by bit pattern), each ascending.
fn emitter_meshes(tris: &[[Vec3; 3]], emitter: &impl Fn(usize) -> Option<bool>) -> Vec<Vec<usize>> {
    let mut ids: HashMap<[u32; 3], usize> = HashMap::new();
    let mut corners: Vec<(usize, [usize; 3])> = vec![];
    for (i, t) in tris.iter().enumerate() {
        if emitter(i).is_none() {
            continue;
        }
        let c = t.map(|p| {
            let n = ids.len();
            *ids.entry(p.to_array().map(f32::to_bits)).or_insert(n)
        });
        corners.push((i, c));
    }
    let ids_of: Vec<[usize; 3]> = corners.iter().map(|c| c.1).collect();
    let mut meshes: Vec<Vec<usize>> = mesh_components(&ids_of, ids.len())
        .into_iter()
        .map(|m| m.into_iter().map(|k| corners[k].0).collect())
        .collect();
    meshes.sort_by_key(|m| m[0]);
    meshes
}

/// The mesh with its stop box if no triangle of it can block a shadow ray towards another (planar, or closed,
/// convex, wound outwards and one-sided); None otherwise.
fn shadow_safe(
    tris: &[[Vec3; 3]],
    emitter: &impl Fn(usize) -> Option<bool>,
    mesh: Vec<usize>,
) -> Option<IsolatedEmitter> {
    let mut lo = Vec3::splat(f32::INFINITY);
    let mut hi = Vec3::splat(f32::NEG_INFINITY);
    for &t in &mesh {
        for p in tris[t] {
            lo = lo.min(p);
            hi = hi.max(p);
        }
    }
    let extent = (hi - lo).max_element();
    if !(extent > 0.0 && extent.is_finite()) {
        return None;
    }
    // Relative to the mesh's size, and at least a few roundings of its coordinates (a small emitter far from the
    // origin is convex only up to those).
    let size = (extent as f64) * 3f64.sqrt();
    let tol = PLANE_TOLERANCE * (size + lo.abs().max(hi.abs()).max_element() as f64);
    let points: Vec<DVec3> = mesh.iter().flat_map(|&t| tris[t].map(|p| p.as_dvec3())).collect();
    let planar = {
        // The plane of the largest triangle.
        let (a, n) = mesh
            .iter()
            .map(|&t| {
                let [a, b, c] = tris[t].map(|p| p.as_dvec3());
                (a, (b - a).cross(c - a))
            })
            .max_by(|x, y| x.1.length_squared().total_cmp(&y.1.length_squared()))?;
        let len = n.length();
        len > 0.0 && points.iter().all(|&p| (n.dot(p - a) / len).abs() <= tol)
    };
    let one_sided = mesh.iter().all(|&t| emitter(t) == Some(false));
    if !(planar || one_sided && convex_outward(tris, &mesh, tol)) {
        return None;
    }
    let pad = Vec3::splat(0.5 * MARGIN * extent) + (lo.abs().max(hi.abs()) * 1e-6);
    Some(IsolatedEmitter { triangles: mesh, lo: lo - pad, hi: hi + pad })
}

/// Whether `mesh` is closed (each edge in two triangles, once in each direction), convex (every vertex behind or on
/// every face's plane, within `tol`) and wound so that each face's normal points out of the solid.
fn convex_outward(tris: &[[Vec3; 3]], mesh: &[usize], tol: f64) -> bool {
    if mesh.len() < 4 {
        return false;
    }
    let mut weld = Weld::new(tol);
    let corners: Vec<[usize; 3]> = mesh.iter().map(|&t| tris[t].map(|p| weld.id(p.as_dvec3()))).collect();
    let points = weld.points;
    let mut directed: HashSet<(usize, usize)> = HashSet::new();
    for c in &corners {
        for (a, b) in [(c[0], c[1]), (c[1], c[2]), (c[2], c[0])] {
            if a == b || !directed.insert((a, b)) {
                return false;
            }
        }
    }
    if directed.iter().any(|&(a, b)| !directed.contains(&(b, a))) {
        return false;
    }
    let centroid = points.iter().sum::<DVec3>() / points.len() as f64;
    let clusters = Clusters::new(&points);
    corners.iter().all(|c| {
        let [a, b, cc] = c.map(|v| points[v]);
        let n = (b - a).cross(cc - a);
        let len = n.length();
        if !(len > 0.0) {
            return false;
        }
        let n = n / len;
        let dist = n.dot(a);
        // Wound outwards with the centroid strictly inside, and no vertex in front of the face.
        n.dot(centroid) - dist < -tol && !clusters.any_in_front(&points, n, dist + tol)
    })
}

/// Vertices within `tol` of one another as one (a UV sphere's seam: the two copies of a vertex at φ = 0 and 2π may
/// differ in their last bit), so that such a mesh counts as closed.
struct Weld {
    tol: f64,
    cells: HashMap<[i64; 3], Vec<usize>>,
    points: Vec<DVec3>,
}

impl Weld {
    fn new(tol: f64) -> Weld {
        Weld { tol: tol.max(f64::MIN_POSITIVE), cells: HashMap::new(), points: vec![] }
    }

    fn id(&mut self, p: DVec3) -> usize {
        let c = (p / self.tol).floor();
        let c = [c.x, c.y, c.z].map(|v| v.clamp(-1e15, 1e15) as i64);
        // Its own cell first: most lookups are a shared vertex, met again with the same bits.
        let offsets = std::iter::once([0, 0, 0])
            .chain((0..27).map(|k| [k % 3 - 1, k / 3 % 3 - 1, k / 9 - 1]).filter(|o| *o != [0, 0, 0]));
        for o in offsets {
            let near = self.cells.get(&[c[0] + o[0], c[1] + o[1], c[2] + o[2]]).into_iter().flatten();
            if let Some(&i) = near.into_iter().find(|&&i| (self.points[i] - p).length() <= self.tol) {
                return i;
            }
        }
        self.points.push(p);
        self.cells.entry(c).or_default().push(self.points.len() - 1);
        self.points.len() - 1
    }
}

/// Vertices grouped by cell of a coarse grid, each group with a bounding sphere, so that "is any vertex in front of
/// this plane" skips the groups well behind it: O(faces × groups) instead of O(faces × vertices).
struct Clusters {
    members: Vec<Vec<usize>>,
    spheres: Vec<(DVec3, f64)>,
}

impl Clusters {
    fn new(points: &[DVec3]) -> Clusters {
        let lo = points.iter().fold(DVec3::splat(f64::INFINITY), |a, &p| a.min(p));
        let hi = points.iter().fold(DVec3::splat(f64::NEG_INFINITY), |a, &p| a.max(p));
        let k = ((points.len() as f64 / 16.0).cbrt().ceil()).max(1.0);
        let cell = ((hi - lo) / k).max(DVec3::splat(1e-300));
        let mut cells: HashMap<[i64; 3], Vec<usize>> = HashMap::new();
        for (i, p) in points.iter().enumerate() {
            let c = ((*p - lo) / cell).floor().min(DVec3::splat(k - 1.0));
            cells.entry([c.x as i64, c.y as i64, c.z as i64]).or_default().push(i);
        }
        let members: Vec<Vec<usize>> = cells.into_values().collect();
        let spheres = members
            .iter()
            .map(|m| {
                let a = m.iter().fold(DVec3::splat(f64::INFINITY), |a, &i| a.min(points[i]));
                let b = m.iter().fold(DVec3::splat(f64::NEG_INFINITY), |a, &i| a.max(points[i]));
                let c = 0.5 * (a + b);
                (c, m.iter().map(|&i| (points[i] - c).length()).fold(0.0, f64::max))
            })
            .collect();
        Clusters { members, spheres }
    }

    /// Whether some vertex p has n·p > d.
    fn any_in_front(&self, points: &[DVec3], n: DVec3, d: f64) -> bool {
        self.members
            .iter()
            .zip(&self.spheres)
            .any(|(m, &(c, r))| n.dot(c) + r > d && m.iter().any(|&i| n.dot(points[i]) > d))
    }
}

/// The candidates' boxes on a uniform grid whose cells are as large as the largest box, so that each box lies in
/// at most eight cells and a primitive's box is tested only against the candidates in the cells it touches (or
/// against all of them, where that is fewer).
struct BoxGrid<'a> {
    boxes: &'a [IsolatedEmitter],
    origin: Vec3,
    cell: Vec3,
    cells: HashMap<[i64; 3], Vec<usize>>,
}

impl<'a> BoxGrid<'a> {
    fn new(boxes: &'a [IsolatedEmitter]) -> BoxGrid<'a> {
        let origin = boxes.iter().fold(Vec3::splat(f32::INFINITY), |a, b| a.min(b.lo));
        let cell = boxes.iter().fold(Vec3::splat(f32::MIN_POSITIVE), |a, b| a.max(b.hi - b.lo));
        let mut grid = BoxGrid { boxes, origin, cell, cells: HashMap::new() };
        for (g, b) in boxes.iter().enumerate() {
            let (l, h) = (grid.cell_of(b.lo), grid.cell_of(b.hi));
            for x in l[0]..=h[0] {
                for y in l[1]..=h[1] {
                    for z in l[2]..=h[2] {
                        grid.cells.entry([x, y, z]).or_default().push(g);
                    }
                }
            }
        }
        grid
    }

    fn cell_of(&self, p: Vec3) -> [i64; 3] {
        let c = ((p - self.origin) / self.cell).floor();
        [c.x, c.y, c.z].map(|v| v.clamp(-1e12, 1e12) as i64)
    }

    /// Calls `f(g)` for every candidate g whose margin-padded box meets [lo, hi] (a non-finite box meets all).
    fn overlapping(&self, lo: Vec3, hi: Vec3, mut f: impl FnMut(usize)) {
        let meets = |b: &IsolatedEmitter| {
            let margin = Vec3::splat(0.5 * MARGIN * (b.hi - b.lo).max_element());
            !(lo.is_finite() && hi.is_finite()) || (lo.cmple(b.hi + margin).all() && hi.cmpge(b.lo - margin).all())
        };
        let (l, h) = (self.cell_of(lo - self.cell), self.cell_of(hi + self.cell));
        let touched = (0..3).map(|k| (h[k] - l[k] + 1).max(0) as f64).product::<f64>();
        if !(lo.is_finite() && hi.is_finite()) || touched >= self.boxes.len() as f64 {
            for (g, b) in self.boxes.iter().enumerate() {
                if meets(b) {
                    f(g);
                }
            }
            return;
        }
        let mut seen = HashSet::new();
        for x in l[0]..=h[0] {
            for y in l[1]..=h[1] {
                for z in l[2]..=h[2] {
                    for &g in self.cells.get(&[x, y, z]).into_iter().flatten() {
                        if seen.insert(g) && meets(&self.boxes[g]) {
                            f(g);
                        }
                    }
                }
            }
        }
    }
}
