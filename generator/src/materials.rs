//! The materials file (`materials.toml` at the repository root): named
//! materials with their two-scale parameters, read by `generator build` and
//! `verify` for T4.
//!
//! ```toml
//! wavelengths = [0.645, 0.526, 0.444]   # µm, one per channel (1 to 3); HP15 §5.5
//!
//! [[material]]
//! name = "nickel"          # file t4-nickel.tbl; [a-z0-9-], unique
//! beta = 0.0598            # EPD width β (HP17 34-35), (0, 1]
//! p = 1.0                  # EPD shape p, [0.2, 5]
//! sigma_s = 0.0273         # RMS height of the nano-roughness σs, µm, ≥ 0
//! b = 4.8418               # correlation length of the K-correlation spectrum, µm, > 0
//! c = 2.0                  # K-correlation exponent, (1, 100]
//! n = [2.0, 1.8, 1.7]      # complex index n + ik per wavelength
//! k = [3.8, 3.3, 2.8]
//! base = "conductor"       # or "plastic" / "subsurface" (then `albedo` per wavelength, and k = 0)
//! lambertian = 0.0         # optional Lambertian term k_d ∈ [0, 1] (adds k_d/π); default 0
//! band_limit = 48          # T4 band limit L, [2, 127]; absent: no T4 file for the material
//! filter = { start = 40, width = 8 }   # optional half-Gaussian band filter (WAT92 §2.5)
//! ```
//!
//! Unknown keys, missing fields and out-of-range values are errors that name
//! the material and the field.

use serde::Deserialize;
use std::fmt;
use std::path::Path;

use crate::sh::BandFilter;

/// The text of the repository's `materials.toml` ([`Materials::shipped`]).
pub const SHIPPED: &str = include_str!("../../materials.toml");

/// The materials file.
#[derive(Clone, Debug, PartialEq)]
pub struct Materials {
    /// Wavelength of each channel, µm.
    pub wavelengths: Vec<f64>,
    /// The materials, in file order.
    pub materials: Vec<Material>,
}

/// Base layer under the microfacet interface (docs/model.md §2.6).
#[derive(Clone, Debug, PartialEq)]
pub enum Base {
    /// No base: a conductor.
    Conductor,
    /// A varnish of index `n` (real) over a diffuse layer of albedo ρd per
    /// wavelength (HP17 42-43).
    Plastic {
        /// ρd per wavelength, in [0, 1).
        albedo: Vec<f64>,
    },
    /// A varnish of index `n` (real) over a scattering medium of
    /// single-scattering albedo α per wavelength (HP17 44-47).
    Subsurface {
        /// α per wavelength, in [0, 1).
        albedo: Vec<f64>,
    },
}

impl Base {
    /// The albedo (ρd or α) at `channel`, 0 for a conductor.
    pub fn albedo(&self, channel: usize) -> f64 {
        match self {
            Base::Conductor => 0.0,
            Base::Plastic { albedo } | Base::Subsurface { albedo } => albedo[channel],
        }
    }
}

/// One material.
#[derive(Clone, Debug, PartialEq)]
pub struct Material {
    /// Name, `[a-z0-9-]+`; the T4 file is `t4-<name>.tbl`.
    pub name: String,
    /// EPD width β.
    pub beta: f64,
    /// EPD shape p.
    pub p: f64,
    /// σs, µm.
    pub sigma_s: f64,
    /// b, µm.
    pub b: f64,
    /// c.
    pub c: f64,
    /// Real part of the index, per wavelength.
    pub n: Vec<f64>,
    /// Imaginary part of the index, per wavelength.
    pub k: Vec<f64>,
    /// Base layer.
    pub base: Base,
    /// Lambertian term `k_d ∈ [0, 1]` (adds `k_d/π`; 0 if absent from the file).
    pub lambertian: f64,
    /// T4 band limit L; `None`: no T4 file (a lobe too narrow for SH).
    pub band_limit: Option<usize>,
    /// Optional half-Gaussian band filter of T4.
    pub filter: Option<BandFilter>,
}

/// What is wrong with a materials file.
#[derive(Clone, Debug, PartialEq)]
pub struct MaterialsError(pub String);

impl fmt::Display for MaterialsError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(&self.0)
    }
}

impl std::error::Error for MaterialsError {}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawFile {
    wavelengths: Vec<f64>,
    #[serde(default)]
    material: Vec<RawMaterial>,
}

#[derive(Deserialize, Default)]
#[serde(deny_unknown_fields)]
struct RawMaterial {
    /// A shipped preset of the runtime (`twoscale::materials::PRESETS`):
    /// its name and parameters, with no model field of its own.
    preset: Option<String>,
    name: Option<String>,
    beta: Option<f64>,
    p: Option<f64>,
    sigma_s: Option<f64>,
    b: Option<f64>,
    c: Option<f64>,
    n: Option<Vec<f64>>,
    k: Option<Vec<f64>>,
    base: Option<String>,
    albedo: Option<Vec<f64>>,
    lambertian: Option<f64>,
    band_limit: Option<usize>,
    filter: Option<RawFilter>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawFilter {
    start: f64,
    width: f64,
}

impl Materials {
    /// Reads and validates a materials file.
    pub fn load(path: &Path) -> Result<Materials, MaterialsError> {
        let text = std::fs::read_to_string(path)
            .map_err(|e| MaterialsError(format!("cannot read {}: {e}", path.display())))?;
        Self::parse(&text).map_err(|e| MaterialsError(format!("{}: {e}", path.display())))
    }

    /// The repository's `materials.toml`, compiled into the binary: the
    /// runtime's presets with T4's band limits (the default of `build`,
    /// `verify` and `plot` when no `--materials FILE` is given).
    pub fn shipped() -> Materials {
        match Self::parse(SHIPPED) {
            Ok(materials) => materials,
            // The test `the_repository_file_is_valid` parses the same text.
            Err(e) => panic!("the shipped materials.toml is invalid: {e}"),
        }
    }

    /// `--materials FILE` if given, else [`Materials::shipped`].
    pub fn load_or_shipped(path: Option<&Path>) -> Result<Materials, MaterialsError> {
        path.map_or_else(|| Ok(Self::shipped()), Self::load)
    }

    /// Parses and validates the text of a materials file.
    pub fn parse(text: &str) -> Result<Materials, MaterialsError> {
        let raw: RawFile = toml::from_str(text).map_err(|e| MaterialsError(e.to_string()))?;
        let channels = raw.wavelengths.len();
        if !(1..=twoscale::sh::MAX_CHANNELS).contains(&channels) {
            return Err(MaterialsError(format!(
                "wavelengths: {channels} given, 1 to {} allowed",
                twoscale::sh::MAX_CHANNELS
            )));
        }
        for &lambda in &raw.wavelengths {
            if !(0.2..=2.0).contains(&lambda) {
                return Err(MaterialsError(format!(
                    "wavelengths: {lambda} µm is outside [0.2, 2] µm"
                )));
            }
        }
        let mut materials: Vec<Material> = Vec::new();
        for m in raw.material {
            let m = m.resolve_preset(&raw.wavelengths)?;
            let material = m.validate(channels)?;
            if materials.iter().any(|other| other.name == material.name) {
                return Err(MaterialsError(format!(
                    "material '{}' is defined twice",
                    material.name
                )));
            }
            materials.push(material);
        }
        Ok(Materials {
            wavelengths: raw.wavelengths,
            materials,
        })
    }
}

fn in_range(
    name: &str,
    field: &str,
    value: f64,
    lo: f64,
    hi: f64,
    open_lo: bool,
) -> Result<(), MaterialsError> {
    let ok = value.is_finite() && value <= hi && if open_lo { value > lo } else { value >= lo };
    if ok {
        Ok(())
    } else {
        let bracket = if open_lo { '(' } else { '[' };
        Err(MaterialsError(format!(
            "material '{name}': {field} = {value} is outside {bracket}{lo}, {hi}]"
        )))
    }
}

impl RawMaterial {
    /// A `preset = "…"` entry with the runtime preset's parameters filled in
    /// (the presets are defined once, in `twoscale::materials`); other
    /// entries unchanged.
    fn resolve_preset(self, wavelengths: &[f64]) -> Result<RawMaterial, MaterialsError> {
        let Some(preset) = self.preset else {
            return Ok(self);
        };
        let err = |m: String| Err(MaterialsError(format!("preset '{preset}': {m}")));
        let Some(material) = twoscale::materials::preset(&preset) else {
            let names: Vec<_> = twoscale::materials::PRESETS
                .iter()
                .map(|(n, _)| *n)
                .collect();
            return err(format!("not a shipped preset ({})", names.join(", ")));
        };
        let rgb = twoscale::brdf::RGB_WAVELENGTHS.map(f64::from);
        if wavelengths.len() != 3
            || wavelengths
                .iter()
                .zip(rgb)
                .any(|(a, b)| (a - b).abs() > 1e-6)
        {
            return err(format!(
                "presets are defined at the RGB wavelengths {rgb:?} µm"
            ));
        }
        let own = [
            self.name.is_some(),
            self.beta.is_some(),
            self.p.is_some(),
            self.sigma_s.is_some(),
            self.b.is_some(),
            self.c.is_some(),
            self.n.is_some(),
            self.k.is_some(),
            self.base.is_some(),
            self.albedo.is_some(),
            self.lambertian.is_some(),
        ];
        if own.into_iter().any(|given| given) {
            return err("give only band_limit and filter with a preset".into());
        }
        let layer = material.layer;
        let s = layer.surface;
        let (base, albedo) = match layer.base {
            twoscale::brdf::BaseLayer::Conductor => ("conductor", None),
            twoscale::brdf::BaseLayer::Plastic { albedo } => ("plastic", Some(albedo)),
            twoscale::brdf::BaseLayer::Subsurface { albedo } => ("subsurface", Some(albedo)),
        };
        Ok(RawMaterial {
            name: Some(preset.clone()),
            beta: Some(f64::from(s.beta)),
            p: Some(f64::from(s.p)),
            sigma_s: Some(f64::from(s.sigma_s)),
            b: Some(f64::from(s.b)),
            c: Some(f64::from(s.c)),
            n: Some(material.eta_rgb.iter().map(|e| f64::from(e.re)).collect()),
            k: Some(material.eta_rgb.iter().map(|e| f64::from(e.im)).collect()),
            base: Some(base.into()),
            albedo: albedo.map(|a| vec![f64::from(a); 3]),
            lambertian: Some(f64::from(layer.lambertian)),
            band_limit: self.band_limit,
            filter: self.filter,
            preset: None,
        })
    }

    fn validate(self, channels: usize) -> Result<Material, MaterialsError> {
        let name = self.name.unwrap_or_default();
        let need = |field: &str, value: Option<f64>| {
            value.ok_or_else(|| MaterialsError(format!("material '{name}': missing field {field}")))
        };
        let (beta, p, sigma_s, b, c) = (
            need("beta", self.beta)?,
            need("p", self.p)?,
            need("sigma_s", self.sigma_s)?,
            need("b", self.b)?,
            need("c", self.c)?,
        );
        let missing =
            |field: &str| MaterialsError(format!("material '{name}': missing field {field}"));
        let n = self.n.ok_or_else(|| missing("n"))?;
        let k = self.k.ok_or_else(|| missing("k"))?;
        let base_kind = self.base.ok_or_else(|| missing("base"))?;
        let lambertian = self.lambertian.unwrap_or(0.0);
        if name.is_empty()
            || !name
                .bytes()
                .all(|c| c.is_ascii_lowercase() || c.is_ascii_digit() || c == b'-')
        {
            return Err(MaterialsError(format!(
                "material name '{name}' must be non-empty and use only a-z, 0-9 and '-'"
            )));
        }
        in_range(&name, "beta", beta, 0.0, 1.0, true)?;
        in_range(&name, "p", p, 0.2, 5.0, false)?;
        in_range(&name, "sigma_s", sigma_s, 0.0, 1.0, false)?;
        in_range(&name, "b", b, 0.0, 1000.0, true)?;
        in_range(&name, "c", c, 1.0, 100.0, true)?;
        for (field, values) in [("n", &n), ("k", &k)] {
            if values.len() != channels {
                return Err(MaterialsError(format!(
                    "material '{name}': {field} has {} values, one per wavelength ({channels}) needed",
                    values.len()
                )));
            }
        }
        for &v in &n {
            in_range(&name, "n", v, 0.0, 10.0, true)?;
        }
        for &v in &k {
            in_range(&name, "k", v, 0.0, 20.0, false)?;
        }
        let base = match (base_kind.as_str(), self.albedo) {
            ("conductor", None) => Base::Conductor,
            ("conductor", Some(_)) => {
                return Err(MaterialsError(format!(
                    "material '{name}': albedo is only for base = \"plastic\" or \"subsurface\""
                )));
            }
            (kind @ ("plastic" | "subsurface"), Some(albedo)) => {
                if albedo.len() != channels {
                    return Err(MaterialsError(format!(
                        "material '{name}': albedo has {} values, one per wavelength ({channels}) needed",
                        albedo.len()
                    )));
                }
                for &a in &albedo {
                    in_range(&name, "albedo", a, 0.0, 0.999, false)?;
                }
                if k.iter().any(|&k| k != 0.0) || n.iter().any(|&n| n < 1.0) {
                    return Err(MaterialsError(format!(
                        "material '{name}': a {kind} base's varnish needs a real index n ≥ 1 (k = 0)"
                    )));
                }
                if kind == "plastic" {
                    Base::Plastic { albedo }
                } else {
                    Base::Subsurface { albedo }
                }
            }
            (kind @ ("plastic" | "subsurface"), None) => {
                return Err(MaterialsError(format!(
                    "material '{name}': base = \"{kind}\" needs an albedo per wavelength"
                )));
            }
            (other, _) => {
                return Err(MaterialsError(format!(
                    "material '{name}': unknown base '{other}' (conductor, plastic or subsurface)"
                )));
            }
        };
        in_range(&name, "lambertian", lambertian, 0.0, 1.0, false)?;
        let max = twoscale::sh::MAX_BAND_LIMIT;
        if let Some(l) = self.band_limit
            && !(twoscale::sh::MIN_BAND_LIMIT..=max).contains(&l)
        {
            return Err(MaterialsError(format!(
                "material '{name}': band_limit = {l} is outside [2, {max}]"
            )));
        }
        let filter = match self.filter {
            None => None,
            Some(f) => {
                in_range(&name, "filter.start", f.start, 0.0, max as f64, false)?;
                in_range(&name, "filter.width", f.width, 0.0, 1000.0, true)?;
                Some(BandFilter {
                    start: f.start,
                    width: f.width,
                })
            }
        };
        Ok(Material {
            name,
            beta,
            p,
            sigma_s,
            b,
            c,
            n,
            k,
            base,
            lambertian,
            band_limit: self.band_limit,
            filter,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const GOOD: &str = r#"
wavelengths = [0.645, 0.526, 0.444]
[[material]]
name = "ni"
beta = 0.06
p = 1.0
sigma_s = 0.03
b = 4.8
c = 2.0
n = [2.0, 1.8, 1.7]
k = [3.8, 3.3, 2.8]
base = "conductor"
band_limit = 16
"#;

    fn error_of(text: &str) -> String {
        Materials::parse(text).unwrap_err().0
    }

    #[test]
    fn parses_a_valid_file() {
        let m = Materials::parse(GOOD).unwrap();
        assert_eq!(m.wavelengths, vec![0.645, 0.526, 0.444]);
        assert_eq!(m.materials.len(), 1);
        assert_eq!(m.materials[0].base, Base::Conductor);
        assert_eq!(m.materials[0].filter, None);
    }

    #[test]
    fn the_repository_file_is_valid() {
        let path = concat!(env!("CARGO_MANIFEST_DIR"), "/../materials.toml");
        let m = Materials::load(Path::new(path)).unwrap();
        assert!(m.materials.len() >= 2);
        assert_eq!(Materials::shipped(), m);
    }

    /// The repository file holds exactly the runtime presets
    /// (`twoscale::materials::PRESETS`): same names, and every value equal
    /// once rounded to the runtime's f32.
    #[test]
    fn preset_entries_take_the_runtime_presets() {
        use twoscale::brdf::{BaseLayer, RGB_WAVELENGTHS};
        let path = concat!(env!("CARGO_MANIFEST_DIR"), "/../materials.toml");
        let file = Materials::load(Path::new(path)).unwrap();
        let f = |v: f64| v as f32;
        assert_eq!(
            file.wavelengths.iter().map(|&w| f(w)).collect::<Vec<_>>(),
            RGB_WAVELENGTHS
        );
        let names: Vec<&str> = file.materials.iter().map(|m| m.name.as_str()).collect();
        let preset_names: Vec<&str> = twoscale::materials::PRESETS.iter().map(|p| p.0).collect();
        assert_eq!(names, preset_names);
        for (m, (name, preset)) in file.materials.iter().zip(twoscale::materials::PRESETS) {
            let layer = preset.layer;
            let s = layer.surface;
            assert_eq!(
                [f(m.beta), f(m.p), f(m.sigma_s), f(m.b), f(m.c)],
                [s.beta, s.p, s.sigma_s, s.b, s.c],
                "{name}: surface"
            );
            assert_eq!(f(m.lambertian), layer.lambertian, "{name}: lambertian");
            for c in 0..3 {
                let eta = preset.eta_rgb[c];
                assert_eq!([f(m.n[c]), f(m.k[c])], [eta.re, eta.im], "{name}: η[{c}]");
                let albedo = f(m.base.albedo(c));
                let base = match m.base {
                    Base::Conductor => BaseLayer::Conductor,
                    Base::Plastic { .. } => BaseLayer::Plastic { albedo },
                    Base::Subsurface { .. } => BaseLayer::Subsurface { albedo },
                };
                assert_eq!(base, layer.base, "{name}: base at channel {c}");
            }
        }
    }

    #[test]
    fn a_preset_entry_is_checked() {
        let head = "wavelengths = [0.645, 0.526, 0.444]\n[[material]]\n";
        let e = error_of(&format!("{head}preset = \"gold\"\n"));
        assert!(
            e.contains("not a shipped preset") && e.contains("gold-rough"),
            "{e}"
        );
        let e = error_of(&format!("{head}preset = \"marble\"\nbeta = 0.1\n"));
        assert!(e.contains("only band_limit and filter"), "{e}");
        let e = error_of("wavelengths = [0.5]\n[[material]]\npreset = \"marble\"\n");
        assert!(e.contains("RGB wavelengths"), "{e}");
    }

    #[test]
    fn rejects_unknown_keys_missing_fields_and_bad_values() {
        let e = error_of(&GOOD.replace("c = 2.0", "c = 2.0\ncolour = 1"));
        assert!(e.contains("unknown field") && e.contains("colour"), "{e}");
        let e = error_of(&GOOD.replace("beta = 0.06\n", ""));
        assert!(e.contains("missing field") && e.contains("beta"), "{e}");
        let e = error_of(&GOOD.replace("beta = 0.06", "beta = 1.5"));
        assert!(e.contains("'ni'") && e.contains("beta"), "{e}");
        let e = error_of(&GOOD.replace("c = 2.0", "c = 1.0"));
        assert!(e.contains("c = 1"), "{e}");
        let e = error_of(&GOOD.replace("k = [3.8, 3.3, 2.8]", "k = [3.8, 3.3]"));
        assert!(e.contains("k has 2 values"), "{e}");
        let e = error_of(&GOOD.replace("band_limit = 16", "band_limit = 500"));
        assert!(e.contains("band_limit"), "{e}");
        let e = error_of(&GOOD.replace("\"conductor\"", "\"wood\""));
        assert!(e.contains("unknown base"), "{e}");
        let e = error_of(&GOOD.replace("\"conductor\"", "\"plastic\""));
        assert!(e.contains("needs an albedo"), "{e}");
        let subsurface = GOOD.replace(
            "base = \"conductor\"",
            "base = \"subsurface\"\nalbedo = [0.9, 0.9, 0.9]",
        );
        let e = error_of(&subsurface);
        assert!(e.contains("real index"), "{e}");
        let dielectric = subsurface.replace("k = [3.8, 3.3, 2.8]", "k = [0.0, 0.0, 0.0]");
        let m = Materials::parse(&dielectric).unwrap();
        assert_eq!(m.materials[0].base.albedo(2), 0.9);
        let e = error_of(&GOOD.replace("c = 2.0", "c = 2.0\nlambertian = 1.5"));
        assert!(e.contains("lambertian"), "{e}");
        let m = Materials::parse(&GOOD.replace("band_limit = 16\n", "")).unwrap();
        assert_eq!(m.materials[0].band_limit, None);
        let e = error_of(&GOOD.replace("name = \"ni\"", "name = \"Ni 2\""));
        assert!(e.contains("a-z"), "{e}");
        let twice = format!("{GOOD}{}", &GOOD[GOOD.find("[[material]]").unwrap()..]);
        assert!(error_of(&twice).contains("twice"));
        let e = error_of(&GOOD.replace("[0.645, 0.526, 0.444]", "[]"));
        assert!(e.contains("wavelengths"), "{e}");
    }
}
