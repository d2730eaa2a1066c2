//! T3: the convolution `C(θh; u, c, β, p)` of the diffraction kernel with the
//! EPD NDF (docs/model.md §2.5), in both forms of `twoscale::tables::convolution` (where the layout,
//! the normalised angle and the out-of-domain rules are documented): the
//! paper's `s · k(2 g sin θh)` (T3a) and `ln C` at 32 normalised angles
//! (T3b), at every node of a `(u, c, β, p)` grid, in one file.
//!
//! # What a node costs, and the build
//!
//! Each node needs the exact profile at its 32 angles (the reference
//! `convolution_profile`: zonal harmonics when affordable, otherwise direct
//! 2-D quadrature per angle; 1 ms to ~1 s per node). The build shares the
//! zonal-harmonic moments between nodes ([`MomentCache`]: the kernel's
//! depend on `(u, c)` only, the NDF's on `(β, p)` only), which leaves the
//! direct quadrature of the narrow kernels (`u ≳ 150` on cusped `D`, a
//! quarter of the nodes) as most of the cost. The progress bar counts
//! estimated CPU time ([`node_cost`]), not nodes. The nodes can be computed
//! in shards on several machines and merged bit-identically ([`Shard`],
//! `generator build t3 --shard K/N`, `generator merge`). Measured times, the
//! profile and a cluster example: docs/design/t3-build-speed.md.
//!
//! # The fit of T3a
//!
//! `s, g` minimise the docs/model.md §2.5 metric `e_L2` of `s · k(2g sin θh)` against
//! the node's exact profile (variable projection: `s` in closed form, `ln g`
//! by scan + golden section; `generator::fit`), with the metric's integral
//! `∫ (…)² sin θh dθh` discretised on the node's 32 angles: trapezoid weights
//! in `ξ` times `dθh/dξ` (central differences of the exact inverse). The
//! fit is deterministic (no warm start).
//!
//! # Grid
//!
//! u: 28 nodes in ln(u + 0.1) over [0, 3000]; c: 10 in ln(c − 1) + c/2 over
//! [1.01, 10]; β: 12 in ln β over [0.002, 1]; p: 12 in p^−½ over [0.2, 5].
//! 40 320 nodes × 34 channels, stored quantised per node (`ValueType::U16`:
//! 34 u16 codes and an f32 offset and step per node, 76 bytes instead of
//! 136; error ≤ 3.4e-4 in ln C, the largest node range being 44) = 3.06 MB, so that T1–T3 stay within the 4 MiB budget
//! of docs/model.md §3. The u axis got the nodes that quantisation freed: measured along u
//! alone (`studies t3-axis u --triples 30`, 30
//! random (c, β, p), exact profiles), 16 → 28 nodes cut the 95th percentile
//! of the pointwise error where C > 1e-3 C(0) from 2.4% to 0.31% on
//! `brdf_scipy.py`'s distribution (1.3% → 0.16% on verify's), and where
//! 1e-9 < C/C(0) < 1e-3 from 3.2% to 0.46% (5.7% → 1.4%). Moving the offset
//! to ln(u + 1) or ln(u + 3) made it worse (p95 12% and 40% at 16 nodes):
//! the profile changes fastest for u ≲ 1. The first layout (20 × 8 × 14 × 9, from the design
//! study, now only in git history) was measured with its nodes snapped to the
//! grid one axis at a time: snapping p cut the mean e_L2 from 0.76% to 0.47%,
//! c to 0.67%, u and β to 0.74–0.75%; so p and c got the nodes, u and β gave
//! some up. The c mapping's linear term is documented at [`C_AXIS`].

use indicatif::ProgressBar;
use rayon::prelude::*;
use twoscale::tables::convolution::{
    ConvTable, Convolution, FIT_CHANNELS, kernel, tan_of_normalised_angle,
};
use twoscale::tables::format::AngleParams;
use twoscale::tables::format::write::{TableSpec, encode};
use twoscale::tables::format::{AxisHeader, ConvParams, Mapping, quantise_node};
use twoscale::tables::interp::node_value;
use twoscale::{Table, TableId};

use super::{Accuracy, Budget, BuildError, Export, GENERATOR_VERSION, SpotCheck, TableKind};
use crate::fit::{WidthFitOptions, fit_k_lobe};
use crate::reference::conv::{
    ConvError, MomentCache, Params, ProfileRule, convolution_profile, convolution_profile_cached,
    tries_zonal_harmonics,
};
use crate::rng::SplitMix64;

/// u ∈ [0, 3000], evenly spaced in ln(u + 0.1).
pub const U_AXIS: AxisHeader = AxisHeader {
    nodes: 28,
    mapping: Mapping::LogOffset,
    lo: 0.0,
    hi: 3000.0,
    param: 0.1,
    param2: 0.0,
};

/// c ∈ [1.01, 10], evenly spaced in ln(c − 1) + c/2: logarithmic near
/// c = 1, where the narrow-kernel limit `ln C ≈ ln D − ln(c − 1) + …` is linear
/// in ln(c − 1), and linear for large c, where the kernel's tail
/// `ln C ≈ −(c+1)/2 · ln(1 + 4u² sin²θh)` is linear in c. Measured along c
/// alone (`studies t3-axis c`, 40 random
/// (u, β, p), 80 random c, 32 angles each; Catmull–Rom): the 95th percentile
/// of the relative error where 1e-9 < C/C(0) < 1e-3 is 18% with pure
/// ln(c − 1) spacing, 7.8% with slope ¼, 2.7% with ½ (1.7% on
/// `brdf_scipy.py`'s distribution), while where C > 1e-3 C(0) it stays ≤ 1.3%.
pub const C_AXIS: AxisHeader = AxisHeader {
    nodes: 10,
    mapping: Mapping::LogOffset,
    lo: 1.01,
    hi: 10.0,
    param: -1.0,
    param2: 0.5,
};

/// β ∈ [0.002, 1], evenly spaced in ln β.
pub const BETA_AXIS: AxisHeader = AxisHeader {
    nodes: 12,
    mapping: Mapping::Log,
    lo: 0.002,
    hi: 1.0,
    param: 0.0,
    param2: 0.0,
};

/// p ∈ [0.2, 5], evenly spaced in p^−½.
pub const P_AXIS: AxisHeader = AxisHeader {
    nodes: 12,
    mapping: Mapping::Power,
    lo: 0.2,
    hi: 5.0,
    param: -0.5,
    param2: 0.0,
};

/// Number of normalised angles `ξ_k = k / (ANGLES − 1)` per node.
pub const ANGLES: usize = 32;

/// The normalised angle's constants (`twoscale::tables::convolution`): `τ_max = 1e4`,
/// `u_floor = 1`, `λ = 1`, `Y = 30` (the design study's choice), `κ = 1`
/// (`studies t3-angle-softening`: of κ ∈ {0, ½, 1, 2, 4},
/// 1 gave the lowest ξ-interpolation error on `brdf_scipy.py`'s parameter
/// distribution, e_L2 max 5.1% → 1.0%, and verify's max 3.5% → 1.6%), and
/// the horizon and edge terms `w_h = ½`, `w_e = ½`, smoothed over 2 kernel
/// widths, faded with `τ_f = 3` (`studies t3-angle-at-points`
/// and `studies t3-angle-forms`, ξ interpolation alone: at the BRDF check's 400
/// points p95 4.3% → 0.37%, max 11% → 3.7% against format 1's angle; on
/// verify's distribution e_L2 max 0.99% → 0.46%, pointwise p95 0.46% →
/// 0.77%; docs/design/t3-normalised-angle.md), and since format 3 the edge
/// term faded by `(p′/p)^m`, `m = 2`, where the kernel is wider than the NDF
/// (patch mode, β and p interpolated: verify's e_L2 max 11% → 3.1%, energy
/// 23% → 4.3%; docs/design/t3-accuracy-candidates.md).
pub const ANGLE: AngleParams = AngleParams {
    tau_max: 1e4,
    kernel_scale_floor: 1.0,
    ndf_weight: 1.0,
    ndf_exponent_cap: 30.0,
    ndf_softening: 1.0,
    horizon_weight: 0.5,
    edge_weight: 0.5,
    edge_smoothing: 2.0,
    edge_fade_tan: 3.0,
    edge_softening_fade: 2.0,
};

/// T3a stores `ln(g² + G_OFFSET)`: smooth through `g → 0` (flat profiles).
pub const G_OFFSET: f64 = 0.09;

/// Values below `VALUE_FLOOR · max C` of a node are stored as that floor (the
/// zonal-harmonic series is only accurate to ~1e-13 of the peak there).
pub const VALUE_FLOOR: f64 = 1e-12;

/// Channels per node.
pub const CHANNELS: usize = FIT_CHANNELS + ANGLES;

mod shard;
pub use shard::{Shard, ShardError};

/// The T3 builder.
pub struct Conv;

const AXES: [AxisHeader; 4] = [U_AXIS, C_AXIS, BETA_AXIS, P_AXIS];

/// The number of T3's nodes (the product of the axes' node counts).
pub fn node_count() -> usize {
    AXES.iter().map(|a| a.nodes as usize).product()
}

/// `(u, c, β, p)` of node `index` (storage order: p fastest).
pub fn node_params(index: usize) -> [f64; 4] {
    let mut rest = index;
    let mut out = [0.0; 4];
    for d in (0..4).rev() {
        let n = AXES[d].nodes as usize;
        out[d] = node_value(&AXES[d], rest % n);
        rest /= n;
    }
    out
}

fn conv_error(at: String, e: ConvError) -> BuildError {
    BuildError::Convolution {
        at,
        message: e.to_string(),
    }
}

/// The 32 angles `θ_k` of a parameter point and the weights of the discretised
/// `∫ f(θ) sin θ dθ` on them (trapezoid in `ξ` times `dθ/dξ`).
pub fn angle_rule(u: f64, beta: f64, p: f64) -> (Vec<f64>, Vec<f64>) {
    let theta_of = |xi: f64| tan_of_normalised_angle(xi, u, beta, p, &ANGLE).atan();
    let step = 1.0 / (ANGLES - 1) as f64;
    let h = 1e-4;
    let mut thetas = Vec::with_capacity(ANGLES);
    let mut weights = Vec::with_capacity(ANGLES);
    for k in 0..ANGLES {
        let xi = k as f64 * step;
        let theta = theta_of(xi);
        let (a, b) = ((xi - h).max(0.0), (xi + h).min(1.0));
        let jacobian = (theta_of(b) - theta_of(a)) / (b - a);
        let trapezoid = if k == 0 || k + 1 == ANGLES {
            0.5 * step
        } else {
            step
        };
        thetas.push(theta);
        weights.push(trapezoid * jacobian * theta.sin());
    }
    (thetas, weights)
}

/// The paper's fit `(s, g)` to a profile on the angle rule of its point.
pub fn fit_paper_form(c: f64, thetas: &[f64], weights: &[f64], values: &[f64]) -> (f64, f64) {
    let fit = fit_k_lobe(thetas, weights, values, c, 0.0, &WidthFitOptions::default());
    (fit.s, fit.g)
}

/// The 34 stored values of node `index`.
pub fn node_values(index: usize) -> Result<Vec<f32>, BuildError> {
    node_values_cached(index, &MomentCache::new())
}

/// [`node_values`] with the zonal-harmonic moments shared through `cache`
/// (bit-identical; the build shares one cache between all nodes).
pub fn node_values_cached(index: usize, cache: &MomentCache) -> Result<Vec<f32>, BuildError> {
    let [u, c, beta, p] = node_params(index);
    let at = || format!("T3 node {index} (u = {u}, c = {c}, β = {beta}, p = {p})");
    let (thetas, weights) = angle_rule(u, beta, p);
    let (values, _) = convolution_profile_cached(u, c, beta, p, &thetas, cache)
        .map_err(|e| conv_error(at(), e))?;
    let peak = values.iter().cloned().fold(0.0f64, f64::max);
    if peak.is_nan() || peak <= 0.0 || peak.is_infinite() {
        return Err(BuildError::Convolution {
            at: at(),
            message: format!("profile has no positive finite maximum ({peak})"),
        });
    }
    let (s, g) = fit_paper_form(c, &thetas, &weights, &values);
    let mut out = Vec::with_capacity(CHANNELS);
    out.push(s.max(f64::MIN_POSITIVE).ln() as f32);
    out.push((g * g + G_OFFSET).ln() as f32);
    let floor = VALUE_FLOOR * peak;
    out.extend(values.iter().map(|&v| v.max(floor).ln() as f32));
    Ok(out)
}

/// The header's generation parameters of a T3 file with `angles` angles and
/// the angle constants `angle` (`ConvTable::from_table` reads them back).
pub fn header_params(angles: usize, angle: &AngleParams) -> ConvParams {
    ConvParams::new(angles, angle, G_OFFSET, VALUE_FLOOR)
}

fn encode_table(grid: &[f32]) -> Result<Vec<u8>, BuildError> {
    Ok(encode(&TableSpec {
        table_id: TableId::Convolution,
        channels: CHANNELS as u32,
        kernel: TableId::Convolution.descriptor().kernel,
        value_type: TableId::Convolution.descriptor().value_type,
        axes: &AXES,
        params: &header_params(ANGLES, &ANGLE).to_values(),
        grid,
        aux: &[],
        generator_version: GENERATOR_VERSION,
    })?)
}

/// Estimated cost of node `index`, in units of 0.1 ms of CPU (the weights of
/// the progress bar, so that its ETA is honest although node costs span four
/// decades). Nodes tried by zonal harmonics ([`node_tries_zonal_harmonics`])
/// cost little once the lobes' moments are shared; the others take
/// the direct quadrature at every angle, whose lobe evaluations were fitted
/// on every 7th node (`studies t3-direct-cost --stride 7`, 1 528 direct
/// nodes with `u > 100`) as `634 000 (u/100)^0.056 β^0.103 p^(−0.358)`
/// (half the nodes within 0.68–1.44× of it), at ≈ 76 ns per evaluation
/// (docs/design/t3-build-speed.md, passes 3 and 4).
pub fn node_cost(index: usize) -> u64 {
    let [u, _, beta, p] = node_params(index);
    if node_tries_zonal_harmonics(index) {
        ZH_NODE_COST
    } else {
        let shape = 0.056 * (u.max(1.0) / 100.0).ln() + 0.103 * beta.ln() - 0.358 * p.ln();
        (DIRECT_NODE_COST * shape.exp()) as u64
    }
}

/// Whether node `index` is tried by zonal harmonics first
/// ([`tries_zonal_harmonics`]); otherwise it takes the direct quadrature.
pub fn node_tries_zonal_harmonics(index: usize) -> bool {
    let [u, c, beta, p] = node_params(index);
    tries_zonal_harmonics(&Params::new(u, c, beta, p).expect("grid nodes are valid"))
}

/// [`node_cost`] of a zonal-harmonic node (moments amortised), 0.1 ms units.
const ZH_NODE_COST: u64 = 20;
/// [`node_cost`] of a direct-quadrature node at `u = 100`, `β = 1`, `p = 1`
/// (634 000 evaluations at ≈ 76 ns each, docs/design/t3-build-speed.md),
/// 0.1 ms units.
const DIRECT_NODE_COST: f64 = 480.0;

/// Computes the nodes `indices` (results in that order), advancing
/// `progress` by each node's [`node_cost`]; one [`MomentCache`] is shared by
/// all. The most expensive nodes are computed first: the progress rate is
/// then set by the direct-quadrature nodes, whose cost is modelled, rather
/// than by the first zonal-harmonic nodes, which pay for the shared moments
/// (the ETA was 2.5–2.9× too high in the first 90 s in index order), and no
/// long node is left for the end. Each node's values do not depend on the
/// order (the moments are a function of the lobe and the band limit).
fn compute_nodes(indices: &[usize], progress: &ProgressBar) -> Result<Vec<Vec<f32>>, BuildError> {
    let cache = MomentCache::new();
    let mut order: Vec<(usize, u64)> = indices
        .iter()
        .enumerate()
        .map(|(k, &i)| (k, node_cost(i)))
        .collect();
    order.sort_by_key(|&(k, cost)| (std::cmp::Reverse(cost), k));
    let computed: Vec<(usize, Vec<f32>)> = order
        .par_iter()
        .map(|&(k, cost)| {
            let values = node_values_cached(indices[k], &cache)?;
            progress.inc(cost);
            Ok((k, values))
        })
        .collect::<Result<_, BuildError>>()?;
    let mut nodes = vec![Vec::new(); indices.len()];
    for (k, values) in computed {
        nodes[k] = values;
    }
    Ok(nodes)
}

/// Total [`node_cost`] of the nodes of `shard` (all nodes: `None`).
pub fn work(shard: Option<Shard>) -> u64 {
    match shard {
        Some(s) => s.indices().map(node_cost).sum(),
        None => (0..node_count()).map(node_cost).sum(),
    }
}

/// The bytes of the shard file of `shard` (see [`Shard`]).
pub fn build_shard(shard: Shard, progress: &ProgressBar) -> Result<Vec<u8>, BuildError> {
    let indices: Vec<usize> = shard.indices().collect();
    Ok(shard::encode(shard, &compute_nodes(&indices, progress)?)?)
}

/// The table from the shard files `files` (name, bytes) of one `N`-way
/// split: bit-identical to [`Conv`]'s build.
pub fn merge(files: &[(String, Vec<u8>)]) -> Result<Vec<u8>, BuildError> {
    encode_table(&shard::merge_grid(files)?)
}

impl TableKind for Conv {
    fn id(&self) -> TableId {
        TableId::Convolution
    }

    /// No coarser than what the runtime reads: half the largest per-node
    /// step of the file's own quantisation (3.4e-4 in `ln C`).
    fn export(&self) -> Option<Export> {
        Some(Export {
            interpolation: "per parameter axis Catmull-Rom on nodes i-1..i+2 (quadratic in the first and last cell); channels 2..33: ln C at xi = k/31, Catmull-Rom along xi with one-sided end slopes; C = exp(ln C); channels 0, 1: ln s, ln(g^2 + g_offset)",
            budget: Budget::HalfQuantisationStep,
            c_lookups: crate::export::c::convolution,
            c_constants: Some(crate::export::c::normalised_angle),
        })
    }

    fn work_items(&self) -> u64 {
        work(None)
    }

    /// [`node_cost`]s: the progress reads "4.6% of the estimated work".
    fn work_unit(&self) -> &'static str {
        "estimated work"
    }

    fn build(&self, progress: &ProgressBar) -> Result<Vec<u8>, BuildError> {
        let indices: Vec<usize> = (0..node_count()).collect();
        let grid: Vec<f32> = compute_nodes(&indices, progress)?
            .into_iter()
            .flatten()
            .collect();
        encode_table(&grid)
    }

    fn spot_check(&self, bytes: &[u8], nodes: usize) -> Option<Result<SpotCheck, BuildError>> {
        Some(spot_check(bytes, nodes))
    }

    fn verify(&self, bytes: &[u8], points: usize, seed: u64) -> Result<Vec<Accuracy>, BuildError> {
        verify(bytes, profiles_for(points), seed)
    }
}

/// Recomputes `nodes` nodes spread evenly over the grid (first and last
/// included) and compares their bits with the file's.
pub fn spot_check(bytes: &[u8], nodes: usize) -> Result<SpotCheck, BuildError> {
    let table = Table::from_bytes_expecting(bytes, TableId::Convolution)?;
    let total = node_count();
    let Some(stored) = table
        .quantised()
        .filter(|q| q.codes.len() == total * CHANNELS)
    else {
        return Err(BuildError::Convolution {
            at: "T3 spot check".into(),
            message: "the file's grid does not have this generator's layout".into(),
        });
    };
    let nodes = nodes.clamp(1, total);
    let indices: Vec<usize> = (0..nodes)
        .map(|k| {
            if nodes == 1 {
                0
            } else {
                k * (total - 1) / (nodes - 1)
            }
        })
        .collect();
    let cache = MomentCache::new();
    let mismatches = indices
        .par_iter()
        .map(|&i| {
            // The stored form: the node's quantisation pair and its codes.
            let fresh = node_values_cached(i, &cache)?;
            let mut codes = [0u16; CHANNELS];
            let scale = quantise_node(&fresh, &mut codes);
            let bits = |x: &[f32]| x.iter().map(|v| v.to_bits()).collect::<Vec<_>>();
            let same = stored.scales.get(2 * i..2 * i + 2).map(bits) == Some(bits(&scale))
                && stored.codes.get(i * CHANNELS..(i + 1) * CHANNELS) == Some(&codes[..]);
            Ok(if same { None } else { Some(i) })
        })
        .collect::<Result<Vec<_>, BuildError>>()?;
    Ok(SpotCheck {
        checked: indices.len(),
        mismatched: mismatches.into_iter().flatten().collect(),
    })
}

/// `verify` measures whole profiles: one per 500 requested points, at least 8
/// and at most 400.
pub fn profiles_for(points: usize) -> usize {
    (points / 500).clamp(8, 400)
}

/// Random parameter points, uniform in each axis's mapped coordinate (so
/// every cell is equally likely), rounded to f32 as the runtime takes them.
pub fn verification_points(count: usize, seed: u64) -> Vec<[f64; 4]> {
    let mut rng = SplitMix64::new(seed ^ 0x7433);
    (0..count)
        .map(|_| {
            let u = (rng.uniform_in(0.1f64.ln(), 3000.1f64.ln()).exp() - 0.1).max(0.0);
            let c = 1.0 + rng.log_uniform_in(0.01, 9.0);
            let beta = rng.log_uniform_in(0.002, 1.0);
            let p = rng
                .uniform_in(5.0f64.powf(-0.5), 0.2f64.powf(-0.5))
                .powi(-2);
            let r = |x: f64, lo: f64, hi: f64| f64::from(x as f32).clamp(lo, hi);
            [
                r(u, 0.0, 3000.0),
                r(c, 1.01, 10.0),
                r(beta, 0.002, 1.0),
                r(p, 0.2, 5.0),
            ]
        })
        .collect()
}

/// Random angles per profile for the pointwise errors of [`verify_point`].
pub const POINTWISE_ANGLES: usize = 16;

/// Per-profile results of [`verify_point`].
#[derive(Clone, Debug)]
pub struct ProfileErrors {
    /// `e_L2` of T3b against exact C.
    pub accurate_e_l2: f64,
    /// Relative energy error of T3b, `|∫(C̃ − C) sin cos| / ∫ C sin cos`.
    pub accurate_energy: f64,
    /// Relative errors of T3b where `C > 1e-3 · C(0)`, at
    /// [`POINTWISE_ANGLES`] angles uniform in `[0, π/2]` (exact C by the
    /// direct quadrature at each).
    pub accurate_pointwise: Vec<f64>,
    /// `e_L2` of T3a (interpolated `s, g`) against exact C.
    pub fit_e_l2: f64,
    /// `e_L2` of the T3a form fitted at this point itself against exact C.
    pub fit_at_point_e_l2: f64,
    /// `e_L2` between the interpolated T3a form and the form fitted at this
    /// point (docs/model.md §3: "s, g interpolation").
    pub fit_interpolation_e_l2: f64,
}

/// Measures both forms of `table` at one parameter point against the exact
/// profile on the rule of the e_L2 metric (docs/model.md §2.5) ([`ProfileRule::with_order`], 8 nodes per
/// interval).
pub fn verify_point(table: &ConvTable<'_>, point: [f64; 4]) -> Result<ProfileErrors, BuildError> {
    let [u, c, beta, p] = point;
    let at = || format!("T3 verify u = {u}, c = {c}, β = {beta}, p = {p}");
    let params = Params::new(u, c, beta, p).map_err(|e| conv_error(at(), e))?;
    let rule = ProfileRule::with_order(ProfileRule::width_for(&params), 8);
    let exact = convolution_profile(u, c, beta, p, &rule.nodes).map_err(|e| conv_error(at(), e))?;
    let c0 = convolution_profile(u, c, beta, p, &[0.0]).map_err(|e| conv_error(at(), e))?[0];
    let (uf, cf, bf, pf) = (u as f32, c as f32, beta as f32, p as f32);
    let accurate: Vec<f64> = rule
        .nodes
        .iter()
        .map(|&t| f64::from(table.at_tan(t.tan(), uf, cf, bf, pf)))
        .collect();
    let fit = table.fit();
    let fitted: Vec<f64> = rule
        .nodes
        .iter()
        .map(|&t| {
            f64::from(fit.convolution_sin_cos(t.sin() as f32, t.cos() as f32, uf, cf, bf, pf))
        })
        .collect();
    // The form fitted at this very point, as the generator fits nodes.
    let (thetas, weights) = angle_rule(u, beta, p);
    let values = convolution_profile(u, c, beta, p, &thetas).map_err(|e| conv_error(at(), e))?;
    let (s, g) = fit_paper_form(c, &thetas, &weights, &values);
    let at_point: Vec<f64> = rule
        .nodes
        .iter()
        .map(|&t| s * f64::from(kernel((2.0 * g * t.sin()) as f32, cf)))
        .collect();
    let e_l2 = |approx: &[f64], exact: &[f64]| {
        let (mut num, mut den) = (0.0, 0.0);
        for ((a, e), w) in approx.iter().zip(exact).zip(&rule.weights) {
            num += w * (a - e) * (a - e);
            den += w * e * e;
        }
        (num / den).sqrt()
    };
    let (mut energy_diff, mut energy) = (0.0, 0.0);
    for (((&t, &w), &e), &a) in rule
        .nodes
        .iter()
        .zip(&rule.weights)
        .zip(&exact)
        .zip(&accurate)
    {
        energy_diff += w * t.cos() * (a - e);
        energy += w * t.cos() * e;
    }
    // Pointwise: angles uniform in [0, π/2] (the rule's nodes crowd the
    // horizon and would over-weight it), seeded by the point.
    let mut rng = SplitMix64::new(u.to_bits() ^ c.to_bits().rotate_left(17) ^ beta.to_bits());
    let mut pointwise = Vec::new();
    for _ in 0..POINTWISE_ANGLES {
        let t = rng.uniform_in(0.0, std::f64::consts::FRAC_PI_2);
        let e = crate::reference::conv::convolution(t, u, c, beta, p)
            .map_err(|e| conv_error(at(), e))?;
        if e > 1e-3 * c0 {
            let (sin, cos) = (t.sin() as f32, t.cos() as f32);
            let a = f64::from(table.convolution_sin_cos(sin, cos, uf, cf, bf, pf));
            pointwise.push(((a - e) / e).abs());
        }
    }
    Ok(ProfileErrors {
        accurate_e_l2: e_l2(&accurate, &exact),
        accurate_energy: (energy_diff / energy).abs(),
        accurate_pointwise: pointwise,
        fit_e_l2: e_l2(&fitted, &exact),
        fit_at_point_e_l2: e_l2(&at_point, &exact),
        fit_interpolation_e_l2: e_l2(&fitted, &at_point),
    })
}

/// The verification of T3 at `profiles` random parameter points.
pub fn verify(bytes: &[u8], profiles: usize, seed: u64) -> Result<Vec<Accuracy>, BuildError> {
    let table = ConvTable::from_bytes(bytes)?;
    let points = verification_points(profiles, seed);
    let results = points
        .par_iter()
        .map(|&pt| verify_point(&table, pt).map(|r| (pt, r)))
        .collect::<Result<Vec<_>, BuildError>>()?;
    let describe = |pt: &[f64; 4]| {
        format!(
            "u = {:.4}, c = {:.4}, β = {:.4}, p = {:.3}",
            pt[0], pt[1], pt[2], pt[3]
        )
    };
    let per_profile = |f: &dyn Fn(&ProfileErrors) -> f64| -> Vec<(f64, String)> {
        results.iter().map(|(pt, r)| (f(r), describe(pt))).collect()
    };
    let mut pointwise = Vec::new();
    for (pt, r) in &results {
        for &e in &r.accurate_pointwise {
            pointwise.push((e, describe(pt)));
        }
    }
    Ok(vec![
        // The acceptance figures for T3b: pointwise where C > 1e-3 C(0).
        Accuracy::from_errors("T3b rel err (C>1e-3C0) p50", 0.01, pointwise.clone()).gated_at(0.5),
        Accuracy::from_errors("T3b rel err (C>1e-3C0) p95", 0.05, pointwise).gated_at(0.95),
        // docs/model.md §3's targets, reported (not met everywhere; see the README).
        Accuracy::from_errors(
            "T3b e_L2 vs exact C",
            0.01,
            per_profile(&|r| r.accurate_e_l2),
        )
        .report_only(),
        Accuracy::from_errors(
            "T3b energy error",
            0.01,
            per_profile(&|r| r.accurate_energy),
        )
        .report_only(),
        Accuracy::from_errors(
            "T3a e_L2 interp vs fit",
            0.01,
            per_profile(&|r| r.fit_interpolation_e_l2),
        )
        .report_only(),
        Accuracy::from_errors(
            "T3a e_L2 vs exact C",
            f64::INFINITY,
            per_profile(&|r| r.fit_e_l2),
        )
        .report_only(),
        Accuracy::from_errors(
            "T3a fit-at-point e_L2 vs C",
            f64::INFINITY,
            per_profile(&|r| r.fit_at_point_e_l2),
        )
        .report_only(),
    ])
}

#[cfg(test)]
mod tests {
    use super::*;
    use twoscale::tables::format::{ConvParams, HEADER_SIZE, Header};
    use zerocopy::TryFromBytes;

    /// What this generator's encoder writes for T3's nodes is the committed
    /// table byte for byte (header, kernel, quantised payload and checksum):
    /// encoded here from the committed file's own decoded node values, which
    /// re-quantise to the same codes, so a rebuild that computes the same
    /// nodes writes the same file. Its named parameters read back equal the
    /// ones written.
    #[test]
    fn header_matches_the_committed_table() {
        let path = concat!(env!("CARGO_MANIFEST_DIR"), "/../tables/t3-convolution.tbl");
        let committed = std::fs::read(path).expect("the committed T3");
        let aligned = twoscale::tables::format::aligned_copy(&committed);
        let table = Table::from_bytes(aligned.bytes()).expect("the committed T3 validates");
        let q = table.quantised().expect("T3 is quantised");
        let grid: Vec<f32> = (0..q.nodes())
            .flat_map(|n| (0..q.channels).map(move |ch| q.value(n, ch)))
            .collect();
        let written = encode_table(&grid).expect("encodes");
        assert!(
            written == committed,
            "the encoder does not write the committed T3"
        );
        let header = Header::try_read_from_bytes(&committed[..HEADER_SIZE]).expect("header");
        assert_eq!(
            ConvParams::from_header(&header),
            header_params(ANGLES, &ANGLE)
        );
        assert_eq!(ConvParams::from_header(&header).angle, ANGLE);
    }
}
