//! T3's parameter axes (`docs/design/t3-grid-and-quantisation.md`): node
//! count and mapping of one axis at a time, with the others exact.
//!
//! For random triples of points, the first fixes the other parameters;
//! `ln C` at its node angles is computed exactly at every node of each
//! candidate axis and interpolated as the lookup does (the runtime's
//! `Axis::locate` and Catmull–Rom `axis_weights`) to the triple's other two
//! values of the axis, against exact `ln C` there.

use crate::common::{Distribution, exact_c, floored_ln, percentiles};
use generator::tables::convolution;
use rayon::prelude::*;
use twoscale::tables::convolution::axis_weights;
use twoscale::tables::format::{AxisHeader, Mapping};
use twoscale::tables::interp::{Axis, node_value};

/// A parameter axis of T3.
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub enum Param {
    /// `u`, the kernel's scale.
    U,
    /// `c`, the kernel's exponent.
    C,
    /// `p`, the NDF's shape.
    P,
}

impl Param {
    /// Index in `(u, c, β, p)`.
    fn index(self) -> usize {
        match self {
            Param::U => 0,
            Param::C => 1,
            Param::P => 3,
        }
    }

    /// The candidate layouts compared for this axis (the shipped one among
    /// them).
    fn candidates(self) -> Vec<AxisHeader> {
        let with = |base: AxisHeader, nodes, mapping, param, param2| AxisHeader {
            nodes,
            mapping,
            param,
            param2,
            ..base
        };
        match self {
            Param::U => [
                (16, 0.1),
                (16, 1.0),
                (16, 3.0),
                (20, 1.0),
                (28, 0.1),
                (28, 1.0),
            ]
            .map(|(n, offset)| with(convolution::U_AXIS, n, Mapping::LogOffset, offset, 0.0))
            .to_vec(),
            Param::C => [(10, 0.0), (10, 0.25), (10, 0.5), (10, 1.0), (12, 0.5)]
                .map(|(n, linear)| with(convolution::C_AXIS, n, Mapping::LogOffset, -1.0, linear))
                .to_vec(),
            Param::P => vec![
                with(convolution::P_AXIS, 12, Mapping::Power, -0.5, 0.0),
                with(convolution::P_AXIS, 12, Mapping::Log, 0.0, 0.0),
                with(convolution::P_AXIS, 12, Mapping::Power, -0.25, 0.0),
                with(convolution::P_AXIS, 12, Mapping::LogOffset, 0.0, 0.3),
                with(convolution::P_AXIS, 14, Mapping::Log, 0.0, 0.0),
            ],
        }
    }
}

/// Runs the study of `param`'s axis on `triples` triples of both
/// distributions; prints the pointwise error where `C > 1e-3 C(0)` (core)
/// and `1e-9 C(0) < C ≤ 1e-3 C(0)` (tail) per candidate.
pub fn run(param: Param, triples: usize) {
    let axis = param.index();
    let candidates = param.candidates();
    for (distribution, seed) in [
        (Distribution::Verify, 7 + axis as u64),
        (Distribution::Brdf, 107 + axis as u64),
    ] {
        let points = distribution.points(triples * 3, seed);
        // ln C along the base point's node angles, with the axis set to x.
        let profile = |base: [f64; 4], x: f64| -> Vec<f64> {
            let mut q = base;
            q[axis] = x;
            // The node angles depend on u, β, p (not on c).
            let angles_of = if axis == 1 { base } else { q };
            let (thetas, _) = convolution::angle_rule(angles_of[0], angles_of[2], angles_of[3]);
            floored_ln(&exact_c(q, &thetas))
        };
        type Row = (Vec<Vec<Vec<f64>>>, Vec<(f64, Vec<f64>)>);
        let rows: Vec<Row> = (0..triples)
            .into_par_iter()
            .map(|t| {
                let base = points[3 * t];
                let at_nodes = candidates
                    .iter()
                    .map(|a| {
                        (0..a.nodes as usize)
                            .map(|i| profile(base, node_value(a, i)))
                            .collect()
                    })
                    .collect();
                let tests = (1..3)
                    .map(|k| {
                        let x = points[3 * t + k][axis];
                        (x, profile(base, x))
                    })
                    .collect();
                (at_nodes, tests)
            })
            .collect();
        for (ci, a) in candidates.iter().enumerate() {
            let runtime_axis = Axis::new(a).expect("valid candidate axis");
            let (mut core, mut tail) = (Vec::new(), Vec::new());
            for (at_nodes, tests) in &rows {
                let at_nodes = &at_nodes[ci];
                for (x, exact) in tests {
                    let cell = runtime_axis.locate(*x as f32);
                    let (start, count, w) = axis_weights(a.nodes as usize, cell, true);
                    let peak = exact.iter().copied().fold(f64::MIN, f64::max);
                    for (k, &e) in exact.iter().enumerate() {
                        let v: f64 = (0..count)
                            .map(|j| f64::from(w[j]) * at_nodes[start + j][k])
                            .sum();
                        let rel = (v - e).exp_m1().abs();
                        if e > peak + 1e-3f64.ln() {
                            core.push(rel);
                        } else if e > peak + 1e-9f64.ln() {
                            tail.push(rel);
                        }
                    }
                }
            }
            println!(
                "{distribution:?} {:2} nodes {:?} param {} param2 {}: core median/p95/max {} | tail {}",
                a.nodes,
                a.mapping,
                a.param,
                a.param2,
                percentiles(&mut core, &[0.5, 0.95, 1.0]),
                percentiles(&mut tail, &[0.5, 0.95, 1.0]),
            );
        }
    }
}
