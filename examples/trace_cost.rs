//! What a ray costs in a kernel that only traces (no shading, no path state), against what it costs inside the
//! render's one big kernel — the question a wavefront design turns on (docs/profile-bvh.md). Traces rays against
//! DamagedHelmet's 8-wide BVH in a probe kernel that does nothing else, `REPEAT` times per ray, and prints ns per ray
//! per lane (the difference of two repeat counts, so pipeline compilation and upload cancel out).
//! `cargo run --release --example trace_cost [RAYS]`

use glam::{Vec3, Vec3Swizzles};
use mislab::accel::bvh;
use mislab::gpu::GpuContext;
use mislab::testkit::probe::{GeometryBuffers, Probe, ProbeRay};
use std::time::Instant;

const HELMET: &str =
    concat!(env!("CARGO_MANIFEST_DIR"), "/../shared/testdata/gltf/khronos/DamagedHelmet/glTF-Binary/DamagedHelmet.glb");

const KERNEL: &str = "
override REPEAT: u32 = 1u;
fn probe_closest(r: ProbeRay) -> u32 {
    var acc = 0u;
    var t_max = r.t_max;
    for (var k = 0u; k < REPEAT; k++) {
        let h = trace_closest(r.o, r.d, t_max);
        acc += h.prim;
        // Never true for a hit (t < t_max), but the compiler cannot know: each trace depends on the last.
        t_max = select(t_max, t_max * 0.5, h.t > t_max);
    }
    return acc;
}
fn probe_any(r: ProbeRay) -> u32 {
    var acc = 0u;
    var t_max = r.t_max;
    for (var k = 0u; k < REPEAT; k++) {
        let a = trace_any(r.o, r.d, t_max);
        acc += select(0u, 1u, a);
        t_max = select(t_max, t_max * 0.5, acc > 1000000u);
    }
    return acc;
}
";

/// DamagedHelmet's triangles as mislab loads them (the product's glTF import and scene flattening).
fn helmet() -> Vec<[Vec3; 3]> {
    let scene = mislab::scene::load(HELMET, &mislab::scene::LoadOptions::default()).unwrap_or_else(|e| panic!("{e}"));
    let data = mislab::render::scene_data::SceneData::build(&scene);
    data.tri_verts.chunks_exact(3).map(|t| [0, 1, 2].map(|k| Vec3::from_slice(&t[k][..3]))).collect()
}

struct Lcg(u64);
impl Lcg {
    fn next(&mut self) -> f32 {
        self.0 = self.0.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
        (self.0 >> 40) as f32 / (1u64 << 24) as f32
    }
}

/// Camera rays of a `side`² image in 8×8 tiles (a workgroup's lanes), looking at the model from +z.
fn camera_rays(tris: &[[Vec3; 3]], side: u32) -> Vec<ProbeRay> {
    let (lo, hi) = bounds(tris);
    let c = (lo + hi) * 0.5;
    let r = (hi - lo).length() * 0.5;
    let eye = c + Vec3::new(0.0, 0.0, 2.2 * r);
    let mut rays = Vec::new();
    for ty in 0..side / 8 {
        for tx in 0..side / 8 {
            for l in 0..64 {
                let (x, y) = (tx * 8 + l % 8, ty * 8 + l / 8);
                let u = (x as f32 + 0.5) / side as f32 * 2.0 - 1.0;
                let v = 1.0 - (y as f32 + 0.5) / side as f32 * 2.0;
                let d = Vec3::new(u * 0.5, v * 0.5, -1.0).normalize();
                rays.push(ProbeRay { o: eye.into(), t_max: f32::MAX, d: d.into(), _pad: 0.0 });
            }
        }
    }
    rays
}

fn bounds(tris: &[[Vec3; 3]]) -> (Vec3, Vec3) {
    tris.iter().flatten().fold((Vec3::MAX, Vec3::MIN), |(lo, hi), &p| (lo.min(p), hi.max(p)))
}

/// Bounce-like rays: from a random point of a random triangle, cosine-distributed about its normal, in random
/// order (`sorted`: ordered by the origin's cell on a 64³ grid and the direction's octant, a crude ray sort).
fn bounce_rays(tris: &[[Vec3; 3]], n: usize, sorted: bool) -> Vec<ProbeRay> {
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
    rays.into_iter().map(|r| r.1).collect()
}

fn seconds(probe: &Probe, source: &str, function: &str, rays: &[ProbeRay], geo: &GeometryBuffers) -> f64 {
    let t = Instant::now();
    let out: Vec<u32> =
        probe.map(source, "ProbeRay", "u32", function, rays, Some(geo)).unwrap_or_else(|e| panic!("{e}"));
    std::hint::black_box(out);
    t.elapsed().as_secs_f64()
}

fn main() {
    let n: usize = std::env::args().nth(1).map(|s| s.parse().expect("RAYS")).unwrap_or(1 << 19);
    let ctx = GpuContext::new().unwrap_or_else(|e| panic!("{e}"));
    let tris = helmet();
    let wide = bvh::build_wide(&tris, &[], &[], bvh::Presplit::Large { keep_whole: &[] });
    let geo = GeometryBuffers::new(&ctx, &wide, &tris, &[], &[]);
    let library = mislab::testkit::probe::trace_module(KERNEL)
        .replace("override WIDE_BVH: bool = false;", "override WIDE_BVH: bool = true;");
    let probe = Probe::new(&ctx);
    let side = ((n as f64).sqrt() as u32 / 8 * 8).max(8);
    let sets = [
        ("camera rays, 8x8 tiles", camera_rays(&tris, side)),
        ("bounce rays, random order", bounce_rays(&tris, n, false)),
        ("bounce rays, sorted by origin cell + octant", bounce_rays(&tris, n, true)),
    ];
    for (name, rays) in &sets {
        for function in ["probe_closest", "probe_any"] {
            let mut best = f64::MAX;
            for _ in 0..2 {
                let src1 = library.replace("override REPEAT: u32 = 1u;", "override REPEAT: u32 = 1u;");
                let src9 = library.replace("override REPEAT: u32 = 1u;", "override REPEAT: u32 = 9u;");
                let a = seconds(&probe, &src1, function, rays, &geo);
                let b = seconds(&probe, &src9, function, rays, &geo);
                best = best.min((b - a) / 8.0);
            }
            println!(
                "{name:45} {function:14} {:>8} rays: {:6.1} ns per ray ({:.2} Mrays/s)",
                rays.len(),
                best / rays.len() as f64 * 1e9,
                rays.len() as f64 / best / 1e6
            );
        }
    }
}
