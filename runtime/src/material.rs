//! The model's vocabulary: the plain parameter types a material is made of
//! (its [`Surface`], [`BaseLayer`], [`Layer`], [`Material`]) and the
//! [`Options`] that choose among the model's variants, with the ranges the
//! model accepts. No behaviour: the BRDFs that read them are in
//! [`crate::brdf`], their validation in [`crate::validate`].

use crate::math::Complex;

/// Smallest and largest accepted β.
pub const BETA_RANGE: (f32, f32) = (1e-4, 10.0);
/// Smallest and largest accepted p (the domain of T1).
pub const P_RANGE: (f32, f32) = (0.2, 5.0);

/// The default RGB wavelengths in µm, red, green, blue (HP15 §5.5; docs/model.md §1).
pub const RGB_WAVELENGTHS: [f32; 3] = [0.645, 0.526, 0.444];

/// The micro- and nano-geometry of a surface (wavelength independent).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Surface {
    /// EPD width β (HP17 35).
    pub beta: f32,
    /// EPD shape p (HP17 35), in [0.2, 5].
    pub p: f32,
    /// RMS height of the nano-geometry σs, µm (HP17 16). 0 disables diffraction.
    pub sigma_s: f32,
    /// Correlation length b of the K-correlation spectrum, µm (HP17 16).
    pub b: f32,
    /// Spectral exponent c > 1 of the K-correlation spectrum (HP17 16).
    pub c: f32,
}

/// What lies under the two-scale interface (docs/model.md §2.6).
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum BaseLayer {
    /// A conductor: no base, `ρ_base = 0`.
    Conductor,
    /// A dielectric varnish of real index `η = n` (the material's index) over a
    /// diffuse layer of albedo ρd (HP17 43, corrected in docs/model.md §2.6):
    /// `ρ_base = (1 − F(θi))(1 − F(θo)) ρd / (π η² (1 − ρd F_dr,int(η)))`.
    Plastic {
        /// Albedo ρd ∈ [0, 1] of the diffuse layer.
        albedo: f32,
    },
    /// Subsurface scattering under the interface (HP17 44-47), with albedo α.
    Subsurface {
        /// Single-scattering albedo α ∈ [0, 1] of the medium.
        albedo: f32,
    },
}

/// The kind of a [`BaseLayer`], without its albedo (named by
/// [`crate::validate::Named`]).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum BaseKind {
    /// [`BaseLayer::Conductor`] (the default).
    #[default]
    Conductor,
    /// [`BaseLayer::Plastic`].
    Plastic,
    /// [`BaseLayer::Subsurface`].
    Subsurface,
}

impl BaseKind {
    /// The base layer of this kind with diffuse `albedo` (ignored by a conductor).
    pub fn with_albedo(self, albedo: f32) -> BaseLayer {
        match self {
            BaseKind::Conductor => BaseLayer::Conductor,
            BaseKind::Plastic => BaseLayer::Plastic { albedo },
            BaseKind::Subsurface => BaseLayer::Subsurface { albedo },
        }
    }
}

impl BaseLayer {
    /// Its kind.
    pub fn kind(&self) -> BaseKind {
        match self {
            BaseLayer::Conductor => BaseKind::Conductor,
            BaseLayer::Plastic { .. } => BaseKind::Plastic,
            BaseLayer::Subsurface { .. } => BaseKind::Subsurface,
        }
    }
}

/// A layered material at one wavelength's worth of geometry: the surface, its
/// base layer and an optional Lambertian term `k_d/π`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Layer {
    /// Micro- and nano-geometry.
    pub surface: Surface,
    /// The base layer.
    pub base: BaseLayer,
    /// Optional Lambertian reflectance `k_d ∈ [0, 1]` (0 for none): adds `k_d/π`.
    pub lambertian: f32,
}

/// A material with one complex index per RGB channel (at [`RGB_WAVELENGTHS`]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Material {
    /// Geometry, base layer, Lambertian term.
    pub layer: Layer,
    /// Index of refraction `n + ik` at 0.645, 0.526, 0.444 µm.
    pub eta_rgb: [Complex; 3],
}

/// Which shadowing–masking term G the model uses (docs/model.md §2.2).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Masking {
    /// `G = G1(i) G1(o)`, as both papers (the default).
    #[default]
    Separable,
    /// `G = 1 / (1 + Λ(i) + Λ(o))`.
    HeightCorrelated,
}

/// How σrel enters A_spec and the halo's normalisation (docs/model.md §7).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum SigmaRelMode {
    /// `σrel = σrel(θi)` (HP17 19), the paper's model (the default). Not reciprocal.
    #[default]
    Incident,
    /// `σrel² = (σrel²(θi) + σrel²(θo)) / 2`: reciprocal.
    Symmetrised,
}

/// The colour terms of the model.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum ColourTerms {
    /// F of (HP17 3-4) and Q̄ of (HP17 10) from the complex index (the default).
    #[default]
    Physical,
    /// `F ≡ 1` and `Q̄ ≡ 1`: the white-furnace configuration of docs/model.md §7. The
    /// base layers then receive no light (T = 0); the Lambertian term stays.
    White,
}

/// Which `A` weighs the diffraction halo, `(1 − A)/σrel²` in `ρ_CTD`.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum HaloWeight {
    /// `A = A_spec(θd)` at every `o`, as printed (HP17 32-33; the default).
    /// The halo's normalisation by σrel(θi) assumes `1 − A(θi)`, so wherever
    /// `cos θd > cos θi` it gets more: the model gains energy at oblique
    /// incidence when the halo is strong (docs/design/halo-weight-incident.md).
    #[default]
    Printed,
    /// `A = A(θi) = exp(−(4π σrel cos θi / λ)²)` for the halo (the specular
    /// lobe keeps `A_spec(θd)`): a flat facet's halo then carries exactly
    /// `(1 − A(θi)) Q̄`, its specular peak `A(θi) F`. Not the paper's model;
    /// offered because it keeps the white furnace ≤ 1 (measured in docs/design/halo-weight-incident.md).
    Incident,
}

/// Whether the light that bounces more than once between microfacets is
/// put back (docs/model.md §2.11).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum MultipleScattering {
    /// Single scattering only, as both papers (the default): rough and
    /// heavy-tailed surfaces lose up to half of the light.
    #[default]
    None,
    /// A Kulla–Conty energy-compensation lobe (a fourth, diffuse-like lobe,
    /// [`Lobe::Multiple`](crate::brdf::Lobe::Multiple)):
    /// `ρ_ms = F_ms (1 − E_s(μi)) (1 − E_s(μo)) / (π (1 − E_avg))`, `E_s`
    /// the white albedo of the specular peak and the halo (T6's E plus the
    /// halo's deficit), `F_ms = F_avg² E_avg / (1 − F_avg (1 − E_avg))`.
    KullaConty,
}

/// Model options; `Options::default()` is the paper's model.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Options {
    /// Shadowing–masking term.
    pub masking: Masking,
    /// σrel symmetrisation.
    pub sigma_rel: SigmaRelMode,
    /// Physical or white colour terms.
    pub colour: ColourTerms,
    /// Which `A` weighs the halo.
    pub halo_weight: HaloWeight,
    /// Energy compensation for multiple scattering.
    pub multiple_scattering: MultipleScattering,
}

/// Which RGB a material's model gives: the paper's three wavelengths
/// ([`crate::brdf::Rgb`], HP15 §5.5; what reproduces HP15/HP17) or the integral
/// over the spectrum ([`crate::brdf::IntegratedRgb`], docs/model.md §2.12). Named
/// `rgb_mode` in material files and Python, `ts_material_desc.rgb_mode` in
/// C. When none is given, [`RgbMode::default_for`] decides.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum RgbMode {
    /// ρ at 0.645, 0.526, 0.444 µm as red, green, blue.
    PaperWavelengths,
    /// `ρ_c = ∫ ρ(λ) w_c(λ) dλ` (needs the index over the spectrum).
    Integrated,
}

impl RgbMode {
    /// The mode of a material that names none: [`RgbMode::Integrated`] for
    /// a material given over the spectrum (every preset; `eta = (lambda,
    /// n, k)`), [`RgbMode::PaperWavelengths`] for one given by its index at
    /// the paper's three wavelengths (or one constant index), which
    /// integration would only interpolate. The one place that decides it
    /// ([`crate::io::desc::MaterialDesc::rgb`] and
    /// [`crate::io::desc::MaterialDesc::spectral`] call it).
    pub const fn default_for(over_spectrum: bool) -> RgbMode {
        if over_spectrum {
            RgbMode::Integrated
        } else {
            RgbMode::PaperWavelengths
        }
    }
}
