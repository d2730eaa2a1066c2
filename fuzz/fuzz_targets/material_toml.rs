//! libFuzzer target of material files (`twoscale::io::desc`) (the input format
//! is documented in `fuzz/parsers/material_toml.rs`).
#![no_main]

#[path = "../parsers/material_toml.rs"]
mod harness;

libfuzzer_sys::fuzz_target!(|data: &[u8]| {
    harness::run(data);
});
