//! What a `generator` subcommand can fail with: the typed errors of the
//! library (builds, shards, queries, pictures, the materials file) and the
//! command line's own (files, arguments), each with the file or table it
//! concerns.

use std::fmt;
use std::path::PathBuf;

use twoscale::io::desc::DescError;

use crate::materials::MaterialsError;
use crate::plot::PlotError;
use crate::query::QueryError;
use crate::table_source::TableFileError;
use crate::tables::BuildError;
use crate::tables::convolution::ShardError;

/// What was being done to a file when it failed.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum FileAction {
    /// Reading it whole.
    Read,
    /// Opening (mapping) it.
    Open,
    /// Writing it (atomically).
    Write,
    /// Creating a directory.
    Create,
}

/// A failed subcommand.
#[derive(Debug)]
pub enum Error {
    /// A file or directory could not be read, opened, written or created.
    File {
        /// What was being done.
        action: FileAction,
        /// The file or directory.
        path: PathBuf,
        /// Why it failed.
        source: std::io::Error,
    },
    /// The command line names something that does not exist or asks for
    /// something that cannot be done (the message says what and lists the
    /// choices).
    Usage(String),
    /// The materials file is unreadable or invalid.
    Materials(MaterialsError),
    /// A material file (`query --material`) is unreadable or invalid.
    Material(DescError),
    /// A table file could not be read or is malformed.
    Tables(TableFileError),
    /// A table could not be built, verified or spot-checked.
    Table {
        /// The table's file stem (or the shard's file name).
        table: String,
        /// What went wrong.
        source: BuildError,
    },
    /// T3 shards could not be parsed or merged.
    Shard(ShardError),
    /// A batch query could not run.
    Query(QueryError),
    /// A picture could not be drawn.
    Plot(PlotError),
    /// `export` failed (the message names the table or file and says why;
    /// `generator::export` reports its failures as messages).
    Export(String),
    /// The worker threads could not be set up.
    Threads {
        /// How many were asked for.
        threads: usize,
        /// Why it failed.
        source: rayon::ThreadPoolBuildError,
    },
}

impl Error {
    /// A failed file operation.
    pub fn file(
        action: FileAction,
        path: impl Into<PathBuf>,
    ) -> impl FnOnce(std::io::Error) -> Self {
        let path = path.into();
        move |source| Error::File {
            action,
            path,
            source,
        }
    }

    /// A failed build, verification or spot check of `table`.
    pub fn table(table: impl Into<String>) -> impl FnOnce(BuildError) -> Self {
        let table = table.into();
        move |source| Error::Table { table, source }
    }
}

impl fmt::Display for Error {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Error::File {
                action,
                path,
                source,
            } => {
                let verb = match action {
                    FileAction::Read => "read",
                    FileAction::Open => "open",
                    FileAction::Write => "write",
                    FileAction::Create => "create",
                };
                write!(f, "cannot {verb} {}: {source}", path.display())
            }
            Error::Usage(message) => write!(f, "{message}"),
            Error::Materials(e) => write!(f, "{e}"),
            Error::Material(e) => write!(f, "{e}"),
            Error::Tables(e) => write!(f, "{e}"),
            Error::Table { table, source } => write!(f, "{table}: {source}"),
            Error::Shard(e) => write!(f, "T3 shards: {e}"),
            Error::Query(e) => write!(f, "{e}"),
            Error::Plot(e) => write!(f, "{e}"),
            Error::Export(message) => write!(f, "{message}"),
            Error::Threads { threads, source } => {
                write!(f, "cannot set {threads} threads: {source}")
            }
        }
    }
}

impl std::error::Error for Error {
    fn source(&self) -> Option<&(dyn std::error::Error + 'static)> {
        match self {
            Error::File { source, .. } => Some(source),
            Error::Usage(_) => None,
            Error::Materials(e) => Some(e),
            Error::Material(e) => Some(e),
            Error::Tables(e) => Some(e),
            Error::Table { source, .. } => Some(source),
            Error::Shard(e) => Some(e),
            Error::Query(e) => Some(e),
            Error::Plot(e) => Some(e),
            Error::Export(_) => None,
            Error::Threads { source, .. } => Some(source),
        }
    }
}

impl From<MaterialsError> for Error {
    fn from(e: MaterialsError) -> Self {
        Error::Materials(e)
    }
}

impl From<TableFileError> for Error {
    fn from(e: TableFileError) -> Self {
        Error::Tables(e)
    }
}

impl From<ShardError> for Error {
    fn from(e: ShardError) -> Self {
        Error::Shard(e)
    }
}

impl From<QueryError> for Error {
    fn from(e: QueryError) -> Self {
        Error::Query(e)
    }
}

impl From<PlotError> for Error {
    fn from(e: PlotError) -> Self {
        Error::Plot(e)
    }
}
