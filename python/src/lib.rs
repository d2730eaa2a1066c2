//! Python bindings of the two-scale BRDF: the RGB model of a material over
//! NumPy arrays of directions, the table lookups (T1 G1, T2 σrel/σs, T3 C),
//! and the f64 reference of each quantity (`twoscale_reference::reference`).
//!
//! Conventions are the runtime's (`twoscale::brdf`): unit vectors in the
//! local frame (normal `+z`), `wi` towards the light, `wo` towards the
//! viewer; lengths in µm. Arrays of directions are `(…, 3)` and broadcast
//! together as NumPy's do; results are float32 (the runtime's precision) for
//! the model and the lookups, float64 for the reference. Parameters go
//! through the runtime's validation (`twoscale::validate`) and raise
//! `ValueError` with its message; the lookups check their table's domain
//! unless `clamp=True`. The GIL is released while rows are evaluated;
//! batches of 2048 rows or more (`PARALLEL_ROWS`) are split over rayon's
//! threads. The types are in `twoscale/_native.pyi`.

mod merl;

use std::collections::BTreeMap;
use std::sync::{LazyLock, OnceLock};

use numpy::ndarray::{Array1, ArrayD, IxDyn};
use numpy::{IntoPyArray, PyArray1, PyArrayDyn, PyReadonlyArray1, PyReadonlyArrayDyn};
use pyo3::exceptions::{PyOSError, PyValueError};
use pyo3::prelude::*;
use pyo3::types::{PyDict, PyTuple};
use rayon::prelude::*;
use twoscale::brdf::{BakeVisitor, ChannelBake};
use twoscale::brdf::{BoxedSpectral, RgbModel, SPECTRAL_WAVELENGTHS, Spectral};
use twoscale::domain::{self, Invalid};
use twoscale::io::desc::{self, DescError, DescErrorKind, Eta, Keywords, MaterialDesc};
use twoscale::material::RgbMode;
use twoscale::material::{
    BaseKind, BaseLayer, ColourTerms, HaloWeight, Layer, Masking, MultipleScattering, Options,
    SigmaRelMode, Surface,
};
use twoscale::spectrum::optical::{OwnedSpectralMaterial, SpectralMaterial};
use twoscale::validate::{self, Named};
use twoscale::{Bxdf, Complex, Convolution, TableSet, TwoScale};
use twoscale_reference::reference::{brdf as ref_brdf, conv as ref_conv, epd as ref_epd};
use twoscale_reference::reference::{fresnel as ref_fresnel, kcorr as ref_kcorr};

/// The committed tables, compiled into the extension.
static TABLES: LazyLock<TableSet<'static>> = LazyLock::new(TableSet::embedded);

/// Batches of at least this many rows are evaluated on rayon's threads.
const PARALLEL_ROWS: usize = 2048;

/// `f(k)` for `k in 0..n`, on rayon's threads when `n ≥ PARALLEL_ROWS`.
fn rows<T: Send>(n: usize, f: impl Fn(usize) -> T + Sync) -> Vec<T> {
    if n >= PARALLEL_ROWS {
        (0..n).into_par_iter().map(&f).collect()
    } else {
        (0..n).map(f).collect()
    }
}

fn value_error(message: impl Into<String>) -> PyErr {
    PyValueError::new_err(message.into())
}

/// A batch of 3-vectors (`(…, 3)` arrays broadcast together): the leading
/// shape `…` and the rows in C order.
struct Vectors<const K: usize> {
    shape: Vec<usize>,
    rows: [Vec<[f32; 3]>; K],
}

impl<const K: usize> Vectors<K> {
    fn len(&self) -> usize {
        self.rows[0].len()
    }
}

/// What the rows of a `(…, 3)` argument must hold, checked as the C API
/// checks them (`capi/src/lib.rs`, docs/c-api.md): a `ValueError` names the
/// argument, the row (`entry`, in C order) and its values.
#[derive(Clone, Copy, PartialEq, Eq)]
enum Rows {
    /// Directions: finite components.
    Directions,
    /// Uniforms: each component in [0, 1).
    Uniforms,
    /// Not checked here (the caller checks them).
    Any,
}

impl Rows {
    /// The first row of `values` (shape `(…, 3)`) outside the domain, as
    /// a `ValueError`.
    fn check(self, name: &str, values: &ArrayD<f32>) -> PyResult<()> {
        if self == Rows::Any {
            return Ok(());
        }
        let lead = &values.shape()[..values.ndim() - 1];
        for (k, row) in values.rows().into_iter().enumerate() {
            let v = [row[0], row[1], row[2]];
            let what = if !v.iter().all(|x| x.is_finite()) {
                "has a non-finite component"
            } else if self == Rows::Uniforms && !v.iter().all(|x| (0.0..1.0).contains(x)) {
                "has a component outside [0, 1) (uniforms)"
            } else {
                continue;
            };
            // The row's index in the array as given, beside its C-order number.
            let index = if lead.len() > 1 {
                let mut index = vec![0; lead.len()];
                let mut rest = k;
                for (axis, n) in lead.iter().enumerate().rev() {
                    index[axis] = rest % n;
                    rest /= n;
                }
                format!(", index {index:?}")
            } else {
                String::new()
            };
            return Err(value_error(format!(
                "{name} (entry {k}{index}) {what}: {v:?}"
            )));
        }
        Ok(())
    }
}

/// `array` as an f32 array of shape `(…, 3)`: float32 and float64 arrays as
/// they are, anything else through `numpy.asarray(array, dtype=float64)`.
fn vector_array(name: &str, array: &Bound<'_, PyAny>) -> PyResult<ArrayD<f32>> {
    let values = if let Ok(a) = array.extract::<PyReadonlyArrayDyn<'_, f32>>() {
        a.as_array().to_owned()
    } else if let Ok(a) = array.extract::<PyReadonlyArrayDyn<'_, f64>>() {
        a.as_array().mapv(|x| x as f32)
    } else {
        let converted = PyModule::import(array.py(), "numpy")?
            .call_method1("asarray", (array, "float64"))
            .ok()
            .and_then(|a| {
                a.extract::<PyReadonlyArrayDyn<'_, f64>>()
                    .ok()
                    .map(|a| a.as_array().mapv(|x| x as f32))
            });
        converted.ok_or_else(|| {
            value_error(format!(
                "{name} must be an array of numbers of shape (..., 3), got {}",
                describe(array)
            ))
        })?
    };
    if values.shape().last() == Some(&3) {
        Ok(values)
    } else {
        Err(value_error(format!(
            "{name} must have shape (..., 3), got {}",
            describe(array)
        )))
    }
}

/// The arrays of shape `(…, 3)`, each checked ([`Rows`]), broadcast
/// together as NumPy does (the leading shapes aligned on the right, each
/// axis of length 1 or the common length).
fn vectors<const K: usize>(arrays: [(&str, &Bound<'_, PyAny>, Rows); K]) -> PyResult<Vectors<K>> {
    let mut values = Vec::with_capacity(K);
    for (name, array, rows) in arrays {
        let array = vector_array(name, array)?;
        rows.check(name, &array)?;
        values.push(array);
    }
    let leading = |a: &ArrayD<f32>| a.shape()[..a.ndim() - 1].to_vec();
    let ndim = values.iter().map(|a| a.ndim() - 1).max().unwrap_or(0);
    let mut shape = vec![1; ndim];
    for a in &values {
        let lead = leading(a);
        for (out, &n) in shape[ndim - lead.len()..].iter_mut().zip(&lead) {
            if *out == 1 {
                *out = n;
            } else if n != 1 && n != *out {
                let shapes: Vec<String> = arrays
                    .iter()
                    .zip(&values)
                    .map(|((name, _, _), a)| format!("{name} of shape {:?}", a.shape()))
                    .collect();
                return Err(value_error(format!(
                    "{} do not broadcast together",
                    shapes.join(" and ")
                )));
            }
        }
    }
    let mut full = shape.clone();
    full.push(3);
    let rows = std::array::from_fn(|j| {
        let view = values[j]
            .broadcast(IxDyn(&full))
            .expect("the shapes broadcast (checked above)");
        let flat: Vec<f32> = view.iter().copied().collect();
        flat.chunks_exact(3).map(|r| [r[0], r[1], r[2]]).collect()
    });
    Ok(Vectors { shape, rows })
}

/// "an array of dtype D and shape S" or the Python type's name.
fn describe(object: &Bound<'_, PyAny>) -> String {
    let attr = |name: &str| {
        object
            .getattr(name)
            .and_then(|a| a.str().map(|s| s.to_string()))
    };
    match (attr("dtype"), attr("shape")) {
        (Ok(dtype), Ok(shape)) => format!("an array of dtype {dtype} and shape {shape}"),
        _ => match object.get_type().name() {
            Ok(name) => format!("a {name}"),
            Err(_) => "an object of unknown type".into(),
        },
    }
}

/// Checks that two batches have the same number of rows.
fn same_rows(a: (&str, usize), b: (&str, usize)) -> PyResult<()> {
    if a.1 == b.1 {
        Ok(())
    } else {
        Err(value_error(format!(
            "{} has {} rows but {} has {}",
            a.0, a.1, b.0, b.1
        )))
    }
}

/// Values of shape `shape` (one per row of a batch) as a NumPy array.
fn shaped<'py, T: numpy::Element>(
    py: Python<'py>,
    shape: &[usize],
    values: Vec<T>,
) -> Bound<'py, PyArrayDyn<T>> {
    ArrayD::from_shape_vec(IxDyn(shape), values)
        .expect("one value per element of the shape")
        .into_pyarray(py)
}

/// 3-vectors, one per row of a batch of leading shape `shape`, as an array
/// of shape `(*shape, 3)`.
fn shaped_vectors<'py, T: numpy::Element>(
    py: Python<'py>,
    shape: &[usize],
    values: Vec<[T; 3]>,
) -> Bound<'py, PyArrayDyn<T>> {
    let mut full = shape.to_vec();
    full.push(3);
    shaped(py, &full, values.into_iter().flatten().collect())
}

/// The value of option `T` called `given` (None: the runtime's default),
/// refused with the runtime's message (`validate::named`).
fn named<T: Named + Default>(given: Option<&str>) -> PyResult<T> {
    validate::named(given).map_err(|e| value_error(e.to_string()))
}

/// The options named by the keywords; None keeps the runtime's default.
fn options(
    masking: Option<&str>,
    sigma_rel: Option<&str>,
    colour: Option<&str>,
    halo_weight: Option<&str>,
    multiple_scattering: Option<&str>,
) -> PyResult<Options> {
    Ok(Options {
        masking: named(masking)?,
        sigma_rel: named(sigma_rel)?,
        colour: named(colour)?,
        halo_weight: named(halo_weight)?,
        multiple_scattering: named(multiple_scattering)?,
    })
}

/// The names of option `T`'s values, the default first.
fn names<T: Named>() -> Vec<&'static str> {
    T::NAMES.iter().map(|(n, _)| *n).collect()
}

/// A refused material file as `OSError` (unreadable) or `ValueError`, with
/// the runtime's message.
fn desc_error(error: DescError) -> PyErr {
    match error.kind {
        DescErrorKind::Io => PyOSError::new_err(error.message),
        DescErrorKind::Syntax | DescErrorKind::Refused => value_error(error.message),
    }
}

/// A parameter outside the runtime's domain as a `ValueError` with the
/// runtime's message.
fn invalid(error: Invalid) -> PyErr {
    value_error(error.to_string())
}

/// `(wo, pdf, weight)` of [`Material::sample`].
type SampleArrays<'py> = (
    Bound<'py, PyArrayDyn<f32>>,
    Bound<'py, PyArrayDyn<f32>>,
    Bound<'py, PyArrayDyn<f32>>,
);

/// `(wo, pdf)` of [`Material::sample_spectral`].
type SpectralSampleArrays<'py> = (Bound<'py, PyArrayDyn<f32>>, Bound<'py, PyArrayDyn<f32>>);

/// Material(*, beta, p, eta, sigma_s=None, b=None, c=None, base=None,
/// albedo=None, lambertian=None, masking=None, sigma_rel=None, colour=None,
/// halo_weight=None, multiple_scattering=None, rgb_mode=None): the RGB two-scale model of one material, built once
/// (the runtime bakes its per-material tables) and evaluated over arrays of
/// directions.
///
/// `beta`, `p`: the EPD's roughness and shape; `sigma_s`, `b` (µm), `c`: the
/// nanoscale roughness's RMS height, lateral scale and exponent; `eta`: three
/// (n, k) pairs, red, green, blue at `RGB_WAVELENGTHS` (0.645, 0.526,
/// 0.444 µm), or the index over the spectrum `(lam, n, k)`, three 1-D arrays
/// of one length (λ in µm, increasing; linear in 1/λ between rows; three
/// arrays of two values are read as (n, k) pairs); `rgb_mode`: one of
/// `RGB_MODES`, "paper-wavelengths" (ρ at `RGB_WAVELENGTHS`; the default for
/// (n, k) pairs) or "integrated" (the integral over the spectrum,
/// docs/model.md §2.12; the default for a spectrum; needs a spectrum, or one
/// (n, k) for every channel); `base`: one of `BASES`;
/// `albedo`: the base layer's, in [0, 1]
/// (plastic or subsurface only); `lambertian`: the weight k_d in [0, 1] of a
/// Lambertian term. A keyword left out (None) takes the runtime's default:
/// sigma_s = 0 (no diffraction), b = 1 µm, c = 2, base "conductor",
/// lambertian = 0, and for the options (names in `OPTIONS`) the paper's
/// model. The keywords are the keys of a material file's `[material]`
/// table (`from_toml`), read by the same code. Parameters outside their
/// domain raise `ValueError` with the runtime's message.
#[pyclass(frozen, module = "twoscale")]
struct Material {
    model: Box<RgbModel<'static, Box<ChannelBake>>>,
    material: twoscale::material::Material,
    options: Options,
    rgb_mode: RgbMode,
    /// The index over the spectrum (`MaterialDesc::spectral`): given, a
    /// preset's measured one, or the one index of every channel.
    spectral: Option<OwnedSpectralMaterial>,
    /// `spectral`'s model at any wavelength, built by the first `eval_spectral`.
    spectral_model: OnceLock<Box<BoxedSpectral<'static>>>,
    /// The preset's name, for a material `Material.preset` built (its repr).
    preset: Option<&'static str>,
}

impl Material {
    /// The model of `desc`, its bakes allocated zeroed on the heap and
    /// filled in place (`RgbModel::boxed`): built on any thread, 64 KiB of
    /// stack is enough (`tests/test_small_stack.py`).
    fn build(desc: &MaterialDesc<'_>) -> Self {
        Material {
            model: Box::new(RgbModel::boxed(&TABLES.brdf_tables(), desc)),
            material: desc.material,
            options: desc.options,
            rgb_mode: desc.rgb_mode,
            spectral: desc.spectral.as_ref().map(OwnedSpectralMaterial::new),
            spectral_model: OnceLock::new(),
            preset: None,
        }
    }

    /// The description the material was built from (rebuilding it gives
    /// the same model).
    fn desc(&self) -> MaterialDesc<'_> {
        MaterialDesc {
            material: self.material,
            spectral: self.spectral.as_ref().map(OwnedSpectralMaterial::get),
            options: self.options,
            rgb_mode: self.rgb_mode,
        }
    }

    /// `Material.preset(name, …)` with the options and `rgb_mode` that
    /// differ from the preset's defaults.
    fn preset_repr(&self, name: &str) -> String {
        let mut args = vec![format!("{name:?}")];
        let default = MaterialDesc::spectral(
            twoscale::materials::spectral(name).expect("a preset's name"),
            Options::default(),
            None,
        )
        .expect("every preset validates");
        let keys = self.desc().keys();
        for ((key, value), (_, default)) in keys.iter().zip(default.keys()) {
            if let desc::KeyValue::Name(v) = value
                && *value != default
            {
                args.push(format!("{key}={v:?}"));
            }
        }
        format!("twoscale.Material.preset({})", args.join(", "))
    }

    /// The model at any wavelength of `spectral` (this material's index over
    /// the spectrum), built by the first call.
    fn spectral_model(&self, spectral: &OwnedSpectralMaterial) -> &BoxedSpectral<'static> {
        self.spectral_model.get_or_init(|| {
            Box::new(Spectral::boxed(
                &TABLES.brdf_tables(),
                &spectral.get(),
                self.options,
            ))
        })
    }

    /// The rows of `arrays` (`(..., 3)`) and of `lam` (µm, `(...)`, as a
    /// third array of rows `[λ, λ, λ]`) broadcast together, and the model at
    /// any wavelength; `ValueError` (naming `method`) without an index over
    /// the spectrum or for `lam` outside the models' range.
    fn spectral_rows<'py>(
        &self,
        py: Python<'py>,
        method: &str,
        arrays: [(&str, &Bound<'py, PyAny>, Rows); 2],
        lam: &Bound<'py, PyAny>,
    ) -> PyResult<(Vectors<3>, &BoxedSpectral<'static>)> {
        let Some(spectral) = &self.spectral else {
            return Err(value_error(format!(
                "{method} needs an index over the spectrum: a preset, eta=(lam, n, k), or one (n, k) for every channel"
            )));
        };
        // lam as a (..., 3) array, to broadcast with the directions.
        let np = PyModule::import(py, "numpy")?;
        let lam = np.call_method1("asarray", (lam, "float64")).map_err(|_| {
            value_error(format!(
                "lam must be an array of numbers (µm), got {}",
                describe(lam)
            ))
        })?;
        let lam3 = np.call_method1(
            "repeat",
            (np.call_method1("expand_dims", (lam, -1))?, 3, -1),
        )?;
        let [a, b] = arrays;
        let v = vectors([a, b, ("lam", &lam3, Rows::Any)])?;
        let (lo, hi) = (
            SPECTRAL_WAVELENGTHS[0],
            SPECTRAL_WAVELENGTHS[SPECTRAL_WAVELENGTHS.len() - 1],
        );
        if let Some(k) = v.rows[2].iter().position(|l| !(l[0] >= lo && l[0] <= hi)) {
            return Err(value_error(format!(
                "lam must be in [{lo}, {hi}] µm, got {} at row {k}",
                v.rows[2][k][0]
            )));
        }
        Ok((v, self.spectral_model(spectral)))
    }

    /// `f(model, wi, wo, λ)` on every row of `wi`, `wo` and `lam` broadcast
    /// together ([`Material::spectral_rows`]), as a float32 array.
    fn spectral_pairs<'py>(
        &self,
        py: Python<'py>,
        method: &str,
        wi: &Bound<'py, PyAny>,
        wo: &Bound<'py, PyAny>,
        lam: &Bound<'py, PyAny>,
        f: impl Fn(&BoxedSpectral<'static>, [f32; 3], [f32; 3], f32) -> f32 + Sync,
    ) -> PyResult<Bound<'py, PyArrayDyn<f32>>> {
        let (v, model) = self.spectral_rows(
            py,
            method,
            [("wi", wi, Rows::Directions), ("wo", wo, Rows::Directions)],
            lam,
        )?;
        let [wi, wo, lam] = &v.rows;
        let values = py.detach(|| rows(v.len(), |k| f(model, wi[k], wo[k], lam[k][0])));
        Ok(shaped(py, &v.shape, values))
    }
}

/// `values` as a Python list of numbers (`desc::number`).
fn py_list(values: impl Iterator<Item = f32>) -> String {
    let items: Vec<String> = values.map(desc::number).collect();
    format!("[{}]", items.join(", "))
}

/// `Material(eta=…)`: three (n, k) pairs, or `(lam, n, k)` arrays as rows.
enum EtaArgument {
    Channels(Vec<[f32; 2]>),
    Spectrum(Vec<[f32; 3]>),
}

impl EtaArgument {
    fn read(eta: &Bound<'_, PyAny>) -> PyResult<Self> {
        if let Ok(pairs) = eta.extract::<Vec<[f32; 2]>>() {
            return Ok(EtaArgument::Channels(pairs));
        }
        // Any sequence of three 1-D sequences: a tuple, a list, a (3, N) array.
        let arrays = eta
            .extract::<Vec<Vec<f32>>>()
            .ok()
            .filter(|a| a.len() == 3)
            .ok_or_else(|| {
                value_error(format!(
                    "eta must be three (n, k) pairs or (lam, n, k), three 1-D arrays, got {}",
                    describe(eta)
                ))
            })?;
        desc::spectrum_rows(&arrays[0], &arrays[1], &arrays[2])
            .map(EtaArgument::Spectrum)
            .map_err(|e| value_error(e.to_string()))
    }

    fn eta(&self) -> Eta<'_> {
        match self {
            EtaArgument::Channels(pairs) => Eta::Channels(pairs),
            EtaArgument::Spectrum(rows) => Eta::Spectrum(rows),
        }
    }
}

#[pymethods]
impl Material {
    #[new]
    #[pyo3(signature = (*, beta, p, eta, sigma_s=None, b=None, c=None, base=None,
        albedo=None, lambertian=None, masking=None, sigma_rel=None, colour=None,
        halo_weight=None, multiple_scattering=None, rgb_mode=None))]
    #[allow(clippy::too_many_arguments)]
    fn new(
        beta: f32,
        p: f32,
        eta: &Bound<'_, PyAny>, // (n, k) sequences (tuples, or lists from TOML), or (lam, n, k)
        sigma_s: Option<f32>,
        b: Option<f32>,
        c: Option<f32>,
        base: Option<&str>,
        albedo: Option<f32>,
        lambertian: Option<f32>,
        masking: Option<&str>,
        sigma_rel: Option<&str>,
        colour: Option<&str>,
        halo_weight: Option<&str>,
        multiple_scattering: Option<&str>,
        rgb_mode: Option<&str>,
    ) -> PyResult<Self> {
        // The keywords are a material description's keys (`twoscale::io::desc`):
        // one reading, with its defaults and messages, for Python and TOML.
        let eta = EtaArgument::read(eta)?;
        let keywords = Keywords {
            beta,
            p,
            eta: eta.eta(),
            sigma_s,
            b,
            c,
            base,
            albedo,
            lambertian,
            masking,
            sigma_rel,
            colour,
            halo_weight,
            multiple_scattering,
            rgb_mode,
        };
        let desc = keywords
            .material()
            .map_err(|e| value_error(e.to_string()))?;
        Ok(Material::build(&desc))
    }

    /// from_toml(path): the material of a material file (TOML: a
    /// `[material]` table whose keys are this class's keywords, and an
    /// optional `[metrics]` table, not read), as `python -m twoscale.fit`
    /// writes it. Read by the runtime (`twoscale::io::desc`), as the C API and
    /// the generator read it: a refused file raises `ValueError` (`OSError`
    /// if it cannot be read) with their message, which starts with the path.
    #[staticmethod]
    fn from_toml(path: std::path::PathBuf) -> PyResult<Self> {
        MaterialDesc::from_toml_file(path)
            .map(|d| Material::build(&d.get()))
            .map_err(desc_error)
    }

    /// from_toml_string(text): `from_toml` of the text of a material file.
    #[staticmethod]
    fn from_toml_string(text: &str) -> PyResult<Self> {
        MaterialDesc::from_toml_str(text)
            .map(|d| Material::build(&d.get()))
            .map_err(desc_error)
    }

    /// preset(name, *, masking=None, sigma_rel=None, colour=None,
    /// halo_weight=None, multiple_scattering=None, rgb_mode=None): the shipped
    /// preset `name` (`Material.presets()` lists them; its measured index
    /// over the spectrum) with the given options (names as in `OPTIONS` and
    /// `RGB_MODES`; None: the runtime's default: the paper's model, and the
    /// RGB by integration over the spectrum; `rgb_mode="paper-wavelengths"`
    /// reproduces HP15/HP17's RGB).
    #[staticmethod]
    #[pyo3(signature = (name, *, masking=None, sigma_rel=None, colour=None, halo_weight=None,
        multiple_scattering=None, rgb_mode=None))]
    fn preset(
        name: &str,
        masking: Option<&str>,
        sigma_rel: Option<&str>,
        colour: Option<&str>,
        halo_weight: Option<&str>,
        multiple_scattering: Option<&str>,
        rgb_mode: Option<&str>,
    ) -> PyResult<Self> {
        let spectral = twoscale::materials::spectral(name)
            .ok_or_else(|| value_error(twoscale::UnknownMaterial { name }.to_string()))?;
        let options = options(masking, sigma_rel, colour, halo_weight, multiple_scattering)?;
        let rgb_mode = validate::named_or_none(rgb_mode).map_err(|e| value_error(e.to_string()))?;
        let desc = MaterialDesc::spectral(spectral, options, rgb_mode)
            .map_err(|e| value_error(e.to_string()))?;
        let preset = twoscale::materials::PRESETS
            .iter()
            .map(|(n, _)| *n)
            .find(|n| *n == name);
        Ok(Material {
            preset,
            ..Material::build(&desc)
        })
    }

    /// presets(): the names of the shipped presets, for `Material.preset`.
    #[staticmethod]
    fn presets() -> Vec<&'static str> {
        twoscale::materials::PRESETS
            .iter()
            .map(|(n, _)| *n)
            .collect()
    }

    /// eval(wi, wo): ρ(wi, wo) per RGB channel in sr⁻¹, float32 of shape
    /// `(..., 3)`: red, green, blue at `RGB_WAVELENGTHS`, or linear sRGB by
    /// integration over the spectrum (`rgb_mode="integrated"`).
    ///
    /// `wi` (towards the light) and `wo` (towards the viewer) are unit
    /// vectors in the local frame (normal +z), arrays of shape `(..., 3)`
    /// that broadcast together as NumPy's do; a single direction `(3,)`
    /// gives `(3,)`. 0 where either is below the horizon. A direction with
    /// a NaN or infinite component raises `ValueError` naming the argument
    /// and the entry (as the C API refuses it); so do the other methods.
    fn eval<'py>(
        &self,
        py: Python<'py>,
        wi: &Bound<'py, PyAny>,
        wo: &Bound<'py, PyAny>,
    ) -> PyResult<Bound<'py, PyArrayDyn<f32>>> {
        let v = vectors([("wi", wi, Rows::Directions), ("wo", wo, Rows::Directions)])?;
        let ([wi, wo], model) = (&v.rows, &*self.model);
        let values = py.detach(|| rows(v.len(), |k| Bxdf::eval(model, wi[k], wo[k])));
        Ok(shaped_vectors(py, &v.shape, values))
    }

    /// eval_spectral(wi, wo, lam): ρ(wi, wo) in sr⁻¹ at the wavelength `lam`
    /// (µm, in [0.36, 0.83]), float32 of the broadcast leading shape of `wi`,
    /// `wo` (`(..., 3)`) and `lam` (`(...)`), from one construction that
    /// serves every wavelength (`twoscale::brdf::Spectral`, docs/model.md
    /// §2.12; built by the first call). For presets (their measured index),
    /// materials given `eta=(lam, n, k)` and those whose `eta` is one (n, k)
    /// for every channel; other materials, and `lam` outside the range,
    /// raise `ValueError`.
    fn eval_spectral<'py>(
        &self,
        py: Python<'py>,
        wi: &Bound<'py, PyAny>,
        wo: &Bound<'py, PyAny>,
        lam: &Bound<'py, PyAny>,
    ) -> PyResult<Bound<'py, PyArrayDyn<f32>>> {
        self.spectral_pairs(py, "eval_spectral", wi, wo, lam, Spectral::eval)
    }

    /// pdf_spectral(wi, wo, lam): the density (sr⁻¹) of `sample_spectral(wi,
    /// ·, lam)` at `wo`: that of the nearest of the sampler models, every
    /// other one (`Spectral::pdf`). Arguments and errors as `eval_spectral`'s.
    fn pdf_spectral<'py>(
        &self,
        py: Python<'py>,
        wi: &Bound<'py, PyAny>,
        wo: &Bound<'py, PyAny>,
        lam: &Bound<'py, PyAny>,
    ) -> PyResult<Bound<'py, PyArrayDyn<f32>>> {
        self.spectral_pairs(py, "pdf_spectral", wi, wo, lam, Spectral::pdf)
    }

    /// sample_spectral(wi, u, lam): `(wo, pdf)`, a direction drawn for the
    /// wavelength `lam` (µm) from three uniforms `u` in [0, 1) (`Spectral::sample`: the
    /// sampler of the model nearest `lam`) and its density; `(0, 0, 0)` and 0
    /// where none is drawn. Arguments and errors as `eval_spectral`'s.
    fn sample_spectral<'py>(
        &self,
        py: Python<'py>,
        wi: &Bound<'py, PyAny>,
        u: &Bound<'py, PyAny>,
        lam: &Bound<'py, PyAny>,
    ) -> PyResult<SpectralSampleArrays<'py>> {
        let (v, model) = self.spectral_rows(
            py,
            "sample_spectral",
            [("wi", wi, Rows::Directions), ("u", u, Rows::Uniforms)],
            lam,
        )?;
        let [wi, u, lam] = &v.rows;
        let samples = py.detach(|| {
            rows(v.len(), |k| match model.sample(wi[k], u[k], lam[k][0]) {
                Some(s) => (s.o, s.pdf),
                None => ([0.0; 3], 0.0),
            })
        });
        let (dirs, pdf): (Vec<_>, Vec<_>) = samples.into_iter().unzip();
        Ok((
            shaped_vectors(py, &v.shape, dirs),
            shaped(py, &v.shape, pdf),
        ))
    }

    /// pdf(wi, wo): the solid-angle density (sr⁻¹) of `sample(wi, ·)` at
    /// `wo`, float32 of the broadcast leading shape of `wi` and `wo` (both
    /// `(..., 3)`; a 0-d array for two single directions).
    fn pdf<'py>(
        &self,
        py: Python<'py>,
        wi: &Bound<'py, PyAny>,
        wo: &Bound<'py, PyAny>,
    ) -> PyResult<Bound<'py, PyArrayDyn<f32>>> {
        let v = vectors([("wi", wi, Rows::Directions), ("wo", wo, Rows::Directions)])?;
        let ([wi, wo], model) = (&v.rows, &*self.model);
        let values = py.detach(|| rows(v.len(), |k| Bxdf::pdf(model, wi[k], wo[k])));
        Ok(shaped(py, &v.shape, values))
    }

    /// sample(wi, u) -> (wo, pdf, weight): samples `wo` given `wi` (towards
    /// the light) with three uniform numbers in [0, 1) per row `u`; `wi` and
    /// `u` are `(..., 3)` and broadcast together. A row of `u` with a
    /// component outside [0, 1) (or not finite) raises `ValueError` naming
    /// the entry, as the C API's `ts_sample_rgb` refuses it.
    ///
    /// Returns `wo` `(..., 3)`, its density `pdf` `(...)` in sr⁻¹ and
    /// `weight = ρ(wi, wo) cos θo / pdf` `(..., 3)`, float32; rows where
    /// sampling fails (below the horizon) are all zeros.
    fn sample<'py>(
        &self,
        py: Python<'py>,
        wi: &Bound<'py, PyAny>,
        u: &Bound<'py, PyAny>,
    ) -> PyResult<SampleArrays<'py>> {
        let v = vectors([("wi", wi, Rows::Directions), ("u", u, Rows::Uniforms)])?;
        let ([wi, u], model) = (&v.rows, &*self.model);
        let samples = py.detach(|| {
            rows(v.len(), |k| match Bxdf::sample(model, wi[k], u[k]) {
                Some(s) => (s.o, s.pdf, s.value.map(|x| x * s.o[2] / s.pdf)),
                None => ([0.0; 3], 0.0, [0.0; 3]),
            })
        });
        let n = samples.len();
        let (mut dirs, mut pdf, mut weight) = (
            Vec::with_capacity(n),
            Vec::with_capacity(n),
            Vec::with_capacity(n),
        );
        for (o, p, w) in samples {
            dirs.push(o);
            pdf.push(p);
            weight.push(w);
        }
        Ok((
            shaped_vectors(py, &v.shape, dirs),
            shaped(py, &v.shape, pdf),
            shaped_vectors(py, &v.shape, weight),
        ))
    }

    /// eval_reference(wi, wo): the f64 reference ρ(wi, wo) per RGB channel
    /// at the paper's wavelengths whatever `rgb_mode` is (compare it with a
    /// material built with `rgb_mode="paper-wavelengths"`) in sr⁻¹ (exact
    /// Λ, σrel and C; the reference crate's `brdf`), float64 of
    /// shape `(..., 3)`, for conductors without a Lambertian term. Arguments
    /// as `eval`'s. Costs 1–30 ms per row and channel (on all cores).
    fn eval_reference<'py>(
        &self,
        py: Python<'py>,
        wi: &Bound<'py, PyAny>,
        wo: &Bound<'py, PyAny>,
    ) -> PyResult<Bound<'py, PyArrayDyn<f64>>> {
        let options = self.options;
        let params = ref_brdf::Params::rgb_with(&self.material, &options)
            .map_err(|e| value_error(e.to_string()))?;
        let compensation = py
            .detach(|| ref_brdf::Compensation::rgb(&params, &options))
            .map_err(|e| value_error(e.to_string()))?;
        let v = vectors([("wi", wi, Rows::Directions), ("wo", wo, Rows::Directions)])?;
        let [wi, wo] = &v.rows;
        let values = py.detach(|| {
            (0..v.len() * 3)
                .into_par_iter()
                .map(|j| {
                    let (k, ch) = (j / 3, j % 3);
                    let f64s = |v: [f32; 3]| v.map(f64::from);
                    let (i, o) = (f64s(wi[k]), f64s(wo[k]));
                    let multiple = match &compensation {
                        Some(lobes) => lobes[ch].value(i, o),
                        None => Ok(0.0),
                    };
                    ref_brdf::two_scale(&params[ch], i, o, &options)
                        .and_then(|v| Ok(v.total() + multiple?))
                        .map_err(|e| format!("row {k}: {e}"))
                })
                .collect::<Result<Vec<f64>, String>>()
        });
        let mut full = v.shape.clone();
        full.push(3);
        Ok(shaped(py, &full, values.map_err(value_error)?))
    }

    /// bakes(): the model's per-channel constants and bakes as the runtime
    /// built them, for ports of `eval` and `pdf` (`twoscale.drjit`):
    /// a list of three dicts (red, green, blue) mapping names to float
    /// scalars, str (the base layer's kind and the options, by name) and
    /// float32 or float64 arrays, and `columns` to a dict from an array's
    /// name to the names of its last axis (the names and layouts of
    /// `TwoScale::visit_bakes` and `runtime/src/bake/`; not a stable
    /// interface: read by name). For `rgb_mode="paper-wavelengths"` only.
    fn bakes<'py>(&self, py: Python<'py>) -> PyResult<Vec<Bound<'py, PyDict>>> {
        let RgbModel::PaperWavelengths(model) = &*self.model else {
            return Err(value_error(
                "bakes() gives the model at the paper's wavelengths: build the material with rgb_mode='paper-wavelengths'",
            ));
        };
        model
            .channels
            .iter()
            .map(|channel| bake_dict(py, |v| channel.visit_bakes(v)))
            .collect()
    }

    /// integrated_bakes(): the colour weights and bakes of the integrated
    /// RGB model (`rgb_mode="integrated"`), for ports of `eval`, `pdf` and
    /// `sample` (`twoscale.drjit`): a dict of `wavelengths` (the 8
    /// models', µm), `surface` (`[nodes, 8, 3]`: the surface lobes' weights
    /// over `√cos θd`), `plain` (`[8, 3]`), `sampler_nodes` (the 3 models the
    /// sampler mixes) and `models`, a list of 8 dicts as `bakes()` gives
    /// them (not a stable interface). For `rgb_mode="integrated"` only.
    fn integrated_bakes<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        let RgbModel::Integrated(model) = &*self.model else {
            return Err(value_error(
                "integrated_bakes() gives the integrated RGB model: build the material with rgb_mode='integrated'",
            ));
        };
        let dict = bake_dict(py, |v| model.visit_colour(v))?;
        with_models(py, dict, model.nodes())
    }

    /// spectral_bakes(): the constants and bakes of the model at any
    /// wavelength (`eval_spectral`'s), for ports of it
    /// (`twoscale.drjit`): a dict of `wavelengths` (the 19 models', µm),
    /// `fresnel` (F over λ every `eta_step` µm from `eta_first` and √cos θ),
    /// `eta` (n, k at those λ), `white`, `models`
    /// (one dict with the names of `bakes()`: a quantity equal in the 19
    /// models once, as `bakes()` gives it; the others stacked along a
    /// leading node axis of 19, scalars as float64 arrays of 19) and
    /// `per_node` (the names of the stacked ones). Not a stable interface.
    /// Raises `ValueError` as `eval_spectral` does for a material without
    /// an index over the spectrum.
    fn spectral_bakes<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        let Some(spectral) = &self.spectral else {
            return Err(value_error(
                "spectral_bakes needs an index over the spectrum: a preset, eta=(lam, n, k), or one (n, k) for every channel",
            ));
        };
        let model = self.spectral_model(spectral);
        let dict = bake_dict(py, |v| model.visit_index(v))?;
        let nodes: Vec<Collected> = model
            .nodes()
            .iter()
            .map(|node| {
                let mut c = Collected::default();
                node.visit_bakes(&mut c);
                c
            })
            .collect();
        let (models, per_node) = stacked(py, &nodes)?;
        dict.set_item("models", models)?;
        dict.set_item("per_node", per_node)?;
        Ok(dict)
    }

    /// with_layer(*, albedo=None, lambertian=None): this material with the
    /// base layer's albedo and/or the Lambertian k_d replaced (the same
    /// geometry, index, spectrum and options), rebuilt and re-baked; refused
    /// as the constructor refuses them (`ValueError`). For the Mitsuba
    /// plugin's `parameters_changed`.
    #[pyo3(signature = (*, albedo=None, lambertian=None))]
    fn with_layer(&self, albedo: Option<f32>, lambertian: Option<f32>) -> PyResult<Self> {
        let mut layer = self.material.layer;
        if let Some(albedo) = albedo {
            layer.base = validate::base_layer(layer.base.kind(), Some(albedo))
                .map_err(|e| value_error(e.to_string()))?;
        }
        if let Some(lambertian) = lambertian {
            layer.lambertian = lambertian;
        }
        layer.validate().map_err(invalid)?;
        let desc = match &self.spectral {
            Some(spectral) => MaterialDesc::spectral(
                SpectralMaterial {
                    layer,
                    ..spectral.get()
                },
                self.options,
                Some(self.rgb_mode),
            ),
            None => MaterialDesc::rgb(
                twoscale::material::Material {
                    layer,
                    ..self.material
                },
                self.options,
                Some(self.rgb_mode),
            ),
        }
        .map_err(|e| value_error(e.to_string()))?;
        Ok(Material::build(&desc))
    }

    /// β, the EPD's roughness (slope scale), dimensionless.
    #[getter]
    fn beta(&self) -> f32 {
        self.material.layer.surface.beta
    }
    /// p, the EPD's shape exponent (1: Beckmann), dimensionless.
    #[getter]
    fn p(&self) -> f32 {
        self.material.layer.surface.p
    }
    /// σs, the RMS height of the nanoscale roughness, in µm.
    #[getter]
    fn sigma_s(&self) -> f32 {
        self.material.layer.surface.sigma_s
    }
    /// b, the K-correlation spectrum's lateral length scale, in µm.
    #[getter]
    fn b(&self) -> f32 {
        self.material.layer.surface.b
    }
    /// c, the K-correlation spectrum's exponent (> 1), dimensionless.
    #[getter]
    fn c(&self) -> f32 {
        self.material.layer.surface.c
    }
    /// The complex indices of refraction as three (n, k) pairs: red, green,
    /// blue (at `RGB_WAVELENGTHS`).
    #[getter]
    fn eta(&self) -> Vec<(f32, f32)> {
        self.material.eta_rgb.iter().map(|e| (e.re, e.im)).collect()
    }
    /// The base layer: "conductor", "plastic" or "subsurface".
    #[getter]
    fn base(&self) -> &'static str {
        self.material.layer.base.kind().name()
    }
    /// The base layer's albedo in [0, 1] (None for a conductor).
    #[getter]
    fn albedo(&self) -> Option<f32> {
        match self.material.layer.base {
            BaseLayer::Conductor => None,
            BaseLayer::Plastic { albedo } | BaseLayer::Subsurface { albedo } => Some(albedo),
        }
    }
    /// The weight k_d in [0, 1] of the Lambertian term.
    #[getter]
    fn lambertian(&self) -> f32 {
        self.material.layer.lambertian
    }
    /// The options as a dict of keyword names ("colour", "halo_weight",
    /// "masking", "multiple_scattering", "sigma_rel") to their values.
    #[getter]
    fn options(&self) -> BTreeMap<&'static str, &'static str> {
        let o = self.options;
        BTreeMap::from([
            (Masking::OPTION, o.masking.name()),
            (SigmaRelMode::OPTION, o.sigma_rel.name()),
            (ColourTerms::OPTION, o.colour.name()),
            (HaloWeight::OPTION, o.halo_weight.name()),
            (MultipleScattering::OPTION, o.multiple_scattering.name()),
        ])
    }
    /// Which RGB `eval` gives: "paper-wavelengths" or "integrated" (`RGB_MODES`).
    #[getter]
    fn rgb_mode(&self) -> &'static str {
        self.rgb_mode.name()
    }

    /// to_toml(): the material file of this material: a `[material]` table
    /// of every keyword (numbers as the shortest decimals that read back to
    /// the same float32), which `from_toml_string` (and the C API and the
    /// generator) read back to the same model, bit for bit.
    fn to_toml(&self) -> String {
        self.desc().to_toml()
    }

    /// `twoscale.Material.preset(name, …)` for a preset (the options and
    /// `rgb_mode` that differ from its defaults), else
    /// `twoscale.Material(beta=…, …)` with every keyword (`eta` as the
    /// spectrum's `(lam, n, k)` lists when it was given over the spectrum):
    /// evaluated with `twoscale` imported, it rebuilds the same model, bit
    /// for bit.
    fn __repr__(&self) -> String {
        if let Some(name) = self.preset {
            return self.preset_repr(name);
        }
        let args: Vec<String> = self
            .desc()
            .keys()
            .into_iter()
            .map(|(key, value)| {
                let text = match value {
                    desc::KeyValue::Number(x) => desc::number(x),
                    desc::KeyValue::Name(name) => format!("{name:?}"),
                    desc::KeyValue::Pairs(pairs) => {
                        let items: Vec<String> = pairs
                            .iter()
                            .map(|[n, k]| format!("({}, {})", desc::number(*n), desc::number(*k)))
                            .collect();
                        format!("[{}]", items.join(", "))
                    }
                    desc::KeyValue::Spectrum(rows) => format!(
                        "({}, {}, {})",
                        py_list(rows.iter().map(|r| r[0])),
                        py_list(rows.iter().map(|r| r[1])),
                        py_list(rows.iter().map(|r| r[2])),
                    ),
                };
                format!("{key}={text}")
            })
            .collect();
        format!("twoscale.Material({})", args.join(", "))
    }
}

/// Columns of equal length as rows of `K` values.
fn columns<const K: usize>(
    names: [&str; K],
    cols: [PyReadonlyArray1<'_, f64>; K],
) -> PyResult<Vec<[f64; K]>> {
    let views = cols.each_ref().map(|c| c.as_array());
    let n = views[0].len();
    for (name, view) in names.iter().zip(&views) {
        same_rows((names[0], n), (name, view.len()))?;
    }
    Ok((0..n).map(|k| views.each_ref().map(|v| v[k])).collect())
}

/// `dict` with `models`: each of `nodes`' bakes as `bakes()` gives them.
fn with_models<'py, B: std::borrow::Borrow<ChannelBake>>(
    py: Python<'py>,
    dict: Bound<'py, PyDict>,
    nodes: &[twoscale::TwoScale<'_, B>],
) -> PyResult<Bound<'py, PyDict>> {
    let models = nodes
        .iter()
        .map(|node| bake_dict(py, |v| node.visit_bakes(v)))
        .collect::<PyResult<Vec<_>>>()?;
    dict.set_item("models", models)?;
    Ok(dict)
}

/// The dict that `visit` fills through a [`DictVisitor`].
fn bake_dict<'py>(
    py: Python<'py>,
    visit: impl FnOnce(&mut dyn BakeVisitor),
) -> PyResult<Bound<'py, PyDict>> {
    let mut visitor = DictVisitor {
        dict: PyDict::new(py),
        columns: PyDict::new(py),
        error: None,
    };
    visit(&mut visitor);
    if let Some(e) = visitor.error {
        return Err(e);
    }
    if !visitor.columns.is_empty() {
        visitor.dict.set_item(COLUMNS, visitor.columns)?;
    }
    Ok(visitor.dict)
}

/// The key of a bake dict's column names: a dict from an array's name to
/// the names of its last axis (`BakeVisitor::columns`).
const COLUMNS: &str = "columns";

/// Collects `TwoScale::visit_bakes` into a dict (the first error is kept).
struct DictVisitor<'py> {
    dict: Bound<'py, PyDict>,
    columns: Bound<'py, PyDict>,
    error: Option<PyErr>,
}

impl DictVisitor<'_> {
    fn keep(&mut self, result: PyResult<()>) {
        if let (Err(e), None) = (result, &self.error) {
            self.error = Some(e);
        }
    }
}

impl BakeVisitor for DictVisitor<'_> {
    fn array_u8(&mut self, name: &'static str, shape: &[usize], data: &[u8]) {
        let values: Vec<f32> = data.iter().map(|&x| f32::from(x)).collect();
        self.array(name, shape, &values);
    }

    fn array(&mut self, name: &'static str, shape: &[usize], data: &[f32]) {
        let array = shaped(self.dict.py(), shape, data.to_vec());
        let result = self.dict.set_item(name, array);
        self.keep(result);
    }

    fn array_f64(&mut self, name: &'static str, shape: &[usize], data: &[f64]) {
        let array = shaped(self.dict.py(), shape, data.to_vec());
        let result = self.dict.set_item(name, array);
        self.keep(result);
    }

    fn scalar(&mut self, name: &'static str, value: f64) {
        let result = self.dict.set_item(name, value);
        self.keep(result);
    }

    fn columns(&mut self, name: &'static str, columns: &'static [&'static str]) {
        let result = self.columns.set_item(name, columns);
        self.keep(result);
    }

    fn named(&mut self, name: &'static str, value: &'static str) {
        let result = self.dict.set_item(name, value);
        self.keep(result);
    }
}

/// One quantity as `TwoScale::visit_bakes` hands it.
#[derive(PartialEq)]
enum Quantity {
    F32(Vec<usize>, Vec<f32>),
    F64(Vec<usize>, Vec<f64>),
    Scalar(f64),
    Named(&'static str),
    Columns(&'static [&'static str]),
}

/// One model's quantities in the order visited.
#[derive(Default)]
struct Collected(Vec<(&'static str, Quantity)>);

impl BakeVisitor for Collected {
    fn array_u8(&mut self, name: &'static str, shape: &[usize], data: &[u8]) {
        let values: Vec<f32> = data.iter().map(|&x| f32::from(x)).collect();
        self.array(name, shape, &values);
    }

    fn array(&mut self, name: &'static str, shape: &[usize], data: &[f32]) {
        self.0
            .push((name, Quantity::F32(shape.to_vec(), data.to_vec())));
    }

    fn array_f64(&mut self, name: &'static str, shape: &[usize], data: &[f64]) {
        self.0
            .push((name, Quantity::F64(shape.to_vec(), data.to_vec())));
    }

    fn scalar(&mut self, name: &'static str, value: f64) {
        self.0.push((name, Quantity::Scalar(value)));
    }

    fn columns(&mut self, name: &'static str, columns: &'static [&'static str]) {
        self.0.push((name, Quantity::Columns(columns)));
    }

    fn named(&mut self, name: &'static str, value: &'static str) {
        self.0.push((name, Quantity::Named(value)));
    }
}

/// The models' quantities in one dict (`spectral_bakes`' `models`): one
/// equal in every model once, the others stacked along a leading node axis
/// (scalars as an f64 array); and the names of the stacked ones.
fn stacked<'py>(
    py: Python<'py>,
    nodes: &[Collected],
) -> PyResult<(Bound<'py, PyDict>, Vec<&'static str>)> {
    let dict = PyDict::new(py);
    let columns = PyDict::new(py);
    let mut per_node = Vec::new();
    let n = nodes.len();
    for (j, (name, first)) in nodes[0].0.iter().enumerate() {
        let all = || nodes.iter().map(move |node| &node.0[j].1);
        if all().all(|q| q == first) {
            match first {
                Quantity::F32(shape, data) => {
                    dict.set_item(name, shaped(py, shape, data.clone()))?
                }
                Quantity::F64(shape, data) => {
                    dict.set_item(name, shaped(py, shape, data.clone()))?
                }
                Quantity::Scalar(value) => dict.set_item(name, *value)?,
                Quantity::Named(value) => dict.set_item(name, *value)?,
                Quantity::Columns(names) => columns.set_item(name, *names)?,
            }
            continue;
        }
        per_node.push(*name);
        let full = |shape: &[usize]| [&[n][..], shape].concat();
        match first {
            Quantity::F32(shape, _) => {
                let data = all().flat_map(|q| match q {
                    Quantity::F32(_, d) => d.clone(),
                    _ => unreachable!("every model visits the same quantities"),
                });
                dict.set_item(name, shaped(py, &full(shape), data.collect()))?;
            }
            Quantity::F64(shape, _) => {
                let data = all().flat_map(|q| match q {
                    Quantity::F64(_, d) => d.clone(),
                    _ => unreachable!("every model visits the same quantities"),
                });
                dict.set_item(name, shaped(py, &full(shape), data.collect()))?;
            }
            Quantity::Scalar(_) => {
                let data = all().map(|q| match q {
                    Quantity::Scalar(v) => *v,
                    _ => unreachable!("every model visits the same quantities"),
                });
                dict.set_item(name, shaped(py, &[n], data.collect()))?;
            }
            Quantity::Named(_) => {
                let names = all().map(|q| match q {
                    Quantity::Named(v) => *v,
                    _ => unreachable!("every model visits the same quantities"),
                });
                dict.set_item(name, names.collect::<Vec<_>>())?;
            }
            Quantity::Columns(_) => unreachable!("a bake's columns are its type's"),
        }
    }
    if !columns.is_empty() {
        dict.set_item(COLUMNS, columns)?;
    }
    Ok((dict, per_node))
}

/// Evaluates `f` on every row without the GIL; the first failing row's error
/// becomes a `ValueError`.
fn evaluate<'py, const K: usize>(
    py: Python<'py>,
    rows_in: Vec<[f64; K]>,
    parallel: bool,
    f: impl Fn([f64; K]) -> Result<f64, String> + Sync,
) -> PyResult<Bound<'py, PyArray1<f64>>> {
    let values = evaluate_rows(py, rows_in, parallel, f)?;
    Ok(Array1::from_vec(values).into_pyarray(py))
}

/// [`evaluate`] as a vector.
fn evaluate_rows<const K: usize>(
    py: Python<'_>,
    rows_in: Vec<[f64; K]>,
    parallel: bool,
    f: impl Fn([f64; K]) -> Result<f64, String> + Sync,
) -> PyResult<Vec<f64>> {
    let out = py.detach(|| {
        let row = |(k, x): (usize, &[f64; K])| f(*x).map_err(|e| format!("row {k}: {e}"));
        if parallel || rows_in.len() >= PARALLEL_ROWS {
            rows_in.par_iter().enumerate().map(row).collect()
        } else {
            rows_in
                .iter()
                .enumerate()
                .map(row)
                .collect::<Result<Vec<f64>, String>>()
        }
    });
    out.map_err(value_error)
}

/// `Ok(())` unless `clamp` is false and `check` refuses the row.
fn in_domain(clamp: bool, check: impl FnOnce() -> Result<(), Invalid>) -> Result<(), String> {
    if clamp {
        Ok(())
    } else {
        check().map_err(|e| e.to_string())
    }
}

/// g1(p, a, *, reference, clamp=False): G1 of the EPD at shape `p` and
/// `a = β tan θ` (HP17 36–38), both dimensionless, as float64 columns of
/// equal length: table T1, or the f64 reference (Λ by quadrature) with
/// `reference=True`. A row outside T1's domain raises `ValueError`
/// (`SmithG1Table::check`) unless `clamp=True`.
#[pyfunction]
#[pyo3(signature = (p, a, *, reference, clamp=false))]
fn g1<'py>(
    py: Python<'py>,
    p: PyReadonlyArray1<'py, f64>,
    a: PyReadonlyArray1<'py, f64>,
    reference: bool,
    clamp: bool,
) -> PyResult<Bound<'py, PyArray1<f64>>> {
    let rows_in = columns(["p", "a"], [p, a])?;
    if reference {
        return evaluate(py, rows_in, true, |[p, a]| {
            ref_epd::g1(p, a).map_err(|e| e.to_string())
        });
    }
    let t = TABLES.smith;
    evaluate(py, rows_in, false, |[p, a]| {
        let (p, a) = (p as f32, a as f32);
        in_domain(clamp, || t.check(p, a))?;
        Ok(t.g1(p, a).into())
    })
}

/// sigma_ratio(theta_i, big_b, c, *, reference, clamp=False): σrel/σs at
/// incidence `theta_i` (radians), `B = b/λ` and K-correlation exponent `c`
/// (HP17 19), as float64 columns of equal length: table T2, or the f64
/// reference (quadrature of the spectrum) with `reference=True`. A row
/// outside T2's domain raises `ValueError` (`SigmaRatioTable::check`, on
/// cos θi) unless `clamp=True`.
#[pyfunction]
#[pyo3(signature = (theta_i, big_b, c, *, reference, clamp=false))]
fn sigma_ratio<'py>(
    py: Python<'py>,
    theta_i: PyReadonlyArray1<'py, f64>,
    big_b: PyReadonlyArray1<'py, f64>,
    c: PyReadonlyArray1<'py, f64>,
    reference: bool,
    clamp: bool,
) -> PyResult<Bound<'py, PyArray1<f64>>> {
    let rows_in = columns(["theta_i", "B", "c"], [theta_i, big_b, c])?;
    if reference {
        return evaluate(py, rows_in, true, |[th, bb, c]| {
            ref_kcorr::sigma_ratio(th, bb, c).map_err(|e| e.to_string())
        });
    }
    let t = TABLES.sigma_ratio;
    evaluate(py, rows_in, false, |[th, bb, c]| {
        // T2's axis is cos θi, checked on the cosine of the angle as given
        // (f64: θi = π/2 is inside, although cos of its f32 is -4.4e-8), the
        // angle named too.
        let (cos_given, bb, c) = (th.cos() as f32, bb as f32, c as f32);
        if !clamp {
            t.check(cos_given, bb, c).map_err(|e| match e.name {
                "cos_theta_i" => format!("theta_i = {}: {e}", domain::Shortest(th)),
                _ => e.to_string(),
            })?;
        }
        Ok(t.sigma_ratio(th as f32, bb, c).into())
    })
}

/// The sources of C that [`conv`] reads.
const CONV_SOURCES: [&str; 3] = ["table", "fit", "reference"];

/// conv(theta_h, u, c, beta, p, *, source, clamp=False): the convolution
/// `C(θh; u, c, β, p)` (HP17 40), `theta_h` in radians and the others
/// dimensionless, as float64 columns of equal length, from `source`:
/// "table" (T3b), "fit" (the paper's fitted form, T3a) or "reference" (the
/// f64 direct 2-D quadrature). A row outside T3's domain raises `ValueError`
/// (`ConvTable::check`) unless `clamp=True`.
#[pyfunction]
#[pyo3(signature = (theta_h, u, c, beta, p, *, source, clamp=false))]
#[allow(clippy::too_many_arguments)]
fn conv<'py>(
    py: Python<'py>,
    theta_h: PyReadonlyArray1<'py, f64>,
    u: PyReadonlyArray1<'py, f64>,
    c: PyReadonlyArray1<'py, f64>,
    beta: PyReadonlyArray1<'py, f64>,
    p: PyReadonlyArray1<'py, f64>,
    source: &str,
    clamp: bool,
) -> PyResult<Bound<'py, PyArray1<f64>>> {
    let rows_in = columns(["theta_h", "u", "c", "beta", "p"], [theta_h, u, c, beta, p])?;
    let (t3b, t3a) = (TABLES.convolution, TABLES.convolution.fit());
    let table: &(dyn Convolution + Sync) = match source {
        "table" => &t3b,
        "fit" => &t3a,
        "reference" => {
            return evaluate(py, rows_in, true, |[th, u, c, beta, p]| {
                ref_conv::convolution(th, u, c, beta, p).map_err(|e| e.to_string())
            });
        }
        other => {
            let known = CONV_SOURCES.map(|s| format!("'{s}'")).join(", ");
            return Err(value_error(format!(
                "source must be one of {known}, got '{other}'"
            )));
        }
    };
    evaluate(py, rows_in, false, |[th, u, c, beta, p]| {
        let [u, c, beta, p] = [u, c, beta, p].map(|x| x as f32);
        in_domain(clamp, || t3b.check(u, c, beta, p))?;
        let (sin, cos) = (th.sin() as f32, th.cos() as f32);
        Ok(table.convolution_sin_cos(sin, cos, u, c, beta, p).into())
    })
}

/// fresnel(n, k, cos_theta, *, reference, clamp=False): the unpolarised
/// Fresnel reflectance F(η = n + ik, cos θ) as float64 columns of equal
/// length: the runtime's (f32), or the f64 reference with `reference=True`.
/// An index outside the runtime's domain (`validate::eta`: n > 0, k ≥ 0)
/// raises `ValueError` unless `clamp=True`.
#[pyfunction]
#[pyo3(signature = (n, k, cos_theta, *, reference, clamp=false))]
fn fresnel<'py>(
    py: Python<'py>,
    n: PyReadonlyArray1<'py, f64>,
    k: PyReadonlyArray1<'py, f64>,
    cos_theta: PyReadonlyArray1<'py, f64>,
    reference: bool,
    clamp: bool,
) -> PyResult<Bound<'py, PyArray1<f64>>> {
    let rows_in = columns(["n", "k", "cos_theta"], [n, k, cos_theta])?;
    evaluate(py, rows_in, false, |[n, k, cos]| {
        if reference {
            ref_fresnel::fresnel(ref_fresnel::Complex64::new(n, k), cos).map_err(|e| e.to_string())
        } else {
            let eta = Complex::new(n as f32, k as f32);
            in_domain(clamp, || validate::eta(("n", "k"), eta))?;
            Ok(twoscale::model::fresnel::fresnel(eta, cos as f32).into())
        }
    })
}

/// brdf(wi, wo, *, beta, p, sigma_s, b, c, n, k, lam, reference,
/// clamp=False): the one-wavelength conductor ρ(wi, wo) in sr⁻¹ (the model
/// of `query brdf`, docs/model.md §2.5) with the paper's options; σs, b and
/// the wavelength `lam` in µm, η = n + ik. `wi`, `wo` are `(..., 3)` and
/// broadcast together; the result has their leading shape. The runtime
/// (`TwoScale`, T3b), or with `reference=True` the f64 reference (exact Λ,
/// σrel and C). Parameters outside the runtime's domain
/// (`Layer::validate`, `validate::eta`, `validate::wavelength`) raise
/// `ValueError` unless `clamp=True` (then the runtime clamps them).
#[pyfunction]
#[pyo3(signature = (wi, wo, *, beta, p, sigma_s, b, c, n, k, lam, reference, clamp=false))]
#[allow(clippy::too_many_arguments)]
fn brdf<'py>(
    py: Python<'py>,
    wi: &Bound<'py, PyAny>,
    wo: &Bound<'py, PyAny>,
    beta: f64,
    p: f64,
    sigma_s: f64,
    b: f64,
    c: f64,
    n: f64,
    k: f64,
    lam: f64,
    reference: bool,
    clamp: bool,
) -> PyResult<Bound<'py, PyArrayDyn<f64>>> {
    // Unchecked with clamp=True, as the other domains are.
    let directions = if clamp { Rows::Any } else { Rows::Directions };
    let v = vectors([("wi", wi, directions), ("wo", wo, directions)])?;
    let [wi, wo] = &v.rows;
    let options = Options::default();
    if reference {
        let params = ref_brdf::Params {
            beta,
            p,
            sigma_s,
            b,
            c,
            n,
            k,
            lambda: lam,
        };
        let rows_in: Vec<[f64; 6]> = wi
            .iter()
            .zip(wo)
            .map(|(i, o)| [i[0], i[1], i[2], o[0], o[1], o[2]].map(f64::from))
            .collect();
        let values = evaluate_rows(py, rows_in, true, |x| {
            ref_brdf::two_scale(&params, [x[0], x[1], x[2]], [x[3], x[4], x[5]], &options)
                .map(|v| v.total())
                .map_err(|e| e.to_string())
        })?;
        return Ok(shaped(py, &v.shape, values));
    }
    let f = |v: f64| v as f32;
    let layer = Layer {
        surface: Surface {
            beta: f(beta),
            p: f(p),
            sigma_s: f(sigma_s),
            b: f(b),
            c: f(c),
        },
        base: BaseLayer::Conductor,
        lambertian: 0.0,
    };
    let (eta, lam) = (Complex::new(f(n), f(k)), f(lam));
    if !clamp {
        layer.validate().map_err(invalid)?;
        validate::eta(("n", "k"), eta).map_err(invalid)?;
        validate::wavelength(lam).map_err(invalid)?;
    }
    let model = TwoScale::new(&TABLES.brdf_tables(), layer, lam, eta, options);
    let values = py.detach(|| rows(v.len(), |j| f64::from(Bxdf::eval(&model, wi[j], wo[j]))));
    Ok(shaped(py, &v.shape, values))
}

/// The extension of the `twoscale` package: `Material` (the RGB model of a
/// material), the names of its options (`OPTIONS`, `BASES`), the wavelengths
/// of its channels (`RGB_WAVELENGTHS`, µm) and the row functions behind
/// `twoscale.lookup` and `twoscale.reference`.
#[pymodule]
fn _native(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_class::<Material>()?;
    // The workspace's version: the `twoscale` crate's, the package's.
    m.add("__version__", env!("CARGO_PKG_VERSION"))?;
    m.add(
        "RGB_WAVELENGTHS",
        twoscale::material::RGB_WAVELENGTHS.to_vec(),
    )?;
    let options = BTreeMap::from([
        (Masking::OPTION, names::<Masking>()),
        (SigmaRelMode::OPTION, names::<SigmaRelMode>()),
        (ColourTerms::OPTION, names::<ColourTerms>()),
        (HaloWeight::OPTION, names::<HaloWeight>()),
        (MultipleScattering::OPTION, names::<MultipleScattering>()),
    ]);
    let options = options
        .into_iter()
        .map(|(k, v)| Ok((k, PyTuple::new(m.py(), v)?)));
    m.add("OPTIONS", options.collect::<PyResult<BTreeMap<_, _>>>()?)?;
    m.add("BASES", PyTuple::new(m.py(), names::<BaseKind>())?)?;
    m.add("RGB_MODES", PyTuple::new(m.py(), names::<RgbMode>())?)?;
    m.add_function(wrap_pyfunction!(g1, m)?)?;
    m.add_function(wrap_pyfunction!(sigma_ratio, m)?)?;
    m.add_function(wrap_pyfunction!(conv, m)?)?;
    m.add_function(wrap_pyfunction!(fresnel, m)?)?;
    m.add_function(wrap_pyfunction!(brdf, m)?)?;
    merl::register(m)?;
    Ok(())
}
