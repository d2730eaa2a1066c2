//! T4 through the runtime: the committed files' shape, exact reciprocity, the
//! absent coefficients, the f32 evaluation against the f64 projection, and
//! the reflected radiance of a constant sky (directional albedo).

use generator::analytic::{BeckmannCt, Lambertian};
use generator::sh::{IsotropicBrdf, Projection, default_quadrature, project};
use generator::tables::TableKind;
use generator::tables::t4::ShBrdf;
use twoscale::ShBrdfTable;
use twoscale::format::aligned_copy;
use twoscale::sh::{ProjectedModel, coefficient_count, normalized_legendre};

/// Builds a one-material T4 file in memory from the materials text.
fn built(materials: &str) -> twoscale::format::AlignedBuf {
    let materials = generator::materials::Materials::parse(materials).unwrap();
    let kind = &ShBrdf::all(&materials)[0];
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
n = [1.5, 1.5]
k = [0.0, 0.0]
base = "plastic"
albedo = [0.5, 0.2]
band_limit = 10
"#;

#[test]
fn committed_t4_files_read_and_are_reciprocal() {
    let buf = suite::read_table(twoscale::TableId::ShBrdf);
    let table = ShBrdfTable::from_bytes(buf.bytes()).unwrap();
    assert_eq!(table.model(), ProjectedModel::BeckmannStandIn);
    assert_eq!(table.channels(), 3);
    let pairs = generator::tables::t4::verification_pairs(500, 3);
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
    let brdf = generator::tables::t4::material_brdf(&materials.materials[0], 1, 0.526).unwrap();
    let projection = project(brdf.as_ref(), 10, default_quadrature(10), None);
    let mut worst: f64 = 0.0;
    for (wi, wo) in generator::tables::t4::verification_pairs(2000, 5) {
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
fn table_from(projection: &Projection) -> twoscale::format::AlignedBuf {
    use twoscale::format::write::{TableSpec, encode};
    use twoscale::format::{AxisHeader, Kernel, Mapping};
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
    let mut aux = vec![0.0f32; twoscale::sh::AUX_NAMES.len()];
    aux[0] = ProjectedModel::Lambertian.code() as f32;
    let bytes = encode(&TableSpec {
        table_id: twoscale::TableId::ShBrdf,
        channels: 1,
        kernel: Kernel::Multilinear,
        axes: &[axis],
        params: &[l as f64, 0.0, 0.0, 0.5, 0.0, 0.0, 0.0, 40.0],
        grid: &grid,
        aux: &aux,
        generator_version: "test",
    })
    .unwrap();
    aligned_copy(&bytes)
}
