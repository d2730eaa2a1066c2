//! The `f64` reference implementation of the models of `SPEC.md` §2.
//!
//! * [`conv`]: the normalised spherical convolution `C(θh; u, c, β, p)` of
//!   SPEC §2.5 (HP17 32–33, 61–64), by zonal harmonics and by direct 2-D
//!   quadrature.

pub mod conv;
