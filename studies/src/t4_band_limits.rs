//! T4's band limits (`docs/design/t4-band-limits.md`): the error of the
//! projected BRDF against band limit `L` — relative RMS of
//! `f = ρ cos θi cos θo` and p99 / max of `|f_SH − f| / max f` over 20 000
//! random pairs (`sh_brdf::verification_pairs`, seed 11) — and the asymmetry
//! `‖M − Mᵀ‖/‖M‖` before symmetrising (WAT92 26–27).

use crate::common;
use generator::analytic::BeckmannCt;
use generator::materials::Materials;
use generator::sh::{IsotropicBrdf, default_quadrature, project};
use generator::tables::sh_brdf::{
    ModelInputs, WORKSPACE_TABLES, two_scale_brdf, verification_pairs,
};
use std::fmt::Write as _;
use std::path::Path;
use std::time::Instant;

/// Which BRDFs are projected.
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub enum Subject {
    /// The two-scale model (as T4 projects it, with the workspace's T1, T2,
    /// T5 and T3b) of the rough and the glossy presets, green channel.
    TwoScale,
    /// Beckmann Cook–Torrance lobes (F = 1), rough and glossy.
    Beckmann,
    /// A Beckmann lobe as narrow as the polished preset's (α = 0.005) at
    /// L = 64 and 127, with 4× the default θ nodes.
    Polished,
}

/// One markdown row per band limit of `brdf` appended to `out`; the
/// projection's time goes to stderr (the machine's, not the projection's).
fn study(
    out: &mut String,
    name: &str,
    brdf: &dyn IsotropicBrdf,
    bands: &[usize],
    theta_factor: usize,
) {
    let pairs = verification_pairs(20_000, 11);
    let exact: Vec<f64> = pairs
        .iter()
        .map(|&(i, o)| brdf.eval(i, o) * i[2] * o[2])
        .collect();
    let peak = exact.iter().fold(0.0f64, |m, v| m.max(*v));
    let norm: f64 = exact.iter().map(|v| v * v).sum::<f64>();
    for &l in bands {
        let start = Instant::now();
        let mut quadrature = default_quadrature(l);
        quadrature.theta_nodes *= theta_factor;
        let projection = project(brdf, l, quadrature, None);
        let seconds = start.elapsed().as_secs_f64();
        let (diff, matrix_norm) = projection.asymmetry();
        let mut errors = Vec::new();
        let mut sum2 = 0.0;
        for (k, &(i, o)) in pairs.iter().enumerate() {
            let e = projection.eval(i, o) * i[2] * o[2] - exact[k];
            sum2 += e * e;
            errors.push(e.abs() / peak);
        }
        errors.sort_by(f64::total_cmp);
        eprintln!("{name}, L = {l}: projected in {seconds:.1} s");
        let _ = writeln!(
            out,
            "| {name} | {l} | {:.2e} | {:.2e} | {:.2e} | {:.2e} |",
            (sum2 / norm).sqrt(),
            errors[errors.len() * 99 / 100],
            errors[errors.len() - 1],
            diff / matrix_norm,
        );
    }
}

/// Runs the study on each of `subjects`; prints one table (and writes it to
/// `markdown` when given).
pub fn run(subjects: &[Subject], materials: &Path, markdown: Option<&Path>) -> Result<(), String> {
    common::check_markdown(markdown)?;
    let mut out = String::from(
        "| BRDF | L | rel RMS of f | p99 \\|Δf\\|/max f | max \\|Δf\\|/max f | asymmetry |\n\
         |---|---:|---:|---:|---:|---:|\n",
    );
    for &subject in subjects {
        run_one(&mut out, subject, materials)?;
    }
    print!("{out}");
    let Some(path) = markdown else {
        return Ok(());
    };
    let names: Vec<&str> = subjects
        .iter()
        .map(|s| match s {
            Subject::TwoScale => "two-scale",
            Subject::Beckmann => "beckmann",
            Subject::Polished => "polished",
        })
        .collect();
    common::write_markdown(
        path,
        "T4's error against the band limit L",
        &format!("t4-band-limits {}", names.join(" ")),
        &format!(
            "Each BRDF projected to real SH at band limit L with T4's quadrature (the \
             polished lobe with 4× its θ nodes), at 20 000 random pairs \
             (`sh_brdf::verification_pairs`, seed 11): the relative RMS of \
             `f = ρ cos θi cos θo`, p99 and max of `|f_SH − f| / max f`, and the \
             projected matrix's asymmetry `‖M − Mᵀ‖/‖M‖` before symmetrising. The \
             two-scale presets are projected at one wavelength (the green channel of \
             `materials.toml`), as T4 projected them before it took the integrated \
             RGB.\n\n{out}"
        ),
    )
}

/// Appends the rows of `subject` to `out`.
fn run_one(out: &mut String, subject: Subject, materials: &Path) -> Result<(), String> {
    match subject {
        Subject::Beckmann => {
            for (name, alpha, bands) in [
                (
                    "Beckmann rough α = 0.35",
                    0.35,
                    &[4usize, 8, 12, 16, 24, 32][..],
                ),
                (
                    "Beckmann glossy α = 0.0598",
                    0.0598,
                    &[8, 16, 32, 48, 64, 96][..],
                ),
            ] {
                study(out, name, &BeckmannCt { alpha, eta: None }, bands, 1);
            }
        }
        Subject::Polished => {
            let brdf = BeckmannCt {
                alpha: 0.005,
                eta: None,
            };
            study(out, "Beckmann polished α = 0.005", &brdf, &[64, 127], 4);
        }
        Subject::TwoScale => {
            let materials = Materials::load(materials).map_err(|e| e.to_string())?;
            let inputs =
                ModelInputs::load(Path::new(WORKSPACE_TABLES)).map_err(|e| e.to_string())?;
            let parsed = inputs.parse().map_err(|e| e.to_string())?;
            let tables = parsed.brdf_tables();
            let channel = 1;
            let lambda = materials.wavelengths[channel];
            for (name, bands) in [
                ("gold-rough", &[4usize, 8, 12, 16, 24, 32][..]),
                ("gold-hp17-geometry", &[8, 16, 32, 48, 64, 96][..]),
            ] {
                let material = materials
                    .materials
                    .iter()
                    .find(|m| m.name == name)
                    .ok_or_else(|| format!("no preset {name} in the materials file"))?;
                let brdf = two_scale_brdf(material, channel, lambda, &tables);
                study(
                    out,
                    &format!("two-scale {name} at {lambda} µm"),
                    &brdf,
                    bands,
                    1,
                );
            }
        }
    }
    Ok(())
}
