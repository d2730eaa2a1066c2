//! T4 error against band limit L, for the README: relative RMS and p99 of
//! |f_SH − f| / max f (f = ρ cos θi cos θo) over 20 000 random pairs, for a
//! rough and a glossy Beckmann Cook–Torrance lobe (F = 1) and each band limit.
//!
//! `cargo run -p generator --release --example t4_study`

use generator::analytic::BeckmannCt;
use generator::sh::{IsotropicBrdf, default_quadrature, project};
use generator::tables::t4::verification_pairs;

fn main() {
    let pairs = verification_pairs(20_000, 11);
    for (name, alpha, bands) in [
        ("rough α = 0.35", 0.35, &[4usize, 8, 12, 16, 24, 32][..]),
        ("glossy α = 0.0598", 0.0598, &[8, 16, 32, 48, 64, 96][..]),
    ] {
        let brdf = BeckmannCt { alpha, eta: None };
        let exact: Vec<f64> = pairs
            .iter()
            .map(|&(i, o)| brdf.eval(i, o) * i[2] * o[2])
            .collect();
        let peak = exact.iter().fold(0.0f64, |m, v| m.max(*v));
        let norm: f64 = exact.iter().map(|v| v * v).sum::<f64>();
        for &l in bands {
            let projection = project(&brdf, l, default_quadrature(l), None);
            let mut errors = Vec::new();
            let mut sum2 = 0.0;
            for (k, &(i, o)) in pairs.iter().enumerate() {
                let approx = projection.eval(i, o);
                let e = approx * i[2] * o[2] - exact[k];
                sum2 += e * e;
                errors.push(e.abs() / peak);
            }
            errors.sort_by(f64::total_cmp);
            println!(
                "{name}, L = {l:3}: rel RMS of f {:.2e}, p99 |Δf|/max f {:.2e}, max {:.2e}",
                (sum2 / norm).sqrt(),
                errors[errors.len() * 99 / 100],
                errors[errors.len() - 1],
            );
        }
    }
}
