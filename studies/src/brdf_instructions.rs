//! Instruction counts of the BRDF's `eval`, `pdf`, `sample` and
//! construction against the GGX baseline of `benches/brdf.rs`, on the same
//! inputs (`suite::cost`), counted by callgrind (docs/design/speed.md).
//!
//! Unlike criterion's times, the counts do not depend on what else the
//! machine is doing, so they can be compared across runs; they do not see
//! latency (a division counts as one instruction), so criterion's ratios
//! remain the figures of record.
//!
//! `studies brdf-instructions` runs itself under `valgrind --tool=callgrind`
//! twice per operation (N and 3N calls) and prints the difference per call.

use crate::common;
use std::fmt::Write as _;
use std::hint::black_box;
use std::path::Path;
use std::process::Command;
use suite::cost::{self, Inputs};
use twoscale::TableSet;
use twoscale::brdf::{BoxedSpectral, ChannelBake, IntegratedRgb, Rgb, Spectral, TwoScale};
use twoscale::material::{BaseLayer, Layer, MultipleScattering, Options};
use twoscale::materials::{self, HP17_NICKEL_SURFACE, PRESETS};

/// The operations, their baselines first.
pub const OPERATIONS: [&str; 15] = [
    "ggx-eval",
    "ggx-eval-rgb",
    "ggx-sample-eval",
    "eval",
    "eval-kulla-conty",
    "eval-t3a",
    "eval-rgb",
    "eval-rgb-integrated",
    "eval-spectral",
    "eval4-spectral",
    "pdf",
    "sample",
    "construct",
    "construct-rgb",
    "construct-spectral",
];

/// One of [`OPERATIONS`], resolved once so that the timed loop matches on
/// an enum rather than comparing strings per call.
#[derive(Clone, Copy)]
enum Operation {
    GgxEval,
    GgxEvalRgb,
    GgxSampleEval,
    Eval,
    EvalKullaConty,
    EvalT3a,
    EvalRgb,
    EvalRgbIntegrated,
    EvalSpectral,
    Eval4Spectral,
    Pdf,
    Sample,
    Construct,
    ConstructRgb,
    ConstructSpectral,
}

impl Operation {
    /// The operation named `name`, or an error listing [`OPERATIONS`].
    fn named(name: &str) -> Result<Self, String> {
        Ok(match name {
            "ggx-eval" => Operation::GgxEval,
            "ggx-eval-rgb" => Operation::GgxEvalRgb,
            "ggx-sample-eval" => Operation::GgxSampleEval,
            "eval" => Operation::Eval,
            "eval-kulla-conty" => Operation::EvalKullaConty,
            "eval-t3a" => Operation::EvalT3a,
            "eval-rgb" => Operation::EvalRgb,
            "eval-rgb-integrated" => Operation::EvalRgbIntegrated,
            "eval-spectral" => Operation::EvalSpectral,
            "eval4-spectral" => Operation::Eval4Spectral,
            "pdf" => Operation::Pdf,
            "sample" => Operation::Sample,
            "construct" => Operation::Construct,
            "construct-rgb" => Operation::ConstructRgb,
            "construct-spectral" => Operation::ConstructSpectral,
            other => {
                return Err(format!(
                    "unknown operation {other}; one of {}",
                    OPERATIONS.join(", ")
                ));
            }
        })
    }
}

/// The models and inputs every operation runs on (the same set-up for every
/// operation and count).
pub struct Workload<'a> {
    set: &'a TableSet<'static>,
    model: TwoScale<'a>,
    /// `model` with the energy-compensation lobe (issue 27).
    model_kc: TwoScale<'a>,
    model_fit: TwoScale<'a>,
    ggx: cost::Ggx,
    rgb: Rgb<'a>,
    rgb_eta: [twoscale::Complex; 3],
    /// The RGB preset by integration over the spectrum (issue 26).
    integrated: IntegratedRgb<'a, Box<ChannelBake>>,
    /// HP17's nickel geometry at any wavelength (the `nickel` preset).
    spectral: BoxedSpectral<'a>,
    inputs: Inputs,
}

impl<'a> Workload<'a> {
    /// The models of `suite::cost` on `set` (and T3a's fit, kept in `fit`).
    pub fn new(
        set: &'a TableSet<'static>,
        fit: &'a twoscale::tables::convolution::ConvFitTable<'static>,
    ) -> Self {
        let (rgb, rgb_eta) = cost::rgb_preset(set);
        Workload {
            set,
            model: cost::nickel(set, &set.convolution),
            model_kc: TwoScale::new(
                &set.brdf_tables(),
                Layer {
                    surface: HP17_NICKEL_SURFACE,
                    base: BaseLayer::Conductor,
                    lambertian: 0.0,
                },
                cost::LAMBDA,
                cost::NICKEL_LIKE,
                Options {
                    multiple_scattering: MultipleScattering::KullaConty,
                    ..Options::default()
                },
            ),
            model_fit: cost::nickel(set, fit),
            ggx: cost::ggx(),
            rgb,
            rgb_eta,
            integrated: IntegratedRgb::boxed(
                &set.brdf_tables(),
                &materials::spectral(cost::RGB_PRESET).expect("preset"),
                Options::default(),
            ),
            spectral: Spectral::boxed(
                &set.brdf_tables(),
                &materials::spectral("nickel").expect("preset"),
                Options::default(),
            ),
            inputs: Inputs::new(),
        }
    }

    /// Runs `calls` calls of `operation` (one of [`OPERATIONS`]), cycling
    /// over the inputs from input `start`.
    pub fn run(&self, operation: &str, start: usize, calls: usize) -> Result<f32, String> {
        let inputs = &self.inputs;
        let n = inputs.pairs.len();
        let (set, model, model_fit, ggx, rgb) =
            (self.set, &self.model, &self.model_fit, &self.ggx, &self.rgb);
        let operation = Operation::named(operation)?;
        let mut sum = 0.0f32;
        for k in start..start + calls {
            let (i, o) = inputs.pairs[k % n];
            let (iu, u) = inputs.uniforms[k % n];
            sum += match operation {
                Operation::GgxEval => ggx.eval(black_box(i), black_box(o)),
                Operation::GgxEvalRgb => ggx.eval_rgb(&self.rgb_eta, black_box(i), black_box(o))[1],
                Operation::GgxSampleEval => ggx
                    .sample_eval(black_box(iu), [u[1], u[2]])
                    .map_or(0.0, |(_, pdf, value)| value / pdf),
                Operation::Eval => model.eval(black_box(i), black_box(o)),
                Operation::EvalKullaConty => self.model_kc.eval(black_box(i), black_box(o)),
                Operation::EvalT3a => model_fit.eval(black_box(i), black_box(o)),
                Operation::EvalRgb => rgb.eval(black_box(i), black_box(o))[1],
                Operation::EvalRgbIntegrated => self.integrated.eval(black_box(i), black_box(o))[1],
                Operation::EvalSpectral => {
                    self.spectral.eval(black_box(i), black_box(o), cost::LAMBDA)
                }
                // The four wavelengths of benches/brdf.rs.
                Operation::Eval4Spectral => {
                    self.spectral
                        .eval4(black_box(i), black_box(o), [0.45, 0.53, 0.61, 0.69])[1]
                }
                Operation::Pdf => model.pdf(black_box(i), black_box(o)),
                Operation::Sample => model
                    .sample(black_box(iu), black_box(u))
                    .map_or(0.0, |s| s.value / s.pdf),
                // One wavelength's model per call (as criterion's `two_scale_new`).
                Operation::Construct => TwoScale::conductor(
                    &set.brdf_tables(),
                    black_box(HP17_NICKEL_SURFACE),
                    cost::LAMBDA,
                    cost::NICKEL_LIKE,
                )
                .eval(i, o),
                Operation::ConstructRgb => Rgb::new(
                    &set.brdf_tables(),
                    black_box(&PRESETS[0].1),
                    Options::default(),
                )
                .eval(i, o)[1],
                // The `nickel` preset at any wavelength (criterion's `spectral_preset`).
                Operation::ConstructSpectral => Spectral::boxed(
                    &set.brdf_tables(),
                    &materials::spectral(black_box("nickel")).expect("preset"),
                    Options::default(),
                )
                .eval(i, o, cost::LAMBDA),
            };
        }
        Ok(black_box(sum))
    }
}

/// The baseline an operation's ratio is taken against (empty: none):
/// eval-rgb against the RGB GGX eval, sample against GGX's visible-normal
/// sample + eval, eval with the compensation lobe against eval without, the
/// other BRDF operations against the GGX eval.
fn baseline(operation: &str) -> &'static str {
    match operation {
        "eval-rgb" => "ggx-eval-rgb",
        "eval-rgb-integrated" => "eval-rgb",
        "eval-spectral" | "eval4-spectral" => "eval",
        "sample" => "ggx-sample-eval",
        "eval-kulla-conty" => "eval",
        _ if operation.starts_with("ggx") || operation.starts_with("construct") => "",
        _ => "ggx-eval",
    }
}

/// Calls per timed batch or counted run: construction is ~10⁴× an eval.
fn calls_of(operation: &str, calls: usize) -> usize {
    if operation.starts_with("construct") {
        (calls / 1000).max(3)
    } else {
        calls
    }
}

/// Runs `calls` calls of `operation` (what the report runs under callgrind).
pub fn run_calls(operation: &str, calls: usize) -> Result<(), String> {
    let set = TableSet::embedded();
    let fit = set.convolution.fit();
    Workload::new(&set, &fit).run(operation, 0, calls).map(drop)
}

/// Wall time per call of every operation, interleaved: each of `rounds`
/// rounds times one batch of `batch` calls of every operation in turn, so a
/// change of the machine's load hits all operations alike. Prints the
/// minimum and median over the rounds (ns per call) and the ratios of the
/// minima to the baselines: the minimum is the run least disturbed by other
/// processes, which on a shared machine only ever add time.
pub fn timing(rounds: usize, batch: usize) -> Result<(), String> {
    let set = TableSet::embedded();
    let fit = set.convolution.fit();
    let work = Workload::new(&set, &fit);
    let mut times: Vec<Vec<f64>> = vec![Vec::with_capacity(rounds); OPERATIONS.len()];
    for round in 0..rounds {
        for (k, op) in OPERATIONS.iter().enumerate() {
            let n = calls_of(op, batch);
            let start = std::time::Instant::now();
            work.run(op, round * n, n)?;
            times[k].push(start.elapsed().as_secs_f64() * 1e9 / n as f64);
        }
    }
    let stats: Vec<(f64, f64)> = times
        .iter_mut()
        .map(|t| {
            t.sort_by(f64::total_cmp);
            (t[0], t[t.len() / 2])
        })
        .collect();
    let min_of = |name: &str| {
        OPERATIONS
            .iter()
            .position(|op| *op == name)
            .map_or(f64::NAN, |k| stats[k].0)
    };
    println!("| operation | min ns per call | median | min ratio | against |");
    println!("|---|---|---|---|---|");
    for (op, &(min, median)) in OPERATIONS.iter().zip(&stats) {
        let against = baseline(op);
        let ratio = if against.is_empty() {
            String::new()
        } else {
            format!("{:.2}×", min / min_of(against))
        };
        println!("| {op} | {min:.1} | {median:.1} | {ratio} | {against} |");
    }
    Ok(())
}

/// Instructions of `studies brdf-instructions --operation <op> --calls <n>`
/// under callgrind (the `Collected` line of its summary).
fn instructions(operation: &str, calls: usize) -> Result<u64, String> {
    let exe = std::env::current_exe().map_err(|e| format!("cannot find this program: {e}"))?;
    let output = Command::new("valgrind")
        .args(["--tool=callgrind", "--callgrind-out-file=/dev/null"])
        .arg(&exe)
        .args(["brdf-instructions", "--operation", operation, "--calls"])
        .arg(calls.to_string())
        .output()
        .map_err(|e| format!("cannot run valgrind (apt-get install valgrind): {e}"))?;
    let log = String::from_utf8_lossy(&output.stderr);
    if !output.status.success() {
        return Err(format!("{operation} under callgrind failed:\n{log}"));
    }
    log.lines()
        .find_map(|line| line.split("Collected :").nth(1))
        .and_then(|n| n.trim().parse().ok())
        .ok_or_else(|| format!("no instruction count in callgrind's output:\n{log}"))
}

/// Prints instructions per call of every operation and their ratios to the
/// baselines (eval-rgb to the RGB GGX eval, sample to GGX's visible-normal
/// sample + eval, the rest to the GGX eval), and writes the table to
/// `markdown` when given.
pub fn report(calls: usize, markdown: Option<&Path>) -> Result<(), String> {
    common::check_markdown(markdown)?;
    let mut per_call = Vec::new();
    for op in OPERATIONS {
        let n = calls_of(op, calls);
        let (low, high) = (instructions(op, n)?, instructions(op, 3 * n)?);
        let count = high.saturating_sub(low) as f64 / (2 * n) as f64;
        eprintln!("{op}: {count:.0} instructions per call");
        per_call.push((op, count));
    }
    let of = |name: &str| {
        per_call
            .iter()
            .find(|(n, _)| *n == name)
            .map_or(f64::NAN, |x| x.1)
    };
    let mut out = String::from(
        "| operation | instructions per call | ratio | against |\n|---|---|---|---|\n",
    );
    for &(op, count) in &per_call {
        let baseline = baseline(op);
        if baseline.is_empty() {
            let _ = writeln!(out, "| {op} | {count:.0} | | |");
        } else {
            let _ = writeln!(
                out,
                "| {op} | {count:.0} | {:.2}× | {baseline} |",
                count / of(baseline)
            );
        }
    }
    print!("{out}");
    match markdown {
        Some(path) => common::write_markdown(
            path,
            "Instructions per call of the BRDF's operations",
            &format!("brdf-instructions --calls {calls}"),
            &format!(
                "Counted by callgrind on the release build: each operation run N and 3N \
                 times (N = {calls}; construction N/1000, at least 3), the difference \
                 over 2N. The workload is `benches/brdf.rs`'s (`suite::cost`): HP17's \
                 nickel geometry at 0.526 µm, the `gold-hp17-geometry` preset for RGB, \
                 the `nickel` preset for the spectral model. Instruction counts do not \
                 depend on the machine's load but do on the compiler; they do not see \
                 latency (times: `studies brdf-timing`, docs/design/speed.md).\n\n{out}"
            ),
        ),
        None => Ok(()),
    }
}
