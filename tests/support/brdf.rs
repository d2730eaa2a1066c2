//! Helpers of the BRDF tests and benchmarks: stand-ins for the T3
//! convolution tables, random directions and percentiles, and a χ² test of a
//! direction sampler against its pdf.

use generator::quad::gauss_legendre;
use generator::reference::conv;
use generator::rng::SplitMix64;
use std::f64::consts::PI;
use twoscale::brdf::{Lobe, TwoScale};
use twoscale::tables::convolution::{Convolution, kernel};

/// A cheap stand-in for C where its accuracy does not matter (sampling
/// tests, robustness sweeps, benchmarks until T3 exists): the narrow-NDF
/// limit `C ≈ k(2u sin θh) cos²θh`, D acting as a Dirac (HP17 §4.4).
#[derive(Clone, Copy, Debug, Default)]
pub struct NarrowNdfConvolution;

impl Convolution for NarrowNdfConvolution {
    fn convolution_sin_cos(&self, sin: f32, cos: f32, u: f32, c: f32, _beta: f32, _p: f32) -> f32 {
        let cos = cos.clamp(0.0, 1.0);
        kernel(2.0 * u * sin.clamp(0.0, 1.0), c) * cos * cos
    }
}

/// Exact C (the f64 reference, through its zonal-harmonic / direct profile)
/// tabulated for one `(c, β, p)` on a grid of `u ∈ [0, u_max]` and
/// `θh ∈ [0, π/2]`, interpolated bilinearly in `(u, θh)` on `ln C`. Built in
/// a few seconds; accurate to well under 1% on a smooth lobe, which is what
/// the white-furnace test needs. Other `(c, β, p)` than the tabulated ones
/// are a test bug (debug assertion).
pub struct ProfileConvolution {
    c: f32,
    beta: f32,
    p: f32,
    u_nodes: Vec<f64>,
    theta_nodes: Vec<f64>,
    /// `ln C` row-major `[u][θ]` (−745 for zeros).
    ln_c: Vec<f64>,
}

impl ProfileConvolution {
    /// Tabulates C for `(c, β, p)` up to `u_max` (`b/λ`).
    pub fn new(c: f32, beta: f32, p: f32, u_max: f64) -> Self {
        let nu = 33;
        let nt = 161;
        let u_nodes: Vec<f64> = (0..nu)
            .map(|k| u_max * (k as f64 / (nu - 1) as f64).powi(2))
            .collect();
        let theta_nodes: Vec<f64> = (0..nt)
            .map(|k| std::f64::consts::FRAC_PI_2 * (k as f64 / (nt - 1) as f64).powi(2))
            .collect();
        let mut ln_c = Vec::with_capacity(nu * nt);
        for &u in &u_nodes {
            let profile = conv::convolution_profile(
                u,
                f64::from(c),
                f64::from(beta),
                f64::from(p),
                &theta_nodes,
            )
            .expect("reference convolution profile");
            ln_c.extend(
                profile
                    .iter()
                    .map(|&v| if v > 0.0 { v.ln() } else { -745.0 }),
            );
        }
        ProfileConvolution {
            c,
            beta,
            p,
            u_nodes,
            theta_nodes,
            ln_c,
        }
    }
}

fn locate(nodes: &[f64], x: f64) -> (usize, f64) {
    let x = x.clamp(nodes[0], nodes[nodes.len() - 1]);
    let k = nodes.partition_point(|&v| v <= x).clamp(1, nodes.len() - 1) - 1;
    let t = (x - nodes[k]) / (nodes[k + 1] - nodes[k]);
    (k, t)
}

impl Convolution for ProfileConvolution {
    fn convolution_sin_cos(&self, sin: f32, cos: f32, u: f32, c: f32, beta: f32, p: f32) -> f32 {
        debug_assert!(c == self.c && beta == self.beta && p == self.p);
        let theta = f64::from(sin.max(0.0)).atan2(f64::from(cos.max(0.0)));
        let (ku, tu) = locate(&self.u_nodes, f64::from(u));
        let (kt, tt) = locate(&self.theta_nodes, theta);
        let nt = self.theta_nodes.len();
        let at = |a: usize, b: usize| self.ln_c[a * nt + b];
        let row = |a: usize| at(a, kt) * (1.0 - tt) + at(a, kt + 1) * tt;
        (row(ku) * (1.0 - tu) + row(ku + 1) * tu).exp() as f32
    }
}

/// Outcome of [`chi_square_sampler`].
#[derive(Clone, Debug)]
pub struct SamplerCheck {
    /// The χ² test over the pooled cells.
    pub chi: crate::ChiSquare,
    /// `∫ pdf dω` over the hemisphere (sum of the cell integrals).
    pub pdf_integral: f64,
    /// Fraction of the calls to the sampler that returned a direction.
    pub success: f64,
}

impl SamplerCheck {
    /// Asserts `∫ pdf ≤ 1 + 1e-5` and that it is the success rate of `n`
    /// draws within 5 binomial standard errors `√(s(1 − s)/n)` plus
    /// `slack` (the cell rule's error); `label` names the case.
    pub fn assert_pdf_is_the_success_rate(&self, n: usize, slack: f64, label: &str) {
        let se = (self.success * (1.0 - self.success) / n as f64).sqrt();
        assert!(
            self.pdf_integral <= 1.0 + 1e-5,
            "{label}: ∫pdf {}",
            self.pdf_integral
        );
        assert!(
            (self.pdf_integral - self.success).abs() <= 5.0 * se + slack,
            "{label}: ∫pdf {} vs sampled {}",
            self.pdf_integral,
            self.success
        );
    }
}

/// [`chi_square_sampler`] of `model` at incidence `i`: its whole sampler
/// (`sample`, `pdf`) when `lobe` is `None`, else that lobe's (`sample_lobe`
/// with `u[1], u[2]`, `pdf_lobe`).
pub fn chi_square_two_scale(
    model: &TwoScale<'_>,
    lobe: Option<Lobe>,
    i: [f32; 3],
    n: usize,
    scale: f64,
    seed: u64,
) -> SamplerCheck {
    match lobe {
        Some(lobe) => chi_square_sampler(
            i,
            |u| model.sample_lobe(lobe, i, [u[1], u[2]]),
            |o| f64::from(model.pdf_lobe(lobe, i, o)),
            n,
            scale,
            seed,
        ),
        None => chi_square_sampler(
            i,
            |u| model.sample(i, u).map(|s| s.o),
            |o| f64::from(model.pdf(i, o)),
            n,
            scale,
            seed,
        ),
    }
}

/// χ² test of a direction sampler against its claimed solid-angle density.
///
/// Cells are in coordinates around the mirror direction `r = (−ix, −iy, iz)`:
/// the angle `α` from `r` (edges at 0 and geometrically spaced from
/// `scale/8` to π, so that lobes of width ~`scale` are resolved) and the
/// azimuth around `r` (16 equal sectors). Expected counts are `n · ∫ pdf dω`
/// over each cell by a Gauss product rule (on four sub-sectors), with the part of the cell
/// below the horizon cut away analytically (no discontinuity inside the
/// integrals). Cells expecting fewer than 5 events are pooled.
pub fn chi_square_sampler(
    i: [f32; 3],
    sampler: impl Fn([f32; 3]) -> Option<[f32; 3]>,
    pdf: impl Fn([f32; 3]) -> f64,
    n: usize,
    scale: f64,
    seed: u64,
) -> SamplerCheck {
    let wi = i.map(f64::from);
    let r = [-wi[0], -wi[1], wi[2]];
    // e1: the part of +z orthogonal to r (in the plane of incidence), e2 = r × e1.
    let z_dot_r = r[2];
    let mut e1 = [-z_dot_r * r[0], -z_dot_r * r[1], 1.0 - z_dot_r * r[2]];
    let len = (e1[0] * e1[0] + e1[1] * e1[1] + e1[2] * e1[2]).sqrt();
    if len < 1e-9 {
        e1 = [1.0, 0.0, 0.0];
    } else {
        e1 = e1.map(|x| x / len);
    }
    let e2 = [
        r[1] * e1[2] - r[2] * e1[1],
        r[2] * e1[0] - r[0] * e1[2],
        r[0] * e1[1] - r[1] * e1[0],
    ];
    let direction = |alpha: f64, phi: f64| -> [f64; 3] {
        let (sa, ca) = alpha.sin_cos();
        let (sp, cp) = phi.sin_cos();
        [0, 1, 2].map(|k| ca * r[k] + sa * (cp * e1[k] + sp * e2[k]))
    };
    let n_alpha = 30;
    let mut alpha_edges = vec![0.0];
    let first = (scale / 8.0).min(0.05);
    for k in 0..n_alpha {
        alpha_edges.push(first * (PI / first).powf(k as f64 / (n_alpha - 1) as f64));
    }
    let n_phi = 16;
    let dphi = 2.0 * PI / n_phi as f64;

    // Observed counts.
    let mut observed = vec![0.0; n_alpha * n_phi];
    let mut rng = SplitMix64::new(seed);
    let mut successes = 0usize;
    for _ in 0..n {
        let u = [
            rng.uniform() as f32,
            rng.uniform() as f32,
            rng.uniform() as f32,
        ];
        let Some(o) = sampler(u) else { continue };
        successes += 1;
        let o = o.map(f64::from);
        let c = (o[0] * r[0] + o[1] * r[1] + o[2] * r[2]).clamp(-1.0, 1.0);
        let x = o[0] * e1[0] + o[1] * e1[1] + o[2] * e1[2];
        let y = o[0] * e2[0] + o[1] * e2[1] + o[2] * e2[2];
        let alpha = x.hypot(y).atan2(c);
        let phi = y.atan2(x).rem_euclid(2.0 * PI);
        let ka = alpha_edges
            .partition_point(|&e| e <= alpha)
            .clamp(1, n_alpha)
            - 1;
        let kp = ((phi / dphi) as usize).min(n_phi - 1);
        observed[ka * n_phi + kp] += 1.0;
    }

    // Expected counts: o·z = cos α r_z + sin α cos φ e1_z (e2_z = 0), so o is
    // above the horizon for |φ| < φc with cos φc = −cos α r_z / (sin α e1_z).
    // Each cell is integrated by an 8 × 8 Gauss–Legendre product rule in
    // (α, φ) over its part above the horizon (cut analytically, so the
    // integrand has no jump inside); the cells are small against the lobes'
    // scales (geometric in α), where the f32 pdf is smooth.
    let (gx, gw) = gauss_legendre(8);
    let cell_part = |a0: f64, a1: f64, p0: f64, p1: f64| -> f64 {
        let mut total = 0.0;
        for (&xa, &wa) in gx.iter().zip(&gw) {
            let alpha = 0.5 * (a0 + a1) + 0.5 * (a1 - a0) * xa;
            let (sa, ca) = alpha.sin_cos();
            let phi_c = if e1[2].abs() < 1e-12 {
                if ca * r[2] > 0.0 { PI } else { 0.0 }
            } else {
                (-(ca * r[2]) / (sa * e1[2])).clamp(-1.0, 1.0).acos()
            };
            let mut inner = 0.0;
            for (lo, hi) in [(0.0, phi_c), (2.0 * PI - phi_c, 2.0 * PI)] {
                let (l, h) = (p0.max(lo), p1.min(hi));
                if h > l {
                    for (&xp, &wp) in gx.iter().zip(&gw) {
                        let phi = 0.5 * (l + h) + 0.5 * (h - l) * xp;
                        inner += 0.5 * (h - l) * wp * pdf(direction(alpha, phi).map(|x| x as f32));
                    }
                }
            }
            total += 0.5 * (a1 - a0) * wa * inner * sa;
        }
        total
    };
    // In α the visible φ range is everything for α < π/2 − θr, shrinks (with
    // a square-root kink) until α = π/2 + θr and is empty beyond: the α
    // range of each cell is split at the first and cut at the second.
    let theta_r = r[2].clamp(-1.0, 1.0).acos();
    let (alpha_full, alpha_none) = (PI / 2.0 - theta_r, PI / 2.0 + theta_r);
    let piece = |a0: f64, a1: f64, p0: f64, p1: f64| -> f64 {
        let a1 = a1.min(alpha_none);
        if a1 <= a0 {
            return 0.0;
        }
        if a0 < alpha_full && alpha_full < a1 {
            return cell_part(a0, alpha_full, p0, p1) + cell_part(alpha_full, a1, p0, p1);
        }
        cell_part(a0, a1, p0, p1)
    };
    // Each α range is integrated as ALPHA_SPLIT equal pieces: the halo
    // sampler's density is piecewise linear in 1 − cos θh (kinks at its
    // nodes), and for HP17's geometry at normal incidence one 8-point rule
    // per α cell gave ∫ pdf = 0.999677 against 0.999920 by a 2·10⁶-point
    // midpoint rule in θo (and a success rate of 0.999920).
    const ALPHA_SPLIT: usize = 4;
    let cell = |a0: f64, a1: f64, p0: f64, p1: f64| -> f64 {
        let step = (a1 - a0) / ALPHA_SPLIT as f64;
        (0..ALPHA_SPLIT)
            .map(|j| {
                let b0 = a0 + j as f64 * step;
                let b1 = if j + 1 == ALPHA_SPLIT { a1 } else { b0 + step };
                piece(b0, b1, p0, p1)
            })
            .sum()
    };
    // Each sector is integrated as PHI_SPLIT sub-sectors: at grazing
    // incidence a narrow lobe is a thin ridge along the plane of incidence
    // (φ = 0 and π, which are sector edges), stretched 1/(2 cos θi) times
    // along it (reflection about m moves o by 2δ in the plane and by
    // 2 cos θi δ across it). One 8-point rule over a whole sector puts its
    // first node 0.008 rad from that edge and misses most of a ridge
    // narrower than that: for β = 0.004, p = 0.6 at θi = 87° the undivided
    // rule gave ∫ pdf = 0.99965 against a success rate of 0.99995
    // (p ≈ 1e-26); split in 2, 4 or 8 it gives 0.999953, 0.999956,
    // 0.999956 (p = 0.94 at each).
    const PHI_SPLIT: usize = 4;
    let sub = dphi / PHI_SPLIT as f64;
    let mut expected = vec![0.0; n_alpha * n_phi];
    for ka in 0..n_alpha {
        for kp in 0..n_phi {
            let p0 = kp as f64 * dphi;
            expected[ka * n_phi + kp] = (0..PHI_SPLIT)
                .map(|j| {
                    let q0 = p0 + j as f64 * sub;
                    cell(alpha_edges[ka], alpha_edges[ka + 1], q0, q0 + sub)
                })
                .sum();
        }
    }
    let pdf_integral: f64 = expected.iter().sum();
    // n·∫pdf per cell, plus one cell for the calls that returned nothing
    // (expected n(1 − ∫pdf)), so that both sides count n events.
    let mut expected_counts: Vec<f64> = expected.iter().map(|e| e * n as f64).collect();
    expected_counts.push((1.0 - pdf_integral).max(0.0) * n as f64);
    observed.push((n - successes) as f64);
    SamplerCheck {
        chi: crate::chi_square(&observed, &expected_counts, 5.0),
        pdf_integral,
        success: successes as f64 / n as f64,
    }
}

/// A direction uniform over the upper hemisphere (`cos θ` uniform).
pub fn random_direction(rng: &mut SplitMix64) -> [f32; 3] {
    let z = rng.uniform();
    let r = (1.0 - z * z).max(0.0).sqrt();
    let phi = 2.0 * PI * rng.uniform();
    [(r * phi.cos()) as f32, (r * phi.sin()) as f32, z as f32]
}

/// The `q`-quantile (`q ∈ [0, 1]`, nearest rank) of `values` (sorted in place); 0 if empty.
pub fn percentile(values: &mut [f64], q: f64) -> f64 {
    if values.is_empty() {
        return 0.0;
    }
    values.sort_by(f64::total_cmp);
    let k = ((q * values.len() as f64).ceil() as usize).clamp(1, values.len()) - 1;
    values[k]
}
