//! `generator`: builds, verifies, inspects and queries the two-scale tables.
//! The command line only: each subcommand's body is a module of the library
//! ([`generator::build`], [`generator::verify`], [`generator::inspect`],
//! [`generator::plot`], [`generator::export`], [`generator::query`]).
//!
//! `query`, `verify`, `inspect` and `plot` read the tables compiled into the
//! binary unless given a directory; `build` writes to `./tables` unless given
//! `--out`. With no subcommand it prints its help.

use clap::{CommandFactory, Parser, Subcommand};
use std::io::{BufReader, Write};
use std::path::{Path, PathBuf};
use std::process::ExitCode;

use generator::error::Error;
use generator::materials::Materials;
use generator::table_source::TableSource;
use generator::tables::sh_brdf::{Projected, ShBrdf};
use generator::tables::{self, TableKind};

/// Where `build` and `merge` write unless given `--out` (relative to the
/// working directory).
const DEFAULT_OUT: &str = "tables";
/// Where `plot` writes unless given `--out`.
const DEFAULT_IMAGES: &str = "img";

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
        #[arg(long, default_value = DEFAULT_OUT)]
        out: PathBuf,
        /// Materials file (T4: one table per material with a band limit).
        /// Default: the shipped presets with their band limits (the
        /// repository's materials.toml, compiled in).
        #[arg(long, value_name = "FILE")]
        materials: Option<PathBuf>,
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
        #[arg(long, default_value = DEFAULT_OUT)]
        out: PathBuf,
    },
    /// Check headers and checksums of a table directory, then measure every
    /// table against the reference at random off-grid points.
    Verify {
        /// Table directory (T4 files included; the spectral bakes' row reads
        /// its T1, T2, T3, T5, T6). Default: the tables compiled into the
        /// binary (T1, T2, T3, T5, T6).
        dir: Option<PathBuf>,
        /// Materials file (T4: one table per material). Default: the
        /// shipped presets.
        #[arg(long, value_name = "FILE")]
        materials: Option<PathBuf>,
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
        /// Random materials of the BRDF section (24 direction pairs each).
        #[arg(long, default_value_t = generator::brdf_accuracy::DEFAULT_SIZE.materials)]
        brdf_materials: usize,
        /// How many of them also get an exact-node C bake (seconds of CPU each).
        #[arg(long, default_value_t = generator::brdf_accuracy::DEFAULT_SIZE.exact)]
        brdf_exact: usize,
    },
    /// Recompute a spread of grid nodes of tables too expensive to rebuild
    /// in CI (T3) and compare their bits with the files in a directory.
    SpotCheck {
        /// Tables to check (names or prefixes); all that support it if none.
        tables: Vec<String>,
        /// Table directory. Default: the tables compiled into the binary.
        #[arg(long, value_name = "DIR")]
        dir: Option<PathBuf>,
        /// Materials file (T4: one table per material). Default: the
        /// shipped presets.
        #[arg(long, value_name = "FILE")]
        materials: Option<PathBuf>,
        /// Nodes to recompute per table (spread evenly, first and last included).
        #[arg(long, default_value_t = 24)]
        nodes: usize,
        /// Worker threads (default: all cores).
        #[arg(long)]
        threads: Option<usize>,
    },
    /// Draw the pictures of docs/img/ (`plot --out docs/img`): the BRDF lobes of each material in the
    /// plane of incidence (lobes-<name>.png) and the error maps of T1, T2 and
    /// T3 at verify's points (error-t1.png, error-t2.png, error-t3.png).
    Plot {
        /// Output directory.
        #[arg(long, default_value = DEFAULT_IMAGES)]
        out: PathBuf,
        /// Table directory. Default: the tables compiled into the binary.
        #[arg(long, value_name = "DIR")]
        tables: Option<PathBuf>,
        /// Materials file. Default: the shipped presets.
        #[arg(long, value_name = "FILE")]
        materials: Option<PathBuf>,
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
        /// Tables to export (names or prefixes: t1, t2, t3, t5, t6); all five if none.
        #[arg(long = "table")]
        tables: Vec<String>,
        /// f32, unorm16 or f16. Default: every precision whose rounding is
        /// within the table's budget (half its accuracy target). A precision
        /// a table cannot meet is refused with its rounding error.
        #[arg(long)]
        precision: Option<String>,
        /// Table directory to read. Default: the tables compiled into the binary.
        #[arg(long, value_name = "DIR")]
        dir: Option<PathBuf>,
        /// Random points of the measurement per table and precision, as for
        /// verify (0: no measurement).
        #[arg(long, default_value_t = 20_000)]
        points: usize,
        /// Seed of the random points.
        #[arg(long, default_value_t = 2017)]
        seed: u64,
    },
    /// Print the header of table files readably, and whether each is valid.
    Inspect {
        /// Table files, or directories (every .tbl file in them). Default:
        /// the tables compiled into the binary.
        paths: Vec<PathBuf>,
    },
    /// Batch query (docs/model.md §6): CSV on stdin, CSV on stdout with `table` and
    /// `reference` columns. A row outside a table's domain (g1, sigma-ratio,
    /// conv, fresnel) or the model's (brdf) is reported with the domain and
    /// left out; the exit status is then 1. Quantities: g1 (columns p,a), sigma-ratio
    /// (columns theta_i,B,c; θi in radians), fresnel (columns n,k,cos_theta;
    /// `table` is the runtime's f32 value, which needs no table), conv
    /// (columns u,c,beta,p,theta_h; outputs fit = T3a, table = T3b,
    /// reference = exact C), brdf (docs/model.md §6 columns; conductor two-scale model).
    Query {
        /// The quantity.
        quantity: String,
        /// Table directory. Default: the tables compiled into the binary.
        #[arg(long, value_name = "DIR")]
        tables: Option<PathBuf>,
        /// Answer rows outside a single table's domain at the clamped point
        /// (as the renderer-facing lookups do) and add a column `in_domain`
        /// (false for those rows).
        #[arg(long)]
        clamp: bool,
        /// `brdf` of the material of this material file (TOML: a
        /// `[material]` table, what `python -m twoscale.fit` writes; a
        /// conductor, its Lambertian term k_d/π added to the reference):
        /// the rows then give `channel,ix,iy,iz,ox,oy,oz` (channel 0, 1, 2:
        /// red, green, blue) and `table` is the RGB model's channel, or
        /// `lambda,ix,iy,iz,ox,oy,oz` (λ in [0.36, 0.83] µm) and `table` is
        /// the spectral model at λ (for a material over the spectrum:
        /// `eta = { lambda, n, k }`, or one (n, k) for every channel).
        #[arg(long, value_name = "FILE")]
        material: Option<PathBuf>,
    },
}

fn main() -> ExitCode {
    let cli = Cli::parse();
    let Some(command) = cli.command else {
        // No subcommand: the help, and the usage-error status.
        let _ = Cli::command().print_help();
        return ExitCode::from(2);
    };
    let result = match command {
        Command::Build {
            tables,
            out,
            materials,
            threads,
            shard,
        } => set_threads(threads).and_then(|()| {
            let t4 = material_tables(materials.as_deref(), &out)?;
            let kinds = selected(&tables, &t4)?;
            match shard {
                None => generator::build::build(&kinds, &out),
                Some(shard) => {
                    if tables.is_empty()
                        || kinds
                            .iter()
                            .any(|k| k.id() != twoscale::TableId::Convolution)
                    {
                        return Err(Error::Usage(
                            "--shard applies to T3 alone: `build t3 --shard K/N`".into(),
                        ));
                    }
                    generator::build::build_shard(&out, &shard)
                }
            }
        }),
        Command::Merge { shards, out } => generator::build::merge(&shards, &out),
        Command::Verify {
            dir,
            materials,
            tables,
            points,
            seed,
            threads,
            markdown,
            brdf_materials,
            brdf_exact,
        } => set_threads(threads).and_then(|()| {
            let source = TableSource::new(dir);
            let t4 = t4_tables(materials.as_deref(), &source)?;
            let kinds = selected_in(&tables, &t4, &source)?;
            let args = generator::verify::VerifyArgs {
                names: &tables,
                points,
                seed,
                markdown: markdown.as_deref(),
                brdf: generator::brdf_accuracy::Size {
                    materials: brdf_materials,
                    exact: brdf_exact.min(brdf_materials),
                    ..generator::brdf_accuracy::DEFAULT_SIZE
                },
            };
            generator::verify::verify(&kinds, &source, &args)
        }),
        Command::SpotCheck {
            tables,
            dir,
            materials,
            nodes,
            threads,
        } => set_threads(threads).and_then(|()| {
            let source = TableSource::new(dir);
            let t4 = t4_tables(materials.as_deref(), &source)?;
            let kinds = selected_in(&tables, &t4, &source)?;
            generator::build::spot_check(&kinds, !tables.is_empty(), &source, nodes)
        }),
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
            generator::plot::run(&generator::plot::PlotArgs {
                out,
                tables: TableSource::new(tables),
                materials: Materials::load_or_shipped(materials.as_deref())?,
                only,
                errors: !no_errors,
                points,
                seed,
                font,
            })?;
            Ok(ExitCode::SUCCESS)
        }),
        Command::Export {
            out,
            format,
            tables,
            precision,
            dir,
            points,
            seed,
        } => generator::export::cli::run(&generator::export::cli::ExportArgs {
            out,
            format,
            tables,
            precision,
            dir: TableSource::new(dir),
            points,
            seed,
        })
        .map_err(Error::Export),
        Command::Inspect { paths } => {
            generator::inspect::inspect(&paths, &mut std::io::stdout().lock())
        }
        Command::Query {
            quantity,
            tables,
            clamp,
            material,
        } => query(
            &quantity,
            &TableSource::new(tables),
            clamp,
            material.as_deref(),
        ),
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

/// The T4 builders of the materials file (default: the shipped one),
/// projecting the two-scale model with the tables of `dir` (or the
/// embedded ones: `sh_brdf::input_dir`).
fn material_tables(materials: Option<&Path>, dir: &Path) -> Result<Vec<ShBrdf>, Error> {
    let materials = Materials::load_or_shipped(materials)?;
    Ok(ShBrdf::all(
        &materials,
        &Projected::TwoScale {
            dir: dir.to_path_buf(),
        },
    ))
}

/// The T4 tables of `source`: none for the embedded tables (T4 files are
/// per material and not compiled in).
fn t4_tables(materials: Option<&Path>, source: &TableSource) -> Result<Vec<ShBrdf>, Error> {
    match source.dir() {
        Some(dir) => material_tables(materials, dir),
        None => Ok(Vec::new()),
    }
}

/// [`selected`], saying where T4 is when reading the embedded tables.
fn selected_in<'a>(
    names: &[String],
    t4: &'a [ShBrdf],
    source: &TableSource,
) -> Result<Vec<&'a dyn TableKind>, Error> {
    selected(names, t4).map_err(|e| match (e, source) {
        (Error::Usage(m), TableSource::Embedded) => Error::Usage(format!(
            "{m}; T4 files are per material and not compiled in: give the table directory"
        )),
        (e, _) => e,
    })
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

/// `query`: stdin to stdout; exit status 1 if a row was not answered.
fn query(
    quantity: &str,
    tables: &TableSource,
    clamp: bool,
    material: Option<&Path>,
) -> Result<ExitCode, Error> {
    let material = material
        .map(twoscale::io::desc::MaterialDesc::from_toml_file)
        .transpose()
        .map_err(Error::Material)?;
    let stdin = std::io::stdin();
    let stdout = std::io::stdout();
    let mut out = std::io::BufWriter::new(stdout.lock());
    let summary = generator::query::run(
        quantity,
        tables,
        &generator::query::Options { clamp, material },
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
