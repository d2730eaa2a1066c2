//! Named material presets for [`crate::brdf`], as plain `const` data: each
//! preset is a [`SpectralMaterial`] (its index over the spectrum, from the
//! measured tables of [`crate::spectrum::optical`]), and [`PRESETS`] holds them at the
//! paper's three RGB wavelengths 0.645, 0.526, 0.444 µm
//! ([`crate::material::RGB_WAVELENGTHS`]; [`SpectralMaterial::paper_rgb`]).
//!
//! Geometry parameters are in the ranges HP17 fits to measured materials;
//! HP17's nickel fit is β = 0.0598, σs = 0.0273 µm, b = 4.8418 µm
//! (docs/model.md §1: lengths in µm). The other geometries are **our**
//! choices, one per metal, spread over glossy to rough and weak to strong
//! halos; none is a fit to a measurement.
//!
//! Optical constants: [`crate::spectrum::optical`] (Johnson & Christy 1972 for gold,
//! silver, copper; 1974 for nickel, chromium, titanium, iron; Rakić 1995
//! for aluminium), interpolated linearly in photon energy between rows.
//!
//! **Polymer varnish** (plastic presets): a constant real index n = 1.5, the
//! usual round value for acrylic/PMMA-like varnishes in the visible (PMMA's
//! index is 1.48–1.50 over 0.44–0.65 µm); the dispersion is neglected.

use crate::material::{BaseLayer, Layer, Material, Surface};
use crate::math::Complex;
use crate::spectrum::optical::{
    AG_JOHNSON, AL_RAKIC, AU_JOHNSON, CR_JOHNSON, CU_JOHNSON, FE_JOHNSON, Ior, NI_JOHNSON,
    SpectralMaterial, TI_JOHNSON, Tabulated,
};

/// A measured metal index ([`crate::spectrum::optical`]).
const fn measured(rows: &'static [[f32; 3]]) -> Ior<'static> {
    Ior::Tabulated(Tabulated::shipped(rows))
}

/// A polymer varnish, n = 1.5 at every wavelength (see the module documentation).
pub const VARNISH: Ior<'static> = Ior::Constant(Complex::real(1.5));

/// A conductor layer (no base, no Lambertian term) of `surface`.
const fn conductor(surface: Surface) -> Layer {
    Layer {
        surface,
        base: BaseLayer::Conductor,
        lambertian: 0.0,
    }
}

/// A conductor preset: `surface` over the measured index `rows`.
const fn metal(surface: Surface, rows: &'static [[f32; 3]]) -> SpectralMaterial<'static> {
    SpectralMaterial {
        layer: conductor(surface),
        eta: measured(rows),
    }
}

/// A surface of EPD `(β, p)` and K-correlation `(σs, b, c)`.
const fn surface(beta: f32, p: f32, sigma_s: f32, b: f32, c: f32) -> Surface {
    Surface {
        beta,
        p,
        sigma_s,
        b,
        c,
    }
}

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

/// A named preset.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Preset {
    /// The name (`gold-hp17-geometry`, …) by which every interface knows it.
    pub name: &'static str,
    /// The material over the spectrum.
    pub material: SpectralMaterial<'static>,
}

/// Every preset, over the spectrum. [`PRESETS`] is this list at the paper's
/// RGB wavelengths.
pub const SPECTRAL_PRESETS: [Preset; 12] = [
    // Gold with HP17's nickel geometry: a moderately glossy metal with a visible halo.
    Preset {
        name: "gold-hp17-geometry",
        material: metal(HP17_NICKEL_SURFACE, &AU_JOHNSON),
    },
    // Polished gold: a very narrow lobe and a faint halo.
    Preset {
        name: "gold-polished",
        material: metal(surface(0.005, 0.6, 0.005, 2.0, 1.8), &AU_JOHNSON),
    },
    // Brushed-looking rough gold: wide lobe and strong nano-roughness.
    Preset {
        name: "gold-rough",
        material: metal(surface(0.35, 1.5, 0.06, 8.0, 2.5), &AU_JOHNSON),
    },
    // White plastic: varnish with HP17-range nano-roughness over a diffuse
    // layer of albedo 0.8.
    Preset {
        name: "white-plastic",
        material: SpectralMaterial {
            layer: Layer {
                surface: surface(0.08, 0.8, 0.02, 3.0, 2.2),
                base: BaseLayer::Plastic { albedo: 0.8 },
                lambertian: 0.0,
            },
            eta: VARNISH,
        },
    },
    // A marble-like dielectric: subsurface base (α = 0.95) under a glossy varnish.
    Preset {
        name: "marble",
        material: SpectralMaterial {
            layer: Layer {
                surface: surface(0.04, 1.0, 0.01, 4.0, 2.0),
                base: BaseLayer::Subsurface { albedo: 0.95 },
                lambertian: 0.0,
            },
            eta: VARNISH,
        },
    },
    // Silver: glossy, with a wide, strong halo (a slowly decaying spectrum, c = 1.6).
    Preset {
        name: "silver",
        material: metal(surface(0.02, 1.0, 0.03, 3.0, 1.6), &AG_JOHNSON),
    },
    // Copper: a medium lobe with a strong, short-correlated halo.
    Preset {
        name: "copper",
        material: metal(surface(0.1, 1.0, 0.05, 2.0, 2.5), &CU_JOHNSON),
    },
    // Nickel with HP17's fit of the MERL nickel (HP17 Figs. 16-17).
    Preset {
        name: "nickel",
        material: metal(HP17_NICKEL_SURFACE, &NI_JOHNSON),
    },
    // Chromium plating: near-mirror, a heavy-tailed lobe (p = 0.5), a faint halo.
    Preset {
        name: "chromium",
        material: metal(surface(0.01, 0.5, 0.008, 3.0, 2.0), &CR_JOHNSON),
    },
    // Machined titanium: a rough lobe and a moderate halo.
    Preset {
        name: "titanium",
        material: metal(surface(0.2, 1.2, 0.03, 5.0, 2.2), &TI_JOHNSON),
    },
    // Bead-blasted iron: very rough, short-tailed (p = 2).
    Preset {
        name: "iron",
        material: metal(surface(0.5, 2.0, 0.04, 6.0, 2.0), &FE_JOHNSON),
    },
    // Satin aluminium: a glossy heavy-tailed lobe (p = 0.8) and a halo.
    Preset {
        name: "aluminium",
        material: metal(surface(0.06, 0.8, 0.02, 4.0, 2.0), &AL_RAKIC),
    },
];

/// Every preset at the paper's RGB wavelengths, with its name (the same
/// order as [`SPECTRAL_PRESETS`]).
pub const PRESETS: [(&str, Material); SPECTRAL_PRESETS.len()] = {
    let mut out = [("", SPECTRAL_PRESETS[0].material.paper_rgb()); SPECTRAL_PRESETS.len()];
    let mut k = 0;
    while k < out.len() {
        let preset = &SPECTRAL_PRESETS[k];
        out[k] = (preset.name, preset.material.paper_rgb());
        k += 1;
    }
    out
};

/// Gold with HP17's nickel geometry at the RGB wavelengths.
pub const GOLD_HP17_GEOMETRY: Material = PRESETS[0].1;

/// The preset called `name` at the paper's RGB wavelengths, if there is one.
pub fn preset(name: &str) -> Option<Material> {
    PRESETS.iter().find(|(n, _)| *n == name).map(|(_, m)| *m)
}

/// The preset called `name` over the spectrum, if there is one.
pub fn spectral(name: &str) -> Option<SpectralMaterial<'static>> {
    SPECTRAL_PRESETS
        .iter()
        .find(|p| p.name == name)
        .map(|p| p.material)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn presets_are_valid_and_named_once() {
        for (k, p) in SPECTRAL_PRESETS.iter().enumerate() {
            p.material
                .validate()
                .unwrap_or_else(|e| panic!("{}: {e:?}", p.name));
            PRESETS[k].1.validate().unwrap();
            assert_eq!(PRESETS[k].0, p.name);
            assert_eq!(spectral(p.name), Some(p.material));
            assert_eq!(preset(p.name), Some(p.material.paper_rgb()));
            assert!(SPECTRAL_PRESETS[..k].iter().all(|q| q.name != p.name));
        }
        assert_eq!(preset("unobtainium"), None);
    }
}
