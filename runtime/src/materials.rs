//! Named material presets for [`crate::brdf`], as plain `const` data.
//!
//! Indices are given at the default RGB wavelengths 0.645, 0.526, 0.444 µm
//! ([`crate::brdf::RGB_WAVELENGTHS`]). Geometry parameters are in the ranges
//! HP17 fits to measured materials; HP17's nickel fit is β = 0.0598,
//! σs = 0.0273 µm, b = 4.8418 µm (docs/model.md §1: lengths in µm).
//!
//! **Gold** optical constants: P. B. Johnson and R. W. Christy, "Optical
//! constants of the noble metals", Phys. Rev. B 6, 4370 (1972), Table I (as
//! tabulated by refractiveindex.info, `main/Au/Johnson`), interpolated
//! linearly in photon energy between the table's rows:
//!
//! | λ (µm) | E (eV) | rows used (eV: n, k) | n + ik |
//! |---|---|---|---|
//! | 0.645 | 1.922 | 1.88: 0.14, 3.697; 2.01: 0.21, 3.272 | 0.163 + 3.56i |
//! | 0.526 | 2.357 | 2.26: 0.43, 2.455; 2.38: 0.62, 2.081 | 0.584 + 2.15i |
//! | 0.444 | 2.792 | 2.75: 1.38, 1.914; 2.88: 1.45, 1.948 | 1.403 + 1.925i |
//!
//! **Polymer varnish** (plastic presets): a constant real index n = 1.5, the
//! usual round value for acrylic/PMMA-like varnishes in the visible (PMMA's
//! index is 1.48–1.50 over 0.44–0.65 µm); the dispersion is neglected.

use crate::brdf::{BaseLayer, Layer, Material, Surface};
use crate::fresnel::Complex;

/// Gold at the RGB wavelengths (Johnson & Christy 1972; see the module table).
pub const GOLD_ETA: [Complex; 3] = [
    Complex::new(0.163, 3.56),
    Complex::new(0.584, 2.15),
    Complex::new(1.403, 1.925),
];

/// A polymer varnish, n = 1.5 at every channel (see the module documentation).
pub const VARNISH_ETA: [Complex; 3] = [Complex::real(1.5), Complex::real(1.5), Complex::real(1.5)];

/// HP17's nickel geometry (HP17 Figs. 16-17): β = 0.0598, σs = 0.0273 µm,
/// b = 4.8418. The caption of Fig. 17 prints `b = 4.8418 µm⁻¹`, but in
/// (HP17 16) `b f` is dimensionless with f in µm⁻¹, so b is a length (µm), as
/// docs/model.md §1 has it. The captions give neither p nor c: p = 1 (Beckmann) and
/// c = 2 are **our** choices, not fitted values.
pub const HP17_NICKEL_SURFACE: Surface = Surface {
    beta: 0.0598,
    p: 1.0,
    sigma_s: 0.0273,
    b: 4.8418,
    c: 2.0,
};

/// Gold with HP17's nickel geometry: a moderately glossy metal with a visible halo.
pub const GOLD_HP17_GEOMETRY: Material = Material {
    layer: Layer {
        surface: HP17_NICKEL_SURFACE,
        base: BaseLayer::Conductor,
        lambertian: 0.0,
    },
    eta_rgb: GOLD_ETA,
};

/// Polished gold: a very narrow lobe (β = 0.005, p = 0.6) and a faint halo.
pub const GOLD_POLISHED: Material = Material {
    layer: Layer {
        surface: Surface {
            beta: 0.005,
            p: 0.6,
            sigma_s: 0.005,
            b: 2.0,
            c: 1.8,
        },
        base: BaseLayer::Conductor,
        lambertian: 0.0,
    },
    eta_rgb: GOLD_ETA,
};

/// Brushed-looking rough gold: wide lobe (β = 0.35, p = 1.5) and strong nano-roughness.
pub const GOLD_ROUGH: Material = Material {
    layer: Layer {
        surface: Surface {
            beta: 0.35,
            p: 1.5,
            sigma_s: 0.06,
            b: 8.0,
            c: 2.5,
        },
        base: BaseLayer::Conductor,
        lambertian: 0.0,
    },
    eta_rgb: GOLD_ETA,
};

/// White plastic: varnish (n = 1.5) with HP17-range nano-roughness over a
/// diffuse layer of albedo 0.8.
pub const WHITE_PLASTIC: Material = Material {
    layer: Layer {
        surface: Surface {
            beta: 0.08,
            p: 0.8,
            sigma_s: 0.02,
            b: 3.0,
            c: 2.2,
        },
        base: BaseLayer::Plastic { albedo: 0.8 },
        lambertian: 0.0,
    },
    eta_rgb: VARNISH_ETA,
};

/// A marble-like dielectric: subsurface base (α = 0.95) under a glossy varnish.
pub const MARBLE: Material = Material {
    layer: Layer {
        surface: Surface {
            beta: 0.04,
            p: 1.0,
            sigma_s: 0.01,
            b: 4.0,
            c: 2.0,
        },
        base: BaseLayer::Subsurface { albedo: 0.95 },
        lambertian: 0.0,
    },
    eta_rgb: VARNISH_ETA,
};

/// All presets with their names.
pub const PRESETS: [(&str, Material); 5] = [
    ("gold-hp17-geometry", GOLD_HP17_GEOMETRY),
    ("gold-polished", GOLD_POLISHED),
    ("gold-rough", GOLD_ROUGH),
    ("white-plastic", WHITE_PLASTIC),
    ("marble", MARBLE),
];

/// The preset called `name`, if there is one.
pub fn preset(name: &str) -> Option<Material> {
    PRESETS.iter().find(|(n, _)| *n == name).map(|(_, m)| *m)
}
