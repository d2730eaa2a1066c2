//! The runtime's Fresnel factor, diffraction colour term Q̄ and T5 against the
//! f64 reference: a dense (n, k, cos θ) sweep, Q̄ = F in the specular
//! direction, Q̄ finite everywhere, T5 at random points and out of range, and
//! `generator query fresnel`.

use generator::query;
use generator::reference::fresnel as reference;
use generator::reference::fresnel::Complex64;
use generator::rng::SplitMix64;
use generator::table_source::TableSource;
use twoscale::model::fresnel::{fresnel, q_bar};
use twoscale::{Complex, DiffuseFresnelTable, FormatError, TableId};

/// n ∈ [0.05, 10] log-spaced, with values straddling 1 and the f32 neighbours
/// of 1; k = 0 and k ∈ [1e-4, 20] log-spaced.
fn indices() -> Vec<(f32, f32)> {
    let mut ns: Vec<f32> = (0..48)
        .map(|j| (0.05f64 * (200.0f64).powf(j as f64 / 47.0)) as f32)
        .collect();
    ns.extend([
        0.999, 0.9999999, 1.0, 1.0000001, 1.001, 1.333, 1.5, 2.4, 0.2, 1.2,
    ]);
    let mut ks: Vec<f32> = vec![0.0];
    ks.extend((0..24).map(|j| (1e-4f64 * (2e5f64).powf(j as f64 / 23.0)) as f32));
    ns.iter()
        .flat_map(|&n| ks.iter().map(move |&k| (n, k)))
        .collect()
}

/// cos θ ∈ [0, 1]: a uniform grid, log-spaced values down to grazing, and
/// points next to the critical cosine of each dielectric below 1 (added per n).
fn cosines(n: f32, k: f32) -> Vec<f32> {
    let mut cs: Vec<f32> = (0..=100).map(|j| j as f32 / 100.0).collect();
    cs.extend((0..40).map(|j| (1e-8f64 * 1e8f64.powf(j as f64 / 39.0)) as f32));
    if k == 0.0 && n < 1.0 {
        let critical = (1.0 - f64::from(n) * f64::from(n)).sqrt();
        for d in [-1e-3, -1e-6, 0.0, 1e-6, 1e-3] {
            cs.push((critical + d).clamp(0.0, 1.0) as f32);
        }
    }
    cs
}

#[test]
fn fresnel_matches_the_reference_on_a_dense_sweep() {
    let mut worst = (0.0f64, 0.0f32, 0.0f32, 0.0f32);
    let mut points = 0usize;
    for (n, k) in indices() {
        for cos in cosines(n, k) {
            let got = fresnel(Complex::new(n, k), cos);
            assert!((0.0..=1.0).contains(&got));
            let Ok(want) =
                reference::fresnel(Complex64::new(f64::from(n), f64::from(k)), f64::from(cos))
            else {
                // The only indeterminate point: η = 1 at grazing incidence,
                // where the runtime answers 0 (no interface).
                assert!(n == 1.0 && k == 0.0 && cos == 0.0, "{n} {k} {cos}");
                assert_eq!(got, 0.0);
                continue;
            };
            points += 1;
            let error = (f64::from(got) - want).abs();
            if error > worst.0 {
                worst = (error, n, k, cos);
            }
        }
    }
    eprintln!(
        "fresnel: max |F − F_ref| = {:.3e} over {points} points (at n = {}, k = {}, cos θ = {})",
        worst.0, worst.1, worst.2, worst.3
    );
    assert!(worst.0 <= 1e-5, "{worst:?}");
    // In practice only the final rounding to f32 is left.
    assert!(worst.0 <= 1e-7, "{worst:?}");
}

/// A direction with polar angle from `cos θ` and azimuth φ, rounded to f32.
fn direction(cos_theta: f64, phi: f64) -> [f32; 3] {
    let sin_theta = (1.0 - cos_theta * cos_theta).max(0.0).sqrt();
    [
        (sin_theta * phi.cos()) as f32,
        (sin_theta * phi.sin()) as f32,
        cos_theta as f32,
    ]
}

fn widen(v: [f32; 3]) -> [f64; 3] {
    v.map(f64::from)
}

const MATERIALS: [(f32, f32); 8] = [
    (1.5, 0.0),
    (0.6667, 0.0),
    (0.05, 0.0),
    (10.0, 0.0),
    (0.2, 3.0),
    (1.2, 7.26),
    (0.05, 20.0),
    (10.0, 20.0),
];

#[test]
fn q_bar_matches_the_reference_at_random_directions() {
    let mut rng = SplitMix64::new(4242);
    let mut worst = (0.0f64, String::new());
    let mut largest = 0.0f64;
    for (n, k) in MATERIALS {
        let eta = Complex::new(n, k);
        let exact = Complex64::new(f64::from(n), f64::from(k));
        for m in 0..6000 {
            // Cosines uniform, or log-uniform down to 1e-6 (grazing), or 0.
            let mut cosine = || match m % 3 {
                0 => rng.uniform(),
                1 => rng.log_uniform_in(1e-6, 1.0),
                _ if rng.uniform() < 0.5 => 0.0,
                _ => rng.uniform(),
            };
            let (ci, co) = (cosine(), cosine());
            let phi_i = rng.uniform_in(-3.2, 3.2);
            // Half the outgoing azimuths near back-scattering (φo ≈ φi).
            let phi_o = if m % 2 == 0 {
                rng.uniform_in(-3.2, 3.2)
            } else {
                phi_i + rng.uniform_in(-1e-3, 1e-3)
            };
            let (i, o) = (direction(ci, phi_i), direction(co, phi_o));
            let got = f64::from(q_bar(eta, i, o));
            let want = reference::q_bar(exact, widen(i), widen(o)).unwrap();
            largest = largest.max(want);
            let error = (got - want).abs() / want.max(1e-3);
            if error > worst.0 {
                worst = (error, format!("η = {n}+{k}i, i = {i:?}, o = {o:?}"));
            }
        }
    }
    eprintln!(
        "q_bar: max |Q̄ − Q̄_ref| / max(Q̄_ref, 1e-3) = {:.3e} (largest Q̄ {largest:.1}) at {}",
        worst.0, worst.1
    );
    assert!(worst.0 <= 1e-5, "{worst:?}");
}

#[test]
fn q_bar_equals_fresnel_in_the_specular_direction() {
    let mut worst = 0.0f64;
    for (n, k) in MATERIALS {
        let eta = Complex::new(n, k);
        for deg in [0.0f64, 1.0, 20.0, 45.0, 60.0, 75.0, 85.0, 89.0, 89.99, 90.0] {
            for phi in [0.0f64, 0.9, 2.0, -2.7] {
                let cos = deg.to_radians().cos();
                let i = direction(cos, phi);
                let o = [-i[0], -i[1], i[2]];
                let (q, f) = (f64::from(q_bar(eta, i, o)), f64::from(fresnel(eta, i[2])));
                worst = worst.max((q - f).abs());
                assert!(
                    (q - f).abs() <= 1e-6,
                    "η = {n}+{k}i θ = {deg}° φ = {phi}: Q̄ {q} vs F {f}"
                );
            }
        }
    }
    eprintln!("specular: max |Q̄ − F| = {worst:.3e}");
}

/// Q̄ is finite and non-negative everywhere, grazing and back-scattering
/// included, and at double grazing back-scattering it reaches ≈ |η|⁴
/// (docs/model.md §7: Q̄ is not bounded by 1).
#[test]
fn q_bar_is_finite_everywhere() {
    let mut rng = SplitMix64::new(77);
    let specials = [0.0f32, -0.0, 1.0, -1.0, 1e-30, 1e-7, f32::MAX, f32::NAN];
    for (n, k) in MATERIALS
        .into_iter()
        .chain([(1.0, 0.0), (0.0, 0.0), (1e9, 1e9)])
    {
        let eta = Complex::new(n, k);
        for _ in 0..2000 {
            let i = [
                rng.uniform_in(-1.0, 1.0) as f32,
                rng.uniform_in(-1.0, 1.0) as f32,
                rng.uniform_in(-0.2, 1.0) as f32,
            ];
            for o in [
                i,
                [-i[0], -i[1], i[2]],
                [i[0], i[1], 0.0],
                [-i[1], i[0], 0.0],
            ] {
                let q = q_bar(eta, i, o);
                assert!(q.is_finite() && q >= 0.0, "η = {n}+{k}i {i:?} {o:?}: {q}");
            }
        }
        for &x in &specials {
            for &z in &specials {
                let q = q_bar(eta, [x, 0.0, z], [0.0, x, z]);
                assert!(q.is_finite() && q >= 0.0, "η = {n}+{k}i x {x} z {z}: {q}");
            }
        }
    }
    // Aluminium-like index: grazing back-scattering, Q̄ ≈ (1 + |1 − 2η²|²)/2.
    let eta = Complex::new(1.2, 7.26);
    let back = f64::from(q_bar(eta, [1.0, 0.0, 0.0], [1.0, 0.0, 0.0]));
    let eta_sq = Complex64::new(1.2 * 1.2 - 7.26 * 7.26, 2.0 * 1.2 * 7.26);
    let want = 0.5 * (1.0 + (1.0 - 2.0 * eta_sq.re).powi(2) + (2.0 * eta_sq.im).powi(2));
    assert!(((back - want) / want).abs() < 1e-5, "{back} vs {want}");
    assert!(back > 5000.0);
}

fn with_t5<R>(f: impl FnOnce(&DiffuseFresnelTable<'_>) -> R) -> R {
    let buf = suite::read_table(TableId::DiffuseFresnel);
    let table = DiffuseFresnelTable::from_bytes(buf.bytes()).expect("valid T5");
    f(&table)
}

/// The same measurement as `generator verify`, at other points.
#[test]
fn t5_is_within_target_at_random_points() {
    with_t5(|t5| {
        let mut worst = (0.0f64, 0.0f64);
        for eta in generator::tables::diffuse_fresnel::verification_points(4000, 555) {
            let want = reference::diffuse_internal(eta).unwrap();
            let error = (f64::from(t5.f_dr_int(eta as f32)) - want).abs();
            if error > worst.0 {
                worst = (error, eta);
            }
        }
        eprintln!(
            "t5: max |F_dr,int − ref| = {:.3e} at η = {}",
            worst.0, worst.1
        );
        assert!(worst.0 <= 1e-6, "{worst:?}");
    });
}

/// η outside [1, 3] clamps: below 1 (and NaN) gives F_dr,int(1) = 0, above 3
/// gives F_dr,int(3); the ends agree with the reference; the other tables'
/// files are refused.
#[test]
fn t5_clamps_out_of_range() {
    with_t5(|t5| {
        let at_1 = t5.f_dr_int(1.0);
        let at_3 = t5.f_dr_int(3.0);
        assert!(at_1.abs() < 1e-7, "{at_1}");
        assert!((f64::from(at_3) - reference::diffuse_internal(3.0).unwrap()).abs() < 1e-6);
        for eta in [0.999, 0.5, 0.0, -2.0, f32::NEG_INFINITY, f32::NAN] {
            assert_eq!(t5.f_dr_int(eta), at_1, "η = {eta}");
        }
        for eta in [3.0001, 4.0, 1e30, f32::INFINITY] {
            assert_eq!(t5.f_dr_int(eta), at_3, "η = {eta}");
        }
        // Monotone increasing on a fine grid (the physical function is).
        let values: Vec<f32> = (0..=4000)
            .map(|j| t5.f_dr_int(1.0 + 2.0 * j as f32 / 4000.0))
            .collect();
        assert!(values.windows(2).all(|w| w[1] >= w[0]));
    });
    let t1 = suite::read_table(TableId::SmithG1);
    assert!(matches!(
        DiffuseFresnelTable::from_bytes(t1.bytes()),
        Err(FormatError::WrongTable { .. })
    ));
}

fn run_query(input: &str) -> (query::Summary, String, String) {
    let (mut out, mut err) = (Vec::new(), Vec::new());
    let summary = query::run(
        "fresnel",
        &TableSource::Dir(suite::tables_dir()),
        &query::Options::default(),
        input.as_bytes(),
        &mut out,
        &mut err,
    )
    .unwrap();
    (
        summary,
        String::from_utf8(out).unwrap(),
        String::from_utf8(err).unwrap(),
    )
}

/// `generator query fresnel`: `table` is the runtime's value, `reference` the
/// f64 reference; rows outside the reference's domain are reported.
#[test]
fn query_fresnel() {
    let mut rng = SplitMix64::new(8);
    let mut input = String::from("cos_theta,n,k,label\n");
    for j in 0..100 {
        let n = rng.log_uniform_in(0.05, 10.0);
        let k = if j % 3 == 0 {
            0.0
        } else {
            rng.uniform_in(0.0, 20.0)
        };
        input.push_str(&format!("{},{n},{k},p{j}\n", rng.uniform()));
    }
    input.push_str("1.5,1.5,0,bad\n0.5,x,0,bad\n");
    let (summary, out, err) = run_query(&input);
    assert_eq!(
        summary,
        query::Summary {
            answered: 100,
            bad: 2
        },
        "{err}"
    );
    assert!(
        err.contains("line 102") && err.contains("cos_theta"),
        "{err}"
    );
    assert!(
        err.contains("line 103") && err.contains("'n' is not a number"),
        "{err}"
    );
    let mut lines = out.lines();
    assert_eq!(lines.next().unwrap(), "cos_theta,n,k,label,table,reference");
    for line in lines {
        let fields: Vec<&str> = line.split(',').collect();
        let value = |i: usize| fields[i].parse::<f64>().unwrap();
        let (cos, n, k, want) = (value(0), value(1), value(2), value(5));
        let table: f32 = fields[4].parse().unwrap();
        let independent = reference::fresnel(Complex64::new(n, k), cos).unwrap();
        assert_eq!(want, independent, "{line}");
        let runtime = fresnel(Complex::new(n as f32, k as f32), cos as f32);
        assert_eq!(table, runtime, "{line}");
        assert!((f64::from(table) - want).abs() <= 1e-5, "{line}");
    }
}
