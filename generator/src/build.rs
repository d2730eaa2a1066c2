//! `generator build`, `merge` and `spot-check`: tables written to a
//! directory (whole, or T3 as shards and their merge), and T3's spot check
//! of committed nodes, with a progress report while they run.

use indicatif::{ProgressBar, ProgressStyle};
use std::io::IsTerminal;
use std::path::{Path, PathBuf};
use std::process::ExitCode;
use std::time::Instant;
use twoscale::tables::format::TableId;
use twoscale::tables::format::write::write_atomic;

use crate::error::{Error, FileAction};
use crate::table_source::TableSource;
use crate::tables::{self, TableKind};

/// `build`: each of `kinds` computed and written to `out/<stem>.tbl` (in
/// the order given: T4 after the tables it projects).
pub fn build(kinds: &[&dyn TableKind], out: &Path) -> Result<ExitCode, Error> {
    std::fs::create_dir_all(out).map_err(Error::file(FileAction::Create, out))?;
    let out = &std::fs::canonicalize(out).unwrap_or_else(|_| out.to_path_buf());
    let total = Instant::now();
    let mut announced = false;
    for kind in kinds {
        if kind.id() == TableId::ShBrdf && !announced {
            announced = true;
            let inputs =
                tables::sh_brdf::input_dir(out).map_or(TableSource::Embedded, TableSource::Dir);
            eprintln!("T4 projects the two-scale model reading T1, T2, T5, T3 from {inputs}");
        }
        let stem = kind.file_stem();
        let start = Instant::now();
        let bytes = with_progress(&stem, kind.work_items(), kind.work_unit(), |progress| {
            kind.build(progress)
        })
        .map_err(Error::table(&stem))?;
        let path = out.join(format!("{stem}.tbl"));
        write_atomic(&path, &bytes).map_err(Error::file(FileAction::Write, &path))?;
        eprintln!(
            "built {} ({} bytes) in {:.1} s -> {}",
            stem,
            bytes.len(),
            start.elapsed().as_secs_f64(),
            path.display()
        );
    }
    eprintln!("all done in {:.1} s", total.elapsed().as_secs_f64());
    Ok(ExitCode::SUCCESS)
}

/// Runs `work` with a progress bar of `len` units of `unit` (drawn on a
/// terminal; elsewhere, as in CI logs or redirected output, a plain progress
/// line every 30 s, [`progress_line`]).
fn with_progress<T>(name: &str, len: u64, unit: &str, work: impl FnOnce(&ProgressBar) -> T) -> T {
    let progress = ProgressBar::new(len).with_style(
        ProgressStyle::with_template(&format!(
            "{{prefix:>14}} [{{bar:40}}] {{percent}}% of the {unit}, {{elapsed}} elapsed, about {{eta}} left"
        ))
        .expect("valid template")
        .progress_chars("=> "),
    );
    progress.set_prefix(name.to_string());
    let start = Instant::now();
    let done = std::sync::atomic::AtomicBool::new(false);
    let result = std::thread::scope(|scope| {
        if !std::io::stderr().is_terminal() {
            scope.spawn(|| plain_progress(name, unit, &progress, &done, start));
        }
        let result = work(&progress);
        done.store(true, std::sync::atomic::Ordering::Relaxed);
        result
    });
    progress.finish_and_clear();
    result
}

/// `build t3 --shard K/N`: the shard file of T3's nodes, in `out`.
pub fn build_shard(out: &Path, shard: &str) -> Result<ExitCode, Error> {
    let shard = tables::convolution::Shard::parse(shard)?;
    std::fs::create_dir_all(out).map_err(Error::file(FileAction::Create, out))?;
    let name = shard.file_name();
    let start = Instant::now();
    let work = tables::convolution::work(Some(shard));
    let bytes = with_progress(
        &name,
        work,
        tables::convolution::Conv.work_unit(),
        |progress| tables::convolution::build_shard(shard, progress),
    )
    .map_err(Error::table(&name))?;
    let path = out.join(&name);
    write_atomic(&path, &bytes).map_err(Error::file(FileAction::Write, &path))?;
    eprintln!(
        "built {name} ({} bytes) in {:.1} s -> {}",
        bytes.len(),
        start.elapsed().as_secs_f64(),
        path.display()
    );
    Ok(ExitCode::SUCCESS)
}

/// `merge`: T3 from its shard files, written to `out`.
pub fn merge(shards: &[PathBuf], out: &Path) -> Result<ExitCode, Error> {
    let files = shards
        .iter()
        .map(|p| {
            std::fs::read(p)
                .map(|bytes| (p.display().to_string(), bytes))
                .map_err(Error::file(FileAction::Read, p))
        })
        .collect::<Result<Vec<_>, Error>>()?;
    let bytes = tables::convolution::merge(&files).map_err(|e| match e {
        tables::BuildError::Shard(e) => Error::Shard(e),
        e => Error::table(TableId::Convolution.name())(e),
    })?;
    std::fs::create_dir_all(out).map_err(Error::file(FileAction::Create, out))?;
    let path = out.join(tables::file_name(TableId::Convolution));
    write_atomic(&path, &bytes).map_err(Error::file(FileAction::Write, &path))?;
    eprintln!(
        "merged {} shards ({} bytes) -> {}",
        files.len(),
        bytes.len(),
        path.display()
    );
    Ok(ExitCode::SUCCESS)
}

/// The plain progress line: `name: 4.6% of the <unit>, 30 s elapsed,
/// about 630 s left` (`pos` of `len` units done after `elapsed` seconds;
/// the time left assumes the rate so far).
pub fn progress_line(name: &str, unit: &str, pos: u64, len: u64, elapsed: f64) -> String {
    let percent = if len > 0 {
        100.0 * pos as f64 / len as f64
    } else {
        0.0
    };
    let left = if pos > 0 {
        format!(
            "about {:.0} s left",
            elapsed * len.saturating_sub(pos) as f64 / pos as f64
        )
    } else {
        "time left unknown".into()
    };
    format!("{name}: {percent:.1}% of the {unit}, {elapsed:.0} s elapsed, {left}")
}

/// Prints [`progress_line`] every 30 s until `done`.
fn plain_progress(
    name: &str,
    unit: &str,
    progress: &ProgressBar,
    done: &std::sync::atomic::AtomicBool,
    start: Instant,
) {
    let mut last = Instant::now();
    while !done.load(std::sync::atomic::Ordering::Relaxed) {
        std::thread::sleep(std::time::Duration::from_millis(200));
        if last.elapsed().as_secs() >= 30 {
            last = Instant::now();
            let (pos, len) = (progress.position(), progress.length().unwrap_or(0));
            let elapsed = start.elapsed().as_secs_f64();
            eprintln!("{}", progress_line(name, unit, pos, len, elapsed));
        }
    }
}

/// `spot-check`: recomputes `nodes` grid nodes of each of `kinds` that has
/// a spot check and compares their bits with the files of `source`
/// (`named`: the tables were named on the command line, so say which have
/// none).
pub fn spot_check(
    kinds: &[&dyn TableKind],
    named: bool,
    source: &TableSource,
    nodes: usize,
) -> Result<ExitCode, Error> {
    let mut failed = false;
    let mut any = false;
    for kind in kinds {
        let stem = kind.file_stem();
        let start = Instant::now();
        let file = source.open_stem(&stem, kind.id())?;
        let Some(outcome) = kind.spot_check(file.bytes(), nodes) else {
            if named {
                eprintln!("{stem}: no spot check (rebuild it whole instead)");
            }
            continue;
        };
        any = true;
        let check = outcome.map_err(Error::table(&stem))?;
        if check.mismatched.is_empty() {
            println!(
                "{stem}: {} nodes recomputed bit-identically in {:.1} s",
                check.checked,
                start.elapsed().as_secs_f64()
            );
        } else {
            failed = true;
            println!(
                "{stem}: {} of {} recomputed nodes differ from the file (nodes {:?})",
                check.mismatched.len(),
                check.checked,
                check.mismatched
            );
        }
    }
    if !any {
        return Err(Error::Usage(
            "none of the selected tables has a spot check".into(),
        ));
    }
    Ok(if failed {
        ExitCode::FAILURE
    } else {
        ExitCode::SUCCESS
    })
}

#[cfg(test)]
mod tests {
    use super::progress_line;

    #[test]
    fn the_progress_line_reads_as_a_sentence() {
        assert_eq!(
            progress_line("T3", "estimated work", 273_748, 5_991_760, 30.0),
            "T3: 4.6% of the estimated work, 30 s elapsed, about 627 s left"
        );
        assert_eq!(
            progress_line("t1-smith-g1", "nodes", 0, 100, 0.2),
            "t1-smith-g1: 0.0% of the nodes, 0 s elapsed, time left unknown"
        );
    }
}
