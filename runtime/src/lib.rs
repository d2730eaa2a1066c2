//! `twoscale`: the lookup runtime of the Holzschuch–Pacanowski two-scale
//! reflectance model.
//!
//! The expensive parts of the model are precomputed by the `generator` crate
//! into self-describing table files; this crate reads them zero-copy and
//! interpolates them. It is `no_std` unless the `std` feature is enabled, never
//! allocates, and never panics on a lookup path.
#![cfg_attr(not(feature = "std"), no_std)]
#![forbid(unsafe_code)]
#![warn(missing_docs)]

pub mod format;
pub mod gamma;
pub mod interp;
pub mod math;

pub use format::{AlignedBytes, FormatError, Table, TableId};
