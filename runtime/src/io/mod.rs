//! Reading and writing what users hand the runtime: material files
//! ([`desc`], feature `toml` for the parser) and MERL BRDF files ([`merl`]).

pub mod desc;
pub mod merl;
