//! Closed-form isotropic BRDFs for testing the spherical-harmonic projection
//! ([`crate::sh`]) and its convergence studies, where an analytic BRDF (and
//! no table) is wanted.
//!
//! The stand-in ([`StandIn`]) is a Beckmann Cook–Torrance microfacet BRDF with
//! the material's complex Fresnel factor and, for a plastic, the base layer of
//! docs/model.md §2.6; it has no diffraction lobe, no EPD shape (`p` is ignored: the NDF
//! is Beckmann with `α = β`), and no σs, b, c. The committed T4 files project
//! the two-scale model instead (`tables::sh_brdf`); the stand-in is
//! `tables::sh_brdf::Projected::BeckmannStandIn` (header `brdf_model = 2`).

use std::f64::consts::PI;

use crate::reference::fresnel::{Complex64, fresnel};
use crate::sh::IsotropicBrdf;

/// `ρ = albedo / π`. Its `f = ρ cos θi cos θo` completed oddly is
/// `(albedo/π)(4π/3) Y_10(i) Y_10(o)`, so its SH matrix has the single
/// element `B^0_{11} = 4·albedo/3` (the closed form the tests check).
#[derive(Clone, Copy, Debug)]
pub struct Lambertian {
    /// Directional-hemispherical reflectance, in [0, 1].
    pub albedo: f64,
}

impl IsotropicBrdf for Lambertian {
    fn eval(&self, wi: [f64; 3], wo: [f64; 3]) -> f64 {
        if wi[2] > 0.0 && wo[2] > 0.0 {
            self.albedo / PI
        } else {
            0.0
        }
    }
}

/// Beckmann Cook–Torrance: `ρ = F(i·h) D(h) G1(i) G1(o) / (4 cos θi cos θo)`,
/// `D(h) = exp(−tan²θh/α²) / (π α² cos⁴θh)`, Smith `G1 = 1/(1 + Λ(α tan θ))`
/// with Beckmann's closed-form Λ (docs/model.md §2.2 at p = 1). `eta = None` means
/// `F ≡ 1`. Reciprocal, and even in `φo − φi`.
#[derive(Clone, Copy, Debug)]
pub struct BeckmannCt {
    /// Beckmann roughness α (RMS slope).
    pub alpha: f64,
    /// Complex index `n + ik` for the Fresnel factor; `None` for `F = 1`.
    pub eta: Option<Complex64>,
}

impl BeckmannCt {
    /// Smith `G1 = 1/(1 + Λ(a))`, `a = α tan θ`, with Beckmann's closed form
    /// `Λ = (e^{−μ²}/(μ√π) − erfc μ)/2`, `μ = 1/a` (docs/model.md §2.2). For μ > 6,
    /// Λ < 1e-17 and is dropped; below, the difference loses at most a few
    /// digits of Λ, i.e. nothing visible in G1 (checked against
    /// `reference::epd::beckmann_lambda` in the tests).
    pub fn g1(&self, cos_theta: f64) -> f64 {
        let sin = (1.0 - cos_theta * cos_theta).max(0.0).sqrt();
        let mu = cos_theta / (self.alpha * sin);
        if mu > 6.0 || mu.is_nan() {
            return 1.0;
        }
        let lambda = 0.5 * ((-mu * mu).exp() / (mu * PI.sqrt()) - libm::erfc(mu));
        1.0 / (1.0 + lambda)
    }
}

impl IsotropicBrdf for BeckmannCt {
    fn eval(&self, wi: [f64; 3], wo: [f64; 3]) -> f64 {
        let (ci, co) = (wi[2], wo[2]);
        if !(ci > 0.0 && co > 0.0) {
            return 0.0;
        }
        let h = [wi[0] + wo[0], wi[1] + wo[1], wi[2] + wo[2]];
        let len = (h[0] * h[0] + h[1] * h[1] + h[2] * h[2]).sqrt();
        let cos_h = h[2] / len;
        let cos_d = ((wi[0] * h[0] + wi[1] * h[1] + wi[2] * h[2]) / len).clamp(0.0, 1.0);
        let cos2 = cos_h * cos_h;
        let tan2 = (1.0 - cos2) / cos2;
        let a2 = self.alpha * self.alpha;
        let d = (-tan2 / a2).exp() / (PI * a2 * cos2 * cos2);
        let f = match self.eta {
            None => 1.0,
            Some(eta) => fresnel(eta, cos_d).unwrap_or(1.0),
        };
        f * d * self.g1(ci) * self.g1(co) / (4.0 * ci * co)
    }
}

/// The T4 stand-in for one material at one wavelength (see the module docs):
/// a Beckmann Cook–Torrance lobe with complex Fresnel, plus for a plastic the
/// base layer of docs/model.md §2.6,
/// `(1 − F(θi))(1 − F(θo)) ρd / (π η² (1 − ρd F_dr,int))`.
#[derive(Clone, Copy, Debug)]
pub struct StandIn {
    /// The specular lobe.
    pub lobe: BeckmannCt,
    /// `ρd / (π η² (1 − ρd F_dr,int))` of the plastic base, 0 for a conductor.
    pub base_factor: f64,
}

impl IsotropicBrdf for StandIn {
    fn eval(&self, wi: [f64; 3], wo: [f64; 3]) -> f64 {
        let specular = self.lobe.eval(wi, wo);
        if self.base_factor == 0.0 || !(wi[2] > 0.0 && wo[2] > 0.0) {
            return specular;
        }
        let eta = self.lobe.eta.unwrap_or(Complex64::real(1.5));
        let ti = 1.0 - fresnel(eta, wi[2].min(1.0)).unwrap_or(0.0);
        let to = 1.0 - fresnel(eta, wo[2].min(1.0)).unwrap_or(0.0);
        specular + ti * to * self.base_factor
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::reference::epd::beckmann_lambda;

    #[test]
    fn fast_g1_matches_the_reference_lambda() {
        let brdf = BeckmannCt {
            alpha: 0.3,
            eta: None,
        };
        for k in 1..1000 {
            let cos = k as f64 / 1000.0;
            let tan = (1.0 - cos * cos).sqrt() / cos;
            let want = 1.0 / (1.0 + beckmann_lambda(0.3 * tan));
            assert!((brdf.g1(cos) - want).abs() < 1e-14, "cos θ = {cos}");
        }
    }
}
