//! Projection of an isotropic BRDF onto the spherical-harmonic matrix of T4
//! (\[WAT92\] §2, docs/model.md §2.9), generic over the BRDF.
//!
//! The layout, the odd completion and the real-SH convention are documented
//! in `twoscale::tables::sh_brdf`. Block `m` of the matrix is
//!
//! ```text
//! B^m_{l l'} = 4 ∫₀¹ ∫₀¹ P̄_l^m(xi) P̄_l'^m(xo) g_m(xi, xo) dxi dxo,
//! g_m(xi, xo) = 2π ∫₀^{2π} f(xi, xo, Δφ) cos(m Δφ) dΔφ,     f = ρ cos θi cos θo,
//! ```
//!
//! computed by
//!
//! - the azimuthal Fourier decomposition: `f` is even in `Δφ`, so
//!   `g_m = 4π ∫₀^π f cos(m Δφ) dΔφ`, integrated by Gauss–Legendre of order
//!   [`PHI_ORDER`] on panels (see [`Quadrature::phi_rule`]): of width ≤ 8/L
//!   so as to resolve `cos(LΔφ)`, and geometric ones towards `Δφ = π`,
//!   because a specular lobe at grazing incidence and exitance is very narrow
//!   in `Δφ` (width `~ 2 α cos θ`, around the mirror azimuth `Δφ = π`): a
//!   uniform midpoint rule with 96 nodes left 1.4e-3 (of the largest
//!   coefficient) for Beckmann α = 0.1 at L = 32, and 256 were needed;
//! - Gauss–Legendre with `N_θ` nodes in `x = cos θ ∈ [0, 1]` for both angles
//!   (exact for polynomials of degree `2N_θ − 1`; `P̄_l^m` has degree ≤ L).
//!
//! The BRDF is sampled once on the `N_θ × N_θ × N_φ` grid (rows in parallel,
//! each value computed by one thread, every sum in a fixed order, so the
//! result does not depend on the thread count). Both `(xi, xo)` and
//! `(xo, xi)` are sampled, so a non-reciprocal BRDF gives a non-symmetric
//! matrix, whose asymmetry (WAT92 26-27) is reported before symmetrising.
//!
//! The quadrature's own error is measured in the tests by doubling both node
//! counts (see `default_quadrature`).

// Index loops mirror the recurrences and the block formulas of the docs.
#![allow(clippy::needless_range_loop)]

use indicatif::ProgressBar;
use rayon::prelude::*;
use std::f64::consts::PI;
use twoscale::Bxdf;
use twoscale::tables::sh_brdf::{MAX_BAND_LIMIT, block_size, normalized_legendre};

use crate::quad::gauss_legendre;

/// What the projection evaluates: an isotropic BRDF `ρ(wi, wo)` in sr⁻¹ at
/// f64 directions, in the local frame (normal `+z`), with `wi` towards the
/// light and `wo` towards the viewer, both unit vectors in the upper
/// hemisphere. It must be even in `φo − φi` (mirror-symmetric), as every
/// isotropic model of docs/model.md §2 is.
///
/// The runtime's BRDFs are [`twoscale::Bxdf`]s; any one-wavelength one is an
/// `IsotropicBrdf` through [`Runtime`]. The f64 BRDFs of the reference and of
/// [`crate::analytic`] implement it directly, and any
/// `Fn([f64; 3], [f64; 3]) -> f64 + Sync` is one.
pub trait IsotropicBrdf: Sync {
    /// `ρ(wi, wo)`.
    fn eval(&self, wi: [f64; 3], wo: [f64; 3]) -> f64;
}

impl<F: Fn([f64; 3], [f64; 3]) -> f64 + Sync> IsotropicBrdf for F {
    fn eval(&self, wi: [f64; 3], wo: [f64; 3]) -> f64 {
        self(wi, wo)
    }
}

/// Several isotropic BRDFs evaluated together at each direction pair (an RGB
/// model's channels, which share most of their work), projected in one pass
/// by [`project_channels`].
pub trait ChannelBrdf: Sync {
    /// The number of channels.
    fn channels(&self) -> usize;
    /// `ρ_c(wi, wo)` of every channel `c` into `out` (`channels()` long).
    fn eval_channels(&self, wi: [f64; 3], wo: [f64; 3], out: &mut [f64]);
}

/// One channel per BRDF of the list.
pub struct EachChannel<'a>(pub Vec<Box<dyn IsotropicBrdf + 'a>>);

impl ChannelBrdf for EachChannel<'_> {
    fn channels(&self) -> usize {
        self.0.len()
    }
    fn eval_channels(&self, wi: [f64; 3], wo: [f64; 3], out: &mut [f64]) {
        for (v, brdf) in out.iter_mut().zip(&self.0) {
            *v = brdf.eval(wi, wo);
        }
    }
}

/// One BRDF as a one-channel [`ChannelBrdf`].
struct One<'a>(&'a dyn IsotropicBrdf);

impl ChannelBrdf for One<'_> {
    fn channels(&self) -> usize {
        1
    }
    fn eval_channels(&self, wi: [f64; 3], wo: [f64; 3], out: &mut [f64]) {
        out[0] = self.0.eval(wi, wo);
    }
}

/// A one-wavelength runtime BRDF as an [`IsotropicBrdf`]: [`Bxdf::eval`] at
/// the directions rounded to f32, widened to f64 (relative rounding ~6e-8).
#[derive(Clone)]
pub struct Runtime<B>(pub B);

impl<B: Bxdf<Value = f32> + Sync> IsotropicBrdf for Runtime<B> {
    fn eval(&self, wi: [f64; 3], wo: [f64; 3]) -> f64 {
        f64::from(self.0.eval(wi.map(|v| v as f32), wo.map(|v| v as f32)))
    }
}

/// Gauss–Legendre order on each azimuthal panel.
pub const PHI_ORDER: usize = 16;

/// The projection quadrature.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Quadrature {
    /// Gauss–Legendre nodes in `cos θ ∈ [0, 1]` (each of θi, θo).
    pub theta_nodes: usize,
    /// Largest panel width in `Δφ` (radians): the panels must resolve
    /// `cos(L Δφ)`; Gauss–Legendre of order 16 over `L·h ≤ 8` integrates it to
    /// about 1e-16 relative.
    pub phi_max_width: f64,
    /// Number of geometric panels (halving towards `Δφ = π`) below the first
    /// panel of width `phi_max_width`.
    pub phi_levels: usize,
}

impl Quadrature {
    /// Nodes in `Δφ ∈ [0, π]` and their weights (which sum to π): panels in
    /// `u = π − Δφ`, `[0, h 2^−K], [h 2^−K, h 2^(1−K)], …, [h/2, h]`, then
    /// panels of width ≤ `h` up to `π`, each with [`PHI_ORDER`] nodes.
    pub fn phi_rule(&self) -> (Vec<f64>, Vec<f64>) {
        let (t, w) = gauss_legendre(PHI_ORDER);
        let uniform = (PI / self.phi_max_width).ceil().max(1.0) as usize;
        let h = PI / uniform as f64;
        let mut edges = vec![0.0];
        for j in (1..=self.phi_levels).rev() {
            edges.push(h * 0.5f64.powi(j as i32));
        }
        for j in 1..=uniform {
            edges.push(if j == uniform { PI } else { h * j as f64 });
        }
        let mut nodes = Vec::new();
        let mut weights = Vec::new();
        for pair in edges.windows(2) {
            let (lo, hi) = (pair[0], pair[1]);
            for (ti, wi) in t.iter().zip(&w) {
                nodes.push(PI - (lo + 0.5 * (hi - lo) * (ti + 1.0)));
                weights.push(0.5 * (hi - lo) * wi);
            }
        }
        (nodes, weights)
    }

    /// Total nodes in `Δφ`.
    pub fn phi_nodes(&self) -> usize {
        self.phi_rule().0.len()
    }
}

/// The default quadrature for band limit `L`: `N_θ = L + 32` Gauss–Legendre
/// nodes in `cos θ`; in `Δφ`, panels of width ≤ min(π/4, 8/L) and 12
/// geometric levels below them (down to `π − Δφ ≈ 2e-4 h`).
///
/// Measured (test `quadrature_converges`, against a rule with more θ nodes,
/// half the panel width and four more levels): the coefficients agree to a
/// few 1e-15 of the largest one, for Beckmann α = 0.06 and α = 0.5.
pub fn default_quadrature(band_limit: usize) -> Quadrature {
    Quadrature {
        theta_nodes: band_limit + 32,
        phi_max_width: (PI / 4.0).min(8.0 / band_limit as f64),
        phi_levels: 12,
    }
}

/// The half-Gaussian band filter of \[WAT92\] §2.5: coefficient `M_jk` is
/// multiplied by `h(l_j) h(l_k)`, `h(l) = exp(−(l − start)² / (2 width²))` for
/// `l > start`, 1 otherwise.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct BandFilter {
    /// `l_filter`: degrees up to it are kept as they are.
    pub start: f64,
    /// Width of the half-Gaussian, in degrees (> 0).
    pub width: f64,
}

impl BandFilter {
    /// `h(l)`.
    pub fn attenuation(&self, l: usize) -> f64 {
        let excess = l as f64 - self.start;
        if excess <= 0.0 || self.width <= 0.0 {
            1.0
        } else {
            (-(excess * excess) / (2.0 * self.width * self.width)).exp()
        }
    }
}

/// The matrix of one BRDF as computed, before symmetrising: for each `m`,
/// the full `n_m × n_m` block `B^m` (row-major, rows = the `l` of `i`).
#[derive(Clone, Debug)]
pub struct Projection {
    band_limit: usize,
    blocks: Vec<Vec<f64>>,
}

/// Projects `brdf` onto the SH matrix of band limit `band_limit`
/// (2 ..= [`MAX_BAND_LIMIT`]); `progress` advances by one per row of the
/// `N_θ` incident angles.
pub fn project(
    brdf: &dyn IsotropicBrdf,
    band_limit: usize,
    quadrature: Quadrature,
    progress: Option<&ProgressBar>,
) -> Projection {
    let mut projections = project_channels(&One(brdf), band_limit, quadrature, progress);
    projections.pop().expect("one channel")
}

/// [`project`] for every channel of `brdf`, sampling the grid once: each
/// channel's projection is the one [`project`] gives for that channel alone
/// (the same sums in the same order).
pub fn project_channels(
    brdf: &dyn ChannelBrdf,
    band_limit: usize,
    quadrature: Quadrature,
    progress: Option<&ProgressBar>,
) -> Vec<Projection> {
    assert!(
        (2..=MAX_BAND_LIMIT).contains(&band_limit),
        "band limit {band_limit} outside 2..={MAX_BAND_LIMIT}"
    );
    let n_theta = quadrature.theta_nodes;
    let (delta, delta_weights) = quadrature.phi_rule();
    let n_phi = delta.len();
    let (nodes, weights) = gauss_legendre(n_theta);
    // Map [−1, 1] to [0, 1].
    let x: Vec<f64> = nodes.iter().map(|t| 0.5 * (t + 1.0)).collect();
    let w: Vec<f64> = weights.iter().map(|v| 0.5 * v).collect();
    // 4π w_k cos(m Δφ_k) for m ≤ L.
    let cos_table: Vec<f64> = (0..=band_limit)
        .flat_map(|m| {
            delta
                .iter()
                .zip(&delta_weights)
                .map(move |(d, w)| 4.0 * PI * w * (m as f64 * d).cos())
        })
        .collect();
    let (cos_delta, sin_delta): (Vec<f64>, Vec<f64>) =
        delta.iter().map(|d| (d.cos(), d.sin())).unzip();

    let channels = brdf.channels();
    let row_len = (band_limit + 1) * n_theta;
    // g[m][a * n_theta + b] = g_m(x_a, x_b) of channel c at rows[a][c * row_len ..].
    let rows: Vec<Vec<f64>> = (0..n_theta)
        .into_par_iter()
        .map(|a| {
            let (xi, si) = (x[a], (1.0 - x[a] * x[a]).sqrt());
            let wi = [si, 0.0, xi];
            let mut row = vec![0.0; channels * row_len];
            // f[c * n_phi + k]: channel c at Δφ_k.
            let mut f = vec![0.0; channels * n_phi];
            let mut values = vec![0.0; channels];
            for b in 0..n_theta {
                let (xo, so) = (x[b], (1.0 - x[b] * x[b]).sqrt());
                for k in 0..n_phi {
                    let wo = [so * cos_delta[k], so * sin_delta[k], xo];
                    brdf.eval_channels(wi, wo, &mut values);
                    for (c, v) in values.iter().enumerate() {
                        f[c * n_phi + k] = v * xi * xo;
                    }
                }
                for c in 0..channels {
                    let f = &f[c * n_phi..(c + 1) * n_phi];
                    for m in 0..=band_limit {
                        let cosines = &cos_table[m * n_phi..(m + 1) * n_phi];
                        let sum: f64 = f.iter().zip(cosines).map(|(v, cos)| v * cos).sum();
                        row[c * row_len + m * n_theta + b] = sum;
                    }
                }
            }
            if let Some(p) = progress {
                p.inc(1);
            }
            row
        })
        .collect();
    (0..channels)
        .map(|c| {
            let rows: Vec<&[f64]> = rows
                .iter()
                .map(|row| &row[c * row_len..(c + 1) * row_len])
                .collect();
            blocks_of(&rows, band_limit, n_theta, &x, &w)
        })
        .collect()
}

/// The blocks `B^m` from `g_m` (`rows[a][m * n_theta + b] = g_m(x_a, x_b)`)
/// and the Gauss–Legendre rule `(x, w)` on [0, 1].
fn blocks_of(
    rows: &[&[f64]],
    band_limit: usize,
    n_theta: usize,
    x: &[f64],
    w: &[f64],
) -> Projection {
    let mut column = vec![0.0; band_limit + 1];
    let blocks = (0..=band_limit)
        .map(|m| {
            let n = block_size(band_limit, m);
            // wp[a][j] = w_a P̄_{l_j}^m(x_a).
            let wp: Vec<Vec<f64>> = (0..n_theta)
                .map(|a| {
                    normalized_legendre(m, x[a], band_limit, &mut column)
                        .expect("valid Legendre arguments");
                    (0..n).map(|j| w[a] * column[m + 1 + 2 * j]).collect()
                })
                .collect();
            // t[a][k] = Σ_b g_m(a, b) wp[b][k]
            let t: Vec<Vec<f64>> = (0..n_theta)
                .map(|a| {
                    let g = &rows[a][m * n_theta..(m + 1) * n_theta];
                    (0..n)
                        .map(|k| (0..n_theta).map(|b| g[b] * wp[b][k]).sum())
                        .collect()
                })
                .collect();
            let mut block = vec![0.0; n * n];
            for j in 0..n {
                for k in 0..n {
                    block[j * n + k] = 4.0 * (0..n_theta).map(|a| wp[a][j] * t[a][k]).sum::<f64>();
                }
            }
            block
        })
        .collect();
    Projection { band_limit, blocks }
}

impl Projection {
    /// The band limit.
    pub fn band_limit(&self) -> usize {
        self.band_limit
    }

    /// `B^m_{l l'}` as computed (not symmetrised); 0 for an element that is
    /// not stored (`l + m` or `l' + m` even, or out of range).
    pub fn element(&self, m: usize, l: usize, lp: usize) -> f64 {
        let n = block_size(self.band_limit, m);
        if l <= m || lp <= m || (l + m).is_multiple_of(2) || (lp + m).is_multiple_of(2) {
            return 0.0;
        }
        let (a, b) = ((l - m - 1) / 2, (lp - m - 1) / 2);
        if a >= n || b >= n {
            return 0.0;
        }
        self.blocks[m][a * n + b]
    }

    /// `(‖M − Mᵀ‖, ‖M‖)` with the norm of (WAT92 27), `‖A‖ = Σ_jk |A_jk| / J²`,
    /// over the whole matrix (`J` rows: the cos and the sin harmonics of every
    /// `(l, m)` with `l + m` odd; blocks `m > 0` count twice).
    pub fn asymmetry(&self) -> (f64, f64) {
        let (mut diff, mut norm, mut rows) = (0.0, 0.0, 0usize);
        for (m, block) in self.blocks.iter().enumerate() {
            let n = block_size(self.band_limit, m);
            let copies = if m == 0 { 1 } else { 2 };
            rows += copies * n;
            for a in 0..n {
                for b in 0..n {
                    diff += copies as f64 * (block[a * n + b] - block[b * n + a]).abs();
                    norm += copies as f64 * block[a * n + b].abs();
                }
            }
        }
        let j2 = (rows * rows) as f64;
        (diff / j2, norm / j2)
    }

    /// The symmetrised matrix `(M + Mᵀ)/2` (WAT92 §3), filtered, in the packed
    /// layout of `twoscale::tables::sh_brdf` (upper triangles of the blocks, `m` ascending).
    pub fn packed(&self, filter: Option<BandFilter>) -> Vec<f64> {
        let h = |l: usize| filter.map_or(1.0, |f| f.attenuation(l));
        let mut out = Vec::with_capacity(twoscale::tables::sh_brdf::coefficient_count(
            self.band_limit,
        ));
        for (m, block) in self.blocks.iter().enumerate() {
            let n = block_size(self.band_limit, m);
            for a in 0..n {
                for b in a..n {
                    let (la, lb) = (m + 1 + 2 * a, m + 1 + 2 * b);
                    let value = 0.5 * (block[a * n + b] + block[b * n + a]);
                    out.push(value * h(la) * h(lb));
                }
            }
        }
        out
    }

    /// `ρ(i, o)` from the symmetrised (unfiltered) matrix in f64, the same
    /// formula as `twoscale::ShBrdfTable::eval` (for tests and verification
    /// without the f32 rounding of the file).
    pub fn eval(&self, wi: [f64; 3], wo: [f64; 3]) -> f64 {
        let l_max = self.band_limit;
        let (xi, xo) = (wi[2], wo[2]);
        if !(xi > 0.0 && xo > 0.0) {
            return 0.0;
        }
        let (si, so) = (wi[0].hypot(wi[1]), wo[0].hypot(wo[1]));
        let cos_d = if si > 0.0 && so > 0.0 {
            (wi[0] * wo[0] + wi[1] * wo[1]) / (si * so)
        } else {
            1.0
        };
        let delta = cos_d.clamp(-1.0, 1.0).acos();
        let (mut pi, mut po) = (vec![0.0; l_max + 1], vec![0.0; l_max + 1]);
        let mut total = 0.0;
        for (m, block) in self.blocks.iter().enumerate() {
            let n = block_size(l_max, m);
            if n == 0 {
                continue;
            }
            normalized_legendre(m, xi, l_max, &mut pi).expect("valid arguments");
            normalized_legendre(m, xo, l_max, &mut po).expect("valid arguments");
            let mut sum = 0.0;
            for a in 0..n {
                for b in 0..n {
                    let value = 0.5 * (block[a * n + b] + block[b * n + a]);
                    sum += pi[m + 1 + 2 * a] * value * po[m + 1 + 2 * b];
                }
            }
            let weight = if m == 0 { 1.0 } else { 2.0 };
            total += weight * (m as f64 * delta).cos() * sum;
        }
        total / (xi * xo)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::analytic::{BeckmannCt, Lambertian};
    use crate::rng::SplitMix64;

    /// A direction uniform on the upper hemisphere.
    fn random_direction(rng: &mut SplitMix64) -> [f64; 3] {
        let z: f64 = rng.uniform_in(1e-3, 1.0);
        let phi = rng.uniform_in(0.0, 2.0 * PI);
        let s = (1.0 - z * z).sqrt();
        [s * phi.cos(), s * phi.sin(), z]
    }

    /// `max |f_SH − f| / max f` and the relative RMS error of
    /// `f = ρ cos θi cos θo` over `points` random pairs of directions.
    fn f_errors(brdf: &dyn IsotropicBrdf, projection: &Projection, points: usize) -> (f64, f64) {
        let mut rng = SplitMix64::new(6);
        let (mut max_err, mut max_f, mut sum_err2, mut sum_f2) = (0.0f64, 0.0f64, 0.0, 0.0);
        for _ in 0..points {
            let (wi, wo) = (random_direction(&mut rng), random_direction(&mut rng));
            let cc = wi[2] * wo[2];
            let exact = brdf.eval(wi, wo) * cc;
            let approx = projection.eval(wi, wo) * cc;
            max_err = max_err.max((approx - exact).abs());
            max_f = max_f.max(exact.abs());
            sum_err2 += (approx - exact).powi(2);
            sum_f2 += exact * exact;
        }
        (max_err / max_f, (sum_err2 / sum_f2).sqrt())
    }

    #[test]
    fn lambertian_has_its_closed_form_matrix() {
        let albedo = 0.8;
        let projection = project(&Lambertian { albedo }, 8, default_quadrature(8), None);
        for m in 0..=8 {
            for l in 0..=8 {
                for lp in 0..=8 {
                    let want = if (m, l, lp) == (0, 1, 1) {
                        4.0 * albedo / 3.0
                    } else {
                        0.0
                    };
                    let got = projection.element(m, l, lp);
                    assert!((got - want).abs() < 1e-14, "m {m} ({l}, {lp}): {got:e}");
                }
            }
        }
        let rho = projection.eval([0.6, 0.0, 0.8], [0.0, -0.28, 0.96]);
        assert!((rho - albedo / PI).abs() < 1e-14, "{rho}");
    }

    #[test]
    fn channels_projected_together_equal_each_alone() {
        let narrow = BeckmannCt {
            alpha: 0.15,
            eta: None,
        };
        let wide = BeckmannCt {
            alpha: 0.6,
            eta: None,
        };
        let q = default_quadrature(10);
        let both = EachChannel(vec![Box::new(narrow), Box::new(wide)]);
        let together = project_channels(&both, 10, q, None);
        assert_eq!(together.len(), 2);
        for (projection, brdf) in together.iter().zip(&both.0) {
            let alone = project(brdf.as_ref(), 10, q, None);
            assert_eq!(projection.packed(None), alone.packed(None));
        }
        assert_ne!(together[0].packed(None), together[1].packed(None));
    }

    #[test]
    fn reciprocal_brdf_gives_a_symmetric_matrix() {
        let brdf = BeckmannCt {
            alpha: 0.3,
            eta: None,
        };
        let projection = project(&brdf, 12, default_quadrature(12), None);
        let (asymmetry, norm) = projection.asymmetry();
        assert!(
            norm > 0.0 && asymmetry <= 1e-14 * norm,
            "{asymmetry:e} / {norm:e}"
        );
        // A non-reciprocal BRDF is reported as such.
        let skewed = |wi: [f64; 3], wo: [f64; 3]| brdf.eval(wi, wo) * (1.0 + 0.5 * wi[2]);
        let (asymmetry, norm) = project(&skewed, 12, default_quadrature(12), None).asymmetry();
        assert!(asymmetry > 1e-3 * norm, "{asymmetry:e} / {norm:e}");
    }

    #[test]
    fn projection_does_not_depend_on_the_thread_count() {
        let brdf = BeckmannCt {
            alpha: 0.2,
            eta: None,
        };
        let quadrature = default_quadrature(10);
        let serial = rayon::ThreadPoolBuilder::new()
            .num_threads(1)
            .build()
            .unwrap()
            .install(|| project(&brdf, 10, quadrature, None).packed(None));
        let parallel = rayon::ThreadPoolBuilder::new()
            .num_threads(3)
            .build()
            .unwrap()
            .install(|| project(&brdf, 10, quadrature, None).packed(None));
        assert!(
            serial
                .iter()
                .zip(&parallel)
                .all(|(a, b)| a.to_bits() == b.to_bits())
        );
    }

    #[test]
    fn quadrature_converges() {
        // A finer rule changes the coefficients by < 1e-10 of the largest one.
        for (alpha, l) in [(0.06, 16), (0.5, 8)] {
            let brdf = BeckmannCt { alpha, eta: None };
            let q = default_quadrature(l);
            let fine = Quadrature {
                theta_nodes: q.theta_nodes + 24,
                phi_max_width: q.phi_max_width / 2.0,
                phi_levels: q.phi_levels + 4,
            };
            let a = project(&brdf, l, q, None).packed(None);
            let b = project(&brdf, l, fine, None).packed(None);
            let largest = b.iter().fold(0.0f64, |m, v| m.max(v.abs()));
            let change = a
                .iter()
                .zip(&b)
                .fold(0.0f64, |m, (x, y)| m.max((x - y).abs()));
            eprintln!(
                "alpha {alpha} L {l}: quadrature change {:e}",
                change / largest
            );
            assert!(
                change < 1e-10 * largest,
                "α {alpha}: {change:e} of {largest:e}"
            );
        }
    }

    #[test]
    fn rough_brdf_converges_as_l_grows() {
        let brdf = BeckmannCt {
            alpha: 0.5,
            eta: None,
        };
        let mut previous = f64::INFINITY;
        for l in [4, 8, 16, 24] {
            let projection = project(&brdf, l, default_quadrature(l), None);
            let (max, rms) = f_errors(&brdf, &projection, 4000);
            eprintln!("alpha 0.5 L {l}: max {max:.3e} rms {rms:.3e}");
            assert!(rms < 0.7 * previous, "L {l}: {rms:e} after {previous:e}");
            previous = rms;
        }
        assert!(previous < 0.01, "{previous:e}");
    }
}
