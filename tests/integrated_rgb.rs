//! The RGB model by integration over the spectrum (`twoscale::brdf::IntegratedRgb`,
//! docs/design/rgb-integration.md) against the CIE 5 nm sum of 85
//! one-wavelength models, and its sampler against its pdf.

use generator::rng::SplitMix64;
use generator::spectral_accuracy::{direction, integrated_errors};
use suite::brdf::chi_square_sampler;
use twoscale::TableSet;
use twoscale::brdf::{IntegratedRgb, TwoScale};
use twoscale::material::{BaseLayer, ColourTerms, Layer, Options, Surface};
use twoscale::materials::SPECTRAL_PRESETS;
use twoscale::math::Complex;
use twoscale::spectrum::optical::{Ior, SpectralMaterial};

/// p99 and max of the relative error per channel of `model` against the
/// 5 nm sum over 600 pairs, half uniform and half drawn from the model's
/// sampler, where the sum exceeds 1e-3 of its largest value at the pairs.
fn errors(
    tables: &twoscale::brdf::Tables<'_>,
    material: &SpectralMaterial<'_>,
    options: Options,
    seed: u64,
) -> (f64, f64, usize) {
    let mut errors: Vec<f64> = integrated_errors(tables, material, options, 600, seed)
        .into_iter()
        .map(|(e, _)| e)
        .collect();
    let p99 = suite::brdf::percentile(&mut errors, 0.99);
    (p99, *errors.last().unwrap(), errors.len())
}

/// Every preset, at pairs half uniform and half drawn from the model's
/// sampler: the relative error per channel, where the 5 nm sum exceeds
/// 1e-3 of the largest value seen, is within 0.5% at p99 and 1% at most
/// (the target; the study measures 0.29% / 0.52% with exact
/// weights, the baked weights add their interpolation over cos θd).
#[test]
fn presets_match_the_5_nm_sum() {
    let set = TableSet::embedded();
    let tables = set.brdf_tables();
    let options = Options::default();
    let mut worst = (0.0f64, "");
    for preset in SPECTRAL_PRESETS {
        let (p99, max, count) = errors(&tables, &preset.material, options, 41);
        eprintln!(
            "{}: p99 {:.3}%, max {:.3}%",
            preset.name,
            100.0 * p99,
            100.0 * max
        );
        assert!(count > 100, "{}: {count} values", preset.name);
        if p99 > worst.0 {
            worst = (p99, preset.name);
        }
        assert!(
            p99 <= 5e-3 && max <= 1e-2,
            "{}: p99 {p99}, max {max}",
            preset.name
        );
    }
    eprintln!("worst p99 {:.3}% ({})", 100.0 * worst.0, worst.1);
}

/// Random metals with strong halos (σs up to 0.1 µm, b from 1 to 20 µm,
/// β from 0.01 to 0.5, p from 0.3 to 4, c from 1.5 to 3): the same target.
#[test]
fn random_materials_match_the_5_nm_sum() {
    let set = TableSet::embedded();
    let tables = set.brdf_tables();
    let metals = [
        "gold-rough",
        "silver",
        "copper",
        "nickel",
        "chromium",
        "titanium",
        "iron",
        "aluminium",
    ];
    let mut rng = SplitMix64::new(2026);
    let mut failed: Vec<(Surface, f64, f64)> = Vec::new();
    for (k, metal) in metals.into_iter().enumerate() {
        let eta = twoscale::materials::spectral(metal).unwrap().eta;
        let surface = Surface {
            beta: (0.01f64 * 50f64.powf(rng.uniform())) as f32,
            p: (0.3f64 * (4.0f64 / 0.3).powf(rng.uniform())) as f32,
            sigma_s: (0.01 + 0.09 * rng.uniform()) as f32,
            b: (20f64.powf(rng.uniform())) as f32,
            c: (1.5 + 1.5 * rng.uniform()) as f32,
        };
        let material = SpectralMaterial {
            layer: Layer {
                surface,
                base: BaseLayer::Conductor,
                lambertian: 0.0,
            },
            eta,
        };
        let (p99, max, count) = errors(&tables, &material, Options::default(), k as u64);
        eprintln!(
            "{surface:?} ({}): p99 {:.3}%, max {:.3}% over {count}",
            metal,
            100.0 * p99,
            100.0 * max
        );
        if !(p99 <= 5e-3 && max <= 1e-2) {
            failed.push((surface, p99, max));
        }
    }
    assert!(failed.is_empty(), "{failed:?}");
}

/// A material whose reflectance does not depend on λ (constant index, no
/// diffraction, white or physical colour terms) comes out grey and equal to
/// its one-wavelength value: the weights of each channel sum to 1.
#[test]
fn a_wavelength_independent_material_is_grey() {
    let set = TableSet::embedded();
    let tables = set.brdf_tables();
    let surface = Surface {
        beta: 0.3,
        p: 1.4,
        sigma_s: 0.0,
        b: 0.0,
        c: 2.0,
    };
    for (base, colour_terms, eta) in [
        (
            BaseLayer::Conductor,
            ColourTerms::Physical,
            Complex::new(1.2, 3.0),
        ),
        (
            BaseLayer::Plastic { albedo: 0.7 },
            ColourTerms::Physical,
            Complex::real(1.5),
        ),
        (
            BaseLayer::Conductor,
            ColourTerms::White,
            Complex::new(0.2, 3.0),
        ),
    ] {
        let material = SpectralMaterial {
            layer: Layer {
                surface,
                base,
                lambertian: 0.1,
            },
            eta: Ior::Constant(eta),
        };
        let options = Options {
            colour: colour_terms,
            ..Options::default()
        };
        let model = IntegratedRgb::boxed(&tables, &material, options);
        let one = TwoScale::boxed(&tables, material.layer, 0.55, eta, options);
        let mut rng = SplitMix64::new(7);
        for _ in 0..200 {
            let (i, o) = (direction(&mut rng), direction(&mut rng));
            let v = model.eval(i, o);
            let r = f64::from(one.eval(i, o));
            for c in v {
                assert!(
                    (f64::from(c) - r).abs() <= 2e-5 * r + 1e-7,
                    "{base:?} {colour_terms:?}: {v:?} vs {r}"
                );
            }
        }
    }
}

/// `sample` returns `pdf` and `eval` at its direction, and its directions
/// follow `pdf` (χ²) for the presets with the strongest halos.
#[test]
fn sampler_follows_its_pdf() {
    let set = TableSet::embedded();
    let tables = set.brdf_tables();
    let alpha = suite::sidak(0.01, 6);
    for name in ["gold-rough", "copper", "silver"] {
        let m = twoscale::materials::spectral(name).unwrap();
        let model = IntegratedRgb::boxed(&tables, &m, Options::default());
        let mut rng = SplitMix64::new(3);
        for _ in 0..200 {
            let i = direction(&mut rng);
            let u = [0, 1, 2].map(|_| rng.uniform() as f32);
            if let Some(s) = model.sample(i, u) {
                assert_eq!(s.pdf, model.pdf(i, s.o));
                assert_eq!(s.value, model.eval(i, s.o));
            }
        }
        for (k, deg) in [30.0f64, 75.0].into_iter().enumerate() {
            let t = deg.to_radians();
            let i = [t.sin() as f32, 0.0, t.cos() as f32];
            let check = chi_square_sampler(
                i,
                |u| model.sample(i, u).map(|s| s.o),
                |o| f64::from(model.pdf(i, o)),
                300_000,
                0.2,
                k as u64,
            );
            eprintln!("{name} θi = {deg}°: p = {:.4}", check.chi.p_value);
            assert!(
                check.chi.p_value >= alpha,
                "{name} θi = {deg}°: p = {}",
                check.chi.p_value
            );
            assert!(check.pdf_integral <= 1.0 + 1e-4, "{}", check.pdf_integral);
        }
    }
}

/// `brdf::Spectral` at random wavelengths of [0.36, 0.83] µm against a
/// one-wavelength model built at that λ with the same interpolated index:
/// relative error within 0.5% at p99 and 2% at most (the target),
/// where the one-wavelength value exceeds 1e-3 of the largest seen; the
/// four-wavelength form equals four single calls; `sample` returns `pdf`
/// and `eval` at its direction.
#[test]
fn spectral_matches_one_wavelength_models() {
    use twoscale::brdf::Spectral;
    let set = TableSet::embedded();
    let tables = set.brdf_tables();
    let options = Options::default();
    let mut rng = SplitMix64::new(5);
    // The sampler check's uniforms, apart from the accuracy draw's.
    let mut sample_rng = SplitMix64::new(6);
    let mut failed = Vec::new();
    let mut materials: Vec<(String, SpectralMaterial<'static>)> = SPECTRAL_PRESETS
        .iter()
        .map(|p| (p.name.to_string(), p.material))
        .collect();
    for (k, metal) in ["gold-rough", "copper", "silver", "iron"]
        .into_iter()
        .enumerate()
    {
        let mut m = twoscale::materials::spectral(metal).unwrap();
        m.layer.surface = Surface {
            beta: (0.01f64 * 50f64.powf(rng.uniform())) as f32,
            p: (0.3f64 * (4.0f64 / 0.3).powf(rng.uniform())) as f32,
            sigma_s: (0.01 + 0.09 * rng.uniform()) as f32,
            b: (20f64.powf(rng.uniform())) as f32,
            c: (1.5 + 1.5 * rng.uniform()) as f32,
        };
        materials.push((format!("random {k} ({metal})"), m));
    }
    for (name, m) in &materials {
        let model = Spectral::boxed(&tables, m, options);
        let mut rows = Vec::new();
        for _ in 0..40 {
            let lambda = (0.36 + 0.47 * rng.uniform()) as f32;
            let one = TwoScale::boxed(&tables, m.layer, lambda, m.eta.at(lambda), options);
            for k in 0..20 {
                let i = direction(&mut rng);
                let o = if k % 2 == 0 {
                    direction(&mut rng)
                } else {
                    let u = [0, 1, 2].map(|_| rng.uniform() as f32);
                    match one.sample(i, u) {
                        Some(s) => s.o,
                        None => continue,
                    }
                };
                rows.push((
                    f64::from(one.eval(i, o)),
                    f64::from(model.eval(i, o, lambda)),
                ));
                let u = [0, 1, 2].map(|_| sample_rng.uniform() as f32);
                if let Some(s) = model.sample(i, u, lambda) {
                    assert_eq!(s.pdf, model.pdf(i, s.o, lambda));
                    assert_eq!(s.value, model.eval(i, s.o, lambda));
                }
                let ls = [lambda, 0.4, 0.55, 0.8];
                let four = model.eval4(i, o, ls);
                for (l, v) in ls.iter().zip(four) {
                    assert_eq!(v, model.eval(i, o, *l));
                }
            }
        }
        let peak = rows.iter().map(|r| r.0).fold(0.0, f64::max);
        let mut errors: Vec<f64> = rows
            .iter()
            .filter(|r| r.0 > 1e-3 * peak)
            .map(|r| (r.1 - r.0).abs() / r.0)
            .collect();
        let p99 = suite::brdf::percentile(&mut errors, 0.99);
        let max = *errors.last().unwrap();
        eprintln!(
            "{name}: p99 {:.3}%, max {:.3}% over {}",
            100.0 * p99,
            100.0 * max,
            errors.len()
        );
        if !(p99 <= 5e-3 && max <= 2e-2) {
            failed.push((name.clone(), p99, max));
        }
    }
    assert!(failed.is_empty(), "{failed:?}");
}
