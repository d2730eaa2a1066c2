//! Unit tests of the parent module.

use super::*;
use core::f64::consts::PI;

/// Gauss–Legendre nodes and weights on [−1, 1] by Newton's method on the
/// Legendre recurrence (independent of the recurrence under test).
fn gauss_legendre(n: usize) -> (Vec<f64>, Vec<f64>) {
    let mut nodes = Vec::with_capacity(n);
    let mut weights = Vec::with_capacity(n);
    for k in 0..n {
        let mut x = (PI * (k as f64 + 0.75) / (n as f64 + 0.5)).cos();
        let mut derivative = 0.0;
        for _ in 0..100 {
            let (mut p0, mut p1) = (1.0, x);
            for j in 2..=n {
                let p2 = ((2 * j - 1) as f64 * x * p1 - (j - 1) as f64 * p0) / j as f64;
                p0 = p1;
                p1 = p2;
            }
            derivative = n as f64 * (x * p1 - p0) / (x * x - 1.0);
            let step = p1 / derivative;
            x -= step;
            if step.abs() < 1e-16 {
                break;
            }
        }
        nodes.push(x);
        weights.push(2.0 / ((1.0 - x * x) * derivative * derivative));
    }
    (nodes, weights)
}

/// Legendre polynomial P_l by Bonnet's recurrence.
fn legendre(l: usize, x: f64) -> f64 {
    let (mut p0, mut p1) = (1.0, x);
    if l == 0 {
        return 1.0;
    }
    for j in 2..=l {
        let p2 = ((2 * j - 1) as f64 * x * p1 - (j - 1) as f64 * p0) / j as f64;
        p0 = p1;
        p1 = p2;
    }
    p1
}

fn direction(theta: f64, phi: f64) -> [f64; 3] {
    [
        theta.sin() * phi.cos(),
        theta.sin() * phi.sin(),
        theta.cos(),
    ]
}

#[test]
fn low_degrees_match_closed_forms() {
    let mut y = vec![0.0; 9];
    for &(theta, phi) in &[(0.3, 0.2), (1.2, -2.0), (2.9, 4.0), (0.0, 0.0)] {
        let d = direction(theta, phi);
        let (x, yy, z) = (d[0], d[1], d[2]);
        assert_eq!(real_sh(d, 2, &mut y), Some(9));
        let c1 = (3.0 / (4.0 * PI)).sqrt();
        let c2 = (15.0 / (4.0 * PI)).sqrt();
        let want = [
            0.5 / PI.sqrt(),
            c1 * yy,
            c1 * z,
            c1 * x,
            c2 * x * yy,
            c2 * yy * z,
            (5.0 / (16.0 * PI)).sqrt() * (3.0 * z * z - 1.0),
            c2 * x * z,
            0.5 * c2 * (x * x - yy * yy),
        ];
        for k in 0..9 {
            assert!(
                (y[k] - want[k]).abs() < 1e-15,
                "k = {k}: {} vs {}",
                y[k],
                want[k]
            );
        }
    }
}

#[test]
fn orthonormal_by_quadrature() {
    // Gauss–Legendre (24 nodes, exact to degree 47 in cos θ) × 32 midpoint
    // nodes in φ (exact for trigonometric degree < 32): exact for l ≤ 12.
    let l_max = 12;
    let count = (l_max + 1) * (l_max + 1);
    let (nodes, weights) = gauss_legendre(24);
    let n_phi = 32;
    let mut gram = vec![0.0; count * count];
    let mut y = vec![0.0; count];
    for (&x, &w) in nodes.iter().zip(&weights) {
        for k in 0..n_phi {
            let phi = 2.0 * PI * (k as f64 + 0.5) / n_phi as f64;
            real_sh(direction(x.acos(), phi), l_max, &mut y).unwrap();
            let weight = w * 2.0 * PI / n_phi as f64;
            for a in 0..count {
                for b in 0..count {
                    gram[a * count + b] += weight * y[a] * y[b];
                }
            }
        }
    }
    for a in 0..count {
        for b in 0..count {
            let want = if a == b { 1.0 } else { 0.0 };
            assert!((gram[a * count + b] - want).abs() < 1e-13, "({a}, {b})");
        }
    }
}

#[test]
fn high_degrees_satisfy_the_addition_theorem() {
    // Σ_m Y_lm(a) Y_lm(b) = (2l+1)/(4π) P_l(a·b): checks every order m of
    // the recurrence against Bonnet's recurrence for P_l, up to l = 127.
    let l_max = MAX_BAND_LIMIT;
    let mut ya = vec![0.0; (l_max + 1) * (l_max + 1)];
    let mut yb = ya.clone();
    let mut worst: f64 = 0.0;
    for &(ta, pa, tb, pb) in &[
        (0.4, 0.1, 0.45, 0.3),
        (1.3, 2.0, 1.5, -1.0),
        (0.05, 1.0, 2.8, 0.5),
        (1.5, 0.0, 1.55, 0.0),
        (0.9, 0.7, 0.9, 0.7),
    ] {
        let (a, b) = (direction(ta, pa), direction(tb, pb));
        real_sh(a, l_max, &mut ya).unwrap();
        real_sh(b, l_max, &mut yb).unwrap();
        let cos_ab = a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
        for l in [1, 10, 30, 60, 61, 90, 127] {
            let sum: f64 = (l * l..(l + 1) * (l + 1)).map(|k| ya[k] * yb[k]).sum();
            let want = (2 * l + 1) as f64 / (4.0 * PI) * legendre(l, cos_ab);
            let scale = (2 * l + 1) as f64 / (4.0 * PI);
            worst = worst.max((sum - want).abs() / scale);
        }
    }
    // Measured: 1.3e-12 (rounding grows about linearly in l).
    assert!(worst < 1e-11, "worst relative error {worst:e}");
}

#[test]
fn packed_layout_counts_and_indices() {
    for l in MIN_BAND_LIMIT..=40 {
        let mut seen = vec![false; coefficient_count(l)];
        for m in 0..=l {
            for a in m..=l {
                for b in m..=l {
                    let index = packed_coefficient_index(l, m, a, b);
                    let stored = a > m && b > m && (a + m) % 2 == 1 && (b + m) % 2 == 1;
                    assert_eq!(index.is_some(), stored, "L {l} m {m} ({a}, {b})");
                    assert_eq!(index, packed_coefficient_index(l, m, b, a));
                    if let (Some(k), true) = (index, a <= b) {
                        assert!(!seen[k], "index {k} used twice");
                        seen[k] = true;
                    }
                }
            }
        }
        assert!(seen.iter().all(|&s| s), "L = {l}: a packed slot is unused");
    }
    assert_eq!(packed_coefficient_index(5, 6, 7, 7), None);
}

#[test]
fn real_sh_rejects_bad_input() {
    let mut y = [0.0; 4];
    assert_eq!(real_sh([0.0, 0.0, 1.0], 2, &mut y), None);
    assert_eq!(real_sh([0.0, 0.0, 0.0], 1, &mut y), None);
    assert_eq!(real_sh([f64::NAN, 0.0, 1.0], 1, &mut y), None);
    assert_eq!(real_sh([0.0, 0.0, 1.0], 1, &mut y), Some(4));
}
