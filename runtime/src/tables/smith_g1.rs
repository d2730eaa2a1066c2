//! T1: Smith masking G1 of the Exponential Power Distribution NDF.
//!
//! Smith's Λ for the EPD depends on the shape `p` and on `a = β tan θ` only
//! (HP17 36-38, with the factor 2 of the slope marginal restored; docs/model.md §2.2).
//! Its asymptote is `Λ(a) = k_p·a − 1/2 + O(1/a)`, with
//! `k_p = Γ(3/(2p)) / (π Γ(1/p))`, and `k_p` spans 0.207 (p = 5) to 24.8
//! (p = 0.2): the transition from G1 ≈ 1 to G1 ≈ 1/(k_p a) moves by two decades
//! of `a` across the p range. The table therefore uses the scaled variable
//!
//! ```text
//! ã = k_p · a        (so that Λ ≈ ã − 1/2 for every p)
//! ```
//!
//! and stores `G1(p, ã)` on
//! - axis 0: `p ∈ [0.2, 5]`, nodes evenly spaced in `p^−½`;
//! - axis 1: `ã ∈ [0, ã_last]`, nodes evenly spaced in `ln(ã + 0.01)`
//!   (parameters in the header);
//!
//! and, as aux values, `k_p` at each p node. The runtime computes `k_p` in
//! closed form for the p it is asked about (two `lgamma`, once per material in
//! [`SmithG1Table::shape`]) and checks at load time that the stored values
//! agree with it at the nodes (relative 1e-5), so a file built with another
//! scaling convention is rejected. Interpolating `k_p` between p nodes instead
//! was measured: `k_p` falls 4x between p = 0.2 and 0.25, and linear
//! interpolation of it put a 1.2e-3 error into G1 near p = 0.22.
//!
//! Beyond the last node the asymptote continues the table with unit slope in ã:
//! `Λ(ã) = Λ(ã_last) + (ã − ã_last)`, continuous at the seam by construction;
//! the neglected `O(1/ã)` term changes G1 by less than 1e-8 at ã_last = 100.
//!
//! Out of domain: `p` clamps to [0.2, 5]; `a ≤ 0` or NaN gives G1 = 1; `a = +∞`
//! gives G1 = 0. No input returns NaN or panics.

use crate::domain::{self, Domain, Invalid};
use crate::tables::format::{FormatError, Mapping, Table, TableId};
use crate::tables::interp::{Axis, Grid};

/// T1 viewed in place: `G1(p, ã)` and `k_p` per p node.
#[derive(Clone, Copy, Debug)]
pub struct SmithG1Table<'a> {
    grid: Grid<'a>,
    /// `k_p` at each p node, as stored (checked against the closed form at load).
    stored_slopes: &'a [f32],
}

impl<'a> SmithG1Table<'a> {
    /// Validates a T1 file (see [`Table::from_bytes`]) and its shape.
    pub fn from_bytes(bytes: &'a [u8]) -> Result<Self, FormatError> {
        Self::from_table(Table::from_bytes_expecting(bytes, TableId::SmithG1)?)
    }

    /// Checks that a validated table has the shape of T1.
    pub fn from_table(table: Table<'a>) -> Result<Self, FormatError> {
        let header = table.expecting(TableId::SmithG1)?.header();
        let axes = header.used_axes();
        if axes.len() != 2 || header.channels != 1 {
            return Err(FormatError::Shape("T1 has two axes (p, ã) and one channel"));
        }
        if axes[1].lo != 0.0 || axes[1].mapping != Mapping::LogOffset {
            return Err(FormatError::Shape(
                "T1's ã axis starts at 0 with a log-offset mapping",
            ));
        }
        if axes[0].lo <= 0.0 {
            return Err(FormatError::Shape("T1's p axis must be positive"));
        }
        let kappa = table.aux();
        if kappa.len() != axes[0].nodes as usize {
            return Err(FormatError::Shape(
                "T1 stores k_p at each p node as aux values",
            ));
        }
        for (j, &stored) in kappa.iter().enumerate() {
            let p = crate::tables::interp::node_value(&axes[0], j);
            let exact = asymptotic_slope(p);
            if !(((f64::from(stored) - exact) / exact).abs() <= 1e-5) {
                return Err(FormatError::Shape(
                    "T1's stored k_p disagrees with k_p = Γ(3/(2p)) / (π Γ(1/p))",
                ));
            }
        }
        if table.grid().iter().any(|&g| !(0.0..=1.0).contains(&g)) {
            return Err(FormatError::Shape("T1's G1 values must lie in [0, 1]"));
        }
        Ok(SmithG1Table {
            grid: Grid::new(header, table.grid())?,
            stored_slopes: kappa,
        })
    }

    /// `k_p` at each p node, as stored in the file.
    pub fn stored_slopes(&self) -> &'a [f32] {
        self.stored_slopes
    }

    /// The p axis.
    pub fn p_axis(&self) -> &Axis {
        self.grid.axis(0)
    }

    /// The ã axis.
    pub fn scaled_axis(&self) -> &Axis {
        self.grid.axis(1)
    }

    /// Everything that depends on `p` only, computed once per material.
    pub fn shape(&self, p: f32) -> SmithShape<'a> {
        let (cell, t) = self.grid.axis(0).locate(p);
        let n_a = self.grid.axis(1).nodes();
        let values = self.grid.values();
        let row = |i: usize| values.get(i * n_a..(i + 1) * n_a).unwrap_or(&[]);
        let p = p.max(self.grid.axis(0).lo()).min(self.grid.axis(0).hi());
        let mut shape = SmithShape {
            axis: *self.grid.axis(1),
            row0: row(cell),
            row1: row(cell + 1),
            t,
            kappa: asymptotic_slope(f64::from(p)) as f32,
            lambda_last: 0.0,
        };
        let g1_last = shape.g1_in_table(shape.axis.hi());
        shape.lambda_last = lambda_from_g1(g1_last);
        shape
    }

    /// Checks a lookup point against T1's domain: `p` within the table's p
    /// axis (from its header), `a ∈ [0, ∞]` ([`crate::validate`]).
    pub fn check(&self, p: f32, a: f32) -> Result<(), Invalid> {
        let axis = self.grid.axis(0);
        let p_domain = Domain::Closed(domain::widen(axis.lo()), domain::widen(axis.hi()));
        domain::check("p", domain::widen(p), p_domain, "T1's domain")?;
        let a_domain = Domain::Closed(0.0, f64::INFINITY);
        domain::check("a", domain::widen(a), a_domain, "T1's domain")
    }

    /// G1(p, a) with `a = β tan θ` (for repeated lookups at one p, keep a [`SmithShape`]).
    pub fn g1(&self, p: f32, a: f32) -> f32 {
        self.shape(p).g1(a)
    }

    /// Λ(p, a).
    pub fn lambda(&self, p: f32, a: f32) -> f32 {
        self.shape(p).lambda(a)
    }
}

/// T1 at one value of `p`: the two table rows around it and the interpolated `k_p`.
#[derive(Clone, Copy, Debug)]
pub struct SmithShape<'a> {
    axis: Axis,
    row0: &'a [f32],
    row1: &'a [f32],
    /// Fraction between `row0` and `row1`.
    t: f32,
    /// `k_p` (closed form).
    kappa: f32,
    /// Λ at the last ã node.
    lambda_last: f32,
}

impl SmithShape<'_> {
    /// The asymptotic slope `k_p` of Λ in `a`.
    pub fn kappa(&self) -> f32 {
        self.kappa
    }

    /// G1 at a table point `ã ≤ ã_last` (bilinear: the a cell in both rows).
    #[inline]
    fn g1_in_table(&self, a_scaled: f32) -> f32 {
        let (i, s) = self.axis.locate(a_scaled);
        let at = |row: &[f32], j: usize| row.get(j).copied().unwrap_or(0.0);
        let g0 = at(self.row0, i) + s * (at(self.row0, i + 1) - at(self.row0, i));
        let g1 = at(self.row1, i) + s * (at(self.row1, i + 1) - at(self.row1, i));
        g0 + self.t * (g1 - g0)
    }

    /// Smith G1 at `a = β tan θ` (HP17 38): from the table for ã ≤ ã_last, from
    /// the asymptote beyond. `a ≤ 0` or NaN → 1; `a = +∞` → 0.
    #[inline]
    pub fn g1(&self, a: f32) -> f32 {
        // NaN fails the comparison and lands here too.
        if !(a > 0.0) {
            return 1.0;
        }
        let a_scaled = self.kappa * a;
        if a_scaled <= self.axis.hi() {
            self.g1_in_table(a_scaled)
        } else {
            // Λ = Λ_last + (ã − ã_last); for ã = ∞ this is 1/∞ = 0.
            1.0 / (1.0 + self.lambda_last + (a_scaled - self.axis.hi()))
        }
    }

    /// Smith Λ at `a = β tan θ` (HP17 37), `= 1/G1 − 1`; finite for finite `a`.
    #[inline]
    pub fn lambda(&self, a: f32) -> f32 {
        if !(a > 0.0) {
            return 0.0;
        }
        let a_scaled = self.kappa * a;
        if a_scaled <= self.axis.hi() {
            lambda_from_g1(self.g1_in_table(a_scaled))
        } else {
            // a = ∞ (a horizontal direction) would give ∞: clamp to stay finite.
            (self.lambda_last + (a_scaled - self.axis.hi())).min(f32::MAX)
        }
    }
}

/// The asymptotic slope of Smith Λ for the EPD, `k_p = Γ(3/(2p)) / (π Γ(1/p))`
/// (docs/model.md §2.2): `k_p = ∫₀^∞ r P2(r) dr`, half the mean |slope| along one axis.
pub fn asymptotic_slope(p: f64) -> f64 {
    crate::math::exp(crate::math::ln_gamma(1.5 / p) - crate::math::ln_gamma(1.0 / p))
        / core::f64::consts::PI
}

/// Λ = 1/G1 − 1, guarded so that G1 = 0 gives the largest finite value.
#[inline]
fn lambda_from_g1(g1: f32) -> f32 {
    if g1 > 0.0 {
        (1.0 / g1 - 1.0).max(0.0)
    } else {
        f32::MAX
    }
}
