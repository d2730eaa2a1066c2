//! The domain of every model parameter, and one validation that every front
//! end calls (the C API, Python, `generator query`, the generator itself).
//!
//! The renderer-facing constructors and `eval`/`sample`/`pdf` clamp their
//! inputs as each documents: that is their contract, and it keeps them
//! panic-free. Whoever takes parameters from a user validates them first with
//! [`Material::validate`] (or the
//! [`Layer`] and [`Surface`] forms),
//! [`wavelength`], [`eta`] and, for lookups of a single table, the table's own
//! `check` ([`SmithG1Table::check`](crate::SmithG1Table::check),
//! [`SigmaRatioTable::check`](crate::SigmaRatioTable::check),
//! [`ConvTable::check`](crate::ConvTable::check),
//! [`DiffuseFresnelTable::check`](crate::DiffuseFresnelTable::check)), whose
//! domains are read from the table's header. An [`Invalid`]
//! ([`crate::domain`]) names the parameter, its value and its domain.
//!
//! [`Named`] gives each option's values their one spelling.

use crate::domain::{Domain, Invalid, check, widen};
use crate::material::{
    BETA_RANGE, BaseKind, BaseLayer, ColourTerms, HaloWeight, Layer, Masking, Material,
    MultipleScattering, P_RANGE, RgbMode, SigmaRelMode, Surface,
};
use crate::math::Complex;
use core::fmt;

/// The wavelengths the model accepts, µm (those [`crate::brdf::TwoScale::new`]
/// does not clamp).
pub const WAVELENGTH_DOMAIN: Domain = Domain::Closed(0.01, 100.0);

/// Checks a wavelength `lambda` in µm against [`WAVELENGTH_DOMAIN`].
pub fn wavelength(lambda: f32) -> Result<(), Invalid> {
    check("lambda", widen(lambda), WAVELENGTH_DOMAIN, "µm")
}

/// Checks a complex index of refraction `n + ik`: `n > 0`, `k ≥ 0`, both
/// finite. `names` are the two parts' names (`("n", "k")`, `("eta[0].n",
/// "eta[0].k")`).
pub fn eta(names: (&'static str, &'static str), eta: Complex) -> Result<(), Invalid> {
    check(names.0, widen(eta.re), Domain::Above(0.0), "")?;
    check(names.1, widen(eta.im), Domain::AtLeast(0.0), "")
}

/// Checks optical-constant rows `(λ µm, n, k)` ([`crate::spectrum::optical::Tabulated`]):
/// at least one row; λ finite, > 0 and strictly increasing (each row's λ must
/// be above the previous one's); each `n + ik` as [`eta`].
pub fn optical_constants(rows: &[[f32; 3]]) -> Result<(), Invalid> {
    check(
        "rows",
        rows.len() as f64,
        Domain::AtLeast(1.0),
        "(lambda, n, k) rows",
    )?;
    let mut previous = 0.0f64;
    for row in rows {
        let lambda = widen(row[0]);
        check(
            "lambda",
            lambda,
            Domain::Above(previous),
            "µm, increasing rows",
        )?;
        eta(("n", "k"), Complex::new(row[1], row[2]))?;
        previous = lambda;
    }
    Ok(())
}

impl Surface {
    /// Checks the surface against the model's domain: β in
    /// [`BETA_RANGE`], p in [`P_RANGE`] (T1's), `σs ≥ 0`, `b ≥ 0` and
    /// `b > 0` when `σs > 0` (the K-correlation spectrum needs a length,
    /// HP17 16), `c > 1`; all finite.
    pub fn validate(&self) -> Result<(), Invalid> {
        let range = |(lo, hi): (f32, f32)| Domain::Closed(widen(lo), widen(hi));
        check("beta", widen(self.beta), range(BETA_RANGE), "")?;
        check("p", widen(self.p), range(P_RANGE), "")?;
        check("sigma_s", widen(self.sigma_s), Domain::AtLeast(0.0), "µm")?;
        check("b", widen(self.b), Domain::AtLeast(0.0), "µm")?;
        if self.sigma_s > 0.0 {
            check(
                "b",
                widen(self.b),
                Domain::Above(0.0),
                "µm, when sigma_s > 0",
            )?;
        }
        check("c", widen(self.c), Domain::Above(1.0), "")
    }
}

impl Layer {
    /// [`Surface::validate`], and the base layer's albedo and the Lambertian
    /// `k_d` in [0, 1].
    pub fn validate(&self) -> Result<(), Invalid> {
        self.surface.validate()?;
        match self.base {
            BaseLayer::Conductor => {}
            BaseLayer::Plastic { albedo } | BaseLayer::Subsurface { albedo } => {
                check("albedo", widen(albedo), Domain::Closed(0.0, 1.0), "")?;
            }
        }
        check(
            "lambertian",
            widen(self.lambertian),
            Domain::Closed(0.0, 1.0),
            "",
        )
    }
}

impl Material {
    /// [`Layer::validate`] and each channel's index ([`eta`], named
    /// `eta[0].n` … `eta[2].k`, red, green, blue).
    pub fn validate(&self) -> Result<(), Invalid> {
        self.layer.validate()?;
        const NAMES: [(&str, &str); 3] = [
            ("eta[0].n", "eta[0].k"),
            ("eta[1].n", "eta[1].k"),
            ("eta[2].n", "eta[2].k"),
        ];
        for (names, &channel) in NAMES.iter().zip(&self.eta_rgb) {
            eta(*names, channel)?;
        }
        Ok(())
    }
}

/// An option whose values have names (the spelling Python keywords, C
/// enumerator comments and `generator query` columns use): one list per
/// option, here.
pub trait Named: Copy + PartialEq + Sized + 'static {
    /// The option's name (`masking`).
    const OPTION: &'static str;
    /// Every value with its name, the default first.
    const NAMES: &'static [(&'static str, Self)];

    /// The value's name.
    fn name(self) -> &'static str {
        Self::NAMES
            .iter()
            .find(|(_, v)| *v == self)
            .map_or("", |(n, _)| n)
    }

    /// The value called `name` (exact match), if any.
    fn from_name(name: &str) -> Option<Self> {
        Self::NAMES
            .iter()
            .find(|(n, _)| *n == name)
            .map(|(_, v)| *v)
    }

    /// The names, for messages: `'separable' or 'height-correlated'`.
    fn choices() -> Choices<Self> {
        Choices(core::marker::PhantomData)
    }
}

/// [`Named::choices`]: displays the names of `T`'s values.
#[derive(Clone, Copy, Debug)]
pub struct Choices<T>(core::marker::PhantomData<T>);

impl<T: Named> fmt::Display for Choices<T> {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let n = T::NAMES.len();
        for (k, (name, _)) in T::NAMES.iter().enumerate() {
            let sep = match k {
                0 => "",
                _ if k + 1 == n => " or ",
                _ => ", ",
            };
            write!(f, "{sep}'{name}'")?;
        }
        Ok(())
    }
}

impl Named for Masking {
    const OPTION: &'static str = "masking";
    const NAMES: &'static [(&'static str, Self)] = &[
        ("separable", Masking::Separable),
        ("height-correlated", Masking::HeightCorrelated),
    ];
}

impl Named for SigmaRelMode {
    const OPTION: &'static str = "sigma_rel";
    const NAMES: &'static [(&'static str, Self)] = &[
        ("incident", SigmaRelMode::Incident),
        ("symmetrised", SigmaRelMode::Symmetrised),
    ];
}

impl Named for ColourTerms {
    const OPTION: &'static str = "colour";
    const NAMES: &'static [(&'static str, Self)] = &[
        ("physical", ColourTerms::Physical),
        ("white", ColourTerms::White),
    ];
}

impl Named for HaloWeight {
    const OPTION: &'static str = "halo_weight";
    const NAMES: &'static [(&'static str, Self)] = &[
        ("printed", HaloWeight::Printed),
        ("incident", HaloWeight::Incident),
    ];
}

impl Named for MultipleScattering {
    const OPTION: &'static str = "multiple_scattering";
    const NAMES: &'static [(&'static str, Self)] = &[
        ("none", MultipleScattering::None),
        ("kulla-conty", MultipleScattering::KullaConty),
    ];
}

impl Named for RgbMode {
    const OPTION: &'static str = "rgb_mode";
    const NAMES: &'static [(&'static str, Self)] = &[
        ("paper-wavelengths", RgbMode::PaperWavelengths),
        ("integrated", RgbMode::Integrated),
    ];
}

impl Named for BaseKind {
    const OPTION: &'static str = "base";
    const NAMES: &'static [(&'static str, Self)] = &[
        ("conductor", BaseKind::Conductor),
        ("plastic", BaseKind::Plastic),
        ("subsurface", BaseKind::Subsurface),
    ];
}

/// The value of option `T` called `given`; `None` is `T`'s default.
pub fn named<T: Named + Default>(given: Option<&str>) -> Result<T, UnknownName<'_>> {
    Ok(named_or_none(given)?.unwrap_or_default())
}

/// The value named `given`, `None` when none is given (an option whose
/// default depends on the material: [`crate::material::RgbMode::default_for`]).
pub fn named_or_none<T: Named>(given: Option<&str>) -> Result<Option<T>, UnknownName<'_>> {
    given
        .map(|name| {
            T::from_name(name).ok_or(UnknownName {
                option: T::OPTION,
                name,
                choices: |f| write!(f, "{}", T::choices()),
            })
        })
        .transpose()
}

/// A name that is none of an option's values ([`named`]).
///
/// Displays as `base must be one of 'conductor', 'plastic' or 'subsurface',
/// got 'glass'`.
#[derive(Clone, Copy)]
pub struct UnknownName<'a> {
    /// The option ([`Named::OPTION`]).
    pub option: &'static str,
    /// The name given.
    pub name: &'a str,
    /// Writes the option's names ([`Named::choices`]).
    choices: fn(&mut fmt::Formatter<'_>) -> fmt::Result,
}

impl PartialEq for UnknownName<'_> {
    /// The option and the name (the choices follow from the option).
    fn eq(&self, other: &Self) -> bool {
        self.option == other.option && self.name == other.name
    }
}

impl fmt::Debug for UnknownName<'_> {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.debug_struct("UnknownName")
            .field("option", &self.option)
            .field("name", &self.name)
            .finish()
    }
}

impl fmt::Display for UnknownName<'_> {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{} must be one of ", self.option)?;
        (self.choices)(f)?;
        write!(f, ", got '{}'", self.name)
    }
}

/// Why a material given by its named parts (Python's keywords, a TOML
/// table: [`crate::io::desc::Keywords`]) is refused.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Refused<'a> {
    /// A number outside its domain.
    Invalid(Invalid),
    /// A name that is none of an option's values.
    UnknownName(UnknownName<'a>),
    /// `eta` holds another number of `(n, k)` pairs than there are channels.
    EtaCount {
        /// Pairs given.
        found: usize,
        /// Channels.
        expected: usize,
    },
    /// An albedo given with `base = "conductor"`, which has no base layer.
    AlbedoOnConductor,
    /// A plastic or subsurface base without its albedo.
    MissingAlbedo(BaseKind),
    /// `eta = (lambda, n, k)` whose three arrays differ in length.
    SpectrumLengths([usize; 3]),
    /// `rgb_mode = "integrated"` for a material without an index over the
    /// spectrum (different (n, k) per channel).
    IntegratedNeedsSpectrum,
}

impl From<Invalid> for Refused<'_> {
    fn from(invalid: Invalid) -> Self {
        Refused::Invalid(invalid)
    }
}

impl<'a> From<UnknownName<'a>> for Refused<'a> {
    fn from(unknown: UnknownName<'a>) -> Self {
        Refused::UnknownName(unknown)
    }
}

impl fmt::Display for Refused<'_> {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Refused::Invalid(e) => write!(f, "{e}"),
            Refused::UnknownName(e) => write!(f, "{e}"),
            Refused::EtaCount { found, expected: 3 } => write!(
                f,
                "eta must be three (n, k) pairs (red, green, blue), got {found}"
            ),
            Refused::EtaCount { found, expected } => write!(
                f,
                "eta must be {expected} (n, k) pairs, one per wavelength, got {found}"
            ),
            Refused::AlbedoOnConductor => write!(
                f,
                "albedo is for the base layers with a diffuse albedo, not '{}'",
                BaseKind::Conductor.name()
            ),
            Refused::MissingAlbedo(kind) => write!(f, "base '{}' needs an albedo", kind.name()),
            Refused::SpectrumLengths([l, n, k]) => write!(
                f,
                "eta = (lambda, n, k) needs three arrays of one length, got {l}, {n} and {k}"
            ),
            Refused::IntegratedNeedsSpectrum => write!(
                f,
                "rgb_mode '{}' needs an index over the spectrum: eta = (lambda, n, k), \
                 or one (n, k) for every channel",
                RgbMode::Integrated.name()
            ),
        }
    }
}

#[cfg(feature = "std")]
impl std::error::Error for Refused<'_> {}

/// The base layer of `kind` with `albedo`: a plastic or subsurface base needs
/// one, a conductor takes none. (Its range is [`Layer::validate`]'s.)
pub fn base_layer(kind: BaseKind, albedo: Option<f32>) -> Result<BaseLayer, Refused<'static>> {
    match (kind, albedo) {
        (BaseKind::Conductor, None) => Ok(BaseLayer::Conductor),
        (BaseKind::Conductor, Some(_)) => Err(Refused::AlbedoOnConductor),
        (kind, Some(albedo)) => Ok(kind.with_albedo(albedo)),
        (kind, None) => Err(Refused::MissingAlbedo(kind)),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::material::{BaseLayer, Layer, Material, Surface};

    fn gold() -> Material {
        Material {
            layer: Layer {
                surface: Surface {
                    beta: 0.1,
                    p: 1.0,
                    sigma_s: 0.02,
                    b: 3.0,
                    c: 1.6,
                },
                base: BaseLayer::Conductor,
                lambertian: 0.0,
            },
            eta_rgb: [Complex::new(0.2, 3.5); 3],
        }
    }

    #[test]
    fn a_valid_material_passes() {
        assert_eq!(gold().validate(), Ok(()));
    }

    /// Each bad input the C API used to accept (issue 23) is refused, naming
    /// the parameter.
    #[test]
    fn each_bad_parameter_is_named() {
        type Spoil = fn(&mut Material);
        let cases: [(&str, Spoil); 12] = [
            ("beta", |m| m.layer.surface.beta = -0.1),
            ("p", |m| m.layer.surface.p = 100.0),
            ("p", |m| m.layer.surface.p = f32::NAN),
            ("c", |m| m.layer.surface.c = 0.5),
            ("c", |m| m.layer.surface.c = 1.0),
            ("sigma_s", |m| m.layer.surface.sigma_s = -1.0),
            ("b", |m| m.layer.surface.b = -5.0),
            ("b", |m| m.layer.surface.b = 0.0),
            ("albedo", |m| {
                m.layer.base = BaseLayer::Plastic { albedo: 1.5 }
            }),
            ("lambertian", |m| m.layer.lambertian = -0.1),
            ("eta[1].n", |m| m.eta_rgb[1] = Complex::new(-1.0, 0.0)),
            ("eta[2].k", |m| {
                m.eta_rgb[2] = Complex::new(1.5, f32::INFINITY)
            }),
        ];
        for (name, spoil) in cases {
            let mut m = gold();
            spoil(&mut m);
            let err = m.validate().expect_err(name);
            assert_eq!(err.name, name, "{err}");
        }
    }

    #[test]
    fn b_zero_is_fine_without_diffraction() {
        let mut m = gold();
        m.layer.surface.sigma_s = 0.0;
        m.layer.surface.b = 0.0;
        assert_eq!(m.validate(), Ok(()));
    }

    #[test]
    fn messages_name_value_and_domain() {
        let err = check("p", 0.15, Domain::Closed(0.2, 5.0), "T1's domain").unwrap_err();
        assert_eq!(
            err.to_string(),
            "p = 0.15: must be in [0.2, 5] (T1's domain)"
        );
        let err = wavelength(-0.25).unwrap_err();
        assert_eq!(
            err.to_string(),
            "lambda = -0.25: must be in [0.01, 100] (µm)"
        );
        let err = check("a", f64::NAN, Domain::Closed(0.0, f64::INFINITY), "").unwrap_err();
        assert_eq!(err.to_string(), "a = NaN: must be in [0, inf]");
        assert!(Domain::Closed(0.0, f64::INFINITY).contains(f64::INFINITY));
        assert!(!Domain::AtLeast(0.0).contains(f64::INFINITY));
        assert!(!Domain::LeftOpen(1.0, 2.0).contains(1.0));
    }

    #[test]
    fn names_round_trip() {
        fn all<T: Named + core::fmt::Debug>() {
            for &(name, value) in T::NAMES {
                assert_eq!(value.name(), name);
                assert_eq!(T::from_name(name), Some(value));
            }
            assert_eq!(T::from_name("no such value"), None);
        }
        all::<Masking>();
        all::<SigmaRelMode>();
        all::<ColourTerms>();
        all::<HaloWeight>();
        all::<MultipleScattering>();
        all::<BaseKind>();
        assert_eq!(Masking::NAMES[0].1, Masking::default());
        assert_eq!(
            BaseKind::choices().to_string(),
            "'conductor', 'plastic' or 'subsurface'"
        );
    }

    /// Each table's `check` reads its domain from the file and names the
    /// parameter (the silent clamps of issue 23: p = 0.15 and NaN in T1).
    #[cfg(feature = "embedded")]
    #[test]
    fn table_checks_name_the_parameter() {
        let set = crate::TableSet::embedded();
        let t1 = set.smith;
        assert_eq!(t1.check(1.0, 0.5), Ok(()));
        assert_eq!(t1.check(0.2, f32::INFINITY), Ok(()));
        let err = t1.check(0.15, 0.5).unwrap_err();
        assert_eq!(
            err.to_string(),
            "p = 0.15: must be in [0.2, 5] (T1's domain)"
        );
        assert_eq!(t1.check(f32::NAN, 0.5).unwrap_err().name, "p");
        assert_eq!(t1.check(1.0, -0.1).unwrap_err().name, "a");
        let t2 = set.sigma_ratio;
        assert_eq!(t2.check(0.5, 1e4, 2.0), Ok(()));
        assert_eq!(t2.check(1.5, 1.0, 2.0).unwrap_err().name, "cos_theta_i");
        assert_eq!(t2.check(0.5, -4.0, 2.0).unwrap_err().name, "B");
        assert_eq!(t2.check(0.5, 1.0, 1.0).unwrap_err().name, "c");
        let t3 = set.convolution;
        assert_eq!(t3.check(1e5, 2.0, 0.1, 1.0), Ok(()));
        assert_eq!(t3.check(1.0, 2.0, 5.0, 1.0).unwrap_err().name, "beta");
        assert_eq!(t3.check(1.0, 2.0, 0.1, 0.05).unwrap_err().name, "p");
        assert_eq!(t3.fit().check(1.0, 20.0, 0.1, 1.0).unwrap_err().name, "c");
        let t5 = set.diffuse_fresnel;
        assert_eq!(t5.check(1.5), Ok(()));
        assert_eq!(t5.check(0.5).unwrap_err().name, "eta");
    }
}
