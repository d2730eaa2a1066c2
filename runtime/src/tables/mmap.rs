//! Loading table files from disk through a read-only memory map (`std` only).
//!
//! The map is read-only and the file is never modified by this crate. Table
//! files must be treated as immutable: if another process truncates or rewrites
//! a mapped file in place, reading the map raises SIGBUS (or shows mixed
//! contents). The generator therefore always writes a new file under a
//! temporary name and renames it over the old one
//! ([`crate::tables::format::write::write_atomic`]), which leaves existing maps intact.

use std::fs::File;
use std::path::Path;

/// A table file mapped read-only into memory. The map is page-aligned, which
/// satisfies the 64-byte alignment that [`crate::Table::from_bytes`] requires.
#[derive(Debug)]
pub struct MappedFile {
    map: memmap2::Mmap,
}

impl MappedFile {
    /// Maps the file at `path` read-only. Validation happens when the bytes
    /// are given to [`crate::Table::from_bytes`] or a typed table constructor.
    pub fn open(path: impl AsRef<Path>) -> std::io::Result<MappedFile> {
        let file = File::open(path.as_ref())?;
        // SAFETY: the map is read-only, and table files are immutable by
        // contract (written to a temporary name, then renamed; see the module
        // documentation): nothing modifies the mapped bytes while we hold them.
        #[allow(unsafe_code)]
        let map = unsafe { memmap2::Mmap::map(&file)? };
        Ok(MappedFile { map })
    }

    /// The mapped bytes.
    pub fn bytes(&self) -> &[u8] {
        &self.map
    }
}
