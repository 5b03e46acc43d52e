//! Chi-square goodness-of-fit tests of sampling routines against their own pdf (after Mitsuba 3's `chi2.py` and
//! pbrt-v4's `bsdfs_test.cpp`): samples are binned over a 2D parametrisation of the sample space, the pdf is
//! integrated over every cell numerically (Gauss–Legendre, refined where the pdf's support ends inside a cell),
//! cells expecting fewer than 5 samples are pooled, and Pearson's statistic is turned into a p-value with the
//! regularised incomplete gamma function. A sample in a cell whose integrated pdf is 0 fails the test outright.
//!
//! Where samples come from and where the pdf is evaluated is up to the caller (the tests run both on the GPU);
//! this module is pure CPU code in f64.
//!
//! Layout: `stats` (special functions, Gauss–Legendre, Pearson's statistic), `domain` (2D parametrisations of the
//! sample space), `quadrature` (integrating a pdf over the cells), `report` (the outcome of a test) and `driver`
//! (the options, [`Chi2Test`] and [`discrete_test`]).

mod domain;
mod driver;
mod quadrature;
mod report;
mod stats;

pub use domain::{Domain, Equirect, Location, PlaneWindow, SphereCap, UnitSquare};
pub use driver::{discrete_test, Chi2Options, Chi2Test};
pub use quadrature::Quadrature;
pub use report::Chi2Report;
pub use stats::{chi2_sf, gamma_p, gamma_q, gauss_legendre, ln_gamma, pearson, sidak_alpha, Pearson};
