//! The two-scale BRDF of the runtime (`twoscale::brdf`) and the 2015 model
//! (`twoscale::brdf::hp15`), verified physically (docs/model.md §7): the Beckmann limit,
//! reciprocity, the white furnace, χ² tests of the samplers against their
//! pdfs, robustness over a dense sweep, and agreement with the f64 reference.
//!
//! The tables are the embedded `TableSet`. C comes from stand-ins where the
//! test is about something else than T3 (see `suite::brdf`): the exact
//! reference through `ExactConvolution` where few evaluations are needed, a
//! tabulated exact profile (`ProfileConvolution`) for the furnace, and the
//! narrow-NDF limit where C's accuracy does not matter (sampling, sweeps).
//! Those sources offer no material slice, so C is read directly; every other
//! part of the model (F, Q̄, σrel, G1) is the baked one. The C bake is
//! measured against T3b in `tests/bake.rs`.

use generator::reference::brdf::{self as reference, ExactConvolution};
use generator::rng::SplitMix64;
use std::f64::consts::PI;
use std::sync::Mutex;
use suite::brdf::{
    NarrowNdfConvolution, ProfileConvolution, chi_square_sampler, chi_square_two_scale,
    random_direction,
};
use twoscale::Complex;
use twoscale::brdf::hp15::{Energy, Hp15, Hp15Params};
use twoscale::brdf::{Lobe, TwoScale};
use twoscale::material::{
    BaseLayer, ColourTerms, HaloWeight, Layer, Masking, MultipleScattering, Options, SigmaRelMode,
    Surface,
};

const NICKEL_LIKE: Complex = Complex::new(1.98, 3.74);

fn surface(beta: f32, p: f32, sigma_s: f32, b: f32, c: f32) -> Surface {
    Surface {
        beta,
        p,
        sigma_s,
        b,
        c,
    }
}

fn conductor(s: Surface) -> Layer {
    Layer {
        surface: s,
        base: BaseLayer::Conductor,
        lambertian: 0.0,
    }
}

fn from_angles(theta: f64, phi: f64) -> [f32; 3] {
    [
        (theta.sin() * phi.cos()) as f32,
        (theta.sin() * phi.sin()) as f32,
        theta.cos() as f32,
    ]
}

/// At σs = 0 and p = 1 the model is the Beckmann Cook–Torrance conductor:
/// `F(θd) D_B(θh) G1_B(θi) G1_B(θo) / (4 cos θi cos θo)` with
/// `D_B = exp(−tan²θh/α²) / (π α² cos⁴θh)` and
/// `Λ_B(a) = (erf(μ) − 1)/2 + exp(−μ²)/(2μ√π)`, `μ = 1/(α tan θ)`, written
/// here in closed form (F from the f64 reference).
#[test]
fn sigma_s_zero_p_one_is_beckmann_cook_torrance() {
    let set = twoscale::TableSet::embedded();
    let conv = NarrowNdfConvolution;
    let tables = set.brdf_tables_with(&conv);
    let eta = generator::reference::fresnel::Complex64::new(1.98, 3.74);
    let lambda_b = |alpha: f64, w: [f64; 3]| {
        let tan = w[0].hypot(w[1]) / w[2];
        if tan == 0.0 {
            return 0.0;
        }
        let mu = 1.0 / (alpha * tan);
        0.5 * (libm::erf(mu) - 1.0) + (-mu * mu).exp() / (2.0 * mu * PI.sqrt())
    };
    let mut rng = SplitMix64::new(5);
    let mut worst: f64 = 0.0;
    for alpha in [0.01f32, 0.0598, 0.2, 0.5, 1.0] {
        let model = TwoScale::conductor(
            &tables,
            surface(alpha, 1.0, 0.0, 4.0, 2.0),
            0.526,
            NICKEL_LIKE,
        );
        let a = f64::from(alpha);
        for _ in 0..2000 {
            let i = random_direction(&mut rng);
            // Half the points near the mirror direction, where D matters.
            let o = if rng.uniform() < 0.5 {
                let m = model
                    .ndf()
                    .sample([rng.uniform() as f32, rng.uniform() as f32]);
                let k = 2.0 * (i[0] * m[0] + i[1] * m[1] + i[2] * m[2]);
                let o = [k * m[0] - i[0], k * m[1] - i[1], k * m[2] - i[2]];
                if o[2] <= 1e-3 {
                    continue;
                }
                o
            } else {
                random_direction(&mut rng)
            };
            // The runtime normalises its inputs in f64: so does the oracle
            // (near back-scattering, h is ill-conditioned in i and o).
            let unit = |v: [f32; 3]| {
                let v = v.map(f64::from);
                let l = (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]).sqrt();
                v.map(|x| x / l)
            };
            let (wi, wo) = (unit(i), unit(o));
            let s = [wi[0] + wo[0], wi[1] + wo[1], wi[2] + wo[2]];
            let l = (s[0] * s[0] + s[1] * s[1] + s[2] * s[2]).sqrt();
            let h = s.map(|x| x / l);
            let cos_d = wi[0] * h[0] + wi[1] * h[1] + wi[2] * h[2];
            let tan2 = (h[0] * h[0] + h[1] * h[1]) / (h[2] * h[2]);
            let d = (-tan2 / (a * a)).exp() / (PI * a * a * h[2].powi(4));
            let g = 1.0 / ((1.0 + lambda_b(a, wi)) * (1.0 + lambda_b(a, wo)));
            let f = generator::reference::fresnel::fresnel(eta, cos_d).unwrap();
            let expected = f * d * g / (4.0 * wi[2] * wo[2]);
            let got = f64::from(model.eval(i, o));
            if expected < 1e-30 {
                assert!(got < 1e-25, "α = {alpha}: got {got}, expected {expected}");
                continue;
            }
            // T1's G1 error is ≤ 1.1e-5 absolute per factor; the rest is f32.
            let g1_i = 1.0 / (1.0 + lambda_b(a, wi));
            let g1_o = 1.0 / (1.0 + lambda_b(a, wo));
            let allowed = 1.2e-5 / g1_i + 1.2e-5 / g1_o + 2e-5;
            let rel = (got - expected).abs() / expected;
            worst = worst.max(rel / allowed);
            assert!(
                rel <= allowed,
                "α = {alpha}, i = {i:?}, o = {o:?}: runtime {got}, Beckmann {expected} (rel {rel:e} > {allowed:e})"
            );
            assert_eq!(model.eval_lobes(i, o).diffraction, 0.0);
        }
    }
    eprintln!("Beckmann limit: worst error / allowance = {worst:.3}");
}

/// ρ(i, o) = ρ(o, i) where the model is reciprocal (σs = 0; σs > 0 with the
/// symmetrised σrel), and the measured asymmetry of the paper's model
/// (σrel(θi)) with the exact C.
#[test]
fn reciprocity() {
    let set = twoscale::TableSet::embedded();
    let stub = NarrowNdfConvolution;
    let tables = set.brdf_tables_with(&stub);
    let mut rng = SplitMix64::new(11);
    let rel = |a: f32, b: f32| {
        let (a, b) = (f64::from(a), f64::from(b));
        if a.max(b) == 0.0 {
            0.0
        } else {
            (a - b).abs() / a.max(b)
        }
    };
    for (s, options) in [
        (surface(0.0598, 1.0, 0.0, 4.84, 2.0), Options::default()),
        (
            surface(0.3, 0.4, 0.0, 4.84, 2.0),
            Options {
                masking: Masking::HeightCorrelated,
                ..Options::default()
            },
        ),
        (
            surface(0.0598, 1.0, 0.0273, 4.84, 2.0),
            Options {
                sigma_rel: SigmaRelMode::Symmetrised,
                ..Options::default()
            },
        ),
        (
            surface(0.2, 2.0, 0.08, 2.0, 3.0),
            Options {
                sigma_rel: SigmaRelMode::Symmetrised,
                ..Options::default()
            },
        ),
    ] {
        let model = TwoScale::new(&tables, conductor(s), 0.526, NICKEL_LIKE, options);
        let mut worst: f64 = 0.0;
        for _ in 0..20_000 {
            let (i, o) = (random_direction(&mut rng), random_direction(&mut rng));
            worst = worst.max(rel(model.eval(i, o), model.eval(o, i)));
        }
        eprintln!("reciprocity {s:?} {options:?}: max relative asymmetry {worst:e}");
        assert!(worst <= 2e-6, "{s:?}, {options:?}: asymmetry {worst:e}");
    }

    // The paper's model with the exact C: report the asymmetry.
    let exact = ExactConvolution;
    let tables = set.brdf_tables_with(&exact);
    let model = TwoScale::conductor(
        &tables,
        surface(0.0598, 1.0, 0.0273, 4.8418, 2.0),
        0.526,
        NICKEL_LIKE,
    );
    let mut asym = Vec::new();
    for _ in 0..40 {
        let i = random_direction(&mut rng);
        let m = model
            .ndf()
            .sample([rng.uniform() as f32, rng.uniform() as f32]);
        let k = 2.0 * (i[0] * m[0] + i[1] * m[1] + i[2] * m[2]);
        let o = [k * m[0] - i[0], k * m[1] - i[1], k * m[2] - i[2]];
        let o = if o[2] > 0.01 {
            o
        } else {
            random_direction(&mut rng)
        };
        asym.push(rel(model.eval(i, o), model.eval(o, i)));
    }
    asym.sort_by(f64::total_cmp);
    let (median, max) = (asym[asym.len() / 2], asym[asym.len() - 1]);
    eprintln!(
        "σs > 0, σrel(θi) (HP17 nickel geometry, exact C, 40 pairs): asymmetry median {median:.2e}, max {max:.2e}"
    );
    assert!(max > 0.0 && max < 0.1, "asymmetry {max}");
}

/// White furnace (docs/model.md §7): with F ≡ Q̄ ≡ 1, `∫ ρ cos θo dωo ≤ 1` for a grid
/// of incidences and materials. The integral is estimated by importance
/// sampling with the model's own sampler (validated by the χ² tests),
/// 10⁵ samples; the bound is asserted with 4 standard errors of slack
/// where the model guarantees it (see the comment in the loop).
/// C is the exact profile tabulated per material (`ProfileConvolution`).
#[test]
fn white_furnace() {
    let set = twoscale::TableSet::embedded();
    let lambda = 0.526f32;
    let materials = [
        ("hp17-nickel", surface(0.0598, 1.0, 0.0273, 4.8418, 2.0)),
        ("rough", surface(0.5, 1.5, 0.06, 8.0, 2.5)),
        ("heavy-tail", surface(0.2, 0.4, 0.1, 2.0, 1.5)),
        ("strong-halo", surface(0.1, 2.0, 0.15, 1.5, 3.0)),
        ("hp17-no-halo", surface(0.0598, 1.0, 0.0, 4.8418, 2.0)),
        ("rough-no-halo", surface(0.5, 1.5, 0.0, 8.0, 2.5)),
    ];
    let incidences = [0.0, 30.0, 50.0, 70.0, 80.0, 85.0, 89.0];
    let n = 100_000;
    let mut excess: Vec<String> = Vec::new();
    for (name, s, halo_weight) in materials
        .iter()
        .map(|&(name, s)| (name, s, HaloWeight::Printed))
        .chain(
            materials
                .iter()
                .filter(|m| m.1.sigma_s > 0.0)
                .map(|&(name, s)| (name, s, HaloWeight::Incident)),
        )
    {
        let conv = ProfileConvolution::new(s.c, s.beta, s.p, f64::from(s.b / lambda) * 1.0001);
        let tables = set.brdf_tables_with(&conv);
        let options = Options {
            colour: ColourTerms::White,
            halo_weight,
            ..Options::default()
        };
        let model = TwoScale::new(
            &tables,
            conductor(s),
            lambda,
            Complex::new(1.0, 1.0),
            options,
        );
        let mut curve = String::new();
        for deg in incidences {
            let i = from_angles(f64::to_radians(deg), 0.3);
            let mut rng = SplitMix64::new(3);
            let (mut sum, mut sum_sq, mut diffraction) = (0.0, 0.0, 0.0);
            for _ in 0..n {
                let u = [
                    rng.uniform() as f32,
                    rng.uniform() as f32,
                    rng.uniform() as f32,
                ];
                if let Some(sample) = model.sample(i, u) {
                    let w =
                        f64::from(sample.value) * f64::from(sample.o[2]) / f64::from(sample.pdf);
                    let lobes = model.eval_lobes(i, sample.o);
                    diffraction += f64::from(lobes.diffraction) * f64::from(sample.o[2])
                        / f64::from(sample.pdf);
                    sum += w;
                    sum_sq += w * w;
                }
            }
            let mean = sum / n as f64;
            let err = ((sum_sq / n as f64 - mean * mean) / n as f64).sqrt();
            curve.push_str(&format!(
                "  θi = {deg:>4}°: albedo {mean:.4} ± {err:.4} (loss {:.4}; halo {:.4})\n",
                1.0 - mean,
                diffraction / n as f64
            ));
            // Guaranteed: without nano-roughness (Smith-masked Cook–Torrance),
            // and at normal incidence, where cos θd ≤ cos θi = 1 over the
            // hemisphere so 1 − A_spec(θd) ≤ 1 − A_spec(θi). Elsewhere the
            // paper's ρ_CTD weights the halo by 1 − A_spec(θd) at each o,
            // which exceeds the 1 − A(θi) its normalisation by σrel(θi)
            // assumes wherever cos θd > cos θi: the model gains energy at
            // oblique incidence (reported, not asserted).
            // With the halo weighted by A(θi) (HaloWeight::Incident) the
            // furnace is asserted ≤ 1 everywhere.
            let bounded = deg == 0.0 || s.sigma_s == 0.0 || halo_weight == HaloWeight::Incident;
            if mean > 1.0 + 4.0 * err {
                excess.push(format!("{name}, θi = {deg}°: albedo {mean:.4} ± {err:.4}"));
                assert!(!bounded, "{name}, θi = {deg}°: albedo {mean} ± {err} > 1");
            }
            assert!(mean > 0.0);
        }
        eprintln!("white furnace, {name} ({halo_weight:?}) {s:?}, λ = {lambda} µm:\n{curve}");
    }
    eprintln!("above 1: {excess:#?}");
}

/// The albedo `∫ ρ cos θo dωo` of every preset (`twoscale::materials`) per
/// RGB channel with its real F and Q̄ (HP17 10), at θi = 0°, 45°, 70°, 85°:
/// importance sampling with the model's sampler, 2·10⁴ samples per value
/// (the printed ± is one standard error); C exact (`ProfileConvolution`, one
/// profile per preset). Q̄ is not bounded by 1 away from the specular
/// direction (docs/model.md §7), so nothing bounds the albedo by 1: the test prints
/// the table and lists the values above 1 by more than 4 standard errors;
/// it asserts only that every albedo is finite and positive (even at normal
/// incidence the real Q̄ can push a strong halo above 1: gold-rough).
#[test]
fn preset_albedos() {
    let set = twoscale::TableSet::embedded();
    let incidences = [0.0, 45.0, 70.0, 85.0];
    let n = 20_000;
    let mut table = String::from(
        "preset               θi   albedo R          G                 B                 (halo R, G, B)\n",
    );
    let mut above = Vec::new();
    for (name, material) in twoscale::materials::PRESETS {
        let s = material.layer.surface;
        let u_max = f64::from(s.b / twoscale::material::RGB_WAVELENGTHS[2]) * 1.0001;
        let conv = ProfileConvolution::new(s.c, s.beta, s.p, u_max);
        let tables = set.brdf_tables_with(&conv);
        let rgb = twoscale::Rgb::new(&tables, &material, Options::default());
        for deg in incidences {
            let i = from_angles(f64::to_radians(deg), 0.7);
            let mut row = format!("{name:<20} {deg:>3}° ");
            let mut halos = Vec::new();
            for (k, model) in rgb.channels.iter().enumerate() {
                let mut rng = SplitMix64::new(31 + k as u64);
                let (mut sum, mut sum_sq, mut halo) = (0.0, 0.0, 0.0);
                for _ in 0..n {
                    let u = [0, 1, 2].map(|_| rng.uniform() as f32);
                    if let Some(sample) = model.sample(i, u) {
                        let cos_o = f64::from(sample.o[2]) / f64::from(sample.pdf);
                        let w = f64::from(sample.value) * cos_o;
                        halo += f64::from(model.eval_lobes(i, sample.o).diffraction) * cos_o;
                        sum += w;
                        sum_sq += w * w;
                    }
                }
                let mean = sum / n as f64;
                let err = ((sum_sq / n as f64 - mean * mean) / n as f64).sqrt();
                let halo = halo / n as f64;
                assert!(mean.is_finite() && mean > 0.0, "{name} θi = {deg}°: {mean}");
                if mean > 1.0 + 4.0 * err {
                    above.push(format!(
                        "{name} θi = {deg}° channel {k}: {mean:.4} ± {err:.4}"
                    ));
                }
                row.push_str(&format!("{mean:.4} ± {err:.4}   "));
                halos.push(format!("{halo:.4}"));
            }
            table.push_str(&format!("{row}({})\n", halos.join(", ")));
        }
    }
    eprintln!("preset albedos (real F and Q̄, exact C):\n{table}above 1: {above:#?}");
}

/// χ² tests of `sample` against `pdf`, per lobe and for the full model,
/// several incidences (grazing included) and materials (very narrow, HP17,
/// very rough, plastic), 10⁶ samples for the full model and 4·10⁵ per lobe,
/// Šidák-corrected α = 0.01; and `∫ pdf ≤ 1`, equal to the sampler's
/// success rate.
#[test]
fn sampling_matches_pdf() {
    let set = twoscale::TableSet::embedded();
    let stub = NarrowNdfConvolution;
    let tables = set.brdf_tables_with(&stub);
    let lambda = 0.526f32;
    let materials: [(&str, Layer); 4] = [
        ("narrow", conductor(surface(0.004, 0.6, 0.008, 2.0, 1.8))),
        (
            "hp17-nickel",
            conductor(surface(0.0598, 1.0, 0.0273, 4.8418, 2.0)),
        ),
        ("rough", conductor(surface(0.8, 0.3, 0.06, 8.0, 2.5))),
        (
            "plastic",
            Layer {
                surface: surface(0.1, 1.0, 0.03, 3.0, 2.2),
                base: BaseLayer::Plastic { albedo: 0.8 },
                lambertian: 0.05,
            },
        ),
    ];
    let incidences = [0.0, 60.0, 87.0];
    let mut cases = Vec::new();
    for (name, layer) in materials {
        let eta = if matches!(layer.base, BaseLayer::Plastic { .. }) {
            Complex::real(1.5)
        } else {
            NICKEL_LIKE
        };
        for deg in incidences {
            for lobe in [Some(Lobe::Specular), Some(Lobe::Diffraction), None] {
                // The narrow specular lobe at grazing incidence has its own
                // test with 10⁶ samples (`narrow_grazing_specular_sampling`).
                if name == "narrow" && deg == 87.0 && lobe == Some(Lobe::Specular) {
                    continue;
                }
                // The surface lobes' samplers depend on the geometry only,
                // not on the base layer: the conductors cover them; the
                // plastic is tested for its full mixture and its base lobe.
                if name == "plastic" && matches!(lobe, Some(Lobe::Specular | Lobe::Diffraction)) {
                    continue;
                }
                cases.push((name, layer, eta, deg, lobe));
            }
            if name == "plastic" && deg == 60.0 {
                cases.push((name, layer, eta, deg, Some(Lobe::Base)));
            }
        }
    }
    let alpha = suite::sidak(0.01, cases.len() + 2);
    // 10⁶ samples for the full model (every lobe at once), 4·10⁵ per lobe.
    let (n, n_lobe) = (1_000_000, 400_000);
    let results = Mutex::new(Vec::new());
    let next = Mutex::new(0usize);
    std::thread::scope(|scope| {
        for _ in 0..2 {
            scope.spawn(|| {
                loop {
                    let k = {
                        let mut g = next.lock().unwrap();
                        let k = *g;
                        *g += 1;
                        k
                    };
                    let Some(&(name, layer, eta, deg, lobe)) = cases.get(k) else {
                        break;
                    };
                    let model = TwoScale::new(&tables, layer, lambda, eta, Options::default());
                    let i = from_angles(f64::to_radians(deg), 1.1);
                    let s = model.surface();
                    let scale = f64::from(2.0 * s.beta).min(f64::from(lambda / s.b));
                    let count = if lobe.is_some() { n_lobe } else { n };
                    let check = chi_square_two_scale(&model, lobe, i, count, scale, k as u64 + 100);
                    results
                        .lock()
                        .unwrap()
                        .push((name, deg, lobe, count, check));
                }
            });
        }
    });
    let mut results = results.into_inner().unwrap();
    results.sort_by(|a, b| a.4.chi.p_value.total_cmp(&b.4.chi.p_value));
    let mut failures = Vec::new();
    for (name, deg, lobe, n, check) in &results {
        let lobe = lobe.map_or("full".to_string(), |l| format!("{l:?}"));
        eprintln!(
            "χ² {name:>12} θi = {deg:>4}° {lobe:>11}: p = {:.4} (χ² = {:.1}, dof {}), ∫pdf = {:.6}, sampled {:.6}",
            check.chi.p_value,
            check.chi.statistic,
            check.chi.dof,
            check.pdf_integral,
            check.success
        );
        // ∫ pdf ≤ 1, and it is the fraction of calls that returned a direction
        // (binomial standard error √(s(1 − s)/n); 5σ plus the cell rule's
        // error, measured up to 2.3e-5 on the diffraction pdf, whose φmax has
        // a kink at |d| = 1 − sin θi inside some cells).
        let se = (check.success * (1.0 - check.success) / *n as f64).sqrt();
        if check.pdf_integral > 1.0 + 1e-5
            || (check.pdf_integral - check.success).abs() > 5.0 * se + 5e-5
        {
            failures.push(format!(
                "{name} {deg}° {lobe}: ∫pdf {} vs sampled {}",
                check.pdf_integral, check.success
            ));
        }
        if check.chi.p_value < alpha {
            failures.push(format!(
                "{name} {deg}° {lobe}: p = {} < {alpha}",
                check.chi.p_value
            ));
        }
    }
    eprintln!(
        "Šidák per-test α = {alpha:.2e} over {} tests",
        results.len()
    );
    assert!(failures.is_empty(), "{failures:#?}");
}

/// The 2015 model: exact vs printed energy, and its sampler's χ².
#[test]
fn hp15_model() {
    let set = twoscale::TableSet::embedded();
    let stub = NarrowNdfConvolution;
    let tables = set.brdf_tables_with(&stub);
    let lambda = 0.526f32;
    // Diffraction lobe alone, G ≈ 1 (β tiny): ∫ ρ cos θo dωo at normal
    // incidence is k_w/λ⁴ · E_exact/E (k_w chosen so that k_w/λ⁴ = 0.5).
    let kw = 0.5 * lambda.powi(4);
    let params = Hp15Params {
        beta: 1e-4,
        p: 1.0,
        a: 1.5,
        kd: 0.0,
        ks: 0.0,
        kw,
        f0: 0.04,
    };
    let i = [0.0f32, 0.0, 1.0];
    for (energy, expected) in [
        (Energy::Exact, 0.5),
        (Energy::Printed, {
            let x = 1.0 / (1.5f64 * 0.526).powi(2);
            0.5 / ((1.0 + x) * (1.0 + x))
        }),
    ] {
        let model = Hp15::new(&tables.smith, params, lambda, energy);
        // ∫ ρ cos dω = ∫₀¹ 2π ρ(μ) μ dμ (ρ is rotationally symmetric here).
        let integral = generator::quad::integrate(
            |mu| {
                let o = [(1.0 - mu * mu).max(0.0).sqrt() as f32, 0.0, mu as f32];
                2.0 * PI * f64::from(model.eval(i, o)) * mu
            },
            0.0,
            1.0,
            generator::quad::Tolerance::new(1e-9, 1e-7),
        )
        .unwrap()
        .value;
        eprintln!(
            "HP15 {energy:?}: diffraction albedo at normal incidence {integral:.6} (expected {expected:.6})"
        );
        assert!(
            (integral - expected).abs() < 2e-4,
            "{energy:?}: {integral} vs {expected}"
        );
    }
    let params = Hp15Params {
        beta: 0.1,
        p: 0.8,
        a: 1.5,
        kd: 0.2,
        ks: 0.6,
        kw: 0.01,
        f0: 0.9,
    };
    let model = Hp15::new(&tables.smith, params, lambda, Energy::Exact);
    let alpha = suite::sidak(0.01, 2);
    for (k, deg) in [20.0, 80.0].into_iter().enumerate() {
        let i = from_angles(f64::to_radians(deg), 0.0);
        let check = chi_square_sampler(
            i,
            |u| model.sample(i, u).map(|s| s.0),
            |o| f64::from(model.pdf(i, o)),
            1_000_000,
            0.2,
            k as u64,
        );
        eprintln!(
            "HP15 χ² θi = {deg}°: p = {:.4}, ∫pdf = {:.6}",
            check.chi.p_value, check.pdf_integral
        );
        assert!(
            check.chi.p_value >= alpha,
            "HP15 θi = {deg}: p = {}",
            check.chi.p_value
        );
        assert!(check.pdf_integral <= 1.0 + 1e-5);
    }
}

/// `eval`, `pdf`, `sample` never NaN/∞ (and ≥ 0) over a dense sweep of
/// directions, grazing and exactly horizontal ones included, for extreme
/// materials and every base layer and option.
#[test]
fn never_nan_over_dense_sweep() {
    let set = twoscale::TableSet::embedded();
    let stub = NarrowNdfConvolution;
    let tables = set.brdf_tables_with(&stub);
    let thetas: Vec<f64> = (0..=40)
        .map(|k| PI / 2.0 * k as f64 / 40.0)
        .chain([
            PI / 2.0 - 1e-7,
            PI / 2.0 - 1e-4,
            PI / 2.0,
            PI / 2.0 + 1e-6,
            1e-8,
        ])
        .collect();
    let layers = [
        conductor(surface(1e-4, 0.2, 0.5, 0.01, 1.001)),
        conductor(surface(10.0, 5.0, 1.0, 100.0, 100.0)),
        conductor(surface(0.002, 5.0, 0.0, 0.0, 0.5)),
        Layer {
            surface: surface(0.05, 1.0, 0.02, 3.0, 2.0),
            base: BaseLayer::Plastic { albedo: 1.0 },
            lambertian: 1.0,
        },
        Layer {
            surface: surface(0.05, 1.0, 0.02, 3.0, 2.0),
            base: BaseLayer::Subsurface { albedo: 1.0 },
            lambertian: 0.0,
        },
    ];
    let etas = [
        Complex::new(0.05, 10.0),
        Complex::real(1.0),
        Complex::real(3.0),
        Complex::new(1e9, 0.0),
    ];
    let options = [
        Options::default(),
        Options {
            masking: Masking::HeightCorrelated,
            sigma_rel: SigmaRelMode::Symmetrised,
            colour: ColourTerms::White,
            halo_weight: HaloWeight::Incident,
            multiple_scattering: MultipleScattering::KullaConty,
        },
    ];
    let mut count = 0usize;
    for layer in layers {
        for eta in etas {
            for opt in options {
                for lambda in [0.444f32, 5.0] {
                    let model = TwoScale::new(&tables, layer, lambda, eta, opt);
                    for &ti in &thetas {
                        let i = from_angles(ti, 0.0);
                        for &to in thetas.iter().step_by(3) {
                            for phi in [0.0, 1.0, PI, PI + 1e-6] {
                                let o = from_angles(to, phi);
                                let v = model.eval(i, o);
                                let p = model.pdf(i, o);
                                assert!(
                                    v.is_finite() && v >= 0.0,
                                    "eval {v} at {i:?} {o:?} {layer:?} {eta:?}"
                                );
                                assert!(p.is_finite() && p >= 0.0, "pdf {p} at {i:?} {o:?}");
                                count += 1;
                            }
                        }
                        for u in [
                            [0.0f32, 0.0, 0.0],
                            [0.5, 0.5, 0.5],
                            [1.0, 1.0, 1.0],
                            [0.999_999, 0.3, 0.999_999],
                        ] {
                            if let Some(s) = model.sample(i, u) {
                                assert!(
                                    s.pdf.is_finite()
                                        && s.pdf > 0.0
                                        && s.value.is_finite()
                                        && s.o[2] > 0.0,
                                    "{s:?}"
                                );
                            }
                        }
                    }
                }
            }
        }
    }
    eprintln!("{count} evaluations, all finite");
}

/// The runtime (`f32`, T1, T2) against the f64 reference (exact Λ, σrel, C)
/// at random parameters in the HP17 range; C is exact on both sides
/// (`ExactConvolution`), so this measures T1, T2 and f32 rounding.
#[test]
fn runtime_matches_reference() {
    let set = twoscale::TableSet::embedded();
    let exact = ExactConvolution;
    let tables = set.brdf_tables_with(&exact);
    let mut rng = SplitMix64::new(2024);
    let mut errors = Vec::new();
    let mut worst = (0.0, String::new());
    while errors.len() < 150 {
        let params = reference::Params {
            beta: rng.log_uniform_in(0.02, 0.5),
            p: rng.uniform_in(0.5, 3.0),
            sigma_s: rng.log_uniform_in(0.005, 0.08),
            b: rng.log_uniform_in(1.0, 15.0),
            c: rng.uniform_in(1.5, 4.0),
            n: rng.uniform_in(0.1, 2.5),
            k: rng.uniform_in(0.5, 5.0),
            lambda: rng.uniform_in(0.444, 0.645),
        };
        let f = |v: f64| v as f32;
        let model = TwoScale::conductor(
            &tables,
            surface(
                f(params.beta),
                f(params.p),
                f(params.sigma_s),
                f(params.b),
                f(params.c),
            ),
            f(params.lambda),
            Complex::new(f(params.n), f(params.k)),
        );
        let i = random_direction(&mut rng);
        let o = if rng.uniform() < 0.5 {
            let m = model
                .ndf()
                .sample([rng.uniform() as f32, rng.uniform() as f32]);
            let k = 2.0 * (i[0] * m[0] + i[1] * m[1] + i[2] * m[2]);
            [k * m[0] - i[0], k * m[1] - i[1], k * m[2] - i[2]]
        } else {
            random_direction(&mut rng)
        };
        if !(o[2] > 1e-3 && i[2] > 1e-3) {
            continue;
        }
        // The reference sees the same f32 inputs the runtime sees.
        let r = |v: f64| f64::from(v as f32);
        let p32 = reference::Params {
            beta: r(params.beta),
            p: r(params.p),
            sigma_s: r(params.sigma_s),
            b: r(params.b),
            c: r(params.c),
            n: r(params.n),
            k: r(params.k),
            lambda: r(params.lambda),
        };
        let expected = reference::two_scale(
            &p32,
            i.map(f64::from),
            o.map(f64::from),
            &Options::default(),
        )
        .expect("reference")
        .total();
        if expected < 1e-6 {
            continue;
        }
        let got = f64::from(model.eval(i, o));
        let rel = (got - expected).abs() / expected;
        if rel > worst.0 {
            worst = (
                rel,
                format!("{p32:?} i = {i:?} o = {o:?}: {got} vs {expected}"),
            );
        }
        errors.push(rel);
    }
    errors.sort_by(f64::total_cmp);
    let median = errors[errors.len() / 2];
    let p95 = errors[errors.len() * 95 / 100];
    let max = errors[errors.len() - 1];
    eprintln!(
        "runtime vs reference, {} points: median {median:.2e}, p95 {p95:.2e}, max {max:.2e}\n  worst: {}",
        errors.len(),
        worst.1
    );
    assert!(
        median <= 1e-4 && p95 <= 1e-3 && max <= 1e-2,
        "median {median:e}, p95 {p95:e}, max {max:e}"
    );
}

/// The specular lobe of a very narrow material (β = 0.004, p = 0.6) at
/// θi = 87°, 10⁶ samples. This case once failed (p ≈ 1e-26, ∫ pdf = 0.99965
/// against a success rate of 0.99995) because of the test, not the runtime:
/// at grazing incidence the lobe is a ridge along the plane of incidence,
/// 1/(2 cos θi) ≈ 10 times longer than wide, lying on the χ² cells' sector
/// edges, and a single 8-point rule per sector missed it in the tail
/// (`suite::brdf::chi_square_sampler` now integrates each sector in four
/// parts; refined further, ∫ pdf moves by < 5e-7).
#[test]
fn narrow_grazing_specular_sampling() {
    let set = twoscale::TableSet::embedded();
    let stub = NarrowNdfConvolution;
    let tables = set.brdf_tables_with(&stub);
    let model = TwoScale::conductor(
        &tables,
        surface(0.004, 0.6, 0.008, 2.0, 1.8),
        0.526,
        NICKEL_LIKE,
    );
    let i = from_angles(f64::to_radians(87.0), 1.1);
    let n = 1_000_000;
    let check = chi_square_sampler(
        i,
        |u| model.sample_lobe(Lobe::Specular, i, [u[1], u[2]]),
        |o| f64::from(model.pdf_lobe(Lobe::Specular, i, o)),
        n,
        0.008,
        7,
    );
    eprintln!(
        "narrow, θi = 87°, specular: p = {:.4}, ∫pdf = {:.7}, sampled {:.7}",
        check.chi.p_value, check.pdf_integral, check.success
    );
    assert!(check.chi.p_value >= 0.01, "p = {}", check.chi.p_value);
    check.assert_pdf_is_the_success_rate(n, 5e-6, "narrow, θi = 87°");
}

/// Prints `check` and whether it fails: χ² below `alpha`, `∫ pdf` above
/// `1 + 1e-5`, or `∫ pdf` off the success rate by more than 5 standard
/// errors of `n` draws (+ 5e-5, the cell rule's error).
fn sampler_check_fails(
    label: &str,
    check: &suite::brdf::SamplerCheck,
    n: usize,
    alpha: f64,
) -> bool {
    eprintln!(
        "{label}: p-value {:.4} (χ² {:.1}, dof {}), ∫pdf = {:.6}, sampled {:.6}",
        check.chi.p_value, check.chi.statistic, check.chi.dof, check.pdf_integral, check.success
    );
    let se = (check.success * (1.0 - check.success) / n as f64).sqrt();
    check.chi.p_value < alpha
        || check.pdf_integral > 1.0 + 1e-5
        || (check.pdf_integral - check.success).abs() > 5.0 * se + 5e-5
}

/// The visible-normal sampler of the specular lobe (docs/model.md §2.1)
/// against its pdf: χ² and `∫ pdf` = success rate for p ∈ {0.3, 1, 4}, a
/// narrow (β = 0.01) and a wide (β = 1) lobe, θi ∈ {45°, 85°}, 4·10⁵
/// samples each.
#[test]
fn visible_normal_sampling_chi2() {
    let set = twoscale::TableSet::embedded();
    let stub = NarrowNdfConvolution;
    let tables = set.brdf_tables_with(&stub);
    let mut cases = Vec::new();
    for p in [0.3f32, 1.0, 4.0] {
        for beta in [0.01f32, 1.0] {
            for deg in [45.0, 85.0] {
                cases.push((p, beta, deg));
            }
        }
    }
    let alpha = suite::sidak(0.01, cases.len());
    let n = 400_000;
    let mut failures = Vec::new();
    for (k, &(p, beta, deg)) in cases.iter().enumerate() {
        let model =
            TwoScale::conductor(&tables, surface(beta, p, 0.0, 1.0, 2.0), 0.526, NICKEL_LIKE);
        let i = from_angles(f64::to_radians(deg), 0.4);
        let check = chi_square_sampler(
            i,
            |u| model.sample_lobe(Lobe::Specular, i, [u[1], u[2]]),
            |o| f64::from(model.pdf_lobe(Lobe::Specular, i, o)),
            n,
            // Cells from β/16: the narrow flat-topped p = 4 lobe at 85° needs
            // them for the cell rule's ∫pdf to settle within 1e-5 (it moved
            // from 0.99994 to 1.000014 to 1.000009 with cells from β/4, β/8, β/16).
            0.5 * f64::from(beta),
            k as u64 + 300,
        );
        let label = format!("visible normals p = {p}, β = {beta}, θi = {deg}°");
        if sampler_check_fails(&label, &check, n, alpha) {
            failures.push((
                p,
                beta,
                deg,
                check.chi.p_value,
                check.pdf_integral,
                check.success,
            ));
        }
    }
    assert!(failures.is_empty(), "{failures:?}");
}

/// The material slice of T3b (`ConvTable::slice`, which the per-material bake
/// samples) gives the full 4-D lookup's values: the tensor-product
/// interpolation is separable, so only f32 rounding differs.
#[test]
fn t3b_material_slice_gives_the_full_lookup_values() {
    let set = twoscale::TableSet::embedded();
    let table = set.convolution;
    let mut rng = SplitMix64::new(77);
    let mut worst = 0.0f64;
    for &(beta, p, c) in &[
        (0.0598f32, 1.0f32, 2.0f32),
        (0.3, 0.4, 1.2),
        (0.02, 4.0, 6.0),
    ] {
        let slice = table.slice(c, beta, p).expect("slice");
        for _ in 0..4000 {
            let tau = (rng.uniform() * 1.5).tan();
            let u = (rng.uniform() * 40.0) as f32;
            let (x, y) = (slice.at_tan(tau, u), table.at_tan(tau, u, c, beta, p));
            assert!(x.is_finite());
            if y > 1e-30 {
                worst = worst.max(f64::from(x / y - 1.0).abs());
            }
        }
    }
    eprintln!("C, slice vs full T3b lookup: max relative difference {worst:.2e}");
    assert!(worst < 1e-4, "{worst}");
}

/// The diffraction lobe's sampler (the spectrum's draw mixed with the
/// half-vector draw of the C bake, docs/design/halo-sampling.md) against its
/// pdf with the embedded T3b (so that C is baked): χ² and `∫ pdf` = success
/// rate for HP17's geometry and strong halos (σs 0.1 µm; b 1–20 µm; β
/// 0.01–0.5; p 0.6–2), θi ∈ {0°, 60°, 85°}, 3·10⁵ samples each; and the
/// whole model (lobe choice by energy) at 85°.
#[test]
fn halo_sampling_chi2() {
    let set = twoscale::TableSet::embedded();
    let tables = set.brdf_tables();
    let gold = Complex::new(0.58, 2.15);
    let surfaces = [
        surface(0.0598, 1.0, 0.0273, 4.8418, 2.0),
        surface(0.1, 1.0, 0.1, 3.0, 1.6),
        surface(0.01, 0.6, 0.1, 1.0, 2.0),
        surface(0.5, 2.0, 0.1, 20.0, 2.0),
    ];
    let mut cases = Vec::new();
    for (k, s) in surfaces.iter().enumerate() {
        for deg in [0.0, 60.0, 85.0] {
            cases.push((k, *s, deg, Some(Lobe::Diffraction)));
        }
        cases.push((k, *s, 85.0, None));
    }
    let alpha = suite::sidak(0.01, cases.len());
    let n = 300_000;
    let mut failures = Vec::new();
    for (seed, &(k, s, deg, lobe)) in cases.iter().enumerate() {
        let model = TwoScale::conductor(&tables, s, 0.526, gold);
        let i = from_angles(f64::to_radians(deg), 0.3);
        let scale = 0.5 * f64::from(s.beta);
        let check = chi_square_two_scale(&model, lobe, i, n, scale, seed as u64 + 900);
        let label = format!("halo surface {k}, θi = {deg}°, {lobe:?}");
        if sampler_check_fails(&label, &check, n, alpha) {
            failures.push((
                k,
                deg,
                lobe,
                check.chi.p_value,
                check.pdf_integral,
                check.success,
            ));
        }
    }
    assert!(failures.is_empty(), "{failures:?}");
}

/// `sample` shares the lobe weights and the visible-normal sampler's
/// per-incidence quantities between its draw and its pdf (issue 24): its
/// pdf and value must still be exactly `pdf(i, o)` and `eval(i, o)`, for
/// T3b's halo sampler and the spectrum's alone, with and without a base.
#[test]
fn sample_returns_pdf_and_eval_exactly() {
    let set = twoscale::TableSet::embedded();
    let stub = NarrowNdfConvolution;
    let tables = [set.brdf_tables(), set.brdf_tables_with(&stub)];
    let layers = [
        conductor(surface(0.0598, 1.0, 0.0273, 4.8418, 2.0)),
        Layer {
            surface: surface(0.3, 0.5, 0.06, 3.0, 2.2),
            base: BaseLayer::Plastic { albedo: 0.8 },
            lambertian: 0.05,
        },
    ];
    let mut rng = SplitMix64::new(24);
    let mut drawn = 0;
    for tables in &tables {
        for layer in layers {
            let model = TwoScale::new(tables, layer, 0.526, NICKEL_LIKE, Options::default());
            for _ in 0..2000 {
                let i = random_direction(&mut rng);
                let u = [0; 3].map(|_| rng.uniform() as f32);
                let Some(s) = model.sample(i, u) else {
                    continue;
                };
                drawn += 1;
                assert_eq!(s.pdf, model.pdf(i, s.o), "pdf at {i:?} {u:?}");
                assert_eq!(s.value, model.eval(i, s.o), "eval at {i:?} {u:?}");
            }
        }
    }
    assert!(drawn > 7000, "{drawn} of 8000 drawn");
}
