//! T5: the internal diffuse Fresnel reflectance `F_dr,int(η)` of a dielectric,
//! η ∈ [1, 3], as 1-D cubic B-spline coefficients. The layout and the
//! out-of-range rule are documented where the runtime reads it, in
//! `twoscale::tables::diffuse_fresnel::DiffuseFresnelTable`.
//!
//! Node count and mapping were chosen by measuring the not-a-knot spline of
//! the exact function (Stern's closed form at 40 digits) at 2000 points:
//! uniform nodes leave 4.7e-5 with 64 nodes, because of the `(η − 1)² ln(η − 1)`
//! term at η = 1; nodes evenly spaced in `ln(η − 1 + δ) + β η` fix it. Over
//! δ ∈ {0.01, 0.02, 0.03, 0.05}, β ∈ {0.5, 1, 2, 4} and 24–48 nodes, δ = 0.02,
//! β = 0.5 was best: max error 4.4e-7 (32 nodes), 1.9e-7 (40), 9.4e-8 (48).
//! 48 nodes keep the spline error well below the f32 rounding of the
//! coefficients and of the lookup, for the 1e-6 target, in 200 bytes.

use indicatif::{ParallelProgressIterator, ProgressBar};
use rayon::prelude::*;
use twoscale::tables::format::write::{TableSpec, encode};
use twoscale::tables::format::{AxisHeader, DiffuseFresnelParams, Mapping};
use twoscale::tables::interp::node_value;
use twoscale::{DiffuseFresnelTable, TableId};

use super::{Accuracy, Budget, BuildError, Export, GENERATOR_VERSION, TableKind};
use crate::bspline::prefilter;
use crate::reference::fresnel;
use crate::rng::SplitMix64;

/// η ∈ [1, 3], evenly spaced in ln(η − 0.98) + 0.5 η.
pub const ETA_AXIS: AxisHeader = AxisHeader {
    nodes: 48,
    mapping: Mapping::LogOffset,
    lo: 1.0,
    hi: 3.0,
    param: -0.98,
    param2: 0.5,
};

/// Target: max |F_dr,int − reference| ≤ 1e-6 (docs/model.md §3 sets none for T5; the
/// plastic base divides by `1 − ρd F_dr,int`, so this keeps the base layer
/// within ~1e-6 relative for ρd ≤ 0.5).
pub const TARGET_MAX_ABS_ERROR: f64 = 1e-6;

/// The T5 builder.
pub struct DiffuseFresnel;

fn reference(eta: f64, what: &str) -> Result<f64, BuildError> {
    fresnel::diffuse_internal(eta).map_err(|source| BuildError::Quadrature {
        at: format!("T5 {what} η = {eta}"),
        source,
    })
}

impl TableKind for DiffuseFresnel {
    fn id(&self) -> TableId {
        TableId::DiffuseFresnel
    }

    /// `|ΔF_dr| ≤ 5e-7`, half the target 1e-6.
    fn export(&self) -> Option<Export> {
        Some(Export {
            interpolation: "cubic uniform B-spline on the coefficients (coefficient j sits at node j - 1)",
            budget: Budget::Absolute(TARGET_MAX_ABS_ERROR / 2.0),
            c_lookups: crate::export::c::diffuse_fresnel,
            c_constants: None,
        })
    }

    fn work_items(&self) -> u64 {
        u64::from(ETA_AXIS.nodes)
    }

    fn build(&self, progress: &ProgressBar) -> Result<Vec<u8>, BuildError> {
        let n = ETA_AXIS.nodes as usize;
        let samples = (0..n)
            .into_par_iter()
            .progress_with(progress.clone())
            .map(|i| reference(node_value(&ETA_AXIS, i), "node"))
            .collect::<Result<Vec<f64>, BuildError>>()?;
        let coefficients: Vec<f32> = prefilter(&samples, &[n])
            .into_iter()
            .map(|v| v as f32)
            .collect();
        Ok(encode(&TableSpec {
            table_id: TableId::DiffuseFresnel,
            channels: 1,
            kernel: TableId::DiffuseFresnel.descriptor().kernel,
            value_type: TableId::DiffuseFresnel.descriptor().value_type,
            axes: &[ETA_AXIS],
            params: &DiffuseFresnelParams {
                quadrature_rel_tol: fresnel::DIFFUSE_TOL.rel,
                quadrature_abs_tol: fresnel::DIFFUSE_TOL.abs,
            }
            .to_values(),
            grid: &coefficients,
            aux: &[],
            generator_version: GENERATOR_VERSION,
        })?)
    }

    fn verify(&self, bytes: &[u8], points: usize, seed: u64) -> Result<Vec<Accuracy>, BuildError> {
        let table = DiffuseFresnelTable::from_bytes(bytes)?;
        let errors = verification_points(points, seed)
            .par_iter()
            .map(|&eta| {
                let want = reference(eta, "verify")?;
                let got = f64::from(table.f_dr_int(eta as f32));
                Ok(((got - want).abs(), format!("η = {eta:.7}")))
            })
            .collect::<Result<Vec<_>, BuildError>>()?;
        Ok(vec![Accuracy::from_errors(
            "max |F_dr,int - ref|",
            TARGET_MAX_ABS_ERROR,
            errors,
        )])
    }
}

/// Random points in [1, 3], rounded to f32 as the runtime takes them: half
/// uniform in η, half with η − 1 log-uniform in [1e-6, 2] (the cells near
/// η = 1, where the function is least smooth).
pub fn verification_points(points: usize, seed: u64) -> Vec<f64> {
    let mut rng = SplitMix64::new(seed);
    (0..points)
        .map(|k| {
            let eta = if k % 2 == 0 {
                rng.uniform_in(1.0, 3.0)
            } else {
                1.0 + rng.log_uniform_in(1e-6, 2.0)
            };
            f64::from(eta as f32).clamp(1.0, 3.0)
        })
        .collect()
}
