//! Axis-aligned boxes as the BVH builders and the baked shaders use them: the f32 box of each primitive kind,
//! rounded outwards where its bounds are computed (spheres, quads) and `None` for a primitive no ray can hit.

use glam::{DVec3, Vec3};

use crate::gpu::types::{GpuQuad, GpuSphere};

/// An axis-aligned box (f32, as uploaded).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Aabb {
    pub min: Vec3,
    pub max: Vec3,
}

impl Aabb {
    /// The inverted box that unions to anything.
    pub const EMPTY: Aabb = Aabb { min: Vec3::splat(f32::MAX), max: Vec3::splat(-f32::MAX) };

    /// The smallest box holding both.
    pub fn union(&self, o: &Aabb) -> Aabb {
        Aabb { min: self.min.min(o.min), max: self.max.max(o.max) }
    }

    /// Half the surface area, in f64 (a scene of extent 1e20 must not overflow the SAH sum).
    pub fn half_area(&self) -> f64 {
        let e = (self.max.as_dvec3() - self.min.as_dvec3()).max(DVec3::ZERO);
        e.x * e.y + e.y * e.z + e.z * e.x
    }

    /// Whether `o` lies inside (inclusive).
    pub fn contains(&self, o: &Aabb) -> bool {
        self.min.cmple(o.min).all() && self.max.cmpge(o.max).all()
    }
}

fn finite3(v: Vec3) -> bool {
    v.is_finite()
}

/// The next f32 towards +inf / -inf (for rounding sphere and quad boxes outwards).
pub(crate) fn next_up(x: f32) -> f32 {
    if x.is_nan() || x == f32::INFINITY {
        return x;
    }
    if x == 0.0 {
        return f32::from_bits(1);
    }
    let b = x.to_bits();
    f32::from_bits(if x > 0.0 { b + 1 } else { b - 1 })
}

pub(crate) fn next_down(x: f32) -> f32 {
    -next_up(-x)
}

fn outward(min: Vec3, max: Vec3) -> Aabb {
    Aabb {
        min: Vec3::new(next_down(min.x), next_down(min.y), next_down(min.z)),
        max: Vec3::new(next_up(max.x), next_up(max.y), next_up(max.z)),
    }
}

/// The box of a triangle, or `None` if it is excluded from the BVH (non-finite, or exactly zero area: the edge
/// cross product is evaluated in f64, where the products of f32 differences are exact).
pub fn triangle_aabb(v: &[Vec3; 3]) -> Option<Aabb> {
    if !v.iter().all(|p| finite3(*p)) {
        return None;
    }
    let (a, b, c) = (v[0].as_dvec3(), v[1].as_dvec3(), v[2].as_dvec3());
    if (b - a).cross(c - a) == DVec3::ZERO {
        return None;
    }
    // Exact: the traversal tests the same f32 vertices.
    Some(Aabb { min: v[0].min(v[1]).min(v[2]), max: v[0].max(v[1]).max(v[2]) })
}

/// The box of a sphere (rounded outwards), or `None` if excluded (non-finite, radius not > 0).
pub fn sphere_aabb(s: &GpuSphere) -> Option<Aabb> {
    let c = Vec3::from(s.center);
    if !finite3(c) || s.radius.is_nan() || s.radius <= 0.0 || !s.radius.is_finite() {
        return None;
    }
    let b = outward(c - s.radius, c + s.radius);
    (finite3(b.min) && finite3(b.max)).then_some(b)
}

/// The box of a quad's four corners (rounded outwards), or `None` if excluded (non-finite, zero area).
pub fn quad_aabb(q: &GpuQuad) -> Option<Aabb> {
    let (p, u, v) = (Vec3::from(q.corner), Vec3::from(q.edge_u), Vec3::from(q.edge_v));
    if !finite3(p) || !finite3(u) || !finite3(v) || u.as_dvec3().cross(v.as_dvec3()) == DVec3::ZERO {
        return None;
    }
    let corners = [p, p + u, p + v, p + u + v];
    let min = corners.iter().fold(Vec3::splat(f32::MAX), |m, c| m.min(*c));
    let max = corners.iter().fold(Vec3::splat(-f32::MAX), |m, c| m.max(*c));
    let b = outward(min, max);
    (finite3(b.min) && finite3(b.max)).then_some(b)
}
