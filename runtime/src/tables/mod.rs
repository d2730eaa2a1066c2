//! The tables: the file format ([`format`](mod@format)), its interpolation ([`interp`]),
//! loading (feature `std`: [`mmap`]) and one typed reader per table, named
//! as the generator's builder of the same table:
//!
//! | table | reader | quantity |
//! |---|---|---|
//! | T1 | [`smith_g1`] | Smith G1 of the EPD |
//! | T2 | [`sigma_ratio`] | σrel/σs of the K-correlation spectrum |
//! | T3 | [`convolution`] | the convolution C of the diffraction kernel with the EPD |
//! | T4 | [`sh_brdf`] | a material's BRDF as a spherical-harmonic matrix |
//! | T5 | [`diffuse_fresnel`] | F_dr,int(η) of the plastic base |
//! | T6 | [`albedo`] | the microfacet lobe's directional albedo |

pub mod albedo;
pub mod convolution;
pub mod diffuse_fresnel;
pub mod format;
pub mod interp;
#[cfg(feature = "std")]
pub mod mmap;
pub mod sh_brdf;
pub mod sigma_ratio;
pub mod smith_g1;
