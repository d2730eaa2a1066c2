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

use generator::error::{Error, FileAction};
use generator::materials::Materials;
use generator::report::{self, TableReport};
use generator::tables::t4::{Projected, ShBrdf};
use generator::tables::{self, TableKind};

/// The workspace's table directory (the default for every subcommand).
const DEFAULT_TABLES: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/../tables");
/// Where `plot` writes (the pictures of the docs).
const DEFAULT_IMAGES: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/../docs/img");
/// The workspace's materials file (T4 builds one table per material).
const DEFAULT_MATERIALS: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/../materials.toml");

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
        /// Tables to build (file names without .tbl, or prefixes: t1, t4 = every
        /// material's T4, t4-nickel); all if none.
        tables: Vec<String>,
        /// Output directory.
        #[arg(long, default_value = DEFAULT_TABLES)]
        out: PathBuf,
        /// Materials file (T4: one table per material).
        #[arg(long, default_value = DEFAULT_MATERIALS)]
        materials: PathBuf,
        /// Worker threads (default: all cores). The output does not depend on it.
        #[arg(long)]
        threads: Option<usize>,
        /// T3 only: compute shard K of N (the nodes i with i mod N = K − 1)
        /// into `<out>/t3-convolution.shard-K-of-N`; `merge` assembles the N
        /// shards into the table.
        #[arg(long, value_name = "K/N")]
        shard: Option<String>,
    },
    /// Assemble T3 shard files (`build t3 --shard K/N`, all N of them, in
    /// any order) into `<out>/t3-convolution.tbl`, bit-identical to a
    /// single build.
    Merge {
        /// The shard files.
        #[arg(required = true)]
        shards: Vec<PathBuf>,
        /// Output directory.
        #[arg(long, default_value = DEFAULT_TABLES)]
        out: PathBuf,
    },
    /// Check headers and checksums of a table directory, then measure every
    /// table against the reference at random off-grid points.
    Verify {
        /// Table directory.
        #[arg(default_value = DEFAULT_TABLES)]
        dir: PathBuf,
        /// Materials file (T4: one table per material).
        #[arg(long, default_value = DEFAULT_MATERIALS)]
        materials: PathBuf,
        /// Only these tables (names or prefixes as for `build`, e.g.
        /// `--table t4`); all if none.
        #[arg(long = "table")]
        tables: Vec<String>,
        /// Random points per table.
        #[arg(long, default_value_t = 20_000)]
        points: usize,
        /// Seed of the random points.
        #[arg(long, default_value_t = 2017)]
        seed: u64,
        /// Worker threads (default: all cores). The figures do not depend on it.
        #[arg(long)]
        threads: Option<usize>,
        /// Also write the figures as markdown to this file (what
        /// `docs/accuracy.md` holds; no timestamps, so the same tables, points
        /// and seed give the same bytes).
        #[arg(long, value_name = "FILE")]
        markdown: Option<PathBuf>,
    },
    /// Recompute a spread of grid nodes of tables too expensive to rebuild
    /// in CI (T3) and compare their bits with the files in a directory.
    SpotCheck {
        /// Tables to check (names or prefixes); all that support it if none.
        tables: Vec<String>,
        /// Table directory.
        #[arg(long, default_value = DEFAULT_TABLES)]
        dir: PathBuf,
        /// Materials file (T4: one table per material).
        #[arg(long, default_value = DEFAULT_MATERIALS)]
        materials: PathBuf,
        /// Nodes to recompute per table (spread evenly, first and last included).
        #[arg(long, default_value_t = 24)]
        nodes: usize,
        /// Worker threads (default: all cores).
        #[arg(long)]
        threads: Option<usize>,
    },
    /// Draw the pictures of docs/img/: the BRDF lobes of each material in the
    /// plane of incidence (lobes-<name>.png) and the error maps of T1, T2 and
    /// T3 at verify's points (error-t1.png, error-t2.png, error-t3.png).
    Plot {
        /// Output directory.
        #[arg(long, default_value = DEFAULT_IMAGES)]
        out: PathBuf,
        /// Table directory.
        #[arg(long, default_value = DEFAULT_TABLES)]
        tables: PathBuf,
        /// Materials file.
        #[arg(long, default_value = DEFAULT_MATERIALS)]
        materials: PathBuf,
        /// Only these materials' lobes (all if none).
        #[arg(long = "material")]
        only: Vec<String>,
        /// No error maps (they repeat verify's measurement of T1, T2, T3).
        #[arg(long)]
        no_errors: bool,
        /// Random points of the error maps, as for verify.
        #[arg(long, default_value_t = 20_000)]
        points: usize,
        /// Seed of the random points, as for verify.
        #[arg(long, default_value_t = 2017)]
        seed: u64,
        /// TrueType font for the text.
        #[arg(long, default_value = generator::plot::DEFAULT_FONT)]
        font: PathBuf,
        /// Worker threads (default: all cores).
        #[arg(long)]
        threads: Option<usize>,
    },
    /// Export tables for use outside Rust (GPU kernels, NumPy, Mitsuba
    /// textures): `--format npy` writes one .npy per array, `--format c`
    /// one C header per table; both write tables.json (axes, node values,
    /// parameters, decoding). Then measures each exported precision as
    /// `verify` does: decoded, interpolated as the runtime (and a shader)
    /// does, against the f64 reference. docs/export.md describes every array.
    Export {
        /// Output directory (created if missing).
        #[arg(long)]
        out: PathBuf,
        /// npy or c.
        #[arg(long, default_value = "npy")]
        format: String,
        /// Tables to export (names or prefixes: t1, t2, t3, t5); all four if none.
        #[arg(long = "table")]
        tables: Vec<String>,
        /// f32, unorm16 or f16. Default: every precision whose rounding is
        /// within the table's budget (half its accuracy target). A precision
        /// a table cannot meet is refused with its rounding error.
        #[arg(long)]
        precision: Option<String>,
        /// Table directory to read.
        #[arg(long, default_value = DEFAULT_TABLES)]
        dir: PathBuf,
        /// Random points of the measurement per table and precision, as for
        /// verify (0: no measurement).
        #[arg(long, default_value_t = 20_000)]
        points: usize,
        /// Seed of the random points.
        #[arg(long, default_value_t = 2017)]
        seed: u64,
    },
    /// Print the header of table files readably.
    Inspect {
        /// Table files.
        #[arg(required = true)]
        files: Vec<PathBuf>,
    },
    /// Batch query (docs/model.md §6): CSV on stdin, CSV on stdout with `table` and
    /// `reference` columns. Quantities: g1 (columns p,a), sigma-ratio
    /// (columns theta_i,B,c; θi in radians), fresnel (columns n,k,cos_theta;
    /// `table` is the runtime's f32 value, which needs no table), conv
    /// (columns u,c,beta,p,theta_h; outputs fit = T3a, table = T3b,
    /// reference = exact C), brdf (docs/model.md §6 columns; conductor two-scale model).
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
        materials: PathBuf::from(DEFAULT_MATERIALS),
        threads: None,
        shard: None,
    });
    let result = match command {
        Command::Build {
            tables,
            out,
            materials,
            threads,
            shard: None,
        } => set_threads(threads).and_then(|()| build(&tables, &out, &materials)),
        Command::Build {
            tables,
            out,
            materials,
            threads,
            shard: Some(shard),
        } => set_threads(threads).and_then(|()| build_shard(&tables, &out, &materials, &shard)),
        Command::Merge { shards, out } => merge(&shards, &out),
        Command::Verify {
            dir,
            materials,
            tables,
            points,
            seed,
            threads,
            markdown,
        } => set_threads(threads)
            .and_then(|()| verify(&dir, &materials, &tables, points, seed, markdown.as_deref())),
        Command::SpotCheck {
            tables,
            dir,
            materials,
            nodes,
            threads,
        } => set_threads(threads).and_then(|()| spot_check(&tables, &dir, &materials, nodes)),
        Command::Plot {
            out,
            tables,
            materials,
            only,
            no_errors,
            points,
            seed,
            font,
            threads,
        } => set_threads(threads).and_then(|()| {
            plot(&PlotArgs {
                out,
                tables,
                materials,
                only,
                errors: !no_errors,
                points,
                seed,
                font,
            })
        }),
        Command::Export {
            out,
            format,
            tables,
            precision,
            dir,
            points,
            seed,
        } => export(&ExportArgs {
            out,
            format,
            tables,
            precision,
            dir,
            points,
            seed,
        })
        .map_err(Error::Export),
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

fn set_threads(threads: Option<usize>) -> Result<(), Error> {
    if let Some(n) = threads {
        rayon::ThreadPoolBuilder::new()
            .num_threads(n)
            .build_global()
            .map_err(|source| Error::Threads { threads: n, source })?;
    }
    Ok(())
}

/// The T4 builders of the materials file, projecting the two-scale model
/// with the tables of `dir` (or the workspace's: `t4::input_dir`).
fn material_tables(materials: &Path, dir: &Path) -> Result<Vec<ShBrdf>, Error> {
    let materials = Materials::load(materials)?;
    Ok(ShBrdf::all(
        &materials,
        &Projected::TwoScale {
            dir: dir.to_path_buf(),
        },
    ))
}

/// Every table: the fixed ones, then T4 per material.
fn catalogue(t4: &[ShBrdf]) -> Vec<&dyn TableKind> {
    let mut kinds = tables::all();
    kinds.extend(t4.iter().map(|k| k as &dyn TableKind));
    kinds
}

/// The tables named ([`tables::select`]); every table when none is named.
fn selected<'a>(names: &[String], t4: &'a [ShBrdf]) -> Result<Vec<&'a dyn TableKind>, Error> {
    let all = catalogue(t4);
    if names.is_empty() {
        return Ok(all);
    }
    let mut chosen: Vec<&dyn TableKind> = Vec::new();
    for n in names {
        chosen.extend(tables::select(n, &all).map_err(Error::Usage)?);
    }
    Ok(chosen)
}

fn build(names: &[String], out: &Path, materials: &Path) -> Result<ExitCode, Error> {
    let t4 = material_tables(materials, out)?;
    let kinds = selected(names, &t4)?;
    std::fs::create_dir_all(out).map_err(Error::file(FileAction::Create, out))?;
    let out = &std::fs::canonicalize(out).unwrap_or_else(|_| out.to_path_buf());
    let total = Instant::now();
    let mut announced = false;
    for kind in kinds {
        if kind.id() == TableId::ShBrdf && !announced {
            announced = true;
            eprintln!(
                "T4 projects the two-scale model reading T1, T2, T5, T3 from {}",
                tables::t4::input_dir(out).display()
            );
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
            "built {} ({} bytes, {} {}) in {:.1} s -> {}",
            stem,
            bytes.len(),
            kind.work_items(),
            kind.work_unit(),
            start.elapsed().as_secs_f64(),
            path.display()
        );
    }
    eprintln!("all done in {:.1} s", total.elapsed().as_secs_f64());
    Ok(ExitCode::SUCCESS)
}

/// Runs `work` with a progress bar of `len` units named `unit` (drawn on a
/// terminal; elsewhere, as in CI logs or redirected output, a plain progress
/// line every 30 s).
fn with_progress<T>(name: &str, len: u64, unit: &str, work: impl FnOnce(&ProgressBar) -> T) -> T {
    let progress = ProgressBar::new(len).with_style(
        ProgressStyle::with_template(&format!(
            "{{prefix:>14}} [{{bar:40}}] {{pos}}/{{len}} {unit}, {{elapsed}}, eta {{eta}}"
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

/// `build t3 --shard K/N`: the shard file of T3's nodes.
fn build_shard(
    names: &[String],
    out: &Path,
    materials: &Path,
    shard: &str,
) -> Result<ExitCode, Error> {
    let shard = tables::t3::Shard::parse(shard)?;
    let t4 = material_tables(materials, out)?;
    let kinds = selected(names, &t4)?;
    if names.is_empty() || kinds.iter().any(|k| k.id() != TableId::Convolution) {
        return Err(Error::Usage(
            "--shard applies to T3 alone: `build t3 --shard K/N`".into(),
        ));
    }
    std::fs::create_dir_all(out).map_err(Error::file(FileAction::Create, out))?;
    let name = shard.file_name();
    let start = Instant::now();
    let work = tables::t3::work(Some(shard));
    let bytes = with_progress(&name, work, tables::t3::Conv.work_unit(), |progress| {
        tables::t3::build_shard(shard, progress)
    })
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

/// `merge`: T3 from its shard files.
fn merge(shards: &[PathBuf], out: &Path) -> Result<ExitCode, Error> {
    let files = shards
        .iter()
        .map(|p| {
            std::fs::read(p)
                .map(|bytes| (p.display().to_string(), bytes))
                .map_err(Error::file(FileAction::Read, p))
        })
        .collect::<Result<Vec<_>, Error>>()?;
    let bytes = tables::t3::merge(&files).map_err(|e| match e {
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

/// Prints `name: pos/len unit, elapsed, eta` every 30 s until `done`.
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
            let eta = if pos > 0 {
                format!(
                    "{:.0} s",
                    elapsed * (len.saturating_sub(pos)) as f64 / pos as f64
                )
            } else {
                "?".into()
            };
            eprintln!("{name}: {pos}/{len} {unit}, {elapsed:.0} s, eta {eta}");
        }
    }
}

fn spot_check(
    names: &[String],
    dir: &Path,
    materials: &Path,
    nodes: usize,
) -> Result<ExitCode, Error> {
    let t4 = material_tables(materials, dir)?;
    let kinds = selected(names, &t4)?;
    let mut failed = false;
    let mut any = false;
    for kind in kinds {
        let stem = kind.file_stem();
        let path = dir.join(format!("{stem}.tbl"));
        let start = Instant::now();
        let file = MappedFile::open(&path).map_err(Error::file(FileAction::Open, &path))?;
        let Some(outcome) = kind.spot_check(file.bytes(), nodes) else {
            if !names.is_empty() {
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

fn verify(
    dir: &Path,
    materials: &Path,
    names: &[String],
    points: usize,
    seed: u64,
    markdown: Option<&Path>,
) -> Result<ExitCode, Error> {
    let t4 = material_tables(materials, dir)?;
    let mut reports = Vec::new();
    for kind in selected(names, &t4)? {
        let id = kind.id();
        let stem = kind.file_stem();
        let path = dir.join(format!("{stem}.tbl"));
        let outcome = MappedFile::open(&path)
            .map_err(Error::file(FileAction::Open, &path))
            .and_then(|file| {
                let size = file.bytes().len() as u64;
                Table::from_bytes_expecting(file.bytes(), id).map_err(|source| Error::Format {
                    path: path.clone(),
                    source,
                })?;
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
    print!("{}", report::text(&reports));
    if let Some(file) = markdown {
        let mut command = format!("generator verify --points {points} --seed {seed}");
        for n in names {
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

/// The arguments of `plot`.
struct PlotArgs {
    out: PathBuf,
    tables: PathBuf,
    materials: PathBuf,
    only: Vec<String>,
    errors: bool,
    points: usize,
    seed: u64,
    font: PathBuf,
}

fn plot(args: &PlotArgs) -> Result<ExitCode, Error> {
    use generator::plot;
    plot::load_font(&args.font)?;
    let materials = Materials::load(&args.materials)?;
    for name in &args.only {
        if !materials.materials.iter().any(|m| &m.name == name) {
            return Err(Error::Usage(format!(
                "no material {name} in {}",
                args.materials.display()
            )));
        }
    }
    std::fs::create_dir_all(&args.out).map_err(Error::file(FileAction::Create, &args.out))?;
    let out = std::fs::canonicalize(&args.out).unwrap_or_else(|_| args.out.clone());
    // The green channel (as T4's band-limit study).
    let channel = 1;
    let lambda = materials.wavelengths[channel];
    for material in &materials.materials {
        if !args.only.is_empty() && !args.only.contains(&material.name) {
            continue;
        }
        let path = out.join(format!("lobes-{}.png", material.name));
        plot::lobes(material, channel, lambda, &args.tables, &path)?;
        eprintln!("wrote {}", path.display());
    }
    if args.errors {
        let (dir, points, seed) = (&args.tables, args.points, args.seed);
        let suffix = format!("{points} verify points, seed {seed}; largest error per bin");
        let t1 = plot::View {
            title: format!("T1 (Smith G1): |G1 − G1_ref|, {suffix}"),
            x: (0.2, 5.0, "p"),
            y: (-4.0, 4.0, "log10 a"),
        };
        let path = out.join("error-t1.png");
        plot::heat_map(
            &path,
            &t1,
            &plot::t1_errors(dir, points, seed)?,
            (48, 32),
            "|G1 − G1_ref|",
        )?;
        eprintln!("wrote {}", path.display());
        let t2 = plot::View {
            title: format!("T2 (σ ratio): relative error, {suffix} (over c)"),
            x: (0.0, 90.0, "θi (°)"),
            y: (-1.0, 3000f64.log10(), "log10 B"),
        };
        let path = out.join("error-t2.png");
        plot::heat_map(
            &path,
            &t2,
            &plot::t2_errors(dir, points, seed)?,
            (45, 30),
            "relative error",
        )?;
        eprintln!("wrote {}", path.display());
        let profiles = plot::t3_errors(dir, points, seed)?;
        let path = out.join("error-t3.png");
        plot::t3_map(
            &path,
            &profiles,
            &format!(
                "T3b: e_L2 of each of verify's {} profiles (seed {seed})",
                profiles.len()
            ),
        )?;
        eprintln!("wrote {}", path.display());
    }
    Ok(ExitCode::SUCCESS)
}

/// The arguments of `export`.
struct ExportArgs {
    out: PathBuf,
    format: String,
    tables: Vec<String>,
    precision: Option<String>,
    dir: PathBuf,
    points: usize,
    seed: u64,
}

fn export(args: &ExportArgs) -> Result<ExitCode, String> {
    use generator::export::{self, Format, Precision, Source};
    let format = Format::parse(&args.format)?;
    let precision = args
        .precision
        .as_deref()
        .map(Precision::parse)
        .transpose()?;
    let kinds = if args.tables.is_empty() {
        export::EXPORTABLE
            .iter()
            .map(|id| export::table_by_name(id.name()))
            .collect::<Result<Vec<_>, _>>()?
    } else {
        args.tables
            .iter()
            .map(|n| export::table_by_name(n))
            .collect::<Result<Vec<_>, _>>()?
    };
    let files = kinds
        .iter()
        .map(|kind| {
            let path = args.dir.join(tables::file_name(kind.id()));
            MappedFile::open(&path).map_err(|e| format!("cannot open {}: {e}", path.display()))
        })
        .collect::<Result<Vec<_>, _>>()?;
    let sources = kinds
        .iter()
        .zip(&files)
        .map(|(kind, file)| {
            Source::new(file.bytes(), kind.id()).map_err(|e| format!("{}: {e}", kind.id().name()))
        })
        .collect::<Result<Vec<_>, _>>()?;
    // Every requested precision is checked before anything is written.
    let encoded = sources
        .iter()
        .map(|source| match precision {
            Some(p) => export::export_precision(source, p).map(|e| vec![e]),
            None => export::allowed_precisions(source)
                .into_iter()
                .map(|p| export::export_precision(source, p))
                .collect(),
        })
        .collect::<Result<Vec<_>, _>>()?;
    std::fs::create_dir_all(&args.out)
        .map_err(|e| format!("cannot create {}: {e}", args.out.display()))?;
    let write = |name: &str, bytes: &[u8]| {
        let path = args.out.join(name);
        write_atomic(&path, bytes).map_err(|e| format!("cannot write {}: {e}", path.display()))?;
        eprintln!("wrote {} ({} bytes)", path.display(), bytes.len());
        Ok::<(), String>(())
    };
    for (source, encoded) in sources.iter().zip(&encoded) {
        let stem = source.id().name();
        match format {
            Format::Npy => {
                let arrays = encoded.iter().flat_map(|e| &e.arrays);
                for a in export::aux_array(source).iter().chain(arrays) {
                    write(
                        &format!("{stem}.{}.npy", a.suffix),
                        &export::npy::encode(&a.array)?,
                    )?;
                }
            }
            Format::C => write(
                &format!("{stem}.h"),
                export::c::header(source, encoded).as_bytes(),
            )?,
        }
    }
    let entries: Vec<_> = sources.iter().zip(encoded.iter().cloned()).collect();
    write("tables.json", export::json(&entries).as_bytes())?;
    if args.points == 0 {
        return Ok(ExitCode::SUCCESS);
    }
    // The measurement reads back what was written (npy) or the arrays of
    // the headers (c: the same arrays), decoded as a shader decodes them.
    let mut reports = Vec::new();
    for ((kind, file), (source, encoded)) in
        kinds.iter().zip(&files).zip(sources.iter().zip(&encoded))
    {
        for e in encoded {
            let mut e = e.clone();
            if format == Format::Npy {
                e.decoded = read_back(&args.out, source.id().name(), &e)?;
            }
            let start = Instant::now();
            let outcome = export::measure(*kind, source, &e, file.bytes(), args.points, args.seed);
            eprintln!(
                "measured {} {} in {:.1} s",
                source.id().name(),
                e.precision.name(),
                start.elapsed().as_secs_f64()
            );
            let bytes: usize = e
                .arrays
                .iter()
                .map(|a| a.array.data.len() * a.array.data.item_size())
                .sum();
            reports.push(TableReport {
                stem: format!("{} {}", source.id().name(), e.precision.name()),
                bytes: bytes as u64,
                outcome: outcome.map_err(Error::Export),
            });
        }
    }
    print!("{}", report::text(&reports));
    Ok(if reports.iter().all(TableReport::passed) {
        ExitCode::SUCCESS
    } else {
        ExitCode::FAILURE
    })
}

/// The values of an exported precision decoded from the .npy files written.
fn read_back(
    dir: &Path,
    stem: &str,
    encoded: &generator::export::Encoded,
) -> Result<Vec<f32>, String> {
    use generator::export::npy::{self, Data};
    let read = |suffix: &str| {
        let path = dir.join(format!("{stem}.{suffix}.npy"));
        let bytes =
            std::fs::read(&path).map_err(|e| format!("cannot read {}: {e}", path.display()))?;
        npy::decode(&bytes).map_err(|e| format!("{}: {e}", path.display()))
    };
    let name = encoded.precision.name();
    match (read(name)?.data, encoded.unorm) {
        (Data::F32(values), _) => Ok(values),
        (Data::U16(bits), _) if name == "f16" => Ok(bits
            .iter()
            .map(|&b| half::f16::from_bits(b).to_f32())
            .collect()),
        (Data::U16(codes), Some((offset, step))) => Ok(codes
            .iter()
            .map(|&q| offset + f32::from(q) * step)
            .collect()),
        (Data::U16(codes), None) => {
            let Data::F32(scales) = read("unorm16-scales")?.data else {
                return Err(format!("{stem}.unorm16-scales.npy is not f32"));
            };
            let channels = codes.len() / (scales.len() / 2).max(1);
            Ok(codes
                .iter()
                .enumerate()
                .map(|(k, &q)| {
                    let node = k / channels.max(1);
                    scales[2 * node] + f32::from(q) * scales[2 * node + 1]
                })
                .collect())
        }
    }
}

fn inspect(files: &[PathBuf]) -> Result<ExitCode, Error> {
    let mut failed = false;
    for path in files {
        let file = MappedFile::open(path).map_err(Error::file(FileAction::Open, path))?;
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
            "  table              T{} {} (tag {}): {}",
            id.number(),
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
        if id == TableId::ShBrdf
            && let Ok(table) = twoscale::ShBrdfTable::from_bytes(bytes)
        {
            println!(
                "  projected BRDF     {:?}, {} packed coefficients per channel",
                table.model(),
                twoscale::sh::coefficient_count(table.band_limit())
            );
            for (name, value) in twoscale::sh::AUX_NAMES.iter().zip(table.aux()) {
                println!("  aux {name:<20} {value}");
            }
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

fn query(quantity: &str, tables: &Path) -> Result<ExitCode, Error> {
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
    out.flush()
        .map_err(|e| Error::Query(generator::query::QueryError::Write(e)))?;
    if summary.bad > 0 {
        eprintln!(
            "{} row(s) answered, {} bad row(s) reported above",
            summary.answered, summary.bad
        );
        return Ok(ExitCode::FAILURE);
    }
    Ok(ExitCode::SUCCESS)
}
