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
use twoscale::brdf::{Options, Rgb, TwoScale};
use twoscale::materials::{HP17_NICKEL_SURFACE, PRESETS};
use twoscale::{Complex, Convolution, TableSet};

const BATCH: usize = 1024;
const LAMBDA: f32 = 0.526;
const NICKEL_LIKE: Complex = Complex::new(1.98, 3.74);

/// A GGX Cook–Torrance conductor in f32, as a renderer would write it:
/// `F(η, i·h) D(h) G1(i) G1(o) / (4 cos θi cos θo)` with
/// `D = α² / (π cos⁴θh (α² + tan²θh)²)`, `G1 = 2 / (1 + √(1 + α² tan²θ))`
/// and the same complex Fresnel as the two-scale model.
struct Ggx {
    alpha: f32,
    eta: Complex,
}

impl Ggx {
    #[inline]
    fn g1(&self, w: [f32; 3]) -> f32 {
        let z2 = w[2] * w[2];
        let tan2 = (1.0 - z2).max(0.0) / z2;
        2.0 / (1.0 + libm::sqrtf(1.0 + self.alpha * self.alpha * tan2))
    }

    /// `cos θd` and `D G1(i) G1(o) / (4 cos θi cos θo)`, or `None` below
    /// the horizon.
    #[inline]
    fn cos_d_and_dg(&self, i: [f32; 3], o: [f32; 3]) -> Option<(f32, f32)> {
        if !(i[2] > 0.0 && o[2] > 0.0) {
            return None;
        }
        let s = [i[0] + o[0], i[1] + o[1], i[2] + o[2]];
        let inv = 1.0 / libm::sqrtf(s[0] * s[0] + s[1] * s[1] + s[2] * s[2]);
        let h = s.map(|x| x * inv);
        let cos_d = (i[0] * h[0] + i[1] * h[1] + i[2] * h[2]).clamp(0.0, 1.0);
        let a2 = self.alpha * self.alpha;
        let c2 = h[2] * h[2];
        let t = a2 * c2 + (1.0 - c2);
        let d = a2 / (core::f32::consts::PI * t * t);
        Some((cos_d, d * self.g1(i) * self.g1(o) / (4.0 * i[2] * o[2])))
    }

    #[inline]
    fn eval(&self, i: [f32; 3], o: [f32; 3]) -> f32 {
        match self.cos_d_and_dg(i, o) {
            Some((cos_d, dg)) => twoscale::fresnel::fresnel(self.eta, cos_d) * dg,
            None => 0.0,
        }
    }

    /// The RGB GGX conductor: D and G once, Fresnel per channel.
    #[inline]
    fn eval_rgb(&self, etas: &[Complex; 3], i: [f32; 3], o: [f32; 3]) -> [f32; 3] {
        match self.cos_d_and_dg(i, o) {
            Some((cos_d, dg)) => etas.map(|eta| twoscale::fresnel::fresnel(eta, cos_d) * dg),
            None => [0.0; 3],
        }
    }

    /// Samples a visible normal (Heitz 2018, "Sampling the GGX Distribution
    /// of Visible Normals", JCGT 7(4)), reflects `i` about it, and returns
    /// the direction, its pdf `D_i(h) / (4 i·h)` and the eval there.
    #[inline]
    fn sample_eval(&self, i: [f32; 3], u: [f32; 2]) -> Option<([f32; 3], f32, f32)> {
        let a = self.alpha;
        let vh = [a * i[0], a * i[1], i[2]];
        let l = libm::sqrtf(vh[0] * vh[0] + vh[1] * vh[1] + vh[2] * vh[2]);
        let vh = vh.map(|x| x / l);
        let lensq = vh[0] * vh[0] + vh[1] * vh[1];
        let t1 = if lensq > 0.0 {
            let inv = 1.0 / libm::sqrtf(lensq);
            [-vh[1] * inv, vh[0] * inv, 0.0]
        } else {
            [1.0, 0.0, 0.0]
        };
        let t2 = [
            vh[1] * t1[2] - vh[2] * t1[1],
            vh[2] * t1[0] - vh[0] * t1[2],
            vh[0] * t1[1] - vh[1] * t1[0],
        ];
        let r = libm::sqrtf(u[0]);
        let phi = 2.0 * core::f32::consts::PI * u[1];
        let p1 = r * libm::cosf(phi);
        let s = 0.5 * (1.0 + vh[2]);
        let p2 = (1.0 - s) * libm::sqrtf((1.0 - p1 * p1).max(0.0)) + s * r * libm::sinf(phi);
        let p3 = libm::sqrtf((1.0 - p1 * p1 - p2 * p2).max(0.0));
        let nh = [0, 1, 2].map(|k| p1 * t1[k] + p2 * t2[k] + p3 * vh[k]);
        let m = [a * nh[0], a * nh[1], nh[2].max(0.0)];
        let lm = libm::sqrtf(m[0] * m[0] + m[1] * m[1] + m[2] * m[2]);
        let m = m.map(|x| x / lm);
        let k = 2.0 * (i[0] * m[0] + i[1] * m[1] + i[2] * m[2]);
        let o = [k * m[0] - i[0], k * m[1] - i[1], k * m[2] - i[2]];
        if o[2] <= 0.0 || o[2].is_nan() {
            return None;
        }
        let a2 = a * a;
        let c2 = m[2] * m[2];
        let t = a2 * c2 + (1.0 - c2);
        let d = a2 / (core::f32::consts::PI * t * t);
        let pdf = self.g1(i) * d / (4.0 * i[2]);
        Some((o, pdf, self.eval(i, o)))
    }
}

fn direction(rng: &mut generator::rng::SplitMix64) -> [f32; 3] {
    // Uniform over the upper hemisphere.
    let z = rng.uniform();
    let r = (1.0 - z * z).sqrt();
    let phi = 2.0 * std::f64::consts::PI * rng.uniform();
    [(r * phi.cos()) as f32, (r * phi.sin()) as f32, z as f32]
}

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
    let tables = set.brdf_tables_with(conv);
    let model = TwoScale::conductor(&tables, HP17_NICKEL_SURFACE, LAMBDA, NICKEL_LIKE);
    let ggx = Ggx {
        alpha: HP17_NICKEL_SURFACE.beta,
        eta: NICKEL_LIKE,
    };

    let mut rng = generator::rng::SplitMix64::new(17);
    let pairs: Vec<([f32; 3], [f32; 3])> = (0..BATCH)
        .map(|_| (direction(&mut rng), direction(&mut rng)))
        .collect();
    let uniforms: Vec<([f32; 3], [f32; 3])> = (0..BATCH)
        .map(|_| {
            let u = [0, 1, 2].map(|_| rng.uniform() as f32);
            (direction(&mut rng), u)
        })
        .collect();

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
    let gold = set.material("gold-hp17-geometry").expect("preset");
    let gold_eta = PRESETS
        .iter()
        .find(|(n, _)| *n == "gold-hp17-geometry")
        .map(|(_, m)| m.eta_rgb)
        .expect("preset");
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
    setup.bench_function("rgb_preset", |b| {
        b.iter(|| {
            Rgb::new(
                &set.brdf_tables(),
                black_box(&PRESETS[0].1),
                Options::default(),
            )
        })
    });
    setup.finish();
}

criterion_group!(benches, brdf);
criterion_main!(benches);
