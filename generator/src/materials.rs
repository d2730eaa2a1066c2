//! The materials file (`materials.toml` at the repository root): named
//! materials with their two-scale parameters, read by `generator build` and
//! `verify` for T4.
//!
//! ```toml
//! wavelengths = [0.645, 0.526, 0.444]   # µm, one per channel (1 to 3); HP15 §5.5
//!
//! [[material]]
//! name = "nickel"          # file t4-nickel.tbl; [a-z0-9-], unique
//! beta = 0.0598            # the material's keys, as a material file's [material]
//! p = 1.0                  # (twoscale::io::desc): beta, p, eta, sigma_s, b, c, base,
//! sigma_s = 0.0273         # albedo, lambertian, with their defaults
//! b = 4.8418
//! eta = [[2.0, 3.8], [1.8, 3.3], [1.7, 2.8]]   # n + ik, one pair per wavelength
//! band_limit = 48          # T4 band limit L, [2, 127]; absent: no T4 file for the material
//! filter = { start = 40, width = 8 }   # optional half-Gaussian band filter (WAT92 §2.5)
//!
//! [[material]]
//! preset = "gold-rough"    # a shipped preset (twoscale::materials): its name and
//! band_limit = 24          # parameters; only band_limit and filter with it
//! ```
//!
//! A material's keys are the one schema of a material description
//! ([`twoscale::io::desc`]: Python's `twoscale.Material` keywords, the fit's
//! output), read and validated by the runtime, so a value is refused here
//! as everywhere else. `name`, `preset`, `band_limit` and `filter` are this
//! file's own. T4 projects the model with the default options, so the
//! option keys (`masking`, …) are refused here. Unknown keys, missing
//! fields and out-of-range values are errors that name the material and the
//! field.

use serde::Deserialize;
use std::fmt;
use std::path::Path;
use twoscale::Complex;
use twoscale::io::desc::{EtaTable, KeywordTable};
use twoscale::material::{Layer, Options, RgbMode};
use twoscale::spectrum::optical::SpectralMaterial;

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

/// One material.
#[derive(Clone, Debug, PartialEq)]
pub struct Material {
    /// Name, `[a-z0-9-]+`; the T4 file is `t4-<name>.tbl`.
    pub name: String,
    /// The surface, base layer and Lambertian term, validated by the runtime
    /// (`Layer::validate`).
    pub layer: Layer,
    /// The index `n + ik` at each wavelength.
    pub eta: Vec<Complex>,
    /// A preset's material over the spectrum (`twoscale::materials::spectral`;
    /// `None` for a material given by its indices): T4 projects what
    /// [`Material::rgb_mode`] says.
    pub spectral: Option<SpectralMaterial<'static>>,
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
    material: Vec<toml::Table>,
}

/// The keys of a `[[material]]` that are this file's, not the material's.
#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct FileKeys {
    /// A shipped preset of the runtime (`twoscale::materials::PRESETS`):
    /// its name and parameters, with no material key of its own.
    preset: Option<String>,
    name: Option<String>,
    band_limit: Option<usize>,
    filter: Option<RawFilter>,
}

/// The keys [`FileKeys`] takes out of a `[[material]]` table.
const FILE_KEYS: [&str; 4] = ["preset", "name", "band_limit", "filter"];

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
        if !(1..=twoscale::tables::sh_brdf::MAX_CHANNELS).contains(&channels) {
            return Err(MaterialsError(format!(
                "wavelengths: {channels} given, 1 to {} allowed",
                twoscale::tables::sh_brdf::MAX_CHANNELS
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
        for (index, table) in raw.material.into_iter().enumerate() {
            let material = Material::from_table(table, index, &raw.wavelengths)?;
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

impl Material {
    /// What T4 projects for this material: the integral over the spectrum
    /// for a preset, the materials file's wavelengths otherwise (the
    /// runtime's rule, [`RgbMode::default_for`]).
    pub fn rgb_mode(&self) -> RgbMode {
        RgbMode::default_for(self.spectral.is_some())
    }

    /// The material of `[[material]]` number `index` (from 0): the file's
    /// keys taken out, the rest read as a material description
    /// ([`twoscale::io::desc`]) with one index per wavelength.
    fn from_table(
        mut table: toml::Table,
        index: usize,
        wavelengths: &[f64],
    ) -> Result<Material, MaterialsError> {
        let mut own = toml::Table::new();
        for key in FILE_KEYS {
            if let Some(value) = table.remove(key) {
                own.insert(key.to_string(), value);
            }
        }
        let own: FileKeys = own
            .try_into()
            .map_err(|e| MaterialsError(format!("[[material]] {}: {e}", index + 1)))?;
        let (name, layer, eta, spectral) = match own.preset {
            Some(preset) if own.name.is_none() => from_preset(&preset, &table, wavelengths)?,
            Some(preset) => {
                return Err(MaterialsError(format!(
                    "preset '{preset}': give only band_limit and filter with a preset"
                )));
            }
            None => {
                let name = own.name.unwrap_or_default();
                let (layer, eta) = keywords(&name, table, wavelengths.len())?;
                (name, layer, eta, None)
            }
        };
        let err = |m: String| Err(MaterialsError(format!("material '{name}': {m}")));
        if name.is_empty()
            || !name
                .bytes()
                .all(|c| c.is_ascii_lowercase() || c.is_ascii_digit() || c == b'-')
        {
            return Err(MaterialsError(format!(
                "material name '{name}' must be non-empty and use only a-z, 0-9 and '-'"
            )));
        }
        let max = twoscale::tables::sh_brdf::MAX_BAND_LIMIT;
        if let Some(l) = own.band_limit
            && !(twoscale::tables::sh_brdf::MIN_BAND_LIMIT..=max).contains(&l)
        {
            return err(format!("band_limit = {l} is outside [2, {max}]"));
        }
        let filter = match own.filter {
            None => None,
            Some(f) => {
                if !(f.start.is_finite() && (0.0..=max as f64).contains(&f.start)) {
                    return err(format!("filter.start = {} is outside [0, {max}]", f.start));
                }
                if !(f.width.is_finite() && f.width > 0.0 && f.width <= 1000.0) {
                    return err(format!("filter.width = {} is outside (0, 1000]", f.width));
                }
                Some(BandFilter {
                    start: f.start,
                    width: f.width,
                })
            }
        };
        Ok(Material {
            name,
            layer,
            eta,
            spectral,
            band_limit: own.band_limit,
            filter,
        })
    }
}

/// The layer and indices of the material keys in `table` (`name` for the
/// messages), validated by the runtime ([`twoscale::io::desc::Keywords::layer`]);
/// options other than the default are refused (T4 projects the default).
fn keywords(
    name: &str,
    table: toml::Table,
    channels: usize,
) -> Result<(Layer, Vec<Complex>), MaterialsError> {
    let err = |m: &dyn fmt::Display| MaterialsError(format!("material '{name}': {m}"));
    let keywords: KeywordTable = table.try_into().map_err(|e| err(&e))?;
    let (layer, options) = keywords.keywords().layer(channels).map_err(|e| err(&e))?;
    if options != Options::default() || keywords.rgb_mode.is_some() {
        return Err(err(
            &"T4 projects the model with the default options: remove masking, sigma_rel, \
              colour, halo_weight and rgb_mode",
        ));
    }
    // `layer` refused a spectrum: T4 takes one index per wavelength of the file.
    let pairs: &[[f32; 2]] = match &keywords.eta {
        EtaTable::Channels(pairs) => pairs,
        EtaTable::Spectrum(_) => &[],
    };
    let eta = pairs.iter().map(|&[n, k]| Complex::new(n, k)).collect();
    Ok((layer, eta))
}

/// The name, layer, RGB indices and material over the spectrum of shipped
/// preset `preset` (defined once, in `twoscale::materials`); `rest` must hold
/// no material key.
fn from_preset(
    preset: &str,
    rest: &toml::Table,
    wavelengths: &[f64],
) -> Result<
    (
        String,
        Layer,
        Vec<Complex>,
        Option<SpectralMaterial<'static>>,
    ),
    MaterialsError,
> {
    let err = |m: String| Err(MaterialsError(format!("preset '{preset}': {m}")));
    let Some(material) = twoscale::materials::preset(preset) else {
        let names: Vec<_> = twoscale::materials::PRESETS
            .iter()
            .map(|(n, _)| *n)
            .collect();
        return err(format!("not a shipped preset ({})", names.join(", ")));
    };
    let rgb = twoscale::material::RGB_WAVELENGTHS.map(f64::from);
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
    if !rest.is_empty() {
        return err("give only band_limit and filter with a preset".into());
    }
    Ok((
        preset.to_string(),
        material.layer,
        material.eta_rgb.to_vec(),
        twoscale::materials::spectral(preset),
    ))
}

#[cfg(test)]
mod tests {
    use super::*;
    use twoscale::material::BaseLayer;

    const GOOD: &str = r#"
wavelengths = [0.645, 0.526, 0.444]
[[material]]
name = "ni"
beta = 0.06
p = 1.0
sigma_s = 0.03
b = 4.8
c = 2.0
eta = [[2.0, 3.8], [1.8, 3.3], [1.7, 2.8]]
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
        let ni = &m.materials[0];
        assert_eq!(ni.layer.base, BaseLayer::Conductor);
        assert_eq!(ni.layer.surface.beta, 0.06);
        assert_eq!(ni.eta[1], Complex::new(1.8, 3.3));
        assert_eq!(ni.filter, None);
    }

    /// A material file's `[material]` table (the fit's output) is a
    /// `[[material]]` of this file once named: one schema.
    #[test]
    fn a_material_file_table_is_an_entry() {
        let table = r#"beta = 0.1
p = 1.2
eta = [[1.5, 0.0], [1.5, 0.0], [1.5, 0.0]]
sigma_s = 0.01
b = 3.0
base = "plastic"
albedo = 0.6
lambertian = 0.1
"#;
        let file = format!("[material]\n{table}\n[metrics]\nrmse = [0.1, 0.1, 0.1]\n");
        let desc = twoscale::io::desc::MaterialDesc::from_toml_str(&file).unwrap();
        let desc = desc.get();
        let entry =
            format!("wavelengths = [0.645, 0.526, 0.444]\n[[material]]\nname = \"fit\"\n{table}");
        let m = Materials::parse(&entry).unwrap();
        assert_eq!(m.materials[0].layer, desc.material.layer);
        assert_eq!(m.materials[0].eta, desc.material.eta_rgb.to_vec());
    }

    #[test]
    fn the_repository_file_is_valid() {
        let path = concat!(env!("CARGO_MANIFEST_DIR"), "/../materials.toml");
        let m = Materials::load(Path::new(path)).unwrap();
        assert!(m.materials.len() >= 2);
        assert_eq!(Materials::shipped(), m);
    }

    /// The repository file holds exactly the runtime presets
    /// (`twoscale::materials::PRESETS`): same names and parameters.
    #[test]
    fn preset_entries_take_the_runtime_presets() {
        use twoscale::material::RGB_WAVELENGTHS;
        let path = concat!(env!("CARGO_MANIFEST_DIR"), "/../materials.toml");
        let file = Materials::load(Path::new(path)).unwrap();
        assert_eq!(
            file.wavelengths
                .iter()
                .map(|&w| w as f32)
                .collect::<Vec<_>>(),
            RGB_WAVELENGTHS
        );
        let names: Vec<&str> = file.materials.iter().map(|m| m.name.as_str()).collect();
        let preset_names: Vec<&str> = twoscale::materials::PRESETS.iter().map(|p| p.0).collect();
        assert_eq!(names, preset_names);
        for (m, (name, preset)) in file.materials.iter().zip(twoscale::materials::PRESETS) {
            assert_eq!(m.layer, preset.layer, "{name}");
            assert_eq!(m.eta, preset.eta_rgb.to_vec(), "{name}");
            // T4 projects a preset's integrated RGB, the runtime's default.
            assert_eq!(m.spectral, twoscale::materials::spectral(name), "{name}");
            assert_eq!(
                m.rgb_mode(),
                twoscale::material::RgbMode::Integrated,
                "{name}"
            );
        }
        let own = Materials::parse(GOOD).unwrap();
        assert_eq!(own.materials[0].spectral, None);
        assert_eq!(
            own.materials[0].rgb_mode(),
            twoscale::material::RgbMode::PaperWavelengths
        );
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
        let e = error_of(&format!("{head}preset = \"marble\"\nname = \"m\"\n"));
        assert!(e.contains("only band_limit and filter"), "{e}");
        let e = error_of("wavelengths = [0.5]\n[[material]]\npreset = \"marble\"\n");
        assert!(e.contains("RGB wavelengths"), "{e}");
    }

    /// Values are refused with the runtime's messages (`twoscale::validate`),
    /// named by the material.
    #[test]
    fn rejects_unknown_keys_missing_fields_and_bad_values() {
        let e = error_of(&GOOD.replace("c = 2.0", "c = 2.0\ncolor = 1"));
        assert!(e.contains("unknown field") && e.contains("color"), "{e}");
        let e = error_of(&GOOD.replace("beta = 0.06\n", ""));
        assert!(e.contains("missing field") && e.contains("beta"), "{e}");
        let e = error_of(&GOOD.replace("beta = 0.06", "beta = 15"));
        assert_eq!(e, "material 'ni': beta = 15: must be in [0.0001, 10]");
        let e = error_of(&GOOD.replace("c = 2.0", "c = 1.0"));
        assert_eq!(e, "material 'ni': c = 1: must be finite and > 1");
        let e = error_of(&GOOD.replace(", [1.7, 2.8]]", "]"));
        assert_eq!(
            e,
            "material 'ni': eta must be three (n, k) pairs (red, green, blue), got 2"
        );
        let e = error_of(&GOOD.replace("band_limit = 16", "band_limit = 500"));
        assert!(e.contains("band_limit"), "{e}");
        let e = error_of(&GOOD.replace("\"conductor\"", "\"wood\""));
        assert_eq!(
            e,
            "material 'ni': base must be one of 'conductor', 'plastic' or 'subsurface', got 'wood'"
        );
        let e = error_of(&GOOD.replace("\"conductor\"", "\"plastic\""));
        assert_eq!(e, "material 'ni': base 'plastic' needs an albedo");
        let subsurface = GOOD.replace(
            "base = \"conductor\"",
            "base = \"subsurface\"\nalbedo = 0.9",
        );
        let m = Materials::parse(&subsurface).unwrap();
        assert_eq!(
            m.materials[0].layer.base,
            BaseLayer::Subsurface { albedo: 0.9 }
        );
        let e = error_of(&GOOD.replace("c = 2.0", "c = 2.0\nlambertian = 1.5"));
        assert_eq!(e, "material 'ni': lambertian = 1.5: must be in [0, 1]");
        let e = error_of(&GOOD.replace("c = 2.0", "c = 2.0\nmasking = \"height-correlated\""));
        assert!(e.contains("default options"), "{e}");
        let m = Materials::parse(&GOOD.replace("band_limit = 16\n", "")).unwrap();
        assert_eq!(m.materials[0].band_limit, None);
        let e = error_of(&GOOD.replace("name = \"ni\"", "name = \"Ni 2\""));
        assert!(e.contains("a-z"), "{e}");
        let twice = format!("{GOOD}{}", &GOOD[GOOD.find("[[material]]").unwrap()..]);
        assert!(error_of(&twice).contains("twice"));
        let e = error_of(&GOOD.replace("[0.645, 0.526, 0.444]", "[]"));
        assert!(e.contains("wavelengths"), "{e}");
        let two = GOOD.replace("[0.645, 0.526, 0.444]", "[0.645, 0.526]");
        assert_eq!(
            error_of(&two),
            "material 'ni': eta must be 2 (n, k) pairs, one per wavelength, got 3"
        );
    }
}
