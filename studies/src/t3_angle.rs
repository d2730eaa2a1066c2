//! T3b's normalised angle ξ (`docs/design/t3-normalised-angle.md`): which
//! form of the angle, with which constants, lets 32 angles follow `ln C`.
//!
//! Every measurement builds what one table node would hold — `ln C` at the
//! 32 node angles of the angle under test, from exact profiles — and
//! interpolates it as the lookup does (`twoscale::tables::convolution::along_xi`; across β
//! and p with `twoscale::tables::convolution::axis_weights`), against exact `C`.

use crate::common::{Distribution, Exact, cell_on, exact_c, floored_ln, percentiles, quantile};
use generator::tables::convolution;
use rayon::prelude::*;
use twoscale::tables::convolution::{
    along_xi, axis_weights, normalised_angle, tan_of_normalised_angle,
};
use twoscale::tables::format::AngleParams;
use twoscale::tables::format::AxisHeader;
use twoscale::tables::interp::node_value;
use twoscale_reference::reference::conv::{kernel_integral, ndf_integral};
use twoscale_reference::reference::epd::{ndf_peak, ndf_sin_cos};

/// An angle under test: the runtime's (any constants), or format 1's.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Angle {
    /// The runtime's `normalised_angle` with these constants.
    Runtime(AngleParams),
    /// Format 1's angle, no longer in the runtime:
    /// `F(τ) = asinh(2 u_e τ) + λ ln(1 + Y (1 − e^(−y/Y)))` with the softened
    /// `y = (τ/β)^(2p')` (constants `τ_max, u_floor, λ, Y, κ` of the params).
    Format1(AngleParams),
}

impl Angle {
    /// Parses `format1` (format 1 with the shipped constants) or
    /// `w_h,w_e,s_e,τ_f[,m]` (the runtime's angle with those weights and the
    /// shipped constants otherwise; `τ_f = 0`: no fade; `m` the edge term's
    /// fade `(p′/p)^m` where the kernel is wider than the NDF, default 0).
    pub fn parse(s: &str) -> Result<Angle, String> {
        if s == "format1" {
            return Ok(Angle::Format1(convolution::ANGLE));
        }
        let v: Vec<f64> = s
            .split(',')
            .map(|x| x.trim().parse::<f64>().map_err(|e| format!("{s}: {e}")))
            .collect::<Result<_, _>>()?;
        let (horizon, edge, smoothing, fade, sharp) = match v[..] {
            [h, e, s, f] => (h, e, s, f, 0.0),
            [h, e, s, f, m] => (h, e, s, f, m),
            _ => return Err(format!("{s}: expected format1 or w_h,w_e,s_e,tau_f[,m]")),
        };
        Ok(Angle::Runtime(AngleParams {
            horizon_weight: horizon,
            edge_weight: edge,
            edge_smoothing: smoothing,
            edge_fade_tan: if fade > 0.0 { fade } else { f64::INFINITY },
            edge_softening_fade: sharp,
            ..convolution::ANGLE
        }))
    }

    /// The same angle with the NDF softening `κ`.
    fn with_softening(self, kappa: f64) -> Angle {
        match self {
            Angle::Runtime(a) => Angle::Runtime(AngleParams {
                ndf_softening: kappa,
                ..a
            }),
            Angle::Format1(a) => Angle::Format1(AngleParams {
                ndf_softening: kappa,
                ..a
            }),
        }
    }

    /// `ξ` of `τ = tan θh` at `(u, β, p)`.
    fn xi(&self, tau: f64, u: f64, beta: f64, p: f64) -> f64 {
        match self {
            Angle::Runtime(a) => normalised_angle(tau, u, beta, p, a),
            Angle::Format1(a) => {
                let tau = tau.max(0.0).min(a.tau_max);
                format1_f(tau, u, beta, p, a) / format1_f(a.tau_max, u, beta, p, a)
            }
        }
    }

    /// `θh` at `ξ` (the inverse of [`Angle::xi`]).
    fn theta(&self, xi: f64, u: f64, beta: f64, p: f64) -> f64 {
        match self {
            Angle::Runtime(a) => tan_of_normalised_angle(xi, u, beta, p, a),
            Angle::Format1(a) => {
                let target = xi * format1_f(a.tau_max, u, beta, p, a);
                let (mut lo, mut hi) = (0.0f64, a.tau_max.ln_1p());
                for _ in 0..100 {
                    let mid = 0.5 * (lo + hi);
                    if format1_f(mid.exp_m1(), u, beta, p, a) < target {
                        lo = mid;
                    } else {
                        hi = mid;
                    }
                }
                (0.5 * (lo + hi)).exp_m1()
            }
        }
        .atan()
    }
}

impl std::fmt::Display for Angle {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Angle::Format1(a) => write!(f, "format 1 (κ {})", a.ndf_softening),
            Angle::Runtime(a) => write!(
                f,
                "w_h {}, w_e {}, s_e {}, τ_f {}, m {}, κ {}",
                a.horizon_weight,
                a.edge_weight,
                a.edge_smoothing,
                a.edge_fade_tan,
                a.edge_softening_fade,
                a.ndf_softening
            ),
        }
    }
}

/// Format 1's `F(τ)` (see [`Angle::Format1`]).
fn format1_f(tau: f64, u: f64, beta: f64, p: f64, a: &AngleParams) -> f64 {
    let ue = (u * u + a.kernel_scale_floor * a.kernel_scale_floor).sqrt();
    let p_eff = p / (1.0 + a.ndf_softening * p / (2.0 * ue * beta));
    let y = if tau > 0.0 {
        (2.0 * p_eff * (tau / beta).ln()).exp()
    } else {
        0.0
    };
    let cap = a.ndf_exponent_cap;
    (2.0 * ue * tau).asinh() + a.ndf_weight * (cap * -(-(y / cap)).exp_m1()).ln_1p()
}

/// The angles compared by default: format 1, the horizon term alone, the
/// edge term unsmoothed, smoothed and faded, format 2's (`½, ½, 2, 3`) and
/// the shipped form of format 3 (`½, ½, 2, 3, m = 2`).
pub const DEFAULT_ANGLES: [&str; 6] = [
    "format1",
    "0.5,0,0,0",
    "0.5,1,0,0",
    "0.5,1,2,3",
    "0.5,0.5,2,3",
    "0.5,0.5,2,3,2",
];

/// Normalised angles per node in the studies' tables (default
/// `convolution::ANGLES`; `--xi` of t3-angle-patch and t3-angle-at-points).
pub static XI_COUNT: std::sync::OnceLock<usize> = std::sync::OnceLock::new();

/// [`XI_COUNT`], or `convolution::ANGLES` when unset.
fn xi_count() -> usize {
    *XI_COUNT.get_or_init(|| convolution::ANGLES)
}

/// The node angles `θ_k` of `angle` at `point` (one node of a table built
/// with that angle).
fn node_thetas([u, _, beta, p]: [f64; 4], angle: Angle) -> Vec<f64> {
    let n = xi_count();
    (0..n)
        .map(|k| angle.theta(k as f64 / (n - 1) as f64, u, beta, p))
        .collect()
}

/// `ln C` (floored as stored) at the node angles of `angle` for `point`.
fn node_ln_values(point: [f64; 4], angle: Angle) -> Vec<f64> {
    floored_ln(&exact_c(point, &node_thetas(point, angle)))
}

/// The lookup's cubic along ξ at `θh`, on `ln C` values `window(first)`.
fn along_angle(
    angle: Angle,
    [u, _, beta, p]: [f64; 4],
    theta: f64,
    window: impl FnOnce(usize) -> [f32; 4],
) -> f64 {
    ln_along_angle(angle, [u, 0.0, beta, p], theta, window).exp()
}

/// [`along_angle`] before the exponential: the cubic's `ln C`.
fn ln_along_angle(
    angle: Angle,
    [u, _, beta, p]: [f64; 4],
    theta: f64,
    window: impl FnOnce(usize) -> [f32; 4],
) -> f64 {
    let xi = angle.xi(theta.tan(), u, beta, p);
    f64::from(along_xi(xi_count(), xi, window))
}

/// The four values of `ln_v` from `first` (as the lookup reads a node).
fn window(ln_v: &[f64], first: usize) -> [f32; 4] {
    std::array::from_fn(|j| ln_v[first + j] as f32)
}

/// `C` at `thetas` from the exact node values of `angle` at `point`,
/// interpolated along ξ only (parameters exact).
fn xi_only(point: [f64; 4], angle: Angle, thetas: &[f64]) -> Vec<f64> {
    let ln_v = node_ln_values(point, angle);
    thetas
        .iter()
        .map(|&t| along_angle(angle, point, t, |first| window(&ln_v, first)))
        .collect()
}

/// How the corners of a parameter cell are combined at a query angle `θh`.
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub enum Blend {
    /// The lookup's (format 2): `ln C` blended at equal ξ, then the cubic
    /// along ξ at the query's own ξ(θh).
    Xi,
    /// Equal θh: each corner's cubic along ξ at its own ξ of the query's θh,
    /// then the values blended.
    Theta,
    /// A residual table: `ln C − ln C̃` (`twoscale::tables::convolution::ln_approximation`
    /// with each node's own parameters) blended at equal ξ, the cubic at the
    /// query's ξ, plus `ln C̃` with the query's parameters.
    Residual,
    /// [`Blend::Residual`] with the corners at equal θh ([`Blend::Theta`]).
    ResidualTheta,
}

/// `ln C̃`'s floor below `ln C̃(0)` in [`Blend::Residual`] (default 30).
pub static RESIDUAL_FLOOR: std::sync::OnceLock<f64> = std::sync::OnceLock::new();

/// One corner of a parameter cell: its lookup weight, parameters, node
/// angles and `ln C` there (floored as stored).
struct Corner {
    weight: f64,
    point: [f64; 4],
    thetas: Vec<f64>,
    ln_v: Vec<f64>,
}

/// The corners around `point` along the axes flagged in `axes` (u, c, β, p;
/// the others exact) on the axes `grid`, with the lookup's weights; exact profiles at each
/// corner's own node angles of `angle`. No axis: the point itself (ξ alone).
fn corners(point: [f64; 4], angle: Angle, axes: [bool; 4], grid: &[AxisHeader; 4]) -> Vec<Corner> {
    let per_axis: Vec<Vec<(f64, f64)>> = (0..4)
        .map(|d| {
            if axes[d] {
                let (first, count, w) =
                    axis_weights(grid[d].nodes as usize, cell_on(&grid[d], point[d]), true);
                (0..count)
                    .map(|i| (f64::from(w[i]), node_value(&grid[d], first + i)))
                    .collect()
            } else {
                vec![(1.0, point[d])]
            }
        })
        .collect();
    let mut out = Vec::new();
    for &(wu, u) in &per_axis[0] {
        for &(wc, c) in &per_axis[1] {
            for &(wb, beta) in &per_axis[2] {
                for &(wp, p) in &per_axis[3] {
                    let node = [u, c, beta, p];
                    let thetas = node_thetas(node, angle);
                    let ln_v = floored_ln(&exact_c(node, &thetas));
                    out.push(Corner {
                        weight: wu * wc * wb * wp,
                        point: node,
                        thetas,
                        ln_v,
                    });
                }
            }
        }
    }
    out
}

/// `ln C̃` of [`Blend::Residual`] at `θh` for `point`: a closed-form stand-in
/// for `ln C` from the two limits of docs/model.md §2.5 (narrow kernel
/// `W_K D(θh)`, narrow NDF `W_D k(2u sin θh) cos²θh`), each capped at the
/// other's peak (a lobe convolved with a wider one cannot exceed the wider
/// one's peak), `C̃ = h(W_K D, W_D) + h(W_D k cos², W_K D(0))` with
/// `h(a, b) = ab/(a + b)`, held at or above `ln C̃(0) − RESIDUAL_FLOOR`.
fn ln_approx([u, c, beta, p]: [f64; 4], theta: f64) -> f64 {
    let floor = *RESIDUAL_FLOOR.get_or_init(|| 30.0);
    let wk = kernel_integral(u, c).expect("T3's domain").ln();
    let wd = ndf_integral(beta, p).expect("T3's domain").ln();
    let peak = ndf_peak(beta, p);
    // ln(a + b) and ln(ab/(a + b)) from ln a, ln b (−∞ allowed).
    let ln_sum = |a: f64, b: f64| {
        let (hi, lo) = if a > b { (a, b) } else { (b, a) };
        if hi == f64::NEG_INFINITY {
            hi
        } else {
            hi + (lo - hi).exp().ln_1p()
        }
    };
    let ln_harmonic = |a: f64, b: f64| a + b - ln_sum(a, b);
    let narrow_peak = wk + peak.ln();
    let at = |theta: f64| {
        let (sin, cos) = theta.sin_cos();
        let narrow = wk + ndf_sin_cos(beta, p, peak, sin, cos).ln();
        let wide = wd
            + f64::from(twoscale::tables::convolution::kernel(
                (2.0 * u * sin) as f32,
                c as f32,
            ))
            .ln()
            + 2.0 * cos.ln();
        ln_sum(ln_harmonic(narrow, wd), ln_harmonic(wide, narrow_peak))
    };
    at(theta).max(at(0.0) - floor)
}

/// `C` at `theta` from the corners, combined by `blend`, for the query
/// `point`.
fn blended(point: [f64; 4], angle: Angle, corners: &[Corner], blend: Blend, theta: f64) -> f64 {
    let residual = matches!(blend, Blend::Residual | Blend::ResidualTheta);
    let stored = |k: &Corner| -> Vec<f64> {
        if residual {
            k.ln_v
                .iter()
                .zip(&k.thetas)
                .map(|(v, &t)| v - ln_approx(k.point, t))
                .collect()
        } else {
            k.ln_v.clone()
        }
    };
    let values: Vec<(f64, Vec<f64>)> = corners.iter().map(|k| (k.weight, stored(k))).collect();
    let ln_c = match blend {
        Blend::Xi | Blend::Residual => ln_along_angle(angle, point, theta, |first| {
            std::array::from_fn(|j| {
                values.iter().map(|(w, v)| w * v[first + j]).sum::<f64>() as f32
            })
        }),
        Blend::Theta | Blend::ResidualTheta => corners
            .iter()
            .zip(&values)
            .map(|(k, (w, v))| w * ln_along_angle(angle, k.point, theta, |f| window(v, f)))
            .sum(),
    };
    (ln_c
        + if residual {
            ln_approx(point, theta)
        } else {
            0.0
        })
    .exp()
}

/// ξ-alone and interpolated errors for each angle and blend on `points`
/// (e.g. `profiles` of a distribution's, seed 61): e_L2 and core pointwise on
/// the profile rule. The corners are the nodes around each point along `axes`
/// (u, c, β, p; the others exact), at their own node angles: predicts a
/// table's error without building it. `per_profile`: also each point's
/// figures.
pub fn patch(
    points: &[[f64; 4]],
    angles: &[Angle],
    blends: &[Blend],
    axes: [bool; 4],
    grid: &[AxisHeader; 4],
    per_profile: bool,
) {
    type Row = (Exact, Vec<Vec<[Vec<f64>; 2]>>);
    let rows: Vec<Row> = points
        .par_iter()
        .map(|&pt| {
            let exact = Exact::new(pt);
            let per_angle = angles
                .iter()
                .map(|&a| {
                    let alone = corners(pt, a, [false; 4], grid);
                    let cell = corners(pt, a, axes, grid);
                    blends
                        .iter()
                        .map(|&b| {
                            let at = |k: &[Corner]| -> Vec<f64> {
                                exact
                                    .rule
                                    .nodes
                                    .iter()
                                    .map(|&t| blended(pt, a, k, b, t))
                                    .collect()
                            };
                            [at(&alone), at(&cell)]
                        })
                        .collect()
                })
                .collect();
            (exact, per_angle)
        })
        .collect();
    for (k, angle) in angles.iter().enumerate() {
        for (b, blend) in blends.iter().enumerate() {
            for (which, name) in ["ξ only", "patch"].iter().enumerate() {
                let (mut el2, mut core, mut tail, mut energy) = (vec![], vec![], vec![], vec![]);
                let mut worst = (0.0f64, [0.0; 4]);
                let mut worst_energy = (0.0f64, [0.0; 4]);
                for (exact, per_angle) in &rows {
                    let approx = &per_angle[k][b][which];
                    let e = exact.e_l2(approx);
                    if e > worst.0 {
                        worst = (e, exact.point);
                    }
                    let en = exact.energy(approx);
                    if en > worst_energy.0 {
                        worst_energy = (en, exact.point);
                    }
                    el2.push(e);
                    energy.push(en);
                    let (mut c, mut t) = (vec![], vec![]);
                    exact.pointwise(approx, &mut c, &mut t);
                    if per_profile && which == 1 {
                        println!(
                            "  {:?}: e_L2 {:.2}% energy {:.2}% core p95/max {}",
                            exact.point,
                            100.0 * e,
                            100.0 * en,
                            percentiles(&mut c, &[0.95, 1.0])
                        );
                    }
                    core.extend(c);
                    tail.extend(t);
                }
                println!(
                    "{angle} {blend:?} {name:6}: e_L2 median/p90/max {} | energy p90/max {} | \
                     core median/p95/p99/max {} | tail p95 {} | worst e_L2 at {:?}, energy at {:?}",
                    percentiles(&mut el2, &[0.5, 0.9, 1.0]),
                    percentiles(&mut energy, &[0.9, 1.0]),
                    percentiles(&mut core, &[0.5, 0.95, 0.99, 1.0]),
                    percentiles(&mut tail, &[0.95]),
                    worst.1,
                    worst_energy.1,
                );
            }
        }
    }
}

/// ξ-only errors (e_L2, core and tail pointwise on the profile rule) of
/// each angle on `profiles` points of a distribution.
fn xi_only_table(points: &[[f64; 4]], angles: &[Angle], label: &str) {
    let rows: Vec<(Exact, Vec<Vec<f64>>)> = points
        .par_iter()
        .map(|&pt| {
            let exact = Exact::new(pt);
            let approx = angles
                .iter()
                .map(|&a| xi_only(pt, a, &exact.rule.nodes))
                .collect();
            (exact, approx)
        })
        .collect();
    for (k, angle) in angles.iter().enumerate() {
        let (mut el2, mut core, mut tail) = (vec![], vec![], vec![]);
        for (exact, approx) in &rows {
            el2.push(exact.e_l2(&approx[k]));
            exact.pointwise(&approx[k], &mut core, &mut tail);
        }
        println!(
            "{label} {angle}: e_L2 median/p90/max {} | core median/p95/max {} | tail {}",
            percentiles(&mut el2, &[0.5, 0.9, 1.0]),
            percentiles(&mut core, &[0.5, 0.95, 1.0]),
            percentiles(&mut tail, &[0.5, 0.95, 1.0]),
        );
    }
}

/// The NDF term's softening κ: ξ-only error of `angle` with each κ, on
/// verify's profiles (seed 31) and the BRDF check's (seed 32).
pub fn softening(profiles: usize, angle: Angle, kappas: &[f64]) {
    let angles: Vec<Angle> = kappas.iter().map(|&k| angle.with_softening(k)).collect();
    for (distribution, seed) in [(Distribution::Verify, 31), (Distribution::Brdf, 32)] {
        let points = distribution.points(profiles, seed);
        xi_only_table(&points, &angles, &format!("{distribution:?}"));
    }
}

/// The forms of the angle, ξ alone (parameters exact), on `profiles` points
/// of `distribution` (seed 57): e_L2 and pointwise on the profile rule, and
/// pointwise at 64 θh evenly spaced up to 1.3 (BRDF check: both directions
/// within 75°) or 1.55 (verify's), where `C > 1e-9 C(0)`.
pub fn forms(profiles: usize, distribution: Distribution, angles: &[Angle]) {
    let points = distribution.points(profiles, 57);
    let horizon = match distribution {
        Distribution::Verify => 1.55,
        Distribution::Brdf => 1.3,
    };
    let uniform: Vec<f64> = (0..64).map(|k| horizon * (k as f64 + 0.5) / 64.0).collect();
    type Row = (Exact, Vec<f64>, Vec<(Vec<f64>, Vec<f64>)>);
    let rows: Vec<Row> = points
        .par_iter()
        .map(|&pt| {
            let exact = Exact::new(pt);
            let exact_uniform = exact_c(pt, &uniform);
            let per_angle = angles
                .iter()
                .map(|&a| (xi_only(pt, a, &exact.rule.nodes), xi_only(pt, a, &uniform)))
                .collect();
            (exact, exact_uniform, per_angle)
        })
        .collect();
    for (k, angle) in angles.iter().enumerate() {
        let (mut el2, mut core, mut tail, mut far) = (vec![], vec![], vec![], vec![]);
        let mut worst = (0.0f64, [0.0; 4], 0.0);
        for (exact, exact_uniform, per_angle) in &rows {
            let (on_rule, on_uniform) = &per_angle[k];
            el2.push(exact.e_l2(on_rule));
            exact.pointwise(on_rule, &mut core, &mut tail);
            for ((a, x), &theta) in on_uniform.iter().zip(exact_uniform).zip(&uniform) {
                if *x > 1e-9 * exact.c0 {
                    let rel = ((a - x) / x).abs();
                    far.push(rel);
                    if rel > worst.0 {
                        worst = (rel, exact.point, theta);
                    }
                }
            }
        }
        println!(
            "{angle}: e_L2 median/p90/max {} | rule core p95/max {} | rule tail p95/max {} | \
             θh uniform ≤ {horizon} median/p95/max {} (worst at u,c,β,p {:?}, θh {:.3})",
            percentiles(&mut el2, &[0.5, 0.9, 1.0]),
            percentiles(&mut core, &[0.95, 1.0]),
            percentiles(&mut tail, &[0.95, 1.0]),
            percentiles(&mut far, &[0.5, 0.95, 1.0]),
            worst.1,
            worst.2,
        );
    }
}

/// At given points (`u,c,beta,p,theta_h` CSV with a header line, e.g. the
/// BRDF check's): exact `C`, and per angle and blend `C` from the corners
/// along `axes` (none: ξ alone; see [`patch`]). Writes CSV to stdout and the
/// relative error's p95 / p99 / max per angle and blend to stderr.
pub fn at_points(
    path: &std::path::Path,
    angles: &[Angle],
    blends: &[Blend],
    axes: [bool; 4],
    grid: &[AxisHeader; 4],
) -> Result<(), String> {
    let text = std::fs::read_to_string(path).map_err(|e| format!("{}: {e}", path.display()))?;
    let points: Vec<[f64; 5]> = text
        .lines()
        .skip(1)
        .filter_map(|l| {
            let v: Vec<f64> = l.split(',').filter_map(|x| x.trim().parse().ok()).collect();
            (v.len() == 5).then(|| [v[0], v[1], v[2], v[3], v[4]])
        })
        .collect();
    let rows: Vec<Vec<f64>> = points
        .par_iter()
        .map(|&[u, c, beta, p, theta]| {
            let pt = [u, c, beta, p];
            let mut out = vec![exact_c(pt, &[theta])[0]];
            for &a in angles {
                let cell = corners(pt, a, axes, grid);
                for &b in blends {
                    out.push(blended(pt, a, &cell, b, theta));
                }
            }
            out
        })
        .collect();
    let names: Vec<String> = angles
        .iter()
        .flat_map(|a| blends.iter().map(move |b| format!("\"{a} {b:?}\"")))
        .collect();
    println!("exact,{}", names.join(","));
    for r in &rows {
        let cells: Vec<String> = r.iter().map(|x| x.to_string()).collect();
        println!("{}", cells.join(","));
    }
    for (k, name) in names.iter().enumerate() {
        let mut rel: Vec<f64> = rows
            .iter()
            .map(|r| ((r[k + 1] - r[0]) / r[0]).abs())
            .collect();
        eprintln!(
            "{name}: {} points, relative error p95 {:.2}%, p99 {:.2}%, max {:.2}%",
            rel.len(),
            100.0 * quantile(&mut rel, 0.95),
            100.0 * quantile(&mut rel, 0.99),
            100.0 * quantile(&mut rel, 1.0)
        );
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_last_default_angle_is_the_shipped_one() {
        let shipped = Angle::parse(DEFAULT_ANGLES[DEFAULT_ANGLES.len() - 1]).unwrap();
        assert_eq!(shipped, Angle::Runtime(convolution::ANGLE));
        assert_eq!(
            Angle::parse("format1").unwrap(),
            Angle::Format1(convolution::ANGLE)
        );
        assert!(Angle::parse("0.5,0.5").is_err());
        assert!(Angle::parse("a,b,c,d").is_err());
    }

    #[test]
    fn angles_invert_and_increase() {
        for angle in DEFAULT_ANGLES.map(|s| Angle::parse(s).unwrap()) {
            for [u, beta, p] in [[0.0, 0.002, 0.2], [20.0, 0.1, 1.0], [3000.0, 1.0, 5.0]] {
                let mut previous = -1.0;
                for k in 0..=16 {
                    let xi = f64::from(k) / 16.0;
                    let theta = angle.theta(xi, u, beta, p);
                    assert!((0.0..=std::f64::consts::FRAC_PI_2).contains(&theta));
                    assert!(theta >= previous, "{angle}: θ({xi}) decreases");
                    previous = theta;
                    if (0.05..0.95).contains(&xi) {
                        let back = angle.xi(theta.tan(), u, beta, p);
                        assert!(
                            (back - xi).abs() < 1e-9,
                            "{angle} at {u} {beta} {p}: {xi} -> {back}"
                        );
                    }
                }
            }
        }
    }
}
