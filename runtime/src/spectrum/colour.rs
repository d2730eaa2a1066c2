//! Colour: a spectral reflectance turned into linear sRGB by integration
//! against the CIE 1931 2° colour-matching functions under illuminant D65.
//!
//! ```text
//! ρ_c = ∫ ρ(λ) w_c(λ) dλ ≈ Σ_j ρ(λ_j) W_c,j                 λ_j = 360, 365, …, 780 nm
//! W_c,j = Σ_k M_ck x̄_k(λ_j) D65(λ_j) / Σ_j' Σ_k M_ck x̄_k(λ_j') D65(λ_j')
//! ```
//!
//! with `x̄_k = (x̄, ȳ, z̄)` and `M` the XYZ → linear sRGB (Rec. 709 primaries,
//! D65 white) matrix of IEC 61966-2-1:1999. The sum is the CIE's 5 nm
//! summation (CIE 015:2018 §7.1); each channel is normalised so that a
//! spectrally flat reflectance `ρ(λ) = r` gives `(r, r, r)` (the white of
//! the sRGB primaries is D65). The red weights are negative between about
//! 440 and 545 nm, as the sRGB matching functions are: a saturated spectrum
//! can have a negative channel.
//!
//! # Data (data/cie/)
//!
//! The CIE 1931 2° standard observer (CIE 018:2019) and the relative
//! spectral power of D65 (CIE S 014-2), every 5 nm over 360–780 nm, as
//! colour-science 0.4.7 ships them (`MSDS_CMFS["CIE 1931 2 Degree Standard
//! Observer"]`, `SDS_ILLUMINANTS["D65"]`); `data/generate.py` writes them
//! into this crate. Above 780 nm, where colour-science's D65 ends, ȳ is
//! below 1.5e-5 of its peak; the sum leaves it out.

#[rustfmt::skip]
mod data {
    include!("colour_data.rs");
}
pub use data::CIE_1931_D65;

/// Number of wavelengths of the 5 nm sum.
pub const WAVELENGTH_COUNT: usize = CIE_1931_D65.len();

/// XYZ → linear sRGB (IEC 61966-2-1:1999, Rec. 709 primaries, D65 white), rows R, G, B.
pub const XYZ_TO_LINEAR_SRGB: [[f64; 3]; 3] = [
    [3.2406, -1.5372, -0.4986],
    [-0.9689, 1.8758, 0.0415],
    [0.0557, -0.2040, 1.0570],
];

/// The wavelength of the sum's node `j`, µm.
pub const fn wavelength(j: usize) -> f32 {
    CIE_1931_D65[j][0] / 1000.0
}

/// The weights `W_c,j` of linear sRGB channel `c` at node `j` (module
/// documentation): `SRGB_WEIGHTS[j][c]`; each channel's weights sum to 1.
pub const SRGB_WEIGHTS: [[f32; 3]; WAVELENGTH_COUNT] = {
    let mut raw = [[0.0f64; 3]; WAVELENGTH_COUNT];
    let mut total = [0.0f64; 3];
    let mut j = 0;
    while j < WAVELENGTH_COUNT {
        let row = CIE_1931_D65[j];
        let mut c = 0;
        while c < 3 {
            let m = XYZ_TO_LINEAR_SRGB[c];
            let v = (m[0] * row[1] as f64 + m[1] * row[2] as f64 + m[2] * row[3] as f64)
                * row[4] as f64;
            raw[j][c] = v;
            total[c] += v;
            c += 1;
        }
        j += 1;
    }
    let mut out = [[0.0f32; 3]; WAVELENGTH_COUNT];
    let mut j = 0;
    while j < WAVELENGTH_COUNT {
        let mut c = 0;
        while c < 3 {
            out[j][c] = (raw[j][c] / total[c]) as f32;
            c += 1;
        }
        j += 1;
    }
    out
};

/// Linear sRGB of the spectral reflectance `rho(λ µm)` by the 5 nm sum
/// (module documentation): `WAVELENGTH_COUNT` calls of `rho`.
pub fn srgb_of(mut rho: impl FnMut(f32) -> f64) -> [f64; 3] {
    let mut out = [0.0; 3];
    for (j, w) in SRGB_WEIGHTS.iter().enumerate() {
        let r = rho(wavelength(j));
        for c in 0..3 {
            out[c] += f64::from(w[c]) * r;
        }
    }
    out
}

/// The luminance `Y` of linear sRGB (Rec. 709: the middle row of the inverse of
/// [`XYZ_TO_LINEAR_SRGB`], 0.2126 R + 0.7152 G + 0.0722 B).
pub fn luminance(rgb: [f64; 3]) -> f64 {
    0.2126 * rgb[0] + 0.7152 * rgb[1] + 0.0722 * rgb[2]
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_table_is_the_5_nm_grid() {
        for (j, row) in CIE_1931_D65.iter().enumerate() {
            assert_eq!(row[0], 360.0 + 5.0 * j as f32);
            assert!(row[1..].iter().all(|v| *v >= 0.0 && v.is_finite()));
        }
        assert_eq!(CIE_1931_D65[WAVELENGTH_COUNT - 1][0], 780.0);
        // D65 is 100 at 560 nm by definition (CIE S 014-2).
        assert_eq!(CIE_1931_D65[(560 - 360) / 5][4], 100.0);
    }

    /// D65's chromaticity from the tables is the CIE's (x, y) = (0.31272,
    /// 0.32903) for the 2° observer (CIE 015:2018 Table 3): an independent
    /// check of the data and of the sum.
    #[test]
    fn d65_chromaticity_is_the_published_one() {
        let mut xyz = [0.0f64; 3];
        for row in CIE_1931_D65 {
            for k in 0..3 {
                xyz[k] += f64::from(row[k + 1]) * f64::from(row[4]);
            }
        }
        let sum = xyz[0] + xyz[1] + xyz[2];
        let (x, y) = (xyz[0] / sum, xyz[1] / sum);
        assert!(
            (x - 0.31272).abs() < 5e-5 && (y - 0.32903).abs() < 5e-5,
            "{x} {y}"
        );
        // The matrix maps that white to equal channels (to the matrix's 4 digits).
        let rgb: Vec<f64> = XYZ_TO_LINEAR_SRGB
            .iter()
            .map(|m| (m[0] * xyz[0] + m[1] * xyz[1] + m[2] * xyz[2]) / xyz[1])
            .collect();
        for v in &rgb {
            assert!((v - 1.0).abs() < 2e-3, "{rgb:?}");
        }
    }

    #[test]
    fn a_flat_spectrum_gives_equal_channels() {
        for r in [0.0, 0.25, 1.0] {
            let rgb = srgb_of(|_| r);
            for v in rgb {
                assert!((v - r).abs() < 1e-6, "{rgb:?}");
            }
            assert!((luminance(rgb) - r).abs() < 1e-6);
        }
    }

    /// Monochromatic light at 450, 530 and 610 nm falls mostly in blue,
    /// green and red; red is negative in the blue–green (the sRGB gamut).
    #[test]
    fn narrow_spectra_fall_in_their_channel() {
        let line = |nm: f32| srgb_of(move |l| f64::from(((l * 1000.0) - nm).abs() < 1.0));
        let (b, g, r) = (line(450.0), line(530.0), line(610.0));
        assert!(b[2] > b[1] && b[2] > b[0], "{b:?}");
        assert!(g[1] > g[0] && g[1] > g[2], "{g:?}");
        assert!(r[0] > r[1] && r[0] > r[2], "{r:?}");
        assert!(line(500.0)[0] < 0.0);
    }
}
