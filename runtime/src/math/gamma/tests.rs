//! Unit tests of the parent module.

extern crate std;
use super::*;
use statrs::function::gamma::{gamma_lr, gamma_ur};
use std::println;

/// `n` points from `lo` to `hi`, evenly spaced in the logarithm.
fn log_grid(lo: f64, hi: f64, n: usize) -> impl Iterator<Item = f64> {
    let (l0, l1) = (lo.ln(), hi.ln());
    (0..n).map(move |i| (l0 + (l1 - l0) * i as f64 / (n - 1) as f64).exp())
}

fn rel(got: f64, want: f64) -> f64 {
    if got == want {
        0.0
    } else {
        ((got - want) / want).abs()
    }
}

/// Values below this are not compared in relative terms (statrs flushes to 0 there,
/// and near the subnormal range relative precision is lost anyway).
const TINY_VALUE: f64 = 1e-290;

#[test]
fn p_and_q_match_statrs() {
    let mut worst_p = (0.0, 0.0, 0.0);
    let mut worst_q = (0.0, 0.0, 0.0);
    let shapes = [
        0.1, 0.15, 0.2, 0.37, 0.5, 0.9, 1.0, 1.6, 2.0, 3.3, 5.0, 7.9, 10.0,
    ];
    for &a in &shapes {
        let near_split = [a + 1.0 - 1e-9, a + 1.0, a + 1.0 + 1e-9, a, a - 1.0 / 3.0];
        let xs = log_grid(1e-10, 200.0, 121).chain(near_split.into_iter().filter(|&x| x > 0.0));
        for x in xs {
            let (p, q) = (gamma_p(a, x), gamma_q(a, x));
            let (p_ref, q_ref) = (gamma_lr(a, x), gamma_ur(a, x));
            if p_ref > TINY_VALUE && rel(p, p_ref) > worst_p.0 {
                worst_p = (rel(p, p_ref), a, x);
            }
            if q_ref > TINY_VALUE && rel(q, q_ref) > worst_q.0 {
                worst_q = (rel(q, q_ref), a, x);
            }
        }
    }
    println!("max rel err vs statrs: P {worst_p:?}, Q {worst_q:?} (err, a, x)");
    assert!(worst_p.0 < 1e-13 && worst_q.0 < 1e-13);
}

/// High-precision references (mpmath, 50 digits): `(a, x, P, Q)`.
#[allow(clippy::excessive_precision)]
const REFERENCE_PQ: [(f64, f64, f64, f64); 21] = [
    (0.2, 1e-10, 1.0891244210401839672e-2, 0.98910875578959816033),
    (0.2, 0.3, 8.1652679433365272778e-1, 0.18347320566634727222),
    (0.2, 1.2, 9.6113847826635090475e-1, 0.038861521733649095253),
    (0.2, 50.0, 1.0, 1.809020124965986229e-24),
    (0.2, 700.0, 1.0, 1.1360472110212616684e-307),
    (0.5, 1e-06, 1.1283787909692363544e-3, 0.99887162120903076365),
    (0.5, 3.0, 9.8569412156457036047e-1, 0.014305878435429639526),
    (0.73, 0.73, 6.5353506526205439046e-1, 0.34646493473794560954),
    (1.0, 1e-300, 1.0000000000000000251e-300, 1.0),
    (
        2.0,
        2.9999,
        8.0083678991015485585e-1,
        0.19916321008984514415,
    ),
    (2.0, 3.0, 8.0085172652854422808e-1, 0.19914827347145577192),
    (3.3, 0.01, 2.814896095500034961e-8, 0.999999971851039045),
    (5.0, 5.0, 5.5950671493478758856e-1, 0.44049328506521241144),
    (5.0, 120.0, 1.0, 6.8512896853737731478e-46),
    (6.0, 700.0, 1.0, 1.3908502554045540519e-292),
    (10.0, 0.001, 2.7532278594284628353e-37, 1.0),
    (10.0, 11.0, 6.5948935753433895272e-1, 0.34051064246566104728),
    (10.0, 200.0, 1.0, 2.0440955935807319668e-72),
    (10.0, 700.0, 1.0, 1.1106924650193636197e-284),
    (
        0.1,
        1e-200,
        1.0511370061117751209e-20,
        0.99999999999999999999,
    ),
    (0.1, 690.0, 1.0, 6.3523928121210361028e-304),
];

/// High-precision references (mpmath, 50 digits): `(a, q, Q⁻¹(a, q))`.
#[allow(clippy::excessive_precision)]
const REFERENCE_INVERSE_Q: [(f64, f64, f64); 14] = [
    (0.15, 1e-300, 683.39845655214209229),
    (0.15, 1e-20, 41.046357649642563969),
    (0.15, 0.3, 0.061608021364389015296),
    (0.15, 0.9, 1.3572859640895555473e-7),
    (0.2, 1e-05, 8.2191098894525011604),
    (0.5, 0.5, 0.22746821155978637597),
    (0.3333333333333333, 1e-100, 225.65747275161295327),
    (1.0, 0.25, 1.3862943611198906188),
    (2.0, 1e-300, 697.32421137935258462),
    (2.0, 0.999999, 0.0014148806614996954247),
    (5.0, 1e-12, 39.23582328141924038),
    (5.0, 0.5, 4.6709088827959837203),
    (6.0, 1e-300, 718.88350248949328108),
    (6.0, 0.999999999999999, 0.0094787755360367822053),
];

#[test]
fn p_and_q_match_high_precision_references() {
    let mut worst: f64 = 0.0;
    for &(a, x, p_ref, q_ref) in &REFERENCE_PQ {
        let (ep, eq) = (rel(gamma_p(a, x), p_ref), rel(gamma_q(a, x), q_ref));
        assert!(ep < 1e-13 && eq < 1e-13, "a={a} x={x}: {ep:e} {eq:e}");
        worst = worst.max(ep).max(eq);
    }
    println!("max rel err vs mpmath table: {worst:e}");
}

#[test]
fn closed_form_a_one_is_exponential() {
    let mut worst = (0.0, 0.0);
    for x in log_grid(1e-10, 700.0, 400).chain([0.5, 1.0, 2.0, 2.5, 700.0]) {
        let (p, q) = (gamma_p(1.0, x), gamma_q(1.0, x));
        let (p_ref, q_ref) = (-libm::expm1(-x), libm::exp(-x));
        worst.0 = rel(p, p_ref).max(worst.0);
        worst.1 = rel(q, q_ref).max(worst.1);
    }
    println!("a = 1: max rel err P {:e}, Q {:e}", worst.0, worst.1);
    assert!(worst.0 < 1e-13 && worst.1 < 1e-13);
}

#[test]
fn closed_form_a_half_is_erfc() {
    // x = z² with z = k/64 exact, so that the reference erfc(√x) = erfc(z) has no
    // rounding in its argument (that alone would cost ~x·ε at x = 700).
    let mut worst = (0.0, 0.0);
    for k in 1..=(26 * 64 + 29) {
        let z = f64::from(k) / 64.0;
        let x = z * z;
        let (p, q) = (gamma_p(0.5, x), gamma_q(0.5, x));
        worst.0 = rel(p, libm::erf(z)).max(worst.0);
        worst.1 = rel(q, libm::erfc(z)).max(worst.1);
    }
    for z in log_grid(1e-5, 0.01, 40) {
        let x = z * z;
        worst.0 = rel(gamma_p(0.5, x), libm::erf(z)).max(worst.0);
    }
    println!("a = 1/2: max rel err P {:e}, Q {:e}", worst.0, worst.1);
    assert!(worst.0 < 1e-13 && worst.1 < 1e-13);
}

/// Probabilities for the inverse tests: 1e-300 … 1/2 log-spaced, a linear sweep
/// over (0, 1), and 1 − 10⁻ᵏ up to 1 − 1e-16.
fn probabilities() -> impl Iterator<Item = f64> {
    log_grid(1e-300, 0.5, 150)
        .chain((1..40).map(|i| f64::from(i) / 40.0))
        .chain((1..=16).map(|k| 1.0 - 10f64.powi(-k)))
        .chain([1.0 - EPS / 2.0, 1.0 - EPS, 0.5, 5e-324, f64::MIN_POSITIVE])
}

/// `|d ln T / d ln x|` at `x` for `T = min(P, Q)`: converts a relative error in the
/// tail probability into a relative error in `x`.
fn log_slope(a: f64, x: f64) -> f64 {
    let t = gamma_p(a, x).min(gamma_q(a, x));
    (a * x.ln() - x - math::ln_gamma(a) - t.ln()).exp()
}

/// Round trips: returns (max relative residual of the smaller tail, max implied
/// relative error of x, max evaluations).
fn round_trips(shapes: &[f64]) -> (f64, f64, u32) {
    let mut worst = (0.0f64, 0.0f64, 0u32);
    for &a in shapes {
        for prob in probabilities() {
            // Upper-tail parameterisation.
            let y = inverse_gamma_q(a, prob);
            assert!(y.is_finite() && y > 0.0, "a={a} q={prob}: {y}");
            let (residual, tail) = if prob <= 0.5 {
                (rel(gamma_q(a, y), prob), prob)
            } else {
                (rel(gamma_p(a, y), 1.0 - prob), 1.0 - prob)
            };
            let implied = residual / log_slope(a, y);
            if tail > 1e-300 {
                worst.0 = worst.0.max(residual);
                worst.1 = worst.1.max(implied);
            }
            // Lower-tail parameterisation, checked the same way.
            let x = inverse_gamma_p(a, prob);
            assert!(x.is_finite() && x >= 0.0, "a={a} p={prob}: {x}");
            if x > 1e-300 && prob < 1.0 {
                let residual = if prob <= 0.5 {
                    rel(gamma_p(a, x), prob)
                } else {
                    rel(gamma_q(a, x), 1.0 - prob)
                };
                worst.0 = worst.0.max(residual);
                worst.1 = worst.1.max(residual / log_slope(a, x));
            }
            // Evaluation counts of the solver itself.
            let (t, tail) = if prob <= 0.5 {
                (prob, Tail::Upper)
            } else {
                (1.0 - prob, Tail::Lower)
            };
            worst.2 = worst.2.max(solve(&GammaShape::new(a), tail, t).1);
            worst.2 = worst
                .2
                .max(solve(&GammaShape::new(a), Tail::Lower, prob.min(0.5)).1);
        }
    }
    worst
}

#[test]
fn inverses_round_trip_on_epd_range() {
    // a = 1/p for p ∈ [0.2, 5] (plus a margin).
    let shapes: [f64; 14] = [
        0.15, 0.2, 0.25, 0.33, 0.45, 0.5, 0.7, 1.0, 1.3, 2.0, 2.7, 4.0, 5.0, 6.0,
    ];
    let (residual, implied, evaluations) = round_trips(&shapes);
    println!(
        "round trips a ∈ [0.15, 6]: max rel residual of the tail {residual:e}, \
         implied max rel err of x {implied:e}, max evaluations {evaluations}"
    );
    assert!(residual < 1e-12, "{residual:e}");
    assert!(implied < 1e-12, "{implied:e}");
    assert!(evaluations <= 6, "{evaluations}");
}

#[test]
fn inverses_round_trip_wider_range() {
    let shapes: [f64; 6] = [0.1, 0.12, 7.5, 10.0, 30.0, 100.0];
    let (residual, implied, evaluations) = round_trips(&shapes);
    println!(
        "round trips a ∈ [0.1, 100]: max rel residual {residual:e}, implied x err \
         {implied:e}, max evaluations {evaluations}"
    );
    assert!(implied < 1e-11, "{implied:e}");
    assert!(evaluations <= 8, "{evaluations}");
}

#[test]
fn inverse_matches_high_precision_references() {
    let mut worst: f64 = 0.0;
    for &(a, q, y_ref) in &REFERENCE_INVERSE_Q {
        let e = rel(inverse_gamma_q(a, q), y_ref);
        let e_p = rel(inverse_gamma_p(a, 1.0 - q), y_ref);
        // 1 − q is rounded for q < 1/2, which moves the quantile by
        // ~ε/(q·|d ln Q/d ln x|); only the upper-tail form is exact there.
        assert!(e < 1e-12, "a={a} q={q}: {e:e}");
        if q >= 0.5 {
            assert!(e_p < 1e-12, "a={a} p={}: {e_p:e}", 1.0 - q);
        }
        worst = worst.max(e);
    }
    println!("max rel err of Q⁻¹ vs mpmath table: {worst:e}");
}

#[test]
fn inverse_at_a_one_is_minus_ln_q() {
    let mut worst: f64 = 0.0;
    for q in probabilities() {
        // −ln q as accurately as the input allows: directly for q ≤ 1/2, and as
        // −ln(1 − (1 − q)) with the exact 1 − q above.
        let want = if q <= 0.5 {
            -libm::log(q)
        } else {
            -libm::log1p(-(1.0 - q))
        };
        let y = inverse_gamma_q(1.0, q);
        worst = worst.max(rel(y, want));
    }
    println!("a = 1: max rel err of Q⁻¹ vs −ln q: {worst:e}");
    assert!(worst < 1e-13);
}

#[test]
fn edge_cases_are_defined() {
    let specials = [
        f64::NAN,
        f64::NEG_INFINITY,
        -1.0,
        0.0,
        5e-324,
        1e-300,
        1e-10,
        0.5,
        1.0,
        3.0,
        700.0,
        1e4,
        LARGE_A * (1.0 + EPS),
        1e7,
        1e300,
        f64::MAX,
        f64::INFINITY,
    ];
    let probs = [
        f64::NAN,
        -1.0,
        0.0,
        5e-324,
        1e-300,
        0.3,
        0.5,
        0.7,
        1.0 - EPS / 2.0,
        1.0,
        2.0,
        f64::INFINITY,
    ];
    for &a in &specials {
        for &x in &specials {
            let (p, q) = (gamma_p(a, x), gamma_q(a, x));
            assert!((0.0..=1.0).contains(&p), "P({a}, {x}) = {p}");
            assert!((0.0..=1.0).contains(&q), "Q({a}, {x}) = {q}");
        }
        for &t in &probs {
            let (yp, yq) = (inverse_gamma_p(a, t), inverse_gamma_q(a, t));
            assert!(yp.is_finite() && yp >= 0.0, "P⁻¹({a}, {t}) = {yp}");
            assert!(yq.is_finite() && yq >= 0.0, "Q⁻¹({a}, {t}) = {yq}");
        }
    }
    // Documented values.
    assert_eq!((gamma_p(2.0, 0.0), gamma_q(2.0, 0.0)), (0.0, 1.0));
    assert_eq!((gamma_p(2.0, f64::NAN), gamma_q(2.0, -3.0)), (0.0, 1.0));
    assert_eq!(
        (gamma_p(2.0, f64::INFINITY), gamma_q(2.0, f64::INFINITY)),
        (1.0, 0.0)
    );
    assert_eq!((gamma_p(0.0, 1.0), gamma_q(f64::NAN, 1.0)), (1.0, 0.0));
    assert_eq!(
        (gamma_p(f64::INFINITY, 1.0), gamma_q(f64::INFINITY, 1.0)),
        (0.0, 1.0)
    );
    assert_eq!(inverse_gamma_p(2.0, 0.0), 0.0);
    assert_eq!(inverse_gamma_p(2.0, f64::NAN), 0.0);
    assert_eq!(inverse_gamma_q(2.0, 1.0), 0.0);
    assert_eq!(inverse_gamma_q(2.0, f64::NAN), 0.0);
    assert_eq!(inverse_gamma_q(-1.0, 0.3), 0.0);
    assert_eq!(inverse_gamma_p(f64::NAN, 0.3), 0.0);
    // prob = 1 → the quantile at 1 − 2⁻⁵³; q = 0 → the quantile at 2⁻¹⁰⁷⁴.
    assert_eq!(inverse_gamma_p(3.0, 1.0), inverse_gamma_q(3.0, EPS / 2.0));
    assert!(rel(inverse_gamma_p(1.0, 1.0), 53.0 * LN_2) < 1e-14);
    assert!(rel(inverse_gamma_q(1.0, 0.0), 1074.0 * LN_2) < 1e-14);
    assert_eq!(inverse_gamma_q(0.2, 0.0), inverse_gamma_q(0.2, -5.0));
    assert_eq!(inverse_gamma_q(f64::INFINITY, 0.5), f64::MAX);
    // A lower-tail quantile that underflows is 0, not NaN.
    assert_eq!(inverse_gamma_p(0.15, 1e-300), 0.0);
}

#[test]
fn tiny_lower_tail_quantiles_are_resolved() {
    // The closed-form return for x₀ < 1e-10: check against the series directly.
    for &a in &[0.15, 0.5, 1.0, 6.0] {
        for p in log_grid(1e-300, 1e-5, 60) {
            let x = inverse_gamma_p(a, p);
            if x > 1e-300 {
                assert!(rel(gamma_p(a, x), p) < 1e-12, "a={a} p={p}");
            }
        }
    }
}

#[test]
fn inverses_are_monotone() {
    for &a in &[0.15, 1.0, 6.0] {
        let mut last = f64::INFINITY;
        for q in log_grid(1e-300, 1.0, 400) {
            let y = inverse_gamma_q(a, q);
            assert!(y <= last, "a={a} q={q}");
            last = y;
        }
    }
}

#[test]
fn large_shape_uses_wilson_hilferty() {
    let a = 2.0 * LARGE_A;
    let mut worst: f64 = 0.0;
    for k in -20..=20 {
        let x = a + f64::from(k) * 0.5 * a.sqrt();
        worst = worst.max((gamma_p(a, x) - gamma_lr(a, x)).abs());
        worst = worst.max((gamma_q(a, x) - gamma_ur(a, x)).abs());
    }
    println!("a = {a}: max abs err of the Wilson–Hilferty P, Q: {worst:e}");
    assert!(worst < 1e-6);
    // Its inverse inverts it.
    for &t in &[1e-10, 0.01, 0.3, 0.5] {
        let y = inverse_gamma_q(a, t);
        assert!(rel(gamma_q(a, y), t) < 1e-6, "t={t}");
        let x = inverse_gamma_p(a, t);
        assert!(rel(gamma_p(a, x), t) < 1e-6, "t={t}");
    }
    // Just below the switch the exact algorithm still converges.
    let a = LARGE_A;
    for k in -8..=8 {
        let x = a + f64::from(k) * a.sqrt();
        assert!((gamma_p(a, x) - gamma_lr(a, x)).abs() < 1e-10, "x={x}");
    }
}
