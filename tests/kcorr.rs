//! T2 (σrel/σs of the K-correlation spectrum) through the runtime: accuracy at
//! random points against the f64 reference, the documented behaviour outside
//! the table's domain, and the spectrum type.

use generator::reference::kcorr as reference;
use twoscale::tables::sigma_ratio::normal_incidence_ratio;
use twoscale::{KCorrelation, SigmaRatioTable, TableId};

fn with_t2<R>(f: impl FnOnce(&SigmaRatioTable<'_>) -> R) -> R {
    let buf = suite::read_table(TableId::SigmaRatio);
    let table = SigmaRatioTable::from_bytes(buf.bytes()).expect("valid T2");
    f(&table)
}

fn rel(a: f64, b: f64) -> f64 {
    ((a - b) / b).abs()
}

/// The same measurement as `generator verify`, at other points.
#[test]
fn t2_is_within_target_at_random_points() {
    with_t2(|t2| {
        let mut worst = (0.0f64, 0.0, 0.0, 0.0);
        for (cos_theta_i, big_b, c) in
            generator::tables::sigma_ratio::verification_points(4000, 777)
        {
            let reference = reference::sigma_ratio(cos_theta_i.acos(), big_b, c).unwrap();
            let got = f64::from(t2.sigma_ratio_cos(cos_theta_i as f32, big_b as f32, c as f32));
            if rel(got, reference) > worst.0 {
                worst = (rel(got, reference), cos_theta_i, big_b, c);
            }
        }
        assert!(worst.0 <= 1e-4, "max relative error {worst:?}");
    });
}

/// B → 0 is linear in B (r → B √((c−1)/2)); the small-B rule joins the table
/// continuously at B = 0.05.
#[test]
fn small_b_is_linear_and_continuous() {
    with_t2(|t2| {
        for theta_i in [0.0f32, 0.6, 1.2, 1.5] {
            for c in [1.01f32, 2.5, 40.0] {
                let slope = (f64::from(c - 1.0) / 2.0).sqrt();
                for big_b in [1e-3f32, 1e-2] {
                    let got = f64::from(t2.sigma_ratio(theta_i, big_b, c));
                    let reference =
                        reference::sigma_ratio(f64::from(theta_i), f64::from(big_b), f64::from(c))
                            .unwrap();
                    assert!(
                        rel(got, reference) < 1e-4,
                        "θi {theta_i} B {big_b} c {c}: {got} vs {reference}"
                    );
                    assert!(
                        rel(got, slope * f64::from(big_b)) < 0.05 * f64::from(big_b / 1e-3),
                        "not linear"
                    );
                }
                let below = t2.sigma_ratio(theta_i, 0.05 * (1.0 - 1e-5), c);
                let above = t2.sigma_ratio(theta_i, 0.05 * (1.0 + 1e-5), c);
                assert!(
                    (below / above - 1.0).abs() < 1e-4,
                    "seam at B = 0.05: {below} vs {above}"
                );
            }
        }
    });
}

/// B → ∞ tends to 1 (θi < π/2), continuously from the last node; c > 100 and
/// other out-of-domain inputs stay finite and in [0, 1].
#[test]
fn large_b_and_other_edges() {
    with_t2(|t2| {
        for theta_i in [0.0f32, 0.7, 1.3] {
            for c in [1.5f32, 3.0, 50.0] {
                let at_seam = t2.sigma_ratio(theta_i, 3000.0, c);
                let past_seam = t2.sigma_ratio(theta_i, 3000.0 * (1.0 + 1e-5), c);
                assert!((at_seam / past_seam - 1.0).abs() < 1e-4, "seam at B = 3000");
                let far = t2.sigma_ratio(theta_i, 1e30, c);
                assert!(
                    (far - 1.0).abs() < 1e-3,
                    "θi {theta_i} c {c}: B = 1e30 gives {far}"
                );
            }
        }
        let at_100 = t2.sigma_ratio(0.5, 10.0, 100.0);
        let past_100 = t2.sigma_ratio(0.5, 10.0, 100.0 * (1.0 + 1e-6));
        assert!((at_100 / past_100 - 1.0).abs() < 1e-4, "seam at c = 100");
        let c_200 = f64::from(t2.sigma_ratio(0.5, 10.0, 200.0));
        assert!(rel(c_200, reference::sigma_ratio(0.5, 10.0, 200.0).unwrap()) < 0.05);
        assert_eq!(t2.sigma_ratio(0.5, 10.0, 1.0), 0.0);
        assert_eq!(t2.sigma_ratio(0.5, 10.0, 0.5), 0.0);
        assert_eq!(t2.sigma_ratio(0.5, 0.0, 3.0), 0.0);
        assert_eq!(t2.sigma_ratio(0.5, -1.0, 3.0), 0.0);
        for x in [
            f32::NAN,
            f32::INFINITY,
            f32::NEG_INFINITY,
            f32::MAX,
            -f32::MAX,
            0.0,
            1e-30,
        ] {
            for v in [
                t2.sigma_ratio(x, 10.0, 3.0),
                t2.sigma_ratio(0.5, x, 3.0),
                t2.sigma_ratio(0.5, 10.0, x),
                t2.sigma_ratio_cos(x, x, x),
            ] {
                assert!(
                    v.is_finite() && (0.0..=1.0 + 1e-6).contains(&v),
                    "input {x}: {v}"
                );
            }
        }
    });
}

/// The normal-incidence closed form in f64 and the spectrum of the runtime.
#[test]
fn spectrum_and_closed_form() {
    for (big_b, c) in [(0.1, 1.01), (4.8, 2.3), (3000.0, 100.0)] {
        let want = reference::sigma_ratio_sq_normal(big_b, c).sqrt();
        assert!(rel(normal_incidence_ratio(big_b, c), want) < 1e-14);
    }
    let spectrum = KCorrelation {
        sigma_s: 0.0273,
        b: 4.8418,
        c: 2.3,
    };
    let exact = reference::KCorrelation {
        sigma_s: 0.0273,
        b: 4.8418,
        c: 2.3,
    };
    for f in [0.0f32, 0.1, 1.0, 10.0, 1e4] {
        let got = f64::from(spectrum.spectrum(f));
        assert!(rel(got, exact.spectrum(f64::from(f))) < 1e-5, "f = {f}");
    }
    with_t2(|t2| {
        // HP17's nickel at 0.5 µm, 30° incidence.
        let got = f64::from(spectrum.sigma_rel(t2, 0.5, 30f32.to_radians().cos()));
        let want = exact.sigma_rel(0.5, 30f64.to_radians()).unwrap();
        assert!(rel(got, want) < 1e-4, "{got} vs {want}");
    });
}

/// `sigma_ratio_cos_many` (one (B, c) blend, then a 1-D spline per incidence)
/// gives `sigma_ratio_cos`'s values up to f32 rounding, inside and outside the
/// table's domain (small and large B, c > 100, no diffraction).
#[test]
fn many_incidences_match_one_at_a_time() {
    with_t2(|t2| {
        let cosines: Vec<f32> = (0..=400)
            .map(|k| (k as f32 / 400.0).powi(2))
            .chain([-0.5, 1.5, f32::NAN])
            .collect();
        let mut worst = (0.0f64, 0.0f32, 0.0f32, 0.0f32);
        for (big_b, c) in [
            (9.2f32, 2.0f32),
            (0.01, 3.0),
            (0.05, 1.01),
            (40.0, 8.0),
            (3000.0, 100.0),
            (9000.0, 2.5),
            (5.0, 150.0),
            (5.0, 1.0),
            (0.0, 2.0),
        ] {
            let mut many = vec![0.0f32; cosines.len()];
            t2.sigma_ratio_cos_many(&cosines, big_b, c, &mut many);
            for (&cos, &got) in cosines.iter().zip(&many) {
                let one = t2.sigma_ratio_cos(cos, big_b, c);
                let e = if one == 0.0 {
                    f64::from(got.abs())
                } else {
                    rel(f64::from(got), f64::from(one))
                };
                if e > worst.0 {
                    worst = (e, cos, big_b, c);
                }
            }
        }
        assert!(worst.0 <= 1e-6, "{worst:?}");
    });
}
