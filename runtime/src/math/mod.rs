//! Elementary functions: `std`'s when the `std` feature is on, `libm`'s otherwise.
//!
//! Everything in the crate calls these wrappers instead of the inherent float
//! methods, so the `no_std` build and the `std` build run the same code.

pub mod complex;
pub mod gamma;

pub use complex::Complex;

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
    /// arccos x (f64).
    acos(x) -> f64 = acos / acos;
    /// The angle of the point (x, y), in (−π, π] (f64).
    atan2(y, x) -> f64 = atan2 / atan2;
    /// arctan x (f32).
    atanf(x) -> f32 = atan / atanf;
}

/// ln(1 + x) (f32) from `ln`: `ln(u) x/(u − 1)` with `u = 1 + x` rounded,
/// which cancels the rounding of `u` (Goldberg 1991, Theorem 4; within a few
/// ulp, tested). glibc's `log1pf` costs about twice its `logf`.
#[inline(always)]
pub fn ln_1pf_via_ln(x: f32) -> f32 {
    let u = 1.0 + x;
    if u == 1.0 || !(u < f32::INFINITY) {
        // x below half an ulp of 1 (ln(1 + x) = x in f32), ∞ or NaN.
        if u == 1.0 { x } else { lnf(u) }
    } else {
        lnf(u) * (x / (u - 1.0))
    }
}

/// A float type with the elementary functions above, so that one formula
/// serves in f64 (tables, reference paths) and in f32 (per-material bakes,
/// where f32's rounding is within the error budget).
pub trait Real:
    Copy
    + PartialOrd
    + core::ops::Add<Output = Self>
    + core::ops::Sub<Output = Self>
    + core::ops::Mul<Output = Self>
    + core::ops::Div<Output = Self>
    + core::ops::Neg<Output = Self>
{
    /// `x` rounded to this type.
    fn of(x: f64) -> Self;
    /// This value as f64.
    fn wide(self) -> f64;
    /// √x.
    fn sqrt(self) -> Self;
    /// ln x.
    fn ln(self) -> Self;
    /// ln(1 + x).
    fn ln_1p(self) -> Self;
    /// e^x.
    fn exp(self) -> Self;
    /// e^x − 1.
    fn exp_m1(self) -> Self;
    /// arctan x.
    fn atan(self) -> Self;
    /// sin x.
    fn sin(self) -> Self;
}

macro_rules! real {
    ($ty:ty: $sqrt:ident $ln:ident $ln_1p:ident $exp:ident $exp_m1:ident $atan:ident $sin:ident) => {
        impl Real for $ty {
            #[inline(always)]
            fn of(x: f64) -> Self {
                x as $ty
            }
            #[inline(always)]
            fn wide(self) -> f64 {
                f64::from(self)
            }
            #[inline(always)]
            fn sqrt(self) -> Self {
                $sqrt(self)
            }
            #[inline(always)]
            fn ln(self) -> Self {
                $ln(self)
            }
            #[inline(always)]
            fn ln_1p(self) -> Self {
                $ln_1p(self)
            }
            #[inline(always)]
            fn exp(self) -> Self {
                $exp(self)
            }
            #[inline(always)]
            fn exp_m1(self) -> Self {
                $exp_m1(self)
            }
            #[inline(always)]
            fn atan(self) -> Self {
                $atan(self)
            }
            #[inline(always)]
            fn sin(self) -> Self {
                $sin(self)
            }
        }
    };
}

real!(f64: sqrt ln ln_1p exp exp_m1 atan sin);
real!(f32: sqrtf lnf ln_1pf_via_ln expf exp_m1f atanf sinf);

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

/// 4-point Gauss–Legendre nodes and weights on [−1, 1], the positive half
/// (the rule is symmetric: each `(x, w)` stands for `±x`).
pub(crate) const GAUSS_LEGENDRE_4: [(f64, f64); 2] = [
    (0.339_981_043_584_856_3, 0.652_145_154_862_546_1),
    (0.861_136_311_594_052_6, 0.347_854_845_137_453_9),
];

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
///
/// Mirrored in python/twoscale/drjit/math.py.
#[inline]
pub fn log2_axis(x: f32) -> f32 {
    let bits = x.to_bits();
    let exponent = ((bits >> 23) & 0xff) as i32 - 127;
    let m = f32::from_bits((bits & 0x007f_ffff) | 0x3f80_0000) - 1.0;
    exponent as f32 + m * (AXIS_D0 + m * (AXIS_C2 + m * AXIS_C3))
}

/// The inverse of [`log2_axis`] (f64; for building a table's nodes):
/// Newton's method on the cubic, which is increasing on [0, 1], from a
/// least-squares cubic fit of its inverse (within 1.3e-3). With
/// `|p''/(2p')| ≤ 0.85` on [0, 1], three steps bring that to below 1e-23,
/// beyond f64's resolution.
pub fn exp2_axis(y: f64) -> f64 {
    // ⌊y⌋ without a library call (|y| ≥ 2^52 is an integer; NaN stays NaN).
    let exponent = if abs(y) < 4.0e15 {
        let t = (y as i64) as f64;
        if t > y { t - 1.0 } else { t }
    } else {
        y
    };
    let f = y - exponent;
    let (d0, c2, c3) = (f64::from(AXIS_D0), f64::from(AXIS_C2), f64::from(AXIS_C3));
    let mut m = (f * (0.691_137_3 + f * (0.200_992_36 + f * 0.109_167_52)))
        .max(0.0)
        .min(1.0);
    for _ in 0..3 {
        let value = m * (d0 + m * (c2 + m * c3)) - f;
        let slope = d0 + m * (2.0 * c2 + 3.0 * m * c3);
        m = (m - value / slope).max(0.0).min(1.0);
    }
    // 2^exponent exactly, from its bits (no library call).
    let scale = if (-1022.0..=1023.0).contains(&exponent) {
        f64::from_bits(((exponent as i64 + 1023) as u64) << 52)
    } else if exponent > 1023.0 {
        f64::INFINITY
    } else if exponent >= -1074.0 {
        // Subnormal.
        f64::from_bits(1u64 << ((exponent as i64 + 1074) as u32))
    } else if exponent < -1074.0 {
        0.0
    } else {
        f64::NAN
    };
    scale * (1.0 + m)
}

/// `p(m) = d₀ m + c₂ m² + c₃ m³` of [`log2_axis`]: `d₀ = 1/ln 2`,
/// `c₂ = 3 − 2d₀ − d₁`, `c₃ = d₀ + d₁ − 2` with `d₁ = d₀/2` (cubic Hermite).
const AXIS_D0: f32 = core::f32::consts::LOG2_E;
const AXIS_C2: f32 = 3.0 - 2.5 * core::f32::consts::LOG2_E;
const AXIS_C3: f32 = 1.5 * core::f32::consts::LOG2_E - 2.0;

/// `acos x` for `x ∈ [−1, 1]` (f64), inlined: `√(1 − |x|) P(|x|)` with the
/// degree-7 polynomial of Abramowitz & Stegun 4.4.46, and `π − acos|x|`
/// for `x < 0`. Absolute error ≤ 2.2e-8 (A&S give 2e-8; their 10-digit
/// coefficients give 2.18e-8 at `x = 0`; tested against `acos`).
///
/// Mirrored in python/twoscale/drjit/math.py.
#[inline]
pub fn acos_approx(x: f64) -> f64 {
    let a = abs(x).min(1.0);
    let p = 1.570_796_305_0
        + a * (-0.214_598_801_6
            + a * (0.088_978_987_4
                + a * (-0.050_174_304_6
                    + a * (0.030_891_881_0
                        + a * (-0.017_088_125_6 + a * (0.006_670_090_1 - 0.001_262_491_1 * a))))));
    let r = sqrt(1.0 - a) * p;
    if x < 0.0 {
        core::f64::consts::PI - r
    } else {
        r
    }
}

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

/// `e^x` (f32), branch-free and inlined, so that a loop over lanes of it
/// vectorises: `x = n ln 2 + r`, `n` the integer nearest `x log₂ e`, `r`
/// with `ln 2` split in two (Cody–Waite: `n ln2_hi` exact), `|r| ≤ 0.35`,
/// `e^r` by its Taylor series to `r⁷` (truncation below 1e-8), `2ⁿ` from
/// the exponent bits; relative error below 4e-7 (tested against `exp`).
/// `n` is clamped to `[−126, 127]` (`x` to about `[−87.3, 88.0]`: 2⁻¹²⁶,
/// the smallest normal f32, for every `x` below; NaN gives 2⁻¹²⁶).
#[inline(always)]
pub fn exp_lanef(x: f32) -> f32 {
    // 1.5·2²³: adding it rounds |y| < 2²² to the nearest integer.
    const ROUND: f32 = 12_582_912.0;
    // ln 2 = LN2_HI + LN2_LO, LN2_HI with 16 significant bits (n·LN2_HI exact).
    const LN2_HI: f32 = 0.693_145_75;
    const LN2_LO: f32 = 1.428_606_8e-6;
    let x = x
        .max(-126.0 * core::f32::consts::LN_2)
        .min(127.0 * core::f32::consts::LN_2);
    let shifted = x * core::f32::consts::LOG2_E + ROUND;
    let n = shifted - ROUND;
    // n in the low bits (no saturating float-to-int conversion).
    let n_bits = shifted.to_bits().wrapping_sub(ROUND.to_bits());
    let r = (x - n * LN2_HI) - n * LN2_LO;
    let p = 1.0
        + r * (1.0
            + r * (0.5
                + r * (1.0 / 6.0
                    + r * (1.0 / 24.0
                        + r * (1.0 / 120.0 + r * (1.0 / 720.0 + r * (1.0 / 5040.0)))))));
    // |x log₂ e| ≤ 127 rounds to |n| ≤ 127: 2ⁿ is normal.
    p * f32::from_bits(n_bits.wrapping_add(127) << 23)
}

/// `2 ∫₀¹ E(μ) μ dμ` of `n ≥ 2` values `e(k)` at `μ_k = x_k²`,
/// `x_k = k/(n − 1)`, interpolated linearly in `x` (as the per-material bake
/// holds them): with `μ = x²` the integral is `4 ∫₀¹ E(x) x³ dx`, exact per
/// cell for the linear interpolant.
pub fn cosine_weighted_mean(n: usize, e: impl Fn(usize) -> f32) -> f64 {
    if n < 2 {
        return f64::from(e(0));
    }
    let h = 1.0 / (n - 1) as f64;
    let mut total = 0.0;
    let mut ea = f64::from(e(0));
    for k in 0..n - 1 {
        let eb = f64::from(e(k + 1));
        let (a, b) = (k as f64 * h, (k + 1) as f64 * h);
        // ∫_a^b (ea (b − x) + eb (x − a))/h · 4x³ dx
        let (a4, b4) = (a * a * a * a, b * b * b * b);
        let (a5, b5) = (a4 * a, b4 * b);
        let int_x3 = b4 - a4; // ∫ 4x³
        let int_x4 = 0.8 * (b5 - a5); // ∫ 4x⁴
        total += (ea * (b * int_x3 - int_x4) + eb * (int_x4 - a * int_x3)) / h;
        ea = eb;
    }
    total
}

#[cfg(test)]
mod tests {
    use super::*;

    /// `pow_positive` against libm's `pow` over `x ∈ [10⁻¹², 10¹²]`
    /// (log-uniform, and just above 1) and `y ∈ [−60, 60]`; `exp2` and
    /// `exp_inline` over their ranges.
    #[test]
    fn pow_positive_matches_pow() {
        let mut rng = crate::test_rng::Lcg(1);
        let mut next = || rng.next();
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

    /// `exp_lanef` against f64 `exp` over every f32 input it does not clamp
    /// (a step of 1e-4 over [−87.3, 88]), and at its clamps.
    #[test]
    fn exp_lanef_matches_exp() {
        let mut worst = 0.0f64;
        for k in -873_000..=880_000 {
            let x = k as f32 * 1e-4;
            let exact = libm::exp(f64::from(x));
            worst = worst.max((f64::from(exp_lanef(x)) / exact - 1.0).abs());
        }
        std::eprintln!("exp_lanef: worst {worst:e}");
        assert!(worst < 4e-7, "{worst:e}");
        assert_eq!(exp_lanef(0.0), 1.0);
        let tiny = |y: f32| (y / f32::MIN_POSITIVE - 1.0).abs() < 1e-5;
        assert!(tiny(exp_lanef(-1e4)) && tiny(exp_lanef(f32::NAN)));
        assert!(exp_lanef(1e4).is_finite() && exp_lanef(1e4) > 1e38);
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

    /// Error of an f32 result in ulp of the exact value.
    fn ulps(got: f32, exact: f64) -> f64 {
        let ulp = f64::from(f32::EPSILON) * exact.abs().max(f64::from(f32::MIN_POSITIVE));
        // The ulp of |exact| ∈ [2^k, 2^(k+1)) is 2^(k−23): halve ε |exact| at most.
        let ulp = 2f64.powi(ulp.log2().floor() as i32);
        (f64::from(got) - exact).abs() / ulp
    }

    /// `acos_approx` against `acos` on 200 001 points of [−1, 1].
    #[test]
    fn acos_approx_is_within_its_bound() {
        let mut worst = (0.0f64, 0.0f64);
        for k in 0..=200_000 {
            let x = -1.0 + 2.0 * k as f64 / 200_000.0;
            let e = (acos_approx(x) - x.acos()).abs();
            if e > worst.0 {
                worst = (e, x);
            }
        }
        std::eprintln!("acos_approx: worst {:.2e} at {}", worst.0, worst.1);
        assert!(worst.0 <= 2.2e-8, "{worst:?}");
        assert_eq!(acos_approx(1.0), 0.0);
    }

    /// `ln_1pf_via_ln` against f64 over f32's range.
    #[test]
    fn ln_1pf_via_ln_is_within_a_few_ulp() {
        let mut worst_1p = (0.0f64, 0.0f32);
        for k in 0..2_000_000u32 {
            // Log-uniform over [1e-37, 1e38], and a dense band around 1.
            let x = if k % 2 == 0 {
                (f64::from(k) / 2e6 * 75.0 - 37.0).exp2().min(1e38) as f32
            } else {
                let width = if k % 4 == 1 { 1e-2 } else { 1e-6 };
                (1.0 + (f64::from(k) / 2e6 - 0.5) * width) as f32
            };
            let y = x - 1.0;
            if y > -1.0 {
                let e = ulps(ln_1pf_via_ln(y), f64::from(y).ln_1p());
                if e > worst_1p.0 {
                    worst_1p = (e, y);
                }
            }
        }
        std::eprintln!("ln_1pf_via_ln {worst_1p:?}");
        assert!(worst_1p.0 <= 4.0, "ln_1pf_via_ln: {worst_1p:?}");
        assert_eq!(ln_1pf_via_ln(0.0), 0.0);
        assert!(ln_1pf_via_ln(-1.0) == f32::NEG_INFINITY && ln_1pf_via_ln(f32::NAN).is_nan());
    }

    /// `exp2_axis` inverts the f64 form of `log2_axis`'s map to f64
    /// precision (the nodes of the per-material bakes), for negative `y` too.
    #[test]
    fn exp2_axis_inverts_to_f64_precision() {
        let (d0, c2, c3) = (f64::from(AXIS_D0), f64::from(AXIS_C2), f64::from(AXIS_C3));
        let mut worst = 0.0f64;
        for e in [-30.0, -1.0, 0.0, 1.0, 7.0, 40.0] {
            for k in 0..=100_000 {
                let m = f64::from(k) / 100_000.0;
                let y = e + m * (d0 + m * (c2 + m * c3));
                let x = 2f64.powf(e) * (1.0 + m);
                worst = worst.max((exp2_axis(y) / x - 1.0).abs());
            }
        }
        // The rounding of y itself (an ulp of 41 is 7e-15) limits: the
        // eight Newton steps from m = f before gave the same 2.8e-15.
        assert!(worst < 1e-14, "{worst:e}");
        // Powers of two, subnormal, overflowing and NaN exponents.
        for e in -1080..1030 {
            assert_eq!(exp2_axis(f64::from(e)), 2f64.powf(f64::from(e)), "{e}");
        }
        assert!(exp2_axis(f64::NAN).is_nan());
    }

    /// The mean of a constant is the constant; of `E = μ` it is 2/3 to the
    /// linear interpolation's error in `x`.
    #[test]
    fn cosine_weighted_mean_integrates() {
        let n = 257;
        assert!((cosine_weighted_mean(n, |_| 1.0) - 1.0).abs() < 1e-12);
        let mu = |k: usize| {
            let x = k as f32 / (n - 1) as f32;
            x * x
        };
        assert!((cosine_weighted_mean(n, mu) - 2.0 / 3.0).abs() < 1e-5);
    }
}
