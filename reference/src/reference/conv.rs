//! Exact `f64` reference of the normalised spherical convolution of docs/model.md §2.5:
//!
//! ```text
//!   C(θh; u, c, β, p) = ∫_{h·m > 0} k(2u sin∠(h,m)) cos²∠(h,m) D(m) dω_m      (HP17 32–33)
//!   k(x) = (1 + x²)^(−(c+1)/2)                                  (K-correlation shape, HP17 14)
//!   D(θ) = χ(θ < π/2) · p / (π β² Γ(1/p)) · exp(−(tan²θ/β²)^p) / cos⁴θ    (EPD, HP17 34–35)
//! ```
//!
//! `D` is centred on the normal `n`, the kernel `K(γ) = k(2u sin γ) cos²γ` on
//! the half vector `h`, which is at the angle `θh` from `n`. Both lobes are cut
//! at their own horizon: `D(m) = 0` for `n·m ≤ 0` and `K = 0` for `h·m ≤ 0`
//! (the cut-off of docs/model.md §2.5). `C` is a function of the single angle `θh`
//! because both lobes are rotationally symmetric about their axes.
//!
//! # Methods
//!
//! Two independent computations, which the tests compare:
//!
//! * **Zonal harmonics** ([`convolution_zh`], module `zh`; HP17 61–64). With
//!   `a_l = ∫₀^{π/2} K(γ) P_l(cos γ) sin γ dγ` and
//!   `b_l = ∫₀^{π/2} D(θ) P_l(cos θ) sin θ dθ`, the Funk–Hecke theorem gives
//!   `C(θh) = π Σ_l (2l+1) a_l b_l P_l(cos θh)`, which is (HP17 64) written
//!   with Legendre polynomials (`S_l = 2π √((2l+1)/4π) a_l`,
//!   `D_l = 2π √((2l+1)/4π) b_l`). The band limit is found by doubling `L`
//!   until the profile stops changing.
//! * **Direct 2-D quadrature** ([`convolution_direct`], module `direct`):
//!   nested adaptive Gauss–Kronrod in polar coordinates around one lobe's
//!   axis, with every kink and every scale of both lobes given to the
//!   quadrature as a breakpoint.
//!
//! and the **limiting forms** of module `limits` ([`narrow_kernel_limit`],
//! [`narrow_ndf_limit`]) for one lobe much narrower than the other.
//!
//! [`convolution`] (one angle) uses the direct quadrature;
//! [`convolution_profile`] (many angles at one parameter point) chooses:
//! zonal harmonics when the band limit they need is affordable, the direct
//! quadrature otherwise (see [`convolution_profile_with_method`]). [`e_l2`] implements the error metric
//! of docs/model.md §2.5 with a quadrature in `θh` graded to the profile's width.
//!
//! # Accuracy target
//!
//! Relative `1e-6` wherever `C(θh) > 1e-6 · C(0)`. Below that the methods
//! are held to the stricter, continuous criterion
//! `|error| ≤ 1e-6 · max(|C|, 1e-6 · C(0))`, i.e. `1e-12 · C(0)` absolute in
//! the deep tails (the direct quadrature is in fact relative to `1e-9`
//! everywhere, down to values of `1e-48`). The measured agreement between
//! the methods is given in the documentation of [`convolution`].
//!
//! # Shapes worth knowing
//!
//! * `∫ D dω ≠ 1` (it is `∫ D cos θ dω = 1`): [`ndf_integral`] is
//!   `1 + O(β²)` for narrow lobes but 78 at `β = 1`, `p = 0.2`, where `D`
//!   has a narrow maximum of `1.2e3` at `cos θ ≈ 3e-3`, next to the horizon.
//!   There `C` *increases* towards grazing `θh`: at `u = 0` from
//!   `C(0) = 0.049` to `C(π/2) = 19.5`, at `u = 3000` from `4.4e-10` to
//!   `9.4e-6`. `C(0)` is then not the scale of the profile, and the
//!   single-lobe form `s · k(2g sin θh)` of (HP17 39) cannot represent it.
//! * Narrow lobes with steep tails make `C` span tens of decades over the
//!   hemisphere (`u = 3000, c = 10, β = 0.002, p = 5`: from `1.7e-3` at
//!   `θh = 0` to `1.6e-48` at `π/2`).

mod direct;
mod limits;
mod zh;

#[cfg(test)]
mod tests;

pub use direct::{DirectOptions, DirectResult, Frame, convolution_direct};
pub use limits::{
    kernel_integral, kernel_moment, narrow_kernel_limit, narrow_ndf_limit, ndf_integral, ndf_moment,
};
pub use zh::{
    MomentCache, ZhOptions, ZhProfile, convolution_zh, convolution_zh_cached, legendre_moments,
    zh_band_estimate, zh_series,
};

use crate::quad::{QuadError, gauss_legendre};
pub(crate) use crate::reference::epd::{ndf_peak, ndf_sin_cos as ndf_sc};
use std::f64::consts::{FRAC_PI_2, PI};
use std::fmt;

/// The accuracy the public entry points aim at: relative, with an absolute
/// floor of `TARGET · TARGET · C(0)` in the deep tails.
pub const TARGET: f64 = 1e-6;

/// Why a convolution could not be computed.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum ConvError {
    /// A parameter is outside the domain where `C` is defined.
    InvalidParameter {
        /// The parameter's name.
        name: &'static str,
        /// The value given.
        value: f64,
        /// What was expected, in words.
        expected: &'static str,
    },
    /// A quadrature failed (see [`QuadError`]).
    Quadrature(QuadError),
    /// The zonal-harmonic series did not converge before the band limit cap:
    /// doubling the band limit from `band_limit / 2` to `band_limit` still
    /// changed the profile by `change` (in units of the tolerance's scale).
    BandLimitExceeded {
        /// The last band limit tried.
        band_limit: usize,
        /// The last relative change observed.
        change: f64,
    },
}

impl fmt::Display for ConvError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match *self {
            ConvError::InvalidParameter {
                name,
                value,
                expected,
            } => write!(f, "invalid parameter {name} = {value}: expected {expected}"),
            ConvError::Quadrature(e) => write!(f, "convolution quadrature failed: {e}"),
            ConvError::BandLimitExceeded { band_limit, change } => write!(
                f,
                "zonal-harmonic series not converged at band limit {band_limit} \
                 (last relative change {change:e})"
            ),
        }
    }
}

impl std::error::Error for ConvError {}

impl From<QuadError> for ConvError {
    fn from(e: QuadError) -> Self {
        ConvError::Quadrature(e)
    }
}

/// One parameter point `(u, c, β, p)` of the convolution, validated.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Params {
    /// `u = (b/λ) cos θd` (HP17 40), ≥ 0.
    pub u: f64,
    /// K-correlation exponent `c` (> 1).
    pub c: f64,
    /// EPD width `β` (> 0).
    pub beta: f64,
    /// EPD shape `p` (> 0).
    pub p: f64,
}

impl Params {
    /// Validates a parameter point. The reference is defined for any finite
    /// `u ≥ 0`, `c > 1`, `β > 0`, `p > 0`; it is verified on the table domain
    /// of docs/model.md §3 (`u ≤ 3000`, `c ∈ [1.01, 10]`, `β ∈ [0.002, 1]`,
    /// `p ∈ [0.2, 5]`).
    pub fn new(u: f64, c: f64, beta: f64, p: f64) -> Result<Self, ConvError> {
        let check = |name, value: f64, ok: bool, expected| {
            if ok && value.is_finite() {
                Ok(())
            } else {
                Err(ConvError::InvalidParameter {
                    name,
                    value,
                    expected,
                })
            }
        };
        check("u", u, u >= 0.0, "a finite value >= 0")?;
        check("c", c, c > 1.0, "a finite value > 1")?;
        check("beta", beta, beta > 0.0, "a finite value > 0")?;
        check("p", p, p > 0.0, "a finite value > 0")?;
        Ok(Self { u, c, beta, p })
    }

    /// The kernel lobe `K(γ) = k(2u sin γ) cos²γ`.
    fn kernel(&self) -> Lobe {
        Lobe::Kernel {
            u: self.u,
            q: 0.5 * (self.c + 1.0),
        }
    }

    /// The NDF lobe `D(θ)`.
    fn ndf(&self) -> Lobe {
        Lobe::Ndf {
            beta: self.beta,
            p: self.p,
            peak: ndf_peak(self.beta, self.p),
        }
    }

    /// Angular half-width of the kernel, `1/(2u)` (where `k` has fallen to
    /// `2^(−(c+1)/2)`), or `π/2` when the kernel is not peaked.
    pub fn kernel_width(&self) -> f64 {
        if 2.0 * self.u > 1.0 / FRAC_PI_2 {
            0.5 / self.u
        } else {
            FRAC_PI_2
        }
    }

    /// Typical angular width of `D`: the polar angle of the median of the
    /// slope distribution, `tan θ = β · y_med^(1/(2p))` with
    /// `y ~ Gamma(1/p, 1)` (median approximated by `1/p − 1/3`, floored at
    /// `0.1`). For `p = 0.2` this is `≈ 53 β`: small-`p` lobes are far wider
    /// than `β` suggests.
    pub fn ndf_width(&self) -> f64 {
        let y_med = (1.0 / self.p - 1.0 / 3.0).max(0.1);
        (self.beta * y_med.powf(0.5 / self.p)).atan()
    }

    fn validate_theta(theta_h: f64) -> Result<(), ConvError> {
        if (0.0..=FRAC_PI_2).contains(&theta_h) {
            Ok(())
        } else {
            Err(ConvError::InvalidParameter {
                name: "theta_h",
                value: theta_h,
                expected: "an angle in [0, π/2]",
            })
        }
    }
}

/// The kernel `K(γ) = k(2u sin γ) cos²γ` with `k(x) = (1 + x²)^(−q)`,
/// `q = (c+1)/2`, cut to zero for `cos γ ≤ 0` (docs/model.md §2.5).
fn kernel_sc(u: f64, q: f64, sin_gamma: f64, cos_gamma: f64) -> f64 {
    let x = 2.0 * u * sin_gamma;
    kernel_x2(q, x * x, cos_gamma)
}

/// [`kernel_sc`] given `x² = 4u² sin²γ` and `cos γ`: `(1 + x²)^(−q) cos²γ`,
/// 0 for `cos γ ≤ 0`. `ln(1 + x²)` rather than `ln_1p(x²)`: rounding
/// `1 + x²` errs by `≤ 1.1e-16` in the logarithm, `≤ 1.1e-16 q` relative in
/// the kernel, and `ln` costs about half the instructions of `ln_1p`.
fn kernel_x2(q: f64, x2: f64, cos_gamma: f64) -> f64 {
    if cos_gamma.is_nan() || cos_gamma <= 0.0 {
        return 0.0;
    }
    (-q * (1.0 + x2).ln()).exp() * cos_gamma * cos_gamma
}

/// One of the two rotationally symmetric lobes of the convolution, as a
/// function of the angle from its own axis.
#[derive(Clone, Copy, Debug)]
enum Lobe {
    /// `K(γ) = (1 + 4u² sin²γ)^(−q) cos²γ`, `q = (c+1)/2`.
    Kernel { u: f64, q: f64 },
    /// The EPD NDF with its precomputed peak value.
    Ndf { beta: f64, p: f64, peak: f64 },
}

impl Lobe {
    /// The lobe's kind and the bits of the parameters that define it (the
    /// NDF's peak is a function of `β, p`): the key of its moments in
    /// [`MomentCache`].
    fn key(&self) -> (u8, [u64; 2]) {
        match *self {
            Lobe::Kernel { u, q } => (0, [u.to_bits(), q.to_bits()]),
            Lobe::Ndf { beta, p, .. } => (1, [beta.to_bits(), p.to_bits()]),
        }
    }

    /// The lobe at polar angle θ from its axis, given `sin θ ≥ 0`, `cos θ`.
    fn value(&self, sin_t: f64, cos_t: f64) -> f64 {
        match *self {
            Lobe::Kernel { u, q } => kernel_sc(u, q, sin_t, cos_t),
            Lobe::Ndf { beta, p, peak } => ndf_sc(beta, p, peak, sin_t, cos_t),
        }
    }

    /// The lobe at the direction whose squared chord to the axis is `d2`
    /// (`d2 = |axis − m|² = 4 sin²(θ/2)`): `cos θ = 1 − d2/2`,
    /// `sin θ = √(d2 (1 − d2/4))`, both accurate for small θ.
    fn value_chord2(&self, d2: f64) -> f64 {
        if d2.is_nan() || d2 >= 2.0 {
            return 0.0;
        }
        let sin2 = (d2 * (1.0 - 0.25 * d2)).max(0.0);
        match *self {
            // The kernel needs sin²θ only.
            Lobe::Kernel { u, q } => kernel_x2(q, 4.0 * u * u * sin2, 1.0 - 0.5 * d2),
            Lobe::Ndf { .. } => self.value(sin2.sqrt(), 1.0 - 0.5 * d2),
        }
    }

    /// Polar angles in `(0, π/2)` where the lobe's profile changes scale:
    /// geometric grids (ratio 2, finer towards the feature) around every
    /// feature, so that on each interval between two consecutive points the
    /// lobe is smooth on the scale of the interval.
    ///
    /// * Kernel: the peak at 0 with half-width `w = 1/(2u)`: `w·2^k`, `k ≥ 0`
    ///   (the kernel is analytic within `w` of its axis).
    /// * NDF: the peak (a cusp for non-integer `p`) at 0, scale
    ///   `θβ = atan β`: `θβ·2^k` for `k ≥ 0` and `θβ·4^(−k)`, `k = 1..8`;
    ///   the angles where `(tan θ/β)^(2p) = 2^k`, `k = −3..6`; and,
    ///   for small `p` and wide `β`, the maximum of `D` next to the horizon
    ///   at `cos θ ≈ ε_s = (p/2)^(1/(2p)) / β` (where
    ///   `d/dθ [−(tan θ/β)^(2p) − 4 ln cos θ] = 0`; e.g. `ε_s = 3.2e-3` for
    ///   `p = 0.2`, `β = 1`, where `D` reaches `1.2e3`): `π/2 − ε_s·2^k`.
    fn breakpoints(&self) -> Vec<f64> {
        let mut out = Vec::new();
        let inside = |x: f64| x > 0.0 && x < FRAC_PI_2;
        match *self {
            Lobe::Kernel { u, .. } => {
                if u > 0.0 {
                    let w = 0.5 / u;
                    let mut x = w;
                    while x < FRAC_PI_2 {
                        out.push(x);
                        x *= 2.0;
                    }
                }
            }
            Lobe::Ndf { beta, p, .. } => {
                let tb = beta.atan();
                let mut x = tb;
                while x < FRAC_PI_2 {
                    out.push(x);
                    x *= 2.0;
                }
                let mut x = tb;
                for _ in 0..8 {
                    x /= 4.0;
                    out.push(x);
                }
                // Where the exponent y = (tan θ/β)^(2p) is 2^k: a grid on
                // the scale of D's own decay, which resolves the sharp
                // shoulder of large p (y goes from 1/8 to 64 within
                // ±50% of θβ at p = 5) and the spread of small p.
                for k in -3..=6 {
                    out.push((beta * 2f64.powf(k as f64 / (2.0 * p))).atan());
                }
                // D vanishes at the horizon like exp(−(β cos θ)^(−2p)) / cos⁴θ:
                // smooth, but not polynomial-like; grade the grid towards it.
                for k in 1..=8 {
                    out.push(FRAC_PI_2 - 0.25 * PI * 0.5f64.powi(k));
                }
                let eps = (0.5 * p).powf(0.5 / p) / beta;
                if eps < 0.25 {
                    let mut x = eps / 64.0;
                    while x < 0.25 * PI {
                        out.push(FRAC_PI_2 - x);
                        x *= 2.0;
                    }
                }
            }
        }
        out.retain(|&x| inside(x));
        sort_dedup(&mut out);
        out
    }
}

/// Sorts ascending and removes points closer than `1e-12` (relative) to
/// their predecessor.
fn sort_dedup(v: &mut Vec<f64>) {
    v.sort_by(f64::total_cmp);
    v.dedup_by(|b, a| (*b - *a).abs() <= 1e-12 * a.abs().max(1e-300));
}

/// How [`convolution_profile`] chose to compute a profile.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Method {
    /// Zonal harmonics with the given band limit.
    ZonalHarmonics {
        /// The band limit `L` of the returned series.
        band_limit: usize,
    },
    /// Direct 2-D quadrature, one nested integral per angle.
    Direct,
}

/// Largest band limit [`convolution_profile`] lets the zonal harmonics
/// reach before falling back on the direct quadrature. Above it the direct
/// quadrature is cheaper: a profile at `L = 16384` costs ≈ 0.2–0.5 s
/// (coefficients up to `L`, plus the doublings that led there), about the
/// cost of 30–60 direct evaluations.
pub const ZH_MAX_BAND: usize = 16384;

/// `C(θh; u, c, β, p)` (docs/model.md §2.5, HP17 32–33) at one angle, by the direct
/// quadrature ([`convolution_direct`] with the default [`DirectOptions`],
/// 1–30 ms): for a single angle it is cheaper than the zonal harmonics,
/// whose cost is per profile.
///
/// # Accuracy (measured)
///
/// On the corner sweep of the domain (`u ∈ {0, 1, 30, 300, 3000}`,
/// `β ∈ {0.002, 0.05, 1}`, `p ∈ {0.2, 0.5, 1, 5}`, `c ∈ {1.01, 2, 10}`,
/// 14 angles from 0 to π/2, test `corner_sweep`), with the error measure
/// `|Δ| / max(|C|, 1e-6 · C(0))` (relative, with an absolute floor of
/// `1e-12 · C(0)` in the deep tails):
///
/// * the two direct frames ([`Frame`]) agree to `≤ 1.1e-12`;
/// * zonal harmonics and direct quadrature agree to `≤ 2.3e-8` (worst at
///   `u = 1, c = 10, β = 1, p = 0.2, θh = 0`, the cusp) on the 163 of 180
///   points where the series converged within `L = 65536`, typically to
///   `1e-11`.
///
/// Cost: 0.6–20 ms per angle (more for narrow kernels).
pub fn convolution(theta_h: f64, u: f64, c: f64, beta: f64, p: f64) -> Result<f64, ConvError> {
    convolution_direct(theta_h, u, c, beta, p, &DirectOptions::default()).map(|r| r.value)
}

/// `C(θh; u, c, β, p)` at every angle of `theta_h` (radians, in `[0, π/2]`).
///
/// See [`convolution_profile_with_method`] for the choice of the method.
pub fn convolution_profile(
    u: f64,
    c: f64,
    beta: f64,
    p: f64,
    theta_h: &[f64],
) -> Result<Vec<f64>, ConvError> {
    convolution_profile_with_method(u, c, beta, p, theta_h).map(|(v, _)| v)
}

/// [`convolution_profile`], also saying which method was used.
///
/// The method: zonal harmonics ([`convolution_zh`] with the default
/// [`ZhOptions`] and `max_band = ZH_MAX_BAND`) when [`zh_band_estimate`]
/// is at most [`ZH_MAX_BAND`]; otherwise, or when the series does not
/// converge within that band limit, the direct quadrature at each angle.
/// On the corner grid of the domain this picks zonal harmonics for 132 of
/// the 180 points (all `u ≤ 30` except narrow `p = 5` lobes, and `u = 300`,
/// `3000` with smooth `D` of moderate width) and the direct quadrature for
/// the other 48 (narrow kernels on cusped `D`, narrow `p = 5` lobes); no
/// zonal-harmonic attempt failed. Cost of one 64-angle profile (release, one
/// core): 0.3 ms (`u = 1, β = 1, p = 1`) to 0.1 s (`L = 8192`) with zonal
/// harmonics; 0.05–1.3 s with the direct quadrature (the slowest:
/// `u = 3000, c = 1.01, β = 0.002, p = 0.2`).
///
/// The series' rounding and truncation noise (`≲ 1e-13 · C(0)`) can make
/// deep-tail values slightly negative; they are clamped to 0.
pub fn convolution_profile_with_method(
    u: f64,
    c: f64,
    beta: f64,
    p: f64,
    theta_h: &[f64],
) -> Result<(Vec<f64>, Method), ConvError> {
    convolution_profile_cached(u, c, beta, p, theta_h, &MomentCache::new())
}

/// Whether [`convolution_profile_cached`] tries zonal harmonics first at
/// `params`: the estimated band limit ([`zh_band_estimate`]) is at most
/// [`ZH_MAX_BAND`]. Otherwise the direct quadrature is used at once.
pub fn tries_zonal_harmonics(params: &Params) -> bool {
    zh_band_estimate(params) <= ZH_MAX_BAND
}

/// [`convolution_profile_with_method`] taking the zonal-harmonic moments
/// from `cache`, for many profiles that share lobes (the T3 grid): the
/// results are bit-identical to the uncached ones (see [`MomentCache`]).
pub fn convolution_profile_cached(
    u: f64,
    c: f64,
    beta: f64,
    p: f64,
    theta_h: &[f64],
    cache: &MomentCache,
) -> Result<(Vec<f64>, Method), ConvError> {
    let params = Params::new(u, c, beta, p)?;
    for &t in theta_h {
        Params::validate_theta(t)?;
    }
    if tries_zonal_harmonics(&params) {
        let opts = ZhOptions {
            max_band: ZH_MAX_BAND,
            ..ZhOptions::default()
        };
        match convolution_zh_cached(u, c, beta, p, theta_h, &opts, cache) {
            Ok(zh) => {
                let values = zh.values.into_iter().map(|v| v.max(0.0)).collect();
                return Ok((
                    values,
                    Method::ZonalHarmonics {
                        band_limit: zh.band_limit,
                    },
                ));
            }
            Err(ConvError::BandLimitExceeded { .. }) => {}
            Err(e) => return Err(e),
        }
    }
    let opts = DirectOptions::default();
    let values = theta_h
        .iter()
        .map(|&t| convolution_direct(t, u, c, beta, p, &opts).map(|r| r.value))
        .collect::<Result<Vec<_>, _>>()?;
    Ok((values, Method::Direct))
}

/// A quadrature rule in `θh` on `[0, π/2]` for integrals `∫ f(θh) sin θh dθh`
/// of convolution profiles, graded to the profile's width (used by
/// [`e_l2`]).
#[derive(Clone, Debug, PartialEq)]
pub struct ProfileRule {
    /// Abscissae `θh` in `(0, π/2)`, ascending.
    pub nodes: Vec<f64>,
    /// Weights, including the `sin θh` of the measure.
    pub weights: Vec<f64>,
}

impl ProfileRule {
    /// Composite 16-point Gauss–Legendre on the intervals between
    /// `0, w/64, w/32, …` (ratio 2, up to `π/4`), then `π/2 − 2^(−k)·π/4` for
    /// `k = 1..20` towards the horizon (where the cut-off of both lobes and
    /// the horizon maximum of small-`p` NDFs put narrow features), and `π/2`.
    /// `w` is the profile's width; [`ProfileRule::for_params`] takes it as
    /// `√(w_K² + w_D²)` from [`Params::kernel_width`] and
    /// [`Params::ndf_width`].
    pub fn new(width: f64) -> Self {
        Self::with_order(width, 16)
    }

    /// The rule of [`ProfileRule::new`] with an `order`-point Gauss–Legendre
    /// rule (instead of 16) on each interval: cheaper profiles for studies
    /// that integrate smooth profiles (the nodes of interval `k` are
    /// `nodes[k·order .. (k+1)·order]`). `order = 0` is treated as 1.
    pub fn with_order(width: f64, order: usize) -> Self {
        let w = width.clamp(1e-9, FRAC_PI_2);
        let mut cuts = vec![0.0];
        let mut x = w / 64.0;
        while x < 0.25 * PI {
            cuts.push(x);
            x *= 2.0;
        }
        for k in 0..=20 {
            cuts.push(FRAC_PI_2 - 0.25 * PI * 0.5f64.powi(k));
        }
        cuts.push(FRAC_PI_2);
        sort_dedup(&mut cuts);
        let (gx, gw) = gauss_legendre(order.max(1));
        let mut nodes = Vec::new();
        let mut weights = Vec::new();
        for pair in cuts.windows(2) {
            let (a, b) = (pair[0], pair[1]);
            let (mid, half) = (0.5 * (a + b), 0.5 * (b - a));
            for (x, wt) in gx.iter().zip(&gw) {
                let t = mid + half * x;
                nodes.push(t);
                weights.push(half * wt * t.sin());
            }
        }
        Self { nodes, weights }
    }

    /// The rule for one parameter point.
    pub fn for_params(params: &Params) -> Self {
        Self::new(Self::width_for(params))
    }

    /// The profile width `√(w_K² + w_D²)` that [`ProfileRule::for_params`]
    /// grades its rule to.
    pub fn width_for(params: &Params) -> f64 {
        params.kernel_width().hypot(params.ndf_width())
    }
}

/// docs/model.md §2.5's error metric of a representation `C̃` of `C` at one parameter
/// point, given the exact profile on `rule.nodes`:
///
/// ```text
///   e_L2 = sqrt( ∫₀^{π/2} (C̃ − C)² sin θh dθh / ∫₀^{π/2} C² sin θh dθh )
/// ```
pub fn e_l2_on(rule: &ProfileRule, approx: impl Fn(f64) -> f64, exact: &[f64]) -> f64 {
    let mut num = 0.0;
    let mut den = 0.0;
    for ((&t, &w), &e) in rule.nodes.iter().zip(&rule.weights).zip(exact) {
        let d = approx(t) - e;
        num += w * d * d;
        den += w * e * e;
    }
    (num / den).sqrt()
}

/// [`e_l2_on`] with the exact profile computed by `exact` (for example
/// `|t| convolution_profile(u, c, beta, p, t)`) on [`ProfileRule::new`]`(width)`.
pub fn e_l2(
    approx: impl Fn(f64) -> f64,
    exact: impl Fn(&[f64]) -> Result<Vec<f64>, ConvError>,
    width: f64,
) -> Result<f64, ConvError> {
    let rule = ProfileRule::new(width);
    let values = exact(&rule.nodes)?;
    Ok(e_l2_on(&rule, approx, &values))
}

/// [`e_l2`] of `approx` against the reference [`convolution_profile`] at one
/// parameter point.
pub fn e_l2_for(
    approx: impl Fn(f64) -> f64,
    u: f64,
    c: f64,
    beta: f64,
    p: f64,
) -> Result<f64, ConvError> {
    let params = Params::new(u, c, beta, p)?;
    let rule = ProfileRule::for_params(&params);
    let values = convolution_profile(u, c, beta, p, &rule.nodes)?;
    Ok(e_l2_on(&rule, approx, &values))
}
