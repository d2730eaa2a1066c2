//! Which parameter axes of T3b deserve Catmull–Rom instead of linear
//! interpolation: the committed T3 file, measured at random parameter points
//! (`t3::verification_points`, seed 99) against exact profiles on the SPEC
//! metric's rule, for every combination of cubic axes.
//!
//! ```text
//! cargo run --release -p generator --example t3_interp_study -- [profiles]
//! ```

use generator::reference::conv::{Params, ProfileRule, convolution_profile};
use generator::tables::t3;
use rayon::prelude::*;
use twoscale::conv::ConvTable;

fn main() {
    let profiles: usize = std::env::args()
        .nth(1)
        .and_then(|s| s.parse().ok())
        .unwrap_or(60);
    let bytes = std::fs::read(concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../tables/t3-convolution.tbl"
    ))
    .expect("tables/t3-convolution.tbl");
    let buf = twoscale::format::aligned_copy(&bytes);
    let base = ConvTable::from_bytes(buf.bytes()).expect("valid T3");
    let points = t3::verification_points(profiles, 99);
    let exact: Vec<(ProfileRule, Vec<f64>, f64)> = points
        .par_iter()
        .map(|&[u, c, beta, p]| {
            let params = Params::new(u, c, beta, p).unwrap();
            let rule = ProfileRule::with_order(ProfileRule::width_for(&params), 8);
            let values = convolution_profile(u, c, beta, p, &rule.nodes).unwrap();
            let c0 = convolution_profile(u, c, beta, p, &[0.0]).unwrap()[0];
            (rule, values, c0)
        })
        .collect();
    println!(
        "{profiles} profiles; cubic axes (u c β p): e_L2 median/p90/max, pointwise (C > 1e-3 C(0)) median/p95"
    );
    let masks: Vec<u32> = if std::env::var("T3_WORST").is_ok() {
        vec![15]
    } else {
        (0..16).collect()
    };
    for mask in masks {
        let cubic = [mask & 1 != 0, mask & 2 != 0, mask & 4 != 0, mask & 8 != 0];
        let table = base.with_cubic_axes(cubic);
        let mut el2 = Vec::new();
        let mut pointwise = Vec::new();
        for (pt, (rule, values, c0)) in points.iter().zip(&exact) {
            let (u, c, b, p) = (pt[0] as f32, pt[1] as f32, pt[2] as f32, pt[3] as f32);
            let (mut num, mut den) = (0.0, 0.0);
            for ((&t, &w), &e) in rule.nodes.iter().zip(&rule.weights).zip(values) {
                let a = f64::from(table.at_tan(t.tan(), u, c, b, p));
                num += w * (a - e) * (a - e);
                den += w * e * e;
                if e > 1e-3 * c0 {
                    pointwise.push(((a - e) / e).abs());
                    if std::env::var("T3_WORST").is_ok() && ((a - e) / e).abs() > 0.05 {
                        println!(
                            "  {pt:?} θ {t:.6} C/C0 {:.3e} rel {:.3}",
                            e / c0,
                            (a - e) / e
                        );
                    }
                }
            }
            el2.push((num / den).sqrt());
        }
        el2.sort_by(f64::total_cmp);
        pointwise.sort_by(f64::total_cmp);
        let q = |v: &[f64], f: f64| v[((v.len() - 1) as f64 * f).round() as usize];
        println!(
            "{cubic:?}: e_L2 {:.4} {:.4} {:.4}   pointwise {:.4} {:.4}",
            q(&el2, 0.5),
            q(&el2, 0.9),
            q(&el2, 1.0),
            q(&pointwise, 0.5),
            q(&pointwise, 0.95)
        );
    }
}
