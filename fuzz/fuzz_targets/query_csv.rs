//! libFuzzer target of `generator query`'s CSV rows (the input format
//! is documented in `fuzz/parsers/query_csv.rs`).
#![no_main]

#[path = "../parsers/query_csv.rs"]
mod harness;

libfuzzer_sys::fuzz_target!(|data: &[u8]| {
    harness::run(data);
});
