//! libFuzzer target of the C API's material-file readers (the input format
//! is documented in `fuzz/parsers/capi_toml.rs`).
#![no_main]

#[path = "../parsers/capi_toml.rs"]
mod harness;

libfuzzer_sys::fuzz_target!(|data: &[u8]| {
    harness::run(data);
});
