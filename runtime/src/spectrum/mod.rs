//! The spectrum: measured optical constants n(λ), k(λ) ([`optical`]) and the
//! CIE colour matching that turns a spectrum into linear sRGB ([`colour`]).

pub mod colour;
pub mod optical;
