//! The two-scale BRDF of Holzschuch & Pacanowski 2017 (docs/model.md §2.5–§2.7):
//! evaluation, importance sampling and the pdf of the sampler (the density it
//! draws: the specular lobe's visible normals come from a tabulated density
//! that `pdf` evaluates, docs/model.md §2.1), at one
//! wavelength ([`TwoScale`]) and at the three default RGB wavelengths
//! ([`Rgb`]).
//!
//! ```text
//! ρ(i,o)  = A_spec(θd) · ρ_CT(i,o) + ρ_CTD(i,o) + ρ_base(i,o) [+ k_d/π]   (HP17 24)
//! A_spec  = exp(−(4π σrel cos θd / λ)²)                                   (HP17 25)
//! ρ_CT    = F(η, θd) D(θh) G(i,o) / (4 cos θi cos θo)                      (HP17 26)
//! ρ_CTD   = Q̄(i,o) G(i,o) (1 − A_spec) (c−1) σs² b² / (2π σrel² λ²) · C(θh; u, c, β, p)
//!           u = (b/λ) cos θd                                              (HP17 32-33, 40)
//! ```
//!
//! With [`MultipleScattering::KullaConty`] a fourth term puts back the
//! light that single scattering loses (docs/model.md §2.11):
//!
//! ```text
//! ρ_ms    = F_ms (1 − E_s(μi)) (1 − E_s(μo)) / (π (1 − E_avg))
//! F_ms    = F_avg² E_avg / (1 − F_avg (1 − E_avg)),   F_avg = 2 ∫ F(η, μ) μ dμ
//! ```
//!
//! with E_s the white albedo (F = Q̄ = 1) of the specular peak and the halo:
//! T6's E ([`AlbedoTable`]) plus the halo's deficit, computed per material.
//!
//! `σrel = σrel(θi)` comes from T2 ([`SigmaRatioTable`]), D and G from the EPD
//! distribution ([`Epd`], T1), `C` from any [`Convolution`] (the T3 tables, or
//! an adapter), F and Q̄ from [`crate::fresnel`]. The constant of ρ_CTD makes
//! the halo of a flat facet carry exactly `(1 − A) Q̄` (docs/model.md §2.5).
//!
//! # Conventions and guards
//!
//! Directions are unit vectors in the local frame (normal `+z`), `i` towards
//! the light, `o` towards the viewer; they are renormalised in f64. Lengths
//! (σs, b, λ) are in µm. Everything is computed in f64 and rounded once to
//! f32. `eval` is 0 when either direction is at or below the horizon
//! (`z ≤ 0`) or not finite; `pdf` likewise; `sample` returns `None` then, and
//! when the sampled direction falls at or below the horizon. No function
//! allocates, panics or returns NaN/∞ for finite input: every result passes
//! through a final guard that maps a non-finite value to 0 (documented as a
//! last resort; the tests check it is never needed on the sweep).
//!
//! # Reciprocity
//!
//! With `σs = 0` the model is the EPD Cook–Torrance conductor and is
//! reciprocal. With `σs > 0` it is not exactly, because σrel — hence A_spec
//! and the halo's normalisation — depends on θi only (docs/model.md §7). The option
//! [`SigmaRelMode::Symmetrised`] uses `σrel² = (σrel²(θi) + σrel²(θo))/2`,
//! which makes the two-scale part reciprocal (Q̄, G, D, C and F(θd) are
//! symmetric in i ↔ o) at the price of the halo's exact energy normalisation.
//!
//! # Sampling (docs/model.md §2.7)
//!
//! One lobe is chosen with probabilities that depend on `i` only
//! ([`TwoScale::lobe_weights`]); its direction is sampled; [`TwoScale::pdf`]
//! is the mixture `Σ w_k pdf_k(o)`, the exact solid-angle density of what
//! [`TwoScale::sample`] returns (directions that would fall below the horizon
//! are not returned, so `∫ pdf ≤ 1`).

use crate::albedo::AlbedoTable;
pub use crate::bake::BakeVisitor;
use crate::bake::{
    ConvBake, DirectionBake, DirectionCell, DirectionValues, MaskingBake, RadialNormBake,
};
use crate::conv::{ConvSlice, Convolution};
use crate::epd::Epd;
use crate::fresnel::{Complex, DiffuseFresnelTable, QConstants, fresnel_average};
use crate::halo::HaloBake;
use crate::kcorr::SigmaRatioTable;
use crate::math::{self, BELOW_ONE, upper_unit};
use crate::smith::SmithG1Table;
use crate::visible::{VisibleIncidence, VisibleSlopeBake};
use core::borrow::{Borrow, BorrowMut};
use core::f64::consts::PI;
use zerocopy::FromZeros;

mod integrated;
mod spectral;
pub use integrated::{INTEGRATED_COUNT, INTEGRATED_WAVELENGTHS, IntegratedRgb, RgbMode, RgbModel};
#[cfg(feature = "std")]
pub use spectral::BoxedSpectral;
pub use spectral::{FresnelBake, SPECTRAL_COUNT, SPECTRAL_WAVELENGTHS, Spectral};

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
    /// [`Lobe::Multiple`]):
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

/// The tables the model reads. `convolution` is the source of C: the T3b
/// table by default, T3a for the paper's form, or any adapter.
#[derive(Clone, Copy)]
pub struct Tables<'a> {
    /// T1, Smith G1 of the EPD.
    pub smith: SmithG1Table<'a>,
    /// T2, σrel/σs.
    pub sigma_ratio: SigmaRatioTable<'a>,
    /// T5, F_dr,int (plastic and subsurface bases).
    pub diffuse_fresnel: DiffuseFresnelTable<'a>,
    /// T6, the directional albedo of the specular lobe (what the
    /// energy compensation of docs/model.md §2.10 needs).
    pub albedo: AlbedoTable<'a>,
    /// The source of `C(θh; u, c, β, p)` (`Sync`, so that one model can be
    /// shared by a renderer's threads).
    pub convolution: &'a (dyn Convolution + Sync),
}

/// The lobes of the model, for sampling and for [`Lobes`].
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Lobe {
    /// `A_spec · ρ_CT`, sampled through the EPD (HP17 49-50).
    Specular,
    /// `ρ_CTD`, sampled from the spectrum around the specular direction (HP17
    /// 51-55) mixed with a half-vector draw that follows C (`crate::halo`).
    Diffraction,
    /// `ρ_base + k_d/π`, cosine-weighted.
    Base,
    /// `ρ_ms`, the energy compensation of [`MultipleScattering::KullaConty`],
    /// cosine-weighted.
    Multiple,
}

/// The terms of ρ at one pair of directions (sr⁻¹).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Lobes {
    /// `A_spec(θd) · ρ_CT`.
    pub specular: f32,
    /// `ρ_CTD`.
    pub diffraction: f32,
    /// `ρ_base + k_d/π`.
    pub base: f32,
    /// `ρ_ms` (0 unless [`MultipleScattering::KullaConty`]).
    pub multiple: f32,
}

impl Lobes {
    /// `ρ`, the sum of the four terms.
    pub fn total(&self) -> f32 {
        finite_or_zero(
            f64::from(self.specular)
                + f64::from(self.diffraction)
                + f64::from(self.base)
                + f64::from(self.multiple),
        )
    }
}

/// A sampled outgoing direction.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Sample {
    /// The outgoing direction (unit vector, `z > 0`).
    pub o: [f32; 3],
    /// [`TwoScale::pdf`] at `o` (solid-angle density, > 0).
    pub pdf: f32,
    /// ρ(i, o) (sr⁻¹).
    pub value: f32,
    /// The lobe that produced `o`.
    pub lobe: Lobe,
}

/// Maps a non-finite value to 0 and rounds to f32 (saturating at f32::MAX).
#[inline]
fn finite_or_zero(x: f64) -> f32 {
    if x.is_finite() {
        x.max(-f64::from(f32::MAX)).min(f64::from(f32::MAX)) as f32
    } else {
        0.0
    }
}

#[inline]
fn to_f32(v: [f64; 3]) -> [f32; 3] {
    v.map(|x| x as f32)
}

#[inline]
fn dot(a: [f64; 3], b: [f64; 3]) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}

/// `(exp(−x s), (1 − exp(−x s))/s)` for `x, s ≥ 0` from one exponential
/// ([`math::exp_inline`], to 2e-15): `1 − e^−t` loses at most `3e-16/t`
/// relatively, below 3e-8 for `t ≥ 1e-8`; below that its series; the second
/// → `x` as `s → 0`.
#[inline]
fn exp_and_one_minus_over(x: f64, s: f64) -> (f64, f64) {
    let t = x * s;
    if t < 1e-8 {
        (1.0 - t, x * (1.0 - 0.5 * t))
    } else {
        let e = math::exp_inline(-t);
        (e, (1.0 - e) / s)
    }
}

/// What a [`TwoScale`] bakes for its material and wavelength (F, Q̄'s
/// factors and σrel over `cos θ`, G1 over the slope, the sampler's
/// visible-slope density, and C over `(u, θh)` when the source of C is T3b;
/// modules `bake`, `visible` and `halo`): 122 KB of plain numbers (the
/// visible-slope tables 40 KB, the halo sampler's densities 44 KB, C 18 KB,
/// the direction bake 12 KB, G1 4 KB, the diffraction sampler's `1/M` 2 KB).
///
/// All zeros is a valid (empty) value, so storage can be allocated zeroed on
/// the heap (`ChannelBake::boxed`, feature `std`) or provided by the caller
/// (`&mut ChannelBake`, e.g. a `static`); [`TwoScale::new_in`] and
/// [`Rgb::new_in`] fill it in place, and construction then needs no stack
/// beyond a few KB (the test `construction_fits_a_64_kib_stack`).
#[derive(Clone, FromZeros)]
pub struct ChannelBake {
    /// G1 at the material's (β, p).
    masking: MaskingBake,
    /// The specular sampler's visible-slope tables at the material's (β, p).
    visible: VisibleSlopeBake,
    /// F, Q̄'s factors and σrel/σs over `cos θ`.
    direction: DirectionBake,
    /// `1/M(sin θi)` of the diffraction sampler.
    radial_norm: RadialNormBake,
    /// `C` over `(u, θh)` for this material, valid when `conv_baked`.
    conv: ConvBake,
    /// Whether `conv` holds C (the source of C offers a slice, as T3b does);
    /// else the source is read directly.
    conv_baked: bool,
    /// The halo sampler's densities over the half-vector, from `conv`
    /// (valid when `halo_baked`).
    halo: HaloBake,
    /// Whether `halo` holds the halo sampler (implies `conv_baked`; else
    /// the halo is drawn from the spectrum, HP17 51–55).
    halo_baked: bool,
}

impl ChannelBake {
    /// Empty storage on the heap, allocated zeroed: no stack temporary
    /// (feature `std`; aborts as `Box::new` does if allocation fails).
    #[cfg(feature = "std")]
    pub fn boxed() -> std::boxed::Box<ChannelBake> {
        ChannelBake::new_box_zeroed().unwrap_or_else(|_| {
            std::alloc::handle_alloc_error(core::alloc::Layout::new::<ChannelBake>())
        })
    }

    /// Empty storage by value (122 KB on the caller's stack).
    pub fn zeroed() -> ChannelBake {
        ChannelBake::new_zeroed()
    }

    /// T3b's `C` bake, when there is one.
    #[inline]
    fn conv(&self) -> Option<&ConvBake> {
        self.conv_baked.then_some(&self.conv)
    }

    /// The halo sampler's densities, when they are baked.
    #[inline]
    fn halo(&self) -> Option<&HaloBake> {
        self.halo_baked.then_some(&self.halo)
    }
}

/// The two-scale BRDF at one wavelength (see the module documentation).
///
/// Construction bakes what depends only on the material and wavelength into
/// a [`ChannelBake`] (so that `eval` reads small tables), held as `B`: by
/// value (the default, 122 KB; [`TwoScale::new`]), boxed
/// (`TwoScale::boxed`, feature `std`) or borrowed (`&mut ChannelBake`),
/// any `B: Borrow<ChannelBake>`; [`Rgb`] is three of them. `Clone` (when `B`
/// is), not `Copy`.
#[derive(Clone)]
pub struct TwoScale<'a, B = ChannelBake> {
    ndf: Epd<'a>,
    /// Q̄'s constants of η (`None` for η = 1: Q̄ = 0).
    q: Option<QConstants>,
    conv: &'a (dyn Convolution + Sync),
    /// Sanitised surface (β, p as the EPD clamps them; σs = 0 when c ≤ 1).
    surface: Surface,
    lambda: f64,
    /// `B = b / λ`.
    big_b: f64,
    /// `(4π/λ)²`: A_spec's exponent is `(4π/λ)² cos²θd σrel²`.
    x_scale: f64,
    /// `σs²` (µm²).
    sigma_s_sq: f64,
    /// `(c−1) σs² b² / (2π λ²)`, the constant of ρ_CTD.
    halo_scale: f64,
    base: BaseLayer,
    /// `F_dr,int(n)` from T5 (0 for a conductor).
    f_dr_int: f64,
    /// `Re η` (the varnish index of the base layers).
    eta_re: f64,
    lambertian: f64,
    /// `F_ms / (π (1 − E_avg))` of the compensation lobe (0 when off).
    multiple_scale: f64,
    /// `F_ms`, the compensation lobe's albedo over `1 − E_s(μi)` (0 when off).
    multiple_colour: f64,
    options: Options,
    /// The per-material tables.
    bake: B,
}

/// What [`TwoScale::new`] derives from the surface alone, independent of the
/// wavelength: made once for the three channels of [`Rgb`] (G1 and the
/// visible-slope tables are baked once, into the first channel, and copied).
struct SurfaceBakes<'a> {
    ndf: Epd<'a>,
    /// Sanitised surface (β, p as the EPD clamps them; σs = 0 when c ≤ 1).
    surface: Surface,
    /// T3b's material slice when there is diffraction and the source of C
    /// offers one.
    slice: Option<ConvSlice<'a>>,
}

impl<'a> SurfaceBakes<'a> {
    /// Sanitises `s` (as [`TwoScale::new`] documents) and blends C's
    /// material slice.
    fn new(tables: &Tables<'a>, s: Surface) -> Self {
        let nonneg = |x: f32| if x > 0.0 { x.min(f32::MAX) } else { 0.0 };
        let c_ok = s.c > 1.0;
        let ndf = Epd::new(s.beta, s.p, &tables.smith);
        let surface = Surface {
            beta: ndf.beta(),
            p: ndf.p(),
            sigma_s: if c_ok { nonneg(s.sigma_s) } else { 0.0 },
            b: nonneg(s.b),
            c: if c_ok { s.c.min(1e6) } else { 2.0 },
        };
        let slice = if surface.sigma_s > 0.0 {
            tables
                .convolution
                .material_slice(surface.c, surface.beta, surface.p)
        } else {
            None
        };
        SurfaceBakes {
            ndf,
            surface,
            slice,
        }
    }

    /// Bakes G1 and the sampler's visible-slope tables into `bake`.
    fn bake_into(&self, tables: &Tables<'a>, bake: &mut ChannelBake) {
        let (beta, p) = (self.ndf.beta(), self.ndf.p());
        bake.masking.init(beta, &tables.smith.shape(p));
        bake.visible.init(beta, p);
    }
}

/// What one pair of directions gives, independent of the wavelength: the
/// geometry (shared by `pdf` and `eval`, and by the channels of [`Rgb`];
/// `pdf` needs no D, [`Pair`] adds it).
#[derive(Clone, Copy, Debug)]
struct Geometry {
    wi: [f64; 3],
    wo: [f64; 3],
    /// The half-vector in f32, as D reads it.
    h: [f32; 3],
    cos_d: f64,
    cos_h: f64,
    sin_h: f64,
}

/// [`Geometry`], D(h) and G(i, o): what `eval` needs of a pair of
/// directions before the wavelength.
#[derive(Clone, Copy, Debug)]
struct Pair {
    geometry: Geometry,
    /// D(h).
    d: f64,
    g: f64,
    /// The direction bake's cells of `cos θi`, `cos θo` and `cos θd`.
    cells: [DirectionCell; 3],
    /// `sin θi sin θo (cos φ, sin φ)` with φ = φo − φi − π (for Q̄).
    along: f64,
    across: f64,
}

/// What [`TwoScale::surface_terms`] computes at a pair.
#[derive(Clone, Copy)]
struct SurfaceTerms {
    /// `A_spec(θd)`.
    a_spec: f64,
    /// `ρ_CT`.
    rho_ct: f64,
    /// `ρ_CTD`.
    diffraction: f64,
    /// The direction bake at `cos θi` and `cos θo`.
    at_i: DirectionValues,
    at_o: DirectionValues,
}

impl<'a> TwoScale<'a> {
    /// The model for `layer` at wavelength `lambda` (µm) and index `eta`.
    /// Construct once per material and wavelength: it bakes the tables of
    /// [`ChannelBake`] (cost: `cargo bench --bench brdf -- construct`). The
    /// value is 122 KB: on small stacks use `TwoScale::boxed` or
    /// [`TwoScale::new_in`].
    ///
    /// Sanitising: β and p as [`Epd::new`]; σs, b negative or NaN → 0; c NaN
    /// or ≤ 1 → no diffraction (σs = 0); λ NaN or ≤ 0 → 0.526 µm, λ clamped to
    /// [0.01, 100] µm; albedos and `k_d` clamped to [0, 1].
    pub fn new(
        tables: &Tables<'a>,
        layer: Layer,
        lambda: f32,
        eta: Complex,
        options: Options,
    ) -> Self {
        Self::new_in(ChannelBake::zeroed(), tables, layer, lambda, eta, options)
    }

    /// A conductor (no base layer, no Lambertian term) with the default options.
    pub fn conductor(tables: &Tables<'a>, surface: Surface, lambda: f32, eta: Complex) -> Self {
        let layer = Layer {
            surface,
            base: BaseLayer::Conductor,
            lambertian: 0.0,
        };
        Self::new(tables, layer, lambda, eta, Options::default())
    }
}

#[cfg(feature = "std")]
impl<'a> TwoScale<'a, std::boxed::Box<ChannelBake>> {
    /// [`TwoScale::new`] with the bakes on the heap (`ChannelBake::boxed`,
    /// filled in place): the value is a few hundred bytes, and construction
    /// runs on a 64 KiB stack.
    pub fn boxed(
        tables: &Tables<'a>,
        layer: Layer,
        lambda: f32,
        eta: Complex,
        options: Options,
    ) -> Self {
        Self::new_in(ChannelBake::boxed(), tables, layer, lambda, eta, options)
    }
}

impl<'a, B: BorrowMut<ChannelBake>> TwoScale<'a, B> {
    /// [`TwoScale::new`] baking into the storage `bake` in place (whatever
    /// it held is overwritten): a zeroed [`ChannelBake`], a box, a `&mut`
    /// to caller-provided storage, or [`TwoScale::into_bake`] of a model to
    /// rebuild.
    pub fn new_in(
        bake: B,
        tables: &Tables<'a>,
        layer: Layer,
        lambda: f32,
        eta: Complex,
        options: Options,
    ) -> Self {
        let shared = SurfaceBakes::new(tables, layer.surface);
        let mut model = Self::around(bake, tables, &shared, layer, lambda, eta, options);
        shared.bake_into(tables, model.bake.borrow_mut());
        model.bake_wavelength(tables, &shared, eta, NodeBakes::ALL);
        model
    }

    /// The model's parameters for `layer` at `lambda` and `eta` around the
    /// storage `bake`, not yet baked (`shared` must come from the same
    /// tables and surface).
    fn around(
        bake: B,
        tables: &Tables<'a>,
        shared: &SurfaceBakes<'a>,
        layer: Layer,
        lambda: f32,
        eta: Complex,
        options: Options,
    ) -> Self {
        let (ndf, surface) = (shared.ndf, shared.surface);
        let lambda = math::sanitised_wavelength(lambda);
        let unit = |x: f32| f64::from(x.max(0.0).min(1.0));
        let base = match layer.base {
            BaseLayer::Conductor => BaseLayer::Conductor,
            BaseLayer::Plastic { albedo } => BaseLayer::Plastic {
                albedo: unit(albedo) as f32,
            },
            BaseLayer::Subsurface { albedo } => BaseLayer::Subsurface {
                albedo: unit(albedo) as f32,
            },
        };
        let f_dr_int = match base {
            BaseLayer::Conductor => 0.0,
            _ => f64::from(tables.diffuse_fresnel.f_dr_int(eta.re)),
        };
        let sigma_s = f64::from(surface.sigma_s);
        let b = f64::from(surface.b);
        TwoScale {
            x_scale: (4.0 * PI / lambda) * (4.0 * PI / lambda),
            sigma_s_sq: sigma_s * sigma_s,
            halo_scale: (f64::from(surface.c) - 1.0) * sigma_s * sigma_s * b * b
                / (2.0 * PI * lambda * lambda),
            ndf,
            q: QConstants::new(eta),
            conv: tables.convolution,
            surface,
            lambda,
            big_b: b / lambda,
            base,
            f_dr_int,
            eta_re: f64::from(eta.re),
            lambertian: unit(layer.lambertian),
            multiple_scale: 0.0,
            multiple_colour: 0.0,
            options,
            bake,
        }
    }

    /// Bakes, in place, what depends on the wavelength: the direction bake
    /// and its lobe weights, `1/M` and C (G1 and the visible-slope tables are
    /// [`SurfaceBakes::bake_into`]'s).
    fn bake_wavelength(
        &mut self,
        tables: &Tables<'a>,
        shared: &SurfaceBakes<'a>,
        eta: Complex,
        what: NodeBakes,
    ) {
        let (surface, big_b, q) = (self.surface, self.big_b, self.q);
        let white = self.white();
        let sigma_s = f64::from(surface.sigma_s);
        let bake = self.bake.borrow_mut();
        bake.direction.init(
            eta,
            q.as_ref(),
            &tables.sigma_ratio,
            big_b as f32,
            surface.c,
        );
        // Read only when there is diffraction (`diffraction_setup`).
        if sigma_s > 0.0 && big_b > 0.0 {
            bake.radial_norm.init(big_b, f64::from(surface.c));
        } else {
            bake.radial_norm.clear();
        }
        if what.conv {
            bake.conv_baked = match &shared.slice {
                Some(slice) => bake.conv.init(slice, big_b as f32, surface.beta, surface.p),
                None => false,
            };
        }
        bake.halo_baked = bake.conv_baked && what.halo_sampler;
        if !bake.halo_baked {
            // Not read (`ChannelBake::halo`); zeroed so that exports are
            // the same whatever the storage held.
            bake.halo.zero();
        } else {
            let (x_scale, sigma_s_sq, options) = (self.x_scale, self.sigma_s_sq, self.options);
            let (direction, masking) = (&bake.direction, &bake.masking);
            // The halo's factors besides C and the projections: Q̄ G (1 − A)/σrel².
            let g1 =
                |z: f64| f64::from(masking.g1(math::sqrt((1.0 - z * z).max(0.0)) as f32, z as f32));
            // The incidence's values, computed once per row.
            let row = core::cell::Cell::new((f64::NAN, direction.at(1.0), 1.0));
            let weight = |cos_i: f64, cos_d: f64, cos_o: f64, along: f64, across: f64| {
                if row.get().0 != cos_i {
                    row.set((cos_i, direction.at(cos_i as f32), g1(cos_i)));
                }
                let (_, at_i, g1_i) = row.get();
                let at_o = direction.at(cos_o as f32);
                let q = q_bar(q.as_ref(), white, &at_i, &at_o, along, across);
                let sigma_rel_sq = sigma_s_sq * sigma_ratio_sq(options.sigma_rel, &at_i, &at_o);
                let printed = exp_and_one_minus_over(x_scale * cos_d * cos_d, sigma_rel_sq).1;
                let halo =
                    halo_attenuation(options.halo_weight, printed, x_scale, cos_i, sigma_rel_sq);
                q * halo * masking_g(options.masking, g1_i, g1(cos_o))
            };
            bake.halo.init(&bake.conv, &weight);
        }
        let specular = tables
            .albedo
            .column(surface.beta, surface.p, self.options.masking);
        (self.multiple_colour, self.multiple_scale) = match self.options.multiple_scattering {
            MultipleScattering::None => (0.0, 0.0),
            MultipleScattering::KullaConty => {
                // The halo's share of the white albedo (0 without diffraction).
                let mut deficit = [0.0f64; DEFICIT_NODES];
                if sigma_s > 0.0 && big_b > 0.0 {
                    for (j, value) in deficit.iter_mut().enumerate() {
                        let x = j as f64 / (DEFICIT_NODES - 1) as f64;
                        *value = self.halo_deficit((x * x).max(DEFICIT_MIN_COS));
                    }
                }
                let deficit_at = |cos: f64| {
                    let t = math::sqrt(cos.max(0.0).min(1.0)) * (DEFICIT_NODES - 1) as f64;
                    let k = (t as usize).min(DEFICIT_NODES - 2);
                    let f = t - k as f64;
                    deficit[k] + f * (deficit[k + 1] - deficit[k])
                };
                let e_avg =
                    self.bake.borrow_mut().direction.set_albedo(|cos| {
                        (f64::from(specular.albedo(cos)) + deficit_at(cos)) as f32
                    });
                let f_avg = if self.options.colour == ColourTerms::White {
                    1.0
                } else {
                    fresnel_average(eta)
                };
                compensation(e_avg, f_avg)
            }
        };
        let halo = self.halo_albedo_nodes();
        let weights = self.bake().direction.lobe_weight_nodes(|at, cos| {
            let energies = LobeEnergies {
                specular: f64::from(specular.albedo(cos)),
                halo: halo_albedo_at(&halo, cos),
            };
            self.weights_at(at, cos, energies)
        });
        self.bake.borrow_mut().direction.set_lobe_weights(&weights);
    }

    /// The halo's change to the surface's white albedo at `cos θi`
    /// (docs/model.md §2.11):
    ///
    /// ```text
    /// Δ(μ) = ∫ [(A_spec(θd) − 1) ρ_CT + ρ_CTD]_{F = Q̄ = 1} cos θo dωo
    /// ```
    ///
    /// so that `E(μ) + Δ(μ)` is the white albedo of the specular peak and
    /// the halo together (E of T6). In polar coordinates `(α, φ)` around the
    /// mirror direction, `α = e^t` from `10⁻³ w` to π (`w` the narrower of
    /// the NDF's width β and the halo's `λ/2b`) by 4-point Gauss–Legendre on
    /// [`DEFICIT_PANELS`] panels of t, φ by the trapezoid rule on
    /// [`DEFICIT_AZIMUTHS`] points; both terms come from the same nodes.
    fn halo_deficit(&self, cos_i: f64) -> f64 {
        let sin_i = math::sqrt((1.0 - cos_i * cos_i).max(0.0));
        let i = [sin_i as f32, 0.0, cos_i as f32];
        // The mirror direction r and two unit vectors orthogonal to it.
        let r = [-sin_i, 0.0, cos_i];
        let e1 = [cos_i, 0.0, sin_i];
        let e2 = [0.0, 1.0, 0.0];
        let halo_width = 0.5 * self.lambda / f64::from(self.surface.b).max(1e-6);
        let width = f64::from(self.surface.beta)
            .min(halo_width)
            .max(1e-4)
            .min(1.0);
        let (t0, t1) = (math::ln(1e-3 * width), math::ln(PI));
        let h = (t1 - t0) / DEFICIT_PANELS as f64;
        let mut total = 0.0;
        for k in 0..DEFICIT_PANELS {
            let mid = t0 + (k as f64 + 0.5) * h;
            for (x, weight) in math::GAUSS_LEGENDRE_4 {
                for t in [mid - 0.5 * h * x, mid + 0.5 * h * x] {
                    let alpha = math::exp(t);
                    let (sa, ca) = (math::sin(alpha), math::cos(alpha));
                    // The integrand is even in φ (i lies in the xz-plane): the
                    // trapezoid rule over [0, π], ends halved, doubled.
                    let half = DEFICIT_AZIMUTHS / 2;
                    let mut ring = 0.0;
                    for m in 0..=half {
                        let phi = PI * m as f64 / half as f64;
                        let (sp, cp) = (math::sin(phi), math::cos(phi));
                        let o = [0, 1, 2].map(|c| ca * r[c] + sa * (cp * e1[c] + sp * e2[c]));
                        if !(o[2] > 0.0) {
                            continue;
                        }
                        let Some(pair) = self.pair(i, to_f32(o)) else {
                            continue;
                        };
                        let terms = self.surface_terms(&pair, true);
                        let value = (terms.a_spec - 1.0) * terms.rho_ct + terms.diffraction;
                        if value.is_finite() {
                            let end = if m == 0 || m == half { 0.5 } else { 1.0 };
                            ring += end * value * o[2];
                        }
                    }
                    total += 0.5 * h * weight * ring * (2.0 * PI / half as f64) * sa * alpha;
                }
            }
        }
        total
    }

    /// The storage of the bakes, to rebuild another model in
    /// ([`TwoScale::new_in`]).
    pub fn into_bake(self) -> B {
        self.bake
    }
}

impl<'a, B: Borrow<ChannelBake>> TwoScale<'a, B> {
    /// The bakes.
    #[inline]
    fn bake(&self) -> &ChannelBake {
        self.bake.borrow()
    }

    /// Whether the model has a diffraction lobe (σs > 0 and b > 0) and a
    /// diffuse term (a base layer that receives light, or `k_d > 0`): its
    /// [`crate::Bxdf::flags`].
    pub(crate) fn has_lobes(&self) -> (bool, bool) {
        let diffraction = self.surface.sigma_s > 0.0 && self.surface.b > 0.0;
        let base = self.base != BaseLayer::Conductor && !self.white();
        (
            diffraction,
            base || self.lambertian > 0.0 || self.multiple_scale > 0.0,
        )
    }

    /// Hands the model's constants and bakes to `v` (names in the
    /// visitor's calls; layouts as [`crate::bake`] documents), for ports of
    /// `eval` and `pdf` (the Python package's `Material.bakes()`).
    #[doc(hidden)]
    pub fn visit_bakes(&self, v: &mut dyn BakeVisitor) {
        let s = &self.surface;
        for (name, value) in [
            ("beta", s.beta),
            ("p", s.p),
            ("sigma_s", s.sigma_s),
            ("b", s.b),
            ("c", s.c),
        ] {
            v.scalar(name, f64::from(value));
        }
        let (norm, inv_beta_sq) = self.ndf.d_constants();
        v.scalar("epd_norm", f64::from(norm));
        v.scalar("epd_inv_beta_sq", f64::from(inv_beta_sq));
        let (e_norm_sqr, eta_sq) = self.q.map_or((0.0, [0.0; 2]), |q| q.combine_constants());
        v.scalar("has_q", if self.q.is_some() { 1.0 } else { 0.0 });
        v.scalar("q_e_norm_sqr", e_norm_sqr);
        v.scalar("q_eta_sq_re", eta_sq[0]);
        v.scalar("q_eta_sq_im", eta_sq[1]);
        let (base, albedo) = match self.base {
            BaseLayer::Conductor => (0.0, 0.0),
            BaseLayer::Plastic { albedo } => (1.0, f64::from(albedo)),
            BaseLayer::Subsurface { albedo } => (2.0, f64::from(albedo)),
        };
        let flag = |b: bool| if b { 1.0 } else { 0.0 };
        for (name, value) in [
            ("lambda", self.lambda),
            ("big_b", self.big_b),
            ("x_scale", self.x_scale),
            ("sigma_s_sq", self.sigma_s_sq),
            ("halo_scale", self.halo_scale),
            ("f_dr_int", self.f_dr_int),
            ("eta_re", self.eta_re),
            ("lambertian", self.lambertian),
            ("multiple_scale", self.multiple_scale),
            ("base", base),
            ("albedo", albedo),
            ("white", flag(self.white())),
            (
                "height_correlated",
                flag(self.options.masking == Masking::HeightCorrelated),
            ),
            (
                "symmetrised",
                flag(self.options.sigma_rel == SigmaRelMode::Symmetrised),
            ),
            (
                "halo_incident",
                flag(self.options.halo_weight == HaloWeight::Incident),
            ),
            ("conv_baked", flag(self.bake().conv_baked)),
        ] {
            v.scalar(name, value);
        }
        let bake = self.bake();
        bake.direction.visit(v);
        bake.masking.visit(v);
        bake.radial_norm.visit(v);
        bake.conv.visit(v);
        bake.halo.visit(v);
        bake.visible.visit(v);
    }

    /// The sanitised surface parameters in use.
    pub fn surface(&self) -> Surface {
        self.surface
    }

    /// The wavelength in use (µm).
    pub fn wavelength(&self) -> f32 {
        self.lambda as f32
    }

    /// The EPD distribution in use.
    pub fn ndf(&self) -> &Epd<'a> {
        &self.ndf
    }

    fn white(&self) -> bool {
        self.options.colour == ColourTerms::White
    }

    /// F(η, cos θ) from the direction bake, or 1 for white colour terms.
    fn fresnel_of(&self, values: &DirectionValues) -> f64 {
        if self.white() { 1.0 } else { values.fresnel() }
    }

    /// F(η, cos θ) from the direction bake at `cos θ`'s cell, or 1 for
    /// white colour terms.
    fn fresnel_at(&self, at: DirectionCell) -> f64 {
        if self.white() {
            1.0
        } else {
            f64::from(self.bake().direction.fresnel_at(at))
        }
    }

    /// `σrel²/σs²` for the incidence `i` (and `o` when symmetrised).
    fn sigma_ratio_sq(&self, at_i: &DirectionValues, at_o: &DirectionValues) -> f64 {
        sigma_ratio_sq(self.options.sigma_rel, at_i, at_o)
    }

    /// The geometry of `(i, o)`; `None` below the horizon.
    fn geometry(&self, i: [f32; 3], o: [f32; 3]) -> Option<Geometry> {
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
    fn pair(&self, i: [f32; 3], o: [f32; 3]) -> Option<Pair> {
        Some(self.with_masking(self.geometry(i, o)?))
    }

    /// D(h) and G(i, o) added to `geometry`.
    fn with_masking(&self, geometry: Geometry) -> Pair {
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
    fn lobes(&self, pair: &Pair) -> Lobes {
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
    fn surface_terms(&self, pair: &Pair, white: bool) -> SurfaceTerms {
        let g = &pair.geometry;
        let u = (self.big_b * g.cos_d) as f32;
        self.surface_terms_with(pair, white, || self.conv_at(g.sin_h, g.cos_h, u))
    }

    /// [`TwoScale::surface_terms`] with C(θh; u) from `conv` (called only
    /// where the diffraction lobe is evaluated; `IntegratedRgb` hands in C
    /// interpolated over its wavelengths).
    #[inline(always)]
    fn surface_terms_with(
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
    fn ln_conv_at(&self, sin_h: f64, cos_h: f64, u: f32) -> Option<f32> {
        let bake = self.bake().conv()?;
        Some(bake.ln_at(sin_h as f32, cos_h as f32, u))
    }

    /// C(θh; u) (≥ 0) from the bake, or from the source of C when it offers
    /// no slice; `u` is clamped to the bake's `[0, B]`.
    #[inline(always)]
    fn conv_at(&self, sin_h: f64, cos_h: f64, u: f32) -> f64 {
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
    fn multiple_value(&self, at_i: &DirectionValues, at_o: &DirectionValues) -> f64 {
        self.multiple_scale * at_i.lost() * at_o.lost()
    }

    /// `ρ_base + k_d/π` (docs/model.md §2.6; HP17 42-47).
    fn base_value(
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

    /// The lobe-selection probabilities `[specular, diffraction, base,
    /// multiple]` for incidence `i` (sum 1; all 0 for `i` below the horizon),
    /// proportional to estimates of the lobes' directional albedos at θi
    /// (docs/design/halo-sampling.md):
    ///
    /// ```text
    /// E_s  = A(θi) F(η, cos θi) E(μ; β, p)      A(θi) = exp(−(4π σrel(θi) cos θi / λ)²) (HP17 25),
    ///                                           E of T6 (F = 1), F = 1 with white colour terms
    /// E_d  = ∫ ρ_CTD cos θo dωo                  by the diffraction lobe's own sampler, 34 lattice
    ///                                           points at 9 incidences, linear in √cos θi between
    /// E_b  = base albedo estimate: plastic (1 − F(θi)) ρd (1 − F_dr,int)/(1 − ρd F_dr,int)
    ///        (its exact albedo), subsurface (1 − F(θi)) α, plus k_d
    /// E_ms = F_ms (1 − E_w(μi)), the compensation lobe's albedo (0 when off), E_w the white
    ///        albedo of docs/model.md §2.11 (T6's E plus the halo's deficit)
    /// w    ∝ [E_s, max(E_d, 10⁻³ ΣE), E_b, E_ms]  (E_d's floor only where the lobe exists)
    /// ```
    ///
    /// When every estimate is 0 (η = 1 and no base) the split
    /// `[A, 1 − A, 0, 0]` is used. The weights are tabulated with the material
    /// (linear in `√cos θi` between 257 nodes): `sample` and `pdf` read the
    /// same table, so the weights add no error to the pdf.
    pub fn lobe_weights(&self, i: [f32; 3]) -> [f32; 4] {
        let Some(wi) = upper_unit(i) else {
            return [0.0; 4];
        };
        self.weights(wi[2]).map(|w| w as f32)
    }

    /// The lobe weights at `cos θi`, from the direction bake's table of
    /// [`TwoScale::weights_at`].
    fn weights(&self, cos_i: f64) -> [f64; 4] {
        self.bake().direction.lobe_weights(cos_i as f32)
    }

    /// The diffraction lobe's directional albedo at [`HALO_ALBEDO_NODES`]
    /// incidences even in `√cos θi`, estimated with its own sampler on a
    /// rank-1 lattice of [`HALO_ALBEDO_POINTS`] points (deterministic;
    /// zeros without a diffraction lobe). Needs the bakes but not the
    /// lobe weights.
    fn halo_albedo_nodes(&self) -> [f64; HALO_ALBEDO_NODES] {
        let mut out = [0.0; HALO_ALBEDO_NODES];
        if !self.has_lobes().0 {
            return out;
        }
        let n = HALO_ALBEDO_POINTS;
        for (k, slot) in out.iter_mut().enumerate().skip(1) {
            let x = k as f64 / (HALO_ALBEDO_NODES - 1) as f64;
            let cos = x * x;
            let i = [
                math::sqrt((1.0 - cos * cos).max(0.0)) as f32,
                0.0,
                cos as f32,
            ];
            let mut sum = 0.0;
            for j in 0..n {
                let u0 = (j as f64 + 0.5) / n as f64;
                let u1 = ((j * HALO_ALBEDO_STRIDE) as f64 + 0.5) / n as f64;
                let u = [u0 as f32, (u1 - math::floor(u1)) as f32];
                let Some(o) = self.sample_lobe(Lobe::Diffraction, i, u) else {
                    continue;
                };
                let Some(geometry) = self.geometry(i, o) else {
                    continue;
                };
                let pdf = self.diffraction_pdf(&geometry);
                if pdf > 0.0 {
                    let value = f64::from(self.lobes(&self.with_masking(geometry)).diffraction);
                    sum += value * geometry.wo[2] / pdf;
                }
            }
            let e = sum / n as f64;
            *slot = if e.is_finite() { e } else { 0.0 };
        }
        out
    }

    /// The lobe weights (see [`TwoScale::lobe_weights`]) with F from `at_i`
    /// and the lobes' albedo estimates `e`.
    fn weights_at(&self, at_i: &DirectionValues, cos_i: f64, e: LobeEnergies) -> [f64; 4] {
        let sigma_rel = f64::from(self.surface.sigma_s) * at_i.sigma_ratio();
        let t = self.x_scale * cos_i * cos_i * sigma_rel * sigma_rel;
        let a = math::exp(-t);
        let e_s = a * self.fresnel_of(at_i) * e.specular;
        let mut e_b = self.lambertian;
        if !self.white() {
            let into = 1.0 - at_i.fresnel();
            e_b += match self.base {
                BaseLayer::Conductor => 0.0,
                BaseLayer::Plastic { albedo } => {
                    let rho_d = f64::from(albedo);
                    into * rho_d * (1.0 - self.f_dr_int) / (1.0 - rho_d * self.f_dr_int)
                }
                BaseLayer::Subsurface { albedo } => into * f64::from(albedo),
            };
        }
        let mut e_d = e.halo.max(0.0);
        if self.has_lobes().0 {
            e_d = e_d.max(HALO_FLOOR * (e_s + e_d + e_b));
        }
        // ∫ ρ_ms cos θo dωo = F_ms (1 − E_s(μi)): π (1 − E_avg) cancels.
        let e_ms = self.multiple_colour * at_i.lost();
        let w = [e_s, e_d, e_b, e_ms];
        let total = w[0] + w[1] + w[2] + w[3];
        if total > 0.0 && total.is_finite() {
            w.map(|x| x / total)
        } else {
            [a, 1.0 - a, 0.0, 0.0]
        }
    }

    /// The solid-angle density over `o` of [`TwoScale::sample`] for incidence
    /// `i`: `Σ_k w_k(i) pdf_k(i, o)` with the weights of
    /// [`TwoScale::lobe_weights`] and the lobe densities of
    /// [`TwoScale::pdf_lobe`]. 0 below the horizon.
    pub fn pdf(&self, i: [f32; 3], o: [f32; 3]) -> f32 {
        match self.geometry(i, o) {
            Some(geometry) => finite_or_zero(self.pdf_at(&geometry)),
            None => 0.0,
        }
    }

    /// [`TwoScale::pdf`] at a pair's geometry.
    fn pdf_at(&self, geometry: &Geometry) -> f64 {
        self.pdf_with_specular(geometry, self.specular_pdf(geometry))
    }

    /// The specular lobe's density at a pair (wavelength independent).
    #[inline]
    fn specular_pdf(&self, geometry: &Geometry) -> f64 {
        self.bake().visible.pdf(geometry.wi, geometry.wo)
    }

    /// [`TwoScale::pdf_at`] given the specular lobe's density `specular`
    /// (which [`Rgb`] computes once for its channels).
    fn pdf_with_specular(&self, geometry: &Geometry, specular: f64) -> f64 {
        self.pdf_with(geometry, &self.weights(geometry.wi[2]), specular)
    }

    /// [`TwoScale::pdf_at`] given the lobe weights `w` at θi and the
    /// specular lobe's density `specular` (which [`TwoScale::sample`] has from
    /// its draw).
    fn pdf_with(&self, geometry: &Geometry, w: &[f64; 4], specular: f64) -> f64 {
        let mut total = 0.0;
        if w[0] > 0.0 {
            total += w[0] * specular;
        }
        if w[1] > 0.0 {
            total += w[1] * self.lobe_pdf(Lobe::Diffraction, geometry);
        }
        // The base and the compensation lobe share the cosine-weighted density.
        let diffuse = w[2] + w[3];
        if diffuse > 0.0 {
            total += diffuse * self.lobe_pdf(Lobe::Base, geometry);
        }
        total
    }

    /// The solid-angle density of [`TwoScale::sample_lobe`] for one lobe:
    ///
    /// * specular: the density of reflecting `i` about a visible EPD normal
    ///   (the tabulated `D_vis`, `crate::visible`: `P2_tab g_tab / (8 N_tab β²
    ///   |i'| cos⁴θh)`, docs/model.md §2.1), 0 where `i·h ≤ 0`;
    /// * diffraction: the half-vector draw's where C is baked, else the
    ///   spectrum's. The spectrum's
    ///   (HP17 51-55): with `d = o_p + i_p` (the tangential parts;
    ///   `|d| = λ f`), `B = b/λ`, `s = sin θi`,
    ///   `M = 1 − (1 + B²(1 + s)²)^(−(c−1)/2)` and `φmax(|d|)` of (HP17 53),
    ///   `pdf = (c−1) B² (1 + B²|d|²)^(−(c+1)/2) / (2 M φmax) · cos θo`; the
    ///   half-vector draw's `Σ_j w_j p_j(ζ) cos θo / (4 N(θh))` (`crate::halo`);
    /// * base and multiple: `cos θo / π`.
    ///
    /// 0 below the horizon or where the lobe cannot produce `o`.
    pub fn pdf_lobe(&self, lobe: Lobe, i: [f32; 3], o: [f32; 3]) -> f32 {
        match self.geometry(i, o) {
            Some(geometry) => finite_or_zero(self.lobe_pdf(lobe, &geometry)),
            None => 0.0,
        }
    }

    /// [`TwoScale::pdf_lobe`] at a pair's geometry.
    fn lobe_pdf(&self, lobe: Lobe, geometry: &Geometry) -> f64 {
        let wo = geometry.wo;
        match lobe {
            Lobe::Specular => self.specular_pdf(geometry),
            Lobe::Diffraction => self.diffraction_pdf(geometry),
            Lobe::Base | Lobe::Multiple => wo[2] / PI,
        }
    }

    /// `(B, s, 1/M)` of the diffraction sampler (M of HP17 52 from the
    /// bake), or `None` when the spectrum is degenerate (σs = 0 or b = 0) or
    /// M is not positive.
    fn diffraction_setup(&self, wi: [f64; 3]) -> Option<(f64, f64, f64)> {
        if !(self.surface.sigma_s > 0.0 && self.big_b > 0.0) {
            return None;
        }
        let sin_i = math::sqrt(wi[0] * wi[0] + wi[1] * wi[1]).min(1.0);
        let inv_m = self.bake().radial_norm.inv_m(sin_i);
        if !(inv_m > 0.0) {
            return None;
        }
        Some((self.big_b, sin_i, inv_m))
    }

    /// φmax of (HP17 53) for `r = λ f`: the half-width of the arc of
    /// directions of `d` around `i_p` that keeps `o_p = d − i_p` in the unit disc.
    fn phi_max(r: f64, sin_i: f64) -> f64 {
        if r + sin_i <= 1.0 {
            return PI;
        }
        let x = (r * r + sin_i * sin_i - 1.0) / (2.0 * r * sin_i);
        math::acos_approx(x.max(-1.0).min(1.0))
    }

    /// The diffraction lobe's density: the half-vector draw of [`HaloBake`],
    /// `p(h) / (4 i·h)`, when the C bake is there; else the spectrum's draw.
    fn diffraction_pdf(&self, geometry: &Geometry) -> f64 {
        let Geometry {
            wi,
            wo,
            cos_d,
            cos_h,
            sin_h,
            ..
        } = *geometry;
        match self.bake().halo() {
            Some(halo) if cos_d > 0.0 => halo.pdf(wi, self.big_b * wi[2], sin_h, cos_h, wo[2]),
            Some(_) => 0.0,
            None => self.spectrum_pdf(wi, wo),
        }
    }

    /// The density of the spectrum's draw (HP17 51-55).
    fn spectrum_pdf(&self, wi: [f64; 3], wo: [f64; 3]) -> f64 {
        let Some((b, sin_i, inv_m)) = self.diffraction_setup(wi) else {
            return 0.0;
        };
        let (dx, dy) = (wo[0] + wi[0], wo[1] + wi[1]);
        let r = math::sqrt(dx * dx + dy * dy);
        if r > 1.0 + sin_i {
            return 0.0;
        }
        let phi_max = Self::phi_max(r, sin_i);
        if !(phi_max > 0.0) {
            return 0.0;
        }
        let c = f64::from(self.surface.c);
        let density =
            (c - 1.0) * b * b * math::pow_positive(1.0 + b * b * r * r, -0.5 * (c + 1.0)) * inv_m
                / (2.0 * phi_max);
        density * wo[2]
    }

    /// Samples `o` from one lobe with the uniforms `u` (clamped to [0, 1));
    /// `None` when `i` is below the horizon, the lobe is degenerate, or the
    /// direction falls at or below the horizon. Its density is
    /// [`TwoScale::pdf_lobe`].
    ///
    /// * specular: `m` a visible normal of the EPD (the tabulated visible-slope
    ///   sampler of docs/model.md §2.1, `u` its two uniforms), `o = 2(i·m)m − i`;
    /// * diffraction: the half-vector draw of `crate::halo` reflected where C
    ///   is baked, else the spectrum's draw
    ///   (HP17 51-55): `r = λ f = √((1 − M u₀)^(−2/(c−1)) − 1) / B`,
    ///   `ψ = (2u₁ − 1) φmax(r)`, `d = r (cos(φi + ψ), sin(φi + ψ))`,
    ///   `o_p = d − i_p`. (HP17 54-55) write the same arc as `φf = φi + π ± φmax`
    ///   with `o_p = −i_p + λ f`; the arc that keeps `o_p` in the disc is
    ///   centred on `+i_p` as written here (at ψ = 0, `o_p` moves from the
    ///   mirror direction towards `i`'s side);
    /// * base and multiple: cosine-weighted hemisphere.
    pub fn sample_lobe(&self, lobe: Lobe, i: [f32; 3], u: [f32; 2]) -> Option<[f32; 3]> {
        let wi = upper_unit(i)?;
        let visible = match lobe {
            Lobe::Specular => Some(self.bake().visible.incidence(wi)),
            _ => None,
        };
        self.draw_lobe(lobe, wi, visible.as_ref(), u)
    }

    /// [`TwoScale::sample_lobe`] for the unit incidence `wi`, with the
    /// visible-normal sampler's incidence `visible` (needed for the specular
    /// lobe only).
    fn draw_lobe(
        &self,
        lobe: Lobe,
        wi: [f64; 3],
        visible: Option<&VisibleIncidence>,
        u: [f32; 2],
    ) -> Option<[f32; 3]> {
        let u = u.map(|x| f64::from(x.max(0.0).min(BELOW_ONE)));
        let o = match lobe {
            Lobe::Specular => {
                let m = self.bake().visible.sample_at(visible?, u)?;
                let k = 2.0 * dot(wi, m);
                [k * m[0] - wi[0], k * m[1] - wi[1], k * m[2] - wi[2]]
            }
            Lobe::Diffraction => self.sample_diffraction(wi, u)?,
            Lobe::Base | Lobe::Multiple => {
                let r = math::sqrt(u[0]);
                let phi = 2.0 * PI * u[1];
                [
                    r * math::cos(phi),
                    r * math::sin(phi),
                    math::sqrt((1.0 - u[0]).max(0.0)),
                ]
            }
        };
        let o = upper_unit(to_f32(o))?;
        Some(to_f32(o))
    }

    /// The diffraction lobe's draw: a half-vector from [`HaloBake`] (`u[1]`
    /// picks its row and then the azimuth, `u[0]` gives θh) reflected, when
    /// the C bake is there; else the spectrum's.
    fn sample_diffraction(&self, wi: [f64; 3], u: [f64; 2]) -> Option<[f64; 3]> {
        let Some(halo) = self.bake().halo() else {
            return self.sample_spectrum(wi, u);
        };
        let m = halo.sample_h(wi, self.big_b * wi[2], u[1], u[0])?;
        let k = 2.0 * dot(wi, m);
        if !(k > 0.0) {
            return None;
        }
        Some([k * m[0] - wi[0], k * m[1] - wi[1], k * m[2] - wi[2]])
    }

    /// The spectrum's draw (HP17 51-55; [`TwoScale::sample_lobe`]).
    fn sample_spectrum(&self, wi: [f64; 3], u: [f64; 2]) -> Option<[f64; 3]> {
        let (b, sin_i, inv_m) = self.diffraction_setup(wi)?;
        let m = 1.0 / inv_m;
        let c = f64::from(self.surface.c);
        let t = -2.0 / (c - 1.0) * f64::from(math::ln_1pf((-m * u[0]) as f32)); // (HP17 51)
        let r = (math::sqrt(f64::from(math::exp_m1f(t as f32)).max(0.0)) / b).min(1.0 + sin_i);
        let psi = (2.0 * u[1] - 1.0) * Self::phi_max(r, sin_i); // (HP17 53-54)
        let (cos_phi_i, sin_phi_i) = if sin_i > 0.0 {
            (wi[0] / sin_i, wi[1] / sin_i)
        } else {
            (1.0, 0.0)
        };
        let (cp, sp) = (math::cos(psi), math::sin(psi));
        let dir = [
            cos_phi_i * cp - sin_phi_i * sp,
            sin_phi_i * cp + cos_phi_i * sp,
        ];
        let ox = r * dir[0] - wi[0]; // (HP17 55)
        let oy = r * dir[1] - wi[1];
        let z2 = 1.0 - ox * ox - oy * oy;
        if !(z2 > 0.0) {
            return None;
        }
        Some([ox, oy, math::sqrt(z2)])
    }

    /// Samples an outgoing direction for incidence `i` from three uniforms:
    /// `u[0]` picks the lobe with the weights of [`TwoScale::lobe_weights`]
    /// (and is rescaled), `u[1], u[2]` drive [`TwoScale::sample_lobe`].
    /// Returns the direction, [`TwoScale::pdf`] there (> 0) and ρ there;
    /// `None` when nothing can be sampled (see `sample_lobe`). The specular
    /// lobe draws visible normals from the material's tabulated visible-slope
    /// density, which `pdf` evaluates (docs/model.md §2.1).
    pub fn sample(&self, i: [f32; 3], u: [f32; 3]) -> Option<Sample> {
        let wi = upper_unit(i)?;
        // The lobe weights and the visible-normal sampler's incidence serve
        // the draw and the pdf: the same values `pdf(i, o)` computes from `i`.
        let w = self.weights(wi[2]);
        let lobe = pick_lobe(f64::from(u[0].max(0.0).min(BELOW_ONE)), w);
        let visible = (w[0] > 0.0).then(|| self.bake().visible.incidence(wi));
        let o = self.draw_lobe(lobe, wi, visible.as_ref(), [u[1], u[2]])?;
        // pdf(i, o) and eval(i, o) from one geometry.
        let geometry = self.geometry(i, o)?;
        let specular = match &visible {
            Some(inc) => self.bake().visible.pdf_at(inc, geometry.wi, geometry.wo),
            None => 0.0,
        };
        let pdf = finite_or_zero(self.pdf_with(&geometry, &w, specular));
        if !(pdf > 0.0) {
            return None;
        }
        Some(Sample {
            o,
            pdf,
            value: self.lobes(&self.with_masking(geometry)).total(),
            lobe,
        })
    }

    /// The direction and lobe of [`TwoScale::sample`].
    fn sample_direction(&self, i: [f32; 3], u: [f32; 3]) -> Option<([f32; 3], Lobe)> {
        let wi = upper_unit(i)?;
        let w = self.weights(wi[2]);
        let pick = f64::from(u[0].max(0.0).min(BELOW_ONE));
        let lobe = pick_lobe(pick, w);
        Some((self.sample_lobe(lobe, i, [u[1], u[2]])?, lobe))
    }
}

/// What [`TwoScale::bake_wavelength`] bakes besides the direction bake:
/// a model on its own bakes everything; models that serve only the eval of
/// a model over λ between its sampler models skip the halo sampler (their
/// own halo draws come from the spectrum, HP17 51–55) and may take C from
/// a model at a shorter wavelength (whose bake covers their `u` range).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
struct NodeBakes {
    /// Bake C (else the caller has copied a bake covering `[0, B]` in).
    conv: bool,
    /// Bake the halo sampler ([`HaloBake`]) from C.
    halo_sampler: bool,
}

impl NodeBakes {
    /// Everything.
    const ALL: NodeBakes = NodeBakes {
        conv: true,
        halo_sampler: true,
    };
}

/// The albedo estimates of the lobes at one incidence, for
/// [`TwoScale::weights_at`].
#[derive(Clone, Copy, Debug)]
struct LobeEnergies {
    /// `E(μ; β, p)` of T6 (F = 1, no A).
    specular: f64,
    /// `∫ ρ_CTD cos θo dωo`.
    halo: f64,
}

/// Incidences of [`TwoScale::halo_albedo_nodes`] (every 32nd node of the
/// direction bake's 257).
const HALO_ALBEDO_NODES: usize = 9;
/// Lattice points per incidence, and the lattice's generator (Fibonacci).
const HALO_ALBEDO_POINTS: usize = 34;
const HALO_ALBEDO_STRIDE: usize = 21;
/// The diffraction lobe's smallest share of the estimated albedo.
const HALO_FLOOR: f64 = 1e-3;

/// The halo albedo between [`HALO_ALBEDO_NODES`], linear in `√cos θi`.
fn halo_albedo_at(nodes: &[f64; HALO_ALBEDO_NODES], cos: f64) -> f64 {
    let x = math::sqrt(cos.max(0.0).min(1.0)) * (HALO_ALBEDO_NODES - 1) as f64;
    let k = (x as usize).min(HALO_ALBEDO_NODES - 2);
    let t = x - k as f64;
    nodes[k] + t * (nodes[k + 1] - nodes[k])
}

/// Q̄ of a pair (HP17 33, docs/model.md §2.5), clamped at 0: 1 for white
/// colour terms, 0 without an index (`q` `None`).
#[inline]
fn q_bar(
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
fn masking_g(mode: Masking, g1_i: f64, g1_o: f64) -> f64 {
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
fn halo_attenuation(
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
fn sigma_ratio_sq(mode: SigmaRelMode, at_i: &DirectionValues, at_o: &DirectionValues) -> f64 {
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

/// Nodes of [`TwoScale::halo_deficit`] over `√cos θi` (linear between).
const DEFICIT_NODES: usize = 17;
/// The smallest `cos θi` at which the deficit is computed (the first node's).
const DEFICIT_MIN_COS: f64 = 1e-4;
/// Panels of [`TwoScale::halo_deficit`]'s rule in `ln α`.
const DEFICIT_PANELS: usize = 16;
/// Azimuths of [`TwoScale::halo_deficit`]'s rule.
const DEFICIT_AZIMUTHS: usize = 32;

/// `(F_ms, F_ms / (π (1 − E_avg)))` of the compensation lobe
/// (docs/model.md §2.11) for the albedo average `E_avg` and the Fresnel
/// average `F_avg`:
///
/// ```text
/// F_ms = F_avg² E_avg / (1 − F_avg (1 − E_avg))
/// ```
///
/// (the light that leaves after k ≥ 2 bounces, `Σ F_avg^k E_avg (1 − E_avg)^(k−1)`,
/// over its value at `F_avg = 1`, `1 − E_avg`). `(0, 0)` when
/// `1 − E_avg ≤ 1e-6` (nothing to put back).
fn compensation(e_avg: f64, f_avg: f64) -> (f64, f64) {
    let lost = 1.0 - e_avg;
    if !(lost > 1e-6) {
        return (0.0, 0.0);
    }
    let f_ms = f_avg * f_avg * e_avg / (1.0 - f_avg * lost);
    if !f_ms.is_finite() {
        return (0.0, 0.0);
    }
    (f_ms, f_ms / (PI * lost))
}

/// The lobe weights of three channels whose samplers are mixed with equal
/// probability under one density ([`Rgb::pdf`]), set in each channel's
/// table. With `s_cl` a channel's own weights (its lobes'
/// albedo shares, [`TwoScale::lobe_weights`]), the mixture picks lobe `l` with
///
/// ```text
/// π_l ∝ (min_c s_cl + max_c s_cl) / 2,     Σ_l π_l = 1
/// ```
///
/// and the halo's `π_h` is split over the channels' halo draws (whose shapes
/// differ) as their own shares, channel `c`'s weights being
///
/// ```text
/// w_ch = min(1, 3 π_h s_ch / Σ_c' s_c'h),   w_cl = π_l (1 − w_ch)/(1 − π_h)  (l ≠ h)
/// ```
///
/// so that `(1/3) Σ_c w_cl = π_l`. For lobes apart, a channel's relative
/// variance is at least `Σ_l s_cl²/π_l − 1`; with two lobes that is
/// `(s_c − π)²/(π (1 − π))`, whose largest over the channels is smallest at
/// the mid-range `π = (min s_c + max s_c)/2`. Each channel's own weights
/// (the mixture `π_l = mean_c s_cl`) sent the lobe carrying most of the
/// energy in one channel too few samples (docs/design/halo-sampling.md;
/// not applied to `IntegratedRgb`'s sampler nodes, where it raised the
/// presets' largest variance by up to 10%).
fn share_lobe_weights<B: BorrowMut<ChannelBake>>(channels: [&mut TwoScale<'_, B>; 3]) {
    let nodes = {
        let own = |cos: f64| channels.each_ref().map(|ch| ch.weights(cos));
        let shared = |c: usize, cos: f64| shared_lobe_weights(own(cos))[c];
        [0, 1, 2].map(|c| {
            channels[c]
                .bake()
                .direction
                .lobe_weight_nodes(|_, cos| shared(c, cos))
        })
    };
    for (channel, nodes) in channels.into_iter().zip(&nodes) {
        channel.bake.borrow_mut().direction.set_lobe_weights(nodes);
    }
}

/// [`share_lobe_weights`] at one incidence: the channels' weights from
/// their own (normalised) weights `s`.
fn shared_lobe_weights(s: [[f64; 4]; 3]) -> [[f64; 4]; 3] {
    let mut pi = [0usize, 1, 2, 3].map(|l| {
        let (lo, hi) = s.iter().fold((f64::INFINITY, 0.0f64), |(lo, hi), w| {
            (lo.min(w[l]), hi.max(w[l]))
        });
        0.5 * (lo + hi)
    });
    let total: f64 = pi.iter().sum();
    if !(total > 0.0 && total.is_finite()) {
        return s;
    }
    pi = pi.map(|x| x / total);
    let halo: f64 = s.iter().map(|w| w[1]).sum();
    let rest = 1.0 - pi[1];
    s.map(|w| {
        let h = if halo > 0.0 {
            (3.0 * pi[1] * w[1] / halo).min(1.0)
        } else {
            0.0
        };
        let k = if rest > 0.0 { (1.0 - h) / rest } else { 0.0 };
        [pi[0] * k, h, pi[2] * k, pi[3] * k]
    })
}

/// The lobe whose cumulative-weight interval holds `pick ∈ [0, 1)`; rounding
/// past the last interval falls on the last lobe of positive weight.
fn pick_lobe(pick: f64, w: [f64; 4]) -> Lobe {
    const LOBES: [Lobe; 4] = [
        Lobe::Specular,
        Lobe::Diffraction,
        Lobe::Base,
        Lobe::Multiple,
    ];
    let mut cumulative = 0.0;
    let mut last = Lobe::Specular;
    for (k, lobe) in LOBES.into_iter().enumerate() {
        if w[k] > 0.0 {
            cumulative += w[k];
            last = lobe;
            if pick < cumulative {
                return lobe;
            }
        }
    }
    last
}

/// The model at the three [`RGB_WAVELENGTHS`], one complex index per channel.
/// The channels share the geometry, D and G of each evaluation (they must
/// share the surface, as [`Rgb::new`] makes them). The bakes are held as `B`,
/// as [`TwoScale`]'s: by value ([`Rgb::new`], 366 KB), boxed (`Rgb::boxed`)
/// or in caller-provided storage ([`Rgb::new_in`]).
#[derive(Clone)]
pub struct Rgb<'a, B = ChannelBake> {
    /// The red, green and blue channels.
    pub channels: [TwoScale<'a, B>; 3],
}

/// A sampled direction of the RGB model.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RgbSample {
    /// The outgoing direction (unit vector, `z > 0`).
    pub o: [f32; 3],
    /// [`Rgb::pdf`] at `o`.
    pub pdf: f32,
    /// ρ(i, o) per channel (sr⁻¹).
    pub value: [f32; 3],
}

impl<'a> Rgb<'a> {
    /// The three channels of `material` at [`RGB_WAVELENGTHS`]. The value is
    /// 366 KB: on small stacks use `Rgb::boxed` or [`Rgb::new_in`].
    pub fn new(tables: &Tables<'a>, material: &Material, options: Options) -> Self {
        let bakes = [
            ChannelBake::zeroed(),
            ChannelBake::zeroed(),
            ChannelBake::zeroed(),
        ];
        Self::new_in(bakes, tables, material, options)
    }
}

#[cfg(feature = "std")]
impl<'a> Rgb<'a, std::boxed::Box<ChannelBake>> {
    /// [`Rgb::new`] with the bakes on the heap (`ChannelBake::boxed`,
    /// filled in place): construction runs on a 64 KiB stack.
    pub fn boxed(tables: &Tables<'a>, material: &Material, options: Options) -> Self {
        let bakes = [
            ChannelBake::boxed(),
            ChannelBake::boxed(),
            ChannelBake::boxed(),
        ];
        Self::new_in(bakes, tables, material, options)
    }
}

impl<'a, B: BorrowMut<ChannelBake>> Rgb<'a, B> {
    /// [`Rgb::new`] baking into the storage `bakes` in place (see
    /// [`TwoScale::new_in`]).
    pub fn new_in(
        bakes: [B; 3],
        tables: &Tables<'a>,
        material: &Material,
        options: Options,
    ) -> Self {
        // G1, the visible-slope tables and C's slice do not depend on the wavelength.
        let shared = SurfaceBakes::new(tables, material.layer.surface);
        let mut k = 0;
        let mut channels = bakes.map(|bake| {
            let channel = TwoScale::around(
                bake,
                tables,
                &shared,
                material.layer,
                RGB_WAVELENGTHS[k],
                material.eta_rgb[k],
                options,
            );
            k += 1;
            channel
        });
        let (first, rest) = channels.split_at_mut(1);
        let first = first[0].bake.borrow_mut();
        shared.bake_into(tables, first);
        for channel in rest {
            let bake = channel.bake.borrow_mut();
            bake.masking.clone_from(&first.masking);
            bake.visible.clone_from(&first.visible);
        }
        for (channel, eta) in channels.iter_mut().zip(material.eta_rgb) {
            channel.bake_wavelength(tables, &shared, eta, NodeBakes::ALL);
        }
        let [r, g, b] = &mut channels;
        share_lobe_weights([r, g, b]);
        Rgb { channels }
    }

    /// The storage of the bakes, to rebuild another model in ([`Rgb::new_in`]).
    pub fn into_bakes(self) -> [B; 3] {
        self.channels.map(TwoScale::into_bake)
    }
}

impl<B: Borrow<ChannelBake>> Rgb<'_, B> {
    /// ρ(i, o) per channel.
    pub fn eval(&self, i: [f32; 3], o: [f32; 3]) -> [f32; 3] {
        match self.channels[0].pair(i, o) {
            Some(pair) => self.channels.each_ref().map(|ch| ch.lobes(&pair).total()),
            None => [0.0; 3],
        }
    }

    /// The density of [`Rgb::sample`]: the mean of the channels' pdfs (one
    /// channel's sampler is picked uniformly; the channels' lobe weights are
    /// shared, `share_lobe_weights`).
    pub fn pdf(&self, i: [f32; 3], o: [f32; 3]) -> f32 {
        match self.channels[0].geometry(i, o) {
            Some(geometry) => finite_or_zero(self.pdf_at(&geometry)),
            None => 0.0,
        }
    }

    /// [`Rgb::pdf`] at a pair's geometry.
    fn pdf_at(&self, geometry: &Geometry) -> f64 {
        // The channels share the surface, hence the specular density.
        let specular = self.channels[0].specular_pdf(geometry);
        let sum: f64 = self
            .channels
            .iter()
            .map(|ch| f64::from(finite_or_zero(ch.pdf_with_specular(geometry, specular))))
            .sum();
        sum / 3.0
    }

    /// Picks a channel's sampler with `u[0]` (uniformly; `u[0]` is rescaled
    /// and reused to pick the lobe), samples it, and returns the direction,
    /// the mixture density [`Rgb::pdf`] and the three values.
    pub fn sample(&self, i: [f32; 3], u: [f32; 3]) -> Option<RgbSample> {
        let pick = 3.0 * f64::from(u[0].max(0.0).min(BELOW_ONE));
        let k = (pick as usize).min(2);
        let rest = (pick - k as f64) as f32;
        let (o, _) = self.channels[k].sample_direction(i, [rest, u[1], u[2]])?;
        // pdf(i, o) and eval(i, o) from one geometry.
        let geometry = self.channels[0].geometry(i, o)?;
        let pdf = finite_or_zero(self.pdf_at(&geometry));
        if !(pdf > 0.0) {
            return None;
        }
        let pair = self.channels[0].with_masking(geometry);
        Some(RgbSample {
            o,
            pdf,
            value: self.channels.each_ref().map(|ch| ch.lobes(&pair).total()),
        })
    }
}
