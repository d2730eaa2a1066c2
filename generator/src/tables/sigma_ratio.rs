//! T2: σrel/σs of the K-correlation spectrum over (cos θi, B = b/λ, c), stored
//! as tricubic B-spline coefficients of `q = r / r0(B, c)`. The layout and the
//! out-of-domain rules are documented where the runtime reads it, in
//! `twoscale::tables::sigma_ratio`; why it is a B-spline and not trilinear is in docs/design/t2-tricubic-bspline.md.

use indicatif::{ParallelProgressIterator, ProgressBar};
use rayon::prelude::*;
use twoscale::tables::format::write::{TableSpec, encode};
use twoscale::tables::format::{AxisHeader, Mapping, SigmaRatioParams};
use twoscale::tables::interp::node_value;
use twoscale::{SigmaRatioTable, TableId};

use super::{Accuracy, Budget, BuildError, Export, GENERATOR_VERSION, TableKind};
use crate::bspline::prefilter;
use crate::reference::kcorr;
use crate::rng::SplitMix64;

/// cos θi ∈ [0, 1], evenly spaced in ln(cos θi + 0.003) + 1.5 cos θi.
pub const COS_AXIS: AxisHeader = AxisHeader {
    nodes: 72,
    mapping: Mapping::LogOffset,
    lo: 0.0,
    hi: 1.0,
    param: 0.003,
    param2: 1.5,
};

/// B = b/λ ∈ [0.05, 3000], evenly spaced in ln B.
pub const B_AXIS: AxisHeader = AxisHeader {
    nodes: 68,
    mapping: Mapping::Log,
    lo: 0.05,
    hi: 3000.0,
    param: 0.0,
    param2: 0.0,
};

/// c ∈ [1, 100], evenly spaced in ln(c − 0.8).
pub const C_AXIS: AxisHeader = AxisHeader {
    nodes: 32,
    mapping: Mapping::LogOffset,
    lo: 1.0,
    hi: 100.0,
    param: -0.8,
    param2: 0.0,
};

/// The c = 1 node is evaluated at c = 1 + this (the c → 1 limit of q).
pub const C_MINUS_1_AT_FIRST_NODE: f64 = 1e-12;

/// Target of docs/model.md §3: max relative error ≤ 1e-4.
pub const TARGET_MAX_REL_ERROR: f64 = 1e-4;

/// The T2 builder.
pub struct SigmaRatio;

/// `q = r / r0` at a node (θi from cos θi; c = 1 replaced by its limit).
fn node_sample(cos_theta_i: f64, big_b: f64, c: f64) -> Result<f64, BuildError> {
    let c = c.max(1.0 + C_MINUS_1_AT_FIRST_NODE);
    let theta_i = cos_theta_i.clamp(0.0, 1.0).acos();
    let ratio_sq =
        kcorr::sigma_ratio_sq(theta_i, big_b, c).map_err(|source| BuildError::Quadrature {
            at: format!("T2 θi = {theta_i}, B = {big_b}, c = {c}"),
            source,
        })?;
    Ok((ratio_sq / kcorr::sigma_ratio_sq_normal(big_b, c)).sqrt())
}

impl TableKind for SigmaRatio {
    fn id(&self) -> TableId {
        TableId::SigmaRatio
    }

    /// Relative target 1e-4 on `r = q · r0`: the B-spline weights are
    /// non-negative and sum to 1, so `|Δq| ≤ max |Δcoefficient|`, and the
    /// budget is `0.5e-4 · min q`.
    fn export(&self) -> Option<Export> {
        Some(Export {
            interpolation: "tricubic uniform B-spline on the coefficients (coefficient j of an axis sits at node j - 1); gives q = r/r0, multiply by r0 = sqrt(1 - (1 + B^2)^(-(c-1)/2))",
            budget: Budget::RelativeToMin(TARGET_MAX_REL_ERROR / 2.0),
            c_lookups: crate::export::c::sigma_ratio,
            c_constants: None,
        })
    }

    fn work_items(&self) -> u64 {
        u64::from(COS_AXIS.nodes) * u64::from(B_AXIS.nodes) * u64::from(C_AXIS.nodes)
    }

    fn build(&self, progress: &ProgressBar) -> Result<Vec<u8>, BuildError> {
        let (n0, n1, n2) = (
            COS_AXIS.nodes as usize,
            B_AXIS.nodes as usize,
            C_AXIS.nodes as usize,
        );
        let samples = (0..n0 * n1 * n2)
            .into_par_iter()
            .progress_with(progress.clone())
            .map(|k| {
                let (i, j, l) = (k / (n1 * n2), (k / n2) % n1, k % n2);
                node_sample(
                    node_value(&COS_AXIS, i),
                    node_value(&B_AXIS, j),
                    node_value(&C_AXIS, l),
                )
            })
            .collect::<Result<Vec<f64>, BuildError>>()?;
        let coefficients: Vec<f32> = prefilter(&samples, &[n0, n1, n2])
            .into_iter()
            .map(|v| v as f32)
            .collect();
        Ok(encode(&TableSpec {
            table_id: TableId::SigmaRatio,
            channels: 1,
            kernel: TableId::SigmaRatio.descriptor().kernel,
            value_type: TableId::SigmaRatio.descriptor().value_type,
            axes: &[COS_AXIS, B_AXIS, C_AXIS],
            params: &SigmaRatioParams {
                quadrature_rel_tol: kcorr::SIGMA_RATIO_TOL.rel,
                c_minus_1_at_first_node: C_MINUS_1_AT_FIRST_NODE,
            }
            .to_values(),
            grid: &coefficients,
            aux: &[],
            generator_version: GENERATOR_VERSION,
        })?)
    }

    fn verify(&self, bytes: &[u8], points: usize, seed: u64) -> Result<Vec<Accuracy>, BuildError> {
        let table = SigmaRatioTable::from_bytes(bytes)?;
        let errors = verification_points(points, seed)
            .par_iter()
            .map(|&(cos_theta_i, big_b, c)| {
                Ok((
                    error_at(&table, cos_theta_i, big_b, c)?,
                    format!(
                        "θi = {:.4}°, B = {big_b:.4}, c = {c:.4}",
                        cos_theta_i.acos().to_degrees()
                    ),
                ))
            })
            .collect::<Result<Vec<_>, BuildError>>()?;
        Ok(vec![Accuracy::from_errors(
            "max rel |r - r_ref|",
            TARGET_MAX_REL_ERROR,
            errors,
        )])
    }
}

/// The error `verify` measures at one point: the relative error of the
/// table's σ ratio at `(cos θi, B, c)` against the reference.
pub fn error_at(
    table: &SigmaRatioTable<'_>,
    cos_theta_i: f64,
    big_b: f64,
    c: f64,
) -> Result<f64, BuildError> {
    let theta_i = cos_theta_i.acos();
    let reference =
        kcorr::sigma_ratio(theta_i, big_b, c).map_err(|source| BuildError::Quadrature {
            at: format!("T2 verify θi = {theta_i}, B = {big_b}, c = {c}"),
            source,
        })?;
    let got = f64::from(table.sigma_ratio_cos(cos_theta_i as f32, big_b as f32, c as f32));
    Ok(((got - reference) / reference).abs())
}

/// Random points over T2's domain (docs/model.md §3) θi ∈ [0, π/2], B ∈ [0.1, 3000],
/// c ∈ [1.01, 100] (returned as cos θi, B, c, each rounded to f32 as the
/// runtime API takes them): ln B and ln(c − 1) uniform; θi uniform for half
/// the points, and cos θi log-uniform in [1e-4, 1] for the other half, to
/// probe the grazing boundary layer.
pub fn verification_points(points: usize, seed: u64) -> Vec<(f64, f64, f64)> {
    let mut rng = SplitMix64::new(seed);
    (0..points)
        .map(|k| {
            let cos_theta_i = if k % 2 == 0 {
                rng.uniform_in(0.0, std::f64::consts::FRAC_PI_2).cos()
            } else {
                rng.log_uniform_in(1e-4, 1.0)
            };
            let big_b = rng.log_uniform_in(0.1, 3000.0);
            let c = 1.0 + rng.log_uniform_in(0.01, 99.0);
            let f32_round = |x: f64| f64::from(x as f32);
            (f32_round(cos_theta_i), f32_round(big_b), f32_round(c))
        })
        .collect()
}
