//! The Exponential Power Distribution (EPD) microfacet NDF, pbrt-style: the
//! distribution D, Smith Λ, G1 and G, and the sampling routine with its pdf
//! live together in [`Epd`].
//!
//! ```text
//! P22(x) = p / (π β² Γ(1/p)) · exp(−(x/β²)^p),   x = tan²θ          (HP17 35)
//! D(θ)   = χ(θ < π/2) · P22(tan²θ) / cos⁴θ                            (HP17 34)
//! ```
//!
//! `p = 1` is Beckmann with `α = β`; `p < 1` has heavier tails, `p > 1` a flatter
//! top. Smith masking comes from table T1 ([`crate::tables::smith_g1`]).
//!
//! Parameter domain: `p` is clamped to [0.2, 5] (the domain of T1) and `β` to
//! [1e-4, 10]; NaN parameters become the lower bound. Directions are in the
//! local frame (normal = +z) as unit vectors `[x, y, z]`.

use crate::material::BETA_RANGE;
use crate::material::P_RANGE;
use crate::math::gamma::inverse_gamma_two_tailed;
use crate::math::{self, BELOW_ONE};
use crate::tables::smith_g1::{SmithG1Table, SmithShape};

/// An EPD microfacet distribution with parameters (β, p).
#[derive(Clone, Copy, Debug)]
pub struct Epd<'a> {
    beta: f32,
    p: f32,
    /// `p / (π β² Γ(1/p))`, the normalisation of P22.
    norm: f32,
    /// `1 / β²`.
    inv_beta_sq: f32,
    /// `1/p`, the shape of the Gamma variable `y = (tan²θ/β²)^p`.
    gamma_shape: f64,
    smith: SmithShape<'a>,
}

impl<'a> Epd<'a> {
    /// The distribution with roughness `beta` and shape `p` (clamped to
    /// [`BETA_RANGE`], [`P_RANGE`]), masking from the T1 table `smith`.
    pub fn new(beta: f32, p: f32, smith: &SmithG1Table<'a>) -> Self {
        let beta = beta.max(BETA_RANGE.0).min(BETA_RANGE.1);
        let p = p.max(P_RANGE.0).min(P_RANGE.1);
        let (beta64, p64) = (f64::from(beta), f64::from(p));
        let norm =
            p64 / (core::f64::consts::PI * beta64 * beta64) * math::exp(-math::ln_gamma(1.0 / p64));
        Epd {
            beta,
            p,
            norm: norm as f32,
            inv_beta_sq: 1.0 / (beta * beta),
            gamma_shape: 1.0 / p64,
            smith: smith.shape(p),
        }
    }

    /// β after clamping.
    pub fn beta(&self) -> f32 {
        self.beta
    }

    /// p after clamping.
    pub fn p(&self) -> f32 {
        self.p
    }

    /// `(norm, 1/β²)` of [`Epd::d`]: `D = norm · e^−(tan²θ/β²)^p / cos⁴θ`.
    pub(crate) fn d_constants(&self) -> (f32, f32) {
        (self.norm, self.inv_beta_sq)
    }

    /// The NDF D(θm) (HP17 34-35) of a microfacet normal `m` (unit vector, local
    /// frame). Zero at and below the horizon; `∫ D cos θm dω = 1`.
    ///
    /// `tan²θ` is computed from the components, `(x² + y²) / z²`, not from
    /// `cos θ`: near the normal `1 − cos θ` loses all precision in f32, and for
    /// β = 0.002 that alone would make D wrong by percents.
    ///
    /// Mirrored in python/twoscale/drjit/models.py.
    #[inline]
    pub fn d(&self, m: [f32; 3]) -> f32 {
        let cos_theta = m[2];
        // NaN fails the comparison and lands here too.
        if !(cos_theta > 0.0) {
            return 0.0;
        }
        let cos_sq = cos_theta * cos_theta;
        // 1/cos⁴θ alongside the exponentials, not after them.
        let inv_cos4 = 1.0 / (cos_sq * cos_sq);
        let tan_sq = tan_sq(m);
        // libm's f32 powf and expf: the inlined f64 forms (math::pow_positive,
        // exp_inline) count fewer instructions but ran slower (speed.md).
        let x = tan_sq * self.inv_beta_sq;
        // Beckmann (p = 1) needs no power: powf(x, 1) is x exactly.
        let y = if self.p == 1.0 {
            x
        } else {
            math::powff(x, self.p)
        };
        // e^−y is 0 in f32 beyond y ≈ 104.
        if !(y < 104.0) {
            return 0.0;
        }
        let falloff = math::expf(-y);
        if !(falloff > 0.0) {
            // Also covers z so small that cos⁴θ underflows (tan² = ∞).
            return 0.0;
        }
        // A unit `m` has cos⁴θ ≫ 0 here; a shorter one can underflow it to 0.
        (self.norm * inv_cos4 * falloff).min(f32::MAX)
    }

    /// Smith Λ (HP17 37) of direction `w`, from T1. Normal incidence → 0; at or
    /// below the horizon → `f32::MAX` (G1 = 0).
    #[inline]
    pub fn lambda(&self, w: [f32; 3]) -> f32 {
        if !(w[2] > 0.0) {
            return f32::MAX;
        }
        self.smith.lambda(self.beta * math::sqrtf(tan_sq(w)))
    }

    /// Smith masking G1 = 1/(1 + Λ) (HP17 38) of direction `w`, from T1. Zero
    /// at and below the horizon, one at normal incidence.
    #[inline]
    pub fn g1(&self, w: [f32; 3]) -> f32 {
        if !(w[2] > 0.0) {
            return 0.0;
        }
        self.smith.g1(self.beta * math::sqrtf(tan_sq(w)))
    }

    /// Separable shadowing–masking `G1(i) · G1(o)`, as both papers use.
    #[inline]
    pub fn g(&self, i: [f32; 3], o: [f32; 3]) -> f32 {
        self.g1(i) * self.g1(o)
    }

    /// Height-correlated shadowing–masking `1 / (1 + Λ(i) + Λ(o))` (an option;
    /// it accounts for the correlation the separable form ignores).
    #[inline]
    pub fn g_height_correlated(&self, i: [f32; 3], o: [f32; 3]) -> f32 {
        if !(i[2] > 0.0 && o[2] > 0.0) {
            return 0.0;
        }
        // Λ ≤ f32::MAX each: the sum can overflow to ∞, and 1/(1+∞) = 0 is right.
        1.0 / (1.0 + self.lambda(i) + self.lambda(o))
    }

    /// Density of [`Epd::sample`] as a solid-angle density over microfacet
    /// normals `m` (unit vector): `D(m) cos θm`.
    #[inline]
    pub fn pdf(&self, m: [f32; 3]) -> f32 {
        self.d(m) * m[2].max(0.0)
    }

    /// Samples a microfacet normal with density `D(m) cos θm` (HP17 49-50):
    /// `y = Q⁻¹(1/p, 1 − u₀)` (so `u₀ = 0` gives the normal), `tan θm = β y^{1/(2p)}`,
    /// `φm = 2π u₁`. The variable `y = (tan²θ/β²)^p` is Gamma(1/p, 1)
    /// distributed, which is why its quantile is the inverse regularised
    /// incomplete gamma. `u` is clamped to [0, 1).
    pub fn sample(&self, u: [f32; 2]) -> [f32; 3] {
        normal_at(self.sample_tan_theta(u[0]), u[1])
    }

    /// The polar part of [`Epd::sample`]: `tan θm = β · Q⁻¹(1/p, 1 − u₀)^{1/(2p)}`
    /// (HP17 50), computed in f64 and rounded once (`P⁻¹(1/p, u₀)` below
    /// `u₀ = ½`, where `1 − u₀` would round away the low tail).
    pub fn sample_tan_theta(&self, u0: f32) -> f32 {
        let u0 = f64::from(u0.max(0.0).min(BELOW_ONE));
        let y = inverse_gamma_two_tailed(self.gamma_shape, u0, 1.0 - u0);
        (f64::from(self.beta) * math::powf(y, 0.5 * self.gamma_shape)) as f32
    }
}

/// The unit normal with polar angle `tan θ` and azimuth `φ = 2π u₁` (`u₁`
/// clamped to [0, 1)).
#[inline]
pub(crate) fn normal_at(tan_theta: f32, u1: f32) -> [f32; 3] {
    let tan_theta = f64::from(tan_theta);
    let cos_theta = 1.0 / math::sqrt(1.0 + tan_theta * tan_theta);
    let sin_theta = (tan_theta * cos_theta) as f32;
    let phi = 2.0 * core::f32::consts::PI * u1.max(0.0).min(BELOW_ONE);
    [
        sin_theta * math::cosf(phi),
        sin_theta * math::sinf(phi),
        cos_theta as f32,
    ]
}

/// `tan²θ = (x² + y²) / z²` of a direction (∞ when z = 0; callers check z > 0).
#[inline]
fn tan_sq(w: [f32; 3]) -> f32 {
    (w[0] * w[0] + w[1] * w[1]) / (w[2] * w[2])
}
