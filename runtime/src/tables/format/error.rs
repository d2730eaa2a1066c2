//! [`FormatError`]: what is wrong with a table file.

use super::FORMAT_VERSION;
use super::HEADER_SIZE;
use super::Kernel;
use super::MAGIC;
use super::MAX_AXES;
use super::PAYLOAD_ALIGN;
use super::TableId;
use super::ValueType;
use core::fmt;
/// What is wrong with a table file.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum FormatError {
    /// The buffer ends before the header or the payload does.
    Truncated {
        /// Bytes the header says the file has (or the header size).
        needed: u64,
        /// Bytes present.
        actual: u64,
    },
    /// Bytes follow the end of the payload.
    TrailingBytes {
        /// Bytes the header says the file has.
        expected: u64,
        /// Bytes present.
        actual: u64,
    },
    /// The file does not start with [`MAGIC`].
    WrongMagic {
        /// The first eight bytes.
        found: [u8; 8],
    },
    /// A format version this crate does not read.
    UnsupportedVersion {
        /// Version in the file.
        found: u32,
    },
    /// The header size field disagrees with this crate's header layout.
    HeaderSize {
        /// Size in the file.
        found: u32,
    },
    /// The buffer does not start on a 64-byte boundary.
    Misaligned {
        /// Address of the buffer modulo 64.
        address_mod_64: usize,
    },
    /// An unknown table id tag.
    UnknownTableId(u32),
    /// An unknown value type tag.
    UnknownValueType(u32),
    /// An unknown interpolation kernel tag.
    UnknownKernel(u32),
    /// An unknown axis mapping tag.
    UnknownMapping {
        /// Axis index.
        axis: usize,
        /// The tag.
        tag: u32,
    },
    /// Axis count outside 1..=4.
    AxisCount(u32),
    /// An axis whose fields are inconsistent (see the reason).
    BadAxis {
        /// Axis index.
        axis: usize,
        /// What is wrong.
        reason: &'static str,
    },
    /// Some other header field is invalid (see the reason).
    BadHeader(&'static str),
    /// `payload_len` disagrees with node counts × channels + aux values.
    PayloadLength {
        /// Bytes implied by the node counts, channels and aux count.
        expected: u64,
        /// `payload_len` in the header.
        found: u64,
    },
    /// The checksum does not match the contents.
    ChecksumMismatch {
        /// Checksum in the header.
        stored: u64,
        /// Checksum of the bytes.
        computed: u64,
    },
    /// A payload value is NaN or infinite.
    NonFinite {
        /// Index of the value in the payload.
        index: usize,
    },
    /// The file is valid but holds another table than the one asked for.
    WrongTable {
        /// The table asked for.
        expected: TableId,
        /// The table in the file.
        found: TableId,
    },
    /// The file is valid but its kernel is not the one the runtime uses for
    /// this table ([`TableDescriptor::kernel`](super::TableDescriptor::kernel)).
    WrongKernel {
        /// The table.
        table: TableId,
        /// The kernel in the file.
        found: Kernel,
    },
    /// The file is valid but its values are not stored as the runtime reads
    /// them for this table ([`TableDescriptor::value_type`](super::TableDescriptor::value_type)).
    WrongValueType {
        /// The table.
        table: TableId,
        /// The value type in the file.
        found: ValueType,
    },
    /// The file is valid but its shape is not the one this table kind needs.
    Shape(&'static str),
}

impl fmt::Display for FormatError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        use FormatError::*;
        match *self {
            Truncated { needed, actual } => {
                write!(f, "truncated table file: {actual} bytes, needs {needed}")
            }
            TrailingBytes { expected, actual } => write!(
                f,
                "table file has {actual} bytes, but its header describes {expected}"
            ),
            WrongMagic { found } => write!(
                f,
                "not a twoscale table file: starts with {found:?}, expected {MAGIC:?}"
            ),
            UnsupportedVersion { found } => write!(
                f,
                "table format version {found} is not supported (this reader knows version {FORMAT_VERSION})"
            ),
            HeaderSize { found } => {
                write!(f, "header size field is {found}, expected {HEADER_SIZE}")
            }
            Misaligned { address_mod_64 } => write!(
                f,
                "table bytes must start on a {PAYLOAD_ALIGN}-byte boundary (address mod 64 = {address_mod_64}); use twoscale::AlignedBytes"
            ),
            UnknownTableId(tag) => write!(f, "unknown table id {tag}"),
            UnknownValueType(tag) => write!(f, "unknown value type {tag}"),
            UnknownKernel(tag) => write!(f, "unknown interpolation kernel {tag}"),
            UnknownMapping { axis, tag } => write!(f, "axis {axis}: unknown mapping {tag}"),
            AxisCount(n) => write!(f, "axis count {n} is outside 1..={MAX_AXES}"),
            BadAxis { axis, reason } => write!(f, "axis {axis}: {reason}"),
            BadHeader(reason) => write!(f, "invalid header: {reason}"),
            PayloadLength { expected, found } => write!(
                f,
                "payload length {found} bytes disagrees with the node counts, channels and aux count ({expected} bytes)"
            ),
            ChecksumMismatch { stored, computed } => write!(
                f,
                "checksum mismatch: header says {stored:#018x}, contents give {computed:#018x}"
            ),
            NonFinite { index } => write!(f, "payload value {index} is not finite"),
            WrongTable { expected, found } => write!(
                f,
                "expected table {}, found {}",
                expected.name(),
                found.name()
            ),
            WrongKernel { table, found } => write!(
                f,
                "{} is interpolated with kernel {:?}, the file says {found:?}; rebuild it with this generator",
                table.name(),
                table.descriptor().kernel
            ),
            WrongValueType { table, found } => write!(
                f,
                "{} is stored as {:?}, the file holds {found:?}; rebuild it with this generator",
                table.name(),
                table.descriptor().value_type
            ),
            Shape(reason) => write!(f, "unexpected table shape: {reason}"),
        }
    }
}

#[cfg(feature = "std")]
impl std::error::Error for FormatError {}
