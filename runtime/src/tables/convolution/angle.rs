//! The normalised angle ξ(θh; u, β, p) at which T3b stores `ln C`
//! ([`crate::tables::convolution`]'s documentation gives its terms).

use crate::math::{self, Real};
use crate::tables::format::AngleParams;

/// `asinh x` for `x ≥ 0`, accurate for small `x`.
#[inline]
fn asinh_pos<T: Real>(x: T) -> T {
    let one = T::of(1.0);
    (x + x * x / (one + (one + x * x).sqrt())).ln_1p()
}

/// The parts of `F` that depend on `(u, β, p)` only, computed once per
/// lookup (`F` is evaluated at `τ` and at `τ_max`, and many times by the
/// inverse), in f64 and rounded to `T`, the type `F` is evaluated in.
pub(super) struct AngleShape<T> {
    beta: T,
    /// `u_e = √(u² + u_floor²)`.
    ue: T,
    /// The softened exponent `p'`.
    p_eff: T,
    /// `tan θe`, the NDF's edge (∞ for tiny `p'`).
    tau_edge: T,
    /// The edge term's fade `f_e` (0 when `tan θe` is not finite in `T`).
    fade: T,
    /// The edge term's smoothing width `δ = s_e / (2 u_e)`.
    delta: T,
    /// `Y`, `w_h`, `w_e`, `λ` of [`AngleParams`].
    cap: T,
    /// `ln(40 Y)`: for `ln y` above it, `1 − e^(−y/Y)` rounds to 1 in f64
    /// (and f32), and the NDF term is `ln(1 + Y)`.
    ln_saturation: T,
    /// `ln(1 + Y)`.
    ndf_saturated: T,
    horizon_weight: T,
    edge_weight: T,
    ndf_weight: T,
}

impl<T: Real> AngleShape<T> {
    #[inline]
    pub(super) fn new(u: f64, beta: f64, p: f64, a: &AngleParams) -> Self {
        let ue = math::sqrt(u * u + a.kernel_scale_floor * a.kernel_scale_floor);
        // The kernel (width ~1/(2u_e)) smooths the NDF's cliff at τ ≈ β over
        // Δln τ ≈ 1/(2 u_e β): soften the exponent to match.
        let p_eff = p / (1.0 + a.ndf_softening * p / (2.0 * ue * beta));
        // The NDF's edge θe, where y = Y: tan θe = β Y^(1/(2p')).
        let tau_edge = beta * math::exp(math::ln(a.ndf_exponent_cap) / (2.0 * p_eff));
        let fade = 1.0 / (1.0 + (tau_edge / a.edge_fade_tan) * (tau_edge / a.edge_fade_tan));
        // Where the kernel is wider than the NDF, C has no edge: (p'/p)^m.
        let fade = if a.edge_softening_fade > 0.0 {
            fade * math::exp(a.edge_softening_fade * math::ln(p_eff / p))
        } else {
            fade
        };
        let delta = a.edge_smoothing / (2.0 * ue);
        let tau_edge = T::of(tau_edge);
        AngleShape {
            beta: T::of(beta),
            ue: T::of(ue),
            p_eff: T::of(p_eff),
            tau_edge,
            fade: if tau_edge.wide() < f64::INFINITY {
                T::of(fade)
            } else {
                T::of(0.0)
            },
            delta: T::of(delta),
            cap: T::of(a.ndf_exponent_cap),
            ln_saturation: T::of(math::ln(40.0 * a.ndf_exponent_cap)),
            ndf_saturated: T::of(a.ndf_exponent_cap).ln_1p(),
            horizon_weight: T::of(a.horizon_weight),
            edge_weight: T::of(a.edge_weight),
            ndf_weight: T::of(a.ndf_weight),
        }
    }

    /// `F(τ)` of the normalised angle (module documentation), `τ ≥ 0`.
    #[inline]
    pub(super) fn f(&self, tau: T) -> T {
        let (zero, one, two, half) = (T::of(0.0), T::of(1.0), T::of(2.0), T::of(0.5));
        let ue = self.ue;
        // sec θh = √(1 + τ²); sin θh = τ / sec θh.
        let secant = (one + tau * tau).sqrt();
        let kernel_term = asinh_pos(two * ue * tau / secant);
        let horizon_term = half * (tau * tau).ln_1p();
        let ln_y = if tau > zero {
            two * self.p_eff * (tau / self.beta).ln()
        } else {
            T::of(f64::NEG_INFINITY)
        };
        let ndf_term = if ln_y > self.ln_saturation {
            self.ndf_saturated
        } else {
            let cap = self.cap;
            // 1 − e^(−y/Y).
            let saturated = -(-(ln_y.exp() / cap)).exp_m1();
            (cap * saturated).ln_1p()
        };
        let edge_term = if self.fade > zero {
            // θh − θe = atan((τ − τe) / (1 + τ τe)), in (−π/2, π/2); its
            // positive part smoothed, (x + √(x² + δ²)) / 2, and held ≤ π/2
            // so that the sine (and F) keeps increasing.
            let tau_edge = self.tau_edge;
            let offset = ((tau - tau_edge) / (one + tau * tau_edge)).atan();
            let delta = self.delta;
            let beyond = half * (offset + (offset * offset + delta * delta).sqrt());
            let right_angle = T::of(core::f64::consts::FRAC_PI_2);
            let beyond = if beyond < right_angle {
                beyond
            } else {
                right_angle
            };
            self.fade * asinh_pos(two * ue * beyond.sin())
        } else {
            zero
        };
        kernel_term
            + self.horizon_weight * horizon_term
            + self.edge_weight * edge_term
            + self.ndf_weight * ndf_term
    }
}

/// The normalised angle `ξ ∈ [0, 1]` of `τ = tan θh` for the parameters
/// `(u, β, p)`: `ξ = F(min(τ, τ_max)) / F(τ_max)` (module documentation).
/// Shared by the generator (node placement) and the lookup. Inputs must be
/// finite with `β, p > 0`, `u ≥ 0`; `τ < 0` is treated as 0.
pub fn normalised_angle(tau: f64, u: f64, beta: f64, p: f64, a: &AngleParams) -> f64 {
    let tau = tau.max(0.0).min(a.tau_max);
    let shape = AngleShape::<f64>::new(u, beta, p, a);
    (shape.f(tau) / shape.f(a.tau_max)).max(0.0).min(1.0)
}

/// The inverse of [`normalised_angle`]: `τ(ξ)` by bisection on `[0, τ_max]`
/// in `ln(1 + τ)` (F is increasing), to full f64 precision. For the generator.
pub fn tan_of_normalised_angle(xi: f64, u: f64, beta: f64, p: f64, a: &AngleParams) -> f64 {
    if !(xi > 0.0) {
        return 0.0;
    }
    if xi >= 1.0 {
        return a.tau_max;
    }
    let shape = AngleShape::<f64>::new(u, beta, p, a);
    let target = xi * shape.f(a.tau_max);
    let (mut lo, mut hi) = (0.0f64, math::ln_1p(a.tau_max));
    for _ in 0..200 {
        let mid = 0.5 * (lo + hi);
        if mid <= lo || mid >= hi {
            break;
        }
        if shape.f(math::exp_m1(mid)) < target {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    math::exp_m1(0.5 * (lo + hi))
}
