//! `generator plot`: the pictures of `docs/img/`.
//!
//! * **Lobes** (one PNG per material, as HP17 Figs. 12–15): the two-scale
//!   BRDF in the plane of incidence at four incidences, on a log scale, with
//!   its three terms apart (`TwoScale::eval_lobes`: specular `A_spec ρ_CT`,
//!   diffraction `ρ_CTD`, base `ρ_base + k_d/π`).
//! * **Error maps** of T1, T2 and T3: the errors `verify` measures, at
//!   `verify`'s random points (the same functions: `smith_g1::error_at`,
//!   `sigma_ratio::error_at`, `convolution::verify_point`), binned over two axes of the
//!   table's domain (the largest error per bin; T3's profiles, being few,
//!   are drawn one marker each).
//!
//! Text needs a TrueType font, read from a file at run time (plotters'
//! `ab_glyph` feature: no system font lookup); [`DEFAULT_FONT`] is where
//! Debian's `fonts-dejavu-core` puts DejaVu Sans.

use crate::error::{Error, FileAction};
use crate::materials::{Material, Materials};
use crate::table_source::{TableFileError, TableSource};
use crate::tables::sh_brdf::two_scale_brdf;
use crate::tables::{BuildError, convolution, sigma_ratio, smith_g1};
use plotters::coord::types::RangedCoordf64;
use plotters::prelude::*;
use plotters::style::colors::colormaps::ViridisRGB;
use rayon::prelude::*;
use std::fmt;
use std::path::{Path, PathBuf};
use twoscale::brdf::{IntegratedRgb, Spectral, Tables};
use twoscale::material::Options;
use twoscale::spectrum::optical::SpectralMaterial;
use twoscale::{ConvTable, FormatError, Rgb, SigmaRatioTable, SmithG1Table, TableId};

/// DejaVu Sans as Debian's `fonts-dejavu-core` installs it.
pub const DEFAULT_FONT: &str = "/usr/share/fonts/truetype/dejavu/DejaVuSans.ttf";

/// The incidences of the lobe plots, degrees.
pub const INCIDENCES: [f64; 4] = [0.0, 30.0, 60.0, 80.0];

/// Size of every picture, pixels.
const SIZE: (u32, u32) = (800, 540);

/// The font family name the pictures use.
const FONT: &str = "sans-serif";

/// Why a picture could not be drawn.
#[derive(Debug)]
pub enum PlotError {
    /// The font file could not be read.
    FontUnreadable {
        /// The file.
        path: PathBuf,
        /// Why.
        source: std::io::Error,
    },
    /// The font file is not a TrueType font.
    NotAFont(PathBuf),
    /// A table file could not be read or is malformed.
    Tables(TableFileError),
    /// The tables could not be loaded or an error could not be measured.
    Table(BuildError),
    /// The material's BRDF is zero everywhere (nothing to draw on a log scale).
    ZeroBrdf(String),
    /// plotters failed (its error, as it formats it).
    Draw(String),
}

impl fmt::Display for PlotError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            PlotError::FontUnreadable { path, source } => write!(
                f,
                "cannot read the font {} ({source}); install fonts-dejavu-core or pass --font",
                path.display()
            ),
            PlotError::NotAFont(path) => write!(f, "{} is not a TrueType font", path.display()),
            PlotError::Tables(e) => write!(f, "{e}"),
            PlotError::Table(e) => write!(f, "{e}"),
            PlotError::ZeroBrdf(material) => write!(f, "{material}: the BRDF is zero everywhere"),
            PlotError::Draw(e) => write!(f, "drawing failed: {e}"),
        }
    }
}

impl std::error::Error for PlotError {
    fn source(&self) -> Option<&(dyn std::error::Error + 'static)> {
        match self {
            PlotError::FontUnreadable { source, .. } => Some(source),
            PlotError::Tables(e) => Some(e),
            PlotError::Table(e) => Some(e),
            _ => None,
        }
    }
}

impl From<TableFileError> for PlotError {
    fn from(e: TableFileError) -> Self {
        PlotError::Tables(e)
    }
}

impl From<BuildError> for PlotError {
    fn from(e: BuildError) -> Self {
        PlotError::Table(e)
    }
}

/// Reads the TrueType file at `path` and registers it as the pictures' font.
pub fn load_font(path: &Path) -> Result<(), PlotError> {
    let bytes = std::fs::read(path).map_err(|source| PlotError::FontUnreadable {
        path: path.to_path_buf(),
        source,
    })?;
    // plotters keeps fonts for the life of the process.
    let bytes: &'static [u8] = Box::leak(bytes.into_boxed_slice());
    plotters::style::register_font(FONT, FontStyle::Normal, bytes)
        .map_err(|_| PlotError::NotAFont(path.to_path_buf()))
}

fn draw_error(e: impl fmt::Debug) -> PlotError {
    PlotError::Draw(format!("{e:?}"))
}

/// One term of the BRDF, as drawn.
struct Term {
    name: &'static str,
    color: RGBColor,
    pick: fn(&twoscale::brdf::Lobes) -> f32,
}

const TERMS: [Term; 4] = [
    Term {
        name: "total ρ",
        color: BLACK,
        pick: |l| l.total(),
    },
    Term {
        name: "specular",
        color: RGBColor(31, 119, 180),
        pick: |l| l.specular,
    },
    Term {
        name: "diffraction",
        color: RGBColor(214, 39, 40),
        pick: |l| l.diffraction,
    },
    Term {
        name: "base",
        color: RGBColor(44, 160, 44),
        pick: |l| l.base,
    },
];

/// Outgoing angles in the plane of incidence, degrees (positive: the
/// mirror side), with a fine run around the mirror direction so that narrow
/// specular peaks are resolved.
fn outgoing_angles(theta_i: f64) -> Vec<f64> {
    let mut v: Vec<f64> = (0..=716).map(|k| -89.5 + 0.25 * f64::from(k)).collect();
    v.extend((0..=600).map(|k| theta_i - 3.0 + 0.01 * f64::from(k)));
    v.retain(|t| t.abs() <= 89.5);
    v.sort_by(f64::total_cmp);
    v.dedup();
    v
}

/// One curve of a lobe picture: its legend label, colour and line width.
struct Curve {
    label: String,
    color: RGBColor,
    width: u32,
}

/// Per incidence of [`INCIDENCES`]: θi, the outgoing angles in the plane of
/// incidence and `values(i, o)` at each.
type PlaneCurves<const K: usize> = Vec<(f64, Vec<f64>, Vec<[f64; K]>)>;

/// `values(i, o)` in the plane of incidence, per incidence of [`INCIDENCES`].
fn plane_curves<const K: usize>(values: impl Fn([f32; 3], [f32; 3]) -> [f64; K]) -> PlaneCurves<K> {
    INCIDENCES
        .iter()
        .map(|&theta_i| {
            let ti = theta_i.to_radians();
            let i = [-ti.sin() as f32, 0.0, ti.cos() as f32];
            let thetas = outgoing_angles(theta_i);
            let v = thetas
                .iter()
                .map(|&t| {
                    let to = t.to_radians();
                    values(i, [to.sin() as f32, 0.0, to.cos() as f32])
                })
                .collect();
            (theta_i, thetas, v)
        })
        .collect()
}

/// Draws `curves` (one panel per incidence, log scale over six decades
/// below the peak) titled `title` to `path`; `name` is the material's, for
/// the error of an all-zero BRDF.
fn draw_plane_curves<const K: usize>(
    path: &Path,
    title: &str,
    name: &str,
    curves: &PlaneCurves<K>,
    series: &[Curve; K],
) -> Result<(), PlotError> {
    let peak = curves
        .iter()
        .flat_map(|(_, _, v)| v.iter().flatten().copied())
        .fold(0.0f64, f64::max);
    if !(peak > 0.0 && peak.is_finite()) {
        return Err(PlotError::ZeroBrdf(name.to_string()));
    }
    let hi = 10f64.powf(peak.log10().ceil() + 0.3);
    let lo = hi * 1e-6;

    let root = BitMapBackend::new(path, SIZE).into_drawing_area();
    root.fill(&WHITE).map_err(draw_error)?;
    let root = root.titled(title, (FONT, 20)).map_err(draw_error)?;
    for (panel, (theta_i, thetas, values)) in root.split_evenly((2, 2)).iter().zip(curves) {
        let mut chart = ChartBuilder::on(panel)
            .caption(format!("θi = {theta_i}°"), (FONT, 15))
            .margin(6)
            .x_label_area_size(32)
            .y_label_area_size(58)
            .build_cartesian_2d(-90f64..90f64, (lo..hi).log_scale())
            .map_err(draw_error)?;
        chart
            .configure_mesh()
            .x_desc("θo (°), + on the mirror side")
            .y_desc("ρ (sr⁻¹)")
            .x_labels(7)
            .x_label_formatter(&|v| format!("{v:.0}"))
            .y_label_formatter(&|v| format!("{v:.0e}"))
            .label_style((FONT, 11))
            .axis_desc_style((FONT, 12))
            .draw()
            .map_err(draw_error)?;
        for (k, curve) in series.iter().enumerate() {
            let runs = runs_above(thetas.iter().zip(values).map(|(&t, v)| (t, v[k])), lo);
            let style = ShapeStyle::from(&curve.color).stroke_width(curve.width);
            if runs.is_empty() {
                // Listed all the same: absent (a conductor has no base), or
                // below the plot.
                let largest = values.iter().map(|v| v[k]).fold(0.0f64, f64::max);
                let label = if largest > 0.0 {
                    format!("{}: all < {lo:.0e}", curve.label)
                } else {
                    format!("{}: none", curve.label)
                };
                chart
                    .draw_series(std::iter::empty::<PathElement<(f64, f64)>>())
                    .map_err(draw_error)?
                    .label(label)
                    .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 18, y)], style));
                continue;
            }
            for (r, run) in runs.into_iter().enumerate() {
                let drawn = chart
                    .draw_series(LineSeries::new(run, style))
                    .map_err(draw_error)?;
                if r == 0 {
                    drawn
                        .label(curve.label.as_str())
                        .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 18, y)], style));
                }
            }
        }
        legend(&mut chart, SeriesLabelPosition::UpperLeft, 11)?;
    }
    root.present().map_err(draw_error)
}

/// Draws the legend of `chart`'s labelled series at `position`, text of `size`.
fn legend<'a, CT: plotters::coord::CoordTranslate>(
    chart: &mut ChartContext<'a, BitMapBackend<'a>, CT>,
    position: SeriesLabelPosition,
    size: u32,
) -> Result<(), PlotError> {
    chart
        .configure_series_labels()
        .position(position)
        .label_font((FONT, size))
        .background_style(WHITE.mix(0.85))
        .border_style(BLACK)
        .draw()
        .map_err(draw_error)
}

/// Draws the lobes of `material` at `channel` (wavelength `lambda`, µm)
/// with the tables of `source` to `path`.
pub fn lobes(
    material: &Material,
    channel: usize,
    lambda: f64,
    source: &TableSource,
    path: &Path,
) -> Result<(), PlotError> {
    let inputs = source.model_inputs()?;
    let parsed = inputs.parse()?;
    let tables = parsed.brdf_tables();
    let brdf = two_scale_brdf(material, channel, lambda, &tables).0;
    let curves = plane_curves(|i, o| {
        let lobes = brdf.eval_lobes(i, o);
        TERMS.map(|term| f64::from((term.pick)(&lobes)))
    });
    let series = TERMS.each_ref().map(|term| Curve {
        label: term.name.to_string(),
        color: term.color,
        width: if term.name == TERMS[0].name { 2 } else { 1 },
    });
    let title = format!(
        "{}: ρ in the plane of incidence, λ = {lambda} µm (log scale)",
        material.name
    );
    draw_plane_curves(path, &title, &material.name, &curves, &series)
}

/// The runs of `points` above `lo` (a log axis has no 0): one polyline per
/// run, none when no point is above.
fn runs_above(points: impl Iterator<Item = (f64, f64)>, lo: f64) -> Vec<Vec<(f64, f64)>> {
    let mut runs: Vec<Vec<(f64, f64)>> = vec![Vec::new()];
    for (t, v) in points {
        if v > lo {
            runs.last_mut().expect("one run").push((t, v));
        } else if !runs.last().expect("one run").is_empty() {
            runs.push(Vec::new());
        }
    }
    runs.retain(|r| !r.is_empty());
    runs
}

/// The wavelengths (µm) of [`spectral_lobes`] and a colour for each.
const SPECTRAL_LINES: [(f32, RGBColor); 5] = [
    (0.40, RGBColor(118, 0, 196)),
    (0.50, RGBColor(0, 160, 170)),
    (0.60, RGBColor(230, 130, 0)),
    (0.70, RGBColor(200, 0, 0)),
    (0.80, RGBColor(100, 0, 0)),
];

/// Draws ρ of preset `name` over the spectrum (`material`) in the plane of
/// incidence at 0.4, 0.5, 0.6, 0.7 and 0.8 µm, one panel per incidence,
/// through `brdf::Spectral` (HP17 Fig. 15: the halo widens with λ) with
/// `tables`, to `path`.
pub fn spectral_lobes(
    name: &str,
    material: &SpectralMaterial<'_>,
    tables: &Tables<'_>,
    path: &Path,
) -> Result<(), PlotError> {
    let model = Spectral::boxed(tables, material, Options::default());
    let curves =
        plane_curves(|i, o| SPECTRAL_LINES.map(|(lambda, _)| f64::from(model.eval(i, o, lambda))));
    let series = SPECTRAL_LINES.map(|(lambda, color)| Curve {
        label: format!("λ = {lambda} µm"),
        color,
        width: 1,
    });
    let title = format!("{name}: ρ in the plane of incidence at five wavelengths (log scale)");
    draw_plane_curves(path, &title, name, &curves, &series)
}

/// The incidence (°) of [`rgb_comparison`].
const COMPARISON_INCIDENCE: f64 = 45.0;

/// Draws preset `name`'s RGB in the plane of incidence at θi = 45°,
/// integrated over the spectrum (`brdf::IntegratedRgb`, solid) against the
/// paper's three wavelengths (`brdf::Rgb`, dashed): ρ per channel (linear
/// scale, around the mirror direction) and each channel over red (the
/// colour), with `tables`, to `path`.
pub fn rgb_comparison(
    name: &str,
    material: &SpectralMaterial<'_>,
    tables: &Tables<'_>,
    path: &Path,
) -> Result<(), PlotError> {
    let options = Options::default();
    let paper = Rgb::boxed(tables, &material.paper_rgb(), options);
    let integrated = IntegratedRgb::boxed(tables, material, options);
    let ti = COMPARISON_INCIDENCE.to_radians();
    let i = [-ti.sin() as f32, 0.0, ti.cos() as f32];
    let thetas: Vec<f64> = (0..=600)
        .map(|k| COMPARISON_INCIDENCE - 30.0 + 0.1 * f64::from(k))
        .filter(|t| t.abs() <= 89.5)
        .collect();
    let values: Vec<([f64; 3], [f64; 3])> = thetas
        .iter()
        .map(|&t| {
            let to = t.to_radians();
            let o = [to.sin() as f32, 0.0, to.cos() as f32];
            (
                integrated.eval(i, o).map(f64::from),
                paper.eval(i, o).map(f64::from),
            )
        })
        .collect();
    let peak = values
        .iter()
        .flat_map(|(a, b)| a.iter().chain(b))
        .copied()
        .fold(0.0f64, f64::max);
    if !(peak > 0.0 && peak.is_finite()) {
        return Err(PlotError::ZeroBrdf(name.to_string()));
    }
    let channels = [
        ("R", RGBColor(200, 30, 30)),
        ("G", RGBColor(30, 150, 30)),
        ("B", RGBColor(30, 60, 200)),
    ];
    let x_range = (thetas[0], thetas[thetas.len() - 1]);
    let root = BitMapBackend::new(path, (SIZE.0, SIZE.1 / 2 + 40)).into_drawing_area();
    root.fill(&WHITE).map_err(draw_error)?;
    let root = root
        .titled(
            &format!(
                "{name}, θi = {COMPARISON_INCIDENCE}°: RGB integrated over the spectrum (solid) \
                 vs at 0.645, 0.526, 0.444 µm (dashed)"
            ),
            (FONT, 15),
        )
        .map_err(draw_error)?;
    let panels = root.split_evenly((1, 2));
    // Left: ρ per channel; right: each channel over red.
    for (p, panel) in panels.iter().enumerate() {
        let y_max = if p == 0 { peak * 1.05 } else { 1.2 };
        let mut chart = ChartBuilder::on(panel)
            .margin(8)
            .x_label_area_size(32)
            .y_label_area_size(52)
            .build_cartesian_2d(x_range.0..x_range.1, 0f64..y_max)
            .map_err(draw_error)?;
        chart
            .configure_mesh()
            .x_desc("θo (°), in the plane of incidence")
            .y_desc(if p == 0 {
                "ρ (sr⁻¹)"
            } else {
                "ρ_c / ρ_R"
            })
            .x_labels(7)
            .x_label_formatter(&|v| format!("{v:.0}"))
            .label_style((FONT, 11))
            .axis_desc_style((FONT, 12))
            .draw()
            .map_err(draw_error)?;
        for (c, &(label, color)) in channels.iter().enumerate() {
            if p == 1 && c == 0 {
                continue;
            }
            // Where red is above 1e-3 of the peak (the ratio is colour there).
            let pick = |v: &[f64; 3]| if p == 0 { v[c] } else { v[c] / v[0] };
            let shown = |v: &[f64; 3]| p == 0 || v[0] > 1e-3 * peak;
            let solid: Vec<(f64, f64)> = thetas
                .iter()
                .zip(&values)
                .filter(|(_, (a, _))| shown(a))
                .map(|(&t, (a, _))| (t, pick(a)))
                .collect();
            let dashed: Vec<(f64, f64)> = thetas
                .iter()
                .zip(&values)
                .filter(|(_, (_, b))| shown(b))
                .map(|(&t, (_, b))| (t, pick(b)))
                .collect();
            let style = ShapeStyle::from(&color).stroke_width(2);
            chart
                .draw_series(LineSeries::new(solid, style))
                .map_err(draw_error)?
                .label(format!("{label} integrated"))
                .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 18, y)], style));
            let thin = ShapeStyle::from(&color).stroke_width(1);
            chart
                .draw_series(DashedLineSeries::new(dashed, 6, 4, thin))
                .map_err(draw_error)?
                .label(format!("{label} three wavelengths"))
                .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 8, y)], thin));
        }
        legend(&mut chart, SeriesLabelPosition::UpperRight, 10)?;
    }
    root.present().map_err(draw_error)
}

/// The metal of the README's comparison picture ([`rgb_comparison`]).
pub const COMPARISON_PRESET: &str = "gold-hp17-geometry";

/// Errors at points of a 2-D view of a table's domain: `(x, y, error)` in
/// plot coordinates.
pub type Samples = Vec<(f64, f64, f64)>;

/// The error of table `id`'s file in `source` being malformed.
fn malformed(source: &TableSource, id: TableId) -> impl FnOnce(FormatError) -> PlotError {
    let error = source.format_error(id.name());
    move |e| PlotError::Tables(error(e))
}

/// T1's errors at `verify`'s points: `(p, log10 a, |G1 − G1_ref|)`.
pub fn t1_errors(source: &TableSource, points: usize, seed: u64) -> Result<Samples, PlotError> {
    let file = source.open(TableId::SmithG1)?;
    let table =
        SmithG1Table::from_bytes(file.bytes()).map_err(malformed(source, TableId::SmithG1))?;
    smith_g1::verification_points(points, seed)
        .par_iter()
        .map(|&(p, a)| Ok((p, a.max(1e-300).log10(), smith_g1::error_at(&table, p, a)?)))
        .collect::<Result<_, BuildError>>()
        .map_err(PlotError::Table)
}

/// T2's errors at `verify`'s points: `(θi in degrees, log10 B, relative error)`.
pub fn t2_errors(source: &TableSource, points: usize, seed: u64) -> Result<Samples, PlotError> {
    let file = source.open(TableId::SigmaRatio)?;
    let table = SigmaRatioTable::from_bytes(file.bytes())
        .map_err(malformed(source, TableId::SigmaRatio))?;
    sigma_ratio::verification_points(points, seed)
        .par_iter()
        .map(|&(cos_i, big_b, c)| {
            Ok((
                cos_i.acos().to_degrees(),
                big_b.log10(),
                sigma_ratio::error_at(&table, cos_i, big_b, c)?,
            ))
        })
        .collect::<Result<_, BuildError>>()
        .map_err(PlotError::Table)
}

/// T3b's e_L2 at `verify`'s profiles (`convolution::profiles_for(points)` of them):
/// `([u, c, β, p], e_L2)`.
pub fn t3_errors(
    source: &TableSource,
    points: usize,
    seed: u64,
) -> Result<Vec<([f64; 4], f64)>, PlotError> {
    let file = source.open(TableId::Convolution)?;
    let table =
        ConvTable::from_bytes(file.bytes()).map_err(malformed(source, TableId::Convolution))?;
    convolution::verification_points(convolution::profiles_for(points), seed)
        .par_iter()
        .map(|&pt| Ok((pt, convolution::verify_point(&table, pt)?.accurate_e_l2)))
        .collect::<Result<_, BuildError>>()
        .map_err(PlotError::Table)
}

/// A 2-D view of a domain: ranges and axis descriptions.
pub struct View {
    /// Picture title.
    pub title: String,
    /// x range and description.
    pub x: (f64, f64, &'static str),
    /// y range and description.
    pub y: (f64, f64, &'static str),
}

/// The colour scale of the error maps: `log10` of the error from `lo` to
/// `hi` (decades).
struct Scale {
    lo: f64,
    hi: f64,
}

impl Scale {
    fn of(errors: impl Iterator<Item = f64>) -> Scale {
        let (mut lo, mut hi) = (f64::INFINITY, f64::NEG_INFINITY);
        for e in errors.filter(|e| *e > 0.0 && e.is_finite()) {
            lo = lo.min(e.log10());
            hi = hi.max(e.log10());
        }
        if lo >= hi {
            // No positive error (or one value): any decade range will do.
            (lo, hi) = (lo.min(0.0) - 8.0, lo.min(0.0));
        }
        Scale {
            lo: lo.floor().max(hi.ceil() - 8.0),
            hi: hi.ceil(),
        }
    }

    fn color(&self, error: f64) -> RGBColor {
        let v = if error > 0.0 { error.log10() } else { self.lo };
        ViridisRGB::get_color_normalized(v.clamp(self.lo, self.hi), self.lo, self.hi)
    }
}

/// Draws the colour bar of `scale` into `area`.
fn color_bar(
    area: &DrawingArea<BitMapBackend<'_>, plotters::coord::Shift>,
    scale: &Scale,
    what: &str,
) -> Result<(), PlotError> {
    let mut chart = ChartBuilder::on(area)
        .margin_top(40)
        .margin_bottom(40)
        .margin_right(8)
        .y_label_area_size(52)
        .build_cartesian_2d(0f64..1f64, scale.lo..scale.hi)
        .map_err(draw_error)?;
    chart
        .configure_mesh()
        .disable_x_mesh()
        .disable_x_axis()
        .y_desc(what)
        .y_label_formatter(&|v| format!("{:.0e}", 10f64.powf(*v)))
        .label_style((FONT, 11))
        .axis_desc_style((FONT, 12))
        .draw()
        .map_err(draw_error)?;
    let steps = 100;
    let step = (scale.hi - scale.lo) / f64::from(steps);
    chart
        .draw_series((0..steps).map(|k| {
            let v0 = scale.lo + step * f64::from(k);
            let c = ViridisRGB::get_color_normalized(v0 + 0.5 * step, scale.lo, scale.hi);
            Rectangle::new([(0.0, v0), (1.0, v0 + step)], c.filled())
        }))
        .map_err(draw_error)?;
    Ok(())
}

/// A bitmap drawing area.
type Area<'a> = DrawingArea<BitMapBackend<'a>, plotters::coord::Shift>;

/// A picture at `path` with `title`: the whole canvas, the plot area and the
/// colour bar's area.
fn canvas<'a>(path: &'a Path, title: &str) -> Result<(Area<'a>, Area<'a>, Area<'a>), PlotError> {
    let root = BitMapBackend::new(path, SIZE).into_drawing_area();
    root.fill(&WHITE).map_err(draw_error)?;
    let titled = root.titled(title, (FONT, 18)).map_err(draw_error)?;
    let (main, bar) = titled.split_horizontally(SIZE.0 - 130);
    Ok((root, main, bar))
}

/// Axes over `x` and `y` (range and description) in `area`, drawn, with or
/// without the mesh.
fn axes<'a, 'b>(
    area: &'a Area<'b>,
    x: (f64, f64, &str),
    y: (f64, f64, &str),
    mesh: bool,
) -> Result<
    ChartContext<'a, BitMapBackend<'b>, Cartesian2d<RangedCoordf64, RangedCoordf64>>,
    PlotError,
> {
    let mut chart = ChartBuilder::on(area)
        .margin(10)
        .x_label_area_size(40)
        .y_label_area_size(60)
        .build_cartesian_2d(x.0..x.1, y.0..y.1)
        .map_err(draw_error)?;
    let mut style = chart.configure_mesh();
    if !mesh {
        style.disable_mesh();
    }
    style
        .x_desc(x.2)
        .y_desc(y.2)
        .label_style((FONT, 12))
        .axis_desc_style((FONT, 13))
        .draw()
        .map_err(draw_error)?;
    Ok(chart)
}

/// The error map of `samples` over `view`: the largest error in each of
/// `bins.0 × bins.1` bins (samples outside the view go to the edge bins),
/// empty bins left white; `what` names the error.
pub fn heat_map(
    path: &Path,
    view: &View,
    samples: &Samples,
    bins: (usize, usize),
    what: &str,
) -> Result<(), PlotError> {
    let (nx, ny) = bins;
    let (x0, x1, y0, y1) = (view.x.0, view.x.1, view.y.0, view.y.1);
    let index = |v: f64, lo: f64, hi: f64, n: usize| {
        (((v - lo) / (hi - lo) * n as f64).floor().max(0.0) as usize).min(n - 1)
    };
    let mut worst = vec![None::<f64>; nx * ny];
    for &(x, y, e) in samples {
        let k = index(y, y0, y1, ny) * nx + index(x, x0, x1, nx);
        worst[k] = Some(worst[k].map_or(e, |w: f64| w.max(e)));
    }
    let scale = Scale::of(worst.iter().flatten().copied());
    let (root, main, bar) = canvas(path, &view.title)?;
    let mut chart = axes(&main, view.x, view.y, false)?;
    let (dx, dy) = ((x1 - x0) / nx as f64, (y1 - y0) / ny as f64);
    chart
        .draw_series(worst.iter().enumerate().filter_map(|(k, w)| {
            let (i, j) = ((k % nx) as f64, (k / nx) as f64);
            w.map(|e| {
                Rectangle::new(
                    [
                        (x0 + i * dx, y0 + j * dy),
                        (x0 + (i + 1.0) * dx, y0 + (j + 1.0) * dy),
                    ],
                    scale.color(e).filled(),
                )
            })
        }))
        .map_err(draw_error)?;
    color_bar(&bar, &scale, what)?;
    root.present().map_err(draw_error)
}

/// The T3 map: one marker per profile in two views, `(ln u, ln β)` and
/// `(c, p)`, coloured by T3b's e_L2.
pub fn t3_map(path: &Path, profiles: &[([f64; 4], f64)], title: &str) -> Result<(), PlotError> {
    let scale = Scale::of(profiles.iter().map(|p| p.1));
    let (root, main, bar) = canvas(path, title)?;
    let panels = main.split_evenly((1, 2));
    /// One panel: the plot coordinates of a point `(u, c, β, p)` and the
    /// axes (range, description).
    struct Panel {
        coords: fn(&[f64; 4]) -> (f64, f64),
        x: (f64, f64, &'static str),
        y: (f64, f64, &'static str),
    }
    let views = [
        Panel {
            coords: |p| ((p[0] + 0.1).log10(), p[2].log10()),
            x: (-1.0, 3.5, "log10(u + 0.1)"),
            y: (0.002f64.log10(), 0.0, "log10 β"),
        },
        Panel {
            coords: |p| (p[1], p[3]),
            x: (1.0, 10.0, "c"),
            y: (0.2, 5.0, "p"),
        },
    ];
    for (panel, view) in panels.iter().zip(views) {
        let coords = view.coords;
        let mut chart = axes(panel, view.x, view.y, true)?;
        chart
            .draw_series(
                profiles
                    .iter()
                    .map(|(p, e)| Circle::new(coords(p), 6, scale.color(*e).filled())),
            )
            .map_err(draw_error)?;
        chart
            .draw_series(
                profiles
                    .iter()
                    .map(|(p, _)| Circle::new(coords(p), 6, BLACK.stroke_width(1))),
            )
            .map_err(draw_error)?;
    }
    color_bar(&bar, &scale, "T3b e_L2 against exact C")?;
    root.present().map_err(draw_error)
}

/// The arguments of `generator plot`.
pub struct PlotArgs {
    /// Output directory.
    pub out: PathBuf,
    /// The tables drawn.
    pub tables: TableSource,
    /// The materials whose lobes are drawn.
    pub materials: Materials,
    /// Only these materials' lobes (all if empty).
    pub only: Vec<String>,
    /// Whether to draw the error maps of T1, T2, T3.
    pub errors: bool,
    /// Random points of the error maps, as for verify.
    pub points: usize,
    /// Seed of the random points, as for verify.
    pub seed: u64,
    /// TrueType font for the text.
    pub font: PathBuf,
}

/// `generator plot`: the lobes of each material (`lobes-<name>.png`), of
/// each preset over the spectrum (`spectral-<name>.png`), the README's
/// comparison of integrated and three-wavelength RGB
/// (`rgb-integration-gold-hp17-geometry.png`) and the error maps
/// (`error-t1.png`, `error-t2.png`, `error-t3.png`) in `args.out`.
pub fn run(args: &PlotArgs) -> Result<(), Error> {
    load_font(&args.font)?;
    let materials = &args.materials;
    for name in &args.only {
        if !materials.materials.iter().any(|m| &m.name == name) {
            let known: Vec<_> = materials
                .materials
                .iter()
                .map(|m| m.name.as_str())
                .collect();
            return Err(Error::Usage(format!(
                "no material {name} (known: {})",
                known.join(", ")
            )));
        }
    }
    std::fs::create_dir_all(&args.out).map_err(Error::file(FileAction::Create, &args.out))?;
    let out = std::fs::canonicalize(&args.out).unwrap_or_else(|_| args.out.clone());
    // The green channel (as T4's band-limit study).
    let channel = 1;
    let lambda = materials.wavelengths[channel];
    let inputs = args.tables.model_inputs().map_err(PlotError::from)?;
    let parsed = inputs.parse().map_err(PlotError::from)?;
    let tables = parsed.brdf_tables();
    for material in &materials.materials {
        if !args.only.is_empty() && !args.only.contains(&material.name) {
            continue;
        }
        let path = out.join(format!("lobes-{}.png", material.name));
        lobes(material, channel, lambda, &args.tables, &path)?;
        eprintln!("wrote {}", path.display());
        // A preset (same name and layer) has its index over the spectrum.
        let preset = twoscale::materials::spectral(&material.name);
        if let Some(spectral) = preset.filter(|s| s.layer == material.layer) {
            let path = out.join(format!("spectral-{}.png", material.name));
            spectral_lobes(&material.name, &spectral, &tables, &path)?;
            eprintln!("wrote {}", path.display());
            if material.name == COMPARISON_PRESET {
                let path = out.join(format!("rgb-integration-{}.png", material.name));
                rgb_comparison(&material.name, &spectral, &tables, &path)?;
                eprintln!("wrote {}", path.display());
            }
        }
    }
    if args.errors {
        let (source, points, seed) = (&args.tables, args.points, args.seed);
        let suffix = format!("{points} verify points, seed {seed}; largest error per bin");
        let t1 = View {
            title: format!("T1 (Smith G1): |G1 − G1_ref|, {suffix}"),
            x: (0.2, 5.0, "p"),
            y: (-4.0, 4.0, "log10 a"),
        };
        let path = out.join("error-t1.png");
        heat_map(
            &path,
            &t1,
            &t1_errors(source, points, seed)?,
            (48, 32),
            "|G1 − G1_ref|",
        )?;
        eprintln!("wrote {}", path.display());
        let t2 = View {
            title: format!("T2 (σ ratio): relative error, {suffix} (over c)"),
            x: (0.0, 90.0, "θi (°)"),
            y: (-1.0, 3000f64.log10(), "log10 B"),
        };
        let path = out.join("error-t2.png");
        heat_map(
            &path,
            &t2,
            &t2_errors(source, points, seed)?,
            (45, 30),
            "relative error",
        )?;
        eprintln!("wrote {}", path.display());
        let profiles = t3_errors(source, points, seed)?;
        let path = out.join("error-t3.png");
        t3_map(
            &path,
            &profiles,
            &format!(
                "T3b: e_L2 of each of verify's {} profiles (seed {seed})",
                profiles.len()
            ),
        )?;
        eprintln!("wrote {}", path.display());
    }
    Ok(())
}
