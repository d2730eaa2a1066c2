//! The normalised spherical convolution `C(θh; u, c, β, p)` of the diffraction
//! lobe with the EPD NDF (docs/model.md §2.5, HP17 32–33, 39–41), and its table T3.
//!
//! ```text
//!   C(θh; u, c, β, p) = ∫_{h·m > 0} k(2u sin∠(h,m)) cos²∠(h,m) D(m) dω_m
//!   k(x) = (1 + x²)^(−(c+1)/2),     u = (b/λ) cos θd
//! ```
//!
//! The BRDF reads `C` through the [`Convolution`] trait, so that the two forms
//! stored in T3 are interchangeable:
//!
//! * [`ConvTable`] (**T3b**, the accurate form, the default): at every node of
//!   the `(u, c, β, p)` grid, `ln C` at 32 evenly spaced values of a
//!   normalised angle `ξ ∈ [0, 1]` ([`normalised_angle`]). A lookup blends
//!   the four `ln C` values around `ξ(θh)` over the parameter cell
//!   (Catmull–Rom in each parameter, quadratic in the first and last cell:
//!   up to 4⁴ corners; [`ConvTable::with_cubic_axes`] switches axes to
//!   linear), then interpolates them along `ξ` by a Catmull–Rom cubic, and
//!   exponentiates. [`ConvTable::slice`] does the parameter blend once per
//!   material `(c, β, p)` ([`ConvSlice`]: 16 taps per lookup instead of 1024).
//! * [`ConvFitTable`] (**T3a**, the paper's form, HP17 39–41):
//!   `C ≈ s · k(2 g sin θh)` with `ln s` and `ln(g² + g_offset)` blended by
//!   the same per-axis weights (Catmull–Rom by default; the issue asked for
//!   quadrilinear, which `with_cubic_axes([false; 4])` gives, but it misses
//!   the 1% interpolation target of docs/model.md §3 by a factor 2, Catmull–Rom meets it at
//!   the median).
//!
//! Both live in one file (table id [`TableId::Convolution`], channels
//! `[ln s, ln(g² + g_offset), ln C(ξ_0), …, ln C(ξ_31)]`) because the generator
//! computes both from the same exact profile at each node. The file is stored
//! quantised per node ([`ValueType::U16`]: an f32 offset and step and 34 u16
//! codes per node, error ≤ half a step, ≤ 3.4e-4 in `ln C`), which halves
//! its size and paid for 28 `u` nodes instead of 16; a blend reads the
//! codes in place (`Σ w·offset + Σ (w·step)·code`).
//!
//! # The normalised angle
//!
//! With `τ = tan θh`, `u_e = √(u² + u_floor²)`, `y = (τ/β)^(2p')`,
//! `p' = p / (1 + κ p / (2 u_e β))` and the NDF's edge `tan θe = β Y^(1/(2p'))`
//! (where `y = Y`),
//!
//! ```text
//!   F(τ) = asinh(2 u_e sin θh)                      kernel
//!        + w_h · ½ ln(1 + τ²)                        horizon
//!        + w_e · f_e · asinh(2 u_e sin x̃)            edge
//!        + λ · ln(1 + Y (1 − e^(−y/Y)))              NDF
//!   x̃ = min((x + √(x² + δ²)) / 2, π/2),  x = θh − θe,  δ = s_e / (2 u_e)
//!   f_e = (p'/p)^m / (1 + (tan θe / τ_f)²)
//!   ξ = F(τ) / F(τ_max)
//! ```
//!
//! Each term follows one way `ln C` changes with `θh`:
//!
//! * **kernel**: the kernel's own variable, `ln k = −(c+1)/2 · ln(1 + 4u² sin²θh)`
//!   is linear in it: linear in `θh` inside the kernel width `1/(2u)`,
//!   logarithmic beyond.
//! * **horizon**: `−ln cos θh`, for the `cos²` factor and small-`p` NDFs that
//!   peak towards the horizon. (Before format version 2 the kernel term was
//!   `asinh(2 u_e tan θh)`, which does both but spends about half of the ξ
//!   range beyond 70° for `u` = 15–35.)
//! * **edge**: just beyond the NDF's support, `C` falls like the kernel's
//!   tail measured from that edge, `ln C ≈ −(c+1) ln(2u sin(θh − θe))`. Its
//!   onset is smoothed over `s_e` kernel widths (a kink in `ξ(θh)` costs
//!   accuracy), and it fades out for edges near the horizon (`θe` within
//!   0.1° of it for small `p`, where `C` falls steeply for other reasons).
//! * **NDF**: the NDF's exponent (`ln D = const − y + 2 ln(1 + τ²)`), which
//!   puts nodes across the cliff of large-`p` lobes and saturates where `D`
//!   has fallen by `e^−Y`. Where the kernel is wider than the NDF
//!   (`1/(2u_e) ≳ β`), it smooths that cliff over `Δ ln τ ≈ 1/(2 u_e β)`, and
//!   `C` shows no cliff: the softened exponent `p'` spends the nodes on the
//!   profile's real width instead. (With `κ = 0`, 32 angles left `e_L2` of ξ
//!   interpolation alone at 5.1% for `p = 5`, `c ≈ 5`; `κ = 1` brings the
//!   worst of 60 such profiles to 1.0%: `studies t3-angle-softening`.) For `u_e β ≪ p`, `p'` tends to 0 and the NDF term
//!   keeps growing down to `τ ~ 1e-59`, so the first few angles of such
//!   nodes hold `C(0)` (where `C` is flat): wasted, not wrong.
//!
//! The shipped `w_h = ½`, `w_e = ½`, `s_e = 2`, `τ_f = 3` (and `m = 2`: t3-accuracy-candidates.md) were chosen with
//! `studies t3-angle-forms` (docs/design/t3-normalised-angle.md). Everything is known at lookup
//! time. `τ_max`, `u_floor`, `λ`, `Y`, `κ`, `w_h`, `w_e`, `s_e`, `τ_f` and `m` are
//! stored in the header (`params`), so the file is self-describing.
//!
//! # Out of the domain
//!
//! * `c`, `β`, `p` clamp to the table's domain (`c ∈ [1.01, 10]`,
//!   `β ∈ [0.002, 1]`, `p ∈ [0.2, 5]` in the shipped table).
//! * `u > u_max` (3000): the kernel is then far narrower than any other
//!   feature and `C` follows the narrow-kernel limit `C ≈ D(θh) ∫K dω`; the
//!   profile is taken at `u_max` and scaled by the ratio of the planar kernel
//!   integrals `I(u) = (1 − (1 + 4u²)^((1−c)/2)) / ((c − 1) u²)` (T3a: `s`
//!   scaled the same way, `g` held at its `u_max` value, as the paper
//!   describes `g` saturating for large `u`).
//! * `θh` beyond `atan(τ_max)` (within 1e-4 rad of the horizon) takes the
//!   value at `τ_max`; `cos θh ≤ 0` is the horizon.
//! * Non-finite inputs give 0. The result is never NaN or ∞.

use crate::domain::{self, Domain, Invalid};
use crate::math::{self, Real};
use crate::tables::format::{
    ConvParams, FormatError, Header, Quantised, Table, TableId, ValueType,
};
use crate::tables::interp::Axis;

mod angle;

use crate::tables::format::AngleParams;
use angle::AngleShape;
pub use angle::{normalised_angle, tan_of_normalised_angle};

/// A source of `C(θh; u, c, β, p)` (docs/model.md §2.5).
///
/// Implementations never panic and never return NaN or ∞ for finite inputs;
/// each documents what it does outside its domain.
pub trait Convolution {
    /// `C` at the half-vector angle given by `sin θh` and `cos θh` (both in
    /// `[0, 1]`; passing both keeps narrow lobes resolved: in f32,
    /// `cos θh` alone cannot tell `θh = 1e-4` from 0) for the kernel
    /// parameters `u ≥ 0`, `c > 1` and the NDF's `β > 0`, `p > 0`.
    fn convolution_sin_cos(
        &self,
        sin_theta_h: f32,
        cos_theta_h: f32,
        u: f32,
        c: f32,
        beta: f32,
        p: f32,
    ) -> f32;

    /// [`Convolution::convolution_sin_cos`] from `cos θh` alone (coarse for
    /// `θh ≲ 1e-3`; prefer the sine and cosine from the half vector).
    fn convolution(&self, cos_theta_h: f32, u: f32, c: f32, beta: f32, p: f32) -> f32 {
        let cos = cos_theta_h.max(0.0).min(1.0);
        let sin = math::sqrtf(((1.0 - cos) * (1.0 + cos)).max(0.0));
        self.convolution_sin_cos(sin, cos, u, c, beta, p)
    }

    /// A faster equivalent for one material `(c, β, p)` and any `u`, if the
    /// source has one ([`ConvTable`] does: [`ConvSlice`]); `None` by default.
    fn material_slice(&self, _c: f32, _beta: f32, _p: f32) -> Option<ConvSlice<'_>> {
        None
    }
}

/// The K-correlation kernel shape `k(x) = (1 + x²)^(−(c+1)/2)` (HP17 14, 40),
/// computed as `exp(−(c+1)/2 · ln(1 + x²))`; 0 for `x = ±∞`, 1 for `x = 0`.
#[inline]
pub fn kernel(x: f32, c: f32) -> f32 {
    let x2 = f64::from(x) * f64::from(x);
    if !(x2 < f64::INFINITY) {
        return 0.0;
    }
    math::exp(-0.5 * (f64::from(c) + 1.0) * math::ln_1p(x2)) as f32
}

/// Number of channels before the `ln C` values: `ln s`, `ln(g² + g_offset)`.
pub const FIT_CHANNELS: usize = 2;

/// The planar kernel integral `I(u) = (1 − (1 + 4u²)^((1−c)/2)) / ((c − 1) u²)`
/// (∝ ∫ k(2u sin γ) dω for a narrow kernel), used for `u > u_max`.
fn planar_kernel_integral(u: f64, c: f64) -> f64 {
    let cm1 = c - 1.0;
    // 1 − (1 + 4u²)^(−(c−1)/2) = −expm1(…), accurate for c → 1.
    let one_minus = -math::exp_m1(-0.5 * cm1 * math::ln_1p(4.0 * u * u));
    one_minus / (cm1 * u * u)
}

/// The T3 file: both forms. Use [`ConvTable::fit`] for the paper's form.
#[derive(Clone, Copy, Debug)]
pub struct ConvTable<'a> {
    /// The four parameter axes `(u, c, β, p)`.
    axes: [Axis; 4],
    /// The per-node quantised values ([`ValueType::U16`]).
    values: Quantised<'a>,
    angle: AngleParams,
    /// Number of `ξ` nodes (channels after the fit channels).
    angles: usize,
    g_offset: f32,
    u_max: f32,
    domain: [(f32, f32); 4],
    /// Per parameter axis: Catmull–Rom (4 nodes) instead of linear (2 nodes).
    cubic: [bool; 4],
}

/// The paper's form of T3 (T3a), a view of a [`ConvTable`].
#[derive(Clone, Copy, Debug)]
pub struct ConvFitTable<'a> {
    table: ConvTable<'a>,
}

/// Inputs after the out-of-domain rules: clamped parameters and the factor
/// for `u > u_max`.
struct Clamped {
    u: f32,
    c: f32,
    beta: f32,
    p: f32,
    factor: f32,
}

impl<'a> ConvTable<'a> {
    /// Reads a T3 file.
    pub fn from_bytes(bytes: &'a [u8]) -> Result<Self, FormatError> {
        Self::from_table(Table::from_bytes_expecting(bytes, TableId::Convolution)?)
    }

    /// Checks that `table` is a T3 file with a usable layout.
    pub fn from_table(table: Table<'a>) -> Result<Self, FormatError> {
        let header: &Header = table.expecting(TableId::Convolution)?.header();
        let used = header.used_axes();
        let channels = header.channels as usize;
        let params = ConvParams::from_header(header);
        let angles = params.angles as usize;
        if used.len() != 4 || angles < 4 || channels != FIT_CHANNELS + angles {
            return Err(FormatError::Shape(
                "T3 needs 4 axes and 2 + angles channels with at least 4 angles",
            ));
        }
        let angle = params.angle;
        // NaN fails every comparison, so it is rejected too.
        let valid = angle.tau_max > 0.0
            && angle.ndf_exponent_cap > 0.0
            && params.g_offset > 0.0
            && (0.0..1e6).contains(&angle.ndf_softening)
            && (0.0..1e6).contains(&angle.horizon_weight)
            && (0.0..1e6).contains(&angle.edge_weight)
            && (0.0..1e6).contains(&angle.edge_smoothing)
            && angle.edge_fade_tan > 0.0
            && (0.0..1e6).contains(&angle.edge_softening_fade);
        if !valid {
            return Err(FormatError::Shape(
                "T3 angle parameters must be positive (softening and term weights finite, ≥ 0)",
            ));
        }
        // T3 is stored quantised per node (half the bytes of f32 for twice
        // the u nodes; `ValueType::U16` states the error, ≤ 0.034% on C).
        let values = match (header.value_type, table.quantised()) {
            (ValueType::U16, Some(q)) => q,
            _ => {
                return Err(FormatError::Shape(
                    "T3 must be stored as u16 (per-node quantised); rebuild it with this generator",
                ));
            }
        };
        let axes = [
            Axis::numbered(0, &used[0])?,
            Axis::numbered(1, &used[1])?,
            Axis::numbered(2, &used[2])?,
            Axis::numbered(3, &used[3])?,
        ];
        let node_total: usize = used.iter().map(|a| a.nodes as usize).product();
        if values.nodes() != node_total || values.codes.len() != node_total * channels {
            return Err(FormatError::Shape("T3 grid length disagrees with the axes"));
        }
        let mut domain = [(0.0, 0.0); 4];
        for (d, slot) in domain.iter_mut().enumerate() {
            *slot = (axes[d].lo(), axes[d].hi());
        }
        if !(domain[1].0 > 1.0) || !(domain[2].0 > 0.0) || !(domain[3].0 > 0.0) || domain[0].0 < 0.0
        {
            return Err(FormatError::Shape(
                "T3 domain must have c > 1, beta > 0, p > 0, u >= 0",
            ));
        }
        Ok(ConvTable {
            axes,
            values,
            angle,
            angles,
            g_offset: params.g_offset as f32,
            u_max: domain[0].1,
            domain,
            cubic: DEFAULT_CUBIC_AXES,
        })
    }

    /// The same table with the given per-axis interpolation along the
    /// parameters, for both forms (`true`: Catmull–Rom through 4 nodes,
    /// `false`: linear).
    pub fn with_cubic_axes(mut self, cubic: [bool; 4]) -> Self {
        self.cubic = cubic;
        self
    }

    /// The interpolation weights of parameter axis `d` in `cell`
    /// ([`axis_weights`] with this table's node count and kernel for `d`).
    #[inline]
    fn axis_weights(&self, d: usize, cell: (usize, f32)) -> (usize, usize, [f32; 4]) {
        axis_weights(self.axes[d].nodes(), cell, self.cubic[d])
    }

    /// T3b restricted to the material `(c, β, p)` (see [`ConvSlice`]);
    /// `None` for non-finite parameters or a table larger than
    /// [`SLICE_CAPACITY`] or with more than [`SLICE_ANGLES`] angles. Costs
    /// one blend of all angles per `u` node (`cargo bench --bench lookup --
    /// convolution_setup`).
    pub fn slice(&self, c: f32, beta: f32, p: f32) -> Option<ConvSlice<'a>> {
        let k = self.clamp(0.0, c, beta, p)?;
        let (u_nodes, angles) = (self.axes[0].nodes(), self.angles);
        if u_nodes * angles > SLICE_CAPACITY || angles > SLICE_ANGLES {
            return None;
        }
        let mut values = [0.0f32; SLICE_CAPACITY];
        let mut cells = self.cells(&k);
        for (i, row) in values.chunks_exact_mut(angles).take(u_nodes).enumerate() {
            // Node i exactly: the start of cell i (the end of the last cell).
            cells[0] = if i + 1 < u_nodes {
                (i, 0.0)
            } else {
                (i - 1, 1.0)
            };
            self.blend_into(cells, FIT_CHANNELS, row);
        }
        Some(ConvSlice {
            table: *self,
            c: k.c,
            beta: k.beta,
            p: k.p,
            values,
        })
    }

    /// Blend of the `N` consecutive channels from `first` over the parameter
    /// cell ([`ConvTable::blend_into`]).
    fn blend_params<const N: usize>(&self, cells: [(usize, f32); 4], first: usize) -> [f32; N] {
        let mut sum = [0.0f32; N];
        self.blend_into(cells, first, &mut sum);
        sum
    }

    /// Blend of the `out.len()` consecutive channels from `first` over the
    /// parameter cell (one pass over the corners, skipping those of zero
    /// weight along `u`), with [`ConvTable::axis_weights`] per axis.
    #[inline(always)]
    fn blend_into(&self, cells: [(usize, f32); 4], first: usize, out: &mut [f32]) {
        let channels = FIT_CHANNELS + self.angles;
        let n = out.len();
        let mut start = [0usize; 4];
        let mut count = [2usize; 4];
        let mut weights = [[0.0f32; 4]; 4];
        for d in 0..4 {
            (start[d], count[d], weights[d]) = self.axis_weights(d, cells[d]);
        }
        let Quantised { scales, codes, .. } = self.values;
        let [n1, n2, n3] = [1, 2, 3].map(|d| self.axes[d].nodes());
        out.iter_mut().for_each(|v| *v = 0.0);
        // Σ w (offset + q step) = Σ w offset + Σ (w step) q.
        let mut offsets = 0.0f32;
        // Corners of zero weight along the first axis (u; a slice's rows at
        // nodes) are skipped: most of a slice's blends; a test per inner
        // corner costs more than it saves (callgrind).
        for (a, wa) in weights[0][..count[0]]
            .iter()
            .enumerate()
            .filter(|(_, w)| **w != 0.0)
        {
            let ia = start[0] + a;
            for (b, wb) in weights[1][..count[1]].iter().enumerate() {
                let ib = ia * n1 + start[1] + b;
                let wab = wa * wb;
                for (c, wc) in weights[2][..count[2]].iter().enumerate() {
                    let ic = ib * n2 + start[2] + c;
                    let wabc = wab * wc;
                    for (d, wd) in weights[3][..count[3]].iter().enumerate() {
                        let node = ic * n3 + start[3] + d;
                        let index = node * channels + first;
                        let w = wabc * wd;
                        if let (Some(q), Some(scale)) = (
                            codes.get(index..index + n),
                            scales.get(2 * node..2 * node + 2),
                        ) {
                            offsets += w * scale[0];
                            let w_step = w * scale[1];
                            for (acc, &x) in out.iter_mut().zip(q) {
                                *acc += w_step * f32::from(x);
                            }
                        }
                    }
                }
            }
        }
        out.iter_mut().for_each(|v| *v += offsets);
    }

    /// Checks a lookup point against T3's domain (from its header): `c`, `β`,
    /// `p` within the table's axes, `u ∈ [u_min, ∞]` (beyond `u_max` the
    /// narrow-kernel rule of the module documentation applies).
    pub fn check(&self, u: f32, c: f32, beta: f32, p: f32) -> Result<(), Invalid> {
        let [du, dc, db, dp] = self.domain;
        let closed = |(lo, hi): (f32, f32)| Domain::Closed(domain::widen(lo), domain::widen(hi));
        let u_domain = Domain::Closed(domain::widen(du.0), f64::INFINITY);
        domain::check("u", domain::widen(u), u_domain, "T3's domain")?;
        domain::check("c", domain::widen(c), closed(dc), "T3's domain")?;
        domain::check("beta", domain::widen(beta), closed(db), "T3's domain")?;
        domain::check("p", domain::widen(p), closed(dp), "T3's domain")
    }

    /// The paper's form (T3a) from the same file.
    pub fn fit(&self) -> ConvFitTable<'a> {
        ConvFitTable { table: *self }
    }

    /// The normalised-angle constants stored in the header.
    pub fn angle_params(&self) -> AngleParams {
        self.angle
    }

    /// Number of `ξ` nodes.
    pub fn angles(&self) -> usize {
        self.angles
    }

    fn clamp(&self, u: f32, c: f32, beta: f32, p: f32) -> Option<Clamped> {
        if !(u.is_finite() && c.is_finite() && beta.is_finite() && p.is_finite()) {
            return None;
        }
        let [du, dc, db, dp] = self.domain;
        let c = c.max(dc.0).min(dc.1);
        let u = u.max(du.0);
        let (u, factor) = if u > self.u_max {
            let (uf, um, cf) = (f64::from(u), f64::from(self.u_max), f64::from(c));
            let ratio = planar_kernel_integral(uf, cf) / planar_kernel_integral(um, cf);
            (
                self.u_max,
                if ratio.is_finite() { ratio as f32 } else { 0.0 },
            )
        } else {
            (u, 1.0)
        };
        Some(Clamped {
            u,
            c,
            beta: beta.max(db.0).min(db.1),
            p: p.max(dp.0).min(dp.1),
            factor,
        })
    }

    fn cells(&self, k: &Clamped) -> [(usize, f32); 4] {
        [
            self.axes[0].locate(k.u),
            self.axes[1].locate(k.c),
            self.axes[2].locate(k.beta),
            self.axes[3].locate(k.p),
        ]
    }

    /// `ln C` at `ξ` for already clamped parameters: blend of the four
    /// channels around `ξ` over the parameter cell, then a Catmull–Rom cubic
    /// along `ξ` (see [`along_xi`]).
    fn ln_c(&self, cells: [(usize, f32); 4], xi: f64) -> f32 {
        along_xi(self.angles, xi, |first| {
            self.blend_params::<4>(cells, FIT_CHANNELS + first)
        })
    }

    /// The out-of-domain rules and the normalised angle `ξ(τ)` for the
    /// clamped parameters; `None` for non-finite parameters or a NaN `τ`.
    fn clamp_with_angle(
        &self,
        tau: f64,
        u: f32,
        c: f32,
        beta: f32,
        p: f32,
    ) -> Option<(Clamped, f64)> {
        let k = self.clamp(u, c, beta, p)?;
        if tau.is_nan() {
            return None;
        }
        let (u, beta, p) = (f64::from(k.u), f64::from(k.beta), f64::from(k.p));
        let xi = normalised_angle(tau, u, beta, p, &self.angle);
        Some((k, xi))
    }

    /// `C` from T3b at `τ = tan θh` (the [`Convolution`] impl forms `τ` from
    /// `sin θh / cos θh`).
    pub fn at_tan(&self, tau: f64, u: f32, c: f32, beta: f32, p: f32) -> f32 {
        let Some((k, xi)) = self.clamp_with_angle(tau, u, c, beta, p) else {
            return 0.0;
        };
        let value = math::expf(self.ln_c(self.cells(&k), xi)) * k.factor;
        if value.is_finite() { value } else { 0.0 }
    }

    /// `(s, g)` of the paper's form (T3a) at the given parameters, after the
    /// out-of-domain rules (`s` includes the `u > u_max` factor). `(0, 0)` for
    /// non-finite inputs.
    pub fn fit_parameters(&self, u: f32, c: f32, beta: f32, p: f32) -> (f32, f32) {
        let Some(k) = self.clamp(u, c, beta, p) else {
            return (0.0, 0.0);
        };
        // Catmull–Rom like T3b (multilinear with `with_cubic_axes([false; 4])`):
        // interpolation error against the form fitted at the point, e_L2
        // median 0.28% vs 1.9% multilinear (40 verify profiles; docs/design/t3-interpolation.md).
        let [ln_s, ln_g2] = self.blend_params::<2>(self.cells(&k), 0);
        let s = math::expf(ln_s) * k.factor;
        let g2 = math::expf(ln_g2) - self.g_offset;
        let s = if s.is_finite() { s } else { 0.0 };
        (s, math::sqrtf(g2.max(0.0)))
    }
}

/// The Catmull–Rom cubic along `ξ` of T3b: `window(first)` gives the
/// (already blended) values of the four channels `first … first + 3` around
/// `ξ`; one-sided slopes in the first and last interval.
#[inline]
pub fn along_xi(angles: usize, xi: f64, window: impl FnOnce(usize) -> [f32; 4]) -> f32 {
    let n = angles;
    let position = (xi.max(0.0).min(1.0) * (n - 1) as f64) as f32;
    // position ≥ 0: truncation is ⌊position⌋.
    let k = (position as usize).min(n - 2);
    let t = position - k as f32;
    // The four channels around ξ (clamped to the table).
    let k = k as isize;
    let first = (k - 1).max(0).min(n as isize - 4) as usize;
    let window = window(first);
    let at = |j: isize| -> f32 {
        let j = j.max(0).min(n as isize - 1) as usize;
        window[(j - first).min(3)]
    };
    let (v0, v1, v2, v3) = (at(k - 1), at(k), at(k + 1), at(k + 2));
    // Secant slopes (per node spacing); Catmull–Rom node derivatives.
    let s_left = if k == 0 { v2 - v1 } else { v1 - v0 };
    let s_mid = v2 - v1;
    let s_right = if k as usize + 2 >= n {
        v2 - v1
    } else {
        v3 - v2
    };
    let (d1, d2) = (0.5 * (s_left + s_mid), 0.5 * (s_mid + s_right));
    // Cubic Hermite on [v1, v2] with derivatives d1, d2 (unit spacing).
    let t2 = t * t;
    let t3 = t2 * t;
    let h00 = 2.0 * t3 - 3.0 * t2 + 1.0;
    let h10 = t3 - 2.0 * t2 + t;
    let h01 = -2.0 * t3 + 3.0 * t2;
    let h11 = t3 - t2;
    h00 * v1 + h10 * d1 + h01 * v2 + h11 * d2
}

/// Largest `u nodes × angles` a [`ConvSlice`] holds (the shipped T3 needs
/// 28 × 32 = 896).
pub const SLICE_CAPACITY: usize = 1024;
/// Largest number of angles `ξ` a [`ConvSlice`] takes (the shipped T3 has 32).
pub const SLICE_ANGLES: usize = 64;

/// T3b restricted to one material: `ln C` blended over `(c, β, p)` once, at
/// every `u` node and angle, so that a lookup interpolates only `u` and `ξ`
/// (16 taps instead of 1024). Same values as [`ConvTable`] up to f32
/// rounding (the tensor-product interpolation is separable); built by
/// [`ConvTable::slice`], for renderers that evaluate one material many times.
#[derive(Clone, Copy, Debug)]
pub struct ConvSlice<'a> {
    table: ConvTable<'a>,
    /// The clamped material parameters (`c`, `β`, `p`).
    c: f32,
    beta: f32,
    p: f32,
    /// `ln C` at `[u node][angle]`, row-major.
    values: [f32; SLICE_CAPACITY],
}

impl ConvSlice<'_> {
    /// `C` at `τ = tan θh` and `u` for the slice's material; the same
    /// out-of-domain rules as [`ConvTable::at_tan`].
    pub fn at_tan(&self, tau: f64, u: f32) -> f32 {
        let mut ln_c = [0.0f32];
        let Some(factor) = self.ln_profile_at_tans(u, &[tau], &mut ln_c) else {
            return 0.0;
        };
        let value = math::expf(ln_c[0]) * factor;
        if value.is_finite() { value } else { 0.0 }
    }

    /// `ln C − ln s` at every `τ` of `taus` for one `u` (into the same
    /// positions of `out`; `f32::MIN` for a NaN `τ`), and the factor `s` of
    /// the `u > u_max` rule (1 inside the table; `None`, and `out` untouched,
    /// for a non-finite `u`): [`ConvSlice::at_tan`] is `s e^out`. The angle's
    /// `(u, β, p)` parts and `F(τ_max)` are computed once per call, `F` in
    /// the type of `τ` (f32 for the per-material bake: measured in
    /// docs/design/per-material-bake.md).
    pub fn ln_profile_at_tans<T: Real>(&self, u: f32, taus: &[T], out: &mut [f32]) -> Option<f32> {
        let t = &self.table;
        let k = t.clamp(u, self.c, self.beta, self.p)?;
        let a = &t.angle;
        let shape = AngleShape::<T>::new(f64::from(k.u), f64::from(k.beta), f64::from(k.p), a);
        let (zero, tau_max) = (T::of(0.0), T::of(a.tau_max));
        let f_max = shape.f(tau_max);
        let (start, count, weights) = t.axis_weights(0, t.axes[0].locate(k.u));
        let angles = t.angles;
        // The u blend of the slice's rows: ln C at this u's ξ nodes.
        let mut at_u = [0.0f32; SLICE_ANGLES];
        let at_u = &mut at_u[..angles.min(SLICE_ANGLES)];
        for (a, w) in weights[..count].iter().enumerate() {
            let row = (start + a) * angles;
            if let Some(v) = self.values.get(row..row + at_u.len()) {
                for (acc, &x) in at_u.iter_mut().zip(v) {
                    *acc += w * x;
                }
            }
        }
        for (&tau, slot) in taus.iter().zip(out.iter_mut()) {
            if tau.wide().is_nan() {
                *slot = f32::MIN;
                continue;
            }
            let tau = if tau > zero { tau } else { zero };
            let tau = if tau < tau_max { tau } else { tau_max };
            let xi = (shape.f(tau) / f_max).wide().max(0.0).min(1.0);
            *slot = along_xi(angles, xi, |first| match at_u.get(first..first + 4) {
                Some(&[a, b, c, d]) => [a, b, c, d],
                _ => [0.0; 4],
            });
        }
        Some(k.factor)
    }

    /// `C` at the half-vector angle given by `sin θh`, `cos θh`, and `u`.
    pub fn convolution_sin_cos(&self, sin_theta_h: f32, cos_theta_h: f32, u: f32) -> f32 {
        self.at_tan(tan_from_sin_cos(sin_theta_h, cos_theta_h), u)
    }
}

/// Which parameter axes (u, c, β, p) both forms interpolate with Catmull–Rom by
/// default (docs/design/t3-interpolation.md has the measurement behind the choice).
pub const DEFAULT_CUBIC_AXES: [bool; 4] = [true, true, true, true];

/// Catmull–Rom weights of nodes `i−1, i, i+1, i+2` at fraction `t` of cell `i`.
///
/// Mirrored in python/twoscale/drjit/lookups.py.
#[inline]
pub(crate) fn catmull_rom_weights(t: f32) -> [f32; 4] {
    let t2 = t * t;
    let t3 = t2 * t;
    [
        0.5 * (-t3 + 2.0 * t2 - t),
        0.5 * (3.0 * t3 - 5.0 * t2 + 2.0),
        0.5 * (-3.0 * t3 + 4.0 * t2 + t),
        0.5 * (t3 - t2),
    ]
}

/// The interpolation weights of a parameter axis with `nodes` nodes in
/// `cell` (from [`Axis::locate`](crate::tables::interp::Axis::locate)):
/// `(first node, node count, weights)`. Linear weights on nodes `i, i+1`, or
/// with `cubic` Catmull–Rom weights on `i−1 … i+2` (quadratic in the first
/// and last cell, where a node is missing).
#[inline]
pub fn axis_weights(nodes: usize, cell: (usize, f32), cubic: bool) -> (usize, usize, [f32; 4]) {
    let (i, t) = cell;
    let n = nodes;
    if cubic && i >= 1 && i + 2 < n {
        (i - 1, 4, catmull_rom_weights(t))
    } else if cubic && n >= 3 && i == 0 {
        // First cell: the quadratic through nodes 0, 1, 2.
        let w = [
            0.5 * (t - 1.0) * (t - 2.0),
            -t * (t - 2.0),
            0.5 * t * (t - 1.0),
            0.0,
        ];
        (0, 3, w)
    } else if cubic && n >= 3 && i + 2 == n {
        // Last cell: the quadratic through nodes n−3, n−2, n−1.
        let w = [
            0.5 * t * (t - 1.0),
            (1.0 - t) * (1.0 + t),
            0.5 * t * (t + 1.0),
            0.0,
        ];
        (i - 1, 3, w)
    } else {
        (i, 2, [1.0 - t, t, 0.0, 0.0])
    }
}

/// `tan θh = sin θh / cos θh`, with non-positive cosines at the horizon (∞)
/// and NaN for non-finite inputs.
#[inline]
fn tan_from_sin_cos(sin_theta_h: f32, cos_theta_h: f32) -> f64 {
    if !(sin_theta_h.is_finite() && cos_theta_h.is_finite()) {
        return f64::NAN;
    }
    let (s, c) = (f64::from(sin_theta_h).max(0.0), f64::from(cos_theta_h));
    if c > 0.0 { s / c } else { f64::INFINITY }
}

impl Convolution for ConvTable<'_> {
    fn convolution_sin_cos(&self, sin: f32, cos: f32, u: f32, c: f32, beta: f32, p: f32) -> f32 {
        self.at_tan(tan_from_sin_cos(sin, cos), u, c, beta, p)
    }

    fn material_slice(&self, c: f32, beta: f32, p: f32) -> Option<ConvSlice<'_>> {
        self.slice(c, beta, p)
    }
}

impl ConvFitTable<'_> {
    /// `(s, g)` at the given parameters; see [`ConvTable::fit_parameters`].
    pub fn parameters(&self, u: f32, c: f32, beta: f32, p: f32) -> (f32, f32) {
        self.table.fit_parameters(u, c, beta, p)
    }

    /// Checks a lookup point against the file's domain ([`ConvTable::check`]).
    pub fn check(&self, u: f32, c: f32, beta: f32, p: f32) -> Result<(), Invalid> {
        self.table.check(u, c, beta, p)
    }
}

impl Convolution for ConvFitTable<'_> {
    /// `s · k(2 g sin θh)` (HP17 39–41); `sin θh` is clamped to `[0, 1]`.
    fn convolution_sin_cos(&self, sin: f32, _cos: f32, u: f32, c: f32, beta: f32, p: f32) -> f32 {
        if !sin.is_finite() {
            return 0.0;
        }
        let (s, g) = self.parameters(u, c, beta, p);
        let c = c.max(self.table.domain[1].0).min(self.table.domain[1].1);
        s * kernel(2.0 * g * sin.max(0.0).min(1.0), c)
    }
}
