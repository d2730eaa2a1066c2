//! Per-material bakes: what a [`crate::brdf::TwoScale`] precomputes once so
//! that a lookup in the inner loop costs a few multiply-adds.
//!
//! * [`DirectionBake`]: the quantities of one direction's `cos θ` at one
//!   wavelength — F(η, cos θ), the factors of Q̄ ([`QConstants::factors`]) and
//!   σrel/σs (T2), and the sampler's lobe weights — on 257 nodes even in `√cos θ` (dense at grazing, where σrel
//!   and F move fastest), linear between nodes.
//! * [`RadialNormBake`]: `1/M(sin θi)`, the normalisation of the diffraction
//!   sampler's radial law, on 513 nodes even in `sin θi`, linear between.
//! * [`MaskingBake`]: Smith G1 (T1 at the material's p) on 1025 nodes even in
//!   `y = a/(1 + a)`, `a = β tan θ`, linear between nodes; `y = 1` is the
//!   horizon (G1 = 0).
//! * [`ConvBake`]: `ln C(θh; u)` for the material's `(c, β, p)` on 33 × 130
//!   nodes, `u = B cos θd ∈ [0, B]` even in `log₂(1 + u/u₀) + a u` and θh
//!   even in `x = ln((1 + sin θh / w(u)) / cos θh)` per row (the logarithms are
//!   [`math::log2_axis`], a cheap C¹ stand-in), Catmull–Rom in both (edge cells
//!   extrapolate linearly: a ghost node on each side). `w(u)` is about a
//!   quarter of the lobe's core at `u` ([`ConvBake::inv_width`]): each row's
//!   core gets nodes, rows are blended at equal `x` (as T3 blends at equal
//!   ξ), and the power-law tail (linear in `ln sin θh`) is interpolated
//!   almost exactly; the `1/cos θh` term spends
//!   nodes on the horizon, where `C ∝ cos²θh` and `ln C` diverges. Beyond
//!   `cos θh = 10⁻³` the last node is used.
//!
//! The errors against the direct lookups are measured by the tests beside
//! each bake (`bake::tests`) and, for the whole BRDF, by `tests/bake.rs`.
//!
//! Each bake is plain numbers, valid when all zero ([`FromZeros`]), and is
//! filled in place by its `init`: a model's storage
//! ([`crate::brdf::ChannelBake`]) can be allocated zeroed on the heap, or
//! provided by the caller, and baked without a stack copy of its arrays.

mod conv;
mod direction;
pub(crate) mod guide;
pub(crate) mod halo;
mod masking;
mod radial;
pub(crate) mod visible;

pub(crate) use conv::*;
pub(crate) use direction::*;
pub(crate) use masking::*;
pub(crate) use radial::*;

/// Linear-interpolation position on `n` nodes (`n ≤ 2²²`) of `x ∈ [0, 1]`
/// (clamped; NaN gives 0): the cell and the fraction in it.
#[inline]
fn cell(x: f32, n: usize) -> (usize, f32) {
    cell_at((x * (n - 1) as f32).max(0.0), n)
}

/// [`cell`] of a position `t` in nodes (`t ≥ 0`, clamped to `n − 1`).
///
/// Mirrored in python/twoscale/drjit/lookups.py.
#[inline]
pub(crate) fn cell_at(t: f32, n: usize) -> (usize, f32) {
    let t = t.min((n - 1) as f32);
    // ⌊t⌋ without a saturating float-to-integer conversion: `t − ½ + 1.5·2²³`
    // rounds to an integer (f32's spacing there is 1), which the low bits
    // hold; a tie rounds to even, which may give the node below `t` with
    // fraction 1 — the same interpolated value.
    let rounded = (t - 0.5) + ROUNDER;
    let i = (rounded.to_bits().wrapping_sub(ROUNDER.to_bits()) as i32)
        .max(0)
        .min(n as i32 - 2);
    (i as usize, t - i as f32)
}

/// `1.5·2²³`: adding it to `x ∈ (−2²², 2²²)` rounds `x` to an integer.
const ROUNDER: f32 = 12_582_912.0;

/// Receives a model's bakes and constants by name, for ports of `eval` and
/// `pdf` to array languages (the Python package's Dr.Jit plugin,
/// python/twoscale/drjit/, reads them through `Material.bakes()`): arrays
/// are row-major f32 with their shape, an array whose last axis holds
/// different quantities names them ([`BakeVisitor::columns`]), scalars are
/// f64, options and kinds are their [`crate::validate::Named`] spelling.
/// The names and layouts are the bakes' own and may change with them; not a
/// stable interface, but a port reads names only, never positions.
#[doc(hidden)]
pub trait BakeVisitor {
    /// An array of `shape` (row-major).
    fn array(&mut self, name: &'static str, shape: &[usize], data: &[f32]);
    /// An f64 array of `shape` (row-major).
    fn array_f64(&mut self, name: &'static str, shape: &[usize], data: &[f64]);
    /// An array of cell indices of `shape` (row-major; the samplers' guides).
    fn array_u8(&mut self, name: &'static str, shape: &[usize], data: &[u8]);
    /// A scalar.
    fn scalar(&mut self, name: &'static str, value: f64);
    /// The names of the columns (the last axis) of the array `name`, in
    /// order.
    fn columns(&mut self, name: &'static str, columns: &'static [&'static str]);
    /// A quantity with named values (an option, the base layer's kind): the
    /// value's name ([`crate::validate::Named::name`]).
    fn named(&mut self, name: &'static str, value: &'static str);
}

#[cfg(all(test, feature = "embedded"))]
mod tests;
