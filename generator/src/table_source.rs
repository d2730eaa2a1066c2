//! Where a subcommand reads its tables: the tables compiled into the
//! binary (feature `embedded`, the default: an installed `generator` needs
//! no source tree) or a directory given on the command line (`--tables DIR`,
//! `verify DIR`, `inspect DIR`).

use std::fmt;
use std::path::{Path, PathBuf};
use twoscale::tables::mmap::MappedFile;
use twoscale::{FormatError, TableId};

use crate::tables::BuildError;
use crate::tables::sh_brdf::ModelInputs;

/// The tables a subcommand reads.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum TableSource {
    /// The committed T1, T2, T3 and T5 compiled into the binary
    /// (`twoscale::TableSet::embedded_bytes`; feature `embedded`).
    Embedded,
    /// The files `<stem>.tbl` of a directory.
    Dir(PathBuf),
}

/// One table file's bytes: a static slice of the binary or a memory map.
pub enum TableFile {
    /// Compiled into the binary.
    Embedded(&'static [u8]),
    /// Mapped from a file.
    Mapped(MappedFile),
}

impl TableFile {
    /// The file's bytes (64-byte aligned).
    pub fn bytes(&self) -> &[u8] {
        match self {
            TableFile::Embedded(bytes) => bytes,
            TableFile::Mapped(file) => file.bytes(),
        }
    }
}

/// Why a table could not be read from its source.
#[derive(Debug)]
pub enum TableFileError {
    /// The file could not be opened or mapped.
    Io {
        /// The file.
        path: PathBuf,
        /// Why.
        source: std::io::Error,
    },
    /// The file is not a valid table of its kind.
    Format {
        /// The file (or `embedded <stem>.tbl`).
        file: String,
        /// What is wrong.
        source: FormatError,
    },
    /// The binary does not carry this table (T4 files are per material and
    /// never embedded; without feature `embedded`, none is).
    NotEmbedded(String),
}

impl fmt::Display for TableFileError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            TableFileError::Io { path, source } => {
                write!(f, "cannot open {}: {source}", path.display())
            }
            TableFileError::Format { file, source } => write!(f, "{file}: {source}"),
            TableFileError::NotEmbedded(stem) => write!(
                f,
                "{stem}.tbl is not compiled into this generator; give the table directory \
                 (--tables DIR)"
            ),
        }
    }
}

impl std::error::Error for TableFileError {
    fn source(&self) -> Option<&(dyn std::error::Error + 'static)> {
        match self {
            TableFileError::Io { source, .. } => Some(source),
            TableFileError::Format { source, .. } => Some(source),
            TableFileError::NotEmbedded(_) => None,
        }
    }
}

/// The embedded bytes of table `id`, if the binary carries it.
#[cfg(feature = "embedded")]
pub fn embedded(id: TableId) -> Option<&'static [u8]> {
    let set = twoscale::TableSet::embedded_bytes();
    match id {
        TableId::SmithG1 => Some(set.smith),
        TableId::SigmaRatio => Some(set.sigma_ratio),
        TableId::Convolution => Some(set.convolution),
        TableId::DiffuseFresnel => Some(set.diffuse_fresnel),
        TableId::Albedo => Some(set.albedo),
        _ => None,
    }
}

/// The embedded bytes of table `id`: none without feature `embedded`.
#[cfg(not(feature = "embedded"))]
pub fn embedded(_id: TableId) -> Option<&'static [u8]> {
    None
}

impl TableSource {
    /// `Dir(dir)` if a directory was given, else the embedded tables.
    pub fn new(dir: Option<PathBuf>) -> TableSource {
        dir.map_or(TableSource::Embedded, TableSource::Dir)
    }

    /// The directory, if the tables are read from one.
    pub fn dir(&self) -> Option<&Path> {
        match self {
            TableSource::Embedded => None,
            TableSource::Dir(dir) => Some(dir),
        }
    }

    /// The bytes of the file `<stem>.tbl` (unvalidated), where `id` is the
    /// table it holds.
    pub fn open_stem(&self, stem: &str, id: TableId) -> Result<TableFile, TableFileError> {
        match self {
            TableSource::Embedded => match embedded(id) {
                Some(bytes) if stem == id.name() => Ok(TableFile::Embedded(bytes)),
                _ => Err(TableFileError::NotEmbedded(stem.to_string())),
            },
            TableSource::Dir(dir) => {
                let path = dir.join(format!("{stem}.tbl"));
                MappedFile::open(&path)
                    .map(TableFile::Mapped)
                    .map_err(|source| TableFileError::Io { path, source })
            }
        }
    }

    /// The bytes of table `id`'s file (unvalidated).
    pub fn open(&self, id: TableId) -> Result<TableFile, TableFileError> {
        self.open_stem(id.name(), id)
    }

    /// The name of the file `<stem>.tbl` in messages: its path, or
    /// `embedded <stem>.tbl`.
    pub fn label(&self, stem: &str) -> String {
        match self {
            TableSource::Embedded => format!("embedded {stem}.tbl"),
            TableSource::Dir(dir) => dir.join(format!("{stem}.tbl")).display().to_string(),
        }
    }

    /// T1, T2, T5 and T3 as the two-scale model reads them (T4's
    /// projection, the lobe plots).
    pub fn model_inputs(&self) -> Result<ModelInputs, BuildError> {
        match self {
            TableSource::Embedded => ModelInputs::embedded(),
            TableSource::Dir(dir) => ModelInputs::load(dir),
        }
    }

    /// A format error of the file `<stem>.tbl`, naming the file.
    pub fn format_error(&self, stem: &str) -> impl FnOnce(FormatError) -> TableFileError {
        let file = self.label(stem);
        move |source| TableFileError::Format { file, source }
    }
}

impl fmt::Display for TableSource {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            TableSource::Embedded => write!(f, "the embedded tables"),
            TableSource::Dir(dir) => write!(f, "{}", dir.display()),
        }
    }
}
