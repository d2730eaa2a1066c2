//! Batch queries (docs/model.md §6): CSV with a header line in, CSV out with the input
//! columns followed by `table` (the runtime's value from the table files) and
//! `reference` (the f64 reference).
//!
//! Input columns are found by name (any order; extra columns are passed
//! through). A bad row — wrong field count, a field that is not a number, or a
//! point where the reference fails — is reported on stderr with its line
//! number and left out of the output; the other rows are still answered.
//! Rows are evaluated in parallel and written in input order.

use rayon::prelude::*;
use std::fmt;
use std::io::{BufRead, Write};
use twoscale::brdf::{BoxedSpectral, ChannelBake, SPECTRAL_WAVELENGTHS, Spectral};
use twoscale::io::desc::OwnedMaterialDesc;
use twoscale::material::{MultipleScattering, RgbMode};
use twoscale::spectrum::optical::SpectralMaterial;
use twoscale::{
    AlbedoTable, ConvTable, Convolution, DiffuseFresnelTable, Rgb, SigmaRatioTable, SmithG1Table,
    TableId, TableSet,
};

use twoscale::domain::{self, Invalid, Shortest, Shortest32};

use twoscale::validate;

use crate::table_source::{TableFile, TableFileError, TableSource};

use crate::reference::{brdf, conv, epd, fresnel, kcorr};

/// A quantity `query` answers: each variant's name, input columns, output
/// columns and evaluation are defined by the methods below, one `match` arm
/// each.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Quantity {
    /// Smith G1 (T1).
    G1,
    /// σrel/σs (T2).
    SigmaRatio,
    /// Fresnel reflectance (no table: the runtime's f32 Fresnel).
    Fresnel,
    /// The convolution C (T3a and T3b).
    Conv,
    /// The conductor two-scale BRDF (docs/model.md §6).
    Brdf,
}

impl Quantity {
    /// Every quantity, in the order `--help` and errors list them.
    pub const ALL: [Quantity; 5] = [
        Quantity::G1,
        Quantity::SigmaRatio,
        Quantity::Fresnel,
        Quantity::Conv,
        Quantity::Brdf,
    ];

    /// The name on the command line.
    pub const fn name(self) -> &'static str {
        match self {
            Quantity::G1 => "g1",
            Quantity::SigmaRatio => "sigma-ratio",
            Quantity::Fresnel => "fresnel",
            Quantity::Conv => "conv",
            Quantity::Brdf => "brdf",
        }
    }

    /// The quantity called `name`.
    pub fn from_name(name: &str) -> Result<Quantity, QueryError> {
        Self::ALL
            .into_iter()
            .find(|q| q.name() == name)
            .ok_or_else(|| QueryError::UnknownQuantity(name.to_string()))
    }

    /// The input columns, in the order the evaluation reads them.
    pub const fn columns(self) -> &'static [&'static str] {
        match self {
            Quantity::G1 => &["p", "a"],
            Quantity::SigmaRatio => &["theta_i", "B", "c"],
            Quantity::Fresnel => &["n", "k", "cos_theta"],
            Quantity::Conv => &["u", "c", "beta", "p", "theta_h"],
            Quantity::Brdf => &[
                "beta", "p", "sigma_s", "b", "c", "n", "k", "lambda", "ix", "iy", "iz", "ox", "oy",
                "oz",
            ],
        }
    }

    /// The output columns, in the order the evaluation returns them.
    pub const fn outputs(self) -> &'static [&'static str] {
        match self {
            Quantity::Conv => &["fit", "table", "reference"],
            _ => &["table", "reference"],
        }
    }

    /// The tables the evaluation reads (only these are opened).
    pub const fn tables(self) -> &'static [TableId] {
        match self {
            Quantity::G1 => &[TableId::SmithG1],
            Quantity::SigmaRatio => &[TableId::SigmaRatio],
            Quantity::Fresnel => &[],
            Quantity::Conv => &[TableId::Convolution],
            Quantity::Brdf => &twoscale::table_set::TABLES,
        }
    }

    /// Whether the quantity is the lookup of one table, whose domain
    /// `--clamp` may clamp to (the others validate model parameters).
    pub const fn clamps(self) -> bool {
        matches!(self, Quantity::G1 | Quantity::SigmaRatio | Quantity::Conv)
    }

    /// The output values for inputs `x` (in the order of [`Self::columns`]),
    /// with the runtime reading `tables` (those of [`Self::tables`]), and
    /// whether the point is in the table's domain; or why there are none.
    /// A point outside the table's domain is an error unless `clamp`.
    fn evaluate(
        self,
        tables: &Tables<'_>,
        x: &[f64],
        clamp: bool,
    ) -> Result<(Vec<String>, bool), RowError> {
        let reference = |e: &dyn fmt::Display| RowError::Reference(e.to_string());
        let f = |v: f64| v as f32;
        // The table's domain, checked before the reference is computed.
        let domain = |check: Result<(), RowError>| match check {
            Ok(()) => Ok(true),
            Err(_) if clamp => Ok(false),
            Err(e) => Err(e),
        };
        Ok(match self {
            Quantity::G1 => {
                let (p, a) = (x[0], x[1]);
                let table = tables.smith()?;
                let in_domain = domain(table.check(f(p), f(a)).map_err(RowError::Invalid))?;
                let reference = epd::g1(p, a).map_err(|e| reference(&e))?;
                let value = table.g1(f(p), f(a));
                (vec![short32(value), short(reference)], in_domain)
            }
            Quantity::SigmaRatio => {
                let (theta_i, big_b, c) = (x[0], x[1], x[2]);
                let table = tables.sigma_ratio()?;
                // T2's axis is cos θi; a bad θi is reported as the θi given.
                let cos_theta_i = twoscale::math::cosf(f(theta_i));
                let in_domain = domain(table.check(cos_theta_i, f(big_b), f(c)).map_err(|e| {
                    if e.name == "cos_theta_i" {
                        RowError::InvalidAngle {
                            column: "theta_i",
                            value: theta_i,
                            invalid: e,
                        }
                    } else {
                        RowError::Invalid(e)
                    }
                }))?;
                let reference = kcorr::sigma_ratio(theta_i, big_b, c).map_err(|e| reference(&e))?;
                let value = table.sigma_ratio(f(theta_i), f(big_b), f(c));
                (vec![short32(value), short(reference)], in_domain)
            }
            Quantity::Fresnel => {
                // `table` is the runtime's f32 Fresnel (computed in f64
                // inside), `reference` the f64 reference.
                let (n, k, cos_theta) = (x[0], x[1], x[2]);
                let eta = twoscale::Complex::new(f(n), f(k));
                validate::eta(("n", "k"), eta).map_err(RowError::Invalid)?;
                let reference = fresnel::fresnel(fresnel::Complex64::new(n, k), cos_theta)
                    .map_err(|e| reference(&e))?;
                let value = twoscale::model::fresnel::fresnel(eta, f(cos_theta));
                (vec![short32(value), short(reference)], true)
            }
            Quantity::Conv => {
                // `fit` = T3a (the paper's s, g form), `table` = T3b, both
                // from the runtime; `reference` = exact C by direct quadrature.
                let (u, c, beta, p, theta_h) = (x[0], x[1], x[2], x[3], x[4]);
                let table = tables.convolution()?;
                let in_domain = domain(
                    table
                        .check(f(u), f(c), f(beta), f(p))
                        .map_err(RowError::Invalid),
                )?;
                let reference =
                    conv::convolution(theta_h, u, c, beta, p).map_err(|e| reference(&e))?;
                let (sin, cos) = (f(theta_h.sin()), f(theta_h.cos()));
                let (u, c, beta, p) = (f(u), f(c), f(beta), f(p));
                let fit = table.fit().convolution_sin_cos(sin, cos, u, c, beta, p);
                let value = table.convolution_sin_cos(sin, cos, u, c, beta, p);
                (
                    vec![short32(fit), short32(value), short(reference)],
                    in_domain,
                )
            }
            Quantity::Brdf => {
                // docs/model.md §6: the conductor two-scale model. `table` is
                // the runtime model (`twoscale::brdf::TwoScale`, f32, baked
                // from the table set: the path a renderer calls);
                // `reference` is `reference::brdf::two_scale` (exact Λ,
                // σrel, C). The parameters are validated as the runtime's
                // (`Layer::validate`, `validate::eta`, `validate::wavelength`)
                // before either is computed.
                let params = brdf::Params {
                    beta: x[0],
                    p: x[1],
                    sigma_s: x[2],
                    b: x[3],
                    c: x[4],
                    n: x[5],
                    k: x[6],
                    lambda: x[7],
                };
                let (i, o) = ([x[8], x[9], x[10]], [x[11], x[12], x[13]]);
                let layer = twoscale::material::Layer {
                    surface: twoscale::material::Surface {
                        beta: f(params.beta),
                        p: f(params.p),
                        sigma_s: f(params.sigma_s),
                        b: f(params.b),
                        c: f(params.c),
                    },
                    base: twoscale::material::BaseLayer::Conductor,
                    lambertian: 0.0,
                };
                let eta = twoscale::Complex::new(f(params.n), f(params.k));
                layer.validate().map_err(RowError::Invalid)?;
                validate::eta(("n", "k"), eta).map_err(RowError::Invalid)?;
                validate::wavelength(f(params.lambda)).map_err(RowError::Invalid)?;
                let options = twoscale::material::Options::default();
                let reference =
                    brdf::two_scale(&params, i, o, &options).map_err(|e| reference(&e))?;
                let set = tables.set()?;
                let model = twoscale::TwoScale::new(
                    &set.brdf_tables(),
                    layer,
                    f(params.lambda),
                    eta,
                    options,
                );
                let value = model.eval(i.map(f), o.map(f));
                (vec![short32(value), short(reference.total())], true)
            }
        })
    }
}

/// A reference value as printed: the shortest form that reads back to it.
fn short(x: f64) -> String {
    Shortest(x).to_string()
}

/// A runtime (f32) value as printed: the shortest form of the f32.
fn short32(x: f32) -> String {
    Shortest32(x).to_string()
}

/// Why a query could not run (before any row is answered, or while writing).
#[derive(Debug)]
pub enum QueryError {
    /// No quantity has this name.
    UnknownQuantity(String),
    /// `--clamp` was given for a quantity that is not the lookup of one
    /// table.
    ClampUnsupported(Quantity),
    /// `--material` was given for another quantity than `brdf`.
    MaterialUnsupported(Quantity),
    /// The material of `--material` is one the reference does not cover
    /// (a base layer, or the compensation of a surface with diffraction).
    Uncovered(brdf::Uncovered),
    /// The reference's compensation lobe of the `--material` could not be built.
    Reference(brdf::BrdfError),
    /// `--material` with `rgb_mode = "integrated"` and a `channel` column:
    /// the reference gives the paper's three wavelengths only.
    IntegratedUnsupported,
    /// A `lambda` column for a material without an index over the spectrum.
    NoSpectrum,
    /// The quantity's tables lack one the model reads (a bug of `run`).
    MissingTables,
    /// The input has no header line.
    EmptyInput,
    /// The input could not be read.
    Read(std::io::Error),
    /// The header lacks one of the quantity's input columns.
    MissingColumn {
        /// The column missing.
        column: &'static str,
        /// The quantity's input columns.
        needs: &'static [&'static str],
    },
    /// A table file could not be opened or is malformed.
    Tables(TableFileError),
    /// The output could not be written.
    Write(std::io::Error),
}

impl fmt::Display for QueryError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            QueryError::UnknownQuantity(name) => {
                let known: Vec<_> = Quantity::ALL.iter().map(|q| q.name()).collect();
                write!(f, "unknown quantity '{name}' (known: {})", known.join(", "))
            }
            QueryError::ClampUnsupported(q) => write!(
                f,
                "--clamp applies to the lookups of one table (g1, sigma-ratio, conv); \
                 {}'s parameters are always validated",
                q.name()
            ),
            QueryError::MaterialUnsupported(q) => write!(
                f,
                "--material applies to brdf (its rows then give {}), not {}",
                MATERIAL_COLUMNS.join(","),
                q.name()
            ),
            QueryError::Uncovered(_) => f.write_str(
                "--material: the f64 reference covers conductors (with a Lambertian term, \
                 k_d/π), and their energy compensation (multiple_scattering) without \
                 diffraction (sigma_s = 0) at the paper's wavelengths",
            ),
            QueryError::Reference(e) => write!(f, "--material: the reference failed: {e}"),
            QueryError::IntegratedUnsupported => write!(
                f,
                "--material: rows of {} compare with the reference at the paper's wavelengths; \
                 rgb_mode 'integrated' has none (give rows of {})",
                MATERIAL_COLUMNS.join(","),
                SPECTRAL_COLUMNS.join(",")
            ),
            QueryError::NoSpectrum => write!(
                f,
                "--material: rows of {} need an index over the spectrum: \
                 eta = {{ lambda, n, k }}, or one (n, k) for every channel",
                SPECTRAL_COLUMNS.join(",")
            ),
            QueryError::MissingTables => write!(f, "the table files were not opened"),
            QueryError::EmptyInput => write!(f, "empty input: expected a CSV header line"),
            QueryError::Read(e) => write!(f, "reading input: {e}"),
            QueryError::MissingColumn { column, needs } => {
                write!(
                    f,
                    "header lacks column '{column}' (needs {})",
                    needs.join(",")
                )
            }
            QueryError::Tables(e) => write!(f, "{e}"),
            QueryError::Write(e) => write!(f, "writing output: {e}"),
        }
    }
}

impl std::error::Error for QueryError {
    fn source(&self) -> Option<&(dyn std::error::Error + 'static)> {
        match self {
            QueryError::Read(e) | QueryError::Write(e) => Some(e),
            QueryError::Tables(e) => Some(e),
            _ => None,
        }
    }
}

/// The validated views of the table files a quantity reads.
#[derive(Default)]
pub struct Tables<'a> {
    smith: Option<SmithG1Table<'a>>,
    sigma_ratio: Option<SigmaRatioTable<'a>>,
    convolution: Option<ConvTable<'a>>,
    diffuse_fresnel: Option<DiffuseFresnelTable<'a>>,
    albedo: Option<AlbedoTable<'a>>,
}

impl<'a> Tables<'a> {
    /// Validates `files` (read from `source`, named in the errors).
    fn parse(
        files: &'a [(TableId, TableFile)],
        source: &TableSource,
    ) -> Result<Self, TableFileError> {
        let mut tables = Tables::default();
        for (id, file) in files {
            let bytes = file.bytes();
            let error = || source.format_error(id.name());
            match id {
                TableId::SmithG1 => {
                    tables.smith = Some(SmithG1Table::from_bytes(bytes).map_err(error())?);
                }
                TableId::SigmaRatio => {
                    tables.sigma_ratio = Some(SigmaRatioTable::from_bytes(bytes).map_err(error())?);
                }
                TableId::Convolution => {
                    tables.convolution = Some(ConvTable::from_bytes(bytes).map_err(error())?);
                }
                TableId::DiffuseFresnel => {
                    tables.diffuse_fresnel =
                        Some(DiffuseFresnelTable::from_bytes(bytes).map_err(error())?);
                }
                TableId::Albedo => {
                    tables.albedo = Some(AlbedoTable::from_bytes(bytes).map_err(error())?);
                }
                _ => {}
            }
        }
        Ok(tables)
    }

    fn smith(&self) -> Result<SmithG1Table<'a>, RowError> {
        self.smith.ok_or(RowError::NoTables)
    }

    fn sigma_ratio(&self) -> Result<SigmaRatioTable<'a>, RowError> {
        self.sigma_ratio.ok_or(RowError::NoTables)
    }

    fn convolution(&self) -> Result<&ConvTable<'a>, RowError> {
        self.convolution.as_ref().ok_or(RowError::NoTables)
    }

    /// The four tables as the runtime's set (`brdf`).
    fn set(&self) -> Result<TableSet<'a>, RowError> {
        Ok(TableSet {
            smith: self.smith()?,
            sigma_ratio: self.sigma_ratio()?,
            convolution: *self.convolution()?,
            diffuse_fresnel: self.diffuse_fresnel.ok_or(RowError::NoTables)?,
            albedo: self.albedo.ok_or(RowError::NoTables)?,
        })
    }
}

/// Why one row was not answered (reported on the error stream with its line
/// number: `line N: …`).
#[derive(Debug, Clone, PartialEq)]
pub enum RowError {
    /// The row has another number of fields than the header.
    FieldCount {
        /// Fields in the row.
        found: usize,
        /// Fields in the header.
        expected: usize,
    },
    /// An input field is not a number.
    NotANumber {
        /// Its column.
        column: &'static str,
        /// The field's text.
        field: String,
    },
    /// An input field is NaN or infinite.
    NotFinite {
        /// Its column.
        column: &'static str,
        /// Its value.
        value: f64,
    },
    /// A parameter outside its domain (the table's, or the model's): names
    /// the parameter, its value and the domain.
    Invalid(Invalid),
    /// An angle whose cosine is outside the table's domain (T2 is indexed by
    /// cos θi).
    InvalidAngle {
        /// The column given.
        column: &'static str,
        /// Its value.
        value: f64,
        /// The cosine's failed check.
        invalid: Invalid,
    },
    /// The reference cannot be computed at this point (outside its domain,
    /// or a quadrature failed).
    Reference(String),
    /// A `channel` that is not 0, 1 or 2.
    Channel(f64),
    /// The quantity reads tables that were not opened (a bug of `run`).
    NoTables,
}

impl fmt::Display for RowError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            RowError::FieldCount { found, expected } => {
                write!(f, "{found} fields, header has {expected}")
            }
            RowError::NotANumber { column, field } => {
                write!(f, "column '{column}' is not a number: '{field}'")
            }
            RowError::NotFinite { column, value } => {
                write!(f, "column '{column}' is not finite: {value}")
            }
            RowError::Invalid(e) => write!(f, "{e}"),
            RowError::InvalidAngle {
                column,
                value,
                invalid,
            } => write!(f, "{column} = {}: {invalid}", Shortest(*value)),
            RowError::Reference(e) => write!(f, "reference: {e}"),
            RowError::Channel(c) => write!(
                f,
                "channel = {}: must be 0, 1 or 2 (red, green, blue)",
                Shortest(*c)
            ),
            RowError::NoTables => write!(f, "the table files were not opened"),
        }
    }
}

impl std::error::Error for RowError {}

/// How `run` treats rows outside a table's domain, and the material of a
/// `brdf` query.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Options {
    /// Answer them at the clamped point (as the renderer-facing lookups
    /// do) and add the column `in_domain`, instead of reporting them.
    pub clamp: bool,
    /// `brdf` of this material (a material file, `--material FILE`): the
    /// rows give [`MATERIAL_COLUMNS`], `table` is the channel of the RGB
    /// model (`twoscale::Rgb`, as the C API and Python build it), or
    /// [`SPECTRAL_COLUMNS`] (a `lambda` column and no `channel`), `table`
    /// is the model at that wavelength (`twoscale::brdf::Spectral`).
    pub material: Option<OwnedMaterialDesc>,
}

/// The input columns of `brdf` with a material: the channel (0, 1, 2: red,
/// green, blue at `RGB_WAVELENGTHS`) and the two directions.
pub const MATERIAL_COLUMNS: [&str; 7] = ["channel", "ix", "iy", "iz", "ox", "oy", "oz"];

/// The input columns of `brdf` with a material over the spectrum: the
/// wavelength (µm, in [0.36, 0.83]) and the two directions.
pub const SPECTRAL_COLUMNS: [&str; 7] = ["lambda", "ix", "iy", "iz", "ox", "oy", "oz"];

/// The model of a `brdf --material` query, and the reference's parameters.
enum MaterialModel<'a> {
    /// Rows of [`MATERIAL_COLUMNS`]: the RGB model, and the reference's
    /// parameters of each channel.
    Channels {
        model: Box<Rgb<'a, Box<ChannelBake>>>,
        params: [brdf::Params; 3],
        options: twoscale::material::Options,
        /// The reference's energy-compensation lobe per channel, when the
        /// material's options ask for it.
        compensation: Option<Box<[brdf::Compensation; 3]>>,
        /// The Lambertian term k_d/π the reference adds.
        lambertian: f64,
    },
    /// Rows of [`SPECTRAL_COLUMNS`]: the spectral model, and the reference's
    /// parameters with `n`, `k`, `λ` set per row from the material's index.
    Spectral {
        model: Box<BoxedSpectral<'a>>,
        spectral: SpectralMaterial<'a>,
        params: brdf::Params,
        options: twoscale::material::Options,
        /// The Lambertian term k_d/π the reference adds.
        lambertian: f64,
    },
}

impl MaterialModel<'_> {
    /// `table` and `reference` of a row of [`MATERIAL_COLUMNS`] or
    /// [`SPECTRAL_COLUMNS`].
    fn evaluate(&self, x: &[f64]) -> Result<Vec<String>, RowError> {
        let (i, o) = ([x[1], x[2], x[3]], [x[4], x[5], x[6]]);
        let f = |v: f64| v as f32;
        let (value, params, options, multiple, lambertian) = match self {
            MaterialModel::Channels {
                model,
                params,
                options,
                compensation,
                lambertian,
            } => {
                let channel = x[0];
                let ch = [0.0, 1.0, 2.0]
                    .iter()
                    .position(|&c| c == channel)
                    .ok_or(RowError::Channel(channel))?;
                let multiple = match compensation {
                    Some(lobes) => lobes[ch]
                        .value(i, o)
                        .map_err(|e| RowError::Reference(e.to_string()))?,
                    None => 0.0,
                };
                (
                    model.eval(i.map(f), o.map(f))[ch],
                    params[ch],
                    options,
                    multiple,
                    *lambertian,
                )
            }
            MaterialModel::Spectral {
                model,
                spectral,
                params,
                options,
                lambertian,
            } => {
                let lambda = f(x[0]);
                let (lo, hi) = (
                    SPECTRAL_WAVELENGTHS[0],
                    SPECTRAL_WAVELENGTHS[SPECTRAL_WAVELENGTHS.len() - 1],
                );
                domain::check(
                    "lambda",
                    domain::widen(lambda),
                    domain::Domain::Closed(domain::widen(lo), domain::widen(hi)),
                    "µm, the spectral model's range",
                )
                .map_err(RowError::Invalid)?;
                let eta = spectral.eta.at(lambda);
                let params = brdf::Params {
                    n: eta.re.into(),
                    k: eta.im.into(),
                    lambda: lambda.into(),
                    ..*params
                };
                (
                    model.eval(i.map(f), o.map(f), lambda),
                    params,
                    options,
                    0.0,
                    *lambertian,
                )
            }
        };
        let reference = brdf::two_scale(&params, i, o, options)
            .map_err(|e| RowError::Reference(e.to_string()))?;
        // k_d/π above the horizon, as the runtime (docs/model.md §2.6).
        let lambertian = if i[2] > 0.0 && o[2] > 0.0 {
            lambertian
        } else {
            0.0
        };
        Ok(vec![
            short32(value),
            short(reference.total() + multiple + lambertian),
        ])
    }
}

/// Outcome of a query run.
#[derive(Debug, Default, PartialEq, Eq)]
pub struct Summary {
    /// Rows answered.
    pub answered: usize,
    /// Rows reported as bad.
    pub bad: usize,
}

/// Runs query `quantity` over CSV `input` with the tables of `tables`,
/// writing CSV to `output` and one line per bad row to `errors`. Fails
/// (before reading rows) on an unknown quantity, a missing or malformed
/// table file (of those the quantity reads), or a header without the
/// required columns.
pub fn run(
    quantity: &str,
    tables: &TableSource,
    options: &Options,
    input: impl BufRead,
    mut output: impl Write,
    mut errors: impl Write,
) -> Result<Summary, QueryError> {
    let quantity = Quantity::from_name(quantity)?;
    if options.clamp && !quantity.clamps() {
        return Err(QueryError::ClampUnsupported(quantity));
    }
    let params = match &options.material {
        Some(_) if quantity != Quantity::Brdf => {
            return Err(QueryError::MaterialUnsupported(quantity));
        }
        Some(desc) => {
            // The reference's parameters of the surface; its Lambertian
            // term is k_d/π in closed form, added per row.
            let desc = desc.get();
            let mut surface = desc.material;
            surface.layer.lambertian = 0.0;
            let params =
                brdf::Params::rgb_with(&surface, &desc.options).map_err(QueryError::Uncovered)?;
            Some((desc, params))
        }
        None => None,
    };
    let mut lines = input.lines().enumerate();
    let header = loop {
        match lines.next() {
            None => return Err(QueryError::EmptyInput),
            Some((_, line)) => {
                let line = line.map_err(QueryError::Read)?;
                if !line.trim().is_empty() {
                    break line;
                }
            }
        }
    };
    let names: Vec<String> = header.split(',').map(|s| s.trim().to_string()).collect();
    // With a material, a `lambda` column and no `channel` asks for the spectral model.
    let spectral_rows = params.is_some()
        && names.iter().any(|n| n == "lambda")
        && !names.iter().any(|n| n == "channel");
    let columns: &'static [&'static str] = match params {
        Some(_) if spectral_rows => &SPECTRAL_COLUMNS,
        Some(_) => &MATERIAL_COLUMNS,
        None => quantity.columns(),
    };
    match &params {
        Some((desc, _)) if spectral_rows && desc.spectral.is_none() => {
            return Err(QueryError::NoSpectrum);
        }
        Some((desc, _)) if !spectral_rows && desc.rgb_mode == RgbMode::Integrated => {
            return Err(QueryError::IntegratedUnsupported);
        }
        // The reference's compensation lobe is built per channel, not per row's λ.
        Some((desc, _))
            if spectral_rows && desc.options.multiple_scattering != MultipleScattering::None =>
        {
            return Err(QueryError::Uncovered(brdf::Uncovered));
        }
        _ => {}
    }
    let positions = columns
        .iter()
        .map(|&column| {
            names
                .iter()
                .position(|n| n == column)
                .ok_or(QueryError::MissingColumn {
                    column,
                    needs: columns,
                })
        })
        .collect::<Result<Vec<usize>, QueryError>>()?;

    // Open the tables the quantity reads before reading rows, so a missing
    // or malformed file fails fast.
    let files = quantity
        .tables()
        .iter()
        .map(|&id| tables.open(id).map(|file| (id, file)))
        .collect::<Result<Vec<_>, _>>()
        .map_err(QueryError::Tables)?;
    let views = Tables::parse(&files, tables).map_err(QueryError::Tables)?;
    let set = match params {
        Some(_) => Some(views.set().map_err(|_| QueryError::MissingTables)?),
        None => None,
    };
    let material = match (params, &set) {
        (Some((desc, params)), Some(set)) => Some({
            let lambertian = f64::from(desc.material.layer.lambertian) / std::f64::consts::PI;
            match desc.spectral {
                Some(spectral) if spectral_rows => MaterialModel::Spectral {
                    model: Box::new(Spectral::boxed(&set.brdf_tables(), &spectral, desc.options)),
                    spectral,
                    params: params[0],
                    options: desc.options,
                    lambertian,
                },
                _ => MaterialModel::Channels {
                    model: Box::new(Rgb::boxed(&set.brdf_tables(), &desc.material, desc.options)),
                    params,
                    options: desc.options,
                    compensation: brdf::Compensation::rgb(&params, &desc.options)
                        .map_err(QueryError::Reference)?
                        .map(Box::new),
                    lambertian,
                },
            }
        }),
        _ => None,
    };

    let rows: Vec<(usize, String)> = lines
        .map(|(n, line)| (n + 1, line.unwrap_or_default()))
        .filter(|(_, line)| !line.trim().is_empty())
        .collect();
    let answer = |line: &str| -> Result<String, RowError> {
        let fields: Vec<&str> = line.split(',').map(str::trim).collect();
        if fields.len() != names.len() {
            return Err(RowError::FieldCount {
                found: fields.len(),
                expected: names.len(),
            });
        }
        let values = positions
            .iter()
            .zip(columns)
            .map(|(&i, &column)| {
                fields[i].parse::<f64>().map_err(|_| RowError::NotANumber {
                    column,
                    field: fields[i].to_string(),
                })
            })
            .collect::<Result<Vec<f64>, RowError>>()?;
        if let Some((&column, &value)) = columns.iter().zip(&values).find(|(_, v)| !v.is_finite()) {
            return Err(RowError::NotFinite { column, value });
        }
        let (out, in_domain) = match &material {
            Some(material) => (material.evaluate(&values)?, true),
            None => quantity.evaluate(&views, &values, options.clamp)?,
        };
        let mut row = format!("{},{}", fields.join(","), out.join(","));
        if options.clamp {
            row.push_str(if in_domain { ",true" } else { ",false" });
        }
        Ok(row)
    };
    let results: Vec<(usize, Result<String, RowError>)> = rows
        .par_iter()
        .map(|(n, line)| (*n, answer(line)))
        .collect();

    let outputs = quantity.outputs();
    let clamp_column = if options.clamp { ",in_domain" } else { "" };
    writeln!(
        output,
        "{},{}{clamp_column}",
        names.join(","),
        outputs.join(",")
    )
    .map_err(QueryError::Write)?;
    let mut summary = Summary::default();
    for (n, result) in results {
        match result {
            Ok(row) => {
                writeln!(output, "{row}").map_err(QueryError::Write)?;
                summary.answered += 1;
            }
            Err(e) => {
                writeln!(errors, "line {n}: {e}").map_err(QueryError::Write)?;
                summary.bad += 1;
            }
        }
    }
    Ok(summary)
}
