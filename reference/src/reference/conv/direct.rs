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
//! sin²((ρ−θh)/2)) / (sin ρ sin θh)`) and at the cut `ψ_max`; when `f_B` is
//! the kernel ([`Frame::Normal`]) it is instead integrated in a variable in
//! which the kernel's leading factor `(1 + 4u² |B − m|²)^(−q)` is smooth
//! over the whole circle (see `ArcMap::Kernel`), so that a circle costs one
//! to three pieces however narrow the kernel. The outer one is
//! split at the angles of `f_A`, at `θh`, and at `θh ± δ_j`, `δ_j − θh`
//! (where the circle starts or stops meeting the circle `δ = δ_j` around `B`;
//! with `δ_j = π/2` this is the kink where `R` starts being cut). When `f_B`
//! is the kernel, the outer integral is instead taken in the variable `s`,
//! `ρ = θh + w sinh s` (see `OuterMap::Kernel`), in which `R` is smooth on
//! the scale 1 at every distance from `θh`: a uniform grid in `s` replaces
//! the kernel's angles `θh ± δ_j`, `δ_j − θh` (only the kink `π/2 − θh`
//! stays). On every piece the integrand is smooth on the scale of the
//! piece, so the adaptive Gauss–Kronrod rule cannot miss a narrow peak.
//!
//! # Tolerances
//!
//! Both integrands are non-negative, so a relative tolerance on each piece
//! bounds the relative error of the sum. A purely relative request cannot be
//! met on circles that barely cross the horizon of `B` (there `cos δ` is a
//! difference of `O(1)` numbers, so a ring worth `1e-21` is computed with
//! noise `1e-16` in `cos δ`): a cheap fixed-rule pass estimates `C`, and
//! the accurate pass also accepts an absolute error `rel_tol · C`, shared out
//! between the pieces (see `nested`).

use super::{ConvError, Lobe, Params, sort_dedup};
use crate::quad::{DEFAULT_MAX_INTERVALS, QuadError, Rule, Tolerance, integrate_with_rule};
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
    /// Gauss–Kronrod pair of both adaptive integrals.
    pub rule: Rule,
}

impl Default for DirectOptions {
    /// `rel_tol = 1e-9`, [`Frame::Normal`] and [`Rule::Gk15`]. The
    /// Gauss–Kronrod error estimates are pessimistic: the two frames agree to
    /// `≤ 4e-12`. Every piece of both integrals is smooth on its own scale, so
    /// one interval nearly always meets the tolerance and the cost is the
    /// number of pieces times the rule's points: G7–K15 evaluates the lobes
    /// ≈ 2× less often than G10–K21, and the two rules agree to `≤ 1e-13`
    /// (test `rules_agree_on_hard_points`).
    fn default() -> Self {
        Self {
            rel_tol: 1e-9,
            frame: Frame::Normal,
            rule: Rule::Gk15,
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
    nested(theta_h, &outer, &inner, opts.rel_tol, opts.rule)
}

/// The nested integral, accurate pass with an absolute floor. A purely
/// relative request cannot be met on pieces that contribute nothing (circles
/// that barely cross the horizon of `B`, where `cos δ` is a difference of
/// `O(1)` numbers and a value of `1e-21` carries rounding noise `1e-16`), so
/// the accurate pass asks each piece for a relative `rel_tol` **or** an
/// absolute error small against `rel_tol · S`, `S ≈ C`.
///
/// `S` comes from [`coarse_estimate`] (a fixed 4-point Gauss rule on every
/// piece of both integrals: 4 × 4 points per pair of pieces against at least
/// 15 × 15 in a pass). Only a too large
/// `S` could loosen the result, so when `S > 2 C` the accurate pass is
/// repeated with `S = C`; when the estimate is not positive or the accurate
/// pass fails, `S` comes from a rough adaptive pass (relative `1e-4`,
/// accepting the best estimate of a piece that does not converge) as it
/// always did before the coarse estimate existed.
fn nested(
    theta_h: f64,
    outer: &Lobe,
    inner: &Lobe,
    rel_tol: f64,
    rule: Rule,
) -> Result<DirectResult, ConvError> {
    let coarse = coarse_estimate(theta_h, outer, inner);
    let pass = |rel_tol, abs_tol, tolerant| {
        let tol = (rel_tol, abs_tol, coarse.outer_mass);
        nested_pass(theta_h, outer, inner, tol, tolerant, rule)
    };
    if coarse.value > 0.0 && coarse.value.is_finite() {
        let mut scale = coarse.value;
        let mut evaluations = coarse.evaluations;
        for _ in 0..2 {
            let Ok(fine) = pass(rel_tol, rel_tol * scale, false) else {
                break;
            };
            evaluations += fine.evaluations;
            if scale <= 2.0 * fine.value {
                return Ok(DirectResult {
                    evaluations,
                    ..fine
                });
            }
            scale = fine.value;
        }
    }
    let rough = pass(1e-4, 0.0, true)?;
    let fine = pass(rel_tol, rel_tol * rough.value, false)?;
    Ok(DirectResult {
        evaluations: rough.evaluations + fine.evaluations,
        ..fine
    })
}

/// Points of the fixed Gauss rule of [`coarse_estimate`] per piece.
const COARSE_NODES: usize = 4;

/// What [`coarse_estimate`] returns.
struct Coarse {
    /// The estimate of `C`.
    value: f64,
    /// Its lobe evaluations.
    evaluations: usize,
    /// The same rule's `∫ f_A sin ρ dρ` (see [`nested_pass`]).
    outer_mass: f64,
}

/// A cheap estimate of the nested integral: the pieces of the accurate pass
/// (outer breakpoints, and the azimuthal breakpoints of every circle), each
/// integrated by a fixed [`COARSE_NODES`]-point Gauss–Legendre rule. Every
/// piece is smooth on its own scale, so this is typically within a few
/// percent of `C`; it only sets the absolute floor of the accurate pass
/// (see [`nested`]). The outer rule also gives `∫ f_A sin ρ dρ`, which
/// turns the floor into one per circle.
fn coarse_estimate(theta_h: f64, outer: &Lobe, inner: &Lobe) -> Coarse {
    let inner_bp = inner.breakpoints();
    let (map, cuts) = outer_cuts(theta_h, outer, inner, &inner_bp);
    let (gx, gw) = crate::quad::gauss_legendre(COARSE_NODES);
    let rule = |a: f64, b: f64, f: &mut dyn FnMut(f64) -> f64| {
        let (mid, half) = (0.5 * (a + b), 0.5 * (b - a));
        gx.iter()
            .zip(&gw)
            .map(|(x, w)| w * f(mid + half * x))
            .sum::<f64>()
            * half
    };
    let mut evaluations = 0;
    let mut value = 0.0;
    let mut outer_mass = 0.0;
    for pair in cuts.windows(2) {
        let (mid, half) = (0.5 * (pair[0] + pair[1]), 0.5 * (pair[1] - pair[0]));
        let (mut piece, mut mass) = (0.0, 0.0);
        for (x, w) in gx.iter().zip(&gw) {
            let (rho, jac) = map.rho(mid + half * x);
            let (s, c) = rho.sin_cos();
            let fa = outer.value(s, c) * jac;
            if fa == 0.0 {
                continue;
            }
            mass += w * fa * s;
            let r = match ring_cuts(inner, &inner_bp, rho, theta_h) {
                Ring::Empty => 0.0,
                Ring::Pole { chord2 } => {
                    evaluations += 1;
                    2.0 * PI * inner.value_chord2(chord2)
                }
                Ring::Arcs { map, cuts } => {
                    let mut sum = 0.0;
                    for arc in cuts.windows(2) {
                        evaluations += COARSE_NODES;
                        sum += rule(arc[0], arc[1], &mut |t| map.value(inner, t));
                    }
                    2.0 * sum
                }
            };
            piece += w * (fa * s * r);
        }
        value += piece * half;
        outer_mass += mass * half;
    }
    Coarse {
        value,
        evaluations,
        outer_mass,
    }
}

/// The outer breakpoints: the outer lobe's own, `θh`, and `θh ± δ_j`,
/// `δ_j − θh` for the inner lobe's angles `δ_j` and `π/2` (see the module
/// documentation), with `0` and `π/2`, ascending, in the variable of the
/// returned [`OuterMap`]. When the inner lobe is the kernel, the outer
/// variable is `s` ([`OuterMap::Kernel`]) and the kernel's angles are
/// replaced by the grid `s = ±j·`[`OUTER_KERNEL_STEP`] (only the horizon
/// kink `π/2 − θh` stays).
fn outer_cuts(theta_h: f64, outer: &Lobe, inner: &Lobe, inner_bp: &[f64]) -> (OuterMap, Vec<f64>) {
    let map = OuterMap::new(theta_h, inner);
    let mut cuts = outer.breakpoints();
    cuts.push(theta_h);
    let kernel_angles: &[f64] = match map {
        OuterMap::Polar => inner_bp,
        OuterMap::Kernel { .. } => &[],
    };
    for &d in kernel_angles.iter().chain(std::iter::once(&FRAC_PI_2)) {
        cuts.extend([theta_h + d, theta_h - d, d - theta_h]);
    }
    cuts.retain(|&x| x > 0.0 && x < FRAC_PI_2);
    cuts.push(0.0);
    cuts.push(FRAC_PI_2);
    let mut cuts: Vec<f64> = cuts.into_iter().map(|x| map.of_rho(x)).collect();
    if let OuterMap::Kernel { .. } = map {
        let (lo, hi) = (map.of_rho(0.0), map.of_rho(FRAC_PI_2));
        let mut s = OUTER_KERNEL_STEP;
        while s < hi || -s > lo {
            cuts.extend([s, -s].into_iter().filter(|&x| x > lo && x < hi));
            s += OUTER_KERNEL_STEP;
        }
    }
    sort_dedup(&mut cuts);
    (map, cuts)
}

/// Fraction of the accurate pass's absolute tolerance that the circles
/// skipped in [`OuterMap::Kernel`]'s variable may add up to (see
/// [`nested_pass`]), and of a circle's tolerance that the kernel's skipped
/// arcs may add up to (see [`ring`]).
const NEGLIGIBLE: f64 = 1e-3;

/// Spacing of the grid of [`OuterMap::Kernel`]'s variable `s` on which the
/// outer integral is split: a piece of length 2 has the singularities
/// `s = ±iπ/2` at 1.6 half-lengths, within reach of G7–K15 at `1e-12`
/// (measured on T3's direct nodes: 1.5, 3, 4 and no grid at all give
/// +5%, −3%, −5%, −8% lobe evaluations; all agree with the quadrature in
/// `ρ` to `≤ 1.1e-12`).
const OUTER_KERNEL_STEP: f64 = 2.0;

/// The variable of the outer integral.
#[derive(Clone, Copy, Debug)]
enum OuterMap {
    /// `ρ` itself.
    Polar,
    /// When the inner lobe is the kernel (half-width `w = 1/(2u)`):
    /// `s` with `ρ = θh + w sinh s`, `dρ = w cosh s ds`. The circle integral
    /// `R(ρ)` of the kernel is analytic in `ρ` except at `ρ − θh ≈ ±i w`
    /// (where `1 + 4u² |B − m|²` vanishes at the circle's nearest point) and
    /// behaves like `(1 + (ρ − θh)²/w²)^(1/2 − q)`; in `s` these points are
    /// `s = ±iπ/2` and `R dρ ∝ cosh^(2−2q) s ds`: smooth on the scale 1 at
    /// every distance from `θh`, where in `ρ` it needed a geometric grid
    /// `θh ± w·2^k`.
    Kernel { theta_h: f64, w: f64 },
}

impl OuterMap {
    /// The map for the inner lobe `inner` around `B` at `theta_h`.
    fn new(theta_h: f64, inner: &Lobe) -> Self {
        match *inner {
            Lobe::Kernel { u, .. } if u > 0.0 => OuterMap::Kernel {
                theta_h,
                w: 0.5 / u,
            },
            _ => OuterMap::Polar,
        }
    }

    /// `ρ` and `dρ/ds` at `s`.
    fn rho(&self, s: f64) -> (f64, f64) {
        match *self {
            OuterMap::Polar => (s, 1.0),
            OuterMap::Kernel { theta_h, w } => (theta_h + w * s.sinh(), w * s.cosh()),
        }
    }

    /// The variable at `ρ`.
    fn of_rho(&self, rho: f64) -> f64 {
        match *self {
            OuterMap::Polar => rho,
            OuterMap::Kernel { theta_h, w } => ((rho - theta_h) / w).asinh(),
        }
    }
}

/// The circle of polar radius `ρ` around `A` as seen by the inner lobe.
// Large on purpose: the kernel's cuts live on the stack (see `Cuts`).
#[allow(clippy::large_enum_variant)]
enum Ring {
    /// Entirely beyond the horizon of `B`.
    Empty,
    /// A point (`ρ = 0` or `θh = 0`): the inner lobe at the squared chord
    /// `chord2` all around.
    Pole { chord2: f64 },
    /// The arcs `[cuts[k], cuts[k+1]]` of the half circle, in the variable of
    /// `map`, on which the inner lobe is smooth.
    Arcs { map: ArcMap, cuts: Cuts },
}

/// Capacity of [`Cuts::Inline`]: the kernel's arcs of a circle number
/// `2 + log₄(π/(4√r))` (see [`kernel_arcs`]), 9 at most on the table domain
/// (`√r ≥ 8e-5`); 32 covers `√r ≥ 1e-18`, and past that the grid stops
/// (coarser arcs, still integrated adaptively).
const INLINE_CUTS: usize = 32;

/// The ascending cuts of a [`Ring`]: the kernel's on the stack (one circle
/// is ≈ 50 lobe evaluations, and an allocation per circle cost ≈ 4% of the
/// instructions), the NDF's on the heap.
// Large on purpose: no allocation per circle.
#[allow(clippy::large_enum_variant)]
enum Cuts {
    /// `t[..len]`.
    Inline { t: [f64; INLINE_CUTS], len: usize },
    /// Any number of cuts.
    Heap(Vec<f64>),
}

impl std::ops::Deref for Cuts {
    type Target = [f64];

    fn deref(&self) -> &[f64] {
        match self {
            Cuts::Inline { t, len } => &t[..*len],
            Cuts::Heap(v) => v,
        }
    }
}

/// The variable of the azimuthal integral of a [`Ring`]. The squared chord
/// from `B` to the point at azimuth `ψ` is `base + 4 sh sin²(ψ/2)`.
#[derive(Clone, Copy, Debug)]
enum ArcMap {
    /// `ψ` itself.
    Azimuth { base: f64, sh: f64 },
    /// For the kernel: `t = tan(x/2)`, `x = π/2 − φ`, with
    /// `tan(ψ/2) = √r tan φ`, `r = a / (a + b)`, `a = 1 + 4u²·base`,
    /// `b = 16u²·sh`. In `φ`, `sin²(ψ/2) = r sin²φ / (cos²φ + r sin²φ)` and
    /// `dψ = 2√r dφ / (cos²φ + r sin²φ)`, so the kernel's leading factor
    /// `(1 + 4u² d²)^(−q)` times `dψ` is `2√r a^(−q) (cos²φ + r sin²φ)^(q−1) dφ`:
    /// smooth on the near half of the circle however narrow the kernel (for
    /// `q = 1` it is constant). The far half (`ψ > π/2`) is squeezed into
    /// `x ≲ √r`, where `cos²φ + r sin²φ ≈ x² + r` changes scale: a geometric
    /// grid in `x` from `√r` resolves it. The rest of the kernel,
    /// `K / (1 + 4u² d²)^(−q)`, is smooth in `d²` on the scale 1. With
    /// `cos φ = 2t/(1+t²)`, `sin φ = (1−t²)/(1+t²)`, `dx = 2 dt/(1+t²)`:
    /// `sin²(ψ/2) = r (1−t²)² / E`, `dψ = 4√r (1+t²) dt / E`,
    /// `E = 4t² + r (1−t²)²`, rational in `t` (no trigonometry per point) and
    /// accurate where `cos φ` is small. `jac = 4√r`.
    Kernel {
        base: f64,
        sh: f64,
        r: f64,
        jac: f64,
    },
}

impl ArcMap {
    /// The squared chord from `B` and `dψ/dt` at `t` (`ψ` or `tan(x/2)`).
    fn point(&self, t: f64) -> (f64, f64) {
        match *self {
            ArcMap::Azimuth { base, sh } => {
                let s = (0.5 * t).sin();
                (base + 4.0 * sh * s * s, 1.0)
            }
            ArcMap::Kernel { base, sh, r, jac } => {
                let t2 = t * t;
                let m = 1.0 - t2;
                let rm2 = r * m * m;
                let inv_e = 1.0 / (4.0 * t2 + rm2);
                (base + 4.0 * sh * (rm2 * inv_e), jac * (1.0 + t2) * inv_e)
            }
        }
    }

    /// For [`ArcMap::Kernel`], a bound of the arc `[t0, t1]`'s integral:
    /// the kernel decreases with `ψ`, which decreases with `t`
    /// (`tan(ψ/2) = √r (1 − t²)/(2t)`), so the integral is at most the
    /// kernel at `t1` times the arc's length in `ψ`. `None` for the azimuth
    /// (the NDF is not monotonic).
    fn arc_bound(&self, inner: &Lobe, t0: f64, t1: f64) -> Option<f64> {
        match *self {
            ArcMap::Azimuth { .. } => None,
            ArcMap::Kernel { r, jac, .. } => {
                // ψ0 − ψ1 = 2 atan((T0 − T1)/(1 + T0 T1)), T = tan(ψ/2) =
                // √r (1 − t²)/(2t): one arctangent instead of two.
                let num = 0.5 * jac * (t1 - t0) * (1.0 + t0 * t1);
                let den = 4.0 * t0 * t1 + r * (1.0 - t0 * t0) * (1.0 - t1 * t1);
                let dpsi = 2.0 * num.atan2(den);
                Some(inner.value_chord2(self.point(t1).0) * dpsi)
            }
        }
    }

    /// The integrand of the azimuthal integral at `t`, Jacobian included.
    fn value(&self, inner: &Lobe, t: f64) -> f64 {
        let (d2, jacobian) = self.point(t);
        inner.value_chord2(d2) * jacobian
    }
}

/// Ratio of the geometric grid of [`ArcMap::Kernel`]'s arcs in `x`, from
/// `√r` (measured on T3's direct nodes: ratio 2 and 8 cost 5% and 7% more
/// lobe evaluations than 4).
const KERNEL_ARC_RATIO: f64 = 4.0;

/// The azimuthal pieces of the circle of radius `rho` (see [`Ring`] and the
/// module documentation): [`kernel_arcs`] for the kernel, [`azimuth_arcs`]
/// for the NDF.
fn ring_cuts(inner: &Lobe, inner_bp: &[f64], rho: f64, theta_h: f64) -> Ring {
    let delta = (rho - theta_h).abs();
    let sd = (0.5 * delta).sin();
    let base = 4.0 * sd * sd; // squared chord at ψ = 0
    if delta >= FRAC_PI_2 {
        return Ring::Empty;
    }
    let sh = rho.sin() * theta_h.sin();
    if sh <= 0.0 {
        return Ring::Pole { chord2: base };
    }
    // sin²(ψ/2) where the circle crosses the horizon of B.
    let cut = (rho - theta_h).cos() / (2.0 * sh);
    match *inner {
        Lobe::Kernel { u, .. } => kernel_arcs(u, base, sh, cut),
        Lobe::Ndf { .. } => azimuth_arcs(inner_bp, base, delta, sh, cut),
    }
}

/// The arcs of a circle in [`ArcMap::Kernel`]'s variable `t`: from `ψ_max`
/// (the horizon cut `sin²(ψ_max/2) = cut`, or `π`) to `ψ = 0` (`t = 1`),
/// split at `x = √r·4^k < π/4`.
fn kernel_arcs(u: f64, base: f64, sh: f64, cut: f64) -> Ring {
    let a = 1.0 + 4.0 * u * u * base;
    let r = a / (a + 16.0 * u * u * sh);
    // t at ψ_max: tan x = 1 / tan φ = √r / tan(ψ_max/2) = z, t = tan(x/2).
    let t_min = if cut >= 1.0 {
        0.0
    } else {
        let z = ((1.0 - cut) * r / cut).sqrt();
        z / (1.0 + z.hypot(1.0))
    };
    // Ascending: t_min, the grid above it, 1 (as `sort_dedup` would leave
    // them: a cut within 1e-12 (relative) of its predecessor is dropped).
    let mut t = [0.0; INLINE_CUTS];
    t[0] = t_min;
    let mut len = 1;
    let mut push = |t_new: f64, len: &mut usize| {
        let last = t[*len - 1];
        if (t_new - last).abs() > 1e-12 * last.abs().max(1e-300) {
            t[*len] = t_new;
            *len += 1;
        }
    };
    let mut x = r.sqrt();
    while x < 0.25 * PI && len < INLINE_CUTS - 1 {
        let tx = (0.5 * x).tan();
        if tx > t_min {
            push(tx, &mut len);
        }
        x *= KERNEL_ARC_RATIO;
    }
    push(1.0, &mut len);
    let cuts = Cuts::Inline { t, len };
    Ring::Arcs {
        map: ArcMap::Kernel {
            base,
            sh,
            r,
            jac: 4.0 * r.sqrt(),
        },
        cuts,
    }
}

/// The arcs of a circle in the azimuth `ψ ∈ [0, ψ_max]`, split where the
/// circle crosses the inner lobe's breakpoints `d > Δ` (`delta`, the
/// circle's nearest angle to `B`):
/// `sin²(ψ_j/2) = (sin²(d/2) − sin²(Δ/2)) / sh`.
fn azimuth_arcs(inner_bp: &[f64], base: f64, delta: f64, sh: f64, cut: f64) -> Ring {
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
    Ring::Arcs {
        map: ArcMap::Azimuth { base, sh },
        cuts: Cuts::Heap(cuts),
    }
}

/// One pass of the nested integral with outer lobe `outer` (axis `A`) and
/// inner lobe `inner` (axis `B` at angle `theta_h` from `A`), relative
/// tolerance `rel_tol`. The total absolute error allowed, `abs_tol`, is split
/// evenly between the outer pieces (half) and the inner integrals (half, as
/// an absolute tolerance `abs_tol / (2 M)` on each circle, `M = ∫ f_A sin ρ
/// dρ` given as `outer_mass`: [`coarse_estimate`]'s, within `6.3e-4` of an
/// adaptive quadrature at relative `1e-6` on T3's direct nodes, stride-61
/// sample). With `tolerant`, pieces that do not converge contribute their
/// best estimate.
fn nested_pass(
    theta_h: f64,
    outer: &Lobe,
    inner: &Lobe,
    (rel_tol, abs_tol, outer_mass): (f64, f64, f64),
    tolerant: bool,
    rule: Rule,
) -> Result<DirectResult, ConvError> {
    let inner_bp = inner.breakpoints();
    let (map, cuts) = outer_cuts(theta_h, outer, inner, &inner_bp);
    let pieces = cuts.len() - 1;
    let ring_abs = if outer_mass > 0.0 {
        0.5 * abs_tol / outer_mass
    } else {
        0.0
    };
    let piece_abs = 0.5 * abs_tol / pieces as f64;

    let evaluations = Cell::new(0usize);
    let failure: Cell<Option<QuadError>> = Cell::new(None);
    let inner_tol = Tolerance::new(ring_abs, 0.1 * rel_tol);
    // Circles whose bound is below `negligible` are skipped (see below).
    let negligible = match map {
        OuterMap::Kernel { .. } => NEGLIGIBLE * abs_tol / (cuts[pieces] - cuts[0]),
        OuterMap::Polar => 0.0,
    };
    let integrand = |x: f64| -> f64 {
        let (rho, jac) = map.rho(x);
        let (s, c) = rho.sin_cos();
        let fa = outer.value(s, c) * jac;
        if fa == 0.0 {
            return 0.0;
        }
        // The kernel decreases away from its axis, so R(ρ) ≤ 2π K(|ρ − θh|):
        // a circle bounded by `negligible` moves the result by less than
        // NEGLIGIBLE · abs_tol over the whole outer range.
        if negligible > 0.0 {
            let sd = (0.5 * (rho - theta_h)).sin();
            if fa * s * 2.0 * PI * inner.value_chord2(4.0 * sd * sd) <= negligible {
                return 0.0;
            }
        }
        match ring(
            inner,
            &inner_bp,
            (rho, theta_h),
            (inner_tol, rule),
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
        match integrate_with_rule(
            integrand,
            pair[0],
            pair[1],
            Tolerance::new(piece_abs, rel_tol),
            DEFAULT_MAX_INTERVALS,
            rule,
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
/// `(tol, rule)` are the tolerance and rule of each arc's integral; with
/// `tolerant`, arcs that do not converge contribute their best estimate.
fn ring(
    inner: &Lobe,
    inner_bp: &[f64],
    (rho, theta_h): (f64, f64),
    (tol, rule): (Tolerance, Rule),
    tolerant: bool,
    evaluations: &Cell<usize>,
) -> Result<f64, QuadError> {
    let (map, cuts) = match ring_cuts(inner, inner_bp, rho, theta_h) {
        Ring::Empty => return Ok(0.0),
        Ring::Pole { chord2 } => {
            evaluations.set(evaluations.get() + 1);
            return Ok(2.0 * PI * inner.value_chord2(chord2));
        }
        Ring::Arcs { map, cuts } => (map, cuts),
    };
    let g = |t: f64| map.value(inner, t);
    let arcs = cuts.len() - 1;
    let mut sum = 0.0;
    // Nearest arc first (the kernel's map runs from ψ_max at cuts[0] to
    // ψ = 0 at 1), so that `sum` can bound what the farther arcs may skip.
    for pair in cuts.windows(2).rev() {
        if let Some(bound) = map.arc_bound(inner, pair[0], pair[1]) {
            if bound * arcs as f64 <= NEGLIGIBLE * tol.abs.max(tol.rel * sum) {
                continue;
            }
        }
        match integrate_with_rule(g, pair[0], pair[1], tol, DEFAULT_MAX_INTERVALS, rule) {
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

#[cfg(test)]
mod tests {
    use super::*;
    use crate::quad::integrate;

    /// `∫ f` over the pieces `cuts`, adaptive G10–K21 at relative `1e-13`.
    fn quad(f: &dyn Fn(f64) -> f64, cuts: &[f64]) -> f64 {
        cuts.windows(2)
            .map(|w| {
                integrate(f, w[0], w[1], Tolerance::new(0.0, 1e-13))
                    .unwrap()
                    .value
            })
            .sum()
    }

    /// `(base, sh, cut)` of the circle of radius `rho` around `A`, `B` at
    /// `theta_h` (as in [`ring_cuts`]).
    fn circle(rho: f64, theta_h: f64) -> (f64, f64, f64) {
        let sd = (0.5 * (rho - theta_h)).sin();
        let sh = rho.sin() * theta_h.sin();
        (4.0 * sd * sd, sh, (rho - theta_h).cos() / (2.0 * sh))
    }

    const CIRCLES: [(f64, f64); 9] = [
        (1e-4, 1e-4),
        (1.0001e-4, 1e-4),
        (0.3, 0.3),
        (0.31, 0.3),
        (0.5, 0.3),
        (1.2, 1.2),
        (1.5, 1.2),
        (0.9, 1.2),
        (1.5, 1.5),
    ];

    #[test]
    fn kernel_map_integrates_closed_forms() {
        // The leading factor (a + b sin²(ψ/2))^(−q), a = 1 + 4u²·base,
        // b = 16u²·sh, on ψ ∈ [0, ψ_max], through the map of ArcMap::Kernel:
        // q = 1: (2/√(a(a+b))) atan(√((a+b)/a) tan(ψ_max/2)) (π/√(a(a+b)) for
        // ψ_max = π); q = 2, ψ_max = π: π(2a+b) / (2 (a(a+b))^(3/2)).
        let mut checked = [0, 0];
        for &u in &[0.5, 30.0, 3000.0] {
            for &(rho, theta_h) in &CIRCLES {
                let (base, sh, cut) = circle(rho, theta_h);
                let (a, b) = (1.0 + 4.0 * u * u * base, 16.0 * u * u * sh);
                let Ring::Arcs { map, cuts } = kernel_arcs(u, base, sh, cut) else {
                    panic!("not arcs");
                };
                let leading = |q: f64| {
                    quad(
                        &|t| {
                            let (d2, jac) = map.point(t);
                            (1.0 + 4.0 * u * u * d2).powf(-q) * jac
                        },
                        &cuts,
                    )
                };
                let ab = a * (a + b);
                let (exact1, full) = if cut >= 1.0 {
                    (PI / ab.sqrt(), true)
                } else {
                    let tan_half = (cut / (1.0 - cut)).sqrt();
                    let e = 2.0 / ab.sqrt() * (((a + b) / a).sqrt() * tan_half).atan();
                    (e, false)
                };
                let v1 = leading(1.0);
                assert!(
                    (v1 - exact1).abs() <= 1e-12 * exact1,
                    "u={u} ρ={rho} θh={theta_h}: {v1} vs {exact1}"
                );
                checked[usize::from(full)] += 1;
                if full {
                    let exact2 = PI * (2.0 * a + b) / (2.0 * ab.powf(1.5));
                    let v2 = leading(2.0);
                    assert!(
                        (v2 - exact2).abs() <= 1e-12 * exact2,
                        "u={u} ρ={rho} θh={theta_h}: {v2} vs {exact2}"
                    );
                }
            }
        }
        // Both kinds of circle were checked: whole and cut by the horizon.
        assert!(checked[0] > 0 && checked[1] > 0, "{checked:?}");
    }

    #[test]
    fn kernel_ring_matches_azimuthal_quadrature() {
        // The exact kernel over a circle: in the map's variable against the
        // azimuth ψ split at the circle's crossings of the kernel's old
        // breakpoint grid w·2^k, k ≥ −4 (the quadrature before the map).
        for &u in &[0.5, 30.0, 3000.0] {
            for &c in &[1.01, 2.0, 10.0] {
                let q = 0.5 * (c + 1.0);
                let lobe = Lobe::Kernel { u, q };
                let w = 0.5 / u;
                let mut bp = lobe.breakpoints();
                bp.extend([w / 2.0, w / 4.0, w / 8.0, w / 16.0]);
                sort_dedup(&mut bp);
                for &(rho, theta_h) in &CIRCLES {
                    let (base, sh, cut) = circle(rho, theta_h);
                    let delta = (rho - theta_h).abs();
                    let value = |ring: Ring| {
                        let Ring::Arcs { map, cuts } = ring else {
                            panic!("not arcs");
                        };
                        quad(&|t| map.value(&lobe, t), &cuts)
                    };
                    let mapped = value(kernel_arcs(u, base, sh, cut));
                    let azimuthal = value(azimuth_arcs(&bp, base, delta, sh, cut));
                    assert!(
                        (mapped - azimuthal).abs() <= 1e-12 * azimuthal,
                        "u={u} c={c} ρ={rho} θh={theta_h}: {mapped} vs {azimuthal}"
                    );
                }
            }
        }
    }
}
