//! The table generator of the two-scale reflectance model.
//!
//! The f64 reference every table is measured against, and its numerical
//! tools, are the crate `twoscale_reference`; they are re-exported here under
//! their old paths ([`quad`], [`reference`](mod@reference), [`fit`],
//! [`bspline`], [`rng`]).
//!
//! - [`tables`]: one module per table: build (parallel, deterministic) and
//!   verify, and the registry of [`tables::TableKind`]s keyed by the
//!   runtime's table descriptors;
//! - [`query`]: the batch CSV queries of docs/model.md §6;
//! - [`error`]: what a `generator` subcommand can fail with;
//! - [`plot`]: the pictures of `docs/img/` (`generator plot`);
//! - [`export`]: `generator export`, the tables as `.npy` or C headers;
//! - [`report`]: what `verify` prints and writes to `docs/accuracy.md`;
//! - [`build`], [`verify`](mod@verify), [`inspect`](mod@inspect): the
//!   bodies of `generator build`/`merge`/`spot-check`, `verify`, `inspect`;
//! - [`table_source`]: where they read tables (embedded, or a directory).

pub use twoscale_reference::{bspline, fit, quad, reference, rng};

pub mod analytic;
pub mod brdf_accuracy;
pub mod build;
pub mod error;
pub mod export;
pub mod inspect;
pub mod materials;
pub mod plot;
pub mod query;
pub mod report;
pub mod sh;
pub mod spectral_accuracy;
pub mod table_source;
pub mod tables;
pub mod verify;
