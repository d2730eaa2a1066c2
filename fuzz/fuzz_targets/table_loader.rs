//! libFuzzer target over every table reader and `TableSet::from_bytes`
//! (the input format is documented in `fuzz/harness.rs`).
#![no_main]

#[path = "../harness.rs"]
mod harness;

libfuzzer_sys::fuzz_target!(|data: &[u8]| {
    harness::run(data);
});
