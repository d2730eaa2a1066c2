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
    /// e^x − 1 (f32), accurate for small |x|.
    exp_m1f(x) -> f32 = exp_m1 / expm1f;
    /// ln(1 + x) (f32), accurate for small |x|.
    ln_1pf(x) -> f32 = ln_1p / log1pf;
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

/// A cheap, smooth and increasing stand-in for `log₂ x`, for table axes
/// that only need some such map (the per-material bakes): `e + p(m)` for
/// `x = 2^e (1 + m)`, with `p` the cubic through `(0, 0)` and `(1, 1)` whose
/// slopes there are `log₂`'s (`1/ln 2` and `1/(2 ln 2)`). So it is exact at
/// powers of two, has a continuous derivative, and is within 0.011 of `log₂ x`.
/// Defined for normal `x > 0`; every finite input gives a finite output.
#[inline]
pub fn log2_axis(x: f32) -> f32 {
    let bits = x.to_bits();
    let exponent = ((bits >> 23) & 0xff) as i32 - 127;
    let m = f32::from_bits((bits & 0x007f_ffff) | 0x3f80_0000) - 1.0;
    exponent as f32 + m * (AXIS_D0 + m * (AXIS_C2 + m * AXIS_C3))
}

/// The inverse of [`log2_axis`] (f64; for building a table's nodes):
/// Newton's method on the cubic, which is increasing on [0, 1].
pub fn exp2_axis(y: f64) -> f64 {
    let exponent = floor(y);
    let f = y - exponent;
    let (d0, c2, c3) = (f64::from(AXIS_D0), f64::from(AXIS_C2), f64::from(AXIS_C3));
    let mut m = f;
    for _ in 0..8 {
        let value = m * (d0 + m * (c2 + m * c3)) - f;
        let slope = d0 + m * (2.0 * c2 + 3.0 * m * c3);
        m = (m - value / slope).max(0.0).min(1.0);
    }
    powf(2.0, exponent) * (1.0 + m)
}

/// `p(m) = d₀ m + c₂ m² + c₃ m³` of [`log2_axis`]: `d₀ = 1/ln 2`,
/// `c₂ = 3 − 2d₀ − d₁`, `c₃ = d₀ + d₁ − 2` with `d₁ = d₀/2` (cubic Hermite).
const AXIS_D0: f32 = core::f32::consts::LOG2_E;
const AXIS_C2: f32 = 3.0 - 2.5 * core::f32::consts::LOG2_E;
const AXIS_C3: f32 = 1.5 * core::f32::consts::LOG2_E - 2.0;

/// `x^y` for normal `x > 0` (f64): `2^(y log₂ x)` with [`log2_positive`] and
/// [`exp2`], inlined (no libm call); relative error below
/// `2e-15 (1 + |y log₂ x|)` (tested against `pow`). Finite for every input.
#[inline]
pub fn pow_positive(x: f64, y: f64) -> f64 {
    exp2(y * log2_positive(x))
}

/// `e^x` (f64) as [`exp2`]`(x log₂ e)`, inlined (no libm call); relative
/// error below `2e-15 (1 + |x|)`; clamped to `[2⁻¹⁰²², 2¹⁰²³]`.
#[inline]
pub fn exp_inline(x: f64) -> f64 {
    exp2(x * core::f64::consts::LOG2_E)
}

/// `log₂ x` for normal `x > 0` (f64; for 0, subnormals, NaN or ∞ the result
/// is finite but meaningless, −1023 for 0): `x = 2^e m` with
/// `m ∈ [√½, √2)`, `ln m = 2 atanh s`, `s = (m − 1)/(m + 1)`, `|s| ≤ 0.172`,
/// by its series to `s¹⁹` (truncation below 1e-16 of `ln m`).
#[inline]
pub fn log2_positive(x: f64) -> f64 {
    let bits = x.to_bits();
    let exponent = ((bits >> 52) & 0x7ff) as i32 - 1023;
    let m = f64::from_bits((bits & 0x000f_ffff_ffff_ffff) | 0x3ff0_0000_0000_0000);
    let (m, exponent) = if m > core::f64::consts::SQRT_2 {
        (0.5 * m, exponent + 1)
    } else {
        (m, exponent)
    };
    let s = (m - 1.0) / (m + 1.0);
    let s2 = s * s;
    let series = s2
        * (1.0 / 3.0
            + s2 * (1.0 / 5.0
                + s2 * (1.0 / 7.0
                    + s2 * (1.0 / 9.0
                        + s2 * (1.0 / 11.0
                            + s2 * (1.0 / 13.0
                                + s2 * (1.0 / 15.0 + s2 * (1.0 / 17.0 + s2 / 19.0))))))));
    f64::from(exponent) + 2.0 * core::f64::consts::LOG2_E * (s + s * series)
}

/// `(ln 2)ⁿ / n!` for n = 0..5: the Taylor coefficients of `2^r`.
const EXP2_TAYLOR: [f64; 6] = {
    let mut c = [1.0f64; 6];
    let mut n = 1;
    while n < 6 {
        c[n] = c[n - 1] * core::f64::consts::LN_2 / n as f64;
        n += 1;
    }
    c
};

/// `2^(j/64)` for j = 0..63, by the Taylor series of `e^x` at compile time.
const EXP2_STEPS: [f64; 64] = {
    let mut table = [1.0f64; 64];
    let mut j = 1;
    while j < 64 {
        let x = j as f64 / 64.0 * core::f64::consts::LN_2;
        let (mut term, mut sum, mut n) = (1.0f64, 1.0f64, 1);
        while n < 30 {
            term = term * x / n as f64;
            sum += term;
            n += 1;
        }
        table[j] = sum;
        j += 1;
    }
    table
};

/// `2^y` (f64), `y` clamped to `[−1022, 1023]` (NaN → 2⁻¹⁰²²): `64 y = n + 64 r`
/// with `n` the nearest integer, `|r| ≤ 1/128`, `2^y = 2^⌊n/64⌋ 2^((n mod 64)/64) 2^r`,
/// the middle factor from a table, `2^r` by its Taylor series to `r⁵`
/// (truncation below 1e-16).
#[inline]
pub fn exp2(y: f64) -> f64 {
    // 1.5·2⁵²: adding it rounds |x| < 2⁵¹ to an integer, held in the low bits.
    const ROUND: f64 = 6_755_399_441_055_744.0;
    let y = y.max(-1022.0).min(1023.0);
    let shifted = y * 64.0 + ROUND;
    let n = shifted.to_bits().wrapping_sub(ROUND.to_bits()) as i64;
    let r = y - (shifted - ROUND) * (1.0 / 64.0);
    let mut p = EXP2_TAYLOR[5];
    for c in EXP2_TAYLOR[..5].iter().rev() {
        p = c + r * p;
    }
    // n ≥ −65 408: ⌊n/64⌋ + 1023 ≥ 1, a normal power of two.
    let scale = f64::from_bits((((n >> 6) + 1023) as u64) << 52);
    EXP2_STEPS[(n & 63) as usize] * p * scale
}

#[cfg(test)]
mod tests {
    use super::*;

    /// `pow_positive` against libm's `pow` over `x ∈ [10⁻¹², 10¹²]`
    /// (log-uniform, and just above 1) and `y ∈ [−60, 60]`; `exp2` and
    /// `exp_inline` over their ranges.
    #[test]
    fn pow_positive_matches_pow() {
        let mut state = 1u64;
        let mut next = || {
            state = state
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            (state >> 11) as f64 / (1u64 << 53) as f64
        };
        let mut worst = 0.0f64;
        for k in 0..200_000 {
            let x = if k % 4 == 0 {
                1.0 + 1e-6 * next()
            } else {
                libm::exp((next() - 0.5) * 55.3)
            };
            let y = (next() - 0.5) * 120.0;
            let exact = libm::pow(x, y);
            if !(exact > 1e-300 && exact < 1e300) {
                continue;
            }
            let e = (pow_positive(x, y) / exact - 1.0).abs() / (1.0 + (y * libm::log2(x)).abs());
            worst = worst.max(e);
        }
        for _ in 0..200_000 {
            let x = (next() - 0.5) * 1400.0;
            let e = (exp_inline(x) / libm::exp(x) - 1.0).abs() / (1.0 + x.abs());
            worst = worst.max(e);
        }
        for k in -1022 * 8..=1023 * 8 {
            let y = f64::from(k) / 8.0;
            worst = worst.max((exp2(y) / libm::exp2(y) - 1.0).abs());
        }
        std::eprintln!("pow_positive, exp_inline, exp2: worst {worst:e}");
        assert!(worst < 2e-15, "{worst:e}");
        assert_eq!(pow_positive(1.0, 5.0), 1.0);
        assert_eq!(exp_inline(0.0), 1.0);
        for x in [f64::NAN, f64::INFINITY, -1.0, 0.0, 1e-310] {
            assert!(pow_positive(x, 2.0).is_finite(), "{x}");
            assert!(pow_positive(x, -2.0).is_finite(), "{x}");
        }
        assert!(exp2(f64::NAN).is_finite() && exp2(1e9).is_finite());
    }

    /// `log2_axis` is increasing, within 0.011 of log₂, exact at powers of
    /// two, and `exp2_axis` inverts it.
    #[test]
    fn log2_axis_is_a_smooth_increasing_log() {
        let mut previous = f32::MIN;
        let mut worst = 0.0f64;
        for k in 0..=200_000 {
            let x = 1.0 + k as f32 * 1e-3;
            let y = log2_axis(x);
            assert!(y > previous, "not increasing at {x}");
            previous = y;
            worst = worst.max((f64::from(y) - f64::from(x).log2()).abs());
            let back = exp2_axis(f64::from(y));
            assert!(
                (back / f64::from(x) - 1.0).abs() < 1e-6,
                "{x} → {y} → {back}"
            );
        }
        assert!(worst < 0.011, "{worst}");
        for e in -20..20 {
            assert_eq!(log2_axis(2f32.powi(e)), e as f32);
        }
        for x in [
            f32::MIN_POSITIVE,
            f32::MAX,
            0.0,
            -1.0,
            f32::INFINITY,
            f32::NAN,
        ] {
            assert!(log2_axis(x).is_finite() || !x.is_finite(), "{x}");
        }
    }
}
