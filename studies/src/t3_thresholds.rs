//! The paper's thresholds for its `s, g` form (HP17 §4.4), read from the
//! committed T3 (T3a): `g ≈ u` while the kernel is wider than the NDF
//! (`u β ≪ 1`), and `g` → a constant once it is narrower (`u β ≫ 1`)
//! (`docs/design/t3-forms.md`).

use crate::common::committed_t3;
use twoscale::ConvTable;

/// Prints `u β`, `g / u` and `g` along `u` for a few `(c, β, p)`.
pub fn run() {
    let buf = committed_t3();
    let table = ConvTable::from_bytes(buf.bytes()).expect("valid T3");
    let fit = table.fit();
    for (c, beta, p) in [
        (2.0f32, 0.002f32, 1.0f32),
        (2.0, 0.05, 1.0),
        (2.0, 0.5, 1.0),
        (5.0, 0.05, 2.0),
        (1.1, 0.05, 0.5),
    ] {
        println!("c = {c}, β = {beta}, p = {p}:   u β   g/u   g");
        for u in [
            0.1f32, 0.3, 1.0, 3.0, 10.0, 30.0, 100.0, 300.0, 1000.0, 3000.0,
        ] {
            let (_, g) = fit.parameters(u, c, beta, p);
            println!("  u = {u:<7} {:>9.3e} {:>7.3} {:>9.3}", u * beta, g / u, g);
        }
    }
}
