//! The 2015 model of Holzschuch & Pacanowski (INRIA RR-8807; docs/model.md §2.8) at one
//! wavelength: a Cook–Torrance lobe with the EPD NDF and Schlick's Fresnel, a
//! diffraction lobe `S_z(f)`, and a Lambertian term:
//!
//! ```text
//! ρ   = k_d/π + G(i,o) · ( k_s D(θh) F(θd) / (4 cos θi cos θo) + (k_w/λ⁴) S_z(f) / E_{a,λ} )   (HP15 24)
//! S_z = (1 + f²/a²)^(−2)                                                                 (HP15 25)
//! D   = EPD with σ ≡ β                                                                   (HP15 26)
//! F   = F0 + (1 − F0)(1 − cos θd)⁵                                                        (HP15 27)
//! f   = |proj(refl(i) − o)| / λ = |i_p + o_p| / λ      (µm⁻¹; a in µm⁻¹)
//! ```
//!
//! `E_{a,λ}` normalises the diffraction lobe. (HP15 17) prints
//! `E = π(1 + 1/(a²λ²))`; the exact energy of `S_z` at normal incidence is
//! `∫ S_z cos θo dωo = π / (1 + 1/(a²λ²))` (docs/model.md §2.8, §8). [`Energy::Exact`]
//! (the default) uses the exact one, [`Energy::Printed`] the printed one.
//!
//! G is the separable EPD Smith term (T1), as in the paper (HP15 §5.5).
//!
//! **Sampling** (HP15 §5.5, multi-lobe selection): the Cook–Torrance lobe
//! through the EPD (reflection about a sampled normal), the diffraction lobe
//! as a diffuse (cosine) lobe, as the paper does, and the Lambertian lobe
//! cosine-weighted. The lobes are chosen with probabilities proportional to
//! `k_s`, `(k_w/λ⁴) · E_exact/E` (the diffraction lobe's albedo at normal
//! incidence without G, so with the exact E it is `k_w/λ⁴`) and `k_d`.
//! Guards as in [`crate::brdf`]: 0 below the horizon, never NaN/∞.

use crate::math::{self, BELOW_ONE, upper_unit};
use crate::model::epd::Epd;
use crate::tables::smith_g1::SmithG1Table;
use core::f64::consts::PI;

/// Which `E_{a,λ}` normalises the diffraction lobe.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Energy {
    /// `π / (1 + 1/(a²λ²))`, the exact energy (the default).
    #[default]
    Exact,
    /// `π (1 + 1/(a²λ²))`, as printed in (HP15 17).
    Printed,
}

/// Parameters of the 2015 model at one wavelength.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Hp15Params {
    /// EPD width σ (β).
    pub beta: f32,
    /// EPD shape p ∈ [0.2, 5].
    pub p: f32,
    /// Spatial-frequency scale a of `S_z`, µm⁻¹.
    pub a: f32,
    /// Lambertian colour k_d.
    pub kd: f32,
    /// Specular colour k_s.
    pub ks: f32,
    /// Diffraction colour k_w.
    pub kw: f32,
    /// Schlick's normal-incidence reflectance F0.
    pub f0: f32,
}

/// The 2015 model at one wavelength.
#[derive(Clone, Copy, Debug)]
pub struct Hp15<'a> {
    ndf: Epd<'a>,
    params: Hp15Params,
    lambda: f64,
    /// `1/(aλ)²`.
    inv_al_sq: f64,
    /// `k_w / (λ⁴ E)`.
    diffraction_scale: f64,
    /// Lobe probabilities `[Cook–Torrance, cosine (diffraction + diffuse)]`.
    weights: [f64; 2],
}

impl<'a> Hp15<'a> {
    /// The model with `params` at wavelength `lambda` (µm). Colours and F0
    /// are clamped to ≥ 0 (F0 ≤ 1), a to ≥ 1e-6 µm⁻¹, λ as in
    /// [`crate::brdf::TwoScale::new`].
    pub fn new(smith: &SmithG1Table<'a>, params: Hp15Params, lambda: f32, energy: Energy) -> Self {
        let nonneg = |x: f32| {
            if x > 0.0 {
                f64::from(x.min(f32::MAX))
            } else {
                0.0
            }
        };
        let lambda = math::sanitised_wavelength(lambda);
        let a = nonneg(params.a).max(1e-6);
        let inv_al_sq = 1.0 / (a * lambda * a * lambda);
        let e_exact = PI / (1.0 + inv_al_sq);
        let e = match energy {
            Energy::Exact => e_exact,
            Energy::Printed => PI * (1.0 + inv_al_sq),
        };
        let (ks, kw, kd) = (nonneg(params.ks), nonneg(params.kw), nonneg(params.kd));
        let lambda4 = lambda * lambda * lambda * lambda;
        let diffraction_scale = kw / (lambda4 * e);
        let w = [ks, kw / lambda4 * e_exact / e, kd];
        let total = w[0] + w[1] + w[2];
        let weights = if total > 0.0 && total.is_finite() {
            [w[0] / total, (w[1] + w[2]) / total]
        } else {
            [1.0, 0.0]
        };
        Hp15 {
            ndf: Epd::new(params.beta, params.p, smith),
            params: Hp15Params {
                f0: params.f0.max(0.0).min(1.0),
                ..params
            },
            lambda,
            inv_al_sq,
            diffraction_scale,
            weights,
        }
    }

    /// ρ(i, o) (HP15 24), sr⁻¹; 0 below the horizon.
    pub fn eval(&self, i: [f32; 3], o: [f32; 3]) -> f32 {
        let (Some(wi), Some(wo)) = (upper_unit(i), upper_unit(o)) else {
            return 0.0;
        };
        let sum = [wi[0] + wo[0], wi[1] + wo[1], wi[2] + wo[2]];
        let len = math::sqrt(sum[0] * sum[0] + sum[1] * sum[1] + sum[2] * sum[2]);
        let h = sum.map(|x| x / len);
        let cos_d = (wi[0] * h[0] + wi[1] * h[1] + wi[2] * h[2])
            .max(0.0)
            .min(1.0);
        let (i32_, o32) = (wi.map(|x| x as f32), wo.map(|x| x as f32));
        let g = f64::from(self.ndf.g(i32_, o32));
        let d = f64::from(self.ndf.d(h.map(|x| x as f32)));
        let f0 = f64::from(self.params.f0);
        let m = 1.0 - cos_d;
        let schlick = f0 + (1.0 - f0) * m * m * m * m * m; // (HP15 27)
        let specular = f64::from(self.params.ks.max(0.0)) * d * schlick / (4.0 * wi[2] * wo[2]);
        // λ² f² = |i_p + o_p|²; f²/a² = λ² f² · 1/(aλ)².
        let (px, py) = (wi[0] + wo[0], wi[1] + wo[1]);
        let x = (px * px + py * py) * self.inv_al_sq;
        let s_z = 1.0 / ((1.0 + x) * (1.0 + x)); // (HP15 25)
        let diffraction = self.diffraction_scale * s_z;
        let kd = f64::from(self.params.kd.max(0.0));
        let value = kd / PI + g * (specular + diffraction);
        if value.is_finite() {
            value.min(f64::from(f32::MAX)) as f32
        } else {
            0.0
        }
    }

    /// The density of [`Hp15::sample`]:
    /// `w_ct · D(h) cos θh / (4 i·h) + (1 − w_ct) · cos θo / π`.
    pub fn pdf(&self, i: [f32; 3], o: [f32; 3]) -> f32 {
        let (Some(wi), Some(wo)) = (upper_unit(i), upper_unit(o)) else {
            return 0.0;
        };
        let sum = [wi[0] + wo[0], wi[1] + wo[1], wi[2] + wo[2]];
        let len = math::sqrt(sum[0] * sum[0] + sum[1] * sum[1] + sum[2] * sum[2]);
        let h = sum.map(|x| x / len);
        let cos_d = wi[0] * h[0] + wi[1] * h[1] + wi[2] * h[2];
        let specular = if cos_d > 0.0 {
            f64::from(self.ndf.pdf(h.map(|x| x as f32))) / (4.0 * cos_d)
        } else {
            0.0
        };
        let value = self.weights[0] * specular + self.weights[1] * wo[2] / PI;
        if value.is_finite() {
            value.min(f64::from(f32::MAX)) as f32
        } else {
            0.0
        }
    }

    /// Samples `o`: `u[0]` picks the Cook–Torrance lobe (probability
    /// `w_ct`) or the cosine lobe, `u[1], u[2]` sample it. Returns `(o, pdf)`,
    /// or `None` below the horizon.
    pub fn sample(&self, i: [f32; 3], u: [f32; 3]) -> Option<([f32; 3], f32)> {
        let wi = upper_unit(i)?;
        let u1 = f64::from(u[1].max(0.0).min(BELOW_ONE));
        let u2 = f64::from(u[2].max(0.0).min(BELOW_ONE));
        let o = if f64::from(u[0].max(0.0).min(BELOW_ONE)) < self.weights[0] {
            let m = self.ndf.sample([u1 as f32, u2 as f32]).map(f64::from);
            let k = 2.0 * (wi[0] * m[0] + wi[1] * m[1] + wi[2] * m[2]);
            [k * m[0] - wi[0], k * m[1] - wi[1], k * m[2] - wi[2]]
        } else {
            let r = math::sqrt(u1);
            let phi = 2.0 * PI * u2;
            [r * math::cos(phi), r * math::sin(phi), math::sqrt(1.0 - u1)]
        };
        let o = upper_unit(o.map(|x| x as f32))?.map(|x| x as f32);
        let pdf = self.pdf(i, o);
        (pdf > 0.0).then_some((o, pdf))
    }

    /// `[k_s, k_w, k_d]` as used (negative colours count as 0).
    pub(crate) fn colours(&self) -> [f32; 3] {
        let p = &self.params;
        [p.ks, p.kw, p.kd].map(|x| x.max(0.0))
    }

    /// The wavelength in use (µm).
    pub fn wavelength(&self) -> f32 {
        self.lambda as f32
    }
}
