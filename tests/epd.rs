//! The EPD distribution of the runtime (D, G1 from T1, sampling) against the
//! f64 reference of the generator: normalisation, T1 accuracy at random
//! points, monotonicity, edge cases, sampling accuracy and a χ² test.

use generator::quad::{Tolerance, integrate, integrate_to_infinity};
use generator::reference::epd as reference;
use generator::rng::SplitMix64;
use twoscale::model::epd::Epd;
use twoscale::{SmithG1Table, TableId};

fn with_t1<R>(f: impl FnOnce(&SmithG1Table<'_>) -> R) -> R {
    let buf = suite::read_table(TableId::SmithG1);
    let table = SmithG1Table::from_bytes(buf.bytes()).expect("valid T1");
    f(&table)
}

/// (β, p) pairs covering the extremes: narrow and wide lobes, heavy and light tails.
const MATERIALS: [(f32, f32); 7] = [
    (0.002, 0.2),
    (0.002, 1.0),
    (0.05, 0.35),
    (0.3, 1.0),
    (0.5, 0.2),
    (1.0, 5.0),
    (0.1, 2.0),
];

/// ∫ D(m) cos θm dω = 1 (HP17 35), integrated in s = tan θ / β so that narrow
/// lobes are resolved: dω = 2π sin θ dθ, θ = atan(β s).
#[test]
fn ndf_is_normalised() {
    with_t1(|t1| {
        for (beta, p) in MATERIALS {
            let epd = Epd::new(beta, p, t1);
            let b = f64::from(beta);
            let integrand = |s: f64| {
                let theta = (b * s).atan();
                let d = f64::from(epd.d([theta.sin() as f32, 0.0, theta.cos() as f32]));
                2.0 * std::f64::consts::PI * d * theta.cos() * theta.sin() * b
                    / (1.0 + b * b * s * s)
            };
            // The integrand is the f32 runtime D: its rounding noise (~1e-7) limits
            // the attainable tolerance.
            let tol = Tolerance {
                abs: 1e-10,
                rel: 1e-6,
            };
            let total = integrate(integrand, 0.0, 1.0, tol).unwrap().value
                + integrate_to_infinity(integrand, 1.0, tol).unwrap().value;
            eprintln!("β = {beta}, p = {p}: ∫ D cos dω = {total:.9}");
            assert!(
                (total - 1.0).abs() < 2e-6,
                "β = {beta}, p = {p}: ∫ D cos = {total}"
            );
        }
    });
}

/// T1 against the f64 reference at random off-grid points over the whole
/// domain (the same measurement as `generator verify`, other points).
#[test]
fn t1_is_within_target_at_random_points() {
    with_t1(|t1| {
        let points = generator::tables::smith_g1::verification_points(6000, 12345);
        let mut worst = (0.0f64, 0.0, 0.0);
        for (p, a) in points {
            let reference = reference::g1(p, a).unwrap();
            let error = (f64::from(t1.g1(p as f32, a as f32)) - reference).abs();
            if error > worst.0 {
                worst = (error, p, a);
            }
        }
        assert!(
            worst.0 <= 2e-5,
            "max |G1 - ref| = {:.3e} at p = {}, a = {}",
            worst.0,
            worst.1,
            worst.2
        );
    });
}

/// The reference values printed in docs/model.md §2.2, read from the table.
#[test]
fn t1_reproduces_the_spec_table() {
    let spec = [
        (0.2, [0.327394, 0.125425, 0.0394837, 0.0133408, 0.00402117]),
        (0.5, [0.999994, 0.989655, 0.782051, 0.406211, 0.145305]),
        (1.0, [1.0, 1.0, 0.975489, 0.695114, 0.298587]),
        (5.0, [1.0, 1.0, 0.999798, 0.812317, 0.383556]),
    ];
    with_t1(|t1| {
        for (p, row) in spec {
            for (a, want) in [0.1f32, 0.3, 1.0, 3.0, 10.0].into_iter().zip(row) {
                let got = f64::from(t1.g1(p, a));
                assert!(
                    (got - want).abs() < 2e-5,
                    "p = {p}, a = {a}: {got} vs {want}"
                );
            }
        }
    });
}

/// G1 ∈ [0, 1], non-increasing in a, continuous across the seam between the
/// table and the asymptote.
#[test]
fn g1_is_monotone_bounded_and_continuous() {
    with_t1(|t1| {
        let last = t1.scaled_axis().hi();
        for k in 0..=40 {
            let p = 0.2 + 4.8 * k as f32 / 40.0;
            let shape = t1.shape(p);
            let mut previous = 1.0f32;
            for i in 0..20_000 {
                let a = 1e-5f32 * 1e10f32.powf(i as f32 / 19_999.0);
                let g = shape.g1(a);
                assert!((0.0..=1.0).contains(&g), "p = {p}, a = {a}: G1 = {g}");
                assert!(
                    g <= previous + 1e-7,
                    "p = {p}: G1 rises at a = {a}: {previous} -> {g}"
                );
                previous = g;
            }
            let seam = last / shape.kappa();
            let below = shape.g1(seam * (1.0 - 1e-6));
            let above = shape.g1(seam * (1.0 + 1e-6));
            assert!(
                (below - above).abs() < 1e-6,
                "p = {p}: seam jump {below} -> {above}"
            );
        }
    });
}

#[test]
fn edge_cases_are_defined() {
    with_t1(|t1| {
        for p in [0.2f32, 1.0, 5.0] {
            assert_eq!(t1.g1(p, 0.0), 1.0);
            assert_eq!(t1.g1(p, -1.0), 1.0);
            assert_eq!(t1.g1(p, f32::NAN), 1.0);
            assert_eq!(t1.g1(p, f32::INFINITY), 0.0);
            assert!(t1.lambda(p, f32::MAX).is_finite());
        }
        // p clamps to the table's domain.
        assert_eq!(t1.g1(0.01, 0.5), t1.g1(0.2, 0.5));
        assert_eq!(t1.g1(100.0, 0.5), t1.g1(5.0, 0.5));
        assert_eq!(t1.g1(f32::NAN, 0.5), t1.g1(0.2, 0.5));
        let epd = Epd::new(0.3, 1.0, t1);
        let (horizon, below, normal) = ([1.0, 0.0, 0.0], [0.6, 0.0, -0.8], [0.0, 0.0, 1.0]);
        assert_eq!(epd.g1(horizon), 0.0);
        assert_eq!(epd.g1(below), 0.0);
        assert_eq!(epd.g1(normal), 1.0);
        assert_eq!(epd.lambda(horizon), f32::MAX);
        assert_eq!(epd.lambda(normal), 0.0);
        assert_eq!(epd.d(horizon), 0.0);
        assert_eq!(epd.d(below), 0.0);
        assert_eq!(epd.d([f32::NAN; 3]), 0.0);
        assert_eq!(epd.g_height_correlated(horizon, normal), 0.0);
        // Not a unit vector: cos⁴θ underflows to 0 while tan²θ = 0 (found by
        // the proptest in CI). D stays finite.
        for m in [[-0.0, 0.0, 1.5e-15], [0.0, 0.0, f32::MIN_POSITIVE]] {
            let lowest = Epd::new(0.0, 0.0, t1);
            assert!(
                lowest.d(m).is_finite() && lowest.pdf(m).is_finite(),
                "{m:?}"
            );
        }
    });
}

/// D, G1, G, pdf and sample are finite over a dense sweep including grazing,
/// horizontal and degenerate inputs, for extreme parameters.
#[test]
fn nothing_is_ever_nan_or_infinite() {
    with_t1(|t1| {
        for (beta, p) in
            MATERIALS
                .into_iter()
                .chain([(1e-6, 0.01), (1e6, 100.0), (f32::NAN, f32::NAN)])
        {
            let epd = Epd::new(beta, p, t1);
            let other = [0.6, 0.0, 0.8];
            for i in 0..=4000 {
                let c = -0.1 + 1.1 * i as f32 / 4000.0;
                for c in [c, 1e-30, 1e-10, f32::MIN_POSITIVE, 1.0 - f32::EPSILON] {
                    let w = [(1.0 - c * c).max(0.0).sqrt(), 0.0, c];
                    for v in [
                        epd.d(w),
                        epd.g1(w),
                        epd.lambda(w),
                        epd.g(w, other),
                        epd.g_height_correlated(w, w),
                        epd.pdf(w),
                    ] {
                        assert!(
                            v.is_finite() && v >= 0.0,
                            "β = {beta}, p = {p}, cos = {c}: {v}"
                        );
                    }
                }
            }
            for u in [
                0.0f32,
                1e-30,
                0.5,
                1.0 - f32::EPSILON,
                1.0,
                2.0,
                -1.0,
                f32::NAN,
            ] {
                let m = epd.sample([u, u]);
                assert!(
                    m.iter().all(|x| x.is_finite()),
                    "β = {beta}, p = {p}, u = {u}: {m:?}"
                );
                assert!(m[2] > 0.0, "sample below or on the horizon: {m:?}");
                assert!(epd.pdf(m).is_finite());
            }
        }
    });
}

/// The polar angle of a sample against the f64 reference quantile
/// (docs/model.md §2.1): relative error of tan θm ≤ 1e-6.
#[test]
fn sampled_tan_theta_matches_the_reference() {
    with_t1(|t1| {
        let mut worst = 0.0f64;
        for (beta, p) in MATERIALS {
            let epd = Epd::new(beta, p, t1);
            for i in 0..2000 {
                let u = (i as f32 + 0.5) / 2000.0;
                for u in [u, u * 1e-6, 1.0 - u * 1e-3] {
                    let got = f64::from(epd.sample_tan_theta(u));
                    // The runtime maps u to Q⁻¹(1/p, 1 − u); the reference takes Q's argument.
                    let want = reference::sample_tan_theta(
                        f64::from(beta),
                        f64::from(p),
                        1.0 - f64::from(u),
                    )
                    .unwrap();
                    let rel = ((got - want) / want).abs();
                    worst = worst.max(rel);
                    assert!(rel <= 1e-6, "β = {beta}, p = {p}, u = {u}: {got} vs {want}");
                }
            }
        }
        eprintln!("max relative error of tan θm: {worst:.2e}");
    });
}

/// χ² goodness of fit of `sample` against `pdf` (docs/model.md §7): 10⁶ samples per
/// material, cells of equal reference probability in θ × 8 cells in φ,
/// expected counts from the runtime pdf integrated by quadrature, cells with
/// fewer than 5 expected pooled, Šidák-corrected α = 0.01 over the materials.
#[test]
fn samples_follow_the_pdf() {
    const SAMPLES: usize = 1_000_000;
    const THETA_CELLS: usize = 40;
    const PHI_CELLS: usize = 8;
    let alpha = suite::sidak(0.01, MATERIALS.len());
    with_t1(|t1| {
        let mut rng = SplitMix64::new(7);
        for (beta, p) in MATERIALS {
            let epd = Epd::new(beta, p, t1);
            // θ cell edges at reference quantiles (edges only balance the
            // counts; correctness rests on the integrated pdf below).
            let mut edges: Vec<f64> = (0..=THETA_CELLS)
                .map(|k| {
                    let u = k as f64 / THETA_CELLS as f64;
                    reference::sample_tan_theta(
                        f64::from(beta),
                        f64::from(p),
                        (1.0 - u).max(1e-300),
                    )
                    .unwrap()
                    .atan()
                })
                .collect();
            edges[THETA_CELLS] = std::f64::consts::FRAC_PI_2;
            let mut observed = vec![0.0; THETA_CELLS * PHI_CELLS];
            for _ in 0..SAMPLES {
                let m = epd.sample([rng.uniform() as f32, rng.uniform() as f32]);
                // θ from all components: acos(z) alone is too coarse near the normal in f32.
                let theta = f64::from(m[0])
                    .hypot(f64::from(m[1]))
                    .atan2(f64::from(m[2]));
                let phi = f64::from(m[1])
                    .atan2(f64::from(m[0]))
                    .rem_euclid(std::f64::consts::TAU);
                let i = edges.partition_point(|&e| e <= theta).clamp(1, THETA_CELLS) - 1;
                let j =
                    ((phi / std::f64::consts::TAU * PHI_CELLS as f64) as usize).min(PHI_CELLS - 1);
                observed[i * PHI_CELLS + j] += 1.0;
            }
            let mut expected = Vec::with_capacity(observed.len());
            let mut total = 0.0;
            for k in 0..THETA_CELLS {
                let density = |theta: f64| {
                    f64::from(epd.pdf([theta.sin() as f32, 0.0, theta.cos() as f32])) * theta.sin()
                };
                let mass = integrate(
                    density,
                    edges[k],
                    edges[k + 1],
                    Tolerance {
                        abs: 1e-10,
                        rel: 1e-6,
                    },
                )
                .unwrap()
                .value
                    * std::f64::consts::TAU;
                total += mass;
                for _ in 0..PHI_CELLS {
                    expected.push(mass / PHI_CELLS as f64 * SAMPLES as f64);
                }
            }
            assert!(
                (total - 1.0).abs() < 1e-5,
                "β = {beta}, p = {p}: ∫ pdf = {total}"
            );
            let test = suite::chi_square(&observed, &expected, 5.0);
            eprintln!(
                "β = {beta}, p = {p}: χ² = {:.1}, dof = {}, p-value = {:.3}",
                test.statistic, test.dof, test.p_value
            );
            assert!(
                test.p_value >= alpha,
                "β = {beta}, p = {p}: {test:?} (α = {alpha:.2e})"
            );
        }
    });
}
