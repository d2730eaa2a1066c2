//! Lookup cost of the tables against their f64 reference and against a
//! closed-form peer, in one run (compare the ratios; absolute times depend on
//! the machine). Each iteration evaluates a batch of 1024 pseudo-random inputs.

use criterion::{Criterion, Throughput, criterion_group, criterion_main};
use generator::sh::IsotropicBrdf;
use std::hint::black_box;
use twoscale::{
    Complex, ConvTable, Convolution, DiffuseFresnelTable, SigmaRatioTable, SmithG1Table, TableId,
};

const BATCH: usize = 1024;

/// Beckmann Smith G1 in closed form (the peer T1 must keep up with):
/// Λ(a) = (erf(μ) − 1)/2 + exp(−μ²)/(2 μ √π), μ = 1/a.
#[inline]
fn beckmann_g1(a: f32) -> f32 {
    if a <= 0.0 {
        return 1.0;
    }
    let mu = 1.0 / a;
    let lambda = 0.5 * (libm::erff(mu) - 1.0)
        + libm::expf(-mu * mu) / (2.0 * mu * core::f32::consts::PI.sqrt());
    1.0 / (1.0 + lambda)
}

fn inputs(seed: u64) -> Vec<(f32, f32)> {
    let mut rng = generator::rng::SplitMix64::new(seed);
    (0..BATCH)
        .map(|_| {
            (
                rng.uniform_in(0.2, 5.0) as f32,
                rng.log_uniform_in(0.01, 100.0) as f32,
            )
        })
        .collect()
}

fn smith_g1(c: &mut Criterion) {
    let buf = suite::read_table(TableId::SmithG1);
    let table = SmithG1Table::from_bytes(buf.bytes()).expect("valid T1");
    let points = inputs(1);
    let shape = table.shape(1.0);
    let mut group = c.benchmark_group("smith_g1");
    group.throughput(Throughput::Elements(BATCH as u64));
    group.bench_function("t1_table_fixed_p", |b| {
        b.iter(|| {
            let mut sum = 0.0f32;
            for &(_, a) in &points {
                sum += shape.g1(black_box(a));
            }
            sum
        })
    });
    group.bench_function("t1_table_any_p", |b| {
        b.iter(|| {
            let mut sum = 0.0f32;
            for &(p, a) in &points {
                sum += table.g1(black_box(p), black_box(a));
            }
            sum
        })
    });
    group.bench_function("beckmann_closed_form", |b| {
        b.iter(|| {
            let mut sum = 0.0f32;
            for &(_, a) in &points {
                sum += beckmann_g1(black_box(a));
            }
            sum
        })
    });
    group.finish();

    // The reference is ~10⁴ times slower: a smaller batch, reported per element.
    const REFERENCE_BATCH: usize = 64;
    let mut group = c.benchmark_group("smith_g1");
    group.throughput(Throughput::Elements(REFERENCE_BATCH as u64));
    group.sample_size(10);
    group.bench_function("f64_reference", |b| {
        b.iter(|| {
            let mut sum = 0.0f64;
            for &(p, a) in points.iter().take(REFERENCE_BATCH) {
                sum += generator::reference::epd::g1(black_box(p as f64), black_box(a as f64))
                    .unwrap_or(0.0);
            }
            sum
        })
    });
    group.finish();
}

fn sigma_ratio(c: &mut Criterion) {
    let buf = suite::read_table(TableId::SigmaRatio);
    let table = SigmaRatioTable::from_bytes(buf.bytes()).expect("valid T2");
    let mut rng = generator::rng::SplitMix64::new(2);
    let points: Vec<(f32, f32, f32)> = (0..BATCH)
        .map(|_| {
            (
                rng.uniform_in(0.0, 1.0) as f32,
                rng.log_uniform_in(0.1, 3000.0) as f32,
                (1.0 + rng.log_uniform_in(0.01, 99.0)) as f32,
            )
        })
        .collect();
    let mut group = c.benchmark_group("sigma_ratio");
    group.throughput(Throughput::Elements(BATCH as u64));
    group.bench_function("t2_table", |b| {
        b.iter(|| {
            let mut sum = 0.0f32;
            for &(cos_theta_i, big_b, c) in &points {
                sum +=
                    table.sigma_ratio_cos(black_box(cos_theta_i), black_box(big_b), black_box(c));
            }
            sum
        })
    });
    group.finish();

    const REFERENCE_BATCH: usize = 64;
    let mut group = c.benchmark_group("sigma_ratio");
    group.throughput(Throughput::Elements(REFERENCE_BATCH as u64));
    group.sample_size(10);
    group.bench_function("f64_reference", |b| {
        b.iter(|| {
            let mut sum = 0.0f64;
            for &(cos_theta_i, big_b, c) in points.iter().take(REFERENCE_BATCH) {
                sum += generator::reference::kcorr::sigma_ratio(
                    black_box(f64::from(cos_theta_i).acos()),
                    black_box(f64::from(big_b)),
                    black_box(f64::from(c)),
                )
                .unwrap_or(0.0);
            }
            sum
        })
    });
    group.finish();
}

/// Complex Fresnel and Q̄ (closed forms, f64 inside) against Schlick's
/// approximation; T5 against its quadrature reference.
fn fresnel(c: &mut Criterion) {
    let mut rng = generator::rng::SplitMix64::new(3);
    let points: Vec<(Complex, f32, [f32; 3])> = (0..BATCH)
        .map(|_| {
            let eta = Complex::new(
                rng.log_uniform_in(0.05, 10.0) as f32,
                rng.uniform_in(0.0, 20.0) as f32,
            );
            let (cos, phi) = (rng.uniform(), rng.uniform_in(0.0, std::f64::consts::TAU));
            let sin = (1.0 - cos * cos).sqrt();
            let o = [
                (sin * phi.cos()) as f32,
                (sin * phi.sin()) as f32,
                cos as f32,
            ];
            (eta, rng.uniform() as f32, o)
        })
        .collect();
    let mut group = c.benchmark_group("fresnel");
    group.throughput(Throughput::Elements(BATCH as u64));
    group.bench_function("complex_fresnel", |b| {
        b.iter(|| {
            let mut sum = 0.0f32;
            for &(eta, cos, _) in &points {
                sum += twoscale::model::fresnel::fresnel(black_box(eta), black_box(cos));
            }
            sum
        })
    });
    group.bench_function("schlick", |b| {
        b.iter(|| {
            let mut sum = 0.0f32;
            for &(eta, cos, _) in &points {
                let (n, k) = (black_box(eta).re, eta.im);
                let f0 = ((n - 1.0) * (n - 1.0) + k * k) / ((n + 1.0) * (n + 1.0) + k * k);
                let m = 1.0 - black_box(cos);
                sum += f0 + (1.0 - f0) * m * m * m * m * m;
            }
            sum
        })
    });
    group.bench_function("q_bar", |b| {
        b.iter(|| {
            let mut sum = 0.0f32;
            for &(eta, _, o) in &points {
                let i = [0.6, 0.0, 0.8];
                sum += twoscale::model::fresnel::q_bar(black_box(eta), black_box(i), black_box(o));
            }
            sum
        })
    });
    let buf = suite::read_table(TableId::DiffuseFresnel);
    let table = DiffuseFresnelTable::from_bytes(buf.bytes()).expect("valid T5");
    group.bench_function("t5_table", |b| {
        b.iter(|| {
            let mut sum = 0.0f32;
            for &(_, cos, _) in &points {
                sum += table.f_dr_int(black_box(1.0 + 2.0 * cos));
            }
            sum
        })
    });
    group.finish();

    const REFERENCE_BATCH: usize = 64;
    let mut group = c.benchmark_group("fresnel");
    group.throughput(Throughput::Elements(REFERENCE_BATCH as u64));
    group.sample_size(10);
    group.bench_function("t5_f64_reference", |b| {
        b.iter(|| {
            let mut sum = 0.0f64;
            for &(_, cos, _) in points.iter().take(REFERENCE_BATCH) {
                sum += generator::reference::fresnel::diffuse_internal(black_box(
                    1.0 + 2.0 * f64::from(cos),
                ))
                .unwrap_or(0.0);
            }
            sum
        })
    });
    group.finish();
}

/// T3: the accurate form (T3b) and the paper's form (T3a) against the exact
/// convolution (direct quadrature, one angle per call).
fn convolution(c: &mut Criterion) {
    let buf = suite::read_table(TableId::Convolution);
    let table = ConvTable::from_bytes(buf.bytes()).expect("valid T3");
    let fit = table.fit();
    let mut rng = generator::rng::SplitMix64::new(3);
    let points: Vec<[f32; 6]> = (0..BATCH)
        .map(|_| {
            let theta = rng.uniform_in(0.0, 0.5) as f32;
            [
                libm::sinf(theta),
                libm::cosf(theta),
                (rng.uniform_in(0.1f64.ln(), 3000.1f64.ln()).exp() - 0.1) as f32,
                (1.0 + rng.log_uniform_in(0.01, 9.0)) as f32,
                rng.log_uniform_in(0.002, 1.0) as f32,
                rng.uniform_in(0.2, 5.0) as f32,
            ]
        })
        .collect();
    let mut group = c.benchmark_group("convolution");
    group.throughput(Throughput::Elements(BATCH as u64));
    for (name, form) in [("t3b_table", &table as &dyn Convolution), ("t3a_fit", &fit)] {
        group.bench_function(name, |b| {
            b.iter(|| {
                let mut sum = 0.0f32;
                for x in &points {
                    let x = black_box(*x);
                    sum += form.convolution_sin_cos(x[0], x[1], x[2], x[3], x[4], x[5]);
                }
                sum
            })
        });
    }
    // One material (c, β, p of the first point) at varying u and θh: the
    // full lookup against its slice (built once, outside the timing).
    let [_, _, _, mc, mbeta, mp] = points[0];
    let slice = table.slice(mc, mbeta, mp).expect("T3 fits a slice");
    group.bench_function("t3b_table_one_material", |b| {
        b.iter(|| {
            let mut sum = 0.0f32;
            for x in &points {
                let x = black_box(*x);
                sum += table.convolution_sin_cos(x[0], x[1], x[2], mc, mbeta, mp);
            }
            sum
        })
    });
    group.bench_function("t3b_slice_one_material", |b| {
        b.iter(|| {
            let mut sum = 0.0f32;
            for x in &points {
                let x = black_box(*x);
                sum += slice.convolution_sin_cos(x[0], x[1], x[2]);
            }
            sum
        })
    });
    group.finish();
    let mut group = c.benchmark_group("convolution_setup");
    group.bench_function("t3b_slice_build", |b| {
        b.iter(|| {
            table
                .slice(black_box(mc), mbeta, mp)
                .map(|s| s.at_tan(0.1, 1.0))
        })
    });
    group.finish();

    const REFERENCE_BATCH: usize = 8;
    let mut group = c.benchmark_group("convolution");
    group.throughput(Throughput::Elements(REFERENCE_BATCH as u64));
    group.sample_size(10);
    group.bench_function("exact_direct", |b| {
        b.iter(|| {
            let mut sum = 0.0f64;
            for x in points.iter().take(REFERENCE_BATCH) {
                let theta = f64::from(x[0]).atan2(f64::from(x[1]));
                sum += generator::reference::conv::convolution(
                    black_box(theta),
                    f64::from(x[2]),
                    f64::from(x[3]),
                    f64::from(x[4]),
                    f64::from(x[5]),
                )
                .unwrap_or(0.0);
            }
            sum
        })
    });
    group.finish();
}

/// T4: SH evaluation (all three channels, committed files) against the
/// direct evaluation of the BRDF it projects (the runtime two-scale model
/// with T3b, one channel, f64 directions rounded to f32 per call).
fn sh_brdf(c: &mut Criterion) {
    let pairs = generator::tables::sh_brdf::verification_pairs(1024, 7);
    let narrow: Vec<([f32; 3], [f32; 3])> = pairs
        .iter()
        .map(|(i, o)| (i.map(|v| v as f32), o.map(|v| v as f32)))
        .collect();
    let materials = generator::materials::Materials::load(std::path::Path::new(concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/materials.toml"
    )))
    .unwrap();
    let mut group = c.benchmark_group("sh_brdf");
    group.throughput(Throughput::Elements(pairs.len() as u64));
    let inputs = generator::tables::sh_brdf::ModelInputs::load(&suite::tables_dir()).unwrap();
    let parsed = inputs.parse().unwrap();
    let model_tables = parsed.brdf_tables();
    for material in &materials.materials {
        let Some(l) = material.band_limit else {
            continue;
        };
        let bytes =
            std::fs::read(suite::tables_dir().join(format!("t4-{}.tbl", material.name))).unwrap();
        let buf = twoscale::tables::format::aligned_copy(&bytes);
        let table = twoscale::ShBrdfTable::from_bytes(buf.bytes()).unwrap();
        let name = format!("{} L={l}", material.name);
        group.bench_function(format!("sh eval_rgb {name}"), |b| {
            b.iter(|| {
                for &(i, o) in &narrow {
                    black_box(table.eval_rgb(black_box(i), black_box(o)));
                }
            })
        });
        let brdf = generator::tables::sh_brdf::two_scale_brdf(material, 0, 0.645, &model_tables);
        group.bench_function(format!("direct two-scale {}", material.name), |b| {
            b.iter(|| {
                for &(i, o) in &pairs {
                    black_box(brdf.eval(black_box(i), black_box(o)));
                }
            })
        });
    }
    group.finish();
}

criterion_group!(
    benches,
    smith_g1,
    sigma_ratio,
    fresnel,
    convolution,
    sh_brdf
);
criterion_main!(benches);
