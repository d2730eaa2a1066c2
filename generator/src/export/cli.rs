//! `generator export`: the command's run (the arrays, `tables.json` and the
//! measurement of each exported precision).

use std::path::{Path, PathBuf};
use std::process::ExitCode;
use std::time::Instant;
use twoscale::tables::format::write::write_atomic;

use super::{
    EXPORTABLE, Encoded, Format, Precision, Source, allowed_precisions, aux_array, c,
    export_precision, json, measure, npy, table_by_name,
};
use crate::error::Error;
use crate::report::{self, TableReport};
use crate::table_source::TableSource;

/// The arguments of `generator export`.
pub struct ExportArgs {
    /// Output directory (created if missing).
    pub out: PathBuf,
    /// `npy` or `c`.
    pub format: String,
    /// Tables to export (names or prefixes); all of [`EXPORTABLE`] if none.
    pub tables: Vec<String>,
    /// One precision, or every one within the table's budget.
    pub precision: Option<String>,
    /// The tables read.
    pub dir: TableSource,
    /// Random points of the measurement per table and precision (0: none).
    pub points: usize,
    /// Seed of the random points.
    pub seed: u64,
}

/// `generator export`: writes the arrays and `tables.json`, then measures
/// each exported precision as `verify` does.
pub fn run(args: &ExportArgs) -> Result<ExitCode, String> {
    let format = Format::parse(&args.format)?;
    let precision = args
        .precision
        .as_deref()
        .map(Precision::parse)
        .transpose()?;
    let kinds = if args.tables.is_empty() {
        EXPORTABLE
            .iter()
            .map(|id| table_by_name(id.name()))
            .collect::<Result<Vec<_>, _>>()?
    } else {
        args.tables
            .iter()
            .map(|n| table_by_name(n))
            .collect::<Result<Vec<_>, _>>()?
    };
    let files = kinds
        .iter()
        .map(|kind| args.dir.open(kind.id()).map_err(|e| e.to_string()))
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
            Some(p) => export_precision(source, p).map(|e| vec![e]),
            None => allowed_precisions(source)
                .into_iter()
                .map(|p| export_precision(source, p))
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
                for a in aux_array(source).iter().chain(arrays) {
                    write(&format!("{stem}.{}.npy", a.suffix), &npy::encode(&a.array)?)?;
                }
            }
            Format::C => write(&format!("{stem}.h"), c::header(source, encoded).as_bytes())?,
        }
    }
    let entries: Vec<_> = sources.iter().zip(encoded.iter().cloned()).collect();
    write("tables.json", json(&entries).as_bytes())?;
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
            let outcome = measure(*kind, source, &e, file.bytes(), args.points, args.seed);
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
fn read_back(dir: &Path, stem: &str, encoded: &Encoded) -> Result<Vec<f32>, String> {
    use super::npy::{self, Data};
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
