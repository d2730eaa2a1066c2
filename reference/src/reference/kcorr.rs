//! The K-correlation (ABC) roughness spectrum and its renormalisation over the
//! disc of reachable frequencies (HP17 14-20; docs/model.md §2.4).
//!
//! ```text
//! S_HS(f) = (c − 1)/(2π) · σs² b² · (1 + b² f²)^(−(c+1)/2),   c > 1     (HP17 16)
//! σrel²(θi) = ∫_{|λ f + i_p| ≤ 1} S_HS(f) d²f                          (HP17 17-19)
//! ```
//!
//! With `B = b/λ`, `s = sin θi` and frequencies measured in units of `1/λ`,
//! the disc is `|f + (s, 0)| ≤ 1`. The origin (the peak of S_HS) lies inside
//! it, so in polar coordinates around the origin the disc reaches out to
//! `R(φ) = s cos φ + sqrt(1 − s² sin² φ)` in direction φ, and the radial
//! integral is elementary:
//!
//! ```text
//! ∫₀^R S_HS f df = σs²/(2π) · [1 − (1 + B² R²)^(−(c−1)/2)]
//! (σrel/σs)² = (1/π) ∫₀^π [1 − (1 + B² R(φ)²)^(−(c−1)/2)] dφ
//! ```
//!
//! (the integrand is even in φ). At θi = 0, `R ≡ 1` and the ratio has the
//! closed form `1 − (1 + B²)^(−(c−1)/2)`.
//!
//! `1 − x^(−e)` is evaluated as `−expm1(−e · ln1p(B²R²))`, which keeps full
//! relative accuracy as `c → 1` (`e → 0`) and as `B R → 0`.

use crate::quad::{QuadError, Tolerance, integrate};
use std::f64::consts::{FRAC_PI_2, PI};

/// Relative tolerance of the 1-D integral in [`sigma_ratio_sq`].
pub const SIGMA_RATIO_TOL: Tolerance = Tolerance::relative(1e-13);

/// The K-correlation spectrum of (HP17 16), lengths in micrometres.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct KCorrelation {
    /// RMS height σs (µm).
    pub sigma_s: f64,
    /// Correlation length scale b (µm).
    pub b: f64,
    /// Spectral exponent c (> 1).
    pub c: f64,
}

impl KCorrelation {
    /// `S_HS(f)` (µm⁴ for f in µm⁻¹): (HP17 16).
    pub fn spectrum(&self, f: f64) -> f64 {
        let bf = self.b * f;
        (self.c - 1.0) / (2.0 * PI)
            * self.sigma_s
            * self.sigma_s
            * self.b
            * self.b
            * (1.0 + bf * bf).powf(-(self.c + 1.0) / 2.0)
    }

    /// `σrel` (µm) at wavelength `lambda` (µm) and incidence `theta_i` (HP17 17-19).
    pub fn sigma_rel(&self, lambda: f64, theta_i: f64) -> Result<f64, QuadError> {
        Ok(self.sigma_s * sigma_ratio(theta_i, self.b / lambda, self.c)?)
    }
}

fn check(theta_i: f64, big_b: f64, c: f64) -> Result<(), QuadError> {
    if !(0.0..=FRAC_PI_2).contains(&theta_i) {
        return Err(QuadError::InvalidParameter {
            name: "theta_i",
            value: theta_i,
            expected: "an angle in [0, π/2]",
        });
    }
    if !(big_b > 0.0 && big_b.is_finite()) {
        return Err(QuadError::InvalidParameter {
            name: "B",
            value: big_b,
            expected: "a finite B = b/λ > 0",
        });
    }
    if !(c > 1.0 && c.is_finite()) {
        return Err(QuadError::InvalidParameter {
            name: "c",
            value: c,
            expected: "a finite exponent c > 1",
        });
    }
    Ok(())
}

/// `1 − (1 + B² R²)^(−(c−1)/2)`, the fraction of σs² within radius R of the
/// origin, accurate for small `c − 1` and small `B R`.
pub fn captured_fraction(big_b: f64, radius: f64, c: f64) -> f64 {
    let x = big_b * radius;
    -(-(c - 1.0) / 2.0 * (x * x).ln_1p()).exp_m1()
}

/// `(σrel/σs)²` at θi = 0 in closed form: `1 − (1 + B²)^(−(c−1)/2)`.
pub fn sigma_ratio_sq_normal(big_b: f64, c: f64) -> f64 {
    captured_fraction(big_b, 1.0, c)
}

/// `(σrel/σs)²(θi, B, c)` by the 1-D integral of docs/model.md §2.4, relative accuracy
/// [`SIGMA_RATIO_TOL`].
///
/// The integral is taken in `ψ = |φ − π/2|` on each half of the circle, where
/// `1 − s² sin²φ = cos²θi + s² sin²ψ` and
/// - front (φ < π/2): `R = s sin ψ + √(cos²θi + s² sin²ψ)`,
/// - back (φ > π/2): `R = cos²θi / (√(cos²θi + s² sin²ψ) + s sin ψ)` (the
///   difference `√(…) − s sin ψ`, rewritten without cancellation).
///
/// Near grazing incidence the integrand has features of width ~cos θi and
/// ~1/B at ψ = 0 (on the back half a spike of width ~B cos²θi); a global
/// adaptive rule started on [0, π/2] can miss such a spike entirely and report
/// convergence (this was measured: 1.4e-4 wrong at θi = 89.985°, B = 160,
/// c = 68). So each half is cut into geometric panels `[0, 1e-12], [1e-12,
/// 2e-12], …, [·, π/2]` (ratio 2), each integrated adaptively with an absolute
/// tolerance tied to the θi = 0 value (≤ 1e-14 relative per panel).
pub fn sigma_ratio_sq(theta_i: f64, big_b: f64, c: f64) -> Result<f64, QuadError> {
    check(theta_i, big_b, c)?;
    if theta_i == 0.0 {
        return Ok(sigma_ratio_sq_normal(big_b, c));
    }
    let (s, cos_theta) = theta_i.sin_cos();
    let cos_sq = cos_theta * cos_theta;
    let root = |psi: f64| {
        let t = s * psi.sin();
        ((cos_sq + t * t).sqrt(), t)
    };
    let front = |psi: f64| {
        let (root, t) = root(psi);
        captured_fraction(big_b, t + root, c)
    };
    let back = |psi: f64| {
        let (root, t) = root(psi);
        let denominator = root + t;
        let radius = if denominator > 0.0 {
            cos_sq / denominator
        } else {
            0.0
        };
        captured_fraction(big_b, radius, c)
    };
    // The halves sum to π·(σrel/σs)² ≥ … ; scale the absolute tolerance by the
    // normal-incidence value, which is of the same order (between ½ and 1 of it).
    let scale = PI * sigma_ratio_sq_normal(big_b, c);
    let tol = Tolerance::new(1e-14 * scale, SIGMA_RATIO_TOL.rel);
    let mut edges = vec![0.0];
    let mut edge = 1e-12;
    while edge < FRAC_PI_2 {
        edges.push(edge);
        edge *= 2.0;
    }
    edges.push(FRAC_PI_2);
    let mut total = 0.0;
    for pair in edges.windows(2) {
        total += integrate(front, pair[0], pair[1], tol)?.value;
        total += integrate(back, pair[0], pair[1], tol)?.value;
    }
    Ok(total / PI)
}

/// `σrel/σs(θi, B, c)` (HP17 17-19), the square root of [`sigma_ratio_sq`].
pub fn sigma_ratio(theta_i: f64, big_b: f64, c: f64) -> Result<f64, QuadError> {
    sigma_ratio_sq(theta_i, big_b, c).map(f64::sqrt)
}

/// `(σrel/σs)²` by a 2-D quadrature of S_HS over the disc in Cartesian
/// coordinates — an independent check of [`sigma_ratio_sq`] (slow). The disc
/// `(x + s)² + y² ≤ 1` is integrated as x outer, y inner, split at x = 0 and
/// y = 0 where the narrow peak of S_HS sits.
pub fn sigma_ratio_sq_2d(theta_i: f64, big_b: f64, c: f64) -> Result<f64, QuadError> {
    check(theta_i, big_b, c)?;
    let s = theta_i.sin();
    let spectrum = KCorrelation {
        sigma_s: 1.0,
        b: big_b,
        c,
    };
    // (σrel/σs)² ≥ 5e-5 over the table domain, and ∫dx ≤ 2: absolute
    // tolerances of 1e-18 (inner) and 1e-17 (outer) keep 1e-12 relative.
    let inner_tol = Tolerance::new(1e-18, 1e-12);
    let tol = Tolerance::new(1e-17, 1e-12);
    let mut failure = None;
    let mut outer = |x: f64| {
        let half = (1.0 - (x + s) * (x + s)).max(0.0).sqrt();
        let inner = |y: f64| spectrum.spectrum((x * x + y * y).sqrt());
        // The integrand is even in y: twice the upper half.
        match integrate(inner, 0.0, half, inner_tol) {
            Ok(e) => 2.0 * e.value,
            Err(e) => {
                failure.get_or_insert(e);
                0.0
            }
        }
    };
    let left = integrate(&mut outer, -s - 1.0, 0.0_f64.min(1.0 - s), tol)?.value;
    let right = if 1.0 - s > 0.0 {
        integrate(&mut outer, 0.0, 1.0 - s, tol)?.value
    } else {
        0.0
    };
    match failure {
        Some(e) => Err(e),
        None => Ok(left + right),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::f64::consts::FRAC_1_SQRT_2;

    fn rel(a: f64, b: f64) -> f64 {
        ((a - b) / b).abs()
    }

    /// ∫_{R²} S_HS d²f = σs² (HP17 16 is normalised).
    #[test]
    fn spectrum_integrates_to_sigma_s_squared() {
        for (b, c) in [(0.5, 1.01), (4.84, 2.3), (2.0, 10.0), (0.1, 100.0)] {
            let k = KCorrelation {
                sigma_s: 0.0273,
                b,
                c,
            };
            // Radial: 2π ∫₀^∞ S f df, in the variable t = ln(1 + b f) for the
            // heavy tail (S f ~ f^−c), evaluated in logarithms to avoid overflow.
            let tol = Tolerance::relative(1e-12);
            let log_scale = ((k.c - 1.0) * k.sigma_s * k.sigma_s).ln();
            let integrand = |t: f64| {
                // L = ln(b f) = ln(e^t − 1); ln(1 + (b f)²) without overflow.
                let log_bf = if t > 30.0 {
                    t + (-(-t).exp()).ln_1p()
                } else {
                    t.exp_m1().ln()
                };
                let log_1p_sq = if log_bf > 300.0 {
                    2.0 * log_bf + (-2.0 * log_bf).exp().ln_1p()
                } else {
                    (2.0 * log_bf).exp().ln_1p()
                };
                // 2π S f df/dt with f = (e^t − 1)/b, df/dt = e^t/b: the b² of S cancels.
                (log_scale - (k.c + 1.0) / 2.0 * log_1p_sq + log_bf + t).exp()
            };
            let total = crate::quad::integrate_to_infinity(integrand, 0.0, tol)
                .unwrap()
                .value;
            assert!(
                rel(total, k.sigma_s * k.sigma_s) < 1e-10,
                "b {b} c {c}: {total}"
            );
        }
    }

    #[test]
    fn normal_incidence_matches_the_closed_form() {
        for big_b in [0.1, 1.0, 37.0, 3000.0] {
            for c in [1.01, 1.5, 3.0, 100.0] {
                // Tiny θi goes through the quadrature; θi = 0 is the closed form.
                let near = sigma_ratio_sq(1e-9, big_b, c).unwrap();
                let exact = sigma_ratio_sq_normal(big_b, c);
                assert!(
                    rel(near, exact) < 1e-12,
                    "B {big_b} c {c}: {near} vs {exact}"
                );
            }
        }
    }

    /// The 1-D form against the independent 2-D quadrature, across the domain.
    #[test]
    fn one_d_form_matches_two_d_quadrature() {
        let mut worst: f64 = 0.0;
        for theta_i in [0.3, 1.0, 1.4, 1.55, FRAC_PI_2] {
            for big_b in [0.1, 1.0, 10.0, 100.0] {
                for c in [1.01, 2.0, 30.0] {
                    let one = sigma_ratio_sq(theta_i, big_b, c).unwrap();
                    let two = sigma_ratio_sq_2d(theta_i, big_b, c).unwrap();
                    worst = worst.max(rel(one, two));
                    assert!(
                        rel(one, two) < 1e-10,
                        "θi {theta_i} B {big_b} c {c}: {one} vs {two}"
                    );
                }
            }
        }
        eprintln!("max relative difference 1-D vs 2-D: {worst:.2e}");
    }

    /// Near-grazing points where a plain adaptive rule fails, against mpmath
    /// (30 digits, with breakpoints at the features; the script is
    /// tests/independent/sigma_ratio_mpmath.py): relative ≤ 1e-12.
    #[test]
    #[allow(clippy::approx_constant)] // 1.5707 is deliberately just below π/2
    fn near_grazing_matches_mpmath() {
        let cases = [
            (
                1.5705362727363494,
                159.5724,
                67.8512,
                0.707_009_834_595_447_9,
            ),
            (
                1.5702727280192983,
                159.5724,
                67.8512,
                0.707_047_703_195_559_8,
            ),
            (1.5707, 3000.0, 100.0, 0.707_140_986_318_133_5),
            (1.56, 2.0, 1.01, 0.068_383_021_879_924_79),
        ];
        for (theta_i, big_b, c, want) in cases {
            let got = sigma_ratio(theta_i, big_b, c).unwrap();
            assert!(
                rel(got, want) < 1e-12,
                "θi {theta_i} B {big_b} c {c}: {got} vs {want}"
            );
        }
    }

    /// Limits: B → 0 is linear in B, B → ∞ tends to 1; grazing keeps half.
    #[test]
    fn limits() {
        // Small B: S_HS is flat over the disc, so (σrel/σs)² ≈ S(0)·area/σs²
        // = (c−1)/2 · B², whatever θi ((1/π)∫₀^π R² dφ = 1 for every s).
        for theta_i in [0.0, 0.7, 1.2, FRAC_PI_2] {
            let c = 2.5;
            let big_b = 1e-4;
            let got = sigma_ratio_sq(theta_i, big_b, c).unwrap();
            let want = (c - 1.0) / 2.0 * big_b * big_b;
            assert!(rel(got, want) < 1e-6, "θi {theta_i}: {got} vs {want}");
        }
        // Large B: the whole peak of S_HS is captured, except at grazing
        // incidence, where the origin lies on the edge of the disc and only
        // half of it is: the ratio tends to 1/√2 there.
        for (theta_i, limit) in [
            (0.0, 1.0),
            (0.7, 1.0),
            (1.5, 1.0),
            (FRAC_PI_2, FRAC_1_SQRT_2),
        ] {
            let got = sigma_ratio(theta_i, 1e9, 3.0).unwrap();
            assert!((got - limit).abs() < 1e-6, "θi {theta_i}: {got}");
        }
    }

    #[test]
    fn bad_parameters_are_errors() {
        assert!(sigma_ratio(-0.1, 1.0, 2.0).is_err());
        assert!(sigma_ratio(2.0, 1.0, 2.0).is_err());
        assert!(sigma_ratio(0.5, 0.0, 2.0).is_err());
        assert!(sigma_ratio(0.5, 1.0, 1.0).is_err());
        assert!(sigma_ratio(0.5, f64::NAN, 2.0).is_err());
    }
}
