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
//! With [`MultipleScattering::KullaConty`](crate::material::MultipleScattering::KullaConty) a fourth term puts back the
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
//! an adapter), F and Q̄ from [`crate::model::fresnel`]. The constant of ρ_CTD makes
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
//! [`SigmaRelMode::Symmetrised`](crate::material::SigmaRelMode::Symmetrised) uses `σrel² = (σrel²(θi) + σrel²(θo))/2`,
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

use crate::bake::halo::HaloBake;
use crate::bake::visible::VisibleSlopeBake;
use crate::bake::{ConvBake, DirectionBake, MaskingBake, RadialNormBake};
use crate::material::{BaseLayer, ColourTerms, Options, Surface};
use crate::math::{self};
use crate::model::epd::Epd;
use crate::model::fresnel::QConstants;
use crate::tables::albedo::AlbedoTable;
use crate::tables::convolution::Convolution;
use crate::tables::diffuse_fresnel::DiffuseFresnelTable;
use crate::tables::sigma_ratio::SigmaRatioTable;
use crate::tables::smith_g1::SmithG1Table;
use core::borrow::Borrow;
use zerocopy::FromZeros;

mod construct;
mod eval;
pub mod hp15;
mod integrated;
mod rgb;
mod sample;
mod spectral;

pub use crate::bake::BakeVisitor;
pub use integrated::{INTEGRATED_COUNT, INTEGRATED_WAVELENGTHS, IntegratedRgb, RgbModel};
pub use rgb::{Rgb, RgbSample};
#[cfg(feature = "std")]
pub use spectral::BoxedSpectral;
pub use spectral::{FresnelBake, SPECTRAL_COUNT, SPECTRAL_WAVELENGTHS, Spectral};

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
    /// 51-55) mixed with a half-vector draw that follows C (`crate::bake::halo`).
    Diffraction,
    /// `ρ_base + k_d/π`, cosine-weighted.
    Base,
    /// `ρ_ms`, the energy compensation of [`MultipleScattering::KullaConty`](crate::material::MultipleScattering::KullaConty),
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
    /// `ρ_ms` (0 unless [`MultipleScattering::KullaConty`](crate::material::MultipleScattering::KullaConty)).
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
///
/// Mirrored in python/twoscale/drjit/lobes.py.
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
/// modules `bake`, `visible` and `halo`): 141 KB of plain numbers (the
/// visible-slope tables 55 KB, the halo sampler's densities 48 KB, C 19 KB,
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
    /// Whether `conv` holds C (the source of C offers a slice, as T3b does,
    /// or bakes its profiles);
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

    /// Empty storage by value (141 KB on the caller's stack).
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
/// value (the default, 141 KB; [`TwoScale::new`]), boxed
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
}

#[cfg(test)]
mod tests;
