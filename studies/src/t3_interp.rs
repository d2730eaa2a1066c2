//! Interpolation of T3b across its parameters
//! (`docs/design/t3-interpolation.md`), measured on the committed table's
//! node values at random parameter points against exact profiles:
//!
//! * [`cubic_axes`]: which parameter axes get Catmull–Rom instead of linear
//!   weights (the runtime's `ConvTable::with_cubic_axes`);
//! * [`spline`]: Catmull–Rom (shipped) against a not-a-knot cubic B-spline
//!   on prefiltered coefficients (`twoscale_reference::bspline::prefilter`, the same
//!   storage), along the parameters, along ξ, or both.

use crate::common::{AXES, Distribution, Exact, cell, committed_t3, percentiles};
use generator::tables::convolution;
use rayon::prelude::*;
use twoscale::tables::convolution::{
    ConvTable, FIT_CHANNELS, along_xi, axis_weights, normalised_angle,
};
use twoscale::tables::interp::{bspline_weights, node_value};
use twoscale_reference::bspline::prefilter;

/// The committed T3 as the runtime reads it, with `cubic` parameter axes,
/// at the rule nodes of `exact`.
fn runtime_lookup(table: &ConvTable<'_>, exact: &Exact) -> Vec<f64> {
    let [u, c, b, p] = exact.point.map(|x| x as f32);
    exact
        .rule
        .nodes
        .iter()
        .map(|&t| f64::from(table.at_tan(t.tan(), u, c, b, p)))
        .collect()
}

/// For every combination of Catmull–Rom (`true`) and linear parameter
/// axes `(u, c, β, p)`: e_L2 and the core's pointwise error of the committed
/// table on `profiles` of verify's profiles (seed 99).
pub fn cubic_axes(profiles: usize) {
    let buf = committed_t3();
    let base = ConvTable::from_bytes(buf.bytes()).expect("valid T3");
    let exact: Vec<Exact> = Distribution::Verify
        .points(profiles, 99)
        .into_par_iter()
        .map(Exact::new)
        .collect();
    println!("{profiles} profiles; cubic axes (u c β p): e_L2 median/p90/max | core median/p95");
    for mask in 0..16u32 {
        let cubic = [0, 1, 2, 3].map(|d| mask & (1 << d) != 0);
        let table = base.with_cubic_axes(cubic);
        let (mut el2, mut core, mut tail) = (vec![], vec![], vec![]);
        for e in &exact {
            let approx = runtime_lookup(&table, e);
            el2.push(e.e_l2(&approx));
            e.pointwise(&approx, &mut core, &mut tail);
        }
        println!(
            "{cubic:?}: e_L2 {} | core {}",
            percentiles(&mut el2, &[0.5, 0.9, 1.0]),
            percentiles(&mut core, &[0.5, 0.95]),
        );
    }
}

/// One way of interpolating the stored `ln C` values.
struct Variant {
    name: &'static str,
    /// B-spline (prefiltered) across the parameters, else Catmull–Rom.
    params_bspline: bool,
    /// B-spline (prefiltered) along ξ, else the lookup's cubic.
    xi_bspline: bool,
    /// Per parameter node (row-major u, c, β, p), the values along ξ:
    /// node values, or B-spline coefficients (`n + 2` per prefiltered axis).
    data: Vec<f64>,
}

impl Variant {
    fn params_dims(&self) -> [usize; 4] {
        let extra = if self.params_bspline { 2 } else { 0 };
        AXES.map(|a| a.nodes as usize + extra)
    }

    fn angles(&self) -> usize {
        convolution::ANGLES + if self.xi_bspline { 2 } else { 0 }
    }

    /// `C` at `τ = tan θh` and the point, in f64 from the variant's data.
    fn lookup(&self, point: [f64; 4], tau: f64) -> f64 {
        let dims = self.params_dims();
        let weights: [(usize, usize, [f32; 4]); 4] = std::array::from_fn(|d| {
            let (i, t) = cell(d, point[d]);
            if self.params_bspline {
                (i, 4, bspline_weights(t))
            } else {
                axis_weights(dims[d], (i, t), true)
            }
        });
        let angles = self.angles();
        // ln C's stored channel k blended over the parameter cell.
        let blend = |k: usize| -> f64 {
            let mut sum = 0.0;
            for a in 0..weights[0].1 {
                for b in 0..weights[1].1 {
                    for c in 0..weights[2].1 {
                        for e in 0..weights[3].1 {
                            let w = f64::from(
                                weights[0].2[a]
                                    * weights[1].2[b]
                                    * weights[2].2[c]
                                    * weights[3].2[e],
                            );
                            let node = (((weights[0].0 + a) * dims[1] + weights[1].0 + b)
                                * dims[2]
                                + weights[2].0
                                + c)
                                * dims[3]
                                + weights[3].0
                                + e;
                            sum += w * self.data[node * angles + k];
                        }
                    }
                }
            }
            sum
        };
        let [u, _, beta, p] = point;
        let xi = normalised_angle(tau, u, beta, p, &convolution::ANGLE);
        let ln_c = if self.xi_bspline {
            let position = xi.clamp(0.0, 1.0) * (convolution::ANGLES - 1) as f64;
            let i = (position.floor() as usize).min(convolution::ANGLES - 2);
            let w = bspline_weights((position - i as f64) as f32);
            (0..4).map(|k| f64::from(w[k]) * blend(i + k)).sum()
        } else {
            f64::from(along_xi(convolution::ANGLES, xi, |first| {
                std::array::from_fn(|k| blend(first + k) as f32)
            }))
        };
        ln_c.exp()
    }
}

/// The committed table's `ln C` node values, `[node][angle]`.
fn node_values() -> Vec<f64> {
    let buf = committed_t3();
    let raw = twoscale::Table::from_bytes(buf.bytes()).expect("valid T3");
    let grid = raw.quantised().expect("T3 is stored quantised");
    (0..grid.nodes())
        .flat_map(|i| {
            (FIT_CHANNELS..convolution::CHANNELS).map(move |k| f64::from(grid.value(i, k)))
        })
        .collect()
}

/// Prefilters `[node][angle]` data along the parameters: per angle, the
/// 4-D array of node values to `n + 2` coefficients per axis.
fn prefilter_params(data: &[f64], angles: usize) -> Vec<f64> {
    let nodes = AXES.map(|a| a.nodes as usize);
    let per_angle: Vec<Vec<f64>> = (0..angles)
        .into_par_iter()
        .map(|k| {
            let samples: Vec<f64> = data.iter().skip(k).step_by(angles).copied().collect();
            prefilter(&samples, &nodes)
        })
        .collect();
    let count = per_angle[0].len();
    (0..count)
        .flat_map(|i| per_angle.iter().map(move |v| v[i]))
        .collect()
}

/// Prefilters `[node][angle]` data along ξ: `angles + 2` coefficients per node.
fn prefilter_xi(data: &[f64], angles: usize) -> Vec<f64> {
    data.chunks(angles)
        .flat_map(|line| prefilter(line, &[angles]))
        .collect()
}

/// Catmull–Rom against the not-a-knot B-spline on `profiles` points of
/// `distribution` from `seed`, with the parameters in `snap` (any of `u`,
/// `c`, `b`, `p`) snapped to their nearest nodes (isolating the other axes'
/// and ξ's error). Prints e_L2 and the pointwise error on the rule's nodes
/// (core and tail) per variant.
pub fn spline(profiles: usize, seed: u64, distribution: Distribution, snap: &str) {
    let values = node_values();
    let angles = convolution::ANGLES;
    let params = prefilter_params(&values, angles);
    let variants = [
        Variant {
            name: "cr/cr",
            params_bspline: false,
            xi_bspline: false,
            data: values.clone(),
        },
        Variant {
            name: "cr/bs",
            params_bspline: false,
            xi_bspline: true,
            data: prefilter_xi(&values, angles),
        },
        Variant {
            name: "bs/bs",
            params_bspline: true,
            xi_bspline: true,
            data: prefilter_xi(&params, angles),
        },
        Variant {
            name: "bs/cr",
            params_bspline: true,
            xi_bspline: false,
            data: params,
        },
    ];
    let points: Vec<[f64; 4]> = distribution
        .points(profiles, seed)
        .into_iter()
        .map(|mut pt| {
            for (d, key) in ['u', 'c', 'b', 'p'].into_iter().enumerate() {
                if snap.contains(key) {
                    let (i, t) = cell(d, pt[d]);
                    pt[d] = node_value(&AXES[d], i + usize::from(t >= 0.5));
                }
            }
            pt
        })
        .collect();
    let exact: Vec<Exact> = points.into_par_iter().map(Exact::new).collect();

    // The f64 Catmull–Rom against the runtime's f32 lookup: the variants'
    // shared blend reproduces the shipped lookup.
    let buf = committed_t3();
    let table = ConvTable::from_bytes(buf.bytes()).expect("valid T3");
    let mut worst = 0.0f64;
    for e in &exact {
        for (&t, r) in e
            .rule
            .nodes
            .iter()
            .zip(runtime_lookup(&table, e))
            .step_by(7)
        {
            if r > 1e-30 {
                let m = variants[0].lookup(e.point, t.tan());
                worst = worst.max(((m - r) / r).abs());
            }
        }
    }
    println!("cr/cr in f64 vs the runtime: max relative difference {worst:.2e}");
    println!(
        "{profiles} profiles ({distribution:?}, seed {seed}, snapped: {snap:?}): \
         e_L2 median/p90/p99/max | core median/p95/max | tail median/p95/max"
    );
    for v in &variants {
        let (mut el2, mut core, mut tail) = (vec![], vec![], vec![]);
        for e in &exact {
            let approx: Vec<f64> = e
                .rule
                .nodes
                .iter()
                .map(|&t| v.lookup(e.point, t.tan()))
                .collect();
            el2.push(e.e_l2(&approx));
            e.pointwise(&approx, &mut core, &mut tail);
        }
        println!(
            "{:6} e_L2 {} | core {} | tail {}",
            v.name,
            percentiles(&mut el2, &[0.5, 0.9, 0.99, 1.0]),
            percentiles(&mut core, &[0.5, 0.95, 1.0]),
            percentiles(&mut tail, &[0.5, 0.95, 1.0]),
        );
    }
}
