//! The table generator of the two-scale reflectance model, and the f64
//! reference implementation every table is measured against.

pub mod quad;
pub mod reference;
