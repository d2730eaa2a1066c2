//! `generator verify`: the header and checksum of each table file, then its
//! accuracy against the f64 reference at random off-grid points
//! (`TableKind::verify`), printed as [`report::text`] and optionally written
//! as [`report::markdown`] (`docs/accuracy.md`).

use std::path::Path;
use std::process::ExitCode;
use std::time::Instant;
use twoscale::Table;
use twoscale::tables::format::write::write_atomic;

use crate::brdf_accuracy;
use crate::error::{Error, FileAction};
use crate::report::{self, TableReport};
use crate::spectral_accuracy;
use crate::table_source::TableSource;
use crate::tables::TableKind;
use crate::tables::sh_brdf::ModelInputs;

/// What `verify` measures.
pub struct VerifyArgs<'a> {
    /// The table names given (`--table`), for the command line the
    /// markdown quotes.
    pub names: &'a [String],
    /// Random points per table (at least 1).
    pub points: usize,
    /// Seed of the random points.
    pub seed: u64,
    /// Where to write the markdown report, if anywhere.
    pub markdown: Option<&'a Path>,
    /// The size of the BRDF section ([`brdf_accuracy::DEFAULT_SIZE`] in CI).
    pub brdf: brdf_accuracy::Size,
}

/// A section measured on the model tables of `source`: its directory's (an
/// error if one is missing: a directory's report never holds figures of the
/// embedded tables), or the embedded ones; `measure` of their
/// [`twoscale::brdf::Tables`].
fn model_report(
    source: &TableSource,
    stem: &str,
    what: &str,
    measure: impl FnOnce(&twoscale::brdf::Tables<'_>) -> Vec<crate::tables::Accuracy>,
) -> TableReport {
    let start = Instant::now();
    let inputs = match source.dir() {
        Some(dir) => ModelInputs::load(dir),
        None => ModelInputs::embedded(),
    };
    let outcome = inputs
        .and_then(|inputs| {
            let set = inputs.parse()?;
            Ok(measure(&set.brdf_tables()))
        })
        .map_err(Error::table(stem));
    eprintln!("verified {what} in {:.1} s", start.elapsed().as_secs_f64());
    TableReport {
        stem: stem.to_string(),
        bytes: 0,
        outcome,
    }
}

/// Verifies each of `kinds` read from `source`, then (when no table is
/// named) the spectral bakes; exit status 1 if a file is unreadable or a
/// gated figure misses its target.
pub fn verify(
    kinds: &[&dyn TableKind],
    source: &TableSource,
    args: &VerifyArgs<'_>,
) -> Result<ExitCode, Error> {
    let (points, seed) = (args.points, args.seed);
    if points == 0 {
        return Err(Error::Usage(
            "--points 0: verify needs at least one point per table".into(),
        ));
    }
    if let Some(dir) = source.dir()
        && !dir.is_dir()
    {
        let source = std::fs::metadata(dir).err().unwrap_or_else(|| {
            std::io::Error::new(std::io::ErrorKind::NotADirectory, "not a directory")
        });
        return Err(Error::file(FileAction::Read, dir)(source));
    }
    let mut reports = Vec::new();
    for kind in kinds {
        let id = kind.id();
        let stem = kind.file_stem();
        let outcome = source
            .open_stem(&stem, id)
            .map_err(Error::from)
            .and_then(|file| {
                let size = file.bytes().len() as u64;
                Table::from_bytes_expecting(file.bytes(), id)
                    .map_err(source.format_error(&stem))?;
                let start = Instant::now();
                let accuracy = kind
                    .verify(file.bytes(), points, seed)
                    .map_err(Error::table(&stem))?;
                eprintln!(
                    "verified {} at {points} points in {:.1} s",
                    stem,
                    start.elapsed().as_secs_f64()
                );
                Ok((size, accuracy))
            });
        reports.push(match outcome {
            Ok((bytes, accuracy)) => TableReport {
                stem,
                bytes,
                outcome: Ok(accuracy),
            },
            Err(e) => TableReport {
                stem,
                bytes: 0,
                outcome: Err(e),
            },
        });
    }
    if args.names.is_empty() {
        reports.push(model_report(
            source,
            spectral_accuracy::STEM,
            "the spectral bakes",
            |tables| spectral_accuracy::accuracy(tables, seed),
        ));
        reports.push(model_report(
            source,
            brdf_accuracy::STEM,
            "the BRDF in the practical domain",
            |tables| brdf_accuracy::accuracy(tables, args.brdf, seed),
        ));
    }
    print!("{}", report::text(&reports));
    if let Some(file) = args.markdown {
        let mut command = format!("generator verify --points {points} --seed {seed}");
        let size = args.brdf;
        if size != brdf_accuracy::DEFAULT_SIZE {
            command.push_str(&format!(
                " --brdf-materials {} --brdf-exact {}",
                size.materials, size.exact
            ));
        }
        for n in args.names {
            command.push_str(&format!(" --table {n}"));
        }
        write_atomic(file, report::markdown(&command, &reports).as_bytes())
            .map_err(Error::file(FileAction::Write, file))?;
    }
    Ok(if reports.iter().all(TableReport::passed) {
        ExitCode::SUCCESS
    } else {
        ExitCode::FAILURE
    })
}
