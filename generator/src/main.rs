//! `generator`: builds, verifies, inspects and queries the two-scale tables.
//!
//! `cargo run -p generator --release` with no arguments rebuilds every table
//! into the workspace's `tables/` directory.

use clap::{Parser, Subcommand};
use indicatif::{ProgressBar, ProgressStyle};
use std::io::{BufReader, IsTerminal, Write};
use std::path::{Path, PathBuf};
use std::process::ExitCode;
use std::time::Instant;
use twoscale::Table;
use twoscale::format::write::write_atomic;
use twoscale::format::{HEADER_SIZE, Header, TableId, checksum};
use twoscale::interp::node_value;
use twoscale::mmap::MappedFile;
use zerocopy::TryFromBytes;

use generator::tables::{self, Accuracy, TableKind, file_name};

/// The workspace's table directory (the default for every subcommand).
const DEFAULT_TABLES: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/../tables");

#[derive(Parser)]
#[command(
    version,
    about = "Builds, verifies, inspects and queries the two-scale reflectance tables"
)]
struct Cli {
    #[command(subcommand)]
    command: Option<Command>,
}

#[derive(Subcommand)]
enum Command {
    /// Build tables (all, or the ones named) into a directory.
    Build {
        /// Tables to build (names or unique prefixes, e.g. t1); all if none.
        tables: Vec<String>,
        /// Output directory.
        #[arg(long, default_value = DEFAULT_TABLES)]
        out: PathBuf,
        /// Worker threads (default: all cores). The output does not depend on it.
        #[arg(long)]
        threads: Option<usize>,
    },
    /// Check headers and checksums of a table directory, then measure every
    /// table against the reference at random off-grid points.
    Verify {
        /// Table directory.
        #[arg(default_value = DEFAULT_TABLES)]
        dir: PathBuf,
        /// Random points per table.
        #[arg(long, default_value_t = 20_000)]
        points: usize,
        /// Seed of the random points.
        #[arg(long, default_value_t = 2017)]
        seed: u64,
        /// Worker threads (default: all cores).
        #[arg(long)]
        threads: Option<usize>,
    },
    /// Recompute a spread of grid nodes of tables too expensive to rebuild
    /// in CI (T3) and compare their bits with the files in a directory.
    SpotCheck {
        /// Tables to check (names or unique prefixes); all that support it if none.
        tables: Vec<String>,
        /// Table directory.
        #[arg(long, default_value = DEFAULT_TABLES)]
        dir: PathBuf,
        /// Nodes to recompute per table (spread evenly, first and last included).
        #[arg(long, default_value_t = 24)]
        nodes: usize,
        /// Worker threads (default: all cores).
        #[arg(long)]
        threads: Option<usize>,
    },
    /// Print the header of table files readably.
    Inspect {
        /// Table files.
        #[arg(required = true)]
        files: Vec<PathBuf>,
    },
    /// Batch query (SPEC §6): CSV on stdin, CSV on stdout with `table` and
    /// `reference` columns. Quantities: g1 (columns p,a), sigma-ratio
    /// (columns theta_i,B,c; θi in radians), fresnel (columns n,k,cos_theta;
    /// `table` is the runtime's f32 value, which needs no table), conv
    /// (columns u,c,beta,p,theta_h; outputs fit = T3a, table = T3b,
    /// reference = exact C).
    Query {
        /// The quantity.
        quantity: String,
        /// Table directory.
        #[arg(long, default_value = DEFAULT_TABLES)]
        tables: PathBuf,
    },
}

fn main() -> ExitCode {
    let cli = Cli::parse();
    let command = cli.command.unwrap_or(Command::Build {
        tables: Vec::new(),
        out: PathBuf::from(DEFAULT_TABLES),
        threads: None,
    });
    let result = match command {
        Command::Build {
            tables,
            out,
            threads,
        } => set_threads(threads).and_then(|()| build(&tables, &out)),
        Command::Verify {
            dir,
            points,
            seed,
            threads,
        } => set_threads(threads).and_then(|()| verify(&dir, points, seed)),
        Command::SpotCheck {
            tables,
            dir,
            nodes,
            threads,
        } => set_threads(threads).and_then(|()| spot_check(&tables, &dir, nodes)),
        Command::Inspect { files } => inspect(&files),
        Command::Query { quantity, tables } => query(&quantity, &tables),
    };
    match result {
        Ok(code) => code,
        Err(message) => {
            eprintln!("error: {message}");
            ExitCode::FAILURE
        }
    }
}

fn set_threads(threads: Option<usize>) -> Result<(), String> {
    if let Some(n) = threads {
        rayon::ThreadPoolBuilder::new()
            .num_threads(n)
            .build_global()
            .map_err(|e| format!("cannot set {n} threads: {e}"))?;
    }
    Ok(())
}

fn selected(names: &[String]) -> Result<Vec<&'static dyn TableKind>, String> {
    if names.is_empty() {
        return Ok(tables::all());
    }
    names
        .iter()
        .map(|n| {
            tables::by_name(n).ok_or_else(|| {
                let known: Vec<_> = tables::all().iter().map(|t| t.id().name()).collect();
                format!("unknown table '{n}' (known: {})", known.join(", "))
            })
        })
        .collect()
}

fn build(names: &[String], out: &Path) -> Result<ExitCode, String> {
    let kinds = selected(names)?;
    std::fs::create_dir_all(out).map_err(|e| format!("cannot create {}: {e}", out.display()))?;
    let out = &std::fs::canonicalize(out).unwrap_or_else(|_| out.to_path_buf());
    let total = Instant::now();
    for kind in kinds {
        let id = kind.id();
        let progress = ProgressBar::new(kind.work_items()).with_style(
            ProgressStyle::with_template(
                "{prefix:>14} [{bar:40}] {pos}/{len} nodes, {elapsed}, eta {eta}",
            )
            .expect("static template")
            .progress_chars("=> "),
        );
        progress.set_prefix(id.name());
        let start = Instant::now();
        // indicatif draws only on a terminal; elsewhere (CI logs, redirected
        // output) print a plain progress line every 30 s instead.
        let done = std::sync::atomic::AtomicBool::new(false);
        let bytes = std::thread::scope(|scope| {
            if !std::io::stderr().is_terminal() {
                scope.spawn(|| plain_progress(id.name(), &progress, &done, start));
            }
            let result = kind.build(&progress);
            done.store(true, std::sync::atomic::Ordering::Relaxed);
            result
        })
        .map_err(|e| format!("{}: {e}", id.name()))?;
        progress.finish_and_clear();
        let path = out.join(file_name(id));
        write_atomic(&path, &bytes).map_err(|e| format!("cannot write {}: {e}", path.display()))?;
        eprintln!(
            "built {} ({} bytes, {} nodes) in {:.1} s -> {}",
            id.name(),
            bytes.len(),
            kind.work_items(),
            start.elapsed().as_secs_f64(),
            path.display()
        );
    }
    eprintln!("all done in {:.1} s", total.elapsed().as_secs_f64());
    Ok(ExitCode::SUCCESS)
}

/// Prints `name: pos/len nodes, elapsed, eta` every 30 s until `done`.
fn plain_progress(
    name: &str,
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
            let eta = if pos > 0 {
                format!(
                    "{:.0} s",
                    elapsed * (len.saturating_sub(pos)) as f64 / pos as f64
                )
            } else {
                "?".into()
            };
            eprintln!("{name}: {pos}/{len} nodes, {elapsed:.0} s, eta {eta}");
        }
    }
}

fn verify(dir: &Path, points: usize, seed: u64) -> Result<ExitCode, String> {
    let mut rows: Vec<(TableId, u64, Result<Vec<Accuracy>, String>)> = Vec::new();
    for kind in tables::all() {
        let id = kind.id();
        let path = dir.join(file_name(id));
        let outcome = MappedFile::open(&path)
            .map_err(|e| format!("cannot open {}: {e}", path.display()))
            .and_then(|file| {
                let size = file.bytes().len() as u64;
                Table::from_bytes_expecting(file.bytes(), id)
                    .map_err(|e| format!("{}: {e}", path.display()))?;
                let start = Instant::now();
                let accuracy = kind
                    .verify(file.bytes(), points, seed)
                    .map_err(|e| format!("{}: {e}", id.name()))?;
                eprintln!(
                    "verified {} at {points} points in {:.1} s",
                    id.name(),
                    start.elapsed().as_secs_f64()
                );
                Ok((size, accuracy))
            });
        match outcome {
            Ok((size, accuracy)) => rows.push((id, size, Ok(accuracy))),
            Err(e) => rows.push((id, 0, Err(e))),
        }
    }
    println!(
        "{:<18} {:>9}  {:<30} {:>7} {:>10} {:>10} {:>10} {:>10} {:>14}  result  worst at",
        "table", "bytes", "metric", "points", "max", "median", "p90", "p99", "target"
    );
    let mut failed = false;
    for (id, size, outcome) in &rows {
        match outcome {
            Ok(accuracy) => {
                for a in accuracy {
                    failed |= !a.passed();
                    let target = if !a.target.is_finite() {
                        "-".to_string()
                    } else if a.gate_quantile < 1.0 {
                        format!("p{:.0} <= {:.0e}", 100.0 * a.gate_quantile, a.target)
                    } else {
                        format!("max <= {:.0e}", a.target)
                    };
                    println!(
                        "{:<18} {:>9}  {:<30} {:>7} {:>10.3e} {:>10.3e} {:>10.3e} {:>10.3e} {:>14}  {:<6}  {}",
                        id.name(),
                        size,
                        a.metric,
                        a.points,
                        a.max,
                        a.median,
                        a.p90,
                        a.p99,
                        target,
                        a.verdict(),
                        a.worst_at
                    );
                }
            }
            Err(e) => {
                failed = true;
                println!("{:<18} {:>9}  FAIL: {e}", id.name(), "-");
            }
        }
    }
    Ok(if failed {
        ExitCode::FAILURE
    } else {
        ExitCode::SUCCESS
    })
}

fn spot_check(names: &[String], dir: &Path, nodes: usize) -> Result<ExitCode, String> {
    let kinds = selected(names)?;
    let mut failed = false;
    let mut any = false;
    for kind in kinds {
        let id = kind.id();
        let path = dir.join(file_name(id));
        let file =
            MappedFile::open(&path).map_err(|e| format!("cannot open {}: {e}", path.display()))?;
        let start = Instant::now();
        let Some(outcome) = kind.spot_check(file.bytes(), nodes) else {
            if !names.is_empty() {
                eprintln!("{}: no spot check (rebuild it whole instead)", id.name());
            }
            continue;
        };
        any = true;
        let check = outcome.map_err(|e| format!("{}: {e}", id.name()))?;
        if check.mismatched.is_empty() {
            println!(
                "{}: {} nodes recomputed bit-identically in {:.1} s",
                id.name(),
                check.checked,
                start.elapsed().as_secs_f64()
            );
        } else {
            failed = true;
            println!(
                "{}: {} of {} recomputed nodes differ from the file (nodes {:?})",
                id.name(),
                check.mismatched.len(),
                check.checked,
                check.mismatched
            );
        }
    }
    if !any {
        return Err("none of the selected tables has a spot check".into());
    }
    Ok(if failed {
        ExitCode::FAILURE
    } else {
        ExitCode::SUCCESS
    })
}

fn inspect(files: &[PathBuf]) -> Result<ExitCode, String> {
    let mut failed = false;
    for path in files {
        let file =
            MappedFile::open(path).map_err(|e| format!("cannot open {}: {e}", path.display()))?;
        let bytes = file.bytes();
        println!("{}  ({} bytes)", path.display(), bytes.len());
        let Some(header) = bytes
            .get(..HEADER_SIZE)
            .and_then(|head| Header::try_ref_from_bytes(head).ok())
        else {
            // Let the validating reader say what is wrong.
            let e = Table::from_bytes(bytes)
                .err()
                .map_or("unreadable header".to_string(), |e| e.to_string());
            println!("  invalid: {e}");
            failed = true;
            continue;
        };
        let id = header.table_id;
        println!("  format version     {}", header.format_version);
        println!(
            "  table              {} (id {}): {}",
            id.name(),
            id.tag(),
            id.description()
        );
        println!(
            "  value type         {:?}, {} channel(s)",
            header.value_type, header.channels
        );
        for (d, axis) in header.used_axes().iter().enumerate() {
            let name = id.axis_names().get(d).copied().unwrap_or("?");
            let second = if axis.nodes > 1 {
                node_value(axis, 1)
            } else {
                f64::NAN
            };
            println!(
                "  axis {d} {:<10}   {} nodes on [{}, {}], evenly spaced in {} (second node {second:.6e})",
                name,
                axis.nodes,
                axis.lo,
                axis.hi,
                axis.mapping.describe(axis.param, axis.param2)
            );
        }
        println!("  interpolation      {:?}", header.kernel);
        println!("  aux values         {}", header.aux_count);
        println!("  generator version  {}", header.generator_version_str());
        for (name, value) in id.param_names().iter().zip(header.params) {
            println!("  param {name:<18} {value:e}");
        }
        println!(
            "  payload            {} bytes at offset {}",
            header.payload_len, header.payload_offset
        );
        let computed = checksum(bytes);
        println!(
            "  checksum           {:#018x} ({})",
            header.checksum,
            if computed == header.checksum {
                "matches"
            } else {
                "MISMATCH"
            }
        );
        match Table::from_bytes(bytes) {
            Ok(_) => println!("  valid"),
            Err(e) => {
                println!("  invalid: {e}");
                failed = true;
            }
        }
    }
    Ok(if failed {
        ExitCode::FAILURE
    } else {
        ExitCode::SUCCESS
    })
}

fn query(quantity: &str, tables: &Path) -> Result<ExitCode, String> {
    let stdin = std::io::stdin();
    let stdout = std::io::stdout();
    let mut out = std::io::BufWriter::new(stdout.lock());
    let summary = generator::query::run(
        quantity,
        tables,
        BufReader::new(stdin.lock()),
        &mut out,
        std::io::stderr(),
    )?;
    out.flush().map_err(|e| format!("writing output: {e}"))?;
    if summary.bad > 0 {
        eprintln!(
            "{} row(s) answered, {} bad row(s) reported above",
            summary.answered, summary.bad
        );
        return Ok(ExitCode::FAILURE);
    }
    Ok(ExitCode::SUCCESS)
}
