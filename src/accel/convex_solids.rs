//! Convex solids among a scene's triangles: closed, convex meshes (a Cornell box's blocks), found so that a
//! shadow ray can test each as the intersection of its bounding half-spaces (Haines 1991, "Fast Ray–Convex
//! Polyhedron Intersection", Graphics Gems II) instead of triangle by triangle.
//!
//! For a closed convex mesh the two tests agree: a segment meets the surface exactly where it meets the solid
//! (its origin being outside, as a shadow ray's offset origin is). A box then costs six plane clips instead of
//! twelve watertight triangle tests, and the half-space test has no cracks to leak through either.

use crate::accel::mesh_components::mesh_components;
use glam::DVec3;
use std::collections::HashMap;

/// A closed convex triangle mesh as the planes bounding it: x is inside when n·x ≤ d for every (n, d), |n| = 1.
#[derive(Clone, Debug)]
pub struct ConvexSolid {
    /// The triangles (indices into the scene's triangle list) it replaces.
    pub triangles: Vec<usize>,
    /// Distinct face planes, outward unit normal and offset.
    pub planes: Vec<(DVec3, f64)>,
}

/// Relative tolerance (of the solid's size) for "on the plane": the vertices of a planar face given in f32.
const PLANE_TOLERANCE: f64 = 1e-6;

/// The closed convex meshes among the first `n` triangles of `tri_verts` (three `[x, y, z, _]` per triangle),
/// leaving out any connected mesh that contains a triangle for which `excluded` holds (lights: a shadow ray aims
/// at a point on them and must not count their own solid).
pub fn convex_solids(tri_verts: &[[f32; 4]], n: usize, excluded: impl Fn(usize) -> bool) -> Vec<ConvexSolid> {
    // Vertices by bit pattern, as the watertight test shares them.
    let mut ids: HashMap<[u32; 3], usize> = HashMap::new();
    let mut points: Vec<DVec3> = vec![];
    let corners: Vec<[usize; 3]> = (0..n)
        .map(|t| {
            [0, 1, 2].map(|k| {
                let p = tri_verts[3 * t + k];
                *ids.entry([p[0].to_bits(), p[1].to_bits(), p[2].to_bits()]).or_insert_with(|| {
                    points.push(DVec3::new(p[0] as f64, p[1] as f64, p[2] as f64));
                    points.len() - 1
                })
            })
        })
        .collect();
    let mut solids: Vec<ConvexSolid> = mesh_components(&corners, points.len())
        .into_iter()
        .filter(|tris| !tris.iter().any(|&t| excluded(t)))
        .filter_map(|tris| solid_of(&tris, &corners, &points))
        .collect();
    solids.sort_by_key(|s| s.triangles[0]);
    solids
}

/// The planes of the mesh `tris` if it is closed and convex.
fn solid_of(tris: &[usize], corners: &[[usize; 3]], points: &[DVec3]) -> Option<ConvexSolid> {
    if tris.len() < 4 {
        return None;
    }
    // Closed: every edge shared by exactly two triangles.
    let mut edges: HashMap<(usize, usize), u32> = HashMap::new();
    for &t in tris {
        let c = corners[t];
        for (a, b) in [(c[0], c[1]), (c[1], c[2]), (c[2], c[0])] {
            *edges.entry((a.min(b), a.max(b))).or_default() += 1;
        }
    }
    if edges.values().any(|&k| k != 2) {
        return None;
    }
    let mut verts: Vec<usize> = tris.iter().flat_map(|&t| corners[t]).collect();
    verts.sort_unstable();
    verts.dedup();
    let centroid = verts.iter().map(|&v| points[v]).sum::<DVec3>() / verts.len() as f64;
    let size = verts.iter().map(|&v| (points[v] - centroid).length()).fold(0.0, f64::max);
    if !(size > 0.0 && size.is_finite()) {
        return None;
    }
    let tol = PLANE_TOLERANCE * size;
    let mut planes: Vec<(DVec3, f64)> = vec![];
    for &t in tris {
        let [a, b, c] = corners[t].map(|v| points[v]);
        let cross = (b - a).cross(c - a);
        let len = cross.length();
        if !(len > 1e-12 * size * size) {
            return None; // degenerate triangle: no plane to trust
        }
        let mut nrm = cross / len;
        let mut d = nrm.dot(a);
        if nrm.dot(centroid) - d > 0.0 {
            (nrm, d) = (-nrm, -d);
        }
        // Convex: the whole mesh on the inner side of every face, and the centroid strictly inside.
        if !(nrm.dot(centroid) - d < -tol) || verts.iter().any(|&v| nrm.dot(points[v]) - d > tol) {
            return None;
        }
        if !planes.iter().any(|(m, e)| m.dot(nrm) > 1.0 - 1e-12 && (e - d).abs() <= tol) {
            planes.push((nrm, d));
        }
    }
    Some(ConvexSolid { triangles: tris.to_vec(), planes })
}
