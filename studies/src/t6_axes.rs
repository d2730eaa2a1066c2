//! T6's axes: node counts of the incidence, width and p axes and the p
//! axis's power against the interpolated error, the file size and the build
//! time (docs/design/t6-albedo-axes.md).
//!
//! Each layout is built by the generator's own `albedo::build_with` (the
//! shipped coordinates of `twoscale::tables::albedo`), read by the runtime's
//! `AlbedoTable`, and measured at `generator verify`'s kind of random points
//! (`albedo::verification_points`, seed 99) against `albedo_pair`, the build's
//! fixed rule (within 3e-6 of the adaptive reference, its test): a table's
//! error at many points in seconds. The points' p is snapped to 50 values so
//! that 50 Λ curves serve them.

use crate::common;
use generator::reference::albedo::albedo_pair;
use generator::reference::epd::LambdaCurve;
use generator::tables::albedo;
use rayon::prelude::*;
use std::fmt::Write as _;
use std::path::Path;
use twoscale::material::Masking;
use twoscale::tables::format::{AxisHeader, Mapping};

/// A layout `ny,nz,np,power` (p even in `p^power`).
pub fn parse_layout(s: &str) -> Result<[f64; 4], String> {
    let v: Vec<f64> = s
        .split(',')
        .map(|x| x.trim().parse::<f64>().map_err(|e| format!("{s}: {e}")))
        .collect::<Result<_, _>>()?;
    <[f64; 4]>::try_from(v).map_err(|_| format!("{s}: a layout is ny,nz,np,power"))
}

/// Builds and measures each layout; prints one row per layout (and writes
/// the table to `markdown` when given). Build times go to stderr: they are
/// the machine's, not the layout's.
pub fn run(layouts: &[[f64; 4]], points: usize, markdown: Option<&Path>) -> Result<(), String> {
    common::check_markdown(markdown)?;
    let samples = albedo::verification_points(points, 99);
    let ps: Vec<f64> = samples.iter().take(50).map(|s| s.0).collect();
    let curves: Vec<LambdaCurve> = ps
        .par_iter()
        .map(|&p| LambdaCurve::new(p).map_err(|e| e.to_string()))
        .collect::<Result<_, _>>()?;
    let exact: Vec<[f64; 2]> = samples
        .par_iter()
        .enumerate()
        .map(|(k, &(_, beta, mu))| {
            albedo_pair(&curves[k % 50], beta, mu).map_err(|e| e.to_string())
        })
        .collect::<Result<_, _>>()?;
    let mut out = String::from(
        "| ny nz np, p power | bytes | max \\|ΔE\\| | p99 | p90 | median | worst at (masking, p, β, μ) |\n\
         |---|---:|---:|---:|---:|---:|---|\n",
    );
    for &[ny, nz, np, power] in layouts {
        let axes = [
            AxisHeader {
                nodes: ny as u32,
                ..albedo::Y_AXIS
            },
            AxisHeader {
                nodes: nz as u32,
                ..albedo::Z_AXIS
            },
            AxisHeader {
                nodes: np as u32,
                mapping: Mapping::Power,
                param: power,
                ..albedo::P_AXIS
            },
        ];
        let start = std::time::Instant::now();
        let bytes = albedo::build_with(axes, &indicatif::ProgressBar::hidden())
            .map_err(|e| e.to_string())?;
        let seconds = start.elapsed().as_secs_f64();
        let buf = twoscale::tables::format::aligned_copy(&bytes);
        let table = twoscale::AlbedoTable::from_bytes(buf.bytes()).map_err(|e| e.to_string())?;
        let mut errors: Vec<(f64, String)> = samples
            .par_iter()
            .zip(&exact)
            .enumerate()
            .flat_map_iter(|(k, (&(_, beta, mu), e))| {
                let p = ps[k % 50];
                let table = &table;
                [Masking::Separable, Masking::HeightCorrelated]
                    .into_iter()
                    .zip(*e)
                    .map(move |(masking, want)| {
                        let got =
                            f64::from(table.albedo(mu as f32, beta as f32, p as f32, masking));
                        (
                            (got - want).abs(),
                            format!("{masking:?}, {p:.3}, {beta:.3e}, {mu:.3e}"),
                        )
                    })
            })
            .collect();
        errors.sort_by(|a, b| b.0.total_cmp(&a.0));
        let at = |q: f64| errors[((errors.len() - 1) as f64 * q) as usize].0;
        eprintln!("{ny} {nz} {np} {power}: built in {seconds:.1} s");
        let _ = writeln!(
            out,
            "| {ny} {nz} {np}, {power} | {} | {:.2e} | {:.2e} | {:.2e} | {:.2e} | {} |",
            bytes.len(),
            errors[0].0,
            at(0.01),
            at(0.1),
            at(0.5),
            errors[0].1
        );
    }
    print!("{out}");
    let Some(path) = markdown else {
        return Ok(());
    };
    let layouts: Vec<String> = layouts
        .iter()
        .map(|l| format!("--layout {},{},{},{}", l[0], l[1], l[2], l[3]))
        .collect();
    common::write_markdown(
        path,
        "T6's layouts: size and interpolated error",
        &format!("t6-axes --points {points} {}", layouts.join(" ")),
        &format!(
            "Each layout (nodes of the incidence y, the width z and p; p even in \
             `p^power`) built by the generator's `albedo::build_with` and read by the \
             runtime's `AlbedoTable`, at {points} random points of `generator verify`'s \
             kind (seed 99), each for both maskings, against `albedo_pair` (the build's \
             rule); `|ΔE|` absolute.\n\n{out}"
        ),
    )
}
