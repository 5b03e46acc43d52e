//! Running a test: [`Chi2Options`], [`Chi2Test`] (histogram the samples, integrate the pdf over the cells with
//! refinement where its support ends, pool, and judge) and the discrete [`discrete_test`].

use super::quadrature::{dilate, integrate_cells, integrate_subset};
use super::{pearson, Chi2Report, Domain, Location, Quadrature};

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
    use crate::testkit::chi2::{PlaneWindow, SphereCap};
    use glam::DVec3;
    use rand::{Rng, SeedableRng};
    use rand_pcg::Pcg64;
    use std::f64::consts::PI;

    fn close(a: f64, b: f64, rel: f64) -> bool {
        (a - b).abs() <= rel * b.abs().max(1e-300)
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
