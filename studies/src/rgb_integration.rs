//! RGB by integration over the spectrum (docs/design/rgb-integration.md):
//! what the paper's three wavelengths miss, and how few wavelengths an
//! integrating RGB model needs.
//!
//! The reference is the CIE 5 nm sum of `twoscale::spectrum::colour` over 85
//! one-wavelength models, each built at its λ with the preset's measured
//! η(λ). The candidates, evaluated at the same pairs, interpolate a spectrum
//! from K wavelengths λ_k with a basis `L_k(λ)` and integrate the
//! interpolant exactly against the 5 nm weights:
//!
//! * `paper`: the RGB model at 0.645, 0.526, 0.444 µm (`brdf::Rgb`);
//! * `hat K`: ρ itself, `L_k` the hat functions of K wavelengths evenly
//!   spaced over [0.40, 0.70] µm (held beyond): `Σ_k ρ(λ_k) Σ_j L_k(λ_j) W_c,j`;
//! * `cheb K`: the same with `L_k` the Lagrange polynomials of K Chebyshev
//!   nodes over [0.38, 0.72] µm (clamped to it beyond);
//! * `F-hat K`, `F-cheb K`: ρ/F(θd) interpolated and integrated against
//!   `F(θd, λ) w_c`: `Σ_k ρ(λ_k)/F(θd, λ_k) · T_kc(cos θd)` with
//!   `T_kc = Σ_j L_k(λ_j) W_c,j F(θd, λ_j)` (a per-material bake over
//!   `cos θd`, computed exactly here). The metal's fast colour lives in F;
//!   what is left of ρ is smooth in λ.
//!
//! Errors are relative per channel, over pairs where the reference channel
//! exceeds 1e-3 of the preset's largest value at the pairs.

use crate::common;
use std::fmt::Write as _;
use std::path::Path;
use twoscale::TableSet;
use twoscale::brdf::{ChannelBake, TwoScale};
use twoscale::material::Options;
use twoscale::materials::SPECTRAL_PRESETS;
use twoscale::model::fresnel::{fresnel, q_bar};
use twoscale::spectrum::colour::{self, SRGB_WEIGHTS, WAVELENGTH_COUNT};
use twoscale_reference::rng::SplitMix64;

/// The candidate wavelength counts.
const COUNTS: [usize; 3] = [4, 6, 8];

/// What a candidate divides each lobe by before interpolating in λ (and
/// integrates the interpolant against): the specular lobe and the halo.
#[derive(Clone, Copy, PartialEq)]
enum Weight {
    /// Nothing (ρ itself).
    None,
    /// F(θd, λ) for every lobe.
    Fd,
    /// F(θd, λ) for the specular lobe, F(0°, λ) for the halo.
    FdR0,
    /// F(θd, λ) for the specular lobe, √(F(θi, λ) F(θo, λ)) for the halo.
    FdFio,
    /// F(θd, λ) for the specular lobe, Q̄(i, o, λ) for the halo (not
    /// bakeable: Q̄ depends on the pair; the bound of what a halo weight can do).
    FdQ,
    /// F(θd, λ) for the specular lobe; the halo as `Q̄ · H` with Q̄ from its
    /// values at this many hat nodes over [0.40, 0.70] µm and H = halo/Q̄ from
    /// the basis' nodes: `Σ_q Σ_k Q̄(λ_q) H(λ_k) M_qkc`,
    /// `M_qkc = Σ_j hat_q(λ_j) L_k(λ_j) W_c,j` (material independent).
    FdQHats(usize),
}

/// An interpolation basis over K wavelengths: the nodes (µm) and `L_k(λ_j)`
/// at the 5 nm nodes, `at[j][k]`.
struct Basis {
    nodes: Vec<f32>,
    at: Vec<Vec<f64>>,
}

impl Basis {
    /// Hats on K nodes evenly spaced over [0.40, 0.70] µm, held beyond.
    fn hats(count: usize) -> Basis {
        let (lo, hi) = (0.40f64, 0.70f64);
        let nodes = (0..count)
            .map(|k| (lo + (hi - lo) * k as f64 / (count - 1) as f64) as f32)
            .collect();
        let at = (0..WAVELENGTH_COUNT)
            .map(|j| {
                let l = f64::from(colour::wavelength(j)).clamp(lo, hi);
                let t = (l - lo) / (hi - lo) * (count - 1) as f64;
                let k = (t.floor() as usize).min(count - 2);
                let f = t - k as f64;
                let mut row = vec![0.0; count];
                row[k] = 1.0 - f;
                row[k + 1] = f;
                row
            })
            .collect();
        Basis { nodes, at }
    }

    /// Lagrange polynomials on K Chebyshev nodes over [0.38, 0.72] µm,
    /// the argument clamped to the interval.
    fn chebyshev(count: usize) -> Basis {
        let (lo, hi) = (0.38f64, 0.72f64);
        let x: Vec<f64> = (0..count)
            .map(|k| {
                let t = ((2 * k + 1) as f64 * std::f64::consts::PI / (2 * count) as f64).cos();
                0.5 * (lo + hi) - 0.5 * (hi - lo) * t
            })
            .collect();
        let at = (0..WAVELENGTH_COUNT)
            .map(|j| {
                let l = f64::from(colour::wavelength(j)).clamp(lo, hi);
                (0..count)
                    .map(|k| {
                        (0..count)
                            .filter(|&m| m != k)
                            .map(|m| (l - x[m]) / (x[k] - x[m]))
                            .product()
                    })
                    .collect()
            })
            .collect();
        Basis {
            nodes: x.iter().map(|&v| v as f32).collect(),
            at,
        }
    }

    /// `Σ_j L_k(λ_j) W_c,j g(λ_j)`, per node k and channel c.
    fn weights(&self, g: &[f64]) -> Vec<[f64; 3]> {
        let mut t = vec![[0.0; 3]; self.nodes.len()];
        for (j, row) in self.at.iter().enumerate() {
            for (k, l) in row.iter().enumerate() {
                for c in 0..3 {
                    t[k][c] += l * f64::from(SRGB_WEIGHTS[j][c]) * g[j];
                }
            }
        }
        t
    }
}

/// A direction with `cos θ` uniform (so grazing pairs are represented).
fn direction(rng: &mut SplitMix64) -> [f32; 3] {
    let z = rng.uniform_in(0.02, 1.0);
    let phi = rng.uniform_in(0.0, 2.0 * std::f64::consts::PI);
    let s = (1.0 - z * z).sqrt();
    [(s * phi.cos()) as f32, (s * phi.sin()) as f32, z as f32]
}

/// `cos θd` of a pair.
fn cos_d(i: [f32; 3], o: [f32; 3]) -> f32 {
    let (wi, wo) = (i.map(f64::from), o.map(f64::from));
    let norm = |v: [f64; 3]| (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]).sqrt();
    let (ni, no) = (norm(wi), norm(wo));
    let h = [0, 1, 2].map(|k| wi[k] / ni + wo[k] / no);
    let nh = norm(h);
    ((wi[0] * h[0] + wi[1] * h[1] + wi[2] * h[2]) / (ni * nh)) as f32
}

/// p99 and max of `errors` (0 when empty).
fn p99_max(errors: &mut [f64]) -> (f64, f64) {
    if errors.is_empty() {
        return (0.0, 0.0);
    }
    errors.sort_by(f64::total_cmp);
    let p99 = errors[((errors.len() as f64 * 0.99) as usize).min(errors.len() - 1)];
    (p99, errors[errors.len() - 1])
}

/// Prints the two tables (and writes them to `markdown` when given).
pub fn run(pairs: usize, seed: u64, markdown: Option<&Path>) -> Result<(), String> {
    common::check_markdown(markdown)?;
    let set = TableSet::embedded();
    let tables = set.brdf_tables();
    let options = Options::default();
    // (family name, weight, basis)
    let mut bases = Vec::new();
    for (name, weighted) in [
        ("hat", Weight::None),
        ("cheb", Weight::None),
        ("F-hat", Weight::Fd),
        ("F-cheb", Weight::Fd),
        ("F/R0-cheb", Weight::FdR0),
        ("F/Fio-cheb", Weight::FdFio),
        ("F/Q-cheb", Weight::FdQ),
        ("F/Q6hat-cheb", Weight::FdQHats(6)),
        ("F/Q8hat-cheb", Weight::FdQHats(8)),
        ("F/Q12hat-cheb", Weight::FdQHats(12)),
    ] {
        for k in COUNTS {
            let basis = if name.ends_with("hat") {
                Basis::hats(k)
            } else {
                Basis::chebyshev(k)
            };
            bases.push((format!("{name} {k}"), weighted, basis));
        }
    }
    let mut geometry_rows = Vec::new();
    let mut table = Vec::new();
    for preset in SPECTRAL_PRESETS {
        let m = preset.material;
        let model = |lambda: f32| {
            TwoScale::new_in(
                ChannelBake::boxed(),
                &tables,
                m.layer,
                lambda,
                m.eta.at(lambda),
                options,
            )
        };
        let spectral: Vec<_> = (0..WAVELENGTH_COUNT)
            .map(|j| model(colour::wavelength(j)))
            .collect();
        let node_models: Vec<Vec<_>> = bases
            .iter()
            .map(|(_, _, b)| b.nodes.iter().map(|&l| model(l)).collect())
            .collect();
        let flat = vec![1.0; WAVELENGTH_COUNT];
        let plain: Vec<_> = bases.iter().map(|(_, _, b)| b.weights(&flat)).collect();
        let paper = set.rgb(&m.paper_rgb(), options);
        let green = &spectral[(530 - 360) / 5];
        // The reference and the candidates (paper, then `bases`) at (i, o).
        let evaluate = |i: [f32; 3], o: [f32; 3]| {
            let mut reference = [0.0; 3];
            for (j, ch) in spectral.iter().enumerate() {
                let v = f64::from(ch.eval(i, o));
                for c in 0..3 {
                    reference[c] += f64::from(SRGB_WEIGHTS[j][c]) * v;
                }
            }
            let cd = cos_d(i, o);
            let f_at = |l: f32, cos: f32| f64::from(fresnel(m.eta.at(l), cos));
            // The halo's weight g(λ) of each kind.
            let halo_weight = |w: Weight, l: f32| match w {
                Weight::None => 1.0,
                Weight::Fd => f_at(l, cd),
                Weight::FdR0 => f_at(l, 1.0),
                Weight::FdFio => (f_at(l, i[2]) * f_at(l, o[2])).sqrt(),
                Weight::FdQ | Weight::FdQHats(_) => f64::from(q_bar(m.eta.at(l), i, o)),
            };
            let lambdas: Vec<f32> = (0..WAVELENGTH_COUNT).map(colour::wavelength).collect();
            let spec_spectrum: Vec<f64> = lambdas.iter().map(|&l| f_at(l, cd)).collect();
            let mut candidates = vec![paper.eval(i, o).map(f64::from)];
            for (k, (_, weighted, basis)) in bases.iter().enumerate() {
                let (t_spec, t_halo) = if *weighted == Weight::None {
                    (plain[k].clone(), plain[k].clone())
                } else {
                    let halo: Vec<f64> =
                        lambdas.iter().map(|&l| halo_weight(*weighted, l)).collect();
                    (basis.weights(&spec_spectrum), basis.weights(&halo))
                };
                let mut out = [0.0; 3];
                for (n, ch) in node_models[k].iter().enumerate() {
                    let lobes = ch.eval_lobes(i, o);
                    let l = basis.nodes[n];
                    let (gs, gh) = if *weighted == Weight::None {
                        (1.0, 1.0)
                    } else {
                        (f_at(l, cd), halo_weight(*weighted, l))
                    };
                    let spec = f64::from(lobes.specular) / gs;
                    let halo = if gh > 0.0 {
                        f64::from(lobes.diffraction) / gh
                    } else {
                        0.0
                    };
                    let halo = if let Weight::FdQHats(q_count) = *weighted {
                        // Σ_q Q̄(λ_q) M_qkc applied to H(λ_k) here; t_halo unused.
                        let hats = Basis::hats(q_count);
                        let q_nodes: Vec<f64> = hats
                            .nodes
                            .iter()
                            .map(|&lq| halo_weight(*weighted, lq))
                            .collect();
                        let mut mq = [0.0; 3];
                        for (j, (hrow, lrow)) in hats.at.iter().zip(&basis.at).enumerate() {
                            let q: f64 = hrow.iter().zip(&q_nodes).map(|(h, q)| h * q).sum();
                            for c in 0..3 {
                                mq[c] += q * lrow[n] * f64::from(SRGB_WEIGHTS[j][c]);
                            }
                        }
                        for c in 0..3 {
                            out[c] += halo * mq[c];
                        }
                        0.0
                    } else {
                        halo
                    };
                    let base = f64::from(lobes.base);
                    for c in 0..3 {
                        out[c] += spec * t_spec[n][c] + halo * t_halo[n][c] + base * plain[k][n][c];
                    }
                }
                candidates.push(out);
            }
            (reference, candidates)
        };
        let mut rows: Vec<([f64; 3], Vec<[f64; 3]>)> = Vec::with_capacity(pairs);
        let mut rng = SplitMix64::new(seed);
        for k in 0..pairs {
            let i = direction(&mut rng);
            let o = if k % 2 == 0 {
                direction(&mut rng)
            } else {
                let u = [
                    rng.uniform() as f32,
                    rng.uniform() as f32,
                    rng.uniform() as f32,
                ];
                match green.sample(i, u) {
                    Some(s) => s.o,
                    None => continue,
                }
            };
            rows.push(evaluate(i, o));
        }
        let peak = rows
            .iter()
            .flat_map(|(r, _)| r.iter().copied())
            .fold(0.0f64, f64::max);
        let stats: Vec<_> = (0..rows[0].1.len())
            .map(|k| {
                let mut e: Vec<f64> = rows
                    .iter()
                    .flat_map(|(r, c)| {
                        (0..3)
                            .filter(move |&ch| r[ch].abs() > 1e-3 * peak)
                            .map(move |ch| (c[k][ch] - r[ch]).abs() / r[ch].abs())
                    })
                    .collect();
                p99_max(&mut e)
            })
            .collect();
        table.push((preset.name, stats));
        // The geometry: θi = 45° in the plane of incidence, o at 0° and 10° from the mirror.
        let t = 45f32.to_radians();
        let i = [t.sin(), 0.0, t.cos()];
        for offset in [0f32, 10.0] {
            let a = (45.0 + offset).to_radians();
            let o = [-a.sin(), 0.0, a.cos()];
            let (reference, candidates) = evaluate(i, o);
            geometry_rows.push((preset.name, offset, reference, candidates[0]));
        }
    }
    let mut out = String::new();
    let _ = writeln!(
        out,
        "## Errors per channel against the 5 nm sum\n\n\
         {pairs} direction pairs per preset (seed {seed}): p99 / max of the relative error \
         per channel, %, where the 5 nm sum exceeds 1e-3 of the preset's peak. `paper` is \
         `Rgb` (0.645, 0.526, 0.444 µm); the others interpolate K wavelengths (`hat K`: \
         hats over [0.40, 0.70] µm, `cheb K`: Chebyshev nodes over [0.38, 0.72] µm) and \
         integrate exactly: ρ itself, `F-`: every lobe divided by F(θd), `F/W-`: the \
         specular lobe by F(θd) and the halo by W (`R0`: F at normal incidence, `Fio`: \
         √(F(θi) F(θo)), `Q`: its exact Q̄, `QNhat`: Q̄ from N hats).\n"
    );
    out.push_str("| preset | paper |");
    for (name, _, _) in &bases {
        let _ = write!(out, " {name} |");
    }
    let _ = writeln!(out, "\n|---|---|{}", "---|".repeat(bases.len()));
    for (name, stats) in &table {
        let _ = write!(out, "| {name} |");
        for (p99, max) in stats {
            let _ = write!(out, " {:.2} / {:.2} |", 100.0 * p99, 100.0 * max);
        }
        out.push('\n');
    }
    let _ = writeln!(
        out,
        "\n## Integrated against three wavelengths at θi = 45°\n\n\
         In the plane of incidence, o at the mirror direction and 10° beyond it; each \
         model's channels divided by their largest; the luminance ratio is the \
         three-wavelength model's Y over the 5 nm sum's.\n"
    );
    let _ = writeln!(
        out,
        "| preset | offset | integrated (R, G, B) | three wavelengths | luminance ratio |\n\
         |---|---|---|---|---|"
    );
    for (name, offset, r, p) in geometry_rows {
        let norm = |v: [f64; 3]| {
            let m = v.iter().copied().fold(f64::MIN, f64::max);
            format!("{:.3}, {:.3}, {:.3}", v[0] / m, v[1] / m, v[2] / m)
        };
        let ratio = colour::luminance(p) / colour::luminance(r);
        let _ = writeln!(
            out,
            "| {name} | {offset}° | {} | {} | {ratio:.3} |",
            norm(r),
            norm(p)
        );
    }
    print!("{out}");
    match markdown {
        Some(path) => common::write_markdown(
            path,
            "RGB by integration over the spectrum: the study's figures",
            &format!("rgb-integration --pairs {pairs} --seed {seed}"),
            &out,
        ),
        None => Ok(()),
    }
}
