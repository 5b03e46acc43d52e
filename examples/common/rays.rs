//! Rays for the tracing examples (trace_cost, lane_refill): a scene's triangles as mislab loads them, and
//! bounce-like rays from them.
#![allow(dead_code)]

use glam::{Vec3, Vec3Swizzles};
use mislab::testkit::probe::ProbeRay;

pub const HELMET: &str =
    concat!(env!("CARGO_MANIFEST_DIR"), "/../shared/testdata/gltf/khronos/DamagedHelmet/glTF-Binary/DamagedHelmet.glb");

/// A scene file's triangles as mislab loads them (the product's import and scene flattening).
pub fn triangles(path: &str) -> Vec<[Vec3; 3]> {
    let scene = mislab::scene::load(path, &mislab::scene::LoadOptions::default()).unwrap_or_else(|e| panic!("{e}"));
    let data = mislab::render::scene_data::SceneData::build(&scene);
    data.tri_verts.chunks_exact(3).map(|t| [0, 1, 2].map(|k| Vec3::from_slice(&t[k][..3]))).collect()
}

pub struct Lcg(pub u64);
impl Lcg {
    pub fn next(&mut self) -> f32 {
        self.0 = self.0.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
        (self.0 >> 40) as f32 / (1u64 << 24) as f32
    }
}

pub fn bounds(tris: &[[Vec3; 3]]) -> (Vec3, Vec3) {
    tris.iter().flatten().fold((Vec3::MAX, Vec3::MIN), |(lo, hi), &p| (lo.min(p), hi.max(p)))
}

/// Bounce-like rays: from a random point of a random triangle, cosine-distributed about its normal, in random
/// order (`sorted`: ordered by the origin's cell on a 64³ grid and the direction's octant, a crude ray sort).
pub fn bounce_rays(tris: &[[Vec3; 3]], n: usize, sorted: bool) -> Vec<ProbeRay> {
    let mut rng = Lcg(7);
    let (lo, hi) = bounds(tris);
    let mut rays: Vec<(u64, ProbeRay)> = (0..n)
        .filter_map(|_| {
            let t = tris[(rng.next() * tris.len() as f32) as usize % tris.len()];
            let ng = (t[1] - t[0]).cross(t[2] - t[0]);
            if ng.length_squared() == 0.0 {
                return None;
            }
            let ng = ng.normalize();
            let (mut a, mut b) = (rng.next(), rng.next());
            if a + b > 1.0 {
                (a, b) = (1.0 - a, 1.0 - b);
            }
            let p = t[0] + a * (t[1] - t[0]) + b * (t[2] - t[0]);
            let (u1, u2) = (rng.next(), rng.next());
            let (s, phi) = (u1.sqrt(), std::f32::consts::TAU * u2);
            let (tx, ty) = ng.any_orthonormal_pair();
            let d = (tx * s * phi.cos() + ty * s * phi.sin() + ng * (1.0 - u1).max(0.0).sqrt()).normalize();
            let o = p + ng * 1e-4 * (hi - lo).length();
            let cell = ((o - lo) / (hi - lo) * 63.99).as_uvec3();
            let oct = (d.x > 0.0) as u64 | ((d.y > 0.0) as u64) << 1 | ((d.z > 0.0) as u64) << 2;
            let key = oct << 40 | (cell.xzy().x as u64) << 12 | (cell.y as u64) << 6 | cell.z as u64;
            Some((key, ProbeRay { o: o.into(), t_max: f32::MAX, d: d.into(), _pad: 0.0 }))
        })
        .collect();
    if sorted {
        rays.sort_by_key(|r| r.0);
    }
    // `_pad` holds the ray's index (lane_refill's kernels read it; the others ignore it).
    rays.into_iter().enumerate().map(|(i, r)| ProbeRay { _pad: f32::from_bits(i as u32), ..r.1 }).collect()
}
