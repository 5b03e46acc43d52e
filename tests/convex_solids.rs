//! Convex-solid detection (src/accel/convex_solids.rs): which triangle meshes shadow rays may test as half-space
//! intersections, and that the Cornell box's blocks are found and agree with their triangles.

mod common;

use glam::{DVec3, Vec3};
use mislab::accel::convex_solids::{convex_solids, ConvexSolid};
use mislab::gpu::types::INVALID;
use mislab::render::scene_data::SceneData;

/// Triangles as the flattened `[x, y, z, 0]` triples `convex_solids` reads.
fn flatten(tris: &[[Vec3; 3]]) -> Vec<[f32; 4]> {
    tris.iter().flat_map(|t| t.map(|v| [v.x, v.y, v.z, 0.0])).collect()
}

/// An axis-aligned box from `lo` to `hi`, two triangles per face.
fn cube(lo: Vec3, hi: Vec3) -> Vec<[Vec3; 3]> {
    let c = |i: u32| {
        Vec3::new([lo.x, hi.x][(i & 1) as usize], [lo.y, hi.y][(i >> 1 & 1) as usize], [lo.z, hi.z][(i >> 2) as usize])
    };
    let faces = [[0, 1, 3, 2], [4, 6, 7, 5], [0, 4, 5, 1], [2, 3, 7, 6], [0, 2, 6, 4], [1, 5, 7, 3]];
    faces.iter().flat_map(|f| [[c(f[0]), c(f[1]), c(f[2])], [c(f[0]), c(f[2]), c(f[3])]]).collect()
}

fn solids(tris: &[[Vec3; 3]]) -> Vec<ConvexSolid> {
    convex_solids(&flatten(tris), tris.len(), |_| false)
}

#[test]
fn a_box_is_one_solid_of_six_planes() {
    let s = solids(&cube(Vec3::splat(-1.0), Vec3::new(2.0, 1.0, 0.5)));
    assert_eq!(s.len(), 1);
    assert_eq!(s[0].triangles.len(), 12);
    assert_eq!(s[0].planes.len(), 6, "coplanar triangle pairs share a plane: {:?}", s[0].planes);
    // Outward: the centre is inside every plane, a far point outside one.
    let centre = DVec3::new(0.5, 0.0, -0.25);
    assert!(s[0].planes.iter().all(|(n, d)| n.dot(centre) < *d));
    assert!(s[0].planes.iter().any(|(n, d)| n.dot(DVec3::new(5.0, 0.0, 0.0)) > *d));
}

#[test]
fn open_concave_and_excluded_meshes_are_not_solids() {
    let mut open = cube(Vec3::ZERO, Vec3::ONE);
    open.pop();
    assert!(solids(&open).is_empty(), "a box with a missing triangle is not closed");

    // Two boxes sharing a vertex form one connected mesh that is neither closed-manifold-convex nor convex.
    let mut two = cube(Vec3::ZERO, Vec3::ONE);
    two.extend(cube(Vec3::ONE, Vec3::splat(2.0)));
    assert!(solids(&two).is_empty(), "two boxes touching at a corner are not one convex solid");

    // An L-shaped prism: closed, not convex.
    let l = [(0.0, 0.0), (2.0, 0.0), (2.0, 1.0), (1.0, 1.0), (1.0, 2.0), (0.0, 2.0)].map(|(x, y)| Vec3::new(x, y, 0.0));
    let up = Vec3::Z;
    let mut prism = vec![];
    for (i, j) in [(4, 5), (5, 0), (0, 1), (1, 2)] {
        prism.push([l[3], l[i], l[j]]);
        prism.push([l[3] + up, l[i] + up, l[j] + up]);
    }
    for i in 0..6 {
        let j = (i + 1) % 6;
        prism.push([l[i], l[j], l[j] + up]);
        prism.push([l[i], l[j] + up, l[i] + up]);
    }
    assert!(solids(&prism).is_empty(), "an L-shaped prism is not convex");
    assert_eq!(
        solids(&prism[..8].iter().chain(&cube(Vec3::splat(5.0), Vec3::splat(6.0))).copied().collect::<Vec<_>>()).len(),
        1
    );

    let light = convex_solids(&flatten(&cube(Vec3::ZERO, Vec3::ONE)), 12, |t| t == 5);
    assert!(light.is_empty(), "a mesh with an emissive triangle stays triangles (shadow rays aim at it)");

    let mut separate = cube(Vec3::ZERO, Vec3::ONE);
    separate.extend(cube(Vec3::splat(3.0), Vec3::splat(4.0)));
    assert_eq!(solids(&separate).len(), 2);
}

/// The Cornell box's two blocks are solids; segments between random points of the box's bounds are blocked by a
/// block's half-spaces exactly when (in f64) they cross one of its triangles, away from grazing contact.
#[test]
fn cornell_blocks_are_solids_that_block_as_their_triangles_do() {
    let scene = common::scene("cornell-box");
    let data = SceneData::build(&scene);
    let n = data.tri_shading.len();
    let found = convex_solids(&data.tri_verts, n, |t| data.tri_shading[t].light != INVALID);
    assert_eq!(found.len(), 2, "the tall and the short block");
    let tri = |t: usize| {
        [0, 1, 2].map(|k| {
            let p = data.tri_verts[3 * t + k];
            DVec3::new(p[0] as f64, p[1] as f64, p[2] as f64)
        })
    };
    let (mut lo, mut hi) = (DVec3::splat(f64::MAX), DVec3::splat(f64::MIN));
    for p in &data.tri_verts {
        let p = DVec3::new(p[0] as f64, p[1] as f64, p[2] as f64);
        (lo, hi) = (lo.min(p), hi.max(p));
    }
    let mut rng = 0x9e3779b97f4a7c15u64;
    let mut uniform = || {
        rng ^= rng << 13;
        rng ^= rng >> 7;
        rng ^= rng << 17;
        (rng >> 11) as f64 / (1u64 << 53) as f64
    };
    let (mut blocked, mut checked) = (0, 0);
    for s in &found {
        for _ in 0..20000 {
            let p = |u: &mut dyn FnMut() -> f64| lo + (hi - lo) * DVec3::new(u(), u(), u());
            let (a, b) = (p(&mut uniform), p(&mut uniform));
            let d = b - a;
            // Half-space clip in f64.
            let (mut t0, mut t1) = (0.0f64, 1.0f64);
            let mut inside_start = true;
            for (nrm, off) in &s.planes {
                let dn = nrm.dot(d);
                let sd = off - nrm.dot(a);
                inside_start &= sd >= 0.0;
                if dn < 0.0 {
                    t0 = t0.max(sd / dn);
                } else if dn > 0.0 {
                    t1 = t1.min(sd / dn);
                } else if sd < 0.0 {
                    t1 = -1.0;
                }
            }
            if inside_start || (t1 - t0).abs() < 1e-6 {
                continue; // segments starting inside the block, or touching it, are not shadow rays' business
            }
            let by_planes = t0 < t1;
            let by_triangles = s.triangles.iter().any(|&t| segment_hits_triangle(a, d, tri(t)));
            assert_eq!(by_planes, by_triangles, "segment {a} → {b}");
            checked += 1;
            blocked += by_planes as u32;
        }
    }
    assert!(checked > 30000 && blocked > 1000, "checked {checked}, blocked {blocked}");
}

/// Whether a + t·d, t ∈ (0, 1), crosses triangle v (Möller–Trumbore in f64).
fn segment_hits_triangle(a: DVec3, d: DVec3, v: [DVec3; 3]) -> bool {
    let (e1, e2) = (v[1] - v[0], v[2] - v[0]);
    let p = d.cross(e2);
    let det = e1.dot(p);
    if det.abs() < 1e-12 {
        return false;
    }
    let s = a - v[0];
    let u = s.dot(p) / det;
    let q = s.cross(e1);
    let w = d.dot(q) / det;
    let t = e2.dot(q) / det;
    (0.0..=1.0).contains(&u) && w >= 0.0 && u + w <= 1.0 && t > 0.0 && t < 1.0
}
