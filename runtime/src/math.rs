//! Elementary functions: `std`'s when the `std` feature is on, `libm`'s otherwise.
//!
//! Everything in the crate calls these wrappers instead of the inherent float
//! methods, so the `no_std` build and the `std` build run the same code.

macro_rules! forward {
    ($($(#[$doc:meta])* $name:ident($($arg:ident),*) -> $ty:ty = $std:ident / $libm:ident;)*) => {
        $(
            $(#[$doc])*
            #[inline(always)]
            pub fn $name($($arg: $ty),*) -> $ty {
                #[cfg(feature = "std")]
                {
                    <$ty>::$std($($arg),*)
                }
                #[cfg(not(feature = "std"))]
                {
                    libm::$libm($($arg),*)
                }
            }
        )*
    };
}

forward! {
    /// e^x (f64).
    exp(x) -> f64 = exp / exp;
    /// ln x (f64).
    ln(x) -> f64 = ln / log;
    /// √x (f64).
    sqrt(x) -> f64 = sqrt / sqrt;
    /// x^y (f64).
    powf(x, y) -> f64 = powf / pow;
    /// ⌊x⌋ (f64).
    floor(x) -> f64 = floor / floor;
    /// |x| (f64).
    abs(x) -> f64 = abs / fabs;
    /// ∛x (f64).
    cbrt(x) -> f64 = cbrt / cbrt;
    /// √(x² + y²) (f64), without overflow or underflow in the squares.
    hypot(x, y) -> f64 = hypot / hypot;
    /// ln(1 + x) (f64), accurate for small |x|.
    ln_1p(x) -> f64 = ln_1p / log1p;
    /// e^x − 1 (f64), accurate for small |x|.
    exp_m1(x) -> f64 = exp_m1 / expm1;
    /// e^x (f32).
    expf(x) -> f32 = exp / expf;
    /// ln x (f32).
    lnf(x) -> f32 = ln / logf;
    /// √x (f32).
    sqrtf(x) -> f32 = sqrt / sqrtf;
    /// x^y (f32).
    powff(x, y) -> f32 = powf / powf;
    /// ⌊x⌋ (f32).
    floorf(x) -> f32 = floor / floorf;
    /// sin x (f32).
    sinf(x) -> f32 = sin / sinf;
    /// cos x (f32).
    cosf(x) -> f32 = cos / cosf;
    /// sin x (f64).
    sin(x) -> f64 = sin / sin;
    /// cos x (f64).
    cos(x) -> f64 = cos / cos;
    /// arctan x (f64).
    atan(x) -> f64 = atan / atan;
    /// arccos x (f64), NaN outside [−1, 1] (callers clamp).
    acos(x) -> f64 = acos / acos;
}

/// ln Γ(x) for x > 0 (f64, libm's `lgamma` in both builds: `std` has no lgamma).
#[inline]
pub fn ln_gamma(x: f64) -> f64 {
    libm::lgamma(x)
}

/// erfc x = 1 − erf x (f64, libm's in both builds: `std` has no stable erfc).
#[inline]
pub fn erfc(x: f64) -> f64 {
    libm::erfc(x)
}

/// The largest f32 below one: uniforms for samplers are clamped to
/// `[0, BELOW_ONE]`.
pub const BELOW_ONE: f32 = 1.0 - f32::EPSILON / 2.0;

/// A direction normalised in f64, or `None` when it is not finite, zero, or
/// at/below the horizon (`z ≤ 0`).
#[inline]
pub fn upper_unit(v: [f32; 3]) -> Option<[f64; 3]> {
    let [x, y, z] = v.map(f64::from);
    let len = sqrt(x * x + y * y + z * z);
    if !(len > 0.0 && len < f64::INFINITY) {
        return None;
    }
    let w = [x / len, y / len, z / len];
    (w[2] > 0.0).then_some(w)
}

/// A wavelength (µm) as the models use it: NaN or ≤ 0 → 0.526 µm (green),
/// otherwise clamped to [0.01, 100] µm.
#[inline]
pub fn sanitised_wavelength(lambda: f32) -> f64 {
    if lambda > 0.0 {
        f64::from(lambda).max(0.01).min(100.0)
    } else {
        0.526
    }
}
