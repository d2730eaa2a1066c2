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
//! [`crate::brdf::RGB_WAVELENGTHS`] for a material; one per wavelength of
//! the file for `materials.toml`. Numbers are read as `f64` and rounded to
//! the runtime's `f32`, as Python's keywords are.
//!
//! With the feature `toml`, [`MaterialDesc::from_toml_str`] and
//! [`MaterialDesc::from_toml_file`] read a material file; unknown keys,
//! missing or mistyped ones and values outside their domain are refused
//! with a [`DescError`] naming the key.

use crate::brdf::{Layer, Material, Options, Surface};
use crate::fresnel::Complex;
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

/// A material by its keywords as given (`None`: not given, the default).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Keywords<'a> {
    /// EPD width β.
    pub beta: f32,
    /// EPD shape p.
    pub p: f32,
    /// `(n, k)` per channel.
    pub eta: &'a [[f32; 2]],
    /// σs, µm ([`DEFAULT_SIGMA_S`]).
    pub sigma_s: Option<f32>,
    /// b, µm ([`DEFAULT_B`]).
    pub b: Option<f32>,
    /// c ([`DEFAULT_C`]).
    pub c: Option<f32>,
    /// The base's name ([`crate::brdf::BaseKind`]; default conductor).
    pub base: Option<&'a str>,
    /// The base's albedo (plastic and subsurface only).
    pub albedo: Option<f32>,
    /// k_d ([`DEFAULT_LAMBERTIAN`]).
    pub lambertian: Option<f32>,
    /// [`crate::brdf::Masking`]'s name.
    pub masking: Option<&'a str>,
    /// [`crate::brdf::SigmaRelMode`]'s name.
    pub sigma_rel: Option<&'a str>,
    /// [`crate::brdf::ColourTerms`]' name.
    pub colour: Option<&'a str>,
    /// [`crate::brdf::HaloWeight`]'s name.
    pub halo_weight: Option<&'a str>,
    /// [`crate::brdf::MultipleScattering`]'s name.
    pub multiple_scattering: Option<&'a str>,
}

impl<'a> Keywords<'a> {
    /// The layer and options, with `eta` checked for `channels` pairs, each
    /// a valid index ([`validate::eta`], named `eta[j].n`, `eta[j].k`).
    /// Checked in this order: the number of pairs, the base's name, its
    /// albedo, the layer ([`Layer::validate`]), each index, the options'
    /// names. `channels` is 1 to 3.
    pub fn layer(&self, channels: usize) -> Result<(Layer, Options), Refused<'a>> {
        if self.eta.len() != channels || channels > ETA_NAMES.len() {
            return Err(Refused::EtaCount {
                found: self.eta.len(),
                expected: channels,
            });
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
        for (&names, &[n, k]) in ETA_NAMES.iter().zip(self.eta) {
            validate::eta(names, Complex::new(n, k))?;
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

    /// The RGB material: [`Self::layer`] with three pairs (red, green,
    /// blue), then [`Material::validate`].
    pub fn material(&self) -> Result<MaterialDesc, Refused<'a>> {
        let (layer, options) = self.layer(3)?;
        let mut eta_rgb = [Complex::new(0.0, 0.0); 3];
        for (eta, &[n, k]) in eta_rgb.iter_mut().zip(self.eta) {
            *eta = Complex::new(n, k);
        }
        let material = Material { layer, eta_rgb };
        material.validate()?;
        Ok(MaterialDesc { material, options })
    }
}

/// A validated RGB material and its options: what a material file
/// describes (and the C API's `ts_material_desc`).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct MaterialDesc {
    /// The material.
    pub material: Material,
    /// The model's options.
    pub options: Options,
}

#[cfg(feature = "toml")]
pub use self::file::{DescError, DescErrorKind, KeywordTable};

#[cfg(feature = "toml")]
mod file {
    use super::{Keywords, MaterialDesc};
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
        pub eta: Vec<[f32; 2]>,
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
    }

    impl KeywordTable {
        /// The table as [`Keywords`].
        pub fn keywords(&self) -> Keywords<'_> {
            Keywords {
                beta: self.beta,
                p: self.p,
                eta: &self.eta,
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

    impl MaterialDesc {
        /// The material of a material file's text (module documentation).
        /// A refused value is reported as `[material] beta = 20: must be in
        /// [0.0001, 10]`; a syntax or schema fault with toml's message
        /// (line, column and the key).
        pub fn from_toml_str(text: &str) -> Result<MaterialDesc, DescError> {
            let file: MaterialFile = toml::from_str(text).map_err(|e| DescError {
                kind: DescErrorKind::Syntax,
                message: e.to_string().trim_end().to_string(),
            })?;
            file.material.keywords().material().map_err(|e| DescError {
                kind: DescErrorKind::Refused,
                message: format!("[material] {e}"),
            })
        }

        /// [`Self::from_toml_str`] of the file at `path` (UTF-8); every
        /// message starts with the path.
        pub fn from_toml_file(path: impl AsRef<Path>) -> Result<MaterialDesc, DescError> {
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
mod tests {
    use super::*;
    use crate::brdf::{
        BaseKind, BaseLayer, ColourTerms, HaloWeight, Masking, MultipleScattering, SigmaRelMode,
    };

    const GOLD: [[f32; 2]; 3] = [[0.163, 3.56], [0.584, 2.15], [1.403, 1.925]];

    fn gold<'a>() -> Keywords<'a> {
        Keywords {
            beta: 0.1,
            p: 1.0,
            eta: &GOLD,
            ..Keywords::default()
        }
    }

    #[test]
    fn defaults_fill_what_is_not_given() {
        let d = gold().material().unwrap();
        let s = d.material.layer.surface;
        assert_eq!((s.sigma_s, s.b, s.c), (0.0, 1.0, 2.0));
        assert_eq!(d.material.layer.base, BaseLayer::Conductor);
        assert_eq!(d.material.layer.lambertian, 0.0);
        assert_eq!(d.options, Options::default());
        assert_eq!(d.material.eta_rgb[2], Complex::new(1.403, 1.925));
    }

    #[test]
    fn names_and_albedo_are_read() {
        let k = Keywords {
            base: Some("plastic"),
            albedo: Some(0.8),
            eta: &[[1.5, 0.0]; 3],
            masking: Some("height-correlated"),
            sigma_rel: Some("symmetrised"),
            colour: Some("white"),
            halo_weight: Some("incident"),
            multiple_scattering: Some("kulla-conty"),
            ..gold()
        };
        let d = k.material().unwrap();
        assert_eq!(d.material.layer.base, BaseLayer::Plastic { albedo: 0.8 });
        assert_eq!(
            d.options,
            Options {
                masking: Masking::HeightCorrelated,
                sigma_rel: SigmaRelMode::Symmetrised,
                colour: ColourTerms::White,
                halo_weight: HaloWeight::Incident,
                multiple_scattering: MultipleScattering::KullaConty,
            }
        );
    }

    #[test]
    fn each_refusal_has_its_message() {
        let cases: [(Keywords<'_>, &str); 7] = [
            (
                Keywords {
                    eta: &GOLD[..2],
                    ..gold()
                },
                "eta must be three (n, k) pairs (red, green, blue), got 2",
            ),
            (
                Keywords {
                    base: Some("glass"),
                    ..gold()
                },
                "base must be one of 'conductor', 'plastic' or 'subsurface', got 'glass'",
            ),
            (
                Keywords {
                    albedo: Some(0.5),
                    ..gold()
                },
                "albedo is for the base layers with a diffuse albedo, not 'conductor'",
            ),
            (
                Keywords {
                    base: Some("subsurface"),
                    ..gold()
                },
                "base 'subsurface' needs an albedo",
            ),
            (
                Keywords {
                    beta: 20.0,
                    ..gold()
                },
                "beta = 20: must be in [0.0001, 10]",
            ),
            (
                Keywords {
                    eta: &[[0.2, 3.0], [0.2, -1.0], [0.2, 3.0]],
                    ..gold()
                },
                "eta[1].k = -1: must be finite and ≥ 0",
            ),
            (
                Keywords {
                    colour: Some("grey"),
                    ..gold()
                },
                "colour must be one of 'physical' or 'white', got 'grey'",
            ),
        ];
        for (k, message) in cases {
            assert_eq!(k.material().unwrap_err().to_string(), message);
        }
        let e = Keywords {
            eta: &GOLD,
            ..gold()
        }
        .layer(2)
        .unwrap_err();
        assert_eq!(
            e.to_string(),
            "eta must be 2 (n, k) pairs, one per wavelength, got 3"
        );
        assert_eq!(
            validate::named::<BaseKind>(Some("metal")).unwrap_err().name,
            "metal"
        );
    }

    #[cfg(feature = "toml")]
    mod toml_files {
        use super::super::*;
        use crate::brdf::BaseLayer;

        const FIT: &str = r#"
[material]
beta = 0.0598
p = 1
eta = [[0.163, 3.56], [0.584, 2.15], [1.403, 1.925]]
sigma_s = 0.0273
b = 4.8418
c = 2.0
base = "conductor"
lambertian = 0.01

[metrics]
rmse = [0.1, 0.2, 0.3]
smape = 0.05
"#;

        #[test]
        fn a_fit_file_reads() {
            let d = MaterialDesc::from_toml_str(FIT).unwrap();
            let m = d.material;
            assert_eq!(m.layer.surface.beta, 0.0598f64 as f32);
            assert_eq!(m.layer.surface.p, 1.0);
            assert_eq!(m.layer.lambertian, 0.01f64 as f32);
            assert_eq!(m.layer.base, BaseLayer::Conductor);
            assert_eq!(m.eta_rgb[0], Complex::new(0.163, 3.56));
        }

        #[test]
        fn faults_are_named() {
            let bad = |from: &str, to: &str| {
                let text = FIT.replacen(from, to, 1);
                MaterialDesc::from_toml_str(&text).unwrap_err()
            };
            let e = bad("beta = 0.0598", "beta = 20.0");
            assert_eq!(e.kind, DescErrorKind::Refused);
            assert_eq!(e.message, "[material] beta = 20: must be in [0.0001, 10]");
            let e = bad("c = 2.0", "c = 2.0\ncolor = \"white\"");
            assert_eq!(e.kind, DescErrorKind::Syntax);
            assert!(e.message.contains("unknown field `color`"), "{e}");
            assert!(e.message.contains("line 9"), "{e}");
            let e = bad("beta = 0.0598", "");
            assert!(e.message.contains("missing field `beta`"), "{e}");
            let e = bad("p = 1", "p = \"one\"");
            assert_eq!(e.kind, DescErrorKind::Syntax);
            let e = bad("[metrics]", "[metric]");
            assert!(e.message.contains("unknown field `metric`"), "{e}");
            let e = bad("lambertian = 0.01", "albedo = 0.5");
            assert_eq!(
                e.message,
                "[material] albedo is for the base layers with a diffuse albedo, not 'conductor'"
            );
            let e = MaterialDesc::from_toml_str("beta = 1").unwrap_err();
            assert!(
                e.message
                    .contains("unknown field `beta`, expected `material` or `metrics`"),
                "{e}"
            );
            let e = MaterialDesc::from_toml_str("[metrics]\nx = 1").unwrap_err();
            assert!(e.message.contains("missing field `material`"), "{e}");
        }

        #[test]
        fn files_name_their_path() {
            let dir = std::env::temp_dir().join(format!("twoscale-desc-{}", std::process::id()));
            std::fs::create_dir_all(&dir).unwrap();
            let path = dir.join("bad.toml");
            std::fs::write(&path, FIT.replacen("p = 1", "p = 9", 1)).unwrap();
            let e = MaterialDesc::from_toml_file(&path).unwrap_err();
            assert_eq!(
                e.message,
                format!("{}: [material] p = 9: must be in [0.2, 5]", path.display())
            );
            let missing = dir.join("missing.toml");
            let e = MaterialDesc::from_toml_file(&missing).unwrap_err();
            assert_eq!(e.kind, DescErrorKind::Io);
            assert!(e.message.starts_with("cannot read "), "{e}");
            std::fs::remove_dir_all(&dir).unwrap();
        }
    }
}
