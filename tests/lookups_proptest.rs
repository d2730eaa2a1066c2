//! Property: the runtime's public lookups never panic and never return NaN or
//! ∞ for finite inputs (the crate's contract), over the whole f32 range
//! (subnormals, ±0, extremes) as well as the tables' domains.

use proptest::prelude::*;
use std::sync::LazyLock;
use twoscale::TableSet;
use twoscale::material::{
    BaseLayer, ColourTerms, HaloWeight, Layer, Masking, Material, MultipleScattering, Options,
    SigmaRelMode, Surface,
};
use twoscale::math::Complex;
use twoscale::model::epd::Epd;
use twoscale::model::fresnel::{fresnel, q_bar};
use twoscale::tables::convolution::Convolution;

/// Any finite f32, or a value in a typical parameter range.
fn finite() -> impl Strategy<Value = f32> {
    use proptest::num::f32::{NEGATIVE, NORMAL, POSITIVE, SUBNORMAL, ZERO};
    prop_oneof![
        POSITIVE | NEGATIVE | NORMAL | SUBNORMAL | ZERO,
        -2.0f32..6.0,
        0.0f32..1.0,
    ]
}

/// Validated once: validation reads 4 MB.
static SET: LazyLock<TableSet<'static>> = LazyLock::new(TableSet::embedded);

fn vec3() -> impl Strategy<Value = [f32; 3]> {
    [finite(), finite(), finite()]
}

fn is_finite(v: f32) -> bool {
    v.is_finite()
}

/// 512 cases from a fixed seed, so that CI is reproducible; set
/// `PROPTEST_RNG_SEED` (and `PROPTEST_CASES`) to explore other inputs.
fn config() -> ProptestConfig {
    let mut config = ProptestConfig::with_cases(512);
    if std::env::var_os("PROPTEST_RNG_SEED").is_none() {
        config.rng_seed = proptest::test_runner::RngSeed::Fixed(20261201);
    }
    if let Some(cases) = std::env::var("PROPTEST_CASES")
        .ok()
        .and_then(|c| c.parse().ok())
    {
        config.cases = cases;
    }
    config
}

proptest! {
    #![proptest_config(config())]

    #[test]
    fn table_lookups_are_finite(a in finite(), b in finite(), c in finite(), d in finite(),
                                e in finite(), s in 0.0f32..=1.0) {
        let set = &*SET;
        prop_assert!(is_finite(set.smith.g1(a, b)), "g1({a}, {b})");
        prop_assert!(is_finite(set.smith.lambda(a, b)), "lambda({a}, {b})");
        prop_assert!(is_finite(set.sigma_ratio.sigma_ratio(a, b, c)), "sigma_ratio({a}, {b}, {c})");
        prop_assert!(is_finite(set.sigma_ratio.sigma_ratio_cos(a, b, c)));
        prop_assert!(is_finite(set.diffuse_fresnel.f_dr_int(a)), "f_dr_int({a})");
        let cos = (1.0 - s * s).max(0.0).sqrt();
        let conv = set.convolution.convolution_sin_cos(s, cos, a, b, c, d);
        prop_assert!(is_finite(conv), "C(sin {s}; {a}, {b}, {c}, {d}) = {conv}");
        let fit = set.convolution.fit().convolution_sin_cos(s, cos, a, b, c, d);
        prop_assert!(is_finite(fit), "C_fit(sin {s}; {a}, {b}, {c}, {d}) = {fit}");
        prop_assert!(is_finite(set.convolution.convolution(e, a, b, c, d)));
    }

    #[test]
    fn fresnel_and_ndf_are_finite(n in finite(), k in finite(), cos in finite(),
                                  i in vec3(), o in vec3(), beta in finite(), p in finite(),
                                  u in [0.0f32..=1.0, 0.0f32..=1.0]) {
        let eta = Complex::new(n, k);
        prop_assert!(is_finite(fresnel(eta, cos)), "F({n}+{k}i, {cos})");
        prop_assert!(is_finite(q_bar(eta, i, o)), "Q̄({n}+{k}i, {i:?}, {o:?})");
        let set = &*SET;
        let ndf = Epd::new(beta, p, &set.smith);
        prop_assert!(is_finite(ndf.d(i)), "D({i:?}) for β {beta}, p {p}");
        prop_assert!(is_finite(ndf.pdf(i)));
        prop_assert!(is_finite(ndf.lambda(i)));
        prop_assert!(is_finite(ndf.g(i, o)));
        prop_assert!(is_finite(ndf.g_height_correlated(i, o)));
        prop_assert!(ndf.sample(u).iter().all(|x| x.is_finite()), "sample({u:?})");
    }

    #[test]
    fn brdf_is_finite(params in [finite(), finite(), finite(), finite(), finite(),
                                 finite(), finite()],
                      eta in [finite(), finite(), finite(), finite(), finite(), finite()],
                      base in 0usize..3, options in [0usize..2, 0usize..2, 0usize..2, 0usize..2, 0usize..2],
                      i in vec3(), o in vec3(), u in vec3()) {
        let [beta, p, sigma_s, b, c, albedo, lambertian] = params;
        let material = Material {
            layer: Layer {
                surface: Surface { beta, p, sigma_s, b, c },
                base: [
                    BaseLayer::Conductor,
                    BaseLayer::Plastic { albedo },
                    BaseLayer::Subsurface { albedo },
                ][base],
                lambertian,
            },
            eta_rgb: [0, 1, 2].map(|k| Complex::new(eta[2 * k], eta[2 * k + 1])),
        };
        let options = Options {
            masking: [Masking::Separable, Masking::HeightCorrelated][options[0]],
            sigma_rel: [SigmaRelMode::Incident, SigmaRelMode::Symmetrised][options[1]],
            colour: [ColourTerms::Physical, ColourTerms::White][options[2]],
            halo_weight: [HaloWeight::Printed, HaloWeight::Incident][options[3]],
            multiple_scattering: [MultipleScattering::None, MultipleScattering::KullaConty]
                [options[4]],
        };
        let set = &*SET;
        let model = set.rgb(&material, options);
        let value = model.eval(i, o);
        prop_assert!(value.iter().all(|v| v.is_finite()), "eval = {value:?}");
        let pdf = model.pdf(i, o);
        prop_assert!(is_finite(pdf), "pdf = {pdf}");
        if let Some(s) = model.sample(i, u) {
            prop_assert!(s.o.iter().all(|v| v.is_finite()), "{s:?}");
            prop_assert!(is_finite(s.pdf) && s.value.iter().all(|v| v.is_finite()), "{s:?}");
        }
    }
}
