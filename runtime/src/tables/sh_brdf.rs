//! T4: spherical-harmonic BRDF matrices (\[WAT92\] §2, docs/model.md §2.9), and the real
//! spherical harmonics they are built on.
//!
//! # The representation
//!
//! For one material and one wavelength, the function represented is
//! `f(i, o) = ρ(i, o) cos θi cos θo` on the upper hemispheres, completed to the
//! whole sphere by the odd reflection of \[WAT92\] §2.5:
//! `f(θi, φi, π − θo, φo) = −f(θi, φi, θo, φo)`, and the same in `i`. Since
//! `Y_lm(π − θ, φ) = (−1)^(l+m) Y_lm(θ, φ)`, every coefficient with `l + m`
//! even vanishes, and
//!
//! ```text
//! M_jk = ∫_S² ∫_S² f Y_j(i) Y_k(o) dωi dωo = 4 ∫_H+ ∫_H+ f Y_j(i) Y_k(o) dωi dωo     (WAT92 7)
//! ρ(i, o) ≈ Y(i)ᵀ M Y(o) / (cos θi cos θo)                                          (WAT92 8)
//! ```
//!
//! For an isotropic BRDF that is also even in `φo − φi` (mirror-symmetric
//! surfaces, which every model of this crate is), `M` couples only equal `m`,
//! the cos–cos and sin–sin blocks are equal, and cos–sin blocks vanish. With
//! the associated Legendre functions `P̄_l^m` normalised as below, block `m` is
//!
//! ```text
//! B^m_{l l'} = 4 ∫₀¹ ∫₀¹ P̄_l^m(xi) P̄_l'^m(xo) g_m(xi, xo) dxi dxo,
//! g_m(xi, xo) = 2π ∫₀^{2π} f(xi, xo, Δφ) cos(m Δφ) dΔφ,          x = cos θ, Δφ = φo − φi
//! ```
//!
//! and the evaluation streams over the blocks:
//!
//! ```text
//! Y(i)ᵀ M Y(o) = Σ_m w_m cos(m Δφ) Σ_{l,l'} P̄_l^m(xi) B^m_{l l'} P̄_l'^m(xo),   w_0 = 1, w_m = 2.
//! ```
//!
//! Reciprocity (WAT92 9) is `M = Mᵀ` (WAT92 10); the file stores the upper
//! triangle of each block, so the matrix read back is symmetric by
//! construction, and [`ShBrdfTable::eval`] is exactly reciprocal (bit for bit:
//! each off-diagonal term is `B_ab (u_a v_b + u_b v_a)`). The generator reports
//! the asymmetry `‖M − Mᵀ‖` (WAT92 26-27) of the matrix it computed before
//! symmetrising it, in the header.
//!
//! # Real spherical harmonics (this crate's convention)
//!
//! ```text
//! Y_l0        = P̄_l^0(cos θ)
//! Y_lm        = √2 P̄_l^m(cos θ) cos(m φ)       m > 0
//! Y_l,−m      = √2 P̄_l^m(cos θ) sin(m φ)       m > 0
//! P̄_l^m(x)   = √((2l+1)/(4π) · (l−m)!/(l+m)!) · P_l^m(x)     (no Condon–Shortley phase)
//! ```
//!
//! so that `∫_S² Y_lm Y_l'm' dω = δ_ll' δ_mm'`. Vectors of coefficients use the
//! standard index `l(l+1) + m`. `P̄` is computed by the normalised three-term
//! recurrence, which is stable to high degree (no factorials, no SH crate):
//!
//! ```text
//! P̄_0^0 = 1/√(4π),     P̄_m^m = √((2m+1)/(2m)) · sin θ · P̄_{m−1}^{m−1},
//! P̄_{m+1}^m = √(2m+3) · x · P̄_m^m,
//! P̄_l^m = a_lm (x P̄_{l−1}^m − P̄_{l−2}^m / a_{l−1,m}),   a_lm = √((4l² − 1)/(l² − m²)).
//! ```
//!
//! # File layout (T4, `t4-<material>.tbl`)
//!
//! One axis, `coefficient`, of [`coefficient_count`]`(L)` nodes (uniform,
//! `0 ..= count − 1`; the axis is an index, nothing is interpolated), one
//! channel per wavelength (1 to 3), channels innermost. For `m = 0 ..= L` in
//! order, block `m` holds the `n_m = ⌊(L − m + 1)/2⌋` degrees `l_a = m + 1 + 2a`
//! (the `l + m` odd ones); its upper triangle `a ≤ b` is stored row by row.
//! Nothing else is stored: the coefficients that must vanish (`l + m` even,
//! `m ≠ m'`, cos–sin) are absent by construction.
//! The header parameters are [`ShBrdfParams`]; the auxiliary values are
//! [`AUX_NAMES`] (what was projected, how, and the material's parameters).
//!
//! # Accuracy
//!
//! A truncated SH series cannot follow a lobe narrower than about `1/L`
//! radians; glossy materials need `L ~ 1/width` and the table grows like `L³`.
//! Dividing by `cos θi cos θo` magnifies the truncation error near grazing
//! (\[WAT92\] §5). Measured figures: docs/design/t4-band-limits.md.

// Index loops mirror the recurrences and the block formulas of the docs.
#![allow(clippy::needless_range_loop)]

use crate::math;
use crate::tables::format::{FormatError, Kernel, Mapping, ShBrdfParams, Table, TableId};

/// The largest band limit `L` this runtime evaluates (it sizes the stack
/// buffers of the evaluation: 2 × 128 `f64`).
pub const MAX_BAND_LIMIT: usize = 127;

/// The smallest band limit a T4 file may have (`L = 1` would store a single
/// coefficient, and an axis needs two nodes).
pub const MIN_BAND_LIMIT: usize = 2;

/// The largest number of wavelengths (channels) in a T4 file.
pub const MAX_CHANNELS: usize = 3;

/// Names of the auxiliary values of T4 (after the coefficients).
///
/// - `brdf_model`: what was projected: 1 Lambertian, 2 Beckmann Cook–Torrance
///   stand-in (no diffraction), 3 the two-scale model of docs/model.md §2.5
///   at each channel's wavelength, 4 its linear-sRGB channels integrated over
///   the spectrum (docs/model.md §2.12; [`ProjectedModel`]);
/// - `phi_nodes`: midpoint nodes in `Δφ ∈ [0, π]` of the azimuthal Fourier
///   decomposition;
/// - `beta`, `p`, `sigma_s` (µm), `b` (µm), `c`: the material's two-scale
///   parameters; `base_albedo`: the albedo of its base layer (0 for none);
/// - `n_0, k_0, n_1, k_1, n_2, k_2`: its complex index per channel.
pub const AUX_NAMES: [&str; 14] = [
    "brdf_model",
    "phi_nodes",
    "beta",
    "p",
    "sigma_s",
    "b",
    "c",
    "base_albedo",
    "n_0",
    "k_0",
    "n_1",
    "k_1",
    "n_2",
    "k_2",
];

/// Number of stored degrees in block `m`: `⌊(L − m + 1)/2⌋` (the `l ∈ [m, L]`
/// with `l + m` odd), 0 for `m > L`.
pub const fn block_size(band_limit: usize, m: usize) -> usize {
    if m > band_limit {
        0
    } else {
        (band_limit - m).div_ceil(2)
    }
}

/// Number of stored values per channel for band limit `L`: the packed upper
/// triangles of the blocks, `Σ_m n_m (n_m + 1)/2`.
pub const fn coefficient_count(band_limit: usize) -> usize {
    let mut total = 0;
    let mut m = 0;
    while m <= band_limit {
        let n = block_size(band_limit, m);
        total += n * (n + 1) / 2;
        m += 1;
    }
    total
}

/// Offset of block `m` in the packed coefficients.
const fn block_offset(band_limit: usize, m: usize) -> usize {
    let mut total = 0;
    let mut k = 0;
    while k < m {
        let n = block_size(band_limit, k);
        total += n * (n + 1) / 2;
        k += 1;
    }
    total
}

/// The index of the coefficient `(l, m, l')` of the packed layout, or `None`
/// when that coefficient is not stored (it vanishes: `l + m` or `l' + m` even,
/// or a degree outside `m ..= L`).
pub fn packed_coefficient_index(band_limit: usize, m: usize, l: usize, lp: usize) -> Option<usize> {
    if m > band_limit || l > band_limit || lp > band_limit || l <= m || lp <= m {
        return None;
    }
    if (l + m).is_multiple_of(2) || (lp + m).is_multiple_of(2) {
        return None;
    }
    let (a, b) = ((l - m - 1) / 2, (lp - m - 1) / 2);
    let (a, b) = if a <= b { (a, b) } else { (b, a) };
    let n = block_size(band_limit, m);
    Some(block_offset(band_limit, m) + triangle_index(n, a, b))
}

/// Row-major packed upper triangle of size `n`, `a ≤ b < n`: rows `0..a`
/// hold `n, n − 1, …` entries, so row `a` starts at `a n − a(a − 1)/2`.
const fn triangle_index(n: usize, a: usize, b: usize) -> usize {
    a * n - (a * a - a) / 2 + (b - a)
}

/// A unit direction in the local frame split into what the harmonics need:
/// `x = cos θ`, `s = sin θ` and `(cos φ, sin φ)` (`(1, 0)` on the pole).
#[derive(Clone, Copy, Debug)]
struct Polar {
    x: f64,
    s: f64,
    cos_phi: f64,
    sin_phi: f64,
}

impl Polar {
    /// Normalises `d`; `None` for a zero, infinite or NaN vector.
    fn new(d: [f64; 3]) -> Option<Polar> {
        let rho = math::hypot(d[0], d[1]);
        let len = math::hypot(rho, d[2]);
        if !(len > 0.0 && len.is_finite()) {
            return None;
        }
        let (x, s) = (d[2] / len, rho / len);
        let (cos_phi, sin_phi) = if rho > 0.0 {
            (d[0] / rho, d[1] / rho)
        } else {
            (1.0, 0.0)
        };
        Some(Polar {
            x,
            s,
            cos_phi,
            sin_phi,
        })
    }
}

/// Streams the columns `P̄_l^m(x), l = m ..= L` for `m = 0, 1, …` (module docs),
/// for one or two arguments at once (the recurrence coefficients are shared).
struct LegendreColumns<const N: usize> {
    x: [f64; N],
    s: [f64; N],
    /// `P̄_m^m` of the current `m`.
    diagonal: [f64; N],
    m: usize,
}

impl<const N: usize> LegendreColumns<N> {
    fn new(x: [f64; N], s: [f64; N]) -> Self {
        LegendreColumns {
            x,
            s,
            diagonal: [0.5 / math::sqrt(core::f64::consts::PI); N],
            m: 0,
        }
    }

    /// Writes column `m` (the current one) into `out[k][m ..= l_max]`, then
    /// advances to `m + 1`. Entries below `m` are left untouched.
    fn next_column(&mut self, l_max: usize, out: &mut [[f64; MAX_BAND_LIMIT + 1]; N]) {
        let m = self.m;
        if m <= l_max {
            for k in 0..N {
                out[k][m] = self.diagonal[k];
            }
        }
        if m < l_max {
            let mut a_prev = math::sqrt((2 * m + 3) as f64);
            for k in 0..N {
                out[k][m + 1] = a_prev * self.x[k] * self.diagonal[k];
            }
            let mm = (m * m) as f64;
            for l in m + 2..=l_max {
                let ll = (l * l) as f64;
                let a = math::sqrt((4.0 * ll - 1.0) / (ll - mm));
                for k in 0..N {
                    out[k][l] = a * (self.x[k] * out[k][l - 1] - out[k][l - 2] / a_prev);
                }
                a_prev = a;
            }
        }
        self.m += 1;
        let next = self.m as f64;
        let factor = math::sqrt((2.0 * next + 1.0) / (2.0 * next));
        for k in 0..N {
            self.diagonal[k] *= factor * self.s[k];
        }
    }
}

/// The real spherical harmonics `Y_lm(d)` for `l ≤ l_max` (module docs), written
/// to `out[l(l+1) + m]`; `d` need not be normalised. Returns the number of
/// values written, `(l_max + 1)²`, or `None` (and writes nothing) when
/// `l_max > MAX_BAND_LIMIT`, `out` is too short, or `d` is zero or not finite.
pub fn real_sh(d: [f64; 3], l_max: usize, out: &mut [f64]) -> Option<usize> {
    let count = (l_max + 1) * (l_max + 1);
    if l_max > MAX_BAND_LIMIT || out.len() < count {
        return None;
    }
    let polar = Polar::new(d)?;
    let mut columns = LegendreColumns::new([polar.x], [polar.s]);
    let mut p = [[0.0; MAX_BAND_LIMIT + 1]; 1];
    // cos(mφ), sin(mφ) by the rotation recurrence.
    let (mut cos_m, mut sin_m) = (1.0, 0.0);
    for m in 0..=l_max {
        columns.next_column(l_max, &mut p);
        for l in m..=l_max {
            let centre = l * (l + 1);
            if m == 0 {
                out[centre] = p[0][l];
            } else {
                out[centre + m] = core::f64::consts::SQRT_2 * p[0][l] * cos_m;
                out[centre - m] = core::f64::consts::SQRT_2 * p[0][l] * sin_m;
            }
        }
        let c = cos_m * polar.cos_phi - sin_m * polar.sin_phi;
        sin_m = sin_m * polar.cos_phi + cos_m * polar.sin_phi;
        cos_m = c;
    }
    Some(count)
}

/// The normalised associated Legendre functions `P̄_l^m(x)`, `l = m ..= l_max`,
/// of one order `m` (module docs; no Condon–Shortley phase), written to
/// `out[l]`; `out[..m]` is set to 0. `x` is clamped to [−1, 1] and
/// `sin θ = √(1 − x²)`. Returns `None` (writing nothing) when
/// `l_max > MAX_BAND_LIMIT`, `m > l_max`, `out.len() ≤ l_max` or `x` is NaN.
pub fn normalized_legendre(m: usize, x: f64, l_max: usize, out: &mut [f64]) -> Option<()> {
    if l_max > MAX_BAND_LIMIT || m > l_max || out.len() <= l_max || x.is_nan() {
        return None;
    }
    let x = x.max(-1.0).min(1.0);
    let s = math::sqrt((1.0 - x) * (1.0 + x));
    let mut columns = LegendreColumns::new([x], [s]);
    let mut p = [[0.0; MAX_BAND_LIMIT + 1]; 1];
    for _ in 0..=m {
        columns.next_column(l_max, &mut p);
    }
    out[..m].fill(0.0);
    out[m..=l_max].copy_from_slice(&p[0][m..=l_max]);
    Some(())
}

/// Which BRDF a T4 file holds the projection of (aux value `brdf_model`).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ProjectedModel {
    /// A Lambertian `ρ = albedo/π` (tests and checks).
    Lambertian,
    /// A Beckmann Cook–Torrance stand-in with conductor Fresnel and no
    /// diffraction (`generator::analytic::StandIn`): analytic, for tests and
    /// convergence studies.
    BeckmannStandIn,
    /// The two-scale model of docs/model.md §2.5–§2.6 as this runtime evaluates it
    /// ([`crate::brdf::TwoScale`], default options: σrel(θi), separable G,
    /// physical F and Q̄) with T1, T2, T5 and C from T3b
    /// ([`crate::ConvTable`]), at the file's wavelengths. Not reciprocal
    /// when σs > 0; the matrix is symmetrised and the header's `asymmetry`
    /// says by how much it was not.
    TwoScale,
    /// The same two-scale model in linear sRGB integrated over the spectrum
    /// ([`crate::brdf::IntegratedRgb`], docs/model.md §2.12; what the presets
    /// give by default, [`crate::material::RgbMode::default_for`]): channel `c`
    /// is ρ_c, red, green, blue; the header's wavelengths are then the
    /// materials file's nominal ones, not what was evaluated. Not reciprocal
    /// when σs > 0, as [`ProjectedModel::TwoScale`].
    IntegratedRgb,
}

impl ProjectedModel {
    /// The code stored in the file.
    pub const fn code(self) -> u32 {
        match self {
            ProjectedModel::Lambertian => 1,
            ProjectedModel::BeckmannStandIn => 2,
            ProjectedModel::TwoScale => 3,
            ProjectedModel::IntegratedRgb => 4,
        }
    }

    /// The model with this code, if any.
    pub fn from_code(code: f32) -> Option<Self> {
        [
            ProjectedModel::Lambertian,
            ProjectedModel::BeckmannStandIn,
            ProjectedModel::TwoScale,
            ProjectedModel::IntegratedRgb,
        ]
        .into_iter()
        .find(|m| m.code() as f32 == code)
    }
}

/// A validated T4 file: the SH matrix of one material, per wavelength.
#[derive(Clone, Copy, Debug)]
pub struct ShBrdfTable<'a> {
    coefficients: &'a [f32],
    aux: &'a [f32],
    params: ShBrdfParams,
    band_limit: usize,
    channels: usize,
}

impl<'a> ShBrdfTable<'a> {
    /// Validates a T4 file (see [`Table::from_bytes`]) and its shape.
    pub fn from_bytes(bytes: &'a [u8]) -> Result<Self, FormatError> {
        Self::from_table(Table::from_bytes_expecting(bytes, TableId::ShBrdf)?)
    }

    /// Checks that a validated table has the shape of T4 (module docs).
    pub fn from_table(table: Table<'a>) -> Result<Self, FormatError> {
        let header = table.expecting(TableId::ShBrdf)?.header();
        let params = ShBrdfParams::from_header(header);
        let axes = header.used_axes();
        let channels = header.channels as usize;
        if header.value_type != crate::tables::format::ValueType::F32 {
            return Err(FormatError::Shape("T4 must be stored as f32"));
        }
        if axes.len() != 1 || header.kernel != Kernel::Multilinear || channels > MAX_CHANNELS {
            return Err(FormatError::Shape(
                "T4 has one axis (coefficient), 1 to 3 channels and no interpolation",
            ));
        }
        let l = params.band_limit;
        if !(l >= MIN_BAND_LIMIT as f64 && l <= MAX_BAND_LIMIT as f64 && l == math::floor(l)) {
            return Err(FormatError::Shape(
                "T4's band limit must be an integer in [2, 127]",
            ));
        }
        let band_limit = l as usize;
        let axis = &axes[0];
        let count = coefficient_count(band_limit);
        if axis.nodes as usize != count
            || axis.mapping != Mapping::Uniform
            || axis.lo != 0.0
            || axis.hi != (count - 1) as f64
        {
            return Err(FormatError::Shape(
                "T4's axis must index the packed coefficients of its band limit",
            ));
        }
        let (start, width) = (params.filter_start, params.filter_width);
        if !(start >= 0.0 && width >= 0.0) {
            return Err(FormatError::Shape(
                "T4's filter start and width must be non-negative",
            ));
        }
        for (c, &lambda) in params.wavelengths().iter().enumerate() {
            if (c < channels) != (lambda > 0.0) || lambda < 0.0 {
                return Err(FormatError::Shape(
                    "T4 needs a positive wavelength per channel and zero for absent ones",
                ));
            }
        }
        if table.aux().len() != AUX_NAMES.len() {
            return Err(FormatError::Shape("T4 has 14 auxiliary values"));
        }
        if ProjectedModel::from_code(table.aux()[0]).is_none() {
            return Err(FormatError::Shape("T4's brdf_model code is unknown"));
        }
        Ok(ShBrdfTable {
            coefficients: table.grid(),
            aux: table.aux(),
            params,
            band_limit,
            channels,
        })
    }

    /// The band limit `L` (largest degree stored).
    pub fn band_limit(&self) -> usize {
        self.band_limit
    }

    /// Number of channels (wavelengths).
    pub fn channels(&self) -> usize {
        self.channels
    }

    /// Wavelength of `channel` in µm (0 for a channel that does not exist).
    pub fn wavelength(&self, channel: usize) -> f64 {
        match self.params.wavelengths().get(channel) {
            Some(&lambda) if channel < self.channels => lambda,
            _ => 0.0,
        }
    }

    /// The half-Gaussian band filter applied by the generator, as
    /// `(l_f, w)`; `w = 0` means none ([`ShBrdfParams`]).
    pub fn filter(&self) -> (f64, f64) {
        (self.params.filter_start, self.params.filter_width)
    }

    /// `‖M − Mᵀ‖/‖M‖` (WAT92 26-27) of the matrix before it was symmetrised.
    pub fn asymmetry(&self) -> f64 {
        self.params.asymmetry_rel
    }

    /// What was projected.
    pub fn model(&self) -> ProjectedModel {
        ProjectedModel::from_code(self.aux[0]).unwrap_or(ProjectedModel::TwoScale)
    }

    /// The auxiliary values ([`AUX_NAMES`]).
    pub fn aux(&self) -> &'a [f32] {
        self.aux
    }

    /// The matrix element between the cos (or the sin) harmonics `(l, m)` and
    /// `(l', m)` in `channel`: the block element `B^m_{l l'}` (module docs). The
    /// matrix couples nothing else: every other element, and every element with
    /// `l + m` even, is zero and not stored; this returns 0 for them (and for
    /// a channel that does not exist).
    pub fn coefficient(&self, channel: usize, m: usize, l: usize, lp: usize) -> f32 {
        if channel >= self.channels {
            return 0.0;
        }
        packed_coefficient_index(self.band_limit, m, l, lp)
            .and_then(|k| self.coefficients.get(k * self.channels + channel))
            .copied()
            .unwrap_or(0.0)
    }

    /// `ρ(i, o)` in sr⁻¹ from the SH matrix, for every channel at once
    /// (channels beyond [`Self::channels`] are 0):
    /// `Y(i)ᵀ M Y(o) / (cos θi cos θo)` (WAT92 8), streamed over the m-blocks
    /// (module docs), in f64 inside, with no allocation (two columns of
    /// `L + 1` values on the stack).
    ///
    /// `i` (towards the light) and `o` (towards the viewer) are in the local
    /// frame (normal `+z`) and need not be normalised. Returns 0 when either is
    /// at or below the horizon, zero or not finite. Exactly reciprocal:
    /// `eval_rgb(i, o) == eval_rgb(o, i)`.
    pub fn eval_rgb(&self, i: [f32; 3], o: [f32; 3]) -> [f32; 3] {
        let mut out = [0.0f32; 3];
        let (Some(pi), Some(po)) = (Polar::new(widen(i)), Polar::new(widen(o))) else {
            return out;
        };
        if !(pi.x > 0.0 && po.x > 0.0) {
            return out;
        }
        let sums = self.bilinear(pi, po);
        let scale = 1.0 / (pi.x * po.x);
        for (c, v) in out.iter_mut().enumerate().take(self.channels) {
            *v = (sums[c] * scale) as f32;
        }
        out
    }

    /// `ρ(i, o)` of one channel; see [`Self::eval_rgb`] (0 for a channel that
    /// does not exist).
    pub fn eval(&self, channel: usize, i: [f32; 3], o: [f32; 3]) -> f32 {
        if channel >= self.channels {
            return 0.0;
        }
        self.eval_rgb(i, o)[channel]
    }

    /// `Y(i)ᵀ M Y(o)` per channel.
    fn bilinear(&self, pi: Polar, po: Polar) -> [f64; MAX_CHANNELS] {
        let l_max = self.band_limit;
        let channels = self.channels;
        // cos Δφ, Δφ = φo − φi, and cos(mΔφ) by the Chebyshev recurrence.
        let cos_d = pi.cos_phi * po.cos_phi + pi.sin_phi * po.sin_phi;
        let (mut cos_m, mut cos_prev) = (1.0, cos_d);
        let mut columns = LegendreColumns::new([pi.x, po.x], [pi.s, po.s]);
        let mut p = [[0.0; MAX_BAND_LIMIT + 1]; 2];
        let mut total = [0.0; MAX_CHANNELS];
        let mut offset = 0;
        for m in 0..=l_max {
            columns.next_column(l_max, &mut p);
            let n = block_size(l_max, m);
            let mut block = [0.0; MAX_CHANNELS];
            for a in 0..n {
                let la = m + 1 + 2 * a;
                let (ua, va) = (p[0][la], p[1][la]);
                for b in a..n {
                    let lb = m + 1 + 2 * b;
                    let weight = if a == b {
                        ua * va
                    } else {
                        ua * p[1][lb] + p[0][lb] * va
                    };
                    let at = offset * channels;
                    for c in 0..channels {
                        let value = self.coefficients.get(at + c).copied().unwrap_or(0.0);
                        block[c] += f64::from(value) * weight;
                    }
                    offset += 1;
                }
            }
            let w = if m == 0 { cos_m } else { 2.0 * cos_m };
            for c in 0..channels {
                total[c] += w * block[c];
            }
            let next = 2.0 * cos_d * cos_m - cos_prev;
            cos_prev = cos_m;
            cos_m = next;
        }
        total
    }

    /// Reflected radiance towards `o` (local frame, need not be normalised)
    /// for incident radiance given by SH coefficients, in `channel`:
    ///
    /// ```text
    /// L_o(o) = ∫_H+ ρ(i, o) L_in(i) cos θi dωi ≈ ½ Σ_jk c_j M_jk Y_k(o) / cos θo.
    /// ```
    ///
    /// **Hemisphere convention.** `lighting[l(l+1) + m]` must hold
    /// `c_lm = 2 ∫_H+ L_in(i) Y_lm(i) dωi`, i.e. the full-sphere coefficients of
    /// the *odd completion* of the upper-hemisphere lighting
    /// (`L̃(π − θ, φ) = −L_in(θ, φ)`), in the local frame and in this module's
    /// real-SH convention (no Condon–Shortley phase; `m < 0` is `sin`). Only
    /// the coefficients with `l + m` odd are read; the others (and all
    /// those beyond `lighting.len()` or `L`) count as zero. A constant sky
    /// `L_in = 1` has `c_l0 = 2 · 2π ∫₀¹ P̄_l^0(x) dx` for odd `l`, and gives the
    /// directional albedo. Ordinary full-sphere coefficients of a lighting
    /// environment are *not* these: they see the lower hemisphere, which the
    /// surface does not. Returns 0 for `o` at or below the horizon.
    pub fn radiance(&self, channel: usize, lighting: &[f32], o: [f32; 3]) -> f32 {
        if channel >= self.channels {
            return 0.0;
        }
        let Some(po) = Polar::new(widen(o)) else {
            return 0.0;
        };
        if !(po.x > 0.0) {
            return 0.0;
        }
        let l_max = self.band_limit;
        let light = |l: usize, m: isize| -> f64 {
            let index = (l * (l + 1)) as isize + m;
            lighting.get(index as usize).map_or(0.0, |&v| f64::from(v))
        };
        let mut columns = LegendreColumns::new([po.x], [po.s]);
        let mut p = [[0.0; MAX_BAND_LIMIT + 1]; 1];
        let (mut cos_m, mut sin_m) = (1.0, 0.0);
        let mut total = 0.0;
        let mut offset = 0;
        for m in 0..=l_max {
            columns.next_column(l_max, &mut p);
            let n = block_size(l_max, m);
            // Σ_{a,b} B_ab P̄_{l_b}(xo) × (lighting of l_a), both triangle halves.
            let mut sum = 0.0;
            for a in 0..n {
                let la = m + 1 + 2 * a;
                let (ca_cos, ca_sin) = (light(la, m as isize), light(la, -(m as isize)));
                let la_light = if m == 0 {
                    ca_cos
                } else {
                    core::f64::consts::SQRT_2 * (ca_cos * cos_m + ca_sin * sin_m)
                };
                for b in a..n {
                    let lb = m + 1 + 2 * b;
                    let value = self
                        .coefficients
                        .get(offset * self.channels + channel)
                        .map_or(0.0, |&v| f64::from(v));
                    offset += 1;
                    sum += value * la_light * p[0][lb];
                    if a != b {
                        let (cb_cos, cb_sin) = (light(lb, m as isize), light(lb, -(m as isize)));
                        let lb_light = if m == 0 {
                            cb_cos
                        } else {
                            core::f64::consts::SQRT_2 * (cb_cos * cos_m + cb_sin * sin_m)
                        };
                        sum += value * lb_light * p[0][la];
                    }
                }
            }
            total += sum;
            let c = cos_m * po.cos_phi - sin_m * po.sin_phi;
            sin_m = sin_m * po.cos_phi + cos_m * po.sin_phi;
            cos_m = c;
        }
        (0.5 * total / po.x) as f32
    }
}

fn widen(d: [f32; 3]) -> [f64; 3] {
    [f64::from(d[0]), f64::from(d[1]), f64::from(d[2])]
}

#[cfg(test)]
mod tests;
