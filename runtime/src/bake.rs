//! Per-material bakes: what a [`crate::brdf::TwoScale`] precomputes once so
//! that a lookup in the inner loop costs a few multiply-adds.
//!
//! * [`DirectionBake`]: the quantities of one direction's `cos θ` at one
//!   wavelength — F(η, cos θ), the factors of Q̄ ([`QConstants::factors`]) and
//!   σrel/σs (T2), and the sampler's lobe weights — on 257 nodes even in `√cos θ` (dense at grazing, where σrel
//!   and F move fastest), linear between nodes.
//! * [`RadialNormBake`]: `1/M(sin θi)`, the normalisation of the diffraction
//!   sampler's radial law, on 513 nodes even in `sin θi`, linear between.
//! * [`MaskingBake`]: Smith G1 (T1 at the material's p) on 1025 nodes even in
//!   `y = a/(1 + a)`, `a = β tan θ`, linear between nodes; `y = 1` is the
//!   horizon (G1 = 0).
//! * [`ConvBake`]: `ln C(θh; u)` for the material's `(c, β, p)` on 33 × 130
//!   nodes, `u = B cos θd ∈ [0, B]` even in `log₂(1 + u/u₀) + a u` and θh
//!   even in `x = ln((1 + sin θh / w(u)) / cos θh)` per row (the logarithms are
//!   [`math::log2_axis`], a cheap C¹ stand-in), Catmull–Rom in both (edge cells
//!   extrapolate linearly: a ghost node on each side). `w(u)` is about a
//!   quarter of the lobe's core at `u` ([`ConvBake::inv_width`]): each row's
//!   core gets nodes, rows are blended at equal `x` (as T3 blends at equal
//!   ξ), and the power-law tail (linear in `ln sin θh`) is interpolated
//!   almost exactly; the `1/cos θh` term spends
//!   nodes on the horizon, where `C ∝ cos²θh` and `ln C` diverges. Beyond
//!   `cos θh = 10⁻³` the last node is used.
//!
//! The errors against the direct lookups are measured by the tests beside
//! each bake (`bake::tests`) and, for the whole BRDF, by `tests/bake.rs`.
//!
//! Each bake is plain numbers, valid when all zero ([`FromZeros`]), and is
//! filled in place by its `init`: a model's storage
//! ([`crate::brdf::ChannelBake`]) can be allocated zeroed on the heap, or
//! provided by the caller, and baked without a stack copy of its arrays.

use crate::conv::{ConvSlice, catmull_rom_weights};
use crate::fresnel::{Complex, QConstants, QFactors, fresnel};
use crate::kcorr::SigmaRatioTable;
use crate::math;
use crate::smith::SmithShape;
use zerocopy::FromZeros;

/// Nodes of [`DirectionBake`].
pub(crate) const MU_NODES: usize = 257;
/// Nodes of [`MaskingBake`].
const MASKING_NODES: usize = 1025;
/// `u` nodes of [`ConvBake`].
pub const CONV_U_NODES: usize = 33;
/// `sin θh` nodes of [`ConvBake`].
pub const CONV_S_NODES: usize = 130;
/// [`CONV_U_NODES`] and [`CONV_S_NODES`] with a ghost node at each end.
const PADDED_U: usize = CONV_U_NODES + 2;
const PADDED_S: usize = CONV_S_NODES + 2;
/// `u₀` of the `u` mapping (as T3's `ln(u + 0.1)`).
const U0: f32 = 0.1;
/// `u₁` of the `u` mapping's linear part.
const U1: f32 = 1.0;
/// The linear part spans at most this many times the logarithmic part.
const LINEAR_SHARE: f32 = 2.0;

/// The `u` axis of [`ConvBake`]: `log₂(1 + u/u₀) + a u` (with
/// [`math::log2_axis`]), `a = min(1/u₁, 2 log₂(1 + B/u₀)/B)`: logarithmic at
/// small `u`, where T3's own nodes are dense, linear at large `u`, where the
/// profile keeps narrowing; for large `B` the linear part is capped at twice
/// the logarithmic one so that small `u` keeps its rows.
#[inline]
fn u_axis(u: f32, linear: f32) -> f32 {
    math::log2_axis(1.0 + u / U0) + u * linear
}
/// Smallest `cos θh` of [`ConvBake`]'s angle axis.
const COS_H_MIN: f64 = 1e-3;
/// Floor of the stored `ln C` relative to its maximum (C below
/// `e^−70 C_max` ≈ 4e-31 C_max is stored as that).
const LN_C_RANGE: f32 = 70.0;

/// Linear-interpolation position on `n` nodes (`n ≤ 2²²`) of `x ∈ [0, 1]`
/// (clamped; NaN gives 0): the cell and the fraction in it.
#[inline]
fn cell(x: f32, n: usize) -> (usize, f32) {
    cell_at((x * (n - 1) as f32).max(0.0), n)
}

/// [`cell`] of a position `t` in nodes (`t ≥ 0`, clamped to `n − 1`).
#[inline]
fn cell_at(t: f32, n: usize) -> (usize, f32) {
    let t = t.min((n - 1) as f32);
    // ⌊t⌋ without a saturating float-to-integer conversion: `t − ½ + 1.5·2²³`
    // rounds to an integer (f32's spacing there is 1), which the low bits
    // hold; a tie rounds to even, which may give the node below `t` with
    // fraction 1 — the same interpolated value.
    let rounded = (t - 0.5) + ROUNDER;
    let i = (rounded.to_bits().wrapping_sub(ROUNDER.to_bits()) as i32)
        .max(0)
        .min(n as i32 - 2);
    (i as usize, t - i as f32)
}

/// `1.5·2²³`: adding it to `x ∈ (−2²², 2²²)` rounds `x` to an integer.
const ROUNDER: f32 = 12_582_912.0;

/// Receives a model's bakes and constants by name, for ports of `eval` and
/// `pdf` to array languages (the Python package's Dr.Jit plugin reads them
/// through `Material.bakes()`): arrays are row-major f32 with their shape,
/// scalars f64. The names and layouts are the bakes' own and may change
/// with them; not a stable interface.
#[doc(hidden)]
pub trait BakeVisitor {
    /// An array of `shape` (row-major).
    fn array(&mut self, name: &'static str, shape: &[usize], data: &[f32]);
    /// An f64 array of `shape` (row-major).
    fn array_f64(&mut self, name: &'static str, shape: &[usize], data: &[f64]);
    /// A scalar.
    fn scalar(&mut self, name: &'static str, value: f64);
}

/// One direction's quantities at one wavelength (module documentation).
#[derive(Clone, Debug, FromZeros)]
pub(crate) struct DirectionBake {
    /// `[a, Re U, Im U, Re W, Im W, σrel/σs, F, 1 − E_s]` per node: what `eval`
    /// reads, in one row (`1 − E_s(μ)`, the white albedo the compensation lobe puts back, 0
    /// when it is off).
    rows: [[f32; ROW]; MU_NODES],
    /// `[w_spec, w_diff, w_base, w_ms]` per node: what the sampler and `pdf` read.
    weights: [[f32; 4]; MU_NODES],
}

/// Values per [`DirectionBake`] row.
const ROW: usize = 8;

/// A `cos θ`'s place on [`DirectionBake`]'s axis (the same for every
/// wavelength, so [`crate::brdf::Rgb`] finds it once for its three channels).
#[derive(Clone, Copy, Debug)]
pub(crate) struct DirectionCell {
    index: usize,
    fraction: f32,
}

impl DirectionCell {
    /// The cell of `cos θ` (clamped to [0, 1]).
    #[inline]
    pub fn new(cos: f32) -> Self {
        let (index, fraction) = cell(math::sqrtf(cos.max(0.0)), MU_NODES);
        DirectionCell { index, fraction }
    }

    /// The cell and fraction of the same `cos θ` on an axis of `N` nodes of
    /// `√cos θ` (`MU_NODES − 1` a multiple of `N − 1`).
    #[inline]
    pub fn coarser<const N: usize>(self) -> (usize, f32) {
        let step = ((MU_NODES - 1) / (N - 1)) as f32;
        cell_at((self.index as f32 + self.fraction) * (1.0 / step), N)
    }
}

/// Interpolated [`DirectionBake`] row at one `cos θ`.
#[derive(Clone, Copy, Debug)]
pub(crate) struct DirectionValues {
    /// `[a, Re U, Im U, Re W, Im W, σrel/σs, F, 1 − E_s]`.
    pub v: [f32; ROW],
}

impl DirectionValues {
    /// F(η, cos θ).
    #[inline]
    pub fn fresnel(&self) -> f64 {
        f64::from(self.v[6])
    }

    /// The factors of Q̄.
    #[inline]
    pub fn q_factors(&self) -> QFactors {
        let v = &self.v;
        [v[0], v[1], v[2], v[3], v[4]].map(f64::from)
    }

    /// σrel/σs.
    #[inline]
    pub fn sigma_ratio(&self) -> f64 {
        f64::from(self.v[5])
    }

    /// `1 − E_s(μ)`, the light single scattering loses (0 unless the
    /// compensation lobe is on).
    #[inline]
    pub fn lost(&self) -> f64 {
        f64::from(self.v[7])
    }
}

/// The lobe weights of [`DirectionBake`] at its nodes, as computed by
/// [`DirectionBake::lobe_weight_nodes`] (4 KB).
pub(crate) struct LobeWeightNodes([[f32; 4]; MU_NODES]);

impl DirectionBake {
    /// Tabulates in place F and Q̄'s factors of `eta` (when `q` is given) and
    /// σrel/σs of the spectrum `(B, c)` from T2; the lobe weights are
    /// cleared (set them with [`DirectionBake::set_lobe_weights`]), and so is
    /// `1 − E_s` (set it with [`DirectionBake::set_albedo`]).
    pub fn init(
        &mut self,
        eta: Complex,
        q: Option<&QConstants>,
        sigma_ratio: &SigmaRatioTable<'_>,
        big_b: f32,
        c: f32,
    ) {
        let mut cosines = [0.0f32; MU_NODES];
        for (k, (row, cos_f32)) in self.rows.iter_mut().zip(cosines.iter_mut()).enumerate() {
            let x = k as f64 / (MU_NODES - 1) as f64;
            let cos = x * x;
            *cos_f32 = cos as f32;
            let factors = q.map(|q| q.factors(cos)).unwrap_or([0.0; 5]);
            for (slot, value) in row[..5].iter_mut().zip(factors) {
                *slot = value as f32;
            }
            row[6] = fresnel(eta, cos as f32);
            row[7] = 0.0;
        }
        let mut ratios = [0.0f32; MU_NODES];
        sigma_ratio.sigma_ratio_cos_many(&cosines, big_b, c, &mut ratios);
        for (row, ratio) in self.rows.iter_mut().zip(ratios) {
            row[5] = ratio;
        }
        self.weights = [[0.0f32; 4]; MU_NODES];
    }

    /// The bake of [`DirectionBake::init`] in new storage.
    #[cfg(test)]
    pub fn new(
        eta: Complex,
        q: Option<&QConstants>,
        sigma_ratio: &SigmaRatioTable<'_>,
        big_b: f32,
        c: f32,
    ) -> Self {
        let mut bake = Self::new_zeroed();
        bake.init(eta, q, sigma_ratio, big_b, c);
        bake
    }

    /// Stores `1 − E_s(μ)` at the nodes from `albedo(μ)` (clamped to
    /// [0, 1]) and returns `E_avg = 2 ∫₀¹ E μ dμ` of the stored values as
    /// `eval` interpolates them (linear in `√μ`,
    /// [`crate::albedo::cosine_weighted_mean`]), so that the compensation lobe
    /// `∝ (1 − E_s(μi)) (1 − E_s(μo)) / (1 − E_avg)` integrates exactly.
    pub fn set_albedo(&mut self, albedo: impl Fn(f64) -> f32) -> f64 {
        for (k, row) in self.rows.iter_mut().enumerate() {
            let x = k as f64 / (MU_NODES - 1) as f64;
            row[7] = 1.0 - albedo(x * x).max(0.0).min(1.0);
        }
        1.0 - crate::albedo::cosine_weighted_mean(MU_NODES, |k| self.rows[k][7])
    }

    /// The lobe weights `weights(values at cos θ, cos θ)` at the nodes, for
    /// [`DirectionBake::set_lobe_weights`].
    pub fn lobe_weight_nodes(
        &self,
        weights: impl Fn(&DirectionValues, f64) -> [f64; 4],
    ) -> LobeWeightNodes {
        let mut nodes = [[0.0f32; 4]; MU_NODES];
        for (k, node) in nodes.iter_mut().enumerate() {
            let x = k as f64 / (MU_NODES - 1) as f64;
            let cos = x * x;
            let w = weights(&self.at(cos as f32), cos);
            for (slot, value) in node.iter_mut().zip(w) {
                *slot = value as f32;
            }
        }
        LobeWeightNodes(nodes)
    }

    /// Stores the lobe weights tabulated by [`DirectionBake::lobe_weight_nodes`].
    pub fn set_lobe_weights(&mut self, nodes: &LobeWeightNodes) {
        self.weights = nodes.0;
    }

    /// F alone at a cell.
    #[inline]
    pub fn fresnel_at(&self, at: DirectionCell) -> f32 {
        let (a, b) = (self.rows[at.index][6], self.rows[at.index + 1][6]);
        a + at.fraction * (b - a)
    }

    /// The values at `cos θ` (clamped to [0, 1]).
    #[inline]
    pub fn at(&self, cos: f32) -> DirectionValues {
        self.at_cell(DirectionCell::new(cos))
    }

    /// The values at a cell.
    #[inline]
    pub fn at_cell(&self, at: DirectionCell) -> DirectionValues {
        let (a, b) = (&self.rows[at.index], &self.rows[at.index + 1]);
        let mut v = [0.0f32; ROW];
        for k in 0..ROW {
            v[k] = a[k] + at.fraction * (b[k] - a[k]);
        }
        DirectionValues { v }
    }

    /// Hands the node rows and lobe weights to `v` (`direction_rows`
    /// `[257, 8]`, `direction_weights` `[257, 4]`; nodes even in `√cos θ`).
    pub fn visit(&self, v: &mut dyn BakeVisitor) {
        v.array("direction_rows", &[MU_NODES, ROW], self.rows.as_flattened());
        v.array(
            "direction_weights",
            &[MU_NODES, 4],
            self.weights.as_flattened(),
        );
    }

    /// The sampler's lobe weights `[specular, diffraction, base, multiple]`
    /// (sum 1) at `cos θ` (clamped to [0, 1]).
    #[inline]
    pub fn lobe_weights(&self, cos: f32) -> [f64; 4] {
        let at = DirectionCell::new(cos);
        let (a, b) = (&self.weights[at.index], &self.weights[at.index + 1]);
        let w = [0, 1, 2, 3].map(|k| f64::from(a[k] + at.fraction * (b[k] - a[k])).max(0.0));
        let total = w[0] + w[1] + w[2] + w[3];
        if total > 0.0 {
            w.map(|x| x / total)
        } else {
            [1.0, 0.0, 0.0, 0.0]
        }
    }
}

/// `1/M(sin θi)` of the diffraction sampler's radial law at one wavelength,
/// `M = 1 − (1 + B²(1 + sin θi)²)^(−(c−1)/2)` (HP17 52), on [`RADIAL_NODES`]
/// nodes even in `sin θi` (where `M` is analytic), linear between; 0 where
/// `M` is not positive (no mass to sample). `sample` and `pdf` read the same
/// values.
#[derive(Clone, Debug, FromZeros)]
pub(crate) struct RadialNormBake {
    inv_m: [f32; RADIAL_NODES],
}

/// Nodes of [`RadialNormBake`].
const RADIAL_NODES: usize = 513;

impl RadialNormBake {
    /// Tabulates `1/M` for `B = b/λ` and the spectrum's `c` in place.
    pub fn init(&mut self, big_b: f64, c: f64) {
        for (k, slot) in self.inv_m.iter_mut().enumerate() {
            let sin_i = k as f64 / (RADIAL_NODES - 1) as f64;
            let reach = big_b * (1.0 + sin_i);
            // −expm1(−(c−1)/2 · ln(1 + reach²)): no cancellation for small reach.
            let m = -math::exp_m1(-0.5 * (c - 1.0) * math::ln_1p(reach * reach));
            let value = (1.0 / m) as f32;
            *slot = if m > 0.0 && value.is_finite() {
                value
            } else {
                0.0
            };
        }
    }

    /// The bake of [`RadialNormBake::init`] in new storage.
    #[cfg(test)]
    pub fn new(big_b: f64, c: f64) -> Self {
        let mut bake = Self::new_zeroed();
        bake.init(big_b, c);
        bake
    }

    /// The bake of a spectrum without diffraction (σs = 0 or B = 0): `1/M`
    /// is 0 everywhere, nothing is sampled from it, and nothing is computed.
    pub fn clear(&mut self) {
        self.inv_m = [0.0f32; RADIAL_NODES];
    }

    /// Hands `1/M` to `v` (`radial_inv_m`, nodes even in `sin θi`).
    pub fn visit(&self, v: &mut dyn BakeVisitor) {
        v.array("radial_inv_m", &[RADIAL_NODES], &self.inv_m);
    }

    /// `1/M` at `sin θi` (clamped to [0, 1]).
    #[inline]
    pub fn inv_m(&self, sin_i: f64) -> f64 {
        let (i, t) = cell(sin_i as f32, RADIAL_NODES);
        let (a, b) = (self.inv_m[i], self.inv_m[i + 1]);
        f64::from(a + t * (b - a))
    }
}

/// Smith G1 at the material's (β, p) (module documentation).
#[derive(Clone, Debug, FromZeros)]
pub(crate) struct MaskingBake {
    beta: f32,
    g1: [f32; MASKING_NODES],
}

impl MaskingBake {
    /// Tabulates `shape` (T1 at p) for slopes `a = β tan θ` in place.
    pub fn init(&mut self, beta: f32, shape: &SmithShape<'_>) {
        self.beta = beta;
        for (k, value) in self.g1.iter_mut().enumerate() {
            let y = k as f64 / (MASKING_NODES - 1) as f64;
            *value = if k + 1 == MASKING_NODES {
                0.0
            } else {
                shape.g1((y / (1.0 - y)) as f32)
            };
        }
    }

    /// The bake of [`MaskingBake::init`] in new storage.
    #[cfg(test)]
    pub fn new(beta: f32, shape: &SmithShape<'_>) -> Self {
        let mut bake = Self::new_zeroed();
        bake.init(beta, shape);
        bake
    }

    /// Hands β and G1 to `v` (`masking_beta`; `masking_g1`, nodes even in
    /// `y = a/(1 + a)`).
    pub fn visit(&self, v: &mut dyn BakeVisitor) {
        v.scalar("masking_beta", f64::from(self.beta));
        v.array("masking_g1", &[MASKING_NODES], &self.g1);
    }

    /// G1 of a direction with `z = cos θ` and tangential length `r = sin θ`
    /// (both ≥ 0; 0 at or below the horizon).
    #[inline]
    pub fn g1(&self, r: f32, z: f32) -> f32 {
        if !(z > 0.0) {
            return 0.0;
        }
        // y = a/(1 + a) with a = β r / z, without forming a (z may be tiny).
        let a_num = self.beta * r;
        let y = a_num / (a_num + z);
        let (i, t) = cell(y, MASKING_NODES);
        self.g1[i] + t * (self.g1[i + 1] - self.g1[i])
    }
}

/// `ln C` for one material and wavelength over `(u, sin θh)` (module
/// documentation).
#[derive(Clone, Debug, FromZeros)]
pub(crate) struct ConvBake {
    /// `B`, the largest `u`.
    big_b: f32,
    /// `(CONV_U_NODES − 1) / u_axis(B)`.
    u_scale: f32,
    /// The slope of `u_axis`'s linear part.
    u_linear: f32,
    /// A quarter of the NDF's core width (the floor of [`ConvBake::inv_width`]'s `w`).
    ndf_quarter_width: f32,
    /// `ln C` row-major `[u][θh]` with one ghost node on each side of both
    /// axes (linear extrapolation), so that every cell has four taps.
    ln_c: [f32; PADDED_U * PADDED_S],
    /// `1/w(u)` of each row (its θh nodes are [`row_tans`] of it).
    pub(crate) row_inv_w: [f32; CONV_U_NODES],
    /// The `u` of each row.
    pub(crate) row_u: [f32; CONV_U_NODES],
}

/// The `tan θh` nodes of a row with `1/w = inv_w`: `x = (1 + sin θ / w)/cos θ`
/// even in [`math::log2_axis`] from 1 to [`angle_span`], inverted as
/// `tan θ = tan(A − B)` with `tan A = w x`, `tan B = w/√(1 + w²(x² − 1))`;
/// in f32, as the slice's angle is evaluated (module documentation).
pub(crate) fn row_tans(inv_w: f32) -> [f32; CONV_S_NODES] {
    let w = 1.0 / f64::from(inv_w);
    let s_span = f64::from(angle_span(inv_w));
    let mut tans = [0.0f32; CONV_S_NODES];
    for (k, tan) in tans.iter_mut().enumerate() {
        let x = math::exp2_axis(k as f64 / (CONV_S_NODES - 1) as f64 * s_span).max(1.0);
        let tan_a = w * x;
        let tan_b = w / math::sqrt(1.0 + w * w * (x * x - 1.0));
        *tan = ((tan_a - tan_b) / (1.0 + tan_a * tan_b)) as f32;
    }
    tans
}

impl ConvBake {
    /// Tabulates `slice` in place for `u ∈ [0, B]` (its normalised angle
    /// evaluated in f32 at the nodes); `beta`, `p` give the NDF's core width.
    /// `false` (and `self` left as it was) when `B` is not positive and finite.
    pub fn init(&mut self, slice: &ConvSlice<'_>, big_b: f32, beta: f32, p: f32) -> bool {
        if !(big_b > 0.0 && big_b.is_finite()) {
            return false;
        }
        let linear = (1.0 / U1).min(LINEAR_SHARE * math::log2_axis(1.0 + big_b / U0) / big_b);
        let u_span = u_axis(big_b, linear);
        // The NDF's core: where D has fallen by 10% (tan θ = β 0.1^(1/2p)).
        let ndf_width = beta * math::powff(0.1, 0.5 / p);
        let bake = self;
        bake.big_b = big_b;
        bake.u_scale = (CONV_U_NODES - 1) as f32 / u_span;
        bake.u_linear = linear;
        bake.ndf_quarter_width = 0.25 * ndf_width;
        let mut top = f32::MIN;
        for j in 0..CONV_U_NODES {
            let x_u = j as f64 / (CONV_U_NODES - 1) as f64 * f64::from(u_span);
            // u_axis⁻¹(x_u) by bisection on [0, B] (u_axis increases).
            let (mut lo, mut hi) = (0.0f32, big_b);
            for _ in 0..48 {
                let mid = 0.5 * (lo + hi);
                if f64::from(u_axis(mid, linear)) < x_u {
                    lo = mid;
                } else {
                    hi = mid;
                }
            }
            let u = 0.5 * (lo + hi);
            let u = if j + 1 == CONV_U_NODES { big_b } else { u };
            let inv_w = bake.inv_width(u);
            bake.row_inv_w[j] = inv_w;
            bake.row_u[j] = u;
            let tans = row_tans(inv_w);
            let row = &mut bake.ln_c[(j + 1) * PADDED_S + 1..(j + 1) * PADDED_S + 1 + CONV_S_NODES];
            // ln C = ln s + the profile (s = 1 inside T3's u range).
            match slice.ln_profile_at_tans(u, &tans, row) {
                Some(factor) if factor > 0.0 => {
                    let ln_factor = math::lnf(factor);
                    for v in row.iter_mut() {
                        *v += ln_factor;
                        top = top.max(*v);
                    }
                }
                _ => row.iter_mut().for_each(|v| *v = f32::MIN),
            }
        }
        let ln_c = &mut bake.ln_c;
        let floor = if top > f32::MIN {
            top - LN_C_RANGE
        } else {
            0.0
        };
        for v in ln_c.iter_mut() {
            *v = v.max(floor);
        }
        // Ghost nodes: along θh in the real rows, then along u in every column.
        for j in 1..=CONV_U_NODES {
            let row = &mut ln_c[j * PADDED_S..(j + 1) * PADDED_S];
            row[0] = 2.0 * row[1] - row[2];
            row[PADDED_S - 1] = 2.0 * row[PADDED_S - 2] - row[PADDED_S - 3];
        }
        for k in 0..PADDED_S {
            let at = |j: usize| j * PADDED_S + k;
            ln_c[at(0)] = 2.0 * ln_c[at(1)] - ln_c[at(2)];
            ln_c[at(PADDED_U - 1)] = 2.0 * ln_c[at(PADDED_U - 2)] - ln_c[at(PADDED_U - 3)];
        }
        true
    }

    /// The bake of [`ConvBake::init`] in new storage (`None` when `init` is `false`).
    #[cfg(test)]
    pub fn new(slice: &ConvSlice<'_>, big_b: f32, beta: f32, p: f32) -> Option<Self> {
        let mut bake = Self::new_zeroed();
        bake.init(slice, big_b, beta, p).then_some(bake)
    }

    /// `1/w(u)`: `w` is about a quarter of the lobe's core width at `u`, the
    /// kernel's `1/(2u)` or the NDF's, whichever is wider, and at most ¼:
    /// `1/w² = 16 + 1/(k² + n²)` with `k = ⅛/(u + ½)`, `n` the NDF's quarter
    /// width. Smooth in `u`, so that rows at equal `x` interpolate well.
    #[inline]
    fn inv_width(&self, u: f32) -> f32 {
        // 1/(k² + n²) = v²/(1/64 + n² v²) with v = u + ½: one division.
        let v = u + 0.5;
        let nv = self.ndf_quarter_width * v;
        math::sqrtf(16.0 + v * v / (1.0 / 64.0 + nv * nv))
    }

    /// Hands the axes' constants and the padded `ln C` grid to `v`
    /// (`conv_ln_c` `[35, 132]`, ghost nodes included; `conv_*` scalars,
    /// and the axes' constants `conv_u0`, `conv_cos_h_min`).
    pub fn visit(&self, v: &mut dyn BakeVisitor) {
        v.scalar("conv_big_b", f64::from(self.big_b));
        v.scalar("conv_u_scale", f64::from(self.u_scale));
        v.scalar("conv_u_linear", f64::from(self.u_linear));
        v.scalar("conv_ndf_quarter_width", f64::from(self.ndf_quarter_width));
        v.scalar("conv_u0", f64::from(U0));
        v.scalar("conv_cos_h_min", COS_H_MIN);
        v.array("conv_ln_c", &[PADDED_U, PADDED_S], &self.ln_c);
    }

    /// `C` at `sin θh`, `cos θh` (in [0, 1]) and `u ∈ [0, B]` (clamped).
    #[inline]
    pub fn at(&self, sin_h: f32, cos_h: f32, u: f32) -> f32 {
        c_of_ln(self.ln_at(sin_h, cos_h, u))
    }

    /// `ln C` of [`ConvBake::at`] (finite: the bake's floor bounds it below).
    #[inline]
    pub fn ln_at(&self, sin_h: f32, cos_h: f32, u: f32) -> f32 {
        let u = u.max(0.0).min(self.big_b);
        // 1/cos θh and tan θh do not wait for `w(u)`: only a multiply-add does.
        let sec_h = 1.0 / cos_h.max(COS_H_MIN as f32);
        let tan_h = sin_h.max(0.0).min(1.0) * sec_h;
        let x_u = u_axis(u, self.u_linear) * self.u_scale;
        let inv_w = self.inv_width(u);
        let x_h = sec_h + tan_h * inv_w;
        let x_s = math::log2_axis(x_h) * ((CONV_S_NODES - 1) as f32 / angle_span(inv_w));
        let (ju, wu) = catmull_rom(x_u, CONV_U_NODES);
        let (ks, ws) = catmull_rom(x_s, CONV_S_NODES);
        // ju ≤ CONV_U_NODES − 2 and ks ≤ CONV_S_NODES − 2: the 4 × 4 taps
        // lie in the padded grid.
        let mut ln_c = 0.0f32;
        for (a, wa) in wu.iter().enumerate() {
            let row = &self.ln_c[(ju + a) * PADDED_S..][..PADDED_S];
            let taps = &row[ks..ks + 4];
            ln_c += wa * (taps[0] * ws[0] + taps[1] * ws[1] + taps[2] * ws[2] + taps[3] * ws[3]);
        }
        ln_c
    }
}

/// `C = e^ln C` of [`ConvBake::ln_at`], 0 where it is not finite.
#[inline]
pub(crate) fn c_of_ln(ln_c: f32) -> f32 {
    // e^x is 0 in f32 below x ≈ −103.3.
    if !(ln_c > -104.0) {
        return 0.0;
    }
    let value = math::expf(ln_c);
    if value.is_finite() { value } else { 0.0 }
}

/// The θh axis's value at `cos θh = 10⁻³` (its last node) for `1/w`.
#[inline]
fn angle_span(inv_w: f32) -> f32 {
    math::log2_axis((1.0 + inv_w) * (1.0 / COS_H_MIN) as f32)
}

/// The first of the four padded node indices (the cell's index, as the
/// padding shifts nodes by one) and the Catmull–Rom weights at position `x`
/// (in nodes, clamped to `[0, n − 1]`).
#[inline]
fn catmull_rom(x: f32, n: usize) -> (usize, [f32; 4]) {
    let (i, t) = cell_at(x.max(0.0), n);
    (i, catmull_rom_weights(t))
}

#[cfg(all(test, feature = "embedded"))]
mod tests {
    use super::*;
    use crate::TableSet;

    use crate::test_rng::Lcg;

    /// The C bake against the slice it samples, at 2000 random (θh, u).
    #[test]
    fn conv_bake_reproduces_the_slice() {
        let set = TableSet::embedded();
        let mut rng = Lcg(7);
        for &(c, beta, p, big_b) in &[(2.0f32, 0.0598f32, 1.0f32, 9.2f32), (2.5, 0.35, 1.5, 12.0)] {
            let slice = set.convolution.slice(c, beta, p).unwrap();
            let bake = ConvBake::new(&slice, big_b, beta, p).unwrap();
            let mut worst = (0.0f64, 0.0, 0.0);
            for _ in 0..2000 {
                let theta = rng.next() * 1.5;
                let u = (rng.next() as f32) * big_b;
                let (s, co) = (math::sin(theta), math::cos(theta));
                let direct = slice.at_tan(s / co, u);
                let baked = bake.at(s as f32, co as f32, u);
                let e = (f64::from(baked) / f64::from(direct) - 1.0).abs();
                if e > worst.0 {
                    worst = (e, theta, f64::from(u));
                }
            }
            std::eprintln!("C bake: worst {worst:?}");
            // The grid's interpolation error of T3b's own profile (measured
            // 0.31% and 0.38%; docs/design/per-material-bake.md).
            assert!(
                worst.0 < 5e-3,
                "c {c}, β {beta}, p {p}, B {big_b}: baked C off by {:.2e} at θh {:.3}, u {:.2}",
                worst.0,
                worst.1,
                worst.2
            );
        }
    }

    /// The baked `1/M` against its closed form (HP17 52) over B ∈ [1e-3, 1e3],
    /// c ∈ [1, 10] and sin θi ∈ [0, 1).
    #[test]
    fn radial_norm_matches_the_closed_form() {
        let mut rng = Lcg(5);
        let mut worst = (0.0f64, 0.0, 0.0, 0.0);
        for _ in 0..400 {
            // B from 1e-3 to 1e3, c from 1 to 10.
            let big_b = 10f64.powf(6.0 * rng.next() - 3.0);
            let c = 1.0 + 9.0 * rng.next() + 1e-3;
            let bake = RadialNormBake::new(big_b, c);
            for _ in 0..200 {
                let sin_i = rng.next();
                let reach = big_b * (1.0 + sin_i);
                let m = -(-0.5 * (c - 1.0) * (reach * reach).ln_1p()).exp_m1();
                let e = (bake.inv_m(sin_i) * m - 1.0).abs();
                if e > worst.0 {
                    worst = (e, big_b, c, sin_i);
                }
            }
        }
        std::eprintln!(
            "1/M: worst {:.2e} at B {:.3e}, c {:.2}, sin θi {:.4}",
            worst.0,
            worst.1,
            worst.2,
            worst.3
        );
        assert!(worst.0 < 5e-6, "{worst:?}");
    }

    /// F, Q̄'s factors and σrel from the direction bake against the direct
    /// functions at 4000 random `cos θ`; G1 against T1.
    #[test]
    fn one_dimensional_bakes_match_the_direct_lookups() {
        let set = TableSet::embedded();
        let eta = Complex::new(0.2, 3.6);
        let q = QConstants::new(eta).unwrap();
        let bake = DirectionBake::new(eta, Some(&q), &set.sigma_ratio, 9.2, 2.0);
        let shape = set.smith.shape(1.3);
        let masking = MaskingBake::new(0.06, &shape);
        let mut rng = Lcg(3);
        let (mut f_err, mut q_err, mut s_err, mut g_err) = (0.0f64, 0.0f64, 0.0f64, 0.0f64);
        for _ in 0..4000 {
            let cos = rng.next() as f32;
            let v = bake.at(cos);
            let f = fresnel(eta, cos);
            f_err = f_err.max((v.fresnel() - f64::from(f)).abs());
            let exact = q.factors(f64::from(cos));
            let got = v.q_factors();
            for k in 0..5 {
                q_err = q_err.max((got[k] - exact[k]).abs() / (1.0 + exact[k].abs()));
            }
            let r = f64::from(set.sigma_ratio.sigma_ratio_cos(cos, 9.2, 2.0));
            s_err = s_err.max((v.sigma_ratio() / r - 1.0).abs());
            let sin = math::sqrtf((1.0 - cos * cos).max(0.0));
            let g1 = shape.g1(0.06 * sin / cos);
            g_err = g_err.max(f64::from((masking.g1(sin, cos) - g1).abs()));
        }
        std::eprintln!("F {f_err:.1e}, Q̄ factors {q_err:.1e}, σrel {s_err:.1e}, G1 {g_err:.1e}");
        // Bounds: T1's and T2's own targets (2e-5 absolute, 1e-4 relative),
        // and the same for F and Q̄'s factors (measured: 1.7e-6, 1.3e-5).
        assert!(f_err < 2e-5 && q_err < 1e-4 && s_err < 1e-4 && g_err < 2e-5);
    }
}
