//! Limiting forms of the convolution when one lobe is much narrower than the
//! other, with their first corrections.
//!
//! # The ring-average expansion
//!
//! Let `f` be smooth near a point `a` of the sphere. Its average over the
//! circle of geodesic radius `θ` around `a` is, for each spherical harmonic
//! component of degree `l`, `P_l(cos θ)` times its value at `a` (Funk–Hecke),
//! and `P_l(cos θ) = 1 − l(l+1)/2 · (1 − cos θ) + O((1 − cos θ)²)` while
//! `Δ_S Y_l = −l(l+1) Y_l`. Hence
//!
//! ```text
//!   ⟨f⟩_θ = f(a) + ½ (1 − cos θ) Δ_S f(a) + O((1 − cos θ)²).
//! ```
//!
//! Integrating a narrow zonal lobe `g` around `a` against `f`:
//! `∫ g f dω = f(a) ∫ g dω + ½ Δ_S f(a) ∫ g (1 − cos θ) dω + …`. With
//! `Δ_S F = F'' + cot θ F'` for a function of the polar angle:
//!
//! * **(a) narrow kernel** (`1/(2u) ≪` width of `D`):
//!   `C(θh) ≈ W_K D(θh) + ½ M_K Δ_S D(θh)`, with
//!   `W_K = ∫_{hemisphere} k(2u sin γ) cos²γ dω = π ∫₀¹ (1 + 4u²v)^(−q) √(1−v) dv`
//!   (`v = sin²γ`, `q = (c+1)/2`; `W_K = 2π/3` at `u = 0`,
//!   `≈ π / (2u² (c−1))` for large `u` and `c` well above 1) and
//!   `M_K = ∫ K (1 − cos γ) dω = π ∫₀¹ (1 + 4u²v)^(−q) √(1−v) v/(1 + √(1−v)) dv`.
//! * **(b) narrow NDF** (`D` much narrower than `1/(2u)`):
//!   `C(θh) ≈ W_D K(θh) + ½ (W_D − 1) Δ_S K(θh)`, with `W_D = ∫ D dω` and
//!   `∫ D (1 − cos θ) dω = W_D − 1` (because `∫ D cos θ dω = 1`).
//!
//! `W_D ≠ 1`: with `x = tan²θ`, `∫ D dω = π ∫ P22(x) √(1+x) dx`, the mean of
//! `√(1 + x)` under the slope density; with `x = β² y^(1/p)`,
//! `y ~ Gamma(1/p, 1)` (docs/model.md §2.1),
//! `W_D = E[√(1 + β² y^(1/p))]`, which grows like `β Γ(3/(2p))/Γ(1/p)` for wide
//! lobes (`W_D ≈ 78` at `β = 1`, `p = 0.2`) and is `1 + O(β²)` for narrow
//! ones.
//!
//! # Validity
//!
//! These are expansions in the width ratio, but neither lobe has a finite
//! width in the usual sense. The kernel's tail `k(x) ~ x^(−(c+1))` makes its
//! second angular moment, and so the correction of (a), dominated by the
//! *whole* hemisphere when `c < 3`: the error of (a) decays only like
//! `(uβ)^(−(c−1))` there (for `c = 1.01` it does not decay at all within the
//! domain), and like `(uβ)^(−2)` (leading form) for `c > 3`. Near the cusp of
//! `D` (`θh ≲ β`, non-integer `p`), `Δ_S D` does not exist and the error of
//! (a) is `O((uβ)^(−2p))`. The `D` of small `p` has stretched-exponential
//! tails, so in (b) the relevant width is `w_D` of [`Params::ndf_width`],
//! not `β`.
//!
//! Measured relative errors against the direct quadrature (test
//! `limits_accuracy_sweep`):
//!
//! * (a), smooth `D` (`p = 1, 5`), `θh ≤ 0.3`, leading / corrected form:
//!   `c = 10`: `≈ 0.07 (uβ)^(−2)` / `≈ 4e-3 (uβ)^(−4)`, so `1e-6` is reached
//!   at `uβ ≈ 300` / `uβ ≈ 10–30`; `c = 4`: `≈ 5 (uβ)^(−2)` /
//!   `≈ 0.06 (uβ)^(−3)`, `1e-6` at `uβ ≈ 2000` / `≈ 50–100`; `c = 2`:
//!   `≈ 0.3/(uβ)` / `≈ 0.1/(uβ)`, never `1e-6` in the domain; `c = 1.01`:
//!   1–10% whatever `u`. At larger `θh`, in the tail of `D`, the kernel's
//!   own tail takes over (`C → W_D K(θh)`) and (a) fails (error → 1 at
//!   `β = 0.3`, `θh = 0.8`, `c ≤ 2`). At the cusp (`θh = 0`, `p < 1`) the
//!   leading form errs by `≈ 1e-2 … 1e-4` and there is no correction.
//! * (b), `u = 0`, `p = 1` or 5: leading `≈ β²` (`4e-6` at `β = 0.002`),
//!   corrected `≈ 1e-11` at `β = 0.002`, `4e-7` at `β = 0.03`: `1e-6` for
//!   `β ≲ 0.03`. With a peaked kernel what matters is `u w_D`: the corrected
//!   form is within `1e-6` for `u w_D ≲ 5e-3` (`c = 10`, or `θh = 0`), up
//!   to `u w_D ≈ 0.04` for `c ≈ 1` away from the peak (`θh ≥ 0.3`).
//!   For `p = 0.2` (b) is never better than a few percent, even at
//!   `β = 0.002`, `u = 0`: the stretched-exponential tail of `D` reaches
//!   `tan θ ~ 10³ β`.
//!
//! So within the table domain the limiting forms reach the `1e-6` of the
//! reference only in corners (`c ≳ 4` with `uβ ≳ 100`; `u ≲ 1` with narrow
//! smooth `D`); they are checks and asymptotes, not a substitute for the
//! two full methods.

use super::{ConvError, Params, kernel_sc, ndf_peak, ndf_sc};
use crate::quad::{Tolerance, integrate, integrate_to_infinity};
use std::f64::consts::PI;

/// Relative tolerance of the 1-D integrals of this module.
const TOL: f64 = 1e-13;

/// `E[g(y)]` for `y ~ Gamma(1/p, 1)`, by adaptive quadrature in `s` with
/// `y = s^r`, `r = max(p, 1)`: the density becomes
/// `r s^(r/p − 1) e^(−s^r) / Γ(1/p)`, which is bounded at `s = 0` for every `p`
/// (`y^(1/p − 1)` is singular there when `p > 1`). Split geometrically around
/// the bulk `s ~ (1/p)^(1/r)`.
fn gamma_expectation(p: f64, g: impl Fn(f64) -> f64) -> Result<f64, ConvError> {
    let r = p.max(1.0);
    let lg = libm::lgamma(1.0 / p);
    let expo = r / p - 1.0;
    let f = |s: f64| {
        if s <= 0.0 {
            return 0.0;
        }
        let y = s.powf(r);
        let logd = r.ln() + expo * s.ln() - y - lg;
        if logd < -745.0 {
            0.0
        } else {
            logd.exp() * g(y)
        }
    };
    let s0 = (1.0 / p).powf(1.0 / r);
    let mut cuts = vec![0.0];
    for k in -12..=6 {
        cuts.push(s0 * 2f64.powi(k));
    }
    let tol = Tolerance::relative(TOL);
    let mut sum = 0.0;
    for pair in cuts.windows(2) {
        sum += integrate(f, pair[0], pair[1], tol)?.value;
    }
    sum += integrate_to_infinity(f, *cuts.last().expect("non-empty"), tol)?.value;
    Ok(sum)
}

/// `W_D = ∫_{hemisphere} D dω = E[√(1 + β² y^(1/p))]`, `y ~ Gamma(1/p, 1)`
/// (see the module documentation). At `p = 1`:
/// `1 + (√π/2) β e^(1/β²) erfc(1/β)`.
pub fn ndf_integral(beta: f64, p: f64) -> Result<f64, ConvError> {
    Params::new(0.0, 2.0, beta, p)?;
    Ok(1.0 + ndf_moment(beta, p)?)
}

/// `∫ D (1 − cos θ) dω = W_D − 1 = E[x / (1 + √(1 + x))]`,
/// `x = β² y^(1/p)`, computed without the cancellation of `W_D − 1`.
pub fn ndf_moment(beta: f64, p: f64) -> Result<f64, ConvError> {
    Params::new(0.0, 2.0, beta, p)?;
    gamma_expectation(p, |y| {
        let x = beta * beta * y.powf(1.0 / p);
        if x.is_finite() {
            x / (1.0 + (1.0 + x).sqrt())
        } else {
            // x/(1+√(1+x)) → √x for huge x.
            beta * y.powf(0.5 / p)
        }
    })
}

/// `∫₀¹ (1 + 4u²v)^(−q) √(1−v) w(v) dv` split geometrically at `v = 4^k/(4u²)`.
fn kernel_v_integral(u: f64, c: f64, w: impl Fn(f64) -> f64) -> Result<f64, ConvError> {
    let q = 0.5 * (c + 1.0);
    let a = 4.0 * u * u;
    let f = |v: f64| (-q * (a * v).ln_1p()).exp() * (1.0 - v).max(0.0).sqrt() * w(v);
    let mut cuts = vec![0.0];
    if a > 4.0 {
        let mut v = 0.25 / a;
        while v < 0.5 {
            cuts.push(v);
            v *= 4.0;
        }
    }
    cuts.push(1.0);
    let tol = Tolerance::relative(TOL);
    let mut sum = 0.0;
    for pair in cuts.windows(2) {
        sum += integrate(&f, pair[0], pair[1], tol)?.value;
    }
    Ok(sum)
}

/// `W_K = ∫_{hemisphere} k(2u sin γ) cos²γ dω = π ∫₀¹ (1 + 4u²v)^(−(c+1)/2) √(1−v) dv`
/// (`v = sin²γ`). `W_K(0) = 2π/3`.
pub fn kernel_integral(u: f64, c: f64) -> Result<f64, ConvError> {
    Params::new(u, c, 1.0, 1.0)?;
    Ok(PI * kernel_v_integral(u, c, |_| 1.0)?)
}

/// `M_K = ∫ K (1 − cos γ) dω = π ∫₀¹ (1 + 4u²v)^(−q) √(1−v) · v/(1 + √(1−v)) dv`.
pub fn kernel_moment(u: f64, c: f64) -> Result<f64, ConvError> {
    Params::new(u, c, 1.0, 1.0)?;
    Ok(PI * kernel_v_integral(u, c, |v| v / (1.0 + (1.0 - v).sqrt()))?)
}

/// `Δ_S K` at the angle `γ` from `h`, for `K = g(sin γ) cos²γ`,
/// `g(s) = (1 + a s²)^(−q)`, `a = 4u²`. With `G(γ) = g(sin γ)`:
/// `K'' = G'' cos²γ − 4 G' sin γ cos γ − 2 G (cos²γ − sin²γ)` and
/// `cot γ K' = (g'(s)/s) cos⁴γ − 2 G cos²γ`, where `G' = g'(s) cos γ`,
/// `G'' = g''(s) cos²γ − g'(s) sin γ`, `g'(s)/s = −2aq (1+as²)^(−q−1)`,
/// `g''(s) = −2aq (1+as²)^(−q−1) + 4a²q(q+1) s² (1+as²)^(−q−2)`. Finite for
/// every `γ ∈ [0, π/2]`; `Δ_S K(0) = −4(aq + 1)`.
fn kernel_laplacian(u: f64, q: f64, gamma: f64) -> f64 {
    let a = 4.0 * u * u;
    let (s, co) = gamma.sin_cos();
    let one = 1.0 + a * s * s;
    let g = one.powf(-q);
    let gp_over_s = -2.0 * a * q * one.powf(-q - 1.0);
    let gp = gp_over_s * s;
    let gpp = gp_over_s + 4.0 * a * a * q * (q + 1.0) * s * s * one.powf(-q - 2.0);
    let big_gp = gp * co;
    let big_gpp = gpp * co * co - gp * s;
    let k2 = big_gpp * co * co - 4.0 * big_gp * s * co - 2.0 * g * (co * co - s * s);
    let cot_k1 = gp_over_s * co.powi(4) - 2.0 * g * co * co;
    k2 + cot_k1
}

/// `Δ_S D` at the polar angle `θ`, from `ln D = const − z − 4 ln cos θ`,
/// `z = (tan θ/β)^(2p)`: with `F = ln D`,
/// `F' = −2pz/(sin θ cos θ) + 4 tan θ`,
/// `F'' = −2pz(2p − cos 2θ)/(sin θ cos θ)² + 4/cos²θ`,
/// `cot θ F' = −2pz/sin²θ + 4` and `Δ_S D = D (F'' + F'² + cot θ F')`.
/// At `θ = 0` the limit is `8 D(0)` for `p > 1`, `(8 − 4/β²) D(0)` for
/// `p = 1`, and `−∞` for `p < 1` (the cusp): `None`.
fn ndf_laplacian(beta: f64, p: f64, theta: f64) -> Option<f64> {
    let peak = ndf_peak(beta, p);
    let (s, co) = theta.sin_cos();
    let d = ndf_sc(beta, p, peak, s, co);
    if theta == 0.0 {
        return if p > 1.0 {
            Some(8.0 * d)
        } else if p == 1.0 {
            Some((8.0 - 4.0 / (beta * beta)) * d)
        } else {
            None
        };
    }
    if d == 0.0 {
        return Some(0.0);
    }
    let z = (2.0 * p * (s / (beta * co)).ln()).exp();
    let sc = s * co;
    let f1 = -2.0 * p * z / sc + 4.0 * s / co;
    let f2 = -2.0 * p * z * (2.0 * p - (2.0 * theta).cos()) / (sc * sc) + 4.0 / (co * co);
    let cot_f1 = -2.0 * p * z / (s * s) + 4.0;
    Some(d * (f2 + f1 * f1 + cot_f1))
}

fn check_order(order: u32) -> Result<(), ConvError> {
    if order <= 1 {
        Ok(())
    } else {
        Err(ConvError::InvalidParameter {
            name: "order",
            value: order as f64,
            expected: "0 (leading form) or 1 (first correction)",
        })
    }
}

/// Limiting form (a), kernel much narrower than `D`:
/// `C(θh) ≈ W_K D(θh)` (`order = 0`), `+ ½ M_K Δ_S D(θh)` (`order = 1`).
/// See the module documentation for its validity; the first correction is
/// not defined at `θh = 0` for `p < 1` (an error).
pub fn narrow_kernel_limit(
    theta_h: f64,
    u: f64,
    c: f64,
    beta: f64,
    p: f64,
    order: u32,
) -> Result<f64, ConvError> {
    Params::new(u, c, beta, p)?;
    Params::validate_theta(theta_h)?;
    check_order(order)?;
    let (s, co) = theta_h.sin_cos();
    let mut value = kernel_integral(u, c)? * ndf_sc(beta, p, ndf_peak(beta, p), s, co);
    if order == 1 {
        let lap = ndf_laplacian(beta, p, theta_h).ok_or(ConvError::InvalidParameter {
            name: "theta_h",
            value: theta_h,
            expected: "θh > 0 for the first-order correction when p < 1",
        })?;
        value += 0.5 * kernel_moment(u, c)? * lap;
    }
    Ok(value)
}

/// Limiting form (b), `D` much narrower than the kernel:
/// `C(θh) ≈ W_D K(θh)` (`order = 0`), `+ ½ (W_D − 1) Δ_S K(θh)` (`order = 1`).
pub fn narrow_ndf_limit(
    theta_h: f64,
    u: f64,
    c: f64,
    beta: f64,
    p: f64,
    order: u32,
) -> Result<f64, ConvError> {
    Params::new(u, c, beta, p)?;
    Params::validate_theta(theta_h)?;
    check_order(order)?;
    let q = 0.5 * (c + 1.0);
    let (s, co) = theta_h.sin_cos();
    let moment = ndf_moment(beta, p)?;
    let mut value = (1.0 + moment) * kernel_sc(u, q, s, co);
    if order == 1 {
        value += 0.5 * moment * kernel_laplacian(u, q, theta_h);
    }
    Ok(value)
}

#[cfg(test)]
pub(super) fn laplacians(u: f64, q: f64, beta: f64, p: f64, theta: f64) -> (f64, Option<f64>) {
    (kernel_laplacian(u, q, theta), ndf_laplacian(beta, p, theta))
}
