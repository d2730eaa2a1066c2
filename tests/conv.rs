//! T3 (the convolution C of docs/model.md §2.5) through the runtime: the lookup
//! machinery on synthetic tables it must reproduce exactly, the documented
//! behaviour outside the domain, the normalised angle, and the shipped table
//! against the exact reference (at its nodes, and at random points with the
//! issue's acceptance figures).

use generator::reference::conv as reference;
use generator::tables::convolution;
use twoscale::TableId;
use twoscale::tables::convolution::{
    ConvTable, Convolution, normalised_angle, tan_of_normalised_angle,
};
use twoscale::tables::format::write::{TableSpec, encode};
use twoscale::tables::format::{AxisHeader, aligned_copy};
use twoscale::tables::interp::{coordinate_f64, node_value};

fn small_axis(nodes: u32, base: &AxisHeader) -> AxisHeader {
    AxisHeader { nodes, ..*base }
}

/// A T3 file on a small grid whose stored `ln C` is linear in the mapped
/// coordinates of the parameters and in `ξ` (and `ln s`, `ln(g² + offset)`
/// linear in the parameters): multilinear blending and the monotone cubic
/// along `ξ` reproduce such data exactly.
fn linear_table(angles: usize) -> (Vec<u8>, [AxisHeader; 4], impl Fn([f64; 4], f64) -> f64) {
    let axes = [
        small_axis(4, &convolution::U_AXIS),
        small_axis(3, &convolution::C_AXIS),
        small_axis(5, &convolution::BETA_AXIS),
        small_axis(3, &convolution::P_AXIS),
    ];
    let coeff = [0.3, -0.7, 1.1, 0.4];
    let f = move |x: [f64; 4], xi: f64| -> f64 {
        let mut v = -2.0 - 5.0 * xi;
        for d in 0..4 {
            v += coeff[d] * coordinate_f64(&axes[d], x[d]);
        }
        v
    };
    let mut grid = Vec::new();
    for i in 0..4 {
        for j in 0..3 {
            for k in 0..5 {
                for l in 0..3 {
                    let x = [
                        node_value(&axes[0], i),
                        node_value(&axes[1], j),
                        node_value(&axes[2], k),
                        node_value(&axes[3], l),
                    ];
                    grid.push(f(x, 0.0) as f32); // ln s
                    grid.push(f(x, 0.5) as f32); // ln(g² + offset)
                    for a in 0..angles {
                        grid.push(f(x, a as f64 / (angles - 1) as f64) as f32);
                    }
                }
            }
        }
    }
    let bytes = encode(&TableSpec {
        table_id: TableId::Convolution,
        channels: (2 + angles) as u32,
        kernel: TableId::Convolution.descriptor().kernel,
        value_type: TableId::Convolution.descriptor().value_type,
        axes: &axes,
        params: &convolution::header_params(
            angles,
            &twoscale::tables::format::AngleParams {
                ndf_softening: 1e-6,
                ..convolution::ANGLE
            },
        )
        .to_values(),
        grid: &grid,
        aux: &[],
        generator_version: "test",
    })
    .unwrap();
    (bytes, axes, f)
}

#[test]
fn lookup_reproduces_data_linear_in_parameters_and_angle() {
    let (bytes, _, f) = linear_table(12);
    let buf = aligned_copy(&bytes);
    let table = ConvTable::from_bytes(buf.bytes()).unwrap();
    let mut rng = generator::rng::SplitMix64::new(5);
    let mut worst = 0.0f64;
    for _ in 0..2000 {
        let x = [
            f64::from(rng.log_uniform_in(1e-3, 3000.0) as f32),
            f64::from((1.0 + rng.log_uniform_in(0.01, 9.0)) as f32),
            f64::from(rng.log_uniform_in(0.002, 1.0) as f32),
            f64::from(rng.uniform_in(0.2, 5.0) as f32),
        ];
        let tau = rng.log_uniform_in(1e-6, 1e5);
        let xi = normalised_angle(tau, x[0], x[2], x[3], &table.angle_params());
        let want = f(x, xi);
        let got =
            f64::from(table.at_tan(tau, x[0] as f32, x[1] as f32, x[2] as f32, x[3] as f32)).ln();
        worst = worst.max((got - want).abs());
    }
    // The stored values are quantised per node (error ≤ step/2 each); the
    // Catmull–Rom blends (4 parameter axes and ξ) amplify a node error by at
    // most their Lebesgue constant, 1.25 per axis; plus f32 blending of
    // values of magnitude ~10: a few ulps.
    let raw = twoscale::Table::from_bytes(buf.bytes()).unwrap();
    let quantised = raw.quantised().unwrap();
    let max_step = (0..quantised.nodes())
        .map(|n| f64::from(quantised.scales[2 * n + 1]))
        .fold(0.0, f64::max);
    let bound = 1.25f64.powi(5) * 0.5 * max_step + 2e-5;
    assert!(
        worst < bound,
        "max |ln C error| {worst} (bound {bound}, max step {max_step})"
    );
    // T3a: s = exp(ln s), g² = exp(…) − offset.
    let (s, g) = table.fit().parameters(10.0, 2.0, 0.1, 1.0);
    let x = [
        f64::from(10.0f32),
        f64::from(2.0f32),
        f64::from(0.1f32),
        f64::from(1.0f32),
    ];
    assert!((f64::from(s).ln() - f(x, 0.0)).abs() < 2e-5);
    let g2 = f(x, 0.5).exp() - convolution::G_OFFSET;
    assert!((f64::from(g) - g2.max(0.0).sqrt()).abs() < 1e-4 * g2.sqrt().max(1.0));
}

#[test]
fn out_of_domain_inputs_give_finite_values() {
    let (bytes, _, _) = linear_table(8);
    let buf = aligned_copy(&bytes);
    let table = ConvTable::from_bytes(buf.bytes()).unwrap();
    let fit = table.fit();
    let odd = [
        f32::NAN,
        f32::INFINITY,
        f32::NEG_INFINITY,
        -1.0,
        0.0,
        1e-30,
        0.5,
        1.0,
        1.5,
        1e30,
        f32::MAX,
    ];
    for &s in &odd {
        for &c in &odd {
            for &u in &odd {
                for &x in &odd {
                    for form in [&table as &dyn Convolution, &fit] {
                        let v = form.convolution_sin_cos(s, c, u, x, x, x);
                        assert!(v.is_finite() && v >= 0.0, "{s} {c} {u} {x}: {v}");
                        let v = form.convolution(c, u, 1.5, 0.1, x);
                        assert!(v.is_finite() && v >= 0.0, "{c} {u} {x}: {v}");
                    }
                }
            }
        }
    }
    // Non-finite parameters give 0.
    assert_eq!(table.convolution(1.0, f32::NAN, 2.0, 0.1, 1.0), 0.0);
    assert_eq!(fit.convolution(1.0, 1.0, 2.0, f32::INFINITY, 1.0), 0.0);
}

/// A material slice (`ConvTable::slice`) gives the full lookup's values (the
/// interpolation is separable; only the f32 summation order differs), across
/// the domain, beyond u_max and for out-of-domain parameters.
#[test]
fn material_slice_matches_the_full_lookup() {
    let buf = shipped();
    let table = ConvTable::from_bytes(buf.bytes()).unwrap();
    let mut rng = generator::rng::SplitMix64::new(404);
    let mut worst = 0.0f64;
    for _ in 0..200 {
        let c = rng.uniform_in(0.5, 12.0) as f32;
        let beta = rng.log_uniform_in(1e-3, 2.0) as f32;
        let p = rng.uniform_in(0.1, 6.0) as f32;
        let slice = table
            .slice(c, beta, p)
            .expect("the shipped table fits a slice");
        for _ in 0..50 {
            let u = rng.log_uniform_in(1e-3, 1e4) as f32;
            let theta = rng.uniform_in(0.0, std::f64::consts::FRAC_PI_2);
            let (sin, cos) = (theta.sin() as f32, theta.cos() as f32);
            let full = f64::from(table.convolution_sin_cos(sin, cos, u, c, beta, p));
            let sliced = f64::from(slice.convolution_sin_cos(sin, cos, u));
            assert!(sliced.is_finite() && sliced >= 0.0);
            if full > 1e-30 {
                worst = worst.max((sliced / full - 1.0).abs());
            }
        }
    }
    println!("slice vs full lookup: max relative difference {worst:.2e}");
    // ln C is blended in f32 with |ln C| up to ~60: ~1e-5 is f32 rounding.
    assert!(worst < 1e-4, "{worst}");
    // Non-finite parameters give no slice; non-finite u and angles give 0.
    assert!(table.slice(f32::NAN, 0.1, 1.0).is_none());
    let slice = table.slice(2.0, 0.1, 1.0).unwrap();
    assert_eq!(slice.convolution_sin_cos(0.1, 0.9, f32::NAN), 0.0);
    assert_eq!(slice.convolution_sin_cos(f32::NAN, 0.9, 1.0), 0.0);
}

/// Beyond u_max the profile at u_max is scaled by the ratio of planar kernel
/// integrals, which falls like 1/u² for large u and is continuous at u_max.
#[test]
fn beyond_u_max_follows_the_narrow_kernel_limit() {
    let (bytes, axes, _) = linear_table(8);
    let buf = aligned_copy(&bytes);
    let table = ConvTable::from_bytes(buf.bytes()).unwrap();
    let u_max = axes[0].hi as f32;
    let at = |u: f32| table.at_tan(0.01, u, 3.0, 0.1, 1.0);
    let continuity = (at(u_max * 1.0001) / at(u_max) - 1.0).abs();
    assert!(continuity < 1e-3, "jump at u_max: {continuity}");
    let ratio = at(4.0 * u_max) / at(2.0 * u_max);
    assert!((ratio - 0.25).abs() < 1e-3, "u² law: {ratio}");
    let (s1, g1) = table.fit().parameters(u_max, 3.0, 0.1, 1.0);
    let (s2, g2) = table.fit().parameters(2.0 * u_max, 3.0, 0.1, 1.0);
    assert_eq!(g1, g2, "g is held beyond u_max");
    assert!(s2 < 0.3 * s1);
}

/// `(u, β, p)` at the corners of the domain and inside it, for the
/// normalised angle's tests.
const ANGLE_CASES: [(f64, f64, f64); 6] = [
    (0.0, 0.002, 0.2),
    (3000.0, 0.002, 5.0),
    (30.0, 0.3, 1.0),
    (3000.0, 1.0, 0.2),
    (0.5, 1.0, 5.0),
    (15.0, 0.05, 3.0),
];

/// The runtime's `F(τ)` against its formula written directly with angles:
/// kernel term `asinh(2 u_e sin θh)`, horizon term `½ ln(1 + τ²)`, edge term
/// `asinh(2 u_e sin x̃)` with `x̃` the smoothed positive part of `θh − θe`,
/// `θe = atan(β Y^(1/(2p')))`, faded by `(p'/p)^m / (1 + (tan θe / τ_f)²)`, NDF
/// term `ln(1 + Y(1 − e^(−y/Y)))`. (The runtime forms `θh − θe` by one
/// `atan` of `(τ − τe) / (1 + τ τe)`.)
#[test]
fn normalised_angle_matches_its_formula() {
    let a = convolution::ANGLE;
    let direct = |tau: f64, u: f64, beta: f64, p: f64| -> f64 {
        let ue = (u * u + a.kernel_scale_floor.powi(2)).sqrt();
        let p_eff = p / (1.0 + a.ndf_softening * p / (2.0 * ue * beta));
        let theta = tau.atan();
        let y = (tau / beta).powf(2.0 * p_eff);
        let cap = a.ndf_exponent_cap;
        let theta_e = (beta * cap.powf(1.0 / (2.0 * p_eff))).atan();
        let fade = (p_eff / p).powf(a.edge_softening_fade)
            / (1.0 + (theta_e.tan() / a.edge_fade_tan).powi(2));
        let x = theta - theta_e;
        let delta = a.edge_smoothing / (2.0 * ue);
        let smoothed =
            (0.5 * (x + (x * x + delta * delta).sqrt())).min(std::f64::consts::FRAC_PI_2);
        (2.0 * ue * theta.sin()).asinh()
            + a.horizon_weight * 0.5 * (tau * tau).ln_1p()
            + a.edge_weight * fade * (2.0 * ue * smoothed.sin()).asinh()
            + a.ndf_weight * (cap * -(-y / cap).exp_m1()).ln_1p()
    };
    let mut worst = 0.0f64;
    for &(u, beta, p) in &ANGLE_CASES {
        let top = direct(a.tau_max, u, beta, p);
        for k in 0..=400 {
            let theta = 1.5706 * k as f64 / 400.0;
            let tau = theta.tan();
            let want = direct(tau, u, beta, p) / top;
            let got = normalised_angle(tau, u, beta, p, &a);
            worst = worst.max((got - want).abs());
        }
    }
    assert!(
        worst < 1e-12,
        "normalised angle off its formula by {worst:e}"
    );
}

#[test]
fn normalised_angle_inverts_and_is_monotone() {
    let a = convolution::ANGLE;
    for &(u, beta, p) in &ANGLE_CASES {
        let mut last = -1.0;
        for k in 0..=200 {
            let xi = k as f64 / 200.0;
            let tau = tan_of_normalised_angle(xi, u, beta, p, &a);
            assert!(tau >= last, "τ(ξ) not monotone at {u} {beta} {p} ξ = {xi}");
            last = tau;
            let back = normalised_angle(tau, u, beta, p, &a);
            // Where the NDF exponent is softened to p' ≪ 1 (small u_e β), the
            // NDF term of F still grows below τ = 1e-50, which the bisection
            // does not reach: the first few ξ then map to τ ≈ 1e-59, where C
            // equals C(0) to double precision (the kernel's width is ≥ 1.7e-4),
            // so those nodes hold C(0). Elsewhere the inverse is exact.
            assert!(
                (back - xi).abs() < 1e-12 || tau < 1e-50,
                "{u} {beta} {p}: ξ {xi} -> τ {tau} -> {back}"
            );
        }
    }
}

/// The angle rule of the T3a fit integrates `sin θ` over `[0, atan τ_max]`
/// (it is the trapezoid rule in ξ with the exact Jacobian).
#[test]
fn angle_rule_integrates_the_measure() {
    for &(u, beta, p) in &[(0.0, 1.0, 1.0), (30.0, 0.05, 2.0), (3000.0, 0.002, 0.2)] {
        let (thetas, weights) = convolution::angle_rule(u, beta, p);
        let sum: f64 = weights.iter().sum();
        let want = 1.0 - thetas.last().unwrap().cos();
        assert!(
            (sum / want - 1.0).abs() < 0.05,
            "{u} {beta} {p}: {sum} vs {want}"
        );
    }
}

fn shipped() -> twoscale::tables::format::AlignedBuf {
    suite::read_table(TableId::Convolution)
}

/// At grid nodes the lookup returns the node's exact profile at its 32
/// angles (the runtime and the generator agree on the layout, the angle and
/// the storage order), to the node's quantisation (half its step in ln C)
/// plus f32 rounding (2e-4 relative, as before the table was quantised).
#[test]
fn shipped_table_reproduces_exact_profiles_at_nodes() {
    let buf = shipped();
    let table = ConvTable::from_bytes(buf.bytes()).unwrap();
    let raw = twoscale::Table::from_bytes(buf.bytes()).unwrap();
    let quantised = raw.quantised().unwrap();
    for index in [0usize, 7, 1234, 5555, 9001, 13_337, 20_159, 30_001, 40_319] {
        let bound = 2e-4 + 0.5 * f64::from(quantised.scales[2 * index + 1]);
        let [u, c, beta, p] = convolution::node_params(index);
        let (thetas, _) = convolution::angle_rule(u, beta, p);
        let exact = reference::convolution_profile(u, c, beta, p, &thetas).unwrap();
        let peak = exact.iter().cloned().fold(0.0, f64::max);
        for (&theta, &want) in thetas.iter().zip(&exact) {
            if want < 1e-9 * peak {
                continue;
            }
            let got =
                f64::from(table.at_tan(theta.tan(), u as f32, c as f32, beta as f32, p as f32));
            assert!(
                ((got - want) / want).abs() < bound,
                "node {index} θ {theta}: {got} vs {want} (bound {bound})"
            );
        }
    }
}

fn pointwise_errors(profiles: usize, seed: u64) -> (Vec<f64>, Vec<f64>) {
    let buf = shipped();
    let table = ConvTable::from_bytes(buf.bytes()).unwrap();
    let mut errors = Vec::new();
    let mut e_l2 = Vec::new();
    for point in convolution::verification_points(profiles, seed) {
        let r = convolution::verify_point(&table, point).unwrap();
        errors.extend(r.accurate_pointwise);
        e_l2.push(r.accurate_e_l2);
    }
    errors.sort_by(f64::total_cmp);
    e_l2.sort_by(f64::total_cmp);
    (errors, e_l2)
}

fn quantile(sorted: &[f64], q: f64) -> f64 {
    sorted[((sorted.len() - 1) as f64 * q).round() as usize]
}

/// The median acceptance figure for T3b: the median pointwise
/// relative error where C > 1e-3 C(0), at random parameter points and angles
/// uniform in [0, π/2] (as `verify` measures it, at other points), ≤ 1%; and
/// the median e_L2 ≤ 1%.
#[test]
fn shipped_table_meets_the_median_targets() {
    let (errors, e_l2) = pointwise_errors(24, 4242);
    eprintln!(
        "T3b at 24 profiles: pointwise ({} angles) median {:.3e}, p95 {:.3e}, max {:.3e}; e_L2 median {:.3e}, max {:.3e}",
        errors.len(),
        quantile(&errors, 0.5),
        quantile(&errors, 0.95),
        quantile(&errors, 1.0),
        quantile(&e_l2, 0.5),
        quantile(&e_l2, 1.0)
    );
    assert!(quantile(&errors, 0.5) <= 0.01);
    assert!(quantile(&e_l2, 0.5) <= 0.01);
}

/// The 95th-percentile target: pointwise relative error ≤ 5% where
/// C > 1e-3 C(0), at angles uniform in [0, π/2]. The shipped table (28 u
/// nodes): 2.3% on these 48 profiles (seed 4243; 16 u nodes 4.4%, the table
/// before 5.3%), 2.8% on verify's 160 (seed 2017), 3.0% on the 51 SciPy
/// points. Deterministic (fixed seed); ~65 s in release.
#[test]
fn shipped_table_meets_the_p95_target() {
    let (errors, _) = pointwise_errors(48, 4243);
    let p95 = quantile(&errors, 0.95);
    eprintln!("T3b pointwise p95 {p95:.3e} at {} angles", errors.len());
    assert!(p95 <= 0.05);
}
