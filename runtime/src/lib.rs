//! `twoscale`: the lookup runtime of the Holzschuch–Pacanowski two-scale
//! reflectance model.
//!
//! The expensive parts of the model are precomputed by the `generator` crate
//! into self-describing table files; this crate reads them zero-copy and
//! interpolates them. It is `no_std` unless the `std` feature is enabled, never
//! allocates, and never panics on a lookup path.
// Unit tests use std (Vec, format!); the library itself is no_std without the feature.
#![cfg_attr(not(any(feature = "std", test)), no_std)]
#![deny(unsafe_code)]
#![warn(missing_docs)]
// `!(x > 0.0)` is the guard that also catches NaN, used on purpose throughout.
#![allow(clippy::neg_cmp_op_on_partial_ord)]
// `x.max(lo).min(hi)` maps NaN to `lo`; `clamp` would propagate NaN.
#![allow(clippy::manual_clamp)]

pub mod albedo;
mod bake;
pub mod brdf;
pub mod bxdf;
pub mod colour;
pub mod conv;
pub mod desc;
pub mod epd;
pub mod format;
pub mod fresnel;
pub mod gamma;
mod halo;
pub mod hp15;
pub mod interp;
pub mod kcorr;
pub mod materials;
pub mod math;
pub mod merl;
#[cfg(feature = "std")]
pub mod mmap;
pub mod optical;
pub mod sh;
pub mod smith;
pub mod table_set;
#[cfg(test)]
mod test_rng;
pub mod validate;
mod visible;

pub use albedo::AlbedoTable;
pub use brdf::{Rgb, TwoScale};
pub use bxdf::{Bxdf, BxdfFlags, BxdfSample};
pub use conv::{ConvFitTable, ConvTable, Convolution};
pub use format::{AlignedBytes, FormatError, Table, TableId};
pub use fresnel::{Complex, DiffuseFresnelTable};
pub use kcorr::{KCorrelation, SigmaRatioTable};
pub use sh::ShBrdfTable;
pub use smith::{SmithG1Table, SmithShape};
#[cfg(feature = "std")]
pub use table_set::{OwnedTableSet, TableStorage};
pub use table_set::{TableBytes, TableSet, TableSetError, UnknownMaterial};
pub use validate::{Domain, Invalid, Named, Shortest, Shortest32};
