//! The unit tests' deterministic generator (not part of the crate's API).

/// A 64-bit linear congruential generator (Knuth's MMIX constants) of
/// uniforms in [0, 1): small, deterministic, the same sequence everywhere.
pub(crate) struct Lcg(pub u64);

impl Lcg {
    /// The next uniform in [0, 1), from the state's top 53 bits.
    pub(crate) fn next(&mut self) -> f64 {
        self.0 = self
            .0
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        (self.0 >> 11) as f64 / (1u64 << 53) as f64
    }
}
