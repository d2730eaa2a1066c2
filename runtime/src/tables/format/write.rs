//! Writing table files (feature `std`): what the generator calls.

use super::*;
use std::io::Write;
use std::path::Path;
use zerocopy::IntoBytes;

/// Everything a table file holds, before encoding.
#[derive(Clone, Debug)]
pub struct TableSpec<'v> {
    /// What the table holds.
    pub table_id: TableId,
    /// Values per node.
    pub channels: u32,
    /// The interpolation kernel (B-spline grids hold prefiltered coefficients).
    pub kernel: Kernel,
    /// How `grid` is stored: as is ([`ValueType::F32`]) or quantised per
    /// node by [`quantise_node`] ([`ValueType::U16`]).
    pub value_type: ValueType,
    /// Used axes, in storage order.
    pub axes: &'v [AxisHeader],
    /// Generation parameters, in the order of [`TableId::param_names`]
    /// (the table's parameter struct's `to_values()`, e.g. [`ConvParams::to_values`]).
    pub params: &'v [f64],
    /// Grid values, row-major, channels innermost.
    pub grid: &'v [f32],
    /// Auxiliary values.
    pub aux: &'v [f32],
    /// Generator version (at most 16 ASCII bytes).
    pub generator_version: &'v str,
}

/// Encodes a table into the bytes of a file, and validates them by reading
/// them back (an encoder bug can never write a file the reader rejects).
pub fn encode(spec: &TableSpec<'_>) -> Result<Vec<u8>, FormatError> {
    if spec.axes.is_empty() || spec.axes.len() > MAX_AXES {
        return Err(FormatError::AxisCount(spec.axes.len() as u32));
    }
    if spec.params.len() != spec.table_id.param_names().len() {
        return Err(FormatError::BadHeader(
            "parameter count disagrees with the table's parameter names",
        ));
    }
    let version = spec.generator_version.as_bytes();
    if version.len() > 16 {
        return Err(FormatError::BadHeader(
            "generator version longer than 16 bytes",
        ));
    }
    let mut axes = [AxisHeader::UNUSED; MAX_AXES];
    axes[..spec.axes.len()].copy_from_slice(spec.axes);
    let mut params = [0.0; PARAM_COUNT];
    params[..spec.params.len()].copy_from_slice(spec.params);
    let mut generator_version = [0u8; 16];
    generator_version[..version.len()].copy_from_slice(version);
    let payload_offset = HEADER_SIZE.next_multiple_of(PAYLOAD_ALIGN);
    let channels = spec.channels as usize;
    if channels == 0 || !spec.grid.len().is_multiple_of(channels) {
        return Err(FormatError::BadHeader(
            "grid length is not a multiple of the channel count",
        ));
    }
    // The f32 values and (U16) the codes, in payload order.
    let (floats, codes): (Vec<f32>, Vec<u16>) = match spec.value_type {
        ValueType::F32 => (spec.grid.iter().chain(spec.aux).copied().collect(), vec![]),
        ValueType::U16 => {
            let nodes = spec.grid.len() / channels;
            let mut scales = Vec::with_capacity(2 * nodes + spec.aux.len());
            let mut codes = vec![0u16; spec.grid.len()];
            for (values, node_codes) in spec
                .grid
                .chunks_exact(channels)
                .zip(codes.chunks_exact_mut(channels))
            {
                scales.extend_from_slice(&quantise_node(values, node_codes));
            }
            scales.extend_from_slice(spec.aux);
            (scales, codes)
        }
    };
    let payload_len = floats.len() * 4 + codes.len() * 2;
    let mut header = Header {
        magic: MAGIC,
        format_version: FORMAT_VERSION,
        header_size: HEADER_SIZE as u32,
        table_id: spec.table_id,
        value_type: spec.value_type,
        channels: spec.channels,
        axis_count: spec.axes.len() as u32,
        axes,
        aux_count: spec.aux.len() as u32,
        kernel: spec.kernel,
        generator_version,
        params,
        payload_offset: payload_offset as u64,
        payload_len: payload_len as u64,
        checksum: 0,
    };
    validate_header(&header)?;
    let mut file = Vec::with_capacity(payload_offset + payload_len);
    file.extend_from_slice(header.as_bytes());
    file.resize(payload_offset, 0);
    for v in &floats {
        file.extend_from_slice(&v.to_le_bytes());
    }
    for q in &codes {
        file.extend_from_slice(&q.to_le_bytes());
    }
    header.checksum = checksum(&file);
    file[..HEADER_SIZE].copy_from_slice(header.as_bytes());
    // Read it back through the validating reader (from an aligned copy).
    let aligned = crate::tables::format::aligned_copy(&file);
    Table::from_bytes(aligned.bytes())?;
    Ok(file)
}

/// Writes `bytes` to `path` atomically: to a temporary file in the same
/// directory, flushed to disk, then renamed over `path`.
///
/// Table files are memory-mapped by readers, and a mapped file that is
/// truncated or rewritten in place makes every process that maps it crash
/// with SIGBUS (or silently see mixed contents). A rename replaces the
/// directory entry and leaves any old mapping on the old inode intact, so
/// never rewrite a table file in place: always go through this function.
pub fn write_atomic(path: &Path, bytes: &[u8]) -> std::io::Result<()> {
    let dir = path.parent().unwrap_or(Path::new("."));
    let name = path
        .file_name()
        .ok_or_else(|| std::io::Error::other("table path has no file name"))?;
    let mut tmp_name = std::ffi::OsString::from(".");
    tmp_name.push(name);
    tmp_name.push(format!(".{}.tmp", std::process::id()));
    let tmp = dir.join(tmp_name);
    let result = (|| {
        let mut file = std::fs::File::create(&tmp)?;
        file.write_all(bytes)?;
        file.sync_all()?;
        std::fs::rename(&tmp, path)
    })();
    if result.is_err() {
        let _ = std::fs::remove_file(&tmp);
    }
    result
}
