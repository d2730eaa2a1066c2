//! The normalised spherical convolution `C(θh; u, c, β, p)` of the diffraction
//! lobe with the EPD NDF (SPEC §2.5, HP17 32–33, 39–41):
//!
//! ```text
//!   C(θh; u, c, β, p) = ∫_{h·m > 0} k(2u sin∠(h,m)) cos²∠(h,m) D(m) dω_m
//!   k(x) = (1 + x²)^(−(c+1)/2),     u = (b/λ) cos θd
//! ```
//!
//! The BRDF reads `C` through the [`Convolution`] trait, so that the table
//! forms (T3b, the accurate form, by default; T3a, the paper's `s · k(2g sin θh)`
//! form, on request) are interchangeable.

use crate::math;

/// A source of `C(θh; u, c, β, p)` (SPEC §2.5).
///
/// Implementations never panic and never return NaN or ∞ for finite inputs;
/// each documents what it does outside its domain.
pub trait Convolution {
    /// `C` at `cos θh ∈ [0, 1]` (the cosine of the half vector's angle to the
    /// normal) for the kernel parameters `u ≥ 0`, `c > 1` and the NDF's
    /// `β > 0`, `p > 0`.
    fn convolution(&self, cos_theta_h: f32, u: f32, c: f32, beta: f32, p: f32) -> f32;
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
