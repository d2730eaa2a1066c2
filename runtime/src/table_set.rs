//! The tables the BRDF reads (T1, T2, T3, T5), validated together, and the
//! shipped material presets built from them.
//!
//! ```
//! # #[cfg(feature = "embedded")] {
//! let tables = twoscale::TableSet::embedded();
//! let gold = tables.material("gold-rough").expect("a shipped preset");
//! let rgb = gold.eval([0.6, 0.0, 0.8], [-0.6, 0.0, 0.8]);
//! assert!(rgb.iter().all(|v| *v > 0.0));
//! # }
//! ```
//!
//! Three ways to get a set: [`TableSet::embedded`] (feature `embedded`: the
//! committed tables compiled into the crate, no files at run time, `no_std`),
//! [`TableSet::from_bytes`] (any 64-byte-aligned bytes, `no_std`) and
//! [`TableSet::open`] (feature `std`: read-only memory maps of a directory).

use crate::brdf::{Material, Options, Rgb, Tables};
use crate::conv::ConvTable;
use crate::format::{FormatError, TableId};
use crate::fresnel::DiffuseFresnelTable;
use crate::kcorr::SigmaRatioTable;
use crate::materials::PRESETS;
use crate::smith::SmithG1Table;
use core::fmt;

/// The tables of a set, in the order of [`TableBytes`]' fields; each is the
/// file `<TableId::name()>.tbl`.
pub const TABLES: [TableId; 4] = [
    TableId::SmithG1,
    TableId::SigmaRatio,
    TableId::Convolution,
    TableId::DiffuseFresnel,
];

/// The bytes of the four files (each 64-byte aligned, e.g. from
/// [`include_table!`](crate::include_table) or a memory map).
#[derive(Clone, Copy, Debug)]
pub struct TableBytes<'a> {
    /// `t1-smith-g1.tbl`.
    pub smith: &'a [u8],
    /// `t2-sigma-ratio.tbl`.
    pub sigma_ratio: &'a [u8],
    /// `t3-convolution.tbl`.
    pub convolution: &'a [u8],
    /// `t5-diffuse-fresnel.tbl`.
    pub diffuse_fresnel: &'a [u8],
}

/// Why a table set could not be formed: which file, and what is wrong with it.
#[derive(Debug)]
pub enum TableSetError {
    /// The file's bytes are not a valid table of the expected kind.
    Format {
        /// The table (its file is `<name>.tbl`).
        table: TableId,
        /// The fault.
        error: FormatError,
    },
    /// The file could not be opened or mapped.
    #[cfg(feature = "std")]
    Io {
        /// The path that failed.
        path: std::path::PathBuf,
        /// The error.
        error: std::io::Error,
    },
}

impl fmt::Display for TableSetError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            TableSetError::Format { table, error } => write!(f, "{}.tbl: {error}", table.name()),
            #[cfg(feature = "std")]
            TableSetError::Io { path, error } => write!(f, "{}: {error}", path.display()),
        }
    }
}

#[cfg(feature = "std")]
impl std::error::Error for TableSetError {}

/// A material name that is not a shipped preset; its `Display` lists the
/// valid names.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct UnknownMaterial<'n> {
    /// The name asked for.
    pub name: &'n str,
}

impl fmt::Display for UnknownMaterial<'_> {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "unknown material `{}`; the presets are ", self.name)?;
        for (k, (name, _)) in PRESETS.iter().enumerate() {
            let sep = if k == 0 { "" } else { ", " };
            write!(f, "{sep}{name}")?;
        }
        Ok(())
    }
}

#[cfg(feature = "std")]
impl std::error::Error for UnknownMaterial<'_> {}

/// The tables the two-scale BRDF reads, each validated (header, checksum,
/// finite values) and checked to be of its kind. `Copy`: a set is four
/// views of borrowed bytes.
#[derive(Clone, Copy, Debug)]
pub struct TableSet<'a> {
    /// T1, Smith G1 of the EPD.
    pub smith: SmithG1Table<'a>,
    /// T2, σrel/σs of the K-correlation spectrum.
    pub sigma_ratio: SigmaRatioTable<'a>,
    /// T3, the convolution C (T3b; `convolution.fit()` is T3a).
    pub convolution: ConvTable<'a>,
    /// T5, F_dr,int of the plastic and subsurface bases.
    pub diffuse_fresnel: DiffuseFresnelTable<'a>,
}

impl<'a> TableSet<'a> {
    /// Validates the four files; the error names the first file at fault.
    pub fn from_bytes(bytes: TableBytes<'a>) -> Result<Self, TableSetError> {
        let at = |k: usize| {
            move |error: FormatError| TableSetError::Format {
                table: TABLES[k],
                error,
            }
        };
        Ok(TableSet {
            smith: SmithG1Table::from_bytes(bytes.smith).map_err(at(0))?,
            sigma_ratio: SigmaRatioTable::from_bytes(bytes.sigma_ratio).map_err(at(1))?,
            convolution: ConvTable::from_bytes(bytes.convolution).map_err(at(2))?,
            diffuse_fresnel: DiffuseFresnelTable::from_bytes(bytes.diffuse_fresnel)
                .map_err(at(3))?,
        })
    }

    /// The view the BRDF constructors take, with T3b as the source of C.
    pub fn brdf_tables(&self) -> Tables<'_> {
        Tables {
            smith: self.smith,
            sigma_ratio: self.sigma_ratio,
            diffuse_fresnel: self.diffuse_fresnel,
            convolution: &self.convolution,
        }
    }

    /// The view the BRDF constructors take, with another source of C (T3a is
    /// `&set.convolution.fit()`; tests pass adapters).
    pub fn brdf_tables_with<'s>(
        &'s self,
        convolution: &'s (dyn crate::conv::Convolution + Sync),
    ) -> Tables<'s> {
        Tables {
            convolution,
            ..self.brdf_tables()
        }
    }

    /// The RGB model of `material` (at [`crate::brdf::RGB_WAVELENGTHS`]).
    /// Construction bakes what depends only on the material (see
    /// [`crate::brdf::TwoScale::new`]); build it once per material.
    pub fn rgb(&self, material: &Material, options: Options) -> Rgb<'_> {
        Rgb::new(&self.brdf_tables(), material, options)
    }

    /// The RGB model of a shipped preset ([`crate::materials::PRESETS`]) with
    /// the paper's options; an unknown name is an error that lists the presets.
    pub fn material<'n>(&self, name: &'n str) -> Result<Rgb<'_>, UnknownMaterial<'n>> {
        let material = crate::materials::preset(name).ok_or(UnknownMaterial { name })?;
        Ok(self.rgb(&material, Options::default()))
    }
}

#[cfg(feature = "embedded")]
mod embedded {
    use crate::format::AlignedBytes;
    // `tables` is a link to the workspace's `tables/` (the generator writes
    // there); `cargo package` follows it, so a packaged crate carries the files.
    pub static T1: &AlignedBytes<[u8]> =
        &AlignedBytes(*include_bytes!("../tables/t1-smith-g1.tbl"));
    pub static T2: &AlignedBytes<[u8]> =
        &AlignedBytes(*include_bytes!("../tables/t2-sigma-ratio.tbl"));
    pub static T3: &AlignedBytes<[u8]> =
        &AlignedBytes(*include_bytes!("../tables/t3-convolution.tbl"));
    pub static T5: &AlignedBytes<[u8]> =
        &AlignedBytes(*include_bytes!("../tables/t5-diffuse-fresnel.tbl"));
}

#[cfg(feature = "embedded")]
impl TableSet<'static> {
    /// The bytes of the tables compiled into the crate (feature `embedded`).
    pub fn embedded_bytes() -> TableBytes<'static> {
        TableBytes {
            smith: embedded::T1.bytes(),
            sigma_ratio: embedded::T2.bytes(),
            convolution: embedded::T3.bytes(),
            diffuse_fresnel: embedded::T5.bytes(),
        }
    }

    /// The committed tables, compiled into the crate (feature `embedded`): no
    /// files or paths at run time, `no_std`. Validates them (≈ the cost of
    /// reading 4 MB once); call once and keep the set.
    ///
    /// # Panics
    ///
    /// Only if the crate was built from table files that fail validation;
    /// the test `embedded_tables_validate` checks the committed ones.
    pub fn embedded() -> TableSet<'static> {
        match Self::from_bytes(Self::embedded_bytes()) {
            Ok(set) => set,
            Err(error) => panic!("the embedded tables are invalid: {error}"),
        }
    }
}

#[cfg(feature = "std")]
impl TableSet<'static> {
    /// Memory-maps the four files of `dir` (read-only) and validates them.
    /// The maps are kept for the rest of the process (the set borrows them
    /// for `'static`): open a directory once, not per material. Table files
    /// are immutable; replacing one while mapped must be a rename.
    pub fn open(dir: impl AsRef<std::path::Path>) -> Result<TableSet<'static>, TableSetError> {
        let map = |k: usize| -> Result<&'static [u8], TableSetError> {
            let path = dir.as_ref().join(std::format!("{}.tbl", TABLES[k].name()));
            match crate::mmap::MappedFile::open(&path) {
                Ok(file) => Ok(std::boxed::Box::leak(std::boxed::Box::new(file)).bytes()),
                Err(error) => Err(TableSetError::Io { path, error }),
            }
        };
        Self::from_bytes(TableBytes {
            smith: map(0)?,
            sigma_ratio: map(1)?,
            convolution: map(2)?,
            diffuse_fresnel: map(3)?,
        })
    }
}

/// A set borrows its tables: models built from it borrow it in turn. Shared
/// by a renderer's threads.
const _: () = {
    const fn send_sync<T: Send + Sync>() {}
    send_sync::<TableSet<'static>>();
    send_sync::<Rgb<'static>>();
    send_sync::<crate::brdf::TwoScale<'static>>();
};

#[cfg(all(test, feature = "embedded"))]
mod tests {
    use super::*;

    #[test]
    fn embedded_tables_validate() {
        let set = TableSet::from_bytes(TableSet::embedded_bytes());
        assert!(set.is_ok(), "{:?}", set.err());
    }

    #[test]
    fn every_preset_is_found_and_an_unknown_name_lists_them() {
        let set = TableSet::embedded();
        for (name, _) in PRESETS {
            let model = set.material(name).expect("preset");
            let v = model.eval([0.3, 0.1, 0.9], [-0.3, 0.0, 0.95]);
            assert!(v.iter().all(|x| x.is_finite() && *x > 0.0), "{name}: {v:?}");
        }
        let error = set.material("gold").err().expect("unknown");
        let message = std::format!("{error}");
        assert!(message.contains("`gold`"), "{message}");
        for (name, _) in PRESETS {
            assert!(message.contains(name), "{message}");
        }
    }
}
