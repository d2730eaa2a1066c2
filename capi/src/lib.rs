//! `twoscale-capi`: the C ABI of the `twoscale` runtime.
//!
//! The header `include/twoscale.h` is generated from this file by cbindgen
//! (`capi/cbindgen.toml`; the header's preamble states the conventions:
//! status codes, the thread-local last error, handle lifetimes, thread
//! safety). Every entry point checks its pointers (NULL, alignment), rejects
//! non-finite numbers, and runs under `catch_unwind`, so misuse is a status
//! code and no panic crosses the boundary.
//!
//! Handles: a `ts_tables` owns its table bytes (a copy, a memory map, or the
//! embedded tables) behind an `Arc`; every `ts_material` holds a reference to
//! it, so handles may be freed in any order.
#![allow(non_camel_case_types)]

use std::cell::RefCell;
use std::ffi::{CStr, CString, c_char, c_int};
use std::fmt::Display;
use std::panic::{AssertUnwindSafe, catch_unwind};
use std::path::PathBuf;
use std::sync::{Arc, OnceLock};

use twoscale::brdf::{ChannelBake, RgbModel};

use twoscale::brdf::{BoxedSpectral, SPECTRAL_WAVELENGTHS, Spectral};
use twoscale::domain::{self, Domain, Invalid};
use twoscale::io::desc::{DescError, DescErrorKind, MaterialDesc};
use twoscale::material::{
    BaseKind, BaseLayer, ColourTerms, HaloWeight, Layer, Masking, Material, MultipleScattering,
    Options, RGB_WAVELENGTHS, RgbMode, SigmaRelMode, Surface,
};
use twoscale::materials::PRESETS;
use twoscale::spectrum::optical::{Ior, OwnedSpectralMaterial, Tabulated};
use twoscale::table_set::TABLES;
use twoscale::tables::format::{FormatError, TableId, aligned_copy};
use twoscale::validate::Refused;
use twoscale::{Bxdf, Complex, OwnedTableSet, TableSet, TableSetError, TableStorage};

/// Success.
pub const TS_OK: c_int = 0;
/// A required pointer argument was NULL.
pub const TS_ERR_NULL: c_int = 1;
/// A `float` pointer argument was not aligned to 4 bytes.
pub const TS_ERR_MISALIGNED: c_int = 2;
/// An argument is invalid: a NaN or infinite number, an unknown enumeration
/// value, a string that is not UTF-8, a count that overflows.
pub const TS_ERR_INVALID: c_int = 3;
/// The material name is not a shipped preset (the message lists them).
pub const TS_ERR_UNKNOWN_MATERIAL: c_int = 4;
/// Table bytes failed validation (the message names the file and the fault).
pub const TS_ERR_TABLES: c_int = 5;
/// A table file could not be opened or mapped.
pub const TS_ERR_IO: c_int = 6;
/// Internal error: a panic inside the library was caught (a bug; please report).
pub const TS_ERR_PANIC: c_int = 7;
/// A material description is not TOML, or not the schema: an unknown,
/// missing or mistyped key (the message gives the line and the key).
pub const TS_ERR_PARSE: c_int = 8;

/// `ts_material_desc.base`: a conductor (no base layer).
pub const TS_BASE_CONDUCTOR: i32 = 0;
/// `ts_material_desc.base`: a dielectric varnish (index `eta_re[k]`) over a
/// diffuse layer of albedo `base_albedo`.
pub const TS_BASE_PLASTIC: i32 = 1;
/// `ts_material_desc.base`: subsurface scattering with albedo `base_albedo`.
pub const TS_BASE_SUBSURFACE: i32 = 2;
/// `ts_material_desc.masking`: `G = G1(i) G1(o)` (the papers' model).
pub const TS_MASKING_SEPARABLE: i32 = 0;
/// `ts_material_desc.masking`: `G = 1 / (1 + Λ(i) + Λ(o))`.
pub const TS_MASKING_HEIGHT_CORRELATED: i32 = 1;
/// `ts_material_desc.sigma_rel`: `σrel = σrel(θi)` (the paper's model).
pub const TS_SIGMA_REL_INCIDENT: i32 = 0;
/// `ts_material_desc.sigma_rel`: `σrel² = (σrel²(θi) + σrel²(θo)) / 2` (reciprocal).
pub const TS_SIGMA_REL_SYMMETRISED: i32 = 1;
/// `ts_material_desc.colour`: Fresnel and Q̄ from the complex index.
pub const TS_COLOUR_PHYSICAL: i32 = 0;
/// `ts_material_desc.colour`: `F ≡ 1`, `Q̄ ≡ 1` (white furnace).
pub const TS_COLOUR_WHITE: i32 = 1;
/// `ts_material_desc.halo_weight`: `A = A_spec(θd)` for the halo (as printed).
pub const TS_HALO_PRINTED: i32 = 0;
/// `ts_material_desc.halo_weight`: `A = A(θi)` for the halo (energy-bounded).
pub const TS_HALO_INCIDENT: i32 = 1;
/// `ts_material_desc.multiple_scattering`: single scattering only (the papers' model).
pub const TS_MULTIPLE_NONE: i32 = 0;
/// `ts_material_desc.multiple_scattering`: the Kulla–Conty energy-compensation
/// lobe (docs/model.md §2.11).
pub const TS_MULTIPLE_KULLA_CONTY: i32 = 1;
/// `ts_material_desc.rgb_mode`: the material's default (0, so a zeroed
/// field): `TS_RGB_MODE_INTEGRATED` for a material
/// over the spectrum (`eta_rows`; every preset),
/// `TS_RGB_MODE_PAPER_WAVELENGTHS` for three indices.
pub const TS_RGB_MODE_DEFAULT: i32 = 0;
/// `ts_material_desc.rgb_mode`: ρ at the paper's wavelengths
/// (`ts_rgb_wavelengths`) as red, green, blue (what reproduces HP15/HP17).
pub const TS_RGB_MODE_PAPER_WAVELENGTHS: i32 = 1;
/// `ts_material_desc.rgb_mode`: linear sRGB by integration over the
/// spectrum (docs/model.md §2.12); needs `eta_rows`, or one index for
/// every channel.
pub const TS_RGB_MODE_INTEGRATED: i32 = 2;

/// A validated set of the four tables (T1, T2, T3, T5). Opaque.
pub struct ts_tables {
    inner: Arc<OwnedTableSet>,
}

/// A material file's description that owns its index's rows (`eta = {
/// lambda, n, k }`), from `ts_material_file_from_toml`; read it with
/// `ts_material_file_desc`, free it with `ts_material_file_free`. Opaque.
pub struct ts_material_file {
    desc: twoscale::io::desc::OwnedMaterialDesc,
}

/// An RGB material built from a `ts_tables`. Opaque; about 136 KB (360 KB
/// with `TS_RGB_MODE_INTEGRATED`), on the heap.
pub struct ts_material {
    /// Borrows `_tables` (declared after it, so dropped before it); its
    /// bakes are allocated zeroed on the heap and filled in place.
    rgb: RgbModel<'static, Box<ChannelBake>>,
    /// The index over the spectrum (`eta_rows`, a preset's measured one, or
    /// the one index of a description that gives the same for every channel).
    spectral: Option<OwnedSpectralMaterial>,
    /// `spectral`'s model at any wavelength, built by the first
    /// `ts_eval_spectral`; borrows `_tables` as `rgb` does.
    spectral_model: OnceLock<BoxedSpectral<'static>>,
    options: Options,
    _tables: Arc<OwnedTableSet>,
}

/// The bytes of the four table files, for `ts_tables_from_bytes`.
#[repr(C)]
pub struct ts_table_bytes {
    /// `t1-smith-g1.tbl`.
    pub smith: *const u8,
    /// Its length in bytes.
    pub smith_len: usize,
    /// `t2-sigma-ratio.tbl`.
    pub sigma_ratio: *const u8,
    /// Its length in bytes.
    pub sigma_ratio_len: usize,
    /// `t3-convolution.tbl`.
    pub convolution: *const u8,
    /// Its length in bytes.
    pub convolution_len: usize,
    /// `t5-diffuse-fresnel.tbl`.
    pub diffuse_fresnel: *const u8,
    /// Its length in bytes.
    pub diffuse_fresnel_len: usize,
    /// `t6-albedo.tbl`.
    pub albedo: *const u8,
    /// Its length in bytes.
    pub albedo_len: usize,
}

/// Every parameter of a material (`twoscale::material::Layer`, the RGB index and
/// `twoscale::material::Options`). Set `size` to `sizeof(ts_material_desc)`
/// (`ts_material_desc_preset` does); other sizes are rejected. All-zero
/// enumeration fields are the defaults (conductor, the paper's options).
/// Lengths are in µm. Values outside the model's domain (`Material::validate`
/// of the runtime: β and p in the EPD's domain, σs ≥ 0, b > 0 when σs > 0,
/// c > 1, albedos in [0, 1], n > 0, k ≥ 0, no albedo on a conductor) and NaN
/// or infinite values are rejected with `TS_ERR_INVALID` and a message naming
/// the field, its value and its domain.
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ts_material_desc {
    /// `sizeof(ts_material_desc)`, set by the caller: the layout the caller
    /// was compiled with.
    pub size: u32,
    /// EPD width β (HP17 35).
    pub beta: f32,
    /// EPD shape p (HP17 35), in [0.2, 5].
    pub p: f32,
    /// RMS height σs of the nano-geometry, µm (HP17 16); 0 disables diffraction.
    pub sigma_s: f32,
    /// Correlation length b of the K-correlation spectrum, µm (HP17 16).
    pub b: f32,
    /// Spectral exponent c > 1 of the K-correlation spectrum (HP17 16).
    pub c: f32,
    /// `TS_BASE_CONDUCTOR`, `TS_BASE_PLASTIC` or `TS_BASE_SUBSURFACE`.
    pub base: i32,
    /// The base layer's albedo in [0, 1] (plastic ρd, subsurface α; unused
    /// for a conductor).
    pub base_albedo: f32,
    /// Lambertian reflectance `k_d` in [0, 1] (adds `k_d/π`; 0 for none).
    pub lambertian: f32,
    /// Real part n of the index per channel, at the wavelengths of
    /// `ts_rgb_wavelengths` (not read when `eta_rows` is given).
    pub eta_re: [f32; 3],
    /// Imaginary part k of the index per channel (not read when `eta_rows`
    /// is given).
    pub eta_im: [f32; 3],
    /// The index over the spectrum, or NULL: `eta_row_count` rows of three
    /// floats `(λ µm, n, k)`, λ increasing (linear in 1/λ between rows,
    /// held beyond the ends). `ts_material_new` copies them. The channels'
    /// index is then the spectrum at `ts_rgb_wavelengths`. Presets
    /// (`ts_material_desc_preset`) point to their measured rows.
    pub eta_rows: *const f32,
    /// Number of rows of `eta_rows` (0 when it is NULL).
    pub eta_row_count: usize,
    /// `TS_MASKING_*`.
    pub masking: i32,
    /// `TS_SIGMA_REL_*`.
    pub sigma_rel: i32,
    /// `TS_COLOUR_*`.
    pub colour: i32,
    /// `TS_HALO_*`.
    pub halo_weight: i32,
    /// `TS_MULTIPLE_*`.
    pub multiple_scattering: i32,
    /// `TS_RGB_MODE_*`.
    pub rgb_mode: i32,
}

impl Default for ts_material_desc {
    /// A conductor with the paper's options, every number 0, `size` set.
    fn default() -> Self {
        ts_material_desc {
            size: desc_size(),
            beta: 0.0,
            p: 0.0,
            sigma_s: 0.0,
            b: 0.0,
            c: 0.0,
            base: TS_BASE_CONDUCTOR,
            base_albedo: 0.0,
            lambertian: 0.0,
            eta_re: [0.0; 3],
            eta_im: [0.0; 3],
            eta_rows: std::ptr::null(),
            eta_row_count: 0,
            masking: TS_MASKING_SEPARABLE,
            sigma_rel: TS_SIGMA_REL_INCIDENT,
            colour: TS_COLOUR_PHYSICAL,
            halo_weight: TS_HALO_PRINTED,
            multiple_scattering: TS_MULTIPLE_NONE,
            rgb_mode: TS_RGB_MODE_DEFAULT,
        }
    }
}

/// `sizeof(ts_material_desc)` of this library (the only size accepted). A
/// function, not a `const`: cbindgen would try to export the constant.
fn desc_size() -> u32 {
    size_of::<ts_material_desc>() as u32
}

/// A sampled direction. `pdf == 0` means no direction was sampled (e.g. `wi`
/// below the horizon); `wo` and `value` are then zero.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct ts_sample {
    /// The outgoing direction (unit vector, z > 0).
    pub wo: [f32; 3],
    /// The density of `wo` (solid angle), as `ts_pdf`.
    pub pdf: f32,
    /// ρ(wi, wo) per channel, as `ts_eval_rgb`.
    pub value: [f32; 3],
}

/// A failure: a status code and its message.
struct Fail(c_int, String);

impl Fail {
    fn new(code: c_int, message: impl Display) -> Fail {
        Fail(code, message.to_string())
    }
}

impl From<TableSetError> for Fail {
    fn from(error: TableSetError) -> Fail {
        let code = match error {
            TableSetError::Format { .. } => TS_ERR_TABLES,
            TableSetError::Io { .. } => TS_ERR_IO,
        };
        Fail::new(code, error)
    }
}

impl From<DescError> for Fail {
    /// The runtime's message, unchanged (Rust and Python show the same).
    fn from(error: DescError) -> Fail {
        let code = match error.kind {
            DescErrorKind::Io => TS_ERR_IO,
            DescErrorKind::Syntax => TS_ERR_PARSE,
            DescErrorKind::Refused => TS_ERR_INVALID,
        };
        Fail(code, error.message)
    }
}

thread_local! {
    /// This thread's last failure: its status code and message.
    static LAST_ERROR: RefCell<(c_int, CString)> = RefCell::new((TS_OK, CString::default()));
}

fn record(fail: Fail) -> c_int {
    let Fail(code, message) = fail;
    let message = CString::new(message.replace('\0', "\\0")).unwrap_or_default();
    // `try_with`: during thread teardown the slot may be gone; the code is
    // still returned.
    let _ = LAST_ERROR.try_with(|last| *last.borrow_mut() = (code, message));
    code
}

/// Runs `f` with panics caught; a panic becomes `TS_ERR_PANIC`.
fn guarded<T>(f: impl FnOnce() -> Result<T, Fail>) -> Result<T, c_int> {
    match catch_unwind(AssertUnwindSafe(f)) {
        Ok(Ok(value)) => Ok(value),
        Ok(Err(fail)) => Err(record(fail)),
        Err(_) => Err(record(Fail::new(
            TS_ERR_PANIC,
            "internal error: a panic was caught (a bug in twoscale; please report it)",
        ))),
    }
}

/// A status-returning entry point.
fn status(f: impl FnOnce() -> Result<(), Fail>) -> c_int {
    match guarded(f) {
        Ok(()) => TS_OK,
        Err(code) => code,
    }
}

/// A handle-returning entry point: NULL on failure.
fn handle<T>(f: impl FnOnce() -> Result<Box<T>, Fail>) -> *mut T {
    guarded(f).map_or(std::ptr::null_mut(), Box::into_raw)
}

fn non_null<T>(ptr: *const T, what: &str) -> Result<(), Fail> {
    if ptr.is_null() {
        return Err(Fail::new(TS_ERR_NULL, format!("{what} is NULL")));
    }
    Ok(())
}

/// Checks a pointer to `float`s: not NULL, 4-byte aligned.
fn floats(ptr: *const f32, what: &str) -> Result<(), Fail> {
    non_null(ptr, what)?;
    if !ptr.is_aligned() {
        return Err(Fail::new(
            TS_ERR_MISALIGNED,
            format!("{what} ({ptr:p}) is not aligned to 4 bytes"),
        ));
    }
    Ok(())
}

/// Reads entry `j` (three finite floats, `ptr[3j..3j+3]`) of a checked array.
///
/// # Safety
///
/// `ptr` passed `floats`, and `ptr[3j..3j+3]` lies within the caller's array.
unsafe fn read3(ptr: *const f32, j: usize, what: &str) -> Result<[f32; 3], Fail> {
    // SAFETY: the caller guarantees `ptr[3j..3j + 3]` is readable and `ptr`
    // is non-null and aligned. Element-wise reads: the array may alias an
    // output array.
    let v = unsafe { [0, 1, 2].map(|k| ptr.add(3 * j + k).read()) };
    if !v.iter().all(|x| x.is_finite()) {
        return Err(Fail::new(
            TS_ERR_INVALID,
            format!("{what} (entry {j}) has a non-finite component: {v:?}"),
        ));
    }
    Ok(v)
}

/// The material behind a checked handle pointer.
///
/// # Safety
///
/// `m` is NULL or a live handle from `ts_material_*`.
unsafe fn material<'m>(m: *const ts_material) -> Result<&'m ts_material, Fail> {
    non_null(m, "the material")?;
    // SAFETY: non-null, and by the caller's contract a live handle.
    Ok(unsafe { &*m })
}

/// `3 n`, or an error if the arrays could not exist.
fn triples(n: usize) -> Result<usize, Fail> {
    n.checked_mul(3)
        .filter(|len| *len <= isize::MAX as usize / size_of::<f32>())
        .ok_or_else(|| Fail::new(TS_ERR_INVALID, format!("n = {n} is too large")))
}

/// The path in the C string `s` (its bytes on Unix, UTF-8 elsewhere).
///
/// # Safety
///
/// `s` is NULL or a NUL-terminated string.
unsafe fn path(s: *const c_char, what: &str) -> Result<PathBuf, Fail> {
    non_null(s, what)?;
    // SAFETY: non-null; the caller passes a NUL-terminated string.
    let s = unsafe { CStr::from_ptr(s) };
    #[cfg(unix)]
    let path =
        PathBuf::from(<std::ffi::OsStr as std::os::unix::ffi::OsStrExt>::from_bytes(s.to_bytes()));
    #[cfg(not(unix))]
    let path = PathBuf::from(
        s.to_str()
            .map_err(|e| Fail::new(TS_ERR_INVALID, format!("{what} is not UTF-8: {e}")))?,
    );
    Ok(path)
}

fn utf8<'s>(s: *const c_char, what: &str) -> Result<&'s str, Fail> {
    non_null(s, what)?;
    // SAFETY: non-null; the caller passes a NUL-terminated string.
    let s = unsafe { CStr::from_ptr(s) };
    s.to_str()
        .map_err(|e| Fail::new(TS_ERR_INVALID, format!("{what} is not UTF-8: {e}")))
}

/// `TS_ERR_INVALID` with the runtime validation's message, the parameter
/// named as the field of `ts_material_desc` that holds it.
fn invalid(error: Invalid) -> Fail {
    let field = match error.name {
        "albedo" => "base_albedo",
        "eta[0].n" => "eta_re[0]",
        "eta[1].n" => "eta_re[1]",
        "eta[2].n" => "eta_re[2]",
        "eta[0].k" => "eta_im[0]",
        "eta[1].k" => "eta_im[1]",
        "eta[2].k" => "eta_im[2]",
        "rows" => "eta_row_count",
        "lambda" => "eta_rows[].lambda",
        "n" => "eta_rows[].n",
        "k" => "eta_rows[].k",
        name => name,
    };
    Fail::new(
        TS_ERR_INVALID,
        format!(
            "ts_material_desc.{}",
            Invalid {
                name: field,
                ..error
            }
        ),
    )
}

/// The runtime value of the enumeration field `field` holding `value`:
/// `choices` are each C constant's name, value and runtime value (matched by
/// value, not by position); any other value is `TS_ERR_INVALID`, listing them.
fn constant<T: Copy>(field: &str, value: i32, choices: &[(&str, i32, T)]) -> Result<T, Fail> {
    if let Some(&(_, _, v)) = choices.iter().find(|(_, c, _)| *c == value) {
        return Ok(v);
    }
    let mut accepted = String::new();
    for (k, (name, v, _)) in choices.iter().enumerate() {
        let sep = if k == 0 { "" } else { ", " };
        accepted.push_str(&format!("{sep}{name} ({v})"));
    }
    Err(Fail::new(
        TS_ERR_INVALID,
        format!("ts_material_desc.{field} = {value} is not one of {accepted}"),
    ))
}

/// A refused description as `TS_ERR_INVALID`, naming the field.
fn refused(error: Refused<'_>) -> Fail {
    match error {
        Refused::Invalid(e) => invalid(e),
        e => Fail::new(TS_ERR_INVALID, format!("ts_material_desc: {e}")),
    }
}

impl ts_material_desc {
    /// The runtime's material description: unknown enumeration values and
    /// what `Material::validate` or `SpectralMaterial::validate` rejects
    /// (non-finite numbers among them) are `TS_ERR_INVALID`, naming the
    /// field.
    ///
    /// # Safety
    ///
    /// `eta_rows` is NULL or holds `3 eta_row_count` floats, valid for `'a`.
    unsafe fn to_model<'a>(self) -> Result<MaterialDesc<'a>, Fail> {
        let albedo = self.base_albedo;
        let base = constant(
            "base",
            self.base,
            &[
                ("TS_BASE_CONDUCTOR", TS_BASE_CONDUCTOR, BaseKind::Conductor),
                ("TS_BASE_PLASTIC", TS_BASE_PLASTIC, BaseKind::Plastic),
                (
                    "TS_BASE_SUBSURFACE",
                    TS_BASE_SUBSURFACE,
                    BaseKind::Subsurface,
                ),
            ],
        )?
        .with_albedo(albedo);
        let masking = constant(
            "masking",
            self.masking,
            &[
                (
                    "TS_MASKING_SEPARABLE",
                    TS_MASKING_SEPARABLE,
                    Masking::Separable,
                ),
                (
                    "TS_MASKING_HEIGHT_CORRELATED",
                    TS_MASKING_HEIGHT_CORRELATED,
                    Masking::HeightCorrelated,
                ),
            ],
        )?;
        let sigma_rel = constant(
            "sigma_rel",
            self.sigma_rel,
            &[
                (
                    "TS_SIGMA_REL_INCIDENT",
                    TS_SIGMA_REL_INCIDENT,
                    SigmaRelMode::Incident,
                ),
                (
                    "TS_SIGMA_REL_SYMMETRISED",
                    TS_SIGMA_REL_SYMMETRISED,
                    SigmaRelMode::Symmetrised,
                ),
            ],
        )?;
        let colour = constant(
            "colour",
            self.colour,
            &[
                (
                    "TS_COLOUR_PHYSICAL",
                    TS_COLOUR_PHYSICAL,
                    ColourTerms::Physical,
                ),
                ("TS_COLOUR_WHITE", TS_COLOUR_WHITE, ColourTerms::White),
            ],
        )?;
        let halo_weight = constant(
            "halo_weight",
            self.halo_weight,
            &[
                ("TS_HALO_PRINTED", TS_HALO_PRINTED, HaloWeight::Printed),
                ("TS_HALO_INCIDENT", TS_HALO_INCIDENT, HaloWeight::Incident),
            ],
        )?;
        let multiple_scattering = constant(
            "multiple_scattering",
            self.multiple_scattering,
            &[
                (
                    "TS_MULTIPLE_NONE",
                    TS_MULTIPLE_NONE,
                    MultipleScattering::None,
                ),
                (
                    "TS_MULTIPLE_KULLA_CONTY",
                    TS_MULTIPLE_KULLA_CONTY,
                    MultipleScattering::KullaConty,
                ),
            ],
        )?;
        let options = Options {
            masking,
            sigma_rel,
            colour,
            halo_weight,
            multiple_scattering,
        };
        let material = Material {
            layer: Layer {
                surface: Surface {
                    beta: self.beta,
                    p: self.p,
                    sigma_s: self.sigma_s,
                    b: self.b,
                    c: self.c,
                },
                base,
                lambertian: self.lambertian,
            },
            eta_rgb: [0, 1, 2].map(|k| Complex::new(self.eta_re[k], self.eta_im[k])),
        };
        if material.layer.base == BaseLayer::Conductor {
            // A conductor has no base layer: its albedo field must stay 0.
            domain::check(
                "albedo",
                domain::widen(albedo),
                Domain::Closed(0.0, 0.0),
                "a conductor has no base layer",
            )
            .map_err(invalid)?;
        }
        let rgb_mode = constant(
            "rgb_mode",
            self.rgb_mode,
            &[
                ("TS_RGB_MODE_DEFAULT", TS_RGB_MODE_DEFAULT, None),
                (
                    "TS_RGB_MODE_PAPER_WAVELENGTHS",
                    TS_RGB_MODE_PAPER_WAVELENGTHS,
                    Some(RgbMode::PaperWavelengths),
                ),
                (
                    "TS_RGB_MODE_INTEGRATED",
                    TS_RGB_MODE_INTEGRATED,
                    Some(RgbMode::Integrated),
                ),
            ],
        )?;
        if self.eta_rows.is_null() {
            if self.eta_row_count != 0 {
                return Err(Fail::new(
                    TS_ERR_INVALID,
                    format!(
                        "ts_material_desc.eta_row_count = {} with eta_rows NULL: must be 0",
                        self.eta_row_count
                    ),
                ));
            }
            return MaterialDesc::rgb(material, options, rgb_mode).map_err(refused);
        }
        if !self.eta_rows.is_aligned() {
            return Err(Fail::new(
                TS_ERR_MISALIGNED,
                "ts_material_desc.eta_rows is misaligned",
            ));
        }
        if self.eta_row_count > isize::MAX as usize / size_of::<[f32; 3]>() {
            return Err(Fail::new(
                TS_ERR_INVALID,
                format!(
                    "ts_material_desc.eta_row_count = {} overflows",
                    self.eta_row_count
                ),
            ));
        }
        // SAFETY: non-null, aligned, and by the caller's contract `3 count`
        // readable floats; `[f32; 3]` has the alignment of `f32`.
        let rows: &'a [[f32; 3]] = unsafe {
            std::slice::from_raw_parts(self.eta_rows.cast::<[f32; 3]>(), self.eta_row_count)
        };
        let eta = Ior::Tabulated(Tabulated::new(rows).map_err(invalid)?);
        let spectral = twoscale::spectrum::optical::SpectralMaterial {
            layer: material.layer,
            eta,
        };
        MaterialDesc::spectral(spectral, options, rgb_mode).map_err(refused)
    }

    /// The description of `desc`; its rows (if a spectrum is tabulated)
    /// must outlive the description: the presets' static ones, or a
    /// `ts_material_file`'s.
    fn from_model(desc: &MaterialDesc<'_>) -> ts_material_desc {
        let (material, options) = (&desc.material, desc.options);
        let (eta_rows, eta_row_count) = match desc.spectral.map(|s| s.eta) {
            Some(Ior::Tabulated(t)) => (t.rows().as_ptr().cast::<f32>(), t.rows().len()),
            _ => (std::ptr::null(), 0),
        };
        let (base, base_albedo) = match material.layer.base {
            BaseLayer::Conductor => (TS_BASE_CONDUCTOR, 0.0),
            BaseLayer::Plastic { albedo } => (TS_BASE_PLASTIC, albedo),
            BaseLayer::Subsurface { albedo } => (TS_BASE_SUBSURFACE, albedo),
        };
        let s = material.layer.surface;
        ts_material_desc {
            size: desc_size(),
            beta: s.beta,
            p: s.p,
            sigma_s: s.sigma_s,
            b: s.b,
            c: s.c,
            base,
            base_albedo,
            lambertian: material.layer.lambertian,
            eta_re: material.eta_rgb.map(|eta| eta.re),
            eta_im: material.eta_rgb.map(|eta| eta.im),
            eta_rows,
            eta_row_count,
            masking: match options.masking {
                Masking::Separable => TS_MASKING_SEPARABLE,
                Masking::HeightCorrelated => TS_MASKING_HEIGHT_CORRELATED,
            },
            sigma_rel: match options.sigma_rel {
                SigmaRelMode::Incident => TS_SIGMA_REL_INCIDENT,
                SigmaRelMode::Symmetrised => TS_SIGMA_REL_SYMMETRISED,
            },
            colour: match options.colour {
                ColourTerms::Physical => TS_COLOUR_PHYSICAL,
                ColourTerms::White => TS_COLOUR_WHITE,
            },
            halo_weight: match options.halo_weight {
                HaloWeight::Printed => TS_HALO_PRINTED,
                HaloWeight::Incident => TS_HALO_INCIDENT,
            },
            multiple_scattering: match options.multiple_scattering {
                MultipleScattering::None => TS_MULTIPLE_NONE,
                MultipleScattering::KullaConty => TS_MULTIPLE_KULLA_CONTY,
            },
            rgb_mode: match desc.rgb_mode {
                RgbMode::PaperWavelengths => TS_RGB_MODE_PAPER_WAVELENGTHS,
                RgbMode::Integrated => TS_RGB_MODE_INTEGRATED,
            },
        }
    }
}

fn new_tables(tables: OwnedTableSet) -> Box<ts_tables> {
    Box::new(ts_tables {
        inner: Arc::new(tables),
    })
}

/// Builds the material handle of `desc` from the set behind `t`.
fn new_material(t: &ts_tables, desc: &MaterialDesc<'_>) -> Box<ts_material> {
    let rgb = RgbModel::boxed(&t.inner.set().brdf_tables(), desc);
    // SAFETY: `rgb` borrows only the `TableSet` inside the `Arc` allocation
    // (which never moves) and, through it, the table storage it owns. The
    // handle keeps a clone of that `Arc` in `_tables`, dropped after `rgb`
    // (field order), so the borrow never dangles.
    let rgb = unsafe {
        std::mem::transmute::<RgbModel<'_, Box<ChannelBake>>, RgbModel<'static, Box<ChannelBake>>>(
            rgb,
        )
    };
    Box::new(ts_material {
        rgb,
        spectral: desc.spectral.as_ref().map(OwnedSpectralMaterial::new),
        spectral_model: OnceLock::new(),
        options: desc.options,
        _tables: Arc::clone(&t.inner),
    })
}

/// The library's version, `"MAJOR.MINOR.PATCH"` (static storage).
#[unsafe(no_mangle)]
pub extern "C" fn ts_version() -> *const c_char {
    const VERSION: &CStr =
        match CStr::from_bytes_with_nul(concat!(env!("CARGO_PKG_VERSION"), "\0").as_bytes()) {
            Ok(version) => version,
            Err(_) => panic!("the package version holds a NUL"),
        };
    VERSION.as_ptr()
}

/// The message of this thread's last failure (an empty string if none). The
/// pointer stays valid until the next failing call on this thread.
#[unsafe(no_mangle)]
pub extern "C" fn ts_last_error() -> *const c_char {
    static EMPTY: &CStr = c"";
    LAST_ERROR
        .try_with(|last| last.borrow().1.as_ptr())
        .unwrap_or(EMPTY.as_ptr())
}

/// The status code of this thread's last failure (`TS_OK` if none): the way
/// to tell why a handle-returning function returned NULL.
#[unsafe(no_mangle)]
pub extern "C" fn ts_last_status() -> c_int {
    LAST_ERROR.try_with(|last| last.borrow().0).unwrap_or(TS_OK)
}

/// The tables compiled into the library (no files needed). NULL on failure.
#[unsafe(no_mangle)]
pub extern "C" fn ts_tables_embedded() -> *mut ts_tables {
    handle(|| {
        let set = TableSet::from_bytes(TableSet::embedded_bytes())?;
        Ok(new_tables(OwnedTableSet::from_static(set)))
    })
}

/// Memory-maps and validates the four table files of directory `dir`
/// (`t1-smith-g1.tbl`, `t2-sigma-ratio.tbl`, `t3-convolution.tbl`,
/// `t5-diffuse-fresnel.tbl`). The maps are released by `ts_tables_free` (and
/// the last material made from them). Files must not be modified in place
/// while mapped. NULL on failure.
///
/// # Safety
///
/// `dir` is NULL or a NUL-terminated string.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn ts_tables_open(dir: *const c_char) -> *mut ts_tables {
    handle(|| {
        // SAFETY: forwarded caller contract.
        let dir = unsafe { path(dir, "dir")? };
        Ok(new_tables(TableSet::open(dir)?))
    })
}

/// Validates the four tables in `bytes` and makes a handle holding a copy of
/// them (64-byte aligned): the caller's buffers may be freed after the call
/// and need no particular alignment. NULL on failure (a NULL pointer, or
/// bytes that are truncated, corrupted or of the wrong table).
///
/// # Safety
///
/// `bytes` is NULL or points to a `ts_table_bytes` whose each pointer is NULL
/// or valid for reads of its length.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn ts_tables_from_bytes(bytes: *const ts_table_bytes) -> *mut ts_tables {
    handle(|| {
        non_null(bytes, "bytes")?;
        // SAFETY: non-null; the caller passes a valid `ts_table_bytes`.
        let b = unsafe { &*bytes };
        let file = |id: TableId| match id {
            TableId::SmithG1 => (b.smith, b.smith_len),
            TableId::SigmaRatio => (b.sigma_ratio, b.sigma_ratio_len),
            TableId::Convolution => (b.convolution, b.convolution_len),
            TableId::DiffuseFresnel => (b.diffuse_fresnel, b.diffuse_fresnel_len),
            TableId::Albedo => (b.albedo, b.albedo_len),
            TableId::ShBrdf => (std::ptr::null(), 0),
        };
        let mut copies = TABLES
            .iter()
            .map(|&id| {
                let (ptr, len) = file(id);
                let name = id.file_name();
                non_null(ptr, &format!("the bytes of {name}"))?;
                if len > isize::MAX as usize {
                    return Err(Fail::new(
                        TS_ERR_INVALID,
                        format!("{name}: length {len} is too large"),
                    ));
                }
                // SAFETY: non-null, `len` ≤ isize::MAX, and the caller
                // guarantees `len` readable bytes; `u8` needs no alignment.
                let slice = unsafe { std::slice::from_raw_parts(ptr, len) };
                Ok(Some(TableStorage::Copied(aligned_copy(slice))))
            })
            .collect::<Result<Vec<_>, _>>()?;
        let set = OwnedTableSet::from_storage(|id| {
            let k = TABLES.iter().position(|&t| t == id);
            k.and_then(|k| copies.get_mut(k)?.take())
                .ok_or(TableSetError::Format {
                    table: id,
                    error: FormatError::BadHeader("no bytes given"),
                })
        })?;
        Ok(new_tables(set))
    })
}

/// Frees a tables handle (NULL is ignored). Materials made from it stay valid:
/// the tables are released with the last of them.
///
/// # Safety
///
/// `t` is NULL or a live handle from `ts_tables_*`, not used afterwards.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn ts_tables_free(t: *mut ts_tables) {
    if !t.is_null() {
        // SAFETY: a live handle made by `Box::into_raw`, freed once.
        let _ = catch_unwind(AssertUnwindSafe(|| drop(unsafe { Box::from_raw(t) })));
    }
}

/// The number of shipped material presets.
#[unsafe(no_mangle)]
pub extern "C" fn ts_preset_count() -> usize {
    PRESETS.len()
}

/// The name of preset `index` (static storage), or NULL if `index` ≥
/// `ts_preset_count()`.
#[unsafe(no_mangle)]
pub extern "C" fn ts_preset_name(index: usize) -> *const c_char {
    static NAMES: OnceLock<Vec<CString>> = OnceLock::new();
    let names = NAMES.get_or_init(|| {
        PRESETS
            .iter()
            .map(|(name, _)| CString::new(*name).unwrap_or_default())
            .collect()
    });
    names.get(index).map_or(std::ptr::null(), |s| s.as_ptr())
}

/// The wavelengths (µm) of the red, green and blue channels, at which
/// `ts_material_desc.eta_re`/`eta_im` are given.
///
/// # Safety
///
/// `out` is NULL or points to 3 writable floats.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn ts_rgb_wavelengths(out: *mut f32) -> c_int {
    status(|| {
        floats(out, "out")?;
        for (k, lambda) in RGB_WAVELENGTHS.iter().enumerate() {
            // SAFETY: checked non-null and aligned; the caller gives 3 floats.
            unsafe { out.add(k).write(*lambda) };
        }
        Ok(())
    })
}

/// Fills `out` with preset `name`'s parameters and the default options, and
/// `out->size` with `sizeof(ts_material_desc)` (a starting point for
/// `ts_material_new`); `out->eta_rows` points to the preset's measured
/// index (static storage).
///
/// # Safety
///
/// `name` is NULL or NUL-terminated; `out` is NULL or writable.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn ts_material_desc_preset(
    name: *const c_char,
    out: *mut ts_material_desc,
) -> c_int {
    status(|| {
        let name = utf8(name, "name")?;
        let desc = preset_desc(name)?;
        // SAFETY: forwarded caller contract.
        unsafe { write_desc(out, &desc) }
    })
}

/// Preset `name` over the spectrum with the default options.
fn preset_desc(name: &str) -> Result<MaterialDesc<'static>, Fail> {
    let spectral = twoscale::materials::spectral(name)
        .ok_or_else(|| Fail::new(TS_ERR_UNKNOWN_MATERIAL, twoscale::UnknownMaterial { name }))?;
    MaterialDesc::spectral(spectral, Options::default(), None).map_err(refused)
}

/// The description of a material file: refused when it gives a tabulated
/// spectrum, whose rows a `ts_material_desc` cannot own.
fn file_desc(desc: &twoscale::io::desc::OwnedMaterialDesc) -> Result<MaterialDesc<'static>, Fail> {
    let desc = desc.get();
    match desc.spectral.map(|s| s.eta) {
        Some(Ior::Tabulated(_)) => Err(Fail::new(
            TS_ERR_INVALID,
            "a material file with eta = { lambda, n, k } does not fit in a ts_material_desc \
             (it would not own the rows): read it with ts_material_file_from_toml",
        )),
        _ => Ok(MaterialDesc {
            spectral: None,
            ..desc
        }),
    }
}

/// Writes `desc` to `out` (checked: not NULL, aligned).
///
/// # Safety
///
/// `out` is NULL or writable.
unsafe fn write_desc(out: *mut ts_material_desc, desc: &MaterialDesc<'_>) -> Result<(), Fail> {
    non_null(out, "out")?;
    if !out.is_aligned() {
        return Err(Fail::new(TS_ERR_MISALIGNED, "out is misaligned"));
    }
    let desc = ts_material_desc::from_model(desc);
    // SAFETY: non-null, aligned, writable by the caller's contract.
    unsafe { out.write(desc) };
    Ok(())
}

/// Fills `out` (and `out->size`) with the material of the TOML text `toml`:
/// a material file, whose `[material]` table has the keys of Python's
/// `twoscale.Material` (`beta`, `p`, `eta = [[n, k], [n, k], [n, k]]`, and
/// optionally `sigma_s`, `b`, `c`, `base`, `albedo`, `lambertian`,
/// `masking`, `sigma_rel`, `colour`, `halo_weight`) and an optional
/// `[metrics]` table, not read (what `python -m twoscale.fit` writes;
/// docs/fitting.md; also `rgb_mode`). `TS_ERR_PARSE`: not TOML, or an
/// unknown, missing or mistyped key; `TS_ERR_INVALID`: a value outside its
/// domain, or `eta = { lambda, n, k }` (a spectrum: its rows would not
/// outlive the call; `ts_material_file_from_toml` reads it). The message
/// is the one Rust and Python give for the same text. `out` is left
/// unchanged on failure.
///
/// # Safety
///
/// `toml` is NULL or NUL-terminated; `out` is NULL or writable.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn ts_material_desc_from_toml(
    toml: *const c_char,
    out: *mut ts_material_desc,
) -> c_int {
    status(|| {
        let text = utf8(toml, "toml")?;
        let desc = file_desc(&MaterialDesc::from_toml_str(text)?)?;
        // SAFETY: forwarded caller contract.
        unsafe { write_desc(out, &desc) }
    })
}

/// `ts_material_desc_from_toml` of the file at `path` (UTF-8 text);
/// `TS_ERR_IO` if it cannot be read. Messages start with the path.
///
/// # Safety
///
/// `path` is NULL or NUL-terminated; `out` is NULL or writable.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn ts_material_desc_from_toml_file(
    path: *const c_char,
    out: *mut ts_material_desc,
) -> c_int {
    status(|| {
        // SAFETY: forwarded caller contract.
        let path = unsafe { self::path(path, "path")? };
        let desc = file_desc(&MaterialDesc::from_toml_file(path)?)?;
        // SAFETY: forwarded caller contract.
        unsafe { write_desc(out, &desc) }
    })
}

/// Reads the material file of the TOML text `toml`, any form of `eta`
/// included (`eta = { lambda, n, k }`: the handle owns the rows), into a new
/// handle at `*out` (free it with `ts_material_file_free`); the checks,
/// status codes and messages are `ts_material_desc_from_toml`'s. `*out` is
/// left unchanged on failure.
///
/// # Safety
///
/// `toml` is NULL or NUL-terminated; `out` is NULL or writable.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn ts_material_file_from_toml(
    toml: *const c_char,
    out: *mut *mut ts_material_file,
) -> c_int {
    status(|| {
        let text = utf8(toml, "toml")?;
        non_null(out, "out")?;
        if !out.is_aligned() {
            return Err(Fail::new(TS_ERR_MISALIGNED, "out is misaligned"));
        }
        let desc = MaterialDesc::from_toml_str(text)?;
        let file = Box::into_raw(Box::new(ts_material_file { desc }));
        // SAFETY: non-null, aligned, writable by the caller's contract.
        unsafe { out.write(file) };
        Ok(())
    })
}

/// Fills `out` (and `out->size`) with the description of `file`; its
/// `eta_rows` (a spectrum's rows, or NULL) point into `file` and stay valid
/// until `ts_material_file_free(file)` (`ts_material_new` copies them).
///
/// # Safety
///
/// `file` is NULL or a live handle; `out` is NULL or writable.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn ts_material_file_desc(
    file: *const ts_material_file,
    out: *mut ts_material_desc,
) -> c_int {
    status(|| {
        non_null(file, "file")?;
        // SAFETY: non-null, a live handle by the caller's contract.
        let file = unsafe { &*file };
        // SAFETY: forwarded caller contract.
        unsafe { write_desc(out, &file.desc.get()) }
    })
}

/// Frees a material file handle (NULL is ignored).
///
/// # Safety
///
/// `file` is NULL or a live handle from `ts_material_file_from_toml`, not
/// used afterwards (nor the rows of a description read from it).
#[unsafe(no_mangle)]
pub unsafe extern "C" fn ts_material_file_free(file: *mut ts_material_file) {
    if !file.is_null() {
        // SAFETY: a live handle made by `Box::into_raw`, freed once.
        let _ = catch_unwind(AssertUnwindSafe(|| drop(unsafe { Box::from_raw(file) })));
    }
}

/// The shipped preset `name` with the paper's options. NULL on failure
/// (`TS_ERR_UNKNOWN_MATERIAL`: the message lists the presets).
///
/// # Safety
///
/// `t` is NULL or a live tables handle; `name` is NULL or NUL-terminated.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn ts_material_preset(
    t: *const ts_tables,
    name: *const c_char,
) -> *mut ts_material {
    handle(|| {
        non_null(t, "the tables")?;
        let name = utf8(name, "name")?;
        let desc = preset_desc(name)?;
        // SAFETY: non-null, a live handle by the caller's contract.
        let t = unsafe { &*t };
        Ok(new_material(t, &desc))
    })
}

/// The material `desc` describes. Construction bakes per-material tables
/// (milliseconds): build once per material, not per evaluation. The tables
/// (~136 KB) are allocated on the heap and filled in place: any thread may
/// build materials (a 64 KiB stack is enough). NULL on failure
/// (`TS_ERR_INVALID`: `desc->size` is not `sizeof(ts_material_desc)`, an
/// unknown enumeration value, or a number outside its domain; the message
/// names the field, its value and its domain).
///
/// # Safety
///
/// `t` is NULL or a live tables handle; `desc` is NULL or readable.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn ts_material_new(
    t: *const ts_tables,
    desc: *const ts_material_desc,
) -> *mut ts_material {
    handle(|| {
        non_null(t, "the tables")?;
        non_null(desc, "desc")?;
        if !desc.is_aligned() {
            return Err(Fail::new(TS_ERR_MISALIGNED, "desc is misaligned"));
        }
        // SAFETY: non-null, aligned, and by the caller's contract readable
        // for at least the `size` field, which every layout starts with.
        let size = unsafe { std::ptr::addr_of!((*desc).size).read() };
        if size != desc_size() {
            return Err(Fail::new(
                TS_ERR_INVALID,
                format!(
                    "ts_material_desc.size = {size} is not sizeof(ts_material_desc) = {} \
                     of this library (set it to sizeof(ts_material_desc))",
                    desc_size()
                ),
            ));
        }
        // SAFETY: as above, and `size` says the caller's struct is this
        // layout; every field is a plain number or a raw pointer, so any bit
        // pattern is a valid value.
        let desc = unsafe { desc.read() };
        // SAFETY: the caller's contract: `eta_rows` NULL or readable rows,
        // used only within this call (`new_material` copies them).
        let desc = unsafe { desc.to_model()? };
        // SAFETY: non-null, a live handle by the caller's contract.
        let t = unsafe { &*t };
        Ok(new_material(t, &desc))
    })
}

/// Frees a material handle (NULL is ignored).
///
/// # Safety
///
/// `m` is NULL or a live handle from `ts_material_*`, not used afterwards.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn ts_material_free(m: *mut ts_material) {
    if !m.is_null() {
        // SAFETY: a live handle made by `Box::into_raw`, freed once.
        let _ = catch_unwind(AssertUnwindSafe(|| drop(unsafe { Box::from_raw(m) })));
    }
}

/// ρ(wi, wo) per channel (sr⁻¹; red, green, blue) into `out`. `wi` points
/// towards the light, `wo` towards the viewer, the normal is +z; neither
/// needs to be normalised. Either below the horizon gives 0.
///
/// # Safety
///
/// `m` is NULL or a live material; each array is NULL or holds 3 floats.
/// cbindgen:ptrs-as-arrays=[[wi;3], [wo;3], [out;3]]
// The annotation's brackets are cbindgen syntax, not links.
#[allow(rustdoc::broken_intra_doc_links)]
#[unsafe(no_mangle)]
pub unsafe extern "C" fn ts_eval_rgb(
    m: *const ts_material,
    wi: *const f32,
    wo: *const f32,
    out: *mut f32,
) -> c_int {
    // SAFETY: forwarded caller contract; one direction pair is a batch of 1.
    unsafe { ts_eval_rgb_batch(m, 1, wi, wo, out) }
}

/// ρ(wi, wo) (sr⁻¹) at four wavelengths `lambda` (µm, each in
/// [0.36, 0.83]) into `out`, as spectral renderers carry them: the model that
/// serves every wavelength from one construction (docs/model.md §2.12),
/// built by the first call on the material (milliseconds; thread-safe). For
/// presets (their measured index) and materials whose `eta` is one (n, k)
/// for every channel; other materials give `TS_ERR_INVALID`, as does a
/// wavelength outside the range or a non-finite direction.
///
/// # Safety
///
/// `m` is NULL or a live material; `wi`, `wo` are NULL or hold 3 floats,
/// `lambda` and `out` NULL or 4.
/// cbindgen:ptrs-as-arrays=[[wi;3], [wo;3], [lambda;4], [out;4]]
// The annotation's brackets are cbindgen syntax, not links.
#[allow(rustdoc::broken_intra_doc_links)]
#[unsafe(no_mangle)]
pub unsafe extern "C" fn ts_eval_spectral(
    m: *const ts_material,
    wi: *const f32,
    wo: *const f32,
    lambda: *const f32,
    out: *mut f32,
) -> c_int {
    status(|| {
        // SAFETY: the caller's contract.
        let m = unsafe { material(m) }?;
        floats(wi, "wi")?;
        floats(wo, "wo")?;
        floats(lambda, "lambda")?;
        floats(out, "out")?;
        // SAFETY: checked pointers; the caller gives 3, 3 and 4 floats.
        let (i, o) = unsafe { (read3(wi, 0, "wi")?, read3(wo, 0, "wo")?) };
        // SAFETY: as above.
        let lambdas: [f32; 4] = unsafe { [0, 1, 2, 3].map(|k| lambda.add(k).read()) };
        let (lo, hi) = (
            SPECTRAL_WAVELENGTHS[0],
            SPECTRAL_WAVELENGTHS[SPECTRAL_WAVELENGTHS.len() - 1],
        );
        if let Some(k) = lambdas.iter().position(|l| !(*l >= lo && *l <= hi)) {
            return Err(Fail::new(
                TS_ERR_INVALID,
                format!("lambda[{k}] = {} is not in [{lo}, {hi}] µm", lambdas[k]),
            ));
        }
        let Some(spectral) = &m.spectral else {
            return Err(Fail::new(
                TS_ERR_INVALID,
                "ts_eval_spectral needs an index over the spectrum: a preset, eta_rows, or one (n, k) for every channel",
            ));
        };
        let model = m.spectral_model.get_or_init(|| {
            let model = Spectral::boxed(&m._tables.set().brdf_tables(), &spectral.get(), m.options);
            // SAFETY: as in `new_material_with`: the model borrows only the
            // `TableSet` inside the `Arc` the handle keeps (`_tables`,
            // declared after `spectral_model`, so dropped after it).
            unsafe { std::mem::transmute::<BoxedSpectral<'_>, BoxedSpectral<'static>>(model) }
        });
        let values = model.eval4(i, o, lambdas);
        for (k, v) in values.iter().enumerate() {
            // SAFETY: `out` holds 4 floats by the caller's contract.
            unsafe { out.add(k).write(*v) };
        }
        Ok(())
    })
}

/// The sampling density of `wo` given `wi` (solid angle), the density of
/// `ts_sample_rgb`, into `*pdf`.
///
/// # Safety
///
/// `m` is NULL or a live material; `wi`, `wo` are NULL or hold 3 floats;
/// `pdf` is NULL or writable.
/// cbindgen:ptrs-as-arrays=[[wi;3], [wo;3]]
// The annotation's brackets are cbindgen syntax, not links.
#[allow(rustdoc::broken_intra_doc_links)]
#[unsafe(no_mangle)]
pub unsafe extern "C" fn ts_pdf(
    m: *const ts_material,
    wi: *const f32,
    wo: *const f32,
    pdf: *mut f32,
) -> c_int {
    // SAFETY: forwarded caller contract; a batch of 1.
    unsafe { ts_pdf_batch(m, 1, wi, wo, pdf) }
}

/// Samples an outgoing direction for `wi` with the uniform numbers `u` in
/// [0, 1) (`u[0]` picks the channel and lobe, `u[1]`, `u[2]` the direction).
/// `out->pdf == 0` if no direction was sampled (not an error).
///
/// # Safety
///
/// `m` is NULL or a live material; `wi`, `u` are NULL or hold 3 floats;
/// `out` is NULL or writable.
/// cbindgen:ptrs-as-arrays=[[wi;3], [u;3]]
// The annotation's brackets are cbindgen syntax, not links.
#[allow(rustdoc::broken_intra_doc_links)]
#[unsafe(no_mangle)]
pub unsafe extern "C" fn ts_sample_rgb(
    m: *const ts_material,
    wi: *const f32,
    u: *const f32,
    out: *mut ts_sample,
) -> c_int {
    // SAFETY: forwarded caller contract; a batch of 1.
    unsafe { ts_sample_rgb_batch(m, 1, wi, u, out) }
}

/// `ts_eval_rgb` over `n` direction pairs: `wi`, `wo` and `out` hold `3 n`
/// floats (x, y, z / r, g, b interleaved). `out` may alias `wi` or `wo`. On
/// a non-finite direction, stops with `TS_ERR_INVALID` (the message gives the
/// index; entries before it are written).
///
/// # Safety
///
/// `m` is NULL or a live material; each array is NULL or holds `3 n` floats.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn ts_eval_rgb_batch(
    m: *const ts_material,
    n: usize,
    wi: *const f32,
    wo: *const f32,
    out: *mut f32,
) -> c_int {
    status(|| {
        // SAFETY: the caller's contract.
        let m = unsafe { material(m) }?;
        triples(n)?;
        floats(wi, "wi")?;
        floats(wo, "wo")?;
        floats(out, "out")?;
        for j in 0..n {
            // SAFETY: checked pointers; the caller gives 3 n floats each.
            let (i, o) = unsafe { (read3(wi, j, "wi")?, read3(wo, j, "wo")?) };
            let value = Bxdf::eval(&m.rgb, i, o);
            for (k, v) in value.iter().enumerate() {
                // SAFETY: as above; element-wise writes allow aliasing.
                unsafe { out.add(3 * j + k).write(*v) };
            }
        }
        Ok(())
    })
}

/// `ts_pdf` over `n` direction pairs: `wi`, `wo` hold `3 n` floats, `pdf`
/// `n` floats.
///
/// # Safety
///
/// `m` is NULL or a live material; `wi`, `wo` are NULL or hold `3 n` floats;
/// `pdf` is NULL or holds `n` floats.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn ts_pdf_batch(
    m: *const ts_material,
    n: usize,
    wi: *const f32,
    wo: *const f32,
    pdf: *mut f32,
) -> c_int {
    status(|| {
        // SAFETY: the caller's contract.
        let m = unsafe { material(m) }?;
        triples(n)?;
        floats(wi, "wi")?;
        floats(wo, "wo")?;
        floats(pdf, "pdf")?;
        for j in 0..n {
            // SAFETY: checked pointers; the caller gives 3 n floats each.
            let (i, o) = unsafe { (read3(wi, j, "wi")?, read3(wo, j, "wo")?) };
            // SAFETY: checked pointer; the caller gives n floats.
            unsafe { pdf.add(j).write(Bxdf::pdf(&m.rgb, i, o)) };
        }
        Ok(())
    })
}

/// `ts_sample_rgb` over `n` directions: `wi`, `u` hold `3 n` floats, `out`
/// `n` samples.
///
/// # Safety
///
/// `m` is NULL or a live material; `wi`, `u` are NULL or hold `3 n` floats;
/// `out` is NULL or holds `n` samples.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn ts_sample_rgb_batch(
    m: *const ts_material,
    n: usize,
    wi: *const f32,
    u: *const f32,
    out: *mut ts_sample,
) -> c_int {
    status(|| {
        // SAFETY: the caller's contract.
        let m = unsafe { material(m) }?;
        triples(n)?;
        floats(wi, "wi")?;
        floats(u, "u")?;
        non_null(out, "out")?;
        if !out.is_aligned() {
            return Err(Fail::new(TS_ERR_MISALIGNED, "out is misaligned"));
        }
        for j in 0..n {
            // SAFETY: checked pointers; the caller gives 3 n floats each.
            let (i, u) = unsafe { (read3(wi, j, "wi")?, read3(u, j, "u")?) };
            let sample = match Bxdf::sample(&m.rgb, i, u) {
                Some(s) => ts_sample {
                    wo: s.o,
                    pdf: s.pdf,
                    value: s.value,
                },
                None => ts_sample::default(),
            };
            // SAFETY: checked pointer; the caller gives n samples.
            unsafe { out.add(j).write(sample) };
        }
        Ok(())
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Every preset and every option survives the trip through the C
    /// description, and a description built from a preset gives the preset's
    /// values.
    #[test]
    fn descriptions_round_trip() {
        let all_options = [Masking::Separable, Masking::HeightCorrelated]
            .into_iter()
            .flat_map(|masking| {
                [SigmaRelMode::Incident, SigmaRelMode::Symmetrised]
                    .into_iter()
                    .map(move |sigma_rel| (masking, sigma_rel))
            })
            .flat_map(|(masking, sigma_rel)| {
                [ColourTerms::Physical, ColourTerms::White]
                    .into_iter()
                    .flat_map(move |colour| {
                        [HaloWeight::Printed, HaloWeight::Incident].map(|halo_weight| Options {
                            masking,
                            sigma_rel,
                            colour,
                            halo_weight,
                            multiple_scattering: MultipleScattering::None,
                        })
                    })
            })
            .flat_map(|o| {
                [MultipleScattering::None, MultipleScattering::KullaConty].map(
                    |multiple_scattering| Options {
                        multiple_scattering,
                        ..o
                    },
                )
            })
            .collect::<Vec<_>>();
        assert_eq!(all_options.len(), 32);
        for (name, material) in PRESETS {
            for options in &all_options {
                for rgb_mode in [RgbMode::PaperWavelengths, RgbMode::Integrated] {
                    let want = MaterialDesc {
                        options: *options,
                        rgb_mode,
                        ..preset_desc(name).ok().expect(name)
                    };
                    let desc = ts_material_desc::from_model(&want);
                    let constant = matches!(want.spectral.map(|s| s.eta), Some(Ior::Constant(_)));
                    assert_eq!(desc.eta_rows.is_null(), constant, "{name}");
                    // SAFETY: the preset's static rows.
                    let back = unsafe { desc.to_model() }.ok().expect(name);
                    assert_eq!(back, want, "{name}");
                    assert_eq!(back.material, material, "{name}");
                }
            }
        }
        // Zeroed enumeration fields are the defaults; zeroed numbers are not
        // a surface (β = 0 is outside the EPD's domain).
        let zero = ts_material_desc {
            beta: 0.3,
            p: 1.0,
            c: 2.0,
            eta_re: [1.5; 3],
            ..ts_material_desc::default()
        };
        // SAFETY: no rows.
        let desc = unsafe { zero.to_model() }
            .ok()
            .expect("zeroed enumerations");
        assert_eq!(desc.options, Options::default());
        assert_eq!(desc.rgb_mode, RgbMode::PaperWavelengths);
        assert_eq!(desc.material.layer.base, BaseLayer::Conductor);
        // SAFETY: no rows.
        let Err(Fail(code, message)) = (unsafe { ts_material_desc::default().to_model() }) else {
            panic!("β = 0 accepted");
        };
        assert_eq!(code, TS_ERR_INVALID);
        assert!(
            message.starts_with("ts_material_desc.beta = 0: must be in"),
            "{message}"
        );
    }

    /// Each parameter outside the runtime's domain is rejected with the
    /// runtime validation's message, naming the description's field.
    #[test]
    fn out_of_domain_descriptions_are_rejected() {
        let gold = twoscale::materials::preset("gold-rough").expect("preset");
        let gold = MaterialDesc::rgb(gold, Options::default(), None).expect("valid");
        let base = ts_material_desc::from_model(&gold);
        type Edit = fn(&mut ts_material_desc);
        let cases: [(Edit, &str); 14] = [
            (
                |d| d.beta = -0.1,
                "ts_material_desc.beta = -0.1: must be in",
            ),
            (
                |d| d.p = 100.0,
                "ts_material_desc.p = 100: must be in [0.2, 5]",
            ),
            (
                |d| d.c = 0.5,
                "ts_material_desc.c = 0.5: must be finite and > 1",
            ),
            (
                |d| d.sigma_s = -1.0,
                "ts_material_desc.sigma_s = -1: must be finite and ≥ 0",
            ),
            (
                |d| d.b = -5.0,
                "ts_material_desc.b = -5: must be finite and ≥ 0",
            ),
            (
                |d| d.base_albedo = 0.5,
                "ts_material_desc.base_albedo = 0.5",
            ),
            (|d| d.eta_im[1] = -1.0, "ts_material_desc.eta_im[1] = -1"),
            (
                |d| d.eta_re[2] = f32::NAN,
                "ts_material_desc.eta_re[2] = NaN",
            ),
            (|d| d.lambertian = 2.0, "ts_material_desc.lambertian = 2"),
            (
                |d| d.rgb_mode = TS_RGB_MODE_INTEGRATED,
                "ts_material_desc: rgb_mode 'integrated' needs an index over the spectrum",
            ),
            (
                |d| d.rgb_mode = 7,
                "ts_material_desc.rgb_mode = 7 is not one of",
            ),
            (
                |d| d.eta_row_count = 2,
                "ts_material_desc.eta_row_count = 2 with eta_rows NULL",
            ),
            (
                |d| {
                    d.eta_rows = DECREASING.as_ptr().cast();
                    d.eta_row_count = 2;
                },
                "ts_material_desc.eta_rows[].lambda = 0.4: must be finite and > 0.5",
            ),
            (
                |d| {
                    d.eta_rows = DECREASING.as_ptr().cast();
                    d.eta_row_count = 0;
                },
                "ts_material_desc.eta_row_count = 0: must be",
            ),
        ];
        static DECREASING: [[f32; 3]; 2] = [[0.5, 1.0, 2.0], [0.4, 1.0, 2.0]];
        assert_eq!(base.base, TS_BASE_CONDUCTOR);
        for (edit, want) in cases {
            let mut desc = base;
            edit(&mut desc);
            // SAFETY: NULL or static rows.
            match unsafe { desc.to_model() } {
                Err(Fail(code, message)) => {
                    assert_eq!(code, TS_ERR_INVALID, "{message}");
                    assert!(message.starts_with(want), "{message} (want {want})");
                }
                Ok(_) => panic!("accepted: {desc:?} (want {want})"),
            }
        }
    }

    /// A material file reads into the description of the runtime's
    /// material, and each fault keeps the runtime's message, with its code.
    #[test]
    fn toml_descriptions_are_the_runtimes() {
        let text = "[material]\nbeta = 0.2\np = 0.8\neta = [[0.2, 3.0], [0.5, 2.5], [1.2, 1.9]]\n\
                    sigma_s = 0.03\nb = 2.0\nlambertian = 0.05\nsigma_rel = \"symmetrised\"\n\
                    [metrics]\nrmse = [0.1, 0.1, 0.1]\n";
        let c_text = CString::new(text).expect("no NUL");
        let mut out = ts_material_desc::default();
        // SAFETY: a NUL-terminated string and a writable description.
        let status = unsafe { ts_material_desc_from_toml(c_text.as_ptr(), &mut out) };
        assert_eq!(status, TS_OK);
        let want = MaterialDesc::from_toml_str(text).expect("valid");
        // SAFETY: no rows.
        assert_eq!(unsafe { out.to_model() }.ok(), Some(want.get()));
        let eta = "eta = [[1, 0], [1, 0], [1, 0]]";
        let cases = [
            (
                format!("[material]\nbeta = 20\np = 1\n{eta}"),
                TS_ERR_INVALID,
            ),
            (
                format!("[material]\nbeta = 0.1\np = 1\n{eta}\nbase = \"wood\""),
                TS_ERR_INVALID,
            ),
            (format!("[material]\nbeta = 0.1\n{eta}"), TS_ERR_PARSE),
            (
                format!("[material]\nbeta = 0.1\np = 1\n{eta}\n[fit]"),
                TS_ERR_PARSE,
            ),
        ];
        for (text, code) in cases {
            let c_text = CString::new(text.as_str()).expect("no NUL");
            // SAFETY: as above.
            let status = unsafe { ts_material_desc_from_toml(c_text.as_ptr(), &mut out) };
            assert_eq!(status, code, "{text}");
            // SAFETY: the last error is a NUL-terminated string.
            let message = unsafe { CStr::from_ptr(ts_last_error()) }
                .to_str()
                .expect("UTF-8");
            let want = MaterialDesc::from_toml_str(&text).expect_err("refused");
            assert_eq!(message, want.message);
        }
    }

    #[test]
    fn preset_handle_matches_the_runtime() {
        let tables = ts_tables_embedded();
        assert!(!tables.is_null());
        let set = TableSet::embedded();
        let (i, o) = ([0.6, 0.1, 0.8], [-0.55, -0.05, 0.83]);
        for (name, _) in PRESETS {
            let c_name = CString::new(name).expect("no NUL");
            // SAFETY: a live handle and a NUL-terminated name.
            let m = unsafe { ts_material_preset(tables, c_name.as_ptr()) };
            assert!(!m.is_null(), "{name}");
            let mut out = [0.0f32; 3];
            // SAFETY: a live material and three-float arrays.
            let status = unsafe { ts_eval_rgb(m, i.as_ptr(), o.as_ptr(), out.as_mut_ptr()) };
            assert_eq!(status, TS_OK);
            let expected = Bxdf::eval(&set.preset(name).expect("preset"), i, o);
            assert_eq!(out, expected, "{name}");
            // SAFETY: live handles, freed once.
            unsafe { ts_material_free(m) };
        }
        // SAFETY: a live handle, freed once.
        unsafe { ts_tables_free(tables) };
    }
}
