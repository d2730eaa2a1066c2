//! One interface for every BRDF of the runtime, as pbrt-v4's `BxDF` and
//! Mitsuba 3's `BSDF` have: [`Bxdf`] with `eval`, `sample`, `pdf` and the
//! [`BxdfFlags`] of what the BRDF holds. Implemented by the two-scale model
//! at one wavelength ([`TwoScale`], `f32` values), in RGB at the paper's
//! wavelengths ([`Rgb`], `[f32; 3]`), integrated over the spectrum
//! ([`IntegratedRgb`]) or either ([`RgbModel`]), the 2015 model ([`Hp15`],
//! `f32`) and the SH matrices ([`ShBrdfTable`], `[f32; 3]`).
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

use crate::brdf::hp15::Hp15;
use crate::brdf::{ChannelBake, IntegratedRgb, Rgb, RgbModel, TwoScale};
use crate::math::{BELOW_ONE, upper_unit};
use crate::tables::sh_brdf::ShBrdfTable;
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

impl<B: Borrow<ChannelBake>> Bxdf for IntegratedRgb<'_, B> {
    type Value = [f32; 3];

    fn flags(&self) -> BxdfFlags {
        self.nodes()
            .iter()
            .map(Bxdf::flags)
            .fold(BxdfFlags::NONE, BitOr::bitor)
    }

    #[inline]
    fn eval(&self, i: [f32; 3], o: [f32; 3]) -> [f32; 3] {
        IntegratedRgb::eval(self, i, o)
    }

    #[inline]
    fn pdf(&self, i: [f32; 3], o: [f32; 3]) -> f32 {
        IntegratedRgb::pdf(self, i, o)
    }

    #[inline]
    fn sample(&self, i: [f32; 3], u: [f32; 3]) -> Option<BxdfSample<[f32; 3]>> {
        IntegratedRgb::sample(self, i, u).map(|s| BxdfSample {
            o: s.o,
            pdf: s.pdf,
            value: s.value,
        })
    }
}

impl<B: Borrow<ChannelBake>> Bxdf for RgbModel<'_, B> {
    type Value = [f32; 3];

    fn flags(&self) -> BxdfFlags {
        match self {
            RgbModel::PaperWavelengths(m) => m.flags(),
            RgbModel::Integrated(m) => m.flags(),
        }
    }

    #[inline]
    fn eval(&self, i: [f32; 3], o: [f32; 3]) -> [f32; 3] {
        match self {
            RgbModel::PaperWavelengths(m) => Rgb::eval(m, i, o),
            RgbModel::Integrated(m) => IntegratedRgb::eval(m, i, o),
        }
    }

    #[inline]
    fn pdf(&self, i: [f32; 3], o: [f32; 3]) -> f32 {
        match self {
            RgbModel::PaperWavelengths(m) => Rgb::pdf(m, i, o),
            RgbModel::Integrated(m) => IntegratedRgb::pdf(m, i, o),
        }
    }

    #[inline]
    fn sample(&self, i: [f32; 3], u: [f32; 3]) -> Option<BxdfSample<[f32; 3]>> {
        match self {
            RgbModel::PaperWavelengths(m) => Bxdf::sample(m, i, u),
            RgbModel::Integrated(m) => Bxdf::sample(m, i, u),
        }
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

#[cfg(all(test, feature = "embedded"))]
mod tests {
    use super::*;
    use crate::TableSet;
    use crate::brdf::hp15::{Energy, Hp15Params};
    use crate::material::Options;
    use crate::materials::PRESETS;
    use crate::test_rng::Lcg;

    /// A direction in the upper hemisphere from two uniforms.
    fn direction(rng: &mut Lcg) -> [f32; 3] {
        let (z, phi) = (
            rng.next() as f32,
            core::f32::consts::TAU * rng.next() as f32,
        );
        let r = (1.0 - z * z).max(0.0).sqrt();
        [r * phi.cos(), r * phi.sin(), z]
    }

    /// Through the trait: eval and pdf are the inherent ones, a sample's
    /// pdf and value are `pdf` and `eval` at its direction.
    fn check<T: Bxdf>(
        model: &T,
        eval: impl Fn([f32; 3], [f32; 3]) -> T::Value,
        pdf: impl Fn([f32; 3], [f32; 3]) -> f32,
    ) where
        T::Value: PartialEq + core::fmt::Debug,
    {
        let mut rng = Lcg(9);
        let mut sampled = 0;
        for _ in 0..200 {
            let (i, o) = (direction(&mut rng), direction(&mut rng));
            assert_eq!(model.eval(i, o), eval(i, o));
            assert_eq!(model.pdf(i, o), pdf(i, o));
            let u = [0, 1, 2].map(|_| rng.next() as f32);
            if let Some(s) = model.sample(i, u) {
                sampled += 1;
                assert!(s.pdf > 0.0 && s.o[2] > 0.0);
                assert_eq!(s.pdf, model.pdf(i, s.o));
                assert_eq!(s.value, model.eval(i, s.o));
            }
        }
        assert!(sampled > 100, "{sampled} of 200 sampled");
        let below = [0.3, 0.0, -0.5];
        assert_eq!(model.pdf(below, [0.0, 0.0, 1.0]), 0.0);
        assert!(model.sample(below, [0.5; 3]).is_none());
    }

    #[test]
    fn every_model_forwards_to_its_own_methods() {
        let set = TableSet::embedded();
        let tables = set.brdf_tables();
        for (_, material) in PRESETS {
            let rgb = Rgb::new(&tables, &material, Options::default());
            check(&rgb, |i, o| rgb.eval(i, o), |i, o| rgb.pdf(i, o));
            let one = &rgb.channels[1];
            check(one, |i, o| one.eval(i, o), |i, o| one.pdf(i, o));
        }
        let params = Hp15Params {
            beta: 0.2,
            p: 1.3,
            a: 2.0,
            kd: 0.1,
            ks: 0.6,
            kw: 0.02,
            f0: 0.9,
        };
        let hp15 = Hp15::new(&set.smith, params, 0.526, Energy::Exact);
        check(&hp15, |i, o| hp15.eval(i, o), |i, o| hp15.pdf(i, o));
        let sh = ShBrdfTable::from_bytes(crate::include_table!("../tables/t4-gold-rough.tbl"))
            .expect("T4");
        // cos θo / π of the renormalised direction.
        let cosine = |_: [f32; 3], o: [f32; 3]| {
            let w = o.map(f64::from);
            (w[2] / (w[0] * w[0] + w[1] * w[1] + w[2] * w[2]).sqrt() / PI) as f32
        };
        check(&sh, |i, o| sh.eval_rgb(i, o), cosine);
    }

    #[test]
    fn flags_say_which_lobes_a_model_has() {
        let set = TableSet::embedded();
        let tables = set.brdf_tables();
        for (name, material) in PRESETS {
            let flags = Rgb::new(&tables, &material, Options::default()).flags();
            let s = material.layer.surface;
            assert!(flags.contains(BxdfFlags::GLOSSY), "{name}");
            assert_eq!(
                flags.contains(BxdfFlags::DIFFRACTION),
                s.sigma_s > 0.0 && s.b > 0.0 && s.c > 1.0,
                "{name}"
            );
            let diffuse = material.layer.base != crate::material::BaseLayer::Conductor
                || material.layer.lambertian > 0.0;
            assert_eq!(flags.contains(BxdfFlags::DIFFUSE), diffuse, "{name}");
        }
        let mirror_like = Hp15Params {
            beta: 0.2,
            p: 1.0,
            a: 1.0,
            kd: 0.0,
            ks: 1.0,
            kw: 0.0,
            f0: 1.0,
        };
        let hp15 = Hp15::new(&set.smith, mirror_like, 0.5, Energy::Exact);
        assert_eq!(hp15.flags(), BxdfFlags::GLOSSY);
        assert_eq!((BxdfFlags::GLOSSY | BxdfFlags::DIFFUSE).bits(), 3);
    }
}
