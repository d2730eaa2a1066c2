//! T5, the internal diffuse Fresnel reflectance `F_dr,int(η)` of the plastic
//! base layer (HP17 43; docs/model.md §2.6): `F_dr,int(η) = 2 ∫₀¹ F(1/η, μ) μ dμ`
//! for η ∈ [1, 3], a 1-D cubic B-spline (layout in [`DiffuseFresnelTable`]).

use crate::domain::{self, Domain, Invalid};
use crate::tables::format::{FormatError, Kernel, Mapping, Table, TableId};
use crate::tables::interp::Grid;

/// First η node of T5.
const ETA_MIN: f32 = 1.0;
/// Last η node of T5.
const ETA_MAX: f32 = 3.0;

/// T5 viewed in place: the internal diffuse Fresnel reflectance of a
/// dielectric of real index η ∈ [1, 3] (docs/model.md §2.6, §3),
///
/// ```text
/// F_dr,int(η) = 2 ∫₀¹ F(1/η, μ) μ dμ
///             = 1 − 1/η² + F_dr,ext(η)/η²,     F_dr,ext(η) = 2 ∫₀¹ F(η, μ) μ dμ
/// ```
///
/// the cosine-weighted hemispherical reflectance seen from inside the
/// dielectric, total internal reflection (μ < √(1 − 1/η²)) included; it is
/// the `F_dr` of the plastic base layer (HP17 43; docs/model.md §2.6, which corrects
/// the `ρd/π` misprint there).
///
/// **Layout**: one axis, `η ∈ [1, 3]`, 48 nodes evenly spaced in
/// `ln(η − 0.98) + 0.5 η` (the header's log-offset mapping), cubic B-spline
/// coefficients. `F_dr,ext` contains a term `∝ (η − 1)² ln(η − 1)` whose
/// second derivative is singular at η = 1: uniform nodes leave 4.7·10⁻⁵ there
/// even with 64 nodes; the logarithm puts nodes near η = 1 (first cell
/// 2.5·10⁻³ wide) and the linear term keeps enough of them near η = 3.
///
/// **Out of range**: η is clamped to [1, 3]; η < 1 or NaN gives
/// `F_dr,int(1) = 0`, η > 3 gives `F_dr,int(3) ≈ 0.9196`. The result is
/// clamped to [0, 1]. Never NaN, never panics.
#[derive(Clone, Copy, Debug)]
pub struct DiffuseFresnelTable<'a> {
    grid: Grid<'a>,
}

impl<'a> DiffuseFresnelTable<'a> {
    /// Validates a T5 file (see [`Table::from_bytes`]) and its shape.
    pub fn from_bytes(bytes: &'a [u8]) -> Result<Self, FormatError> {
        Self::from_table(Table::from_bytes_expecting(bytes, TableId::DiffuseFresnel)?)
    }

    /// Checks that a validated table has the shape of T5.
    pub fn from_table(table: Table<'a>) -> Result<Self, FormatError> {
        let header = table.expecting(TableId::DiffuseFresnel)?.header();
        let axes = header.used_axes();
        if axes.len() != 1 || header.channels != 1 || header.kernel != Kernel::CubicBSpline {
            return Err(FormatError::Shape(
                "T5 has one axis (η), one channel and B-spline coefficients",
            ));
        }
        if (axes[0].lo as f32, axes[0].hi as f32) != (ETA_MIN, ETA_MAX)
            || axes[0].mapping != Mapping::LogOffset
        {
            return Err(FormatError::Shape(
                "T5's axis is η ∈ [1, 3] with a log-offset mapping",
            ));
        }
        // F_dr,int lies in [0, 1]; B-spline coefficients overshoot slightly.
        if table.grid().iter().any(|&v| !(-0.1..=1.1).contains(&v)) {
            return Err(FormatError::Shape(
                "T5's coefficients must lie in [-0.1, 1.1]",
            ));
        }
        Ok(DiffuseFresnelTable {
            grid: Grid::new(header, table.grid())?,
        })
    }

    /// Checks `eta` against T5's domain, the table's η axis ([1, 3]).
    pub fn check(&self, eta: f32) -> Result<(), Invalid> {
        let domain = Domain::Closed(domain::widen(ETA_MIN), domain::widen(ETA_MAX));
        domain::check("eta", domain::widen(eta), domain, "T5's domain")
    }

    /// `F_dr,int(η)` (see the type's documentation): the table, with η
    /// clamped to [1, 3].
    pub fn f_dr_int(&self, eta: f32) -> f32 {
        let eta = eta.max(ETA_MIN).min(ETA_MAX);
        self.grid.interpolate([eta], 0).max(0.0).min(1.0)
    }
}
