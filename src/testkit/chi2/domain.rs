//! Domains: 2D parametrisations of the sample space ([`Domain`]) that samples are binned in — spherical caps,
//! the environment map's equirectangular coordinates, a plane window seen from a point, and the unit square.

use glam::DVec3;
use std::f64::consts::PI;

/// Where a sample lies in a [`Domain`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Location {
    /// In the binned region, at cell coordinates (row, column) ∈ [0, 1)².
    Binned([f64; 2]),
    /// In the rest of the space (one extra cell).
    Rest,
}

/// A parametrisation of (part of) the sample space by [0, 1)², binned into `grid()` cells, plus optionally
/// the rest of the space (also parametrised by [0, 1)², integrated but counted as one cell).
pub trait Domain {
    /// A sample (a direction, a point).
    type Sample: Copy;
    /// Rows × columns of the binned region.
    fn grid(&self) -> (usize, usize);
    /// Where a sample lies.
    fn locate(&self, s: &Self::Sample) -> Location;
    /// The sample at cell coordinates `c` of the binned region and |d(measure)/d(c)|.
    fn point(&self, c: [f64; 2]) -> (Self::Sample, f64);
    /// The sample at coordinates `c` of the rest of the space and its Jacobian; None when the binned region is
    /// the whole space.
    fn rest_point(&self, c: [f64; 2]) -> Option<(Self::Sample, f64)>;
    /// A short description for reports.
    fn describe(&self) -> String;
}

/// Directions in a spherical cap {cosθ ≥ 1 − h} around `frame[2]` (h = 2: the whole sphere), binned in
/// (1 − cosθ)/h (rows) × φ/2π (columns): cells of equal solid angle 2πh/(rows·cols), and a constant Jacobian.
/// 1 − cosθ is computed from the transverse components, so caps of 10⁻⁷ sr resolve in f64 from f32 samples.
#[derive(Clone, Debug)]
pub struct SphereCap {
    /// Orthonormal frame: tangent, bitangent, axis.
    pub frame: [DVec3; 3],
    /// 1 − cosθ of the cap's rim, in (0, 2].
    pub h: f64,
    /// Rows × columns.
    pub grid: (usize, usize),
}

impl SphereCap {
    /// The whole sphere around `axis`.
    pub fn sphere(axis: DVec3, grid: (usize, usize)) -> Self {
        Self::cap(axis, 2.0, grid)
    }
    /// The cap of 1 − cosθ ≤ h around `axis`.
    pub fn cap(axis: DVec3, h: f64, grid: (usize, usize)) -> Self {
        let n = axis.normalize();
        let (t, b) = n.any_orthonormal_pair();
        SphereCap { frame: [t, b, n], h: h.min(2.0), grid }
    }
    /// The cap of half-angle `theta` around `axis`.
    pub fn cap_angle(axis: DVec3, theta: f64, grid: (usize, usize)) -> Self {
        Self::cap(axis, 2.0 * (0.5 * theta).sin().powi(2), grid)
    }
    fn dir(&self, omc: f64, phi: f64) -> DVec3 {
        let sin_theta = (omc * (2.0 - omc)).max(0.0).sqrt();
        let [t, b, n] = self.frame;
        t * (sin_theta * phi.cos()) + b * (sin_theta * phi.sin()) + n * (1.0 - omc)
    }
}

impl Domain for SphereCap {
    type Sample = DVec3;
    fn grid(&self) -> (usize, usize) {
        self.grid
    }
    fn locate(&self, w: &DVec3) -> Location {
        let w = w.normalize();
        let [t, b, n] = self.frame;
        let (x, y, z) = (w.dot(t), w.dot(b), w.dot(n));
        let omc = if z > 0.0 { (x * x + y * y) / (1.0 + z) } else { 1.0 - z };
        if self.h < 2.0 && omc >= self.h {
            return Location::Rest;
        }
        let r = (omc / self.h).clamp(0.0, 1.0 - 1e-16);
        let c = (y.atan2(x) / (2.0 * PI)).rem_euclid(1.0).min(1.0 - 1e-16);
        Location::Binned([r, c])
    }
    fn point(&self, c: [f64; 2]) -> (DVec3, f64) {
        (self.dir(c[0] * self.h, 2.0 * PI * c[1]), 2.0 * PI * self.h)
    }
    fn rest_point(&self, c: [f64; 2]) -> Option<(DVec3, f64)> {
        if self.h >= 2.0 {
            return None;
        }
        Some((self.dir(self.h + c[0] * (2.0 - self.h), 2.0 * PI * c[1]), 2.0 * PI * (2.0 - self.h)))
    }
    fn describe(&self) -> String {
        if self.h >= 2.0 {
            "sphere (1−cosθ, φ)".into()
        } else {
            format!("cap 1−cosθ≤{:.3e} (1−cosθ, φ) + rest", self.h)
        }
    }
}

/// Directions binned in the equirectangular (v = θ/π rows, u columns) coordinates of the environment map
/// (`env_direction_to_uv` in lights.wgsl: +Y up, u = 0.5 looking down −Z, rotated by `rotation` about +Y).
/// With rows and columns multiples of the map's size, cells are unions of texels.
#[derive(Clone, Debug)]
pub struct Equirect {
    /// Rotation about +Y, radians.
    pub rotation: f64,
    /// Rows × columns.
    pub grid: (usize, usize),
}

impl Domain for Equirect {
    type Sample = DVec3;
    fn grid(&self) -> (usize, usize) {
        self.grid
    }
    fn locate(&self, w: &DVec3) -> Location {
        let u = (w.x.atan2(-w.z) / (2.0 * PI) + 0.5 - self.rotation / (2.0 * PI)).rem_euclid(1.0).min(1.0 - 1e-16);
        let v = ((w.x * w.x + w.z * w.z).sqrt().atan2(w.y) / PI).clamp(0.0, 1.0 - 1e-16);
        Location::Binned([v, u])
    }
    fn point(&self, c: [f64; 2]) -> (DVec3, f64) {
        let theta = PI * c[0];
        let phi = 2.0 * PI * (c[1] - 0.5) + self.rotation;
        let st = theta.sin();
        (DVec3::new(st * phi.sin(), theta.cos(), -st * phi.cos()), 2.0 * PI * PI * st)
    }
    fn rest_point(&self, _: [f64; 2]) -> Option<(DVec3, f64)> {
        None
    }
    fn describe(&self) -> String {
        "equirect (θ, φ)".into()
    }
}

/// Directions from a viewpoint `p` through a window of a plane: the parallelogram `origin + x·e1 + y·e2`,
/// (x, y) ∈ [0, 1)², binned in (x, y). The Jacobian is dω/dA = |cos| / d². Directions that miss the window
/// are the rest, which is not integrated: use this for pdfs that vanish outside the window (an emitter inside
/// it, with a margin so that its edges fall inside cells).
#[derive(Clone, Debug)]
pub struct PlaneWindow {
    /// The viewpoint.
    pub p: DVec3,
    /// A corner of the window.
    pub origin: DVec3,
    /// Its edges.
    pub e1: DVec3,
    /// Its edges.
    pub e2: DVec3,
    /// Rows (along e1) × columns (along e2).
    pub grid: (usize, usize),
}

impl Domain for PlaneWindow {
    type Sample = DVec3;
    fn grid(&self) -> (usize, usize) {
        self.grid
    }
    fn locate(&self, w: &DVec3) -> Location {
        let n = self.e1.cross(self.e2);
        let denom = w.dot(n);
        let t = (self.origin - self.p).dot(n) / denom;
        if !(t > 0.0 && t.is_finite()) {
            return Location::Rest;
        }
        let q = self.p + t * *w - self.origin;
        let nn = n.dot(n);
        let x = q.cross(self.e2).dot(n) / nn;
        let y = self.e1.cross(q).dot(n) / nn;
        if (0.0..1.0).contains(&x) && (0.0..1.0).contains(&y) {
            Location::Binned([x, y])
        } else {
            Location::Rest
        }
    }
    fn point(&self, c: [f64; 2]) -> (DVec3, f64) {
        let q = self.origin + c[0] * self.e1 + c[1] * self.e2;
        let v = q - self.p;
        let d2 = v.length_squared();
        let w = v / d2.sqrt();
        let n = self.e1.cross(self.e2);
        (w, n.length() * w.dot(n.normalize()).abs() / d2)
    }
    fn rest_point(&self, _: [f64; 2]) -> Option<(DVec3, f64)> {
        None
    }
    fn describe(&self) -> String {
        "plane window".into()
    }
}

/// Points of the unit square, binned directly (pdf in area measure).
#[derive(Clone, Debug)]
pub struct UnitSquare {
    /// Rows × columns.
    pub grid: (usize, usize),
}

impl Domain for UnitSquare {
    type Sample = [f64; 2];
    fn grid(&self) -> (usize, usize) {
        self.grid
    }
    fn locate(&self, p: &[f64; 2]) -> Location {
        if (0.0..1.0).contains(&p[0]) && (0.0..1.0).contains(&p[1]) {
            Location::Binned(*p)
        } else {
            Location::Rest
        }
    }
    fn point(&self, c: [f64; 2]) -> ([f64; 2], f64) {
        (c, 1.0)
    }
    fn rest_point(&self, _: [f64; 2]) -> Option<([f64; 2], f64)> {
        None
    }
    fn describe(&self) -> String {
        "unit square".into()
    }
}
