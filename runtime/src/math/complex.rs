//! The complex index of refraction, as renderers store it.

/// A complex index of refraction `η = n + i k` relative to the outside medium,
/// in f32 as renderers store it: `re = n`, `im = k` (k ≥ 0 absorbs; the sign
/// does not matter to the formulas that read it, [`crate::model::fresnel`]).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Complex {
    /// Real part, n.
    pub re: f32,
    /// Imaginary part, k (extinction coefficient).
    pub im: f32,
}

impl Complex {
    /// `n + i k`.
    pub const fn new(re: f32, im: f32) -> Complex {
        Complex { re, im }
    }

    /// A real index `n` (a dielectric).
    pub const fn real(re: f32) -> Complex {
        Complex { re, im: 0.0 }
    }
}
