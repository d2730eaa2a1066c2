//! The per-material C bake from exact nodes (`reference::brdf::ExactProfiles`)
//! against the default bake from T3b's slice (docs/design/brdf-accuracy.md):
//! the construction's CPU time of each, per random material of the
//! practical domain (`generator::brdf_accuracy::material`), one thread.
//!
//! CPU time is the thread's own (`/proc/thread-self/schedstat`, ns), so
//! that a shared machine inflates it less than wall time. Each line also
//! gives the default bake's error at its nodes against the exact one
//! (`generator::brdf_accuracy::c_bake_errors`): p99 and max.

use generator::brdf_accuracy::{c_bake_errors, material};
use twoscale::TableSet;
use twoscale::brdf::{ChannelBake, TwoScale};
use twoscale::material::{BaseLayer, Layer, Options};
use twoscale_reference::reference::brdf::ExactProfiles;
use twoscale_reference::rng::SplitMix64;

/// The calling thread's CPU time so far (s); NaN where the kernel does not say.
fn thread_cpu() -> f64 {
    std::fs::read_to_string("/proc/thread-self/schedstat")
        .ok()
        .and_then(|s| s.split_whitespace().next()?.parse::<f64>().ok())
        .map_or(f64::NAN, |ns| ns * 1e-9)
}

/// Times `f` in CPU seconds per call, over `calls` calls.
fn cpu_per_call(calls: usize, mut f: impl FnMut()) -> f64 {
    let start = thread_cpu();
    for _ in 0..calls {
        f();
    }
    (thread_cpu() - start) / calls as f64
}

/// Prints, per material, both constructions' CPU time, then their medians
/// and maxima.
pub fn run(materials: usize, seed: u64) {
    let set = TableSet::embedded();
    let tables = set.brdf_tables();
    let exact = set.brdf_tables_with(&ExactProfiles);
    let mut bake = ChannelBake::boxed();
    let (mut t3, mut ex) = (Vec::new(), Vec::new());
    println!("material,beta,p,c,b_over_lambda,t3b_ms,exact_ms,bake_p99,bake_max");
    for k in 0..materials {
        let mut rng = SplitMix64::new(seed.wrapping_add(k as u64));
        let m = material(&mut rng);
        let layer = Layer {
            surface: m.surface,
            base: BaseLayer::Conductor,
            lambertian: 0.0,
        };
        let options = Options::default();
        let build = |t: &twoscale::brdf::Tables<'_>, bake: &mut ChannelBake| {
            let model = TwoScale::new_in(&mut *bake, t, layer, m.lambda, m.eta, options);
            std::hint::black_box(model.eval([0.0, 0.0, 1.0], [0.0, 0.0, 1.0]));
        };
        let a = cpu_per_call(20, || build(&tables, &mut bake));
        let start = thread_cpu();
        let exact_model = m.model(&exact);
        let b = thread_cpu() - start;
        let mut errors: Vec<f64> = c_bake_errors("", &m.model(&tables), &exact_model)
            .into_iter()
            .map(|e| e.0)
            .collect();
        errors.sort_by(f64::total_cmp);
        let at = |q: f64| errors.get(((errors.len().max(1) - 1) as f64 * q).round() as usize);
        let s = m.surface;
        println!(
            "{k},{:.4},{:.3},{:.3},{:.2},{:.3},{:.1},{:.2e},{:.2e}",
            s.beta,
            s.p,
            s.c,
            s.b / m.lambda,
            a * 1e3,
            b * 1e3,
            at(0.99).copied().unwrap_or(f64::NAN),
            at(1.0).copied().unwrap_or(f64::NAN)
        );
        t3.push(a);
        ex.push(b);
    }
    let summary = |v: &mut Vec<f64>| {
        v.sort_by(f64::total_cmp);
        (v[v.len() / 2], v[v.len() - 1])
    };
    let ((t3_median, t3_max), (ex_median, ex_max)) = (summary(&mut t3), summary(&mut ex));
    eprintln!(
        "construction CPU per wavelength over {materials} materials: T3b median {:.2} ms, max {:.2} ms; exact nodes median {:.0} ms, max {:.0} ms",
        t3_median * 1e3,
        t3_max * 1e3,
        ex_median * 1e3,
        ex_max * 1e3
    );
}
