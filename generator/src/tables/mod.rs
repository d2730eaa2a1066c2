//! The tables the generator builds: one module per table, and what they share
//! (the build/verify interface, error type and accuracy report).

use indicatif::ProgressBar;
use std::fmt;
use twoscale::{FormatError, TableId};

use crate::quad::QuadError;

pub mod t1;
pub mod t2;
pub mod t4;
pub mod t5;

/// A table the generator knows how to build and verify.
pub trait TableKind: Sync {
    /// Which table.
    fn id(&self) -> TableId;

    /// File name without `.tbl` (tables with one file per material override it).
    fn file_stem(&self) -> String {
        self.id().name().to_string()
    }

    /// Number of grid nodes to compute (for the progress bar).
    fn work_items(&self) -> u64;

    /// Computes the table and encodes it as the bytes of a file. Must be
    /// deterministic: the same bytes for every run and thread count.
    fn build(&self, progress: &ProgressBar) -> Result<Vec<u8>, BuildError>;

    /// Measures the table in `bytes` against the f64 reference at `points`
    /// random off-grid points drawn from `seed`.
    fn verify(&self, bytes: &[u8], points: usize, seed: u64) -> Result<Vec<Accuracy>, BuildError>;
}

/// Every table, in build order.
pub fn all() -> Vec<&'static dyn TableKind> {
    vec![&t1::SmithG1, &t2::SigmaRatio, &t5::DiffuseFresnel]
}

/// The table with this name ([`TableId::name`]) or a unique prefix of it.
pub fn by_name(name: &str) -> Option<&'static dyn TableKind> {
    let all = all();
    if let Some(exact) = all.iter().find(|t| t.id().name() == name) {
        return Some(*exact);
    }
    let mut matches = all.into_iter().filter(|t| t.id().name().starts_with(name));
    match (matches.next(), matches.next()) {
        (Some(one), None) => Some(one),
        _ => None,
    }
}

/// File name of a table in a table directory.
pub fn file_name(id: TableId) -> String {
    format!("{}.tbl", id.name())
}

/// Version string written into every header.
pub const GENERATOR_VERSION: &str = env!("CARGO_PKG_VERSION");

/// One accuracy measurement of a table against the reference.
#[derive(Clone, Debug)]
pub struct Accuracy {
    /// What is measured, e.g. `|G1 - G1_ref|`.
    pub metric: String,
    /// Number of points.
    pub points: usize,
    /// Largest error.
    pub max: f64,
    /// Median error.
    pub median: f64,
    /// 99th percentile.
    pub p99: f64,
    /// Where the largest error occurred.
    pub worst_at: String,
    /// The SPEC §3 target for `max`.
    pub target: f64,
}

impl Accuracy {
    /// Summarises per-point errors (each with a description of its point).
    pub fn from_errors(metric: &str, target: f64, mut errors: Vec<(f64, String)>) -> Accuracy {
        let points = errors.len();
        errors.sort_by(|a, b| a.0.total_cmp(&b.0));
        let pick = |q: f64| {
            errors
                .get(((points.saturating_sub(1)) as f64 * q).round() as usize)
                .map_or(f64::NAN, |e| e.0)
        };
        let (max, worst_at) = errors.last().cloned().unwrap_or((f64::NAN, String::new()));
        Accuracy {
            metric: metric.to_string(),
            points,
            max,
            median: pick(0.5),
            p99: pick(0.99),
            worst_at,
            target,
        }
    }

    /// Whether the target is met (a NaN maximum fails).
    pub fn passed(&self) -> bool {
        self.max <= self.target
    }
}

/// Why a build or verification failed.
#[derive(Debug)]
pub enum BuildError {
    /// A reference integral did not converge or met a non-finite value.
    Quadrature {
        /// Where (table and point).
        at: String,
        /// The integrator's report.
        source: QuadError,
    },
    /// The table could not be encoded or read back.
    Format(FormatError),
}

impl fmt::Display for BuildError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            BuildError::Quadrature { at, source } => {
                write!(f, "quadrature failed at {at}: {source}")
            }
            BuildError::Format(e) => write!(f, "{e}"),
        }
    }
}

impl std::error::Error for BuildError {}

impl From<FormatError> for BuildError {
    fn from(e: FormatError) -> Self {
        BuildError::Format(e)
    }
}
