//! T6: the directional albedo `E(μ; β, p)` of the EPD microfacet lobe with
//! `F = 1` (docs/model.md §2.10), for each masking mode, and what the
//! energy-compensation lobe needs of it per material.
//!
//! ```text
//! E(μ; β, p) = ∫ D(h) G(i, o) / (4 μ cos θo) · cos θo dωo,   μ = cos θi
//! E_avg      = 2 ∫₀¹ E(μ) μ dμ
//! ```
//!
//! **Layout** (docs/design/t6-albedo-axes.md): a tricubic B-spline over
//!
//! - axis 0, the incidence `y = L/(1 + L) ∈ [0, 1]`, `L = ln(1 + t)`, `t = σ tan θi`,
//!   `σ = σ₀/(1 + σ₀²)`, `σ₀ = (1 + k_p) β` ([`incidence_coordinate`]): the
//!   stretch of the slopes (as the visible-normal sampler stretches them),
//!   widened by `k_p` for heavy tails (where Λ turns at `k_p a ≈ 1`); for
//!   wide lobes σ falls again and the logarithm spreads the decades of
//!   `t`, so that the height-correlated grazing layer (`μ ≈ 1/(k_p β)`)
//!   lies mid-axis;
//! - axis 1, the width `z = (x − 1)/(x + 1) ∈ [−1, 1]`, `x = (γ/γ_c)^κ`,
//!   `γ = k_p β` ([`width_coordinate`]): `k_p β` lines the shapes up (E is
//!   then smooth in p), and the map spends its nodes on `γ ≈ 0.03 … 5`,
//!   where E falls from its small-slope limit (z = −1) to 0 (z = 1);
//! - axis 2, `p ∈ [0.2, 5]` (its mapping is the file's);
//!
//! two channels, separable then height-correlated masking. The node values
//! are the reference of `twoscale_reference::reference::albedo`.
//!
//! **Out of range**: `μ`, β and p clamp to the domain (β > 0 covers
//! `z ∈ (−1, 1)` whole); the result is clamped to [0, 1]. Never NaN, never
//! panics.

use crate::domain::{self, Domain, Invalid};
use crate::material::Masking;
use crate::math;
use crate::math::cosine_weighted_mean;
use crate::tables::format::{AlbedoParams, FormatError, Kernel, Mapping, Table, TableId};
use crate::tables::interp::Grid;
use crate::tables::smith_g1::asymptotic_slope;

/// `γ_c` of [`width_coordinate`].
pub const WIDTH_CENTRE: f64 = 0.37;
/// `κ` of [`width_coordinate`].
pub const WIDTH_EXPONENT: f64 = 2.0 / 3.0;
/// Smallest p of T6.
const P_MIN: f32 = 0.2;
/// Largest p of T6.
const P_MAX: f32 = 5.0;
/// Most incidence coefficients a column holds ([`AlbedoColumn`]).
pub const MAX_INCIDENCE_COEFFICIENTS: usize = 64;
/// Nodes of [`AlbedoColumn::average`]'s rule, even in `√μ`: those of the
/// per-material direction bake, which holds E on them.
pub const AVERAGE_NODES: usize = 257;

/// The width coordinate of axis 1: `z = (x − 1)/(x + 1)`, `x = (γ/γ_c)^κ`,
/// `γ = k_p β` (`k_p` of [`asymptotic_slope`]); −1 at β = 0, 1 at β = ∞.
pub fn width_coordinate(beta: f64, p: f64) -> f64 {
    let gamma = asymptotic_slope(p) * beta;
    if !(gamma > 0.0) {
        return -1.0;
    }
    let x = math::powf(gamma / WIDTH_CENTRE, WIDTH_EXPONENT);
    if x.is_finite() {
        (x - 1.0) / (x + 1.0)
    } else {
        1.0
    }
}

/// The inverse of [`width_coordinate`]: β at `z ∈ (−1, 1)` and p.
pub fn beta_at(z: f64, p: f64) -> f64 {
    let x = (1.0 + z) / (1.0 - z);
    WIDTH_CENTRE * math::powf(x, 1.0 / WIDTH_EXPONENT) / asymptotic_slope(p)
}

/// The slope stretch `σ = σ₀/(1 + σ₀²)`, `σ₀ = (1 + k_p) β`, of
/// [`incidence_coordinate`].
pub fn incidence_stretch(beta: f64, p: f64) -> f64 {
    let s0 = (1.0 + asymptotic_slope(p)) * beta;
    if s0 < 1e150 {
        s0 / (1.0 + s0 * s0)
    } else {
        1.0 / s0
    }
}

/// The incidence coordinate of axis 0 for `cos θi` and the stretch `σ` of
/// [`incidence_stretch`]: `y = L/(1 + L)`, `L = ln(1 + t)`,
/// `t = σ tan θi` (0 at normal incidence, 1 at the horizon; the logarithm
/// spreads the decades of `t` near grazing, where height-correlated masking
/// has a boundary layer of width `μ ≈ 1/(k_p β)`); `cos` clamps to [0, 1].
pub fn incidence_coordinate(cos: f64, stretch: f64) -> f64 {
    let cos = cos.max(0.0).min(1.0);
    let sin = math::sqrt((1.0 - cos) * (1.0 + cos));
    if !(cos > 0.0) {
        return if stretch > 0.0 { 1.0 } else { 0.0 };
    }
    let l = math::ln_1p(stretch * sin / cos);
    l / (1.0 + l)
}

/// The inverse of [`incidence_coordinate`]: `cos θi` at `y ∈ [0, 1]`.
pub fn cos_at(y: f64, stretch: f64) -> f64 {
    if !(y < 1.0) {
        return 0.0;
    }
    let t = math::exp_m1(y / (1.0 - y));
    let a = stretch;
    let h = math::sqrt(a * a + t * t);
    if h > 0.0 && h.is_finite() {
        a / h
    } else if t.is_finite() {
        1.0
    } else {
        0.0
    }
}

/// The channel of a masking mode.
fn channel(masking: Masking) -> usize {
    match masking {
        Masking::Separable => 0,
        Masking::HeightCorrelated => 1,
    }
}

/// T6 viewed in place.
#[derive(Clone, Copy, Debug)]
pub struct AlbedoTable<'a> {
    grid: Grid<'a>,
}

impl<'a> AlbedoTable<'a> {
    /// Validates a T6 file (see [`Table::from_bytes`]) and its shape.
    pub fn from_bytes(bytes: &'a [u8]) -> Result<Self, FormatError> {
        Self::from_table(Table::from_bytes_expecting(bytes, TableId::Albedo)?)
    }

    /// Checks that a validated table has the shape of T6 and the width
    /// constants of this runtime ([`WIDTH_CENTRE`], [`WIDTH_EXPONENT`]).
    pub fn from_table(table: Table<'a>) -> Result<Self, FormatError> {
        let header = table.expecting(TableId::Albedo)?.header();
        let axes = header.used_axes();
        if axes.len() != 3 || header.channels != 2 || header.kernel != Kernel::CubicBSpline {
            return Err(FormatError::Shape(
                "T6 has three axes (incidence, width, p), two channels and B-spline coefficients",
            ));
        }
        let domain = |d: usize| (axes[d].lo as f32, axes[d].hi as f32, axes[d].mapping);
        if domain(0) != (0.0, 1.0, Mapping::Uniform)
            || domain(1) != (-1.0, 1.0, Mapping::Uniform)
            || (domain(2).0, domain(2).1) != (P_MIN, P_MAX)
            || axes[0].nodes as usize + 2 > MAX_INCIDENCE_COEFFICIENTS
        {
            return Err(FormatError::Shape(
                "T6's axes are y ∈ [0, 1] and z ∈ [−1, 1] (uniform, at most 62 y nodes) and p ∈ [0.2, 5]",
            ));
        }
        let params = AlbedoParams::from_header(header);
        if params.width_centre != WIDTH_CENTRE || params.width_exponent != WIDTH_EXPONENT {
            return Err(FormatError::Shape(
                "T6 was built for other width constants than this runtime's",
            ));
        }
        // E lies in [0, 1]; B-spline coefficients overshoot slightly.
        if table.grid().iter().any(|&v| !(-0.1..=1.1).contains(&v)) {
            return Err(FormatError::Shape(
                "T6's coefficients must lie in [-0.1, 1.1]",
            ));
        }
        Ok(AlbedoTable {
            grid: Grid::new(header, table.grid())?,
        })
    }

    /// Checks a lookup point against T6's domain: `cos θi ∈ [0, 1]`,
    /// `β > 0`, p within the table's axis.
    pub fn check(&self, cos_theta_i: f32, beta: f32, p: f32) -> Result<(), Invalid> {
        let w = domain::widen;
        domain::check(
            "cos_theta_i",
            w(cos_theta_i),
            Domain::Closed(0.0, 1.0),
            "T6's domain",
        )?;
        domain::check(
            "beta",
            w(beta),
            Domain::LeftOpen(0.0, f64::INFINITY),
            "T6's domain",
        )?;
        domain::check("p", w(p), Domain::Closed(w(P_MIN), w(P_MAX)), "T6's domain")
    }

    /// `E(μ; β, p)` with `masking`, `μ = cos θi` (module documentation).
    pub fn albedo(&self, cos_theta_i: f32, beta: f32, p: f32, masking: Masking) -> f32 {
        let (beta, p) = clamped(beta, p);
        let y = incidence_coordinate(f64::from(cos_theta_i), incidence_stretch(beta, p));
        let z = width_coordinate(beta, p);
        let v = self
            .grid
            .interpolate([y as f32, z as f32, p as f32], channel(masking));
        v.max(0.0).min(1.0)
    }

    /// E over the incidence at one `(β, p)` and masking: the spline's
    /// coefficients along axis 0, blended over the width and p once.
    pub fn column(&self, beta: f32, p: f32, masking: Masking) -> AlbedoColumn<'a> {
        let (beta, p) = clamped(beta, p);
        let z = width_coordinate(beta, p) as f32;
        let cells = [
            (0, 0.0),
            self.grid.axis(1).locate(z),
            self.grid.axis(2).locate(p as f32),
        ];
        let mut column = AlbedoColumn {
            coefficients: [0.0; MAX_INCIDENCE_COEFFICIENTS],
            count: 0,
            stretch: incidence_stretch(beta, p),
            grid: self.grid,
        };
        column.count = self
            .grid
            .cubic_column(cells, channel(masking), &mut column.coefficients);
        column
    }
}

/// β and p as T6 takes them: p clamped to [0.2, 5], β to [0, f32::MAX]
/// (NaN → 0).
fn clamped(beta: f32, p: f32) -> (f64, f64) {
    let beta = if beta > 0.0 { beta.min(f32::MAX) } else { 0.0 };
    (f64::from(beta), f64::from(p.max(P_MIN).min(P_MAX)))
}

/// `E(μ)` at one `(β, p)` and masking ([`AlbedoTable::column`]).
#[derive(Clone, Copy, Debug)]
pub struct AlbedoColumn<'a> {
    coefficients: [f32; MAX_INCIDENCE_COEFFICIENTS],
    count: usize,
    stretch: f64,
    grid: Grid<'a>,
}

impl AlbedoColumn<'_> {
    /// `E(μ)`, `μ = cos θi` clamped to [0, 1]; the result in [0, 1].
    pub fn albedo(&self, cos_theta_i: f64) -> f32 {
        let y = incidence_coordinate(cos_theta_i, self.stretch) as f32;
        self.grid
            .interpolate_column(&self.coefficients[..self.count], y)
            .max(0.0)
            .min(1.0)
    }

    /// `E_avg = 2 ∫₀¹ E(μ) μ dμ` of this column as the per-material bake
    /// holds it: E at the bake's nodes, even in `√μ`, linear between them
    /// ([`cosine_weighted_mean`]).
    pub fn average(&self) -> f64 {
        let n = AVERAGE_NODES;
        cosine_weighted_mean(n, |k| {
            let x = k as f64 / (n - 1) as f64;
            self.albedo(x * x)
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn coordinates_invert() {
        for p in [0.2, 1.0, 5.0] {
            for beta in [1e-4, 0.01, 0.5, 3.0, 10.0] {
                let z = width_coordinate(beta, p);
                assert!(z > -1.0 && z < 1.0);
                assert!(((beta_at(z, p) - beta) / beta).abs() < 1e-12, "{p} {beta}");
                let s = incidence_stretch(beta, p);
                for cos in [0.0, 1e-3, 0.3, 0.9, 1.0] {
                    let y = incidence_coordinate(cos, s);
                    assert!((0.0..=1.0).contains(&y));
                    assert!((cos_at(y, s) - cos).abs() < 1e-12, "{p} {beta} {cos}");
                }
            }
        }
        assert_eq!(incidence_coordinate(1.0, 0.5), 0.0);
        assert_eq!(incidence_coordinate(0.0, 0.5), 1.0);
    }
}
