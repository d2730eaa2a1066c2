//! Helpers shared by the integration tests in `tests/` and the benchmarks in
//! `benches/`.
