//! Where the T3 build's time goes (docs/design/t3-build-speed.md): times the
//! reference profile and the fit of a deterministic sample of T3 nodes (every
//! `stride`-th node; 61 is coprime with every axis length, so the sample
//! spreads over all four axes) and prints one CSV row per node, then the
//! totals by method and by u node, extrapolated to the whole grid (×stride).
//! One thread (the per-node CPU time is what the figures are about). With
//! `zh_only`, only the nodes that the build tries by zonal harmonics
//! (`convolution::node_tries_zonal_harmonics`).

use generator::tables::convolution::{
    angle_rule, fit_paper_form, node_count, node_params, node_tries_zonal_harmonics,
};
use std::collections::BTreeMap;
use std::time::Instant;
use twoscale_reference::reference::conv::{Method, MomentCache, convolution_profile_cached};

/// Times every `stride`-th node (only the zonal-harmonic ones with
/// `zh_only`); CSV rows on stdout, totals on stderr.
pub fn run(stride: usize, zh_only: bool) {
    let stride = stride.max(1);
    let total = node_count();
    println!("index,u,c,beta,p,method,band,profile_s,fit_s");
    let mut by_method: BTreeMap<String, (usize, f64)> = BTreeMap::new();
    let mut by_u: BTreeMap<u64, (usize, f64)> = BTreeMap::new();
    let mut fit_total = 0.0;
    // Shared as in the build; a sample reuses moments less often than the
    // whole grid, so the zonal-harmonic figures are upper bounds.
    let cache = MomentCache::new();
    for index in (0..total).step_by(stride) {
        if zh_only && !node_tries_zonal_harmonics(index) {
            continue;
        }
        let [u, c, beta, p] = node_params(index);
        let (thetas, weights) = angle_rule(u, beta, p);
        let start = Instant::now();
        let (values, method) =
            convolution_profile_cached(u, c, beta, p, &thetas, &cache).expect("profile");
        let t_profile = start.elapsed().as_secs_f64();
        let start = Instant::now();
        let _ = fit_paper_form(c, &thetas, &weights, &values);
        let t_fit = start.elapsed().as_secs_f64();
        let (name, band) = match method {
            Method::ZonalHarmonics { band_limit } => ("zh", band_limit),
            Method::Direct => ("direct", 0),
        };
        println!("{index},{u},{c},{beta},{p},{name},{band},{t_profile:.6},{t_fit:.6}");
        let key = if name == "zh" {
            format!("zh L={band:>5}")
        } else {
            "direct".to_string()
        };
        let e = by_method.entry(key).or_default();
        e.0 += 1;
        e.1 += t_profile;
        let e = by_u.entry(u.to_bits()).or_default();
        e.0 += 1;
        e.1 += t_profile + t_fit;
        fit_total += t_fit;
    }
    let k = stride as f64;
    eprintln!("by method (sampled nodes, CPU s, extrapolated ×{stride}):");
    for (m, (n, t)) in &by_method {
        eprintln!("  {m:<12} {n:>5} nodes {t:>9.2} s  -> {:>9.0} s", t * k);
    }
    eprintln!(
        "  fit          {fit_total:>9.2} s -> {:>9.0} s",
        fit_total * k
    );
    eprintln!("by u (profile + fit):");
    for (u, (n, t)) in &by_u {
        eprintln!(
            "  u = {:>10.4} {n:>4} nodes {t:>8.2} s -> {:>8.0} s",
            f64::from_bits(*u),
            t * k
        );
    }
}
