//! Design study for table T3 (SPEC §2.5, §3): the convolution `C(θh; u, c, β, p)`
//! of the diffraction lobe with the EPD NDF, its compact form
//! `s · k(2 g sin θh)` (HP17 39–41, "T3a") and a more accurate representation
//! ("T3b").
//!
//! ```text
//! cargo run --release -p generator --example t3_study -- <subcommand> [args]
//! ```
//!
//! | subcommand | what it does |
//! |---|---|
//! | `compute SET [SECS]` | computes the exact profiles of a point set (`sample`, `sweep-u`, `sweep-c`, `sweep-beta`, `sweep-p`, `sweep-sim`, `cells-A`, `cells-B`; see `point_set`) for at most `SECS` seconds (default 240), appending them to the cache; run again to continue |
//! | `status` | how many profiles of each set are cached, and their cost |
//! | `rule-check` | the fits on the 8-point rule against the 16-point rule of SPEC's metric, and the accuracy of `Exact::at` (recomputes 18 profiles) |
//! | `fits` | the compact forms at the `sample` points: e_L2 and energy error distributions, worst points |
//! | `sweeps` | fitted `s`, `g` along the 1-D sweeps (the curves behind "g ≈ u" and the plateau) |
//! | `show SET K` | one cached profile with its fits (debugging aid) |
//! | `t3a-axes [ls\|mom]` | T3a node counts per axis and mapping: e_L2 of the interpolated form against the fitted form along the sweeps |
//! | `t3b-angle [vars\|scales\|cubic\|mixed\|final]` | T3b's angular axis: error of families of representations at the `sample` points (no parameter interpolation) |
//! | `t3b-axes [--param-only] [--param-cubic] REPR…` | T3b node counts per parameter axis along the sweeps (see `parse_repr` for `REPR`) |
//! | `cells A\|B REPR…` | the 4-D check: at 24 random points, quadrilinear lookups of T3a and T3b from the 16 corners of the grid cell, against the fitted form and exact `C` |
//! | `timing A\|B` | cost of the reference profiles at the grid nodes, and the build time it implies |
//!
//! # What was measured (summary; the report has the tables)
//!
//! * The paper's form fitted by least squares in the e_L2 metric: e_L2 median
//!   0.22, p90 0.39, max 0.99 (where `C` rises towards grazing the best lobe
//!   is a constant, `g → 0`). With a `cos²θh` factor: median 0.036 but max 1.
//! * Quadrilinear (ln s, ln(g² + 0.09)) on a 20 160-node grid adds e_L2
//!   median 2.3%, max 11% against the fitted form; on 184 320 nodes median
//!   0.5%, max 4.3%. The SPEC target (≤ 1%) needs ≈ 100 nodes along `u` and
//!   more than 100 along `β` and `p` where the fit degenerates.
//! * T3b, `ln(C / K^α)` on the angular variable `Var::Mixed` with monotone
//!   cubic interpolation along it: 48–64 angular nodes give max e_L2
//!   1.5–1.9% at the sample points without parameter interpolation; with it,
//!   e_L2 median 3.6% / max 23% on 20 160 nodes and 0.7% / 9.8% on 184 320
//!   nodes.
//!
//! Everything is deterministic (fixed seeds, no warm starts) and
//! single-threaded: the study is meant to run next to other jobs.
//!
//! # The exact profiles
//!
//! `C` at one parameter point is computed by
//! `convolution_profile` on the nodes of
//! `ProfileRule::with_order(width, 8)`: the intervals of the SPEC error
//! metric's rule (graded to the profile's width at 0 and towards the horizon)
//! with 8 instead of 16 Gauss–Legendre nodes each, which halves the cost of
//! the direct quadrature (`rule-check` measures that the metric does not
//! change). Between the nodes of one interval, `C` is evaluated by barycentric
//! interpolation on that interval's Gauss nodes (`Exact::at`); this gives
//! `C` at the angular nodes of a candidate T3b layout without new reference
//! computations (accuracy measured by `rule-check`).
//!
//! The cache is plain text, one profile per line, in
//! `$T3_STUDY_CACHE` (default `$CARGO_TARGET_DIR/t3-study-cache`, else
//! `target/t3-study-cache`): `u c beta p order method seconds v_0 … v_n`
//! with every number in Rust's shortest round-trip form.

use generator::fit::{
    WidthFit, WidthFitOptions, fit_k_lobe, fit_k_lobe_moments, fit_scale_width, k_lobe,
    minimize_scan_golden,
};
use generator::reference::conv::{Method, Params, ProfileRule, convolution_profile_with_method};
use generator::rng::SplitMix64;
use std::collections::HashMap;
use std::f64::consts::FRAC_PI_2;
use std::fs;
use std::io::Write;
use std::path::PathBuf;
use std::time::Instant;
use twoscale::format::{AxisHeader, Mapping};
use twoscale::interp::{coordinate_f64, inverse_coordinate_f64};

// ---------------------------------------------------------------------------
// Domain and point sets
// ---------------------------------------------------------------------------

/// The T3 domain of SPEC §3.
const U_MAX: f64 = 3000.0;
const C_LO: f64 = 1.01;
const C_HI: f64 = 10.0;
const BETA_LO: f64 = 0.002;
const BETA_HI: f64 = 1.0;
const P_LO: f64 = 0.2;
const P_HI: f64 = 5.0;

/// Gauss nodes per interval of the study's profile rule.
const ORDER: usize = 8;

/// One parameter point `(u, c, β, p)`.
#[derive(Clone, Copy, Debug, PartialEq)]
struct Pt {
    u: f64,
    c: f64,
    beta: f64,
    p: f64,
}

impl Pt {
    fn new(u: f64, c: f64, beta: f64, p: f64) -> Self {
        Pt { u, c, beta, p }
    }

    /// The cache key: the exact bit patterns.
    fn key(&self) -> [u64; 4] {
        [self.u, self.c, self.beta, self.p].map(f64::to_bits)
    }

    /// The value of one axis (0 = u, 1 = c, 2 = β, 3 = p).
    fn axis(&self, a: usize) -> f64 {
        [self.u, self.c, self.beta, self.p][a]
    }

    fn with_axis(mut self, a: usize, x: f64) -> Self {
        match a {
            0 => self.u = x,
            1 => self.c = x,
            2 => self.beta = x,
            _ => self.p = x,
        }
        self
    }
}

impl std::fmt::Display for Pt {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(
            f,
            "u={:<8.4} c={:<6.3} β={:<7.4} p={:<6.3}",
            self.u, self.c, self.beta, self.p
        )
    }
}

/// Names of the axes.
const AXES: [&str; 4] = ["u", "c", "beta", "p"];

/// `n` values geometrically spaced from `lo` to `hi` inclusive.
fn geom(lo: f64, hi: f64, n: usize) -> Vec<f64> {
    (0..n)
        .map(|i| {
            if i + 1 == n {
                hi
            } else {
                (lo.ln() + (hi / lo).ln() * i as f64 / (n - 1) as f64).exp()
            }
        })
        .collect()
}

/// The base points of the 1-D sweeps: corners and middles of the domain,
/// including the cases the reference documents as hard (wide β with small
/// p: C rises towards grazing; narrow β with p = 5: steep tails).
fn sweep_bases(axis: usize) -> Vec<Pt> {
    let u_bases = [0.0, 0.3, 30.0, 3000.0];
    // (c, β, p) combinations swept along u; the u sweep uses them directly.
    let cbp = [
        (2.0, 0.05, 1.0),
        (1.01, 0.002, 0.2),
        (10.0, 0.002, 5.0),
        (3.0, 0.3, 0.5),
        (1.5, 1.0, 0.2),
        (10.0, 1.0, 5.0),
        (1.2, 0.02, 2.0),
    ];
    let mut out = Vec::new();
    match axis {
        0 => {
            for &(c, b, p) in &cbp {
                out.push(Pt::new(0.0, c, b, p));
            }
        }
        _ => {
            // Other axes: 4 combinations of the remaining two parameters at
            // three values of u.
            for &u in &u_bases[1..] {
                for &(c, b, p) in &[
                    (2.0, 0.05, 1.0),
                    (1.01, 0.002, 0.2),
                    (10.0, 1.0, 5.0),
                    (3.0, 0.3, 0.5),
                ] {
                    out.push(Pt::new(u, c, b, p));
                }
            }
        }
    }
    out
}

/// The values of one axis visited by the 1-D sweeps (dense, so that the
/// fitted parameters can be interpolated by cubics between them).
fn sweep_values(axis: usize) -> Vec<f64> {
    match axis {
        // u = 0, then 8 per decade from 1e-4 to 3000.
        0 => {
            let mut v = vec![0.0];
            v.extend(geom(1e-4, U_MAX, 61));
            v
        }
        // c − 1 geometric from 0.01 to 9.
        1 => geom(C_LO - 1.0, C_HI - 1.0, 25)
            .into_iter()
            .map(|x| x + 1.0)
            .collect(),
        2 => geom(BETA_LO, BETA_HI, 28),
        _ => geom(P_LO, P_HI, 29),
    }
}

/// The named point sets.
///
/// * `sample`: the 80 corners `u ∈ {0, 1e-3, 1, 30, 3000}` ×
///   `c ∈ {1.01, 10}` × `β ∈ {0.002, 1}` × `p ∈ {0.2, 5}`, then 320 random
///   points (seed 0x7353): `u = 0` with probability 5%, otherwise
///   log-uniform in `[1e-4, 3000]`; `c`, `β`, `p` log-uniform.
/// * `sweep-u`, `sweep-c`, `sweep-beta`, `sweep-p`: [`sweep_values`] along
///   one axis from each of [`sweep_bases`].
/// * `cells-LAYOUT`: see [`cell_points`].
fn point_set(name: &str) -> Option<Vec<Pt>> {
    match name {
        "sample" => Some(sample_points()),
        _ if name.starts_with("cells-") => {
            let layout = layout(&name["cells-".len()..])?;
            Some(
                cell_points(&layout)
                    .into_iter()
                    .flat_map(|c| c.all_points())
                    .collect(),
            )
        }
        "sweep-sim" => Some(sim_groups().into_iter().flatten().collect()),
        _ => {
            let axis = AXES
                .iter()
                .position(|a| name.strip_prefix("sweep-") == Some(*a))?;
            let mut out = Vec::new();
            for base in sweep_bases(axis) {
                for x in sweep_values(axis) {
                    out.push(base.with_axis(axis, x));
                }
            }
            Some(out)
        }
    }
}

/// The sweeps along β at a fixed *similarity variable* `x = u · w_D(β, p)`
/// (the kernel's parameter in units of the NDF's width,
/// [`Params::ndf_width`]), for `x ∈ {0.03, 0.3, 3, 30}` and four `(c, p)`;
/// points with `u > 3000` are left out. Along such a sweep the two lobes keep
/// their width ratio, so the profile's shape (in a normalised angle) changes
/// only through the curvature of the sphere.
fn sim_groups() -> Vec<Vec<Pt>> {
    let mut out = Vec::new();
    for &x in &[0.03, 0.3, 3.0, 30.0] {
        for &(c, p) in &[(2.0, 1.0), (10.0, 5.0), (1.01, 0.2), (3.0, 0.5)] {
            let g: Vec<Pt> = geom(BETA_LO, BETA_HI, 28)
                .into_iter()
                .filter_map(|b| {
                    let w = Params::new(1.0, c, b, p).ok()?.ndf_width();
                    let u = x / w;
                    (u <= U_MAX).then_some(Pt::new(u, c, b, p))
                })
                .collect();
            if g.len() >= 6 {
                out.push(g);
            }
        }
    }
    out
}

fn sample_points() -> Vec<Pt> {
    let mut out = Vec::new();
    for &u in &[0.0, 1e-3, 1.0, 30.0, U_MAX] {
        for &c in &[C_LO, C_HI] {
            for &b in &[BETA_LO, BETA_HI] {
                for &p in &[P_LO, P_HI] {
                    out.push(Pt::new(u, c, b, p));
                }
            }
        }
    }
    let mut rng = SplitMix64::new(0x7353);
    for _ in 0..320 {
        let u = if rng.uniform() < 0.05 {
            0.0
        } else {
            rng.log_uniform_in(1e-4, U_MAX)
        };
        let c = rng.log_uniform_in(C_LO, C_HI);
        let b = rng.log_uniform_in(BETA_LO, BETA_HI);
        let p = rng.log_uniform_in(P_LO, P_HI);
        out.push(Pt::new(u, c, b, p));
    }
    out
}

// ---------------------------------------------------------------------------
// Cache of exact profiles
// ---------------------------------------------------------------------------

fn cache_dir() -> PathBuf {
    if let Ok(d) = std::env::var("T3_STUDY_CACHE") {
        return PathBuf::from(d);
    }
    let target = std::env::var("CARGO_TARGET_DIR").unwrap_or_else(|_| "target".into());
    PathBuf::from(target).join("t3-study-cache")
}

/// One cached exact profile.
#[derive(Clone, Debug)]
struct Cached {
    order: usize,
    method: String,
    seconds: f64,
    /// `None` when the reference failed (the message is in `method`).
    values: Option<Vec<f64>>,
}

/// Reads the cache file of a set (missing file: empty).
fn load_cache(set: &str) -> HashMap<[u64; 4], Cached> {
    let path = cache_dir().join(format!("{set}.txt"));
    let mut out = HashMap::new();
    let Ok(text) = fs::read_to_string(&path) else {
        return out;
    };
    for line in text.lines() {
        let f: Vec<&str> = line.split(' ').collect();
        if f.len() < 7 {
            continue;
        }
        let num = |i: usize| f[i].parse::<f64>().ok();
        let (Some(u), Some(c), Some(b), Some(p)) = (num(0), num(1), num(2), num(3)) else {
            continue;
        };
        let order = f[4].parse().unwrap_or(0);
        let seconds = num(6).unwrap_or(f64::NAN);
        let values = if f[5] == "ERR" {
            None
        } else {
            let v: Option<Vec<f64>> = f[7..].iter().map(|s| s.parse().ok()).collect();
            match v {
                Some(v) => Some(v),
                None => continue,
            }
        };
        out.insert(
            Pt::new(u, c, b, p).key(),
            Cached {
                order,
                method: f[5].to_string(),
                seconds,
                values,
            },
        );
    }
    out
}

/// Computes the profiles of `points` missing from the cache of `set`, in
/// order, for at most `budget` seconds, appending each to the cache file.
fn compute(set: &str, points: &[Pt], budget: f64) {
    let cache = load_cache(set);
    fs::create_dir_all(cache_dir()).expect("cannot create the cache directory");
    let path = cache_dir().join(format!("{set}.txt"));
    let mut file = fs::OpenOptions::new()
        .create(true)
        .append(true)
        .open(&path)
        .expect("cannot open the cache file");
    let start = Instant::now();
    let mut done = 0;
    let mut seen = std::collections::HashSet::new();
    let missing: Vec<Pt> = points
        .iter()
        .filter(|p| !cache.contains_key(&p.key()) && seen.insert(p.key()))
        .copied()
        .collect();
    for pt in &missing {
        if start.elapsed().as_secs_f64() > budget {
            break;
        }
        let params = Params::new(pt.u, pt.c, pt.beta, pt.p).expect("valid point");
        let rule = ProfileRule::with_order(ProfileRule::width_for(&params), ORDER);
        let t = Instant::now();
        let res = convolution_profile_with_method(pt.u, pt.c, pt.beta, pt.p, &rule.nodes);
        let secs = t.elapsed().as_secs_f64();
        let mut line = format!("{:?} {:?} {:?} {:?} {ORDER} ", pt.u, pt.c, pt.beta, pt.p);
        match res {
            Ok((v, m)) => {
                let m = match m {
                    Method::ZonalHarmonics { band_limit } => format!("zh{band_limit}"),
                    Method::Direct => "direct".to_string(),
                };
                line += &format!("{m} {secs:?}");
                for x in v {
                    line += &format!(" {x:?}");
                }
            }
            Err(e) => {
                eprintln!("{pt}: {e}");
                line += &format!("ERR {secs:?} {}", format!("{e}").replace(' ', "_"));
            }
        }
        writeln!(file, "{line}").expect("cannot write the cache");
        done += 1;
    }
    println!(
        "{set}: computed {done} profiles in {:.0} s; {} of {} cached",
        start.elapsed().as_secs_f64(),
        cache.len() + done,
        missing.len() + cache.len()
    );
}

// ---------------------------------------------------------------------------
// Exact profiles, the metric, and evaluation between the nodes
// ---------------------------------------------------------------------------

/// An exact profile at one parameter point, on the study's rule.
#[derive(Clone, Debug)]
struct Exact {
    pt: Pt,
    rule: ProfileRule,
    order: usize,
    values: Vec<f64>,
    /// Barycentric weights of the Gauss–Legendre nodes of one interval
    /// (the same for every interval: they are invariant under the affine map).
    bary: Vec<f64>,
    /// `∫ C² sin θ dθ` and `∫ C sin θ cos θ dθ`.
    norm2: f64,
    energy: f64,
}

impl Exact {
    fn new(pt: Pt, order: usize, values: Vec<f64>) -> Self {
        let params = Params::new(pt.u, pt.c, pt.beta, pt.p).expect("valid point");
        let rule = ProfileRule::with_order(ProfileRule::width_for(&params), order);
        assert_eq!(
            rule.nodes.len(),
            values.len(),
            "cache does not match the rule"
        );
        // Barycentric weights of Gauss–Legendre nodes x_j with weights w_j:
        // λ_j = (−1)^j sqrt((1 − x_j²) w_j).
        let (gx, gw) = generator::quad::gauss_legendre(order);
        let bary = gx
            .iter()
            .zip(&gw)
            .enumerate()
            .map(|(j, (x, w))| {
                let s = ((1.0 - x * x) * w).sqrt();
                if j % 2 == 0 { s } else { -s }
            })
            .collect();
        let mut norm2 = 0.0;
        let mut energy = 0.0;
        for ((&t, &w), &c) in rule.nodes.iter().zip(&rule.weights).zip(&values) {
            norm2 += w * c * c;
            energy += w * c * t.cos();
        }
        Exact {
            pt,
            rule,
            order,
            values,
            bary,
            norm2,
            energy,
        }
    }

    /// SPEC's `e_L2` of `approx` (evaluated at the rule's nodes).
    fn e_l2(&self, approx: impl Fn(f64) -> f64) -> f64 {
        let mut num = 0.0;
        for ((&t, &w), &c) in self
            .rule
            .nodes
            .iter()
            .zip(&self.rule.weights)
            .zip(&self.values)
        {
            let d = approx(t) - c;
            num += w * d * d;
        }
        (num / self.norm2).sqrt()
    }

    /// Both metrics at once from the approximation's values at the nodes:
    /// `(e_L2, relative energy error)`, the energy being `∫ C sin θ cos θ dθ`
    /// (proportional to the albedo of the halo at normal incidence).
    fn errors_from(&self, approx: &[f64]) -> (f64, f64) {
        let mut num = 0.0;
        let mut en = 0.0;
        for (((&t, &w), &c), &a) in self
            .rule
            .nodes
            .iter()
            .zip(&self.rule.weights)
            .zip(&self.values)
            .zip(approx)
        {
            num += w * (a - c) * (a - c);
            en += w * a * t.cos();
        }
        ((num / self.norm2).sqrt(), (en / self.energy - 1.0).abs())
    }

    fn errors(&self, approx: impl Fn(f64) -> f64) -> (f64, f64) {
        let v: Vec<f64> = self.rule.nodes.iter().map(|&t| approx(t)).collect();
        self.errors_from(&v)
    }

    /// `C(θ)` for any `θ ∈ [0, π/2]`: barycentric interpolation on the
    /// Gauss nodes of the rule's interval nearest to `θ`.
    fn at(&self, theta: f64) -> f64 {
        let n = self.order;
        let blocks = self.values.len() / n;
        let nodes = &self.rule.nodes;
        // The block whose node span contains θ, or the nearer of the two
        // blocks around a gap (first block below, last block above).
        let mut k = nodes.partition_point(|&x| x <= theta) / n;
        if k >= blocks {
            k = blocks - 1;
        } else if k > 0 && theta < nodes[k * n] {
            let prev_gap = theta - nodes[k * n - 1];
            let next_gap = nodes[k * n] - theta;
            if prev_gap < next_gap {
                k -= 1;
            }
        }
        let xs = &nodes[k * n..(k + 1) * n];
        let vs = &self.values[k * n..(k + 1) * n];
        let mut num = 0.0;
        let mut den = 0.0;
        for j in 0..n {
            let d = theta - xs[j];
            if d == 0.0 {
                return vs[j];
            }
            let l = self.bary[j] / d;
            num += l * vs[j];
            den += l;
        }
        (num / den).max(0.0)
    }
}

/// The exact profiles of a set that are cached, in the order of the set.
fn exact_set(set: &str) -> Vec<Exact> {
    let points = point_set(set).unwrap_or_else(|| panic!("unknown set {set}"));
    let cache = load_cache(set);
    let mut out = Vec::new();
    let mut seen = std::collections::HashSet::new();
    for pt in points {
        if !seen.insert(pt.key()) {
            continue;
        }
        if let Some(Cached {
            order,
            values: Some(v),
            ..
        }) = cache.get(&pt.key())
        {
            out.push(Exact::new(pt, *order, v.clone()));
        }
    }
    out
}

// ---------------------------------------------------------------------------
// Statistics
// ---------------------------------------------------------------------------

/// Median, 90th percentile, maximum and the index of the maximum.
#[derive(Clone, Copy, Debug)]
struct Stats {
    n: usize,
    median: f64,
    p90: f64,
    max: f64,
    argmax: usize,
}

fn stats(v: &[f64]) -> Stats {
    let mut s: Vec<f64> = v.to_vec();
    s.sort_by(f64::total_cmp);
    let q = |f: f64| s[((s.len() - 1) as f64 * f).round() as usize];
    let argmax = (0..v.len())
        .max_by(|&a, &b| v[a].total_cmp(&v[b]))
        .unwrap_or(0);
    Stats {
        n: v.len(),
        median: q(0.5),
        p90: q(0.9),
        max: q(1.0),
        argmax,
    }
}

impl std::fmt::Display for Stats {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(
            f,
            "n={:<4} median {:.4}  p90 {:.4}  max {:.4}",
            self.n, self.median, self.p90, self.max
        )
    }
}

fn main() {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let cmd = args.first().map(String::as_str).unwrap_or("help");
    match cmd {
        "compute" => {
            let set = args.get(1).expect("compute SET [SECS]");
            let budget = args.get(2).and_then(|s| s.parse().ok()).unwrap_or(240.0);
            let points = point_set(set).unwrap_or_else(|| panic!("unknown set {set}"));
            compute(set, &points, budget);
        }
        "status" => status(),
        "show" => show(&args[1], args[2].parse().expect("index")),
        "rule-check" => rule_check(),
        "fits" => fits(),
        "sweeps" => sweeps(),
        "t3a-axes" => t3a_axes(FitKind::parse(args.get(1))),
        "t3b-angle" => t3b_angle(args.get(1).map(String::as_str).unwrap_or("final")),
        "t3b-axes" => {
            let rest: Vec<String> = args[1..]
                .iter()
                .filter(|a| !a.starts_with("--"))
                .cloned()
                .collect();
            if args.iter().any(|a| a == "--param-only") {
                PARAM_ONLY.store(true, std::sync::atomic::Ordering::Relaxed);
                println!(
                    "parameter interpolation alone (against the representation at each point's own node data)"
                );
            }
            if args.iter().any(|a| a == "--param-cubic") {
                PARAM_CUBIC.store(true, std::sync::atomic::Ordering::Relaxed);
                println!("cubic (4-point) interpolation along the parameter axis");
            }
            t3b_axes(&parse_repr(&rest))
        }
        "cells" => {
            let name = args.get(1).expect("cells LAYOUT [REPR]");
            cells(
                &layout(name).expect("unknown layout"),
                &parse_repr(&args[2..]),
            );
        }
        "timing" => {
            timing(&layout(args.get(1).map(String::as_str).unwrap_or("A")).expect("unknown layout"))
        }
        _ => {
            eprintln!("usage: t3_study <subcommand>; see the module documentation");
            std::process::exit(2);
        }
    }
}

/// How many profiles of each set are cached, and what they cost.
fn status() {
    for set in [
        "sample",
        "sweep-u",
        "sweep-c",
        "sweep-beta",
        "sweep-p",
        "sweep-sim",
        "cells-A",
        "cells-B",
    ] {
        let Some(points) = point_set(set) else {
            continue;
        };
        let cache = load_cache(set);
        let mut secs = 0.0;
        let mut direct = 0;
        let mut errs = 0;
        for c in cache.values() {
            secs += c.seconds;
            direct += usize::from(c.method == "direct");
            errs += usize::from(c.values.is_none());
        }
        let unique: std::collections::HashSet<_> = points.iter().map(Pt::key).collect();
        println!(
            "{set:<11} {:>4}/{:<4} cached, {direct:>4} direct, {errs} failed, {secs:>7.0} s of reference",
            cache.len(),
            unique.len()
        );
    }
}

// ---------------------------------------------------------------------------
// Compact forms and their fits
// ---------------------------------------------------------------------------

/// A compact form fitted at one point: `s · (1 + (2g sin θ)²)^(−e) · cos^m θ`.
/// The paper's form has `e = (c+1)/2`, `m = 0`.
#[derive(Clone, Copy, Debug)]
struct Form {
    s: f64,
    g: f64,
    e: f64,
    m: f64,
    /// e_L2 of the fit against exact `C`.
    e_l2: f64,
    /// Interior local minima seen by the scan over ln g.
    scan_minima: usize,
}

impl Form {
    fn eval(&self, theta: f64) -> f64 {
        self.s * lobe(self.g, self.e, self.m, theta)
    }
}

/// `(1 + (2g sin θ)²)^(−e) · cos^m θ`.
fn lobe(g: f64, e: f64, m: f64, theta: f64) -> f64 {
    // k_lobe(c, m, g, θ) has exponent (c+1)/2: pass c = 2e − 1.
    k_lobe(2.0 * e - 1.0, m, g, theta)
}

fn form_from(fit: WidthFit, e: f64, m: f64) -> Form {
    Form {
        s: fit.s,
        g: fit.g,
        e,
        m,
        e_l2: fit.e_l2,
        scan_minima: fit.scan_minima,
    }
}

/// The paper's form (HP17 39–41), `m = 0`, or with a `cos²θh` factor, `m = 2`.
fn fit_paper(ex: &Exact, m: f64) -> Form {
    let r = &ex.rule;
    let fit = fit_k_lobe(
        &r.nodes,
        &r.weights,
        &ex.values,
        ex.pt.c,
        m,
        &WidthFitOptions::default(),
    );
    form_from(fit, 0.5 * (ex.pt.c + 1.0), m)
}

/// The moment fit of the paper's form ([`fit_k_lobe_moments`]): `s = C(0)`
/// and `g` matching the energy `∫ C sin θ cos θ dθ`.
fn fit_moment(ex: &Exact) -> Form {
    let mf = fit_k_lobe_moments(ex.at(0.0), ex.energy, ex.pt.c);
    let mut f = Form {
        s: mf.s,
        g: mf.g,
        e: 0.5 * (ex.pt.c + 1.0),
        m: 0.0,
        e_l2: 0.0,
        scan_minima: 0,
    };
    f.e_l2 = ex.e_l2(|t| f.eval(t));
    f
}

/// Which fit of the paper's form T3a stores.
#[derive(Clone, Copy, Debug, PartialEq)]
enum FitKind {
    /// Least squares in the e_L2 metric ([`fit_paper`], `m = 0`).
    Ls,
    /// Peak and energy kept ([`fit_moment`]).
    Moment,
}

impl FitKind {
    fn parse(s: Option<&String>) -> FitKind {
        match s.map(String::as_str) {
            Some("mom") => FitKind::Moment,
            _ => FitKind::Ls,
        }
    }

    fn fit(&self, ex: &Exact) -> Form {
        match self {
            FitKind::Ls => fit_paper(ex, 0.0),
            FitKind::Moment => fit_moment(ex),
        }
    }
}

/// A form with one more free parameter: the exponent `e` (for fixed `m`,
/// `free_m = false`) or the cosine power `m` (for `e = (c+1)/2`,
/// `free_m = true`). The extra parameter is found by the same scan +
/// golden section (on `ln e ∈ [ln 0.05, ln 50]` or `m ∈ [−2, 12]`) around
/// the variable-projection fit of `(s, g)`.
fn fit_three(ex: &Exact, m: f64, free_m: bool) -> Form {
    let r = &ex.rule;
    let opts = WidthFitOptions {
        scan: 48,
        tol: 1e-7,
        ..WidthFitOptions::default()
    };
    let e0 = 0.5 * (ex.pt.c + 1.0);
    let inner = |a: f64| {
        let (e, mm) = if free_m { (e0, a) } else { (a.exp(), m) };
        fit_scale_width(&r.nodes, &r.weights, &ex.values, &opts, |g, t| {
            lobe(g, e, mm, t)
        })
    };
    let (lo, hi) = if free_m {
        (-2.0, 12.0)
    } else {
        (0.05f64.ln(), 50f64.ln())
    };
    let best = minimize_scan_golden(|a| inner(a).e_l2, lo, hi, 28, 1e-6);
    let fit = inner(best.x);
    let (e, mm) = if free_m {
        (e0, best.x)
    } else {
        (best.x.exp(), m)
    };
    form_from(fit, e, mm)
}

/// Checks the study's 8-point rule and the interpolation between its nodes
/// against the 16-point rule of SPEC's metric, at every 20th `sample` point
/// (recomputing the 16-point profiles).
fn rule_check() {
    let set = exact_set("sample");
    let mut rows = Vec::new();
    for ex in set.iter().step_by(20) {
        let pt = ex.pt;
        let params = Params::new(pt.u, pt.c, pt.beta, pt.p).unwrap();
        let rule16 = ProfileRule::new(ProfileRule::width_for(&params));
        let t = Instant::now();
        let Ok((v16, _)) =
            convolution_profile_with_method(pt.u, pt.c, pt.beta, pt.p, &rule16.nodes)
        else {
            continue;
        };
        let secs = t.elapsed().as_secs_f64();
        let ex16 = Exact::new(pt, 16, v16);
        let f8 = fit_paper(ex, 0.0);
        let f16 = fit_paper(&ex16, 0.0);
        // e_L2 of the 8-point fit measured on the 16-point rule.
        let e_cross = ex16.e_l2(|t| f8.eval(t));
        // Interpolation of the 8-point profile at the 16-point nodes.
        let e_interp = ex16.e_l2(|t| ex.at(t));
        let cmax = ex16.values.iter().cloned().fold(0.0, f64::max);
        let mut max_rel: f64 = 0.0;
        for (&t, &c) in rule16.nodes.iter().zip(&ex16.values) {
            if c > 1e-6 * cmax {
                max_rel = max_rel.max((ex.at(t) / c - 1.0).abs());
            }
        }
        println!(
            "{pt}  e_L2 fit: rule8 {:.6} rule16 {:.6} (8-fit on 16: {:.6}), g {:.6e}/{:.6e}; interp e_L2 {:.1e} max rel {:.1e}; {secs:.2} s",
            f8.e_l2, f16.e_l2, e_cross, f8.g, f16.g, e_interp, max_rel
        );
        rows.push(((f8.e_l2 - f16.e_l2).abs(), e_interp, max_rel));
    }
    let dm = rows.iter().map(|r| r.0).fold(0.0, f64::max);
    let im = rows.iter().map(|r| r.1).fold(0.0, f64::max);
    let rm = rows.iter().map(|r| r.2).fold(0.0, f64::max);
    println!(
        "max |Δ e_L2| {dm:.1e}; interpolation: max e_L2 {im:.1e}, max rel (C > 1e-6 max) {rm:.1e}"
    );
}

/// Does C rise towards grazing (C(π/2) > C(0))?
fn rising(ex: &Exact) -> bool {
    ex.values.last().copied().unwrap_or(0.0) > ex.values[0]
}

/// The compact forms at the `sample` points.
fn fits() {
    let set = exact_set("sample");
    println!("{} sample profiles cached", set.len());
    type Fitter = fn(&Exact) -> Form;
    let forms: [(&str, Fitter); 6] = [
        ("paper  s·k(2g sinθ)", |ex| fit_paper(ex, 0.0)),
        ("paper, moment fit (s = C(0), energy kept)", fit_moment),
        ("cos²   s·k(2g sinθ)cos²θ", |ex| fit_paper(ex, 2.0)),
        ("free e s·(1+(2g sinθ)²)^-e·cos²θ", |ex| {
            fit_three(ex, 2.0, false)
        }),
        ("free m s·k(2g sinθ)·cos^mθ", |ex| {
            fit_three(ex, 0.0, true)
        }),
        ("free e, m=0", |ex| fit_three(ex, 0.0, false)),
    ];
    let t = Instant::now();
    let all: Vec<Vec<Form>> = set
        .iter()
        .map(|ex| forms.iter().map(|(_, f)| f(ex)).collect())
        .collect();
    println!(
        "fits: {:.1} ms per point for all forms",
        1e3 * t.elapsed().as_secs_f64() / set.len() as f64
    );
    let t = Instant::now();
    for ex in &set {
        let _ = fit_paper(ex, 0.0);
    }
    println!(
        "paper fit alone: {:.2} ms per point",
        1e3 * t.elapsed().as_secs_f64() / set.len() as f64
    );
    for (i, (name, _)) in forms.iter().enumerate() {
        let e: Vec<f64> = all.iter().map(|f| f[i].e_l2).collect();
        let en: Vec<f64> = set
            .iter()
            .zip(&all)
            .map(|(ex, f)| ex.errors(|t| f[i].eval(t)).1)
            .collect();
        let st = stats(&e);
        println!("\n{name}\n  e_L2   {st}   (worst at {})", set[st.argmax].pt);
        let se = stats(&en);
        println!("  energy {se}   (worst at {})", set[se.argmax].pt);
        let multi = all.iter().filter(|f| f[i].scan_minima > 1).count();
        println!("  points with several local minima in ln g: {multi}");
        // Split: profiles rising towards grazing, and the rest.
        let (r, nr): (Vec<usize>, Vec<usize>) = (0..set.len()).partition(|&k| rising(&set[k]));
        let sub = |idx: &[usize]| stats(&idx.iter().map(|&k| e[k]).collect::<Vec<_>>());
        if !r.is_empty() {
            println!("  rising C ({}): {}", r.len(), sub(&r));
        }
        println!("  other   ({}): {}", nr.len(), sub(&nr));
        let mut order: Vec<usize> = (0..set.len()).collect();
        order.sort_by(|&a, &b| e[b].total_cmp(&e[a]));
        for &k in order.iter().take(6) {
            let f = all[k][i];
            println!(
                "    {}  e_L2 {:.3} energy {:.3}  s {:.3e} g {:.3e} e {:.3} m {:.2}",
                set[k].pt, e[k], en[k], f.s, f.g, f.e, f.m
            );
        }
        // Distribution over bins of u.
        let bins = [
            (0.0, 0.0),
            (1e-9, 0.1),
            (0.1, 10.0),
            (10.0, 300.0),
            (300.0, 3001.0),
        ];
        for (lo, hi) in bins {
            let idx: Vec<usize> = (0..set.len())
                .filter(|&k| {
                    let u = set[k].pt.u;
                    if hi == 0.0 {
                        u == 0.0
                    } else {
                        u >= lo && u < hi
                    }
                })
                .collect();
            if !idx.is_empty() {
                println!("    u in [{lo}, {hi}): {}", sub(&idx));
            }
        }
    }
}

// ---------------------------------------------------------------------------
// Axis mappings and 1-D interpolation
// ---------------------------------------------------------------------------

/// A table axis: a runtime mapping (twoscale::format::Mapping) of the
/// variable `x − shift` (`shift = 1` tabulates `c − 1` instead of `c`).
#[derive(Clone, Copy, Debug)]
struct AxisMap {
    mapping: Mapping,
    param: f64,
    shift: f64,
    lo: f64,
    hi: f64,
}

impl AxisMap {
    fn new(mapping: Mapping, param: f64, shift: f64, lo: f64, hi: f64) -> Self {
        AxisMap {
            mapping,
            param,
            shift,
            lo,
            hi,
        }
    }

    /// The runtime's axis header for this mapping (shifted domain, no linear term).
    fn header(&self) -> AxisHeader {
        AxisHeader {
            nodes: 2,
            mapping: self.mapping,
            lo: self.lo - self.shift,
            hi: self.hi - self.shift,
            param: self.param,
            param2: 0.0,
        }
    }

    fn coord(&self, x: f64) -> f64 {
        coordinate_f64(&self.header(), x - self.shift)
    }

    fn inverse(&self, c: f64) -> f64 {
        inverse_coordinate_f64(&self.header(), c) + self.shift
    }

    /// Node `i` of `n` (physical value).
    fn node(&self, n: usize, i: usize) -> f64 {
        if i == 0 {
            return self.lo;
        }
        if i + 1 >= n {
            return self.hi;
        }
        let (a, b) = (self.coord(self.lo), self.coord(self.hi));
        self.inverse(a + (b - a) * i as f64 / (n - 1) as f64)
    }

    /// Cell and fraction of `x` on an `n`-node axis (clamped).
    fn locate(&self, n: usize, x: f64) -> (usize, f64) {
        let (a, b) = (self.coord(self.lo), self.coord(self.hi));
        let y = ((self.coord(x.clamp(self.lo, self.hi)) - a) / (b - a) * (n - 1) as f64)
            .clamp(0.0, (n - 1) as f64);
        let i = (y.floor() as usize).min(n - 2);
        (i, y - i as f64)
    }

    fn describe(&self) -> String {
        let v = if self.shift != 0.0 { "(x−1)" } else { "x" };
        match self.mapping {
            Mapping::Uniform => v.to_string(),
            Mapping::Log => format!("ln {v}"),
            Mapping::LogOffset => format!("ln({v}+{})", self.param),
            Mapping::Power => format!("{v}^{}", self.param),
        }
    }
}

/// Candidate mappings per axis.
fn candidate_maps(axis: usize) -> Vec<AxisMap> {
    use Mapping::*;
    match axis {
        0 => [0.01, 0.1, 0.3, 1.0, 3.0]
            .iter()
            .map(|&k| AxisMap::new(LogOffset, k, 0.0, 0.0, U_MAX))
            .collect(),
        1 => vec![
            AxisMap::new(Uniform, 0.0, 0.0, C_LO, C_HI),
            AxisMap::new(Log, 0.0, 0.0, C_LO, C_HI),
            AxisMap::new(Power, -1.0, 0.0, C_LO, C_HI),
            AxisMap::new(Power, -2.0, 0.0, C_LO, C_HI),
            AxisMap::new(Log, 0.0, 1.0, C_LO, C_HI),
            AxisMap::new(Power, 0.5, 1.0, C_LO, C_HI),
        ],
        2 => vec![
            AxisMap::new(Log, 0.0, 0.0, BETA_LO, BETA_HI),
            AxisMap::new(Power, 0.5, 0.0, BETA_LO, BETA_HI),
            AxisMap::new(Power, 0.25, 0.0, BETA_LO, BETA_HI),
        ],
        _ => vec![
            AxisMap::new(Log, 0.0, 0.0, P_LO, P_HI),
            AxisMap::new(Power, -1.0, 0.0, P_LO, P_HI),
            AxisMap::new(Power, -0.5, 0.0, P_LO, P_HI),
            AxisMap::new(Uniform, 0.0, 0.0, P_LO, P_HI),
        ],
    }
}

/// The coordinate in which the dense sweeps are interpolated by cubics
/// (their own, nearly uniform, spacing).
fn sweep_coord(axis: usize, x: f64) -> f64 {
    match axis {
        0 => (x + 1e-4).ln(),
        1 => (x - 1.0).ln(),
        _ => x.ln(),
    }
}

/// Cubic (4-point Lagrange) interpolation of `ys` at `z` given ascending
/// abscissae `zs` (linear with 2 or 3 points).
fn lagrange4(zs: &[f64], ys: &[f64], z: f64) -> f64 {
    let n = zs.len();
    if n == 1 {
        return ys[0];
    }
    let i = zs.partition_point(|&a| a <= z).clamp(1, n - 1);
    let (lo, hi) = if n < 4 {
        (0, n)
    } else {
        let lo = i.saturating_sub(2).min(n - 4);
        (lo, lo + 4)
    };
    let mut sum = 0.0;
    for j in lo..hi {
        let mut l = 1.0;
        for k in lo..hi {
            if k != j {
                l *= (z - zs[k]) / (zs[j] - zs[k]);
            }
        }
        sum += l * ys[j];
    }
    sum
}

/// The exact profiles of the similarity sweeps ([`sim_groups`]), by base.
fn sim_exact_groups() -> Vec<Vec<Exact>> {
    let set = exact_set("sweep-sim");
    let by_key: HashMap<[u64; 4], &Exact> = set.iter().map(|e| (e.pt.key(), e)).collect();
    sim_groups()
        .iter()
        .map(|g| {
            g.iter()
                .filter_map(|p| by_key.get(&p.key()).map(|e| (*e).clone()))
                .collect::<Vec<_>>()
        })
        .filter(|g| g.len() >= 6)
        .collect()
}

/// The exact profiles of one dense sweep, by base.
fn sweep_groups(axis: usize) -> Vec<Vec<Exact>> {
    if axis == 4 {
        return sim_exact_groups();
    }
    let set = exact_set(&format!("sweep-{}", AXES[axis]));
    sweep_bases(axis)
        .iter()
        .map(|b| {
            let mut g: Vec<Exact> = set
                .iter()
                .filter(|e| (0..4).all(|a| a == axis || e.pt.axis(a) == b.axis(a)))
                .cloned()
                .collect();
            g.sort_by(|x, y| x.pt.axis(axis).total_cmp(&y.pt.axis(axis)));
            g
        })
        .filter(|g| g.len() >= 4)
        .collect()
}

/// Prints the fitted s, g along the sweeps.
fn sweeps() {
    for (axis, name) in AXES.iter().enumerate() {
        for group in sweep_groups(axis) {
            let b = group[0].pt;
            println!("\nsweep along {name} from {b}");
            println!(
                "  {:>10} {:>11} {:>11} {:>8} {:>8} {:>11} {:>11} {:>7}",
                name, "s", "g", "g/u", "e_L2", "C(0)", "s/C(0)", "rising"
            );
            for ex in &group {
                let f = fit_paper(ex, 0.0);
                let f2 = fit_paper(ex, 2.0);
                let x = ex.pt.axis(axis);
                println!(
                    "  {x:>10.4e} {:>11.4e} {:>11.4e} {:>8.3} {:>8.4} {:>11.4e} {:>11.4} {:>7}   cos²: g {:>10.4e} g/u {:>7.3} e {:.4}",
                    f.s,
                    f.g,
                    f.g / ex.pt.u,
                    f.e_l2,
                    ex.values[0],
                    f.s / ex.values[0],
                    rising(ex),
                    f2.g,
                    f2.g / ex.pt.u,
                    f2.e_l2
                );
            }
        }
    }
}

/// e_L2 between two forms at one parameter point, on the study rule.
fn form_distance(pt: Pt, a: &Form, b: &Form) -> f64 {
    let params = Params::new(pt.u, pt.c, pt.beta, pt.p).unwrap();
    let rule = ProfileRule::with_order(ProfileRule::width_for(&params), ORDER);
    let mut num = 0.0;
    let mut den = 0.0;
    for (&t, &w) in rule.nodes.iter().zip(&rule.weights) {
        let (fa, fb) = (a.eval(t), b.eval(t));
        num += w * (fa - fb) * (fa - fb);
        den += w * fb * fb;
    }
    (num / den).sqrt()
}

/// How the two numbers of T3a are stored: `(ln s, ln g)`, raw `(s, g)`, or
/// `(ln s, ln(g + g0))`.
///
/// The last is the proposal: where `C` is flat or rises towards grazing, the
/// best single lobe is a constant and the fit drives `g` to 0 (to the search
/// floor `1e-4`), continuously in the form (`k(2g sin θ) ≈ 1 − 2(c+1) g²
/// sin²θ`) but with a singularity in `ln g`; the offset `g0` removes it
/// while keeping `ln g` (power laws in the parameters) for `g ≫ g0`.
#[derive(Clone, Copy, Debug, PartialEq)]
enum Stored {
    Log,
    Raw,
    LogOff(f64),
    /// `(ln s, ln(g² + g0²))`: the form depends on `g²` analytically, and
    /// where the fit degenerates to a constant `g²` (not `g`) goes to 0
    /// linearly.
    LogSq(f64),
}

impl Stored {
    fn encode(&self, f: &Form) -> (f64, f64) {
        match *self {
            Stored::Log => (f.s.ln(), f.g.ln()),
            Stored::Raw => (f.s, f.g),
            Stored::LogOff(g0) => (f.s.ln(), (f.g + g0).ln()),
            Stored::LogSq(g0) => (f.s.ln(), (f.g * f.g + g0 * g0).ln()),
        }
    }

    fn decode(&self, a: f64, b: f64) -> (f64, f64) {
        match *self {
            Stored::Log => (a.exp(), b.exp()),
            Stored::Raw => (a, b.max(0.0)),
            Stored::LogOff(g0) => (a.exp(), (b.exp() - g0).max(0.0)),
            Stored::LogSq(g0) => (a.exp(), (b.exp() - g0 * g0).max(0.0).sqrt()),
        }
    }
}

/// Node counts per axis for T3a: for every candidate mapping and node count,
/// the largest e_L2 of the interpolated paper form against the fitted form
/// over the dense sweep points (node values from cubics through the sweep).
fn t3a_axes(kind: FitKind) {
    println!("fit: {kind:?}");
    let counts = [4usize, 6, 8, 12, 16, 24, 32, 48, 64, 96, 128];
    for (axis, name) in AXES.iter().enumerate() {
        let groups = sweep_groups(axis);
        if groups.is_empty() {
            continue;
        }
        // Fits along each sweep.
        let fits: Vec<Vec<Form>> = groups
            .iter()
            .map(|g| g.iter().map(|e| kind.fit(e)).collect())
            .collect();
        println!(
            "\naxis {name} ({} sweeps of {} points)",
            groups.len(),
            groups[0].len()
        );
        // Accuracy of the cubic through the sweep: leave-one-out in ln s, ln g.
        let mut loo: f64 = 0.0;
        for (g, f) in groups.iter().zip(&fits) {
            let zs: Vec<f64> = g
                .iter()
                .map(|e| sweep_coord(axis, e.pt.axis(axis)))
                .collect();
            for j in 2..g.len() - 2 {
                let mut z2 = zs.clone();
                z2.remove(j);
                let st = Stored::LogOff(0.1);
                let (mut ls, mut lg): (Vec<f64>, Vec<f64>) = f.iter().map(|x| st.encode(x)).unzip();
                ls.remove(j);
                lg.remove(j);
                let (s, gg) = st.decode(lagrange4(&z2, &ls, zs[j]), lagrange4(&z2, &lg, zs[j]));
                let est = Form { s, g: gg, ..f[j] };
                loo = loo.max(form_distance(g[j].pt, &est, &f[j]));
            }
        }
        println!(
            "  leave-one-out cubic through the sweep (ln s, ln(g+0.1)): max e_L2 {loo:.2e} (resolution of this analysis)"
        );
        for stored in [
            Stored::Log,
            Stored::Raw,
            Stored::LogOff(0.1),
            Stored::LogSq(0.1),
            Stored::LogSq(0.3),
            Stored::LogSq(1.0),
        ] {
            for map in candidate_maps(axis) {
                let mut line = format!("  {:<13} {:<12}", format!("{stored:?}"), map.describe());
                let mut need = [None, None];
                let mut at32 = None;
                for &n in &counts {
                    let mut worst = (0.0f64, groups[0][0].pt);
                    for (g, f) in groups.iter().zip(&fits) {
                        let w = t3a_axis_error(axis, g, f, &map, n, stored);
                        if w.0 > worst.0 {
                            worst = w;
                        }
                    }
                    if n == 32 {
                        at32 = Some(worst.1);
                    }
                    let worst = worst.0;
                    line += &format!(" {n}:{:.4}", worst);
                    for (k, target) in [0.0025, 0.005].iter().enumerate() {
                        if need[k].is_none() && worst <= *target {
                            need[k] = Some(n);
                        }
                    }
                }
                println!(
                    "{line}   N(0.25%)={:?} N(0.5%)={:?}  worst at 32: {}",
                    need[0],
                    need[1],
                    at32.map(|p| p.to_string()).unwrap_or_default()
                );
            }
        }
    }
}

/// Largest e_L2 (interpolated vs fitted form) along one sweep for one axis
/// layout, and where.
fn t3a_axis_error(
    axis: usize,
    g: &[Exact],
    f: &[Form],
    map: &AxisMap,
    n: usize,
    stored: Stored,
) -> (f64, Pt) {
    let zs: Vec<f64> = g
        .iter()
        .map(|e| sweep_coord(axis, e.pt.axis(axis)))
        .collect();
    let (q1, q2): (Vec<f64>, Vec<f64>) = f.iter().map(|x| stored.encode(x)).unzip();
    let lo = g[0].pt.axis(axis);
    let hi = g[g.len() - 1].pt.axis(axis);
    // Node values (cubic through the sweep; exact at the sweep's ends).
    let node_vals: Vec<(f64, f64)> = (0..n)
        .map(|i| {
            let x = map.node(n, i).clamp(lo, hi);
            let z = sweep_coord(axis, x);
            (lagrange4(&zs, &q1, z), lagrange4(&zs, &q2, z))
        })
        .collect();
    let mut worst = (0.0, g[0].pt);
    for (e, fit) in g.iter().zip(f) {
        let (i, t) = map.locate(n, e.pt.axis(axis));
        let a = (1.0 - t) * node_vals[i].0 + t * node_vals[i + 1].0;
        let b = (1.0 - t) * node_vals[i].1 + t * node_vals[i + 1].1;
        let (s, gg) = stored.decode(a, b);
        let est = Form { s, g: gg, ..*fit };
        let d = form_distance(e.pt, &est, fit);
        if d > worst.0 {
            worst = (d, e.pt);
        }
    }
    worst
}

// ---------------------------------------------------------------------------
// T3b: a table over (u, c, β, p, ξ) on top of a fitted form
// ---------------------------------------------------------------------------

/// The angular variable of T3b.
#[derive(Clone, Copy, Debug, PartialEq)]
enum Var {
    /// `ξ = asinh(2 g_e sin θ) / asinh(2 g_e sin θmax)`.
    Sin,
    /// `ξ = asinh(2 g_e tan θ) / asinh(2 g_e tan θmax)`: linear in `θ`
    /// inside the scale (`tan θ ≪ 1/(2 g_e)`), logarithmic in `tan θ`
    /// outside it, so both the core and the horizon (where small-p NDFs peak
    /// at `cos θ ≈ 3e-3`) get nodes.
    Tan,
    /// A sum of two monotone terms, one per lobe, so that the features of
    /// both get nodes:
    ///
    /// ```text
    ///   F(θ) = asinh(2 u_e tan θ) + λ · ln(1 + Y (1 − e^(−y/Y))),   y = (tan θ / β)^(2p),
    ///   ξ = F(θ) / F(θmax),   u_e = √(u² + g_min²)
    /// ```
    ///
    /// The first term is the kernel's variable (linear inside `1/(2u)`,
    /// logarithmic in `tan θ` outside, up to the horizon); the second is the
    /// NDF's own exponent (`ln D = const − y + 2 ln(1 + tan²θ)`), which
    /// follows the cliff of large-p lobes (`y` from 0.1 to 30 within ±40% of
    /// `tan θ = β` at p = 5), the cusp of small-p ones and their maximum near
    /// the horizon; it saturates at `y ≈ Y` where `D` has fallen by `e^−Y`.
    /// (Floor and cap are smooth so that the tabulated values stay smooth
    /// along the parameter axes.)
    /// Everything is known exactly at lookup time: no fitted parameter is
    /// needed.
    Mixed {
        lambda: f64,
        y_cap: f64,
        /// The NDF term is `λ · min(y, Y)/Y` (linear in the exponent, so
        /// that `ln D` is linear in ξ through a cliff) instead of
        /// `λ · ln(1 + min(y, Y))`.
        linear_y: bool,
    },
}

/// Which width sets the scale `g_e` of the angular variable.
#[derive(Clone, Copy, Debug, PartialEq)]
enum Scale {
    /// The fitted `g` (the lobe's width).
    Fit,
    /// The kernel's `u` (the finest scale `C` can have: `1/(2u)`).
    U,
    /// `sqrt(g u)`.
    Geo,
}

/// A T3b representation: at each grid node, the fitted form `(s, g)` (of
/// cosine power `fit_m`) and `n` values `r_k` at `ξ_k = k/(n−1)`:
///
/// ```text
///   r_k = ln( C(θ_k) / B(θ_k) ),   B(θ) = s · k(2g sin θ) · cos^m θ   (base_m = Some(m))
///                                   B(θ) = s                           (base_m = None)
/// ```
///
/// with `θ_k` the angle of `ξ_k` for this node's scale. Lookup:
/// `C̃(θ) = B(θ') · exp(r̃(ξ(θ')))`, `θ' = min(θ, θmax)`, `r̃` linear in `ξ`;
/// beyond `θmax = atan(t_max)` the profile is held constant.
#[derive(Clone, Copy, Debug, PartialEq)]
struct Repr {
    fit_m: f64,
    base_m: Option<f64>,
    var: Var,
    scale: Scale,
    /// `g_e = max(scale, g_min)`.
    g_min: f64,
    t_max: f64,
    n: usize,
    /// Interpolation along ξ.
    interp: Interp,
    /// With [`Var::Mixed`] and no fitted base: divide `C` by the analytic
    /// shape `B = K^α` ([`Repr::analytic_base`]) with this `κ`
    /// (`None`: `B = 1`).
    kd_kappa: Option<f64>,
    /// Also divide by the NDF's exponential factor where the kernel is the
    /// narrower lobe, saturating at `Y_D` ([`Repr::analytic_base`]).
    d_soft: Option<f64>,
}

/// Interpolation of the stored values along ξ (the parameter axes are
/// always multilinear).
#[derive(Clone, Copy, Debug, PartialEq)]
enum Interp {
    Linear,
    /// Local cubic: 4-point Lagrange on the uniform ξ grid.
    Cubic,
    /// Monotone piecewise cubic Hermite (Fritsch–Carlson slopes from the
    /// same 4 nodes): no overshoot at cliffs.
    Pchip,
}

/// What one grid node stores for T3b (`ln s`, `ln g` and the `r_k`).
#[derive(Clone, Debug)]
struct NodeData {
    ln_s: f64,
    ln_g: f64,
    r: Vec<f64>,
}

impl NodeData {
    /// A linear combination `Σ w_j d_j` (the n-linear interpolation).
    fn blend(parts: &[(f64, &NodeData)]) -> NodeData {
        let n = parts[0].1.r.len();
        let mut out = NodeData {
            ln_s: 0.0,
            ln_g: 0.0,
            r: vec![0.0; n],
        };
        for (w, d) in parts {
            out.ln_s += w * d.ln_s;
            out.ln_g += w * d.ln_g;
            for (o, x) in out.r.iter_mut().zip(&d.r) {
                *o += w * x;
            }
        }
        out
    }
}

impl Repr {
    fn theta_max(&self) -> f64 {
        self.t_max.atan()
    }

    fn tau(&self, theta: f64) -> f64 {
        match self.var {
            Var::Sin => theta.sin(),
            _ => theta.tan(),
        }
    }

    /// `2 g_e` for the fitted width `g` at kernel parameter `u`.
    fn two_ge(&self, g: f64, u: f64) -> f64 {
        let w = match self.scale {
            Scale::Fit => g,
            Scale::U => u,
            Scale::Geo => (g * u).sqrt(),
        };
        2.0 * w.max(self.g_min)
    }

    /// `F(θ)` of [`Var::Mixed`].
    fn mixed(&self, pt: &Pt, theta: f64) -> f64 {
        let Var::Mixed {
            lambda,
            y_cap,
            linear_y,
        } = self.var
        else {
            return 0.0;
        };
        let t = theta.min(self.theta_max()).tan();
        // Smooth floor and cap (a kink here would be a kink of the tabulated
        // values along the parameter axes): u_e = √(u² + g_min²), and
        // y saturating softly at Y.
        let ue = 2.0 * pt.u.hypot(self.g_min);
        let y = -y_cap * (-(t / pt.beta).powf(2.0 * pt.p) / y_cap).exp_m1();
        let d_term = if linear_y { y / y_cap } else { y.ln_1p() };
        (ue * t).asinh() + lambda * d_term
    }

    /// `ξ ∈ [0, 1]` of `θ`.
    fn xi(&self, g: f64, pt: &Pt, theta: f64) -> f64 {
        if let Var::Mixed { .. } = self.var {
            let top = self.mixed(pt, self.theta_max());
            return (self.mixed(pt, theta) / top).clamp(0.0, 1.0);
        }
        let ge = self.two_ge(g, pt.u);
        let top = (ge * self.tau(self.theta_max())).asinh();
        ((ge * self.tau(theta.min(self.theta_max()))).asinh() / top).clamp(0.0, 1.0)
    }

    /// The inverse of [`Repr::xi`].
    fn theta_of(&self, g: f64, pt: &Pt, xi: f64) -> f64 {
        if let Var::Mixed { .. } = self.var {
            // F is increasing: bisection on θ.
            let target = xi * self.mixed(pt, self.theta_max());
            let (mut lo, mut hi) = (0.0, self.theta_max());
            for _ in 0..100 {
                let mid = 0.5 * (lo + hi);
                if self.mixed(pt, mid) < target {
                    lo = mid;
                } else {
                    hi = mid;
                }
            }
            return 0.5 * (lo + hi);
        }
        let u = pt.u;
        let ge = self.two_ge(g, u);
        let top = (ge * self.tau(self.theta_max())).asinh();
        let tau = (xi * top).sinh() / ge;
        match self.var {
            Var::Sin => tau.min(1.0).asin(),
            _ => tau.atan(),
        }
    }

    fn base(&self, c: f64, s: f64, g: f64, theta: f64) -> f64 {
        match self.base_m {
            Some(m) => s * k_lobe(c, m, g, theta),
            None => s,
        }
    }

    /// `ln B(θ)` of the analytic base: the kernel's shape, weighted by how
    /// much the kernel (rather than the NDF) shapes `C`:
    ///
    /// ```text
    ///   ln B = α ln K,   ln K = −q ln(1 + 4u² sin²θ) + 2 ln cos θ   (SPEC §2.5),
    ///   α = 1 / (1 + (u w_D / κ)²)
    /// ```
    ///
    /// with `w_D` the NDF's width ([`Params::ndf_width`]). When the NDF is the
    /// narrower lobe (`u w_D ≪ κ`), `C ≈ W_D K` and `ln(C/K)` is nearly
    /// constant: the kernel's core, whose `ln` has a curvature `c + 1` in the
    /// kernel's own variable `asinh(2u tan θ)`, is divided out instead of
    /// tabulated. When the kernel is the narrower lobe, `α → 0` and `C` is
    /// tabulated as it is (dividing by `D` as well was tried: `C` follows the
    /// kernel's tail beyond a large-p cliff of `D`, and `ln(C/D)` explodes).
    fn analytic_base(&self, pt: &Pt, theta: f64) -> f64 {
        let Some(kappa) = self.kd_kappa else {
            return 0.0;
        };
        let (sn, cs) = theta.sin_cos();
        let q = 0.5 * (pt.c + 1.0);
        let ln_k = -q * (4.0 * pt.u * pt.u * sn * sn).ln_1p() + 2.0 * cs.ln();
        let w_d = Params::new(pt.u, pt.c, pt.beta, pt.p)
            .map(|p| p.ndf_width())
            .unwrap_or(1.0);
        let alpha = 1.0 / (1.0 + (pt.u * w_d / kappa).powi(2));
        let ln_d = match self.d_soft {
            // D's exponent, saturating at Y_D: −Y_D (1 − e^(−y/Y_D)).
            Some(yd) => {
                let y = (sn / cs / pt.beta).powf(2.0 * pt.p);
                yd * (-y / yd).exp_m1()
            }
            None => 0.0,
        };
        alpha * ln_k + (1.0 - alpha) * ln_d
    }

    /// The node data of one exact profile (fitting the form first, unless
    /// the representation needs no fit: mixed variable without a base
    /// shape, where the scale is `C(0)`).
    fn encode(&self, ex: &Exact) -> NodeData {
        if self.fit_free() {
            return self.encode_with(ex, ex.at(0.0), 1.0);
        }
        let f = fit_paper(ex, self.fit_m);
        self.encode_with(ex, f.s, f.g)
    }

    fn fit_free(&self) -> bool {
        matches!(self.var, Var::Mixed { .. }) && self.base_m.is_none()
    }

    fn encode_with(&self, ex: &Exact, s: f64, g: f64) -> NodeData {
        let floor = 1e-13 * ex.values.iter().cloned().fold(0.0, f64::max);
        let r = (0..self.n)
            .map(|k| {
                let xi = k as f64 / (self.n - 1) as f64;
                let t = self.theta_of(g, &ex.pt, xi);
                let b = self.base(ex.pt.c, s, g, t).max(1e-300);
                (ex.at(t).max(floor) / b).ln() - self.analytic_base(&ex.pt, t)
            })
            .collect();
        NodeData {
            ln_s: s.ln(),
            ln_g: g.ln(),
            r,
        }
    }

    /// `C̃(θ)` from (interpolated) node data at the point `pt`.
    fn decode(&self, pt: &Pt, d: &NodeData, theta: f64) -> f64 {
        let (s, g) = (d.ln_s.exp(), d.ln_g.exp());
        let t = theta.min(self.theta_max());
        let y = self.xi(g, pt, t) * (self.n - 1) as f64;
        let i = (y.floor() as usize).min(self.n - 2);
        let f = y - i as f64;
        let r = match self.interp {
            Interp::Linear => (1.0 - f) * d.r[i] + f * d.r[i + 1],
            Interp::Cubic => {
                // Nodes i−1 … i+2, shifted inside the grid at the ends.
                let j = i.clamp(1, self.n - 3) - 1;
                let x = y - j as f64; // in [0, 3]
                let l0 = -(x - 1.0) * (x - 2.0) * (x - 3.0) / 6.0;
                let l1 = x * (x - 2.0) * (x - 3.0) / 2.0;
                let l2 = -x * (x - 1.0) * (x - 3.0) / 2.0;
                let l3 = x * (x - 1.0) * (x - 2.0) / 6.0;
                l0 * d.r[j] + l1 * d.r[j + 1] + l2 * d.r[j + 2] + l3 * d.r[j + 3]
            }
            Interp::Pchip => pchip(&d.r, i, f),
        };
        self.base(pt.c, s, g, t) * (r + self.analytic_base(pt, t)).exp()
    }

    fn interp_name(&self) -> &'static str {
        match self.interp {
            Interp::Linear => "",
            Interp::Cubic => " cubic",
            Interp::Pchip => " pchip",
        }
    }

    fn describe(&self) -> String {
        let base = match self.base_m {
            Some(m) => format!("s·k·cos^{m}"),
            None => "s".to_string(),
        };
        if self.fit_free() {
            return format!(
                "ln C{}, ξ={:?} g_min={} T={:e} n={}{}",
                match self.kd_kappa {
                    Some(k) => format!("/K^α κ={k} Y_D={:?}", self.d_soft),
                    None => String::new(),
                },
                self.var,
                self.g_min,
                self.t_max,
                self.n,
                self.interp_name()
            );
        }
        format!(
            "fit m={} base {base} ξ={:?} scale={:?} g_min={} T={:e} n={}{}",
            self.fit_m,
            self.var,
            self.scale,
            self.g_min,
            self.t_max,
            self.n,
            self.interp_name()
        )
    }
}

/// Monotone cubic Hermite interpolation (Fritsch–Carlson) on a uniform grid,
/// in interval `i` at fraction `f`: node slopes are the harmonic mean of the
/// neighbouring differences (0 at a local extremum), one-sided at the ends.
fn pchip(v: &[f64], i: usize, f: f64) -> f64 {
    let n = v.len();
    let delta = |k: usize| v[k + 1] - v[k];
    let slope = |k: usize| {
        if k == 0 {
            delta(0)
        } else if k == n - 1 {
            delta(n - 2)
        } else {
            let (a, b) = (delta(k - 1), delta(k));
            if a * b <= 0.0 {
                0.0
            } else {
                2.0 * a * b / (a + b)
            }
        }
    };
    let (d0, d1) = (slope(i), slope(i + 1));
    let (f2, f3) = (f * f, f * f * f);
    let h00 = 2.0 * f3 - 3.0 * f2 + 1.0;
    let h10 = f3 - 2.0 * f2 + f;
    let h01 = -2.0 * f3 + 3.0 * f2;
    let h11 = f3 - f2;
    h00 * v[i] + h10 * d0 + h01 * v[i + 1] + h11 * d1
}

/// The angular axis of T3b: error of each representation at the `sample`
/// points, with the node data computed from the exact profile at that point
/// (no interpolation in the parameters). `which` selects a family of
/// candidates (`vars`, `scales`, or `final`).
fn t3b_angle(which: &str) {
    let set = exact_set("sample");
    println!("{} sample profiles", set.len());
    let mut reprs = Vec::new();
    let proto = Repr {
        fit_m: 0.0,
        base_m: None,
        var: Var::Tan,
        scale: Scale::Fit,
        g_min: 1.0,
        t_max: 1e4,
        n: 0,
        interp: Interp::Linear,
        kd_kappa: None,
        d_soft: None,
    };
    let counts: &[usize] = match which {
        "vars" => {
            for (fit_m, base_m) in [(0.0, None), (0.0, Some(0.0)), (2.0, Some(2.0))] {
                for var in [Var::Tan, Var::Sin] {
                    reprs.push(Repr {
                        fit_m,
                        base_m,
                        var,
                        ..proto
                    });
                }
            }
            &[16, 32, 48]
        }
        "scales" => {
            for (fit_m, base_m) in [(0.0, None), (0.0, Some(0.0)), (2.0, Some(2.0))] {
                for scale in [Scale::Fit, Scale::U, Scale::Geo] {
                    for g_min in [0.3, 1.0, 3.0] {
                        for t_max in [1e4, 1e3] {
                            reprs.push(Repr {
                                fit_m,
                                base_m,
                                scale,
                                g_min,
                                t_max,
                                ..proto
                            });
                        }
                    }
                }
            }
            &[32, 48, 64]
        }
        "mixed" => {
            for interp in [Interp::Pchip] {
                for (kd_kappa, d_soft) in [
                    (Some(0.3), None),
                    (Some(0.3), Some(3.0)),
                    (Some(0.3), Some(10.0)),
                    (Some(1.0), Some(3.0)),
                    (Some(1.0), Some(10.0)),
                ] {
                    for (lambda, y_cap, linear_y) in [(1.0, 30.0, false), (2.0, 30.0, false)] {
                        let var = Var::Mixed {
                            lambda,
                            y_cap,
                            linear_y,
                        };
                        reprs.push(Repr {
                            var,
                            interp,
                            kd_kappa,
                            d_soft,
                            ..proto
                        });
                    }
                }
            }
            &[32, 48, 64]
        }
        "cubic" => {
            for (fit_m, base_m) in [(0.0, None), (0.0, Some(0.0)), (2.0, Some(2.0))] {
                for scale in [Scale::Fit, Scale::U, Scale::Geo] {
                    reprs.push(Repr {
                        fit_m,
                        base_m,
                        scale,
                        t_max: 1e3,
                        interp: Interp::Pchip,
                        ..proto
                    });
                }
            }
            &[16, 24, 32, 48, 64]
        }
        _ => {
            let var = Var::Mixed {
                lambda: 1.0,
                y_cap: 30.0,
                linear_y: false,
            };
            reprs.push(Repr {
                var,
                interp: Interp::Pchip,
                ..proto
            });
            &[32, 48, 64, 96]
        }
    };
    for proto in reprs {
        let fits: Vec<Form> = if proto.fit_free() {
            Vec::new()
        } else {
            set.iter().map(|ex| fit_paper(ex, proto.fit_m)).collect()
        };
        for &n in counts {
            let repr = Repr { n, ..proto };
            let mut el2 = Vec::new();
            let mut en = Vec::new();
            for (k, ex) in set.iter().enumerate() {
                let d = match fits.get(k) {
                    Some(f) => repr.encode_with(ex, f.s, f.g),
                    None => repr.encode(ex),
                };
                let (a, b) = ex.errors(|t| repr.decode(&ex.pt, &d, t));
                el2.push(a);
                en.push(b);
            }
            let s1 = stats(&el2);
            let s2 = stats(&en);
            let over = el2
                .iter()
                .zip(&en)
                .filter(|(a, b)| a.max(**b) > 0.01)
                .count();
            if which == "final" {
                for (k, ex) in set.iter().enumerate() {
                    if el2[k].max(en[k]) > 0.01 {
                        let params = Params::new(ex.pt.u, ex.pt.c, ex.pt.beta, ex.pt.p).unwrap();
                        println!(
                            "    {}  e_L2 {:.4} energy {:.4}  u·w_D {:.3e}",
                            ex.pt,
                            el2[k],
                            en[k],
                            ex.pt.u * params.ndf_width()
                        );
                    }
                }
            }
            println!(
                "{:<72} e_L2 {s1} ({})  energy p90 {:.4} max {:.4}  points > 1%: {over}",
                repr.describe(),
                set[s1.argmax].pt,
                s2.p90,
                s2.max
            );
        }
    }
}

/// A representation from the command line:
/// `FIT_M BASE VAR SCALE G_MIN T_MAX N [linear|cubic|pchip] [KAPPA] [Y_D]` with `BASE` = `none` or a cosine
/// power, `VAR` = `tan` | `sin` | `mixed:λ:Y` | `mixedlin:λ:Y`, `SCALE` = `fit` | `u` | `geo`
/// (default: `0 none tan u 1 1e4 32`).
fn parse_repr(a: &[String]) -> Repr {
    let get = |i: usize, d: &str| a.get(i).cloned().unwrap_or_else(|| d.to_string());
    Repr {
        fit_m: get(0, "0").parse().expect("FIT_M"),
        base_m: match get(1, "none").as_str() {
            "none" => None,
            m => Some(m.parse().expect("BASE")),
        },
        var: match get(2, "tan").as_str() {
            "sin" => Var::Sin,
            "tan" => Var::Tan,
            m => {
                // mixed:λ:Y (log NDF term) or mixedlin:λ:Y (linear NDF term)
                let f: Vec<f64> = m
                    .split(':')
                    .skip(1)
                    .map(|x| x.parse().expect("mixed:λ:Y"))
                    .collect();
                Var::Mixed {
                    lambda: f[0],
                    y_cap: f[1],
                    linear_y: m.starts_with("mixedlin"),
                }
            }
        },
        scale: match get(3, "u").as_str() {
            "fit" => Scale::Fit,
            "geo" => Scale::Geo,
            _ => Scale::U,
        },
        g_min: get(4, "1").parse().expect("G_MIN"),
        t_max: get(5, "1e4").parse().expect("T_MAX"),
        n: get(6, "32").parse().expect("N"),
        interp: match get(7, "linear").as_str() {
            "cubic" => Interp::Cubic,
            "pchip" => Interp::Pchip,
            _ => Interp::Linear,
        },
        kd_kappa: get(8, "none").parse().ok(),
        d_soft: get(9, "none").parse().ok(),
    }
}

/// Node counts per parameter axis for T3b: along each dense sweep, node data
/// at the nodes of a candidate axis (cubics through the sweep's node data),
/// linear interpolation between them, and the errors against exact `C` at
/// every sweep point (this includes the angular error of `repr`).
fn t3b_axes(repr: &Repr) {
    println!("{}", repr.describe());
    let counts = [4usize, 6, 8, 10, 12, 16, 20, 24, 32, 40, 48, 64];
    // Axis 4: β at fixed x = u w_D (the similarity sweeps), interpolated as
    // the β axis.
    for sweep in 0..5 {
        let groups = sweep_groups(sweep);
        let axis = if sweep == 4 { 2 } else { sweep };
        if groups.is_empty() {
            continue;
        }
        if sweep == 4 {
            println!("\n[β at fixed x = u·w_D]");
        }
        let data: Vec<Vec<NodeData>> = groups
            .iter()
            .map(|g| g.iter().map(|e| repr.encode(e)).collect())
            .collect();
        // The angular error alone (node data used at their own points).
        let mut ang: f64 = 0.0;
        for (g, d) in groups.iter().zip(&data) {
            for (e, nd) in g.iter().zip(d) {
                ang = ang.max(e.errors(|t| repr.decode(&e.pt, nd, t)).0);
            }
        }
        println!(
            "\naxis {} ({} sweeps), angular error alone: max e_L2 {ang:.4}",
            AXES[axis],
            groups.len()
        );
        for map in candidate_maps(axis) {
            let mut line = format!("  {:<12}", map.describe());
            let mut need = [None, None];
            let mut worst_at = Vec::new();
            for &n in &counts {
                let mut worst = (0.0f64, 0.0f64, groups[0][0].pt);
                for (g, d) in groups.iter().zip(&data) {
                    let (e, en, pt) = t3b_axis_error(repr, axis, g, d, &map, n);
                    if e > worst.0 {
                        worst = (e, worst.1.max(en), pt);
                    } else {
                        worst.1 = worst.1.max(en);
                    }
                }
                line += &format!(" {n}:{:.4}/{:.4}", worst.0, worst.1);
                worst_at.push((n, worst.2));
                for (k, target) in [0.0025, 0.005].iter().enumerate() {
                    if need[k].is_none() && worst.0.max(worst.1) <= *target {
                        need[k] = Some(n);
                    }
                }
            }
            println!(
                "{line}\n      N(0.25%)={:?} N(0.5%)={:?}  worst at N=16: {}",
                need[0],
                need[1],
                worst_at
                    .iter()
                    .find(|w| w.0 == 16)
                    .map(|w| w.1.to_string())
                    .unwrap_or_default()
            );
        }
    }
}

/// Largest (e_L2, energy error) along one sweep for one T3b axis layout.
fn t3b_axis_error(
    repr: &Repr,
    axis: usize,
    g: &[Exact],
    d: &[NodeData],
    map: &AxisMap,
    n: usize,
) -> (f64, f64, Pt) {
    let zs: Vec<f64> = g
        .iter()
        .map(|e| sweep_coord(axis, e.pt.axis(axis)))
        .collect();
    let lo = g[0].pt.axis(axis);
    let hi = g[g.len() - 1].pt.axis(axis);
    let comp = |f: &dyn Fn(&NodeData) -> f64, z: f64| {
        let ys: Vec<f64> = d.iter().map(f).collect();
        lagrange4(&zs, &ys, z)
    };
    let nodes: Vec<NodeData> = (0..n)
        .map(|i| {
            let z = sweep_coord(axis, map.node(n, i).clamp(lo, hi));
            NodeData {
                ln_s: comp(&|x| x.ln_s, z),
                ln_g: comp(&|x| x.ln_g, z),
                r: (0..repr.n).map(|k| comp(&|x| x.r[k], z)).collect(),
            }
        })
        .collect();
    let mut worst = (0.0f64, 0.0f64, g[0].pt);
    for (e, own) in g.iter().zip(d) {
        let (i, t) = map.locate(n, e.pt.axis(axis));
        let nd = if PARAM_CUBIC.load(std::sync::atomic::Ordering::Relaxed) && n >= 4 {
            // 4-point Lagrange in the mapped coordinate (nodes i−1 … i+2,
            // shifted inside the axis at its ends).
            let j = i.clamp(1, n - 3) - 1;
            let x = (i - j) as f64 + t;
            let w = [
                -(x - 1.0) * (x - 2.0) * (x - 3.0) / 6.0,
                x * (x - 2.0) * (x - 3.0) / 2.0,
                -x * (x - 1.0) * (x - 3.0) / 2.0,
                x * (x - 1.0) * (x - 2.0) / 6.0,
            ];
            NodeData::blend(&[
                (w[0], &nodes[j]),
                (w[1], &nodes[j + 1]),
                (w[2], &nodes[j + 2]),
                (w[3], &nodes[j + 3]),
            ])
        } else {
            NodeData::blend(&[(1.0 - t, &nodes[i]), (t, &nodes[i + 1])])
        };
        let (a, b) = if PARAM_ONLY.load(std::sync::atomic::Ordering::Relaxed) {
            // The interpolation's own error: against the representation
            // with this point's own node data (relative to ‖C‖).
            let v: Vec<f64> = e
                .rule
                .nodes
                .iter()
                .map(|&th| repr.decode(&e.pt, own, th))
                .collect();
            let mut num = 0.0;
            let mut en = 0.0;
            let mut en0 = 0.0;
            for ((&th, &w), &x) in e.rule.nodes.iter().zip(&e.rule.weights).zip(&v) {
                let y = repr.decode(&e.pt, &nd, th);
                num += w * (y - x) * (y - x);
                en += w * y * th.cos();
                en0 += w * x * th.cos();
            }
            ((num / e.norm2).sqrt(), (en / en0 - 1.0).abs())
        } else {
            e.errors(|th| repr.decode(&e.pt, &nd, th))
        };
        if a > worst.0 {
            worst.0 = a;
            worst.2 = e.pt;
        }
        worst.1 = worst.1.max(b);
    }
    worst
}

/// `t3b-axes` measures the parameter interpolation alone (against the
/// representation at the point's own node data) when set (argument
/// `--param-only`).
static PARAM_ONLY: std::sync::atomic::AtomicBool = std::sync::atomic::AtomicBool::new(false);

/// `t3b-axes` interpolates along the parameter axis with a local cubic
/// (4-point Lagrange in the mapped coordinate) instead of linearly when set
/// (argument `--param-cubic`).
static PARAM_CUBIC: std::sync::atomic::AtomicBool = std::sync::atomic::AtomicBool::new(false);

// ---------------------------------------------------------------------------
// 4-D cell checks of a proposed grid
// ---------------------------------------------------------------------------

/// A proposed 4-D grid: mapping and node count per axis (u, c, β, p).
struct Layout {
    axes: [(AxisMap, usize); 4],
}

impl Layout {
    fn nodes(&self) -> usize {
        self.axes.iter().map(|a| a.1).product()
    }

    fn describe(&self) -> String {
        let mut s = String::new();
        for (k, (m, n)) in self.axes.iter().enumerate() {
            s += &format!("{}: {} nodes, {};  ", AXES[k], n, m.describe());
        }
        s + &format!("{} nodes", self.nodes())
    }
}

/// The grids checked by `cells` (chosen from the 1-D studies).
fn layout(name: &str) -> Option<Layout> {
    use Mapping::*;
    let (u, c, b, p) = match name {
        // A fine grid (184 k nodes): T3a alone would take 0.37 M values;
        // T3b on it would not fit the budget.
        "A" => (
            (AxisMap::new(LogOffset, 0.1, 0.0, 0.0, U_MAX), 40),
            (AxisMap::new(Log, 0.0, 1.0, C_LO, C_HI), 12),
            (AxisMap::new(Log, 0.0, 0.0, BETA_LO, BETA_HI), 24),
            (AxisMap::new(Power, -0.5, 0.0, P_LO, P_HI), 16),
        ),
        // The budget grid (20 160 nodes): T3b with 32 angular values per
        // node (645 k values) plus T3a's 2 (40 k) fits in ≈ 2.6 MiB.
        "B" => (
            (AxisMap::new(LogOffset, 0.1, 0.0, 0.0, U_MAX), 20),
            (AxisMap::new(Log, 0.0, 1.0, C_LO, C_HI), 8),
            (AxisMap::new(Log, 0.0, 0.0, BETA_LO, BETA_HI), 14),
            (AxisMap::new(Power, -0.5, 0.0, P_LO, P_HI), 9),
        ),
        _ => return None,
    };
    Some(Layout { axes: [u, c, b, p] })
}

/// A random test point and the 16 corners of its grid cell, with the
/// quadrilinear weights of the corners.
struct Cell {
    x: Pt,
    corners: Vec<(f64, Pt)>,
}

impl Cell {
    fn all_points(&self) -> Vec<Pt> {
        let mut v = vec![self.x];
        v.extend(self.corners.iter().map(|c| c.1));
        v
    }
}

/// 24 test points, uniform in the mapped coordinate of every axis of the
/// layout (so that every cell is equally likely; seed 0xce11), with their
/// cells.
fn cell_points(layout: &Layout) -> Vec<Cell> {
    let mut rng = SplitMix64::new(0xce11);
    (0..24)
        .map(|_| {
            let mut x = [0.0; 4];
            for (k, (m, _)) in layout.axes.iter().enumerate() {
                let (a, b) = (m.coord(m.lo), m.coord(m.hi));
                let y = rng.uniform_in(a, b);
                x[k] = m.inverse(y).clamp(m.lo, m.hi);
            }
            let pt = Pt::new(x[0], x[1], x[2], x[3]);
            let loc: Vec<(usize, f64)> = layout
                .axes
                .iter()
                .enumerate()
                .map(|(k, (m, n))| m.locate(*n, x[k]))
                .collect();
            let mut corners = Vec::new();
            for bits in 0..16 {
                let mut w = 1.0;
                let mut c = pt;
                for (k, (m, n)) in layout.axes.iter().enumerate() {
                    let hi = (bits >> k) & 1 == 1;
                    let (i, t) = loc[k];
                    w *= if hi { t } else { 1.0 - t };
                    c = c.with_axis(k, m.node(*n, i + usize::from(hi)));
                }
                corners.push((w, c));
            }
            Cell { x: pt, corners }
        })
        .collect()
}

/// The 4-D check: T3a (interpolated paper form vs fitted form and vs exact)
/// and T3b (`repr`, vs exact) at the test points of a layout.
fn cells(layout: &Layout, repr: &Repr) {
    let name = ["A", "B"]
        .into_iter()
        .find(|n| layout.describe() == self::layout(n).unwrap().describe())
        .unwrap();
    let set = format!("cells-{name}");
    println!(
        "layout {name}: {}\nT3b: {}",
        layout.describe(),
        repr.describe()
    );
    let cache = load_cache(&set);
    let get = |pt: &Pt| match cache.get(&pt.key()) {
        Some(Cached {
            order,
            values: Some(v),
            ..
        }) => Some(Exact::new(*pt, *order, v.clone())),
        _ => None,
    };
    let (mut a_fit, mut a_exact, mut a_direct, mut b_el2, mut b_en) =
        (vec![], vec![], vec![], vec![], vec![]);
    for cell in cell_points(layout) {
        let Some(ex) = get(&cell.x) else { continue };
        let corners: Option<Vec<(f64, Exact)>> = cell
            .corners
            .iter()
            .map(|(w, c)| get(c).map(|e| (*w, e)))
            .collect();
        let Some(corners) = corners else { continue };
        // T3a: quadrilinear interpolation of the stored pair, for each fit
        // and storage: [LS (ln s, ln g), LS (ln s, ln(g²+0.09)),
        // moment (ln s, ln(g²+0.09))].
        let variants = [
            (FitKind::Ls, Stored::Log),
            (FitKind::Ls, Stored::LogSq(0.3)),
            (FitKind::Moment, Stored::LogSq(0.3)),
        ];
        let mut e_fit = [0.0; 3];
        let mut e_ex = [0.0; 3];
        let mut e_dir = [0.0; 3];
        for (v, (kind, stored)) in variants.iter().enumerate() {
            let fx = kind.fit(&ex);
            let (mut a, mut b) = (0.0, 0.0);
            for (w, e) in &corners {
                let (qa, qb) = stored.encode(&kind.fit(e));
                a += w * qa;
                b += w * qb;
            }
            let (s, g) = stored.decode(a, b);
            let interp = Form { s, g, ..fx };
            e_fit[v] = form_distance(ex.pt, &interp, &fx);
            e_ex[v] = ex.e_l2(|t| interp.eval(t));
            e_dir[v] = fx.e_l2;
        }
        a_fit.push(e_fit);
        a_exact.push(e_ex);
        a_direct.push(e_dir);
        // T3b.
        let data: Vec<(f64, NodeData)> =
            corners.iter().map(|(w, e)| (*w, repr.encode(e))).collect();
        let parts: Vec<(f64, &NodeData)> = data.iter().map(|(w, d)| (*w, d)).collect();
        let nd = NodeData::blend(&parts);
        let (e1, e2) = ex.errors(|t| repr.decode(&ex.pt, &nd, t));
        b_el2.push(e1);
        b_en.push(e2);
        println!(
            "  {}  T3a interp-vs-fit {:.4}/{:.4}/{:.4} | T3b: e_L2 {:.4} energy {:.4}",
            ex.pt, e_fit[0], e_fit[1], e_fit[2], e1, e2
        );
    }
    for (v, name) in [
        "LS, (ln s, ln g)",
        "LS, (ln s, ln(g²+0.09))",
        "moment, (ln s, ln(g²+0.09))",
    ]
    .iter()
    .enumerate()
    {
        let col = |x: &Vec<[f64; 3]>| x.iter().map(|r| r[v]).collect::<Vec<f64>>();
        println!("T3a {name}:");
        println!("  interpolated vs fitted form: {}", stats(&col(&a_fit)));
        println!("  fitted form vs exact:        {}", stats(&col(&a_direct)));
        println!("  interpolated vs exact:       {}", stats(&col(&a_exact)));
    }
    println!("T3b e_L2 vs exact:               {}", stats(&b_el2));
    println!("T3b energy error:                {}", stats(&b_en));
}

/// Reference cost per grid node, from the corners of the cell checks
/// (uniformly random grid nodes), and the resulting build time.
fn timing(layout: &Layout) {
    let name = ["A", "B"]
        .into_iter()
        .find(|n| layout.describe() == self::layout(n).unwrap().describe())
        .unwrap();
    let cache = load_cache(&format!("cells-{name}"));
    let mut secs = Vec::new();
    // The build needs C at the angular nodes of T3b plus a quadrature for the
    // fit (≈ 100 angles) instead of the study's ≈ 250–600: the direct
    // quadrature costs per angle, the zonal harmonics per profile.
    let build_angles = 100.0;
    let mut build = Vec::new();
    let mut direct = 0;
    let mut seen = std::collections::HashSet::new();
    for cell in cell_points(layout) {
        for (_, c) in &cell.corners {
            if !seen.insert(c.key()) {
                continue;
            }
            if let Some(e) = cache.get(&c.key()) {
                secs.push(e.seconds);
                let n = e.values.as_ref().map_or(1, Vec::len) as f64;
                if e.method == "direct" {
                    direct += 1;
                    build.push(e.seconds * (build_angles / n).min(1.0));
                } else {
                    build.push(e.seconds);
                }
            }
        }
    }
    if secs.is_empty() {
        println!("no cached corners for layout {name}");
        return;
    }
    let mean = secs.iter().sum::<f64>() / secs.len() as f64;
    let st = stats(&secs);
    println!(
        "{} grid nodes sampled ({direct} by direct quadrature): seconds per profile mean {mean:.3}, {st}",
        secs.len()
    );
    let n = layout.nodes() as f64;
    println!(
        "layout {name} ({} nodes), study rule: {:.1} core-hours, {:.1} h on 2 cores",
        layout.nodes(),
        n * mean / 3600.0,
        n * mean / 7200.0
    );
    let bmean = build.iter().sum::<f64>() / build.len() as f64;
    println!(
        "  with {build_angles} angles per direct profile: {bmean:.3} s per node, {:.1} core-hours, {:.1} h on 2 cores",
        n * bmean / 3600.0,
        n * bmean / 7200.0
    );
}

/// Prints one cached sample profile at a few angles with its fits (debugging aid).
fn show(set: &str, k: usize) {
    let ex = &exact_set(set)[k];
    let f0 = fit_paper(ex, 0.0);
    let f2 = fit_paper(ex, 2.0);
    let fm = fit_moment(ex);
    println!("{}  C(0) {:e} energy {:e}", ex.pt, ex.at(0.0), ex.energy);
    println!(
        "  ls  s {:e} g {:e} e_L2 {:.3}\n  ls2 s {:e} g {:e} e_L2 {:.3}\n  mom s {:e} g {:e} e_L2 {:.3}",
        f0.s, f0.g, f0.e_l2, f2.s, f2.g, f2.e_l2, fm.s, fm.g, fm.e_l2
    );
    let mut t = 1e-6;
    while t < FRAC_PI_2 {
        println!(
            "  θ {t:.3e}  C {:.4e}  ls {:.4e} mom {:.4e}",
            ex.at(t),
            f0.eval(t),
            fm.eval(t)
        );
        t *= 2.0;
    }
    // Where the L2 mass is: cumulative ∫ C² sin over the rule.
    let mut acc = 0.0;
    let mut marks = vec![0.1, 0.5, 0.9, 0.99];
    for ((&t, &w), &c) in ex.rule.nodes.iter().zip(&ex.rule.weights).zip(&ex.values) {
        acc += w * c * c;
        while !marks.is_empty() && acc >= marks[0] * ex.norm2 {
            println!(
                "  {:.0}% of ∫C² sinθ below θ = {t:.3e}",
                100.0 * marks.remove(0)
            );
        }
    }
}
