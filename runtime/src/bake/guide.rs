//! Guide tables: the cell of a tabulated CDF's quantile in O(1)
//! (docs/design/visible-normals.md, "Cell location").
//!
//! A sampler that inverts a piecewise CDF `F` on nodes `0 … n−1` (`F`
//! non-decreasing, `F_0 = 0`, `F_{n−1}` the total `T`) needs the cell `j`
//! with `F_j ≤ uT < F_{j+1}`. A guide stores, at each edge `e_b` of a fixed
//! partition of `u ∈ [0, 1]`, the cell `G_b` of the quantile `F⁻¹(e_b T)`. A
//! `u` in bin `b` (`e_b ≤ u < e_{b+1}`) has its cell in `[G_b, G_{b+1}]`, so
//!
//! ```text
//! j = G_b + #{k ∈ (G_b, G_{b+1}] : F_k ≤ uT}
//! ```
//!
//! counts independent comparisons (no chain of dependent look-ups as in a
//! binary search). A guide of a family of CDFs ordered in `u`'s quantile
//! (the visible marginal in the incidence, a blend of two rows) brackets the
//! member's cell between its neighbours' entries.
//!
//! The partition is even in [`position`], which spends [`LINEAR`] bins on
//! `u` itself and one per octave of `min(u, 1 − u)` down to `2⁻⁴⁰`: the
//! tables' tails, where many cells hold little mass, get bins of their own.
//! `position` is exactly monotone in f64 (piecewise linear), so a `u` is in
//! the bin its edges say up to the rounding of `uT` against `F`, which at
//! worst puts the draw on a node's other side by that rounding.

/// Octaves of `min(u, 1 − u)` with a bin each (below `2⁻⁴⁰` all in the end bins).
const OCTAVES: f64 = 40.0;
/// Bins spent evenly on `u ∈ [0, 1]`.
const LINEAR: f64 = 32.0;
/// [`position`] at `u = ½`.
const HALF: f64 = OCTAVES - 1.0 + 0.5 * LINEAR;
/// Bins of the partition.
pub(crate) const BINS: usize = 2 * HALF as usize;
/// Edges of the partition (a guide's entries).
pub(crate) const EDGES: usize = BINS + 1;

/// `e + f` for `m = 2^e (1 + f)`: `log₂ m` linear between powers of two
/// (exact there), for normal `m > 0`.
#[inline]
const fn octave_log2(m: f64) -> f64 {
    let bits = m.to_bits();
    let exponent = ((bits >> 52) & 0x7ff) as i64 - 1023;
    let f = f64::from_bits((bits & 0x000f_ffff_ffff_ffff) | 0x3ff0_0000_0000_0000) - 1.0;
    exponent as f64 + f
}

/// The half of the axis for `m = min(u, 1 − u) ∈ [0, ½]`.
#[inline]
const fn half_position(m: f64) -> f64 {
    let octaves = octave_log2(m) + OCTAVES;
    (if octaves > 0.0 { octaves } else { 0.0 }) + LINEAR * m
}

/// The guide axis's position of `u ∈ [0, 1]`, in bins (`0 … BINS`),
/// increasing.
///
/// Mirrored in python/twoscale/drjit/visible.py.
#[inline]
pub(crate) const fn position(u: f64) -> f64 {
    if u < 0.5 {
        half_position(if u > 0.0 { u } else { 0.0 })
    } else {
        2.0 * HALF - half_position(if u < 1.0 { 1.0 - u } else { 0.0 })
    }
}

/// The bin of `u` (`0 … BINS − 1`): `⌊position⌋` by the rounding trick
/// of `bake::cell_at` in f64 (a tie, `u` on an edge, may give the bin
/// below, whose bracket holds that edge's cell too).
///
/// Mirrored in python/twoscale/drjit/visible.py.
#[inline]
pub(crate) fn bin(u: f64) -> usize {
    const ROUNDER: f64 = 6_755_399_441_055_744.0; // 1.5·2⁵²
    let rounded = (position(u) - 0.5) + ROUNDER;
    (rounded.to_bits().wrapping_sub(ROUNDER.to_bits()) as i64).clamp(0, BINS as i64 - 1) as usize
}

/// The partition's edges: `e_b` the least f64 with `position(e_b) ≥ b`
/// (by bisection over the bit patterns, which order positive f64, at
/// compile time), so that a `u` is in bin `b` of [`bin`] exactly when
/// `e_b ≤ u < e_{b+1}`.
pub(crate) const EDGE_VALUES: [f64; EDGES] = edges();

/// [`EDGE_VALUES`].
const fn edges() -> [f64; EDGES] {
    let mut out = [0.0; EDGES];
    let mut b = 1;
    while b < EDGES {
        let (mut lo, mut hi) = (0u64, 1.0f64.to_bits());
        while hi - lo > 1 {
            let mid = lo + (hi - lo) / 2;
            if position(f64::from_bits(mid)) < b as f64 {
                lo = mid;
            } else {
                hi = mid;
            }
        }
        out[b] = f64::from_bits(hi);
        b += 1;
    }
    out
}

/// Hands the axis's constants to `v` (`guide_octaves`, `guide_linear`).
pub(crate) fn visit(v: &mut dyn crate::bake::BakeVisitor) {
    v.scalar("guide_octaves", OCTAVES);
    v.scalar("guide_linear", LINEAR);
}

/// Fills `guide` for the CDF `cum(k)` on `n` nodes (`cum(0) = 0`,
/// non-decreasing, `cum(n − 1)` the total): the last cell `k ≤ n − 2` with
/// `cum(k) ≤ e_b · total` at each edge.
pub(crate) fn build(n: usize, cum: impl Fn(usize) -> f64, guide: &mut [u8]) {
    let total = cum(n - 1);
    let mut k = 0usize;
    for (slot, &e) in guide.iter_mut().zip(&EDGE_VALUES) {
        let target = e * total;
        while k + 2 < n && cum(k + 1) <= target {
            k += 1;
        }
        *slot = k as u8;
    }
}

/// The cell `j ∈ [lo, hi]` with `cum(j) ≤ target` and `cum(j + 1) > target`
/// (the last `j ≤ hi` with `cum(j) ≤ target`, given `cum(lo) ≤ target`),
/// by counting.
///
/// Mirrored in python/twoscale/drjit/visible.py.
#[inline]
pub(crate) fn scan(lo: usize, hi: usize, target: f64, cum: impl Fn(usize) -> f64) -> usize {
    let mut j = lo;
    for k in lo + 1..=hi {
        j += usize::from(cum(k) <= target);
    }
    j
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn position_is_increasing_and_spans_the_bins() {
        assert_eq!(position(0.0), 0.0);
        assert_eq!(position(1.0), BINS as f64);
        assert_eq!(position(0.5), HALF);
        let mut last = -1.0;
        for k in 0..=200_000 {
            let u = k as f64 / 200_000.0;
            let p = position(u);
            assert!(p >= last, "{u}");
            last = p;
        }
        for b in 1..BINS {
            let (edge, next) = (EDGE_VALUES[b], EDGE_VALUES[b + 1]);
            let below = f64::from_bits(edge.to_bits() - 1);
            assert!(
                position(below) < b as f64 && position(edge) >= b as f64,
                "{b}"
            );
            // ⌊position⌋ by rounding: exact but within rounding of an edge.
            assert_eq!(bin(0.5 * (edge + next)), b, "{b}");
        }
    }
}
