//! T2, the renormalisation σrel/σs of the K-correlation (ABC) roughness
//! spectrum over the disc of reachable frequencies (HP17 14-20; docs/model.md
//! §2.4; the spectrum itself: [`crate::model::kcorr`]).
//!
//! ```text
//! S_HS(f)    = (c − 1)/(2π) · σs² b² · (1 + b² f²)^(−(c+1)/2)              (HP17 16)
//! (σrel/σs)² = (1/π) ∫₀^π [1 − (1 + B² R(φ)²)^(−(c−1)/2)] dφ,   B = b/λ,
//! R(φ)       = s cos φ + √(1 − s² sin²φ),   s = sin θi                   (HP17 17-19)
//! ```
//!
//! At normal incidence the ratio has the closed form
//! `r0(B, c) = √(1 − (1 + B²)^(−(c−1)/2))`. T2 stores `q = r / r0` (in
//! [0.66, 1]; exactly 1 at θi = 0 and as B → 0), so that the table only carries
//! the dependence on the incidence, and the runtime multiplies r0 back in.
//!
//! **Layout** (chosen by a measured design study: docs/design/t2-tricubic-bspline.md):
//! - axis 0: `cos θi ∈ [0, 1]`, 72 nodes evenly spaced in `ln(cos θi + 0.003) + 1.5 cos θi`
//!   (dense near grazing, where r drops from r0 to ~r0/√2 in a boundary layer at
//!   `cos θi ≈ (B √((c−1)/2))^(−½)`);
//! - axis 1: `B ∈ [0.05, 3000]`, 68 nodes evenly spaced in `ln B`;
//! - axis 2: `c ∈ [1, 100]`, 32 nodes evenly spaced in `ln(c − 0.8)`; the node at
//!   c = 1 holds the limit c → 1 (computed at c − 1 = 1e-12);
//! - **tricubic B-spline**, the payload holds prefiltered coefficients. docs/model.md §3
//!   says trilinear, but the study measured trilinear at 1.5e-3 relative error
//!   at best within the 1 MiB budget (target 1e-4); the B-spline reaches
//!   ~2.6e-5 with 74·70·34 coefficients (688 KiB).
//!
//! **One material** (fixed B and c, varying incidence, as in a renderer's
//! BRDF): `TwoScale` tabulates σrel/σs over incidence once per material
//! (the σrel column of the per-material bake, `bake::DirectionBake`).
//!
//! **Out of the table's domain** (never NaN, never ∞):
//! - `c ≤ 1` or NaN: 0 (the spectrum cannot be normalised). `c > 100`: the
//!   table at c = 100 with B rescaled to keep `B √((c−1)/2)` fixed (error
//!   7.6e-3 at c = 120, 3e-2 at c = 200, measured in the study).
//! - `B ≤ 0` or NaN: 0. `B < 0.05`: `q² = 1 − k B² / (1 + μ B²)`,
//!   `k = (c+1)/2 · sin²θi` (the exact small-B slope), μ fitted so that q is
//!   continuous at B = 0.05 (error ≤ 2.9e-5). As B → 0 the ratio is linear in B:
//!   `r → B √((c−1)/2)`.
//! - `B > 3000`: `1 − r² = (1 − r0(B)²) · M` with M frozen at B = 3000
//!   (the large-B form `1 − r² ≈ (1 − r0²)·(1/π)∫R^(1−c) dφ`): continuous at
//!   the seam and tends to 1 as B → ∞. Accurate away from grazing (≤ 1.7e-3 for
//!   cos θi > 0.3 up to B = 10⁴); at grazing the true limit is 1/√2, which this
//!   form misses.
//! - `cos θi` is clamped to [0, 1] (NaN → 0).

use crate::domain::{self, Domain, Invalid};
use crate::math;
use crate::tables::format::{FormatError, Kernel, Table, TableId};
use crate::tables::interp::Grid;

/// First B node of T2.
const B_MIN: f32 = 0.05;
/// Last B node of T2.
const B_MAX: f32 = 3000.0;
/// Last c node of T2.
const C_MAX: f32 = 100.0;

/// T2 viewed in place.
#[derive(Clone, Copy, Debug)]
pub struct SigmaRatioTable<'a> {
    grid: Grid<'a>,
}

impl<'a> SigmaRatioTable<'a> {
    /// Validates a T2 file (see [`Table::from_bytes`]) and its shape.
    pub fn from_bytes(bytes: &'a [u8]) -> Result<Self, FormatError> {
        Self::from_table(Table::from_bytes_expecting(bytes, TableId::SigmaRatio)?)
    }

    /// Checks that a validated table has the shape of T2.
    pub fn from_table(table: Table<'a>) -> Result<Self, FormatError> {
        let header = table.expecting(TableId::SigmaRatio)?.header();
        let axes = header.used_axes();
        if axes.len() != 3 || header.channels != 1 || header.kernel != Kernel::CubicBSpline {
            return Err(FormatError::Shape(
                "T2 has three axes (cos θi, B, c), one channel and B-spline coefficients",
            ));
        }
        let domain = |d: usize| (axes[d].lo as f32, axes[d].hi as f32);
        if domain(0) != (0.0, 1.0) || domain(1) != (B_MIN, B_MAX) || domain(2) != (1.0, C_MAX) {
            return Err(FormatError::Shape(
                "T2's domain is cos θi ∈ [0, 1], B ∈ [0.05, 3000], c ∈ [1, 100]",
            ));
        }
        // q = r/r0 lies in [0.66, 1]; B-spline coefficients overshoot slightly.
        if table.grid().iter().any(|&v| !(0.0..=1.5).contains(&v)) {
            return Err(FormatError::Shape("T2's coefficients must lie in [0, 1.5]"));
        }
        Ok(SigmaRatioTable {
            grid: Grid::new(header, table.grid())?,
        })
    }

    /// `q = r / r0` from the table, inputs already inside the domain.
    #[inline]
    fn ratio_to_normal(&self, cos_theta_i: f32, big_b: f32, c: f32) -> f32 {
        self.grid.interpolate([cos_theta_i, big_b, c], 0)
    }

    /// Checks a lookup point against T2's domain: `cos θi` and `c` within the
    /// table's axes (`c > 1`), `B ∈ [0, ∞]` (the rules of the module
    /// documentation extend the table below and above its B nodes).
    pub fn check(&self, cos_theta_i: f32, b_over_lambda: f32, c: f32) -> Result<(), Invalid> {
        let (cos, c_axis) = (self.grid.axis(0), self.grid.axis(2));
        let cos_domain = Domain::Closed(domain::widen(cos.lo()), domain::widen(cos.hi()));
        domain::check(
            "cos_theta_i",
            domain::widen(cos_theta_i),
            cos_domain,
            "T2's domain",
        )?;
        let b_domain = Domain::Closed(0.0, f64::INFINITY);
        domain::check("B", domain::widen(b_over_lambda), b_domain, "T2's domain")?;
        let c_domain = Domain::LeftOpen(domain::widen(c_axis.lo()), domain::widen(c_axis.hi()));
        domain::check("c", domain::widen(c), c_domain, "T2's domain")
    }

    /// σrel/σs at incidence `theta_i` (radians); see [`Self::sigma_ratio_cos`].
    pub fn sigma_ratio(&self, theta_i: f32, b_over_lambda: f32, c: f32) -> f32 {
        self.sigma_ratio_cos(math::cosf(theta_i), b_over_lambda, c)
    }

    /// σrel/σs (HP17 17-19) for `cos θi`, `B = b/λ` and exponent `c`: the table
    /// inside its domain, the rules of the module documentation outside.
    pub fn sigma_ratio_cos(&self, cos_theta_i: f32, b_over_lambda: f32, c: f32) -> f32 {
        self.sigma_ratio_with(cos_theta_i, b_over_lambda, c, |cos, big_b, c| {
            self.ratio_to_normal(cos, big_b, c)
        })
    }

    /// [`Self::sigma_ratio_cos`] at every `cos θi` of `cos` for one `(B, c)`
    /// (into the same positions of `out`): the table is read at one `(B, c)`
    /// whatever the incidence, so its blend over B and c is done once (the
    /// same values up to f32 rounding).
    pub fn sigma_ratio_cos_many(&self, cos: &[f32], b_over_lambda: f32, c: f32, out: &mut [f32]) {
        let (big_b, c_table) = table_point(b_over_lambda.min(f32::MAX), c.min(f32::MAX));
        let cells = [
            (0, 0.0),
            self.grid.axis(1).locate(big_b.max(B_MIN).min(B_MAX)),
            self.grid.axis(2).locate(c_table),
        ];
        let mut column = [0.0f32; COLUMN_CAPACITY];
        let count = self.grid.cubic_column(cells, 0, &mut column);
        let column = &column[..count];
        for (&cos, slot) in cos.iter().zip(out.iter_mut()) {
            *slot = self.sigma_ratio_with(cos, b_over_lambda, c, |cos, _, _| {
                self.grid.interpolate_column(column, cos)
            });
        }
    }

    /// σrel/σs with `q_at(cos θi, B', c')`, T2's `q` at the one point
    /// `(B', c')` of the table (in its domain) the rules read for `(B, c)`.
    #[inline]
    fn sigma_ratio_with(
        &self,
        cos_theta_i: f32,
        b_over_lambda: f32,
        c: f32,
        q_at: impl Fn(f32, f32, f32) -> f32,
    ) -> f32 {
        let cos_theta_i = cos_theta_i.max(0.0).min(1.0);
        if !(c > 1.0 && b_over_lambda > 0.0) {
            return 0.0;
        }
        let big_b = b_over_lambda.min(f32::MAX);
        let c = c.min(f32::MAX);
        let r0 = normal_incidence_ratio(f64::from(big_b), f64::from(c));
        let (table_b, table_c) = table_point(big_b, c);
        let q = self.ratio_for_any_b(cos_theta_i, table_b, table_c, r0, q_at);
        (q * r0) as f32
    }

    /// `q = r/r0` for any B > 0 at a c inside the table (`r0` is that of the
    /// caller's B and c; it only matters beyond the last B node), from
    /// `q_at` (see [`Self::sigma_ratio_with`]).
    fn ratio_for_any_b(
        &self,
        cos_theta_i: f32,
        big_b: f32,
        c: f32,
        r0: f64,
        q_at: impl Fn(f32, f32, f32) -> f32,
    ) -> f64 {
        if big_b < B_MIN {
            // q² = 1 − k B²/(1 + μ B²), continuous with the table at B_MIN.
            let q_lo = f64::from(q_at(cos_theta_i, B_MIN, c));
            let deficit = 1.0 - q_lo * q_lo;
            let sin_sq = f64::from((1.0 - cos_theta_i) * (1.0 + cos_theta_i));
            let k = f64::from(c + 1.0) / 2.0 * sin_sq;
            if !(deficit > 0.0 && k > 0.0) {
                return q_lo;
            }
            let b0_sq = f64::from(B_MIN) * f64::from(B_MIN);
            let mu = ((k * b0_sq - deficit) / (deficit * b0_sq)).max(0.0);
            let b_sq = f64::from(big_b) * f64::from(big_b);
            return math::sqrt((1.0 - k * b_sq / (1.0 + mu * b_sq)).max(0.0));
        }
        if big_b <= B_MAX {
            return f64::from(q_at(cos_theta_i, big_b, c));
        }
        // 1 − r² = (1 − r0(B)²)·M, M frozen at the last node.
        let q_last = f64::from(q_at(cos_theta_i, B_MAX, c));
        let r0_last = normal_incidence_ratio(f64::from(B_MAX), f64::from(c));
        let r_last = q_last * r0_last;
        let tail_last = 1.0 - r0_last * r0_last;
        if !(tail_last > 1e-300 && r0 > 0.0) {
            return q_last;
        }
        let m = (1.0 - r_last * r_last) / tail_last;
        let r_sq = 1.0 - (1.0 - r0 * r0) * m;
        math::sqrt(r_sq.max(0.0)) / r0
    }
}

/// Largest number of T2 coefficients along `cos θi` that
/// [`SigmaRatioTable::sigma_ratio_cos_many`] blends (the shipped T2 has 74).
const COLUMN_CAPACITY: usize = 128;

/// The `(B, c)` at which T2 is read for the caller's `(B, c)`: beyond
/// c = 100, B √((c−1)/2) is kept fixed at the last c node.
#[inline]
fn table_point(big_b: f32, c: f32) -> (f32, f32) {
    if c > C_MAX {
        let scale = math::sqrt(f64::from(c - 1.0) / f64::from(C_MAX - 1.0));
        ((f64::from(big_b) / scale) as f32, C_MAX)
    } else {
        (big_b, c)
    }
}

/// `r0(B, c) = √(1 − (1 + B²)^(−(c−1)/2))`, σrel/σs at normal incidence,
/// evaluated as `√(−expm1(−(c−1)/2 · ln1p(B²)))` (the naive form loses 3e-4 in f32).
pub fn normal_incidence_ratio(big_b: f64, c: f64) -> f64 {
    let exponent = (c - 1.0) / 2.0 * math::ln_1p(big_b * big_b);
    math::sqrt((-math::exp_m1(-exponent)).max(0.0))
}
