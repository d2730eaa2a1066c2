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
use std::io::{BufRead, Write};
use std::path::Path;
use twoscale::{Convolution, TableSet};

use crate::reference::{brdf, conv, epd, fresnel, kcorr};

/// Quantities that can be queried, with their input columns.
pub const QUANTITIES: &[(&str, &[&str])] = &[
    ("g1", &["p", "a"]),
    ("sigma-ratio", &["theta_i", "B", "c"]),
    ("fresnel", &["n", "k", "cos_theta"]),
    ("conv", &["u", "c", "beta", "p", "theta_h"]),
    (
        "brdf",
        &[
            "beta", "p", "sigma_s", "b", "c", "n", "k", "lambda", "ix", "iy", "iz", "ox", "oy",
            "oz",
        ],
    ),
];

/// Outcome of a query run.
#[derive(Debug, Default, PartialEq, Eq)]
pub struct Summary {
    /// Rows answered.
    pub answered: usize,
    /// Rows reported as bad.
    pub bad: usize,
}

/// Evaluates one row's inputs (in the order of the quantity's input columns)
/// to its output values, or says why it cannot.
type Evaluator<'t> = Box<dyn Fn(&[f64]) -> Result<Vec<String>, String> + Sync + 't>;

/// Runs query `quantity` over CSV `input`, writing CSV to `output` and one line
/// per bad row to `errors`. Fails (before reading rows) on an unknown quantity,
/// a missing table file, or a header without the required columns.
pub fn run(
    quantity: &str,
    tables: &Path,
    input: impl BufRead,
    mut output: impl Write,
    mut errors: impl Write,
) -> Result<Summary, String> {
    let (_, columns) = QUANTITIES
        .iter()
        .find(|(name, _)| *name == quantity)
        .ok_or_else(|| {
            let known: Vec<_> = QUANTITIES.iter().map(|(n, _)| *n).collect();
            format!(
                "unknown quantity '{quantity}' (known: {})",
                known.join(", ")
            )
        })?;
    let mut lines = input.lines().enumerate();
    let header = loop {
        match lines.next() {
            None => return Err("empty input: expected a CSV header line".into()),
            Some((_, line)) => {
                let line = line.map_err(|e| format!("reading input: {e}"))?;
                if !line.trim().is_empty() {
                    break line;
                }
            }
        }
    };
    let names: Vec<String> = header.split(',').map(|s| s.trim().to_string()).collect();
    let positions = columns
        .iter()
        .map(|c| {
            names
                .iter()
                .position(|n| n == c)
                .ok_or_else(|| format!("header lacks column '{c}' (needs {})", columns.join(",")))
        })
        .collect::<Result<Vec<usize>, String>>()?;

    // Load the tables before reading rows, so a missing file fails fast.
    // (`TableSet::open` keeps its maps for the process: one set per run.)
    let open_set = || {
        TableSet::open(tables).map_err(|e| format!("{e} (build the tables with `generator build`)"))
    };
    let (evaluate, outputs): (Evaluator<'_>, &[&str]) = match quantity {
        "g1" => {
            let table = open_set()?.smith;
            (
                Box::new(move |x: &[f64]| {
                    let (p, a) = (x[0], x[1]);
                    let reference = epd::g1(p, a).map_err(|e| format!("reference: {e}"))?;
                    Ok(vec![
                        table.g1(p as f32, a as f32).to_string(),
                        reference.to_string(),
                    ])
                }),
                &["table", "reference"],
            )
        }
        "sigma-ratio" => {
            let table = open_set()?.sigma_ratio;
            (
                Box::new(move |x: &[f64]| {
                    let (theta_i, big_b, c) = (x[0], x[1], x[2]);
                    let reference = kcorr::sigma_ratio(theta_i, big_b, c)
                        .map_err(|e| format!("reference: {e}"))?;
                    Ok(vec![
                        table
                            .sigma_ratio(theta_i as f32, big_b as f32, c as f32)
                            .to_string(),
                        reference.to_string(),
                    ])
                }),
                &["table", "reference"],
            )
        }
        "fresnel" => (
            // No table: `table` is the runtime's f32 Fresnel (computed in f64
            // inside), `reference` the f64 reference.
            Box::new(|x: &[f64]| {
                let (n, k, cos_theta) = (x[0], x[1], x[2]);
                let reference = fresnel::fresnel(fresnel::Complex64::new(n, k), cos_theta)
                    .map_err(|e| format!("reference: {e}"))?;
                let eta = twoscale::Complex::new(n as f32, k as f32);
                Ok(vec![
                    twoscale::fresnel::fresnel(eta, cos_theta as f32).to_string(),
                    reference.to_string(),
                ])
            }),
            &["table", "reference"],
        ),
        "conv" => {
            let table = open_set()?.convolution;
            (
                // `fit` = T3a (the paper's s, g form), `table` = T3b, both
                // from the runtime; `reference` = exact C by direct quadrature.
                Box::new(move |x: &[f64]| {
                    let (u, c, beta, p, theta_h) = (x[0], x[1], x[2], x[3], x[4]);
                    let reference = conv::convolution(theta_h, u, c, beta, p)
                        .map_err(|e| format!("reference: {e}"))?;
                    let (sin, cos) = (theta_h.sin() as f32, theta_h.cos() as f32);
                    let args = (u as f32, c as f32, beta as f32, p as f32);
                    Ok(vec![
                        table
                            .fit()
                            .convolution_sin_cos(sin, cos, args.0, args.1, args.2, args.3)
                            .to_string(),
                        table
                            .convolution_sin_cos(sin, cos, args.0, args.1, args.2, args.3)
                            .to_string(),
                        reference.to_string(),
                    ])
                }),
                &["fit", "table", "reference"],
            )
        }
        "brdf" => {
            // docs/model.md §6: the conductor two-scale model. `table` is the runtime
            // model (`twoscale::brdf::TwoScale`, f32, baked from the table
            // set: the path a renderer calls); `reference` is
            // `reference::brdf::two_scale` (exact Λ, σrel, C).
            let set = open_set()?;
            (
                Box::new(move |x: &[f64]| {
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
                    let options = twoscale::brdf::Options::default();
                    let reference = brdf::two_scale(&params, i, o, &options)
                        .map_err(|e| format!("reference: {e}"))?;
                    let f = |v: f64| v as f32;
                    let layer = twoscale::brdf::Layer {
                        surface: twoscale::brdf::Surface {
                            beta: f(params.beta),
                            p: f(params.p),
                            sigma_s: f(params.sigma_s),
                            b: f(params.b),
                            c: f(params.c),
                        },
                        base: twoscale::brdf::BaseLayer::Conductor,
                        lambertian: 0.0,
                    };
                    let model = twoscale::TwoScale::new(
                        &set.brdf_tables(),
                        layer,
                        f(params.lambda),
                        twoscale::Complex::new(f(params.n), f(params.k)),
                        options,
                    );
                    let table = model.eval(i.map(f), o.map(f));
                    Ok(vec![table.to_string(), reference.total().to_string()])
                }),
                &["table", "reference"],
            )
        }
        _ => unreachable!("quantity list and dispatch agree"),
    };

    let rows: Vec<(usize, String)> = lines
        .map(|(n, line)| (n + 1, line.unwrap_or_default()))
        .filter(|(_, line)| !line.trim().is_empty())
        .collect();
    let results: Vec<Result<String, String>> = rows
        .par_iter()
        .map(|(n, line)| {
            let fields: Vec<&str> = line.split(',').map(str::trim).collect();
            if fields.len() != names.len() {
                return Err(format!(
                    "line {n}: {} fields, header has {}",
                    fields.len(),
                    names.len()
                ));
            }
            let values = positions
                .iter()
                .zip(columns.iter())
                .map(|(&i, c)| {
                    fields[i].parse::<f64>().map_err(|_| {
                        format!("line {n}: column '{c}' is not a number: '{}'", fields[i])
                    })
                })
                .collect::<Result<Vec<f64>, String>>()?;
            if let Some((c, v)) = columns.iter().zip(&values).find(|(_, v)| !v.is_finite()) {
                return Err(format!("line {n}: column '{c}' is not finite: {v}"));
            }
            let out = evaluate(&values).map_err(|e| format!("line {n}: {e}"))?;
            Ok(format!("{},{}", fields.join(","), out.join(",")))
        })
        .collect();

    let io = |e: std::io::Error| format!("writing output: {e}");
    writeln!(output, "{},{}", names.join(","), outputs.join(",")).map_err(io)?;
    let mut summary = Summary::default();
    for result in results {
        match result {
            Ok(row) => {
                writeln!(output, "{row}").map_err(io)?;
                summary.answered += 1;
            }
            Err(message) => {
                writeln!(errors, "{message}").map_err(io)?;
                summary.bad += 1;
            }
        }
    }
    Ok(summary)
}
