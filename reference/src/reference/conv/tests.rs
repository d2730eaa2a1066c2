//! Tests of the convolution reference. The default tests are fast (a few
//! seconds in release); the sweeps that produced the figures quoted in the
//! documentation are `#[ignore]`d: run them with
//! `cargo test --release -p generator conv -- --ignored --nocapture`.

use super::limits::laplacians;
use super::zh::moments_with_rule;
use super::*;
use crate::quad::{Tolerance, integrate};

/// Relative difference.
fn rel(a: f64, b: f64) -> f64 {
    ((a - b) / b).abs()
}

/// `∫ f` over `[0, π/2]` split at `cuts`, adaptive Gauss–Kronrod at `1e-13`.
fn integrate_split(f: impl Fn(f64) -> f64, mut cuts: Vec<f64>) -> f64 {
    cuts.retain(|&x| x > 0.0 && x < FRAC_PI_2);
    cuts.push(0.0);
    cuts.push(FRAC_PI_2);
    sort_dedup(&mut cuts);
    cuts.windows(2)
        .map(|w| {
            integrate(&f, w[0], w[1], Tolerance::relative(1e-13))
                .unwrap()
                .value
        })
        .sum()
}

/// A few parameter points spread over the domain's corners.
const SAMPLE: [(f64, f64, f64, f64); 8] = [
    (0.0, 2.0, 0.002, 0.2),
    (0.0, 10.0, 1.0, 5.0),
    (1.0, 2.0, 0.05, 0.5),
    (1.0, 1.01, 1.0, 5.0),
    (30.0, 1.01, 1.0, 0.2),
    (30.0, 10.0, 0.002, 5.0),
    (300.0, 10.0, 0.05, 1.0),
    (3000.0, 2.0, 1.0, 1.0),
];

#[test]
fn ndf_function_forms() {
    // Beckmann at p = 1: exp(−tan²θ/β²) / (π β² cos⁴θ).
    for &(beta, theta) in &[(0.3f64, 0.0f64), (0.3, 0.4), (1.0, 1.2), (0.002, 0.001)] {
        let (s, c) = theta.sin_cos();
        let beckmann = (-(s / c / beta).powi(2)).exp() / (PI * beta * beta * c.powi(4));
        assert!(rel(ndf_sc(beta, 1.0, ndf_peak(beta, 1.0), s, c), beckmann) < 1e-13);
        let d_cos = crate::reference::epd::Epd::new(beta, 1.0).unwrap().d(c);
        assert!(rel(d_cos, beckmann) < 1e-6);
    }
    // The peak p / (π β² Γ(1/p)), and zero beyond the horizon.
    let peak = ndf_peak(0.5, 0.2);
    assert!(rel(ndf_sc(0.5, 0.2, peak, 0.0, 1.0), 0.2 / (PI * 0.25 * 24.0)) < 1e-13);
    assert_eq!(ndf_sc(0.5, 0.2, peak, 1.0, -0.1), 0.0);
    assert_eq!(ndf_sc(0.5, 0.2, peak, 1.0, 1e-300), 0.0);
    assert_eq!(kernel_sc(10.0, 1.5, 1.0, 0.0), 0.0);
    assert!(rel(kernel_sc(10.0, 1.5, 0.6, 0.8), 0.64 * 145f64.powf(-1.5)) < 1e-14);
}

#[test]
fn ndf_normalisation_and_integral() {
    // b_1 = ∫ D cos θ sin θ dθ = 1/(2π) (the normalisation), and
    // 2π b_0 = W_D, from the zonal-harmonic rule, against the Gamma-variable
    // quadrature of `ndf_integral`: two independent rules.
    for &(beta, p) in &[
        (0.002, 0.2),
        (0.002, 5.0),
        (0.05, 0.5),
        (1.0, 0.2),
        (1.0, 1.0),
        (0.3, 5.0),
    ] {
        let params = Params::new(0.0, 2.0, beta, p).unwrap();
        let ndf = params.ndf();
        let b = legendre_moments(|s, c| ndf.value(s, c), &ndf.breakpoints(), 2);
        assert!(
            (2.0 * PI * b[1] - 1.0).abs() < 1e-12,
            "β={beta} p={p}: {}",
            2.0 * PI * b[1]
        );
        let w = ndf_integral(beta, p).unwrap();
        assert!(
            rel(2.0 * PI * b[0], w) < 1e-12,
            "β={beta} p={p}: {} vs {w}",
            2.0 * PI * b[0]
        );
    }
    // Closed form at p = 1: W_D = 1 + (√π/2) β e^{1/β²} erfc(1/β).
    for &beta in &[0.1, 0.5, 1.0] {
        let exact =
            1.0 + 0.5 * PI.sqrt() * beta * (1.0 / (beta * beta)).exp() * libm::erfc(1.0 / beta);
        assert!(
            rel(ndf_integral(beta, 1.0).unwrap(), exact) < 1e-12,
            "β={beta}"
        );
    }
    // Narrow lobes: W_D − 1 → (β²/2) E[y^{1/p}] = (β²/2) Γ(2/p)/Γ(1/p).
    for &p in &[1.0, 5.0] {
        let beta = 1e-3;
        let lead = 0.5 * beta * beta * (libm::lgamma(2.0 / p) - libm::lgamma(1.0 / p)).exp();
        assert!(rel(ndf_moment(beta, p).unwrap(), lead) < 1e-5, "p={p}");
    }
    // Wide small-p lobes: W_D ≈ β Γ(3/(2p)) / Γ(1/p) = 78 at β = 1, p = 0.2.
    let w = ndf_integral(1.0, 0.2).unwrap();
    assert!((w - 1871.25 / 24.0).abs() < 1.5, "{w}");
}

#[test]
fn kernel_integrals() {
    // u = 0: ∫ cos²γ dω over the hemisphere = 2π/3; M_K = 2π(1/3 − 1/4).
    assert!(rel(kernel_integral(0.0, 2.0).unwrap(), 2.0 * PI / 3.0) < 1e-14);
    assert!(rel(kernel_moment(0.0, 2.0).unwrap(), PI / 6.0) < 1e-13);
    // Against the integral in γ (another variable, other breakpoints).
    for &(u, c) in &[(1.0, 1.01), (30.0, 2.0), (3000.0, 10.0), (3000.0, 1.01)] {
        let q = 0.5 * (c + 1.0);
        let f = |g: f64| {
            let (s, co) = g.sin_cos();
            2.0 * PI * kernel_sc(u, q, s, co) * s
        };
        let cuts: Vec<f64> = (0..40).map(|k| 0.5 / u * 2f64.powi(k - 4)).collect();
        let by_gamma = integrate_split(f, cuts);
        assert!(
            rel(kernel_integral(u, c).unwrap(), by_gamma) < 1e-12,
            "u={u} c={c}"
        );
    }
    // Large u, c well above 1: W_K → π / (2u² (c − 1)).
    let (u, c) = (3000.0, 10.0);
    assert!(
        rel(
            kernel_integral(u, c).unwrap(),
            PI / (2.0 * u * u * (c - 1.0))
        ) < 1e-6
    );
}

#[test]
fn zonal_harmonic_convention() {
    // K ≡ 1 and D ≡ 1 on the whole sphere: a_0 = b_0 = 2, C = 4π.
    assert!(rel(zh_series(&[2.0, 0.0], &[2.0, 0.0], 1, 0.3), 4.0 * PI) < 1e-15);
    // Hemispheres: D = χ(n·m > 0), K = (h·m)² χ(h·m > 0). C(0) = 2π/3,
    // C(π/2) = π/3 (half of it, by symmetry), C(θh) by the ring formula.
    // Both lobes have kinks at their horizons, so the series converges only
    // algebraically; at L = 4000 the error is ≈ 1e-7.
    let l = 4000;
    let a = legendre_moments(|_, c| if c > 0.0 { c * c } else { 0.0 }, &[], l);
    let b = legendre_moments(|_, c| if c > 0.0 { 1.0 } else { 0.0 }, &[], l);
    assert!(rel(zh_series(&a, &b, l, 0.0), 2.0 * PI / 3.0) < 1e-6);
    assert!(rel(zh_series(&a, &b, l, FRAC_PI_2), PI / 3.0) < 1e-6);
    for &t in &[0.3f64, 1.0] {
        let ring = |theta: f64| theta.sin() * ring_u0(theta, t);
        let exact = integrate_split(ring, vec![FRAC_PI_2 - t]);
        assert!(rel(zh_series(&a, &b, l, t), exact) < 1e-6, "θh={t}");
    }
}

/// `∫₀^{2π} (h·m)² χ(h·m > 0) dφ` over the circle of polar angle `θ` around
/// `n`, with `h·m = A + B cos φ`, `A = cos θ cos θh`, `B = sin θ sin θh`:
/// `2π (A² + B²/2)` when the whole circle is in front of `h`, else
/// `2A²φc + 4AB sin φc + B² (φc + sin φc cos φc)` with `cos φc = −A/B`.
fn ring_u0(theta: f64, theta_h: f64) -> f64 {
    let a = theta.cos() * theta_h.cos();
    let b = theta.sin() * theta_h.sin();
    if b <= a.abs() {
        return if a > 0.0 {
            2.0 * PI * (a * a + 0.5 * b * b)
        } else {
            0.0
        };
    }
    let pc = (-a / b).acos();
    let (s, c) = pc.sin_cos();
    2.0 * a * a * pc + 4.0 * a * b * s + b * b * (pc + s * c)
}

#[test]
fn u_zero_matches_ring_formula() {
    // At u = 0 the inner integral has a closed form, so C is a 1-D
    // integral: independent of both methods.
    for &(beta, p) in &[(0.002, 0.2), (0.05, 1.0), (1.0, 0.2), (1.0, 5.0)] {
        let params = Params::new(0.0, 2.0, beta, p).unwrap();
        let ndf = params.ndf();
        let thetas = [0.0, 0.01, 0.5, 1.2, 1.56];
        let zh = convolution_zh(0.0, 2.0, beta, p, &thetas, &ZhOptions::default()).unwrap();
        for (i, &t) in thetas.iter().enumerate() {
            let f = |th: f64| {
                let (s, c) = th.sin_cos();
                ndf.value(s, c) * s * ring_u0(th, t)
            };
            let mut cuts = ndf.breakpoints();
            cuts.push(FRAC_PI_2 - t);
            let exact = integrate_split(f, cuts);
            let direct = convolution(t, 0.0, 2.0, beta, p).unwrap();
            assert!(
                rel(direct, exact) < 1e-10,
                "β={beta} p={p} θh={t}: {direct} vs {exact}"
            );
            assert!(
                rel(zh.values[i], exact) < 1e-6,
                "β={beta} p={p} θh={t}: {} vs {exact}",
                zh.values[i]
            );
        }
    }
    // p = 1, θh = 0: C(0) = E[cos θ] = (√π/β) e^{1/β²} erfc(1/β).
    for &beta in &[0.1, 0.5, 1.0] {
        let exact = PI.sqrt() / beta * (1.0 / (beta * beta)).exp() * libm::erfc(1.0 / beta);
        assert!(
            rel(convolution(0.0, 0.0, 3.0, beta, 1.0).unwrap(), exact) < 1e-12,
            "β={beta}"
        );
    }
}

#[test]
fn theta_zero_is_a_one_dimensional_integral() {
    // Both lobes share the axis: C(0) = 2π ∫ K(θ) D(θ) sin θ dθ.
    for &(u, c, beta, p) in &SAMPLE {
        let params = Params::new(u, c, beta, p).unwrap();
        let (k, d) = (params.kernel(), params.ndf());
        let f = |t: f64| {
            let (s, co) = t.sin_cos();
            2.0 * PI * k.value(s, co) * d.value(s, co) * s
        };
        let mut cuts = k.breakpoints();
        cuts.extend(d.breakpoints());
        let exact = integrate_split(f, cuts);
        for frame in [Frame::Normal, Frame::Half] {
            let opts = DirectOptions {
                frame,
                ..DirectOptions::default()
            };
            let v = convolution_direct(0.0, u, c, beta, p, &opts).unwrap().value;
            assert!(
                rel(v, exact) < 1e-11,
                "{u} {c} {beta} {p} {frame:?}: {v} vs {exact}"
            );
        }
    }
}

#[test]
fn zh_matches_direct_on_sample() {
    for &(u, c, beta, p) in &SAMPLE {
        let zh = convolution_zh(u, c, beta, p, &SWEEP_THETAS, &ZhOptions::default()).unwrap();
        let c0 = zh.c0;
        for (i, &t) in SWEEP_THETAS.iter().enumerate() {
            let d = convolution(t, u, c, beta, p).unwrap();
            let m = metric(zh.values[i], d, c0);
            assert!(
                m <= TARGET,
                "u={u} c={c} β={beta} p={p} θh={t}: zh {} direct {d} ({m:e})",
                zh.values[i]
            );
        }
    }
}

#[test]
fn frames_agree_on_hard_points() {
    // Narrow kernel on a narrow cusped D, and the horizon maximum of a wide
    // small-p D: the two frames discretise completely differently.
    for &(t, u, c, beta, p) in &[
        (1e-4, 3000.0, 1.01, 0.002, 0.2),
        (0.002, 3000.0, 10.0, 0.002, 5.0),
        (1.5697963267948966, 3000.0, 2.0, 1.0, 0.2),
        (1.3, 300.0, 1.01, 1.0, 0.5),
    ] {
        let mut v = vec![];
        for frame in [Frame::Normal, Frame::Half] {
            let opts = DirectOptions {
                frame,
                ..DirectOptions::default()
            };
            v.push(convolution_direct(t, u, c, beta, p, &opts).unwrap().value);
        }
        assert!(
            rel(v[1], v[0]) < 1e-10,
            "θh={t} u={u} c={c} β={beta} p={p}: {v:?}"
        );
    }
}

#[test]
fn rules_agree_on_hard_points() {
    // G7–K15 (the default) against G10–K21 in the same frame: the frames'
    // hard points and T3 nodes of the direct quadrature (u ≥ 444, cusped D).
    for &(t, u, c, beta, p) in &[
        (1e-4, 3000.0, 1.01, 0.002, 0.2),
        (0.002, 3000.0, 10.0, 0.002, 5.0),
        (1.5697963267948966, 3000.0, 2.0, 1.0, 0.2),
        (1.3, 300.0, 1.01, 1.0, 0.5),
        (
            0.05,
            444.5686598259818,
            1.01,
            0.010892127693109842,
            0.39776462853385935,
        ),
        (
            0.3,
            954.1808424736149,
            4.409639507138689,
            0.05931922284150511,
            0.6295525494276792,
        ),
    ] {
        let value = |rule| {
            let opts = DirectOptions {
                rule,
                ..DirectOptions::default()
            };
            convolution_direct(t, u, c, beta, p, &opts).unwrap().value
        };
        let (k15, k21) = (
            value(crate::quad::Rule::Gk15),
            value(crate::quad::Rule::Gk21),
        );
        assert!(
            rel(k15, k21) < 1e-12,
            "θh={t} u={u} c={c} β={beta} p={p}: {k15} vs {k21}"
        );
    }
}

#[test]
fn shared_moments_are_bit_identical() {
    // Two profiles sharing the NDF lobe, and one sharing the kernel, through
    // one cache: the same bits as computed alone.
    let thetas = [0.0, 0.01, 0.3, 1.2, FRAC_PI_2];
    let cache = MomentCache::new();
    for &(u, c, beta, p) in &[
        (30.0, 2.0, 0.05, 1.0),
        (3.0, 2.0, 0.05, 1.0),
        (3.0, 2.0, 0.3, 0.5),
    ] {
        let (shared, m1) = convolution_profile_cached(u, c, beta, p, &thetas, &cache).unwrap();
        let (alone, m2) = convolution_profile_with_method(u, c, beta, p, &thetas).unwrap();
        assert!(matches!(m1, Method::ZonalHarmonics { .. }) && m1 == m2);
        let bits = |v: &[f64]| v.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
        assert_eq!(bits(&shared), bits(&alone), "{u} {c} {beta} {p}");
    }
}

#[test]
fn band_limit_doubling_converges() {
    // A narrow D (β = 0.002) under a moderately narrow kernel (u = 30): one
    // coefficient computation up to 4096, the series truncated at L.
    let (u, c, beta, p) = (30.0, 2.0, 0.002, 1.0);
    let params = Params::new(u, c, beta, p).unwrap();
    let (k, d) = (params.kernel(), params.ndf());
    let lmax = 4096;
    let a = legendre_moments(|s, co| k.value(s, co), &k.breakpoints(), lmax);
    let b = legendre_moments(|s, co| d.value(s, co), &d.breakpoints(), lmax);
    let rule = ProfileRule::for_params(&params);
    let profile = |l: usize| -> Vec<f64> {
        rule.nodes
            .iter()
            .map(|&t| zh_series(&a, &b, l, t))
            .collect()
    };
    let exact = profile(lmax);
    let mut last = f64::INFINITY;
    for l in [128usize, 256, 512, 1024, 2048] {
        let (pl, p2l) = (profile(l), profile(2 * l));
        let change = pl
            .iter()
            .zip(&p2l)
            .map(|(x, y)| (x - y).abs())
            .fold(0.0, f64::max)
            / exact[0];
        assert!(change < last, "L={l}: {change:e} ≥ {last:e}");
        last = change;
    }
    assert!(last < 1e-9, "{last:e}");
    // The paper's 100 bands (HP17 appendix) are far from converged: the
    // lobe comes out much too wide and too low.
    let trunc = profile(100);
    let e = e_l2_on(
        &rule,
        |t| trunc[rule.nodes.iter().position(|&x| x == t).unwrap()],
        &exact,
    );
    assert!(e > 0.3, "e_L2 at L = 100: {e}");
    // And the converged default agrees with the reference.
    let zh = convolution_zh(u, c, beta, p, &rule.nodes, &ZhOptions::default()).unwrap();
    let e = e_l2_on(
        &rule,
        |t| zh.values[rule.nodes.iter().position(|&x| x == t).unwrap()],
        &exact,
    );
    assert!(e < 1e-9, "{e}");
}

#[test]
fn moment_rule_is_converged() {
    // Halving the parts (and 48 instead of 32 nodes) changes the moments by
    // rounding only, for narrow and wide lobes of both kinds. (With the
    // plain recurrence in x = cos θ the narrow kernel's moments moved by
    // 7e-12: see `legendre_step`.)
    for &(u, beta, p) in &[(3000.0, 0.002, 0.2), (0.0, 1.0, 5.0), (300.0, 0.05, 1.0)] {
        let params = Params::new(u, 2.0, beta, p).unwrap();
        for lobe in [params.kernel(), params.ndf()] {
            let f = |s: f64, c: f64| lobe.value(s, c);
            let bp = lobe.breakpoints();
            let m1 = legendre_moments(f, &bp, 2048);
            let m2 = moments_with_rule(f, &bp, 2048, 48, 20.0);
            let scale = m1[0].abs();
            let worst = m1
                .iter()
                .zip(&m2)
                .map(|(x, y)| (x - y).abs())
                .fold(0.0, f64::max)
                / scale;
            assert!(worst < 1e-13, "u={u} β={beta} p={p} {lobe:?}: {worst:e}");
        }
    }
}

#[test]
fn laplacians_match_finite_differences() {
    // Δ_S f = f'' + cot θ f' by central differences.
    let (u, q, beta, p) = (3.0, 1.5, 0.4, 1.7);
    let params = Params::new(u, 2.0 * q - 1.0, beta, p).unwrap();
    let (k, d) = (params.kernel(), params.ndf());
    for &t in &[0.2f64, 0.7, 1.3] {
        let h = 1e-4;
        let fd = |f: &dyn Fn(f64) -> f64| {
            let d2 = (f(t + h) - 2.0 * f(t) + f(t - h)) / (h * h);
            let d1 = (f(t + h) - f(t - h)) / (2.0 * h);
            d2 + d1 / t.tan()
        };
        let (lk, ld) = laplacians(u, q, beta, p, t);
        let fk = |x: f64| k.value(x.sin(), x.cos());
        let fdd = |x: f64| d.value(x.sin(), x.cos());
        assert!(
            (lk - fd(&fk)).abs() < 1e-5 * lk.abs().max(1.0),
            "K at {t}: {lk} vs {}",
            fd(&fk)
        );
        let ld = ld.unwrap();
        assert!(
            (ld - fd(&fdd)).abs() < 1e-5 * ld.abs().max(1.0),
            "D at {t}: {ld} vs {}",
            fd(&fdd)
        );
    }
    // Limits at θ = 0.
    assert!(
        rel(
            laplacians(u, q, beta, p, 0.0).0,
            -4.0 * (4.0 * u * u * q + 1.0)
        ) < 1e-14
    );
    assert!(laplacians(u, q, beta, 0.5, 0.0).1.is_none());
}

#[test]
fn limiting_forms_match_where_valid() {
    // (a) narrow kernel, steep tail (c = 10), smooth wide D: uβ = 3000.
    for &t in &[0.0, 0.3, 0.8] {
        let exact = convolution(t, 3000.0, 10.0, 1.0, 1.0).unwrap();
        let a0 = narrow_kernel_limit(t, 3000.0, 10.0, 1.0, 1.0, 0).unwrap();
        let a1 = narrow_kernel_limit(t, 3000.0, 10.0, 1.0, 1.0, 1).unwrap();
        assert!(rel(a0, exact) < 5e-8, "θh={t}: {}", rel(a0, exact));
        assert!(rel(a1, exact) < 1e-12, "θh={t}: {}", rel(a1, exact));
    }
    // (a) is not a limit for heavy tails: c = 1.01 stays percent-level off.
    let exact = convolution(0.3, 3000.0, 1.01, 1.0, 1.0).unwrap();
    assert!(
        rel(
            narrow_kernel_limit(0.3, 3000.0, 1.01, 1.0, 1.0, 0).unwrap(),
            exact
        ) > 1e-3
    );
    // The first correction needs Δ_S D, which the cusp (p < 1) lacks at 0.
    assert!(narrow_kernel_limit(0.0, 3000.0, 10.0, 1.0, 0.5, 1).is_err());
    // (b) narrow D under a wide kernel: the error of the leading form
    // falls like β², the corrected one like β⁴.
    let err = |beta: f64, order| {
        let exact = convolution(0.3, 1.0, 2.0, beta, 1.0).unwrap();
        rel(
            narrow_ndf_limit(0.3, 1.0, 2.0, beta, 1.0, order).unwrap(),
            exact,
        )
    };
    let (e0a, e0b) = (err(0.004, 0), err(0.002, 0));
    let (e1a, e1b) = (err(0.004, 1), err(0.002, 1));
    assert!((e0a / e0b - 4.0).abs() < 0.2, "{e0a:e} / {e0b:e}");
    assert!((e1a / e1b - 16.0).abs() < 2.0, "{e1a:e} / {e1b:e}");
    assert!(e1b < 1e-9, "{e1b:e}");
}

#[test]
fn profiles_are_finite_and_non_negative() {
    let corners = [
        (3000.0, 10.0, 0.002, 0.2),
        (3000.0, 1.01, 1.0, 5.0),
        (0.0, 1.01, 0.002, 5.0),
        (300.0, 10.0, 0.002, 1.0),
    ];
    for &(u, c, beta, p) in &corners {
        let (v, m) = convolution_profile_with_method(u, c, beta, p, &SWEEP_THETAS).unwrap();
        for (x, t) in v.iter().zip(SWEEP_THETAS) {
            assert!(
                x.is_finite() && *x >= 0.0,
                "u={u} c={c} β={beta} p={p} θh={t} ({m:?}): {x}"
            );
        }
    }
    // The method choice: a narrow kernel on a cusped D is left to the
    // direct quadrature, a wide smooth D goes to zonal harmonics.
    let (_, m) = convolution_profile_with_method(3000.0, 2.0, 0.002, 0.2, &[0.1]).unwrap();
    assert_eq!(m, Method::Direct);
    let (_, m) = convolution_profile_with_method(3000.0, 2.0, 1.0, 1.0, &[0.1]).unwrap();
    assert!(matches!(m, Method::ZonalHarmonics { .. }), "{m:?}");
}

#[test]
fn invalid_parameters_are_errors() {
    let bad = [
        (0.1, -1.0, 2.0, 0.5, 1.0),
        (0.1, f64::INFINITY, 2.0, 0.5, 1.0),
        (0.1, 1.0, 1.0, 0.5, 1.0),
        (0.1, 1.0, 2.0, 0.0, 1.0),
        (0.1, 1.0, 2.0, 0.5, f64::NAN),
        (2.0, 1.0, 2.0, 0.5, 1.0),
        (-0.1, 1.0, 2.0, 0.5, 1.0),
        (f64::NAN, 1.0, 2.0, 0.5, 1.0),
    ];
    for &(t, u, c, beta, p) in &bad {
        let e = convolution(t, u, c, beta, p).unwrap_err();
        assert!(matches!(e, ConvError::InvalidParameter { .. }), "{e:?}");
        assert!(e.to_string().contains("invalid parameter"));
        assert!(convolution_profile(u, c, beta, p, &[t]).is_err());
        assert!(convolution_zh(u, c, beta, p, &[t], &ZhOptions::default()).is_err());
    }
    assert!(narrow_ndf_limit(0.1, 1.0, 2.0, 0.5, 1.0, 2).is_err());
    let opts = DirectOptions {
        rel_tol: 0.0,
        ..DirectOptions::default()
    };
    assert!(convolution_direct(0.1, 1.0, 2.0, 0.5, 1.0, &opts).is_err());
    // The band-limit cap is reported as such.
    let opts = ZhOptions {
        start_band: Some(16),
        max_band: 64,
        ..ZhOptions::default()
    };
    let e = convolution_zh(300.0, 2.0, 0.002, 1.0, &[0.0], &opts).unwrap_err();
    assert!(
        matches!(e, ConvError::BandLimitExceeded { band_limit: 64, .. }),
        "{e:?}"
    );
}

#[test]
fn e_l2_rule_and_metric() {
    // The rule integrates ∫ sin θ = 1 and narrow profiles.
    for &w in &[1e-4, 1e-2, 0.5] {
        let rule = ProfileRule::new(w);
        let s: f64 = rule.weights.iter().sum();
        assert!((s - 1.0).abs() < 1e-14, "{s}");
        let f = |t: f64| (-(t / w).powi(2)).exp();
        let q: f64 = rule
            .nodes
            .iter()
            .zip(&rule.weights)
            .map(|(t, wt)| f(*t) * wt)
            .sum();
        let cuts: Vec<f64> = (0..30).map(|k| w * 2f64.powi(k - 6)).collect();
        let exact = integrate_split(|t| f(t) * t.sin(), cuts);
        assert!(rel(q, exact) < 1e-12, "w={w}: {q} vs {exact}");
    }
    // e_L2 of the exact profile is 0, of a 1%-scaled one 0.01.
    let (u, c, beta, p) = (1.0, 2.0, 0.05, 1.0);
    let exact = |t: &[f64]| convolution_profile(u, c, beta, p, t);
    let params = Params::new(u, c, beta, p).unwrap();
    let rule = ProfileRule::for_params(&params);
    let values = exact(&rule.nodes).unwrap();
    let lookup = |t: f64| values[rule.nodes.iter().position(|&x| x == t).unwrap()];
    let w = params.kernel_width().hypot(params.ndf_width());
    assert_eq!(e_l2(lookup, exact, w).unwrap(), 0.0);
    let e = e_l2_for(|t| 1.01 * lookup(t), u, c, beta, p).unwrap();
    assert!((e - 0.01).abs() < 1e-12, "{e}");
}

#[test]
fn profile_rule_orders() {
    // Lower orders keep the intervals: same node count per interval, ∫ sin = 1
    // to rounding, and order 16 is `new`.
    for &w in &[1e-4, 1e-2, 0.5] {
        assert_eq!(ProfileRule::with_order(w, 16), ProfileRule::new(w));
        let n16 = ProfileRule::new(w).nodes.len();
        for (order, tol) in [(1, 1e-2), (4, 1e-9), (8, 1e-14)] {
            let rule = ProfileRule::with_order(w, order);
            assert_eq!(rule.nodes.len() * 16, n16 * order);
            let s: f64 = rule.weights.iter().sum();
            assert!((s - 1.0).abs() < tol, "{order}: {s}");
        }
    }
    assert_eq!(
        ProfileRule::with_order(0.1, 0),
        ProfileRule::with_order(0.1, 1)
    );
}

/// The angles of the corner sweep: the peak, the scales of both lobes, the
/// tails and the horizon.
const SWEEP_THETAS: [f64; 14] = [
    0.0,
    1e-4,
    5e-4,
    0.002,
    0.01,
    0.05,
    0.1,
    0.3,
    0.5,
    1.0,
    1.3,
    1.5,
    1.5697963267948966,
    std::f64::consts::FRAC_PI_2,
];

/// `|a − b| / max(|b|, TARGET · c0)`: the error measure of the accuracy
/// target (relative where `C > 1e-6 C(0)`, in units of `1e-6 C(0)` below).
fn metric(a: f64, b: f64, c0: f64) -> f64 {
    (a - b).abs() / b.abs().max(TARGET * c0.abs())
}

/// The full corner sweep of the domain: ZH (doubling from L = 32 up to
/// 65536) against the direct quadrature in both frames. Prints one line per
/// parameter point. Run with
/// `cargo test --release -p generator corner_sweep -- --ignored --nocapture`.
#[test]
#[ignore]
fn corner_sweep() {
    use std::time::Instant;
    let mut worst_zh = (0.0f64, String::new());
    let mut worst_frames = (0.0f64, String::new());
    println!(
        "u c beta p | L_zh t_zh change | max m(zh,direct) at θ | max m(normal,half) | ms/θ normal half"
    );
    for &u in &[0.0, 1.0, 30.0, 300.0, 3000.0] {
        for &beta in &[0.002, 0.05, 1.0] {
            for &p in &[0.2, 0.5, 1.0, 5.0] {
                for &c in &[1.01, 2.0, 10.0] {
                    let t0 = Instant::now();
                    let zh = convolution_zh(
                        u,
                        c,
                        beta,
                        p,
                        &SWEEP_THETAS,
                        &ZhOptions {
                            start_band: Some(16),
                            ..ZhOptions::default()
                        },
                    );
                    let t_zh = t0.elapsed().as_secs_f64();
                    let mut normal = vec![];
                    let t0 = Instant::now();
                    for &t in &SWEEP_THETAS {
                        let o = DirectOptions {
                            frame: Frame::Normal,
                            ..DirectOptions::default()
                        };
                        normal.push(convolution_direct(t, u, c, beta, p, &o).unwrap().value);
                    }
                    let t_n = t0.elapsed().as_secs_f64() * 1e3 / SWEEP_THETAS.len() as f64;
                    let mut half = vec![];
                    let t0 = Instant::now();
                    for &t in &SWEEP_THETAS {
                        let o = DirectOptions {
                            frame: Frame::Half,
                            ..DirectOptions::default()
                        };
                        half.push(convolution_direct(t, u, c, beta, p, &o).unwrap().value);
                    }
                    let t_h = t0.elapsed().as_secs_f64() * 1e3 / SWEEP_THETAS.len() as f64;
                    let c0 = normal[0];
                    for v in normal.iter().chain(&half) {
                        assert!(v.is_finite() && *v >= 0.0);
                    }
                    let (mut mf, mut at_f) = (0.0f64, 0.0);
                    for i in 0..SWEEP_THETAS.len() {
                        let m = metric(half[i], normal[i], c0);
                        if m > mf {
                            mf = m;
                            at_f = SWEEP_THETAS[i];
                        }
                    }
                    let label = format!("u={u} c={c} β={beta} p={p}");
                    if mf > worst_frames.0 {
                        worst_frames = (mf, format!("{label} θ={at_f}"));
                    }
                    let zh_part = match &zh {
                        Ok(z) => {
                            let (mut mz, mut at) = (0.0f64, 0.0);
                            for i in 0..SWEEP_THETAS.len() {
                                let m = metric(z.values[i], normal[i], c0);
                                if m > mz {
                                    mz = m;
                                    at = SWEEP_THETAS[i];
                                }
                            }
                            if mz > worst_zh.0 {
                                worst_zh = (mz, format!("{label} θ={at}"));
                            }
                            format!(
                                "{:6} {:7.3}s {:.1e} | {:.1e} at {:.4}",
                                z.band_limit, t_zh, z.change, mz, at
                            )
                        }
                        Err(ConvError::BandLimitExceeded { band_limit, change }) => {
                            format!(">{band_limit:5} {t_zh:7.3}s {change:.1e} | n/a")
                        }
                        Err(e) => panic!("{label}: {e}"),
                    };
                    let est = zh_band_estimate(&Params::new(u, c, beta, p).unwrap());
                    println!(
                        "{label} | est {est:6} | {zh_part} | {mf:.1e} at {at_f:.4} | {t_n:.1} {t_h:.1}"
                    );
                }
            }
        }
    }
    println!("worst ZH vs direct: {:.2e} ({})", worst_zh.0, worst_zh.1);
    println!(
        "worst normal vs half frame: {:.2e} ({})",
        worst_frames.0, worst_frames.1
    );
    assert!(worst_frames.0 <= TARGET);
    assert!(worst_zh.0 <= TARGET);
}

/// Accuracy of the limiting forms against the direct quadrature, as a
/// function of the width ratio. Prints tables; run with `--ignored
/// --nocapture`.
#[test]
#[ignore]
fn limits_accuracy_sweep() {
    let exact = |t: f64, u: f64, c: f64, beta: f64, p: f64| {
        convolution_direct(t, u, c, beta, p, &DirectOptions::default())
            .unwrap()
            .value
    };
    println!("(a) narrow kernel: rel. error of W_K D(θh) [order 0 / order 1] vs uβ");
    for &(beta, p) in &[(1.0, 1.0), (0.3, 1.0), (1.0, 5.0), (1.0, 0.5), (0.3, 0.2)] {
        for &c in &[1.01, 2.0, 4.0, 10.0] {
            for &t in &[0.0, 0.3, 0.8] {
                let mut line = format!("β={beta} p={p} c={c} θh={t}:");
                for &u in &[10.0, 30.0, 100.0, 300.0, 1000.0, 3000.0] {
                    let e = exact(t, u, c, beta, p);
                    let a0 = narrow_kernel_limit(t, u, c, beta, p, 0).unwrap();
                    let a1 = narrow_kernel_limit(t, u, c, beta, p, 1)
                        .map(|a| format!("{:.0e}", (a - e).abs() / e))
                        .unwrap_or("-".into());
                    line += &format!(" uβ={:.0}:{:.0e}/{a1}", u * beta, (a0 - e).abs() / e);
                }
                println!("{line}");
            }
        }
    }
    println!(
        "(b) narrow NDF: rel. error of W_D K(θh) [order 0 / order 1] vs u·w_D (w_D = ndf_width)"
    );
    for &u in &[0.0, 1.0, 10.0, 100.0] {
        for &p in &[0.2, 1.0, 5.0] {
            for &c in &[1.01, 10.0] {
                for &t in &[0.0, 0.3, 1.0] {
                    let mut line = format!("u={u} p={p} c={c} θh={t}:");
                    for &beta in &[0.002, 0.005, 0.01, 0.03, 0.1] {
                        let w = Params::new(u, c, beta, p).unwrap().ndf_width();
                        let e = exact(t, u, c, beta, p);
                        let b0 = narrow_ndf_limit(t, u, c, beta, p, 0).unwrap();
                        let b1 = narrow_ndf_limit(t, u, c, beta, p, 1).unwrap();
                        line += &format!(
                            " β={beta}(uw={:.1e}):{:.0e}/{:.0e}",
                            u * w,
                            (b0 - e).abs() / e,
                            (b1 - e).abs() / e
                        );
                    }
                    println!("{line}");
                }
            }
        }
    }
}

/// Wall time of one 64-angle profile through the public entry point, for a
/// cheap and an expensive corner of each method.
#[test]
#[ignore]
fn profile_timings() {
    use std::time::Instant;
    let thetas: Vec<f64> = (0..64).map(|i| FRAC_PI_2 * i as f64 / 63.0).collect();
    for &(u, c, beta, p) in &[
        (1.0, 2.0, 1.0, 1.0),
        (30.0, 2.0, 0.05, 0.5),
        (300.0, 2.0, 0.002, 1.0),
        (0.0, 2.0, 1.0, 0.2),
        (3000.0, 2.0, 1.0, 1.0),
        (3000.0, 1.01, 0.002, 0.2),
        (3000.0, 10.0, 0.002, 5.0),
        (300.0, 2.0, 1.0, 0.2),
        (0.0, 2.0, 0.002, 5.0),
    ] {
        let t0 = Instant::now();
        let (v, m) = convolution_profile_with_method(u, c, beta, p, &thetas).unwrap();
        let dt = t0.elapsed();
        let t0 = Instant::now();
        let d: Vec<f64> = thetas
            .iter()
            .map(|&t| convolution(t, u, c, beta, p).unwrap())
            .collect();
        let dd = t0.elapsed();
        let worst = v
            .iter()
            .zip(&d)
            .map(|(x, y)| metric(*x, *y, d[0]))
            .fold(0.0, f64::max);
        println!(
            "u={u} c={c} β={beta} p={p} (L est {}): {m:?} {dt:.2?}; direct {dd:.2?}; max diff {worst:.1e}",
            zh_band_estimate(&Params::new(u, c, beta, p).unwrap())
        );
    }
}

/// docs/model.md §2.5 says `L = 400` leaves `e_L2 ≈ 2e-4` at `p = 0.2, u = 30,
/// β = 0.5`; prints the measured value for several `c`.
#[test]
#[ignore]
fn spec_claim_l400() {
    for &c in &[1.01, 2.0, 3.0, 10.0] {
        let (u, beta, p) = (30.0, 0.5, 0.2);
        let params = Params::new(u, c, beta, p).unwrap();
        let (k, d) = (params.kernel(), params.ndf());
        let a = legendre_moments(|s, co| k.value(s, co), &k.breakpoints(), 400);
        let b = legendre_moments(|s, co| d.value(s, co), &d.breakpoints(), 400);
        let e = e_l2_for(|t| zh_series(&a, &b, 400, t), u, c, beta, p).unwrap();
        println!("c={c}: e_L2(L=400) = {e:.2e}");
    }
}

/// Random off-grid parameter points (deterministic LCG, log-uniform in `u`,
/// `β`, `p`, `c − 1`), at random angles: both direct frames, and zonal
/// harmonics where [`zh_band_estimate`] allows them.
#[test]
#[ignore]
fn random_sweep() {
    let mut state = 0x2545_f491_4f6c_dd1du64;
    let mut next = || {
        state = state
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        (state >> 11) as f64 / (1u64 << 53) as f64
    };
    let log_uniform = |x: f64, lo: f64, hi: f64| (lo.ln() + x * (hi / lo).ln()).exp();
    let (mut worst_frames, mut worst_zh) = (0.0f64, 0.0f64);
    let mut n_zh = 0;
    for i in 0..60 {
        let u = if i % 10 == 0 {
            0.0
        } else {
            log_uniform(next(), 0.1, 3000.0)
        };
        let c = 1.0 + log_uniform(next(), 0.01, 9.0);
        let beta = log_uniform(next(), 0.002, 1.0);
        let p = log_uniform(next(), 0.2, 5.0);
        let mut thetas: Vec<f64> = (0..6).map(|_| FRAC_PI_2 * next().powi(2)).collect();
        thetas.push(0.0);
        let mut normal = vec![];
        let mut half = vec![];
        for &t in &thetas {
            for (frame, out) in [(Frame::Normal, &mut normal), (Frame::Half, &mut half)] {
                let o = DirectOptions {
                    frame,
                    ..DirectOptions::default()
                };
                out.push(convolution_direct(t, u, c, beta, p, &o).unwrap().value);
            }
        }
        let c0 = normal[thetas.len() - 1];
        let mf = (0..thetas.len())
            .map(|k| metric(half[k], normal[k], c0))
            .fold(0.0, f64::max);
        worst_frames = worst_frames.max(mf);
        let est = zh_band_estimate(&Params::new(u, c, beta, p).unwrap());
        let mut line = format!("u={u:.3} c={c:.3} β={beta:.4} p={p:.3}: frames {mf:.1e}");
        if est <= ZH_MAX_BAND {
            let o = ZhOptions {
                max_band: ZH_MAX_BAND,
                ..ZhOptions::default()
            };
            match convolution_zh(u, c, beta, p, &thetas, &o) {
                Ok(z) => {
                    let mz = (0..thetas.len())
                        .map(|k| metric(z.values[k], normal[k], c0))
                        .fold(0.0, f64::max);
                    worst_zh = worst_zh.max(mz);
                    n_zh += 1;
                    line += &format!(", zh L={} {mz:.1e}", z.band_limit);
                }
                Err(e) => line += &format!(", zh failed (est {est}): {e}"),
            }
        }
        println!("{line}");
    }
    println!("worst frames {worst_frames:.2e}, worst zh {worst_zh:.2e} over {n_zh} zh points");
    assert!(worst_frames <= TARGET && worst_zh <= TARGET);
}

#[test]
fn outside_the_domain_is_finite_or_an_error() {
    // Beyond the table domain the reference is still defined; it must
    // return a finite non-negative value or an error, never panic or NaN.
    for &(t, u, c, beta, p) in &[
        (0.1, 1e5, 1.001, 1e-4, 0.1),
        (1.5, 1e-3, 50.0, 3.0, 8.0),
        (FRAC_PI_2, 5000.0, 1.5, 0.001, 0.15),
    ] {
        if let Ok(v) = convolution(t, u, c, beta, p) {
            assert!(v.is_finite() && v >= 0.0, "{t} {u} {c} {beta} {p}: {v}");
        }
    }
}
