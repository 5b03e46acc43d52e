//! Convex lamps: an isolated emitter mesh (`accel::isolated_emitters`) that is closed, convex and round — a
//! tessellated sphere lamp — becomes one light, sampled through the cone of a sphere inside it.
//!
//! As triangles, a tessellated sphere is thousands of tiny lights: the light tree walks a dozen levels to pick one
//! and samples it by area, and a sample's density over directions still varies with each face's tilt. As one lamp,
//! a light sample draws a direction uniformly in the cone of the sphere of radius `r_in` about `center` that the
//! mesh contains (every such direction meets the mesh, first on a face that emits towards it), with probability
//! 1 − `rim`; with probability `rim` it draws a face uniformly and a point on it by area, kept only where its
//! direction misses that cone: the thin rim between the inner sphere's silhouette and the mesh's. The two parts
//! cover disjoint directions, so the density of a direction is the part's that can draw it, and together they
//! reach every direction that meets the mesh: unbiased under any strategy, light sampling alone included.
//! A shadow ray towards the lamp stops at its stop box, which nothing else enters, so where the direction meets
//! the mesh does not matter for visibility; the emission is the same on every face (one material, no texture).

use crate::accel::isolated_emitters::IsolatedEmitter;
use glam::{DVec3, Vec3};

/// One convex lamp.
#[derive(Clone, Debug, PartialEq)]
pub struct ConvexLamp {
    /// The mesh's triangles (indices into the scene's triangle list) and its stop box.
    pub mesh: IsolatedEmitter,
    /// Centre of the sphere inside the mesh (the centre of the mesh's bounding box).
    pub center: Vec3,
    /// Its radius: the least distance from `center` to a face's plane, shrunk by [`INNER_SHRINK`].
    pub r_in: f32,
    /// Probability of the rim part of a light sample ([`rim_probability`]).
    pub rim: f32,
}

/// Fewest faces for a mesh to become a lamp: a box or an octahedron stays triangles, which sample it as well.
pub const MIN_FACES: usize = 16;
/// Least ratio of the inner sphere's radius to the largest distance from its centre to a vertex: rounder meshes only
/// (an icosahedron is 0.79; a UV sphere of 8 rings 0.92), so that the cone holds nearly all of the lamp's directions.
pub const MIN_ROUNDNESS: f64 = 0.75;
/// The inner sphere's radius is the least face distance times 1 − this: a direction in its cone meets the mesh even
/// after the f32 roundings of the cone's sampling.
pub const INNER_SHRINK: f64 = 1e-4;

/// The rim part's probability for inner and outer radii r_in ≤ r_out: about the share of the mesh's silhouette
/// outside the inner sphere's (1 − (r_in/r_out)², from far away), at least 1/64 and at most 1/2.
pub fn rim_probability(r_in: f64, r_out: f64) -> f64 {
    (1.0 - (r_in / r_out).powi(2)).clamp(1.0 / 64.0, 0.5)
}

/// The lamp `mesh` makes, or None: fewer than [`MIN_FACES`] faces, a face seen from inside (not convex about the
/// centre, wound inwards, or flat), or not round enough ([`MIN_ROUNDNESS`]). `mesh` must be an isolated emitter:
/// closed, convex and outward-wound when it is not planar.
pub fn convex_lamp(tris: &[[Vec3; 3]], mesh: &IsolatedEmitter) -> Option<ConvexLamp> {
    if mesh.triangles.len() < MIN_FACES {
        return None;
    }
    let v = |t: usize, k: usize| tris[t][k].as_dvec3();
    let (mut lo, mut hi) = (DVec3::INFINITY, DVec3::NEG_INFINITY);
    for &t in &mesh.triangles {
        for k in 0..3 {
            lo = lo.min(v(t, k));
            hi = hi.max(v(t, k));
        }
    }
    let c = 0.5 * (lo + hi);
    let mut r_in = f64::INFINITY;
    let mut r_out: f64 = 0.0;
    for &t in &mesh.triangles {
        let n = (v(t, 1) - v(t, 0)).cross(v(t, 2) - v(t, 0));
        let len = n.length();
        for k in 0..3 {
            r_out = r_out.max((v(t, k) - c).length());
        }
        if !(len > 0.0) {
            continue; // a sliver has no plane of its own; its neighbours bound the solid
        }
        r_in = r_in.min((n / len).dot(v(t, 0) - c));
    }
    if !(r_in > 0.0 && r_out > 0.0 && r_in >= MIN_ROUNDNESS * r_out) {
        return None;
    }
    Some(ConvexLamp {
        mesh: mesh.clone(),
        center: c.as_vec3(),
        r_in: (r_in * (1.0 - INNER_SHRINK)) as f32,
        rim: rim_probability(r_in, r_out) as f32,
    })
}
