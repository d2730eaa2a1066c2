//! `generator export`: the tables as plain arrays for use outside Rust (GPU
//! kernels, NumPy, Mitsuba textures), as `.npy` files or C headers, with a
//! JSON description of every axis. docs/export.md documents each array, its
//! axes and the interpolation a shader must do.
//!
//! What is exported is what the runtime interpolates: T1's G1 at the nodes,
//! T2's and T5's B-spline coefficients, T3's values per node (the fit
//! channels `ln s`, `ln(g² + g_offset)` and `ln C` at the 32 normalised
//! angles) decoded to f32 or as the file's own u16 codes with their per-node
//! `(offset, step)`.
//!
//! Precisions ([`Precision`]): `f32` (the runtime's values, exactly);
//! `unorm16` (`offset + code · step` with a 16-bit code: one `(offset, step)`
//! per array, T3's per node as in the file); `f16`. A precision is exported
//! only if its largest rounding error over the table's stored values is
//! within the table's rounding budget ([`rounding_budget`]: half the table's
//! accuracy target in the units of the stored values); otherwise the export
//! is refused with both figures.

pub mod c;
pub mod cli;
pub mod npy;

use std::fmt::Write as _;

use twoscale::tables::format::write::{TableSpec, encode};
use twoscale::tables::format::{Kernel, Table, TableId, ValueType, quantise_node};
use twoscale::tables::interp::{coordinate_f64, node_value};

use crate::tables::{self, Accuracy, Budget, Export, TableKind};

/// A precision of the exported values.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Precision {
    /// IEEE binary32: the runtime's values, bit for bit.
    F32,
    /// A 16-bit code with an `(offset, step)`: `value = offset + code · step`.
    Unorm16,
    /// IEEE binary16 (rounding 4.9e-4 relative).
    F16,
}

impl Precision {
    /// Every precision.
    pub const ALL: [Precision; 3] = [Precision::F32, Precision::Unorm16, Precision::F16];

    /// Its name on the command line and in file names.
    pub const fn name(self) -> &'static str {
        match self {
            Precision::F32 => "f32",
            Precision::Unorm16 => "unorm16",
            Precision::F16 => "f16",
        }
    }

    /// The precision named `name`.
    pub fn parse(name: &str) -> Result<Precision, String> {
        Self::ALL
            .into_iter()
            .find(|p| p.name() == name)
            .ok_or_else(|| format!("unknown precision '{name}' (known: f32, unorm16, f16)"))
    }
}

/// An output format.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Format {
    /// One `.npy` per array, and `tables.json`.
    Npy,
    /// One C header per table (`static const` arrays, axis constants and
    /// inline position functions), and `tables.json`.
    C,
}

impl Format {
    /// The format named `name`.
    pub fn parse(name: &str) -> Result<Format, String> {
        match name {
            "npy" => Ok(Format::Npy),
            "c" => Ok(Format::C),
            other => Err(format!("unknown format '{other}' (known: npy, c)")),
        }
    }
}

/// The tables `export` knows: those of the runtime's
/// [`TableSet`](twoscale::TableSet), each with an [`Export`] in the registry
/// (T4 is not exported; a unit test of [`tables`] checks both).
pub const EXPORTABLE: [TableId; 5] = twoscale::table_set::TABLES;

/// The table named `name` (a file stem or a unique prefix, as for `build`:
/// [`tables::select`]), if `export` supports it.
pub fn table_by_name(name: &str) -> Result<&'static dyn TableKind, String> {
    let known = EXPORTABLE.map(TableId::name).join(", ");
    if name.starts_with(&format!("t{}", TableId::ShBrdf.number())) {
        return Err(format!(
            "'{name}': T4 (SH matrices) is not exported; exportable tables: {known}"
        ));
    }
    let exportable: Vec<_> = tables::all()
        .into_iter()
        .filter(|k| EXPORTABLE.contains(&k.id()))
        .collect();
    tables::select(name, &exportable)
        .ok()
        .and_then(|kinds| kinds.into_iter().next())
        .ok_or_else(|| format!("unknown table '{name}' (exportable: {known})"))
}

/// One table read from its file: what the runtime interpolates, per node.
pub struct Source<'a> {
    /// The validated file.
    pub table: Table<'a>,
    /// The stored values as the runtime decodes them, row-major, channels
    /// innermost (T3: `offset + code · step` per node, in f32).
    pub values: Vec<f32>,
    /// The array shape: stored values per axis, then channels if more than one.
    pub shape: Vec<usize>,
    /// What the table's registry entry says of its export.
    pub export: Export,
}

impl<'a> Source<'a> {
    /// Reads a table file of an exportable table.
    pub fn new(bytes: &'a [u8], id: TableId) -> Result<Source<'a>, String> {
        let export = tables::by_id(id)
            .and_then(|k| k.export())
            .ok_or_else(|| format!("{} is not exported", id.name()))?;
        let table = Table::from_bytes_expecting(bytes, id).map_err(|e| e.to_string())?;
        let header = table.header();
        let mut shape: Vec<usize> = header
            .used_axes()
            .iter()
            .map(|a| header.kernel.stored_per_axis(a.nodes) as usize)
            .collect();
        let channels = header.channels as usize;
        if channels > 1 {
            shape.push(channels);
        }
        let values = match table.quantised() {
            Some(q) => (0..q.nodes())
                .flat_map(|n| (0..channels).map(move |ch| q.value(n, ch)))
                .collect(),
            None => table.grid().to_vec(),
        };
        Ok(Source {
            table,
            values,
            shape,
            export,
        })
    }

    /// The table id.
    pub fn id(&self) -> TableId {
        self.table.header().table_id
    }
}

/// Half the table's accuracy target, in the units of its stored values: the
/// largest rounding error an exported precision may add (the table's
/// [`Budget`], documented on each table's `export()`).
pub fn rounding_budget(source: &Source<'_>) -> f64 {
    match source.export.budget {
        Budget::Absolute(budget) => budget,
        Budget::RelativeToMin(fraction) => {
            let min = source.values.iter().copied().fold(f32::INFINITY, f32::min);
            fraction * f64::from(min)
        }
        Budget::HalfQuantisationStep => {
            source.table.quantised().map_or(0.0, |q| {
                q.scales
                    .chunks_exact(2)
                    .map(|s| f64::from(s[1]))
                    .fold(0.0, f64::max)
            }) / 2.0
        }
    }
}

/// One exported array.
#[derive(Clone, Debug)]
pub struct NamedArray {
    /// Suffix of its file or identifier: `f32`, `unorm16`, `unorm16-scales`, `aux`.
    pub suffix: String,
    /// The values.
    pub array: npy::Array,
}

/// A table at one precision, encoded.
#[derive(Clone, Debug)]
pub struct Encoded {
    /// The precision.
    pub precision: Precision,
    /// The arrays a user reads (values; for T3 unorm16 also the scales).
    pub arrays: Vec<NamedArray>,
    /// `(offset, step)` of a per-array unorm16 code.
    pub unorm: Option<(f32, f32)>,
    /// The values a shader decodes from `arrays`, in f32.
    pub decoded: Vec<f32>,
    /// Largest `|decoded − runtime value|` over the stored values.
    pub rounding: f64,
}

/// Decodes `offset + code · step` in f32, as the runtime decodes T3.
fn dequantise(offset: f32, step: f32, code: u16) -> f32 {
    offset + f32::from(code) * step
}

/// Encodes a table at `precision` (whether or not it meets the budget).
pub fn encode_precision(source: &Source<'_>, precision: Precision) -> Encoded {
    let shape = source.shape.clone();
    let named = |suffix: &str, data| NamedArray {
        suffix: suffix.to_string(),
        array: npy::Array {
            shape: shape.clone(),
            data,
        },
    };
    let (arrays, unorm, decoded) = match (precision, source.table.quantised()) {
        (Precision::F32, _) => (
            vec![named("f32", npy::Data::F32(source.values.clone()))],
            None,
            source.values.clone(),
        ),
        (Precision::Unorm16, Some(q)) => {
            // The file's own codes and per-node (offset, step).
            let mut scale_shape = shape.clone();
            if let Some(last) = scale_shape.last_mut() {
                *last = 2;
            }
            let decoded = (0..q.nodes())
                .flat_map(|n| {
                    let (offset, step) = (q.scales[2 * n], q.scales[2 * n + 1]);
                    let codes = &q.codes[n * q.channels..(n + 1) * q.channels];
                    codes.iter().map(move |&c| dequantise(offset, step, c))
                })
                .collect();
            let scales = NamedArray {
                suffix: "unorm16-scales".into(),
                array: npy::Array {
                    shape: scale_shape,
                    data: npy::Data::F32(q.scales.to_vec()),
                },
            };
            (
                vec![named("unorm16", npy::Data::U16(q.codes.to_vec())), scales],
                None,
                decoded,
            )
        }
        (Precision::Unorm16, None) => {
            // One (offset, step) for the whole array: the runtime's quantiser.
            let mut codes = vec![0u16; source.values.len()];
            let [offset, step] = quantise_node(&source.values, &mut codes);
            let decoded = codes.iter().map(|&c| dequantise(offset, step, c)).collect();
            (
                vec![named("unorm16", npy::Data::U16(codes))],
                Some((offset, step)),
                decoded,
            )
        }
        (Precision::F16, _) => {
            let bits: Vec<u16> = source
                .values
                .iter()
                .map(|&v| half::f16::from_f32(v).to_bits())
                .collect();
            let decoded = bits
                .iter()
                .map(|&b| half::f16::from_bits(b).to_f32())
                .collect();
            (vec![named("f16", npy::Data::U16(bits))], None, decoded)
        }
    };
    let rounding = decoded
        .iter()
        .zip(&source.values)
        .map(|(&d, &v)| (f64::from(d) - f64::from(v)).abs())
        .fold(0.0, f64::max);
    Encoded {
        precision,
        arrays,
        unorm,
        decoded,
        rounding,
    }
}

/// The table's auxiliary values (T1: `k_p` at each p node), if any.
pub fn aux_array(source: &Source<'_>) -> Option<NamedArray> {
    let aux = source.table.aux();
    (!aux.is_empty()).then(|| NamedArray {
        suffix: "aux".into(),
        array: npy::Array {
            shape: vec![aux.len()],
            data: npy::Data::F32(aux.to_vec()),
        },
    })
}

/// [`encode_precision`], or why the precision is refused: its rounding
/// error exceeds [`rounding_budget`].
pub fn export_precision(source: &Source<'_>, precision: Precision) -> Result<Encoded, String> {
    let encoded = encode_precision(source, precision);
    let budget = rounding_budget(source);
    if encoded.rounding > budget {
        return Err(format!(
            "{} cannot be exported as {}: its rounding error {:.2e} exceeds the table's rounding budget {:.2e} (docs/export.md); use {}",
            source.id().name(),
            precision.name(),
            encoded.rounding,
            budget,
            allowed_precisions(source)
                .iter()
                .map(|p| p.name())
                .collect::<Vec<_>>()
                .join(" or ")
        ));
    }
    Ok(encoded)
}

/// The precisions whose rounding is within the table's budget (the default
/// of `export` without `--precision`).
pub fn allowed_precisions(source: &Source<'_>) -> Vec<Precision> {
    let budget = rounding_budget(source);
    Precision::ALL
        .into_iter()
        .filter(|&p| encode_precision(source, p).rounding <= budget)
        .collect()
}

/// A table file holding `decoded` in place of the source's values, for the
/// runtime's typed readers (and so `generator verify`'s measurement): f32
/// tables are re-encoded with the same header; T3's u16 payload is
/// re-quantised from the decoded values by the runtime's quantiser.
pub fn table_file(source: &Source<'_>, decoded: &[f32]) -> Result<Vec<u8>, String> {
    let header = source.table.header();
    let names = header.table_id.param_names().len();
    encode(&TableSpec {
        table_id: header.table_id,
        channels: header.channels,
        kernel: header.kernel,
        value_type: header.value_type,
        axes: header.used_axes(),
        params: &header.params[..names],
        grid: decoded,
        aux: source.table.aux(),
        generator_version: header.generator_version_str(),
    })
    .map_err(|e| e.to_string())
}

/// `verify`'s measurement of the exported values: the decoded values are
/// put back into a table file ([`table_file`]), read by the runtime's typed
/// reader, interpolated as the runtime interpolates (the scheme a shader
/// must follow, docs/export.md) and compared with the f64 reference at
/// `generator verify`'s random points.
///
/// For T3 the runtime reads u16 codes only: the decoded values are
/// re-quantised per node, and the measurement is refused (an error) unless
/// that gives back the original file byte for byte, i.e. unless the
/// exported values are exactly the runtime's.
pub fn measure(
    kind: &dyn TableKind,
    source: &Source<'_>,
    encoded: &Encoded,
    original: &[u8],
    points: usize,
    seed: u64,
) -> Result<Vec<Accuracy>, String> {
    let file = table_file(source, &encoded.decoded)?;
    if source.table.header().value_type == ValueType::U16 && file != original {
        return Err(format!(
            "{} {}: the exported values do not re-quantise to the runtime's file, so the runtime cannot interpolate them",
            source.id().name(),
            encoded.precision.name()
        ));
    }
    let aligned = twoscale::tables::format::aligned_copy(&file);
    kind.verify(aligned.bytes(), points, seed)
        .map_err(|e| e.to_string())
}

/// The JSON of `tables.json`: per table, its axes (mapping, domain, node
/// values), interpolation, parameters, and per precision its files and
/// decoding.
pub fn json(entries: &[(&Source<'_>, Vec<Encoded>)]) -> String {
    let mut out = String::from(
        "{\n  \"format\": \"twoscale-export 1\",\n  \"doc\": \"docs/export.md\",\n  \"tables\": {\n",
    );
    for (k, (source, encoded)) in entries.iter().enumerate() {
        let header = source.table.header();
        let id = header.table_id;
        let stem = id.name();
        let _ = writeln!(out, "    \"{stem}\": {{");
        let _ = writeln!(
            out,
            "      \"description\": {},",
            json_string(id.description())
        );
        let _ = writeln!(
            out,
            "      \"interpolation\": {},",
            json_string(source.export.interpolation)
        );
        let kernel = match header.kernel {
            Kernel::Multilinear | Kernel::CatmullRom => "node values",
            Kernel::CubicBSpline => "cubic B-spline coefficients (nodes + 2 per axis)",
        };
        let _ = writeln!(out, "      \"stored\": {},", json_string(kernel));
        let _ = writeln!(out, "      \"shape\": {:?},", source.shape);
        let _ = writeln!(out, "      \"channels\": {},", header.channels);
        out.push_str("      \"axes\": [\n");
        let axes = header.used_axes();
        for (d, axis) in axes.iter().enumerate() {
            let nodes: Vec<String> = (0..axis.nodes as usize)
                .map(|i| json_number(node_value(axis, i)))
                .collect();
            let _ = writeln!(
                out,
                "        {{\"name\": \"{}\", \"nodes\": {}, \"stored\": {}, \"lo\": {}, \"hi\": {}, \"mapping\": \"{:?}\", \"param\": {}, \"param2\": {}, \"coordinate\": {}, \"c_lo\": {}, \"c_hi\": {}, \"node_values\": [{}]}}{}",
                id.axis_names().get(d).copied().unwrap_or("?"),
                axis.nodes,
                header.kernel.stored_per_axis(axis.nodes),
                json_number(axis.lo),
                json_number(axis.hi),
                axis.mapping,
                json_number(axis.param),
                json_number(axis.param2),
                json_string(&format!(
                    "c(x) = {}",
                    axis.mapping.describe(axis.param, axis.param2)
                )),
                json_number(coordinate_f64(axis, axis.lo)),
                json_number(coordinate_f64(axis, axis.hi)),
                nodes.join(", "),
                if d + 1 < axes.len() { "," } else { "" }
            );
        }
        out.push_str("      ],\n      \"params\": {");
        let params: Vec<String> = id
            .param_names()
            .iter()
            .zip(header.params)
            .map(|(n, v)| format!("\"{n}\": {}", json_number(v)))
            .collect();
        out.push_str(&params.join(", "));
        out.push_str("},\n");
        if let Some(aux) = aux_array(source) {
            let _ = writeln!(
                out,
                "      \"aux\": {{\"file\": \"{stem}.aux.npy\", \"count\": {}, \"meaning\": {}}},",
                aux.array.data.len(),
                json_string(id.descriptor().aux)
            );
        }
        out.push_str("      \"precisions\": {\n");
        for (j, e) in encoded.iter().enumerate() {
            let files: Vec<String> = e
                .arrays
                .iter()
                .map(|a| format!("\"{stem}.{}.npy\"", a.suffix))
                .collect();
            let decode = match (e.precision, e.unorm) {
                (Precision::F32, _) => "value".to_string(),
                (Precision::F16, _) => "IEEE binary16 bits (np.uint16 .view(np.float16))".into(),
                (Precision::Unorm16, Some((offset, step))) => format!(
                    "value = offset + code * step, offset = {}, step = {} (f32)",
                    json_f32(offset),
                    json_f32(step)
                ),
                (Precision::Unorm16, None) => {
                    "value = scales[..., 0] + code * scales[..., 1] per node (f32)".into()
                }
            };
            let unorm = e.unorm.map_or(String::new(), |(o, s)| {
                format!(", \"offset\": {}, \"step\": {}", json_f32(o), json_f32(s))
            });
            let _ = writeln!(
                out,
                "        \"{}\": {{\"files\": [{}], \"decode\": {}{unorm}, \"rounding_max\": {}, \"rounding_budget\": {}}}{}",
                e.precision.name(),
                files.join(", "),
                json_string(&decode),
                json_number(e.rounding),
                json_number(rounding_budget(source)),
                if j + 1 < encoded.len() { "," } else { "" }
            );
        }
        out.push_str("      }\n");
        let _ = writeln!(
            out,
            "    }}{}",
            if k + 1 < entries.len() { "," } else { "" }
        );
    }
    out.push_str("  }\n}\n");
    out
}

/// A JSON string literal.
fn json_string(s: &str) -> String {
    let mut out = String::from("\"");
    for ch in s.chars() {
        match ch {
            '"' => out.push_str("\\\""),
            '\\' => out.push_str("\\\\"),
            '\n' => out.push_str("\\n"),
            c if (c as u32) < 0x20 => {
                let _ = write!(out, "\\u{:04x}", c as u32);
            }
            c => out.push(c),
        }
    }
    out.push('"');
    out
}

/// A JSON number (shortest round-trip form; non-finite values as null).
fn json_number(x: f64) -> String {
    if x.is_finite() {
        format!("{x:?}")
    } else {
        "null".into()
    }
}

/// An f32 as a JSON number that reads back to the same f32.
fn json_f32(x: f32) -> String {
    if x.is_finite() {
        format!("{x:?}")
    } else {
        "null".into()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn json_escapes_and_numbers() {
        assert_eq!(json_string("a\"b\\c\nd"), "\"a\\\"b\\\\c\\nd\"");
        assert_eq!(json_number(1e-12), "1e-12");
        assert_eq!(json_number(0.2), "0.2");
        assert_eq!(json_number(f64::NAN), "null");
    }

    #[test]
    fn precisions_and_formats_parse_with_clear_errors() {
        assert_eq!(Precision::parse("unorm16"), Ok(Precision::Unorm16));
        assert!(
            Precision::parse("f64")
                .unwrap_err()
                .contains("unknown precision 'f64'")
        );
        assert_eq!(Format::parse("c"), Ok(Format::C));
        assert!(Format::parse("csv").unwrap_err().contains("known: npy, c"));
        let error = |name| table_by_name(name).err().unwrap_or_default();
        assert!(error("t4").contains("not exported"));
        assert!(error("t9").contains("unknown table 't9'"));
        assert_eq!(table_by_name("t1").unwrap().id(), TableId::SmithG1);
    }
}
