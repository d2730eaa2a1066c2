//! T4: the spherical-harmonic BRDF matrix of each material of the materials
//! file (\[WAT92\] §2, docs/model.md §2.9), one file `t4-<material>.tbl` per material,
//! one channel per RGB channel (at a wavelength or integrated: below).
//! Layout and conventions: `twoscale::tables::sh_brdf`; projection: [`crate::sh`].
//!
//! # What is projected
//!
//! The committed files project the **runtime two-scale model**
//! (`twoscale::brdf::TwoScale`, docs/model.md §2.5–§2.6, default [`Options`]: the
//! paper's `σrel(θi)`, separable G, physical F and Q̄) as the runtime gives
//! the material's RGB by default ([`Material::rgb_mode`]): for a preset (all
//! the committed files), each linear-sRGB channel integrated over the
//! spectrum (`twoscale::brdf::IntegratedRgb`, docs/model.md §2.12; header
//! `brdf_model = 4`, [`ProjectedModel::IntegratedRgb`]); for a material
//! given by its indices, the model at each channel's wavelength
//! (`brdf_model = 3`, [`ProjectedModel::TwoScale`]). Either reads the
//! five tables the BRDF reads ([`INPUTS`]: T1, T2, T5, T6 and C from T3b
//! through `twoscale::ConvTable`). The model's interface is
//! f32: the projection's f64 directions are rounded to f32 and ρ comes back
//! in f32 (relative rounding ~6e-8, far below the truncation error in L).
//! The f64 reference (`crate::reference::brdf`, exact C) costs 1–30 ms per
//! call; the projection needs ~10⁶ evaluations per channel, hence the runtime.
//! The channels are projected in one pass ([`crate::sh::project_channels`]):
//! the integrated model's three come from one evaluation.
//!
//! **Where the input tables come from** ([`input_dir`]): the directory the
//! T4 files are written to (`build --out`) or read from (`verify DIR`) when it
//! holds all five input files, else the tables compiled into the binary
//! (feature `embedded`: the committed ones). `build` writes
//! T1, T2, T5, T6, T3 before T4 (the order of [`super::all`], then the materials),
//! so a full build into an empty directory projects the tables just built.
//!
//! The two-scale model with `σs > 0` is not reciprocal (σrel depends on θi
//! only, docs/model.md §7): the asymmetry `‖M − Mᵀ‖/‖M‖` (WAT92 26-27) measured before
//! symmetrising is written into the header (`asymmetry`).
//!
//! The Beckmann Cook–Torrance stand-in of [`crate::analytic::StandIn`]
//! (`brdf_model = 2`; no diffraction, `p`, σs, b, c unused) stays available
//! ([`Projected::BeckmannStandIn`]) for the tests and studies that need an
//! analytic BRDF and no T3.

use indicatif::ProgressBar;
use rayon::prelude::*;
use std::path::{Path, PathBuf};
use twoscale::brdf::{ChannelBake, IntegratedRgb, Tables};
use twoscale::material::{BaseLayer, Options, RgbMode};
use twoscale::tables::format::write::{TableSpec, encode};
use twoscale::tables::format::{AlignedBuf, AxisHeader, Mapping, ShBrdfParams, aligned_copy};
use twoscale::tables::sh_brdf::{AUX_NAMES, ProjectedModel, coefficient_count};
use twoscale::{Complex, ShBrdfTable, TableBytes, TableId, TableSet, TwoScale};

use super::{Accuracy, BuildError, GENERATOR_VERSION, TableKind, file_name};
use crate::analytic::{BeckmannCt, StandIn};
use crate::materials::{Material, Materials};
use crate::reference::fresnel::{self, Complex64};
use crate::rng::SplitMix64;
use crate::sh::{
    ChannelBrdf, EachChannel, IsotropicBrdf, Runtime, default_quadrature, project_channels,
};

/// The workspace's table directory (the studies and tests read it; the
/// generator's defaults never do).
pub const WORKSPACE_TABLES: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/../tables");

/// The tables the two-scale model reads: the runtime's set.
pub const INPUTS: [TableId; 5] = twoscale::table_set::TABLES;

/// Verification target: `max |f_SH − f| / max f` over the random pairs, with
/// `f = ρ cos θi cos θo` (what the matrix represents; dividing by the cosines
/// magnifies any error near grazing, \[WAT92\] §5). The maximum is always at
/// grazing incidence and exitance near the mirror azimuth, where the specular
/// peak is narrower in `Δφ` than any band limit can follow. The target, 0.5,
/// only catches a broken table; the p99 and median are the figures to read
/// (docs/design/t4-band-limits.md).
pub const TARGET_MAX_REL_F_ERROR: f64 = 0.5;

/// Which BRDF a T4 builder projects.
#[derive(Clone, Debug, PartialEq)]
pub enum Projected {
    /// The runtime two-scale model (module docs) reading its tables from
    /// [`input_dir`]`(dir)`.
    TwoScale {
        /// The preferred directory of [`INPUTS`].
        dir: PathBuf,
    },
    /// The Beckmann Cook–Torrance stand-in (analytic, no tables).
    BeckmannStandIn,
}

impl Projected {
    /// The code written into the header of `material`'s file.
    pub fn model(&self, material: &Material) -> ProjectedModel {
        match (self, material.rgb_mode()) {
            (Projected::TwoScale { .. }, RgbMode::Integrated) => ProjectedModel::IntegratedRgb,
            (Projected::TwoScale { .. }, RgbMode::PaperWavelengths) => ProjectedModel::TwoScale,
            (Projected::BeckmannStandIn, _) => ProjectedModel::BeckmannStandIn,
        }
    }
}

/// `preferred` if it holds all of [`INPUTS`], else `None`: the tables
/// compiled into the binary ([`ModelInputs::embedded`]).
pub fn input_dir(preferred: &Path) -> Option<PathBuf> {
    INPUTS
        .iter()
        .all(|&id| preferred.join(file_name(id)).is_file())
        .then(|| preferred.to_path_buf())
}

/// [`INPUTS`] read from a directory or the binary (owned, 64-byte
/// aligned).
pub struct ModelInputs {
    /// Where they were read from (a directory, or "the embedded tables").
    pub dir: PathBuf,
    /// The files of [`INPUTS`], in its order.
    buffers: Vec<AlignedBuf>,
}

impl ModelInputs {
    /// Reads [`INPUTS`] from `dir` (no fallback: see [`input_dir`]).
    pub fn load(dir: &Path) -> Result<ModelInputs, BuildError> {
        let read = |id: TableId| {
            let path = dir.join(file_name(id));
            std::fs::read(&path)
                .map(|bytes| aligned_copy(&bytes))
                .map_err(|e| BuildError::Input {
                    path: path.display().to_string(),
                    message: format!("{e} (T4 projects the two-scale model, which reads it)"),
                })
        };
        Ok(ModelInputs {
            dir: dir.to_path_buf(),
            buffers: INPUTS
                .iter()
                .map(|&id| read(id))
                .collect::<Result<_, _>>()?,
        })
    }

    /// Copies of the tables compiled into the binary (feature `embedded`).
    pub fn embedded() -> Result<ModelInputs, BuildError> {
        let read = |id: TableId| {
            crate::table_source::embedded(id)
                .map(aligned_copy)
                .ok_or_else(|| BuildError::Input {
                    path: file_name(id),
                    message: "not in the output directory, and this generator has no \
                              embedded tables (T4 projects the two-scale model, which reads it)"
                        .into(),
                })
        };
        Ok(ModelInputs {
            dir: PathBuf::from("the embedded tables"),
            buffers: INPUTS
                .iter()
                .map(|&id| read(id))
                .collect::<Result<_, _>>()?,
        })
    }

    /// The inputs of [`Projected::TwoScale`] for directory `preferred`:
    /// read from [`input_dir`]`(preferred)`, else the embedded tables.
    pub fn for_dir(preferred: &Path) -> Result<ModelInputs, BuildError> {
        match input_dir(preferred) {
            Some(dir) => ModelInputs::load(&dir),
            None => ModelInputs::embedded(),
        }
    }

    /// Validates the four files as the runtime's table set.
    pub fn parse(&self) -> Result<TableSet<'_>, BuildError> {
        let bytes = TableBytes::try_from_fn(|id| {
            let k = INPUTS.iter().position(|&input| input == id);
            k.and_then(|k| self.buffers.get(k))
                .map(AlignedBuf::bytes)
                .ok_or(())
        });
        let bytes = bytes.map_err(|()| BuildError::Input {
            path: self.dir.display().to_string(),
            message: "a table of the set is missing".to_string(),
        })?;
        TableSet::from_bytes(bytes).map_err(|e| BuildError::Input {
            path: self.dir.display().to_string(),
            message: e.to_string(),
        })
    }
}

/// The runtime two-scale model as an [`IsotropicBrdf`] (through its
/// [`twoscale::Bxdf`] interface).
pub type TwoScaleBrdf<'a> = Runtime<TwoScale<'a>>;

/// The two-scale model of `material` at `channel` (wavelength `wavelength`
/// µm), default options, reading `tables`.
pub fn two_scale_brdf<'a>(
    material: &Material,
    channel: usize,
    wavelength: f64,
    tables: &Tables<'a>,
) -> TwoScaleBrdf<'a> {
    Runtime(TwoScale::new(
        tables,
        material.layer,
        wavelength as f32,
        material.eta[channel],
        Options::default(),
    ))
}

/// The Beckmann Cook–Torrance stand-in of `material` at `channel`: α = β,
/// the complex Fresnel factor, the plastic base; an error for a subsurface
/// base or a Lambertian term, which it does not model.
pub fn stand_in_brdf(material: &Material, channel: usize) -> Result<StandIn, BuildError> {
    let eta = material.eta[channel];
    let eta = Complex64::new(f64::from(eta.re), f64::from(eta.im));
    let unsupported = |what: &str| BuildError::Input {
        path: format!("material {}", material.name),
        message: format!("the Beckmann stand-in has no {what}"),
    };
    if material.layer.lambertian != 0.0 {
        return Err(unsupported("Lambertian term"));
    }
    let base_factor = match material.layer.base {
        BaseLayer::Conductor => 0.0,
        BaseLayer::Subsurface { .. } => return Err(unsupported("subsurface base")),
        BaseLayer::Plastic { albedo } => {
            let n = eta.re;
            let f_dr = fresnel::diffuse_internal(n).map_err(|source| BuildError::Quadrature {
                at: format!("T4 {} F_dr,int(η = {n})", material.name),
                source,
            })?;
            let rho_d = f64::from(albedo);
            rho_d / (std::f64::consts::PI * n * n * (1.0 - rho_d * f_dr))
        }
    };
    Ok(StandIn {
        lobe: BeckmannCt {
            alpha: f64::from(material.layer.surface.beta),
            eta: Some(eta),
        },
        base_factor,
    })
}

/// The linear-sRGB channels of the integrated two-scale model
/// ([`IntegratedRgb::eval`]) as a [`ChannelBrdf`], at the directions rounded
/// to f32.
pub struct IntegratedChannels<'a>(pub IntegratedRgb<'a, Box<ChannelBake>>);

impl ChannelBrdf for IntegratedChannels<'_> {
    fn channels(&self) -> usize {
        3
    }
    fn eval_channels(&self, wi: [f64; 3], wo: [f64; 3], out: &mut [f64]) {
        let rgb = self.0.eval(wi.map(|v| v as f32), wo.map(|v| v as f32));
        for (v, c) in out.iter_mut().zip(rgb) {
            *v = f64::from(c);
        }
    }
}

/// One channel of a [`ChannelBrdf`] as an [`IsotropicBrdf`].
pub struct ChannelOf<B> {
    /// The model.
    pub model: B,
    /// The channel.
    pub channel: usize,
}

impl<B: ChannelBrdf> IsotropicBrdf for ChannelOf<B> {
    fn eval(&self, wi: [f64; 3], wo: [f64; 3]) -> f64 {
        let mut out = [0.0; 3];
        let out = &mut out[..self.model.channels()];
        self.model.eval_channels(wi, wo, out);
        out[self.channel]
    }
}

/// The BRDF of `material` at `channel` that T4 projects
/// ([`Projected::model`]): with `tables`, the two-scale model as the runtime
/// gives it by default ([`Material::rgb_mode`]: channel `channel` of the
/// integral over the spectrum for a preset, the model at `wavelength` µm
/// otherwise); without, the Beckmann stand-in.
pub fn material_brdf<'a>(
    material: &Material,
    channel: usize,
    wavelength: f64,
    tables: Option<&Tables<'a>>,
) -> Result<Box<dyn IsotropicBrdf + 'a>, BuildError> {
    Ok(match (tables, &material.spectral) {
        (Some(tables), Some(spectral)) if material.rgb_mode() == RgbMode::Integrated => {
            Box::new(ChannelOf {
                model: IntegratedChannels(IntegratedRgb::boxed(
                    tables,
                    spectral,
                    Options::default(),
                )),
                channel,
            })
        }
        (Some(tables), _) => Box::new(two_scale_brdf(material, channel, wavelength, tables)),
        (None, _) => Box::new(stand_in_brdf(material, channel)?),
    })
}

/// Every channel of [`material_brdf`] at `wavelengths` as one [`ChannelBrdf`]:
/// the integrated model's three channels from one evaluation, else one
/// [`material_brdf`] per channel.
pub fn material_channels<'a>(
    material: &Material,
    wavelengths: &[f64],
    tables: Option<&Tables<'a>>,
) -> Result<Box<dyn ChannelBrdf + 'a>, BuildError> {
    Ok(match (tables, &material.spectral) {
        (Some(tables), Some(spectral))
            if material.rgb_mode() == RgbMode::Integrated && wavelengths.len() == 3 =>
        {
            Box::new(IntegratedChannels(IntegratedRgb::boxed(
                tables,
                spectral,
                Options::default(),
            )))
        }
        _ => Box::new(EachChannel(
            wavelengths
                .iter()
                .enumerate()
                .map(|(c, &lambda)| material_brdf(material, c, lambda, tables))
                .collect::<Result<_, _>>()?,
        )),
    })
}

/// The T4 builder of one material.
pub struct ShBrdf {
    /// The material.
    pub material: Material,
    /// Its band limit L.
    pub band_limit: usize,
    /// The wavelengths of the channels, µm.
    pub wavelengths: Vec<f64>,
    /// What is projected.
    pub projected: Projected,
}

/// Runs `f` with the BRDF source of `projected`: the two-scale tables read
/// from [`input_dir`] (for [`Projected::TwoScale`]) or none (the stand-in).
fn with_source<T>(
    projected: &Projected,
    f: impl FnOnce(Option<&Tables<'_>>) -> Result<T, BuildError>,
) -> Result<T, BuildError> {
    match projected {
        Projected::TwoScale { dir } => {
            let inputs = ModelInputs::for_dir(dir)?;
            let parsed = inputs.parse()?;
            f(Some(&parsed.brdf_tables()))
        }
        Projected::BeckmannStandIn => f(None),
    }
}

impl ShBrdf {
    /// One builder per material of the file that has a band limit, each
    /// projecting `projected`.
    pub fn all(materials: &Materials, projected: &Projected) -> Vec<ShBrdf> {
        materials
            .materials
            .iter()
            .filter_map(|m| Some((m, m.band_limit?)))
            .map(|(m, band_limit)| ShBrdf {
                material: m.clone(),
                band_limit,
                wavelengths: materials.wavelengths.clone(),
                projected: projected.clone(),
            })
            .collect()
    }

    fn aux(&self, phi_nodes: usize) -> Vec<f32> {
        let m = &self.material;
        let base_albedo = match m.layer.base {
            BaseLayer::Conductor => 0.0,
            BaseLayer::Plastic { albedo } | BaseLayer::Subsurface { albedo } => albedo,
        };
        let s = m.layer.surface;
        let mut aux = vec![
            self.projected.model(m).code() as f32,
            phi_nodes as f32,
            s.beta,
            s.p,
            s.sigma_s,
            s.b,
            s.c,
            base_albedo,
        ];
        for c in 0..3 {
            let eta = m.eta.get(c).copied().unwrap_or(Complex::new(0.0, 0.0));
            aux.push(eta.re);
            aux.push(eta.im);
        }
        debug_assert_eq!(aux.len(), AUX_NAMES.len());
        aux
    }
}

impl TableKind for ShBrdf {
    fn id(&self) -> TableId {
        TableId::ShBrdf
    }

    fn file_stem(&self) -> String {
        format!("t4-{}", self.material.name)
    }

    fn work_items(&self) -> u64 {
        default_quadrature(self.band_limit).theta_nodes as u64
    }

    fn build(&self, progress: &ProgressBar) -> Result<Vec<u8>, BuildError> {
        let m = &self.material;
        let l = self.band_limit;
        let quadrature = default_quadrature(l);
        let channels = self.wavelengths.len();
        let count = coefficient_count(l);
        let mut grid = vec![0.0f32; count * channels];
        let mut asymmetry: f64 = 0.0;
        with_source(&self.projected, |tables| {
            let brdf = material_channels(m, &self.wavelengths, tables)?;
            let projections = project_channels(brdf.as_ref(), l, quadrature, Some(progress));
            for (c, projection) in projections.iter().enumerate() {
                let (diff, norm) = projection.asymmetry();
                asymmetry = asymmetry.max(if norm > 0.0 { diff / norm } else { 0.0 });
                for (k, v) in projection.packed(m.filter).into_iter().enumerate() {
                    grid[k * channels + c] = v as f32;
                }
            }
            Ok(())
        })?;
        let lambda = |c: usize| self.wavelengths.get(c).copied().unwrap_or(0.0);
        let params = ShBrdfParams {
            band_limit: l as f64,
            filter_start: m.filter.map_or(0.0, |f| f.start),
            filter_width: m.filter.map_or(0.0, |f| f.width),
            lambda_0: lambda(0),
            lambda_1: lambda(1),
            lambda_2: lambda(2),
            asymmetry_rel: asymmetry,
            theta_nodes: quadrature.theta_nodes as f64,
        };
        let axis = AxisHeader {
            nodes: count as u32,
            mapping: Mapping::Uniform,
            lo: 0.0,
            hi: (count - 1) as f64,
            param: 0.0,
            param2: 0.0,
        };
        Ok(encode(&TableSpec {
            table_id: TableId::ShBrdf,
            channels: channels as u32,
            kernel: TableId::ShBrdf.descriptor().kernel,
            value_type: TableId::ShBrdf.descriptor().value_type,
            axes: &[axis],
            params: &params.to_values(),
            grid: &grid,
            aux: &self.aux(quadrature.phi_nodes()),
            generator_version: GENERATOR_VERSION,
        })?)
    }

    fn verify(&self, bytes: &[u8], points: usize, seed: u64) -> Result<Vec<Accuracy>, BuildError> {
        let table = ShBrdfTable::from_bytes(bytes)?;
        let mut out = Vec::new();
        let pairs = verification_pairs(points, seed);
        with_source(&self.projected, |tables| {
            let brdf = material_channels(&self.material, &self.wavelengths, tables)?;
            let channels = self.wavelengths.len();
            // exact[p * channels + c]: channel c at pair p.
            let exact: Vec<f64> = pairs
                .par_iter()
                .flat_map_iter(|&(wi, wo)| {
                    let mut values = vec![0.0; channels];
                    brdf.eval_channels(wi, wo, &mut values);
                    values
                })
                .collect();
            for c in 0..channels {
                let values: Vec<(f64, f64, String)> = pairs
                    .par_iter()
                    .enumerate()
                    .map(|(p, &(wi, wo))| {
                        let cc = wi[2] * wo[2];
                        let exact = exact[p * channels + c] * cc;
                        let got = f64::from(table.eval(c, narrow(wi), narrow(wo))) * cc;
                        let at = format!(
                            "θi {:.1}°, θo {:.1}°, Δφ {:.1}°",
                            wi[2].acos().to_degrees(),
                            wo[2].acos().to_degrees(),
                            wo[1].atan2(wo[0]).to_degrees()
                        );
                        (exact, got, at)
                    })
                    .collect();
                let peak = values.iter().fold(0.0f64, |m, v| m.max(v.0.abs()));
                let errors = values
                    .into_iter()
                    .map(|(exact, got, at)| ((got - exact).abs() / peak, at))
                    .collect();
                out.push(Accuracy::from_errors(
                    &format!("λ{c} |f_SH-f|/max f, L={}", table.band_limit()),
                    TARGET_MAX_REL_F_ERROR,
                    errors,
                ));
            }
            Ok(())
        })?;
        Ok(out)
    }
}

fn narrow(d: [f64; 3]) -> [f32; 3] {
    [d[0] as f32, d[1] as f32, d[2] as f32]
}

/// Random pairs of directions, uniform in solid angle on the upper
/// hemisphere (`cos θ ≥ 1e-3`), `wi` in the xz-plane (isotropy), rounded to
/// f32 as the runtime takes them.
pub fn verification_pairs(points: usize, seed: u64) -> Vec<([f64; 3], [f64; 3])> {
    let mut rng = SplitMix64::new(seed);
    let round = |v: f64| f64::from(v as f32);
    (0..points)
        .map(|_| {
            let zi = round(rng.uniform_in(1e-3, 1.0));
            let zo = round(rng.uniform_in(1e-3, 1.0));
            let phi = rng.uniform_in(0.0, 2.0 * std::f64::consts::PI);
            let (si, so) = ((1.0 - zi * zi).sqrt(), (1.0 - zo * zo).sqrt());
            let wi = [round(si), 0.0, zi];
            let wo = [round(so * phi.cos()), round(so * phi.sin()), zo];
            (normalise(wi), normalise(wo))
        })
        .collect()
}

fn normalise(d: [f64; 3]) -> [f64; 3] {
    let len = (d[0] * d[0] + d[1] * d[1] + d[2] * d[2]).sqrt();
    [d[0] / len, d[1] / len, d[2] / len]
}
