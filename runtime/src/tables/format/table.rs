//! A validated table file viewed in place ([`Table`]), its checksum, and
//! aligned storage for embedded and copied files.

use super::AxisHeader;
use super::FORMAT_VERSION;
use super::FormatError;
use super::HEADER_SIZE;
use super::Header;
use super::Kernel;
use super::MAGIC;
use super::MAX_AXES;
use super::Mapping;
use super::PARAM_COUNT;
use super::PAYLOAD_ALIGN;
use super::Quantised;
use super::TableId;
use super::ValueType;
use super::header::CHECKSUM_OFFSET;
use core::mem::offset_of;
use zerocopy::{FromBytes, TryFromBytes};
#[cfg(feature = "std")]
use zerocopy::{Immutable, IntoBytes, KnownLayout};
/// FNV-1a 64 of `bytes`, continuing from `state` (start with [`FNV_OFFSET`]).
pub const fn fnv1a(mut state: u64, bytes: &[u8]) -> u64 {
    let mut i = 0;
    while i < bytes.len() {
        state ^= bytes[i] as u64;
        state = state.wrapping_mul(0x0000_0100_0000_01b3);
        i += 1;
    }
    state
}

/// FNV-1a 64 offset basis.
pub const FNV_OFFSET: u64 = 0xcbf2_9ce4_8422_2325;

/// The checksum of a whole file image: FNV-1a 64 of every byte except the eight
/// bytes of [`Header::checksum`]. `file.len()` must be at least [`HEADER_SIZE`].
pub fn checksum(file: &[u8]) -> u64 {
    let (before, rest) = file.split_at(CHECKSUM_OFFSET.min(file.len()));
    let after = rest.get(8..).unwrap_or(&[]);
    fnv1a(fnv1a(FNV_OFFSET, before), after)
}

/// Bytes with 64-byte alignment, for embedding a table with `include_bytes!`:
///
/// ```ignore
/// static G1: &twoscale::AlignedBytes<[u8]> =
///     &twoscale::AlignedBytes(*include_bytes!("../tables/t1-smith-g1.tbl"));
/// ```
///
/// (the [`include_table!`](crate::include_table) macro writes exactly this).
/// `include_bytes!` alone only guarantees 1-byte alignment, and a table must be
/// viewable in place as `&[f32]`.
#[repr(C, align(64))]
pub struct AlignedBytes<B: ?Sized>(pub B);

impl<B: AsRef<[u8]> + ?Sized> AlignedBytes<B> {
    /// The wrapped bytes.
    pub fn bytes(&self) -> &[u8] {
        self.0.as_ref()
    }
}

/// Embeds a table file in the binary with the 64-byte alignment it needs, and
/// evaluates to a `&'static [u8]` ready for `Table::from_bytes` or a typed table.
///
/// ```ignore
/// let bytes: &'static [u8] = twoscale::include_table!("../tables/t1-smith-g1.tbl");
/// ```
#[macro_export]
macro_rules! include_table {
    ($path:expr) => {{
        static TABLE: &$crate::AlignedBytes<[u8]> = &$crate::AlignedBytes(*include_bytes!($path));
        &TABLE.0
    }};
}

/// A validated table file viewed in place: its header, grid and aux values.
#[derive(Clone, Copy, Debug)]
pub struct Table<'a> {
    header: &'a Header,
    grid: &'a [f32],
    aux: &'a [f32],
    quantised: Option<Quantised<'a>>,
}

impl<'a> Table<'a> {
    /// Validates `bytes` as a table file and views it in place. Checks, in order:
    /// header size, alignment, magic, version, header size, enum tags, axes, payload
    /// offset and length, trailing bytes, checksum, and that every value is finite.
    pub fn from_bytes(bytes: &'a [u8]) -> Result<Self, FormatError> {
        let actual = bytes.len() as u64;
        let head = bytes.get(..HEADER_SIZE).ok_or(FormatError::Truncated {
            needed: HEADER_SIZE as u64,
            actual,
        })?;
        let address_mod_64 = bytes.as_ptr() as usize % PAYLOAD_ALIGN;
        if address_mod_64 != 0 {
            return Err(FormatError::Misaligned { address_mod_64 });
        }
        if head[..8] != MAGIC {
            let mut found = [0; 8];
            found.copy_from_slice(&head[..8]);
            return Err(FormatError::WrongMagic { found });
        }
        let version = read_u32(head, offset_of!(Header, format_version));
        if version != FORMAT_VERSION {
            return Err(FormatError::UnsupportedVersion { found: version });
        }
        let header_size = read_u32(head, offset_of!(Header, header_size));
        if header_size as usize != HEADER_SIZE {
            return Err(FormatError::HeaderSize { found: header_size });
        }
        let header = Header::try_ref_from_bytes(head).map_err(|_| diagnose_tags(head))?;
        validate_header(header)?;

        let offset = header.payload_offset;
        let end = offset
            .checked_add(header.payload_len)
            .ok_or(FormatError::BadHeader("payload offset + length overflows"))?;
        if end > actual {
            return Err(FormatError::Truncated {
                needed: end,
                actual,
            });
        }
        if end < actual {
            return Err(FormatError::TrailingBytes {
                expected: end,
                actual,
            });
        }
        let computed = checksum(bytes);
        if computed != header.checksum {
            return Err(FormatError::ChecksumMismatch {
                stored: header.checksum,
                computed,
            });
        }
        // Bounds and alignment were checked above, so these cannot fail; map the
        // impossible case to an error rather than panic.
        let payload = bytes
            .get(offset as usize..end as usize)
            .ok_or(FormatError::BadHeader("payload out of bounds"))?;
        // The f32 part: everything (F32), or the scales and aux (U16).
        let (floats, codes) = match header.value_type {
            ValueType::F32 => (payload, &[][..]),
            ValueType::U16 => {
                let nodes = header.grid_values().unwrap_or(0) as usize;
                let float_bytes = (2 * nodes + header.aux_count as usize) * 4;
                payload
                    .split_at_checked(float_bytes)
                    .ok_or(FormatError::BadHeader("payload shorter than its scales"))?
            }
        };
        let values = <[f32]>::ref_from_bytes(floats)
            .map_err(|_| FormatError::BadHeader("payload is not a whole number of aligned f32"))?;
        if let Some(index) = values.iter().position(|v| !v.is_finite()) {
            return Err(FormatError::NonFinite { index });
        }
        let split = values.len() - header.aux_count as usize;
        let (head_values, aux) = values.split_at(split);
        let (grid, quantised) = match header.value_type {
            ValueType::F32 => (head_values, None),
            ValueType::U16 => {
                // Every decoded value must be finite too, like an f32 table's.
                if head_values
                    .chunks_exact(2)
                    .any(|pair| !(pair[1] >= 0.0 && (pair[0] + 65535.0 * pair[1]).is_finite()))
                {
                    return Err(FormatError::BadHeader(
                        "a quantisation step is negative or decodes beyond f32",
                    ));
                }
                let codes = <[u16]>::ref_from_bytes(codes)
                    .map_err(|_| FormatError::BadHeader("codes are not whole aligned u16"))?;
                let quantised = Quantised {
                    scales: head_values,
                    codes,
                    channels: header.channels as usize,
                };
                (&[][..], Some(quantised))
            }
        };
        Ok(Table {
            header,
            grid,
            aux,
            quantised,
        })
    }

    /// Like [`Table::from_bytes`], and also checks the table id.
    pub fn from_bytes_expecting(bytes: &'a [u8], expected: TableId) -> Result<Self, FormatError> {
        Self::from_bytes(bytes)?.expecting(expected)
    }

    /// The table itself if it holds `expected`, else [`FormatError::WrongTable`].
    /// Also checks that the file's kernel and value type are the ones its
    /// [`TableDescriptor`](super::TableDescriptor) says the runtime uses.
    pub fn expecting(self, expected: TableId) -> Result<Self, FormatError> {
        if self.header.table_id != expected {
            return Err(FormatError::WrongTable {
                expected,
                found: self.header.table_id,
            });
        }
        let descriptor = expected.descriptor();
        if self.header.kernel != descriptor.kernel {
            return Err(FormatError::WrongKernel {
                table: expected,
                found: self.header.kernel,
            });
        }
        if self.header.value_type != descriptor.value_type {
            return Err(FormatError::WrongValueType {
                table: expected,
                found: self.header.value_type,
            });
        }
        Ok(self)
    }

    /// The header.
    pub fn header(&self) -> &'a Header {
        self.header
    }

    /// The grid values of a [`ValueType::F32`] table, row-major, channels
    /// innermost (empty for a [`ValueType::U16`] table: see
    /// [`Table::quantised`]).
    pub fn grid(&self) -> &'a [f32] {
        self.grid
    }

    /// The grid of a [`ValueType::U16`] table (`None` for f32 tables).
    pub fn quantised(&self) -> Option<Quantised<'a>> {
        self.quantised
    }

    /// The auxiliary values (meaning fixed per table id).
    pub fn aux(&self) -> &'a [f32] {
        self.aux
    }
}

fn read_u32(head: &[u8], offset: usize) -> u32 {
    let mut word = [0u8; 4];
    if let Some(src) = head.get(offset..offset + 4) {
        word.copy_from_slice(src);
    }
    u32::from_le_bytes(word)
}

/// zerocopy rejected the header: find which enum tag is invalid.
fn diagnose_tags(head: &[u8]) -> FormatError {
    let table_tag = read_u32(head, offset_of!(Header, table_id));
    if TableId::from_tag(table_tag).is_none() {
        return FormatError::UnknownTableId(table_tag);
    }
    let value_tag = read_u32(head, offset_of!(Header, value_type));
    if ValueType::from_tag(value_tag).is_none() {
        return FormatError::UnknownValueType(value_tag);
    }
    let kernel_tag = read_u32(head, offset_of!(Header, kernel));
    if Kernel::from_tag(kernel_tag).is_none() {
        return FormatError::UnknownKernel(kernel_tag);
    }
    for axis in 0..MAX_AXES {
        let at = offset_of!(Header, axes)
            + axis * size_of::<AxisHeader>()
            + offset_of!(AxisHeader, mapping);
        let tag = read_u32(head, at);
        if Mapping::from_tag(tag).is_none() {
            return FormatError::UnknownMapping { axis, tag };
        }
    }
    FormatError::BadHeader("header rejected by layout validation")
}

/// Checks the fields of a header whose tags are already known to be valid.
pub fn validate_header(header: &Header) -> Result<(), FormatError> {
    let count = header.axis_count;
    if count == 0 || count as usize > MAX_AXES {
        return Err(FormatError::AxisCount(count));
    }
    for (axis, a) in header.axes.iter().enumerate() {
        if axis >= count as usize {
            if *a != AxisHeader::UNUSED {
                return Err(FormatError::BadAxis {
                    axis,
                    reason: "unused axis slot is not zeroed",
                });
            }
            continue;
        }
        validate_axis(axis, a)?;
    }
    if header.channels == 0 {
        return Err(FormatError::BadHeader("channel count is zero"));
    }
    if header.params.iter().any(|p| !p.is_finite()) {
        return Err(FormatError::BadHeader(
            "a generation parameter is not finite",
        ));
    }
    let names = header.table_id.param_names().len();
    if header.params[names.min(PARAM_COUNT)..]
        .iter()
        .any(|&p| p != 0.0)
    {
        return Err(FormatError::BadHeader(
            "an unnamed generation parameter is not zero",
        ));
    }
    if !header.generator_version.is_ascii() {
        return Err(FormatError::BadHeader("generator version is not ASCII"));
    }
    if !header.payload_offset.is_multiple_of(PAYLOAD_ALIGN as u64)
        || header.payload_offset < HEADER_SIZE as u64
    {
        return Err(FormatError::BadHeader(
            "payload offset is not a multiple of 64 past the header",
        ));
    }
    let expected = payload_bytes(header).ok_or(FormatError::BadHeader("node counts overflow"))?;
    if expected != header.payload_len {
        return Err(FormatError::PayloadLength {
            expected,
            found: header.payload_len,
        });
    }
    Ok(())
}

/// Payload bytes implied by the node counts, channels, aux count and value
/// type (`None` on overflow).
fn payload_bytes(header: &Header) -> Option<u64> {
    let nodes = header.grid_values()?;
    let values = nodes.checked_mul(u64::from(header.channels))?;
    let aux = u64::from(header.aux_count);
    match header.value_type {
        ValueType::F32 => values.checked_add(aux)?.checked_mul(4),
        ValueType::U16 => nodes
            .checked_mul(2)?
            .checked_add(aux)?
            .checked_mul(4)?
            .checked_add(values.checked_mul(2)?),
    }
}

fn validate_axis(axis: usize, a: &AxisHeader) -> Result<(), FormatError> {
    let bad = |reason| Err(FormatError::BadAxis { axis, reason });
    if a.nodes < 2 {
        return bad("fewer than 2 nodes");
    }
    if !(a.lo.is_finite() && a.hi.is_finite() && a.param.is_finite() && a.param2.is_finite()) {
        return bad("non-finite domain or parameter");
    }
    if a.lo >= a.hi {
        return bad("domain is empty (lo >= hi)");
    }
    if a.mapping != Mapping::LogOffset && a.param2 != 0.0 {
        return bad("only the log-offset mapping takes a second parameter");
    }
    match a.mapping {
        Mapping::Uniform if a.param != 0.0 => bad("uniform mapping takes no parameter"),
        Mapping::Log if a.param != 0.0 => bad("log mapping takes no parameter"),
        Mapping::Log if a.lo <= 0.0 => bad("log mapping needs lo > 0"),
        Mapping::LogOffset if a.lo + a.param <= 0.0 => {
            bad("log-offset mapping needs lo + param > 0")
        }
        Mapping::LogOffset if a.param2 < 0.0 => bad("log-offset mapping needs param2 >= 0"),
        Mapping::Power if a.param == 0.0 => bad("power mapping needs a non-zero exponent"),
        Mapping::Power if a.lo <= 0.0 => bad("power mapping needs lo > 0"),
        _ => Ok(()),
    }
}

/// Writing table files (used by the generator).
/// A 64-byte-aligned heap copy of `bytes` (for tests and for reading a file
/// into memory instead of mapping it).
#[cfg(feature = "std")]
pub fn aligned_copy(bytes: &[u8]) -> AlignedBuf {
    let mut blocks = vec![Block([0; 64]); bytes.len().div_ceil(64)];
    for (block, chunk) in blocks.iter_mut().zip(bytes.chunks(64)) {
        block.0[..chunk.len()].copy_from_slice(chunk);
    }
    AlignedBuf {
        blocks,
        len: bytes.len(),
    }
}

#[cfg(feature = "std")]
#[derive(Clone, Copy, FromBytes, IntoBytes, KnownLayout, Immutable)]
#[repr(C, align(64))]
struct Block([u8; 64]);

/// An owned, 64-byte-aligned byte buffer (see [`aligned_copy`]).
#[cfg(feature = "std")]
#[derive(Clone)]
pub struct AlignedBuf {
    blocks: Vec<Block>,
    len: usize,
}

#[cfg(feature = "std")]
impl AlignedBuf {
    /// The bytes.
    pub fn bytes(&self) -> &[u8] {
        &self.blocks.as_bytes()[..self.len]
    }

    /// The bytes, mutably (for corruption tests).
    pub fn bytes_mut(&mut self) -> &mut [u8] {
        let len = self.len;
        &mut self.blocks.as_mut_bytes()[..len]
    }
}
