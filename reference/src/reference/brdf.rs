//! `f64` reference of the two-scale BRDF of docs/model.md §2.5 (HP17 24-33) for a
//! conductor, with every ingredient exact: Smith Λ by quadrature
//! ([`epd::lambda`]), σrel by quadrature ([`kcorr::sigma_ratio`]), C by the
//! direct 2-D quadrature ([`conv::convolution`]), F and Q̄ in f64
//! ([`fresnel`]). It mirrors `twoscale::brdf::TwoScale::eval_lobes` formula
//! by formula, so that the runtime's error is the tables' error.
//!
//! Cost: dominated by C (1–30 ms per call).
//!
//! [`ExactConvolution`] adapts [`conv::convolution`] to the runtime's
//! `Convolution` trait; it stands in for the T3 tables where they are not yet
//! available (tests, `query brdf`).

use std::f64::consts::PI;
use std::fmt;

use twoscale::material::{
    BaseLayer, ColourTerms, HaloWeight, Masking, Material, MultipleScattering, Options,
    RGB_WAVELENGTHS, SigmaRelMode,
};

use crate::quad::QuadError;
use crate::reference::conv::ConvError;
use crate::reference::{conv, epd, fresnel, kcorr};

/// Why the reference BRDF could not be evaluated.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum BrdfError {
    /// Direction `i` or `o` is zero or not finite.
    Direction(&'static str),
    /// A parameter is invalid or an integral (Λ, σrel, F, Q̄) failed.
    Quadrature(QuadError),
    /// C could not be computed.
    Convolution(ConvError),
}

impl fmt::Display for BrdfError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            BrdfError::Direction(name) => write!(f, "{name}: not a finite non-zero direction"),
            BrdfError::Quadrature(e) => write!(f, "{e}"),
            BrdfError::Convolution(e) => write!(f, "{e}"),
        }
    }
}

impl std::error::Error for BrdfError {
    fn source(&self) -> Option<&(dyn std::error::Error + 'static)> {
        match self {
            BrdfError::Direction(_) => None,
            BrdfError::Quadrature(e) => Some(e),
            BrdfError::Convolution(e) => Some(e),
        }
    }
}

impl From<QuadError> for BrdfError {
    fn from(e: QuadError) -> Self {
        BrdfError::Quadrature(e)
    }
}

impl From<ConvError> for BrdfError {
    fn from(e: ConvError) -> Self {
        BrdfError::Convolution(e)
    }
}

/// The parameters of the conductor two-scale model (docs/model.md §6 `query brdf`).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Params {
    /// EPD width β.
    pub beta: f64,
    /// EPD shape p.
    pub p: f64,
    /// RMS height σs (µm).
    pub sigma_s: f64,
    /// Correlation length b (µm).
    pub b: f64,
    /// Spectral exponent c > 1.
    pub c: f64,
    /// Real part of the index.
    pub n: f64,
    /// Imaginary part of the index.
    pub k: f64,
    /// Wavelength (µm).
    pub lambda: f64,
}

impl Params {
    /// The parameters of each channel of an RGB `material` (red, green, blue
    /// at [`RGB_WAVELENGTHS`]), if the reference covers it: a conductor
    /// without a Lambertian term.
    pub fn rgb(material: &Material) -> Result<[Params; 3], Uncovered> {
        let layer = material.layer;
        if layer.base != BaseLayer::Conductor || layer.lambertian != 0.0 {
            return Err(Uncovered);
        }
        let s = layer.surface;
        Ok(std::array::from_fn(|ch| Params {
            beta: s.beta.into(),
            p: s.p.into(),
            sigma_s: s.sigma_s.into(),
            b: s.b.into(),
            c: s.c.into(),
            n: material.eta_rgb[ch].re.into(),
            k: material.eta_rgb[ch].im.into(),
            lambda: RGB_WAVELENGTHS[ch].into(),
        }))
    }

    /// [`Params::rgb`] for `material` with `options`: also refuses the
    /// energy compensation of a surface with diffraction, which
    /// [`Compensation`] does not cover.
    pub fn rgb_with(material: &Material, options: &Options) -> Result<[Params; 3], Uncovered> {
        if options.multiple_scattering != MultipleScattering::None
            && material.layer.surface.sigma_s > 0.0
        {
            return Err(Uncovered);
        }
        Params::rgb(material)
    }
}

/// A material the reference does not cover ([`Params::rgb`]): a base layer
/// or a Lambertian term (or, for `query brdf`, the energy compensation of a
/// surface with diffraction).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Uncovered;

impl fmt::Display for Uncovered {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(
            "the f64 reference covers conductors without a Lambertian term, and their \
             energy compensation (multiple_scattering) without diffraction (sigma_s = 0) \
             at the paper's wavelengths",
        )
    }
}

impl std::error::Error for Uncovered {}

/// The energy-compensation lobe of docs/model.md §2.11 in f64, for a
/// surface without diffraction (σs = 0; with diffraction the runtime adds the
/// halo's deficit, which the reference does not compute):
///
/// ```text
/// ρ_ms = F_ms (1 − E(μi)) (1 − E(μo)) / (π (1 − E_avg)),
/// F_ms = F_avg² E_avg / (1 − F_avg (1 − E_avg)),   F_avg = 2 ∫ F μ dμ
/// ```
///
/// with E and E_avg of [`albedo`](crate::reference::albedo) (adaptive, to
/// 1e-9) and F_avg by adaptive Gauss–Kronrod of [`fresnel::fresnel`]
/// (1 with white colour terms).
pub struct Compensation {
    curve: epd::LambdaCurve,
    beta: f64,
    masking: Masking,
    /// `F_ms / (π (1 − E_avg))`.
    scale: f64,
}

impl Compensation {
    /// The lobe of `params` with `options` (its masking and colour terms);
    /// building it computes E_avg (about a second).
    pub fn new(params: &Params, options: &Options) -> Result<Compensation, BrdfError> {
        let curve = epd::LambdaCurve::new(params.p)?;
        let e_avg = crate::reference::albedo::albedo_average(&curve, params.beta, options.masking)?;
        let f_avg = if options.colour == ColourTerms::White {
            1.0
        } else {
            let eta = fresnel::Complex64::new(params.n, params.k);
            let failure = std::cell::Cell::new(None);
            let value = crate::quad::integrate(
                |mu| match fresnel::fresnel(eta, mu) {
                    Ok(f) => 2.0 * f * mu,
                    Err(e) => {
                        failure.set(Some(e));
                        0.0
                    }
                },
                0.0,
                1.0,
                crate::quad::Tolerance::new(1e-13, 1e-12),
            )?
            .value;
            if let Some(e) = failure.get() {
                return Err(e.into());
            }
            value
        };
        let lost = 1.0 - e_avg;
        let f_ms = f_avg * f_avg * e_avg / (1.0 - f_avg * lost);
        Ok(Compensation {
            curve,
            beta: params.beta,
            masking: options.masking,
            scale: if lost > 1e-6 { f_ms / (PI * lost) } else { 0.0 },
        })
    }

    /// The lobes of the three channels `params` when `options` ask for the
    /// compensation (`None` otherwise).
    pub fn rgb(
        params: &[Params; 3],
        options: &Options,
    ) -> Result<Option<[Compensation; 3]>, BrdfError> {
        if options.multiple_scattering == MultipleScattering::None {
            return Ok(None);
        }
        let [r, g, b] = params.each_ref().map(|p| Compensation::new(p, options));
        Ok(Some([r?, g?, b?]))
    }

    /// ρ_ms(i, o); 0 at or below the horizon.
    pub fn value(&self, i: [f64; 3], o: [f64; 3]) -> Result<f64, BrdfError> {
        let (wi, wo) = (normalise(i, "i")?, normalise(o, "o")?);
        if !(wi[2] > 0.0 && wo[2] > 0.0) || self.scale == 0.0 {
            return Ok(0.0);
        }
        let lost = |mu: f64| -> Result<f64, BrdfError> {
            let e = crate::reference::albedo::albedo(&self.curve, self.beta, mu, self.masking)?;
            Ok(1.0 - e.clamp(0.0, 1.0))
        };
        Ok(self.scale * lost(wi[2])? * lost(wo[2])?)
    }
}

/// The three terms of ρ (sr⁻¹): `A_spec ρ_CT`, `ρ_CTD`, and their sum.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Value {
    /// `A_spec · ρ_CT` (HP17 25-26).
    pub specular: f64,
    /// `ρ_CTD` (HP17 32-33 with docs/model.md §2.5's constant).
    pub diffraction: f64,
}

impl Value {
    /// ρ.
    pub fn total(&self) -> f64 {
        self.specular + self.diffraction
    }
}

fn normalise(v: [f64; 3], name: &'static str) -> Result<[f64; 3], BrdfError> {
    let len = (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]).sqrt();
    if !(len > 0.0 && len.is_finite()) {
        return Err(BrdfError::Direction(name));
    }
    Ok(v.map(|x| x / len))
}

/// `tan θ` of a unit vector, from its components.
fn tan_theta(w: [f64; 3]) -> f64 {
    w[0].hypot(w[1]) / w[2]
}

/// ρ(i, o) of the conductor two-scale model (module documentation), with the
/// runtime's `options` (masking, σrel mode, colour terms). Directions at or
/// below the horizon give 0, as in the runtime.
pub fn two_scale(
    params: &Params,
    i: [f64; 3],
    o: [f64; 3],
    options: &Options,
) -> Result<Value, BrdfError> {
    let (wi, wo) = (normalise(i, "i")?, normalise(o, "o")?);
    let zero = Value {
        specular: 0.0,
        diffraction: 0.0,
    };
    if !(wi[2] > 0.0 && wo[2] > 0.0) {
        return Ok(zero);
    }
    let Params {
        beta,
        p,
        sigma_s,
        b,
        c,
        n,
        k,
        lambda,
    } = *params;
    let sum = [wi[0] + wo[0], wi[1] + wo[1], wi[2] + wo[2]];
    let len = (sum[0] * sum[0] + sum[1] * sum[1] + sum[2] * sum[2]).sqrt();
    let h = sum.map(|x| x / len);
    let cos_d = (wi[0] * h[0] + wi[1] * h[1] + wi[2] * h[2]).clamp(0.0, 1.0);
    let theta_h = h[0].hypot(h[1]).atan2(h[2]);
    let (cos_i, cos_o) = (wi[2], wo[2]);

    let lambda_i = epd::lambda(p, beta * tan_theta(wi))?;
    let lambda_o = epd::lambda(p, beta * tan_theta(wo))?;
    let g = match options.masking {
        Masking::Separable => 1.0 / ((1.0 + lambda_i) * (1.0 + lambda_o)),
        Masking::HeightCorrelated => 1.0 / (1.0 + lambda_i + lambda_o),
    };
    let eta = fresnel::Complex64::new(n, k);
    let white = options.colour == ColourTerms::White;
    let f = if white {
        1.0
    } else {
        fresnel::fresnel(eta, cos_d)?
    };
    let d = epd::Epd::new(beta, p)?.d(h[2]);
    let rho_ct = f * d * g / (4.0 * cos_i * cos_o);

    let big_b = b / lambda;
    let sigma_rel_sq = if sigma_s > 0.0 {
        let ratio = |cos: f64| kcorr::sigma_ratio(cos.clamp(0.0, 1.0).acos(), big_b, c);
        let ratio_sq = match options.sigma_rel {
            SigmaRelMode::Incident => ratio(cos_i)?.powi(2),
            SigmaRelMode::Symmetrised => 0.5 * (ratio(cos_i)?.powi(2) + ratio(cos_o)?.powi(2)),
        };
        sigma_s * sigma_s * ratio_sq
    } else {
        0.0
    };
    let x = (4.0 * PI * cos_d / lambda).powi(2);
    let a_spec = (-x * sigma_rel_sq).exp();
    let specular = a_spec * rho_ct;

    let diffraction = if sigma_s > 0.0 && b > 0.0 {
        let q = if white {
            1.0
        } else {
            fresnel::q_bar(eta, wi, wo)?
        };
        // (1 − A)/σrel², → x as σrel → 0; A at θd (printed) or θi.
        let x_halo = match options.halo_weight {
            HaloWeight::Printed => x,
            HaloWeight::Incident => (4.0 * PI * cos_i / lambda).powi(2),
        };
        let t = x_halo * sigma_rel_sq;
        let one_minus_a_over = if t < 1e-8 {
            x_halo * (1.0 - 0.5 * t)
        } else {
            -(-t).exp_m1() / sigma_rel_sq
        };
        let halo =
            (c - 1.0) * sigma_s * sigma_s * b * b / (2.0 * PI * lambda * lambda) * one_minus_a_over;
        let c_value = conv::convolution(theta_h, big_b * cos_d, c, beta, p)?;
        q * g * halo * c_value
    } else {
        0.0
    };
    Ok(Value {
        specular,
        diffraction,
    })
}

/// The exact C of [`conv::convolution`] behind the runtime's
/// `twoscale::Convolution` trait (f32 in and out; 0 where the reference
/// fails, e.g. outside its parameter domain). 1–30 ms per call: a stand-in
/// in tests that measure everything but C's table.
///
/// The angle is recovered as `atan2(sin θh, cos θh)` from the f32 pair.
#[derive(Clone, Copy, Debug, Default)]
pub struct ExactConvolution;

impl twoscale::Convolution for ExactConvolution {
    fn convolution_sin_cos(&self, sin: f32, cos: f32, u: f32, c: f32, beta: f32, p: f32) -> f32 {
        let theta_h = f64::from(sin.max(0.0))
            .atan2(f64::from(cos.max(0.0)))
            .clamp(0.0, std::f64::consts::FRAC_PI_2);
        conv::convolution(
            theta_h,
            f64::from(u),
            f64::from(c),
            f64::from(beta),
            f64::from(p),
        )
        .map(|v| v as f32)
        .unwrap_or(0.0)
    }
}
