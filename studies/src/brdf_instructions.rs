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

use std::hint::black_box;
use std::process::Command;
use suite::cost::{self, Inputs};
use twoscale::TableSet;
use twoscale::brdf::{Options, Rgb, TwoScale};
use twoscale::materials::{HP17_NICKEL_SURFACE, PRESETS};

/// The operations, their baselines first.
pub const OPERATIONS: [&str; 10] = [
    "ggx-eval",
    "ggx-eval-rgb",
    "ggx-sample-eval",
    "eval",
    "eval-t3a",
    "eval-rgb",
    "pdf",
    "sample",
    "construct",
    "construct-rgb",
];

/// Runs `calls` calls of `operation` (one of [`OPERATIONS`]), cycling over
/// the inputs; the set-up is the same for every operation and count.
pub fn run_calls(operation: &str, calls: usize) -> Result<(), String> {
    let set = TableSet::embedded();
    let model = cost::nickel(&set, &set.convolution);
    let fit = set.convolution.fit();
    let model_fit = cost::nickel(&set, &fit);
    let ggx = cost::ggx();
    let (rgb, rgb_eta) = cost::rgb_preset(&set);
    let inputs = Inputs::new();
    let n = inputs.pairs.len();
    let mut sum = 0.0f32;
    for k in 0..calls {
        let (i, o) = inputs.pairs[k % n];
        let (iu, u) = inputs.uniforms[k % n];
        sum += match operation {
            "ggx-eval" => ggx.eval(black_box(i), black_box(o)),
            "ggx-eval-rgb" => ggx.eval_rgb(&rgb_eta, black_box(i), black_box(o))[1],
            "ggx-sample-eval" => ggx
                .sample_eval(black_box(iu), [u[1], u[2]])
                .map_or(0.0, |(_, pdf, value)| value / pdf),
            "eval" => model.eval(black_box(i), black_box(o)),
            "eval-t3a" => model_fit.eval(black_box(i), black_box(o)),
            "eval-rgb" => rgb.eval(black_box(i), black_box(o))[1],
            "pdf" => model.pdf(black_box(i), black_box(o)),
            "sample" => model
                .sample(black_box(iu), black_box(u))
                .map_or(0.0, |s| s.value / s.pdf),
            // One wavelength's model per call (as criterion's `two_scale_new`).
            "construct" => TwoScale::conductor(
                &set.brdf_tables(),
                black_box(HP17_NICKEL_SURFACE),
                cost::LAMBDA,
                cost::NICKEL_LIKE,
            )
            .eval(i, o),
            "construct-rgb" => Rgb::new(
                &set.brdf_tables(),
                black_box(&PRESETS[0].1),
                Options::default(),
            )
            .eval(i, o)[1],
            other => {
                return Err(format!(
                    "unknown operation {other}; one of {}",
                    OPERATIONS.join(", ")
                ));
            }
        };
    }
    black_box(sum);
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
/// sample + eval, the rest to the GGX eval).
pub fn report(calls: usize) -> Result<(), String> {
    let mut per_call = Vec::new();
    for op in OPERATIONS {
        // Construction is ~10⁴× an eval: fewer calls.
        let n = if op.starts_with("construct") {
            (calls / 1000).max(3)
        } else {
            calls
        };
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
    println!("| operation | instructions per call | ratio | against |");
    println!("|---|---|---|---|");
    for &(op, count) in &per_call {
        let baseline = match op {
            "eval-rgb" => "ggx-eval-rgb",
            "sample" => "ggx-sample-eval",
            _ if op.starts_with("ggx") || op.starts_with("construct") => "",
            _ => "ggx-eval",
        };
        if baseline.is_empty() {
            println!("| {op} | {count:.0} | | |");
        } else {
            println!(
                "| {op} | {count:.0} | {:.2}× | {baseline} |",
                count / of(baseline)
            );
        }
    }
    Ok(())
}
