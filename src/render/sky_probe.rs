//! Whether a view needs the environment guide (`--env-sampling auto`, the default): a few thousand rays traced on
//! the CPU before any shader is compiled.
//!
//! The guide (`env_guide`) pays where the surfaces the camera sees are lit by a constant sky through openings (the
//! interiors: 1.2–2× lower error at equal samples). Where those surfaces see most of the sky it draws nothing (no
//! slot of the DamagedHelmet's guide is guided) and only costs: its code in the kernel (a sixth of a first
//! compilation on Mesa 25) and its learning pass, an extra dispatch and read-back per render. The probe measures
//! what the guide would learn, at the first vertex only: from a grid of camera rays, the sky seen from each surface
//! hit (cosine-distributed rays about its normal), turned into the share of light samples the guide would draw
//! there (`env_guide::guide_share`, the guide's own rule). Their mean over the camera rays is `guided_share`.

use crate::accel::bvh::reference::{self, Ray};
use crate::accel::wide_bvh::GpuWideNode;
use crate::accel::wide_node::WideChild;
use crate::gpu::types::{
    make_prim, GpuQuad, GpuSphere, INVALID, PRIM_INDEX_MASK, PRIM_KIND_SHIFT, PRIM_QUAD, PRIM_SPHERE,
};
use crate::render::env_guide;
use crate::render::scene_data::{SceneData, FLAT_MAX_PRIMS};
use crate::scene::Camera;
use glam::{DVec3, Vec3};

/// Camera rays along each side of the probe's grid (fewer on a smaller film).
pub const GRID: u32 = 24;
/// Sky rays from each surface a camera ray hits (a stratified cosine, 4 × 4).
pub const SKY_RAYS: u32 = 16;
/// Below this mean share of guided light samples the guide is left out (`SkyProbe::wants_guide`). The bench's open
/// scenes measure 0.00–0.03, its interiors 0.5–0.8 (docs/estimators.md, "Only where the sky is hidden").
pub const MIN_GUIDED_SHARE: f32 = 0.1;

/// What the probe saw.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SkyProbe {
    /// Camera rays traced.
    pub rays: u32,
    /// Of them, those that hit a surface.
    pub hits: u32,
    /// Mean over the camera rays (misses count 0) of the share of light samples the guide would draw at the hit.
    pub guided_share: f32,
}

impl SkyProbe {
    /// Whether the guide would draw enough of the first vertices' light samples to pay for itself.
    pub fn wants_guide(&self) -> bool {
        self.guided_share >= MIN_GUIDED_SHARE
    }
}

/// The scene's geometry as the probe intersects it: the wide BVH's nodes and leaves (or every primitive of a flat
/// scene), and the occluder triangles baked outside the BVH.
struct Geometry<'a> {
    d: &'a SceneData,
}

/// A closest hit: distance and geometric normal (not normalised).
struct ProbeHit {
    t: f64,
    n: DVec3,
}

impl Geometry<'_> {
    fn triangle(&self, i: usize) -> [Vec3; 3] {
        let v = |k: usize| Vec3::from_slice(&self.d.tri_verts[3 * i + k][..3]);
        [v(0), v(1), v(2)]
    }

    /// Intersects primitive word `prim` (as `prim_refs` holds it).
    fn prim(&self, ray: &Ray, prim: u32) -> Option<ProbeHit> {
        let i = (prim & PRIM_INDEX_MASK) as usize;
        match prim >> PRIM_KIND_SHIFT {
            PRIM_SPHERE => {
                let s: &GpuSphere = self.d.spheres.get(i)?;
                let (t, _) = reference::sphere(ray, s, 0.0)?;
                Some(ProbeHit { t, n: ray.o + t * ray.d - Vec3::from(s.center).as_dvec3() })
            }
            PRIM_QUAD => {
                let q: &GpuQuad = self.d.quads.get(i)?;
                let (t, ..) = reference::quad(ray, q, 0.0)?;
                Some(ProbeHit { t, n: Vec3::from(q.edge_u).cross(Vec3::from(q.edge_v)).as_dvec3() })
            }
            _ => self.tri(ray, i),
        }
    }

    fn tri(&self, ray: &Ray, i: usize) -> Option<ProbeHit> {
        if 3 * i + 2 >= self.d.tri_verts.len() {
            return None;
        }
        let v = self.triangle(i);
        let (t, ..) = reference::triangle(ray, &v, 0.0)?;
        Some(ProbeHit { t, n: (v[1] - v[0]).cross(v[2] - v[0]).as_dvec3() })
    }

    /// The closest hit before `ray.t_max`; with `any`, the first found.
    fn trace(&self, ray: &Ray, any: bool) -> Option<ProbeHit> {
        let mut best: Option<ProbeHit> = None;
        let mut ray = *ray;
        // Takes a hit (it is closer than `ray.t_max`, which shrinks to it); true when the search may stop.
        let take = |h: Option<ProbeHit>, ray: &mut Ray, best: &mut Option<ProbeHit>| match h {
            Some(h) => {
                ray.t_max = h.t;
                *best = Some(h);
                any
            }
            None => false,
        };
        let (first, count) = self.d.occluders;
        for i in first..first + count {
            if take(self.tri(&ray, i as usize), &mut ray, &mut best) {
                return best;
            }
        }
        if self.d.wide_nodes.is_empty() {
            for p in self.flat_prims() {
                if take(self.prim(&ray, p), &mut ray, &mut best) {
                    return best;
                }
            }
            return best;
        }
        let inv = DVec3::ONE / ray.d;
        let mut stack = vec![0u32];
        while let Some(n) = stack.pop() {
            let node: &GpuWideNode = &self.d.wide_nodes[n as usize];
            for slot in 0..crate::accel::wide_node::WIDTH {
                let child = node.child(slot);
                if child == WideChild::Empty || !slab(&ray, inv, node, slot) {
                    continue;
                }
                match child {
                    WideChild::Interior(c) => stack.push(c),
                    WideChild::Leaf { first, count } => {
                        for j in first..first + count {
                            // A triangle-only scene uploads no `prim_refs`: entry j is triangle j.
                            let p = self.d.prim_refs.get(j as usize).copied().unwrap_or(INVALID);
                            let p = if p == INVALID { j } else { p };
                            if take(self.prim(&ray, p), &mut ray, &mut best) {
                                return best;
                            }
                        }
                    }
                    WideChild::Empty => {}
                }
            }
        }
        best
    }

    /// Every primitive of a scene without a wide BVH, as `prim_refs` words.
    fn flat_prims(&self) -> impl Iterator<Item = u32> + '_ {
        let d = self.d;
        let tris = match d.occluders {
            (first, count) if count > 0 => first,
            _ => (d.tri_verts.len() / 3) as u32,
        };
        (0..tris)
            .chain((0..d.spheres.len() as u32).map(|i| make_prim(PRIM_SPHERE, i)))
            .chain((0..d.quads.len() as u32).map(|i| make_prim(PRIM_QUAD, i)))
    }
}

/// Whether `ray` enters the (quantised, conservative) box of `node`'s slot before its `t_max`.
fn slab(ray: &Ray, inv: DVec3, node: &GpuWideNode, slot: usize) -> bool {
    let b = node.child_box(slot);
    let t0 = (b.min.as_dvec3() - ray.o) * inv;
    let t1 = (b.max.as_dvec3() - ray.o) * inv;
    let near = t0.min(t1).max_element().max(0.0);
    let far = t0.max(t1).min_element().min(ray.t_max);
    // NaN (a ray along a slab's face) keeps the box: conservative.
    !(near > far)
}

/// Probes what `camera` sees of `d` on a film of `width` × `height` (`probe`).
pub fn probe_view(d: &SceneData, camera: &Camera, width: u32, height: u32) -> Option<SkyProbe> {
    let (right, up, forward) = camera.frame();
    let (forward, tan_half_fov) = camera.cropped_view(forward, right, up, width, height);
    let aspect = width as f32 / height as f32;
    // The shader's camera ray (shaders/integrator.wgsl `camera_direction`) through film point (x, y).
    let ray = |x: f32, y: f32| {
        forward + (2.0 * x - 1.0) * tan_half_fov * aspect * right + (1.0 - 2.0 * y) * tan_half_fov * up
    };
    probe(d, camera.position - d.origin, ray, width, height)
}

/// Probes the view from `eye` (relative to the scene's origin) whose camera ray through film point (x, y) ∈ [0, 1]²
/// is `camera(x, y)`, on a film of `width` × `height`. None where the probe would be slow or blind: a scene whose
/// vertices span several bindings, or one with neither a wide BVH nor few primitives.
pub fn probe(d: &SceneData, eye: Vec3, camera: impl Fn(f32, f32) -> Vec3, width: u32, height: u32) -> Option<SkyProbe> {
    let flat_prims = d.tri_verts.len() / 3 + d.spheres.len() + d.quads.len();
    if !d.tri_verts_hi.is_empty() || (d.wide_nodes.is_empty() && flat_prims > 4 * FLAT_MAX_PRIMS) {
        return None;
    }
    let g = Geometry { d };
    let (gx, gy) = (GRID.min(width).max(1), GRID.min(height).max(1));
    let (mut hits, mut share) = (0u32, 0.0f32);
    let side = (SKY_RAYS as f64).sqrt() as u32;
    for j in 0..gy {
        for i in 0..gx {
            let dir = camera((i as f32 + 0.5) / gx as f32, (j as f32 + 0.5) / gy as f32).as_dvec3().normalize();
            let ray = Ray { o: eye.as_dvec3(), d: dir, t_max: f64::INFINITY };
            let Some(hit) = g.trace(&ray, false) else { continue };
            hits += 1;
            let p = ray.o + hit.t * dir;
            let n = hit.n.normalize();
            let n = if n.dot(dir) > 0.0 { -n } else { n };
            // Off the surface by a scale-aware step, as the shader offsets ray origins.
            let o = p + n * (1e-4 * p.abs().max_element().max(1.0));
            let (t, b) = orthonormal(n);
            let mut seen = 0;
            for k in 0..side * side {
                // Stratified cosine directions, rotated per pixel so that neighbouring hits look different ways.
                let u = ((k % side) as f64 + 0.5) / side as f64;
                let v = ((k / side) as f64 + 0.5) / side as f64;
                let phi = 2.0 * std::f64::consts::PI * (v + 0.618_034 * (i + gx * j) as f64).fract();
                let r = u.sqrt();
                let w = t * (r * phi.cos()) + b * (r * phi.sin()) + n * (1.0 - u).max(0.0).sqrt();
                if g.trace(&Ray { o, d: w, t_max: f64::INFINITY }, true).is_none() {
                    seen += 1;
                }
            }
            share += env_guide::guide_share(seen as f32 / (side * side) as f32);
        }
    }
    let rays = gx * gy;
    Some(SkyProbe { rays, hits, guided_share: share / rays as f32 })
}

fn orthonormal(n: DVec3) -> (DVec3, DVec3) {
    let t = n.any_orthonormal_vector();
    (t, n.cross(t))
}
