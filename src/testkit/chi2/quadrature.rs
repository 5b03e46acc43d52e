//! Numerical integration of a pdf over the cells: the per-cell [`Quadrature`], integration over every cell or a
//! flagged subset, and the dilation of flagged cells to their neighbours.

use super::stats::gauss_legendre;
use super::Domain;

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

pub(super) struct CellMass {
    pub(super) mass: Vec<f64>,
    /// Cells where some quadrature points have pdf 0 and others not.
    pub(super) mixed: Vec<bool>,
}

pub(super) fn integrate_cells<D: Domain>(
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

pub(super) fn integrate_subset<S: Copy>(
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
pub(super) fn dilate(flags: &[bool], rows: usize, cols: usize) -> Vec<bool> {
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
