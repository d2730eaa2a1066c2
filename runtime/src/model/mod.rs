//! The model's distributions, on top of the tables: the EPD microfacet NDF
//! with its Smith masking ([`epd`], T1), the K-correlation roughness
//! spectrum ([`kcorr`], T2) and the Fresnel and diffraction colour terms
//! ([`fresnel`]).

pub mod epd;
pub mod fresnel;
pub mod kcorr;
