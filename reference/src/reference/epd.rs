//! Reference implementation of the Exponential Power Distribution (EPD)
//! normal distribution and of its Smith masking term (docs/model.md §2.1–2.2).
//!
//! # Notation
//!
//! Slopes of the microsurface are `(x, y) = −(m_x, m_y)/m_z`, so a facet of
//! normal `m` at angle `θ` from the mean normal has slope length `tan θ`. The
//! EPD with width `β` and shape `p` has the slope density
//!
//! ```text
//!   P22(x) = p / (π β² Γ(1/p)) · exp(−(x/β²)^p),     x = tan²θ     (HP17 35)
//!   D(θ)   = χ(θ < π/2) · P22(tan²θ) / cos⁴θ                          (HP17 34)
//! ```
//!
//! normalised so that `∫ D(m) (m·n) dω = 1`, i.e. `π ∫₀^∞ P22(x) dx = 1`.
//! `p = 1` is Beckmann with roughness `α = β`; `p < 1` has longer tails (and a
//! cusp at the normal for `p < ½`), `p > 1` is flatter with shorter tails.
//!
//! `P22₁` is the unit-width slope density (`β = 1`). Widths enter Smith's
//! masking only through `a = β tan θ` ("shape invariance"), so Λ is a function
//! of `(p, a)` alone.
//!
//! # Smith masking
//!
//! ```text
//!   P2(r) = ∫_{−∞}^{∞} P22₁(r² + q²) dq          slope marginal      (HP17 36, ×2)
//!   Λ(a)  = ∫_{1/a}^{∞} (r a − 1) P2(r) dr                            (HP17 37)
//!   G1    = 1 / (1 + Λ(β tan θ))                                       (HP17 38)
//! ```
//!
//! (HP17 36) integrates over the half line and so misses a factor 2; with the
//! full line `∫ P2 = 1`.
//!
//! [`lambda`] evaluates Λ from a one-dimensional form (see its documentation
//! for the derivation and the numerics); [`lambda_2d`] evaluates the
//! definition above with a nested quadrature, as an independent check.
//!
//! # Accuracy
//!
//! Measured by the tests of this module against 20-digit values computed
//! independently with mpmath (68 points over `p ∈ [0.15, 6]`,
//! `a ∈ [1e-6, 1e6]`): relative error of [`lambda`] ≤ `8e-15`; against the
//! Beckmann closed form at `p = 1` (141 points, `a ∈ [1e-3, 1e4]`): ≤ `6e-14`.
//! The error grows like `1e-16 · y₀`, `y₀ = a^{−2p}`, because `e^{−y₀}` turns
//! the rounding of `y₀` into a relative error; this is the conditioning of Λ
//! itself (`d ln Λ / d ln a ≈ 2p y₀`), and stays below `1e-13` wherever Λ is
//! a normal `f64`. Λ underflows to 0 when `y₀ ≳ 745`, e.g. `a < 0.0376` for
//! `p = 1`, `a < 2.8e-6` for `p = 0.2`.
//!
//! Transcendental functions come from the `libm` crate (a pure-Rust port of
//! musl), so the results are the same on every platform.

use std::f64::consts::PI;

use crate::quad::{self, QuadError, Tolerance};

/// Smallest shape parameter `p` accepted by the functions of this module.
pub const P_MIN: f64 = 0.1;
/// Largest shape parameter `p` accepted by the functions of this module.
pub const P_MAX: f64 = 10.0;

/// Relative tolerance of the quadrature inside [`lambda`] (recorded in the T1 header).
pub const LAMBDA_TOL: Tolerance = Tolerance::relative(1e-13);

/// From this `a` on, [`lambda`] uses its three-term asymptotic expansion,
/// whose relative error there is below `1e-20`.
const LAMBDA_ASYMPTOTIC_A: f64 = 1e7;

fn invalid(name: &'static str, value: f64, expected: &'static str) -> QuadError {
    QuadError::InvalidParameter {
        name,
        value,
        expected,
    }
}

fn check_p(p: f64) -> Result<(), QuadError> {
    if (P_MIN..=P_MAX).contains(&p) {
        Ok(())
    } else {
        Err(invalid("p", p, "a shape parameter in [0.1, 10]"))
    }
}

fn check_non_negative(name: &'static str, v: f64) -> Result<(), QuadError> {
    if v >= 0.0 {
        Ok(())
    } else {
        Err(invalid(name, v, "a value >= 0 (not NaN)"))
    }
}

/// Normalisation `p / (π Γ(1/p))` of the unit-width EPD slope density.
fn unit_norm(p: f64) -> f64 {
    p / (PI * libm::tgamma(1.0 / p))
}

/// Unit-width EPD slope density `P22₁(x) = p / (π Γ(1/p)) · exp(−x^p)`, with
/// `x = tan²θ` (HP17 35 with β = 1).
///
/// Defined for `x ≥ 0` and `p > 0`; other inputs give NaN.
pub fn p22_unit(p: f64, x: f64) -> f64 {
    if !(p > 0.0 && x >= 0.0) {
        return f64::NAN;
    }
    unit_norm(p) * libm::exp(-libm::pow(x, p))
}

/// `p / (π β² Γ(1/p))`, the value of the EPD NDF at the normal (HP17 35).
pub fn ndf_peak(beta: f64, p: f64) -> f64 {
    p / (PI * beta * beta) * (-libm::lgamma(1.0 / p)).exp()
}

/// The EPD NDF (HP17 34–35) from `sin θ ≥ 0`, `cos θ` and the precomputed
/// [`ndf_peak`]: `tan²θ/β² = (sin θ / (β cos θ))²` and the value is evaluated
/// as `peak · exp(−z − 4 ln cos θ)`, `z = (tan²θ/β²)^p`, so that it underflows
/// to 0 at the horizon instead of producing `0/0`. Taking `sin θ` keeps full
/// precision near the normal, where `√(1 − cos²θ)` loses digits (β = 0.002).
/// Used by the convolution reference, whose lobes can be that narrow.
pub fn ndf_sin_cos(beta: f64, p: f64, peak: f64, sin_theta: f64, cos_theta: f64) -> f64 {
    if cos_theta.is_nan() || cos_theta <= 0.0 {
        return 0.0;
    }
    let r = sin_theta / (beta * cos_theta); // tan θ / β
    let z = if r > 0.0 {
        (2.0 * p * r.ln()).exp()
    } else {
        0.0
    };
    peak * (-z - 4.0 * cos_theta.ln()).exp()
}

/// An EPD microfacet distribution with width `beta` (β) and shape `p`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Epd {
    /// Width β > 0 (slope scale; Beckmann's α when `p = 1`).
    pub beta: f64,
    /// Shape p ∈ [[`P_MIN`], [`P_MAX`]].
    pub p: f64,
}

impl Epd {
    /// A validated distribution: `beta` finite and > 0, `p` ∈ [`P_MIN`, `P_MAX`].
    pub fn new(beta: f64, p: f64) -> Result<Self, QuadError> {
        if !(beta > 0.0 && beta.is_finite()) {
            return Err(invalid("beta", beta, "a finite width > 0"));
        }
        check_p(p)?;
        Ok(Self { beta, p })
    }

    /// `ln(p / (π β² Γ(1/p)))`, the log of the normalisation of [`Epd::p22`].
    fn ln_norm(&self) -> f64 {
        libm::log(self.p) - libm::log(PI) - 2.0 * libm::log(self.beta) - libm::lgamma(1.0 / self.p)
    }

    /// Slope density `P22(x) = p / (π β² Γ(1/p)) · exp(−(x/β²)^p)`, `x = tan²θ`
    /// (HP17 35; HP15 26). `π ∫₀^∞ P22(x) dx = 1`.
    ///
    /// NaN for `x < 0` or NaN; 0 for `x = +∞`.
    pub fn p22(&self, x: f64) -> f64 {
        if x.is_nan() || x < 0.0 {
            return f64::NAN;
        }
        let norm = unit_norm(self.p) / (self.beta * self.beta);
        norm * libm::exp(-libm::pow(x / (self.beta * self.beta), self.p))
    }

    /// Normal distribution `D(θ) = χ(θ < π/2) · P22(tan²θ) / cos⁴θ` as a
    /// function of `cos θ` (HP17 34), in sr⁻¹. `∫ D(m) cos θ dω = 1`.
    ///
    /// Returns 0 for `cos θ ≤ 0`; `cos θ > 1` is treated as 1 (rounding of a
    /// normalised vector). NaN only for a NaN input. For tiny `cos θ` the
    /// value is computed in logarithms, so it underflows to 0 (or, for very
    /// small `p`, where `D` really grows near the horizon before it decays,
    /// saturates to +∞) but is never NaN.
    pub fn d(&self, cos_theta: f64) -> f64 {
        if cos_theta.is_nan() {
            return f64::NAN;
        }
        if cos_theta <= 0.0 {
            return 0.0;
        }
        let c = cos_theta.min(1.0);
        let c2 = c * c;
        if c >= 1e-60 {
            // tan²θ = (1 − c)(1 + c) / c², accurate also for c close to 1.
            let tan2 = (1.0 - c) * (1.0 + c) / c2;
            self.p22(tan2) / (c2 * c2)
        } else {
            // c⁴ would underflow: ln D = ln norm − (tan²θ/β²)^p − 4 ln c, with
            // ln((tan²θ/β²)^p) = p (ln(1 − c²) − 2 ln c − 2 ln β).
            let ln_c = libm::log(c);
            let ln_tan2_over_b2 = libm::log1p(-c2) - 2.0 * ln_c - 2.0 * libm::log(self.beta);
            let exponent = libm::exp(self.p * ln_tan2_over_b2);
            libm::exp(self.ln_norm() - exponent - 4.0 * ln_c)
        }
    }

    /// Smith `Λ(β tan θ)` for this distribution; see [`lambda`].
    pub fn lambda(&self, tan_theta: f64) -> Result<f64, QuadError> {
        check_non_negative("tan_theta", tan_theta)?;
        lambda(self.p, self.beta * tan_theta)
    }

    /// Smith `G1(θ) = 1 / (1 + Λ(β tan θ))` (HP17 38); see [`g1`].
    pub fn g1(&self, tan_theta: f64) -> Result<f64, QuadError> {
        check_non_negative("tan_theta", tan_theta)?;
        g1(self.p, self.beta * tan_theta)
    }

    /// `tan θm` of a normal sampled with density `D(m) cos θm`, from a uniform
    /// `u ∈ [0, 1]`; see [`sample_tan_theta`].
    pub fn sample_tan_theta(&self, u: f64) -> Result<f64, QuadError> {
        sample_tan_theta(self.beta, self.p, u)
    }
}

/// Slope marginal `P2(r) = ∫_{−∞}^{∞} P22₁(r² + q²) dq` of the unit-width EPD
/// (HP17 36 with the factor 2 of the full line restored, so `∫ P2 = 1`).
///
/// Computed as `2 ∫_0^∞` by adaptive quadrature to a relative tolerance of
/// `1e-13`. `P2` is even in `r`; `r = ±∞` gives 0.
pub fn p2_unit(p: f64, r: f64) -> Result<f64, QuadError> {
    p2_unit_with(p, r, Tolerance::relative(1e-13))
}

fn p2_unit_with(p: f64, r: f64, tol: Tolerance) -> Result<f64, QuadError> {
    check_p(p)?;
    if r.is_nan() {
        return Err(invalid("r", r, "a slope (not NaN)"));
    }
    if r.is_infinite() {
        return Ok(0.0);
    }
    let norm = unit_norm(p);
    let r2 = r * r;
    let est =
        quad::integrate_to_infinity(|q| norm * libm::exp(-libm::pow(r2 + q * q, p)), 0.0, tol)?;
    Ok(2.0 * est.value)
}

/// `v − atan v` for `v ≥ 0`, without cancellation for small `v`.
///
/// Below `v = ½` the alternating series `v³ Σ_{j≥0} (−v²)^j / (2j + 3)` is
/// summed (30 terms, truncation below `1e-18` relative); above, the direct
/// difference loses at most a factor 13 (≈ 1 decimal digit).
fn v_minus_atan(v: f64) -> f64 {
    if v < 0.5 {
        let v2 = v * v;
        let mut sum = 0.0;
        for j in (0..30).rev() {
            sum = 1.0 / (2 * j + 3) as f64 - v2 * sum;
        }
        v2 * v * sum
    } else {
        v - libm::atan(v)
    }
}

/// Smith `Λ(a)` of the EPD with shape `p` (HP17 36–37, with the P2 factor of
/// 2 restored), `a = β tan θ`.
///
/// # The one-dimensional form
///
/// Writing the slope plane in polar coordinates `(r, q) = ρ (cos φ, sin φ)`,
/// the definition `Λ(a) = a ∫∫_{r > μ} (r − μ) P22₁(r² + q²) dr dq`, `μ = 1/a`,
/// becomes (docs/model.md §2.2)
///
/// ```text
///   Λ(a) = 2a ∫_μ^∞ ρ P22₁(ρ²) (sqrt(ρ² − μ²) − μ acos(μ/ρ)) dρ
///        = 2  ∫_μ^∞ ρ P22₁(ρ²) w(ρ/μ) dρ,        w(s) = v − atan v,  v = sqrt(s² − 1),
/// ```
///
/// using `acos(1/s) = atan(sqrt(s² − 1))`. `w` is evaluated without the
/// cancellation of the printed form (`w ≈ v³/3` for `s → 1`).
///
/// # Numerics
///
/// With `y = ρ^{2p}` (a Gamma(1/p) variable, which removes the heavy tail of
/// small `p`: at `p = 0.2`, `exp(−ρ^{0.4})` only becomes negligible at
/// `ρ ~ 10⁵`), `y₀ = μ^{2p}` and `y = y₀ + t`,
///
/// ```text
///   Λ(a) = e^{−y₀} / (π Γ(1/p)) · ∫_0^∞ (y₀ + t)^{1/p − 1} e^{−t} w(s) dt,
///   s − 1 = expm1(log1p(t/y₀) / (2p)).
/// ```
///
/// Near `t = 0`, `w ~ t^{3/2}`; and for `p > 1` with small `y₀` the factor
/// `(y₀ + t)^{1/p − 1}` is nearly singular. Both are removed by `t = σ^k`,
/// `k = max(2, 2p)`, which makes the integrand smooth (analytic for `k = 2`).
/// For small `y₀` (large `a`) the change from `w ~ t^{3/2}` to `w ~ s` happens
/// at `σ_c = y₀^{1/k}`, a narrow feature near 0 that adaptive quadrature could
/// miss, so `[0, 1]` is cut geometrically at `σ_c, 8σ_c, 64σ_c, …`. The pieces,
/// and the last one to ∞ (through [`quad::integrate_to_infinity`]), are each
/// integrated to a relative tolerance of `1e-13`. The factor `e^{−y₀}` (and, for `y₀ ≥ 1`,
/// `y₀^{1/p−1}`) is applied outside the integral, so the relative accuracy
/// also holds where Λ is tiny; when Λ is provably below the smallest
/// subnormal (`ln` of an upper bound below −746) the result is exactly 0.
///
/// For `a ≥ 10⁷` the asymptotic expansion `k_p a − ½ + m_p / a` is used (see
/// [`k_p`] and [`m_p`]); its next term is `O(1/a²)`, so its relative error
/// there is below `1e-20`.
///
/// # Domain
///
/// `p ∈ [P_MIN, P_MAX]` (accuracy tested on `[0.15, 6]`), `a ≥ 0`:
/// `a = 0` gives 0, `a = +∞` gives +∞; a negative or NaN `a` or an
/// out-of-range `p` is an [`QuadError::InvalidParameter`].
pub fn lambda(p: f64, a: f64) -> Result<f64, QuadError> {
    check_p(p)?;
    check_non_negative("a", a)?;
    if a == 0.0 {
        return Ok(0.0);
    }
    if a == f64::INFINITY {
        return Ok(f64::INFINITY);
    }
    if a >= LAMBDA_ASYMPTOTIC_A {
        return Ok(lambda_asymptotic(p, a));
    }
    lambda_quadrature(p, a, LAMBDA_TOL)
}

/// `k_p a − ½ + m_p / a`, the large-`a` expansion of Λ.
fn lambda_asymptotic(p: f64, a: f64) -> f64 {
    k_p(p) * a - 0.5 + m_p(p) / a
}

/// The quadrature of [`lambda`] for finite `a > 0`, with a given tolerance.
fn lambda_quadrature(p: f64, a: f64, tol: Tolerance) -> Result<f64, QuadError> {
    let inv_p = 1.0 / p;
    let ln_y0 = -2.0 * p * libm::log(a);
    let y0 = libm::pow(a, -2.0 * p);
    // For y0 ≥ 1 the factor y0^{1/p − 1} is taken out of the integral.
    let factored = y0 >= 1.0;
    if factored {
        // Upper bound of the integral in this case: w(s) ≤ s and
        // (1 + t/y0) ≤ 1 + t give I ≤ ∫ e^{−t} (1+t)^c dt ≤ e·max(1, Γ(3/(2p)))
        // with c = max(3/(2p) − 1, 1/(2p)) ≤ 3/(2p).
        let ln_bound = 1.0 + libm::lgamma(1.5 * inv_p).max(0.0);
        let ln_prefactor = -y0 + (inv_p - 1.0) * ln_y0 - libm::log(PI) - libm::lgamma(inv_p);
        if ln_prefactor + ln_bound < -746.0 {
            return Ok(0.0);
        }
    }
    let k = if p > 1.0 { 2.0 * p } else { 2.0 };
    let integrand = |sigma: f64| {
        let (t, jacobian) = if p > 1.0 {
            let sk1 = libm::pow(sigma, k - 1.0);
            (sk1 * sigma, k * sk1)
        } else {
            (sigma * sigma, 2.0 * sigma)
        };
        let decay = libm::exp(-t);
        if decay == 0.0 {
            return 0.0;
        }
        let log1p_ratio = libm::log1p(t / y0); // ln(y / y0)
        let growth = if factored {
            libm::exp((inv_p - 1.0) * log1p_ratio) // ((y0 + t)/y0)^{1/p − 1}
        } else {
            libm::pow(y0 + t, inv_p - 1.0)
        };
        let s_minus_1 = libm::expm1(log1p_ratio / (2.0 * p)); // ρ/μ − 1
        let v = libm::sqrt(s_minus_1 * (2.0 + s_minus_1));
        jacobian * decay * growth * v_minus_atan(v)
    };
    // Where t ≈ y0 (σ = σc = y0^{1/k}), w changes from w ~ (t/y0)^{3/2} to
    // w ~ s − π/2. When σc ≪ 1 this feature is too narrow for the first
    // panels to notice it, so the σ-axis is cut geometrically from σc up to 1,
    // and each piece is integrated on its own (left to right).
    let sigma_c = libm::pow(y0, 1.0 / k);
    let mut integral = 0.0;
    let mut lower = 0.0;
    if sigma_c < 0.5 {
        let mut upper = sigma_c;
        while upper < 1.0 {
            integral += quad::integrate(integrand, lower, upper, tol)?.value;
            lower = upper;
            upper *= 8.0;
        }
    }
    integral += quad::integrate_to_infinity(integrand, lower, tol)?.value;
    if integral == 0.0 {
        return Ok(0.0);
    }
    let gamma = PI * libm::tgamma(inv_p);
    if !factored {
        Ok(libm::exp(-y0) * integral / gamma)
    } else if y0 < 700.0 {
        Ok(libm::exp(-y0) * libm::pow(y0, inv_p - 1.0) * integral / gamma)
    } else {
        // exp(−y0) alone would underflow before the other factors are applied.
        Ok(libm::exp(
            -y0 + (inv_p - 1.0) * ln_y0 + libm::log(integral) - libm::log(gamma),
        ))
    }
}

/// Smith `Λ(a)` from its definition `Λ(a) = ∫_{1/a}^{∞} (r a − 1) P2(r) dr`
/// (HP17 37), with `P2` from [`p2_unit`]: a nested quadrature, slow (about
/// 17 ms at `p = 0.2`, `a = 1`, against 25 µs for [`lambda`]) but independent
/// of the transformations used by [`lambda`]. Tolerances: `1e-13` relative
/// for `P2`, `1e-11` for the outer integral; it agrees with [`lambda`] to
/// about `1e-14` in the tests.
///
/// Same domain and special values as [`lambda`].
pub fn lambda_2d(p: f64, a: f64) -> Result<f64, QuadError> {
    check_p(p)?;
    check_non_negative("a", a)?;
    if a == 0.0 {
        return Ok(0.0);
    }
    if a == f64::INFINITY {
        return Ok(f64::INFINITY);
    }
    let mu = 1.0 / a;
    let mut inner_error = None;
    // Λ(a) = a ∫_0^∞ x P2(μ + x) dx
    let outer = quad::integrate_to_infinity(
        |x| match p2_unit_with(p, mu + x, Tolerance::relative(1e-13)) {
            Ok(p2) => x * p2,
            Err(e) => {
                inner_error.get_or_insert(e);
                f64::NAN
            }
        },
        0.0,
        Tolerance::relative(1e-11),
    );
    match (outer, inner_error) {
        (Ok(est), _) => Ok(a * est.value),
        (Err(_), Some(inner)) => Err(inner),
        (Err(e), None) => Err(e),
    }
}

/// Slope of the asymptote `Λ(a) = k_p a − ½ + O(1/a)` (docs/model.md §2.2):
/// `k_p = Γ(3/(2p)) / (π Γ(1/p))`.
///
/// Derivation: `k_p = ∫_0^∞ r P2(r) dr` is the mean of the positive part of
/// one slope component, `E|x-slope| / 2`. In polar coordinates the slope is
/// `ρ (cos φ, sin φ)` with φ uniform and independent of ρ, so
/// `E|x-slope| = E[ρ] · E|cos φ| = E[ρ] · 2/π`. With `y = ρ^{2p}` distributed
/// as Gamma(1/p, 1), `E[ρ] = E[y^{1/(2p)}] = Γ(1/p + 1/(2p)) / Γ(1/p)
/// = Γ(3/(2p)) / Γ(1/p)`, hence `k_p = E[ρ]/π`. For `p = 1`,
/// `k_1 = 1/(2√π)` (Beckmann).
///
/// NaN for `p` outside `(0, ∞)`.
pub fn k_p(p: f64) -> f64 {
    if p.is_nan() || p <= 0.0 {
        return f64::NAN;
    }
    libm::tgamma(1.5 / p) / (PI * libm::tgamma(1.0 / p))
}

/// Coefficient of the next term of the asymptote,
/// `Λ(a) = k_p a − ½ + m_p / a + O(1/a²)`:
/// `m_p = E[1/ρ] / (2π) = Γ(1/(2p)) / (2π Γ(1/p))`.
///
/// Derivation: in the form `Λ = E[w(ρ a); ρ > μ] / π` (see [`lambda`]),
/// `w(s) = s − π/2 + 1/(2s) + O(s⁻³)` for large `s`, and the region `ρ < μ`
/// has probability `O(μ²)`. For `p = 1`, `m_1 = 1/(2√π)`, as the expansion of
/// the Beckmann closed form confirms.
///
/// NaN for `p` outside `(0, ∞)`.
pub fn m_p(p: f64) -> f64 {
    if p.is_nan() || p <= 0.0 {
        return f64::NAN;
    }
    libm::tgamma(0.5 / p) / (2.0 * PI * libm::tgamma(1.0 / p))
}

/// `k_p = ∫_0^∞ r P2(r) dr` by quadrature, as a check of [`k_p`].
///
/// In polar coordinates of the slope plane,
/// `∫∫_{r>0} r P22₁(r² + q²) dr dq = ∫_{−π/2}^{π/2} cos φ dφ ∫_0^∞ ρ² P22₁(ρ²) dρ`,
/// so `k_p = 2 ∫_0^∞ ρ² P22₁(ρ²) dρ`, integrated here directly in ρ
/// (relative tolerance `1e-13`).
pub fn k_p_quadrature(p: f64) -> Result<f64, QuadError> {
    check_p(p)?;
    let norm = unit_norm(p);
    let est = quad::integrate_to_infinity(
        |rho| rho * rho * norm * libm::exp(-libm::pow(rho, 2.0 * p)),
        0.0,
        Tolerance::relative(1e-13),
    )?;
    Ok(2.0 * est.value)
}

/// Smith masking `G1 = 1 / (1 + Λ(a))`, `a = β tan θ` (HP17 38). In `[0, 1]`;
/// `a = +∞` gives 0.
pub fn g1(p: f64, a: f64) -> Result<f64, QuadError> {
    lambda(p, a).map(|l| 1.0 / (1.0 + l))
}

/// Smith Λ of one shape `p` as a fast interpolant, for the integrals that
/// need Λ at thousands of directions (the directional albedo,
/// [`crate::reference::albedo`]): piecewise Chebyshev interpolation of
/// [`lambda`] in `x = ln(ã + 0.01)`, `ã = k_p a ∈ [0, 10⁴]` (T1's scaled
/// variable, in which Λ is smooth for every p: `Λ ≈ ã − ½` once `ã ≳ 1`),
/// [`CURVE_PANELS`] equal panels of degree [`CURVE_DEGREE`]; beyond
/// `ã = 10⁴` the asymptote `k_p a − ½ + m_p/a` (next term `O(1/a²)`, below
/// 1e-8 there). Building it costs `CURVE_PANELS · (CURVE_DEGREE + 1)` calls
/// of [`lambda`] (about 40 ms); a lookup about 50 ns.
///
/// Accuracy (tests: 4000 random `a` per p for p ∈ {0.2, 0.35, 0.7, 1, 2.5,
/// 5}): `|ΔΛ| / (1 + Λ)` — the relative error of `G1 = 1/(1 + Λ)` — at most
/// 2.2e-14 (p = 0.2; 6e-15 elsewhere); asserted ≤ 1e-13.
#[derive(Clone, Debug)]
pub struct LambdaCurve {
    p: f64,
    k_p: f64,
    m_p: f64,
    x_lo: f64,
    /// Panels per unit of `x`.
    scale: f64,
    /// Chebyshev coefficients per panel.
    panels: Vec<[f64; CURVE_DEGREE + 1]>,
}

/// Panels of [`LambdaCurve`].
pub const CURVE_PANELS: usize = 48;
/// Degree of each panel of [`LambdaCurve`].
pub const CURVE_DEGREE: usize = 20;
/// `ã` beyond which [`LambdaCurve`] uses the asymptote.
const CURVE_A_SCALED_MAX: f64 = 1e4;
/// The offset of [`LambdaCurve`]'s variable `ln(ã + offset)`.
const CURVE_OFFSET: f64 = 0.01;

impl LambdaCurve {
    /// Interpolates Λ at shape `p` (errors: those of [`lambda`]).
    pub fn new(p: f64) -> Result<Self, QuadError> {
        check_p(p)?;
        let k = k_p(p);
        let x_lo = libm::log(CURVE_OFFSET);
        let x_hi = libm::log(CURVE_A_SCALED_MAX + CURVE_OFFSET);
        let width = (x_hi - x_lo) / CURVE_PANELS as f64;
        let n = CURVE_DEGREE + 1;
        let mut panels = Vec::with_capacity(CURVE_PANELS);
        for j in 0..CURVE_PANELS {
            let centre = x_lo + width * (j as f64 + 0.5);
            // Values at the Chebyshev points t_m = cos(π (m + ½)/n).
            let mut values = [0.0; CURVE_DEGREE + 1];
            for (m, v) in values.iter_mut().enumerate() {
                let t = libm::cos(PI * (m as f64 + 0.5) / n as f64);
                let a_scaled = (libm::exp(centre + 0.5 * width * t) - CURVE_OFFSET).max(0.0);
                *v = lambda(p, a_scaled / k)?;
            }
            let mut coefficients = [0.0; CURVE_DEGREE + 1];
            for (q, c) in coefficients.iter_mut().enumerate() {
                let sum: f64 = values
                    .iter()
                    .enumerate()
                    .map(|(m, v)| v * libm::cos(PI * q as f64 * (m as f64 + 0.5) / n as f64))
                    .sum();
                *c = if q == 0 { 1.0 } else { 2.0 } * sum / n as f64;
            }
            panels.push(coefficients);
        }
        Ok(LambdaCurve {
            p,
            k_p: k,
            m_p: m_p(p),
            x_lo,
            scale: 1.0 / width,
            panels,
        })
    }

    /// The shape p.
    pub fn p(&self) -> f64 {
        self.p
    }

    /// `k_p` of the asymptote ([`k_p`]).
    pub fn k_p(&self) -> f64 {
        self.k_p
    }

    /// Λ(a) for `a ≥ 0` (`a = ∞` gives ∞; NaN gives NaN).
    pub fn lambda(&self, a: f64) -> f64 {
        if a.is_nan() {
            return f64::NAN;
        }
        if a <= 0.0 {
            return 0.0;
        }
        let a_scaled = self.k_p * a;
        if a_scaled >= CURVE_A_SCALED_MAX {
            return self.k_p * a - 0.5 + self.m_p / a;
        }
        let position = (libm::log(a_scaled + CURVE_OFFSET) - self.x_lo) * self.scale;
        let j = (position.max(0.0) as usize).min(CURVE_PANELS - 1);
        let t = 2.0 * (position - j as f64) - 1.0;
        // Clenshaw's recurrence.
        let c = &self.panels[j];
        let (mut b1, mut b2) = (0.0, 0.0);
        for &ck in c[1..].iter().rev() {
            let b0 = 2.0 * t * b1 - b2 + ck;
            b2 = b1;
            b1 = b0;
        }
        (t * b1 - b2 + c[0]).max(0.0)
    }

    /// `c · Λ(s/c)` for the cosine `c ≥ 0` and sine `s ≥ 0` of an angle
    /// (here `a = s/c = tan θ`): finite at `c = 0`, where it is `k_p s`
    /// (the asymptote `c Λ = k_p s − c/2 + m_p c²/s`).
    pub fn cos_lambda(&self, c: f64, s: f64) -> f64 {
        if c.is_nan() || c <= 0.0 {
            return self.k_p * s.max(0.0);
        }
        let a = s / c;
        if self.k_p * a >= CURVE_A_SCALED_MAX {
            return self.k_p * s - 0.5 * c + self.m_p * c * c / s;
        }
        c * self.lambda(a)
    }
}

/// Closed-form Smith Λ of the Beckmann distribution (EPD with `p = 1`),
/// `a = α tan θ`, `μ = 1/a`:
///
/// ```text
///   Λ(a) = (erf(μ) − 1)/2 + exp(−μ²) / (2 μ √π)
///        = exp(−μ²) / (2 √π) · (1/μ − √π e^{μ²} erfc(μ)).
/// ```
///
/// Both terms are nearly equal for large μ, where Λ ≈ `exp(−μ²)/(4 √π μ³)`
/// (the direct difference loses `log₁₀(2μ²)` digits). For `μ < 2` the first
/// line is evaluated with `erfc` (losing at most one digit); for `μ ≥ 2`,
/// `√π e^{μ²} erfc(μ) = 1/(μ + K)` with `K` from Laplace's continued
/// fraction, so the bracket is `K / (μ (μ + K))` without cancellation.
///
/// `a = 0` gives 0, `a = +∞` gives +∞, negative or NaN `a` gives NaN. The
/// result underflows to 0 for `a < 0.0376`.
pub fn beckmann_lambda(a: f64) -> f64 {
    if a.is_nan() || a < 0.0 {
        return f64::NAN;
    }
    if a == 0.0 {
        return 0.0;
    }
    if a == f64::INFINITY {
        return f64::INFINITY;
    }
    let mu = 1.0 / a;
    let sqrt_pi = PI.sqrt();
    let gauss = exp_neg_inv_square(a);
    if mu < 2.0 {
        0.5 * (gauss / (mu * sqrt_pi) - libm::erfc(mu))
    } else {
        // Laplace's continued fraction √π e^{μ²} erfc(μ) = 1/(μ + K) with
        // K = (1/2)/(μ + (2/2)/(μ + (3/2)/(μ + …))), evaluated backwards.
        let mut k = 0.0;
        for n in (1..=CF_TERMS).rev() {
            k = (0.5 * n as f64) / (mu + k);
        }
        // 1/μ − 1/(μ + K) = K / (μ (μ + K)), free of cancellation.
        gauss / (2.0 * sqrt_pi) * k / (mu * (mu + k))
    }
}

/// `exp(−1/a²)` for `a > 0`, with `1/a²` carried to about twice the working
/// precision.
///
/// `exp(−x)` amplifies an absolute error of `x` into the same relative error,
/// and rounding `x = 1/a²` to `f64` costs up to `x · 1.1e-16` (7e-14 when the
/// result is near underflow). Here `a² = s + s_lo` exactly (FMA), `1/s = r +
/// r_lo`, and the low parts enter through a first-order correction.
fn exp_neg_inv_square(a: f64) -> f64 {
    let s = a * a;
    let s_lo = a.mul_add(a, -s);
    let r = 1.0 / s;
    let r_lo = -r.mul_add(s, -1.0) / s;
    let x_lo = r_lo - r * (s_lo / s); // 1/a² ≈ r + x_lo
    libm::exp(-r) * (1.0 - x_lo)
}

/// Terms of the continued fraction in [`beckmann_lambda`]; enough for full
/// double precision at `μ ≥ 2` (checked against 50-digit values).
const CF_TERMS: usize = 400;

/// `tan θm` of a microfacet normal sampled from the EPD (density
/// `D(m) cos θm`), from a uniform number `u ∈ [0, 1]` (HP17 49–50; the
/// exponent of HP15 23 is misprinted):
///
/// ```text
///   tan θm = β · y^{1/(2p)},    y = Q⁻¹(1/p, u),
/// ```
///
/// where `Q` is the regularised upper incomplete gamma function: `(tan²θm/β²)^p`
/// is Gamma(1/p, 1)-distributed, and `P(tan θm > t) = Q(1/p, (t/β)^{2p})`.
/// The azimuth is uniform, `φm = 2π u'`.
///
/// `u = 1` gives 0 and `u = 0` gives +∞ (pass `1 − u` for a `u ∈ [0, 1)` to
/// avoid it). Errors for `beta ≤ 0`, `p` out of range or `u ∉ [0, 1]`.
pub fn sample_tan_theta(beta: f64, p: f64, u: f64) -> Result<f64, QuadError> {
    if !(beta > 0.0 && beta.is_finite()) {
        return Err(invalid("beta", beta, "a finite width > 0"));
    }
    check_p(p)?;
    let y = inverse_gamma_q(1.0 / p, u)?;
    Ok(beta * libm::pow(y, 0.5 / p))
}

/// Smallest shape `a` accepted by [`inverse_gamma_q`].
const GAMMA_A_MIN: f64 = 0.05;
/// Largest shape `a` accepted by [`inverse_gamma_q`].
const GAMMA_A_MAX: f64 = 1000.0;

/// The inverse `y = Q⁻¹(a, q)` of the regularised upper incomplete gamma
/// function `Q(a, y) = Γ(a, y)/Γ(a)`, i.e. the `y` with `P(Y > y) = q` for
/// `Y ~ Gamma(a, 1)`.
///
/// `Q` and `P = 1 − Q` come from `statrs::function::gamma::{gamma_ur,
/// gamma_lr}`. To keep relative accuracy in both tails, the equation solved
/// is `ln P(a, y) = ln(1 − q)` when `q > ½` (`1 − q` is then exact) and
/// `ln Q(a, y) = ln q` otherwise. It is solved by Newton's method in
/// `z = ln y` (where both tails are nearly linear: `ln P ≈ a z` and
/// `ln Q ≈ −e^z`), safeguarded by a bracket `[e^{−740}, 10⁵]` that is bisected
/// (geometrically) whenever a Newton step would leave it; `dP/dy` is the
/// Gamma density. The iteration stops once a Newton step is below `1e-11`
/// in `z`, so the error left is that of `statrs`'s `P`, `Q`: measured relative
/// error in `y` ≤ `1e-13` for `a ∈ [0.15, 6.7]`, `q ∈ [1e-300, 1]`.
///
/// `q = 1` gives 0 and `q = 0` gives +∞. Errors for `a ∉ [0.05, 1000]` or
/// `q ∉ [0, 1]` (including NaN).
pub fn inverse_gamma_q(a: f64, q: f64) -> Result<f64, QuadError> {
    use statrs::function::gamma::{checked_gamma_lr, checked_gamma_ur};
    if !(GAMMA_A_MIN..=GAMMA_A_MAX).contains(&a) {
        return Err(invalid("a", a, "a Gamma shape in [0.05, 1000]"));
    }
    if !(0.0..=1.0).contains(&q) {
        return Err(invalid("q", q, "a probability in [0, 1]"));
    }
    if q == 1.0 {
        return Ok(0.0);
    }
    if q == 0.0 {
        return Ok(f64::INFINITY);
    }
    let lower = q > 0.5;
    let target = if lower { 1.0 - q } else { q };
    let ln_target = libm::log(target);
    let ln_gamma_a = libm::lgamma(a);
    let statrs_error = |y: f64| invalid("y", y, "an argument accepted by statrs");
    // F(y), increasing in y, with F = 0 at the root; and dF/d(ln y).
    let eval = |y: f64| -> Result<(f64, f64), QuadError> {
        let tail = if lower {
            checked_gamma_lr(a, y).map_err(|_| statrs_error(y))?
        } else {
            checked_gamma_ur(a, y).map_err(|_| statrs_error(y))?
        };
        let f = if lower {
            libm::log(tail) - ln_target
        } else {
            ln_target - libm::log(tail)
        };
        // y · (Gamma density at y) / tail
        let df = libm::exp(a * libm::log(y) - y - ln_gamma_a) / tail;
        Ok((f, df))
    };
    // Initial guess from the leading term of the tail.
    let mut y = if lower {
        // P(a, y) ≈ y^a / Γ(a + 1)
        libm::exp((ln_target + libm::lgamma(a + 1.0)) / a).min(a + 1.0)
    } else {
        // Q(a, y) ≈ y^{a−1} e^{−y} / Γ(a): iterate y = −ln(q Γ(a)) + (a−1) ln y
        let mut y = (-ln_target).max(1.0);
        for _ in 0..3 {
            y = (-ln_target - ln_gamma_a + (a - 1.0) * libm::log(y)).max(a.min(1.0));
        }
        y
    };
    let mut lo = libm::exp(-740.0);
    let mut hi = 1e5;
    y = y.clamp(lo, hi);
    for _ in 0..200 {
        let (f, df) = eval(y)?;
        if f == 0.0 {
            return Ok(y);
        }
        if f < 0.0 {
            lo = y;
        } else {
            hi = y;
        }
        let step = f / df; // Newton step in ln y
        if step.is_finite() {
            let next = y * libm::exp(-step);
            if next > lo && next < hi {
                y = next;
                if step.abs() < 1e-11 {
                    return Ok(y);
                }
                continue;
            }
        }
        y = libm::sqrt(lo) * libm::sqrt(hi);
        if hi <= lo * (1.0 + 4.0 * f64::EPSILON) {
            return Ok(y);
        }
    }
    Err(QuadError::NotConverged {
        value: y,
        error: hi - lo,
        evaluations: 200,
    })
}

#[cfg(test)]
// Reference values are printed with 20 digits, as computed.
#[allow(clippy::excessive_precision)]
mod tests {
    use super::*;

    fn rel(x: f64, exact: f64) -> f64 {
        if x == exact {
            0.0
        } else {
            ((x - exact) / exact).abs()
        }
    }

    /// `n` points spaced logarithmically over `[lo, hi]`.
    fn log_sweep(lo: f64, hi: f64, n: usize) -> impl Iterator<Item = f64> {
        (0..n).map(move |i| lo * (hi / lo).powf(i as f64 / (n - 1) as f64))
    }

    /// Λ(p, a) to 20 digits, computed with mpmath at 50 digits from the form
    /// `Λ = 2μ² ∫_0^∞ v (v − atan v) P22₁(μ²(1 + v²)) dv` (ρ = μ sqrt(1 + v²)),
    /// with the exact binary values of p and a, and checked against the
    /// Beckmann closed form (p = 1) to 1e-48. Values that underflow f64 are
    /// left out.
    const LAMBDA_MPMATH: [(f64, f64, f64); 68] = [
        (0.15, 1e-6, 9.9365267212708984154e-23),
        (0.15, 1e-3, 0.10259664152455509889),
        (0.15, 0.01, 2.549933268897018693),
        (0.15, 0.1, 29.201745948469803927),
        (0.15, 0.3, 88.576663314721249002),
        (0.15, 1.0, 296.41095424549860353),
        (0.15, 3.0, 890.22985034306758982),
        (0.15, 10.0, 2968.5983540380903486),
        (0.15, 100.0, 29690.482415675272767),
        (0.15, 1e4, 2969097.7404311208404),
        (0.15, 1e6, 296909823.54310071968),
        (0.2, 1e-6, 5.5601458299052710067e-105),
        (0.2, 1e-3, 0.000016341987634723677545),
        (0.2, 0.01, 0.059309877703901199644),
        (0.2, 0.1, 2.0544198811119318444),
        (0.2, 0.3, 6.9728884813657759555),
        (0.2, 1.0, 24.326924861808118956),
        (0.2, 3.0, 73.95776535718896791),
        (0.2, 10.0, 247.68369088706750007),
        (0.2, 100.0, 2481.3281927299571274),
        (0.2, 1e4, 248182.31045897404584),
        (0.2, 1e6, 24818280.545809258788),
        (0.35, 1e-3, 4.7469349075554858328e-55),
        (0.35, 0.01, 1.7488073141426614296e-11),
        (0.35, 0.1, 0.008752072244759542518),
        (0.35, 0.3, 0.16874384987837129218),
        (0.35, 1.0, 1.1453952333735748062),
        (0.35, 3.0, 4.2395538248493041317),
        (0.35, 10.0, 15.219017604173264038),
        (0.35, 100.0, 156.61109892908349412),
        (0.35, 1e4, 15710.529789513026573),
        (0.35, 1e6, 1571102.4781502045542),
        (0.5, 0.01, 1.5043215726339406542e-45),
        (0.5, 0.1, 6.4560782464002120086e-6),
        (0.5, 0.3, 0.01045294794855130668),
        (0.5, 1.0, 0.27868921237223869436),
        (0.5, 3.0, 1.4617744562779066831),
        (0.5, 10.0, 5.8820667464920656097),
        (0.5, 100.0, 63.163568709204922334),
        (0.5, 1e4, 6365.6977395913076019),
        (0.5, 1e6, 636619.27236774049802),
        (1.0, 0.1, 5.1702659573319022756e-48),
        (1.0, 0.3, 5.0566911253580756036e-8),
        (1.0, 1.0, 0.025127270830006110506),
        (1.0, 3.0, 0.43861258812651851639),
        (1.0, 10.0, 2.349110474981484804),
        (1.0, 100.0, 27.712300078290694799),
        (1.0, 1e4, 2820.4479459482605651),
        (1.0, 1e6, 282094.29177416023827),
        (2.0, 0.3, 4.3596753744366571372e-60),
        (2.0, 1.0, 0.0028269101768778715445),
        (2.0, 3.0, 0.26732474633861008154),
        (2.0, 10.0, 1.7332094461658042377),
        (2.0, 100.0, 21.510161427550844039),
        (2.0, 1e4, 2200.1906225539699695),
        (2.0, 1e6, 220068.55900015831022),
        (5.0, 1.0, 0.00020190148001949896722),
        (5.0, 3.0, 0.23104687170392409717),
        (5.0, 10.0, 1.6071791418417375275),
        (5.0, 100.0, 20.245585223319222942),
        (5.0, 1e4, 2073.7287449999362417),
        (5.0, 1e6, 207422.37120218943442),
        (6.0, 1.0, 0.00012250631939922333845),
        (6.0, 3.0, 0.23045808961286888681),
        (6.0, 10.0, 1.6061552490542218466),
        (6.0, 100.0, 20.236345084750201354),
        (6.0, 1e4, 2072.8057468633662873),
        (6.0, 1e6, 207330.07139869033414),
    ];

    #[test]
    fn lambda_matches_high_precision_values() {
        let mut worst = (0.0, 0.0, 0.0);
        for &(p, a, exact) in LAMBDA_MPMATH.iter() {
            let l = lambda(p, a).unwrap();
            let e = rel(l, exact);
            if e > worst.0 {
                worst = (e, p, a);
            }
            assert!(e < 1e-12, "p={p} a={a}: {l} vs {exact} (rel {e:.2e})");
        }
        println!(
            "lambda vs mpmath: max rel err {:.2e} at p={}, a={}",
            worst.0, worst.1, worst.2
        );
    }

    #[test]
    fn v_minus_atan_is_accurate_on_both_sides_of_the_switch() {
        // 50-digit values of v − atan v.
        let cases = [
            (1e-8, 3.3333333333333333426e-25),
            (0.01, 3.333133347617936807e-7),
            (0.3, 0.0085432055221329070877),
            (0.49999, 0.036350391031193839117),
            (0.5, 0.036352390999193883786),
            (2.0, 0.89285128220590949698),
            (1e6, 999998.4292046732051),
        ];
        for (v, exact) in cases {
            assert!(
                rel(v_minus_atan(v), exact) < 2e-15,
                "v={v}: {}",
                v_minus_atan(v)
            );
        }
        assert_eq!(v_minus_atan(0.0), 0.0);
    }

    #[test]
    fn lambda_matches_beckmann_at_p_1() {
        // The floor: Λ is a normal f64 only for a ≳ 0.0381; below that both
        // sides must be (nearly) 0.
        let mut worst = (0.0, 0.0);
        for a in log_sweep(1e-3, 1e4, 141) {
            let l = lambda(1.0, a).unwrap();
            let b = beckmann_lambda(a);
            if b < f64::MIN_POSITIVE {
                assert!(l < 1e-300, "a={a}: {l} vs {b}");
                continue;
            }
            let e = rel(l, b);
            if e > worst.0 {
                worst = (e, a);
            }
            assert!(e < 1e-10, "a={a}: {l} vs {b} (rel {e:.2e})");
        }
        println!(
            "lambda vs Beckmann: max rel err {:.2e} at a={}",
            worst.0, worst.1
        );
        assert!(worst.0 < 1e-13);
    }

    #[test]
    fn beckmann_closed_form_matches_high_precision() {
        // 50-digit values of the Beckmann Λ (exact binary a).
        let cases = [
            (0.04, 3.3147780416354416077e-277),
            (0.1, 5.1702659573319022756e-48),
            (0.124, 1.4959319953070196427e-32),
            (0.126, 1.2161810371144568508e-31),
            (0.2, 1.4813429336849383813e-14),
            (0.26, 8.5130942660394566522e-10),
            (0.3, 5.0566911253580756036e-8),
            (0.45, 0.000072799164585439704549),
            (0.49, 0.00019683443897664321033),
            (0.51, 0.00030044481537837458655),
            (0.7, 0.0039794681651430869201),
            (1.0, 0.025127270830006110506),
            (10.0, 2.349110474981484804),
            (1e4, 2820.4479459482605651),
            (1e8, 28209478.677387817168),
        ];
        let mut worst = 0.0f64;
        for (a, exact) in cases {
            let b = beckmann_lambda(a);
            worst = worst.max(rel(b, exact));
            assert!(rel(b, exact) < 1e-14, "a={a}: {b} vs {exact}");
        }
        println!("beckmann_lambda vs mpmath: max rel err {worst:.2e}");
        assert_eq!(beckmann_lambda(0.0), 0.0);
        assert_eq!(beckmann_lambda(f64::INFINITY), f64::INFINITY);
        assert_eq!(beckmann_lambda(0.01), 0.0);
        assert!(beckmann_lambda(-1.0).is_nan());
    }

    #[test]
    fn lambda_matches_the_two_dimensional_definition() {
        let mut worst = (0.0, 0.0, 0.0);
        for p in [0.2, 0.35, 0.5, 1.0, 2.0, 5.0] {
            for a in [0.01, 0.1, 0.3, 1.0, 3.0, 10.0, 100.0] {
                let one = lambda(p, a).unwrap();
                let two = lambda_2d(p, a).unwrap();
                if one < 1e-300 && two < 1e-300 {
                    continue; // both underflow
                }
                let e = rel(one, two);
                if e > worst.0 {
                    worst = (e, p, a);
                }
                assert!(
                    e < 1e-8,
                    "p={p} a={a}: 1-D {one} vs 2-D {two} (rel {e:.2e})"
                );
            }
        }
        println!(
            "lambda vs lambda_2d: max rel diff {:.2e} at p={}, a={}",
            worst.0, worst.1, worst.2
        );
    }

    #[test]
    fn reference_g1_table_of_the_spec() {
        let a_values = [0.1, 0.3, 1.0, 3.0, 10.0];
        let table: [(f64, [f64; 5]); 4] = [
            (0.2, [0.327394, 0.125425, 0.0394837, 0.0133408, 0.00402117]),
            (0.5, [0.999994, 0.989655, 0.782051, 0.406211, 0.145305]),
            (1.0, [1.0, 1.0, 0.975489, 0.695114, 0.298587]),
            (5.0, [1.0, 1.0, 0.999798, 0.812317, 0.383556]),
        ];
        for (p, row) in table {
            for (a, printed) in a_values.iter().zip(row) {
                let g = g1(p, *a).unwrap();
                // 6 significant digits: half a unit of the 6th digit.
                let half_unit = 0.5 * 10f64.powf(printed.log10().floor() - 5.0);
                assert!(
                    (g - printed).abs() <= half_unit * (1.0 + 1e-9),
                    "p={p} a={a}: G1 = {g:.9} vs printed {printed}"
                );
            }
        }
    }

    #[test]
    fn slope_marginal_integrates_to_one() {
        for p in [0.2, 0.5, 1.0, 2.0, 5.0] {
            let half = quad::integrate_to_infinity(
                |r| p2_unit(p, r).unwrap(),
                0.0,
                Tolerance::relative(1e-12),
            )
            .unwrap();
            let total = 2.0 * half.value;
            assert!((total - 1.0).abs() < 1e-10, "p={p}: ∫P2 = {total}");
        }
        // P2 at p = 1 is the Gaussian marginal exp(−r²)/√π.
        for r in [0.0f64, 0.5, 2.0, 5.0] {
            let exact = (-r * r).exp() / PI.sqrt();
            assert!(rel(p2_unit(1.0, r).unwrap(), exact) < 1e-13);
        }
        assert_eq!(p2_unit(1.0, f64::INFINITY).unwrap(), 0.0);
        assert!(p2_unit(1.0, f64::NAN).is_err());
    }

    #[test]
    fn ndf_is_normalised() {
        for (beta, p) in [
            (0.002, 0.2),
            (0.002, 1.0),
            (0.002, 5.0),
            (0.1, 2.0),
            (0.5, 0.2),
            (1.0, 0.2),
            (1.0, 1.0),
            (1.0, 5.0),
        ] {
            let epd = Epd::new(beta, p).unwrap();
            // 2π ∫₀^{π/2} D(cos θ) cos θ sin θ dθ, split at θ = atan(β·2^k)
            // so that the adaptive rule sees the lobe whatever its width.
            let mut edges = vec![0.0];
            for k in -4..=12 {
                let t = (beta * 2f64.powi(k)).atan();
                if t < 0.5 * PI - 1e-3 {
                    edges.push(t);
                }
            }
            edges.push(0.5 * PI);
            let mut total = 0.0;
            for w in edges.windows(2) {
                let est = quad::integrate(
                    |t| epd.d(t.cos()) * t.cos() * t.sin(),
                    w[0],
                    w[1],
                    Tolerance::new(1e-15, 1e-12),
                )
                .unwrap();
                total += 2.0 * PI * est.value;
            }
            assert!((total - 1.0).abs() < 1e-9, "beta={beta} p={p}: {total}");
        }
    }

    #[test]
    fn ndf_edge_cases() {
        let epd = Epd::new(0.3, 0.7).unwrap();
        assert_eq!(epd.d(0.0), 0.0);
        assert_eq!(epd.d(-0.5), 0.0);
        assert!(epd.d(f64::NAN).is_nan());
        assert_eq!(epd.d(1.0), epd.p22(0.0));
        assert_eq!(epd.d(1.0 + 1e-16), epd.d(1.0));
        // Continuity across the switch to the logarithmic evaluation, and no
        // NaN down to the smallest subnormal.
        let small = Epd::new(1.0, 0.1).unwrap();
        let below = small.d(1e-60 * (1.0 - 1e-15));
        let above = small.d(1e-60);
        assert!(rel(below, above) < 1e-10, "{below} vs {above}");
        for c in [1e-300, 5e-324, 1e-100, 1e-20] {
            for e in [epd, small, Epd::new(0.002, 6.0).unwrap()] {
                let d = e.d(c);
                assert!(!d.is_nan() && d >= 0.0, "{e:?} at {c}: {d}");
            }
        }
        // p22 of the unit distribution.
        assert!(rel(p22_unit(1.0, 2.0), (-2f64).exp() / PI) < 1e-15);
        assert!(p22_unit(1.0, -1.0).is_nan());
        assert!(Epd::new(0.0, 1.0).is_err());
        assert!(Epd::new(1.0, 0.05).is_err());
        assert!(Epd::new(f64::NAN, 1.0).is_err());
    }

    #[test]
    fn asymptotic_slope_and_next_term() {
        for p in [0.15, 0.2, 0.5, 1.0, 2.0, 5.0, 6.0] {
            let closed = k_p(p);
            let quad = k_p_quadrature(p).unwrap();
            assert!(rel(quad, closed) < 1e-12, "p={p}: {quad} vs {closed}");
            // a (Λ − (k_p a − ½)) → m_p, i.e. Λ − (k_p a − ½) = m_p/a + o(1/a).
            // The measured remainder is below 0.05 m_p / a, up to the rounding
            // of Λ itself (a few ulp of Λ, amplified by the factor a).
            for a in [1e1, 1e2, 1e3] {
                let l = lambda_quadrature(p, a, LAMBDA_TOL).unwrap();
                let scaled = a * (l - (closed * a - 0.5));
                let dev = (scaled - m_p(p)).abs();
                let allowed = 0.05 * m_p(p) / a + 2e-15 * a * l;
                assert!(dev < allowed, "p={p} a={a}: {scaled} vs m_p {}", m_p(p));
            }
            // The quadrature and the asymptote agree where lambda switches.
            let a = LAMBDA_ASYMPTOTIC_A;
            let q = lambda_quadrature(p, a, LAMBDA_TOL).unwrap();
            let asym = lambda_asymptotic(p, a);
            assert!(rel(q, asym) < 1e-13, "p={p}: {q} vs {asym}");
        }
        let b = 0.5 / PI.sqrt();
        assert!(rel(k_p(1.0), b) < 1e-15 && rel(m_p(1.0), b) < 1e-15);
    }

    #[test]
    fn lambda_is_monotone_and_g1_in_unit_interval() {
        for p in [0.15, 0.2, 0.5, 1.0, 3.0, 6.0] {
            let mut prev = 0.0;
            for a in log_sweep(1e-2, 1e8, 60) {
                let l = lambda(p, a).unwrap();
                assert!(l >= prev, "p={p} a={a}: {l} < {prev}");
                if prev > 0.0 {
                    assert!(l > prev);
                }
                prev = l;
                let g = g1(p, a).unwrap();
                assert!((0.0..=1.0).contains(&g));
            }
        }
    }

    #[test]
    fn lambda_special_values_and_errors() {
        assert_eq!(lambda(0.5, 0.0).unwrap(), 0.0);
        assert_eq!(lambda(0.5, f64::INFINITY).unwrap(), f64::INFINITY);
        assert_eq!(g1(0.5, f64::INFINITY).unwrap(), 0.0);
        assert_eq!(g1(0.5, 0.0).unwrap(), 1.0);
        for (p, a) in [
            (0.5, -1.0),
            (0.5, f64::NAN),
            (f64::NAN, 1.0),
            (0.0, 1.0),
            (11.0, 1.0),
        ] {
            let e = lambda(p, a).unwrap_err();
            assert!(matches!(e, QuadError::InvalidParameter { .. }), "{e:?}");
            assert!(lambda_2d(p, a).is_err());
        }
        assert!(
            lambda(0.5, -1.0)
                .unwrap_err()
                .to_string()
                .contains("a = -1")
        );
        // Deep underflow returns exactly 0 without work.
        assert_eq!(lambda(6.0, 1e-6).unwrap(), 0.0);
        assert_eq!(lambda(1.0, 1e-3).unwrap(), 0.0);
        // Through the Epd wrapper, with a width.
        let epd = Epd::new(0.5, 0.2).unwrap();
        assert_eq!(epd.lambda(2.0).unwrap(), lambda(0.2, 1.0).unwrap());
        assert_eq!(epd.g1(2.0).unwrap(), g1(0.2, 1.0).unwrap());
        assert!(epd.lambda(-1.0).is_err());
    }

    /// Bisection on statrs's Q alone, to the last bit, as the reference for
    /// the Newton inversion.
    fn bisect_gamma_q(a: f64, q: f64) -> f64 {
        use statrs::function::gamma::{gamma_lr, gamma_ur};
        let (mut lo, mut hi) = (1e-320f64, 1e5f64);
        for _ in 0..5000 {
            let mid = lo.sqrt() * hi.sqrt();
            if mid <= lo || mid >= hi {
                break;
            }
            // Q decreasing: Q(mid) > q means the root is further right.
            let right = if q > 0.5 {
                gamma_lr(a, mid) < 1.0 - q
            } else {
                gamma_ur(a, mid) > q
            };
            if right {
                lo = mid;
            } else {
                hi = mid;
            }
        }
        lo.sqrt() * hi.sqrt()
    }

    #[test]
    fn inverse_gamma_q_round_trip_and_bisection() {
        use statrs::function::gamma::{gamma_lr, gamma_ur};
        let mut worst = 0.0f64;
        for a in [0.1, 0.15, 0.2, 0.5, 1.0, 2.0, 5.0, 6.7] {
            let qs = [
                1e-300,
                1e-200,
                1e-50,
                1e-10,
                1e-3,
                0.1,
                0.3,
                0.5,
                0.5000001,
                0.7,
                0.9,
                0.999,
                1.0 - 1e-9,
                1.0 - 2f64.powi(-52),
                1.0 - 2f64.powi(-53),
            ];
            for q in qs {
                let y = inverse_gamma_q(a, q).unwrap();
                // Round trip, on the tail that holds the information.
                let back = if q > 0.5 {
                    1.0 - gamma_lr(a, y)
                } else {
                    gamma_ur(a, y)
                };
                let tail_q = if q > 0.5 { 1.0 - q } else { q };
                let tail_back = if q > 0.5 { gamma_lr(a, y) } else { back };
                assert!(
                    rel(tail_back, tail_q) < 1e-12,
                    "a={a} q={q}: y={y}, tail {tail_back} vs {tail_q}"
                );
                let yb = bisect_gamma_q(a, q);
                let e = rel(y, yb);
                worst = worst.max(e);
                assert!(e < 1e-12, "a={a} q={q}: Newton {y} vs bisection {yb}");
            }
        }
        println!("inverse_gamma_q vs bisection: max rel diff {worst:.2e}");
    }

    #[test]
    fn inverse_gamma_q_matches_high_precision() {
        // y with Q(a, y) = q, by 50-digit bisection in mpmath (exact binary
        // values of a and q; the last q is 1 − 2⁻⁵³).
        let one_minus = 1.0 - 2f64.powi(-53);
        let cases = [
            (0.15, 1e-300, 683.39845655214209229),
            (0.15, 1e-20, 41.046357649642563969),
            (0.15, 0.01, 1.9305933774166846393),
            (0.15, 0.5, 0.0062348057589902164373),
            (0.15, 0.9, 1.3572859640895555473e-7),
            (0.15, 0.999999, 6.2999626325928867746e-41),
            (0.15, one_minus, 2.7252488944995450091e-107),
            (1.0, 1e-300, 690.77552789821370518),
            (1.0, 1e-20, 46.051701859880913735),
            (1.0, 0.01, 4.6051701859880913472),
            (1.0, 0.5, std::f64::consts::LN_2),
            (1.0, 0.9, 0.10536051565782627656),
            (1.0, 0.999999, 1.0000005000290890269e-6),
            (1.0, one_minus, 1.1102230246251566021e-16),
            (6.5, 1e-300, 721.31653867482690166),
            (6.5, 1e-20, 63.291055268882416114),
            (6.5, 0.01, 13.844124805228524624),
            (6.5, 0.5, 6.1698779412819497704),
            (6.5, 0.9, 3.5207522900477307167),
            (6.5, 0.999999, 0.40132141323399758461),
            (6.5, one_minus, 0.011207317843713131847),
        ];
        let mut worst = 0.0f64;
        for (a, q, exact) in cases {
            let y = inverse_gamma_q(a, q).unwrap();
            worst = worst.max(rel(y, exact));
            assert!(rel(y, exact) < 1e-12, "a={a} q={q}: {y} vs {exact}");
        }
        println!("inverse_gamma_q vs mpmath: max rel err {worst:.2e}");
    }

    #[test]
    fn inverse_gamma_q_special_values_and_errors() {
        assert_eq!(inverse_gamma_q(0.5, 1.0).unwrap(), 0.0);
        assert_eq!(inverse_gamma_q(0.5, 0.0).unwrap(), f64::INFINITY);
        assert!(inverse_gamma_q(0.5, 5e-324).unwrap().is_finite());
        for (a, q) in [
            (0.5, -0.1),
            (0.5, 1.1),
            (0.5, f64::NAN),
            (0.0, 0.5),
            (f64::NAN, 0.5),
        ] {
            assert!(matches!(
                inverse_gamma_q(a, q),
                Err(QuadError::InvalidParameter { .. })
            ));
        }
    }

    #[test]
    fn sampling_matches_the_ndf() {
        // The sampled θm has CDF 2π ∫_0^θ D cos sin dθ', so the sample of u
        // must satisfy 2π ∫_0^{θ(u)} D cos sin = 1 − u.
        for (beta, p) in [(0.3, 0.2), (0.05, 1.0), (0.8, 4.0)] {
            let epd = Epd::new(beta, p).unwrap();
            for u in [0.9, 0.5, 0.1, 0.01] {
                let theta = epd.sample_tan_theta(u).unwrap().atan();
                let mut edges = vec![0.0];
                for k in -4..=8 {
                    let t = (beta * 2f64.powi(k)).atan();
                    if t < theta {
                        edges.push(t);
                    }
                }
                edges.push(theta);
                let mut cdf = 0.0;
                for w in edges.windows(2) {
                    cdf += 2.0
                        * PI
                        * quad::integrate(
                            |t| epd.d(t.cos()) * t.cos() * t.sin(),
                            w[0],
                            w[1],
                            Tolerance::new(1e-15, 1e-12),
                        )
                        .unwrap()
                        .value;
                }
                assert!(
                    (cdf - (1.0 - u)).abs() < 1e-10,
                    "beta={beta} p={p} u={u}: {cdf}"
                );
            }
        }
        assert_eq!(sample_tan_theta(0.5, 1.0, 1.0).unwrap(), 0.0);
        assert_eq!(sample_tan_theta(0.5, 1.0, 0.0).unwrap(), f64::INFINITY);
        // p = 1 is Beckmann: tan θ = α sqrt(−ln u).
        let t = sample_tan_theta(0.5, 1.0, 0.3).unwrap();
        assert!(rel(t, 0.5 * (-(0.3f64).ln()).sqrt()) < 1e-13);
        assert!(sample_tan_theta(-0.5, 1.0, 0.3).is_err());
        assert!(sample_tan_theta(0.5, 1.0, 1.5).is_err());
    }

    #[test]
    fn lambda_never_fails_over_the_whole_domain() {
        // p ∈ [0.1, 10] (geometric steps) × a ∈ [1e-8, 1e9] (quarter decades):
        // always Ok, finite and ≥ 0, including the switch to the asymptote.
        let mut p = P_MIN;
        while p <= P_MAX {
            for i in 0..=68 {
                let a = 10f64.powf(-8.0 + 0.25 * i as f64);
                let l = lambda(p, a);
                assert!(
                    matches!(l, Ok(v) if v.is_finite() && v >= 0.0),
                    "p={p} a={a}: {l:?}"
                );
            }
            p *= 1.15;
        }
    }

    #[test]
    fn inverse_gamma_q_never_fails_over_its_domain() {
        let mut a = GAMMA_A_MIN;
        while a <= GAMMA_A_MAX {
            for j in 0..=32 {
                let q = 0.5 * 10f64.powf(-10.0 * j as f64); // down to 5e-321 (subnormal)
                let y = inverse_gamma_q(a, q).unwrap();
                assert!(y.is_finite() && y > 0.0, "a={a} q={q}: {y}");
                let y = inverse_gamma_q(a, 1.0 - q).unwrap();
                assert!(y.is_finite() && y >= 0.0, "a={a} q=1-{q}: {y}");
            }
            a *= 1.3;
        }
    }

    /// [`LambdaCurve`] against [`lambda`] at random `a` (half log-uniform
    /// over [1e-4, 1e6], half uniform in the curve's variable up to
    /// `ã = 10⁴`): the relative error of `1 + Λ` is at most 1e-13.
    #[test]
    fn lambda_curve_matches_lambda() {
        let mut rng = crate::rng::SplitMix64::new(27);
        for p in [0.2, 0.35, 0.7, 1.0, 2.5, 5.0] {
            let curve = LambdaCurve::new(p).unwrap();
            let mut worst: f64 = 0.0;
            for k in 0..4000 {
                let a = if k % 2 == 0 {
                    rng.log_uniform_in(1e-4, 1e6)
                } else {
                    let x = rng.uniform_in((0.01f64).ln(), (1e4f64 + 0.01).ln());
                    (x.exp() - 0.01).max(0.0) / k_p(p)
                };
                let exact = lambda(p, a).unwrap();
                let err = (curve.lambda(a) - exact).abs() / (1.0 + exact);
                worst = worst.max(err);
            }
            eprintln!("LambdaCurve p = {p}: max |ΔΛ|/(1 + Λ) = {worst:.2e}");
            assert!(worst <= 1e-13, "p = {p}: {worst:e}");
            // c Λ(s/c) is continuous into c = 0.
            let s = 0.8f64;
            let at_zero = curve.cos_lambda(0.0, s);
            let near = curve.cos_lambda(1e-9, (1.0f64 - 1e-18).sqrt() * s);
            assert!((at_zero - near).abs() < 1e-8, "{at_zero} {near}");
        }
    }
}
