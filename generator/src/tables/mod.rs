//! The tables the generator builds: one module per table, and what they share
//! (the build/verify interface, error type and accuracy report).

use indicatif::ProgressBar;
use std::fmt;
use twoscale::{FormatError, TableId};

use crate::quad::QuadError;

pub mod albedo;
pub mod convolution;
pub mod diffuse_fresnel;
pub mod sh_brdf;
pub mod sigma_ratio;
pub mod smith_g1;

/// A table the generator knows how to build and verify: the generator's
/// side of the table's [`TableDescriptor`](twoscale::tables::format::TableDescriptor)
/// (its id says which; [`all`] is the registry).
pub trait TableKind: Sync {
    /// Which table.
    fn id(&self) -> TableId;

    /// What `generator export` writes of it (`None`: not exported).
    fn export(&self) -> Option<Export> {
        None
    }

    /// File name without `.tbl` (tables with one file per material override it).
    fn file_stem(&self) -> String {
        self.id().name().to_string()
    }

    /// Amount of work of a build, in [`TableKind::work_unit`]s (the length
    /// of the progress bar).
    fn work_items(&self) -> u64;

    /// What [`TableKind::work_items`] counts: grid nodes unless the table
    /// weights its nodes by cost (T3).
    fn work_unit(&self) -> &'static str {
        "nodes"
    }

    /// Computes the table and encodes it as the bytes of a file. Must be
    /// deterministic: the same bytes for every run and thread count.
    fn build(&self, progress: &ProgressBar) -> Result<Vec<u8>, BuildError>;

    /// Measures the table in `bytes` against the f64 reference at `points`
    /// random off-grid points drawn from `seed`.
    fn verify(&self, bytes: &[u8], points: usize, seed: u64) -> Result<Vec<Accuracy>, BuildError>;

    /// For tables too expensive to rebuild in CI: recomputes `nodes` grid
    /// nodes and compares their bits with the file's. `None` if the table
    /// has no spot check (it is cheap enough to rebuild whole).
    fn spot_check(&self, _bytes: &[u8], _nodes: usize) -> Option<Result<SpotCheck, BuildError>> {
        None
    }
}

/// Outcome of [`TableKind::spot_check`].
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct SpotCheck {
    /// Nodes recomputed.
    pub checked: usize,
    /// Indices of the nodes whose recomputed bits differ from the file's.
    pub mismatched: Vec<usize>,
}

/// What `generator export` needs of a table beyond its file and its
/// [`TableDescriptor`](twoscale::tables::format::TableDescriptor).
#[derive(Clone, Copy, Debug)]
pub struct Export {
    /// One-line summary of the interpolation a consumer must do
    /// (docs/export.md has the full recipe).
    pub interpolation: &'static str,
    /// The largest rounding error an exported precision may add.
    pub budget: Budget,
    /// The C lookups (`crate::export::c`): identifier prefix, its upper
    /// case, the C expression of stored value `(k)`.
    pub c_lookups: fn(&str, &str, &str) -> String,
    /// C definitions the lookups need beyond the axes (T3's normalised
    /// angle), from the identifier prefix and its upper case.
    pub c_constants: Option<fn(&str, &str) -> String>,
}

/// A table's rounding budget: half its accuracy target in the units of its
/// stored values ([`crate::export::rounding_budget`]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Budget {
    /// At most this absolute error on a stored value.
    Absolute(f64),
    /// At most this fraction of the smallest stored value (a relative
    /// target on a value interpolated with non-negative weights summing to 1).
    RelativeToMin(f64),
    /// No more than the file's own quantisation: half its largest per-node
    /// step.
    HalfQuantisationStep,
}

/// Every table the generator builds from no input but its own code, in
/// build order (T4 is built per material: [`sh_brdf::ShBrdf`]).
pub fn all() -> Vec<&'static dyn TableKind> {
    vec![
        &smith_g1::SmithG1,
        &sigma_ratio::SigmaRatio,
        &diffuse_fresnel::DiffuseFresnel,
        &albedo::Albedo,
        &convolution::Conv,
    ]
}

/// The table of [`all`] with this id.
pub fn by_id(id: TableId) -> Option<&'static dyn TableKind> {
    all().into_iter().find(|k| k.id() == id)
}

/// The tables `name` selects among `candidates`: the one whose file stem
/// it is, else those whose stems start with it if they are all of one table
/// id (so `t4` selects every material's T4). The one name resolver of
/// `build`, `verify`, `export` and [`by_name`].
pub fn select<'a>(
    name: &str,
    candidates: &[&'a dyn TableKind],
) -> Result<Vec<&'a dyn TableKind>, String> {
    let exact: Vec<_> = candidates
        .iter()
        .filter(|t| t.file_stem() == name)
        .copied()
        .collect();
    let matches: Vec<_> = if exact.is_empty() {
        candidates
            .iter()
            .filter(|t| t.file_stem().starts_with(name))
            .copied()
            .collect()
    } else {
        exact
    };
    if matches.is_empty() || !matches.windows(2).all(|w| w[0].id() == w[1].id()) {
        let known: Vec<_> = candidates.iter().map(|t| t.file_stem()).collect();
        return Err(format!(
            "unknown or ambiguous table '{name}' (known: {})",
            known.join(", ")
        ));
    }
    Ok(matches)
}

/// The table of [`all`] with this name ([`TableId::name`]) or a unique
/// prefix of it ([`select`]).
pub fn by_name(name: &str) -> Option<&'static dyn TableKind> {
    select(name, &all()).ok()?.into_iter().next()
}

/// File name of a table in a table directory.
pub fn file_name(id: TableId) -> String {
    id.file_name()
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
    /// 90th percentile.
    pub p90: f64,
    /// 99th percentile.
    pub p99: f64,
    /// Where the largest error occurred.
    pub worst_at: String,
    /// The target (docs/model.md §3 or the issue's) for the gated quantile.
    pub target: f64,
    /// Which quantile the target applies to (1 = the maximum).
    pub gate_quantile: f64,
    /// The gated quantile's value.
    pub gated: f64,
    /// All errors, ascending (for other quantiles).
    pub sorted: Vec<f64>,
    /// Whether the figure is only reported: it does not fail `verify`.
    pub report_only: bool,
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
            p90: pick(0.9),
            p99: pick(0.99),
            worst_at,
            target,
            gate_quantile: 1.0,
            gated: max,
            report_only: false,
            sorted: errors.into_iter().map(|e| e.0).collect(),
        }
    }

    /// Applies the target to quantile `q` instead of the maximum.
    pub fn gated_at(mut self, q: f64) -> Accuracy {
        let n = self.sorted.len();
        self.gate_quantile = q;
        self.gated = self
            .sorted
            .get(((n.saturating_sub(1)) as f64 * q).round() as usize)
            .copied()
            .unwrap_or(f64::NAN);
        self
    }

    /// Marks the figure as reported only (it never fails `verify`).
    pub fn report_only(mut self) -> Accuracy {
        self.report_only = true;
        self
    }

    /// The target as `verify` prints it: `-` for none, `max <= T`, or
    /// `pQ value<=T` for a gated quantile.
    pub fn target_text(&self) -> String {
        if !self.target.is_finite() {
            "-".to_string()
        } else if self.gate_quantile < 1.0 {
            format!(
                "p{:.0} {:.1e}<={:.0e}",
                100.0 * self.gate_quantile,
                self.gated,
                self.target
            )
        } else {
            format!("max <= {:.0e}", self.target)
        }
    }

    /// Whether the target is met (a NaN fails); always true when reported only.
    pub fn passed(&self) -> bool {
        self.report_only || self.gated <= self.target
    }

    /// `ok`, `FAIL`, or for reported figures `met`/`missed`.
    pub fn verdict(&self) -> &'static str {
        match (self.report_only, self.gated <= self.target) {
            (false, true) => "ok",
            (false, false) => "FAIL",
            (true, true) => "met",
            (true, false) => "missed",
        }
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
    /// A convolution (T3) could not be computed.
    Convolution {
        /// Where (table and point).
        at: String,
        /// What went wrong.
        message: String,
    },
    /// T3's shard files could not be written or merged.
    Shard(convolution::ShardError),
    /// An input of the build (a table T4's BRDF reads, a material it cannot
    /// model) is missing or unusable.
    Input {
        /// The file or material.
        path: String,
        /// What went wrong.
        message: String,
    },
}

impl fmt::Display for BuildError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            BuildError::Quadrature { at, source } => {
                write!(f, "quadrature failed at {at}: {source}")
            }
            BuildError::Format(e) => write!(f, "{e}"),
            BuildError::Convolution { at, message } => write!(f, "{at}: {message}"),
            BuildError::Shard(e) => write!(f, "T3 shards: {e}"),
            BuildError::Input { path, message } => write!(f, "{path}: {message}"),
        }
    }
}

impl std::error::Error for BuildError {}

impl From<convolution::ShardError> for BuildError {
    fn from(e: convolution::ShardError) -> Self {
        BuildError::Shard(e)
    }
}

impl From<FormatError> for BuildError {
    fn from(e: FormatError) -> Self {
        BuildError::Format(e)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The registry has one entry per descriptor (T4's are per material),
    /// each of its own id, every table of the runtime's set among them, and
    /// the exported ones are the set's.
    #[test]
    fn every_descriptor_has_its_registry_entry() {
        for id in TableId::ALL {
            let kind = by_id(id);
            assert_eq!(kind.is_some(), id != TableId::ShBrdf, "{id:?}");
            if let Some(kind) = kind {
                assert_eq!(kind.id(), id);
                assert_eq!(kind.file_stem(), id.descriptor().stem);
                assert_eq!(kind.export().is_some(), id.descriptor().in_set, "{id:?}");
                assert_eq!(by_name(id.name()).map(|k| k.id()), Some(id));
            }
        }
        assert_eq!(all().len(), TableId::ALL.len() - 1);
        for id in twoscale::table_set::TABLES {
            assert!(by_id(id).is_some(), "{id:?}");
        }
    }

    #[test]
    fn names_resolve_by_stem_or_unique_prefix() {
        assert_eq!(by_name("t3").map(|k| k.id()), Some(TableId::Convolution));
        assert_eq!(
            by_name("t2-sigma").map(|k| k.id()),
            Some(TableId::SigmaRatio)
        );
        assert!(by_name("t").is_none());
        let error = select("t9", &all()).err().unwrap_or_default();
        assert!(error.contains("unknown or ambiguous table 't9'"), "{error}");
        assert!(error.contains("t1-smith-g1"), "{error}");
    }
}
