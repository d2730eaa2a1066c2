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

// The layers, bottom up (each imports only from the ones above it in this
// list; tests/layers.rs checks it): ground, tables, model, bakes, BRDFs,
// front doors.
mod bake;
pub mod brdf;
pub mod bxdf;
pub mod domain;
pub mod io;
pub mod material;
pub mod materials;
pub mod math;
pub mod model;
pub mod spectrum;
pub mod table_set;
pub mod tables;
#[cfg(test)]
mod test_rng;
pub mod validate;

pub use brdf::{Rgb, TwoScale};
pub use bxdf::{Bxdf, BxdfFlags, BxdfSample};
pub use domain::{Domain, Invalid, Shortest, Shortest32};
pub use math::Complex;
pub use model::kcorr::KCorrelation;
#[cfg(feature = "std")]
pub use table_set::{OwnedTableSet, TableStorage};
pub use table_set::{TableBytes, TableSet, TableSetError, UnknownMaterial};
pub use tables::albedo::AlbedoTable;
pub use tables::convolution::{ConvFitTable, ConvTable, Convolution};
pub use tables::diffuse_fresnel::DiffuseFresnelTable;
pub use tables::format::{AlignedBytes, FormatError, Table, TableId};
pub use tables::sh_brdf::ShBrdfTable;
pub use tables::sigma_ratio::SigmaRatioTable;
pub use tables::smith_g1::{SmithG1Table, SmithShape};
pub use validate::Named;
