//! f64 reference of the Fresnel reflectance of a complex index (HP17 3-4),
//! the diffraction colour term Q of (HP17 10), and the diffuse Fresnel
//! reflectances of a dielectric (docs/model.md §2.3, §2.6).
//!
//! It is written independently of the runtime's `twoscale::model::fresnel`, so that
//! comparing the two means something: its own complex type (square root from
//! the polar form, where the runtime uses the half-angle formulas), and the
//! angles of (HP17 10) taken literally from `atan2` (where the runtime never
//! forms an angle). Its correctness rests on the independent checks in the
//! tests: the normal-incidence closed form, Brewster's angle, grazing
//! incidence, total internal reflection, energy conservation against the
//! transmitted wave, reciprocity, Abelès' 45° relation for conductors, the
//! double-grazing form of Q, and, for the diffuse reflectances, Stern's
//! closed form.
//!
//! One numerical choice is shared with the runtime because the textbook form
//! is wrong in f64: `c² = η² − sin²θ` is evaluated as `(η² − 1) + cos²θ` with
//! `η² − 1 = (n − 1)(n + 1) − k² + 2ink`. With `sin²θ = 1 − cos²θ` the
//! difference loses `cos²θ` entirely below ~1e-16 and is meaningless when
//! η ≈ 1 near grazing: at η = 1, cos θ = 1.6e-8 the textbook form gave
//! F = 1.3e-3 instead of 0.
//!
//! Arguments outside the physical domain (cos θ outside [0, 1], a direction
//! below the horizon, non-finite values) and the two indeterminate points
//! (η = 1 at grazing incidence, η = 0 at normal incidence) are reported as
//! [`QuadError::InvalidParameter`]; nothing here panics.

use crate::quad::{QuadError, Tolerance, integrate};
use std::f64::consts::PI;
use std::ops::{Add, Div, Mul, Neg, Sub};

/// A complex number in f64, only what this module needs.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Complex64 {
    /// Real part.
    pub re: f64,
    /// Imaginary part.
    pub im: f64,
}

impl Complex64 {
    /// `re + i im`.
    pub const fn new(re: f64, im: f64) -> Self {
        Complex64 { re, im }
    }

    /// A real number.
    pub const fn real(re: f64) -> Self {
        Complex64 { re, im: 0.0 }
    }

    /// `|z|²`.
    pub fn norm_sqr(self) -> f64 {
        self.re * self.re + self.im * self.im
    }

    /// `|z|`.
    pub fn abs(self) -> f64 {
        self.re.hypot(self.im)
    }

    /// The argument in (−π, π]; a negative real number (either sign of zero
    /// imaginary part) has argument +π.
    pub fn arg(self) -> f64 {
        if self.im == 0.0 && self.re < 0.0 {
            PI
        } else {
            self.im.atan2(self.re)
        }
    }

    /// Principal square root from the polar form, `√|z| · e^{i arg(z)/2}`
    /// (so `Re √z ≥ 0`, and `√(−x) = +i√x` for `x > 0`).
    pub fn sqrt(self) -> Self {
        let (r, half) = (self.abs().sqrt(), 0.5 * self.arg());
        Complex64::new(r * half.cos(), r * half.sin())
    }

    /// Whether both parts are finite.
    pub fn is_finite(self) -> bool {
        self.re.is_finite() && self.im.is_finite()
    }
}

impl Add for Complex64 {
    type Output = Self;
    fn add(self, o: Self) -> Self {
        Complex64::new(self.re + o.re, self.im + o.im)
    }
}

impl Sub for Complex64 {
    type Output = Self;
    fn sub(self, o: Self) -> Self {
        Complex64::new(self.re - o.re, self.im - o.im)
    }
}

impl Neg for Complex64 {
    type Output = Self;
    fn neg(self) -> Self {
        Complex64::new(-self.re, -self.im)
    }
}

impl Mul for Complex64 {
    type Output = Self;
    fn mul(self, o: Self) -> Self {
        Complex64::new(
            self.re * o.re - self.im * o.im,
            self.re * o.im + self.im * o.re,
        )
    }
}

impl Mul<f64> for Complex64 {
    type Output = Self;
    fn mul(self, s: f64) -> Self {
        Complex64::new(self.re * s, self.im * s)
    }
}

impl Div for Complex64 {
    type Output = Self;
    fn div(self, o: Self) -> Self {
        let d = o.norm_sqr();
        Complex64::new(
            (self.re * o.re + self.im * o.im) / d,
            (self.im * o.re - self.re * o.im) / d,
        )
    }
}

fn invalid(name: &'static str, value: f64, expected: &'static str) -> QuadError {
    QuadError::InvalidParameter {
        name,
        value,
        expected,
    }
}

fn check_index(eta: Complex64) -> Result<(), QuadError> {
    if !eta.re.is_finite() {
        return Err(invalid("n", eta.re, "a finite real part of the index"));
    }
    if !eta.im.is_finite() {
        return Err(invalid("k", eta.im, "a finite imaginary part of the index"));
    }
    Ok(())
}

fn check_cos(cos_theta: f64) -> Result<(), QuadError> {
    if !(0.0..=1.0).contains(&cos_theta) {
        return Err(invalid("cos_theta", cos_theta, "a cosine in [0, 1]"));
    }
    Ok(())
}

/// The reflectances of the s- and p-polarised waves, `(Fs, Fp)`, at the
/// interface from outside (index 1) into a material of complex index η, at
/// incidence `cos θ` (HP17 4):
///
/// ```text
/// c  = (η² − sin²θ)^½ = ((η² − 1) + cos²θ)^½      (principal root)
/// Fs = |(cos θ − c) / (cos θ + c)|²,   Fp = |(η² cos θ − c) / (η² cos θ + c)|²
/// ```
///
/// Errors: non-finite η, cos θ outside [0, 1], and the indeterminate 0/0 at
/// η² = 1, cos θ = 0 and at η = 0, cos θ = 1.
pub fn fresnel_sp(eta: Complex64, cos_theta: f64) -> Result<(f64, f64), QuadError> {
    check_index(eta)?;
    check_cos(cos_theta)?;
    let eta_sq = eta * eta;
    let c = root(eta, cos_theta);
    let cos = Complex64::real(cos_theta);
    let rs = (cos - c) / (cos + c);
    let rp = (eta_sq * cos_theta - c) / (eta_sq * cos_theta + c);
    let (fs, fp) = (rs.norm_sqr(), rp.norm_sqr());
    if !(fs.is_finite() && fp.is_finite()) {
        return Err(invalid(
            "eta",
            eta.abs(),
            "an index whose Fresnel factor is defined at this angle (not η = 1 at grazing, not η = 0 at normal incidence)",
        ));
    }
    Ok((fs, fp))
}

/// `η² − 1`, as `(n − 1)(n + 1) − k² + 2ink` (exact cancellation near η = 1).
fn eta_sq_minus_one(eta: Complex64) -> Complex64 {
    Complex64::new(
        (eta.re - 1.0) * (eta.re + 1.0) - eta.im * eta.im,
        2.0 * eta.re * eta.im,
    )
}

/// `c = (η² − sin²θ)^½`, principal root, as `((η² − 1) + cos²θ)^½` (see the
/// module documentation).
fn root(eta: Complex64, cos_theta: f64) -> Complex64 {
    (eta_sq_minus_one(eta) + Complex64::real(cos_theta * cos_theta)).sqrt()
}

/// Unpolarised Fresnel reflectance `F = (Fs + Fp)/2` (HP17 3); see [`fresnel_sp`].
pub fn fresnel(eta: Complex64, cos_theta: f64) -> Result<f64, QuadError> {
    let (fs, fp) = fresnel_sp(eta, cos_theta)?;
    Ok(0.5 * (fs + fp))
}

/// The normal-incidence reflectance of `n + ik`, in closed form:
/// `((n − 1)² + k²) / ((n + 1)² + k²)`.
pub fn fresnel_normal(n: f64, k: f64) -> f64 {
    ((n - 1.0) * (n - 1.0) + k * k) / ((n + 1.0) * (n + 1.0) + k * k)
}

/// Spherical coordinates `(θ, φ)` of a direction in the upper hemisphere
/// (horizon included), from `atan2`.
fn spherical(v: [f64; 3], name: &'static str) -> Result<(f64, f64), QuadError> {
    let [x, y, z] = v;
    let len = (x * x + y * y + z * z).sqrt();
    if !(len > 0.0 && len.is_finite()) {
        return Err(invalid(name, len, "a non-zero finite direction"));
    }
    if z < 0.0 {
        return Err(invalid(name, z, "a direction with z >= 0"));
    }
    Ok((x.hypot(y).atan2(z), y.atan2(x)))
}

/// Q of (HP17 10), the Rayleigh–Rice polarisation factor summed over the four
/// polarisation channels, for incident direction `i` and outgoing direction
/// `o` (upper hemisphere, any length), computed literally from the spherical
/// angles `θ = atan2(√(x² + y²), z)`, `φ = atan2(y, x)` (with `ci`, `co` as in
/// [`fresnel_sp`]):
///
/// ```text
/// φ   = φo − φi − π,      ci = (η² − sin²θi)^½,      co = (η² − sin²θo)^½
/// q0  = (η² − 1)(cos θi + ci)⁻¹          q1 = (η² − 1)(η² cos θi + ci)⁻¹
/// q2  = (cos θo + co)⁻¹                  q3 = (η² cos θo + co)⁻¹
/// Qss = q0 q2 cos φ                      Qsp = q0 q3 co sin φ
/// Qps = q1 q2 ci sin φ                   Qpp = q1 q3 (ci co cos φ − η² sin θi sin θo)
/// Q   = |Qss|² + |Qsp|² + |Qps|² + |Qpp|²                              (HP17 10)
/// ```
///
/// Errors: as [`fresnel_sp`], and for directions below the horizon or of zero
/// length.
pub fn q(eta: Complex64, i: [f64; 3], o: [f64; 3]) -> Result<f64, QuadError> {
    check_index(eta)?;
    let (theta_i, phi_i) = spherical(i, "i")?;
    let (theta_o, phi_o) = spherical(o, "o")?;
    let phi = phi_o - phi_i - PI;
    let (eta_sq, e) = (eta * eta, eta_sq_minus_one(eta));
    let one = Complex64::real(1.0);
    let (ci, co) = (root(eta, theta_i.cos()), root(eta, theta_o.cos()));
    let q0 = e / (Complex64::real(theta_i.cos()) + ci);
    let q1 = e / (eta_sq * theta_i.cos() + ci);
    let q2 = one / (Complex64::real(theta_o.cos()) + co);
    let q3 = one / (eta_sq * theta_o.cos() + co);
    let qss = q0 * q2 * phi.cos();
    let qsp = q0 * q3 * co * phi.sin();
    let qps = q1 * q2 * ci * phi.sin();
    let qpp = q1 * q3 * (ci * co * phi.cos() - eta_sq * (theta_i.sin() * theta_o.sin()));
    let value = qss.norm_sqr() + qsp.norm_sqr() + qps.norm_sqr() + qpp.norm_sqr();
    if !value.is_finite() {
        return Err(invalid(
            "eta",
            eta.abs(),
            "an index whose Q is defined at these directions (not η = 1 at grazing)",
        ));
    }
    Ok(value)
}

/// `Q̄ = Q/2`, the colour term for unpolarised light (docs/model.md §2.3); see [`q`].
pub fn q_bar(eta: Complex64, i: [f64; 3], o: [f64; 3]) -> Result<f64, QuadError> {
    Ok(0.5 * q(eta, i, o)?)
}

/// Tolerance of the diffuse-reflectance integrals (absolute part: the values
/// are O(1) and vanish at η = 1).
pub const DIFFUSE_TOL: Tolerance = Tolerance::new(1e-15, 1e-13);

/// The diffuse (cosine-weighted hemispherical) reflectance of the interface
/// into a real relative index `eta_rel > 0`, by adaptive quadrature:
///
/// ```text
/// F_dr(η_rel) = 2 ∫₀¹ F(η_rel, μ) μ dμ
/// ```
///
/// For `η_rel < 1` the integral is split at the critical cosine
/// `μc = √(1 − η_rel²)`: below it F = 1 (total internal reflection), above it
/// F has a square-root kink at μc, which the adaptive rule resolves from the
/// endpoint.
pub fn diffuse_reflectance(eta_rel: f64) -> Result<f64, QuadError> {
    if !(eta_rel > 0.0 && eta_rel.is_finite()) {
        return Err(invalid("eta", eta_rel, "a finite real index > 0"));
    }
    let eta = Complex64::real(eta_rel);
    let mut failure = None;
    let mut integrand = |mu: f64| match fresnel(eta, mu) {
        Ok(f) => 2.0 * f * mu,
        Err(e) => {
            failure.get_or_insert(e);
            f64::NAN
        }
    };
    let mu_c = if eta_rel < 1.0 {
        ((1.0 - eta_rel) * (1.0 + eta_rel)).sqrt()
    } else {
        0.0
    };
    let mut total = 0.0;
    for (a, b) in [(0.0, mu_c), (mu_c, 1.0)] {
        match integrate(&mut integrand, a, b, DIFFUSE_TOL) {
            Ok(estimate) => total += estimate.value,
            Err(e) => return Err(failure.unwrap_or(e)),
        }
    }
    Ok(total)
}

/// The internal diffuse Fresnel reflectance of a dielectric of index η ≥ 1,
/// seen from inside: `F_dr,int(η) = F_dr(1/η) = 2 ∫₀¹ F(1/η, μ) μ dμ`
/// (docs/model.md §2.6, HP17 43), by quadrature ([`diffuse_reflectance`]).
pub fn diffuse_internal(eta: f64) -> Result<f64, QuadError> {
    if !(eta >= 1.0 && eta.is_finite()) {
        return Err(invalid("eta", eta, "a finite real index >= 1"));
    }
    diffuse_reflectance(1.0 / eta)
}

/// The external diffuse reflectance `F_dr,ext(η) = F_dr(η)` of a dielectric of
/// index η > 1 in closed form (Stern, *Transmission of isotropic radiation
/// across an interface between two dielectrics*, Appl. Opt. 3(1):111–113,
/// 1964; the form quoted by later authors):
///
/// ```text
/// F_dr,ext = 1/2 + (η − 1)(3η + 1) / (6(η + 1)²)
///          + η²(η² − 1)² / (η² + 1)³ · ln((η − 1)/(η + 1))
///          − 2η³(η² + 2η − 1) / ((η² + 1)(η⁴ − 1))
///          + 8η⁴(η⁴ + 1) / ((η² + 1)(η⁴ − 1)²) · ln η
/// ```
///
/// It is used only as an independent check of the quadrature. Its terms
/// diverge like `(η − 1)⁻²` and cancel as η → 1, so it loses about
/// `10⁻¹⁶/(η − 1)²` in absolute accuracy: use it for η ≥ 1.01.
pub fn diffuse_external_closed_form(eta: f64) -> f64 {
    let (n2, n3, n4) = (eta * eta, eta * eta * eta, eta * eta * eta * eta);
    0.5 + (eta - 1.0) * (3.0 * eta + 1.0) / (6.0 * (eta + 1.0) * (eta + 1.0))
        + n2 * (n2 - 1.0).powi(2) / (n2 + 1.0).powi(3) * ((eta - 1.0) / (eta + 1.0)).ln()
        - 2.0 * n3 * (n2 + 2.0 * eta - 1.0) / ((n2 + 1.0) * (n4 - 1.0))
        + 8.0 * n4 * (n4 + 1.0) / ((n2 + 1.0) * (n4 - 1.0).powi(2)) * eta.ln()
}

/// The internal diffuse reflectance from the external one:
///
/// ```text
/// F_dr,int(η) = 1 − (1 − F_dr,ext(η)) / η²
/// ```
///
/// Derivation: the transmittance `1 − F` of the interface is the same for the
/// two directions of a refracted pair, `F(1/η, cos θt) = F(η, cos θi)` with
/// `sin θi = η sin θt` (Stokes reciprocity; checked in the tests), and
/// differentiating `1 − cos²θt = (1 − cos²θi)/η²` gives
/// `cos θt d(cos θt) = cos θi d(cos θi)/η²`. Inside, only the cone outside
/// total internal reflection transmits, and it maps onto the whole outer
/// hemisphere, so
/// `1 − F_dr,int = 2 ∫ (1 − F(1/η, μt)) μt dμt = (1/η²) · 2 ∫₀¹ (1 − F(η, μi)) μi dμi
/// = (1 − F_dr,ext)/η²`.
pub fn internal_from_external(eta: f64, external: f64) -> f64 {
    1.0 - (1.0 - external) / (eta * eta)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn c(re: f64, im: f64) -> Complex64 {
        Complex64::new(re, im)
    }

    /// Materials spanning the project's range: dielectrics above and below
    /// 1, and conductors.
    const INDICES: [(f64, f64); 9] = [
        (1.5, 0.0),
        (1.0 / 1.5, 0.0),
        (0.05, 0.0),
        (10.0, 0.0),
        (0.203958032, 3.16688023),
        (1.2, 7.26),
        (0.05, 20.0),
        (10.0, 20.0),
        (2.9, 3.1),
    ];

    #[test]
    fn square_root_is_principal() {
        for z in [
            c(4.0, 0.0),
            c(-4.0, 0.0),
            c(-4.0, -0.0),
            c(3.0, -4.0),
            c(-3.0, 4.0),
            c(-3.0, -4.0),
            c(0.0, 1e-20),
        ] {
            let s = z.sqrt();
            assert!(s.re >= 0.0);
            let back = s * s;
            assert!((back - z).abs() <= 1e-15 * z.abs(), "{z:?}");
        }
        assert_eq!(c(-4.0, -0.0).sqrt().im, 2.0);
    }

    #[test]
    fn normal_incidence_closed_form() {
        for (n, k) in INDICES {
            let got = fresnel(c(n, k), 1.0).unwrap();
            let want = fresnel_normal(n, k);
            assert!((got - want).abs() < 1e-15, "{n}+{k}i: {got} vs {want}");
        }
    }

    #[test]
    fn brewster_angle_zeroes_fp() {
        for n in [1.1f64, 1.5, 2.4, 10.0, 0.7, 0.2] {
            let cos_b = 1.0 / (1.0 + n * n).sqrt();
            let (fs, fp) = fresnel_sp(c(n, 0.0), cos_b).unwrap();
            assert!(fp < 1e-26, "n {n}: Fp {fp}");
            let want = ((1.0 - n * n) / (1.0 + n * n)).powi(2);
            assert!((fs - want).abs() < 1e-14, "n {n}: Fs {fs} vs {want}");
        }
    }

    #[test]
    fn grazing_incidence_reflects_everything() {
        for (n, k) in INDICES {
            assert!((fresnel(c(n, k), 0.0).unwrap() - 1.0).abs() < 1e-15);
            // 1 − F is linear in cos θ near grazing (0 for η < 1: total
            // internal reflection).
            let near = 1.0 - fresnel(c(n, k), 1e-9).unwrap();
            assert!((0.0..1e-7).contains(&near), "{n}+{k}i: 1 − F = {near}");
            assert_eq!(near > 0.0, n > 1.0 || k > 0.0);
        }
        assert!(fresnel(c(1.0, 0.0), 0.0).is_err());
        assert!(fresnel(c(0.0, 0.0), 1.0).is_err());
        assert!(fresnel(c(1.5, 0.0), 1.1).is_err());
        assert!(fresnel(c(f64::NAN, 0.0), 0.5).is_err());
    }

    #[test]
    fn total_internal_reflection() {
        for n in [0.05f64, 0.3, 1.0 / 1.5, 0.99] {
            let cos_c = ((1.0 - n) * (1.0 + n)).sqrt();
            for t in [0.0, 0.3, 0.9, 0.999999] {
                let f = fresnel(c(n, 0.0), t * cos_c).unwrap();
                assert!((f - 1.0).abs() < 1e-15, "n {n} cos {}: {f}", t * cos_c);
            }
            assert!(fresnel(c(n, 0.0), cos_c + 1e-3 * (1.0 - cos_c)).unwrap() < 1.0);
        }
    }

    /// `Fs + Ts = 1` and `Fp + Tp = 1` for dielectrics, with the transmitted
    /// wave computed from Snell's law: `ts = 2 cos θi / (cos θi + η cos θt)`,
    /// `tp = 2 cos θi / (η cos θi + cos θt)`, `T = η cos θt / cos θi · |t|²`.
    #[test]
    fn energy_is_conserved_for_dielectrics() {
        for n in [1.0001, 1.33, 1.5, 2.4, 10.0, 0.5, 0.9] {
            for k in 1..=99 {
                let cos_i = k as f64 / 100.0;
                let sin_t = (1.0f64 - cos_i * cos_i).sqrt() / n;
                if sin_t >= 1.0 {
                    continue;
                }
                let cos_t = (1.0 - sin_t * sin_t).sqrt();
                let ts = 2.0 * cos_i / (cos_i + n * cos_t);
                let tp = 2.0 * cos_i / (n * cos_i + cos_t);
                let factor = n * cos_t / cos_i;
                let (fs, fp) = fresnel_sp(c(n, 0.0), cos_i).unwrap();
                // Both sides lose ~ε/|η² − sin²θ| near grazing when η ≈ 1
                // (4.6e-14 at η = 1.0001, cos θ = 0.01).
                assert!(
                    (fs + factor * ts * ts - 1.0).abs() < 1e-13,
                    "s: n {n} cos {cos_i}"
                );
                assert!(
                    (fp + factor * tp * tp - 1.0).abs() < 1e-13,
                    "p: n {n} cos {cos_i}"
                );
            }
        }
    }

    /// The reflectance is the same from both sides of a refracted pair:
    /// `F(η, cos θi) = F(1/η, cos θt)`, `sin θi = η sin θt` (per polarisation).
    #[test]
    fn reflectance_is_reciprocal_across_the_interface() {
        for n in [1.2, 1.5, 3.0] {
            // Not at cos θi = 0: θt is then exactly critical, where F(1/η, ·)
            // has a square-root kink that turns the rounding of cos θt into 1e-7.
            // Near it, the rounding of cos θt costs ~ε/(cos θi/η)² (1e-13 at
            // η = 3, cos θi = 0.05).
            for k in 1..=20 {
                let cos_i = k as f64 / 20.0;
                let sin_t = (1.0f64 - cos_i * cos_i).sqrt() / n;
                let cos_t = (1.0 - sin_t * sin_t).sqrt();
                let (a, b) = (
                    fresnel_sp(c(n, 0.0), cos_i).unwrap(),
                    fresnel_sp(c(1.0 / n, 0.0), cos_t).unwrap(),
                );
                assert!(
                    (a.0 - b.0).abs() < 1e-12 && (a.1 - b.1).abs() < 1e-12,
                    "n {n} cos {cos_i}"
                );
            }
        }
    }

    /// Conductors: Abelès' relation `Rp = Rs²` at 45° holds for every complex
    /// index (Abelès 1950), F → 1 at grazing, and Fp has a single minimum (the
    /// principal angle) between normal and grazing incidence while Fs rises.
    /// Gold at λ = 0.6 µm: n = 0.203958032, k = 3.16688023 (Yakubovsky et al.,
    /// Opt. Express 25:25574, 2017, 117 nm film, as tabulated in the
    /// refractiveindex.info database); its normal-incidence reflectance is
    /// 0.928926…, the usual ≈ 93% of gold in the red.
    #[test]
    fn conductors() {
        let cos45 = 0.5f64.sqrt();
        for (n, k) in INDICES {
            let (fs, fp) = fresnel_sp(c(n, k), cos45).unwrap();
            assert!(
                (fp - fs * fs).abs() < 1e-14,
                "{n}+{k}i: Fp {fp} vs Fs² {}",
                fs * fs
            );
        }
        let gold = c(0.203958032, 3.16688023);
        let r0 = fresnel(gold, 1.0).unwrap();
        assert!((r0 - 0.928926).abs() < 1e-6, "gold R0 = {r0}");
        let samples: Vec<(f64, f64)> = (0..=900)
            .map(|k| fresnel_sp(gold, (k as f64 / 10.0).to_radians().cos()).unwrap())
            .collect();
        assert!(samples.windows(2).all(|w| w[1].0 >= w[0].0 - 1e-15));
        let minimum = samples
            .iter()
            .enumerate()
            .min_by(|a, b| a.1.1.total_cmp(&b.1.1))
            .unwrap()
            .0;
        assert!(
            (700..890).contains(&minimum),
            "principal angle at {minimum}"
        );
        assert!(samples[..minimum].windows(2).all(|w| w[1].1 <= w[0].1));
        assert!(samples[minimum..].windows(2).all(|w| w[1].1 >= w[0].1));
    }

    /// In the specular direction Q = 2F (HP17 §3.2.1), at every angle and
    /// azimuth; at normal incidence Q does not depend on the azimuth.
    #[test]
    fn q_is_twice_fresnel_in_the_specular_direction() {
        for (n, k) in INDICES {
            let eta = c(n, k);
            for deg in [0.0f64, 5.0, 30.0, 60.0, 80.0, 89.0, 89.999] {
                for phi in [0.0f64, 1.0, -2.5] {
                    let (s, z) = deg.to_radians().sin_cos();
                    let i = [s * phi.cos(), s * phi.sin(), z];
                    let o = [-i[0], -i[1], z];
                    let (qv, f) = (q(eta, i, o).unwrap(), fresnel(eta, z).unwrap());
                    assert!(
                        (qv - 2.0 * f).abs() < 1e-12,
                        "{n}+{k}i θ {deg}: {qv} vs {}",
                        2.0 * f
                    );
                }
            }
            let normal = q(eta, [0.0, 0.0, 1.0], [0.6, 0.0, 0.8]).unwrap();
            for phi in [0.5f64, 2.0, 3.0] {
                let o = [0.6 * phi.cos(), 0.6 * phi.sin(), 0.8];
                assert!((q(eta, [0.0, 0.0, 1.0], o).unwrap() - normal).abs() < 1e-12 * normal);
            }
        }
    }

    /// At double grazing incidence (HP17 10) reduces to
    /// `Q = cos²φ + 2|η² − 1| sin²φ + |(η² − 1) cos φ − η²|²`.
    #[test]
    fn q_at_double_grazing() {
        for (n, k) in INDICES {
            let eta = c(n, k);
            let eta_sq = eta * eta;
            let e = eta_sq - Complex64::real(1.0);
            for phi in [0.0f64, 0.4, 1.7, 3.0, PI] {
                let po = phi + PI;
                let got = q(eta, [1.0, 0.0, 0.0], [po.cos(), po.sin(), 0.0]).unwrap();
                let want = phi.cos().powi(2)
                    + 2.0 * e.abs() * phi.sin().powi(2)
                    + (e * phi.cos() - eta_sq).norm_sqr();
                assert!(
                    (got - want).abs() < 1e-12 * want,
                    "{n}+{k}i φ {phi}: {got} vs {want}"
                );
            }
        }
        assert!(q(c(1.5, 0.0), [0.0, 0.0, -1.0], [0.0, 0.0, 1.0]).is_err());
        assert!(q(c(1.5, 0.0), [0.0, 0.0, 0.0], [0.0, 0.0, 1.0]).is_err());
        assert_eq!(
            q(c(1.0, 0.0), [0.6, 0.0, 0.8], [0.0, 0.6, 0.8]).unwrap(),
            0.0
        );
    }

    /// The quadrature against Stern's closed form (external) and the identity
    /// `F_dr,int = 1 − (1 − F_dr,ext)/η²` (internal); mpmath values at 30
    /// digits for two points.
    #[test]
    fn diffuse_reflectances() {
        for k in 0..=40 {
            let eta = 1.01 + 1.99 * k as f64 / 40.0;
            let external = diffuse_reflectance(eta).unwrap();
            let closed = diffuse_external_closed_form(eta);
            assert!(
                (external - closed).abs() < 1e-13,
                "η {eta}: {external} vs {closed}"
            );
            let internal = diffuse_internal(eta).unwrap();
            let identity = internal_from_external(eta, closed);
            assert!(
                (internal - identity).abs() < 1e-13,
                "η {eta}: {internal} vs {identity}"
            );
        }
        // mpmath (30 digits, quadrature split at the critical angle).
        for (eta, want) in [
            (1.01, 0.022788258682828597),
            (1.5, 0.596_345_759_707_711_6),
            (3.0, 0.919_578_156_666_389_2),
        ] {
            let got = diffuse_internal(eta).unwrap();
            assert!((got - want).abs() < 1e-14, "η {eta}: {got} vs {want}");
        }
        assert!(diffuse_internal(1.0).unwrap().abs() < 1e-20);
        // Near η = 1: F_dr,int ≈ (7/3)(η − 1), the total-internal-reflection
        // cone 2(η − 1) plus F_dr,ext ≈ (η − 1)/3 (mpmath: 2.333323 at 1e-6).
        let small = diffuse_internal(1.0 + 1e-6).unwrap();
        assert!((small / (7.0 / 3.0 * 1e-6) - 1.0).abs() < 1e-4, "{small}");
        assert!(diffuse_internal(0.9).is_err());
        assert!(diffuse_reflectance(f64::NAN).is_err());
    }
}
