//! Helpers shared by the integration tests in `tests/` and the benchmarks in
//! `benches/`: the χ² goodness-of-fit test, and locating the table files.

use std::path::PathBuf;

pub mod brdf;
pub mod cost;

// The README's code examples run as doctests of this crate.
#[doc = include_str!("../../README.md")]
mod readme {}

/// The workspace's committed table directory.
pub fn tables_dir() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("tables")
}

/// Reads a committed table file into a 64-byte-aligned buffer (for T4, which
/// has one file per material, the rough gold's).
pub fn read_table(id: twoscale::TableId) -> twoscale::tables::format::AlignedBuf {
    let name = match id {
        twoscale::TableId::ShBrdf => "t4-gold-rough.tbl".to_string(),
        _ => generator::tables::file_name(id),
    };
    let path = tables_dir().join(name);
    let bytes = std::fs::read(&path).unwrap_or_else(|e| {
        panic!(
            "{}: {e} (build it with `cargo run -p generator --release`)",
            path.display()
        )
    });
    twoscale::tables::format::aligned_copy(&bytes)
}

/// Outcome of a χ² goodness-of-fit test.
#[derive(Clone, Debug)]
pub struct ChiSquare {
    /// The statistic Σ (O − E)² / E over the pooled cells.
    pub statistic: f64,
    /// Degrees of freedom (pooled cells − 1).
    pub dof: usize,
    /// P(χ²_dof ≥ statistic).
    pub p_value: f64,
}

/// χ² test of observed counts against expected counts (same total), after
/// pooling: cells are taken in order and merged until each pooled cell expects
/// at least `min_expected` events (a trailing remainder joins the last cell).
/// Observed counts in cells that expect nothing make the test fail outright
/// (p-value 0): the sampler produced something of zero density.
pub fn chi_square(observed: &[f64], expected: &[f64], min_expected: f64) -> ChiSquare {
    assert_eq!(observed.len(), expected.len());
    let mut pooled: Vec<(f64, f64)> = Vec::new();
    let (mut o_acc, mut e_acc) = (0.0, 0.0);
    let mut impossible = 0.0;
    for (&o, &e) in observed.iter().zip(expected) {
        if e <= 0.0 {
            impossible += o;
            continue;
        }
        o_acc += o;
        e_acc += e;
        if e_acc >= min_expected {
            pooled.push((o_acc, e_acc));
            o_acc = 0.0;
            e_acc = 0.0;
        }
    }
    if e_acc > 0.0 || o_acc > 0.0 {
        match pooled.last_mut() {
            Some(last) => {
                last.0 += o_acc;
                last.1 += e_acc;
            }
            None => pooled.push((o_acc, e_acc)),
        }
    }
    let statistic: f64 = pooled.iter().map(|(o, e)| (o - e) * (o - e) / e).sum();
    let dof = pooled.len().saturating_sub(1).max(1);
    let p_value = if impossible > 0.0 {
        0.0
    } else {
        twoscale::math::gamma::gamma_q(dof as f64 / 2.0, statistic / 2.0)
    };
    ChiSquare {
        statistic,
        dof,
        p_value,
    }
}

/// Šidák-corrected per-test significance for `tests` tests at family-wise `alpha`.
pub fn sidak(alpha: f64, tests: usize) -> f64 {
    1.0 - (1.0 - alpha).powf(1.0 / tests as f64)
}
