//! The table-loader fuzz harness (`fuzz/harness.rs`) on stable Rust: every
//! seed and every saved regression input (`fuzz/seeds/`, `fuzz/regressions/`:
//! one file per crash the fuzzer found), then deterministic random mutations
//! of each table with the checksum recomputed, so that the checks past the
//! checksum and the lookups on tables that still load are exercised without
//! libFuzzer.

#[path = "../fuzz/harness.rs"]
mod harness;

use generator::rng::SplitMix64;
use std::path::Path;

fn replay(dir: &str) -> usize {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join(dir);
    let mut count = 0;
    for entry in std::fs::read_dir(&dir).expect("fuzz input directory") {
        let path = entry.expect("entry").path();
        if path.extension().is_some_and(|e| e == "md") {
            continue;
        }
        let data = std::fs::read(&path).expect("fuzz input");
        let outcome = std::panic::catch_unwind(|| harness::run(&data));
        assert!(outcome.is_ok(), "{} panics", path.display());
        count += 1;
    }
    count
}

#[test]
fn seeds_and_regressions_replay() {
    assert!(replay("fuzz/seeds") >= 25, "the seed corpus is missing");
    replay("fuzz/regressions");
}

#[test]
fn random_mutations_with_valid_checksums() {
    let mut rng = SplitMix64::new(13);
    let mut loaded = 0;
    for n in 0..400 {
        let table = (n % 5) as u8;
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
        let mut data = vec![table + 5 * (n / 5 % 5) as u8, flags];
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
