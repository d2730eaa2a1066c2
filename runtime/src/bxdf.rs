//! One interface for every BRDF of the runtime, as pbrt-v4's `BxDF` and
//! Mitsuba 3's `BSDF` have: [`Bxdf`] with `eval`, `sample`, `pdf` and the
//! [`BxdfFlags`] of what the BRDF holds. Implemented by the two-scale model
//! at one wavelength ([`TwoScale`], `f32` values) and in RGB ([`Rgb`],
//! `[f32; 3]`), the 2015 model ([`Hp15`], `f32`) and the SH matrices
//! ([`ShBrdfTable`], `[f32; 3]`).
//!
//! Conventions (those of [`crate::brdf`]): reflection only, directions in the
//! local frame (normal `+z`), `i` towards the light, `o` towards the viewer,
//! ρ in sr⁻¹; `pdf` is the solid-angle density of `sample`'s directions;
//! below the horizon `eval` and `pdf` are 0 and `sample` is `None`.
//!
//! The value type is an associated type: one wavelength is `f32`, `N`
//! channels `[f32; N]`, so an RGB model cannot be used where one wavelength
//! is expected. Each implementation forwards to the type's own methods
//! (static dispatch: no cost over calling them directly).

use crate::brdf::{ChannelBake, Rgb, TwoScale};
use crate::hp15::Hp15;
use crate::math::{BELOW_ONE, upper_unit};
use crate::sh::ShBrdfTable;
use core::borrow::Borrow;
use core::f64::consts::PI;
use core::ops::BitOr;

/// What a BRDF holds (pbrt-v4's `BxDFFlags`, Mitsuba's `BSDFFlags`,
/// reflection only); combine with `|`.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub struct BxdfFlags(u8);

impl BxdfFlags {
    /// Nothing: a BRDF that is 0 everywhere.
    pub const NONE: BxdfFlags = BxdfFlags(0);
    /// A glossy (microfacet) lobe around the mirror direction.
    pub const GLOSSY: BxdfFlags = BxdfFlags(1);
    /// A diffuse term: a base layer or a Lambertian `k_d/π`.
    pub const DIFFUSE: BxdfFlags = BxdfFlags(2);
    /// A diffraction lobe (the halo of nano-scale roughness).
    pub const DIFFRACTION: BxdfFlags = BxdfFlags(4);
    /// Band-limited: a projection onto spherical harmonics, sampled
    /// cosine-weighted rather than by its lobes.
    pub const BAND_LIMITED: BxdfFlags = BxdfFlags(8);

    /// Whether every flag of `other` is set.
    pub fn contains(self, other: BxdfFlags) -> bool {
        self.0 & other.0 == other.0
    }

    /// The flags as bits (GLOSSY 1, DIFFUSE 2, DIFFRACTION 4, BAND_LIMITED 8).
    pub fn bits(self) -> u8 {
        self.0
    }

    /// `flag` when `condition` holds, else [`BxdfFlags::NONE`].
    pub fn when(condition: bool, flag: BxdfFlags) -> BxdfFlags {
        if condition { flag } else { BxdfFlags::NONE }
    }
}

impl BitOr for BxdfFlags {
    type Output = BxdfFlags;
    fn bitor(self, other: BxdfFlags) -> BxdfFlags {
        BxdfFlags(self.0 | other.0)
    }
}

/// A sampled outgoing direction of a [`Bxdf`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct BxdfSample<V> {
    /// The outgoing direction (unit vector, `z > 0`).
    pub o: [f32; 3],
    /// [`Bxdf::pdf`] at `o` (solid-angle density, > 0).
    pub pdf: f32,
    /// [`Bxdf::eval`] at `o` (sr⁻¹).
    pub value: V,
}

/// A BRDF: evaluation, importance sampling and the sampler's density (module
/// documentation).
pub trait Bxdf {
    /// ρ's type: `f32` at one wavelength, `[f32; N]` for `N` channels.
    type Value: Copy;

    /// What the BRDF holds.
    fn flags(&self) -> BxdfFlags;

    /// ρ(i, o) in sr⁻¹; 0 below the horizon.
    fn eval(&self, i: [f32; 3], o: [f32; 3]) -> Self::Value;

    /// The solid-angle density over `o` of [`Bxdf::sample`] given `i`.
    fn pdf(&self, i: [f32; 3], o: [f32; 3]) -> f32;

    /// An outgoing direction for `i` from three uniforms in [0, 1), with its
    /// density and ρ; `None` when nothing is sampled.
    fn sample(&self, i: [f32; 3], u: [f32; 3]) -> Option<BxdfSample<Self::Value>>;
}

impl<B: Borrow<ChannelBake>> Bxdf for TwoScale<'_, B> {
    type Value = f32;

    fn flags(&self) -> BxdfFlags {
        let (has_diffraction, has_diffuse) = self.has_lobes();
        BxdfFlags::GLOSSY
            | BxdfFlags::when(has_diffraction, BxdfFlags::DIFFRACTION)
            | BxdfFlags::when(has_diffuse, BxdfFlags::DIFFUSE)
    }

    #[inline]
    fn eval(&self, i: [f32; 3], o: [f32; 3]) -> f32 {
        TwoScale::eval(self, i, o)
    }

    #[inline]
    fn pdf(&self, i: [f32; 3], o: [f32; 3]) -> f32 {
        TwoScale::pdf(self, i, o)
    }

    #[inline]
    fn sample(&self, i: [f32; 3], u: [f32; 3]) -> Option<BxdfSample<f32>> {
        TwoScale::sample(self, i, u).map(|s| BxdfSample {
            o: s.o,
            pdf: s.pdf,
            value: s.value,
        })
    }
}

impl<B: Borrow<ChannelBake>> Bxdf for Rgb<'_, B> {
    type Value = [f32; 3];

    fn flags(&self) -> BxdfFlags {
        self.channels
            .iter()
            .map(Bxdf::flags)
            .fold(BxdfFlags::NONE, BitOr::bitor)
    }

    #[inline]
    fn eval(&self, i: [f32; 3], o: [f32; 3]) -> [f32; 3] {
        Rgb::eval(self, i, o)
    }

    #[inline]
    fn pdf(&self, i: [f32; 3], o: [f32; 3]) -> f32 {
        Rgb::pdf(self, i, o)
    }

    #[inline]
    fn sample(&self, i: [f32; 3], u: [f32; 3]) -> Option<BxdfSample<[f32; 3]>> {
        Rgb::sample(self, i, u).map(|s| BxdfSample {
            o: s.o,
            pdf: s.pdf,
            value: s.value,
        })
    }
}

impl Bxdf for Hp15<'_> {
    type Value = f32;

    fn flags(&self) -> BxdfFlags {
        let [ks, kw, kd] = self.colours();
        BxdfFlags::when(ks > 0.0, BxdfFlags::GLOSSY)
            | BxdfFlags::when(kw > 0.0, BxdfFlags::DIFFRACTION)
            | BxdfFlags::when(kd > 0.0, BxdfFlags::DIFFUSE)
    }

    #[inline]
    fn eval(&self, i: [f32; 3], o: [f32; 3]) -> f32 {
        Hp15::eval(self, i, o)
    }

    #[inline]
    fn pdf(&self, i: [f32; 3], o: [f32; 3]) -> f32 {
        Hp15::pdf(self, i, o)
    }

    fn sample(&self, i: [f32; 3], u: [f32; 3]) -> Option<BxdfSample<f32>> {
        let (o, pdf) = Hp15::sample(self, i, u)?;
        Some(BxdfSample {
            o,
            pdf,
            value: Hp15::eval(self, i, o),
        })
    }
}

/// The SH matrices: ρ per channel from [`ShBrdfTable::eval_rgb`] (0 for the
/// channels the file does not have); sampled cosine-weighted, `pdf = cos θo / π`
/// (`u[0]` unused), since a band-limited matrix has no lobes to sample.
impl Bxdf for ShBrdfTable<'_> {
    type Value = [f32; 3];

    fn flags(&self) -> BxdfFlags {
        BxdfFlags::BAND_LIMITED
    }

    #[inline]
    fn eval(&self, i: [f32; 3], o: [f32; 3]) -> [f32; 3] {
        self.eval_rgb(i, o)
    }

    fn pdf(&self, i: [f32; 3], o: [f32; 3]) -> f32 {
        match (upper_unit(i), upper_unit(o)) {
            (Some(_), Some(wo)) => (wo[2] / PI) as f32,
            _ => 0.0,
        }
    }

    fn sample(&self, i: [f32; 3], u: [f32; 3]) -> Option<BxdfSample<[f32; 3]>> {
        upper_unit(i)?;
        let (u1, u2) = (
            f64::from(u[1].max(0.0).min(BELOW_ONE)),
            f64::from(u[2].max(0.0).min(BELOW_ONE)),
        );
        let r = crate::math::sqrt(u1);
        let phi = 2.0 * PI * u2;
        let o = [
            r * crate::math::cos(phi),
            r * crate::math::sin(phi),
            crate::math::sqrt(1.0 - u1),
        ];
        let o = upper_unit(o.map(|x| x as f32))?.map(|x| x as f32);
        let pdf = Bxdf::pdf(self, i, o);
        (pdf > 0.0).then(|| BxdfSample {
            o,
            pdf,
            value: self.eval_rgb(i, o),
        })
    }
}
