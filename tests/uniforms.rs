//! The renderer-facing samplers' contract for uniforms outside [0, 1)
//! (issue 47; `Bxdf::sample`'s documentation): each component is clamped
//! into [0, 1) (below 0 reads 0, 1 and above read the largest `f32` below
//! 1, NaN reads 0), so a sample with such `u` is the sample at the clamped
//! `u`, bit for bit, in every model. (The C API and Python refuse them.)

use twoscale::brdf::Spectral;
use twoscale::brdf::hp15::{Energy, Hp15, Hp15Params};
use twoscale::material::Options;
use twoscale::{Bxdf, ShBrdfTable, TableSet};

/// `x` clamped as the contract says.
fn clamped(x: f32) -> f32 {
    if x.is_nan() {
        0.0
    } else {
        x.clamp(0.0, 1.0f32.next_down())
    }
}

const BAD: [f32; 7] = [
    -0.25,
    -f32::INFINITY,
    1.0,
    1.5,
    f32::INFINITY,
    f32::NAN,
    -0.0,
];
const GOOD: [f32; 4] = [0.0, 0.3, 0.71, 0.999];

/// Every `u` with at least one component of [`BAD`] (and the others from
/// [`GOOD`]), with the clamped `u`.
fn cases() -> Vec<([f32; 3], [f32; 3])> {
    let mut out = Vec::new();
    for &bad in &BAD {
        for &good in &GOOD {
            for k in 0..3 {
                let mut u = [good, 0.5, 0.25];
                u[k] = bad;
                out.push((u, u.map(clamped)));
            }
        }
    }
    out
}

/// `sample(i, u)` equals `sample(i, clamp(u))` for every case.
fn check<T: PartialEq + std::fmt::Debug>(what: &str, sample: impl Fn([f32; 3], [f32; 3]) -> T) {
    let mut sampled = 0;
    for i in [[0.5f32, 0.0, 0.866], [0.1, 0.2, 0.97], [0.95, 0.1, 0.3]] {
        for (u, c) in cases() {
            let (got, want) = (sample(i, u), sample(i, c));
            assert_eq!(
                format!("{got:?}"),
                format!("{want:?}"),
                "{what}: i = {i:?}, u = {u:?}"
            );
            sampled += 1;
        }
    }
    assert!(sampled > 200);
}

#[test]
fn uniforms_outside_the_unit_interval_are_clamped_into_it() {
    let set = TableSet::embedded();
    let rgb = set
        .material_at_paper_wavelengths("gold-hp17-geometry")
        .expect("preset");
    check("Rgb", |i, u| Bxdf::sample(&rgb, i, u));
    check("TwoScale", |i, u| Bxdf::sample(&rgb.channels[1], i, u));
    let integrated = set.material("gold-hp17-geometry").expect("preset");
    check("IntegratedRgb", |i, u| Bxdf::sample(&integrated, i, u));
    let marble = set.material("marble").expect("preset");
    check("IntegratedRgb (marble)", |i, u| Bxdf::sample(&marble, i, u));
    let spectral = twoscale::materials::spectral("nickel").expect("preset");
    let spectral = Spectral::boxed(&set.brdf_tables(), &spectral, Options::default());
    check("Spectral", |i, u| {
        spectral.sample(i, u, 0.55).map(|s| (s.o, s.pdf, s.value))
    });
    let params = Hp15Params {
        beta: 0.2,
        p: 1.5,
        a: 1.5,
        kd: 0.2,
        ks: 0.6,
        kw: 0.2,
        f0: 0.04,
    };
    let hp15 = Hp15::new(&set.smith, params, 0.55, Energy::Exact);
    check("Hp15", |i, u| Bxdf::sample(&hp15, i, u));
    let t4 = suite::read_table(twoscale::TableId::ShBrdf);
    let sh = ShBrdfTable::from_bytes(t4.bytes()).expect("T4");
    check("ShBrdfTable", |i, u| Bxdf::sample(&sh, i, u));
}
