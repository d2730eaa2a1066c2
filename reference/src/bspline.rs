//! Prefiltering for the runtime's cubic B-spline tables: from samples at the
//! nodes to the spline coefficients that interpolate them.
//!
//! Along one axis with `n` nodes at coordinates `0 … n−1`, the spline is
//! `S(t) = Σ_j c_j B(t − j)` over `j = −1 … n` (`n + 2` coefficients; the
//! runtime stores coefficient `j` at index `j + 1`), with `B` the uniform cubic
//! B-spline. The `n + 2` unknowns are fixed by
//! - interpolation at the nodes: `(c_{i−1} + 4 c_i + c_{i+1}) / 6 = y_i`, and
//! - the not-a-knot end conditions: the third derivative is continuous at the
//!   first and last interior knots, i.e. the fourth difference of the
//!   coefficients around them vanishes:
//!   `c_{−1} − 4c_0 + 6c_1 − 4c_2 + c_3 = 0` and its mirror at the other end.
//!
//! Not-a-knot needs no end derivatives and reproduces cubic polynomials
//! exactly. In several dimensions the prefilter is applied along each axis in
//! turn (the tensor-product spline then interpolates every node). The linear
//! system is solved by Gaussian elimination with partial pivoting, factored
//! once per axis; everything is sequential f64, so the result is bit-reproducible.

/// The LU factors of one axis's `(n+2) × (n+2)` system.
struct Factored {
    size: usize,
    /// Row-major LU (unit lower triangle implied), after row exchanges.
    lu: Vec<f64>,
    /// Row permutation.
    pivot: Vec<usize>,
}

impl Factored {
    fn new(nodes: usize) -> Factored {
        assert!(nodes >= 4, "not-a-knot needs at least 4 nodes per axis");
        let size = nodes + 2;
        let mut a = vec![0.0; size * size];
        let mut set = |row: usize, col: usize, v: f64| a[row * size + col] = v;
        for (k, v) in [1.0, -4.0, 6.0, -4.0, 1.0].into_iter().enumerate() {
            set(0, k, v);
            set(size - 1, size - 5 + k, v);
        }
        for i in 0..nodes {
            set(i + 1, i, 1.0 / 6.0);
            set(i + 1, i + 1, 4.0 / 6.0);
            set(i + 1, i + 2, 1.0 / 6.0);
        }
        let mut pivot: Vec<usize> = (0..size).collect();
        for col in 0..size {
            let best = (col..size)
                .max_by(|&x, &y| a[x * size + col].abs().total_cmp(&a[y * size + col].abs()))
                .unwrap_or(col);
            if best != col {
                for k in 0..size {
                    a.swap(col * size + k, best * size + k);
                }
                pivot.swap(col, best);
            }
            let diag = a[col * size + col];
            for row in col + 1..size {
                let factor = a[row * size + col] / diag;
                a[row * size + col] = factor;
                if factor != 0.0 {
                    for k in col + 1..size {
                        a[row * size + k] -= factor * a[col * size + k];
                    }
                }
            }
        }
        Factored { size, lu: a, pivot }
    }

    /// Solves for the coefficients given the `n` samples (the right-hand side
    /// is `[0, y_0 … y_{n−1}, 0]`).
    fn solve(&self, samples: &[f64], out: &mut [f64]) {
        let n = self.size;
        let rhs = |row: usize| {
            if row == 0 || row == n - 1 {
                0.0
            } else {
                samples[row - 1]
            }
        };
        for (i, &p) in self.pivot.iter().enumerate() {
            out[i] = rhs(p);
        }
        for row in 0..n {
            out[row] = (0..row).fold(out[row], |v, k| v - self.lu[row * n + k] * out[k]);
        }
        for row in (0..n).rev() {
            let v = (row + 1..n).fold(out[row], |v, k| v - self.lu[row * n + k] * out[k]);
            out[row] = v / self.lu[row * n + row];
        }
    }
}

/// Turns samples on a row-major grid with `nodes[d]` nodes per axis into
/// row-major B-spline coefficients with `nodes[d] + 2` per axis.
pub fn prefilter(samples: &[f64], nodes: &[usize]) -> Vec<f64> {
    assert_eq!(samples.len(), nodes.iter().product::<usize>());
    let mut shape: Vec<usize> = nodes.to_vec();
    let mut data = samples.to_vec();
    for axis in 0..nodes.len() {
        let n = nodes[axis];
        let factored = Factored::new(n);
        let outer: usize = shape[..axis].iter().product();
        let inner: usize = shape[axis + 1..].iter().product();
        let mut next = vec![0.0; outer * (n + 2) * inner];
        let mut line = vec![0.0; n];
        let mut coefficients = vec![0.0; n + 2];
        for o in 0..outer {
            for i in 0..inner {
                for (k, v) in line.iter_mut().enumerate() {
                    *v = data[(o * n + k) * inner + i];
                }
                factored.solve(&line, &mut coefficients);
                for (k, &v) in coefficients.iter().enumerate() {
                    next[(o * (n + 2) + k) * inner + i] = v;
                }
            }
        }
        shape[axis] = n + 2;
        data = next;
    }
    data
}

/// Evaluates the 1-D spline with `coefficients` (`n + 2` of them) at node
/// coordinate `t ∈ [0, n − 1]`, in f64 (for tests and verification).
pub fn evaluate_1d(coefficients: &[f64], t: f64) -> f64 {
    let cells = coefficients.len() - 3;
    let i = (t.floor().max(0.0) as usize).min(cells - 1);
    let f = t - i as f64;
    let s = 1.0 - f;
    let w = [
        s * s * s / 6.0,
        (3.0 * f * f * f - 6.0 * f * f + 4.0) / 6.0,
        (-3.0 * f * f * f + 3.0 * f * f + 3.0 * f + 1.0) / 6.0,
        f * f * f / 6.0,
    ];
    (0..4).map(|k| w[k] * coefficients[i + k]).sum()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn interpolates_the_samples_and_reproduces_cubics() {
        for n in [4usize, 5, 9, 72] {
            let cubic = |t: f64| 0.3 - 1.2 * t + 0.05 * t * t + 0.01 * t * t * t;
            let samples: Vec<f64> = (0..n).map(|i| cubic(i as f64)).collect();
            let c = prefilter(&samples, &[n]);
            assert_eq!(c.len(), n + 2);
            for (i, &y) in samples.iter().enumerate() {
                assert!((evaluate_1d(&c, i as f64) - y).abs() < 1e-12 * (1.0 + y.abs()));
            }
            for k in 0..=100 {
                let t = (n - 1) as f64 * k as f64 / 100.0;
                let want = cubic(t);
                assert!(
                    (evaluate_1d(&c, t) - want).abs() < 1e-11 * (1.0 + want.abs()),
                    "n {n} t {t}"
                );
            }
        }
    }

    /// Fourth-order convergence on a smooth function: the error falls ~16x
    /// when the node spacing halves.
    #[test]
    fn converges_at_fourth_order() {
        let f = |x: f64| (2.0 * x).sin() + x.exp();
        let mut errors = Vec::new();
        for n in [33usize, 65, 129, 257] {
            let h = 2.0 / (n - 1) as f64;
            let samples: Vec<f64> = (0..n).map(|i| f(i as f64 * h)).collect();
            let c = prefilter(&samples, &[n]);
            let max = (0..1000)
                .map(|k| {
                    let x = 2.0 * (k as f64 + 0.5) / 1000.0;
                    (evaluate_1d(&c, x / h) - f(x)).abs()
                })
                .fold(0.0, f64::max);
            errors.push(max);
        }
        for pair in errors.windows(2) {
            let ratio = pair[0] / pair[1];
            assert!(
                (12.0..=20.0).contains(&ratio),
                "ratio {ratio} in {errors:?}"
            );
        }
    }

    /// In 2-D the tensor-product spline interpolates every node.
    #[test]
    fn two_dimensional_prefilter_interpolates() {
        let (n0, n1) = (6usize, 7usize);
        let f = |a: f64, b: f64| (a * 0.7).sin() * (b * 0.3).cos() + a * b * 0.01;
        let samples: Vec<f64> = (0..n0 * n1)
            .map(|k| f((k / n1) as f64, (k % n1) as f64))
            .collect();
        let c = prefilter(&samples, &[n0, n1]);
        assert_eq!(c.len(), (n0 + 2) * (n1 + 2));
        for i in 0..n0 {
            // Evaluate along axis 1 for each of the 4 neighbouring rows, then along axis 0.
            for j in 0..n1 {
                let rows: Vec<f64> = (0..n0 + 2)
                    .map(|r| evaluate_1d(&c[r * (n1 + 2)..(r + 1) * (n1 + 2)], j as f64))
                    .collect();
                let got = evaluate_1d(&rows, i as f64);
                assert!((got - f(i as f64, j as f64)).abs() < 1e-12);
            }
        }
    }
}
