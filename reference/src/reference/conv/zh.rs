//! Zonal-harmonic (Legendre) computation of the convolution (HP17 61–64).
//!
//! # The series
//!
//! For a zonal kernel `K(h·m)` the Funk–Hecke theorem says that the
//! spherical harmonics of degree `l` are eigenfunctions of
//! `f ↦ ∫ K(h·m) f(m) dω_m` with eigenvalue `λ_l = 2π ∫_{−1}^{1} K(t) P_l(t) dt`.
//! Expanding the zonal `D(n·m) = Σ_l (2l+1)/(4π) · d_l · P_l(n·m)`,
//! `d_l = 2π ∫ D(t) P_l(t) dt`, gives
//!
//! ```text
//!   C(θh) = Σ_l (2l+1)/(4π) · λ_l d_l P_l(cos θh) = π Σ_l (2l+1) a_l b_l P_l(cos θh),
//!   a_l = ∫₀^{π/2} K(γ) P_l(cos γ) sin γ dγ,    b_l = ∫₀^{π/2} D(θ) P_l(cos θ) sin θ dθ,
//! ```
//!
//! with both integrals over the upper hemisphere of each lobe only (the cut
//! of docs/model.md §2.5). This is (HP17 64): with `Y_l⁰ = √((2l+1)/4π) P_l` (HP17 61),
//! `S_l = 2π √((2l+1)/4π) a_l` (HP17 62), `D_l = 2π √((2l+1)/4π) b_l`
//! (HP17 63), `S_l D_l √(4π/(2l+1)) Y_l⁰ = π (2l+1) a_l b_l P_l`. Checks of the
//! convention: `K ≡ 1`, `D ≡ 1` on the whole sphere give `a_0 = b_0 = 2` and
//! `C = 4π`; `b_1 = 1/(2π)` is the normalisation `∫ D cos θ dω = 1`.
//!
//! # The moments
//!
//! `P_l(cos θ)` (bounded by 1, so no normalisation is needed against
//! overflow; the forward recurrence is stable) is evaluated at every node for
//! every `l ≤ L_q`, by the three-term recurrence rewritten for
//! `s = 1 − cos θ = 2 sin²(θ/2)` (see [`legendre_step`]), which keeps full
//! relative accuracy next to the pole.
//! The rule is composite Gauss–Legendre **in the angle** (not in `cos θ`,
//! which crowds a narrow lobe into `1 − cos θ ~ β²/2`): the lobe's own
//! breakpoints (geometric grids around its peak, see `Lobe::breakpoints`)
//! cut `[0, π/2]` into pieces on which it is smooth, and each piece is cut
//! further into equal parts of length at most `40 / L_q`, each with 32 nodes.
//! `P_l(cos θ)` is a trigonometric polynomial of degree `l` in `θ`: on a part
//! of half-length `h/2` it oscillates like `e^{iωx}`, `ω = l h/2 ≤ 20`, which
//! an `n = 32` point Gauss rule integrates with an error of order
//! `(e ω / 4n)^(2n) ≈ 1e-24`. Measured: 48 nodes on parts of `20 / L_q`
//! change the moments by `≤ 1e-15` of `m_0` (test `moment_rule_is_converged`).
//! The cost is `N_nodes · L_q ≈ 1.3 L_q²` multiply–adds per lobe, vectorised
//! over blocks of 8 nodes: ≈ 0.1 s at `L_q = 8192`, 0.3 s at 16384, 3.5 s at
//! 65536 (release build, one core).
//!
//! # Band limit
//!
//! The series converges once the product `a_l b_l` has decayed, i.e. on the
//! scale of the *wider* lobe, but how fast depends on the smoothness of both:
//!
//! * the kernel `(1 + 4u² sin²γ)^(−q)` is analytic at its peak, with poles at
//!   `sin γ = ± i/(2u)`: `a_l ~ exp(−l/(2u))` (times powers of `l`), so
//!   reaching `1e-12` needs `L_K ≈ 2u · ln 1e12 ≈ 55 u`. Its cut at `γ = π/2`
//!   (a jump of `K''` of size `2 k(2u)`) adds an algebraic tail
//!   `a_l ~ k(2u) l^(−5/2)`, which decides for small `u`;
//! * `D` behaves like `exp(−(θ/β)^(2p))` near the normal: smooth only for
//!   integer `p`. For any other `p` it has a cusp (infinite slope for
//!   `p < ½`, a cone at `p = ½`, infinite curvature for `½ < p < 1`, a
//!   weaker singularity above), whose 2-D Fourier transform, hence `b_l`,
//!   decays only like `(lβ)^(−2−2p)`: then only the kernel cuts the series
//!   off, and `L ≈ 110 u` whatever `β` (measured). Small `p` also spreads `D`
//!   over `tan θ ~ β·y^(1/(2p))`, `y ~ Gamma(1/p)` (for `p = 0.2`, up to
//!   `10³ β`), and gives it a narrow maximum next to the horizon for wide
//!   `β` (`cos θ ≈ 3e-3` at `β = 1`, `p = 0.2`), which needs `L ≈ 10⁴` by
//!   itself.
//!
//! The measured band limits are tabulated at [`zh_band_estimate`], which
//! encodes these rules. Zonal harmonics become infeasible (`L > 65536`,
//! several seconds per profile and growing like `L²`) for a narrow kernel
//! (`u = 3000`) on any cusped `D`, and on narrow smooth `D` with `p = 5`;
//! [`convolution_zh`] reports that as [`ConvError::BandLimitExceeded`].

use super::{ConvError, Lobe, Params, TARGET, sort_dedup};
use crate::quad::gauss_legendre;
use std::collections::HashMap;
use std::f64::consts::{FRAC_PI_2, PI};
use std::sync::{Arc, Mutex, OnceLock};

/// Nodes per Gauss–Legendre part of the moment rule.
const NODES: usize = 32;
/// `l_max · h` bound for the parts of the moment rule.
const BAND_PER_PART: f64 = 40.0;

/// Options of [`convolution_zh`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ZhOptions {
    /// Convergence tolerance: doubling the band limit must change every
    /// requested value by at most `tol · max(|C(θh)|, floor · C(0))`.
    pub tol: f64,
    /// Relative floor of the tolerance's scale (see `tol`).
    pub floor: f64,
    /// First band limit tried (the series is compared between `L` and `2L`);
    /// `None`: 64.
    pub start_band: Option<usize>,
    /// Largest band limit of the returned series (coefficients up to it).
    pub max_band: usize,
}

impl Default for ZhOptions {
    /// `tol = TARGET/4`, `floor = TARGET` (so `2.5e-13 · C(0)` absolute in
    /// the deep tails), start at `L = 64`, `max_band = 65536`. The quarter:
    /// on the corner sweep the error of the returned series (against the
    /// direct quadrature) was up to 4× the last change.
    fn default() -> Self {
        Self {
            tol: 0.25 * TARGET,
            floor: TARGET,
            start_band: None,
            max_band: 65536,
        }
    }
}

/// A converged zonal-harmonic profile.
#[derive(Clone, Debug, PartialEq)]
pub struct ZhProfile {
    /// `C` at the requested angles, from the series truncated at
    /// `band_limit`.
    pub values: Vec<f64>,
    /// `C(0)` from the same series.
    pub c0: f64,
    /// Band limit `L` of the returned values.
    pub band_limit: usize,
    /// The largest change between the series at `L/2` and at `L`, relative
    /// to `max(|C|, floor · C(0))`.
    pub change: f64,
}

/// The Legendre moments of lobes, kept so that profiles sharing a lobe share
/// its moments: in the T3 grid the kernel's `a_l` depend on `(u, c)` only
/// (280 pairs) and the NDF's `b_l` on `(β, p)` only (144 pairs), while each
/// of the 40 320 nodes needs both. The moments of a lobe at a band limit are
/// a deterministic function of the lobe's parameters and that band limit
/// ([`legendre_moments`] on the lobe's breakpoints), so a profile computed
/// with the cache is bit-identical to one computed without.
///
/// Thread-safe: each entry is computed once, by the first thread that asks;
/// the others wait for it. Memory: `8 · (l_max + 1)` bytes per entry, never
/// released while the cache lives (≈ 0.26 MB per lobe for the doublings up
/// to `L = 16384`, ≈ 110 MB for the T3 grid).
#[derive(Debug, Default)]
pub struct MomentCache {
    entries: Mutex<HashMap<MomentKey, MomentSlot>>,
}

/// One cache entry: the moments once computed.
type MomentSlot = Arc<OnceLock<Arc<[f64]>>>;

/// A lobe (its kind and defining parameters, as bits) and a band limit.
type MomentKey = (u8, [u64; 2], usize);

impl MomentCache {
    /// An empty cache.
    pub fn new() -> Self {
        Self::default()
    }

    /// The moments of `lobe` up to `l_max`, computed on first use.
    fn moments(&self, lobe: &Lobe, breakpoints: &[f64], l_max: usize) -> Arc<[f64]> {
        let (kind, bits) = lobe.key();
        let slot = {
            // A poisoned lock only means another thread panicked while
            // inserting; the map itself is still consistent.
            let mut map = self
                .entries
                .lock()
                .unwrap_or_else(std::sync::PoisonError::into_inner);
            Arc::clone(map.entry((kind, bits, l_max)).or_default())
        };
        Arc::clone(
            slot.get_or_init(|| {
                legendre_moments(|s, c| lobe.value(s, c), breakpoints, l_max).into()
            }),
        )
    }
}

/// `C(θh)` at the angles `theta_h` by zonal harmonics, doubling the band
/// limit until converged (see the module documentation).
pub fn convolution_zh(
    u: f64,
    c: f64,
    beta: f64,
    p: f64,
    theta_h: &[f64],
    opts: &ZhOptions,
) -> Result<ZhProfile, ConvError> {
    convolution_zh_cached(u, c, beta, p, theta_h, opts, &MomentCache::new())
}

/// [`convolution_zh`] taking the lobes' moments from `cache` (bit-identical
/// results; see [`MomentCache`]).
pub fn convolution_zh_cached(
    u: f64,
    c: f64,
    beta: f64,
    p: f64,
    theta_h: &[f64],
    opts: &ZhOptions,
    cache: &MomentCache,
) -> Result<ZhProfile, ConvError> {
    let params = Params::new(u, c, beta, p)?;
    for &t in theta_h {
        Params::validate_theta(t)?;
    }
    let kernel = params.kernel();
    let ndf = params.ndf();
    let (kbp, dbp) = (kernel.breakpoints(), ndf.breakpoints());
    let mut band = opts
        .start_band
        .unwrap_or(64)
        .max(16)
        .min(opts.max_band / 2)
        .max(1);
    loop {
        let lq = 2 * band;
        let a = cache.moments(&kernel, &kbp, lq);
        let b = cache.moments(&ndf, &dbp, lq);
        let full0 = zh_series(&a, &b, lq, 0.0);
        let half0 = zh_series(&a, &b, band, 0.0);
        let scale = opts.floor * full0.abs();
        let rel = |full: f64, half: f64| (full - half).abs() / full.abs().max(scale);
        let mut change = rel(full0, half0);
        let mut values = Vec::with_capacity(theta_h.len());
        for &t in theta_h {
            let full = zh_series(&a, &b, lq, t);
            let half = zh_series(&a, &b, band, t);
            change = change.max(rel(full, half));
            values.push(full);
        }
        if change <= opts.tol && values.iter().all(|v| v.is_finite()) {
            return Ok(ZhProfile {
                values,
                c0: full0,
                band_limit: lq,
                change,
            });
        }
        if 2 * lq > opts.max_band {
            return Err(ConvError::BandLimitExceeded {
                band_limit: lq,
                change,
            });
        }
        band = lq;
    }
}

/// `π Σ_{l=0}^{L} (2l+1) a_l b_l P_l(cos θh)` (HP17 64 in Legendre form),
/// with `P_l` from the three-term recurrence written for
/// `s = 1 − cos θh = 2 sin²(θh/2)`.
pub fn zh_series(a: &[f64], b: &[f64], band: usize, theta_h: f64) -> f64 {
    if a.is_empty() || b.is_empty() {
        return 0.0;
    }
    let band = band.min(a.len() - 1).min(b.len() - 1);
    let s = 2.0 * (0.5 * theta_h).sin().powi(2);
    let mut p = 1.0; // P_0
    let mut d = 0.0; // P_0 − P_{−1}, with P_{−1} = 1 so that P_1 = 1 − s
    let mut sum = a[0] * b[0];
    for l in 0..band {
        legendre_step(l, s, &mut p, &mut d);
        sum += (2 * l + 3) as f64 * a[l + 1] * b[l + 1] * p;
    }
    PI * sum
}

/// One step `(P_l, P_l − P_{l−1}) → (P_{l+1}, P_{l+1} − P_l)` of the
/// Legendre recurrence `(l+1) P_{l+1} = (2l+1) x P_l − l P_{l−1}` written for
/// `s = 1 − x`:
///
/// ```text
///   Δ_{l+1} = (l Δ_l − (2l+1) s P_l) / (l+1),    P_{l+1} = P_l + Δ_{l+1}.
/// ```
///
/// Near the pole (`θ ~ 1e-4`, where the narrow lobes live) `x = cos θ`
/// itself carries an absolute rounding error of `1e-16`, i.e. a relative
/// error of `1e-8` in `1 − x`, which `P_l` amplifies by `l²/2`; `s` computed
/// as `2 sin²(θ/2)` has none (measured: moments at `l = 2048` of a `u = 3000`
/// kernel moved by `7e-12` relative with the plain recurrence). The start
/// `P_0 = 1`, `Δ_0 = 0` gives `P_1 = 1 − s = x`. `|P_l| ≤ 1` on `[−1, 1]`,
/// so nothing overflows.
#[inline]
fn legendre_step(l: usize, s: f64, p: &mut f64, d: &mut f64) {
    let lf = l as f64;
    let next = (lf * *d - (2.0 * lf + 1.0) * s * *p) / (lf + 1.0);
    *d = next;
    *p += next;
}

/// The Legendre moments `m_l = ∫₀^{π/2} f(sin θ, cos θ) P_l(cos θ) sin θ dθ`,
/// `l = 0..=l_max`, by composite Gauss–Legendre in `θ` on the pieces between
/// `breakpoints` (angles in `(0, π/2)`), each cut into parts of length
/// `≤ 40 / l_max` with 32 nodes (see the module documentation).
pub fn legendre_moments(
    f: impl Fn(f64, f64) -> f64,
    breakpoints: &[f64],
    l_max: usize,
) -> Vec<f64> {
    moments_with_rule(f, breakpoints, l_max, NODES, BAND_PER_PART)
}

/// [`legendre_moments`] with an explicit rule (nodes per part, bound on
/// `l_max · h`), for the refinement tests.
pub(super) fn moments_with_rule(
    f: impl Fn(f64, f64) -> f64,
    breakpoints: &[f64],
    l_max: usize,
    nodes: usize,
    band_per_part: f64,
) -> Vec<f64> {
    let mut cuts: Vec<f64> = breakpoints
        .iter()
        .copied()
        .filter(|&x| x > 0.0 && x < FRAC_PI_2)
        .collect();
    cuts.push(0.0);
    cuts.push(FRAC_PI_2);
    sort_dedup(&mut cuts);
    let h_max = band_per_part / (l_max.max(1) as f64);
    let (gx, gw) = gauss_legendre(nodes);
    let mut t = Vec::new();
    let mut w = Vec::new();
    for pair in cuts.windows(2) {
        let (a, b) = (pair[0], pair[1]);
        let parts = ((b - a) / h_max).ceil().max(1.0) as usize;
        let h = (b - a) / parts as f64;
        for k in 0..parts {
            let lo = a + h * k as f64;
            let (mid, half) = (lo + 0.5 * h, 0.5 * h);
            for (x, wt) in gx.iter().zip(&gw) {
                let theta = mid + half * x;
                let (s, c) = theta.sin_cos();
                let v = f(s, c) * s * half * wt;
                if v != 0.0 {
                    t.push(2.0 * (0.5 * theta).sin().powi(2));
                    w.push(v);
                }
            }
        }
    }
    accumulate(&t, &w, l_max)
}

/// Width of the node blocks of [`accumulate`].
const LANES: usize = 8;

/// `m_l = Σ_i w_i P_l(1 − s_i)` for `l = 0..=l_max`, running the recurrence
/// of [`legendre_step`] on blocks of [`LANES`] nodes at once (independent
/// lanes, so the compiler vectorises them; each lane keeps its own partial
/// sums, added in a fixed order at the end, so the result is deterministic).
fn accumulate(s: &[f64], w: &[f64], l_max: usize) -> Vec<f64> {
    // (l, (2l+1)) / (l+1) for the recurrence.
    let c1: Vec<f64> = (0..=l_max).map(|l| l as f64 / (l + 1) as f64).collect();
    let c2: Vec<f64> = (0..=l_max)
        .map(|l| (2 * l + 1) as f64 / (l + 1) as f64)
        .collect();
    let mut lanes = vec![[0.0f64; LANES]; l_max + 1];
    for (sc, wc) in s.chunks(LANES).zip(w.chunks(LANES)) {
        let mut x = [0.0; LANES];
        let mut ww = [0.0; LANES];
        x[..sc.len()].copy_from_slice(sc);
        ww[..wc.len()].copy_from_slice(wc);
        let mut p = [1.0; LANES];
        let mut d = [0.0; LANES];
        for j in 0..LANES {
            lanes[0][j] += ww[j];
        }
        for l in 0..l_max {
            let (a, b) = (c1[l], c2[l]);
            let acc = &mut lanes[l + 1];
            for j in 0..LANES {
                d[j] = a * d[j] - b * x[j] * p[j];
                p[j] += d[j];
                acc[j] += ww[j] * p[j];
            }
        }
    }
    lanes
        .iter()
        .map(|lane| {
            let mut sum = 0.0;
            for v in lane {
                sum += v;
            }
            sum
        })
        .collect()
}

/// Prior estimate of the band limit needed with the default [`ZhOptions`]
/// (see the module documentation), fitted to the measured band limits
/// below. It only decides whether
/// [`convolution_profile`](super::convolution_profile) tries zonal
/// harmonics at all (the series always starts at `L = 64` and doubles, so a
/// conservative estimate costs nothing but a direct quadrature):
///
/// * `D` smooth (integer `p`): `L_D = 16 p^0.86 / β` (the Fourier transform
///   of `exp(−(θ/β)^(2p))` decays on the scale `1/β`, more slowly for the
///   sharp shoulder of large `p`);
/// * `D` with a cusp (non-integer `p`): `L_D = 30/β`, and at least `30/ε_s`
///   for the narrow maximum next to the horizon
///   (`ε_s = (p/2)^(1/(2p)) / β < 1/4`);
/// * a peaked kernel (`u ≥ 10`): `L = min(L_D, 55u + 128)` for smooth `D`
///   (`a_l ~ exp(−l/(2u))` must fall to `~1e-12`, the default floor), but
///   `L = 110u + 128` under a cusp, whose algebraic tail of `b_l` must then
///   be cut by the kernel alone, whatever `β`. Below `u = 10` the kernel's
///   cut at the horizon keeps `a_l` algebraic and `L = L_D`.
///
/// Measured band limits (doubling from 16 until the change is below
/// `2.5e-7`, `c = 2`; `c = 10` often needs twice as much at `u ≥ 300`):
///
/// | u \ (β, p) | .002,.2 | .002,.5 | .002,1 | .002,5 | .05,.2 | .05,.5 | .05,1 | .05,5 | 1,.2 | 1,.5 | 1,1 | 1,5 |
/// |---|---|---|---|---|---|---|---|---|---|---|---|---|
/// | 0    | 1024   | 16384  | 8192  | 32768  | 512    | 512    | 256 | 1024 | 8192   | 128   | 64  | 128  |
/// | 1    | 1024   | 16384  | 8192  | 16384  | 256    | 512    | 256 | 1024 | 8192   | 128   | 64  | 128  |
/// | 30   | 4096   | 4096   | 4096  | 4096   | 2048   | 2048   | 512 | 2048 | 4096   | 1024  | 256 | 512  |
/// | 300  | 32768  | 32768  | 8192  | 32768  | 16384  | 16384  | 512 | 4096 | 32768  | 8192  | 512 | 1024 |
/// | 3000 | >65536 | >65536 | 16384 | >65536 | >65536 | >65536 | 512 | 8192 | >65536 | 65536 | 512 | 1024 |
pub fn zh_band_estimate(params: &Params) -> usize {
    let (u, beta, p) = (params.u, params.beta, params.p);
    let smooth = (p - p.round()).abs() < 1e-9;
    let mut l_d = if smooth {
        16.0 * p.powf(0.86) / beta
    } else {
        30.0 / beta
    };
    let eps = (0.5 * p).powf(0.5 / p) / beta;
    if !smooth && eps < 0.25 {
        l_d = l_d.max(30.0 / eps);
    }
    let l = if u < 10.0 {
        l_d
    } else if smooth {
        (55.0 * u + 128.0).min(l_d)
    } else {
        110.0 * u + 128.0
    };
    l.clamp(64.0, 1e9) as usize
}
