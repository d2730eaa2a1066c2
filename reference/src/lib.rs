//! The f64 reference implementation of the two-scale reflectance model
//! (docs/model.md §2), which every table is measured against, and the
//! numerical tools it and the table builds share. It carries none of the
//! generator's CLI dependencies, so the Python extension, the studies and the
//! tests link it alone.
//!
//! - [`quad`]: adaptive quadrature that reports convergence;
//! - [`reference`](mod@reference): the f64 reference of docs/model.md §2 (EPD, Smith Λ, K-correlation, …);
//! - [`fit`]: deterministic least-squares fits of scaled lobes (the compact
//!   forms of the convolution, table T3);
//! - [`bspline`]: the cubic B-spline prefilter of the spline tables;
//! - [`rng`]: deterministic random points for verification.

pub mod bspline;
pub mod fit;
pub mod quad;
pub mod reference;
pub mod rng;
