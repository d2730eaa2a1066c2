//! Optical constants over the spectrum: the complex index `η(λ) = n(λ) + i k(λ)`
//! of a material, constant or tabulated, and the measured tables of the
//! shipped metals.
//!
//! # Sources (data/optical-constants/, refractiveindex.info, CC0 1.0)
//!
//! | metal | constant | source |
//! |---|---|---|
//! | gold, silver, copper | [`AU_JOHNSON`], [`AG_JOHNSON`], [`CU_JOHNSON`] | P. B. Johnson and R. W. Christy, "Optical constants of the noble metals", Phys. Rev. B 6, 4370 (1972) |
//! | nickel, chromium, titanium, iron | [`NI_JOHNSON`], [`CR_JOHNSON`], [`TI_JOHNSON`], [`FE_JOHNSON`] | P. B. Johnson and R. W. Christy, "Optical constants of transition metals: Ti, V, Cr, Mn, Fe, Co, Ni, and Pd", Phys. Rev. B 9, 5056 (1974) |
//! | aluminium | [`AL_RAKIC`] | A. D. Rakić, "Algorithm for the determination of intrinsic optical constants of metal films: application to aluminum", Appl. Opt. 34, 4755 (1995) |
//!
//! Each table holds the rows of its file that cover [0.36, 0.83] µm plus the
//! nearest row beyond each end (`data/generate.py` writes them; the test
//! `embedded_tables_are_the_files` checks them against the files).
//!
//! # Interpolation
//!
//! Between rows, n and k are linear in photon energy `E ∝ 1/λ` (Johnson &
//! Christy's rows are about evenly spaced in E); outside the rows they are
//! held at the end row. Its error is estimated by leaving each interior row
//! out and interpolating it from its neighbours over [0.36, 0.83] µm (test
//! `leave_one_out_error_is_as_documented`; twice the row spacing, so an upper
//! estimate of the error between rows): at most 0.20 in n or k, and the
//! normal-incidence reflectance `R = |(η−1)/(η+1)|²` within 0.059 of the
//! row's (p50 0.0016). The largest errors sit on gold's and copper's
//! absorption edges (0.50 and 0.62 µm: ΔR 0.058, 0.051); the other metals
//! stay within ΔR 0.01.

use crate::domain::Invalid;
use crate::material::{Layer, Material};
use crate::math::Complex;
use crate::validate;

#[rustfmt::skip]
#[allow(clippy::approx_constant)] // measured values (chromium's k = 3.14 at 0.451 µm), not π
mod data {
    include!("optical_data.rs");
}
pub use data::{
    AG_JOHNSON, AL_RAKIC, AU_JOHNSON, CR_JOHNSON, CU_JOHNSON, FE_JOHNSON, NI_JOHNSON, TI_JOHNSON,
};

/// The spectral range the shipped tables cover, µm (with one row beyond each end).
pub const SPECTRAL_RANGE: (f32, f32) = (0.36, 0.83);

/// A tabulated index `(λ µm, n, k)` per row, λ strictly increasing
/// ([`Tabulated::new`] checks it; the shipped constants are checked by a test).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Tabulated<'a> {
    rows: &'a [[f32; 3]],
}

/// The index of refraction of a material over the spectrum.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Ior<'a> {
    /// The same `n + ik` at every wavelength (a dielectric varnish, or a
    /// renderer's single value).
    Constant(Complex),
    /// Tabulated rows, interpolated (module documentation).
    Tabulated(Tabulated<'a>),
}

impl<'a> Tabulated<'a> {
    /// Checked rows: at least one; λ finite, > 0 and strictly increasing;
    /// `n > 0`, `k ≥ 0` finite ([`validate::optical_constants`]).
    pub fn new(rows: &'a [[f32; 3]]) -> Result<Self, Invalid> {
        validate::optical_constants(rows)?;
        Ok(Tabulated { rows })
    }

    /// Rows known to be valid (the shipped tables; a test checks them).
    pub const fn shipped(rows: &'static [[f32; 3]]) -> Tabulated<'static> {
        Tabulated { rows }
    }

    /// The rows.
    pub fn rows(&self) -> &'a [[f32; 3]] {
        self.rows
    }

    /// `n + ik` at `lambda` (µm): linear in `1/λ` between the rows around
    /// it, the end row's value outside them (and for NaN).
    pub const fn at(&self, lambda: f32) -> Complex {
        let rows = self.rows;
        let count = rows.len();
        if count == 0 {
            return Complex::real(1.0);
        }
        if !(lambda > rows[0][0]) {
            return Complex::new(rows[0][1], rows[0][2]);
        }
        if !(lambda < rows[count - 1][0]) {
            return Complex::new(rows[count - 1][1], rows[count - 1][2]);
        }
        // First row with λ ≥ lambda (1 ≤ hi < count).
        let mut hi = 1;
        while hi < count - 1 && rows[hi][0] < lambda {
            hi += 1;
        }
        let (a, b) = (rows[hi - 1], rows[hi]);
        let (ea, eb, e) = (1.0 / a[0] as f64, 1.0 / b[0] as f64, 1.0 / lambda as f64);
        let t = (e - ea) / (eb - ea);
        Complex::new(lerp(a[1], b[1], t), lerp(a[2], b[2], t))
    }
}

impl Ior<'_> {
    /// `n + ik` at `lambda` (µm).
    pub const fn at(&self, lambda: f32) -> Complex {
        match self {
            Ior::Constant(eta) => *eta,
            Ior::Tabulated(t) => t.at(lambda),
        }
    }

    /// The index at the paper's RGB wavelengths ([`crate::material::RGB_WAVELENGTHS`]).
    pub const fn at_rgb(&self) -> [Complex; 3] {
        let l = crate::material::RGB_WAVELENGTHS;
        [self.at(l[0]), self.at(l[1]), self.at(l[2])]
    }
}

/// `x + t (y − x)` in f64, rounded to f32.
const fn lerp(x: f32, y: f32, t: f64) -> f32 {
    (x as f64 + t * (y as f64 - x as f64)) as f32
}

/// A layered material with its index over the spectrum (the spectral
/// counterpart of [`Material`]; for a dielectric base the varnish index is
/// `Re η(λ)`).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SpectralMaterial<'a> {
    /// Geometry, base layer, Lambertian term.
    pub layer: Layer,
    /// The index over the spectrum.
    pub eta: Ior<'a>,
}

impl SpectralMaterial<'_> {
    /// The material at the paper's three RGB wavelengths (HP15 §5.5).
    pub const fn paper_rgb(&self) -> Material {
        Material {
            layer: self.layer,
            eta_rgb: self.eta.at_rgb(),
        }
    }

    /// `material` over the spectrum when it has one index for every channel
    /// (a constant [`Ior`]); `None` when its channels' indices differ (they
    /// are no spectrum).
    pub fn with_one_index(material: &Material) -> Option<SpectralMaterial<'static>> {
        let first = material.eta_rgb[0];
        material
            .eta_rgb
            .iter()
            .all(|&eta| eta == first)
            .then_some(SpectralMaterial {
                layer: material.layer,
                eta: Ior::Constant(first),
            })
    }

    /// Checks the layer ([`Layer::validate`]) and the index (every row, or
    /// the constant, as [`validate::eta`]).
    pub fn validate(&self) -> Result<(), Invalid> {
        self.layer.validate()?;
        match self.eta {
            Ior::Constant(eta) => validate::eta(("n", "k"), eta),
            Ior::Tabulated(t) => validate::optical_constants(t.rows),
        }
    }
}

/// A [`SpectralMaterial`] that owns its rows (feature `std`): what a front
/// end keeps of a material given at run time (Python's `Material`, the C
/// API's handle, a material file). Built from a valid material only, so
/// [`OwnedSpectralMaterial::get`] gives one.
#[cfg(feature = "std")]
#[derive(Clone, Debug, PartialEq)]
pub struct OwnedSpectralMaterial {
    layer: Layer,
    /// The constant index, or `None` for `rows`.
    constant: Option<Complex>,
    rows: std::vec::Vec<[f32; 3]>,
}

#[cfg(feature = "std")]
impl OwnedSpectralMaterial {
    /// A copy of `material` (its rows copied).
    pub fn new(material: &SpectralMaterial<'_>) -> Self {
        let (constant, rows) = match material.eta {
            Ior::Constant(eta) => (Some(eta), std::vec::Vec::new()),
            Ior::Tabulated(t) => (None, t.rows.to_vec()),
        };
        OwnedSpectralMaterial {
            layer: material.layer,
            constant,
            rows,
        }
    }

    /// The material, borrowing the rows.
    pub fn get(&self) -> SpectralMaterial<'_> {
        SpectralMaterial {
            layer: self.layer,
            eta: match self.constant {
                Some(eta) => Ior::Constant(eta),
                None => Ior::Tabulated(Tabulated { rows: &self.rows }),
            },
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const FILES: [(&str, &[[f32; 3]]); 8] = [
        (
            include_str!("../../../data/optical-constants/Au-Johnson.yml"),
            &AU_JOHNSON,
        ),
        (
            include_str!("../../../data/optical-constants/Ag-Johnson.yml"),
            &AG_JOHNSON,
        ),
        (
            include_str!("../../../data/optical-constants/Cu-Johnson.yml"),
            &CU_JOHNSON,
        ),
        (
            include_str!("../../../data/optical-constants/Ni-Johnson.yml"),
            &NI_JOHNSON,
        ),
        (
            include_str!("../../../data/optical-constants/Cr-Johnson.yml"),
            &CR_JOHNSON,
        ),
        (
            include_str!("../../../data/optical-constants/Ti-Johnson.yml"),
            &TI_JOHNSON,
        ),
        (
            include_str!("../../../data/optical-constants/Fe-Johnson.yml"),
            &FE_JOHNSON,
        ),
        (
            include_str!("../../../data/optical-constants/Al-Rakic.yml"),
            &AL_RAKIC,
        ),
    ];

    /// The `λ n k` rows of a refractiveindex.info file.
    fn file_rows(text: &str) -> Vec<[f64; 3]> {
        text.lines()
            .filter_map(|line| {
                let v: Vec<f64> = line
                    .split_whitespace()
                    .map(|x| x.parse::<f64>())
                    .collect::<Result<_, _>>()
                    .ok()?;
                (v.len() == 3).then(|| [v[0], v[1], v[2]])
            })
            .collect()
    }

    #[test]
    fn embedded_tables_are_the_files() {
        let (lo, hi) = SPECTRAL_RANGE;
        for (text, table) in FILES {
            let rows = file_rows(text);
            let first = rows.iter().rposition(|r| r[0] <= f64::from(lo)).unwrap();
            let last = rows.iter().position(|r| r[0] >= f64::from(hi)).unwrap();
            let want = &rows[first..=last];
            assert_eq!(want.len(), table.len());
            for (w, t) in want.iter().zip(table.iter()) {
                for k in 0..3 {
                    assert_eq!(w[k] as f32, t[k], "{w:?} vs {t:?}");
                }
            }
            validate::optical_constants(table).unwrap();
        }
    }

    fn reflectance(eta: Complex) -> f64 {
        let (n, k) = (f64::from(eta.re), f64::from(eta.im));
        ((n - 1.0).powi(2) + k * k) / ((n + 1.0).powi(2) + k * k)
    }

    #[test]
    fn leave_one_out_error_is_as_documented() {
        let (lo, hi) = SPECTRAL_RANGE;
        let mut worst_index = 0.0f64;
        let mut r_errors = Vec::new();
        for (_, table) in FILES {
            for j in 1..table.len() - 1 {
                let lambda = table[j][0];
                if lambda < lo || lambda > hi {
                    continue;
                }
                let neighbours = [table[j - 1], table[j + 1]];
                let eta = Tabulated::new(&neighbours).unwrap().at(lambda);
                let row = Complex::new(table[j][1], table[j][2]);
                let dn = f64::from((eta.re - row.re).abs());
                let dk = f64::from((eta.im - row.im).abs());
                worst_index = worst_index.max(dn).max(dk);
                r_errors.push((reflectance(eta) - reflectance(row)).abs());
            }
        }
        r_errors.sort_by(f64::total_cmp);
        let max_r = *r_errors.last().unwrap();
        let p50 = r_errors[r_errors.len() / 2];
        eprintln!("leave-one-out: max |Δn|,|Δk| {worst_index:.3}, R max {max_r:.4} p50 {p50:.4}");
        assert!(worst_index <= 0.21, "{worst_index}");
        assert!(max_r <= 0.059, "{max_r}");
        assert!(p50 <= 0.0017, "{p50}");
    }

    #[test]
    fn interpolation_hits_the_rows_and_holds_the_ends() {
        let t = Tabulated::shipped(&AU_JOHNSON);
        for row in AU_JOHNSON {
            assert_eq!(t.at(row[0]), Complex::new(row[1], row[2]));
        }
        let first = AU_JOHNSON[0];
        assert_eq!(t.at(0.1), Complex::new(first[1], first[2]));
        assert_eq!(t.at(f32::NAN), Complex::new(first[1], first[2]));
        let last = AU_JOHNSON[AU_JOHNSON.len() - 1];
        assert_eq!(t.at(5.0), Complex::new(last[1], last[2]));
        // Linear in 1/λ: the midpoint in energy gives the mean.
        let (a, b) = (AU_JOHNSON[3], AU_JOHNSON[4]);
        let mid = 2.0 / (1.0 / a[0] + 1.0 / b[0]);
        let eta = t.at(mid);
        assert!((eta.re - 0.5 * (a[1] + b[1])).abs() < 1e-5);
        assert!((eta.im - 0.5 * (a[2] + b[2])).abs() < 1e-5);
    }

    #[test]
    fn one_index_for_every_channel_is_a_spectrum() {
        let mut m = crate::materials::preset("gold-rough").unwrap();
        assert_eq!(SpectralMaterial::with_one_index(&m), None);
        m.eta_rgb = [Complex::new(1.5, 2.0); 3];
        let s = SpectralMaterial::with_one_index(&m).unwrap();
        assert_eq!(s.eta, Ior::Constant(Complex::new(1.5, 2.0)));
        assert_eq!(s.paper_rgb(), m);
    }

    #[test]
    fn bad_rows_are_rejected() {
        assert!(Tabulated::new(&[]).is_err());
        let e = Tabulated::new(&[[0.5, 1.0, 2.0], [0.4, 1.0, 2.0]]).unwrap_err();
        assert_eq!(e.name, "lambda");
        assert!(Tabulated::new(&[[0.5, -1.0, 2.0]]).is_err());
        assert!(Tabulated::new(&[[0.5, 1.0, f32::NAN]]).is_err());
        assert!(Tabulated::new(&[[f32::INFINITY, 1.0, 1.0]]).is_err());
    }

    /// The gold presets' RGB indices agree with a hand interpolation of
    /// Johnson & Christy's rows (0.645 µm: 1.88 eV 0.14 + 3.697i, 2.01 eV
    /// 0.21 + 3.272i; 0.526 µm: 2.26 eV 0.43 + 2.455i, 2.38 eV 0.62 +
    /// 2.081i; 0.444 µm: 2.75 eV 1.38 + 1.914i, 2.88 eV 1.45 + 1.948i),
    /// rounded to 3–4 digits.
    #[test]
    fn gold_rgb_indices_agree_with_a_hand_interpolation() {
        let by_hand = [
            Complex::new(0.163, 3.56),
            Complex::new(0.584, 2.15),
            Complex::new(1.403, 1.925),
        ];
        let gold = crate::materials::preset("gold-hp17-geometry").unwrap();
        for (a, b) in gold.eta_rgb.iter().zip(by_hand) {
            assert!(
                (a.re - b.re).abs() < 0.006 && (a.im - b.im).abs() < 0.006,
                "{a:?} {b:?}"
            );
        }
    }
}
