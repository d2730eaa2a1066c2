//! A material by its named parameters: the keywords of Python's
//! `twoscale.Material`, the keys of a material file's `[material]` table
//! (the fit's output, `python -m twoscale.fit`) and of each `[[material]]`
//! of the generator's `materials.toml`. One schema, read and checked here;
//! every number is then checked by [`Material::validate`] ([`crate::validate`]).
//!
//! ```toml
//! [material]
//! beta = 0.0598        # EPD width β (HP17 35); required
//! p = 1.0              # EPD shape p (HP17 35); required
//! eta = [[0.163, 3.56], [0.584, 2.15], [1.403, 1.925]]   # n + ik per channel; required
//! sigma_s = 0.0273     # σs, µm (HP17 16); default 0: no diffraction
//! b = 4.8418           # b, µm (HP17 16); default 1
//! c = 2.0              # c > 1 (HP17 16); default 2
//! base = "conductor"   # or "plastic", "subsurface"; default "conductor"
//! albedo = 0.8         # the base's ρd or α: required by, and only for, plastic and subsurface
//! lambertian = 0.0     # k_d ∈ [0, 1] (adds k_d/π); default 0
//! masking = "separable"   # the options (crate::validate::Named); default: the paper's model
//! sigma_rel = "incident"
//! colour = "physical"
//! halo_weight = "printed"
//! multiple_scattering = "none"   # or "kulla-conty" (docs/model.md §2.11)
//!
//! [metrics]            # optional and not read: what the fit measured
//! rmse = [0.01, 0.01, 0.01]
//! ```
//!
//! `eta` holds one `(n, k)` pair per channel: red, green, blue at
//! [`crate::material::RGB_WAVELENGTHS`] for a material; one per wavelength of
//! the file for `materials.toml`. A material may instead give its index
//! over the spectrum, `eta = { lambda = [0.4, 0.5, 0.6], n = […], k = […] }`
//! (λ in µm, increasing; [`crate::spectrum::optical::Tabulated`]): its model's RGB is
//! then the integral over the spectrum (`rgb_mode = "integrated"`, the
//! default of a material over the spectrum, [`RgbMode::default_for`]), or
//! with `rgb_mode = "paper-wavelengths"` the spectrum at the paper's
//! wavelengths (the default of three `(n, k)` pairs). Python's `Material(eta=(lam, n, k))` and
//! the C API's `ts_material_desc.eta_rows` are the same form. Numbers are read as `f64` and rounded to
//! the runtime's `f32`, as Python's keywords are.
//!
//! With the feature `toml`, [`MaterialDesc::from_toml_str`] and
//! [`MaterialDesc::from_toml_file`] read a material file; unknown keys,
//! missing or mistyped ones and values outside their domain are refused
//! with a [`DescError`] naming the key.

#[cfg(feature = "std")]
use crate::brdf::{ChannelBake, IntegratedRgb, Rgb, RgbModel, Tables};
use crate::material::{Layer, Material, Options, RgbMode, Surface};
use crate::math::Complex;
#[cfg(feature = "std")]
use crate::spectrum::optical::OwnedSpectralMaterial;
use crate::spectrum::optical::{Ior, SpectralMaterial, Tabulated};
use crate::validate::{self, Refused};

/// The default of `sigma_s` (no diffraction).
pub const DEFAULT_SIGMA_S: f32 = 0.0;
/// The default of `b`, µm.
pub const DEFAULT_B: f32 = 1.0;
/// The default of `c`.
pub const DEFAULT_C: f32 = 2.0;
/// The default of `lambertian`.
pub const DEFAULT_LAMBERTIAN: f32 = 0.0;

/// The names of each channel's index in messages, red, green, blue
/// ([`Material::validate`]'s).
const ETA_NAMES: [(&str, &str); 3] = [
    ("eta[0].n", "eta[0].k"),
    ("eta[1].n", "eta[1].k"),
    ("eta[2].n", "eta[2].k"),
];

/// The index of a material as given: `(n, k)` per channel, or rows
/// `(λ µm, n, k)` of a spectrum ([`crate::spectrum::optical::Tabulated`]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Eta<'a> {
    /// `(n, k)` per channel.
    Channels(&'a [[f32; 2]]),
    /// `(λ, n, k)` rows, λ increasing.
    Spectrum(&'a [[f32; 3]]),
}

impl Default for Eta<'_> {
    fn default() -> Self {
        Eta::Channels(&[])
    }
}

/// A material by its keywords as given (`None`: not given, the default).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Keywords<'a> {
    /// EPD width β.
    pub beta: f32,
    /// EPD shape p.
    pub p: f32,
    /// The index: `(n, k)` per channel, or a spectrum.
    pub eta: Eta<'a>,
    /// σs, µm ([`DEFAULT_SIGMA_S`]).
    pub sigma_s: Option<f32>,
    /// b, µm ([`DEFAULT_B`]).
    pub b: Option<f32>,
    /// c ([`DEFAULT_C`]).
    pub c: Option<f32>,
    /// The base's name ([`crate::material::BaseKind`]; default conductor).
    pub base: Option<&'a str>,
    /// The base's albedo (plastic and subsurface only).
    pub albedo: Option<f32>,
    /// k_d ([`DEFAULT_LAMBERTIAN`]).
    pub lambertian: Option<f32>,
    /// [`crate::material::Masking`]'s name.
    pub masking: Option<&'a str>,
    /// [`crate::material::SigmaRelMode`]'s name.
    pub sigma_rel: Option<&'a str>,
    /// [`crate::material::ColourTerms`]' name.
    pub colour: Option<&'a str>,
    /// [`crate::material::HaloWeight`]'s name.
    pub halo_weight: Option<&'a str>,
    /// [`crate::material::MultipleScattering`]'s name.
    pub multiple_scattering: Option<&'a str>,
    /// [`RgbMode`]'s name (default: [`RgbMode::default_for`]).
    pub rgb_mode: Option<&'a str>,
}

impl<'a> Keywords<'a> {
    /// The layer and options, with `eta` checked for `channels` pairs, each
    /// a valid index ([`validate::eta`], named `eta[j].n`, `eta[j].k`), or
    /// valid spectrum rows when `channels` is `None`
    /// ([`validate::optical_constants`]). Checked in this order: the number
    /// of pairs, the base's name, its albedo, the layer
    /// ([`Layer::validate`]), each index, the options' names. `channels` is
    /// 1 to 3.
    fn checked(&self, channels: Option<usize>) -> Result<(Layer, Options), Refused<'a>> {
        let found = match self.eta {
            Eta::Channels(pairs) => pairs.len(),
            Eta::Spectrum(rows) => rows.len(),
        };
        let pairs = matches!(self.eta, Eta::Channels(_));
        if let Some(expected) = channels
            && (!pairs || found != expected || expected > ETA_NAMES.len())
        {
            return Err(Refused::EtaCount { found, expected });
        }
        let base = validate::base_layer(validate::named(self.base)?, self.albedo)?;
        let layer = Layer {
            surface: Surface {
                beta: self.beta,
                p: self.p,
                sigma_s: self.sigma_s.unwrap_or(DEFAULT_SIGMA_S),
                b: self.b.unwrap_or(DEFAULT_B),
                c: self.c.unwrap_or(DEFAULT_C),
            },
            base,
            lambertian: self.lambertian.unwrap_or(DEFAULT_LAMBERTIAN),
        };
        layer.validate()?;
        match self.eta {
            Eta::Channels(pairs) => {
                for (&names, &[n, k]) in ETA_NAMES.iter().zip(pairs) {
                    validate::eta(names, Complex::new(n, k))?;
                }
            }
            Eta::Spectrum(rows) => validate::optical_constants(rows)?,
        }
        let options = Options {
            masking: validate::named(self.masking)?,
            sigma_rel: validate::named(self.sigma_rel)?,
            colour: validate::named(self.colour)?,
            halo_weight: validate::named(self.halo_weight)?,
            multiple_scattering: validate::named(self.multiple_scattering)?,
        };
        Ok((layer, options))
    }

    /// The layer and options with `eta` one `(n, k)` pair per channel
    /// (`channels`, 1 to 3; the order of checks is [`Self::material`]'s).
    pub fn layer(&self, channels: usize) -> Result<(Layer, Options), Refused<'a>> {
        self.checked(Some(channels))
    }

    /// The material: three `(n, k)` pairs (red, green, blue) or a spectrum,
    /// then [`MaterialDesc::rgb`] or [`MaterialDesc::spectral`]. Checked in this order: the number of
    /// pairs, the base's name, its albedo, the layer ([`Layer::validate`]),
    /// each index (or the rows), the options' names, `rgb_mode`.
    pub fn material(&self) -> Result<MaterialDesc<'a>, Refused<'a>> {
        let channels = match self.eta {
            Eta::Channels(_) => Some(3),
            Eta::Spectrum(_) => None,
        };
        let (layer, options) = self.checked(channels)?;
        let rgb_mode = validate::named_or_none(self.rgb_mode)?;
        match self.eta {
            Eta::Channels(pairs) => {
                let mut eta_rgb = [Complex::new(0.0, 0.0); 3];
                for (eta, &[n, k]) in eta_rgb.iter_mut().zip(pairs) {
                    *eta = Complex::new(n, k);
                }
                MaterialDesc::rgb(Material { layer, eta_rgb }, options, rgb_mode)
            }
            Eta::Spectrum(rows) => {
                let eta = Ior::Tabulated(Tabulated::new(rows)?);
                MaterialDesc::spectral(SpectralMaterial { layer, eta }, options, rgb_mode)
            }
        }
    }
}

/// The rows `(λ, n, k)` of three arrays of one length (Python's
/// `eta=(lam, n, k)`, a material file's `eta = { lambda = […], n = […],
/// k = […] }`); the rows are checked later ([`Keywords::material`]).
#[cfg(feature = "std")]
pub fn spectrum_rows(
    lambda: &[f32],
    n: &[f32],
    k: &[f32],
) -> Result<std::vec::Vec<[f32; 3]>, Refused<'static>> {
    if lambda.len() != n.len() || lambda.len() != k.len() {
        return Err(Refused::SpectrumLengths([lambda.len(), n.len(), k.len()]));
    }
    Ok((0..lambda.len()).map(|j| [lambda[j], n[j], k[j]]).collect())
}

/// A validated material and its options: the RGB material at the paper's
/// wavelengths, its index over the spectrum when it has one, and which RGB
/// the model gives. What a material file describes (and the C API's
/// `ts_material_desc`).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct MaterialDesc<'a> {
    /// The material at [`crate::material::RGB_WAVELENGTHS`].
    pub material: Material,
    /// The material over the spectrum: given as one, or the one index of a
    /// material with the same `(n, k)` in every channel
    /// ([`SpectralMaterial::with_one_index`]); else `None`.
    pub spectral: Option<SpectralMaterial<'a>>,
    /// The model's options.
    pub options: Options,
    /// Which RGB the model gives ([`crate::brdf::RgbModel`]).
    pub rgb_mode: RgbMode,
}

impl<'a> MaterialDesc<'a> {
    /// An RGB material (validated, [`Material::validate`]); its spectrum if
    /// every channel has the same index. [`RgbMode::Integrated`] needs one
    /// ([`Refused::IntegratedNeedsSpectrum`]); `None`: the paper's
    /// wavelengths ([`RgbMode::default_for`]).
    pub fn rgb(
        material: Material,
        options: Options,
        rgb_mode: Option<RgbMode>,
    ) -> Result<MaterialDesc<'static>, Refused<'static>> {
        material.validate()?;
        let rgb_mode = rgb_mode.unwrap_or(RgbMode::default_for(false));
        let spectral = SpectralMaterial::with_one_index(&material);
        if rgb_mode == RgbMode::Integrated && spectral.is_none() {
            return Err(Refused::IntegratedNeedsSpectrum);
        }
        Ok(MaterialDesc {
            material,
            spectral,
            options,
            rgb_mode,
        })
    }

    /// A material over the spectrum (validated,
    /// [`SpectralMaterial::validate`]); its RGB material is the spectrum at
    /// the paper's wavelengths. `None`: the integrated RGB
    /// ([`RgbMode::default_for`]).
    pub fn spectral(
        spectral: SpectralMaterial<'a>,
        options: Options,
        rgb_mode: Option<RgbMode>,
    ) -> Result<MaterialDesc<'a>, Refused<'a>> {
        spectral.validate()?;
        Ok(MaterialDesc {
            material: spectral.paper_rgb(),
            spectral: Some(spectral),
            options,
            rgb_mode: rgb_mode.unwrap_or(RgbMode::default_for(true)),
        })
    }

    /// A copy that owns its rows (feature `std`).
    #[cfg(feature = "std")]
    pub fn to_owned_desc(&self) -> OwnedMaterialDesc {
        OwnedMaterialDesc {
            material: self.material,
            spectral: self.spectral.as_ref().map(OwnedSpectralMaterial::new),
            options: self.options,
            rgb_mode: self.rgb_mode,
        }
    }
}

/// The model a material description names (here rather than in
/// [`crate::brdf`], which knows nothing of descriptions).
#[cfg(feature = "std")]
impl<'a> RgbModel<'a, std::boxed::Box<ChannelBake>> {
    /// The model `desc.rgb_mode` names, its bakes on the heap
    /// ([`MaterialDesc`] holds the spectrum that [`RgbMode::Integrated`]
    /// needs).
    pub fn boxed(tables: &Tables<'a>, desc: &MaterialDesc<'_>) -> Self {
        match (desc.rgb_mode, &desc.spectral) {
            (RgbMode::Integrated, Some(spectral)) => {
                RgbModel::Integrated(IntegratedRgb::boxed(tables, spectral, desc.options))
            }
            _ => RgbModel::PaperWavelengths(Rgb::boxed(tables, &desc.material, desc.options)),
        }
    }
}

/// A [`MaterialDesc`] that owns its spectrum's rows (feature `std`): what a
/// material file or a front end's material keeps.
#[cfg(feature = "std")]
#[derive(Clone, Debug, PartialEq)]
pub struct OwnedMaterialDesc {
    material: Material,
    spectral: Option<OwnedSpectralMaterial>,
    options: Options,
    rgb_mode: RgbMode,
}

#[cfg(feature = "std")]
impl OwnedMaterialDesc {
    /// The description, borrowing the rows.
    pub fn get(&self) -> MaterialDesc<'_> {
        MaterialDesc {
            material: self.material,
            spectral: self.spectral.as_ref().map(OwnedSpectralMaterial::get),
            options: self.options,
            rgb_mode: self.rgb_mode,
        }
    }
}

#[cfg(feature = "toml")]
pub use self::file::{DescError, DescErrorKind, EtaTable, KeywordTable};

#[cfg(feature = "toml")]
mod file {
    use super::{Eta, Keywords, MaterialDesc, OwnedMaterialDesc, spectrum_rows};
    use serde::Deserialize;
    use std::fmt;
    use std::path::Path;
    use std::string::{String, ToString};
    use std::vec::Vec;

    /// The keys of a material table, owned ([`Keywords`] borrows them):
    /// deserialised by serde with unknown keys refused. Numbers are read as
    /// `f64` and rounded to `f32`.
    #[derive(Clone, Debug, Default, PartialEq, Deserialize)]
    #[serde(deny_unknown_fields)]
    pub struct KeywordTable {
        /// [`Keywords::beta`].
        pub beta: f32,
        /// [`Keywords::p`].
        pub p: f32,
        /// [`Keywords::eta`].
        pub eta: EtaTable,
        /// [`Keywords::sigma_s`].
        pub sigma_s: Option<f32>,
        /// [`Keywords::b`].
        pub b: Option<f32>,
        /// [`Keywords::c`].
        pub c: Option<f32>,
        /// [`Keywords::base`].
        pub base: Option<String>,
        /// [`Keywords::albedo`].
        pub albedo: Option<f32>,
        /// [`Keywords::lambertian`].
        pub lambertian: Option<f32>,
        /// [`Keywords::masking`].
        pub masking: Option<String>,
        /// [`Keywords::sigma_rel`].
        pub sigma_rel: Option<String>,
        /// [`Keywords::colour`].
        pub colour: Option<String>,
        /// [`Keywords::halo_weight`].
        pub halo_weight: Option<String>,
        /// [`Keywords::multiple_scattering`].
        pub multiple_scattering: Option<String>,
        /// [`Keywords::rgb_mode`].
        pub rgb_mode: Option<String>,
    }

    /// `eta` of a material table: `[[n, k], …]` per channel, or
    /// `{ lambda = […], n = […], k = […] }` (µm), read into rows.
    #[derive(Clone, Debug, PartialEq, Deserialize)]
    #[serde(try_from = "RawEta")]
    pub enum EtaTable {
        /// `(n, k)` per channel.
        Channels(Vec<[f32; 2]>),
        /// `(λ, n, k)` rows ([`spectrum_rows`]).
        Spectrum(Vec<[f32; 3]>),
    }

    impl Default for EtaTable {
        fn default() -> Self {
            EtaTable::Channels(Vec::new())
        }
    }

    #[derive(Deserialize)]
    #[serde(untagged)]
    enum RawEta {
        Channels(Vec<[f32; 2]>),
        Spectrum(SpectrumArrays),
    }

    #[derive(Deserialize)]
    #[serde(deny_unknown_fields)]
    struct SpectrumArrays {
        lambda: Vec<f32>,
        n: Vec<f32>,
        k: Vec<f32>,
    }

    impl TryFrom<RawEta> for EtaTable {
        type Error = String;
        fn try_from(raw: RawEta) -> Result<Self, String> {
            match raw {
                RawEta::Channels(pairs) => Ok(EtaTable::Channels(pairs)),
                RawEta::Spectrum(a) => spectrum_rows(&a.lambda, &a.n, &a.k)
                    .map(EtaTable::Spectrum)
                    .map_err(|e| e.to_string()),
            }
        }
    }

    impl KeywordTable {
        /// The table as [`Keywords`].
        pub fn keywords(&self) -> Keywords<'_> {
            Keywords {
                beta: self.beta,
                p: self.p,
                eta: match &self.eta {
                    EtaTable::Channels(pairs) => Eta::Channels(pairs),
                    EtaTable::Spectrum(rows) => Eta::Spectrum(rows),
                },
                sigma_s: self.sigma_s,
                b: self.b,
                c: self.c,
                base: self.base.as_deref(),
                albedo: self.albedo,
                lambertian: self.lambertian,
                masking: self.masking.as_deref(),
                sigma_rel: self.sigma_rel.as_deref(),
                colour: self.colour.as_deref(),
                halo_weight: self.halo_weight.as_deref(),
                multiple_scattering: self.multiple_scattering.as_deref(),
                rgb_mode: self.rgb_mode.as_deref(),
            }
        }
    }

    /// A material file: `[material]` and, not read, `[metrics]`.
    #[derive(Deserialize)]
    #[serde(deny_unknown_fields)]
    struct MaterialFile {
        material: KeywordTable,
        #[allow(dead_code)] // accepted, not read
        metrics: Option<toml::Table>,
    }

    /// What kind of fault a [`DescError`] is.
    #[derive(Clone, Copy, Debug, PartialEq, Eq)]
    pub enum DescErrorKind {
        /// The file could not be read.
        Io,
        /// Not TOML, or not the schema: an unknown, missing or mistyped key.
        Syntax,
        /// A value the model refuses ([`crate::validate::Refused`]).
        Refused,
    }

    /// Why a material file was refused: its kind and the message every
    /// front end shows (Rust's `Display`, C's `ts_last_error`, Python's
    /// exception), which names the file when one was read, and the key.
    #[derive(Clone, Debug, PartialEq, Eq)]
    pub struct DescError {
        /// The kind of fault.
        pub kind: DescErrorKind,
        /// The message.
        pub message: String,
    }

    impl fmt::Display for DescError {
        fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
            f.write_str(&self.message)
        }
    }

    impl std::error::Error for DescError {}

    impl MaterialDesc<'_> {
        /// The material of a material file's text (module documentation).
        /// A refused value is reported as `[material] beta = 20: must be in
        /// [0.0001, 10]`; a syntax or schema fault with toml's message
        /// (line, column and the key).
        pub fn from_toml_str(text: &str) -> Result<OwnedMaterialDesc, DescError> {
            let file: MaterialFile = toml::from_str(text).map_err(|e| DescError {
                kind: DescErrorKind::Syntax,
                message: e.to_string().trim_end().to_string(),
            })?;
            file.material
                .keywords()
                .material()
                .map(|d| d.to_owned_desc())
                .map_err(|e| DescError {
                    kind: DescErrorKind::Refused,
                    message: format!("[material] {e}"),
                })
        }

        /// [`Self::from_toml_str`] of the file at `path` (UTF-8); every
        /// message starts with the path.
        pub fn from_toml_file(path: impl AsRef<Path>) -> Result<OwnedMaterialDesc, DescError> {
            let path = path.as_ref();
            let text = std::fs::read_to_string(path).map_err(|e| DescError {
                kind: DescErrorKind::Io,
                message: format!("cannot read {}: {e}", path.display()),
            })?;
            Self::from_toml_str(&text).map_err(|e| DescError {
                message: format!("{}: {}", path.display(), e.message),
                ..e
            })
        }
    }
}

#[cfg(test)]
mod tests;
