//! Does a not-a-knot cubic B-spline (coefficients prefiltered by the
//! generator, stored in place of the node values: same size) interpolate
//! T3b better than the shipped Catmull–Rom lookup? Measured on the committed
//! table's node values at random parameter points against exact profiles.
//!
//! ```text
//! cargo run --release -p generator --example t3_spline_study -- [profiles] [seed]
//! ```
//!
//! Variants (parameters / ξ): `cr/cr` is the shipped lookup (re-implemented
//! here in f64, checked against the runtime), `bs/cr` prefilters the four
//! parameter axes, `bs/bs` also ξ. Errors: e_L2 per profile; pointwise
//! relative error on the metric's rule nodes, split by C/C(0) (the BRDF
//! reads C's tails, down to ~1e-9 C(0)).
//!
//! Environment switches (the studies behind the shipped T3; README, T3):
//! * `T3_SNAP=ucbp` (any subset): snap those parameters of the points to their
//!   nearest nodes, isolating the other axes' (and ξ's) error;
//! * `T3_BRDF_POINTS=1`: draw points as `tests/independent/brdf_scipy.py` does;
//! * `T3_AXIS_STUDY=n T3_AXIS=u|c|p`: one axis's mapping alone, candidates
//!   compared on `n` random points (exact profiles at the candidate nodes);
//! * `T3_ANGLE_STUDY=n`: the normalised angle's softening κ, ξ alone;
//! * `T3_ANGLE_VARIABLE_STUDY=n`: forms of the angle ([`Form`]: kernel
//!   term in `sin θh`, horizon and edge terms), ξ alone, including θh
//!   uniform; `T3_FULL_DOMAIN=1` draws verify's profiles instead of the BRDF
//!   check's;
//! * `T3_XI_AT_POINTS=file.csv` (`u,c,beta,p,theta_h`): exact C and its
//!   ξ-only interpolation with the previous (format 1) and the shipped
//!   (format 2) angle, per point;
//! * `T3_PATCH_STUDY=n`: the angle forms with β and p interpolated too (the
//!   4 × 4 β, p nodes around each of `n` verify profiles, u and c exact),
//!   against ξ alone; `T3_PATCH=1` does the same at `T3_XI_AT_POINTS`;
//! * `T3_FORMS="w_h,w_e,smoothing,τ_f;…"`: the forms those three compare
//!   (`w_h < 0`: format 1's angle).

use generator::reference::conv::{Params, ProfileRule, convolution_profile, e_l2_on};
use generator::tables::t3;
use rayon::prelude::*;
use twoscale::conv::{
    AngleParams, ConvTable, FIT_CHANNELS, normalised_angle, tan_of_normalised_angle,
};
use twoscale::interp::{coordinate_f64, node_value};

const AXES: [twoscale::format::AxisHeader; 4] = [t3::U_AXIS, t3::C_AXIS, t3::BETA_AXIS, t3::P_AXIS];

#[derive(Clone, Copy, PartialEq)]
enum Scheme {
    /// Catmull–Rom, quadratic in the end cells (the shipped lookup).
    CatmullRom,
    /// Catmull–Rom with secant end slopes (the shipped lookup along ξ).
    CatmullRomSecantEnds,
    /// Cubic B-spline on prefiltered coefficients, not-a-knot ends.
    NotAKnot,
}

/// Weights on 4 consecutive nodes/coefficients `start..start+4` at fractional
/// position `x ∈ [0, n−1]`.
fn weights(scheme: Scheme, n: usize, x: f64) -> (usize, [f64; 4]) {
    let i = (x.floor().max(0.0) as usize).min(n - 2);
    let t = x - i as f64;
    match scheme {
        Scheme::CatmullRom => {
            if i == 0 {
                (
                    0,
                    [
                        0.5 * (t - 1.0) * (t - 2.0),
                        -t * (t - 2.0),
                        0.5 * t * (t - 1.0),
                        0.0,
                    ],
                )
            } else if i + 2 == n {
                (
                    n - 4,
                    [
                        0.0,
                        0.5 * t * (t - 1.0),
                        (1.0 - t) * (1.0 + t),
                        0.5 * t * (t + 1.0),
                    ],
                )
            } else {
                let t2 = t * t;
                let t3 = t2 * t;
                (
                    i - 1,
                    [
                        0.5 * (-t3 + 2.0 * t2 - t),
                        0.5 * (3.0 * t3 - 5.0 * t2 + 2.0),
                        0.5 * (-3.0 * t3 + 4.0 * t2 + t),
                        0.5 * (t3 - t2),
                    ],
                )
            }
        }
        Scheme::CatmullRomSecantEnds => {
            let t2 = t * t;
            let t3 = t2 * t;
            let h00 = 2.0 * t3 - 3.0 * t2 + 1.0;
            let h10 = t3 - 2.0 * t2 + t;
            let h01 = -2.0 * t3 + 3.0 * t2;
            let h11 = t3 - t2;
            if i == 0 {
                (0, [h00 - h10 - 0.5 * h11, h10 + h01, 0.5 * h11, 0.0])
            } else if i + 2 == n {
                (n - 4, [0.0, -0.5 * h10, h00 - h11, 0.5 * h10 + h01 + h11])
            } else {
                weights(Scheme::CatmullRom, n, x)
            }
        }
        Scheme::NotAKnot => {
            let s = 1.0 - t;
            let b = [
                s * s * s / 6.0,
                (3.0 * t * t * t - 6.0 * t * t + 4.0) / 6.0,
                (-3.0 * t * t * t + 3.0 * t * t + 3.0 * t + 1.0) / 6.0,
                t * t * t / 6.0,
            ];
            if i == 0 {
                // c₋₁ = 4c₀ − 6c₁ + 4c₂ − c₃ (zero 4th difference: not-a-knot).
                (
                    0,
                    [
                        b[1] + 4.0 * b[0],
                        b[2] - 6.0 * b[0],
                        b[3] + 4.0 * b[0],
                        -b[0],
                    ],
                )
            } else if i + 2 == n {
                (
                    n - 4,
                    [
                        -b[3],
                        b[0] + 4.0 * b[3],
                        b[1] - 6.0 * b[3],
                        b[2] + 4.0 * b[3],
                    ],
                )
            } else {
                (i - 1, b)
            }
        }
    }
}

/// The matrix taking coefficients to node values, inverted: coefficients =
/// inverse · values.
fn prefilter_matrix(n: usize) -> Vec<Vec<f64>> {
    let mut m = vec![vec![0.0; 2 * n]; n];
    for (j, row) in m.iter_mut().enumerate() {
        let (start, w) = weights(Scheme::NotAKnot, n, j as f64);
        for k in 0..4 {
            row[start + k] += w[k];
        }
        row[n + j] = 1.0;
    }
    // Gauss–Jordan with partial pivoting.
    for col in 0..n {
        let pivot = (col..n)
            .max_by(|&a, &b| m[a][col].abs().total_cmp(&m[b][col].abs()))
            .unwrap();
        m.swap(col, pivot);
        let d = m[col][col];
        for v in m[col].iter_mut() {
            *v /= d;
        }
        for r in 0..n {
            if r != col {
                let f = m[r][col];
                if f != 0.0 {
                    let pivot_row = m[col].clone();
                    for (v, pv) in m[r].iter_mut().zip(&pivot_row) {
                        *v -= f * pv;
                    }
                }
            }
        }
    }
    m.into_iter().map(|row| row[n..].to_vec()).collect()
}

/// Applies the prefilter along dimension `d` of a row-major array with
/// dims `dims`.
fn prefilter_along(data: &mut [f64], dims: &[usize], d: usize) {
    let n = dims[d];
    let inv = prefilter_matrix(n);
    let inner: usize = dims[d + 1..].iter().product();
    let outer: usize = dims[..d].iter().product();
    let mut line = vec![0.0; n];
    for o in 0..outer {
        for i in 0..inner {
            for (k, v) in line.iter_mut().enumerate() {
                *v = data[(o * n + k) * inner + i];
            }
            for j in 0..n {
                data[(o * n + j) * inner + i] = (0..n).map(|k| inv[j][k] * line[k]).sum();
            }
        }
    }
}

struct Variant {
    name: &'static str,
    params: Scheme,
    xi: Scheme,
    /// ln C (or coefficients) per node, `ANGLES` per node.
    data: Vec<f64>,
}

fn position(d: usize, x: f64) -> f64 {
    let a = &AXES[d];
    let lo = coordinate_f64(a, a.lo);
    let hi = coordinate_f64(a, a.hi);
    ((coordinate_f64(a, x.clamp(a.lo, a.hi)) - lo) / (hi - lo) * (a.nodes - 1) as f64)
        .clamp(0.0, (a.nodes - 1) as f64)
}

fn lookup(v: &Variant, pt: [f64; 4], tau: f64) -> f64 {
    let n = t3::ANGLES;
    let dims: Vec<usize> = AXES.iter().map(|a| a.nodes as usize).collect();
    let w: Vec<(usize, [f64; 4])> = (0..4)
        .map(|d| weights(v.params, dims[d], position(d, pt[d])))
        .collect();
    let xi = normalised_angle(tau, pt[0], pt[2], pt[3], &t3::ANGLE) * (n - 1) as f64;
    let (xs, xw) = weights(v.xi, n, xi);
    let mut sum = 0.0;
    for a in 0..4 {
        for b in 0..4 {
            for c in 0..4 {
                for e in 0..4 {
                    let wt = w[0].1[a] * w[1].1[b] * w[2].1[c] * w[3].1[e];
                    if wt == 0.0 {
                        continue;
                    }
                    let node = (((w[0].0 + a) * dims[1] + w[1].0 + b) * dims[2] + w[2].0 + c)
                        * dims[3]
                        + w[3].0
                        + e;
                    let base = node * n + xs;
                    let s: f64 = (0..4).map(|k| xw[k] * v.data[base + k]).sum();
                    sum += wt * s;
                }
            }
        }
    }
    sum.exp()
}

struct Exact {
    point: [f64; 4],
    rule: ProfileRule,
    values: Vec<f64>,
    c0: f64,
}

/// SPEC's e_L2 (`generator::reference::conv::e_l2_on`) of values `approx`
/// already computed at the rule's nodes (ascending), against `exact` there.
fn e_l2_at_nodes(rule: &ProfileRule, approx: &[f64], exact: &[f64]) -> f64 {
    e_l2_on(
        rule,
        |t| {
            let k = rule.nodes.partition_point(|&x| x < t);
            assert_eq!(rule.nodes[k], t, "rule nodes ascending");
            approx[k]
        },
        exact,
    )
}

/// The `qs` quantiles of `v` as percentages, space-separated.
fn percentiles(v: &mut [f64], qs: &[f64]) -> String {
    let cells: Vec<String> = qs
        .iter()
        .map(|&q| format!("{:.2}%", 100.0 * quantile(v, q)))
        .collect();
    cells.join(" ")
}

fn quantile(v: &mut [f64], q: f64) -> f64 {
    if v.is_empty() {
        return f64::NAN;
    }
    v.sort_by(f64::total_cmp);
    v[((v.len() - 1) as f64 * q).round() as usize]
}

/// 1-D study of one parameter axis's mapping (`axis` 1 = c, 3 = p): at
/// random other parameters and the node's 32 angles, ln C at the nodes of
/// each candidate axis, interpolated (Catmull–Rom, as shipped) to random
/// values and compared with exact. Two distributions: `verify`'s (uniform in
/// the shipped mapped coordinates) and `brdf_scipy.py`'s (β log-uniform in
/// [0.05, 1], p uniform in [0.5, 5], c uniform in [1.2, 6], u log-uniform in
/// [0.5, 50]).
fn axis_study(
    axis: usize,
    candidates: &[twoscale::format::AxisHeader],
    triples: usize,
    brdf: bool,
) {
    let mut rng = generator::rng::SplitMix64::new(7 + axis as u64 + 100 * brdf as u64);
    let points: Vec<[f64; 4]> = if brdf {
        brdf_check_profiles(&mut rng, triples * 3)
    } else {
        t3::verification_points(triples * 3, 7 + axis as u64)
    };
    let t0 = std::time::Instant::now();
    type Row = (Vec<Vec<Vec<f64>>>, Vec<(f64, Vec<f64>)>);
    let rows: Vec<Row> = (0..triples)
        .into_par_iter()
        .map(|t| {
            let base = points[3 * t];
            let (thetas, _) = t3::angle_rule(base[0], base[2], base[3]);
            let profile = |x: f64| -> Vec<f64> {
                let mut q = base;
                q[axis] = x;
                let (thetas, _) = if axis == 3 || axis == 0 {
                    t3::angle_rule(q[0], q[2], q[3])
                } else {
                    (thetas.clone(), vec![])
                };
                let v = convolution_profile(q[0], q[1], q[2], q[3], &thetas).unwrap();
                let peak = v.iter().cloned().fold(0.0f64, f64::max);
                v.iter()
                    .map(|&x| x.max(t3::VALUE_FLOOR * peak).ln())
                    .collect()
            };
            let nodes: Vec<Vec<Vec<f64>>> = candidates
                .iter()
                .map(|a| {
                    (0..a.nodes as usize)
                        .map(|i| profile(twoscale::interp::node_value(a, i)))
                        .collect()
                })
                .collect();
            let tests: Vec<(f64, Vec<f64>)> = (1..3)
                .map(|k| {
                    let x = points[3 * t + k][axis];
                    (x, profile(x))
                })
                .collect();
            (nodes, tests)
        })
        .collect();
    eprintln!(
        "axis {axis} study: {triples} triples in {:.1} s",
        t0.elapsed().as_secs_f64()
    );
    for (ci, a) in candidates.iter().enumerate() {
        let n = a.nodes as usize;
        let (mut core, mut tail) = (Vec::new(), Vec::new());
        for (nodes, tests) in &rows {
            let nodes = &nodes[ci];
            for (x, exact) in tests {
                let lo = coordinate_f64(a, a.lo);
                let hi = coordinate_f64(a, a.hi);
                let pos = (coordinate_f64(a, *x) - lo) / (hi - lo) * (n - 1) as f64;
                let (start, w) = weights(Scheme::CatmullRom, n, pos.clamp(0.0, (n - 1) as f64));
                let peak = exact.iter().cloned().fold(f64::MIN, f64::max);
                for (k, &e) in exact.iter().enumerate() {
                    let v: f64 = (0..4).map(|j| w[j] * nodes[start + j][k]).sum();
                    let rel = (v - e).exp_m1().abs();
                    if e > peak + (1e-3f64).ln() {
                        core.push(rel);
                    } else if e > peak + (1e-9f64).ln() {
                        tail.push(rel);
                    }
                }
            }
        }
        let pct = |x: f64| format!("{:.2}%", 100.0 * x);
        println!(
            "{} {:2} nodes {:?} param {} param2 {}: core median/p95/max {} {} {} | tail {} {} {}",
            if brdf { "brdf  " } else { "verify" },
            n,
            a.mapping,
            a.param,
            a.param2,
            pct(quantile(&mut core, 0.5)),
            pct(quantile(&mut core, 0.95)),
            pct(quantile(&mut core, 1.0)),
            pct(quantile(&mut tail, 0.5)),
            pct(quantile(&mut tail, 0.95)),
            pct(quantile(&mut tail, 1.0)),
        );
    }
}

/// The normalised angle with the NDF exponent softened where the kernel is
/// wider than the NDF: `2p → 2p / (1 + κ p r)`, `r = 1/(2 u_e β)`
/// (κ = 0: the first tables' angle; κ = 1: format 1's).
fn angle_f(tau: f64, u: f64, beta: f64, p: f64, kappa: f64) -> f64 {
    let a = t3::ANGLE;
    let ue = (u * u + a.kernel_scale_floor * a.kernel_scale_floor).sqrt();
    let r = 1.0 / (2.0 * ue * beta);
    let p_eff = p / (1.0 + kappa * p * r);
    let y = if tau > 0.0 {
        (2.0 * p_eff * (tau / beta).ln()).exp()
    } else {
        0.0
    };
    let cap = a.ndf_exponent_cap;
    (2.0 * ue * tau).asinh() + a.ndf_weight * (cap * -(-(y / cap)).exp_m1()).ln_1p()
}

fn tau_of_xi(xi: f64, u: f64, beta: f64, p: f64, kappa: f64) -> f64 {
    let top = angle_f(t3::ANGLE.tau_max, u, beta, p, kappa);
    let (mut lo, mut hi) = (0.0f64, t3::ANGLE.tau_max.ln_1p());
    for _ in 0..100 {
        let mid = 0.5 * (lo + hi);
        if angle_f(mid.exp_m1(), u, beta, p, kappa) < xi * top {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    (0.5 * (lo + hi)).exp_m1()
}

/// `(u, c, β, p)` of `profiles` profiles drawn from `brdf_scipy.py`'s
/// parameter distribution (u log-uniform in [0.5, 50]).
fn brdf_check_profiles(rng: &mut generator::rng::SplitMix64, profiles: usize) -> Vec<[f64; 4]> {
    (0..profiles)
        .map(|_| {
            let u = rng.log_uniform_in(0.5, 50.0);
            let c = rng.uniform_in(1.2, 6.0);
            let beta = rng.log_uniform_in(0.05, 1.0);
            let p = rng.uniform_in(0.5, 5.0);
            [u, c, beta, p]
        })
        .collect()
}

/// ξ-only error (parameters exact) of 32 angles under the angle function
/// with each κ, on the same distributions as `axis_study`.
fn angle_study(profiles: usize, kappas: &[f64]) {
    for brdf in [false, true] {
        let mut rng = generator::rng::SplitMix64::new(31 + brdf as u64);
        let points: Vec<[f64; 4]> = if brdf {
            brdf_check_profiles(&mut rng, profiles)
        } else {
            t3::verification_points(profiles, 31)
        };
        // Per point, per κ: (e_L2, approximation, exact) on the rule.
        type PerKappa = Vec<(f64, Vec<f64>, Vec<f64>)>;
        let results: Vec<PerKappa> = points
            .par_iter()
            .map(|&[u, c, beta, p]| {
                let params = Params::new(u, c, beta, p).unwrap();
                let rule = ProfileRule::with_order(ProfileRule::width_for(&params), 8);
                let exact = convolution_profile(u, c, beta, p, &rule.nodes).unwrap();
                kappas
                    .iter()
                    .map(|&kappa| {
                        let n = t3::ANGLES;
                        let thetas: Vec<f64> = (0..n)
                            .map(|k| tau_of_xi(k as f64 / (n - 1) as f64, u, beta, p, kappa).atan())
                            .collect();
                        let v = convolution_profile(u, c, beta, p, &thetas).unwrap();
                        let peak = v.iter().cloned().fold(0.0f64, f64::max);
                        let ln_v: Vec<f64> = v
                            .iter()
                            .map(|&x| x.max(t3::VALUE_FLOOR * peak).ln())
                            .collect();
                        let top = angle_f(t3::ANGLE.tau_max, u, beta, p, kappa);
                        let approx: Vec<f64> = rule
                            .nodes
                            .iter()
                            .map(|&t| {
                                let xi = angle_f(t.tan().min(t3::ANGLE.tau_max), u, beta, p, kappa)
                                    / top;
                                let (start, w) = weights(
                                    Scheme::CatmullRomSecantEnds,
                                    n,
                                    (xi * (n - 1) as f64).clamp(0.0, (n - 1) as f64),
                                );
                                (0..4).map(|j| w[j] * ln_v[start + j]).sum::<f64>().exp()
                            })
                            .collect();
                        (e_l2_at_nodes(&rule, &approx, &exact), approx, exact.clone())
                    })
                    .collect()
            })
            .collect();
        for (ki, kappa) in kappas.iter().enumerate() {
            let (mut el2, mut core, mut tail) = (Vec::new(), Vec::new(), Vec::new());
            for r in &results {
                let (e, approx, exact) = &r[ki];
                el2.push(*e);
                let peak = exact.iter().cloned().fold(0.0f64, f64::max);
                for (a, x) in approx.iter().zip(exact) {
                    let rel = ((a - x) / x).abs();
                    if *x > 1e-3 * peak {
                        core.push(rel);
                    } else if *x > 1e-9 * peak {
                        tail.push(rel);
                    }
                }
            }
            println!(
                "{} kappa {kappa:4}: e_L2 median/p90/max {} | core median/p95/max {} | tail {}",
                if brdf { "brdf  " } else { "verify" },
                percentiles(&mut el2, &[0.5, 0.9, 1.0]),
                percentiles(&mut core, &[0.5, 0.95, 1.0]),
                percentiles(&mut tail, &[0.5, 0.95, 1.0]),
            );
        }
    }
}

/// The forms of `T3_FORMS="w_h,w_e,smooth,τ_cut;…"` ([`Form`]), or `default`.
fn forms_from_env_or(default: &[Form]) -> Vec<Form> {
    std::env::var("T3_FORMS")
        .map(|v| {
            v.split(';')
                .filter_map(|f| {
                    let mut x = [0.0; 4];
                    for (slot, v) in x.iter_mut().zip(f.split(',')) {
                        *slot = v.trim().parse().ok()?;
                    }
                    Some(x)
                })
                .collect()
        })
        .unwrap_or_else(|_| default.to_vec())
}

/// The angle variable study's forms: `T3_FORMS`, or the first study's five.
fn forms_from_env() -> Vec<Form> {
    forms_from_env_or(
        &[(-1.0, 0.0), (0.5, 0.0), (0.5, 1.0), (0.5, 2.0), (1.0, 1.0)]
            .map(|(h, e)| [h, e, 0.0, 0.0]),
    )
}

/// An angle form: `[w_h, w_e, smoothing, τ_f]`, the runtime's
/// `AngleParams::{horizon_weight, edge_weight, edge_smoothing, edge_fade_tan}`
/// with the other constants of `t3::ANGLE` (format 2 ships `[½, ½, 2, 3]`;
/// `τ_f = 0`: no fade). `w_h < 0`: format 1's angle (`angle_f` with κ = 1).
type Form = [f64; 4];

/// The runtime's angle constants for `form`; `None` for format 1's angle.
fn form_params([horizon, edge, smoothing, fade_tan]: Form) -> Option<AngleParams> {
    (horizon >= 0.0).then_some(AngleParams {
        horizon_weight: horizon,
        edge_weight: edge,
        edge_smoothing: smoothing,
        edge_fade_tan: if fade_tan > 0.0 {
            fade_tan
        } else {
            f64::INFINITY
        },
        ..t3::ANGLE
    })
}

/// ξ of `τ = tan θh` under the angle `form` (the runtime's
/// `normalised_angle`, or format 1's).
fn xi_of(tau: f64, u: f64, beta: f64, p: f64, form: Form) -> f64 {
    let tau = tau.min(t3::ANGLE.tau_max);
    match form_params(form) {
        Some(a) => normalised_angle(tau, u, beta, p, &a),
        None => {
            let kappa = t3::ANGLE.ndf_softening;
            angle_f(tau, u, beta, p, kappa) / angle_f(t3::ANGLE.tau_max, u, beta, p, kappa)
        }
    }
}

/// θh of `ξ` under the angle `form` (the inverse of [`xi_of`]).
fn theta_of(xi: f64, u: f64, beta: f64, p: f64, form: Form) -> f64 {
    match form_params(form) {
        Some(a) => tan_of_normalised_angle(xi, u, beta, p, &a),
        None => tau_of_xi(xi, u, beta, p, t3::ANGLE.ndf_softening),
    }
    .atan()
}

/// C at the angles `thetas` from the exact values at the 32 nodes of the
/// angle `form` ([`Form`]; the node angles by the runtime's inverse),
/// interpolated along ξ as the lookup does: the ξ-only part of T3b's error.
fn xi_only(u: f64, c: f64, beta: f64, p: f64, form: Form, thetas: &[f64]) -> Vec<f64> {
    let ln_v = node_ln_values(u, c, beta, p, form);
    thetas
        .iter()
        .map(|&theta| {
            let (start, w) = xi_weights(u, beta, p, form, theta);
            (0..4).map(|j| w[j] * ln_v[start + j]).sum::<f64>().exp()
        })
        .collect()
}

/// ln C (floored as the table stores it) at the 32 node angles of the angle
/// `form` for the parameters `(u, c, β, p)`: one node of a table built with
/// that form.
fn node_ln_values(u: f64, c: f64, beta: f64, p: f64, form: Form) -> Vec<f64> {
    let n = t3::ANGLES;
    let nodes: Vec<f64> = (0..n)
        .map(|k| theta_of(k as f64 / (n - 1) as f64, u, beta, p, form))
        .collect();
    let v = convolution_profile(u, c, beta, p, &nodes).unwrap();
    let peak = v.iter().cloned().fold(0.0f64, f64::max);
    v.iter()
        .map(|&x| x.max(t3::VALUE_FLOOR * peak).ln())
        .collect()
}

/// The lookup's Catmull–Rom weights along ξ at `θh` for the parameters
/// `(u, β, p)` under the angle `form`.
fn xi_weights(u: f64, beta: f64, p: f64, form: Form, theta: f64) -> (usize, [f64; 4]) {
    let n = t3::ANGLES;
    let xi = xi_of(theta.tan(), u, beta, p, form);
    weights(
        Scheme::CatmullRomSecantEnds,
        n,
        (xi * (n - 1) as f64).clamp(0.0, (n - 1) as f64),
    )
}

/// C at the angles `thetas` as a table built with the angle `form` would
/// give it with u and c exact and β, p interpolated: the 4 × 4 β, p nodes
/// around the point (exact profiles at their own 32 node angles), blended
/// by the lookup's Catmull–Rom weights at equal ξ, then Catmull–Rom along ξ
/// at the point's own ξ(θh). Isolates what β and p interpolation adds to
/// the ξ-only error.
fn beta_p_patch(u: f64, c: f64, beta: f64, p: f64, form: Form, thetas: &[f64]) -> Vec<f64> {
    let (bn, pn) = (t3::BETA_AXIS.nodes as usize, t3::P_AXIS.nodes as usize);
    let (b0, wb) = weights(Scheme::CatmullRom, bn, position(2, beta));
    let (p0, wp) = weights(Scheme::CatmullRom, pn, position(3, p));
    let mut corners = Vec::new();
    for (i, &w_beta) in wb.iter().enumerate() {
        for (j, &w_p) in wp.iter().enumerate() {
            if w_beta * w_p != 0.0 {
                let node_beta = node_value(&t3::BETA_AXIS, b0 + i);
                let node_p = node_value(&t3::P_AXIS, p0 + j);
                corners.push((w_beta * w_p, node_ln_values(u, c, node_beta, node_p, form)));
            }
        }
    }
    thetas
        .iter()
        .map(|&theta| {
            let (start, w) = xi_weights(u, beta, p, form, theta);
            corners
                .iter()
                .map(|(weight, ln_v)| weight * (0..4).map(|j| w[j] * ln_v[start + j]).sum::<f64>())
                .sum::<f64>()
                .exp()
        })
        .collect()
}

/// ξ-only and β, p-patch errors of the angle forms on verify's profiles
/// (u and c exact): pointwise on the profile rule's nodes where
/// C > 1e-3 C(0), and e_L2.
fn patch_study(profiles: usize, forms: &[Form]) {
    let points = t3::verification_points(profiles, 61);
    type Row = Vec<[(f64, Vec<f64>); 2]>;
    let rows: Vec<(Row, Vec<f64>, Vec<f64>, f64)> = points
        .par_iter()
        .map(|&[u, c, beta, p]| {
            let params = Params::new(u, c, beta, p).unwrap();
            let rule = ProfileRule::with_order(ProfileRule::width_for(&params), 8);
            let exact = convolution_profile(u, c, beta, p, &rule.nodes).unwrap();
            let c0 = convolution_profile(u, c, beta, p, &[0.0]).unwrap()[0];
            let per_form = forms
                .iter()
                .map(|&form| {
                    let xi = xi_only(u, c, beta, p, form, &rule.nodes);
                    let patch = beta_p_patch(u, c, beta, p, form, &rule.nodes);
                    [
                        (e_l2_at_nodes(&rule, &xi, &exact), xi),
                        (e_l2_at_nodes(&rule, &patch, &exact), patch),
                    ]
                })
                .collect();
            (per_form, exact, rule.weights.clone(), c0)
        })
        .collect();
    for (fi, form) in forms.iter().enumerate() {
        for (which, name) in ["ξ only", "β, p patch"].iter().enumerate() {
            let (mut el2, mut core) = (vec![], vec![]);
            for (per_form, exact, _, c0) in &rows {
                let (e, approx) = &per_form[fi][which];
                el2.push(*e);
                for (a, x) in approx.iter().zip(exact) {
                    if *x > 1e-3 * c0 {
                        core.push(((a - x) / x).abs());
                    }
                }
            }
            println!(
                "{form:?} {name:10}: e_L2 median/p90/max {} | core median/p95/max {}",
                percentiles(&mut el2, &[0.5, 0.9, 1.0]),
                percentiles(&mut core, &[0.5, 0.95, 1.0]),
            );
        }
    }
}

/// ξ-only error (parameters exact, 32 angles) of the candidate angles
/// ([`Form`]) on `brdf_scipy.py`'s parameter distribution, at the
/// profile rule's nodes and at θh uniform in [0, 1.3] (where the BRDF check
/// reads C: both directions within 75°).
fn angle_variable_study(profiles: usize, horizons: &[Form]) {
    let mut rng = generator::rng::SplitMix64::new(57);
    // `T3_FULL_DOMAIN=1`: verify's distribution over the whole table domain
    // (`generator::tables::t3`, verify) instead of the BRDF check's.
    let full_domain = std::env::var("T3_FULL_DOMAIN").is_ok();
    let points: Vec<[f64; 4]> = if full_domain {
        t3::verification_points(profiles, 57)
    } else {
        brdf_check_profiles(&mut rng, profiles)
    };
    let horizon = if full_domain { 1.55 } else { 1.3 };
    let uniform: Vec<f64> = (0..64).map(|k| horizon * (k as f64 + 0.5) / 64.0).collect();
    // Per point, per variant: (e_L2 on the rule, [(approx, exact)] on the rule
    // and on the uniform angles, C(0)).
    type Row = Vec<(f64, Vec<(f64, f64)>, Vec<(f64, f64)>, f64)>;
    let rows: Vec<Row> = points
        .par_iter()
        .map(|&[u, c, beta, p]| {
            let params = Params::new(u, c, beta, p).unwrap();
            let rule = ProfileRule::with_order(ProfileRule::width_for(&params), 8);
            let exact_rule = convolution_profile(u, c, beta, p, &rule.nodes).unwrap();
            let exact_uniform = convolution_profile(u, c, beta, p, &uniform).unwrap();
            let c0 = convolution_profile(u, c, beta, p, &[0.0]).unwrap()[0];
            horizons
                .iter()
                .map(|&h| {
                    let at_rule = xi_only(u, c, beta, p, h, &rule.nodes);
                    let at_uniform = xi_only(u, c, beta, p, h, &uniform);
                    let e_l2 = e_l2_at_nodes(&rule, &at_rule, &exact_rule);
                    let on_rule: Vec<(f64, f64)> = at_rule
                        .into_iter()
                        .zip(exact_rule.iter().copied())
                        .collect();
                    let on_uniform: Vec<(f64, f64)> = at_uniform
                        .into_iter()
                        .zip(exact_uniform.iter().copied())
                        .collect();
                    (e_l2, on_rule, on_uniform, c0)
                })
                .collect()
        })
        .collect();
    for (vi, h) in horizons.iter().enumerate() {
        let (mut el2, mut core, mut tail, mut far) = (vec![], vec![], vec![], vec![]);
        let mut worst = (0.0f64, [0.0; 4], 0.0, 0.0);
        let mut worst_core = (0.0f64, [0.0; 4]);
        for (row, point) in rows.iter().zip(&points) {
            let (e, on_rule, on_uniform, c0) = &row[vi];
            el2.push(*e);
            for (a, x) in on_rule {
                let rel = ((a - x) / x).abs();
                if *x > 1e-3 * c0 {
                    core.push(rel);
                    if rel > worst_core.0 {
                        worst_core = (rel, *point);
                    }
                } else if *x > 1e-9 * c0 {
                    tail.push(rel);
                }
            }
            for ((a, x), theta) in on_uniform.iter().zip(&uniform) {
                if *x > 1e-9 * c0 {
                    let rel = ((a - x) / x).abs();
                    far.push(rel);
                    if rel > worst.0 {
                        worst = (rel, *point, *theta, x / c0);
                    }
                }
            }
        }
        let pct = |x: f64| format!("{:.2}%", 100.0 * x);
        println!(
            "{}: e_L2 median/p90/max {} {} {} | rule core p95/max {} {} | rule tail p95/max {} {} | θh uniform ≤ {horizon} (C > 1e-9 C0) median/p95/max {} {} {} (worst at u,c,β,p {:?}, θh {:.3}, C/C0 {:.1e}; worst core at {:?})",
            if h[0] < 0.0 {
                "previous (tan θh, format 1)".to_string()
            } else {
                format!(
                    "sin θh, w_h {}, w_e {}, smooth {}, τ_cut {}",
                    h[0], h[1], h[2], h[3]
                )
            },
            pct(quantile(&mut el2, 0.5)),
            pct(quantile(&mut el2, 0.9)),
            pct(quantile(&mut el2, 1.0)),
            pct(quantile(&mut core, 0.95)),
            pct(quantile(&mut core, 1.0)),
            pct(quantile(&mut tail, 0.95)),
            pct(quantile(&mut tail, 1.0)),
            pct(quantile(&mut far, 0.5)),
            pct(quantile(&mut far, 0.95)),
            pct(quantile(&mut far, 1.0)),
            worst.1,
            worst.2,
            worst.3,
            worst_core.1,
        );
    }
}

/// ξ-only C at given points (`u,c,beta,p,theta_h` lines of a CSV file,
/// e.g. the BRDF check's points): exact C, and C from 32 exact node values
/// interpolated along ξ with the previous angle (format 1) and with the
/// form shipped since format 2 (`[½, ½, 2, 3]`), or the
/// forms of `T3_FORMS`. Prints the exact value and one column per form.
fn xi_only_at_points(path: &str) {
    let text = std::fs::read_to_string(path).expect("readable CSV");
    let points: Vec<[f64; 5]> = text
        .lines()
        .skip(1)
        .filter_map(|l| {
            let v: Vec<f64> = l.split(',').filter_map(|x| x.trim().parse().ok()).collect();
            (v.len() == 5).then(|| [v[0], v[1], v[2], v[3], v[4]])
        })
        .collect();
    let forms = forms_from_env_or(&[[-1.0, 0.0, 0.0, 0.0], [0.5, 0.5, 2.0, 3.0]]);
    // `T3_PATCH=1`: β and p interpolated too ([`beta_p_patch`]).
    let patch = std::env::var("T3_PATCH").is_ok();
    let rows: Vec<Vec<f64>> = points
        .par_iter()
        .map(|&[u, c, beta, p, theta]| {
            let exact = convolution_profile(u, c, beta, p, &[theta]).unwrap()[0];
            let mut out = vec![exact];
            for &form in &forms {
                out.push(if patch {
                    beta_p_patch(u, c, beta, p, form, &[theta])[0]
                } else {
                    xi_only(u, c, beta, p, form, &[theta])[0]
                });
            }
            out
        })
        .collect();
    let names: Vec<String> = forms
        .iter()
        .map(|f| format!("{f:?}").replace(", ", " "))
        .collect();
    println!("exact,{}", names.join(","));
    for r in rows {
        let cells: Vec<String> = r.iter().map(|x| x.to_string()).collect();
        println!("{}", cells.join(","));
    }
}

fn main() {
    if let Ok(path) = std::env::var("T3_XI_AT_POINTS") {
        xi_only_at_points(&path);
        return;
    }
    if let Ok(n) = std::env::var("T3_PATCH_STUDY") {
        let forms = forms_from_env_or(&[[-1.0, 0.0, 0.0, 0.0], [0.5, 0.5, 2.0, 3.0]]);
        patch_study(n.parse().unwrap_or(20), &forms);
        return;
    }
    if let Ok(n) = std::env::var("T3_ANGLE_VARIABLE_STUDY") {
        // `T3_FORMS="w_h,w_e;…"` overrides the forms compared (w_h < 0: the
        // previous angle).
        let forms = forms_from_env();
        angle_variable_study(n.parse().unwrap_or(60), &forms);
        return;
    }
    if let Ok(n) = std::env::var("T3_ANGLE_STUDY") {
        angle_study(n.parse().unwrap_or(60), &[0.0, 0.5, 1.0, 2.0, 4.0]);
        return;
    }
    if let Ok(n) = std::env::var("T3_AXIS_STUDY") {
        use twoscale::format::Mapping;
        let n: usize = n.parse().unwrap_or(40);
        let with = |base: twoscale::format::AxisHeader, nodes, mapping, param, param2| {
            let mut a = base;
            (a.nodes, a.mapping, a.param, a.param2) = (nodes, mapping, param, param2);
            a
        };
        let which = std::env::var("T3_AXIS").unwrap_or_else(|_| "p".into());
        let (axis, candidates) = if which == "c" {
            let c = t3::C_AXIS;
            (
                1,
                vec![
                    with(c, 10, Mapping::LogOffset, -1.0, 0.0),
                    with(c, 10, Mapping::LogOffset, -1.0, 0.25),
                    with(c, 10, Mapping::LogOffset, -1.0, 0.5),
                    with(c, 10, Mapping::LogOffset, -1.0, 1.0),
                    with(c, 12, Mapping::LogOffset, -1.0, 0.5),
                ],
            )
        } else if which == "u" {
            let u = t3::U_AXIS;
            (
                0,
                vec![
                    with(u, 16, Mapping::LogOffset, 0.1, 0.0),
                    with(u, 16, Mapping::LogOffset, 1.0, 0.0),
                    with(u, 16, Mapping::LogOffset, 3.0, 0.0),
                    with(u, 20, Mapping::LogOffset, 1.0, 0.0),
                    with(u, 28, Mapping::LogOffset, 0.1, 0.0),
                    with(u, 28, Mapping::LogOffset, 1.0, 0.0),
                ],
            )
        } else {
            let p = t3::P_AXIS;
            (
                3,
                vec![
                    with(p, 12, Mapping::Power, -0.5, 0.0),
                    with(p, 12, Mapping::Log, 0.0, 0.0),
                    with(p, 12, Mapping::Power, -0.25, 0.0),
                    with(p, 12, Mapping::LogOffset, 0.0, 0.3),
                    with(p, 14, Mapping::Log, 0.0, 0.0),
                ],
            )
        };
        for brdf in [false, true] {
            axis_study(axis, &candidates, n, brdf);
        }
        return;
    }
    let args: Vec<String> = std::env::args().collect();
    let profiles: usize = args.get(1).and_then(|s| s.parse().ok()).unwrap_or(120);
    let seed: u64 = args.get(2).and_then(|s| s.parse().ok()).unwrap_or(99);
    let bytes = std::fs::read(concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../tables/t3-convolution.tbl"
    ))
    .expect("tables/t3-convolution.tbl");
    let buf = twoscale::format::aligned_copy(&bytes);
    let table = ConvTable::from_bytes(buf.bytes()).expect("valid T3");
    let raw = twoscale::Table::from_bytes(buf.bytes()).unwrap();
    let grid = raw.quantised().expect("T3 is stored quantised");
    let channels = FIT_CHANNELS + t3::ANGLES;
    let nodes = grid.nodes();
    let ln_c: Vec<f64> = (0..nodes)
        .flat_map(|i| (FIT_CHANNELS..channels).map(move |k| f64::from(grid.value(i, k))))
        .collect();
    let mut dims: Vec<usize> = AXES.iter().map(|a| a.nodes as usize).collect();
    dims.push(t3::ANGLES);
    let mut params_only = ln_c.clone();
    for d in 0..4 {
        prefilter_along(&mut params_only, &dims, d);
    }
    let mut all = params_only.clone();
    prefilter_along(&mut all, &dims, 4);
    let mut xi_only = ln_c.clone();
    prefilter_along(&mut xi_only, &dims, 4);
    let variants = vec![
        Variant {
            name: "cr/cr",
            params: Scheme::CatmullRom,
            xi: Scheme::CatmullRomSecantEnds,
            data: ln_c,
        },
        Variant {
            name: "cr/bs",
            params: Scheme::CatmullRom,
            xi: Scheme::NotAKnot,
            data: xi_only,
        },
        Variant {
            name: "bs/cr",
            params: Scheme::NotAKnot,
            xi: Scheme::CatmullRomSecantEnds,
            data: params_only,
        },
        Variant {
            name: "bs/bs",
            params: Scheme::NotAKnot,
            xi: Scheme::NotAKnot,
            data: all,
        },
    ];

    let t0 = std::time::Instant::now();
    // T3_SNAP=uc..: snap those axes of the points to their nearest node
    // (isolates the error of the other axes and of ξ).
    let snap = std::env::var("T3_SNAP").unwrap_or_default();
    // T3_BRDF_POINTS: draw the points as brdf_scipy.py does (see axis_study).
    let drawn: Vec<[f64; 4]> = if std::env::var("T3_BRDF_POINTS").is_ok() {
        let mut rng = generator::rng::SplitMix64::new(seed);
        brdf_check_profiles(&mut rng, profiles)
    } else {
        t3::verification_points(profiles, seed)
    };
    let points: Vec<[f64; 4]> = drawn
        .into_iter()
        .map(|mut pt| {
            for (d, key) in ['u', 'c', 'b', 'p'].iter().enumerate() {
                if snap.contains(*key) {
                    let i = position(d, pt[d]).round() as usize;
                    pt[d] = twoscale::interp::node_value(&AXES[d], i);
                }
            }
            pt
        })
        .collect();
    let exact: Vec<Exact> = points
        .into_par_iter()
        .map(|pt| {
            let [u, c, beta, p] = pt;
            let params = Params::new(u, c, beta, p).unwrap();
            let rule = ProfileRule::with_order(ProfileRule::width_for(&params), 8);
            let values = convolution_profile(u, c, beta, p, &rule.nodes).unwrap();
            let c0 = convolution_profile(u, c, beta, p, &[0.0]).unwrap()[0];
            Exact {
                point: pt,
                rule,
                values,
                c0,
            }
        })
        .collect();
    eprintln!(
        "{profiles} exact profiles in {:.1} s",
        t0.elapsed().as_secs_f64()
    );

    // The f64 re-implementation of the shipped lookup against the runtime.
    let mut worst = 0.0f64;
    for e in &exact {
        let [u, c, b, p] = e.point;
        for &t in e.rule.nodes.iter().step_by(7) {
            let r = f64::from(table.at_tan(t.tan(), u as f32, c as f32, b as f32, p as f32));
            let m = lookup(&variants[0], e.point, t.tan());
            if r > 1e-30 {
                worst = worst.max(((m - r) / r).abs());
            }
        }
    }
    println!("cr/cr in f64 vs runtime: max rel diff {worst:.2e}");

    println!(
        "{profiles} profiles (seed {seed}). e_L2 median/p90/p99/max | pointwise on rule nodes: C>1e-3C0 median/p95/max | 1e-9<C/C0<1e-3 median/p95/max"
    );
    for v in &variants {
        let mut el2 = Vec::new();
        let mut core = Vec::new();
        let mut tail = Vec::new();
        let mut worst_profile = (0.0, [0.0; 4]);
        for e in &exact {
            let (mut num, mut den) = (0.0, 0.0);
            for ((&t, &w), &x) in e.rule.nodes.iter().zip(&e.rule.weights).zip(&e.values) {
                let a = lookup(v, e.point, t.tan());
                num += w * (a - x) * (a - x);
                den += w * x * x;
                let rel = ((a - x) / x).abs();
                if x > 1e-3 * e.c0 {
                    core.push(rel);
                } else if x > 1e-9 * e.c0 {
                    tail.push(rel);
                }
            }
            let el = (num / den).sqrt();
            if el > worst_profile.0 {
                worst_profile = (el, e.point);
            }
            el2.push(el);
        }
        let pct = |x: f64| format!("{:.2}%", 100.0 * x);
        println!(
            "{:6} e_L2 {} {} {} {} | core {} {} {} | tail {} {} {} | worst at u,c,β,p = {:?}",
            v.name,
            pct(quantile(&mut el2, 0.5)),
            pct(quantile(&mut el2, 0.9)),
            pct(quantile(&mut el2, 0.99)),
            pct(quantile(&mut el2, 1.0)),
            pct(quantile(&mut core, 0.5)),
            pct(quantile(&mut core, 0.95)),
            pct(quantile(&mut core, 1.0)),
            pct(quantile(&mut tail, 0.5)),
            pct(quantile(&mut tail, 0.95)),
            pct(quantile(&mut tail, 1.0)),
            worst_profile.1,
        );
    }
}
