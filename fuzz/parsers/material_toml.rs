//! The material-file fuzz harness (`twoscale::io::desc::MaterialDesc::from_toml_str`,
//! what Rust, Python's `Material.from_toml_string`, C and the generator
//! read), shared by the libFuzzer target (`fuzz/fuzz_targets/material_toml.rs`)
//! and the stable-Rust replay (`tests/fuzz_regressions.rs`).
//!
//! The input is the file's text (invalid UTF-8 is refused before parsing,
//! as every front end refuses it). A file that reads must: write back to a
//! text that reads to the same description (`to_toml`), and build a model
//! (`RgbModel::boxed`, as Python and C build it) whose `eval`, `pdf` and
//! `sample` give finite values at a few directions.

use std::sync::LazyLock;
use twoscale::brdf::RgbModel;
use twoscale::io::desc::MaterialDesc;
use twoscale::{Bxdf, TableSet};

/// The embedded tables, validated once: validating them took 0.2 s of
/// each run of a file that reads under ASan.
static TABLES: LazyLock<TableSet<'static>> = LazyLock::new(TableSet::embedded);

/// Runs one input (module documentation); true if the text read.
pub fn run(data: &[u8]) -> bool {
    let Ok(text) = std::str::from_utf8(data) else {
        return false;
    };
    let Ok(owned) = MaterialDesc::from_toml_str(text) else {
        return false;
    };
    let desc = owned.get();
    let written = desc.to_toml();
    match MaterialDesc::from_toml_str(&written) {
        Ok(back) => assert_eq!(back.get(), desc, "{written}"),
        Err(e) => panic!("to_toml wrote a file that does not read: {e}\n{written}"),
    }
    let model = RgbModel::boxed(&TABLES.brdf_tables(), &desc);
    evaluate(&model);
    true
}

/// `model` at a few directions: finite values, a sample's pdf > 0.
pub fn evaluate(model: &impl Bxdf<Value = [f32; 3]>) {
    for (i, o) in [
        ([0.6, 0.1, 0.8], [-0.55, -0.05, 0.83]),
        ([0.0, 0.0, 1.0], [0.0, 0.0, 1.0]),
        ([1.0, 0.0, 1e-6], [-1.0, 0.0, 1e-6]),
    ] {
        let v = model.eval(i, o);
        assert!(v.iter().all(|x| x.is_finite() && *x >= 0.0), "eval {v:?}");
        let pdf = model.pdf(i, o);
        assert!(pdf.is_finite() && pdf >= 0.0, "pdf {pdf}");
        for u in [[0.3, 0.7, 0.2], [0.0, 0.0, 0.0], [0.999, 0.5, 0.999]] {
            if let Some(s) = model.sample(i, u) {
                assert!(s.pdf.is_finite() && s.pdf > 0.0, "sample pdf {}", s.pdf);
                assert!(
                    s.value.iter().all(|x| x.is_finite()),
                    "sample {:?}",
                    s.value
                );
            }
        }
    }
}
