//! T6: the directional albedo `E(μ; β, p)` of the EPD microfacet lobe with
//! F = 1, separable and height-correlated masking, as tricubic B-spline
//! coefficients. The layout and the coordinates are documented where the
//! runtime reads it, in `twoscale::tables::albedo`; the node counts were chosen by
//! measuring the interpolated error against the reference
//! (docs/design/t6-albedo-axes.md).

use indicatif::{ParallelProgressIterator, ProgressBar};
use rayon::prelude::*;
use twoscale::TableId;
use twoscale::material::Masking;
use twoscale::tables::albedo::{self as runtime, AlbedoTable};
use twoscale::tables::format::write::{TableSpec, encode};
use twoscale::tables::format::{AlbedoParams, AxisHeader, Mapping};
use twoscale::tables::interp::node_value;

use super::{Accuracy, Budget, BuildError, Export, GENERATOR_VERSION, TableKind};
use crate::bspline::prefilter;
use crate::reference::albedo;
use crate::reference::epd::LambdaCurve;
use crate::rng::SplitMix64;

/// Incidence axis `y ∈ [0, 1]`, uniform.
pub const Y_AXIS: AxisHeader = AxisHeader {
    nodes: 36,
    mapping: Mapping::Uniform,
    lo: 0.0,
    hi: 1.0,
    param: 0.0,
    param2: 0.0,
};

/// Width axis `z ∈ [−1, 1]`, uniform.
pub const Z_AXIS: AxisHeader = AxisHeader {
    nodes: 48,
    mapping: Mapping::Uniform,
    lo: -1.0,
    hi: 1.0,
    param: 0.0,
    param2: 0.0,
};

/// p axis: [0.2, 5], evenly spaced in p^−0.35.
pub const P_AXIS: AxisHeader = AxisHeader {
    nodes: 14,
    mapping: Mapping::Power,
    lo: 0.2,
    hi: 5.0,
    param: -0.35,
    param2: 0.0,
};

/// β at which the nodes `z = −1` (the limit β → 0) are computed.
pub const BETA_AT_FIRST_NODE: f64 = 1e-7;

/// β at which the nodes `z = 1` (the limit β → ∞ at fixed y: the separable
/// albedo vanishes, the height-correlated one keeps its grazing boundary
/// layer) are computed; converged to 1e-6 from β = 10⁴ on.
pub const BETA_AT_LAST_NODE: f64 = 1e6;

/// Target: max |E − E_ref| ≤ 5e-4 for each masking, and the same for E_avg.
pub const TARGET_MAX_ABS_ERROR: f64 = 5e-4;

/// The T6 builder.
pub struct Albedo;

fn quadrature(at: String) -> impl FnOnce(crate::quad::QuadError) -> BuildError {
    move |source| BuildError::Quadrature { at, source }
}

/// `[E_separable, E_height_correlated]` at node `(iy, iz)` of the axes
/// `y_axis`, `z_axis`, for the p node whose curve is `curve`.
fn node(
    curve: &LambdaCurve,
    y_axis: &AxisHeader,
    z_axis: &AxisHeader,
    iy: usize,
    iz: usize,
) -> Result<[f64; 2], BuildError> {
    let p = curve.p();
    let beta = if iz == 0 {
        BETA_AT_FIRST_NODE
    } else if iz + 1 == z_axis.nodes as usize {
        BETA_AT_LAST_NODE
    } else {
        runtime::beta_at(node_value(z_axis, iz), p)
    };
    let mu = runtime::cos_at(node_value(y_axis, iy), runtime::incidence_stretch(beta, p));
    albedo::albedo_pair(curve, beta, mu)
        .map_err(quadrature(format!("T6 p = {p}, β = {beta}, μ = {mu}")))
}

impl TableKind for Albedo {
    fn id(&self) -> TableId {
        TableId::Albedo
    }

    /// `|ΔE| ≤ 2.5e-4`, half the target (the B-spline weights are
    /// non-negative and sum to 1).
    fn export(&self) -> Option<Export> {
        Some(Export {
            interpolation: "tricubic uniform B-spline on the coefficients (coefficient j of an axis sits at node j - 1) at y(cos theta_i, beta, p), z(beta, p), p; two channels (separable, height-correlated masking)",
            budget: Budget::Absolute(TARGET_MAX_ABS_ERROR / 2.0),
            c_lookups: crate::export::c::albedo,
            c_constants: None,
        })
    }

    fn work_items(&self) -> u64 {
        u64::from(Y_AXIS.nodes) * u64::from(Z_AXIS.nodes) * u64::from(P_AXIS.nodes)
    }

    fn build(&self, progress: &ProgressBar) -> Result<Vec<u8>, BuildError> {
        build_with([Y_AXIS, Z_AXIS, P_AXIS], progress)
    }

    /// E at `points / 50` random points against the adaptive reference
    /// (about 2 ms each), both maskings; E_avg at `points / 5000` (at least
    /// 4) random `(β, p)`, separable (about 0.5 s each).
    fn verify(&self, bytes: &[u8], points: usize, seed: u64) -> Result<Vec<Accuracy>, BuildError> {
        let table = AlbedoTable::from_bytes(bytes)?;
        let samples = verification_points((points / 50).max(8), seed);
        let errors = samples
            .par_iter()
            .map(|&(p, beta, mu)| {
                let curve =
                    LambdaCurve::new(p).map_err(quadrature(format!("T6 verify p = {p}")))?;
                let mut out = [(0.0, String::new()), (0.0, String::new())];
                for (k, masking) in [Masking::Separable, Masking::HeightCorrelated]
                    .into_iter()
                    .enumerate()
                {
                    let want = albedo::albedo(&curve, beta, mu, masking).map_err(quadrature(
                        format!("T6 verify p = {p}, β = {beta}, μ = {mu}"),
                    ))?;
                    let got = f64::from(table.albedo(mu as f32, beta as f32, p as f32, masking));
                    out[k] = (
                        (got - want).abs(),
                        format!("p = {p:.4}, β = {beta:.4e}, μ = {mu:.4e}"),
                    );
                }
                Ok(out)
            })
            .collect::<Result<Vec<_>, BuildError>>()?;
        let (sep, hc): (Vec<_>, Vec<_>) = errors.into_iter().map(|[a, b]| (a, b)).unzip();
        let averages = verification_points((points / 5000).max(4), seed ^ 0x6a)
            .par_iter()
            .map(|&(p, beta, _)| {
                let curve =
                    LambdaCurve::new(p).map_err(quadrature(format!("T6 verify p = {p}")))?;
                let want = albedo::albedo_average(&curve, beta, Masking::Separable)
                    .map_err(quadrature(format!("T6 verify E_avg p = {p}, β = {beta}")))?;
                let got = table
                    .column(beta as f32, p as f32, Masking::Separable)
                    .average();
                Ok(((got - want).abs(), format!("p = {p:.4}, β = {beta:.4e}")))
            })
            .collect::<Result<Vec<_>, BuildError>>()?;
        Ok(vec![
            Accuracy::from_errors("separable: max |E - E_ref|", TARGET_MAX_ABS_ERROR, sep),
            Accuracy::from_errors(
                "height-correlated: max |E - E_ref|",
                TARGET_MAX_ABS_ERROR,
                hc,
            ),
            Accuracy::from_errors(
                "separable: max |E_avg - E_avg,ref|",
                TARGET_MAX_ABS_ERROR,
                averages,
            ),
        ])
    }
}

/// T6's bytes on the axes `[y, z, p]` (the shipped ones are
/// [`Y_AXIS`], [`Z_AXIS`], [`P_AXIS`]; the design study of
/// docs/design/t6-albedo-axes.md builds others).
pub fn build_with(axes: [AxisHeader; 3], progress: &ProgressBar) -> Result<Vec<u8>, BuildError> {
    let [y_axis, z_axis, p_axis] = axes;
    let (ny, nz, np) = (
        y_axis.nodes as usize,
        z_axis.nodes as usize,
        p_axis.nodes as usize,
    );
    let curves = (0..np)
        .into_par_iter()
        .map(|k| {
            let p = node_value(&p_axis, k);
            LambdaCurve::new(p).map_err(quadrature(format!("T6 Λ curve p = {p}")))
        })
        .collect::<Result<Vec<_>, BuildError>>()?;
    let values = (0..ny * nz * np)
        .into_par_iter()
        .progress_with(progress.clone())
        .map(|k| {
            let (iy, iz, ip) = (k / (nz * np), (k / np) % nz, k % np);
            node(&curves[ip], &y_axis, &z_axis, iy, iz)
        })
        .collect::<Result<Vec<[f64; 2]>, BuildError>>()?;
    let channel = |c: usize| {
        prefilter(
            &values.iter().map(|v| v[c]).collect::<Vec<_>>(),
            &[ny, nz, np],
        )
    };
    let (sep, hc) = (channel(0), channel(1));
    let grid: Vec<f32> = sep
        .iter()
        .zip(&hc)
        .flat_map(|(&a, &b)| [a as f32, b as f32])
        .collect();
    Ok(encode(&TableSpec {
        table_id: TableId::Albedo,
        channels: 2,
        kernel: TableId::Albedo.descriptor().kernel,
        value_type: TableId::Albedo.descriptor().value_type,
        axes: &axes,
        params: &AlbedoParams {
            width_centre: runtime::WIDTH_CENTRE,
            width_exponent: runtime::WIDTH_EXPONENT,
            quadrature_points: albedo::PAIR_POINTS as f64,
            beta_at_first_node: BETA_AT_FIRST_NODE,
            beta_at_last_node: BETA_AT_LAST_NODE,
        }
        .to_values(),
        grid: &grid,
        aux: &[],
        generator_version: GENERATOR_VERSION,
    })?)
}

/// Random points `(p, β, μ)` in the runtime's domain, rounded to f32 as the
/// runtime takes them: p uniform in [0.2, 5], β log-uniform in [1e-4, 10];
/// μ uniform in [0, 1] for half the points, log-uniform in [1e-5, 1] (near
/// grazing, where E changes fastest) for the other half.
pub fn verification_points(points: usize, seed: u64) -> Vec<(f64, f64, f64)> {
    let mut rng = SplitMix64::new(seed);
    let f = |x: f64| f64::from(x as f32);
    (0..points)
        .map(|k| {
            let p = f(rng.uniform_in(0.2, 5.0)).clamp(0.2, 5.0);
            let beta = f(rng.log_uniform_in(1e-4, 10.0));
            let mu = if k % 2 == 0 {
                rng.uniform()
            } else {
                rng.log_uniform_in(1e-5, 1.0)
            };
            (p, beta, f(mu).clamp(0.0, 1.0))
        })
        .collect()
}
