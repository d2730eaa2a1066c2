//! The halo sampler's density over the half-vector, tabulated once per
//! material and wavelength from the C bake (docs/model.md §2.7;
//! docs/design/halo-sampling.md).
//!
//! The halo is `ρ_CTD ∝ Q̄ G (1 − A)/σrel² · C(θh; u)`, `u = B cos θd`, and
//! `ρ_CTD cos θo dωo = ρ_CTD cos θo · 4 (i·h) dζ dψ` over the half-vector
//! (`ζ = 1 − cos θh`, `ψ = φh − φi`). [`HaloBake`] keeps, for each row `u_j`
//! of the C bake ([`ConvBake`]), i.e. for the incidence `cos θi,j = u_j / B`,
//! a density over ζ, piecewise linear between every other of the row's θh
//! nodes (66 of 130). The sampler draws ζ from the rows around
//! `u = B cos θi`, then ψ from the [`Azimuth`] law
//! `∝ (i·h) (cos θo)₊`, which holds two of the halo's factors exactly; the
//! row's node values are the ζ density that minimises the weight's second
//! moment given that law, `√(N(θh) ∫ (i·h)(cos θo)₊ (C(θh; B i·h) W)² dψ)`
//! with `W = Q̄ G (1 − A)/σrel²` at the row's incidence (4-point
//! Gauss–Legendre in ψ):
//!
//! ```text
//! p(h)   = Σ_j w_j(B cos θi) p_j(ζ) · (i·h)(cos θo)₊ / N(θh)
//! p_j(ζ) = (s_jk + σ_jk (ζ − ζ_k)) / M_j                          ζ in cell k
//! N(θh)  = ∫ (i·h)(cos θo)₊ dψ = 2 F(H)              (Azimuth: i·h = a cos ψ + b,
//!          cos θo = 2 (i·h) cos θh − cos θi, a = sin θi sin θh, b = cos θi cos θh)
//! pdf(o) = p(h) / (4 i·h) = Σ_j w_j p_j(ζ) cos θo / (4 N(θh))
//! ```
//!
//! with `w_j` the weights of the rows around `u`, linear in `u` between the
//! rows' own `u_j` (a mixture: the row is picked with its weight; found on
//! the C bake's `u` axis and checked against the f64 `u_j`), `s_jk`,
//! `σ_jk` the start and slope of the piecewise-linear density on cell `k`
//! (baked in f32 from the node values: a gather and one multiply-add per
//! row) and `M_j` the row's total, the integral of the stored coefficients
//! in f64. The cell of ζ is found in O(1): in `pdf` from the row's θh axis,
//! in the draw from the row's guide ([`guide`]). Within a cell the CDF of ζ
//! is a quadratic, solved in closed form; the azimuth's CDF `F(ψ)/F(H)` on each
//! side is inverted by Newton's method in a shrinking bracket.
//! [`HaloBake::pdf`] evaluates the same expression, so the density is the
//! one drawn (to rounding). Where no azimuth gives `cos θo > 0` nothing is
//! drawn; beyond the C bake's last node (`cos θh = 10⁻³`) neither. The
//! support covers the halo's: a row at a larger θi reaches further
//! (`θh < 45° + θi/2`), and the lower row's weight is positive unless the
//! incidence is the upper row's own.

use crate::bake::{
    BakeVisitor, CONV_S_NODES, CONV_U_NODES, ConvBake, angle_span, guide, row_tans, u_axis,
};

/// ζ nodes per row: every other θh node of the C bake's row (and its last).
const NODES: usize = CONV_S_NODES / 2 + 1;

/// The C bake's θh node of the halo's node `k`.
#[inline]
fn conv_node(k: usize) -> usize {
    (2 * k).min(CONV_S_NODES - 1)
}
use crate::math;
use core::f64::consts::PI;
use zerocopy::FromZeros;

/// The halo sampler's per-row densities over `ζ = 1 − cos θh` (module
/// documentation), as per-cell coefficients, with their guides: 48 KB.
#[derive(Clone, Debug, FromZeros)]
pub(crate) struct HaloBake {
    /// The `u` of each row (increasing from 0 to `B`).
    u: [f64; CONV_U_NODES],
    /// `1/(u_{j+1} − u_j)` (0 where the rows coincide; the last unused).
    inv_du: [f64; CONV_U_NODES],
    /// `ζ` at each row's nodes (increasing from 0).
    zeta: [[f32; NODES]; CONV_U_NODES],
    /// `[start, slope]` of each cell `k`: the row's density on
    /// `[ζ_k, ζ_k+1]` is `(start + slope (ζ − ζ_k)) / M_j` (≥ 0 on the cell;
    /// the last node's unused).
    coef: [[[f32; 2]; NODES]; CONV_U_NODES],
    /// The integral of `start + slope (ζ − ζ_0)` from 0 to each node, exact
    /// in f64 from the stored coefficients (the last is `M_j`, 1 up to
    /// rounding; 0 for a row without density).
    cum: [[f64; NODES]; CONV_U_NODES],
    /// `1/M_j` (0 for a row without density).
    inv_total: [f64; CONV_U_NODES],
    /// Each row's guide ([`guide`]) of `cum`.
    guide: [[u8; guide::EDGES]; CONV_U_NODES],
    /// `1/w` of each row's θh axis (the C bake's) and the halo nodes per unit
    /// of `log2_axis(x)`, `x = (1 + sin θh / w)/cos θh`: the cell of ζ in O(1).
    row_inv_w: [f32; CONV_U_NODES],
    row_node_scale: [f32; CONV_U_NODES],
    /// The rows' `u` axis of the C bake: `u_axis(u) · u_scale` is the row position.
    u_linear: f32,
    u_scale: f32,
}

impl HaloBake {
    /// Tabulates the densities of `conv`'s rows in place; `weight(cos θi,
    /// cos θd, cos θo, along, across)` is the halo's `Q̄ G (1 − A)/σrel²`
    /// (`along`, `across` as [`crate::model::fresnel`]'s Q̄ takes them).
    pub fn init(&mut self, conv: &ConvBake, weight: &dyn Fn(f64, f64, f64, f64, f64) -> f64) {
        let big_b = f64::from(conv.row_u[CONV_U_NODES - 1]);
        for j in 0..CONV_U_NODES {
            self.u[j] = f64::from(conv.row_u[j]);
            // The row's incidence, `cos θi = u_j / B`.
            let cos_i = if big_b > 0.0 {
                (self.u[j] / big_b).min(1.0)
            } else {
                1.0
            };
            let tans = row_tans(conv.row_inv_w[j]);
            let mut f = [0.0f64; NODES];
            let mut integral = 0.0f64;
            for k in 0..NODES {
                let t = f64::from(tans[conv_node(k)]);
                let sec = math::sqrt(1.0 + t * t);
                // ζ = 1 − cos θ = tan²θ / (1 + tan²θ + sec θ), without cancellation.
                self.zeta[j][k] = (t * t / (1.0 + t * t + sec)) as f32;
                f[k] = row_value(conv, big_b, cos_i, 1.0 / sec, weight);
                if k > 0 {
                    let dz = f64::from(self.zeta[j][k]) - f64::from(self.zeta[j][k - 1]);
                    integral += 0.5 * dz * (f[k] + f[k - 1]);
                }
            }
            self.set_row(j, &f, integral);
            let inv_w = conv.row_inv_w[j];
            self.row_inv_w[j] = inv_w;
            // The halo's node k is the C bake's 2k (its last the C bake's last).
            self.row_node_scale[j] = 0.5 * (CONV_S_NODES - 1) as f32 / angle_span(inv_w);
        }
        for j in 0..CONV_U_NODES {
            let cum = &self.cum[j];
            guide::build(NODES, |k| cum[k], &mut self.guide[j]);
        }
        // The row axis: the C bake's u position, as `row_cell` reads it.
        let (u_linear, u_scale) = conv.u_axis_constants();
        self.u_linear = u_linear;
        self.u_scale = u_scale;
        for j in 0..CONV_U_NODES {
            let du = if j + 1 < CONV_U_NODES {
                self.u[j + 1] - self.u[j]
            } else {
                0.0
            };
            self.inv_du[j] = if du > 0.0 { 1.0 / du } else { 0.0 };
        }
    }

    /// Row `j`'s cells from its node values `f` (piecewise linear in ζ over
    /// `self.zeta[j]`, of integral `integral`): the coefficients normalised
    /// and rounded to f32 (a slope rounded so that the cell's density stays
    /// ≥ 0), the cumulative and `1/M_j` from the stored coefficients in f64.
    fn set_row(&mut self, j: usize, f: &[f64; NODES], integral: f64) {
        let (zeta, coef, cum) = (&self.zeta[j], &mut self.coef[j], &mut self.cum[j]);
        *coef = [[0.0; 2]; NODES];
        *cum = [0.0; NODES];
        self.inv_total[j] = 0.0;
        if !(integral > 0.0 && integral.is_finite()) {
            return;
        }
        let mut sum = 0.0f64;
        for k in 0..NODES - 1 {
            let dz = f64::from(zeta[k + 1]) - f64::from(zeta[k]);
            let (d0, d1) = (f[k] / integral, f[k + 1] / integral);
            let start = d0 as f32;
            let mut slope = if dz > 0.0 {
                ((d1 - f64::from(start)) / dz) as f32
            } else {
                0.0
            };
            // At the cell's end `start + slope Δζ` must not round below 0.
            while slope < 0.0 && f64::from(start) + f64::from(slope) * dz < 0.0 {
                slope = f32::from_bits(slope.to_bits() - 1);
            }
            coef[k] = [start, slope];
            sum += dz * (f64::from(start) + 0.5 * f64::from(slope) * dz);
            cum[k + 1] = sum;
        }
        if sum > 0.0 && sum.is_finite() {
            self.inv_total[j] = 1.0 / sum;
        } else {
            *coef = [[0.0; 2]; NODES];
            *cum = [0.0; NODES];
        }
    }

    /// Hands the tables to `v` (`halo_zeta` `[33, 66]`, `halo_coef`
    /// `[33, 66, 2]`, columns `start`, `slope`; f64: `halo_cum` `[33, 66]`, `halo_u`, `halo_inv_du`,
    /// `halo_inv_total` `[33]`; rows as `conv_ln_c`'s without ghosts).
    pub fn visit(&self, v: &mut dyn BakeVisitor) {
        let shape = [CONV_U_NODES, NODES];
        v.array("halo_zeta", &shape, self.zeta.as_flattened());
        v.array(
            "halo_coef",
            &[CONV_U_NODES, NODES, 2],
            self.coef.as_flattened().as_flattened(),
        );
        v.columns("halo_coef", &["start", "slope"]);
        v.array_f64("halo_cum", &shape, self.cum.as_flattened());
        v.array_f64("halo_u", &[CONV_U_NODES], &self.u);
        v.array_f64("halo_inv_du", &[CONV_U_NODES], &self.inv_du);
        v.array_f64("halo_inv_total", &[CONV_U_NODES], &self.inv_total);
        v.array_u8(
            "halo_guide",
            &[CONV_U_NODES, guide::EDGES],
            self.guide.as_flattened(),
        );
        v.array("halo_row_inv_w", &[CONV_U_NODES], &self.row_inv_w);
        v.array("halo_row_node_scale", &[CONV_U_NODES], &self.row_node_scale);
    }

    /// Draws `h` for the incidence `wi` and `u = B cos θi` from two
    /// uniforms in [0, 1): `pick` picks the row (the lower one below
    /// `1 − t`) and, rescaled, the azimuth; `along` gives `ζ`. `None` when
    /// the row holds no density or no azimuth at the drawn θh reflects `i`
    /// above the horizon.
    ///
    /// Mirrored in python/twoscale/drjit/halo.py.
    pub fn sample_h(&self, wi: [f64; 3], u_i: f64, pick: f64, along: f64) -> Option<[f64; 3]> {
        let (j, t) = self.row_cell(u_i);
        let (row, azimuth) = if pick < 1.0 - t {
            (j, pick / (1.0 - t))
        } else {
            (j + 1, (pick - (1.0 - t)) / t)
        };
        let azimuth = azimuth.max(0.0).min(f64::from(math::BELOW_ONE));
        let (zeta, coef, cum) = (&self.zeta[row], &self.coef[row], &self.cum[row]);
        let total = cum[NODES - 1];
        if !(total > 0.0) {
            return None;
        }
        let target = along * total;
        let b = guide::bin(along);
        let (lo, hi) = (
            usize::from(self.guide[row][b]),
            usize::from(self.guide[row][b + 1]),
        );
        let k = guide::scan(lo, hi, target, |k| cum[k]);
        // ∫₀^s (start + slope x) dx = rest, the root in [0, Δζ].
        let rest = (target - cum[k]).max(0.0);
        let (start, slope) = (f64::from(coef[k][0]), f64::from(coef[k][1]));
        let (z0, z1) = (f64::from(zeta[k]), f64::from(zeta[k + 1]));
        let den = start + math::sqrt((start * start + 2.0 * slope * rest).max(0.0));
        let s = if den > 0.0 { 2.0 * rest / den } else { 0.0 };
        let z = z0 + s.min(z1 - z0);
        let cos_h = 1.0 - z;
        let sin_h = math::sqrt((z * (2.0 - z)).max(0.0));
        // ψ = φh − φi from (i·h)(cos θo)₊: the side from the azimuth's
        // first half, the magnitude from the rest.
        let sin_i = math::sqrt(wi[0] * wi[0] + wi[1] * wi[1]).min(1.0);
        let law = Azimuth::new(sin_i, wi[2], sin_h, cos_h)?;
        let (side, rest) = if azimuth < 0.5 {
            (-1.0, 2.0 * azimuth)
        } else {
            (1.0, 2.0 * azimuth - 1.0)
        };
        let psi = side * law.solve(rest * law.half);
        let (cos_phi_i, sin_phi_i) = if sin_i > 0.0 {
            (wi[0] / sin_i, wi[1] / sin_i)
        } else {
            (1.0, 0.0)
        };
        let (cp, sp) = (math::cos(psi), math::sin(psi));
        let (cos_phi, sin_phi) = (
            cos_phi_i * cp - sin_phi_i * sp,
            sin_phi_i * cp + cos_phi_i * sp,
        );
        Some([sin_h * cos_phi, sin_h * sin_phi, cos_h])
    }

    /// The density over the outgoing direction of reflecting `wi` about
    /// [`HaloBake::sample_h`]'s draw for `u = B cos θi`, at a half-vector
    /// with `sin θh`, `cos θh` and `cos θo` (module documentation:
    /// `Σ_j w_j p_j(ζ) cos θo / (4 N(θh))`).
    ///
    /// Mirrored in python/twoscale/drjit/halo.py and python/twoscale/drjit/lobes.py.
    pub fn pdf(&self, wi: [f64; 3], u_i: f64, sin_h: f64, cos_h: f64, cos_o: f64) -> f64 {
        let sin_i = math::sqrt(wi[0] * wi[0] + wi[1] * wi[1]).min(1.0);
        let Some(law) = Azimuth::new(sin_i, wi[2], sin_h, cos_h) else {
            return 0.0;
        };
        let zeta = sin_h * sin_h / (1.0 + cos_h);
        // N(θh) = 2 F(H).
        self.pdf_zeta(u_i, zeta, sin_h, cos_h) * cos_o.max(0.0) / (8.0 * law.half)
    }

    /// The density of ζ drawn for `u = B cos θi`, `Σ_j w_j p_j(ζ)`, at the
    /// half-vector of `sin θh`, `cos θh`.
    fn pdf_zeta(&self, u_i: f64, zeta: f64, sin_h: f64, cos_h: f64) -> f64 {
        let (j, t) = self.row_cell(u_i);
        // The C bake's θh axis variables (as `ConvBake::ln_at`).
        let sec_h = 1.0 / (cos_h as f32).max(1e-3);
        let tan_h = (sin_h as f32).max(0.0).min(1.0) * sec_h;
        let mut p = 0.0;
        if t < 1.0 {
            p += (1.0 - t) * self.row_pdf(j, zeta, sec_h, tan_h);
        }
        if t > 0.0 {
            p += t * self.row_pdf(j + 1, zeta, sec_h, tan_h);
        }
        p
    }

    /// The row below `u` (clamped to the rows) and the fraction towards the
    /// next, `(u − u_j)/(u_j+1 − u_j)`.
    ///
    /// Mirrored in python/twoscale/drjit/halo.py.
    #[inline]
    fn row_cell(&self, u: f64) -> (usize, f64) {
        let u = u.max(0.0).min(self.u[CONV_U_NODES - 1]);
        let j = at_node(u, &self.u, u_axis(u as f32, self.u_linear) * self.u_scale);
        let t = ((u - self.u[j]) * self.inv_du[j]).max(0.0).min(1.0);
        (j, t)
    }

    /// The cell of `z = ζ` in row `j` from the C bake's θh axis at `sec θh`,
    /// `tan θh` (f32, as `ConvBake::ln_at` computes them), corrected by one
    /// node where it and the nodes disagree.
    ///
    /// Mirrored in python/twoscale/drjit/halo.py.
    #[inline]
    fn zeta_cell(&self, j: usize, z: f64, sec_h: f32, tan_h: f32) -> usize {
        let x = sec_h + tan_h * self.row_inv_w[j];
        at_node(
            z,
            &self.zeta[j],
            math::log2_axis(x) * self.row_node_scale[j],
        )
    }

    /// `p_j(ζ) = (start_k + slope_k (ζ − ζ_k)) / M_j` of row `j` on its cell
    /// `k` (module documentation); 0 beyond its last node.
    ///
    /// Mirrored in python/twoscale/drjit/halo.py.
    #[inline]
    fn row_pdf(&self, j: usize, z: f64, sec_h: f32, tan_h: f32) -> f64 {
        let zeta = &self.zeta[j];
        if !(z <= f64::from(zeta[NODES - 1])) {
            return 0.0;
        }
        let k = self.zeta_cell(j, z, sec_h, tan_h);
        let [start, slope] = self.coef[j][k];
        let d = f64::from(start) + f64::from(slope) * (z - f64::from(zeta[k]));
        d.max(0.0) * self.inv_total[j]
    }
}

/// The last node `k ≤ N − 2` with `nodes[k] ≤ x` (`nodes` increasing, `x`
/// within them) from an estimate `position` of `x` in nodes that is within
/// one node of it.
///
/// Mirrored in python/twoscale/drjit/halo.py.
#[inline]
fn at_node<T: Copy + Into<f64>, const N: usize>(x: f64, nodes: &[T; N], position: f32) -> usize {
    let (mut k, _) = crate::bake::cell_at(position.max(0.0), N);
    if k > 0 && x < nodes[k].into() {
        k -= 1;
    } else if k + 2 < N && x >= nodes[k + 1].into() {
        k += 1;
    }
    k
}

/// The azimuth law of `h` about the normal for the incidence
/// `(sin θi, cos θi)` at `(sin θh, cos θh)`: with `ψ = φh − φi`,
/// `i·h = a cos ψ + b` (`a = sin θi sin θh`, `b = cos θi cos θh`) and
/// `cos θo = 2 (i·h) cos θh − cos θi`, the density is
/// `∝ (i·h) (cos θo)₊ = A₂ cos²ψ + A₁ cos ψ + A₀` on `|ψ| < H`, where
/// `cos θo > 0` (`i·h > κ = cos θi / (2 cos θh)`), with
/// `A₂ = 2 cos θh a²`, `A₁ = (4 cos θh b − cos θi) a`, `A₀ = (2 cos θh b − cos θi) b`.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Azimuth {
    /// `H`, the half-width of the azimuths where `cos θo > 0`.
    pub big_h: f64,
    /// `[A₂, A₁, A₀]`.
    coef: [f64; 3],
    /// `F(H)` with `F(ψ) = A₂ (ψ + sin ψ cos ψ)/2 + A₁ sin ψ + A₀ ψ`; the
    /// normalisation `N(θh) = ∫ (i·h)(cos θo)₊ dψ` is `2 F(H)`. With
    /// `x = cos H = (κ − b)/a`, `F(H) = A₂ (H + x √(1 − x²))/2 + A₁ √(1 − x²)
    /// + A₀ H` (`A₂ π/2 + A₀ π` at `H = π`): `H` to 2.2e-8 moves it by
    /// `O(10⁻¹⁶)` only, as `F′(H) ∝ (cos θo)₊ = 0` there.
    pub half: f64,
}

impl Azimuth {
    /// The law at `(sin θi, cos θi)` and `(sin θh, cos θh)`; `None` where no
    /// azimuth gives `cos θo > 0` (or `cos θh ≤ 0`).
    ///
    /// Mirrored in python/twoscale/drjit/halo.py.
    pub fn new(sin_i: f64, cos_i: f64, sin_h: f64, cos_h: f64) -> Option<Self> {
        if !(cos_h > 0.0) {
            return None;
        }
        let (a, b) = (sin_i * sin_h, cos_i * cos_h);
        let kappa = cos_i / (2.0 * cos_h);
        let coef = [
            2.0 * cos_h * a * a,
            (4.0 * cos_h * b - cos_i) * a,
            (2.0 * cos_h * b - cos_i) * b,
        ];
        // F(H) from x = cos H, without a sine or cosine: sin H = √(1 − x²).
        let (big_h, half) = if b - a >= kappa {
            (PI, (0.5 * coef[0] + coef[2]) * PI)
        } else if b + a > kappa {
            let x = ((kappa - b) / a).max(-1.0).min(1.0);
            // Inlined (to 2.2e-8, as φmax): a libm call was 13% of `pdf`.
            let big_h = math::acos_approx(x);
            let sin = math::sqrt((1.0 - x * x).max(0.0));
            let half = 0.5 * coef[0] * (big_h + x * sin) + coef[1] * sin + coef[2] * big_h;
            (big_h, half)
        } else {
            return None;
        };
        (half > 0.0).then_some(Azimuth { big_h, coef, half })
    }

    /// The `ψ ∈ [0, H]` with `F(ψ) = target` (`0 ≤ target ≤ F(H)`; F
    /// increases on [0, H]): Newton's method kept in a shrinking bracket (a
    /// step leaving it bisects), to `1e-12` in ψ.
    ///
    /// Mirrored in python/twoscale/drjit/halo.py and python/twoscale/drjit/math.py.
    pub fn solve(&self, target: f64) -> f64 {
        let (mut lo, mut hi) = (0.0f64, self.big_h);
        let mut psi = self.big_h * (target / self.half).max(0.0).min(1.0);
        for _ in 0..AZIMUTH_STEPS {
            let f = cdf(self.coef, psi) - target;
            if f > 0.0 {
                hi = psi;
            } else {
                lo = psi;
            }
            let c = math::cos(psi);
            let slope = (self.coef[0] * c + self.coef[1]) * c + self.coef[2];
            let next = psi - f / slope;
            let newton = slope > 0.0 && next >= lo && next <= hi;
            // A converged step is taken even where it rounds onto the
            // bracket's end (bisecting there would leave the root).
            if newton && (next - psi).abs() < 1e-12 {
                return next;
            }
            let next = if newton && next > lo && next < hi {
                next
            } else {
                0.5 * (lo + hi)
            };
            if (next - psi).abs() < 1e-12 {
                return next;
            }
            psi = next;
        }
        psi
    }
}

/// `F(ψ) = A₂ (ψ + sin ψ cos ψ)/2 + A₁ sin ψ + A₀ ψ` of [`Azimuth`].
///
/// Mirrored in python/twoscale/drjit/halo.py.
#[inline]
fn cdf(coef: [f64; 3], psi: f64) -> f64 {
    let (s, c) = (math::sin(psi), math::cos(psi));
    0.5 * coef[0] * (psi + s * c) + coef[1] * s + coef[2] * psi
}

/// The row density's value at `θh` for the row's incidence: the density of
/// ζ that minimises the halo weight's second moment under the azimuth law
/// [`Azimuth`], `√(N(θh) ∫ (i·h)(cos θo)₊ (C(θh; B i·h) W)² dψ)` with
/// `W = weight(cos θi, i·h, cos θo)` (the halo's factors besides C and the
/// projections), the integral by Gauss–Legendre over `[0, H]` (symmetric).
fn row_value(
    conv: &ConvBake,
    big_b: f64,
    cos_i: f64,
    cos_h: f64,
    weight: &dyn Fn(f64, f64, f64, f64, f64) -> f64,
) -> f64 {
    let sin_i = math::sqrt((1.0 - cos_i * cos_i).max(0.0));
    let sin_h = math::sqrt((1.0 - cos_h * cos_h).max(0.0));
    let Some(law) = Azimuth::new(sin_i, cos_i, sin_h, cos_h) else {
        return 0.0;
    };
    let (a, b) = (sin_i * sin_h, cos_i * cos_h);
    let mut sum = 0.0;
    let nodes = math::GAUSS_LEGENDRE_4
        .iter()
        .flat_map(|&(x, w)| [(-x, w), (x, w)]);
    for (x, w) in nodes {
        let psi = 0.5 * law.big_h * (1.0 + x);
        let (cos_psi, sin_psi) = (math::cos(psi), math::sin(psi));
        let cos_d = a * cos_psi + b;
        let cos_o = 2.0 * cos_d * cos_h - cos_i;
        if cos_o > 0.0 {
            // −i_p·o_p and −(i_p × o_p)_z with o_p = 2 (i·h) h_p − i_p, φi = 0.
            let along = -sin_i * (2.0 * cos_d * sin_h * cos_psi - sin_i);
            let across = -2.0 * cos_d * sin_i * sin_h * sin_psi;
            let c = f64::from(conv.at(sin_h as f32, cos_h as f32, (big_b * cos_d) as f32));
            let g = c * weight(cos_i, cos_d, cos_o, along, across);
            sum += w * cos_d * cos_o * g * g;
        }
    }
    let value = math::sqrt((sum * law.big_h * law.half).max(0.0));
    if value.is_finite() { value } else { 0.0 }
}

/// At most this many Newton steps for the azimuth (bisection alone would
/// need ~40 for 1e-12 of π).
const AZIMUTH_STEPS: usize = 40;

#[cfg(all(test, feature = "embedded"))]
mod tests {
    use super::*;
    use crate::TableSet;
    use crate::test_rng::Lcg;

    /// The test materials `(c, β, p, B)`: HP17's gold, narrow and wide
    /// lobes, a long halo and p ≠ 1.
    const MATERIALS: &[(f32, f32, f32, f32)] = &[
        (2.0, 0.0598, 1.0, 9.2),
        (1.6, 0.1, 1.0, 5.5),
        (2.0, 0.01, 1.0, 1.8),
        (2.0, 0.5, 1.0, 36.0),
        (2.5, 0.35, 1.5, 12.0),
    ];

    /// `halo`'s rows for one of [`MATERIALS`] with a positive weight that
    /// varies with all three cosines (the identities under test hold for
    /// whatever density the rows carry).
    fn init_test_rows(halo: &mut HaloBake, set: &TableSet, c: f32, beta: f32, p: f32, big_b: f32) {
        let slice = set.convolution.slice(c, beta, p).unwrap();
        let conv = ConvBake::new(&slice, big_b, beta, p).unwrap();
        halo.init(&conv, &|cos_i, cos_d, cos_o, _, _| {
            (0.5 + cos_i) * cos_d * (0.2 + cos_o.max(0.0))
        });
    }

    fn reflect(wi: [f64; 3], h: [f64; 3]) -> [f64; 3] {
        let k = 2.0 * (wi[0] * h[0] + wi[1] * h[1] + wi[2] * h[2]);
        [k * h[0] - wi[0], k * h[1] - wi[1], k * h[2] - wi[2]]
    }

    /// `|∂f/∂a × ∂f/∂b|` from the central differences `(a₊ − a₋)/2e`, `(b₊ − b₋)/2e`.
    fn area(a: [[f64; 3]; 2], b: [[f64; 3]; 2], e: f64) -> f64 {
        let d0: [f64; 3] = core::array::from_fn(|k| (a[0][k] - a[1][k]) / (2.0 * e));
        let d1: [f64; 3] = core::array::from_fn(|k| (b[0][k] - b[1][k]) / (2.0 * e));
        let cross = [
            d0[1] * d1[2] - d0[2] * d1[1],
            d0[2] * d1[0] - d0[0] * d1[2],
            d0[0] * d1[1] - d0[1] * d1[0],
        ];
        (cross[0] * cross[0] + cross[1] * cross[1] + cross[2] * cross[2]).sqrt()
    }

    /// The map `(pick, along) → h → o = 2(i·h)h − i` of [`HaloBake::sample_h`],
    /// pointwise: its Jacobians by central differences against the density
    /// of the branch drawn (the row picked, weight `w_j`; `pdf` at the row's
    /// own `u` is that row's density alone), `q(o) = w_j pdf(o)`:
    /// `q · |∂o/∂pick × ∂o/∂along| = 1` and, for the half-vector,
    /// `q · 4 (i·h) · |∂h/∂pick × ∂h/∂along| = 1` (`|dh/do| = 1/(4 o·h)`).
    /// HP17's geometry and strong halos (β 0.01–0.5, B 1.8–36, c 1.6–2.5,
    /// p 1 and 1.5), θi up to 85°. The differences' own error with steps of
    /// 10⁻⁶: rounding, ~10⁻¹⁰ (median); at the few points whose stencil
    /// straddles a node of the piecewise-linear density (the map's second
    /// derivative jumps there) up to ~10⁻⁴ (it grows as the step: 1.6e-2
    /// with 10⁻⁵).
    #[test]
    fn pdf_is_the_jacobian_of_the_half_vector_draw() {
        let set = TableSet::embedded();
        let mut rng = Lcg(29);
        let e = 1e-6;
        let (mut errors_o, mut errors_h) = (std::vec::Vec::new(), std::vec::Vec::new());
        let mut worst = (0.0f64, 0.0f32, 0.0f32, 0.0f64);
        let mut halo = HaloBake::new_zeroed();
        for &(c, beta, p, big_b) in MATERIALS {
            init_test_rows(&mut halo, &set, c, beta, p, big_b);
            for theta in [0.0f64, 30.0, 60.0, 80.0, 85.0] {
                let (s, co) = (theta.to_radians().sin(), theta.to_radians().cos());
                let wi = [s * 0.7f64.cos(), s * 0.7f64.sin(), co];
                let u_i = f64::from(big_b) * co;
                let (j, t) = halo.row_cell(u_i);
                for _ in 0..300 {
                    let (pick, along) = (rng.next(), rng.next());
                    // The branch: row j below 1 − t, row j + 1 above; the
                    // azimuth's uniform (pick rescaled) jumps from ψ = −H to 0 at ½.
                    let (weight, row_u, start) = if pick < 1.0 - t {
                        (1.0 - t, halo.u[j], 0.0)
                    } else {
                        (t, halo.u[j + 1], 1.0 - t)
                    };
                    let azimuth = (pick - start) / weight;
                    if !(pick - e > start && pick + e < start + weight)
                        || (azimuth - 0.5).abs() < 2.0 * e / weight
                        || !(along > e && along + e < 1.0)
                    {
                        continue;
                    }
                    let draw = |pick: f64, along: f64| halo.sample_h(wi, u_i, pick, along).unwrap();
                    let h = draw(pick, along);
                    let hs = [
                        [draw(pick + e, along), draw(pick - e, along)],
                        [draw(pick, along + e), draw(pick, along - e)],
                    ];
                    let os = hs.map(|pair| pair.map(|h| reflect(wi, h)));
                    let sin_h = (h[0] * h[0] + h[1] * h[1]).sqrt();
                    let cos_o = reflect(wi, h)[2];
                    let q = weight * halo.pdf(wi, row_u, sin_h, h[2], cos_o);
                    let i_h = wi[0] * h[0] + wi[1] * h[1] + wi[2] * h[2];
                    let err_o = (q * area(os[0], os[1], e) - 1.0).abs();
                    let err_h = (q * 4.0 * i_h * area(hs[0], hs[1], e) - 1.0).abs();
                    errors_o.push(err_o);
                    errors_h.push(err_h);
                    if err_o.max(err_h) > worst.0 {
                        worst = (err_o.max(err_h), beta, big_b, theta);
                    }
                }
            }
        }
        for errors in [&mut errors_o, &mut errors_h] {
            errors.sort_by(f64::total_cmp);
        }
        let q = |errors: &[f64], f: f64| errors[((errors.len() - 1) as f64 * f) as usize];
        std::eprintln!(
            "{} points: o median {:.1e}, p99 {:.1e}, max {:.1e}; h median {:.1e}, p99 {:.1e}, max {:.1e}; worst at (β, B, θi) {:?}",
            errors_o.len(),
            q(&errors_o, 0.5),
            q(&errors_o, 0.99),
            q(&errors_o, 1.0),
            q(&errors_h, 0.5),
            q(&errors_h, 0.99),
            q(&errors_h, 1.0),
            worst
        );
        assert!(errors_o.len() > 5000);
        for errors in [&errors_o, &errors_h] {
            assert!(
                q(errors, 0.5) < 1e-8 && q(errors, 0.99) < 2e-5 && q(errors, 1.0) < 1e-3,
                "{worst:?}"
            );
        }
    }

    /// The O(1) cells (rows from the u axis, ζ cells from the θh axis, the
    /// draw's cell from the guide) are the binary search's, for the
    /// materials of the Jacobian test, at random `u`, θh and uniforms; and
    /// the guides' brackets stay short.
    #[test]
    fn cells_are_the_searched_ones() {
        use crate::bake::visible::last_at_most;
        let set = TableSet::embedded();
        let mut rng = Lcg(31);
        let mut halo = HaloBake::new_zeroed();
        let mut widest = 0u8;
        for &(c, beta, p, big_b) in MATERIALS {
            init_test_rows(&mut halo, &set, c, beta, p, big_b);
            for g in &halo.guide {
                for b in 0..guide::BINS {
                    widest = widest.max(g[b + 1] - g[b]);
                }
            }
            for _ in 0..20_000 {
                let u = f64::from(big_b) * rng.next();
                let (j, _) = halo.row_cell(u);
                assert_eq!(
                    j,
                    last_at_most(CONV_U_NODES - 1, |j| halo.u[j] <= u),
                    "u {u}"
                );
                let row = (rng.next() * CONV_U_NODES as f64) as usize;
                let zeta = &halo.zeta[row];
                let z = f64::from(zeta[NODES - 1]) * rng.next().powi(3);
                let (cos_h, sin_h) = (1.0 - z, (z * (2.0 - z)).sqrt());
                let sec = 1.0 / (cos_h as f32).max(1e-3);
                let k = halo.zeta_cell(row, z, sec, sin_h as f32 * sec);
                assert_eq!(
                    k,
                    last_at_most(NODES - 1, |k| f64::from(zeta[k]) <= z),
                    "z {z}"
                );
                let cum = &halo.cum[row];
                let along = rng.next();
                let target = along * cum[NODES - 1];
                let b = guide::bin(along);
                let (lo, hi) = (
                    usize::from(halo.guide[row][b]),
                    usize::from(halo.guide[row][b + 1]),
                );
                let k = guide::scan(lo, hi, target, |k| cum[k]);
                let searched = last_at_most(NODES - 1, |k| cum[k] <= target);
                assert!(k == searched || (cum[k.max(searched)] - target).abs() <= 1e-14);
            }
        }
        std::eprintln!("widest bracket {widest}");
        assert!(widest <= 6, "{widest}");
    }
}
