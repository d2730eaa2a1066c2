//! The K-correlation (ABC) roughness spectrum of a surface (HP17 14-16;
//! docs/model.md §2.4); its renormalisation σrel/σs is T2
//! ([`crate::tables::sigma_ratio`]).

use crate::math;
use crate::tables::sigma_ratio::SigmaRatioTable;

/// The K-correlation (ABC) spectrum of a surface (HP17 16), lengths in µm.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct KCorrelation {
    /// RMS height σs (µm).
    pub sigma_s: f32,
    /// Correlation length scale b (µm).
    pub b: f32,
    /// Spectral exponent c (> 1).
    pub c: f32,
}

impl KCorrelation {
    /// `S_HS(f) = (c − 1)/(2π) · σs² b² · (1 + b² f²)^(−(c+1)/2)` for a spatial
    /// frequency `f` in µm⁻¹ (HP17 16); 0 for `c ≤ 1` or NaN.
    pub fn spectrum(&self, f: f32) -> f32 {
        if !(self.c > 1.0) {
            return 0.0;
        }
        let bf = self.b * f;
        let value = (self.c - 1.0) / (2.0 * core::f32::consts::PI)
            * self.sigma_s
            * self.sigma_s
            * self.b
            * self.b
            * math::powff(1.0 + bf * bf, -(self.c + 1.0) / 2.0);
        if value.is_finite() { value } else { 0.0 }
    }

    /// `σrel` (µm) at wavelength `lambda` (µm) for an incident direction with
    /// cosine `cos_theta_i` (HP17 17-19), from T2.
    pub fn sigma_rel(&self, table: &SigmaRatioTable<'_>, lambda: f32, cos_theta_i: f32) -> f32 {
        self.sigma_s * table.sigma_ratio_cos(cos_theta_i, self.b / lambda, self.c)
    }
}
