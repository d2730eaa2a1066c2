//! Visible-normal sampling of the EPD (docs/model.md §2.1; Heitz & d'Eon
//! 2014, "Importance Sampling Microfacet-Based BSDFs using the Distribution
//! of Visible Normals"), tabulated once per material.
//!
//! Stretched by β, the slope density is the unit-width `P22₁(x̃² + ỹ²)`,
//! isotropic. With the incidence stretched to `i' = (β i_x, β i_y, i_z)`,
//! `c = cos θ'`, `s = sin θ'`, and `x̃` the slope component along `i'`'s
//! azimuth, the visible slopes have the density
//!
//! ```text
//! (c − s x̃)₊ P22₁(x̃² + ỹ²) / N,      N = c (1 + Λ)
//!   = [(c − s x̃)₊ P2(x̃) / N] · [P22₁(x̃² + ỹ²) / P2(x̃)]      marginal × conditional
//! ```
//!
//! The marginal `P2` is one function and the conditional one function of
//! `(|x̃|, |ỹ|)`, both of `p` only. [`VisibleSlopeBake`] tabulates them on
//! the square `|x̃|, |ỹ| ≤ r_max` (beyond it the EPD holds less than 1e-7 of
//! its mass): `P2` piecewise linear in `x̃` on [`ROWS`] nodes per side, the
//! conditional piecewise linear in `|ỹ|` on [`COLS`] nodes per row, rows
//! blended linearly in `|x̃|`. The sampler draws exactly that tabulated
//! density (the marginal's CDF is a cubic per cell, solved by Newton's
//! method; the conditional's a quadratic per cell, solved in closed form;
//! the cells found in O(1) by guide tables, [`guide`]),
//! and [`VisibleSlopeBake::pdf`] evaluates the same tabulated density, so the
//! pdf is the density drawn by construction (to rounding), whatever the
//! tables' distance to the exact `D_vis`; that distance only costs variance.
//! As a solid-angle density over the outgoing direction (`m = h`):
//!
//! ```text
//! pdf(o) = P2_tab(x̃) g_tab(|ỹ|; |x̃|) / (8 N_tab β² |i'| cos⁴θh)     for i·h > 0
//! ```
//!
//! (the factor `c − s x̃` of the marginal cancels against `4 i·h`). It is 0
//! where `i·h ≤ 0` and outside the square, so it integrates to the success
//! rate (`1 − O(1e-7)` of sampled normals reflect below the horizon or
//! nowhere).

use crate::bake::guide;
use crate::math;
use crate::math::gamma::GammaShape;
use zerocopy::FromZeros;

/// `|x̃|` nodes (rows), from 0 to `r_max`.
pub(crate) const ROWS: usize = 64;
/// `|ỹ|` nodes (columns) per row, from 0 to `r_max`.
pub(crate) const COLS: usize = 48;
/// `x̃` nodes: `−r_max … 0 … r_max`.
const X_NODES: usize = 2 * ROWS - 1;
/// The EPD's radial tail mass left outside the tables.
const TAIL_MASS: f64 = 1e-7;
/// Incidence nodes of the marginal's guide beyond `μ = r_max`, even in
/// `r_max/μ` (`μ = c/s = cot θ'` of the stretched incidence).
const GUIDE_TAIL: usize = 8;
/// Incidence nodes of the marginal's guide: `μ` at each row node (the rows
/// are the x̃ nodes, where the marginal's shape changes), then
/// [`GUIDE_TAIL`] more up to `μ = ∞`.
const GUIDE_INCIDENCES: usize = ROWS + GUIDE_TAIL;

/// The tabulated visible-slope sampler at one (β, p) (module documentation).
#[derive(Clone, Debug, FromZeros)]
pub(crate) struct VisibleSlopeBake {
    beta: f64,
    /// `1/σ` of the node axis `log2_axis(1 + a/σ)` (f32: only finds cells).
    inv_sigma: f32,
    /// `(ROWS − 1)` and `(COLS − 1)` over the axis span.
    row_scale: f32,
    col_scale: f32,
    /// `a_i` (rows) and `y_k` (columns); the last of each is `r_max`.
    rows: [f64; ROWS],
    cols: [f64; COLS],
    /// `P2_tab(a_i)` (unnormalised; `N` normalises).
    p2: [f64; ROWS],
    /// `∫ P2_tab` and `∫ x̃ P2_tab` from `−r_max` to each `x̃` node.
    mass: [f64; X_NODES],
    moment: [f64; X_NODES],
    /// The conditional density of `|ỹ|` per row at the columns (each row
    /// integrates to `cum[i][COLS − 1]`, 1 up to rounding).
    dens: [[f32; COLS]; ROWS],
    /// Its integral from 0 to each column (of the f32 densities, in f64).
    cum: [[f64; COLS]; ROWS],
    /// The marginal's guide ([`guide`]) at each incidence node `μ_a`: the
    /// cell of `Φ`'s quantile at each edge.
    marginal_guide: [[u8; guide::EDGES]; GUIDE_INCIDENCES],
    /// The conditional's guide per row.
    conditional_guide: [[u8; guide::EDGES]; ROWS],
}

/// The stretched incidence: `c = cos θ'`, `s = sin θ'`, `|i'|` and the unit
/// tangential direction of `i` (`(1, 0)` at normal incidence).
#[derive(Clone, Copy, Debug)]
struct Stretched {
    c: f64,
    s: f64,
    len: f64,
    t: [f64; 2],
}

/// What the sampler and its density need of one incidence (computed once
/// when one call does both): the stretched incidence, the last cell the
/// visible marginal reaches, the visible length of it, and `N_tab`.
#[derive(Clone, Copy, Debug)]
pub(crate) struct VisibleIncidence {
    st: Stretched,
    j_end: usize,
    tau_end: f64,
    norm: f64,
}

/// Axis position of `a ≥ 0` on nodes `σ (exp2_axis(k/scale) − 1)`.
#[inline]
fn axis(a: f64, inv_sigma: f32, scale: f32) -> f32 {
    math::log2_axis(1.0 + (a as f32) * inv_sigma) * scale
}

/// The cell `[nodes[k], nodes[k + 1]]` of `a` (clamped to the first and last
/// cells) from its axis position, corrected by one node where the f32 axis
/// and the f64 nodes disagree, and the fraction in it (in [0, 1]).
///
/// Mirrored in python/twoscale/drjit/visible.py.
#[inline]
fn locate<const N: usize>(a: f64, nodes: &[f64; N], position: f32) -> (usize, f64) {
    let mut k = (position.max(0.0) as usize).min(N - 2);
    if k > 0 && a < nodes[k] {
        k -= 1;
    } else if k + 2 < N && a >= nodes[k + 1] {
        k += 1;
    }
    let t = ((a - nodes[k]) / (nodes[k + 1] - nodes[k]))
        .max(0.0)
        .min(1.0);
    (k, t)
}

impl VisibleSlopeBake {
    /// The bake of [`VisibleSlopeBake::init`] in new storage.
    #[cfg(test)]
    pub fn new(beta: f32, p: f32) -> Self {
        let mut bake = Self::new_zeroed();
        bake.init(beta, p);
        bake
    }

    /// Tabulates, in place, the marginal and the conditional for `(β, p)` as
    /// [`crate::model::epd::Epd`] clamps them (all zeros is the empty bake).
    pub fn init(&mut self, beta: f32, p: f32) {
        let p = f64::from(p);
        let a_shape = 1.0 / p;
        // r_max: the radial variable r^{2p} is Gamma(1/p); leave TAIL_MASS out.
        let y_max = GammaShape::new(a_shape).inverse_two_tailed(1.0 - TAIL_MASS, TAIL_MASS);
        let r_max = math::powf(y_max, 0.5 / p);
        // σ: for p < 1 a quarter of the radius of mean r^{2p} (nodes dense in
        // the peaked core, geometric in the heavy tail); for p ≥ 1 twice
        // r_max (nodes nearly even: the flat top and the steep edge).
        let sigma = if p >= 1.0 {
            2.0 * r_max
        } else {
            0.25 * math::powf(a_shape, 0.5 / p)
        };
        let span = math::log2_axis((1.0 + r_max / sigma) as f32);
        let node = |k: usize, n: usize| {
            if k == 0 {
                0.0
            } else if k + 1 == n {
                r_max
            } else {
                sigma * (math::exp2_axis(f64::from(span) * k as f64 / (n - 1) as f64) - 1.0)
            }
        };
        let bake = self;
        bake.beta = f64::from(beta);
        bake.inv_sigma = (1.0 / sigma) as f32;
        bake.row_scale = (ROWS - 1) as f32 / span;
        bake.col_scale = (COLS - 1) as f32 / span;
        for (k, slot) in bake.rows.iter_mut().enumerate() {
            *slot = node(k, ROWS);
        }
        for (k, slot) in bake.cols.iter_mut().enumerate() {
            *slot = node(k, COLS);
        }
        bake.mass[0] = 0.0;
        bake.moment[0] = 0.0;
        for i in 0..ROWS {
            let a2 = bake.rows[i] * bake.rows[i];
            let mut raw = [0.0f64; COLS];
            for (k, slot) in raw.iter_mut().enumerate() {
                let y = bake.cols[k];
                *slot = math::exp(-math::powf(a2 + y * y, p));
            }
            let total = trapezoid(&bake.cols, &raw);
            bake.p2[i] = 2.0 * total;
            let inv = if total > 0.0 { 1.0 / total } else { 0.0 };
            let mut acc = 0.0;
            for (k, &value) in raw.iter().enumerate() {
                bake.dens[i][k] = (value * inv) as f32;
                if k > 0 {
                    let w = bake.cols[k] - bake.cols[k - 1];
                    acc += 0.5 * w * (f64::from(bake.dens[i][k - 1]) + f64::from(bake.dens[i][k]));
                }
                bake.cum[i][k] = acc;
            }
        }
        for j in 0..X_NODES - 1 {
            let (x0, h, p0, k) = bake.x_cell(j);
            let p1 = p0 + k * h;
            bake.mass[j + 1] = bake.mass[j] + 0.5 * h * (p0 + p1);
            bake.moment[j + 1] =
                bake.moment[j] + h * (0.5 * x0 * (p0 + p1) + h * (p0 + 2.0 * p1) / 6.0);
        }
        bake.init_guides();
    }

    /// The guides of the marginal and the conditional (after the tables).
    ///
    /// The marginal's quantile at `u` increases with `μ = c/s` (its density
    /// `(μ − x̃)₊ P2_tab` has a likelihood ratio between two `μ` increasing
    /// in `x̃`), so for `μ` in `[μ_a, μ_{a+1}]` and `u` in bin `b` its cell
    /// lies in `[G_{a, b}, G_{a+1, b+1}]`. A blend of two conditional rows
    /// has its quantile between the rows' own.
    fn init_guides(&mut self) {
        let r_max = self.rows[ROWS - 1];
        for a in 0..GUIDE_INCIDENCES {
            // Φ is homogeneous in (c, s): (μ, 1) stands for them, (1, 0) at μ = ∞.
            let (c, s) = if a < ROWS {
                (self.rows[a], 1.0)
            } else {
                let k = a + 1 - ROWS;
                let w = (GUIDE_TAIL - k) as f64 / GUIDE_TAIL as f64;
                if w > 0.0 { (r_max, w) } else { (1.0, 0.0) }
            };
            let st = Stretched {
                c,
                s,
                len: 1.0,
                t: [1.0, 0.0],
            };
            let (j_end, _, norm) = self.extent(&st);
            let phi = |k: usize| {
                if k <= j_end {
                    self.phi_node(st.c, st.s, k)
                } else {
                    norm
                }
            };
            let mut row = [0u8; guide::EDGES];
            guide::build(j_end + 2, phi, &mut row);
            self.marginal_guide[a] = row;
        }
        for i in 0..ROWS {
            let cum = &self.cum[i];
            guide::build(COLS, |k| cum[k], &mut self.conditional_guide[i]);
        }
    }

    /// The marginal's cells for incidence cell `a` and bin `b`, the last
    /// clamped to `j_end`.
    ///
    /// Mirrored in python/twoscale/drjit/visible.py.
    #[inline]
    fn marginal_bracket(&self, a: usize, b: usize, j_end: usize) -> (usize, usize) {
        let hi = usize::from(self.marginal_guide[a + 1][b + 1]).min(j_end);
        let lo = usize::from(self.marginal_guide[a][b]).min(hi);
        (lo, hi)
    }

    /// The columns of the blend of rows `i`, `i + 1` for bin `b`.
    ///
    /// Mirrored in python/twoscale/drjit/visible.py.
    #[inline]
    fn conditional_bracket(&self, i: usize, b: usize) -> (usize, usize) {
        let (gi, gn) = (&self.conditional_guide[i], &self.conditional_guide[i + 1]);
        (
            usize::from(gi[b].min(gn[b])),
            usize::from(gi[b + 1].max(gn[b + 1])),
        )
    }

    /// The incidence cell of the marginal's guide for the stretched `(c, s)`
    /// whose marginal ends in cell `j_end`: `μ`'s row cell where `μ < r_max`
    /// (which [`VisibleSlopeBake::extent`] found), else the cell of
    /// `r_max/μ`.
    #[inline]
    fn guide_incidence(&self, c: f64, s: f64, j_end: usize) -> usize {
        let r_max = self.rows[ROWS - 1];
        if s * r_max > c {
            j_end + 1 - ROWS
        } else {
            let k = ((1.0 - s * r_max / c) * GUIDE_TAIL as f64) as usize;
            ROWS - 1 + k.min(GUIDE_TAIL - 1)
        }
    }

    /// Hands the tables to `v` (`visible_*`: β, the axis constants, the
    /// row and column nodes, `P2_tab`, its mass and moment at the `x̃`
    /// nodes, the conditional's densities and integrals per row).
    pub fn visit(&self, v: &mut dyn crate::bake::BakeVisitor) {
        v.scalar("visible_beta", self.beta);
        v.scalar("visible_inv_sigma", f64::from(self.inv_sigma));
        v.scalar("visible_row_scale", f64::from(self.row_scale));
        v.scalar("visible_col_scale", f64::from(self.col_scale));
        v.array_f64("visible_rows", &[ROWS], &self.rows);
        v.array_f64("visible_cols", &[COLS], &self.cols);
        v.array_f64("visible_p2", &[ROWS], &self.p2);
        v.array_f64("visible_mass", &[X_NODES], &self.mass);
        v.array_f64("visible_moment", &[X_NODES], &self.moment);
        v.array("visible_dens", &[ROWS, COLS], self.dens.as_flattened());
        v.array_f64("visible_cum", &[ROWS, COLS], self.cum.as_flattened());
        guide::visit(v);
        v.array_u8(
            "visible_marginal_guide",
            &[GUIDE_INCIDENCES, guide::EDGES],
            self.marginal_guide.as_flattened(),
        );
        v.array_u8(
            "visible_conditional_guide",
            &[ROWS, guide::EDGES],
            self.conditional_guide.as_flattened(),
        );
    }

    /// The `x̃` node `j` (`j = ROWS − 1` is 0).
    #[inline]
    fn x_node(&self, j: usize) -> f64 {
        if j + 1 >= ROWS {
            self.rows[j + 1 - ROWS]
        } else {
            -self.rows[ROWS - 1 - j]
        }
    }

    /// `P2_tab` at `x̃` node `j`.
    #[inline]
    fn p_node(&self, j: usize) -> f64 {
        if j + 1 >= ROWS {
            self.p2[j + 1 - ROWS]
        } else {
            self.p2[ROWS - 1 - j]
        }
    }

    /// Cell `j` of the marginal: its left node, width, `P2_tab` there and
    /// slope.
    #[inline]
    fn x_cell(&self, j: usize) -> (f64, f64, f64, f64) {
        let (x0, h) = (self.x_node(j), self.x_node(j + 1) - self.x_node(j));
        let p0 = self.p_node(j);
        (x0, h, p0, (self.p_node(j + 1) - p0) / h)
    }

    /// The stretched incidence of the unit `wi` (`wi[2] > 0`).
    #[inline]
    fn stretched(&self, wi: [f64; 3]) -> Stretched {
        let tangential = math::sqrt(wi[0] * wi[0] + wi[1] * wi[1]);
        let bt = self.beta * tangential;
        let len = math::sqrt(bt * bt + wi[2] * wi[2]);
        let t = if tangential > 0.0 {
            [wi[0] / tangential, wi[1] / tangential]
        } else {
            [1.0, 0.0]
        };
        Stretched {
            c: wi[2] / len,
            s: bt / len,
            len,
            t,
        }
    }

    /// `∫₀^τ (c − s x̃)(P0 + k t) dt` over cell `j` from its left node.
    ///
    /// Mirrored in python/twoscale/drjit/visible.py.
    #[inline]
    fn cell_integral(c: f64, s: f64, x0: f64, p0: f64, k: f64, tau: f64) -> f64 {
        let a = c - s * x0;
        tau * (a * p0 + tau * (0.5 * (a * k - s * p0) - tau * (s * k / 3.0)))
    }

    /// `Φ` at node `j`: `c ∫P2_tab − s ∫x̃ P2_tab` from `−r_max`.
    #[inline]
    fn phi_node(&self, c: f64, s: f64, j: usize) -> f64 {
        c * self.mass[j] - s * self.moment[j]
    }

    /// The last cell the visible marginal reaches, the length of it that is
    /// visible, and `N_tab = Φ(min(μ, r_max))`, `μ = c/s`.
    #[inline]
    fn extent(&self, st: &Stretched) -> (usize, f64, f64) {
        let (c, s) = (st.c, st.s);
        let r_max = self.rows[ROWS - 1];
        if !(s * r_max > c) {
            let j = X_NODES - 2;
            let (_, h, _, _) = self.x_cell(j);
            return (j, h, self.phi_node(c, s, X_NODES - 1));
        }
        let mu = c / s;
        let (i, _) = locate(mu, &self.rows, axis(mu, self.inv_sigma, self.row_scale));
        let j = ROWS - 1 + i;
        let (x0, _, p0, k) = self.x_cell(j);
        let tau = mu - x0;
        (
            j,
            tau,
            self.phi_node(c, s, j) + Self::cell_integral(c, s, x0, p0, k, tau),
        )
    }

    /// Row position of `|x̃|` (the blend of the conditional and `P2_tab`).
    #[inline]
    fn row(&self, a: f64) -> (usize, f64) {
        locate(a, &self.rows, axis(a, self.inv_sigma, self.row_scale))
    }

    /// The per-incidence part of [`VisibleSlopeBake::sample`] and
    /// [`VisibleSlopeBake::pdf`] for the unit `wi` (`wi[2] > 0`).
    ///
    /// Mirrored in python/twoscale/drjit/visible.py.
    #[inline]
    pub fn incidence(&self, wi: [f64; 3]) -> VisibleIncidence {
        let st = self.stretched(wi);
        let (j_end, tau_end, norm) = self.extent(&st);
        VisibleIncidence {
            st,
            j_end,
            tau_end,
            norm,
        }
    }

    /// Samples a microfacet normal for the unit incidence `wi` (`wi[2] > 0`)
    /// from `u ∈ [0, 1)²`; `None` where the tables give no mass.
    ///
    /// Mirrored in python/twoscale/drjit/visible.py.
    #[cfg(test)]
    pub fn sample(&self, wi: [f64; 3], u: [f64; 2]) -> Option<[f64; 3]> {
        self.sample_at(&self.incidence(wi), u)
    }

    /// [`VisibleSlopeBake::sample`] at the incidence `inc` of [`VisibleSlopeBake::incidence`].
    pub fn sample_at(&self, inc: &VisibleIncidence, u: [f64; 2]) -> Option<[f64; 3]> {
        let VisibleIncidence {
            st,
            j_end,
            tau_end,
            norm,
        } = *inc;
        let (c, s) = (st.c, st.s);
        if !(norm > 0.0) {
            return None;
        }
        let target = u[0] * norm;
        // The last node j ≤ j_end with Φ_j ≤ target (Φ_0 = 0), in the guide's bracket.
        let a = self.guide_incidence(c, s, j_end);
        let (lo, hi) = self.marginal_bracket(a, guide::bin(u[0]), j_end);
        let j = guide::scan(lo, hi, target, |j| self.phi_node(c, s, j));
        let (x0, h, p0, k) = self.x_cell(j);
        let tau_max = if j == j_end { tau_end } else { h };
        let rest = target - self.phi_node(c, s, j);
        let tau = solve_cell(c, s, x0, p0, k, tau_max, rest);
        let x = x0 + tau;
        // The conditional at |x̃|: its row is the cell j itself, mirrored
        // where x̃ < 0 (no second look-up of |x̃|).
        let x1 = self.x_node(j + 1);
        let (i, a0, a1) = if j + 1 < ROWS {
            (ROWS - 2 - j, -x1, -x0)
        } else {
            (j + 1 - ROWS, x0, x1)
        };
        let lambda = ((x.abs() - a0) / (a1 - a0)).max(0.0).min(1.0);
        let blend = |a: f64, b: f64| a + lambda * (b - a);
        let (ci, cn) = (&self.cum[i], &self.cum[i + 1]);
        let (di, dn) = (&self.dens[i], &self.dens[i + 1]);
        let signed = 2.0 * u[1] - 1.0;
        let q = signed.abs() * blend(ci[COLS - 1], cn[COLS - 1]);
        let (lo, hi) = self.conditional_bracket(i, guide::bin(signed.abs()));
        let kk = guide::scan(lo, hi, q, |k| blend(ci[k], cn[k]));
        let w = self.cols[kk + 1] - self.cols[kk];
        let g0 = blend(f64::from(di[kk]), f64::from(dn[kk]));
        let g1 = blend(f64::from(di[kk + 1]), f64::from(dn[kk + 1]));
        let r = (q - blend(ci[kk], cn[kk])).max(0.0);
        // (g1 − g0) w τ²/2 + g0 w τ = r, the root in [0, 1] without cancellation.
        let b = g0 * w;
        let disc = (b * b + 2.0 * (g1 - g0) * w * r).max(0.0);
        let denom = b + math::sqrt(disc);
        let tau_y = if denom > 0.0 {
            (2.0 * r / denom).max(0.0).min(1.0)
        } else {
            0.0
        };
        let y = (self.cols[kk] + tau_y * w).copysign(signed);
        // Back to the surface: slope β (x̃ t + ỹ t⊥), m = (−slope, 1)/|…|.
        let sx = self.beta * (x * st.t[0] - y * st.t[1]);
        let sy = self.beta * (x * st.t[1] + y * st.t[0]);
        let inv = 1.0 / math::sqrt(1.0 + sx * sx + sy * sy);
        Some([-sx * inv, -sy * inv, inv])
    }

    /// The solid-angle density over `wo` of reflecting `wi` about a normal
    /// from [`VisibleSlopeBake::sample`] (module documentation); both unit,
    /// upper hemisphere.
    ///
    /// Mirrored in python/twoscale/drjit/visible.py.
    pub fn pdf(&self, wi: [f64; 3], wo: [f64; 3]) -> f64 {
        let st = self.stretched(wi);
        // N_tab only where the density is not 0.
        self.pdf_with(&st, wi, wo, || self.extent(&st).2)
    }

    /// [`VisibleSlopeBake::pdf`] with the incidence `inc` of `wi` from
    /// [`VisibleSlopeBake::incidence`].
    pub fn pdf_at(&self, inc: &VisibleIncidence, wi: [f64; 3], wo: [f64; 3]) -> f64 {
        self.pdf_with(&inc.st, wi, wo, || inc.norm)
    }

    /// [`VisibleSlopeBake::pdf`] with the stretched incidence `st` of `wi`
    /// and `N_tab` from `norm`.
    #[inline(always)]
    fn pdf_with(
        &self,
        st: &Stretched,
        wi: [f64; 3],
        wo: [f64; 3],
        norm: impl FnOnce() -> f64,
    ) -> f64 {
        let sum = [wi[0] + wo[0], wi[1] + wo[1], wi[2] + wo[2]];
        if !(sum[2] > 0.0) {
            return 0.0;
        }
        // Stretched slopes of h (|i + o| cancels).
        let inv_bz = 1.0 / (self.beta * sum[2]);
        let (sx, sy) = (-sum[0] * inv_bz, -sum[1] * inv_bz);
        let x = sx * st.t[0] + sy * st.t[1];
        let y = -sx * st.t[1] + sy * st.t[0];
        let r_max = self.rows[ROWS - 1];
        if !(st.c - st.s * x > 0.0 && x.abs() <= r_max && y.abs() <= r_max) {
            return 0.0;
        }
        let norm = norm();
        let (i, lambda) = self.row(x.abs());
        let blend = |a: f64, b: f64| a + lambda * (b - a);
        let p2 = blend(self.p2[i], self.p2[i + 1]);
        let ay = y.abs();
        let (kk, t) = locate(ay, &self.cols, axis(ay, self.inv_sigma, self.col_scale));
        let (di, dn) = (&self.dens[i], &self.dens[i + 1]);
        let g0 = blend(f64::from(di[kk]), f64::from(dn[kk]));
        let g1 = blend(f64::from(di[kk + 1]), f64::from(dn[kk + 1]));
        let total = blend(self.cum[i][COLS - 1], self.cum[i + 1][COLS - 1]);
        let g = (g0 + t * (g1 - g0)) / total;
        // 1/cos⁴θh = (1 + |slope|²)² with the unstretched slope β (sx, sy).
        let slope_sq = self.beta * self.beta * (sx * sx + sy * sy);
        let sec4 = (1.0 + slope_sq) * (1.0 + slope_sq);
        p2 * g * sec4 / (8.0 * norm * self.beta * self.beta * st.len)
    }
}

/// The last index `k < n` with `below(k)` (`below` true at 0 and
/// monotone), by halving: the reference the guides are tested against.
#[cfg(test)]
pub(crate) fn last_at_most(n: usize, below: impl Fn(usize) -> bool) -> usize {
    let (mut base, mut len) = (0usize, n);
    while len > 1 {
        let half = len / 2;
        base = if below(base + half) {
            base + half
        } else {
            base
        };
        len -= half;
    }
    base
}

/// `∫ f` of samples `f` at `x` (trapezoid: exact for piecewise linear `f`).
fn trapezoid<const N: usize>(x: &[f64; N], f: &[f64; N]) -> f64 {
    let mut sum = 0.0;
    for k in 1..N {
        sum += 0.5 * (x[k] - x[k - 1]) * (f[k] + f[k - 1]);
    }
    sum
}

/// The `τ ∈ [0, τ_max]` with `∫₀^τ (c − s(x0 + t))(p0 + k t) dt = rest`
/// (the density is ≥ 0 on the cell): Newton's method kept in a shrinking
/// bracket.
///
/// Mirrored in python/twoscale/drjit/math.py and python/twoscale/drjit/visible.py.
fn solve_cell(c: f64, s: f64, x0: f64, p0: f64, k: f64, tau_max: f64, rest: f64) -> f64 {
    let a = c - s * x0;
    let density = |t: f64| (a - s * t) * (p0 + k * t);
    let (mut lo, mut hi) = (0.0, tau_max);
    // Start from the root without the cubic term: f0 t + b t²/2 = rest.
    let f0 = density(0.0);
    let b = a * k - s * p0;
    let disc = f0 * f0 + 2.0 * b * rest;
    let denom = f0 + math::sqrt(disc.max(0.0));
    let mut t = if denom > 0.0 {
        (2.0 * rest / denom).max(0.0).min(tau_max)
    } else {
        0.5 * tau_max
    };
    for _ in 0..40 {
        let f = VisibleSlopeBake::cell_integral(c, s, x0, p0, k, t) - rest;
        if f < 0.0 {
            lo = t;
        } else {
            hi = t;
        }
        let d = density(t);
        let tolerance = 1e-13 * (x0.abs() + tau_max);
        let mut next = if d > 0.0 { t - f / d } else { 0.5 * (lo + hi) };
        // A converged step is taken even where it rounds onto the bracket's
        // end (bisecting there would leave the root).
        if d > 0.0 && next >= lo && next <= hi && (next - t).abs() <= tolerance {
            return next;
        }
        if !(next > lo && next < hi) {
            next = 0.5 * (lo + hi);
        }
        if (next - t).abs() <= tolerance {
            return next;
        }
        t = next;
    }
    t
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::test_rng::Lcg;

    fn unit(theta_deg: f64, phi: f64) -> [f64; 3] {
        let t = theta_deg.to_radians();
        [t.sin() * phi.cos(), t.sin() * phi.sin(), t.cos()]
    }

    fn reflect(wi: [f64; 3], m: [f64; 3]) -> [f64; 3] {
        let k = 2.0 * (wi[0] * m[0] + wi[1] * m[1] + wi[2] * m[2]);
        [k * m[0] - wi[0], k * m[1] - wi[1], k * m[2] - wi[2]]
    }

    /// The map `u → o` (sample, reflect): its Jacobian by central differences
    /// against `pdf` at random `u`, over p ∈ {0.3, 1, 4}, β ∈ {0.01, 0.3, 1},
    /// θi up to 89°. `pdf · |∂o/∂u₀ × ∂o/∂u₁|` must be 1.
    #[test]
    fn pdf_is_the_jacobian_of_the_sampler() {
        let mut rng = Lcg(17);
        let mut worst = (0.0f64, 0.0, 0.0, 0.0);
        let mut errors = std::vec::Vec::new();
        for p in [0.3f32, 1.0, 4.0] {
            for beta in [0.01f32, 0.3, 1.0] {
                let bake = VisibleSlopeBake::new(beta, p);
                for theta in [0.0, 30.0, 60.0, 80.0, 85.0, 89.0] {
                    let wi = unit(theta, 0.7);
                    for _ in 0..400 {
                        let u = [rng.next(), rng.next()];
                        let e = 1e-7;
                        let at = |u: [f64; 2]| bake.sample(wi, u).map(|m| reflect(wi, m));
                        let (Some(o), Some(a0), Some(b0), Some(a1), Some(b1)) = (
                            at(u),
                            at([u[0] + e, u[1]]),
                            at([u[0] - e, u[1]]),
                            at([u[0], u[1] + e]),
                            at([u[0], u[1] - e]),
                        ) else {
                            continue;
                        };
                        if !(o[2] > 0.0) {
                            continue;
                        }
                        let d0: [f64; 3] = core::array::from_fn(|k| (a0[k] - b0[k]) / (2.0 * e));
                        let d1: [f64; 3] = core::array::from_fn(|k| (a1[k] - b1[k]) / (2.0 * e));
                        let cross = [
                            d0[1] * d1[2] - d0[2] * d1[1],
                            d0[2] * d1[0] - d0[0] * d1[2],
                            d0[0] * d1[1] - d0[1] * d1[0],
                        ];
                        let jac = (cross[0].powi(2) + cross[1].powi(2) + cross[2].powi(2)).sqrt();
                        let err = (bake.pdf(wi, o) * jac - 1.0).abs();
                        errors.push(err);
                        if err > worst.0 {
                            worst = (err, f64::from(p), f64::from(beta), theta);
                        }
                    }
                }
            }
        }
        errors.sort_by(f64::total_cmp);
        let q = |f: f64| errors[((errors.len() - 1) as f64 * f) as usize];
        std::eprintln!(
            "{} points: median {:.1e}, p99 {:.1e}, max {:.1e} at p {}, β {}, θ {}",
            errors.len(),
            q(0.5),
            q(0.99),
            worst.0,
            worst.1,
            worst.2,
            worst.3
        );
        assert!(q(0.99) < 3e-5 && worst.0 < 1e-3, "{worst:?}");
    }

    /// The guides' cells are the binary search's, over p ∈ [0.2, 5] (the
    /// tables depend on p only), θi to 89.9° and random `u`; and the
    /// brackets stay short (the scan's comparisons, `scan_cells`).
    #[test]
    fn guides_find_the_searched_cells() {
        let mut rng = Lcg(29);
        let (mut widest, mut mismatches, mut n) = ([0u8; 2], 0usize, 0usize);
        for step in 0..=48 {
            let p = 0.2 * 25.0f32.powf(step as f32 / 48.0);
            let bake = VisibleSlopeBake::new(0.5, p);
            for b in 0..guide::BINS {
                for a in 0..GUIDE_INCIDENCES - 1 {
                    let (lo, hi) = bake.marginal_bracket(a, b, X_NODES - 2);
                    widest[0] = widest[0].max((hi - lo) as u8);
                }
                for i in 0..ROWS - 1 {
                    let (lo, hi) = bake.conditional_bracket(i, b);
                    widest[1] = widest[1].max((hi - lo) as u8);
                }
            }
            for _ in 0..2000 {
                let theta = 89.9 * rng.next().powf(0.5);
                let inc = bake.incidence(unit(theta, 0.0));
                let (c, s) = (inc.st.c, inc.st.s);
                let u = [rng.next(), rng.next()];
                let target = u[0] * inc.norm;
                let searched = last_at_most(inc.j_end + 1, |j| bake.phi_node(c, s, j) <= target);
                let a = bake.guide_incidence(c, s, inc.j_end);
                let (lo, hi) = bake.marginal_bracket(a, guide::bin(u[0]), inc.j_end);
                let j = guide::scan(lo, hi, target, |j| bake.phi_node(c, s, j));
                // A different cell only where the target is a node's Φ to rounding.
                if j != searched {
                    let gap = (bake.phi_node(c, s, j.max(searched)) - target).abs();
                    assert!(
                        gap <= 1e-14 * inc.norm,
                        "p {p} θ {theta} u {u:?}: {j} {searched}"
                    );
                    mismatches += 1;
                }
                let i = (rng.next() * (ROWS - 1) as f64) as usize;
                let lambda = rng.next();
                let blend =
                    |k: usize| bake.cum[i][k] + lambda * (bake.cum[i + 1][k] - bake.cum[i][k]);
                let q = u[1] * blend(COLS - 1);
                let searched = last_at_most(COLS - 1, |k| blend(k) <= q);
                let (lo, hi) = bake.conditional_bracket(i, guide::bin(u[1]));
                let k = guide::scan(lo, hi, q, blend);
                if k != searched {
                    assert!((blend(k.max(searched)) - q).abs() <= 1e-14, "p {p} row {i}");
                    mismatches += 1;
                }
                n += 2;
            }
        }
        std::eprintln!("{n} cells, {mismatches} at a node's rounding; widest brackets {widest:?}");
        assert!(widest[0] <= 6 && widest[1] <= 6, "{widest:?}");
    }

    /// The tables' cost in variance: the relative variance of `D(m) / pdf`
    /// (the weight of exact visible-normal sampling is `∝ D / pdf_vis`, so
    /// this is what the tables add to it), 10⁵ samples per case, p from 0.3
    /// to 4, β ∈ {0.05, 0.5}, θi up to 85°: at most 3.6e-5 (p = 0.3).
    #[test]
    fn tables_add_little_variance() {
        let mut rng = Lcg(3);
        let mut worst = (0.0f64, 0.0f32, 0.0f32, 0.0f64);
        for p in [0.3f32, 0.6, 1.0, 2.0, 4.0] {
            for beta in [0.05f32, 0.5] {
                let bake = VisibleSlopeBake::new(beta, p);
                for theta in [0.0f64, 45.0, 85.0] {
                    let wi = unit(theta, 0.3);
                    let (mut s1, mut s2, n) = (0.0, 0.0, 100_000);
                    for _ in 0..n {
                        let u = [rng.next(), rng.next()];
                        let Some(m) = bake.sample(wi, u) else {
                            continue;
                        };
                        let tan2 = (m[0] * m[0] + m[1] * m[1]) / (m[2] * m[2]);
                        let beta2 = f64::from(beta) * f64::from(beta);
                        let d = (-(tan2 / beta2).powf(f64::from(p))).exp() / m[2].powi(4);
                        let w = d / bake.pdf(wi, reflect(wi, m));
                        s1 += w;
                        s2 += w * w;
                    }
                    let (m1, m2) = (s1 / f64::from(n), s2 / f64::from(n));
                    let overhead = m2 / (m1 * m1) - 1.0;
                    if overhead > worst.0 {
                        worst = (overhead, p, beta, theta);
                    }
                }
            }
        }
        std::eprintln!("tables' relative variance: worst {worst:?}");
        assert!(worst.0 < 1e-4, "{worst:?}");
    }
}
