//! The table file format: defined here, once, and used by the generator to write.
//!
//! A table file is a fixed-size [`Header`] followed by a 64-byte-aligned payload
//! of little-endian values. With [`ValueType::F32`] (every table but T3):
//!
//! ```text
//! offset 0                         Header (HEADER_SIZE bytes, #[repr(C)], read in place)
//! offset HEADER_SIZE .. 64k        zero padding
//! offset payload_offset            grid values (f32), row-major (last axis fastest), channels innermost
//!                                  then `aux_count` auxiliary f32 values (meaning fixed per table id)
//! end = payload_offset + payload_len   (nothing may follow)
//! ```
//!
//! With [`ValueType::U16`] (per-node quantised, T3), the payload is the nodes'
//! `(offset, step)` f32 pairs, then the aux f32 values, then the grid's u16
//! codes (row-major, channels innermost); see [`Quantised`]. Both sections
//! are viewed in place (`&[f32]`, `&[u16]`).
//!
//! Every field is validated by [`Table::from_bytes`]; any malformed input returns a
//! [`FormatError`] that says what is wrong, and no input can make it panic.
//! The checksum ([`checksum`], FNV-1a 64) covers every byte of the file except
//! the checksum field itself, so a flipped bit in the header or in the padding is
//! caught, not only one in the payload.
//!
//! Byte order: the format is little-endian and the crate reads it in place, so
//! the crate refuses to compile for big-endian targets (every renderer target we
//! know of — x86-64, AArch64, wasm32 — is little-endian).

use core::mem::size_of;

#[cfg(target_endian = "big")]
compile_error!(
    "twoscale table files are little-endian and read in place; big-endian targets are not supported"
);

/// The eight bytes every table file starts with.
pub const MAGIC: [u8; 8] = *b"TWOSCALE";
/// The format version this crate reads and writes.
///
/// * 1: eight generation parameters.
/// * 2: sixteen (T3's normalised angle gained its horizon and edge terms;
///   four slots spare).
/// * 3: T3's thirteenth parameter, the edge term's `(p′/p)^m` fade, is set
///   (`m = 2`); a format-2 reader would ignore it and misread T3. Older
///   versions are refused: rebuild them.
pub const FORMAT_VERSION: u32 = 3;
/// The largest number of axes a table may have (T3 is four-dimensional).
pub const MAX_AXES: usize = 4;
/// Number of table-specific generation parameters in the header.
pub const PARAM_COUNT: usize = 16;
/// Alignment of the payload, and of the start of the file in memory.
pub const PAYLOAD_ALIGN: usize = 64;
/// Size of [`Header`] in bytes.
pub const HEADER_SIZE: usize = size_of::<Header>();

mod descriptor;
mod error;
mod header;
mod params;
mod table;
#[cfg(feature = "std")]
pub mod write;

pub use descriptor::*;
pub use error::*;
pub use header::*;
pub use params::*;
pub use table::*;

#[cfg(test)]
mod tests;
