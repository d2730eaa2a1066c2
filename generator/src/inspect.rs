//! `generator inspect`: the header of table files, readably, and whether
//! each file is valid.

use std::io::Write;
use std::path::{Path, PathBuf};
use std::process::ExitCode;
use twoscale::Table;
use twoscale::domain::{Shortest, Shortest32};
use twoscale::tables::format::{HEADER_SIZE, Header, MAGIC, TableId, checksum};
use twoscale::tables::interp::node_value;
use zerocopy::TryFromBytes;

use crate::error::{Error, FileAction};
use crate::table_source::TableSource;

/// What `inspect` reads: a table file, or every `*.tbl` file of a
/// directory (in name order).
fn files_of(path: &Path) -> Result<Vec<PathBuf>, Error> {
    if !path.is_dir() {
        return Ok(vec![path.to_path_buf()]);
    }
    let mut files = std::fs::read_dir(path)
        .map_err(Error::file(FileAction::Read, path))?
        .map(|entry| entry.map(|e| e.path()))
        .collect::<Result<Vec<_>, _>>()
        .map_err(Error::file(FileAction::Read, path))?;
    files.retain(|f| f.extension().is_some_and(|e| e == "tbl") && f.is_file());
    files.sort();
    if files.is_empty() {
        return Err(Error::Usage(format!(
            "{} holds no .tbl files",
            path.display()
        )));
    }
    Ok(files)
}

/// Prints the header of each of `paths` (files, or directories: every
/// `.tbl` file in them), or of the embedded tables if `paths` is empty, to
/// `out`. Exit status 1 if a file is invalid.
pub fn inspect(paths: &[PathBuf], out: &mut impl Write) -> Result<ExitCode, Error> {
    let write_error = |e| Error::file(FileAction::Write, "standard output")(e);
    let mut failed = false;
    if paths.is_empty() {
        for id in twoscale::table_set::TABLES {
            let file = TableSource::Embedded.open(id)?;
            let name = TableSource::Embedded.label(id.name());
            failed |= !describe(&name, file.bytes(), out).map_err(write_error)?;
        }
    }
    for path in paths {
        for file in files_of(path)? {
            let bytes = std::fs::read(&file).map_err(Error::file(FileAction::Read, &file))?;
            let bytes = twoscale::tables::format::aligned_copy(&bytes);
            failed |=
                !describe(&file.display().to_string(), bytes.bytes(), out).map_err(write_error)?;
        }
    }
    Ok(if failed {
        ExitCode::FAILURE
    } else {
        ExitCode::SUCCESS
    })
}

/// The bytes `b` as text, with anything but printable ASCII escaped
/// (`TS2TABLE`, `\x00\x01…`).
fn escaped(b: &[u8]) -> String {
    b.escape_ascii().to_string()
}

/// Prints the header of the table file `name` holding `bytes`; whether it
/// is valid.
fn describe(name: &str, bytes: &[u8], out: &mut impl Write) -> std::io::Result<bool> {
    writeln!(out, "{name}  ({} bytes)", bytes.len())?;
    if let Some(magic) = bytes.get(..MAGIC.len())
        && magic != MAGIC
    {
        writeln!(
            out,
            "  invalid: not a twoscale table file: starts with \"{}\", expected \"{}\"",
            escaped(magic),
            escaped(&MAGIC)
        )?;
        return Ok(false);
    }
    let Some(header) = bytes
        .get(..HEADER_SIZE)
        .and_then(|head| Header::try_ref_from_bytes(head).ok())
    else {
        // Let the validating reader say what is wrong.
        let e = Table::from_bytes(bytes)
            .err()
            .map_or("unreadable header".to_string(), |e| e.to_string());
        writeln!(out, "  invalid: {e}")?;
        return Ok(false);
    };
    let id = header.table_id;
    writeln!(out, "  format version     {}", header.format_version)?;
    writeln!(
        out,
        "  table              T{} {} (tag {}): {}",
        id.number(),
        id.name(),
        id.tag(),
        id.description()
    )?;
    writeln!(
        out,
        "  value type         {:?}, {} channel(s)",
        header.value_type, header.channels
    )?;
    for (d, axis) in header.used_axes().iter().enumerate() {
        let axis_name = id.axis_names().get(d).copied().unwrap_or("?");
        let second = if axis.nodes > 1 {
            format!(" (second node {})", number(node_value(axis, 1)))
        } else {
            String::new()
        };
        writeln!(
            out,
            "  axis {d} {:<10}   {} nodes on [{}, {}], evenly spaced in {}{second}",
            axis_name,
            axis.nodes,
            number(axis.lo),
            number(axis.hi),
            axis.mapping.describe(axis.param, axis.param2)
        )?;
    }
    writeln!(out, "  interpolation      {:?}", header.kernel)?;
    writeln!(out, "  aux values         {}", header.aux_count)?;
    writeln!(
        out,
        "  generator version  {}",
        header.generator_version_str()
    )?;
    for (param, value) in id.param_names().iter().zip(header.params) {
        writeln!(out, "  param {param:<18} {}", number(value))?;
    }
    if id == TableId::ShBrdf
        && let Ok(table) = twoscale::ShBrdfTable::from_bytes(bytes)
    {
        writeln!(
            out,
            "  projected BRDF     {:?}, {} packed coefficients per channel",
            table.model(),
            twoscale::tables::sh_brdf::coefficient_count(table.band_limit())
        )?;
        for (aux, value) in twoscale::tables::sh_brdf::AUX_NAMES.iter().zip(table.aux()) {
            writeln!(out, "  aux {aux:<20} {}", Shortest32(*value))?;
        }
    }
    writeln!(
        out,
        "  payload            {} bytes at offset {}",
        header.payload_len, header.payload_offset
    )?;
    let computed = checksum(bytes);
    writeln!(
        out,
        "  checksum           {:#018x} ({})",
        header.checksum,
        if computed == header.checksum {
            "matches"
        } else {
            "MISMATCH"
        }
    )?;
    Ok(match Table::from_bytes(bytes) {
        Ok(_) => {
            writeln!(out, "  valid")?;
            true
        }
        Err(e) => {
            writeln!(out, "  invalid: {e}")?;
            false
        }
    })
}

/// A header value as printed: integers as integers, others in the
/// shortest form that round-trips (exponent form only for very small or
/// large magnitudes).
fn number(value: f64) -> String {
    Shortest(value).to_string()
}
