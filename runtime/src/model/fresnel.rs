//! Fresnel reflectance of a complex index of refraction (HP17 3-4) and the
//! colour term Q̄ of the diffraction lobe (HP17 10) (docs/model.md §2.3).
//!
//! # The index of refraction
//!
//! [`Complex`] holds the relative index `η = n + i k` of the material (outside
//! medium: index 1). `k = 0` is a dielectric (`η < 1` included, with total
//! internal reflection), `k > 0` a conductor. Both functions depend on η only
//! through η² and are unchanged by `η → −η` and by `η → η̄` (every term is then
//! conjugated), so they use `|n|` and `|k|`; NaN counts as 0, and `|n|`, `|k|`
//! are capped at 10⁹ (beyond which F differs from 1 by less than 4·10⁻⁹ and
//! Q̄ ≤ 2|η|⁴ would overflow f32). Two degenerate indices are defined by their
//! limits: `η = ±1` (no interface) gives F = 0 and Q̄ = 0 at every angle, and
//! `|η| < 10⁻¹⁰` is evaluated at `η = 10⁻¹⁰` (F → 1 as η → 0).
//!
//! # Precision
//!
//! The f32 API computes internally in f64: the same formulas evaluated in f32
//! were measured at 1.9·10⁻⁵ absolute error (n = 0.23, k = 0, near the
//! critical angle, where `c = √(η² − sin²θ)` vanishes), above the 10⁻⁵ the
//! project asks for; in f64 the only error left is the final rounding to f32.
//!
//! T5, the diffuse Fresnel reflectance of the plastic base, is read by
//! [`crate::tables::diffuse_fresnel`].

use crate::math::{self, Complex};
use core::ops::{Add, Div, Mul, Sub};

/// Largest |n| and |k| used (larger values are capped).
const INDEX_MAX: f64 = 1e9;
/// Smallest |η| used (smaller indices are evaluated at this real index).
const INDEX_MIN: f64 = 1e-10;

/// f64 complex arithmetic, only what the formulas below need.
#[derive(Clone, Copy, Debug, PartialEq)]
struct C64 {
    re: f64,
    im: f64,
}

impl C64 {
    const fn new(re: f64, im: f64) -> C64 {
        C64 { re, im }
    }

    const fn real(re: f64) -> C64 {
        C64 { re, im: 0.0 }
    }

    /// `|z|²`.
    fn norm_sqr(self) -> f64 {
        self.re * self.re + self.im * self.im
    }

    /// Principal square root (`Re √z ≥ 0`; on the negative real axis the
    /// result is `+i√|z|`, whatever the sign of a zero imaginary part).
    ///
    /// With `r = |z|`: for `Re z ≥ 0`, `t = √((r + Re z)/2)` and
    /// `√z = t + i Im z/(2t)`; for `Re z < 0`, `t = √((r − Re z)/2)` and
    /// `√z = |Im z|/(2t) ± i t` (sign of `Im z`). Both forms avoid the
    /// cancellation of `r − |Re z|`.
    fn sqrt(self) -> C64 {
        let (x, y) = (self.re, self.im);
        if x == 0.0 && y == 0.0 {
            return C64::real(0.0);
        }
        // |z| as √(x² + y²) where that is exact to rounding (every `Index`
        // gives such z), `hypot` where the squares would under- or overflow.
        let n = x * x + y * y;
        let r = if (1e-290..=1e300).contains(&n) {
            math::sqrt(n)
        } else {
            math::hypot(x, y)
        };
        if x >= 0.0 {
            let t = math::sqrt(0.5 * (r + x));
            C64::new(t, y / (2.0 * t))
        } else {
            let t = math::sqrt(0.5 * (r - x));
            C64::new(math::abs(y) / (2.0 * t), if y < 0.0 { -t } else { t })
        }
    }
}

impl Add for C64 {
    type Output = C64;
    fn add(self, o: C64) -> C64 {
        C64::new(self.re + o.re, self.im + o.im)
    }
}

impl Sub for C64 {
    type Output = C64;
    fn sub(self, o: C64) -> C64 {
        C64::new(self.re - o.re, self.im - o.im)
    }
}

impl Mul for C64 {
    type Output = C64;
    fn mul(self, o: C64) -> C64 {
        C64::new(
            self.re * o.re - self.im * o.im,
            self.re * o.im + self.im * o.re,
        )
    }
}

impl Mul<f64> for C64 {
    type Output = C64;
    fn mul(self, s: f64) -> C64 {
        C64::new(self.re * s, self.im * s)
    }
}

impl Div for C64 {
    type Output = C64;
    /// `a / b = a b̄ / |b|²`; callers guarantee `b ≠ 0` (see [`Index`]).
    fn div(self, o: C64) -> C64 {
        let d = o.norm_sqr();
        C64::new(
            (self.re * o.re + self.im * o.im) / d,
            (self.im * o.re - self.re * o.im) / d,
        )
    }
}

/// A sanitised index: `η²` and `e = η² − 1`.
///
/// With `n, k ≥ 0` and `η² ≠ 1` no denominator of the formulas vanishes:
/// `cos θ + c = 0` needs `c = 0 = cos θ`, i.e. `η² = sin²θ = 1`; and
/// `η² cos θ + c = 0` needs `c² = η⁴ cos²θ`, i.e. `(η² − 1)(η² cos²θ − sin²θ) = 0`,
/// whose second factor makes `η²` real and positive, where the principal root
/// is `c = +η² cos θ`, not `−η² cos θ` (η = 0 is excluded by [`INDEX_MIN`]).
#[derive(Clone, Copy, Debug)]
struct Index {
    eta_sq: C64,
    /// `η² − 1`, as `(n − 1)(n + 1) − k² + 2ink` (no cancellation near η = 1).
    e: C64,
}

impl Index {
    /// The sanitised index (module documentation), or `None` for `η² = 1`.
    fn new(eta: Complex) -> Option<Index> {
        let part = |x: f32| f64::from(x).abs().max(0.0).min(INDEX_MAX);
        let (mut n, k) = (part(eta.re), part(eta.im));
        if n * n + k * k < INDEX_MIN * INDEX_MIN {
            n = INDEX_MIN;
        }
        let e = C64::new((n - 1.0) * (n + 1.0) - k * k, 2.0 * n * k);
        if e.re == 0.0 && e.im == 0.0 {
            return None;
        }
        Some(Index {
            eta_sq: C64::new(n * n - k * k, 2.0 * n * k),
            e,
        })
    }

    /// `c = √(η² − sin²θ)`, principal root, computed as `√(η² − 1 + cos²θ)`.
    fn c(&self, cos_theta: f64) -> C64 {
        (self.e + C64::real(cos_theta * cos_theta)).sqrt()
    }

    /// F of [`fresnel`] at `cos θ ∈ [0, 1]`, in f64 (not clamped).
    fn reflectance(&self, cos: f64) -> f64 {
        let c = self.c(cos);
        // Fs + Fp = |a − c|²/|a + c|² + |b − c|²/|b + c|² over one division:
        // each |·|² lies within ≈ [1e-40, 2.3e36] (|η| ∈ [INDEX_MIN,
        // INDEX_MAX]; 2·10⁶ sampled indices and angles), so the products are
        // finite and not 0.
        let a = C64::real(cos);
        let b = self.eta_sq * cos;
        let (na, da) = ((a - c).norm_sqr(), (a + c).norm_sqr());
        let (nb, db) = ((b - c).norm_sqr(), (b + c).norm_sqr());
        0.5 * (na * db + nb * da) / (da * db)
    }
}

/// Unpolarised Fresnel reflectance of the interface from outside (index 1)
/// into a material of complex index `η = n + i k`, at incidence `cos θ`
/// (HP17 3-4; docs/model.md §2.3):
///
/// ```text
/// c  = (η² − sin²θ)^½          (principal root)
/// Fs = |(cos θ − c) / (cos θ + c)|²
/// Fp = |(η² cos θ − c) / (η² cos θ + c)|²
/// F  = (Fs + Fp) / 2                                             (HP17 3-4)
/// ```
///
/// A real η is a dielectric; for `η < 1` and `sin θ ≥ η`, c is imaginary and
/// F = 1 (total internal reflection). F ∈ [0, 1]; F = 1 at grazing incidence
/// for every η ≠ 1.
///
/// Guards: `cos θ` is clamped to [0, 1] (`cos θ ≤ 0` or NaN is grazing
/// incidence, F = 1; `cos θ > 1` is normal incidence). Index conventions and
/// the degenerate indices (η = 1 gives 0) are in the module documentation.
/// Never NaN, never panics; computed in f64.
pub fn fresnel(eta: Complex, cos_theta: f32) -> f32 {
    let Some(index) = Index::new(eta) else {
        return 0.0;
    };
    let cos = f64::from(cos_theta.max(0.0).min(1.0));
    (index.reflectance(cos) as f32).max(0.0).min(1.0)
}

/// Panel ends of [`fresnel_average`]'s rule in `s/S`, graded towards grazing.
const AVERAGE_PANELS: [f64; 7] = [
    0.0,
    1.0 / 32.0,
    1.0 / 16.0,
    1.0 / 8.0,
    1.0 / 4.0,
    1.0 / 2.0,
    1.0,
];

/// 8-point Gauss–Legendre nodes and weights on [−1, 1] (positive half).
const GAUSS_8: [(f64, f64); 4] = [
    (0.183_434_642_495_649_8, 0.362_683_783_378_362),
    (0.525_532_409_916_329, 0.313_706_645_877_887_3),
    (0.796_666_477_413_626_7, 0.222_381_034_453_374_5),
    (0.960_289_856_497_536_3, 0.101_228_536_290_376_3),
];

/// The cosine-weighted hemispherical average of [`fresnel`] (the
/// energy-compensation lobe's `F_avg`, docs/model.md §2.11):
///
/// ```text
/// F_avg(η) = 2 ∫₀¹ F(η, μ) μ dμ
/// ```
///
/// in f64 with `μ = μc + s²`, `s ∈ [0, S]`, `S = √(1 − μc)` (`μc` the
/// critical cosine `√(1 − η²)` of a real `η < 1`, below which F = 1; else 0),
/// which makes the integrand smooth at `μc` (F has a square-root edge
/// there), by 8-point Gauss–Legendre on 6 panels graded towards `s = 0`:
/// within 1e-9 of an adaptive quadrature of the f64 reference for the
/// presets' conductors, dielectrics (η = 1.001 … 3) and `η < 1` (test
/// `fresnel_average_matches_the_reference` in tests/energy.rs). 0 for
/// η = 1; never NaN.
pub fn fresnel_average(eta: Complex) -> f64 {
    let Some(index) = Index::new(eta) else {
        return 0.0;
    };
    // F ≡ 1 below the critical cosine of a real index below 1.
    let critical = if index.eta_sq.im == 0.0 && index.eta_sq.re < 1.0 {
        math::sqrt((1.0 - index.eta_sq.re).max(0.0)).min(1.0)
    } else {
        0.0
    };
    let span = math::sqrt(1.0 - critical);
    let mut total = critical * critical;
    for w in AVERAGE_PANELS.windows(2) {
        let (mid, half) = (0.5 * (w[0] + w[1]) * span, 0.5 * (w[1] - w[0]) * span);
        for (x, weight) in GAUSS_8 {
            for s in [mid - half * x, mid + half * x] {
                let mu = critical + s * s;
                // 2 F μ dμ, dμ = 2 s ds.
                let f = index.reflectance(mu).max(0.0).min(1.0);
                total += half * weight * 4.0 * f * mu * s;
            }
        }
    }
    total.max(0.0).min(1.0)
}

/// A direction reduced to what eq. 10 needs: `cos θ`, `sin θ` and the unit
/// tangential direction `(cos φ, sin φ)` scaled by `sin θ`, i.e. `(x, y)`.
#[derive(Clone, Copy, Debug)]
struct Direction {
    cos: f64,
    x: f64,
    y: f64,
}

impl Direction {
    /// Normalises `v`; a direction below the horizon is moved onto it
    /// (azimuth kept; straight down becomes `+x`); a zero or non-finite vector
    /// is taken as the normal.
    fn new(v: [f32; 3]) -> Direction {
        let [x, y, z] = v.map(f64::from);
        let len = math::sqrt(x * x + y * y + z * z);
        if !(len > 0.0 && len.is_finite()) {
            return Direction {
                cos: 1.0,
                x: 0.0,
                y: 0.0,
            };
        }
        let (x, y, z) = (x / len, y / len, z / len);
        if z >= 0.0 {
            return Direction {
                cos: z.min(1.0),
                x,
                y,
            };
        }
        let t = math::hypot(x, y);
        let (x, y) = if t > 0.0 { (x / t, y / t) } else { (1.0, 0.0) };
        Direction { cos: 0.0, x, y }
    }
}

/// The colour term of the diffraction lobe for unpolarised light,
/// `Q̄ = Q / 2`, with Q the Rayleigh–Rice polarisation factor of (HP17 10),
/// for the incident direction `i` (towards the light) and the outgoing
/// direction `o` (towards the viewer), unit vectors in the local frame
/// (normal +z), and the complex index η. With `(θi, φi)`, `(θo, φo)` the
/// spherical coordinates of i and o, (HP17 10) reads:
///
/// ```text
/// φ   = φo − φi − π,      ci = (η² − sin²θi)^½,      co = (η² − sin²θo)^½
/// q0  = (η² − 1)(cos θi + ci)⁻¹          q1 = (η² − 1)(η² cos θi + ci)⁻¹
/// q2  = (cos θo + co)⁻¹                  q3 = (η² cos θo + co)⁻¹
/// Qss = q0 q2 cos φ                      Qsp = q0 q3 co sin φ
/// Qps = q1 q2 ci sin φ                   Qpp = q1 q3 (ci co cos φ − η² sin θi sin θo)
/// Q   = |Qss|² + |Qsp|² + |Qps|² + |Qpp|²                              (HP17 10)
/// Q̄   = Q / 2
/// ```
///
/// (square roots principal, arithmetic complex). `Q_ab` is the amplitude
/// factor from incident polarisation a to scattered polarisation b (s or p)
/// of first-order (Rayleigh–Rice) scattering by a smooth surface; the cross
/// terms `Qsp`, `Qps` transfer power between polarisations. Q sums the four
/// channels; unpolarised light carries half its power in each incident
/// polarisation, hence `Q̄ = Q/2` (docs/model.md §2.3, §8).
///
/// **Specular check**: for `o` the mirror direction of `i` (`θo = θi`,
/// `φo = φi + π`, so φ = 0) `Qsp = Qps = 0`, `|Qss|² = Fs`, `|Qpp|² = Fp`, so
/// `Q = 2F` and `Q̄ = F` ([`fresnel`] at `cos θi`). Off the specular direction
/// Q̄ is not bounded by 1: at double grazing incidence
/// `Q = cos²φ + 2|η² − 1| sin²φ + |(η² − 1) cos φ − η²|²`, which is
/// `≈ 2|η|⁴` in the back-scattering direction (φ = π).
///
/// φ is never formed: `sin θi sin θo cos φ = −(ix ox + iy oy)` and
/// `sin θi sin θo sin φ = −(ix oy − iy ox)`, normalised. When `sin θi` or
/// `sin θo` is 0 the azimuth is undefined and Q does not depend on it; φ = 0
/// is used.
///
/// Guards: `i` and `o` are normalised; a direction below the horizon is moved
/// onto it (cos θ = 0, azimuth kept), a zero or non-finite vector is taken as
/// the normal. Index conventions as in the module documentation (η = 1 gives
/// 0). Finite for every input (at most ≈ 8·10³⁶ with the index cap), never
/// panics; computed in f64.
pub fn q_bar(eta: Complex, i: [f32; 3], o: [f32; 3]) -> f32 {
    let Some(q) = QConstants::new(eta) else {
        return 0.0;
    };
    let (di, dout) = (Direction::new(i), Direction::new(o));
    // sin θi sin θo (cos φ, sin φ) with φ = φo − φi − π.
    let along = -(di.x * dout.x + di.y * dout.y);
    let across = -(di.x * dout.y - di.y * dout.x);
    let (fi, fo) = (q.factors(di.cos), q.factors(dout.cos));
    (q.combine(&fi, &fo, along, across) as f32)
        .max(0.0)
        .min(f32::MAX)
}

/// What Q̄ (HP17 10) needs of the index: `|η² − 1|²` and `η²`. With
/// `c = √(η² − sin²θ)`, `W = 1/(η² cos θ + c)`, `U = c W` and
/// `a = 1/|cos θ + c|²` per direction ([`QConstants::factors`]),
///
/// ```text
/// Q̄ = |η² − 1|² / 2 · [ a_i a_o cos²φ + (a_i |U_o|² + |U_i|² a_o) sin²φ
///                       + |U_i U_o cos φ − η² sin θi sin θo W_i W_o|² ]
/// ```
///
/// the four terms of [`q_bar`] with `q0 = (η² − 1)/(cos θi + ci)`,
/// `q1 = (η² − 1) W_i`, `q2 = 1/(cos θo + co)`, `q3 = W_o` factored out.
#[derive(Clone, Copy, Debug)]
pub(crate) struct QConstants {
    index: Index,
    e_norm_sqr: f64,
}

/// The per-direction factors of Q̄ at one `cos θ`: `[a, Re U, Im U, Re W, Im W]`.
pub(crate) type QFactors = [f64; 5];

impl QConstants {
    /// `None` for `η² = 1` (Q̄ = 0).
    pub(crate) fn new(eta: Complex) -> Option<QConstants> {
        let index = Index::new(eta)?;
        Some(QConstants {
            index,
            e_norm_sqr: index.e.norm_sqr(),
        })
    }

    /// `[a, U, W]` at `cos θ ∈ [0, 1]` (see the type's documentation).
    pub(crate) fn factors(&self, cos: f64) -> QFactors {
        let c = self.index.c(cos);
        let one = C64::real(1.0);
        let sum = C64::real(cos) + c;
        let w = one / (self.index.eta_sq * cos + c);
        let u = c * w;
        [1.0 / sum.norm_sqr(), u.re, u.im, w.re, w.im]
    }

    /// `(|η² − 1|², η²)` of [`QConstants::combine`].
    pub(crate) fn combine_constants(&self) -> (f64, [f64; 2]) {
        let eta_sq = self.index.eta_sq;
        (self.e_norm_sqr, [eta_sq.re, eta_sq.im])
    }

    /// Q̄ from both directions' factors and `sin θi sin θo (cos φ, sin φ)`
    /// (its length is `sin θi sin θo`; φ is normalised out, φ = 0 when either
    /// sine is 0).
    ///
    /// Mirrored in python/twoscale/drjit/lobes.py.
    pub(crate) fn combine(&self, fi: &QFactors, fo: &QFactors, along: f64, across: f64) -> f64 {
        // With s² = along² + across² = (sin θi sin θo)², the bracket times s²
        // is a_i a_o along² + (a_i |U_o|² + |U_i|² a_o) across²
        // + |U_i U_o along − η² s² W_i W_o|²: one division, no square root.
        // |along|, |across| ≤ 1: the squares cannot overflow.
        let s_sq = along * along + across * across;
        let (along, across, inv_s_sq) = if s_sq > 0.0 {
            (along, across, 1.0 / s_sq)
        } else {
            (1.0, 0.0, 1.0)
        };
        let (ui, uo) = (C64::new(fi[1], fi[2]), C64::new(fo[1], fo[2]));
        let (wi, wo) = (C64::new(fi[3], fi[4]), C64::new(fo[3], fo[4]));
        let pp = ui * uo * along - self.index.eta_sq * (wi * wo) * s_sq;
        let q = fi[0] * fo[0] * (along * along)
            + (fi[0] * uo.norm_sqr() + ui.norm_sqr() * fo[0]) * (across * across)
            + pp.norm_sqr();
        0.5 * self.e_norm_sqr * q * inv_s_sq
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn close(a: f64, b: f64, tol: f64) -> bool {
        (a - b).abs() <= tol
    }

    #[test]
    fn complex_square_root_is_principal() {
        for (re, im) in [
            (4.0, 0.0),
            (-4.0, 0.0),
            (-4.0, -0.0),
            (0.0, 2.0),
            (0.0, -2.0),
            (3.0, -4.0),
            (-3.0, 4.0),
            (-3.0, -4.0),
            (1e-300, 1e-300),
            (-1e20, 1e-20),
        ] {
            let z = C64::new(re, im);
            let s = z.sqrt();
            assert!(s.re >= 0.0, "{z:?} -> {s:?}");
            let back = s * s;
            let scale = re.hypot(im);
            assert!(
                close(back.re, re, 1e-15 * scale) && close(back.im, im, 1e-15 * scale),
                "{z:?}: {s:?}² = {back:?}"
            );
        }
        // The negative real axis maps to +i, whatever the zero's sign.
        assert_eq!(C64::new(-4.0, -0.0).sqrt(), C64::new(0.0, 2.0));
        assert_eq!(C64::real(0.0).sqrt(), C64::real(0.0));
    }

    #[test]
    fn normal_incidence_closed_form() {
        for (n, k) in [
            (1.5f32, 0.0f32),
            (0.2, 3.0),
            (0.5, 0.0),
            (2.9, 3.1),
            (10.0, 20.0),
        ] {
            let (n64, k64) = (f64::from(n), f64::from(k));
            let want = ((n64 - 1.0).powi(2) + k64 * k64) / ((n64 + 1.0).powi(2) + k64 * k64);
            let got = f64::from(fresnel(Complex::new(n, k), 1.0));
            assert!(close(got, want, 1e-7), "{n} {k}: {got} vs {want}");
        }
    }

    #[test]
    fn dielectric_limits() {
        let glass = Complex::real(1.5);
        // Brewster: tan θB = η, Fp = 0, so F = Fs/2.
        // There c = √(η² − sin²θB) = η² cos θB, so Fs = ((1 − η²)/(1 + η²))².
        let cos_b = 1.0 / (1.0f64 + 1.5 * 1.5).sqrt();
        let fs = ((1.0 - 1.5 * 1.5) / (1.0 + 1.5 * 1.5f64)).powi(2);
        let got = f64::from(fresnel(glass, cos_b as f32));
        assert!(close(got, fs / 2.0, 1e-6), "{got} vs {}", fs / 2.0);
        // Grazing and the guards.
        assert_eq!(fresnel(glass, 0.0), 1.0);
        assert_eq!(fresnel(glass, -0.3), 1.0);
        assert_eq!(fresnel(glass, f32::NAN), 1.0);
        assert_eq!(fresnel(glass, 2.0), fresnel(glass, 1.0));
        // Total internal reflection from inside glass.
        let inside = Complex::real(1.0 / 1.5);
        let cos_critical = (1.0f32 - 1.0 / 2.25).sqrt();
        assert_eq!(fresnel(inside, cos_critical * 0.999), 1.0);
        assert!(fresnel(inside, cos_critical * 1.01) < 1.0);
        // No interface.
        assert_eq!(fresnel(Complex::real(1.0), 0.5), 0.0);
        assert_eq!(fresnel(Complex::real(-1.0), 0.0), 0.0);
        assert_eq!(
            q_bar(Complex::real(1.0), [0.0, 0.0, 1.0], [0.0, 0.0, 1.0]),
            0.0
        );
    }

    #[test]
    fn index_symmetries_and_extremes_stay_finite() {
        for (n, k) in [(1.3f32, 2.0f32), (0.4, 0.0)] {
            for cos in [0.0f32, 0.01, 0.5, 1.0] {
                let f = fresnel(Complex::new(n, k), cos);
                assert_eq!(f, fresnel(Complex::new(-n, k), cos));
                assert_eq!(f, fresnel(Complex::new(n, -k), cos));
            }
        }
        let specials = [
            0.0f32,
            -0.0,
            1.0,
            1e-30,
            1e-45,
            f32::MAX,
            -f32::MAX,
            f32::INFINITY,
            f32::NEG_INFINITY,
            f32::NAN,
        ];
        for &n in &specials {
            for &k in &specials {
                for cos in [0.0f32, 1e-7, 0.5, 1.0, f32::NAN] {
                    let f = fresnel(Complex::new(n, k), cos);
                    assert!((0.0..=1.0).contains(&f), "n {n} k {k} cos {cos}: {f}");
                }
                for (i, o) in [
                    ([0.0f32, 0.0, 1.0], [0.0f32, 0.0, 1.0]),
                    ([1.0, 0.0, 0.0], [1.0, 0.0, 0.0]),
                    ([1.0, 0.0, 0.0], [-1.0, 0.0, 0.0]),
                    ([0.0, 0.0, 0.0], [f32::NAN, 0.0, 1.0]),
                    ([0.0, 0.0, -1.0], [0.3, 0.4, -0.1]),
                ] {
                    let q = q_bar(Complex::new(n, k), i, o);
                    assert!(q.is_finite() && q >= 0.0, "n {n} k {k} {i:?} {o:?}: {q}");
                }
            }
        }
        // A zero index behaves as its limit F → 1.
        assert!(fresnel(Complex::new(0.0, 0.0), 1.0) > 1.0 - 1e-6);
    }

    #[test]
    fn q_bar_is_fresnel_in_the_specular_direction() {
        for (n, k) in [(1.5f32, 0.0f32), (0.2, 3.0), (1.2, 7.0), (0.7, 0.0)] {
            let eta = Complex::new(n, k);
            for deg in [0.0f32, 10.0, 45.0, 70.0, 85.0, 89.9] {
                let (s, c) = deg.to_radians().sin_cos();
                let phi = 0.7f32;
                let i = [s * phi.cos(), s * phi.sin(), c];
                let o = [-i[0], -i[1], i[2]];
                let (q, f) = (q_bar(eta, i, o), fresnel(eta, c));
                assert!(
                    (q - f).abs() <= 2e-6 * f.max(1e-3),
                    "η = {n}+{k}i, θ = {deg}: Q̄ {q} vs F {f}"
                );
            }
        }
    }

    #[test]
    fn q_bar_at_double_grazing_matches_its_closed_form() {
        let eta = Complex::new(1.2, 7.0);
        let (eta_sq, e) = (C64::new(1.44 - 49.0, 16.8), C64::new(0.44 - 49.0, 16.8));
        for phi in [0.0f64, 0.5, 1.5, 2.5, core::f64::consts::PI] {
            // φ = φo − φi − π with φi = 0.
            let po = phi + core::f64::consts::PI;
            let i = [1.0f32, 0.0, 0.0];
            let o = [po.cos() as f32, po.sin() as f32, 0.0];
            // sin θi sin θo (cos φ, sin φ) = −(ix ox + iy oy, ix oy − iy ox).
            let (cp, sp) = (-f64::from(o[0]), -f64::from(o[1]));
            let t = e * cp - eta_sq;
            let want = 0.5 * (cp * cp + 2.0 * e.norm_sqr().sqrt() * sp * sp + t.norm_sqr());
            let got = f64::from(q_bar(eta, i, o));
            assert!(
                ((got - want) / want).abs() < 1e-6,
                "φ {phi}: {got} vs {want}"
            );
        }
    }
}
