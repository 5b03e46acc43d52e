//! Light tables on the CPU: the alias method (Vose 1991, built in f64), the light table with power and
//! uniform selection probabilities, and the environment map's sampling distribution (∝ luminance·sinθ).

use crate::gpu::types::*;
use crate::scene::EnvMap;

/// Relative luminance of linear Rec.709 RGB.
pub fn luminance(c: [f32; 3]) -> f64 {
    0.2126 * c[0] as f64 + 0.7152 * c[1] as f64 + 0.0722 * c[2] as f64
}

/// An alias table over `weights` and the normalised probabilities it samples.
#[derive(Clone, Debug)]
pub struct AliasTable {
    /// Entries as the GPU reads them.
    pub entries: Vec<GpuAliasEntry>,
    /// pmf[i] = weights[i] / Σ weights (f64).
    pub pmf: Vec<f64>,
}

/// Builds an alias table (Vose's method). Non-finite and negative weights count as 0; if every weight
/// is 0 the table is uniform. Works in f64 so that tables of millions of entries stay exact enough.
pub fn alias_table(weights: &[f64]) -> AliasTable {
    let n = weights.len();
    if n == 0 {
        return AliasTable { entries: vec![], pmf: vec![] };
    }
    let clean: Vec<f64> = weights.iter().map(|&w| if w.is_finite() && w > 0.0 { w } else { 0.0 }).collect();
    let total: f64 = clean.iter().sum();
    let pmf: Vec<f64> = if total > 0.0 { clean.iter().map(|w| w / total).collect() } else { vec![1.0 / n as f64; n] };
    let mut scaled: Vec<f64> = pmf.iter().map(|p| p * n as f64).collect();
    let mut entries = vec![GpuAliasEntry { prob: 1.0, alias_index: 0 }; n];
    for (i, e) in entries.iter_mut().enumerate() {
        e.alias_index = i as u32;
    }
    let (mut small, mut large): (Vec<usize>, Vec<usize>) = (0..n).partition(|&i| scaled[i] < 1.0);
    while let (Some(s), Some(&l)) = (small.pop(), large.last()) {
        entries[s] = GpuAliasEntry { prob: scaled[s] as f32, alias_index: l as u32 };
        scaled[l] = (scaled[l] + scaled[s]) - 1.0;
        if scaled[l] < 1.0 {
            large.pop();
            small.push(l);
        }
    }
    // Leftovers are 1 up to rounding.
    for i in small.into_iter().chain(large) {
        entries[i] = GpuAliasEntry { prob: 1.0, alias_index: i as u32 };
    }
    AliasTable { entries, pmf }
}

impl AliasTable {
    /// The probability the table actually samples index i with (for tests: from the entries themselves).
    pub fn effective_pmf(&self) -> Vec<f64> {
        let n = self.entries.len() as f64;
        let mut p = vec![0.0; self.entries.len()];
        for (i, e) in self.entries.iter().enumerate() {
            let prob = (e.prob as f64).clamp(0.0, 1.0);
            p[i] += prob / n;
            p[e.alias_index as usize] += (1.0 - prob) / n;
        }
        p
    }
}

/// The environment's GPU data: per texel rgb + density in (u,v) (pmf · W · H), and the alias table.
#[derive(Clone, Debug)]
pub struct EnvDistribution {
    /// rgb radiance (unscaled) and the sampling density in (u, v) space.
    pub texels: Vec<[f32; 4]>,
    /// Alias table over texels ∝ luminance · sinθ.
    pub alias: Vec<GpuAliasEntry>,
    /// Mean of luminance over the sphere (solid-angle weighted), for light power.
    pub mean_luminance: f64,
}

/// Builds the importance distribution of an equirectangular map: texel weight = luminance · sinθ at the
/// texel centre row (the Jacobian of the (u, v) → direction map, 2π² sinθ, up to a constant).
pub fn env_distribution(map: &EnvMap) -> EnvDistribution {
    let (w, h) = (map.width as usize, map.height as usize);
    let mut weights = vec![0.0f64; w * h];
    let mut lum_sum = 0.0;
    let mut sin_sum = 0.0;
    for y in 0..h {
        let sin_theta = (std::f64::consts::PI * (y as f64 + 0.5) / h as f64).sin();
        for x in 0..w {
            let l = luminance(map.texels[y * w + x]).max(0.0);
            weights[y * w + x] = l * sin_theta;
            lum_sum += l * sin_theta;
            sin_sum += sin_theta;
        }
    }
    let table = alias_table(&weights);
    let texels =
        map.texels.iter().zip(&table.pmf).map(|(c, p)| [c[0], c[1], c[2], (p * (w * h) as f64) as f32]).collect();
    EnvDistribution {
        texels,
        alias: table.entries,
        mean_luminance: if sin_sum > 0.0 { lum_sum / sin_sum } else { 0.0 },
    }
}
