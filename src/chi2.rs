//! Chi-square goodness-of-fit tests of sampling routines against their own pdf (after Mitsuba 3's `chi2.py` and
//! pbrt-v4's `bsdfs_test.cpp`): samples are binned over a 2D parametrisation of the sample space, the pdf is
//! integrated over every cell numerically (Gauss–Legendre, refined where the pdf's support ends inside a cell),
//! cells expecting fewer than 5 samples are pooled, and Pearson's statistic is turned into a p-value with the
//! regularised incomplete gamma function. A sample in a cell whose integrated pdf is 0 fails the test outright.
//!
//! Where samples come from and where the pdf is evaluated is up to the caller (the tests run both on the GPU);
//! this module is pure CPU code in f64.

use glam::DVec3;
use std::f64::consts::PI;

// ---------------------------------------------------------------------------------------------------------------
// Special functions

/// ln Γ(x) for x > 0 (Lanczos approximation, g = 7, 9 terms; relative error ~1e-15).
pub fn ln_gamma(x: f64) -> f64 {
    const G: f64 = 7.0;
    const C: [f64; 9] = [
        0.999_999_999_999_809_9,
        676.520_368_121_885_1,
        -1_259.139_216_722_402_8,
        771.323_428_777_653_1,
        -176.615_029_162_140_6,
        12.507_343_278_686_905,
        -0.138_571_095_265_720_12,
        9.984_369_578_019_572e-6,
        1.505_632_735_149_311_6e-7,
    ];
    if x < 0.5 {
        // Reflection: Γ(x)Γ(1 − x) = π / sin(πx).
        return (PI / (PI * x).sin()).ln() - ln_gamma(1.0 - x);
    }
    let x = x - 1.0;
    let mut a = C[0];
    let t = x + G + 0.5;
    for (i, c) in C.iter().enumerate().skip(1) {
        a += c / (x + i as f64);
    }
    0.5 * (2.0 * PI).ln() + (x + 0.5) * t.ln() - t + a.ln()
}

/// Iteration bound of the series and continued fraction below: both need O(√a) terms, so this covers
/// a up to ~10⁸ (the loops must be bounded; see PLATFORM.md on runaway loops, which applies to habits, not the CPU).
const GAMMA_MAX_ITER: usize = 1_000_000;

/// Regularised lower incomplete gamma P(a, x) = γ(a, x)/Γ(a), a > 0, x ≥ 0 (Numerical Recipes §6.2: the series
/// for x < a + 1, else 1 − the continued fraction).
pub fn gamma_p(a: f64, x: f64) -> f64 {
    assert!(a > 0.0 && x >= 0.0, "gamma_p({a}, {x}) needs a > 0, x ≥ 0");
    if x == 0.0 {
        return 0.0;
    }
    if x < a + 1.0 {
        gamma_series(a, x)
    } else {
        1.0 - gamma_cont_fraction(a, x)
    }
}

/// Regularised upper incomplete gamma Q(a, x) = 1 − P(a, x), computed directly in the tail (no cancellation).
pub fn gamma_q(a: f64, x: f64) -> f64 {
    assert!(a > 0.0 && x >= 0.0, "gamma_q({a}, {x}) needs a > 0, x ≥ 0");
    if x == 0.0 {
        return 1.0;
    }
    if x < a + 1.0 {
        1.0 - gamma_series(a, x)
    } else {
        gamma_cont_fraction(a, x)
    }
}

/// P(a, x) by its series e^{−x} x^a / Γ(a+1) · Σ xⁿ / ((a+1)…(a+n)).
fn gamma_series(a: f64, x: f64) -> f64 {
    let mut ap = a;
    let mut del = 1.0 / a;
    let mut sum = del;
    for _ in 0..GAMMA_MAX_ITER {
        ap += 1.0;
        del *= x / ap;
        sum += del;
        if del.abs() < sum.abs() * 1e-16 {
            break;
        }
    }
    (sum.ln() - x + a * x.ln() - ln_gamma(a)).exp()
}

/// Q(a, x) by its continued fraction (modified Lentz).
fn gamma_cont_fraction(a: f64, x: f64) -> f64 {
    const TINY: f64 = 1e-300;
    let mut b = x + 1.0 - a;
    let mut c = 1.0 / TINY;
    let mut d = 1.0 / b;
    let mut h = d;
    for i in 1..GAMMA_MAX_ITER {
        let an = -(i as f64) * (i as f64 - a);
        b += 2.0;
        d = an * d + b;
        if d.abs() < TINY {
            d = TINY;
        }
        c = b + an / c;
        if c.abs() < TINY {
            c = TINY;
        }
        d = 1.0 / d;
        let del = d * c;
        h *= del;
        if (del - 1.0).abs() < 1e-16 {
            break;
        }
    }
    (-x + a * x.ln() - ln_gamma(a)).exp() * h
}

/// Survival function of the chi-square distribution with `dof` degrees of freedom: P(X² ≥ stat) = Q(dof/2, stat/2).
pub fn chi2_sf(stat: f64, dof: f64) -> f64 {
    if dof <= 0.0 {
        return 1.0;
    }
    gamma_q(0.5 * dof, 0.5 * stat.max(0.0))
}

/// Per-test level of `m` independent tests at family-wise level `alpha` (Šidák): 1 − (1 − α)^(1/m).
pub fn sidak_alpha(alpha: f64, m: usize) -> f64 {
    1.0 - (1.0 - alpha).powf(1.0 / m.max(1) as f64)
}

/// Gauss–Legendre nodes and weights of order `n` on [0, 1] (Newton on Pₙ from the Chebyshev guesses).
pub fn gauss_legendre(n: usize) -> Vec<(f64, f64)> {
    assert!(n >= 1);
    let mut out = Vec::with_capacity(n);
    for i in 0..n {
        let mut x = (PI * (i as f64 + 0.75) / (n as f64 + 0.5)).cos();
        let mut dp = 1.0;
        for _ in 0..100 {
            // P_n(x) and P_n'(x) by the three-term recurrence.
            let (mut p0, mut p1) = (1.0, x);
            for k in 2..=n {
                let p2 = ((2 * k - 1) as f64 * x * p1 - (k - 1) as f64 * p0) / k as f64;
                p0 = p1;
                p1 = p2;
            }
            let pn = if n == 1 { x } else { p1 };
            let pn1 = if n == 1 { 1.0 } else { p0 };
            dp = n as f64 * (x * pn - pn1) / (x * x - 1.0);
            let dx = pn / dp;
            x -= dx;
            if dx.abs() < 1e-15 {
                break;
            }
        }
        let w = 2.0 / ((1.0 - x * x) * dp * dp);
        out.push((0.5 * (1.0 - x), 0.5 * w));
    }
    out.sort_by(|a, b| a.0.total_cmp(&b.0));
    out
}

// ---------------------------------------------------------------------------------------------------------------
// Pearson's test with pooling

/// Pearson's statistic over cells of observed and expected counts.
#[derive(Clone, Debug, Default)]
pub struct Pearson {
    /// Σ (O − E)² / E over the cells kept and the pooled cell.
    pub statistic: f64,
    /// Degrees of freedom: cells kept (+1 for the pool) − 1.
    pub dof: usize,
    /// P(X² ≥ statistic).
    pub p_value: f64,
    /// Cells merged into the pool (expected < `min_expected`).
    pub pooled_cells: usize,
    /// Samples observed in cells whose expected count is exactly 0.
    pub zero_cell_hits: u64,
}

/// Pearson's chi-square test. Cells are visited in increasing order of expected count; those expecting fewer
/// than `min_expected` samples go into one pooled cell, which keeps absorbing cells until it expects at least
/// `min_expected` (pbrt-v4's `Chi2Test`). Cells with expected count 0 are left out and their samples counted in
/// `zero_cell_hits` (the caller fails the test on any).
pub fn pearson(observed: &[f64], expected: &[f64], min_expected: f64) -> Pearson {
    assert_eq!(observed.len(), expected.len());
    let mut order: Vec<usize> = (0..expected.len()).collect();
    order.sort_by(|&a, &b| expected[a].total_cmp(&expected[b]));
    let mut r = Pearson::default();
    let (mut pool_o, mut pool_e) = (0.0, 0.0);
    let mut kept = 0usize;
    for i in order {
        let (o, e) = (observed[i], expected[i]);
        if e <= 0.0 {
            r.zero_cell_hits += o as u64;
        } else if e < min_expected || (pool_e > 0.0 && pool_e < min_expected) {
            pool_o += o;
            pool_e += e;
            r.pooled_cells += 1;
        } else {
            r.statistic += (o - e) * (o - e) / e;
            kept += 1;
        }
    }
    if pool_e > 0.0 {
        r.statistic += (pool_o - pool_e) * (pool_o - pool_e) / pool_e;
        kept += 1;
    }
    r.dof = kept.saturating_sub(1);
    r.p_value = chi2_sf(r.statistic, r.dof as f64);
    r
}

// ---------------------------------------------------------------------------------------------------------------
// Domains: 2D parametrisations of the sample space

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

// ---------------------------------------------------------------------------------------------------------------
// Numerical integration of a pdf over the cells

/// Per-cell quadrature: `sub`×`sub` sub-cells with `gauss`×`gauss` Gauss–Legendre points each.
#[derive(Clone, Copy, Debug)]
pub struct Quadrature {
    /// Sub-cells per side.
    pub sub: usize,
    /// Gauss points per side and sub-cell.
    pub gauss: usize,
}

impl Quadrature {
    /// Points per cell.
    pub fn points(&self) -> usize {
        (self.sub * self.gauss).pow(2)
    }
    /// (offset in the cell, weight) per side; the weights sum to 1.
    fn nodes(&self) -> Vec<(f64, f64)> {
        let g = gauss_legendre(self.gauss);
        let s = self.sub as f64;
        (0..self.sub).flat_map(|i| g.iter().map(move |&(x, w)| ((i as f64 + x) / s, w / s))).collect()
    }
}

/// How a [`Chi2Test`] integrates and pools.
#[derive(Clone, Debug)]
pub struct Chi2Options {
    /// Quadrature in every cell.
    pub base: Quadrature,
    /// Quadrature in cells where the pdf's support ends (some base points 0, some not), in cells with samples but
    /// no base point inside the support, and in their neighbours.
    pub refine: Option<Quadrature>,
    /// Grid of the rest of the space (integrated only, counted as one cell).
    pub rest_grid: (usize, usize),
    /// Whether the sampler may fail (return no sample): then failures form one more cell expecting
    /// N·(1 − ∫pdf) (when that is at least `min_expected`), and the pdf must integrate to 1 − (failure fraction)
    /// instead of 1. Otherwise any failure fails the test.
    pub may_fail: bool,
    /// Cells expecting fewer samples than this are pooled.
    pub min_expected: f64,
    /// Significance level of this test (already Šidák-corrected).
    pub alpha: f64,
    /// Largest |∫pdf − 1| (or |∫pdf + failures/N − 1| when `may_fail`) accepted.
    pub integral_tolerance: f64,
}

impl Default for Chi2Options {
    fn default() -> Self {
        Chi2Options {
            base: Quadrature { sub: 1, gauss: 4 },
            refine: Some(Quadrature { sub: 12, gauss: 2 }),
            rest_grid: (50, 100),
            may_fail: false,
            min_expected: 5.0,
            alpha: 0.01,
            integral_tolerance: 0.01,
        }
    }
}

/// The outcome of one test.
#[derive(Clone, Debug, Default)]
pub struct Chi2Report {
    /// What was tested.
    pub name: String,
    /// How the samples were binned.
    pub domain: String,
    /// Samples drawn (including failed ones).
    pub samples: u64,
    /// Samples the routine returned as failures (pdf 0 / no sample).
    pub failed: u64,
    /// Binned cells (rows × columns).
    pub cells: usize,
    /// Cells refined because the pdf's support ends inside them.
    pub refined_cells: usize,
    /// ∫ pdf over the whole space.
    pub integral: f64,
    /// The test statistic.
    pub pearson: Pearson,
    /// Significance level used.
    pub alpha: f64,
    /// Why the test failed (empty: it passed).
    pub failures: Vec<String>,
}

impl Chi2Report {
    /// Whether every check passed.
    pub fn passed(&self) -> bool {
        self.failures.is_empty()
    }
    /// One line for logs and tables.
    pub fn summary(&self) -> String {
        format!(
            "{}: {} samples ({} failed), {} cells ({} refined, {} pooled), X² = {:.1}, dof {}, p = {:.4}, ∫pdf = {:.5}{}",
            self.name,
            self.samples,
            self.failed,
            self.cells,
            self.refined_cells,
            self.pearson.pooled_cells,
            self.pearson.statistic,
            self.pearson.dof,
            self.pearson.p_value,
            self.integral,
            if self.passed() { String::new() } else { format!(" — FAILED: {}", self.failures.join("; ")) }
        )
    }
}

/// A chi-square test of samples in a domain against a pdf.
pub struct Chi2Test<'a, D: Domain> {
    /// Name for the report.
    pub name: String,
    /// Where samples are binned.
    pub domain: &'a D,
    /// Options.
    pub options: Chi2Options,
}

impl<'a, D: Domain> Chi2Test<'a, D> {
    /// A test with default options.
    pub fn new(name: impl Into<String>, domain: &'a D) -> Self {
        Chi2Test { name: name.into(), domain, options: Chi2Options::default() }
    }

    /// Runs the test on `samples` (None = the routine failed to produce one). `pdf` evaluates the routine's pdf
    /// at a batch of samples (its measure is the one the domain's Jacobian converts from: solid angle for
    /// directions); it is called at most six times (base points, refined points, deeper refinements, the rest).
    pub fn run(&self, samples: &[Option<D::Sample>], pdf: &mut dyn FnMut(&[D::Sample]) -> Vec<f64>) -> Chi2Report {
        let d = self.domain;
        let o = &self.options;
        let (rows, cols) = d.grid();
        let n_cells = rows * cols;
        let mut report = Chi2Report {
            name: self.name.clone(),
            domain: d.describe(),
            samples: samples.len() as u64,
            cells: n_cells,
            alpha: o.alpha,
            ..Default::default()
        };

        // Histogram: binned cells, then the rest, then failures.
        let mut observed = vec![0.0f64; n_cells + 2];
        for s in samples {
            match s {
                None => {
                    observed[n_cells + 1] += 1.0;
                    report.failed += 1;
                }
                Some(s) => match d.locate(s) {
                    Location::Binned([x, y]) => {
                        let r = ((x * rows as f64) as usize).min(rows - 1);
                        let c = ((y * cols as f64) as usize).min(cols - 1);
                        observed[r * cols + c] += 1.0;
                    }
                    Location::Rest => observed[n_cells] += 1.0,
                },
            }
        }

        // Integrate the pdf over every cell, refining where the support ends.
        let mut mass = integrate_cells(d, rows, cols, o.base, &|c| d.point(c), pdf);
        if let Some(refine) = o.refine {
            // Cells where the support ends (mixed) or where samples landed although no quadrature point saw the
            // pdf (a support thinner than the point spacing), and their neighbours. Where to refine does not
            // change what is integrated, only how accurately.
            let seed: Vec<bool> =
                (0..n_cells).map(|i| mass.mixed[i] || (observed[i] > 0.0 && mass.mass[i] == 0.0)).collect();
            let flagged = dilate(&seed, rows, cols);
            report.refined_cells = flagged.iter().filter(|&&f| f).count();
            if report.refined_cells > 0 {
                let fine = integrate_subset(rows, cols, refine, &flagged, &|c| d.point(c), pdf);
                for (i, m) in fine {
                    mass.mass[i] = m;
                }
            }
            // Cells that received samples but whose support is still thinner than the refined point spacing (a
            // corner cut off by the support's edge): twice more, 4× finer each time.
            let mut q = refine;
            for _ in 0..2 {
                let empty: Vec<bool> = (0..n_cells).map(|i| observed[i] > 0.0 && mass.mass[i] == 0.0).collect();
                if !empty.iter().any(|&e| e) {
                    break;
                }
                q.sub *= 4;
                for (i, m) in integrate_subset(rows, cols, q, &empty, &|c| d.point(c), pdf) {
                    mass.mass[i] = m;
                }
            }
        }
        let rest_mass = if d.rest_point([0.5, 0.5]).is_some() {
            let (rr, rc) = o.rest_grid;
            let m = integrate_cells(d, rr, rc, o.base, &|c| d.rest_point(c).expect("rest"), pdf);
            m.mass.iter().sum::<f64>()
        } else {
            0.0
        };
        report.integral = mass.mass.iter().sum::<f64>() + rest_mass;

        // Expected counts.
        let n = samples.len() as f64;
        let mut expected: Vec<f64> = mass.mass.iter().map(|m| m * n).collect();
        expected.push(rest_mass * n);
        // Failures: a cell expecting N·(1 − ∫pdf). When that is under `min_expected` it says less than the error of
        // the numerical integral (~1e-5 of N), so the cell is left out and the failures are only held to the
        // integral check below.
        let expected_failures = (1.0 - report.integral) * n;
        if o.may_fail && expected_failures >= o.min_expected {
            expected.push(expected_failures);
        } else if o.may_fail {
            observed.pop();
        } else {
            expected.push(0.0);
        }
        report.pearson = pearson(&observed, &expected, o.min_expected);

        let failed_fraction = report.failed as f64 / n.max(1.0);
        let target = if o.may_fail { 1.0 - failed_fraction } else { 1.0 };
        if report.pearson.zero_cell_hits > 0 {
            report
                .failures
                .push(format!("{} samples in cells where the pdf integrates to 0", report.pearson.zero_cell_hits));
        }
        if !((report.integral - target).abs() <= o.integral_tolerance) {
            report
                .failures
                .push(format!("∫pdf = {:.5}, expected {:.5} ± {}", report.integral, target, o.integral_tolerance));
        }
        if !(report.pearson.p_value >= o.alpha) {
            report.failures.push(format!("p = {:.3e} < α = {:.3e}", report.pearson.p_value, o.alpha));
        }
        report
    }
}

struct CellMass {
    mass: Vec<f64>,
    /// Cells where some quadrature points have pdf 0 and others not.
    mixed: Vec<bool>,
}

fn integrate_cells<D: Domain>(
    _d: &D,
    rows: usize,
    cols: usize,
    q: Quadrature,
    at: &dyn Fn([f64; 2]) -> (D::Sample, f64),
    pdf: &mut dyn FnMut(&[D::Sample]) -> Vec<f64>,
) -> CellMass {
    let nodes = q.nodes();
    let per = nodes.len() * nodes.len();
    let mut points = Vec::with_capacity(rows * cols * per);
    let mut weights = Vec::with_capacity(rows * cols * per);
    for r in 0..rows {
        for c in 0..cols {
            for &(x, wx) in &nodes {
                for &(y, wy) in &nodes {
                    let (s, jac) = at([(r as f64 + x) / rows as f64, (c as f64 + y) / cols as f64]);
                    points.push(s);
                    weights.push(wx * wy * jac / (rows * cols) as f64);
                }
            }
        }
    }
    let values = pdf(&points);
    assert_eq!(values.len(), points.len(), "the pdf callback must return one value per point");
    let mut mass = vec![0.0; rows * cols];
    let mut mixed = vec![false; rows * cols];
    for cell in 0..rows * cols {
        let v = &values[cell * per..(cell + 1) * per];
        let w = &weights[cell * per..(cell + 1) * per];
        mass[cell] = v.iter().zip(w).map(|(p, w)| if p.is_finite() { p * w } else { f64::NAN }).sum();
        let zeros = v.iter().filter(|&&p| p == 0.0).count();
        mixed[cell] = zeros > 0 && zeros < per;
    }
    CellMass { mass, mixed }
}

fn integrate_subset<S: Copy>(
    rows: usize,
    cols: usize,
    q: Quadrature,
    flagged: &[bool],
    at: &dyn Fn([f64; 2]) -> (S, f64),
    pdf: &mut dyn FnMut(&[S]) -> Vec<f64>,
) -> Vec<(usize, f64)> {
    let nodes = q.nodes();
    let per = nodes.len() * nodes.len();
    let cells: Vec<usize> = (0..rows * cols).filter(|&i| flagged[i]).collect();
    let mut points = Vec::with_capacity(cells.len() * per);
    let mut weights = Vec::with_capacity(cells.len() * per);
    for &i in &cells {
        let (r, c) = (i / cols, i % cols);
        for &(x, wx) in &nodes {
            for &(y, wy) in &nodes {
                let (s, jac) = at([(r as f64 + x) / rows as f64, (c as f64 + y) / cols as f64]);
                points.push(s);
                weights.push(wx * wy * jac / (rows * cols) as f64);
            }
        }
    }
    let values = pdf(&points);
    assert_eq!(values.len(), points.len(), "the pdf callback must return one value per point");
    cells
        .iter()
        .enumerate()
        .map(|(k, &i)| {
            let m = (k * per..(k + 1) * per)
                .map(|j| if values[j].is_finite() { values[j] * weights[j] } else { f64::NAN })
                .sum();
            (i, m)
        })
        .collect()
}

/// Flagged cells and their 8 neighbours (columns wrap around: φ is periodic in every domain here).
fn dilate(flags: &[bool], rows: usize, cols: usize) -> Vec<bool> {
    let mut out = flags.to_vec();
    for r in 0..rows {
        for c in 0..cols {
            if !flags[r * cols + c] {
                continue;
            }
            for dr in -1i64..=1 {
                let rr = r as i64 + dr;
                if rr < 0 || rr >= rows as i64 {
                    continue;
                }
                for dc in -1i64..=1 {
                    let cc = (c as i64 + dc).rem_euclid(cols as i64) as usize;
                    out[rr as usize * cols + cc] = true;
                }
            }
        }
    }
    out
}

/// A discrete chi-square test: `observed` counts of categories against `pmf` (cells expecting < `min_expected`
/// pooled). Categories with pmf 0 and observations fail the test outright.
pub fn discrete_test(name: &str, observed: &[u64], pmf: &[f64], alpha: f64) -> Chi2Report {
    let n: u64 = observed.iter().sum();
    let obs: Vec<f64> = observed.iter().map(|&o| o as f64).collect();
    let exp: Vec<f64> = pmf.iter().map(|p| p * n as f64).collect();
    let pearson = pearson(&obs, &exp, 5.0);
    let integral: f64 = pmf.iter().sum();
    let mut failures = Vec::new();
    if pearson.zero_cell_hits > 0 {
        failures.push(format!("{} samples of categories with probability 0", pearson.zero_cell_hits));
    }
    if !((integral - 1.0).abs() <= 0.01) {
        failures.push(format!("Σ pmf = {integral:.5}"));
    }
    if !(pearson.p_value >= alpha) {
        failures.push(format!("p = {:.3e} < α = {:.3e}", pearson.p_value, alpha));
    }
    Chi2Report {
        name: name.into(),
        domain: "discrete".into(),
        samples: n,
        failed: 0,
        cells: pmf.len(),
        refined_cells: 0,
        integral,
        pearson,
        alpha,
        failures,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::{Rng, SeedableRng};
    use rand_pcg::Pcg64;

    fn close(a: f64, b: f64, rel: f64) -> bool {
        (a - b).abs() <= rel * b.abs().max(1e-300)
    }

    #[test]
    fn ln_gamma_known_values() {
        assert!(ln_gamma(1.0).abs() < 1e-14 && ln_gamma(2.0).abs() < 1e-14);
        assert!(close(ln_gamma(0.5), PI.sqrt().ln(), 1e-14));
        assert!(close(ln_gamma(10.0), 362880.0f64.ln(), 1e-14));
        // ln Γ(100) = ln 99!.
        assert!(close(ln_gamma(100.0), 359.134_205_369_575_4, 1e-13));
    }

    #[test]
    fn incomplete_gamma_known_values() {
        // Q(1, x) = e^{−x}; P(0.5, x) = erf(√x); chi-square tables.
        for x in [0.01, 0.5, 1.0, 3.0, 20.0] {
            assert!(close(gamma_q(1.0, x), (-x).exp(), 1e-12), "Q(1, {x})");
            assert!(close(gamma_p(1.0, x), 1.0 - (-x).exp(), 1e-12), "P(1, {x})");
        }
        // erf(1) = 0.8427007929497149.
        assert!(close(gamma_p(0.5, 1.0), 0.842_700_792_949_714_9, 1e-12));
        // Q(3, 2) = e^{−2}(1 + 2 + 2) = 5e^{−2}.
        assert!(close(gamma_q(3.0, 2.0), 5.0 * (-2.0f64).exp(), 1e-12));
        // Upper 1 % points of chi-square: dof 1: 6.634897, 10: 23.209251, 100: 135.806723, 1000: 1106.969.
        assert!(close(chi2_sf(6.634_896_601, 1.0), 0.01, 1e-6));
        assert!(close(chi2_sf(23.209_251_159, 10.0), 0.01, 1e-6));
        assert!(close(chi2_sf(135.806_723, 100.0), 0.01, 1e-5));
        assert!(close(chi2_sf(1_106.969_2, 1000.0), 0.01, 1e-4));
        // Median-ish of a large dof: P(X² ≥ k) for k = 20000 is a bit below 0.5 (skew): 0.4986700…
        let p = chi2_sf(20000.0, 20000.0);
        assert!(p > 0.49 && p < 0.5, "{p}");
        // Symmetric checks P + Q = 1 across the series / continued fraction switch.
        for (a, x) in [(0.5, 0.2), (5.0, 5.5), (5.0, 6.5), (5000.0, 4990.0), (5000.0, 5100.0)] {
            assert!(close(gamma_p(a, x) + gamma_q(a, x), 1.0, 1e-10), "P+Q at ({a}, {x})");
        }
    }

    #[test]
    fn sidak_level() {
        assert!(close(sidak_alpha(0.01, 1), 0.01, 1e-12));
        let a = sidak_alpha(0.01, 50);
        assert!(close(1.0 - (1.0 - a).powi(50), 0.01, 1e-10));
    }

    #[test]
    fn gauss_legendre_is_exact_for_polynomials() {
        for n in 1..=8 {
            let g = gauss_legendre(n);
            assert!(close(g.iter().map(|p| p.1).sum::<f64>(), 1.0, 1e-14));
            for k in 0..2 * n {
                let integral: f64 = g.iter().map(|&(x, w)| w * x.powi(k as i32)).sum();
                assert!(close(integral, 1.0 / (k as f64 + 1.0), 1e-12), "n = {n}, x^{k}: {integral}");
            }
        }
    }

    fn cosine_hemisphere(rng: &mut Pcg64) -> DVec3 {
        let (u1, u2): (f64, f64) = (rng.random(), rng.random());
        let r = u1.sqrt();
        let phi = 2.0 * PI * u2;
        DVec3::new(r * phi.cos(), r * phi.sin(), (1.0 - u1).sqrt())
    }

    fn run_sphere(name: &str, n: usize, sampler: fn(&mut Pcg64) -> DVec3, pdf: fn(DVec3) -> f64) -> Chi2Report {
        let mut rng = Pcg64::seed_from_u64(7);
        let samples: Vec<Option<DVec3>> = (0..n).map(|_| Some(sampler(&mut rng))).collect();
        let domain = SphereCap::sphere(DVec3::Z, (100, 200));
        let test = Chi2Test::new(name, &domain);
        test.run(&samples, &mut |pts| pts.iter().map(|&w| pdf(w)).collect())
    }

    #[test]
    fn a_correct_sampler_passes() {
        let r = run_sphere("cosine", 200_000, cosine_hemisphere, |w| w.z.max(0.0) / PI);
        assert!(r.passed(), "{}", r.summary());
        assert!(close(r.integral, 1.0, 1e-4), "{}", r.summary());
        // A cap around a tilted axis, with the rest of the sphere as one cell.
        let mut rng = Pcg64::seed_from_u64(9);
        let samples: Vec<Option<DVec3>> = (0..200_000).map(|_| Some(cosine_hemisphere(&mut rng))).collect();
        let domain = SphereCap::cap_angle(DVec3::new(0.3, 0.1, 1.0), 1.0, (100, 200));
        let r = Chi2Test::new("cosine in a cap", &domain)
            .run(&samples, &mut |pts| pts.iter().map(|w| w.z.max(0.0) / PI).collect());
        assert!(r.passed(), "{}", r.summary());
    }

    #[test]
    fn a_wrong_pdf_fails() {
        // Cosine-distributed samples against the uniform-hemisphere pdf: integrates to 1 but the shape is wrong.
        let r = run_sphere("cosine vs uniform", 200_000, cosine_hemisphere, |w| if w.z > 0.0 { 0.5 / PI } else { 0.0 });
        assert!(!r.passed() && r.pearson.p_value < 1e-10, "{}", r.summary());
        // A pdf that is off by 3 % in one half: the chi-square sees it.
        let r = run_sphere("cosine, 3% off", 1_000_000, cosine_hemisphere, |w| {
            w.z.max(0.0) / PI * if w.x > 0.0 { 1.03 } else { 0.97 }
        });
        assert!(!r.passed(), "{}", r.summary());
        // Samples where the pdf is 0 fail outright even if the shape is fine elsewhere.
        let mut rng = Pcg64::seed_from_u64(3);
        let mut samples: Vec<Option<DVec3>> = (0..100_000).map(|_| Some(cosine_hemisphere(&mut rng))).collect();
        samples[17] = Some(DVec3::new(0.0, 0.0, -1.0));
        let domain = SphereCap::sphere(DVec3::Z, (100, 200));
        let r = Chi2Test::new("below the horizon", &domain)
            .run(&samples, &mut |pts| pts.iter().map(|w| w.z.max(0.0) / PI).collect());
        assert!(r.failures.iter().any(|f| f.contains("integrates to 0")), "{}", r.summary());
    }

    #[test]
    fn failures_count_against_the_pdf() {
        // Uniform sphere directions, the lower half reported as failures: the pdf of the rest is 1/4π on the
        // upper hemisphere and integrates to 1/2.
        let mut rng = Pcg64::seed_from_u64(5);
        let samples: Vec<Option<DVec3>> = (0..400_000)
            .map(|_| {
                let z: f64 = rng.random_range(-1.0..1.0);
                let phi = 2.0 * PI * rng.random::<f64>();
                let s = (1.0 - z * z).sqrt();
                (z > 0.0).then(|| DVec3::new(s * phi.cos(), s * phi.sin(), z))
            })
            .collect();
        let domain = SphereCap::sphere(DVec3::Z, (100, 200));
        let mut t = Chi2Test::new("half fails", &domain);
        t.options.may_fail = true;
        let r = t.run(&samples, &mut |pts| pts.iter().map(|w| if w.z > 0.0 { 0.25 / PI } else { 0.0 }).collect());
        assert!(r.passed(), "{}", r.summary());
        // The same samples with a pdf claiming twice the density: the failure cell expects nothing.
        let r = t.run(&samples, &mut |pts| pts.iter().map(|w| if w.z > 0.0 { 0.5 / PI } else { 0.0 }).collect());
        assert!(!r.passed(), "{}", r.summary());
    }

    #[test]
    fn tiny_caps_resolve() {
        // Uniform in a cone of 1e-6 sr around a tilted axis, binned in a cap of twice its 1 − cosθ.
        let axis = DVec3::new(0.2, -0.7, 0.4).normalize();
        let omc = 1e-6 / (2.0 * PI);
        let (t, b) = axis.any_orthonormal_pair();
        let mut rng = Pcg64::seed_from_u64(11);
        let samples: Vec<Option<DVec3>> = (0..200_000)
            .map(|_| {
                let o = rng.random::<f64>() * omc;
                let s = (o * (2.0 - o)).sqrt();
                let phi = 2.0 * PI * rng.random::<f64>();
                // Rounded to f32 as a GPU would return it.
                Some((t * s * phi.cos() + b * s * phi.sin() + axis * (1.0 - o)).as_vec3().as_dvec3())
            })
            .collect();
        let domain = SphereCap::cap(axis, omc / 0.505, (100, 200));
        let r = Chi2Test::new("tiny cone", &domain).run(&samples, &mut |pts| {
            pts.iter()
                .map(|w| {
                    let w = w.normalize();
                    let o = w.cross(axis).length_squared() / (1.0 + w.dot(axis));
                    if o <= omc {
                        1.0 / (2.0 * PI * omc)
                    } else {
                        0.0
                    }
                })
                .collect()
        });
        assert!(r.passed(), "{}", r.summary());
    }

    #[test]
    fn plane_window_and_thin_supports() {
        // Uniform points on a long thin triangle seen nearly edge-on, as directions; pdf = d² / (A cos).
        let p = DVec3::new(0.0, 0.0, 0.05);
        let v = [DVec3::new(1.0, -0.5, 0.0), DVec3::new(3.0, -0.4, 0.0), DVec3::new(1.2, 0.6, 0.0)];
        let n = (v[1] - v[0]).cross(v[2] - v[0]);
        let area = 0.5 * n.length();
        let mut rng = Pcg64::seed_from_u64(21);
        let samples: Vec<Option<DVec3>> = (0..300_000)
            .map(|_| {
                let (mut a, mut b): (f64, f64) = (rng.random(), rng.random());
                if a + b > 1.0 {
                    (a, b) = (1.0 - a, 1.0 - b);
                }
                Some((v[0] + a * (v[1] - v[0]) + b * (v[2] - v[0]) - p).normalize())
            })
            .collect();
        let domain = PlaneWindow {
            p,
            origin: DVec3::new(0.8, -0.7, 0.0),
            e1: DVec3::new(2.4, 0.0, 0.0),
            e2: DVec3::new(0.0, 1.5, 0.0),
            grid: (100, 200),
        };
        let pdf = |w: &DVec3| {
            let t = -p.z / w.z;
            let y = p + t * *w;
            let e = [v[1] - v[0], v[2] - v[0]];
            let b1 = (y - v[0]).cross(e[1]).dot(n) / n.dot(n);
            let b2 = e[0].cross(y - v[0]).dot(n) / n.dot(n);
            if t > 0.0 && b1 >= 0.0 && b2 >= 0.0 && b1 + b2 <= 1.0 {
                t * t / (area * w.z.abs())
            } else {
                0.0
            }
        };
        let r = Chi2Test::new("thin triangle", &domain).run(&samples, &mut |pts| pts.iter().map(pdf).collect());
        assert!(r.passed(), "{}", r.summary());
        assert!((r.integral - 1.0).abs() < 1e-3, "{}", r.summary());
        // A sample outside the window fails outright.
        let mut bad = samples.clone();
        bad[3] = Some(DVec3::new(0.0, 0.0, -1.0));
        let r = Chi2Test::new("outside", &domain).run(&bad, &mut |pts| pts.iter().map(pdf).collect());
        assert!(!r.passed(), "{}", r.summary());
    }

    #[test]
    fn discrete() {
        let pmf = [0.5, 0.25, 0.125, 0.125, 0.0];
        let mut rng = Pcg64::seed_from_u64(1);
        let mut obs = [0u64; 5];
        for _ in 0..100_000 {
            let u: f64 = rng.random();
            let i = if u < 0.5 {
                0
            } else if u < 0.75 {
                1
            } else if u < 0.875 {
                2
            } else {
                3
            };
            obs[i] += 1;
        }
        assert!(discrete_test("ok", &obs, &pmf, 0.01).passed());
        let bad = [0.45, 0.30, 0.125, 0.125, 0.0];
        assert!(!discrete_test("bad", &obs, &bad, 0.01).passed());
        obs[4] = 1;
        assert!(!discrete_test("zero", &obs, &pmf, 0.01).passed());
    }
}
