//! `generator verify`: the header and checksum of each table file, then its
//! accuracy against the f64 reference at random off-grid points
//! (`TableKind::verify`), printed as [`report::text`] and optionally written
//! as [`report::markdown`] (`docs/accuracy.md`).

use std::path::Path;
use std::process::ExitCode;
use std::time::Instant;
use twoscale::Table;
use twoscale::tables::format::write::write_atomic;

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
}

/// The spectral bakes' accuracy ([`spectral_accuracy`]) on the model tables
/// of `source` (its directory's if it holds them all, else the embedded
/// ones, as T4 reads them).
fn spectral_report(source: &TableSource, seed: u64) -> TableReport {
    let start = Instant::now();
    let inputs = match source.dir() {
        Some(dir) => ModelInputs::for_dir(dir),
        None => ModelInputs::embedded(),
    };
    let outcome = inputs
        .and_then(|inputs| {
            let set = inputs.parse()?;
            Ok(spectral_accuracy::accuracy(&set.brdf_tables(), seed))
        })
        .map_err(Error::table(spectral_accuracy::STEM));
    eprintln!(
        "verified the spectral bakes in {:.1} s",
        start.elapsed().as_secs_f64()
    );
    TableReport {
        stem: spectral_accuracy::STEM.to_string(),
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
        reports.push(spectral_report(source, seed));
    }
    print!("{}", report::text(&reports));
    if let Some(file) = args.markdown {
        let mut command = format!("generator verify --points {points} --seed {seed}");
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
