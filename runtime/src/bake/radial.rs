//! [`RadialNormBake`]: `1/M(sin θi)` of the diffraction sampler's radial law.

use super::cell;
use crate::bake::BakeVisitor;
use crate::math;
use zerocopy::FromZeros;
/// `1/M(sin θi)` of the diffraction sampler's radial law at one wavelength,
/// `M = 1 − (1 + B²(1 + sin θi)²)^(−(c−1)/2)` (HP17 52), on [`RADIAL_NODES`]
/// nodes even in `sin θi` (where `M` is analytic), linear between; 0 where
/// `M` is not positive (no mass to sample). `sample` and `pdf` read the same
/// values.
#[derive(Clone, Debug, FromZeros)]
pub(crate) struct RadialNormBake {
    inv_m: [f32; RADIAL_NODES],
}

/// Nodes of [`RadialNormBake`].
const RADIAL_NODES: usize = 513;

impl RadialNormBake {
    /// Tabulates `1/M` for `B = b/λ` and the spectrum's `c` in place.
    pub fn init(&mut self, big_b: f64, c: f64) {
        for (k, slot) in self.inv_m.iter_mut().enumerate() {
            let sin_i = k as f64 / (RADIAL_NODES - 1) as f64;
            let reach = big_b * (1.0 + sin_i);
            // −expm1(−(c−1)/2 · ln(1 + reach²)): no cancellation for small reach.
            let m = -math::exp_m1(-0.5 * (c - 1.0) * math::ln_1p(reach * reach));
            let value = (1.0 / m) as f32;
            *slot = if m > 0.0 && value.is_finite() {
                value
            } else {
                0.0
            };
        }
    }

    /// The bake of [`RadialNormBake::init`] in new storage.
    #[cfg(test)]
    pub fn new(big_b: f64, c: f64) -> Self {
        let mut bake = Self::new_zeroed();
        bake.init(big_b, c);
        bake
    }

    /// The bake of a spectrum without diffraction (σs = 0 or B = 0): `1/M`
    /// is 0 everywhere, nothing is sampled from it, and nothing is computed.
    pub fn clear(&mut self) {
        self.inv_m = [0.0f32; RADIAL_NODES];
    }

    /// Hands `1/M` to `v` (`radial_inv_m`, nodes even in `sin θi`).
    pub fn visit(&self, v: &mut dyn BakeVisitor) {
        v.array("radial_inv_m", &[RADIAL_NODES], &self.inv_m);
    }

    /// `1/M` at `sin θi` (clamped to [0, 1]).
    #[inline]
    pub fn inv_m(&self, sin_i: f64) -> f64 {
        let (i, t) = cell(sin_i as f32, RADIAL_NODES);
        let (a, b) = (self.inv_m[i], self.inv_m[i + 1]);
        f64::from(a + t * (b - a))
    }
}
