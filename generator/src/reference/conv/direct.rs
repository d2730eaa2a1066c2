//! Direct 2-D quadrature of `C(θh) = ∫ K(h·m) D(n·m) dω_m`.
//!
//! # Coordinates
//!
//! Both lobes are zonal, so the integral has the same form in polar
//! coordinates `(ρ, ψ)` around either axis. Call `A` the axis of the *outer*
//! lobe `f_A` and `B` (at the angle `θh` from `A`) that of the *inner* lobe
//! `f_B`. Then
//!
//! ```text
//!   C(θh) = ∫₀^{π/2} f_A(ρ) sin ρ · R(ρ) dρ,      R(ρ) = 2 ∫₀^{ψ_max} f_B(δ(ρ, ψ)) dψ,
//!   4 sin²(δ/2) = 4 sin²((ρ − θh)/2) + 4 sin ρ sin θh sin²(ψ/2),
//! ```
//!
//! the second line being the law of cosines written for the squared chord
//! `|B − m|²`, which stays accurate when `δ` is tiny (a narrow kernel at
//! `u = 3000` has `δ ~ 1e-5`). `R` is the integral of `f_B` over the circle of
//! radius `ρ` around `A`; `ψ_max < π` where that circle crosses the horizon of
//! `B`, `sin²(ψ_max/2) = cos(ρ − θh) / (2 sin ρ sin θh)`.
//! [`Frame::Normal`] takes `A = n` (outer `D`, inner `K`), [`Frame::Half`]
//! takes `A = h` (outer `K`, inner `D`).
//!
//! # Breakpoints
//!
//! Each lobe lists the polar angles where its profile changes scale
//! (geometric grids around its peak, plus the horizon maximum of small-`p`
//! NDFs). The inner integral is split at the azimuths where the circle
//! crosses those angles of `f_B` (`sin²(ψ_j/2) = (sin²(δ_j/2) −
//! sin²((ρ−θh)/2)) / (sin ρ sin θh)`) and at the cut `ψ_max`. The outer one is
//! split at the angles of `f_A`, at `θh`, and at `θh ± δ_j`, `δ_j − θh`
//! (where the circle starts or stops meeting the circle `δ = δ_j` around `B`;
//! with `δ_j = π/2` this is the kink where `R` starts being cut). On every
//! piece the integrand is smooth on the scale of the piece, so the adaptive
//! Gauss–Kronrod rule cannot miss a narrow peak.
//!
//! # Tolerances
//!
//! Both integrands are non-negative, so a relative tolerance on each piece
//! bounds the relative error of the sum. A purely relative request cannot be
//! met on circles that barely cross the horizon of `B` (there `cos δ` is a
//! difference of `O(1)` numbers, so a ring worth `1e-21` is computed with
//! noise `1e-16` in `cos δ`): a rough first pass estimates `C`, and the
//! accurate pass also accepts an absolute error `rel_tol · C`, shared out
//! between the pieces (see `nested`).

use super::{ConvError, Lobe, Params, sort_dedup};
use crate::quad::{QuadError, Tolerance, integrate};
use std::cell::Cell;
use std::f64::consts::{FRAC_PI_2, PI};

/// Which axis the outer (polar) integral is centred on.
///
/// Both frames are accurate everywhere in the domain (they agree to
/// `≤ 4e-12` relative on the corner sweep); they are two independent
/// discretisations of the same integral, which is what the tests use them
/// for. [`Frame::Normal`] is the default because it is the cheaper one on
/// almost every corner (typically 1–15 ms per angle against 5–80 ms): the
/// cusp of `D`, its spread over many scales for small `p` and its maximum
/// next to the horizon are then all one-dimensional features of the outer
/// integral, while the kernel, smooth around its own axis, is handled by the
/// mapped breakpoints of the inner one.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Frame {
    /// Around the normal `n`: outer `D`, inner kernel.
    Normal,
    /// Around the half vector `h`: outer kernel, inner `D`.
    Half,
}

/// Options of [`convolution_direct`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct DirectOptions {
    /// Relative tolerance of each outer piece; the inner integrals get a
    /// tenth of it.
    pub rel_tol: f64,
    /// Polar frame.
    pub frame: Frame,
}

impl Default for DirectOptions {
    /// `rel_tol = 1e-9` and [`Frame::Normal`]. The Gauss–Kronrod error
    /// estimates are pessimistic: the two frames agree to `≤ 4e-12`.
    fn default() -> Self {
        Self {
            rel_tol: 1e-9,
            frame: Frame::Normal,
        }
    }
}

/// Result of [`convolution_direct`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct DirectResult {
    /// `C(θh)`.
    pub value: f64,
    /// Sum of the Gauss–Kronrod error estimates of the outer pieces.
    pub error: f64,
    /// Number of lobe evaluations (inner integrand calls).
    pub evaluations: usize,
}

/// `C(θh; u, c, β, p)` by direct 2-D quadrature (see the module
/// documentation).
pub fn convolution_direct(
    theta_h: f64,
    u: f64,
    c: f64,
    beta: f64,
    p: f64,
    opts: &DirectOptions,
) -> Result<DirectResult, ConvError> {
    let params = Params::new(u, c, beta, p)?;
    Params::validate_theta(theta_h)?;
    if !(opts.rel_tol > 0.0 && opts.rel_tol < 1.0) {
        return Err(ConvError::InvalidParameter {
            name: "rel_tol",
            value: opts.rel_tol,
            expected: "a relative tolerance in (0, 1)",
        });
    }
    let (outer, inner) = match opts.frame {
        Frame::Normal => (params.ndf(), params.kernel()),
        Frame::Half => (params.kernel(), params.ndf()),
    };
    nested(theta_h, &outer, &inner, opts.rel_tol)
}

/// The nested integral in two passes. A rough pass (relative `1e-4`, which
/// accepts the best estimate of a piece that does not converge) gives
/// `S ≈ C`; the accurate pass then asks each piece for a relative `rel_tol`
/// **or** an absolute error small against `rel_tol · S`. The absolute part
/// matters only on pieces that contribute nothing: circles that barely cross
/// the horizon of `B`, where `cos δ` is a difference of `O(1)` numbers and a
/// purely relative request on a value of `1e-21` can never be met.
fn nested(
    theta_h: f64,
    outer: &Lobe,
    inner: &Lobe,
    rel_tol: f64,
) -> Result<DirectResult, ConvError> {
    let rough = nested_pass(theta_h, outer, inner, 1e-4, 0.0, true)?;
    let fine = nested_pass(theta_h, outer, inner, rel_tol, rel_tol * rough.value, false)?;
    Ok(DirectResult {
        evaluations: rough.evaluations + fine.evaluations,
        ..fine
    })
}

/// One pass of the nested integral with outer lobe `outer` (axis `A`) and
/// inner lobe `inner` (axis `B` at angle `theta_h` from `A`). The total
/// absolute error allowed, `abs_tol`, is split evenly between the outer
/// pieces (half) and the inner integrals (half, as an absolute tolerance
/// `abs_tol / (2 ∫ f_A sin ρ dρ)` on each circle). With `tolerant`, pieces
/// that do not converge contribute their best estimate.
fn nested_pass(
    theta_h: f64,
    outer: &Lobe,
    inner: &Lobe,
    rel_tol: f64,
    abs_tol: f64,
    tolerant: bool,
) -> Result<DirectResult, ConvError> {
    let inner_bp = inner.breakpoints();
    // Outer breakpoints.
    let mut cuts = outer.breakpoints();
    cuts.push(theta_h);
    for &d in inner_bp.iter().chain(std::iter::once(&FRAC_PI_2)) {
        cuts.extend([theta_h + d, theta_h - d, d - theta_h]);
    }
    cuts.retain(|&x| x > 0.0 && x < FRAC_PI_2);
    cuts.push(0.0);
    cuts.push(FRAC_PI_2);
    sort_dedup(&mut cuts);
    let pieces = cuts.len() - 1;

    // ∫ f_A sin ρ dρ, to turn the absolute budget into one per circle.
    let mut outer_mass = 0.0;
    if abs_tol > 0.0 {
        let fa = |rho: f64| {
            let (s, c) = rho.sin_cos();
            outer.value(s, c) * s
        };
        for pair in cuts.windows(2) {
            outer_mass += integrate(fa, pair[0], pair[1], Tolerance::relative(1e-6))?.value;
        }
    }
    let ring_abs = if outer_mass > 0.0 {
        0.5 * abs_tol / outer_mass
    } else {
        0.0
    };
    let piece_abs = 0.5 * abs_tol / pieces as f64;

    let evaluations = Cell::new(0usize);
    let failure: Cell<Option<QuadError>> = Cell::new(None);
    let inner_tol = Tolerance::new(ring_abs, 0.1 * rel_tol);
    let integrand = |rho: f64| -> f64 {
        let (s, c) = rho.sin_cos();
        let fa = outer.value(s, c);
        if fa == 0.0 {
            return 0.0;
        }
        match ring(
            inner,
            &inner_bp,
            rho,
            theta_h,
            inner_tol,
            tolerant,
            &evaluations,
        ) {
            Ok(r) => fa * s * r,
            Err(e) => {
                if failure.get().is_none() {
                    failure.set(Some(e));
                }
                f64::NAN
            }
        }
    };
    let mut value = 0.0;
    let mut error = 0.0;
    for pair in cuts.windows(2) {
        match integrate(
            integrand,
            pair[0],
            pair[1],
            Tolerance::new(piece_abs, rel_tol),
        ) {
            Ok(est) => {
                value += est.value;
                error += est.error;
            }
            Err(QuadError::NotConverged {
                value: v, error: e, ..
            }) if tolerant => {
                value += v;
                error += e;
            }
            Err(e) => return Err(failure.get().unwrap_or(e).into()),
        }
    }
    Ok(DirectResult {
        value,
        error,
        evaluations: evaluations.get(),
    })
}

/// `R(ρ) = ∫₀^{2π} f_B(δ(ρ, ψ)) dψ`, the integral of the inner lobe over the
/// circle of polar radius `ρ` around `A` (see the module documentation).
fn ring(
    inner: &Lobe,
    inner_bp: &[f64],
    rho: f64,
    theta_h: f64,
    tol: Tolerance,
    tolerant: bool,
    evaluations: &Cell<usize>,
) -> Result<f64, QuadError> {
    let delta = (rho - theta_h).abs();
    let sd = (0.5 * delta).sin();
    let base = 4.0 * sd * sd; // squared chord at ψ = 0
    if delta >= FRAC_PI_2 {
        return Ok(0.0); // the whole circle is beyond the horizon of B
    }
    let sh = rho.sin() * theta_h.sin();
    if sh <= 0.0 {
        evaluations.set(evaluations.get() + 1);
        return Ok(2.0 * PI * inner.value_chord2(base));
    }
    // sin²(ψ/2) where the circle crosses the horizon of B.
    let cut = (rho - theta_h).cos() / (2.0 * sh);
    let psi_max = if cut >= 1.0 {
        PI
    } else {
        2.0 * cut.sqrt().asin()
    };
    let mut cuts = vec![0.0, psi_max];
    for &d in inner_bp {
        if d <= delta {
            continue;
        }
        // sin²(d/2) − sin²(Δ/2) = sin((d+Δ)/2) sin((d−Δ)/2).
        let s2 = (0.5 * (d + delta)).sin() * (0.5 * (d - delta)).sin() / sh;
        if s2 < cut.min(1.0) {
            cuts.push(2.0 * s2.sqrt().asin());
        }
    }
    sort_dedup(&mut cuts);
    let g = |psi: f64| {
        let s = (0.5 * psi).sin();
        inner.value_chord2(base + 4.0 * sh * s * s)
    };
    let mut sum = 0.0;
    for pair in cuts.windows(2) {
        match integrate(g, pair[0], pair[1], tol) {
            Ok(est) => {
                evaluations.set(evaluations.get() + est.evaluations);
                sum += est.value;
            }
            Err(QuadError::NotConverged {
                value,
                evaluations: n,
                ..
            }) if tolerant => {
                evaluations.set(evaluations.get() + n);
                sum += value;
            }
            Err(e) => return Err(e),
        }
    }
    Ok(2.0 * sum)
}
