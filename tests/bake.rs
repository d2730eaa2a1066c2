//! The per-material bake against the unbaked model: the same `TwoScale`
//! with C read from T3b directly (a source that offers no material slice, so
//! nothing of C is baked) on 10⁵ random direction pairs, for every preset
//! and for random materials over the domain.
//!
//! The target is a relative error of ρ with p99 ≤ 0.5%, for every preset and
//! over random materials. `cargo test --release --test bake -- --nocapture`
//! prints the figures (docs/design/per-material-bake.md).

use generator::rng::SplitMix64;
use suite::brdf::{percentile, random_direction};
use twoscale::brdf::Rgb;
use twoscale::material::{Material, Options, Surface};
use twoscale::tables::convolution::{ConvTable, Convolution};
use twoscale::{Complex, TableSet};

/// T3b without its material slice: C straight from the 4-D table.
struct Unbaked<'a>(ConvTable<'a>);

impl Convolution for Unbaked<'_> {
    fn convolution_sin_cos(&self, s: f32, c: f32, u: f32, k: f32, b: f32, p: f32) -> f32 {
        self.0.convolution_sin_cos(s, c, u, k, b, p)
    }
}

/// Relative errors of the baked RGB model against the unbaked one, every
/// channel, at `pairs` random direction pairs (uniform over the hemisphere).
fn errors(set: &TableSet<'_>, material: &Material, pairs: usize, seed: u64) -> Vec<f64> {
    let unbaked_source = Unbaked(set.convolution);
    let unbaked_tables = set.brdf_tables_with(&unbaked_source);
    // Boxed: two models by value (366 KB each) may overflow a test thread's stack.
    let baked = Rgb::boxed(&set.brdf_tables(), material, Options::default());
    let unbaked = Rgb::boxed(&unbaked_tables, material, Options::default());
    let mut rng = SplitMix64::new(seed);
    let mut out = Vec::with_capacity(3 * pairs);
    for _ in 0..pairs {
        let (i, o) = (random_direction(&mut rng), random_direction(&mut rng));
        let (x, y) = (baked.eval(i, o), unbaked.eval(i, o));
        for k in 0..3 {
            assert!(x[k].is_finite() && x[k] >= 0.0, "{x:?} at {i:?}, {o:?}");
            if y[k] > 0.0 {
                out.push((f64::from(x[k]) / f64::from(y[k]) - 1.0).abs());
            }
        }
    }
    out
}

fn report(name: &str, mut e: Vec<f64>) -> f64 {
    let (p50, p99, max) = (
        percentile(&mut e, 0.5),
        percentile(&mut e, 0.99),
        percentile(&mut e, 1.0),
    );
    eprintln!("{name:>28}: median {p50:.2e}, p99 {p99:.2e}, max {max:.2e}");
    p99
}

/// Random conductors over the domain of T3 (β ∈ [0.002, 1] log-uniform,
/// p ∈ [0.2, 5], c ∈ [1.01, 10]) and of the model's lengths (σs from 0.002 to
/// 0.1 µm, b from 0.5 to 20 µm: B = b/λ up to 45).
fn random_materials(count: u64) -> Vec<Material> {
    let mut rng = SplitMix64::new(2026);
    let log_uniform = |rng: &mut SplitMix64, lo: f64, hi: f64| {
        (lo.ln() + rng.uniform() * (hi / lo).ln()).exp() as f32
    };
    (0..count)
        .map(|_| Material {
            layer: twoscale::material::Layer {
                surface: Surface {
                    beta: log_uniform(&mut rng, 0.002, 1.0),
                    p: (0.2 + 4.8 * rng.uniform()) as f32,
                    sigma_s: log_uniform(&mut rng, 0.002, 0.1),
                    b: log_uniform(&mut rng, 0.5, 20.0),
                    c: (1.01 + 8.99 * rng.uniform()) as f32,
                },
                base: twoscale::material::BaseLayer::Conductor,
                lambertian: 0.0,
            },
            eta_rgb: [
                Complex::new(0.2, 3.6),
                Complex::new(0.6, 2.2),
                Complex::new(1.4, 1.9),
            ],
        })
        .collect()
}

/// p99 of every preset.
fn preset_p99s() -> Vec<(&'static str, f64)> {
    let set = TableSet::embedded();
    twoscale::materials::PRESETS
        .iter()
        .enumerate()
        .map(|(k, (name, material))| {
            (
                *name,
                report(name, errors(&set, material, 100_000, 100 + k as u64)),
            )
        })
        .collect()
}

/// p99 of 20 random materials together.
fn random_p99() -> f64 {
    let set = TableSet::embedded();
    let mut all = Vec::new();
    for (m, material) in random_materials(20).iter().enumerate() {
        let e = errors(&set, material, 5_000, 500 + m as u64);
        let s = material.layer.surface;
        let label = format!(
            "β {:.4} p {:.2} c {:.2} B {:.1}",
            s.beta,
            s.p,
            s.c,
            s.b / 0.526
        );
        report(&label, e.clone());
        all.extend(e);
    }
    report("all random materials", all)
}

/// The target for the presets: p99 ≤ 0.5% (worst measured: 0.32%, gold-rough).
#[test]
fn presets_are_within_half_a_percent_at_p99() {
    for (name, p99) in preset_p99s() {
        assert!(p99 <= 5e-3, "{name}: p99 {p99:.2e} > 0.5%");
    }
}

/// The target over 20 random materials: p99 ≤ 0.5% (measured: 0.28%).
#[test]
fn random_materials_are_within_half_a_percent_at_p99() {
    let random = random_p99();
    assert!(random <= 5e-3, "random materials: p99 {random:.2e} > 0.5%");
}
