//! The fuzz harnesses (`fuzz/harness.rs`, `fuzz/parsers/*.rs`) on stable
//! Rust: every seed and every saved regression input of each target
//! (`fuzz/seeds/TARGET/`, `fuzz/regressions/TARGET/`: one file per fault a
//! fuzzer found), then deterministic random mutations of each table with
//! the checksum recomputed, so that the checks past the checksum and the
//! lookups on tables that still load are exercised without libFuzzer.

#[path = "../fuzz/harness.rs"]
mod harness;

// The parser harnesses, as the libFuzzer targets of the same names use them.
#[path = "../fuzz/parsers/capi_toml.rs"]
mod capi_toml;
#[path = "../fuzz/parsers/material_toml.rs"]
mod material_toml;
#[path = "../fuzz/parsers/merl_decode.rs"]
mod merl_decode;
#[path = "../fuzz/parsers/query_csv.rs"]
mod query_csv;

use generator::rng::SplitMix64;
use std::path::Path;

/// A harness: runs one input, true if the parser accepted it.
type Harness = fn(&[u8]) -> bool;

/// Every target: its name and its harness (what `fuzz/fuzz_targets/NAME.rs` runs).
const TARGETS: [(&str, Harness); 5] = [
    ("table_loader", harness::run),
    ("merl_decode", merl_decode::run),
    ("material_toml", material_toml::run),
    ("query_csv", query_csv::run),
    ("capi_toml", capi_toml::run),
];

/// Runs `run` on every file of `dir` (if it exists): (inputs, those the
/// harness accepted).
fn replay(dir: &Path, run: Harness) -> (usize, usize) {
    let Ok(entries) = std::fs::read_dir(dir) else {
        return (0, 0);
    };
    let (mut count, mut accepted) = (0, 0);
    for entry in entries {
        let path = entry.expect("entry").path();
        if path.extension().is_some_and(|e| e == "md") {
            continue;
        }
        let data = std::fs::read(&path).expect("fuzz input");
        let outcome = std::panic::catch_unwind(|| run(&data));
        assert!(outcome.is_ok(), "{} panics", path.display());
        count += 1;
        accepted += usize::from(outcome.unwrap_or(false));
    }
    (count, accepted)
}

#[test]
fn seeds_and_regressions_replay() {
    let fuzz = Path::new(env!("CARGO_MANIFEST_DIR")).join("fuzz");
    // A target's seeds hold inputs that its parser accepts and inputs that
    // it refuses (table_loader: 30 tables with flags, most of which load).
    for (name, run) in TARGETS {
        let (count, accepted) = replay(&fuzz.join("seeds").join(name), run);
        let least = if name == "table_loader" { 30 } else { 5 };
        assert!(count >= least, "{name}: {count} seeds");
        assert!(
            0 < accepted && accepted < count || name == "table_loader",
            "{name}: {accepted} of {count} accepted"
        );
        let target = fuzz.join("fuzz_targets").join(format!("{name}.rs"));
        assert!(target.is_file(), "{}", target.display());
        replay(&fuzz.join("regressions").join(name), run);
    }
    // Every target has a harness here.
    let targets = std::fs::read_dir(fuzz.join("fuzz_targets"))
        .expect("fuzz/fuzz_targets")
        .count();
    assert_eq!(targets, TARGETS.len());
}

#[test]
fn random_mutations_with_valid_checksums() {
    let mut rng = SplitMix64::new(13);
    let mut loaded = 0;
    for n in 0..400 {
        let table = (n % 6) as u8;
        // checksum recomputed; the set and a preset evaluated every 8th input;
        // header-only patches every 3rd; a truncation every 7th.
        let mut flags = 1u8;
        if n % 8 == 0 {
            flags |= 0x80;
        }
        if n % 3 == 0 {
            flags |= 4;
        }
        if n % 7 == 0 {
            flags |= 2 | (((n / 7) % 16) as u8) << 3;
        }
        let mut data = vec![table + 6 * (n / 6 % 5) as u8, flags];
        for _ in 0..1 + n % 4 {
            let word = rng.next_u64();
            data.extend_from_slice(&(word as u32).to_le_bytes());
            data.push(((word >> 32) as u8) | 1);
        }
        loaded += usize::from(harness::run(&data));
    }
    println!("{loaded} of 400 mutated tables loaded");
    // Most mutations keep a loadable table (a changed finite value) or are
    // caught; both outcomes must occur for the test to check anything.
    assert!(
        (40..=360).contains(&loaded),
        "{loaded} of 400 mutated tables loaded"
    );
}
