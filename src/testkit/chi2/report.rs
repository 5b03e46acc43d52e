//! The outcome of one chi-square test ([`Chi2Report`]) and its one-line summary.

use super::Pearson;

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
