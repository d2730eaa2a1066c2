//! The direct quadrature of the T3 build (docs/design/t3-build-speed.md, passes 2–4):
//! for every `stride`-th node that the build computes by direct quadrature,
//! the 32 angles by [`convolution_direct`] (default options), with the lobe
//! evaluations (`DirectResult::evaluations`, a load-independent cost figure)
//! and the CPU time. `--save FILE` writes the values (exact f64 bits),
//! `--compare FILE` reports the largest relative difference to a saved run
//! (same stride): the agreement of a changed quadrature with the old one on
//! real T3 nodes, every angle.

use generator::tables::convolution::{
    angle_rule, node_count, node_params, node_tries_zonal_harmonics,
};
use rayon::prelude::*;
use std::path::Path;
use std::time::Instant;
use twoscale_reference::reference::conv::{DirectOptions, convolution_direct};

/// One direct node: index, evaluations, seconds, values.
type NodeRun = (usize, usize, f64, Vec<f64>);

/// Runs the sample (see the module documentation).
pub fn run(stride: usize, save: Option<&Path>, compare: Option<&Path>) -> Result<(), String> {
    let stride = stride.max(1);
    let nodes: Vec<usize> = (0..node_count())
        .step_by(stride)
        .filter(|&i| !node_tries_zonal_harmonics(i))
        .collect();
    let opts = DirectOptions::default();
    let start = Instant::now();
    let runs: Vec<NodeRun> = nodes
        .par_iter()
        .map(|&i| {
            let [u, c, beta, p] = node_params(i);
            let (thetas, _) = angle_rule(u, beta, p);
            let t0 = Instant::now();
            let mut evaluations = 0;
            let values = thetas
                .iter()
                .map(|&t| {
                    let r = convolution_direct(t, u, c, beta, p, &opts).expect("direct");
                    evaluations += r.evaluations;
                    r.value
                })
                .collect();
            (i, evaluations, t0.elapsed().as_secs_f64(), values)
        })
        .collect();
    let wall = start.elapsed().as_secs_f64();
    println!("index,u,c,beta,p,evaluations,seconds");
    for (i, e, s, _) in &runs {
        let [u, c, beta, p] = node_params(*i);
        println!("{i},{u},{c},{beta},{p},{e},{s:.4}");
    }
    let mut evals: Vec<usize> = runs.iter().map(|r| r.1).collect();
    evals.sort_unstable();
    let n = evals.len().max(1);
    let sum: usize = evals.iter().sum();
    let secs: f64 = runs.iter().map(|r| r.2).sum();
    eprintln!(
        "{} direct nodes (stride {stride}): evaluations per node mean {:.0}, median {}, \
         max {}; node time sum {secs:.1} s (mean {:.3} s), wall {wall:.1} s",
        runs.len(),
        sum as f64 / n as f64,
        evals.get(n / 2).copied().unwrap_or(0),
        evals.last().copied().unwrap_or(0),
        secs / n as f64,
    );
    if let Some(path) = save {
        let text: String = runs
            .iter()
            .map(|(i, _, _, v)| {
                let bits: Vec<String> = v.iter().map(|x| format!("{:016x}", x.to_bits())).collect();
                format!("{i} {}\n", bits.join(" "))
            })
            .collect();
        std::fs::write(path, text).map_err(|e| format!("{}: {e}", path.display()))?;
    }
    if let Some(path) = compare {
        let text = std::fs::read_to_string(path).map_err(|e| format!("{}: {e}", path.display()))?;
        let mut worst = (0.0f64, 0usize, 0usize);
        let mut compared = 0;
        for line in text.lines() {
            let mut it = line.split_whitespace();
            let i: usize = it.next().and_then(|s| s.parse().ok()).ok_or("bad line")?;
            let old: Vec<f64> = it
                .map(|s| u64::from_str_radix(s, 16).map(f64::from_bits))
                .collect::<Result<_, _>>()
                .map_err(|e| e.to_string())?;
            let Some(run) = runs.iter().find(|r| r.0 == i) else {
                return Err(format!("node {i} not in this sample"));
            };
            let peak = old.iter().fold(0.0f64, |m, &x| m.max(x));
            for (k, (a, b)) in old.iter().zip(&run.3).enumerate() {
                // Relative, with the floor of the reference's target (1e-12 of the peak).
                let d = (a - b).abs() / a.abs().max(1e-12 * peak);
                compared += 1;
                if d > worst.0 {
                    worst = (d, i, k);
                }
            }
        }
        eprintln!(
            "compared {compared} values: max relative difference {:.3e} (node {}, angle {})",
            worst.0, worst.1, worst.2
        );
    }
    Ok(())
}
