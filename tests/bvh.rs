//! BVH tests: build invariants on the CPU, and the WGSL traversal (closest and any hit) against a brute-force f64
//! reference on random soups, single primitives, the empty scene and DamagedHelmet; ray-origin offsetting at 1e5.

use glam::{DVec3, Vec3};
use mislab::accel::bvh::reference::{self, Ray, RefHit, Scene};
use mislab::accel::bvh::{self, Bvh, EMPTY_CHILD};
use mislab::accel::wide_bvh;
use mislab::gpu::types::{make_prim, GpuQuad, GpuSphere, INVALID, PRIM_SPHERE, PRIM_TRIANGLE};
use mislab::gpu::GpuContext;
use mislab::testkit::probe::{GeometryBuffers, Probe, ProbeRay};
use rand::{Rng, SeedableRng};
use rand_pcg::Pcg64;

const HELMET: &str =
    concat!(env!("CARGO_MANIFEST_DIR"), "/../shared/testdata/gltf/khronos/DamagedHelmet/glTF-Binary/DamagedHelmet.glb");
/// Same-primitive hits must agree in t to this relative tolerance.
const T_REL: f64 = 1e-5;
/// Two primitives whose reference distances agree this closely are a tie: either may be reported.
const TIE_REL: f64 = 1e-6;
/// A ray this close (in barycentric / normalised units) to a primitive's boundary may go either way in f32.
const EDGE_MARGIN: f64 = 1e-5;

mod common;
use common::gpu;

// ---------------------------------------------------------------------------------------------------------------
// Probe kernels

#[repr(C)]
#[derive(Clone, Copy, Debug, Default, bytemuck::Pod, bytemuck::Zeroable)]
struct ProbeTrace {
    t: f32,
    prim: u32,
    b1: f32,
    b2: f32,
    any: u32,
    _p0: u32,
    _p1: u32,
    _p2: u32,
}

#[repr(C)]
#[derive(Clone, Copy, Debug, Default, bytemuck::Pod, bytemuck::Zeroable)]
struct ProbeSpawn {
    p: [f32; 3],
    _pad0: f32,
    ng: [f32; 3],
    _pad1: f32,
    d: [f32; 3],
    _pad2: f32,
}

#[repr(C)]
#[derive(Clone, Copy, Debug, Default, bytemuck::Pod, bytemuck::Zeroable)]
struct ProbeSpawnOut {
    o: [f32; 3],
    t: f32,
    prim: u32,
    _p0: u32,
    _p1: u32,
    _p2: u32,
}

const PROBE_WGSL: &str = "
struct ProbeTrace { t: f32, prim: u32, b1: f32, b2: f32, any: u32, _p0: u32, _p1: u32, _p2: u32 }
fn probe_trace(r: ProbeRay) -> ProbeTrace {
    let h = trace_closest(r.o, r.d, r.t_max);
    let a = trace_any(r.o, r.d, r.t_max);
    return ProbeTrace(h.t, h.prim, h.b1, h.b2, select(0u, 1u, a), 0u, 0u, 0u);
}
struct ProbeSpawn { p: vec3<f32>, _pad0: f32, ng: vec3<f32>, _pad1: f32, d: vec3<f32>, _pad2: f32 }
struct ProbeSpawnOut { o: vec3<f32>, t: f32, prim: u32, _p0: u32, _p1: u32, _p2: u32 }
fn probe_spawn(s: ProbeSpawn) -> ProbeSpawnOut {
    let o = offset_ray_origin(s.p, s.ng);
    let h = trace_closest(o, s.d, F32_MAX);
    return ProbeSpawnOut(o, h.t, h.prim, 0u, 0u, 0u);
}
";

fn probe_source() -> String {
    mislab::testkit::probe::trace_module(PROBE_WGSL)
}

struct Geometry {
    tris: Vec<[Vec3; 3]>,
    spheres: Vec<GpuSphere>,
    quads: Vec<GpuQuad>,
}

impl Geometry {
    fn scene(&self) -> Scene<'_> {
        Scene { tris: &self.tris, spheres: &self.spheres, quads: &self.quads }
    }
    /// The tree the renderer builds (large triangles pre-split; the geometry here has no emitters).
    fn build(&self) -> Bvh {
        self.build_with(true)
    }
    fn build_with(&self, presplit: bool) -> Bvh {
        bvh::build(&self.tris, &self.spheres, &self.quads, split(presplit))
    }
    fn build_wide(&self) -> Bvh {
        wide_bvh::build(&self.tris, &self.spheres, &self.quads, split(true))
    }
}

/// The probe module traversing the 8-wide tree (the pipeline constant a wide scene's pipelines get).
fn wide_source() -> String {
    let s = probe_source();
    assert!(s.contains("override WIDE_BVH: bool = false;"));
    s.replace("override WIDE_BVH: bool = false;", "override WIDE_BVH: bool = true;")
}

fn gpu_trace(ctx: &GpuContext, g: &Geometry, bvh: &Bvh, rays: &[ProbeRay]) -> Vec<ProbeTrace> {
    gpu_trace_source(ctx, g, bvh, rays, &probe_source())
}

fn gpu_trace_source(ctx: &GpuContext, g: &Geometry, bvh: &Bvh, rays: &[ProbeRay], source: &str) -> Vec<ProbeTrace> {
    let buffers = GeometryBuffers::new(ctx, bvh, &g.tris, &g.spheres, &g.quads);
    Probe::new(ctx)
        .map(source, "ProbeRay", "ProbeTrace", "probe_trace", rays, Some(&buffers))
        .unwrap_or_else(|e| panic!("{e}"))
}

// ---------------------------------------------------------------------------------------------------------------
// Reference: brute force over every primitive, in f64. Bounding spheres (of each primitive and of runs of 32
// consecutive primitives) only skip primitives that provably cannot be hit before the current closest t.

struct Culled {
    /// (centre, radius, first, end) over `prims`.
    chunks: Vec<(DVec3, f64, usize, usize)>,
    prims: Vec<(u32, DVec3, f64)>,
}

fn bounding_sphere(g: &Geometry, prim: u32) -> (DVec3, f64) {
    let i = (prim & mislab::gpu::types::PRIM_INDEX_MASK) as usize;
    match prim >> 30 {
        PRIM_TRIANGLE => {
            let v = g.tris[i].map(|p| p.as_dvec3());
            let c = (v[0] + v[1] + v[2]) / 3.0;
            (c, v.iter().map(|p| (*p - c).length()).fold(0.0, f64::max))
        }
        PRIM_SPHERE => (Vec3::from(g.spheres[i].center).as_dvec3(), g.spheres[i].radius as f64),
        _ => {
            let q = &g.quads[i];
            let (p, u, v) =
                (Vec3::from(q.corner).as_dvec3(), Vec3::from(q.edge_u).as_dvec3(), Vec3::from(q.edge_v).as_dvec3());
            (p + 0.5 * (u + v), 0.5 * (u + v).length().max((u - v).length()))
        }
    }
}

impl Culled {
    fn new(g: &Geometry) -> Self {
        let scene = g.scene();
        let prims: Vec<(u32, DVec3, f64)> = reference::all_prims(&scene)
            .filter_map(|p| {
                let (c, r) = bounding_sphere(g, p);
                (c.is_finite() && r.is_finite()).then_some((p, c, r * (1.0 + 1e-9) + 1e-30))
            })
            .collect();
        let mut chunks = Vec::new();
        for start in (0..prims.len()).step_by(32) {
            let end = (start + 32).min(prims.len());
            let (lo, hi) = prims[start..end]
                .iter()
                .fold((DVec3::MAX, DVec3::MIN), |(lo, hi), (_, c, r)| (lo.min(*c - *r), hi.max(*c + *r)));
            let center = (lo + hi) * 0.5;
            let radius = prims[start..end].iter().map(|(_, c, r)| (*c - center).length() + r).fold(0.0, f64::max);
            chunks.push((center, radius * (1.0 + 1e-9), start, end));
        }
        Culled { chunks, prims }
    }

    fn closest(&self, scene: &Scene, ray: &Ray) -> Option<RefHit> {
        let len = ray.d.length();
        let dn = ray.d / len;
        let mut best: Option<RefHit> = None;
        // Can a sphere hold a point at distance (along dn) in (0, best)?
        let may_hit = |c: DVec3, r: f64, best_t: f64| {
            let f = c - ray.o;
            let tc = f.dot(dn);
            tc + r > 0.0 && tc - r < best_t * len * (1.0 + 1e-9) && (f - tc * dn).length_squared() <= r * r
        };
        for &(cc, cr, a, b) in &self.chunks {
            if !may_hit(cc, cr, best.map_or(ray.t_max, |h| h.t)) {
                continue;
            }
            for &(p, c, r) in &self.prims[a..b] {
                let t_max = best.map_or(ray.t_max, |h| h.t);
                if !may_hit(c, r, t_max) {
                    continue;
                }
                if let Some(h) = reference::intersect(scene, &Ray { t_max, ..*ray }, p, 0.0) {
                    best = Some(h);
                }
            }
        }
        best
    }
}

fn ray64(r: &ProbeRay) -> Ray {
    Ray { o: Vec3::from(r.o).as_dvec3(), d: Vec3::from(r.d).as_dvec3(), t_max: r.t_max as f64 }
}

/// The reference closest hit of every ray, on both cores.
fn reference_hits(g: &Geometry, rays: &[ProbeRay]) -> Vec<Option<RefHit>> {
    let culled = Culled::new(g);
    let scene = g.scene();
    let half = rays.len().div_ceil(2).max(1);
    std::thread::scope(|s| {
        let parts: Vec<_> = rays
            .chunks(half)
            .map(|part| s.spawn(|| part.iter().map(|r| culled.closest(&scene, &ray64(r))).collect::<Vec<_>>()))
            .collect();
        parts.into_iter().flat_map(|h| h.join().unwrap()).collect()
    })
}

// ---------------------------------------------------------------------------------------------------------------
// Comparison

#[derive(Debug, Default)]
struct Stats {
    rays: usize,
    hits: usize,
    ties: usize,
    near_edge: usize,
    failures: Vec<String>,
    grazing: usize,
    max_t_rel: f64,
    max_bary_err: f64,
}

fn rel(a: f64, b: f64) -> f64 {
    (a - b).abs() / b.abs().max(1e-30)
}

/// Rounding errors of the f32 shader grow like 1/cos θ for grazing rays: a perpendicular error of a few ulps of
/// the coordinates (ε·scale) becomes ε·scale / cos θ along the ray, and ε·scale / (size·cos θ) in barycentrics.
/// Returns that error unit along the ray and in the primitive's parameters (K ulps each).
fn f32_error_units(g: &Geometry, prim: u32, r: &Ray, t: f64) -> (f64, f64) {
    const K: f64 = 8.0 * f32::EPSILON as f64 * 0.5;
    let i = (prim & mislab::gpu::types::PRIM_INDEX_MASK) as usize;
    let dn = r.d.normalize();
    let hit = r.o + t * r.d;
    let (cos, size) = match prim >> 30 {
        PRIM_TRIANGLE => {
            let v = g.tris[i].map(|p| p.as_dvec3());
            let n = (v[1] - v[0]).cross(v[2] - v[0]);
            // Size: the smallest altitude, which bounds the barycentrics' sensitivity (slivers!).
            let longest = (v[1] - v[0]).length().max((v[2] - v[1]).length()).max((v[0] - v[2]).length());
            (dn.dot(n.normalize()).abs(), n.length() / longest)
        }
        PRIM_SPHERE => {
            let c = Vec3::from(g.spheres[i].center).as_dvec3();
            (dn.dot((hit - c).normalize()).abs(), g.spheres[i].radius as f64)
        }
        _ => {
            let q = &g.quads[i];
            let (u, v) = (Vec3::from(q.edge_u).as_dvec3(), Vec3::from(q.edge_v).as_dvec3());
            let n = u.cross(v);
            (dn.dot(n.normalize()).abs(), n.length() / u.length().max(v.length()))
        }
    };
    let scale = r.o.abs().max_element() + hit.abs().max_element();
    let cos = cos.max(1e-9);
    (K * scale / cos, K * scale / (size * cos))
}

/// Compares GPU and reference hits ray by ray. `edge` is the boundary band (in `RefHit::margin` units) inside
/// which f32 and f64 may legitimately disagree about hit or miss; it widens by the f32 error for grazing rays.
fn compare(g: &Geometry, rays: &[ProbeRay], gpu: &[ProbeTrace], refs: &[Option<RefHit>], edge: f64) -> Stats {
    let scene = g.scene();
    let mut s = Stats { rays: rays.len(), ..Default::default() };
    for (i, ((ray, gh), rh)) in rays.iter().zip(gpu).zip(refs).enumerate() {
        let r = ray64(ray);
        let mut errs: Vec<String> = Vec::new();
        let mut fail = |msg: String| errs.push(format!("ray {i} {ray:?}: {msg}; gpu {gh:?}; ref {rh:?}"));
        // trace_any must agree with the closest-hit traversal exactly: same tests, same boxes.
        if (gh.any != 0) != (gh.prim != INVALID) {
            fail("trace_any disagrees with trace_closest".into());
        }
        let g_prim = (gh.prim != INVALID).then_some(gh.prim);
        if g_prim.is_some() && !(gh.t > 0.0 && gh.t < ray.t_max) {
            fail("GPU t outside (0, t_max)".into());
            continue;
        }
        if g_prim.is_none() && gh.t.to_bits() != ray.t_max.to_bits() {
            fail("a miss must report t = t_max".into());
        }
        if rh.is_some() {
            s.hits += 1;
        }
        // t agrees to T_REL, or (counted as ill-conditioned) within the grazing-ray error bound.
        let t_agrees = |prim: u32, t_gpu: f64, t_ref: f64, s: &mut Stats| {
            let e = (t_gpu - t_ref).abs();
            s.max_t_rel = s.max_t_rel.max(e / t_ref);
            if e <= T_REL * t_ref {
                return true;
            }
            let ok = e <= T_REL * t_ref + f32_error_units(g, prim, &r, t_ref).0;
            s.grazing += ok as usize;
            ok
        };
        let edge_band = |prim: u32, t: f64| edge + f32_error_units(g, prim, &r, t).1;
        match (g_prim, rh) {
            (None, None) => {}
            (Some(p), Some(q)) if p == q.prim => {
                if !t_agrees(p, gh.t as f64, q.t, &mut s) {
                    fail(format!("t differs by {:.2e} (relative)", rel(gh.t as f64, q.t)));
                }
                if p >> 30 != PRIM_SPHERE {
                    let be = (gh.b1 as f64 - q.b1).abs().max((gh.b2 as f64 - q.b2).abs());
                    s.max_bary_err = s.max_bary_err.max(be);
                    if be > 1e-4 + f32_error_units(g, p, &r, q.t).1 {
                        fail(format!("parameters differ by {be:.2e}"));
                    }
                }
            }
            (Some(p), q) => {
                // The GPU's primitive under a padded reference test.
                let hp = reference::intersect(&scene, &r, p, edge_band(p, gh.t as f64));
                let Some(hp) = hp else {
                    fail("GPU hit a primitive the reference misses even when padded".into());
                    continue;
                };
                if !t_agrees(p, gh.t as f64, hp.t, &mut s) {
                    fail("GPU t differs from the reference t of the same primitive".into());
                } else if q.is_some_and(|q| rel(hp.t, q.t) <= TIE_REL) {
                    s.ties += 1;
                } else if hp.margin < edge_band(p, hp.t) && q.is_none_or(|q| hp.t < q.t) {
                    s.near_edge += 1; // grazed the boundary of p, which the reference just misses
                } else if q.is_some_and(|q| q.margin < edge_band(q.prim, q.t) && hp.t > q.t) {
                    s.near_edge += 1; // slipped past the boundary of q, then hit p behind it
                } else {
                    fail("different primitive, not a tie or an edge case".into());
                }
            }
            (None, Some(q)) => {
                if q.margin < edge_band(q.prim, q.t) || rel(q.t, r.t_max) < T_REL {
                    s.near_edge += 1;
                } else {
                    fail("GPU missed".into());
                }
            }
        }
        for e in errs {
            // Keep the first 20 messages; count the rest.
            s.failures.push(if s.failures.len() < 20 { e } else { String::new() });
        }
    }
    s
}

/// Asserts no failures and fewer than `max_odd` (a fraction of the rays) ties and boundary cases.
fn check(name: &str, s: &Stats, max_odd: f64) {
    eprintln!(
        "{name}: {} rays, {} hit ({:.1} %), ties {}, near-edge {}, grazing {}, max t error {:.2e}, max (b1,b2) error {:.2e}, failures {}",
        s.rays,
        s.hits,
        100.0 * s.hits as f64 / s.rays.max(1) as f64,
        s.ties,
        s.near_edge,
        s.grazing,
        s.max_t_rel,
        s.max_bary_err,
        s.failures.len()
    );
    assert!(s.failures.is_empty(), "{name}: {} failures:\n{}", s.failures.len(), s.failures.join("\n").trim_end());
    // Grazing hits whose t needed more than T_REL (within the 1/cos θ error bound) must be rare too.
    assert!((s.grazing as f64) < 1e-2 * s.rays as f64, "{name}: {} grazing hits of {} rays (≥ 1 %)", s.grazing, s.rays);
    let odd = s.ties + s.near_edge;
    assert!(
        (odd as f64) < max_odd * s.rays as f64,
        "{name}: {odd} tie/edge cases of {} rays (≥ {} %)",
        s.rays,
        100.0 * max_odd
    );
}

// ---------------------------------------------------------------------------------------------------------------
// Scenes and rays

fn unit(rng: &mut Pcg64) -> DVec3 {
    let z = rng.random_range(-1.0..1.0f64);
    let phi = rng.random_range(0.0..std::f64::consts::TAU);
    let s = (1.0 - z * z).sqrt();
    DVec3::new(s * phi.cos(), s * phi.sin(), z)
}

fn v3(rng: &mut Pcg64, lo: f32, hi: f32) -> Vec3 {
    Vec3::new(rng.random_range(lo..hi), rng.random_range(lo..hi), rng.random_range(lo..hi))
}

/// A random point on a primitive (for aiming rays so that most hit).
fn point_on(g: &Geometry, prim: u32, rng: &mut Pcg64) -> DVec3 {
    let i = (prim & mislab::gpu::types::PRIM_INDEX_MASK) as usize;
    match prim >> 30 {
        PRIM_TRIANGLE => {
            let v = g.tris[i].map(|p| p.as_dvec3());
            let (mut a, mut b) = (rng.random::<f64>(), rng.random::<f64>());
            if a + b > 1.0 {
                (a, b) = (1.0 - a, 1.0 - b);
            }
            v[0] + a * (v[1] - v[0]) + b * (v[2] - v[0])
        }
        PRIM_SPHERE => Vec3::from(g.spheres[i].center).as_dvec3() + unit(rng) * g.spheres[i].radius as f64 * 0.999,
        _ => {
            let q = &g.quads[i];
            Vec3::from(q.corner).as_dvec3()
                + rng.random::<f64>() * Vec3::from(q.edge_u).as_dvec3()
                + rng.random::<f64>() * Vec3::from(q.edge_v).as_dvec3()
        }
    }
}

/// Rays from a sphere around the scene: 90 % aimed at a random point of a random (included) primitive, 10 % at a
/// random point of the bounds. Of those, 10 % travel exactly along an axis and 5 % have one zero direction
/// component (the slab test's 1/0 case), and 10 % start inside the bounds. 30 % get a finite t_max (0.2–1.2 × the
/// distance to the aim point), 10 % an infinite one, the rest F32_MAX.
fn make_rays(g: &Geometry, n: usize, seed: u64) -> Vec<ProbeRay> {
    let mut rng = Pcg64::seed_from_u64(seed);
    let included: Vec<u32> = reference::all_prims(&g.scene()).filter(|&p| is_included(g, p)).collect();
    let (lo, hi) = included.iter().fold((DVec3::MAX, DVec3::MIN), |(lo, hi), &p| {
        let (c, r) = bounding_sphere(g, p);
        (lo.min(c - r), hi.max(c + r))
    });
    let (center, radius) =
        if included.is_empty() { (DVec3::ZERO, 1.0) } else { ((lo + hi) * 0.5, ((hi - lo).length() * 0.5).max(1e-3)) };
    (0..n)
        .map(|_| {
            let target = if !included.is_empty() && rng.random::<f64>() < 0.9 {
                point_on(g, included[rng.random_range(0..included.len())], &mut rng)
            } else {
                center + (DVec3::new(rng.random(), rng.random(), rng.random()) * 2.0 - 1.0) * radius
            };
            let dist = radius * rng.random_range(1.2..3.0);
            let kind = rng.random::<f64>();
            let (o, d) = if kind < 0.1 {
                let mut d = DVec3::ZERO;
                d[rng.random_range(0..3)] = if rng.random() { 1.0 } else { -1.0 };
                (target - d * dist, d)
            } else if kind < 0.15 {
                let mut d = unit(&mut rng);
                d[rng.random_range(0..3)] = 0.0;
                let d = d.normalize();
                (target - d * dist, d)
            } else if kind < 0.25 {
                let o = center + (DVec3::new(rng.random(), rng.random(), rng.random()) * 2.0 - 1.0) * radius * 0.8;
                (o, unit(&mut rng))
            } else {
                let o = center + unit(&mut rng) * dist;
                (o, (target - o).normalize())
            };
            let t_max = match rng.random::<f64>() {
                u if u < 0.3 => ((target - o).length() * rng.random_range(0.2..1.2)) as f32,
                u if u < 0.4 => f32::INFINITY,
                _ => f32::MAX,
            };
            ProbeRay { o: o.as_vec3().into(), t_max, d: d.as_vec3().into(), _pad: 0.0 }
        })
        .collect()
}

fn is_included(g: &Geometry, p: u32) -> bool {
    let i = (p & mislab::gpu::types::PRIM_INDEX_MASK) as usize;
    match p >> 30 {
        PRIM_TRIANGLE => bvh::triangle_aabb(&g.tris[i]).is_some(),
        PRIM_SPHERE => bvh::sphere_aabb(&g.spheres[i]).is_some(),
        _ => bvh::quad_aabb(&g.quads[i]).is_some(),
    }
}

fn split(presplit: bool) -> bvh::Presplit<'static> {
    if presplit {
        bvh::Presplit::Large { keep_whole: &[] }
    } else {
        bvh::Presplit::Off
    }
}

/// Random triangles, spheres and quads, a small grid mesh (shared edges and vertices), and excluded junk
/// (zero-area and non-finite primitives).
fn soup(seed: u64) -> Geometry {
    let mut rng = Pcg64::seed_from_u64(seed);
    let mut tris = Vec::new();
    for _ in 0..3000 {
        let c = v3(&mut rng, -1.0, 1.0);
        let s = rng.random_range(0.02..0.3f32);
        tris.push([c + v3(&mut rng, -s, s), c + v3(&mut rng, -s, s), c + v3(&mut rng, -s, s)]);
    }
    // A 24×24 grid of quads split into triangles, tilted.
    let n = 24;
    let vert = |i: usize, j: usize| {
        Vec3::new(
            -0.8 + 1.6 * i as f32 / n as f32,
            0.3 * (i as f32 * 0.7).sin() * (j as f32 * 0.5).cos(),
            -0.8 + 1.6 * j as f32 / n as f32,
        )
    };
    for i in 0..n {
        for j in 0..n {
            let (a, b, c, d) = (vert(i, j), vert(i + 1, j), vert(i + 1, j + 1), vert(i, j + 1));
            tris.push([a, b, c]);
            tris.push([a, c, d]);
        }
    }
    // Axis-aligned triangles and quads: boxes of zero thickness.
    for k in 0..30 {
        let c = v3(&mut rng, -1.0, 1.0);
        let (a, b) = (v3(&mut rng, -0.2, 0.2), v3(&mut rng, -0.2, 0.2));
        let flat = |mut v: Vec3| {
            v[k % 3] = 0.0;
            c + v
        };
        tris.push([flat(Vec3::ZERO), flat(a), flat(b)]);
    }
    // Junk the build must survive and the traversal never hits.
    let p = Vec3::new(0.1, 0.2, 0.3);
    tris.push([p, p, p]);
    tris.push([p, p + Vec3::X, p + 2.0 * Vec3::X]);
    tris.push([p, Vec3::new(f32::NAN, 0.0, 0.0), Vec3::ONE]);
    tris.push([p, Vec3::new(f32::INFINITY, 0.0, 0.0), Vec3::ONE]);
    let mut spheres: Vec<GpuSphere> = (0..100)
        .map(|_| GpuSphere {
            center: v3(&mut rng, -1.0, 1.0).into(),
            radius: rng.random_range(0.01..0.15),
            ..Default::default()
        })
        .collect();
    spheres.push(GpuSphere { center: [0.0; 3], radius: 0.0, ..Default::default() });
    spheres.push(GpuSphere { center: [f32::NAN, 0.0, 0.0], radius: 0.1, ..Default::default() });
    let mut quads: Vec<GpuQuad> = (0..100)
        .map(|_| GpuQuad {
            corner: v3(&mut rng, -1.0, 1.0).into(),
            edge_u: v3(&mut rng, -0.2, 0.2).into(),
            edge_v: v3(&mut rng, -0.2, 0.2).into(),
            ..Default::default()
        })
        .collect();
    for k in 0..30 {
        let mut u = [0.0f32; 3];
        let mut v = [0.0f32; 3];
        u[k % 3] = rng.random_range(0.05..0.3);
        v[(k + 1) % 3] = rng.random_range(0.05..0.3);
        quads.push(GpuQuad { corner: v3(&mut rng, -1.0, 1.0).into(), edge_u: u, edge_v: v, ..Default::default() });
    }
    quads.push(GpuQuad { corner: [0.0; 3], edge_u: [1.0, 0.0, 0.0], edge_v: [2.0, 0.0, 0.0], ..Default::default() });
    Geometry { tris, spheres, quads }
}

fn helmet() -> Geometry {
    let gltf = gltf::Gltf::open(HELMET).unwrap_or_else(|e| panic!("cannot open {HELMET}: {e}"));
    let buffers = gltf::import_buffers(&gltf.document, None, gltf.blob.clone()).expect("DamagedHelmet buffers");
    let mut tris = Vec::new();
    for mesh in gltf.document.meshes() {
        for prim in mesh.primitives() {
            assert_eq!(prim.mode(), gltf::mesh::Mode::Triangles);
            let reader = prim.reader(|b| Some(&buffers[b.index()]));
            let pos: Vec<Vec3> = reader.read_positions().expect("positions").map(Vec3::from).collect();
            let idx: Vec<u32> = reader
                .read_indices()
                .map(|i| i.into_u32().collect())
                .unwrap_or_else(|| (0..pos.len() as u32).collect());
            tris.extend(idx.chunks_exact(3).map(|t| [pos[t[0] as usize], pos[t[1] as usize], pos[t[2] as usize]]));
        }
    }
    Geometry { tris, spheres: Vec::new(), quads: Vec::new() }
}

// ---------------------------------------------------------------------------------------------------------------
// CPU: build invariants

/// The box of an included primitive (by reference), as the builder computes it.
fn prim_box(g: &Geometry, p: u32) -> bvh::Aabb {
    let i = (p & mislab::gpu::types::PRIM_INDEX_MASK) as usize;
    match p >> 30 {
        PRIM_TRIANGLE => bvh::triangle_aabb(&g.tris[i]),
        PRIM_SPHERE => bvh::sphere_aabb(&g.spheres[i]),
        _ => bvh::quad_aabb(&g.quads[i]),
    }
    .expect("an excluded primitive is in the tree")
}

/// Checks the leaves found in a tree, as (leaf box, primitive reference) pairs: a sphere or quad is in exactly
/// one leaf whose box holds it; a triangle is in at least one (pre-split triangles, `accel::presplit`, are in
/// several), never twice in one leaf (`leaf` numbers the leaves), and every point of it lies in one of its leaves'
/// boxes (sampled on a grid of barycentric points, corners and edges included, in f64 with a tolerance far below
/// any gap a wrong piece would leave).
fn check_leaf_cover(g: &Geometry, found: &[(bvh::Aabb, u32, usize)]) {
    let mut by_prim: std::collections::HashMap<u32, Vec<(bvh::Aabb, usize)>> = Default::default();
    for &(bx, p, leaf) in found {
        by_prim.entry(p).or_default().push((bx, leaf));
    }
    for (&p, leaves) in &by_prim {
        let i = (p & mislab::gpu::types::PRIM_INDEX_MASK) as usize;
        if p >> 30 != PRIM_TRIANGLE {
            assert_eq!(leaves.len(), 1, "primitive {p:#x} is in {} leaves", leaves.len());
            assert!(leaves[0].0.contains(&prim_box(g, p)), "leaf box does not hold primitive {p:#x}");
            continue;
        }
        let mut ids: Vec<usize> = leaves.iter().map(|l| l.1).collect();
        ids.sort_unstable();
        assert!(ids.windows(2).all(|w| w[0] != w[1]), "triangle {i} twice in one leaf");
        let t = g.tris[i].map(|v| v.as_dvec3());
        let whole = prim_box(g, p);
        let tol = 1e-6 * (whole.max - whole.min).max_element() as f64;
        let n = 12;
        for a in 0..=n {
            for c in 0..=(n - a) {
                let (u, w) = (a as f64 / n as f64, c as f64 / n as f64);
                let q = t[0] + (t[1] - t[0]) * u + (t[2] - t[0]) * w;
                let inside =
                    |b: &bvh::Aabb| (b.min.as_dvec3() - tol).cmple(q).all() && (b.max.as_dvec3() + tol).cmpge(q).all();
                assert!(leaves.iter().any(|l| inside(&l.0)), "point {q} of triangle {i} is in none of its leaves");
            }
        }
    }
}

/// Every included primitive is referenced (each reference slot in exactly one leaf), every box holds what is
/// below it, leaves are small and cover their primitives ([`check_leaf_cover`]), and the depth fits the GPU stack.
fn check_structure(g: &Geometry, b: &Bvh) {
    assert!(!b.nodes.is_empty());
    assert!(b.depth() <= bvh::BVH_STACK_SIZE, "depth {} exceeds the traversal stack", b.depth());
    let mut seen = vec![0u32; b.prim_refs.len()];
    let mut visited = vec![false; b.nodes.len()];
    let mut found = Vec::new();
    let mut stack = vec![0usize];
    while let Some(n) = stack.pop() {
        assert!(!std::mem::replace(&mut visited[n], true), "node {n} reached twice");
        let node = b.nodes[n];
        for (lo, hi, first, count) in
            [(node.lmin, node.lmax, node.l_first, node.l_count), (node.rmin, node.rmax, node.r_first, node.r_count)]
        {
            let bx = bvh::Aabb { min: lo.into(), max: hi.into() };
            if count > 0 {
                assert!(count <= bvh::MAX_LEAF_PRIMS || b.prim_refs.len() <= bvh::MAX_LEAF_PRIMS as usize);
                for k in first..first + count {
                    seen[k as usize] += 1;
                    found.push((bx, b.prim_refs[k as usize], first as usize));
                }
            } else if first != EMPTY_CHILD {
                let c = b.nodes[first as usize];
                let cb = bvh::Aabb {
                    min: Vec3::from(c.lmin).min(c.rmin.into()),
                    max: Vec3::from(c.lmax).max(c.rmax.into()),
                };
                assert!(bx.contains(&cb), "node {n}'s box of child {first} does not hold its children");
                stack.push(first as usize);
            }
        }
    }
    assert!(visited.iter().all(|&v| v), "unreachable nodes");
    assert!(seen.iter().all(|&c| c == 1), "a primitive reference is not in exactly one leaf");
    check_leaf_cover(g, &found);
    let mut refs = b.prim_refs.clone();
    refs.sort_unstable();
    refs.dedup();
    let included = reference::all_prims(&g.scene()).filter(|&p| is_included(g, p)).count();
    assert_eq!(refs.len(), included, "every included primitive at least once");
    assert!(b.sah_cost.is_finite() && b.sah_cost >= 0.0);
}

#[test]
fn build_invariants() {
    let g = soup(1);
    let b = g.build();
    check_structure(&g, &b);
    let mut distinct = b.prim_refs.clone();
    distinct.sort_unstable();
    distinct.dedup();
    assert_eq!(distinct.len(), 3000 + 24 * 24 * 2 + 30 + 100 + 130, "junk must be excluded");
    let unsplit = g.build_with(false);
    check_structure(&g, &unsplit);
    eprintln!(
        "soup: {} references ({} unsplit), {} nodes, depth {}, SAH {:.1} ({:.1} unsplit), {:.1} bytes/triangle",
        b.prim_refs.len(),
        unsplit.prim_refs.len(),
        b.node_count(),
        b.depth(),
        b.sah_cost,
        unsplit.sah_cost,
        b.bytes_per_triangle()
    );
}

/// Leaf order (what the renderer uploads): after `into_leaf_order` a triangle-only tree references triangle j at
/// `prim_refs[j]` (the shader's triangle-only path reads leaves without `prim_refs`), `order` names every triangle
/// (pre-split ones once per reference), and read back through `order` the tree is the one built.
#[test]
fn leaf_order_makes_triangle_refs_the_identity() {
    let g = helmet();
    let mut b = g.build();
    let order = mislab::accel::bvh::into_leaf_order(&mut b, g.tris.len());
    assert!(b.prim_refs.iter().enumerate().all(|(j, &r)| r == j as u32), "prim_refs[j] == j");
    let mut seen = vec![false; g.tris.len()];
    order.iter().for_each(|&o| seen[o as usize] = true);
    assert!(seen.iter().all(|&s| s), "order holds every triangle");
    assert!(order.len() > g.tris.len(), "some of the helmet's triangles are pre-split (copies in the order)");
    // The renumbered tree is the same tree: read back through `order`, its references name the same triangles.
    let mut back = b.clone();
    back.prim_refs.iter_mut().for_each(|r| *r = order[*r as usize]);
    check_structure(&g, &back);
    // Mixed kinds: triangle references are rewritten, the others kept.
    let soup = soup(2);
    let mut b = soup.build();
    let before = b.prim_refs.clone();
    let order = mislab::accel::bvh::into_leaf_order(&mut b, soup.tris.len());
    for (x, y) in before.iter().zip(&b.prim_refs) {
        if x >> 30 == 0 {
            assert_eq!(order[*y as usize], *x, "a triangle reference names the same triangle");
        } else {
            assert_eq!(x, y, "sphere and quad references unchanged");
        }
    }
}

#[test]
fn build_edge_cases() {
    // Empty, all-excluded, one primitive, two primitives.
    let empty = Geometry { tris: vec![], spheres: vec![], quads: vec![] };
    let b = empty.build();
    assert_eq!(b.nodes.len(), 1);
    assert!(b.prim_refs.is_empty());
    assert_eq!(
        (b.nodes[0].l_first, b.nodes[0].l_count, b.nodes[0].r_first, b.nodes[0].r_count),
        (EMPTY_CHILD, 0, EMPTY_CHILD, 0)
    );
    assert_eq!(b.sah_cost, 0.0);
    assert_eq!(b.bytes_per_triangle(), 0.0);

    let p = Vec3::ONE;
    let junk = Geometry {
        tris: vec![[p, p, p]],
        spheres: vec![GpuSphere { radius: -1.0, ..Default::default() }],
        quads: vec![],
    };
    assert_eq!(junk.build().prim_refs.len(), 0);

    let one = Geometry { tris: vec![[Vec3::ZERO, Vec3::X, Vec3::Y]], spheres: vec![], quads: vec![] };
    let b = one.build();
    check_structure(&one, &b);
    assert_eq!(b.nodes.len(), 1);
    assert_eq!(
        (b.nodes[0].l_first, b.nodes[0].l_count, b.nodes[0].r_first, b.nodes[0].r_count),
        (0, 1, EMPTY_CHILD, 0)
    );
    assert_eq!(b.prim_refs, vec![make_prim(PRIM_TRIANGLE, 0)]);
    assert_eq!(b.sah_cost, 1.0);

    let two = Geometry {
        tris: vec![],
        spheres: vec![GpuSphere { center: [0.0; 3], radius: 1.0, ..Default::default() }],
        quads: vec![GpuQuad {
            corner: [3.0, 0.0, 0.0],
            edge_u: [1.0, 0.0, 0.0],
            edge_v: [0.0, 1.0, 0.0],
            ..Default::default()
        }],
    };
    let b = two.build();
    check_structure(&two, &b);
    assert_eq!(b.prim_refs.len(), 2);
}

#[test]
fn build_pathological_inputs() {
    // 20 000 coincident triangles: PLOC cannot separate them; the depth must still fit the stack.
    let t = [Vec3::ZERO, Vec3::X, Vec3::Y];
    let g = Geometry { tris: vec![t; 20_000], spheres: vec![], quads: vec![] };
    let b = g.build();
    check_structure(&g, &b);
    // Huge but finite coordinates: no overflow in the builder.
    let mut rng = Pcg64::seed_from_u64(7);
    let tris: Vec<[Vec3; 3]> =
        (0..2000).map(|_| [v3(&mut rng, -1e30, 1e30), v3(&mut rng, -1e30, 1e30), v3(&mut rng, -1e30, 1e30)]).collect();
    let g = Geometry { tris, spheres: vec![], quads: vec![] };
    let b = g.build();
    check_structure(&g, &b);
    // A flat scene (zero extent along z) and a line of spheres.
    let tris: Vec<[Vec3; 3]> = (0..1000)
        .map(|i| {
            let x = i as f32;
            [Vec3::new(x, 0.0, 0.0), Vec3::new(x + 1.0, 0.0, 0.0), Vec3::new(x, 1.0, 0.0)]
        })
        .collect();
    let spheres: Vec<GpuSphere> =
        (0..1000).map(|i| GpuSphere { center: [i as f32, 5.0, 0.0], radius: 0.25, ..Default::default() }).collect();
    let g = Geometry { tris, spheres, quads: vec![] };
    check_structure(&g, &g.build());
}

// ---------------------------------------------------------------------------------------------------------------
// GPU: traversal against the reference

#[test]
fn gpu_traversal_matches_reference_on_soup() {
    let ctx = gpu();
    let g = soup(2);
    let b = g.build();
    let rays = make_rays(&g, 120_000, 3);
    let t0 = std::time::Instant::now();
    let gpu = gpu_trace(&ctx, &g, &b, &rays);
    let gpu_s = t0.elapsed().as_secs_f64();
    let t0 = std::time::Instant::now();
    let refs = reference_hits(&g, &rays);
    eprintln!("soup: GPU {gpu_s:.2} s, reference {:.2} s", t0.elapsed().as_secs_f64());
    let s = compare(&g, &rays, &gpu, &refs, EDGE_MARGIN);
    check("soup", &s, 1e-3);
    assert!(s.hits as f64 > 0.6 * s.rays as f64, "rays should mostly hit");
}

#[test]
fn gpu_traversal_matches_reference_on_damaged_helmet() {
    let ctx = gpu();
    let g = helmet();
    let b = g.build();
    check_structure(&g, &b);
    eprintln!(
        "DamagedHelmet: {} triangles, build {:.1} ms, {} nodes, depth {}, {:.1} bytes/triangle, SAH {:.2}",
        g.tris.len(),
        b.build_seconds * 1e3,
        b.node_count(),
        b.depth(),
        b.bytes_per_triangle(),
        b.sah_cost
    );
    let rays = make_rays(&g, 100_000, 4);
    let t0 = std::time::Instant::now();
    let gpu = gpu_trace(&ctx, &g, &b, &rays);
    let gpu_s = t0.elapsed().as_secs_f64();
    let t0 = std::time::Instant::now();
    let refs = reference_hits(&g, &rays);
    eprintln!("DamagedHelmet: GPU {gpu_s:.2} s, reference {:.2} s", t0.elapsed().as_secs_f64());
    let s = compare(&g, &rays, &gpu, &refs, EDGE_MARGIN);
    check("DamagedHelmet", &s, 1e-3);
    assert!(s.hits as f64 > 0.6 * s.rays as f64, "rays should mostly hit");
}

/// Both traversals agree with the reference: the speculative one (subgroupAll vote, where the device has subgroup
/// operations, as lavapipe does) that every other test runs, and the per-lane vote a device without them gets
/// (the source with the vote's marker line changed, so `shaders::for_device` leaves it alone).
#[test]
fn gpu_traversal_without_subgroups_matches_reference() {
    let ctx = gpu();
    let source = probe_source();
    let with_vote = mislab::render::shaders::for_device(&source, ctx.device.features());
    let subgroups = ctx.device.features().contains(wgpu::Features::SUBGROUP);
    assert_eq!(
        with_vote.contains("return subgroupAll(b);"),
        subgroups,
        "the vote must follow the device's subgroup feature"
    );
    let fallback = source.replace("return b; // BVH_VOTE", "return b;");
    assert!(!mislab::render::shaders::for_device(&fallback, ctx.device.features()).contains("return subgroupAll(b);"));
    for (name, g, seed) in [("soup", soup(5), 6), ("DamagedHelmet", helmet(), 7)] {
        let b = g.build();
        let rays = make_rays(&g, 30_000, seed);
        let gpu = gpu_trace_source(&ctx, &g, &b, &rays, &fallback);
        let refs = reference_hits(&g, &rays);
        let s = compare(&g, &rays, &gpu, &refs, EDGE_MARGIN);
        check(&format!("{name} without subgroups"), &s, 1e-3);
        assert!(s.hits as f64 > 0.6 * s.rays as f64, "rays should mostly hit");
    }
}

#[test]
fn gpu_empty_and_single_primitive_scenes() {
    let ctx = gpu();
    let mut rng = Pcg64::seed_from_u64(5);
    // Empty scene (and one where everything is excluded): every ray misses.
    let p = Vec3::ONE;
    for g in [
        Geometry { tris: vec![], spheres: vec![], quads: vec![] },
        Geometry {
            tris: vec![[p, p, p]],
            spheres: vec![GpuSphere { radius: 0.0, ..Default::default() }],
            quads: vec![],
        },
    ] {
        let b = g.build();
        let rays: Vec<ProbeRay> = (0..4096)
            .map(|_| ProbeRay {
                o: v3(&mut rng, -2.0, 2.0).into(),
                t_max: f32::MAX,
                d: unit(&mut rng).as_vec3().into(),
                _pad: 0.0,
            })
            .collect();
        let out = gpu_trace(&ctx, &g, &b, &rays);
        assert!(out.iter().all(|h| h.prim == INVALID && h.any == 0 && h.t == f32::MAX), "a ray hit an empty scene");
    }
    // One triangle, one sphere, one quad, each alone (the root is a single leaf).
    let singles = [
        Geometry {
            tris: vec![[Vec3::new(-1.0, -1.0, 0.2), Vec3::new(1.0, -0.5, 0.0), Vec3::new(0.0, 1.0, -0.3)]],
            spheres: vec![],
            quads: vec![],
        },
        Geometry {
            tris: vec![],
            spheres: vec![GpuSphere { center: [0.2, -0.1, 0.3], radius: 0.7, ..Default::default() }],
            quads: vec![],
        },
        Geometry {
            tris: vec![],
            spheres: vec![],
            quads: vec![GpuQuad {
                corner: [-0.5, -0.5, 0.1],
                edge_u: [1.0, 0.2, 0.0],
                edge_v: [0.1, 0.9, 0.3],
                ..Default::default()
            }],
        },
    ];
    for (k, g) in singles.iter().enumerate() {
        let b = g.build();
        assert_eq!(b.nodes.len(), 1);
        let mut rays = make_rays(g, 8192, 10 + k as u64);
        // Rays starting inside the sphere must hit its far side.
        rays.extend((0..1024).map(|_| ProbeRay {
            o: [0.2, -0.1, 0.3],
            t_max: f32::MAX,
            d: unit(&mut rng).as_vec3().into(),
            _pad: 0.0,
        }));
        let gpu = gpu_trace(&ctx, g, &b, &rays);
        let refs: Vec<_> = rays.iter().map(|r| reference::closest(&g.scene(), &ray64(r))).collect();
        let s = compare(g, &rays, &gpu, &refs, EDGE_MARGIN);
        check(&format!("single primitive {k}"), &s, 1e-3);
        assert!(s.hits > 4000);
    }
}

#[test]
fn gpu_degenerate_rays_miss() {
    // NaN/Inf origins or directions, a zero direction, and t_max ≤ 0 or NaN: no hit, no hang.
    let ctx = gpu();
    let g = soup(4);
    let b = g.build();
    let (nan, inf) = (f32::NAN, f32::INFINITY);
    let good_o = [0.0, 0.0, -5.0];
    let good_d = [0.0, 0.0, 1.0];
    let cases = [
        ([nan, 0.0, -5.0], good_d, f32::MAX),
        ([inf, 0.0, -5.0], good_d, f32::MAX),
        (good_o, [0.0, nan, 1.0], f32::MAX),
        (good_o, [0.0, 0.0, inf], f32::MAX),
        (good_o, [0.0, 0.0, 0.0], f32::MAX),
        (good_o, good_d, 0.0),
        (good_o, good_d, -1.0),
        (good_o, good_d, nan),
        (good_o, good_d, -inf),
    ];
    let rays: Vec<ProbeRay> = cases.iter().map(|&(o, d, t_max)| ProbeRay { o, t_max, d, _pad: 0.0 }).collect();
    let out = gpu_trace(&ctx, &g, &b, &rays);
    for (c, h) in cases.iter().zip(&out) {
        assert!(h.prim == INVALID && h.any == 0, "ray {c:?} should miss: {h:?}");
    }
    // The control ray (finite, t_max large) does hit the soup.
    let control = gpu_trace(&ctx, &g, &b, &[ProbeRay { o: good_o, t_max: f32::MAX, d: good_d, _pad: 0.0 }]);
    assert!(control[0].prim != INVALID || reference::closest(&g.scene(), &ray64(&rays[0])).is_none());
}

#[test]
fn gpu_far_small_sphere() {
    // A 1 cm sphere 10 km from the ray origins. The textbook discriminant b² − ac cancels ~1e8 against ~1e8 and
    // loses the sphere entirely in f32; the RTG ch. 7 form keeps an error of about ulp(|o − c|) ≈ 5e-4, i.e.
    // ~5 % of the radius, so hit/miss may differ only in a band near the silhouette (margin < 0.25, see compare).
    let ctx = gpu();
    let c = DVec3::new(1e4, 3e3, -2e3);
    let r = 0.01;
    let g = Geometry {
        tris: vec![],
        spheres: vec![GpuSphere { center: c.as_vec3().into(), radius: r as f32, ..Default::default() }],
        quads: vec![],
    };
    let b = g.build();
    let mut rng = Pcg64::seed_from_u64(21);
    let rays: Vec<ProbeRay> = (0..20_000)
        .map(|_| {
            let o = unit(&mut rng) * rng.random::<f64>();
            let target = c + (DVec3::new(rng.random(), rng.random(), rng.random()) * 2.0 - 1.0) * 1.5 * r;
            ProbeRay { o: o.as_vec3().into(), t_max: f32::MAX, d: (target - o).normalize().as_vec3().into(), _pad: 0.0 }
        })
        .collect();
    let gpu = gpu_trace(&ctx, &g, &b, &rays);
    let refs: Vec<_> = rays.iter().map(|r| reference::closest(&g.scene(), &ray64(r))).collect();
    let s = compare(&g, &rays, &gpu, &refs, 0.25);
    check("far small sphere", &s, 0.3);
    assert!(s.hits > 4000, "{} hits", s.hits);
}

/// A ray from `o` towards `target`, with the distance at which it should hit there.
fn aimed_ray(o: Vec3, target: Vec3) -> (f64, ProbeRay) {
    let d = (target - o).normalize();
    ((target - o).length() as f64, ProbeRay { o: o.into(), t_max: f32::MAX, d: d.into(), _pad: 0.0 })
}

/// How many aimed rays missed, and how many hit farther than `tol` (relative) from their aim point.
fn misses_and_strays(out: &[ProbeTrace], rays: &[(f64, ProbeRay)], tol: f64) -> (usize, usize) {
    let misses = out.iter().filter(|h| h.prim == INVALID).count();
    let far = out.iter().zip(rays).filter(|(h, (dist, _))| h.prim != INVALID && rel(h.t as f64, *dist) > tol).count();
    (misses, far)
}

/// A closed, bumpy "cube sphere": six n×n grids whose vertices are a function of their integer lattice point, so
/// the vertices shared across faces are bit-identical. Rotated randomly, scaled by `size`, moved to `center`.
fn closed_mesh(n: i32, size: f32, center: Vec3, rng: &mut Pcg64) -> Vec<[Vec3; 3]> {
    let rot = glam::Quat::from_axis_angle(unit(rng).as_vec3(), rng.random_range(0.0..std::f32::consts::TAU));
    let vert = |p: glam::IVec3| {
        let c = (p.as_vec3() / n as f32) * 2.0 - 1.0;
        let bump = 1.0 + 0.15 * (3.0 * c.x).sin() * (2.0 * c.y).cos() * (2.5 * c.z + 1.0).sin();
        center + rot * (c.normalize() * bump * size)
    };
    cube_faces(n, vert)
}

/// The six n×n grids of a cube's surface, two triangles a cell (alternating diagonals, so vertices have different
/// valences), with lattice point p placed at `vert(p)`: the vertices shared across faces are bit-identical.
fn cube_faces(n: i32, vert: impl Fn(glam::IVec3) -> Vec3) -> Vec<[Vec3; 3]> {
    let mut tris = Vec::new();
    for axis in 0..3 {
        for side in [0, n] {
            for i in 0..n {
                for j in 0..n {
                    let p = |a: i32, b: i32| {
                        let mut v = glam::IVec3::ZERO;
                        v[axis] = side;
                        v[(axis + 1) % 3] = a;
                        v[(axis + 2) % 3] = b;
                        vert(v)
                    };
                    let (a, b, c, d) = (p(i, j), p(i + 1, j), p(i + 1, j + 1), p(i, j + 1));
                    // Alternate the diagonal so vertices have different valences.
                    if (i + j) % 2 == 0 {
                        tris.push([a, b, c]);
                        tris.push([a, c, d]);
                    } else {
                        tris.push([a, b, d]);
                        tris.push([b, c, d]);
                    }
                }
            }
        }
    }
    tris
}

#[test]
fn gpu_watertight_through_edges_and_vertices() {
    // Rays from near the centre of a closed star-shaped mesh, aimed exactly at its shared edges and vertices, cross
    // the surface exactly once, transversally: each must hit at the aim point. A crack between adjacent triangles
    // (edge functions of the two triangles disagreeing in sign) would let some through.
    let ctx = gpu();
    let mut rng = Pcg64::seed_from_u64(31);
    // The far meshes: a node's origin far from the ray's and from the world's, where the wide slab test's node-frame
    // form (shaders/bvh_wide.wgsl `wide_node_hits`) leans on its rounding pad.
    let meshes =
        [(Vec3::ZERO, 1.0f32), (Vec3::new(700.0, -300.0, 1200.0), 50.0), (Vec3::new(-2.0e4, 1.0e4, 3.0e4), 400.0)];
    for (center, size) in meshes {
        let tris = closed_mesh(12, size, center, &mut rng);
        let g = Geometry { tris, spheres: vec![], quads: vec![] };
        // Both layouts: the BVH2 with 50 000 rays, the wide tree with 20 000.
        for (b, source, n) in [(g.build(), probe_source(), 50_000), (g.build_wide(), wide_source(), 20_000)] {
            let rays: Vec<(f64, ProbeRay)> = (0..n)
                .map(|k| {
                    let t = g.tris[rng.random_range(0..g.tris.len())];
                    let e = rng.random_range(0..3);
                    // A vertex, or a point on an edge interpolated in f32 as a renderer would.
                    let target = if k % 4 == 0 { t[e] } else { t[e].lerp(t[(e + 1) % 3], rng.random::<f32>()) };
                    // Every eighth ray starts just inside the surface, a thousandth of the way from its vertex
                    // target to the centre: a short ray through large nodes, whose origins are far from its own.
                    let o = if k % 8 == 4 {
                        target + (center - target) * 1e-3
                    } else {
                        center + (unit(&mut rng) * 0.05).as_vec3() * size * rng.random::<f32>()
                    };
                    aimed_ray(o, target)
                })
                .collect();
            let inputs: Vec<ProbeRay> = rays.iter().map(|r| r.1).collect();
            let out = gpu_trace_source(&ctx, &g, &b, &inputs, &source);
            let (misses, far) = misses_and_strays(&out, &rays, 1e-4);
            assert_eq!(
                misses,
                0,
                "{misses} of {} rays through edges/vertices leaked (mesh at {center}, size {size})",
                rays.len()
            );
            assert_eq!(far, 0, "{far} rays hit away from their aim point (mesh at {center}, size {size})");
        }
    }
}

#[test]
fn gpu_wide_traversal_finds_axis_aligned_corners_far_from_the_origin() {
    // An axis-aligned cube of 16×16 quads a face, far from the world's origin, with every vertex and edge midpoint
    // exactly representable: faces lie on the quantised boxes' planes and rays aimed at grid points pass exactly
    // through box edges and corners, where a slab test that rounds past its interval drops a box. Half the rays
    // start a thousandth of the way in from their target (short rays through nodes whose origins are far away).
    let ctx = gpu();
    let mut rng = Pcg64::seed_from_u64(77);
    let (n, h, center) = (16, 64.0f32, Vec3::new(20_000.0, -9_000.0, 31_000.0));
    let grid = |v: glam::IVec3| center + (v.as_vec3() * (2.0 / n as f32) - 1.0) * h;
    let tris = cube_faces(n, grid);
    let g = Geometry { tris, spheres: vec![], quads: vec![] };
    let b = g.build_wide();
    let rays: Vec<(f64, ProbeRay)> = (0..40_000)
        .map(|k| {
            let t = g.tris[rng.random_range(0..g.tris.len())];
            let e = rng.random_range(0..3);
            let target = if k % 2 == 0 { t[e] } else { (t[e] + t[(e + 1) % 3]) * 0.5 };
            let o = if k % 4 < 2 {
                target + (center - target) * 1e-3
            } else {
                center + (unit(&mut rng) * 0.5).as_vec3() * h * rng.random::<f32>()
            };
            aimed_ray(o, target)
        })
        .collect();
    let inputs: Vec<ProbeRay> = rays.iter().map(|r| r.1).collect();
    let out = gpu_trace_source(&ctx, &g, &b, &inputs, &wide_source());
    let (misses, far) = misses_and_strays(&out, &rays, 1e-3);
    assert_eq!(misses, 0, "{misses} of {} rays through the cube's grid points leaked", rays.len());
    assert_eq!(far, 0, "{far} rays hit away from their grid point");
}

// ---------------------------------------------------------------------------------------------------------------
// The 8-wide compressed BVH (src/accel/wide_bvh.rs, shaders/bvh_wide.wgsl)

/// The wide tree references every included primitive (each reference slot in exactly one leaf), each decoded
/// (quantised) child box contains the exact box of everything below it, leaves fit the 24 primitive bits and cover
/// their primitives ([`check_leaf_cover`]), interior children follow `child_base` in slot order, and the depth fits
/// the traversal stack. A pre-split triangle's piece is known only by its leaf's box, so a triangle counts below a
/// leaf by the box of one of its pieces (the split is deterministic: `pieces` repeats it) that the leaf's decoded
/// box holds.
fn check_wide_structure(g: &Geometry, b: &Bvh, presplit: bool) {
    use mislab::accel::presplit::{self, Piece};
    use mislab::accel::wide_bvh::{self, WideChild, MAX_NODE_PRIMS, MAX_WIDE_DEPTH, WIDTH};
    assert!(!b.wide.is_empty(), "not a wide tree");
    assert!(wide_bvh::depth(&b.wide) <= MAX_WIDE_DEPTH, "wide depth {}", wide_bvh::depth(&b.wide));
    let whole: Vec<Piece> = (0..g.tris.len() as u32)
        .filter_map(|t| bvh::triangle_aabb(&g.tris[t as usize]).map(|bx| Piece { tri: t, bx }))
        .collect();
    let budget = if presplit { (presplit::BUDGET * whole.len() as f64) as usize } else { 0 };
    let mut pieces: Vec<Vec<bvh::Aabb>> = vec![Vec::new(); g.tris.len()];
    presplit::split(&whole, &g.tris, budget).iter().for_each(|p| pieces[p.tri as usize].push(p.bx));
    struct Walk<'a> {
        g: &'a Geometry,
        b: &'a Bvh,
        pieces: Vec<Vec<bvh::Aabb>>,
        seen: Vec<u32>,
        visited: Vec<bool>,
        found: Vec<(bvh::Aabb, u32, usize)>,
    }
    // Exact box and primitive count of node n's subtree, checking its children's decoded boxes on the way.
    fn subtree(n: usize, w: &mut Walk) -> (bvh::Aabb, u32) {
        assert!(!std::mem::replace(&mut w.visited[n], true), "wide node {n} reached twice");
        let node = w.b.wide[n];
        let (mut total, mut prims, mut interior) = (bvh::Aabb::EMPTY, 0, 0);
        for i in 0..WIDTH {
            let decoded = node.child_box(i);
            let (exact, count) = match node.child(i) {
                WideChild::Empty => continue,
                WideChild::Interior(c) => {
                    assert_eq!(c, node.links[0] + interior, "interior children in slot order");
                    interior += 1;
                    // (The collapse may keep a node over as few as two primitives where the SAH says so.)
                    let (bx, count) = subtree(c as usize, w);
                    assert!(count >= 2, "node {n} slot {i}: a node over only {count} primitive(s)");
                    (bx, count)
                }
                WideChild::Leaf { first, count } => {
                    assert!((1..=4).contains(&count) && first - node.links[1] + count <= MAX_NODE_PRIMS);
                    let bx = (first..first + count).fold(bvh::Aabb::EMPTY, |a, k| {
                        w.seen[k as usize] += 1;
                        let p = w.b.prim_refs[k as usize];
                        w.found.push((decoded, p, first as usize));
                        let part = if p >> 30 == PRIM_TRIANGLE {
                            let t = (p & mislab::gpu::types::PRIM_INDEX_MASK) as usize;
                            *w.pieces[t].iter().find(|bx| decoded.contains(bx)).unwrap_or_else(|| {
                                panic!("node {n} slot {i}: no piece of triangle {t} fits the leaf's box")
                            })
                        } else {
                            prim_box(w.g, p)
                        };
                        a.union(&part)
                    });
                    (bx, count)
                }
            };
            assert!(decoded.contains(&exact), "node {n} slot {i}: quantised box does not hold its child");
            total = total.union(&exact);
            prims += count;
        }
        (total, prims)
    }
    let mut w = Walk {
        g,
        b,
        pieces,
        seen: vec![0u32; b.prim_refs.len()],
        visited: vec![false; b.wide.len()],
        found: Vec::new(),
    };
    subtree(0, &mut w);
    assert!(w.visited.iter().all(|&v| v), "unreachable wide nodes");
    assert!(w.seen.iter().all(|&c| c == 1), "a primitive reference is not in exactly one leaf");
    check_leaf_cover(g, &w.found);
    let mut refs = b.prim_refs.clone();
    refs.sort_unstable();
    refs.dedup();
    let included = reference::all_prims(&g.scene()).filter(|&p| is_included(g, p)).count();
    assert_eq!(refs.len(), included, "every included primitive at least once");
}

#[test]
fn wide_build_invariants() {
    let p = Vec3::ONE;
    let t = [Vec3::ZERO, Vec3::X, Vec3::Y];
    let mut rng = Pcg64::seed_from_u64(8);
    let huge: Vec<[Vec3; 3]> =
        (0..2000).map(|_| [v3(&mut rng, -1e30, 1e30), v3(&mut rng, -1e30, 1e30), v3(&mut rng, -1e30, 1e30)]).collect();
    let tiny: Vec<[Vec3; 3]> = (0..2000)
        .map(|_| {
            let c = v3(&mut rng, 1e4, 1e4 + 1.0);
            [c, c + v3(&mut rng, -1e-3, 1e-3), c + v3(&mut rng, -1e-3, 1e-3)]
        })
        .collect();
    let cases = [
        ("soup", soup(1)),
        ("helmet", helmet()),
        ("empty", Geometry { tris: vec![], spheres: vec![], quads: vec![] }),
        ("junk", Geometry { tris: vec![[p, p, p]], spheres: vec![], quads: vec![] }),
        ("one", Geometry { tris: vec![t], spheres: vec![], quads: vec![] }),
        // (build_pathological_inputs has 20 000; PLOC takes ~15 CPU-s over them.)
        ("coincident", Geometry { tris: vec![t; 2000], spheres: vec![], quads: vec![] }),
        ("huge", Geometry { tris: huge, spheres: vec![], quads: vec![] }),
        ("tiny far from the origin", Geometry { tris: tiny, spheres: vec![], quads: vec![] }),
    ];
    for (name, g) in cases {
        let b = g.build_wide();
        check_wide_structure(&g, &b, true);
        eprintln!(
            "{name}: {} wide nodes, depth {}, {:.1} bytes/triangle",
            b.wide.len(),
            mislab::accel::wide_bvh::depth(&b.wide),
            b.bytes_per_triangle(),
        );
    }
}

/// A triangle-only scene uploads `IDENTITY_PRIM_REFS` instead of its references, which are then the identity
/// (src/render/scene_data/mod.rs): the generic traversal, which reads `prim_refs`, must find the same hits with it as
/// with the identity uploaded.
#[test]
fn gpu_identity_prim_refs_read_as_the_leaf_order() {
    let ctx = gpu();
    let g = helmet();
    let mut b = g.build_wide();
    let order = bvh::into_leaf_order(&mut b, g.tris.len());
    let g = Geometry { tris: order.iter().map(|&i| g.tris[i as usize]).collect(), spheres: vec![], quads: vec![] };
    assert!(b.prim_refs.iter().enumerate().all(|(j, &r)| r == j as u32), "leaf order is not the identity");
    let rays = make_rays(&g, 20_000, 5);
    let uploaded = gpu_trace_source(&ctx, &g, &b, &rays, &wide_source());
    b.prim_refs = mislab::render::scene_data::IDENTITY_PRIM_REFS.to_vec();
    let sentinel = gpu_trace_source(&ctx, &g, &b, &rays, &wide_source());
    let hits = uploaded.iter().filter(|h| h.prim != INVALID).count();
    assert!(hits as f64 > 0.6 * rays.len() as f64, "rays should mostly hit ({hits} of {})", rays.len());
    let same = uploaded.iter().zip(&sentinel).filter(|(a, b)| a.prim == b.prim && a.t == b.t).count();
    assert_eq!(same, rays.len(), "hits differ with IDENTITY_PRIM_REFS");
}

/// The wide traversal's closest and any hits against the f64 reference (soup of all kinds, DamagedHelmet, single
/// primitives), and its closest hits against the BVH2 traversal's. (It has no subgroup vote: a lane holding a leaf
/// group waits for its SIMD group, so devices with and without subgroups run the same code.)
#[test]
fn gpu_wide_traversal_matches_reference_and_bvh2() {
    let ctx = gpu();
    let wide = wide_source();
    assert!(!wide[wide.find("fn wide_traverse").unwrap()..].contains("bvh_all_lanes"), "the wide loop votes again");
    for (name, g, seed, n) in [("soup", soup(2), 3, 60_000), ("DamagedHelmet", helmet(), 4, 60_000)] {
        let bw = g.build_wide();
        let rays = make_rays(&g, n, seed);
        let refs = reference_hits(&g, &rays);
        let gw = gpu_trace_source(&ctx, &g, &bw, &rays, &wide);
        let s = compare(&g, &rays, &gw, &refs, EDGE_MARGIN);
        check(&format!("{name} (wide)"), &s, 1e-3);
        assert!(s.hits as f64 > 0.6 * s.rays as f64, "rays should mostly hit");
        // Same closest hits as the BVH2: the same primitive at the same t, up to ties.
        let g2 = gpu_trace(&ctx, &g, &g.build(), &rays);
        let same = gw.iter().zip(&g2).filter(|(a, b)| a.prim == b.prim && a.t == b.t).count();
        eprintln!("{name}: wide and BVH2 agree on {same} of {} rays", rays.len());
        assert!(same as f64 >= 0.999 * rays.len() as f64, "wide and BVH2 closest hits differ on {} rays", n - same);
    }
    let singles = [
        Geometry { tris: vec![[Vec3::new(-1.0, -1.0, 0.2), Vec3::X, Vec3::Y]], spheres: vec![], quads: vec![] },
        Geometry {
            tris: vec![],
            spheres: vec![GpuSphere { center: [0.2, -0.1, 0.3], radius: 0.7, ..Default::default() }],
            quads: vec![],
        },
        Geometry { tris: vec![], spheres: vec![], quads: vec![] },
    ];
    for (k, g) in singles.iter().enumerate() {
        let b = g.build_wide();
        let rays = make_rays(g, 4096, 40 + k as u64);
        let gpu = gpu_trace_source(&ctx, g, &b, &rays, &wide);
        let refs: Vec<_> = rays.iter().map(|r| reference::closest(&g.scene(), &ray64(r))).collect();
        let s = compare(g, &rays, &gpu, &refs, EDGE_MARGIN);
        check(&format!("wide, single primitive {k}"), &s, 1e-3);
    }
}

/// The two ways of reading vertices and wide nodes (shaders/geometry_loads.wgsl, 16 bytes a load, and its `_int64`
/// twin, 32 bytes a load, which a device with 64-bit integers gets) find the same hits, bit for bit: on odd and even
/// counts of triangles and nodes (the twin's odd elements start mid-element), and on no geometry at all. The
/// portable file is kept by changing its first line, so `shaders::for_device` no longer recognises it.
#[test]
fn gpu_16_and_32_byte_loads_find_the_same_hits() {
    let ctx = gpu();
    let wide = wide_source();
    let int64 = ctx.device.features().contains(wgpu::Features::SHADER_INT64);
    let as_compiled = mislab::render::shaders::for_device(&wide, ctx.device.features());
    assert_eq!(as_compiled.contains("var<storage, read> wide_nodes: array<vec4<u64>>"), int64);
    let loads = mislab::render::shaders::file("geometry_loads.wgsl");
    let kept = loads.replacen("// geometry_loads.wgsl", "// geometry_loads.wgsl (kept)", 1);
    let portable = wide.replace(loads.as_ref(), &kept);
    assert!(!mislab::render::shaders::for_device(&portable, ctx.device.features()).contains("vec4<u64>"));
    let odd = Geometry { tris: soup(9).tris[..1001].to_vec(), spheres: vec![], quads: vec![] };
    let one = Geometry { tris: vec![[Vec3::new(-1.0, -1.0, 0.2), Vec3::X, Vec3::Y]], spheres: vec![], quads: vec![] };
    let none = Geometry { tris: vec![], spheres: vec![], quads: vec![] };
    for (name, g, seed) in [
        ("soup", soup(8), 10),
        ("DamagedHelmet", helmet(), 11),
        ("odd soup", odd, 12),
        ("one", one, 13),
        ("none", none, 14),
    ] {
        let b = g.build_wide();
        let rays = make_rays(&g, 20_000, seed);
        let a = gpu_trace_source(&ctx, &g, &b, &rays, &wide);
        let p = gpu_trace_source(&ctx, &g, &b, &rays, &portable);
        let bits = |t: &ProbeTrace| (t.prim, t.t.to_bits(), t.b1.to_bits(), t.b2.to_bits(), t.any);
        let differ = a.iter().zip(&p).filter(|(x, y)| bits(x) != bits(y)).count();
        eprintln!(
            "{name}: {} triangles, {} wide nodes, {} rays, {differ} differ",
            g.tris.len(),
            b.wide.len(),
            rays.len()
        );
        assert_eq!(differ, 0, "{name}: 16- and 32-byte loads disagree on {differ} rays");
    }
}

// ---------------------------------------------------------------------------------------------------------------
// GPU: offset_ray_origin

/// A wavy grid mesh of `n`×`n` cells of size `cell`, rotated randomly and centred at `center`.
fn wavy_mesh(center: Vec3, cell: f32, n: usize, rng: &mut Pcg64) -> Vec<[Vec3; 3]> {
    let axis = unit(rng).as_vec3();
    let rot = glam::Quat::from_axis_angle(axis, rng.random_range(0.0..std::f32::consts::TAU));
    let vert = |i: usize, j: usize| {
        let x = (i as f32 - n as f32 / 2.0) * cell;
        let z = (j as f32 - n as f32 / 2.0) * cell;
        let y = cell * ((i as f32 * 0.9).sin() + (j as f32 * 1.3).cos());
        center + rot * Vec3::new(x, y, z)
    };
    let mut tris = Vec::new();
    for i in 0..n {
        for j in 0..n {
            let (a, b, c, d) = (vert(i, j), vert(i + 1, j), vert(i + 1, j + 1), vert(i, j + 1));
            tris.push([a, b, c]);
            tris.push([a, c, d]);
        }
    }
    tris
}

#[test]
fn gpu_offset_ray_origin_avoids_self_intersection() {
    let ctx = gpu();
    let mut rng = Pcg64::seed_from_u64(9);
    let mut total = 0;
    // Magnitudes from the float-offset region around the origin up to 1e5, both signs.
    for (k, &(mag, cell)) in
        [(0.0f32, 0.01f32), (0.05, 0.01), (1.0, 0.1), (300.0, 1.0), (2e4, 10.0), (1e5, 10.0), (1e5, 0.5)]
            .iter()
            .enumerate()
    {
        let center = if mag == 0.0 { Vec3::ZERO } else { unit(&mut rng).as_vec3() * mag };
        let tris = wavy_mesh(center, cell, 32, &mut rng);
        let g = Geometry { tris, spheres: vec![], quads: vec![] };
        let b = g.build();
        let spawns: Vec<(usize, ProbeSpawn)> = (0..20_000)
            .map(|_| {
                let i = rng.random_range(0..g.tris.len());
                let [v0, v1, v2] = g.tris[i];
                let (mut a, mut c) = (rng.random::<f32>(), rng.random::<f32>());
                if a + c > 1.0 {
                    (a, c) = (1.0 - a, 1.0 - c);
                }
                // The hit point as a shader would interpolate it, in f32.
                let p = v0 + a * (v1 - v0) + c * (v2 - v0);
                let side = if rng.random::<bool>() { 1.0 } else { -1.0 };
                let ng = (v1 - v0).cross(v2 - v0).normalize() * side;
                // Cosine-distributed, plus grazing directions.
                let cos = if rng.random::<f32>() < 0.3 {
                    rng.random_range(1e-4..0.02f32)
                } else {
                    rng.random::<f32>().sqrt().max(1e-4)
                };
                let t = ng.any_orthonormal_vector();
                let bt = ng.cross(t);
                let phi = rng.random_range(0.0..std::f32::consts::TAU);
                let sin = (1.0 - cos * cos).sqrt();
                let d = (ng * cos + (t * phi.cos() + bt * phi.sin()) * sin).normalize();
                (i, ProbeSpawn { p: p.into(), ng: ng.into(), d: d.into(), ..Default::default() })
            })
            .collect();
        let inputs: Vec<ProbeSpawn> = spawns.iter().map(|s| s.1).collect();
        let buffers = GeometryBuffers::new(&ctx, &b, &g.tris, &g.spheres, &g.quads);
        let out: Vec<ProbeSpawnOut> = Probe::new(&ctx)
            .map(&probe_source(), "ProbeSpawn", "ProbeSpawnOut", "probe_spawn", &inputs, Some(&buffers))
            .unwrap_or_else(|e| panic!("{e}"));
        let mut self_hits = 0;
        for ((i, s), o) in spawns.iter().zip(&out) {
            let own = make_prim(PRIM_TRIANGLE, *i as u32);
            // The origin must have moved to the leaving side of the plane...
            let [v0, v1, v2] = g.tris[*i].map(|v| v.as_dvec3());
            let n = (v1 - v0).cross(v2 - v0).normalize()
                * Vec3::from(s.ng).as_dvec3().dot((v1 - v0).cross(v2 - v0)).signum();
            assert!(
                (Vec3::from(o.o).as_dvec3() - v0).dot(n) > 0.0,
                "case {k}: offset origin {:?} is not above the plane (p {:?})",
                o.o,
                s.p
            );
            // ...and the ray must not hit its own triangle.
            if o.prim == own {
                self_hits += 1;
            }
        }
        assert_eq!(
            self_hits,
            0,
            "case {k} (|p| ~ {mag}): {self_hits} of {} spawned rays re-hit their own triangle",
            spawns.len()
        );
        total += spawns.len();
    }
    eprintln!("offset_ray_origin: {total} spawned rays, no self-intersections");
}

#[test]
fn probe_reports_sentinel_and_shader_errors() {
    let ctx = gpu();
    let probe = Probe::new(&ctx);
    // A kernel that writes only even elements: the odd ones keep the sentinel.
    let src = "@group(1) @binding(0) var<storage, read_write> out: array<u32>;
               @group(1) @binding(1) var<storage, read> inp: array<u32>;
               @compute @workgroup_size(1) fn main(@builtin(global_invocation_id) g: vec3<u32>) {
                   if g.x % 2u == 0u { out[g.x] = inp[g.x] * 2u; }
               }";
    let input: Vec<u32> = (0..8).collect();
    let bytes = probe
        .run(&mislab::testkit::probe::ProbeJob {
            source: src,
            entry: "main",
            inputs: &[bytemuck::cast_slice(&input)],
            output_bytes: 32,
            workgroups: [8, 1, 1],
            constants: &[],
            geometry: None,
        })
        .unwrap();
    let out: Vec<u32> = bytemuck::pod_collect_to_vec(&bytes);
    assert_eq!(
        out,
        vec![
            0,
            mislab::testkit::probe::PROBE_SENTINEL,
            4,
            mislab::testkit::probe::PROBE_SENTINEL,
            8,
            mislab::testkit::probe::PROBE_SENTINEL,
            12,
            mislab::testkit::probe::PROBE_SENTINEL
        ]
    );
    // A map over more elements than one dispatch row would hold is not needed here; check a plain map and errors.
    let doubled: Vec<f32> = probe
        .map("fn twice(x: f32) -> f32 { return 2.0 * x; }", "f32", "f32", "twice", &[1.0f32, 2.5, -3.0], None)
        .unwrap();
    assert_eq!(doubled, vec![2.0, 5.0, -6.0]);
    // More elements than one row of 65535 workgroups holds: the 2D dispatch must cover every one exactly once.
    let many: Vec<u32> = (0..65_535 * 64 + 1000).collect();
    let out: Vec<u32> =
        probe.map("fn f(x: u32) -> u32 { return 3u * x + 1u; }", "u32", "u32", "f", &many, None).unwrap();
    assert!(out.iter().zip(&many).all(|(o, x)| *o == 3 * x + 1), "2D dispatch missed elements");
    let err = probe
        .map::<f32, f32>("fn twice(x: f32) -> f32 { return 2.0 * y; }", "f32", "f32", "twice", &[1.0], None)
        .unwrap_err();
    assert!(err.to_string().contains("y"), "{err}");
}
