//! The fuzz harness of `generator query`'s CSV rows
//! (`generator::query::run`, what the command runs on stdin), shared by the
//! libFuzzer target (`fuzz/fuzz_targets/query_csv.rs`) and the stable-Rust
//! replay (`tests/fuzz_regressions.rs`).
//!
//! Byte 0 picks the quantity (g1, sigma-ratio, fresnel, conv, brdf) and,
//! for brdf, the material (none, a conductor given by three (n, k), a
//! preset over the spectrum); bit 3 asks for `--clamp`. The rest is the
//! CSV text as bytes (invalid UTF-8 included), cut after 6 lines: a row
//! costs up to tens of ms (the f64 reference), and the header and the
//! rows' parsing are what is fuzzed. The run must end with an answer or an
//! error, never a panic; its output is the header and one line per
//! answered row, each with the header's columns and the outputs.

use generator::query::{self, Options};
use generator::table_source::TableSource;
use twoscale::io::desc::MaterialDesc;

/// A conductor by three (n, k), as the fit writes it.
const PAIRS: &str = "[material]\nbeta = 0.12\np = 1.4\neta = [[0.2, 3.9], [0.45, 2.5], [1.4, 1.9]]\n\
                     sigma_s = 0.03\nb = 2.5\nc = 2.2\nsigma_rel = \"symmetrised\"\n";

/// Runs one input (module documentation); true if the query ran.
pub fn run(data: &[u8]) -> bool {
    let Some((&selector, csv)) = data.split_first() else {
        return false;
    };
    let quantities = ["g1", "sigma-ratio", "fresnel", "conv", "brdf"];
    let quantity = quantities[usize::from(selector & 7) % quantities.len()];
    let material = match (quantity, (selector >> 4) % 3) {
        ("brdf", 1) => Some(MaterialDesc::from_toml_str(PAIRS).expect("a valid file")),
        ("brdf", 2) => {
            let spectral = twoscale::materials::spectral("nickel").expect("a preset");
            let options = twoscale::material::Options::default();
            let desc = MaterialDesc::spectral(spectral, options, None).expect("a preset validates");
            Some(desc.to_owned_desc())
        }
        _ => None,
    };
    let options = Options {
        clamp: selector & 8 != 0,
        material,
    };
    let cut = csv
        .iter()
        .enumerate()
        .filter(|(_, b)| **b == b'\n')
        .nth(5)
        .map_or(csv.len(), |(k, _)| k);
    let mut output = Vec::new();
    let outcome = query::run(
        quantity,
        &TableSource::Embedded,
        &options,
        &csv[..cut],
        &mut output,
        std::io::sink(),
    );
    let Ok(summary) = outcome else {
        return false;
    };
    let text = String::from_utf8(output).expect("the output is UTF-8");
    let mut lines = text.lines();
    let header = lines.next().expect("a header line");
    let columns = header.split(',').count();
    let mut answered = 0;
    for line in lines {
        assert_eq!(line.split(',').count(), columns, "{header}\n{line}");
        answered += 1;
    }
    assert_eq!(answered, summary.answered, "{text}");
    true
}
