//! libFuzzer target of the MERL decoder (the input format is documented in
//! `fuzz/parsers/merl_decode.rs`).
#![no_main]

#[path = "../parsers/merl_decode.rs"]
mod harness;

libfuzzer_sys::fuzz_target!(|data: &[u8]| {
    harness::run(data);
});
