//! The `f64` reference implementation of the models of `SPEC.md` §2.
//!
//! Every table the generator writes is measured against these functions, so
//! they favour accuracy and explicit error reporting over speed. Numerical
//! failures and invalid parameters are reported as
//! [`QuadError`](crate::quad::QuadError); nothing here panics on bad input.
//!
//! * [`epd`]: the Exponential Power Distribution NDF of (HP17 34–35), its
//!   sampling (HP17 49–50) and its Smith masking term Λ, G1 (HP17 36–38).

pub mod epd;
pub mod kcorr;
