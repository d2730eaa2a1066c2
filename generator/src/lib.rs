//! The table generator of the two-scale reflectance model, and the f64
//! reference implementation every table is measured against.
//!
//! - [`quad`]: adaptive quadrature that reports convergence;
//! - [`reference`](mod@reference): the f64 reference of docs/model.md §2 (EPD, Smith Λ, K-correlation, …);
//! - [`tables`]: one module per table: build (parallel, deterministic) and verify;
//! - [`fit`]: deterministic least-squares fits of scaled lobes (the compact
//!   forms of the convolution, table T3);
//! - [`query`]: the batch CSV queries of docs/model.md §6;
//! - [`error`]: what a `generator` subcommand can fail with;
//! - [`plot`]: the pictures of `docs/img/` (`generator plot`);
//! - [`export`]: `generator export`, the tables as `.npy` or C headers;
//! - [`report`]: what `verify` prints and writes to `docs/accuracy.md`;
//! - [`build`], [`verify`](mod@verify), [`inspect`](mod@inspect): the
//!   bodies of `generator build`/`merge`/`spot-check`, `verify`, `inspect`;
//! - [`table_source`]: where they read tables (embedded, or a directory);
//! - [`rng`]: deterministic random points for verification.

pub mod analytic;
pub mod bspline;
pub mod build;
pub mod error;
pub mod export;
pub mod fit;
pub mod inspect;
pub mod materials;
pub mod plot;
pub mod quad;
pub mod query;
pub mod reference;
pub mod report;
pub mod rng;
pub mod sh;
pub mod table_source;
pub mod tables;
pub mod verify;
