//! What the T3 studies share: exact profiles, the committed table, the two
//! parameter distributions, and error summaries.

use generator::tables::convolution;
use generator::tables::sh_brdf::WORKSPACE_TABLES;
use std::path::Path;
use twoscale::tables::format::{AlignedBuf, AxisHeader, TableId};
use twoscale::tables::interp::Axis;
use twoscale_reference::reference::conv::{Params, ProfileRule, convolution_profile, e_l2_on};
use twoscale_reference::rng::SplitMix64;

/// T3's parameter axes `(u, c, β, p)`, as the generator builds them.
pub const AXES: [AxisHeader; 4] = [
    convolution::U_AXIS,
    convolution::C_AXIS,
    convolution::BETA_AXIS,
    convolution::P_AXIS,
];

/// Gauss nodes per interval of the studies' profile rule (half the metric's
/// 16: the metric does not change, and the reference costs half).
pub const ORDER: usize = 8;

/// The committed T3 file, copied to aligned memory.
pub fn committed_t3() -> AlignedBuf {
    let path = Path::new(WORKSPACE_TABLES).join(generator::tables::file_name(TableId::Convolution));
    let bytes = std::fs::read(&path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    twoscale::tables::format::aligned_copy(&bytes)
}

/// The runtime's cell of `x` on axis `d` of [`AXES`] (clamped to the axis).
pub fn cell(d: usize, x: f64) -> (usize, f32) {
    cell_on(&AXES[d], x)
}

/// The runtime's cell of `x` on the axis `header` (clamped to the axis).
pub fn cell_on(header: &AxisHeader, x: f64) -> (usize, f32) {
    Axis::new(header).expect("valid T3 axis").locate(x as f32)
}

/// [`AXES`] with the node counts `nodes` (u, c, β, p; 0 keeps the table's).
pub fn axes_with_nodes(nodes: [u32; 4]) -> [AxisHeader; 4] {
    let mut axes = AXES;
    for (axis, &n) in axes.iter_mut().zip(&nodes) {
        if n > 0 {
            axis.nodes = n;
        }
    }
    axes
}

/// [`axes_with_nodes`] with the u axis even in `ln(u + u_offset)`, the c
/// axis even in `ln(c − 1) + c_linear · c` and the p axis even in
/// `p^p_power` where given (the nodes' placement).
pub fn axes_with(
    nodes: [u32; 4],
    u_offset: Option<f64>,
    c_linear: Option<f64>,
    p_power: Option<f64>,
) -> [AxisHeader; 4] {
    let mut axes = axes_with_nodes(nodes);
    if let Some(power) = p_power {
        axes[3].param = power;
    }
    if let Some(offset) = u_offset {
        axes[0].param = offset;
    }
    if let Some(linear) = c_linear {
        axes[1].param2 = linear;
    }
    axes
}

/// `u,c,beta,p` points from a CSV file with a header line.
pub fn read_points(path: &Path) -> Result<Vec<[f64; 4]>, String> {
    let text = std::fs::read_to_string(path).map_err(|e| format!("{}: {e}", path.display()))?;
    Ok(text
        .lines()
        .skip(1)
        .filter_map(|l| {
            let v: Vec<f64> = l.split(',').filter_map(|x| x.trim().parse().ok()).collect();
            (v.len() >= 4).then(|| [v[0], v[1], v[2], v[3]])
        })
        .collect())
}

/// An exact profile: `C` on the nodes of the studies' profile rule, and `C(0)`.
pub struct Exact {
    /// `(u, c, β, p)`.
    pub point: [f64; 4],
    /// The rule (the metric's intervals, [`ORDER`] nodes each).
    pub rule: ProfileRule,
    /// `C` at the rule's nodes.
    pub values: Vec<f64>,
    /// `C(0)`.
    pub c0: f64,
}

impl Exact {
    /// Computes the profile at `point` with the reference.
    pub fn new(point: [f64; 4]) -> Exact {
        let [u, c, beta, p] = point;
        let params = Params::new(u, c, beta, p).expect("point inside T3's domain");
        let rule = ProfileRule::with_order(ProfileRule::width_for(&params), ORDER);
        let values = exact_c(point, &rule.nodes);
        let c0 = exact_c(point, &[0.0])[0];
        Exact {
            point,
            rule,
            values,
            c0,
        }
    }

    /// e_L2 (`reference::conv::e_l2_on`) of values `approx` given at the
    /// rule's nodes.
    pub fn e_l2(&self, approx: &[f64]) -> f64 {
        let nodes = &self.rule.nodes;
        e_l2_on(
            &self.rule,
            |t| approx[nodes.partition_point(|&x| x < t).min(approx.len() - 1)],
            &self.values,
        )
    }

    /// Relative energy error `|∫(C̃ − C) sin θh cos θh| / ∫ C sin θh cos θh`
    /// of values `approx` at the rule's nodes (as `generator verify`).
    pub fn energy(&self, approx: &[f64]) -> f64 {
        let (mut diff, mut total) = (0.0, 0.0);
        for (((&t, &w), &e), &a) in self
            .rule
            .nodes
            .iter()
            .zip(&self.rule.weights)
            .zip(&self.values)
            .zip(approx)
        {
            diff += w * t.cos() * (a - e);
            total += w * t.cos() * e;
        }
        (diff / total).abs()
    }

    /// Relative errors of `approx` (at the rule's nodes) split into the core
    /// (`C > 1e-3 C(0)`) and the tail (`1e-9 C(0) < C ≤ 1e-3 C(0)`), appended.
    pub fn pointwise(&self, approx: &[f64], core: &mut Vec<f64>, tail: &mut Vec<f64>) {
        for (a, &x) in approx.iter().zip(&self.values) {
            let rel = ((a - x) / x).abs();
            if x > 1e-3 * self.c0 {
                core.push(rel);
            } else if x > 1e-9 * self.c0 {
                tail.push(rel);
            }
        }
    }
}

/// Exact `C` at the angles `thetas` (the reference).
pub fn exact_c([u, c, beta, p]: [f64; 4], thetas: &[f64]) -> Vec<f64> {
    convolution_profile(u, c, beta, p, thetas).expect("reference converges in T3's domain")
}

/// `ln C` floored as the table stores it (`VALUE_FLOOR` times the peak).
pub fn floored_ln(values: &[f64]) -> Vec<f64> {
    let peak = values.iter().copied().fold(0.0f64, f64::max);
    values
        .iter()
        .map(|&x| x.max(convolution::VALUE_FLOOR * peak).ln())
        .collect()
}

/// Which parameter points a study draws.
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub enum Distribution {
    /// `generator verify`'s: uniform in the mapped coordinates of the whole
    /// T3 domain (`convolution::verification_points`).
    Verify,
    /// The BRDF check's (`tests/independent/brdf_scipy.py`): u log-uniform in
    /// [0.5, 50], c uniform in [1.2, 6], β log-uniform in [0.05, 1], p
    /// uniform in [0.5, 5].
    Brdf,
}

impl Distribution {
    /// `count` points of the distribution from `seed`.
    pub fn points(self, count: usize, seed: u64) -> Vec<[f64; 4]> {
        match self {
            Distribution::Verify => convolution::verification_points(count, seed),
            Distribution::Brdf => {
                let mut rng = SplitMix64::new(seed);
                (0..count)
                    .map(|_| {
                        let u = rng.log_uniform_in(0.5, 50.0);
                        let c = rng.uniform_in(1.2, 6.0);
                        let beta = rng.log_uniform_in(0.05, 1.0);
                        let p = rng.uniform_in(0.5, 5.0);
                        [u, c, beta, p]
                    })
                    .collect()
            }
        }
    }
}

/// The `q` quantile of `v` (sorted in place; NaN when empty), with the
/// rounding of `tables::Accuracy`.
pub fn quantile(v: &mut [f64], q: f64) -> f64 {
    if v.is_empty() {
        return f64::NAN;
    }
    v.sort_by(f64::total_cmp);
    v[((v.len() - 1) as f64 * q).round() as usize]
}

/// The `qs` quantiles of `v` as percentages, space-separated.
pub fn percentiles(v: &mut [f64], qs: &[f64]) -> String {
    let cells: Vec<String> = qs
        .iter()
        .map(|&q| format!("{:.2}%", 100.0 * quantile(v, q)))
        .collect();
    cells.join(" ")
}

/// Fails early, before a study's work, when `path` (its `--markdown` file)
/// could not be written: its directory does not exist.
pub fn check_markdown(path: Option<&Path>) -> Result<(), String> {
    let Some(path) = path else { return Ok(()) };
    let dir = match path.parent() {
        Some(dir) if !dir.as_os_str().is_empty() => dir,
        _ => Path::new("."),
    };
    if dir.is_dir() {
        Ok(())
    } else {
        Err(format!(
            "{}: no directory {}",
            path.display(),
            dir.display()
        ))
    }
}

/// Writes a study's tables `body` (markdown) to `path` under `title` and the
/// command that regenerates the file, `studies COMMAND --markdown PATH`, as
/// `generator verify --markdown` writes docs/accuracy.md: the figures of a
/// record live in a generated file under docs/figures/ instead of the
/// record's text.
pub fn write_markdown(path: &Path, title: &str, command: &str, body: &str) -> Result<(), String> {
    let text = format!(
        "# {title}\n\nWritten by `cargo run --release -p studies -- {command} --markdown {}` \
         (do not edit: rerun the command).\n\n{body}",
        path.display()
    );
    std::fs::write(path, text).map_err(|e| format!("{}: {e}", path.display()))
}
