//! [`MaskingBake`]: Smith G1 at the material's (β, p) over the slope.

use super::cell;
use crate::bake::BakeVisitor;
use crate::tables::smith_g1::SmithShape;
use zerocopy::FromZeros;
/// Nodes of [`MaskingBake`].
const MASKING_NODES: usize = 1025;

/// Smith G1 at the material's (β, p) (module documentation).
#[derive(Clone, Debug, FromZeros)]
pub(crate) struct MaskingBake {
    beta: f32,
    g1: [f32; MASKING_NODES],
}

impl MaskingBake {
    /// Tabulates `shape` (T1 at p) for slopes `a = β tan θ` in place.
    pub fn init(&mut self, beta: f32, shape: &SmithShape<'_>) {
        self.beta = beta;
        for (k, value) in self.g1.iter_mut().enumerate() {
            let y = k as f64 / (MASKING_NODES - 1) as f64;
            *value = if k + 1 == MASKING_NODES {
                0.0
            } else {
                shape.g1((y / (1.0 - y)) as f32)
            };
        }
    }

    /// The bake of [`MaskingBake::init`] in new storage.
    #[cfg(test)]
    pub fn new(beta: f32, shape: &SmithShape<'_>) -> Self {
        let mut bake = Self::new_zeroed();
        bake.init(beta, shape);
        bake
    }

    /// Hands β and G1 to `v` (`masking_beta`; `masking_g1`, nodes even in
    /// `y = a/(1 + a)`).
    pub fn visit(&self, v: &mut dyn BakeVisitor) {
        v.scalar("masking_beta", f64::from(self.beta));
        v.array("masking_g1", &[MASKING_NODES], &self.g1);
    }

    /// G1 of a direction with `z = cos θ` and tangential length `r = sin θ`
    /// (both ≥ 0; 0 at or below the horizon).
    ///
    /// Mirrored in python/twoscale/drjit/lookups.py.
    #[inline]
    pub fn g1(&self, r: f32, z: f32) -> f32 {
        if !(z > 0.0) {
            return 0.0;
        }
        // y = a/(1 + a) with a = β r / z, without forming a (z may be tiny).
        let a_num = self.beta * r;
        let y = a_num / (a_num + z);
        let (i, t) = cell(y, MASKING_NODES);
        self.g1[i] + t * (self.g1[i + 1] - self.g1[i])
    }
}
