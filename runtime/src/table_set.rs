//! The tables the BRDF reads (T1, T2, T3, T5, T6), validated together, and the
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

use crate::brdf::{Rgb, Tables};
use crate::material::{Material, Options};
use crate::materials::PRESETS;
use crate::tables::albedo::AlbedoTable;
use crate::tables::convolution::ConvTable;
use crate::tables::diffuse_fresnel::DiffuseFresnelTable;
use crate::tables::format::{FormatError, TableId};
use crate::tables::sigma_ratio::SigmaRatioTable;
use crate::tables::smith_g1::SmithG1Table;
use core::fmt;

/// The tables of a set ([`TableDescriptor::in_set`]), in tag order; each
/// is the file `<TableId::name()>.tbl`.
///
/// [`TableDescriptor::in_set`]: crate::tables::format::TableDescriptor::in_set
pub const TABLES: [TableId; 5] = set_tables();

const fn set_tables<const N: usize>() -> [TableId; N] {
    let mut out = [TableId::SmithG1; N];
    let (mut i, mut k) = (0, 0);
    while i < TableId::ALL.len() {
        if TableId::ALL[i].descriptor().in_set {
            out[k] = TableId::ALL[i];
            k += 1;
        }
        i += 1;
    }
    assert!(
        k == N,
        "TABLES' length is the number of descriptors in the set"
    );
    out
}

/// The bytes of the five files (each 64-byte aligned, e.g. from
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
    /// `t6-albedo.tbl`.
    pub albedo: &'a [u8],
}

impl<'a> TableBytes<'a> {
    /// The bytes of each table of [`TABLES`], from `bytes` (the one place
    /// the fields meet the ids; the first error is returned).
    pub fn try_from_fn<E>(
        mut bytes: impl FnMut(TableId) -> Result<&'a [u8], E>,
    ) -> Result<Self, E> {
        Ok(TableBytes {
            smith: bytes(TableId::SmithG1)?,
            sigma_ratio: bytes(TableId::SigmaRatio)?,
            convolution: bytes(TableId::Convolution)?,
            diffuse_fresnel: bytes(TableId::DiffuseFresnel)?,
            albedo: bytes(TableId::Albedo)?,
        })
    }
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
/// finite values) and checked to be of its kind. `Copy`: a set is five
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
    /// T6, the directional albedo of the specular lobe (energy compensation).
    pub albedo: AlbedoTable<'a>,
}

impl<'a> TableSet<'a> {
    /// Validates the five files; the error names the first file at fault.
    pub fn from_bytes(bytes: TableBytes<'a>) -> Result<Self, TableSetError> {
        let at = |table: TableId| move |error: FormatError| TableSetError::Format { table, error };
        Ok(TableSet {
            smith: SmithG1Table::from_bytes(bytes.smith).map_err(at(TableId::SmithG1))?,
            sigma_ratio: SigmaRatioTable::from_bytes(bytes.sigma_ratio)
                .map_err(at(TableId::SigmaRatio))?,
            convolution: ConvTable::from_bytes(bytes.convolution)
                .map_err(at(TableId::Convolution))?,
            diffuse_fresnel: DiffuseFresnelTable::from_bytes(bytes.diffuse_fresnel)
                .map_err(at(TableId::DiffuseFresnel))?,
            albedo: AlbedoTable::from_bytes(bytes.albedo).map_err(at(TableId::Albedo))?,
        })
    }

    /// The view the BRDF constructors take, with T3b as the source of C.
    pub fn brdf_tables(&self) -> Tables<'_> {
        Tables {
            smith: self.smith,
            sigma_ratio: self.sigma_ratio,
            diffuse_fresnel: self.diffuse_fresnel,
            albedo: self.albedo,
            convolution: &self.convolution,
        }
    }

    /// The view the BRDF constructors take, with another source of C (T3a is
    /// `&set.convolution.fit()`; tests pass adapters).
    pub fn brdf_tables_with<'s>(
        &'s self,
        convolution: &'s (dyn crate::tables::convolution::Convolution + Sync),
    ) -> Tables<'s> {
        Tables {
            convolution,
            ..self.brdf_tables()
        }
    }

    /// The RGB model of `material` (at [`crate::material::RGB_WAVELENGTHS`]).
    /// Construction bakes what depends only on the material (see
    /// [`crate::brdf::TwoScale::new`]); build it once per material.
    pub fn rgb(&self, material: &Material, options: Options) -> Rgb<'_> {
        Rgb::new(&self.brdf_tables(), material, options)
    }

    /// The RGB model of a shipped preset ([`crate::materials::PRESETS`]) with
    /// the paper's options, at the paper's wavelengths (by value and
    /// `no_std`; [`TableSet::preset`] gives the presets' default RGB, the
    /// integral over the spectrum); an unknown name is an error that lists
    /// the presets.
    pub fn material<'n>(&self, name: &'n str) -> Result<Rgb<'_>, UnknownMaterial<'n>> {
        let material = crate::materials::preset(name).ok_or(UnknownMaterial { name })?;
        Ok(self.rgb(&material, Options::default()))
    }

    /// The RGB model of a shipped preset with the paper's options and the
    /// presets' default RGB ([`crate::material::RgbMode::default_for`]: the
    /// integral over the spectrum, [`crate::brdf::IntegratedRgb`]), its
    /// bakes on the heap (feature `std`); an unknown name is an error that
    /// lists the presets.
    #[cfg(feature = "std")]
    pub fn preset<'n>(
        &self,
        name: &'n str,
    ) -> Result<
        crate::brdf::RgbModel<'_, std::boxed::Box<crate::brdf::ChannelBake>>,
        UnknownMaterial<'n>,
    > {
        let spectral = crate::materials::spectral(name).ok_or(UnknownMaterial { name })?;
        // Every preset validates (`every_preset_is_found_and_an_unknown_name_lists_them`).
        let desc = crate::io::desc::MaterialDesc::spectral(spectral, Options::default(), None)
            .map_err(|_| UnknownMaterial { name })?;
        Ok(crate::brdf::RgbModel::boxed(&self.brdf_tables(), &desc))
    }
}

#[cfg(feature = "embedded")]
impl TableSet<'static> {
    /// The bytes of the tables compiled into the crate (feature `embedded`).
    pub fn embedded_bytes() -> TableBytes<'static> {
        // Every table of the set is compiled in (`format::embedded_bytes`).
        let bytes =
            TableBytes::try_from_fn(|id| crate::tables::format::embedded_bytes(id).ok_or(()));
        bytes.unwrap_or(TableBytes {
            smith: &[],
            sigma_ratio: &[],
            convolution: &[],
            diffuse_fresnel: &[],
            albedo: &[],
        })
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
    /// Memory-maps the five files of `dir` (read-only) and validates them.
    /// The set owns the maps: they are released when it is dropped. Table
    /// files are immutable; replacing one while mapped must be a rename.
    pub fn open(dir: impl AsRef<std::path::Path>) -> Result<OwnedTableSet, TableSetError> {
        OwnedTableSet::from_storage(|id| {
            let path = dir.as_ref().join(id.file_name());
            match crate::tables::mmap::MappedFile::open(&path) {
                Ok(file) => Ok(TableStorage::Mapped(file)),
                Err(error) => Err(TableSetError::Io { path, error }),
            }
        })
    }
}

/// Where the bytes of one table of an [`OwnedTableSet`] live.
#[cfg(feature = "std")]
pub enum TableStorage {
    /// A read-only memory map of the file.
    Mapped(crate::tables::mmap::MappedFile),
    /// A 64-byte-aligned heap copy.
    Copied(crate::tables::format::AlignedBuf),
}

#[cfg(feature = "std")]
impl TableStorage {
    /// The bytes.
    pub fn bytes(&self) -> &[u8] {
        match self {
            TableStorage::Mapped(map) => map.bytes(),
            TableStorage::Copied(buf) => buf.bytes(),
        }
    }
}

/// A [`TableSet`] together with the storage of its bytes (memory maps or
/// heap copies), released when it is dropped ([`TableSet::open`]). Models
/// borrow [`OwnedTableSet::set`].
#[cfg(feature = "std")]
pub struct OwnedTableSet {
    /// Views of `storage` (declared first, so dropped first), or of static
    /// bytes; never handed out as `'static` (see [`OwnedTableSet::set`]).
    set: TableSet<'static>,
    storage: std::vec::Vec<TableStorage>,
}

#[cfg(feature = "std")]
impl OwnedTableSet {
    /// Validates the tables of [`TABLES`] held by the storage `storage`
    /// gives for each; the first error is returned.
    pub fn from_storage(
        mut storage: impl FnMut(TableId) -> Result<TableStorage, TableSetError>,
    ) -> Result<OwnedTableSet, TableSetError> {
        let storage = TABLES
            .iter()
            .map(|&id| storage(id))
            .collect::<Result<std::vec::Vec<_>, _>>()?;
        let set = TableSet::from_bytes(
            TableBytes::try_from_fn(|id| {
                let k = TABLES.iter().position(|&t| t == id);
                k.and_then(|k| storage.get(k)).map(extend).ok_or(())
            })
            .map_err(|()| TableSetError::Format {
                table: TableId::SmithG1,
                error: FormatError::BadHeader("a table of the set has no storage"),
            })?,
        )?;
        Ok(OwnedTableSet { set, storage })
    }

    /// A set of `'static` bytes (the embedded tables, say), with no storage
    /// to own.
    pub fn from_static(set: TableSet<'static>) -> OwnedTableSet {
        OwnedTableSet {
            set,
            storage: std::vec::Vec::new(),
        }
    }

    /// The set, borrowed for as long as `self` lives.
    pub fn set(&self) -> &TableSet<'_> {
        &self.set
    }

    /// The storage, in the order of [`TABLES`] (empty for
    /// [`OwnedTableSet::from_static`]).
    pub fn storage(&self) -> &[TableStorage] {
        &self.storage
    }
}

#[cfg(feature = "std")]
impl fmt::Debug for TableStorage {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let kind = match self {
            TableStorage::Mapped(_) => "Mapped",
            TableStorage::Copied(_) => "Copied",
        };
        write!(f, "{kind}({} bytes)", self.bytes().len())
    }
}

#[cfg(feature = "std")]
impl fmt::Debug for OwnedTableSet {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.debug_struct("OwnedTableSet")
            .field("set", &self.set)
            .field("storage", &self.storage)
            .finish()
    }
}

/// The bytes of `storage` for `'static`, for the views of an
/// [`OwnedTableSet`] that owns `storage`.
#[cfg(feature = "std")]
fn extend(storage: &TableStorage) -> &'static [u8] {
    let bytes: *const [u8] = storage.bytes();
    // SAFETY: the bytes lie in a memory map or a heap buffer owned by
    // `storage`; neither moves when the `TableStorage` (or the `Vec` holding
    // it) moves, neither is ever written, and both live until the
    // `OwnedTableSet` that holds `storage` drops it, after its `set` (field
    // order). The `'static` views are reachable only through
    // `OwnedTableSet::set`, which shortens them to the owner's borrow.
    #[allow(unsafe_code)]
    unsafe {
        &*bytes
    }
}

/// A set borrows its tables: models built from it borrow it in turn. Shared
/// by a renderer's threads.
const _: () = {
    const fn send_sync<T: Send + Sync>() {}
    send_sync::<TableSet<'static>>();
    #[cfg(feature = "std")]
    send_sync::<OwnedTableSet>();
    send_sync::<Rgb<'static>>();
    send_sync::<crate::brdf::TwoScale<'static>>();
};

#[cfg(all(test, feature = "embedded"))]
mod tests {
    use super::*;

    /// Lines of this process's memory map that map `file`.
    #[cfg(all(target_os = "linux", feature = "std"))]
    fn mapped(file: &str) -> usize {
        let maps = std::fs::read_to_string("/proc/self/maps").expect("/proc/self/maps");
        maps.lines().filter(|line| line.ends_with(file)).count()
    }

    /// An opened set owns its maps: opening and dropping it 50 times leaves
    /// no map of its files behind (the maps used to be leaked, 4 per open).
    #[cfg(all(target_os = "linux", feature = "std"))]
    #[test]
    fn an_opened_set_releases_its_maps() {
        let dir = concat!(env!("CARGO_MANIFEST_DIR"), "/tables");
        let stem = TableId::Convolution.file_name();
        let before = mapped(&stem);
        for _ in 0..50 {
            let owned = TableSet::open(dir).expect("the committed tables");
            assert_eq!(mapped(&stem), before + 1);
            let rgb = owned.set().material("gold-rough").expect("preset");
            assert!(rgb.eval([0.3, 0.1, 0.9], [-0.3, 0.0, 0.95])[0] > 0.0);
        }
        assert_eq!(mapped(&stem), before);
    }

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
        // `preset` (the integrated RGB, on the heap) needs `std`.
        #[cfg(feature = "std")]
        {
            for (name, _) in PRESETS {
                let model = set.preset(name).expect("preset");
                assert!(
                    matches!(model, crate::brdf::RgbModel::Integrated(_)),
                    "{name}"
                );
                let v = crate::bxdf::Bxdf::eval(&model, [0.3, 0.1, 0.9], [-0.3, 0.0, 0.95]);
                assert!(v.iter().all(|x| x.is_finite() && *x > 0.0), "{name}: {v:?}");
            }
            assert!(set.preset("gold").is_err());
        }
        let error = set.material("gold").err().expect("unknown");
        let message = std::format!("{error}");
        assert!(message.contains("`gold`"), "{message}");
        for (name, _) in PRESETS {
            assert!(message.contains(name), "{message}");
        }
    }
}
