//! T1: Smith G1 of the EPD NDF over (p, ã = k_p·a). The layout and its reasons
//! are documented where the runtime reads it, in `twoscale::tables::smith_g1`.
//!
//! Node count and mappings were chosen by measuring the linear-interpolation
//! error of G1 at cell midpoints against the reference (docs/design/t1-scaled-axis.md): with ã nodes evenly spaced in ln(ã + 0.01) the a-direction error
//! peaks at the steep p = 5 transition near ã ≈ 0.33 and falls as 1/N²; with
//! p nodes evenly spaced in p^−½ the p-direction error is flat across p.
//! 64 × 1000 nodes leave both near 5e-6, well inside the 2e-5 target, in
//! 256 000 bytes of values.

use indicatif::{ParallelProgressIterator, ProgressBar};
use rayon::prelude::*;
use twoscale::tables::format::write::{TableSpec, encode};
use twoscale::tables::format::{AxisHeader, Mapping, SmithG1Params};
use twoscale::tables::interp::node_value;
use twoscale::{SmithG1Table, TableId};

use super::{Accuracy, Budget, BuildError, Export, GENERATOR_VERSION, TableKind};
use crate::reference::epd;
use crate::rng::SplitMix64;

/// p axis: [0.2, 5], evenly spaced in p^−½.
pub const P_AXIS: AxisHeader = AxisHeader {
    nodes: 64,
    mapping: Mapping::Power,
    lo: 0.2,
    hi: 5.0,
    param: -0.5,
    param2: 0.0,
};

/// ã axis: [0, 100], evenly spaced in ln(ã + 0.01).
pub const SCALED_AXIS: AxisHeader = AxisHeader {
    nodes: 1000,
    mapping: Mapping::LogOffset,
    lo: 0.0,
    hi: 100.0,
    param: 0.01,
    param2: 0.0,
};

/// Target of docs/model.md §3: max |G1 − G1_ref| ≤ 2e-5.
pub const TARGET_MAX_ABS_ERROR: f64 = 2e-5;

/// The T1 builder.
pub struct SmithG1;

/// k_p at each p node, as stored in the aux values (the runtime recomputes k_p
/// in closed form and checks these at load time).
pub fn stored_slopes() -> Vec<f32> {
    (0..P_AXIS.nodes as usize)
        .map(|j| epd::k_p(node_value(&P_AXIS, j)) as f32)
        .collect()
}

impl TableKind for SmithG1 {
    fn id(&self) -> TableId {
        TableId::SmithG1
    }

    /// `|ΔG1| ≤ 1e-5`, half the target 2e-5 (bilinear weights sum to 1).
    fn export(&self) -> Option<Export> {
        Some(Export {
            interpolation: "bilinear in (p, a_scaled) node positions; a_scaled = k_p * beta * tan(theta), k_p = Gamma(3/(2p))/(pi Gamma(1/p)); beyond the last a_scaled node Lambda = Lambda(last) + (a_scaled - last)",
            budget: Budget::Absolute(TARGET_MAX_ABS_ERROR / 2.0),
            c_lookups: crate::export::c::smith_g1,
            c_constants: None,
        })
    }

    fn work_items(&self) -> u64 {
        u64::from(P_AXIS.nodes) * u64::from(SCALED_AXIS.nodes)
    }

    fn build(&self, progress: &ProgressBar) -> Result<Vec<u8>, BuildError> {
        let slopes = stored_slopes();
        let n_a = SCALED_AXIS.nodes as usize;
        let grid = (0..self.work_items() as usize)
            .into_par_iter()
            .progress_with(progress.clone())
            .map(|k| {
                let (j, i) = (k / n_a, k % n_a);
                let p = node_value(&P_AXIS, j);
                let a = node_value(&SCALED_AXIS, i) / epd::k_p(p);
                epd::g1(p, a)
                    .map(|g| g as f32)
                    .map_err(|source| BuildError::Quadrature {
                        at: format!("T1 p = {p}, a = {a}"),
                        source,
                    })
            })
            .collect::<Result<Vec<f32>, BuildError>>()?;
        Ok(encode(&TableSpec {
            table_id: TableId::SmithG1,
            channels: 1,
            kernel: TableId::SmithG1.descriptor().kernel,
            value_type: TableId::SmithG1.descriptor().value_type,
            axes: &[P_AXIS, SCALED_AXIS],
            params: &SmithG1Params {
                quadrature_rel_tol: epd::LAMBDA_TOL.rel,
                quadrature_abs_tol: epd::LAMBDA_TOL.abs,
            }
            .to_values(),
            grid: &grid,
            aux: &slopes,
            generator_version: GENERATOR_VERSION,
        })?)
    }

    fn verify(&self, bytes: &[u8], points: usize, seed: u64) -> Result<Vec<Accuracy>, BuildError> {
        let table = SmithG1Table::from_bytes(bytes)?;
        let samples = verification_points(points, seed);
        let errors = samples
            .par_iter()
            .map(|&(p, a)| Ok((error_at(&table, p, a)?, format!("p = {p:.4}, a = {a:.4e}"))))
            .collect::<Result<Vec<_>, BuildError>>()?;
        Ok(vec![Accuracy::from_errors(
            "max |G1 - G1_ref|",
            TARGET_MAX_ABS_ERROR,
            errors,
        )])
    }
}

/// The error `verify` measures at one point: `|G1 − G1_ref|` of the table at
/// `(p, a)` against the reference.
pub fn error_at(table: &SmithG1Table<'_>, p: f64, a: f64) -> Result<f64, BuildError> {
    let reference = epd::g1(p, a).map_err(|source| BuildError::Quadrature {
        at: format!("T1 verify p = {p}, a = {a}"),
        source,
    })?;
    Ok((f64::from(table.g1(p as f32, a as f32)) - reference).abs())
}

/// Random verification points (p, a), off-grid with probability 1: p uniform
/// in [0.2, 5]; half the a values uniform in the ã coordinate ln(ã + 0.01) over
/// [0, 3·ã_last] (so every cell and the asymptotic region are hit), divided by
/// the exact k_p; half log-uniform in [1e-4, 1e4]. The values are rounded to f32
/// first, since the runtime API takes f32: the error then measures the table,
/// not the rounding of the query.
pub fn verification_points(points: usize, seed: u64) -> Vec<(f64, f64)> {
    let mut rng = SplitMix64::new(seed);
    let c_lo = (SCALED_AXIS.param).ln();
    let c_hi = (3.0 * SCALED_AXIS.hi + SCALED_AXIS.param).ln();
    (0..points)
        .map(|k| {
            let p = rng.uniform_in(P_AXIS.lo, P_AXIS.hi) as f32 as f64;
            let a = if k % 2 == 0 {
                let a_scaled = rng.uniform_in(c_lo, c_hi).exp() - SCALED_AXIS.param;
                a_scaled.max(0.0) / epd::k_p(p)
            } else {
                rng.log_uniform_in(1e-4, 1e4)
            };
            (p, a as f32 as f64)
        })
        .collect()
}
