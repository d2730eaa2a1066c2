//! Unit tests of the parent module.

use super::*;
use crate::material::{
    BaseKind, BaseLayer, ColourTerms, HaloWeight, Masking, MultipleScattering, SigmaRelMode,
};

const GOLD: [[f32; 2]; 3] = [[0.163, 3.56], [0.584, 2.15], [1.403, 1.925]];

fn gold<'a>() -> Keywords<'a> {
    Keywords {
        beta: 0.1,
        p: 1.0,
        eta: Eta::Channels(&GOLD),
        ..Keywords::default()
    }
}

#[test]
fn defaults_fill_what_is_not_given() {
    let d = gold().material().unwrap();
    let s = d.material.layer.surface;
    assert_eq!((s.sigma_s, s.b, s.c), (0.0, 1.0, 2.0));
    assert_eq!(d.material.layer.base, BaseLayer::Conductor);
    assert_eq!(d.material.layer.lambertian, 0.0);
    assert_eq!(d.options, Options::default());
    assert_eq!(d.material.eta_rgb[2], Complex::new(1.403, 1.925));
}

#[test]
fn names_and_albedo_are_read() {
    let k = Keywords {
        base: Some("plastic"),
        albedo: Some(0.8),
        eta: Eta::Channels(&[[1.5, 0.0]; 3]),
        masking: Some("height-correlated"),
        sigma_rel: Some("symmetrised"),
        colour: Some("white"),
        halo_weight: Some("incident"),
        multiple_scattering: Some("kulla-conty"),
        ..gold()
    };
    let d = k.material().unwrap();
    assert_eq!(d.material.layer.base, BaseLayer::Plastic { albedo: 0.8 });
    assert_eq!(
        d.options,
        Options {
            masking: Masking::HeightCorrelated,
            sigma_rel: SigmaRelMode::Symmetrised,
            colour: ColourTerms::White,
            halo_weight: HaloWeight::Incident,
            multiple_scattering: MultipleScattering::KullaConty,
        }
    );
}

#[test]
fn each_refusal_has_its_message() {
    let cases: [(Keywords<'_>, &str); 7] = [
        (
            Keywords {
                eta: Eta::Channels(&GOLD[..2]),
                ..gold()
            },
            "eta must be three (n, k) pairs (red, green, blue), got 2",
        ),
        (
            Keywords {
                base: Some("glass"),
                ..gold()
            },
            "base must be one of 'conductor', 'plastic' or 'subsurface', got 'glass'",
        ),
        (
            Keywords {
                albedo: Some(0.5),
                ..gold()
            },
            "albedo is for the base layers with a diffuse albedo, not 'conductor'",
        ),
        (
            Keywords {
                base: Some("subsurface"),
                ..gold()
            },
            "base 'subsurface' needs an albedo",
        ),
        (
            Keywords {
                beta: 20.0,
                ..gold()
            },
            "beta = 20: must be in [0.0001, 10]",
        ),
        (
            Keywords {
                eta: Eta::Channels(&[[0.2, 3.0], [0.2, -1.0], [0.2, 3.0]]),
                ..gold()
            },
            "eta[1].k = -1: must be finite and ≥ 0",
        ),
        (
            Keywords {
                colour: Some("grey"),
                ..gold()
            },
            "colour must be one of 'physical' or 'white', got 'grey'",
        ),
    ];
    for (k, message) in cases {
        assert_eq!(k.material().unwrap_err().to_string(), message);
    }
    let e = Keywords {
        eta: Eta::Channels(&GOLD),
        ..gold()
    }
    .layer(2)
    .unwrap_err();
    assert_eq!(
        e.to_string(),
        "eta must be 2 (n, k) pairs, one per wavelength, got 3"
    );
    assert_eq!(
        validate::named::<BaseKind>(Some("metal")).unwrap_err().name,
        "metal"
    );
}

#[test]
fn a_spectrum_gives_the_rgb_and_the_spectral_material() {
    let rows = crate::spectrum::optical::AU_JOHNSON;
    let k = Keywords {
        eta: Eta::Spectrum(&rows),
        rgb_mode: Some("integrated"),
        ..gold()
    };
    let d = k.material().unwrap();
    let s = d.spectral.unwrap();
    assert_eq!(s.eta, Ior::Tabulated(Tabulated::new(&rows).unwrap()));
    assert_eq!(d.material, s.paper_rgb());
    assert_eq!(d.rgb_mode, RgbMode::Integrated);
    // A spectrum's default is the integrated RGB; the paper's on request.
    let default = Keywords {
        rgb_mode: None,
        ..k
    };
    assert_eq!(default.material().unwrap().rgb_mode, RgbMode::Integrated);
    let paper = Keywords {
        rgb_mode: Some("paper-wavelengths"),
        ..k
    };
    assert_eq!(
        paper.material().unwrap().rgb_mode,
        RgbMode::PaperWavelengths
    );
    // One index for every channel is a spectrum too (its default stays
    // the paper's wavelengths); different ones are not.
    let d = Keywords {
        eta: Eta::Channels(&[[1.5, 0.0]; 3]),
        ..gold()
    }
    .material()
    .unwrap();
    assert_eq!(d.spectral.unwrap().eta, Ior::Constant(Complex::real(1.5)));
    assert_eq!(d.rgb_mode, RgbMode::PaperWavelengths);
    assert_eq!(gold().material().unwrap().spectral, None);
}

#[test]
fn spectral_refusals_have_their_message() {
    let integrated = Keywords {
        rgb_mode: Some("integrated"),
        ..gold()
    };
    assert_eq!(
        integrated.material().unwrap_err().to_string(),
        "rgb_mode 'integrated' needs an index over the spectrum: eta = (lambda, n, k), \
         or one (n, k) for every channel"
    );
    let mode = Keywords {
        rgb_mode: Some("spectral"),
        ..gold()
    };
    assert_eq!(
        mode.material().unwrap_err().to_string(),
        "rgb_mode must be one of 'paper-wavelengths' or 'integrated', got 'spectral'"
    );
    let decreasing = Keywords {
        eta: Eta::Spectrum(&[[0.5, 1.0, 2.0], [0.4, 1.0, 2.0]]),
        ..gold()
    };
    assert_eq!(
        decreasing.material().unwrap_err().to_string(),
        "lambda = 0.4: must be finite and > 0.5 (µm, increasing rows)"
    );
    // A spectrum where one index per wavelength is expected (materials.toml).
    let spectrum = Keywords {
        eta: Eta::Spectrum(&[[0.5, 1.0, 2.0]; 3]),
        ..gold()
    };
    assert!(matches!(
        spectrum.layer(3),
        Err(Refused::EtaCount { found: 3, .. })
    ));
}

#[cfg(feature = "std")]
#[test]
fn spectrum_rows_need_one_length() {
    assert_eq!(
        spectrum_rows(&[0.4, 0.5], &[1.0, 1.1], &[2.0, 2.1]).unwrap(),
        vec![[0.4, 1.0, 2.0], [0.5, 1.1, 2.1]]
    );
    assert_eq!(
        spectrum_rows(&[0.4, 0.5], &[1.0], &[2.0, 2.1])
            .unwrap_err()
            .to_string(),
        "eta = (lambda, n, k) needs three arrays of one length, got 2, 1 and 2"
    );
}

#[cfg(feature = "toml")]
mod toml_files {
    use super::super::*;
    use crate::material::BaseLayer;
    use crate::spectrum::optical::{Ior, Tabulated};

    const FIT: &str = r#"
[material]
beta = 0.0598
p = 1
eta = [[0.163, 3.56], [0.584, 2.15], [1.403, 1.925]]
sigma_s = 0.0273
b = 4.8418
c = 2.0
base = "conductor"
lambertian = 0.01

[metrics]
rmse = [0.1, 0.2, 0.3]
smape = 0.05
"#;

    #[test]
    fn a_fit_file_reads() {
        let d = MaterialDesc::from_toml_str(FIT).unwrap();
        let d = d.get();
        let m = d.material;
        assert_eq!(m.layer.surface.beta, 0.0598f64 as f32);
        assert_eq!(m.layer.surface.p, 1.0);
        assert_eq!(m.layer.lambertian, 0.01f64 as f32);
        assert_eq!(m.layer.base, BaseLayer::Conductor);
        assert_eq!(m.eta_rgb[0], Complex::new(0.163, 3.56));
    }

    #[test]
    fn a_spectral_file_reads() {
        let text = FIT.replacen(
            "eta = [[0.163, 3.56], [0.584, 2.15], [1.403, 1.925]]",
            "eta = { lambda = [0.4, 0.5, 0.7], n = [1.5, 1.0, 0.2], k = [1.9, 2.0, 4.0] }\n\
             rgb_mode = \"integrated\"",
            1,
        );
        let d = MaterialDesc::from_toml_str(&text).unwrap();
        let d = d.get();
        let s = d.spectral.unwrap();
        assert_eq!(
            s.eta,
            Ior::Tabulated(
                Tabulated::new(&[[0.4, 1.5, 1.9], [0.5, 1.0, 2.0], [0.7, 0.2, 4.0]]).unwrap()
            )
        );
        assert_eq!(d.rgb_mode, RgbMode::Integrated);
        assert_eq!(d.material.eta_rgb, s.eta.at_rgb());
        let short = text.replacen("k = [1.9, 2.0, 4.0]", "k = [1.9, 2.0]", 1);
        let e = MaterialDesc::from_toml_str(&short).unwrap_err();
        assert_eq!(e.kind, DescErrorKind::Syntax);
        assert!(
            e.message
                .contains("eta = (lambda, n, k) needs three arrays of one length, got 3, 3 and 2"),
            "{e}"
        );
        let bad = text.replacen("lambda = [0.4, 0.5, 0.7]", "lambda = [0.4, 0.5, 0.5]", 1);
        let e = MaterialDesc::from_toml_str(&bad).unwrap_err();
        assert_eq!(
            e.message,
            "[material] lambda = 0.5: must be finite and > 0.5 (µm, increasing rows)"
        );
    }

    #[test]
    fn faults_are_named() {
        let bad = |from: &str, to: &str| {
            let text = FIT.replacen(from, to, 1);
            MaterialDesc::from_toml_str(&text).unwrap_err()
        };
        let e = bad("beta = 0.0598", "beta = 20.0");
        assert_eq!(e.kind, DescErrorKind::Refused);
        assert_eq!(e.message, "[material] beta = 20: must be in [0.0001, 10]");
        let e = bad("c = 2.0", "c = 2.0\ncolor = \"white\"");
        assert_eq!(e.kind, DescErrorKind::Syntax);
        assert!(e.message.contains("unknown field `color`"), "{e}");
        assert!(e.message.contains("line 9"), "{e}");
        let e = bad("beta = 0.0598", "");
        assert!(e.message.contains("missing field `beta`"), "{e}");
        let e = bad("p = 1", "p = \"one\"");
        assert_eq!(e.kind, DescErrorKind::Syntax);
        let e = bad("[metrics]", "[metric]");
        assert!(e.message.contains("unknown field `metric`"), "{e}");
        let e = bad("lambertian = 0.01", "albedo = 0.5");
        assert_eq!(
            e.message,
            "[material] albedo is for the base layers with a diffuse albedo, not 'conductor'"
        );
        let e = MaterialDesc::from_toml_str("beta = 1").unwrap_err();
        assert!(
            e.message
                .contains("unknown field `beta`, expected `material` or `metrics`"),
            "{e}"
        );
        let e = MaterialDesc::from_toml_str("[metrics]\nx = 1").unwrap_err();
        assert!(e.message.contains("missing field `material`"), "{e}");
    }

    #[test]
    fn files_name_their_path() {
        let dir = std::env::temp_dir().join(format!("twoscale-desc-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let path = dir.join("bad.toml");
        std::fs::write(&path, FIT.replacen("p = 1", "p = 9", 1)).unwrap();
        let e = MaterialDesc::from_toml_file(&path).unwrap_err();
        assert_eq!(
            e.message,
            format!("{}: [material] p = 9: must be in [0.2, 5]", path.display())
        );
        let missing = dir.join("missing.toml");
        let e = MaterialDesc::from_toml_file(&missing).unwrap_err();
        assert_eq!(e.kind, DescErrorKind::Io);
        assert!(e.message.starts_with("cannot read "), "{e}");
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
