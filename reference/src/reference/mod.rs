//! The `f64` reference implementation of the models of docs/model.md §2.
//!
//! Every table the generator writes is measured against these functions, so
//! they favour accuracy and explicit error reporting over speed. Numerical
//! failures and invalid parameters are reported as
//! [`QuadError`](crate::quad::QuadError); nothing here panics on bad input.
//!
//! * [`albedo`]: the directional albedo `E(μ; β, p)` of the EPD microfacet
//!   lobe with F = 1 and its cosine-weighted mean `E_avg` (docs/model.md §2.10).
//! * [`brdf`]: the two-scale BRDF of a conductor (HP17 24-33) with exact
//!   Λ, σrel and C, and the exact-C adapter of the runtime's `Convolution` trait.
//! * [`epd`]: the Exponential Power Distribution NDF of (HP17 34–35), its
//!   sampling (HP17 49–50) and its Smith masking term Λ, G1 (HP17 36–38).
//! * [`kcorr`]: the K-correlation spectrum (HP17 16) and the renormalisation
//!   σrel/σs (HP17 17–19).
//! * [`conv`]: the normalised spherical convolution `C(θh; u, c, β, p)` of
//!   docs/model.md §2.5 (HP17 32–33, 61–64), by zonal harmonics and by direct 2-D
//!   quadrature.
//! * [`fresnel`]: the Fresnel reflectance of a complex index (HP17 3-4), the
//!   diffraction colour term Q of (HP17 10), and the diffuse Fresnel
//!   reflectances of a dielectric (docs/model.md §2.6).

pub mod albedo;
pub mod brdf;
pub mod conv;
pub mod epd;
pub mod fresnel;
pub mod kcorr;
