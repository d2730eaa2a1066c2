//! Cost of the two-scale BRDF (`eval`, `sample`, `pdf`) against a GGX
//! Cook–Torrance conductor evaluated in the same run (docs/model.md §7; the goal of
//! issue 5 is `eval` ≤ 3× GGX). Each iteration handles a batch of 1024
//! pseudo-random inputs; compare the ratios, absolute times depend on the
//! machine.
//!
//! The material is HP17's nickel geometry (`HP17_NICKEL_SURFACE`: β = 0.0598,
//! p = 1, σs = 0.0273 µm, b = 4.8418 µm, c = 2) at λ = 0.526 µm with a
//! nickel-like index 1.98 + 3.74i; C comes from the committed T3 table (T3b,
//! and T3a for the paper's form). Setting `TWOSCALE_BENCH_STANDIN=1` runs the
//! two-scale benchmarks with the narrow-NDF stand-in for C instead (for a
//! checkout without `tables/t3-convolution.tbl`); their names then end in
//! `_standin_c`, so the two are never confused.

use criterion::{Criterion, Throughput, criterion_group, criterion_main};
use std::hint::black_box;
use suite::brdf::NarrowNdfConvolution;
use suite::cost::{BATCH, Inputs, LAMBDA, NICKEL_LIKE, RGB_PRESET, ggx, nickel, rgb_preset};
use twoscale::brdf::{IntegratedRgb, Rgb, Spectral, TwoScale};
use twoscale::material::{BaseLayer, Layer, MultipleScattering, Options};
use twoscale::materials::{self, HP17_NICKEL_SURFACE, PRESETS};
use twoscale::{Convolution, TableSet};

fn brdf(c: &mut Criterion) {
    let set = TableSet::embedded();
    let standin = std::env::var_os("TWOSCALE_BENCH_STANDIN").is_some();
    let table = (!standin).then_some(set.convolution);
    let fit = table.as_ref().map(|t| t.fit());
    let narrow = NarrowNdfConvolution;
    let (conv, suffix): (&(dyn Convolution + Sync), &str) = match &table {
        Some(t) => (t, "t3b"),
        None => (&narrow, "standin_c"),
    };
    let model = nickel(&set, conv);
    let ggx = ggx();
    let Inputs { pairs, uniforms } = Inputs::new();

    let mut group = c.benchmark_group("brdf");
    group.throughput(Throughput::Elements(BATCH as u64));
    group.bench_function("ggx_cook_torrance_eval", |b| {
        b.iter(|| {
            let mut sum = 0.0f32;
            for &(i, o) in &pairs {
                sum += ggx.eval(black_box(i), black_box(o));
            }
            sum
        })
    });
    group.bench_function(format!("two_scale_eval_{suffix}"), |b| {
        b.iter(|| {
            let mut sum = 0.0f32;
            for &(i, o) in &pairs {
                sum += model.eval(black_box(i), black_box(o));
            }
            sum
        })
    });
    // The same model with the energy-compensation lobe (issue 27; target ≤ 1.15× off).
    let compensated = TwoScale::new(
        &set.brdf_tables_with(conv),
        conductor(HP17_NICKEL_SURFACE),
        LAMBDA,
        NICKEL_LIKE,
        kulla_conty(),
    );
    group.bench_function(format!("two_scale_eval_kulla_conty_{suffix}"), |b| {
        b.iter(|| {
            let mut sum = 0.0f32;
            for &(i, o) in &pairs {
                sum += compensated.eval(black_box(i), black_box(o));
            }
            sum
        })
    });
    if let Some(fit) = &fit {
        let tables_fit = set.brdf_tables_with(fit);
        let model_fit = TwoScale::conductor(&tables_fit, HP17_NICKEL_SURFACE, LAMBDA, NICKEL_LIKE);
        group.bench_function("two_scale_eval_t3a", |b| {
            b.iter(|| {
                let mut sum = 0.0f32;
                for &(i, o) in &pairs {
                    sum += model_fit.eval(black_box(i), black_box(o));
                }
                sum
            })
        });
    }
    group.bench_function(format!("two_scale_pdf_{suffix}"), |b| {
        b.iter(|| {
            let mut sum = 0.0f32;
            for &(i, o) in &pairs {
                sum += model.pdf(black_box(i), black_box(o));
            }
            sum
        })
    });
    // `sample` returns the direction, its pdf and ρ there (one sampling, one
    // pdf and one eval per call).
    group.bench_function(format!("two_scale_sample_{suffix}"), |b| {
        b.iter(|| {
            let mut sum = 0.0f32;
            for &(i, u) in &uniforms {
                if let Some(s) = model.sample(black_box(i), black_box(u)) {
                    sum += s.value / s.pdf;
                }
            }
            sum
        })
    });
    // RGB: a preset from the table set against the RGB GGX conductor.
    let (gold, gold_eta) = rgb_preset(&set);
    group.bench_function("ggx_cook_torrance_eval_rgb", |b| {
        b.iter(|| {
            let mut sum = 0.0f32;
            for &(i, o) in &pairs {
                sum += ggx.eval_rgb(&gold_eta, black_box(i), black_box(o))[1];
            }
            sum
        })
    });
    group.bench_function(format!("two_scale_eval_rgb_{suffix}"), |b| {
        b.iter(|| {
            let mut sum = 0.0f32;
            for &(i, o) in &pairs {
                sum += gold.eval(black_box(i), black_box(o))[1];
            }
            sum
        })
    });
    // The same preset in linear sRGB by integration over the spectrum
    // (docs/design/rgb-integration.md): 8 wavelengths and the colour weights.
    let tables = set.brdf_tables();
    let gold_spectral = materials::spectral(RGB_PRESET).expect("preset");
    let integrated = IntegratedRgb::boxed(&tables, &gold_spectral, Options::default());
    group.bench_function("two_scale_eval_rgb_integrated_t3b", |b| {
        b.iter(|| {
            let mut sum = 0.0f32;
            for &(i, o) in &pairs {
                sum += integrated.eval(black_box(i), black_box(o))[1];
            }
            sum
        })
    });
    // Any wavelength from one construction (HP17's nickel geometry with
    // nickel's measured index, the `nickel` preset), at λ = LAMBDA, and at
    // four wavelengths per call.
    let nickel_spectral = materials::spectral("nickel").expect("preset");
    let spectral = Spectral::boxed(&tables, &nickel_spectral, Options::default());
    group.bench_function("two_scale_eval_spectral_t3b", |b| {
        b.iter(|| {
            let mut sum = 0.0f32;
            for &(i, o) in &pairs {
                sum += spectral.eval(black_box(i), black_box(o), LAMBDA);
            }
            sum
        })
    });
    group.bench_function("two_scale_eval4_spectral_t3b", |b| {
        b.iter(|| {
            let mut sum = 0.0f32;
            for &(i, o) in &pairs {
                sum += spectral.eval4(black_box(i), black_box(o), [0.45, 0.53, 0.61, 0.69])[1];
            }
            sum
        })
    });
    group.bench_function("ggx_vndf_sample_and_eval", |b| {
        b.iter(|| {
            let mut sum = 0.0f32;
            for &(i, u) in &uniforms {
                if let Some((_, pdf, value)) = ggx.sample_eval(black_box(i), [u[1], u[2]]) {
                    sum += value / pdf;
                }
            }
            sum
        })
    });
    group.finish();

    // Construction: one wavelength, and the RGB model of a preset.
    let mut setup = c.benchmark_group("construct");
    setup.bench_function("two_scale_new", |b| {
        b.iter(|| {
            TwoScale::conductor(
                &set.brdf_tables(),
                black_box(HP17_NICKEL_SURFACE),
                LAMBDA,
                NICKEL_LIKE,
            )
        })
    });
    // With the compensation lobe: T6's column and the halo's deficit (σs > 0).
    setup.bench_function("two_scale_new_kulla_conty", |b| {
        b.iter(|| {
            TwoScale::new(
                &set.brdf_tables(),
                conductor(black_box(HP17_NICKEL_SURFACE)),
                LAMBDA,
                NICKEL_LIKE,
                kulla_conty(),
            )
        })
    });
    setup.bench_function("rgb_preset", |b| {
        b.iter(|| {
            Rgb::new(
                &set.brdf_tables(),
                black_box(&PRESETS[0].1),
                Options::default(),
            )
        })
    });
    setup.bench_function("spectral_preset", |b| {
        b.iter(|| {
            Spectral::boxed(
                &set.brdf_tables(),
                black_box(&nickel_spectral),
                Options::default(),
            )
        })
    });
    setup.bench_function("rgb_integrated_preset", |b| {
        b.iter(|| {
            IntegratedRgb::boxed(
                &set.brdf_tables(),
                black_box(&gold_spectral),
                Options::default(),
            )
        })
    });
    setup.finish();
}

/// A conductor layer of `surface`.
fn conductor(surface: twoscale::material::Surface) -> Layer {
    Layer {
        surface,
        base: BaseLayer::Conductor,
        lambertian: 0.0,
    }
}

/// The default options with the energy-compensation lobe.
fn kulla_conty() -> Options {
    Options {
        multiple_scattering: MultipleScattering::KullaConty,
        ..Options::default()
    }
}

criterion_group!(benches, brdf);
criterion_main!(benches);
