//! T4 through the runtime: the committed files' shape, exact reciprocity and
//! accuracy against the two-scale model they project, the asymmetry the
//! two-scale model gives before symmetrising, the absent coefficients, the
//! f32 evaluation against the f64 projection, and the reflected radiance of
//! a constant sky (directional albedo).

use generator::analytic::{BeckmannCt, Lambertian};
use generator::sh::{IsotropicBrdf, Projection, default_quadrature, project};
use generator::tables::TableKind;
use generator::tables::sh_brdf::{ModelInputs, Projected, ShBrdf};
use twoscale::ShBrdfTable;
use twoscale::tables::format::aligned_copy;
use twoscale::tables::sh_brdf::{ProjectedModel, coefficient_count, normalized_legendre};

/// Builds a one-material T4 file of the Beckmann stand-in in memory from
/// the materials text.
fn built(materials: &str) -> twoscale::tables::format::AlignedBuf {
    let materials = generator::materials::Materials::parse(materials).unwrap();
    let kind = &ShBrdf::all(&materials, &Projected::BeckmannStandIn)[0];
    let bytes = kind.build(&indicatif::ProgressBar::hidden()).unwrap();
    aligned_copy(&bytes)
}

const ROUGH: &str = r#"
wavelengths = [0.645, 0.526]
[[material]]
name = "rough"
beta = 0.4
p = 1.0
sigma_s = 0.0
b = 1.0
c = 2.0
eta = [[1.5, 0.0], [1.5, 0.0]]
base = "plastic"
albedo = 0.5
band_limit = 10
"#;

#[test]
fn committed_t4_files_read_and_are_reciprocal() {
    let buf = suite::read_table(twoscale::TableId::ShBrdf);
    let table = ShBrdfTable::from_bytes(buf.bytes()).unwrap();
    // The first preset: its integrated RGB (RgbMode::default_for).
    assert_eq!(table.model(), ProjectedModel::IntegratedRgb);
    assert_eq!(table.channels(), 3);
    let pairs = generator::tables::sh_brdf::verification_pairs(500, 3);
    for (wi, wo) in pairs {
        let (i, o) = (wi.map(|v| v as f32), wo.map(|v| v as f32));
        let (a, b) = (table.eval_rgb(i, o), table.eval_rgb(o, i));
        assert_eq!(a.map(f32::to_bits), b.map(f32::to_bits), "{i:?} {o:?}");
    }
    assert_eq!(table.eval(0, [0.0, 0.0, 1.0], [0.3, 0.0, -0.1]), 0.0);
    assert_eq!(table.eval(0, [0.0, 0.0, 0.0], [0.0, 0.0, 1.0]), 0.0);
    assert_eq!(table.eval(7, [0.0, 0.0, 1.0], [0.0, 0.0, 1.0]), 0.0);
}

#[test]
fn vanishing_coefficients_are_absent_and_the_matrix_is_symmetric() {
    let buf = built(ROUGH);
    let table = ShBrdfTable::from_bytes(buf.bytes()).unwrap();
    let l_max = table.band_limit();
    let mut stored = 0;
    for m in 0..=l_max {
        for l in 0..=l_max + 1 {
            for lp in 0..=l_max + 1 {
                let v = table.coefficient(0, m, l, lp);
                assert_eq!(v.to_bits(), table.coefficient(0, m, lp, l).to_bits());
                let odd = l > m && lp > m && (l + m) % 2 == 1 && (lp + m) % 2 == 1;
                if !odd || l > l_max || lp > l_max {
                    assert_eq!(v, 0.0, "m {m} ({l}, {lp})");
                } else if l <= lp {
                    stored += 1;
                }
            }
        }
    }
    assert_eq!(stored, coefficient_count(l_max));
    // The file holds exactly those values per channel, nothing else.
    let header = twoscale::Table::from_bytes(buf.bytes()).unwrap();
    assert_eq!(header.grid().len(), coefficient_count(l_max) * 2);
}

#[test]
fn runtime_eval_matches_the_f64_projection() {
    let buf = built(ROUGH);
    let table = ShBrdfTable::from_bytes(buf.bytes()).unwrap();
    let materials = generator::materials::Materials::parse(ROUGH).unwrap();
    let brdf =
        generator::tables::sh_brdf::material_brdf(&materials.materials[0], 1, 0.526, None).unwrap();
    let projection = project(brdf.as_ref(), 10, default_quadrature(10), None);
    let mut worst: f64 = 0.0;
    for (wi, wo) in generator::tables::sh_brdf::verification_pairs(2000, 5) {
        let want = projection.eval(wi, wo) * wi[2] * wo[2];
        let got = f64::from(table.eval(1, wi.map(|v| v as f32), wo.map(|v| v as f32)));
        worst = worst.max((got * wi[2] * wo[2] - want).abs());
    }
    // f32 coefficients and f32 directions: ~1e-6 of f's scale (0.1 here).
    assert!(worst < 2e-6, "{worst:e}");
}

/// `c_l0 = 2 · 2π ∫₀¹ P̄_l^0(x) dx` of a constant sky (runtime docs), by
/// Gauss–Legendre (exact: degree ≤ L).
fn constant_sky(l_max: usize) -> Vec<f32> {
    let (nodes, weights) = generator::quad::gauss_legendre(64);
    let mut coefficients = vec![0.0f32; (l_max + 1) * (l_max + 1)];
    let mut p = vec![0.0; l_max + 1];
    for l in (1..=l_max).step_by(2) {
        let mut integral = 0.0;
        for (t, w) in nodes.iter().zip(&weights) {
            normalized_legendre(0, 0.5 * (t + 1.0), l_max, &mut p).unwrap();
            integral += 0.5 * w * p[l];
        }
        coefficients[l * (l + 1)] = (4.0 * std::f64::consts::PI * integral) as f32;
    }
    coefficients
}

#[test]
fn constant_sky_gives_the_albedo() {
    // Lambertian: L_o = albedo exactly (the matrix is exact at any L ≥ 1).
    let albedo = 0.7;
    let projection = project(&Lambertian { albedo }, 6, default_quadrature(6), None);
    let table = table_from(&projection);
    let table = ShBrdfTable::from_bytes(table.bytes()).unwrap();
    let sky = constant_sky(6);
    for o in [[0.0f32, 0.0, 1.0], [0.6, 0.0, 0.8], [0.1, -0.99, 0.05]] {
        let got = table.radiance(0, &sky, o);
        assert!((f64::from(got) - albedo).abs() < 2e-6, "{o:?}: {got}");
    }
    // Rough Beckmann: L_o against the directional albedo by direct quadrature.
    let brdf = BeckmannCt {
        alpha: 0.5,
        eta: None,
    };
    let l = 16;
    let table = table_from(&project(&brdf, l, default_quadrature(l), None));
    let table = ShBrdfTable::from_bytes(table.bytes()).unwrap();
    let sky = constant_sky(l);
    for theta in [0.2f64, 0.8, 1.2] {
        let o = [theta.sin(), 0.0, theta.cos()];
        let got = f64::from(table.radiance(0, &sky, o.map(|v| v as f32)));
        let want = albedo_of(&brdf, o);
        assert!(
            (got - want).abs() < 0.01 * want,
            "θo {theta}: {got} vs {want}"
        );
    }
}

/// `∫ ρ(i, o) cos θi dωi` by Gauss–Legendre in cos θi × midpoint in φ.
fn albedo_of(brdf: &dyn IsotropicBrdf, o: [f64; 3]) -> f64 {
    let (nodes, weights) = generator::quad::gauss_legendre(200);
    let n_phi = 400;
    let mut sum = 0.0;
    for (t, w) in nodes.iter().zip(&weights) {
        let x = 0.5 * (t + 1.0);
        let s = (1.0 - x * x).sqrt();
        for k in 0..n_phi {
            let phi = 2.0 * std::f64::consts::PI * (k as f64 + 0.5) / n_phi as f64;
            let i = [s * phi.cos(), s * phi.sin(), x];
            sum += 0.5 * w * x * brdf.eval(i, o) * 2.0 * std::f64::consts::PI / n_phi as f64;
        }
    }
    sum
}

/// A one-channel T4 file of a projection.
fn table_from(projection: &Projection) -> twoscale::tables::format::AlignedBuf {
    use twoscale::tables::format::write::{TableSpec, encode};
    use twoscale::tables::format::{AxisHeader, Kernel, Mapping};
    let l = projection.band_limit();
    let count = coefficient_count(l);
    let grid: Vec<f32> = projection.packed(None).iter().map(|&v| v as f32).collect();
    let axis = AxisHeader {
        nodes: count as u32,
        mapping: Mapping::Uniform,
        lo: 0.0,
        hi: (count - 1) as f64,
        param: 0.0,
        param2: 0.0,
    };
    let mut aux = vec![0.0f32; twoscale::tables::sh_brdf::AUX_NAMES.len()];
    aux[0] = ProjectedModel::Lambertian.code() as f32;
    let bytes = encode(&TableSpec {
        table_id: twoscale::TableId::ShBrdf,
        channels: 1,
        kernel: Kernel::Multilinear,
        value_type: twoscale::tables::format::ValueType::F32,
        axes: &[axis],
        params: &[l as f64, 0.0, 0.0, 0.5, 0.0, 0.0, 0.0, 40.0],
        grid: &grid,
        aux: &aux,
        generator_version: "test",
    })
    .unwrap();
    aligned_copy(&bytes)
}

/// The workspace's T1, T2, T5 and T3 (T4's inputs).
fn model_inputs() -> ModelInputs {
    ModelInputs::load(std::path::Path::new(
        generator::tables::sh_brdf::WORKSPACE_TABLES,
    ))
    .unwrap()
}

/// `(rel RMS of f, p99 and max of |Δf| / max f)` of `rho_sh` against
/// `rho` over `pairs`, `f = ρ cos θi cos θo`.
fn f_errors(
    pairs: &[([f64; 3], [f64; 3])],
    rho: impl Fn([f64; 3], [f64; 3]) -> f64,
    rho_sh: impl Fn([f64; 3], [f64; 3]) -> f64,
) -> (f64, f64, f64) {
    let values: Vec<(f64, f64)> = pairs
        .iter()
        .map(|&(i, o)| {
            let cc = i[2] * o[2];
            (rho(i, o) * cc, rho_sh(i, o) * cc)
        })
        .collect();
    let peak = values.iter().fold(0.0f64, |m, v| m.max(v.0));
    let norm: f64 = values.iter().map(|v| v.0 * v.0).sum();
    let sum2: f64 = values.iter().map(|v| (v.1 - v.0).powi(2)).sum();
    let mut errors: Vec<f64> = values.iter().map(|v| (v.1 - v.0).abs() / peak).collect();
    errors.sort_by(f64::total_cmp);
    (
        (sum2 / norm).sqrt(),
        errors[errors.len() * 99 / 100],
        errors[errors.len() - 1],
    )
}

#[test]
fn committed_rough_file_matches_the_integrated_two_scale_model() {
    let buf = suite::read_table(twoscale::TableId::ShBrdf);
    let table = ShBrdfTable::from_bytes(buf.bytes()).unwrap();
    let path = concat!(env!("CARGO_MANIFEST_DIR"), "/materials.toml");
    let materials = generator::materials::Materials::load(std::path::Path::new(path)).unwrap();
    let gold = materials
        .materials
        .iter()
        .find(|m| m.name == "gold-rough")
        .unwrap();
    assert_eq!(Some(table.band_limit()), gold.band_limit);
    // σs > 0: σrel(θi) makes the model non-reciprocal, and the header says so.
    assert!(table.asymmetry() > 1e-4, "{:e}", table.asymmetry());
    let inputs = model_inputs();
    let parsed = inputs.parse().unwrap();
    let tables = parsed.brdf_tables();
    let pairs = generator::tables::sh_brdf::verification_pairs(4000, 21);
    for (c, &lambda) in materials.wavelengths.iter().enumerate() {
        // The preset's default RGB: channel c of the integral over the spectrum.
        let brdf =
            generator::tables::sh_brdf::material_brdf(gold, c, lambda, Some(&tables)).unwrap();
        let (rms, p99, max) = f_errors(
            &pairs,
            |i, o| brdf.eval(i, o),
            |i, o| f64::from(table.eval(c, i.map(|v| v as f32), o.map(|v| v as f32))),
        );
        eprintln!("gold-rough λ{c}: rel RMS {rms:.3e}, p99 {p99:.3e}, max {max:.3e}");
        // Measured: docs/design/t4-band-limits.md, "Result and cost".
        assert!(
            rms < RMS_BOUND && p99 < P99_BOUND && max < MAX_BOUND,
            "λ{c}"
        );
    }
}

#[test]
fn two_scale_projection_is_asymmetric_only_with_nano_roughness() {
    let inputs = model_inputs();
    let parsed = inputs.parse().unwrap();
    let tables = parsed.brdf_tables();
    let text = ROUGH
        .replace("base = \"plastic\"", "base = \"conductor\"")
        .replace("albedo = 0.5\n", "")
        .replace("[[1.5, 0.0], [1.5, 0.0]]", "[[1.5, 3.0], [1.5, 3.0]]");
    let l = 8;
    let mut asymmetry = Vec::new();
    for sigma_s in ["0.0", "0.05"] {
        let text = text.replace("sigma_s = 0.0", &format!("sigma_s = {sigma_s}"));
        let materials = generator::materials::Materials::parse(&text).unwrap();
        let brdf =
            generator::tables::sh_brdf::two_scale_brdf(&materials.materials[0], 1, 0.526, &tables);
        let (diff, norm) = project(&brdf, l, default_quadrature(l), None).asymmetry();
        eprintln!("σs = {sigma_s}: ‖M − Mᵀ‖/‖M‖ = {:.3e}", diff / norm);
        asymmetry.push(diff / norm);
    }
    // σs = 0: the EPD Cook–Torrance conductor, reciprocal up to the f32
    // rounding of the model's arithmetic; σs > 0: σrel(θi) breaks reciprocity.
    assert!(asymmetry[0] < 1e-6, "{:e}", asymmetry[0]);
    assert!(asymmetry[1] > 1e3 * asymmetry[0].max(1e-9), "{asymmetry:?}");
}

// Bounds of `committed_rough_file_matches_the_two_scale_model`: the figures
// measured on the committed gold-rough file (L = 24, 4000 pairs of seed 21;
// worst channel, blue: rel RMS 3.67e-2, p99 3.44e-2, max 0.134) raised by
// about 15%: a file projected at L = 16 (5.4e-2 RMS) or from another BRDF
// fails (the paper's three wavelengths instead of the integral: 8.0e-2 RMS).
const RMS_BOUND: f64 = 0.042;
const P99_BOUND: f64 = 0.040;
const MAX_BOUND: f64 = 0.15;
