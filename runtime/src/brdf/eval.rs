//! `eval`: the terms of ρ at a pair of directions (HP17 24-33).

use super::ChannelBake;
use super::Lobes;
use super::TwoScale;
use super::dot;
use super::exp_and_one_minus_over;
use super::finite_or_zero;
use super::to_f32;
use crate::bake::{DirectionCell, DirectionValues};
use crate::material::{BaseLayer, HaloWeight, Masking, SigmaRelMode};
use crate::math::{self, upper_unit};
use crate::model::fresnel::QConstants;
use core::borrow::Borrow;
use core::f64::consts::PI;

/// What one pair of directions gives, independent of the wavelength: the
/// geometry (shared by `pdf` and `eval`, and by the channels of [`Rgb`];
/// `pdf` needs no D, [`Pair`] adds it).
#[derive(Clone, Copy, Debug)]
pub(super) struct Geometry {
    pub(super) wi: [f64; 3],
    pub(super) wo: [f64; 3],
    /// The half-vector in f32, as D reads it.
    pub(super) h: [f32; 3],
    pub(super) cos_d: f64,
    pub(super) cos_h: f64,
    pub(super) sin_h: f64,
}

/// [`Geometry`], D(h) and G(i, o): what `eval` needs of a pair of
/// directions before the wavelength.
#[derive(Clone, Copy, Debug)]
pub(super) struct Pair {
    pub(super) geometry: Geometry,
    /// D(h).
    pub(super) d: f64,
    pub(super) g: f64,
    /// The direction bake's cells of `cos θi`, `cos θo` and `cos θd`.
    pub(super) cells: [DirectionCell; 3],
    /// `sin θi sin θo (cos φ, sin φ)` with φ = φo − φi − π (for Q̄).
    pub(super) along: f64,
    pub(super) across: f64,
}

/// What [`TwoScale::surface_terms`] computes at a pair.
#[derive(Clone, Copy)]
pub(super) struct SurfaceTerms {
    /// `A_spec(θd)`.
    pub(super) a_spec: f64,
    /// `ρ_CT`.
    pub(super) rho_ct: f64,
    /// `ρ_CTD`.
    pub(super) diffraction: f64,
    /// The direction bake at `cos θi` and `cos θo`.
    pub(super) at_i: DirectionValues,
    pub(super) at_o: DirectionValues,
}

/// Q̄ of a pair (HP17 33, docs/model.md §2.5), clamped at 0: 1 for white
/// colour terms, 0 without an index (`q` `None`).
#[inline]
pub(super) fn q_bar(
    q: Option<&QConstants>,
    white: bool,
    at_i: &DirectionValues,
    at_o: &DirectionValues,
    along: f64,
    across: f64,
) -> f64 {
    match (q, white) {
        (_, true) => 1.0,
        (Some(q), false) => q
            .combine(&at_i.q_factors(), &at_o.q_factors(), along, across)
            .max(0.0),
        (None, false) => 0.0,
    }
}

/// G(i, o) from G1(i) and G1(o) ([`Masking`]; docs/model.md §2.2).
#[inline]
pub(super) fn masking_g(mode: Masking, g1_i: f64, g1_o: f64) -> f64 {
    match mode {
        Masking::Separable => g1_i * g1_o,
        // Λ = 1/G1 − 1; G1 = 0 gives 1/∞ = 0.
        Masking::HeightCorrelated => 1.0 / (1.0 / g1_i + 1.0 / g1_o - 1.0),
    }
}

/// The halo's `(1 − A)/σrel²` of [`HaloWeight`]: `printed` (at θd, from
/// the same exponential as A_spec) or at θi (`x_scale` the exponent's
/// `(4π/λ)²`).
#[inline]
pub(super) fn halo_attenuation(
    mode: HaloWeight,
    printed: f64,
    x_scale: f64,
    cos_i: f64,
    sigma_rel_sq: f64,
) -> f64 {
    match mode {
        HaloWeight::Printed => printed,
        HaloWeight::Incident => exp_and_one_minus_over(x_scale * cos_i * cos_i, sigma_rel_sq).1,
    }
}

/// `σrel²/σs²` for the incidence `i` (and `o` when symmetrised).
pub(super) fn sigma_ratio_sq(
    mode: SigmaRelMode,
    at_i: &DirectionValues,
    at_o: &DirectionValues,
) -> f64 {
    match mode {
        SigmaRelMode::Incident => {
            let r = at_i.sigma_ratio();
            r * r
        }
        SigmaRelMode::Symmetrised => {
            let (a, b) = (at_i.sigma_ratio(), at_o.sigma_ratio());
            0.5 * (a * a + b * b)
        }
    }
}

impl<'a, B: Borrow<ChannelBake>> TwoScale<'a, B> {
    /// F(η, cos θ) from the direction bake, or 1 for white colour terms.
    pub(super) fn fresnel_of(&self, values: &DirectionValues) -> f64 {
        if self.white() { 1.0 } else { values.fresnel() }
    }

    /// F(η, cos θ) from the direction bake at `cos θ`'s cell, or 1 for
    /// white colour terms.
    pub(super) fn fresnel_at(&self, at: DirectionCell) -> f64 {
        if self.white() {
            1.0
        } else {
            f64::from(self.bake().direction.fresnel_at(at))
        }
    }

    /// `σrel²/σs²` for the incidence `i` (and `o` when symmetrised).
    pub(super) fn sigma_ratio_sq(&self, at_i: &DirectionValues, at_o: &DirectionValues) -> f64 {
        sigma_ratio_sq(self.options.sigma_rel, at_i, at_o)
    }

    /// The geometry of `(i, o)`; `None` below the horizon.
    ///
    /// Mirrored in python/twoscale/drjit/models.py.
    pub(super) fn geometry(&self, i: [f32; 3], o: [f32; 3]) -> Option<Geometry> {
        let (wi, wo) = (upper_unit(i)?, upper_unit(o)?);
        let sum = [wi[0] + wo[0], wi[1] + wo[1], wi[2] + wo[2]];
        // |i + o| ≥ z_i + z_o > 0.
        let len = math::sqrt(dot(sum, sum));
        let h = sum.map(|x| x / len);
        let cos_d = dot(wi, h).max(0.0).min(1.0);
        let cos_h = h[2].max(0.0).min(1.0);
        // sin θh from the tangential components (f64): resolves θh ≪ 1e-3,
        // which an f32 cos θh cannot.
        let sin_h = math::sqrt(h[0] * h[0] + h[1] * h[1]).min(1.0);
        Some(Geometry {
            wi,
            wo,
            h: to_f32(h),
            cos_d,
            cos_h,
            sin_h,
        })
    }

    /// The wavelength-independent part of `eval` at `(i, o)`: geometry, D
    /// and G; `None` below the horizon.
    pub(super) fn pair(&self, i: [f32; 3], o: [f32; 3]) -> Option<Pair> {
        Some(self.with_masking(self.geometry(i, o)?))
    }

    /// D(h) and G(i, o) added to `geometry`.
    ///
    /// Mirrored in python/twoscale/drjit/models.py.
    pub(super) fn with_masking(&self, geometry: Geometry) -> Pair {
        let (wi, wo) = (geometry.wi, geometry.wo);
        let tangential = |w: [f64; 3]| math::sqrtf((w[0] * w[0] + w[1] * w[1]) as f32);
        let (g1_i, g1_o) = (
            self.bake().masking.g1(tangential(wi), wi[2] as f32),
            self.bake().masking.g1(tangential(wo), wo[2] as f32),
        );
        let g = masking_g(self.options.masking, f64::from(g1_i), f64::from(g1_o));
        let cos = |x: f64| DirectionCell::new(x as f32);
        Pair {
            geometry,
            d: f64::from(self.ndf.d(geometry.h)),
            g,
            cells: [cos(wi[2]), cos(wo[2]), cos(geometry.cos_d)],
            along: -(wi[0] * wo[0] + wi[1] * wo[1]),
            across: -(wi[0] * wo[1] - wi[1] * wo[0]),
        }
    }

    /// ρ(i, o) in sr⁻¹ (HP17 24; module documentation). 0 below the horizon.
    pub fn eval(&self, i: [f32; 3], o: [f32; 3]) -> f32 {
        self.eval_lobes(i, o).total()
    }

    /// The four terms of ρ(i, o) separately.
    pub fn eval_lobes(&self, i: [f32; 3], o: [f32; 3]) -> Lobes {
        match self.pair(i, o) {
            Some(pair) => self.lobes(&pair),
            None => Lobes::default(),
        }
    }

    /// The terms of ρ at a pair (HP17 24-33).
    ///
    /// Mirrored in python/twoscale/drjit/lobes.py.
    pub(super) fn lobes(&self, pair: &Pair) -> Lobes {
        let t = self.surface_terms(pair, self.white());
        let (cos_i, cos_o) = (pair.geometry.wi[2], pair.geometry.wo[2]);
        let multiple = self.multiple_value(&t.at_i, &t.at_o);
        Lobes {
            specular: finite_or_zero(t.a_spec * t.rho_ct),
            diffraction: finite_or_zero(t.diffraction),
            base: finite_or_zero(self.base_value(&t.at_i, &t.at_o, cos_i, cos_o)),
            multiple: finite_or_zero(multiple),
        }
    }

    /// The surface lobes' factors at a pair (HP17 24-33), with white colour
    /// terms (F = Q̄ = 1) when `white`.
    #[inline(always)]
    pub(super) fn surface_terms(&self, pair: &Pair, white: bool) -> SurfaceTerms {
        let g = &pair.geometry;
        let u = (self.big_b * g.cos_d) as f32;
        self.surface_terms_with(pair, white, || self.conv_at(g.sin_h, g.cos_h, u))
    }

    /// [`TwoScale::surface_terms`] with C(θh; u) from `conv` (called only
    /// where the diffraction lobe is evaluated; `IntegratedRgb` hands in C
    /// interpolated over its wavelengths).
    ///
    /// Mirrored in python/twoscale/drjit/lobes.py.
    #[inline(always)]
    pub(super) fn surface_terms_with(
        &self,
        pair: &Pair,
        white: bool,
        conv: impl FnOnce() -> f64,
    ) -> SurfaceTerms {
        let Pair {
            geometry: Geometry { wi, wo, cos_d, .. },
            d,
            g,
            cells,
            along,
            across,
        } = *pair;
        let (cos_i, cos_o) = (wi[2], wo[2]);
        let (at_i, at_o) = (
            self.bake().direction.at_cell(cells[0]),
            self.bake().direction.at_cell(cells[1]),
        );
        let s = &self.surface;

        // A_spec = exp(−x σrel²), x = (4π cos θd / λ)²            (HP17 25)
        let x = self.x_scale * cos_d * cos_d;
        let sigma_rel_sq = if s.sigma_s > 0.0 {
            self.sigma_s_sq * self.sigma_ratio_sq(&at_i, &at_o)
        } else {
            0.0
        };
        // (1 − A)/σrel² of the halo below, from the same exponential.
        let (a_spec, one_minus_a_over) = exp_and_one_minus_over(x, sigma_rel_sq);

        // ρ_CT = F D G / (4 cos θi cos θo)                          (HP17 26)
        // D last: the other factors do not wait for its exponentials.
        let f = if white {
            1.0
        } else {
            f64::from(self.bake().direction.fresnel_at(cells[2]))
        };
        let rho_ct = f * g / (4.0 * cos_i * cos_o) * d;

        // ρ_CTD = Q̄ G (1 − A)/σrel² · (c−1) σs² b² / (2π λ²) · C    (HP17 32-33, docs/model.md §2.5)
        let diffraction = if s.sigma_s > 0.0 && s.b > 0.0 && g > 0.0 {
            let q = q_bar(self.q.as_ref(), white, &at_i, &at_o, along, across);
            let halo = self.halo_scale
                * halo_attenuation(
                    self.options.halo_weight,
                    one_minus_a_over,
                    self.x_scale,
                    cos_i,
                    sigma_rel_sq,
                );
            q * g * halo * conv()
        } else {
            0.0
        };

        SurfaceTerms {
            a_spec,
            rho_ct,
            diffraction,
            at_i,
            at_o,
        }
    }

    /// `ln C(θh; u)` of [`TwoScale::conv_at`] when C is baked.
    #[inline(always)]
    pub(super) fn ln_conv_at(&self, sin_h: f64, cos_h: f64, u: f32) -> Option<f32> {
        let bake = self.bake().conv()?;
        Some(bake.ln_at(sin_h as f32, cos_h as f32, u))
    }

    /// C(θh; u) (≥ 0) from the bake, or from the source of C when it offers
    /// no slice; `u` is clamped to the bake's `[0, B]`.
    #[inline(always)]
    pub(super) fn conv_at(&self, sin_h: f64, cos_h: f64, u: f32) -> f64 {
        let s = &self.surface;
        let c_value = f64::from(match self.bake().conv() {
            Some(bake) => bake.at(sin_h as f32, cos_h as f32, u),
            None => self
                .conv
                .convolution_sin_cos(sin_h as f32, cos_h as f32, u, s.c, s.beta, s.p),
        });
        if c_value > 0.0 { c_value } else { 0.0 }
    }

    /// `ρ_ms = F_ms (1 − E_s(μi)) (1 − E_s(μo)) / (π (1 − E_avg))`
    /// (docs/model.md §2.11; 0 when the compensation lobe is off).
    #[inline]
    pub(super) fn multiple_value(&self, at_i: &DirectionValues, at_o: &DirectionValues) -> f64 {
        self.multiple_scale * at_i.lost() * at_o.lost()
    }

    /// `ρ_base + k_d/π` (docs/model.md §2.6; HP17 42-47).
    ///
    /// Mirrored in python/twoscale/drjit/lobes.py.
    pub(super) fn base_value(
        &self,
        at_i: &DirectionValues,
        at_o: &DirectionValues,
        cos_i: f64,
        cos_o: f64,
    ) -> f64 {
        let lambertian = self.lambertian / PI;
        if self.white() || self.base == BaseLayer::Conductor {
            return lambertian;
        }
        let transmitted = (1.0 - at_i.fresnel()) * (1.0 - at_o.fresnel()); // (HP17 42)
        let n = self.eta_re.abs().max(1e-3);
        let base = match self.base {
            BaseLayer::Conductor => 0.0,
            BaseLayer::Plastic { albedo } => {
                // (HP17 43) with docs/model.md §2.6's corrections (ρd in the bracket, 1/η²).
                let rho_d = f64::from(albedo);
                transmitted * rho_d / (PI * n * n * (1.0 - rho_d * self.f_dr_int))
            }
            BaseLayer::Subsurface { albedo } => {
                let alpha = f64::from(albedo);
                let t = transmitted;
                // cos θ' of the refracted ray: √(1 − sin²θ / n²).
                let refracted = |cos: f64| math::sqrt((1.0 - (1.0 - cos * cos) / (n * n)).max(0.0));
                let single =
                    alpha * t / (4.0 * PI) / (refracted(cos_i) + refracted(cos_o)).max(1e-12); // (HP17 44)
                let a_f = (1.0 - self.f_dr_int) / (1.0 + self.f_dr_int); // (HP17 45), as printed
                let root = math::sqrt(3.0 * (1.0 - alpha));
                let multi = alpha * t / (2.0 * PI)
                    * math::exp(-root)
                    * (1.0 + math::exp(-4.0 / 3.0 * a_f * root)); // (HP17 46)
                single + multi // (HP17 47)
            }
        };
        base + lambertian
    }
}
