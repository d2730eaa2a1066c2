//! `generator query g1` (docs/model.md §6): CSV in, CSV out; bad rows are reported and
//! skipped; `table` and `reference` agree with an independent reference.

use generator::query;
use generator::reference::epd;
use generator::rng::SplitMix64;
use generator::table_source::TableSource;

/// The answer, output and errors of query `quantity` over `input` with the
/// committed tables.
fn run_with(
    quantity: &str,
    options: &query::Options,
    input: &str,
) -> (Result<query::Summary, query::QueryError>, String, String) {
    let mut out = Vec::new();
    let mut err = Vec::new();
    let result = query::run(
        quantity,
        &TableSource::Dir(suite::tables_dir()),
        options,
        input.as_bytes(),
        &mut out,
        &mut err,
    );
    (
        result,
        String::from_utf8(out).unwrap(),
        String::from_utf8(err).unwrap(),
    )
}

/// The f64 reference's ρ of `params` at the pair `(i, o)`.
fn reference_total(
    params: &generator::reference::brdf::Params,
    i: [f32; 3],
    o: [f32; 3],
    options: &twoscale::material::Options,
) -> f64 {
    generator::reference::brdf::two_scale(params, i.map(f64::from), o.map(f64::from), options)
        .unwrap()
        .total()
}

fn run(input: &str) -> (Result<query::Summary, query::QueryError>, String, String) {
    run_with("g1", &query::Options::default(), input)
}

#[test]
fn bad_rows_are_reported_and_the_others_answered() {
    let input = "p,a,label\n1,0.5,x\n1,zero,y\n2\n,\n0.5,nan,z\n\n5,3,w\n";
    let (result, out, err) = run(input);
    let summary = result.unwrap();
    assert_eq!(
        summary,
        query::Summary {
            answered: 2,
            bad: 4
        }
    );
    let lines: Vec<&str> = out.lines().collect();
    assert_eq!(lines[0], "p,a,label,table,reference");
    assert!(lines[1].starts_with("1,0.5,x,"));
    assert!(lines[2].starts_with("5,3,w,"));
    assert!(
        err.contains("line 3") && err.contains("'a' is not a number"),
        "{err}"
    );
    assert!(err.contains("line 4") && err.contains("1 fields"), "{err}");
    assert!(err.contains("line 5") && err.contains("2 fields"), "{err}");
    assert!(
        err.contains("line 6") && err.contains("not finite"),
        "{err}"
    );
}

#[test]
fn header_and_quantity_errors_fail_fast() {
    let (result, _, _) = run("p,b\n1,2\n");
    let e = result.unwrap_err();
    assert!(
        matches!(e, query::QueryError::MissingColumn { column: "a", .. }),
        "{e:?}"
    );
    assert!(e.to_string().contains("lacks column 'a'"), "{e}");
    let (result, _, _) = run("");
    let e = result.unwrap_err();
    assert!(matches!(e, query::QueryError::EmptyInput), "{e:?}");
    assert!(e.to_string().contains("header"), "{e}");
    let mut sink = Vec::new();
    let unknown = query::run(
        "nope",
        &TableSource::Dir(suite::tables_dir()),
        &query::Options::default(),
        "x\n".as_bytes(),
        &mut sink,
        &mut Vec::new(),
    );
    let e = unknown.unwrap_err();
    assert!(
        e.to_string()
            .contains("unknown quantity 'nope' (known: g1, sigma-ratio, fresnel, conv, brdf)"),
        "{e}"
    );
}

/// Random points: `table` within 2e-5 of the reference, and `reference`
/// within 1e-9 relative of an independent computation (the 2-D definition of
/// Λ, docs/model.md §2.2; the Beckmann closed form at p = 1).
#[test]
fn answers_agree_with_an_independent_reference() {
    let mut rng = SplitMix64::new(31);
    let mut input = String::from("p,a\n");
    let mut points = Vec::new();
    for k in 0..60 {
        let p = if k % 5 == 0 {
            1.0
        } else {
            rng.uniform_in(0.2, 5.0)
        };
        let a = rng.log_uniform_in(0.01, 50.0);
        input.push_str(&format!("{p},{a}\n"));
        points.push((p, a));
    }
    let (result, out, err) = run(&input);
    assert_eq!(result.unwrap().bad, 0, "{err}");
    for (line, &(p, a)) in out.lines().skip(1).zip(&points) {
        let fields: Vec<f64> = line.split(',').map(|f| f.parse().unwrap()).collect();
        let (table, reference) = (fields[2], fields[3]);
        assert!((table - reference).abs() <= 2e-5, "{line}");
        let independent = if p == 1.0 {
            1.0 / (1.0 + epd::beckmann_lambda(a))
        } else {
            1.0 / (1.0 + epd::lambda_2d(p, a).unwrap())
        };
        assert!(
            ((reference - independent) / independent).abs() <= 1e-9,
            "p = {p}, a = {a}: {reference} vs {independent}"
        );
    }
}

/// Outside T1's domain a row is refused with the domain, unless `clamp`:
/// then it is answered at the clamped point and marked `in_domain = false`.
#[test]
fn out_of_domain_rows_are_refused_or_clamped_and_marked() {
    let input = "p,a\n0.15,0.5\n1,0.5\n";
    let (result, out, err) = run(input);
    assert_eq!(
        result.unwrap(),
        query::Summary {
            answered: 1,
            bad: 1
        }
    );
    assert!(
        err.contains("line 2: p = 0.15: must be in [0.2, 5]"),
        "{err}"
    );
    assert!(!out.contains("0.15,"), "{out}");

    let (mut out, mut err) = (Vec::new(), Vec::new());
    let summary = query::run(
        "g1",
        &TableSource::Dir(suite::tables_dir()),
        &query::Options {
            clamp: true,
            ..query::Options::default()
        },
        input.as_bytes(),
        &mut out,
        &mut err,
    )
    .unwrap();
    assert_eq!(summary.bad, 0);
    let out = String::from_utf8(out).unwrap();
    let lines: Vec<&str> = out.lines().collect();
    assert_eq!(lines[0], "p,a,table,reference,in_domain");
    assert!(lines[1].starts_with("0.15,0.5,") && lines[1].ends_with(",false"));
    assert!(lines[2].starts_with("1,0.5,") && lines[2].ends_with(",true"));
}

/// `query brdf --material FILE`: `table` is the channel of the RGB model the
/// C API and Python build from the same file, bit for bit, and `reference`
/// the f64 reference of that channel; other quantities and materials the
/// reference does not cover are refused before any row.
#[test]
fn brdf_of_a_material_file_is_the_rgb_model() {
    use twoscale::io::desc::MaterialDesc;
    let text = "[material]\nbeta = 0.2\np = 1.3\neta = [[0.2, 3.0], [0.5, 2.5], [1.2, 1.9]]\n\
                sigma_s = 0.03\nb = 2.0\nc = 2.5\nsigma_rel = \"symmetrised\"\n";
    let owned = MaterialDesc::from_toml_str(text).unwrap();
    let desc = owned.get();
    let options = query::Options {
        material: Some(owned.clone()),
        ..query::Options::default()
    };
    let run = run_with;
    let pairs = [
        ([0.5f32, 0.0, 0.866], [-0.45f32, 0.05, 0.89]),
        ([0.1, 0.2, 0.97], [-0.3, -0.1, 0.95]),
        ([0.8, 0.0, 0.6], [-0.7, 0.3, 0.648]),
    ];
    let mut input = String::from("channel,ix,iy,iz,ox,oy,oz\n");
    for (i, o) in pairs {
        for ch in 0..3 {
            let v: Vec<String> = i
                .iter()
                .chain(&o)
                .map(|x| f64::from(*x).to_string())
                .collect();
            input.push_str(&format!("{ch},{}\n", v.join(",")));
        }
    }
    input.push_str("3,0,0,1,0,0,1\n");
    let (result, out, err) = run("brdf", &options, &input);
    assert_eq!(
        result.unwrap(),
        query::Summary {
            answered: 9,
            bad: 1
        }
    );
    assert!(err.contains("channel = 3: must be 0, 1 or 2"), "{err}");
    let set = twoscale::TableSet::open(suite::tables_dir()).unwrap();
    let model = set.set().rgb(&desc.material, desc.options);
    let params = generator::reference::brdf::Params::rgb(&desc.material).unwrap();
    let rows: Vec<&str> = out.lines().skip(1).collect();
    for (k, row) in rows.iter().enumerate() {
        let (i, o) = pairs[k / 3];
        let ch = k % 3;
        let fields: Vec<&str> = row.split(',').collect();
        let table: f32 = fields[7].parse().unwrap();
        assert_eq!(table.to_bits(), model.eval(i, o)[ch].to_bits(), "{row}");
        let reference: f64 = fields[8].parse().unwrap();
        let want = reference_total(&params[ch], i, o, &desc.options);
        assert_eq!(reference, want, "{row}");
    }
    let (result, ..) = run("g1", &options, "p,a\n1,1\n");
    assert!(matches!(
        result,
        Err(query::QueryError::MaterialUnsupported(_))
    ));
    let plastic = MaterialDesc::from_toml_str(
        "[material]\nbeta = 0.2\np = 1\neta = [[1.5, 0], [1.5, 0], [1.5, 0]]\n\
         base = \"plastic\"\nalbedo = 0.5\n",
    )
    .unwrap();
    let options = query::Options {
        material: Some(plastic),
        ..query::Options::default()
    };
    let (result, ..) = run("brdf", &options, "channel,ix,iy,iz,ox,oy,oz\n");
    let message = result.unwrap_err().to_string();
    let uncovered = "--material: the f64 reference covers conductors (with a Lambertian term, \
                     k_d/π), and their energy compensation (multiple_scattering) without \
                     diffraction (sigma_s = 0) at the paper's wavelengths";
    assert_eq!(message, uncovered);
    // The energy compensation of a surface with diffraction is refused too.
    let halo =
        MaterialDesc::from_toml_str(&format!("{text}multiple_scattering = \"kulla-conty\"\n"))
            .unwrap();
    let options = query::Options {
        material: Some(halo),
        ..query::Options::default()
    };
    let (result, ..) = run("brdf", &options, "channel,ix,iy,iz,ox,oy,oz\n");
    assert_eq!(result.unwrap_err().to_string(), uncovered);
}

/// `query brdf --material FILE` of a conductor with a Lambertian term (what
/// `python -m twoscale.fit` writes for a measured conductor): `table` is the
/// RGB model bit for bit, `reference` the f64 reference plus k_d/π above
/// the horizon, and both are 0 below it.
#[test]
fn brdf_of_a_conductor_with_a_lambertian_term() {
    use twoscale::io::desc::MaterialDesc;
    let text = "[material]\nbeta = 0.12\np = 1.3\neta = [[0.2, 3.0], [0.5, 2.5], [1.2, 1.9]]\n\
                sigma_s = 0.02\nb = 3.0\nc = 2.2\nlambertian = 0.04\n";
    let owned = MaterialDesc::from_toml_str(text).unwrap();
    let desc = owned.get();
    let options = query::Options {
        material: Some(owned.clone()),
        ..query::Options::default()
    };
    let pairs = [
        ([0.5f32, 0.0, 0.866], [-0.45f32, 0.05, 0.89]),
        ([0.8, 0.0, 0.6], [0.1, 0.7, 0.71]),
        ([0.6, 0.0, 0.8], [0.6, 0.0, -0.8]),
    ];
    let mut input = String::from("channel,ix,iy,iz,ox,oy,oz\n");
    for (i, o) in pairs {
        for ch in 0..3 {
            let v: Vec<String> = i
                .iter()
                .chain(&o)
                .map(|x| f64::from(*x).to_string())
                .collect();
            input.push_str(&format!("{ch},{}\n", v.join(",")));
        }
    }
    let (result, out, err) = run_with("brdf", &options, &input);
    assert_eq!(result.unwrap().answered, 9, "{err}");
    let set = twoscale::TableSet::open(suite::tables_dir()).unwrap();
    let model = set.set().rgb(&desc.material, desc.options);
    let mut surface = desc.material;
    surface.layer.lambertian = 0.0;
    let params = generator::reference::brdf::Params::rgb(&surface).unwrap();
    let lambertian = 0.04f32 as f64 / std::f64::consts::PI;
    for (k, row) in out.lines().skip(1).enumerate() {
        let (i, o) = pairs[k / 3];
        let fields: Vec<&str> = row.split(',').collect();
        let table: f32 = fields[7].parse().unwrap();
        assert_eq!(table.to_bits(), model.eval(i, o)[k % 3].to_bits(), "{row}");
        let reference: f64 = fields[8].parse().unwrap();
        let above = o[2] > 0.0;
        let want = if above {
            reference_total(&params[k % 3], i, o, &desc.options) + lambertian
        } else {
            0.0
        };
        assert_eq!(reference, want, "{row}");
        // The term is what the rows differ by from the surface alone.
        assert!(!above || reference > lambertian, "{row}");
        assert!(
            (f64::from(table) / reference - 1.0).abs() < 1e-3 || !above,
            "{row}"
        );
    }
}

/// `query brdf --material FILE` with `multiple_scattering = "kulla-conty"`
/// (σs = 0): `table` is the RGB model with the compensation lobe, and
/// `reference` adds the reference's lobe (E by adaptive quadrature); they
/// agree to 1e-4 relative on a wide, heavy-tailed gold where the lobe is a
/// large part of ρ (measured 1.0e-5).
#[test]
fn brdf_of_a_compensated_material() {
    use twoscale::io::desc::MaterialDesc;
    let text = "[material]\nbeta = 0.6\np = 0.6\neta = [[0.163, 3.56], [0.584, 2.15], [1.403, 1.925]]\n\
                multiple_scattering = \"kulla-conty\"\n";
    let desc = MaterialDesc::from_toml_str(text).unwrap();
    let options = query::Options {
        material: Some(desc),
        ..query::Options::default()
    };
    let source = TableSource::Dir(suite::tables_dir());
    let mut input = String::from("channel,ix,iy,iz,ox,oy,oz\n");
    for (i, o) in [
        ("0.5,0,0.866", "-0.45,0.05,0.89"),
        ("0.1,0.2,0.97", "0.6,-0.2,0.7746"),
        ("0.95,0,0.3122", "0.2,0.9,0.3873"),
    ] {
        for ch in 0..3 {
            input.push_str(&format!("{ch},{i},{o}\n"));
        }
    }
    let (mut out, mut err) = (Vec::new(), Vec::new());
    let summary = query::run(
        "brdf",
        &source,
        &options,
        input.as_bytes(),
        &mut out,
        &mut err,
    )
    .unwrap();
    assert_eq!(summary.bad, 0, "{}", String::from_utf8_lossy(&err));
    let mut worst = 0.0f64;
    for row in String::from_utf8(out).unwrap().lines().skip(1) {
        let fields: Vec<f64> = row.split(',').map(|x| x.parse().unwrap()).collect();
        let (table, reference) = (fields[7], fields[8]);
        worst = worst.max((table - reference).abs() / reference);
        assert!(
            (table - reference).abs() <= 1e-4 * reference,
            "{row}: {table} vs {reference}"
        );
    }
    eprintln!("compensated material: max relative |table − reference| = {worst:.2e}");
    // Rows over the spectrum: the reference's lobe is per channel, so refused.
    let one_index = "[material]\nbeta = 0.6\np = 0.6\neta = [[0.2, 3.0], [0.2, 3.0], [0.2, 3.0]]\n\
                     multiple_scattering = \"kulla-conty\"\n";
    let options = query::Options {
        material: Some(MaterialDesc::from_toml_str(one_index).unwrap()),
        ..query::Options::default()
    };
    let (result, ..) = run_with("brdf", &options, "lambda,ix,iy,iz,ox,oy,oz\n");
    assert!(
        matches!(result, Err(query::QueryError::Uncovered(_))),
        "{result:?}"
    );
}

/// `query brdf --material FILE` with a `lambda` column: `table` is the
/// spectral model (`brdf::Spectral`) of the file's index at that
/// wavelength, bit for bit, and `reference` the f64 reference at λ with the
/// index interpolated there; λ outside [0.36, 0.83] µm is a bad row, and a
/// material without a spectrum, or with `rgb_mode = "integrated"` and
/// `channel` rows, is refused before any row.
#[test]
fn brdf_with_a_lambda_column_is_the_spectral_model() {
    use twoscale::io::desc::MaterialDesc;
    let text = "[material]\nbeta = 0.2\np = 1.3\n\
                eta = { lambda = [0.4, 0.5, 0.7], n = [1.4, 0.8, 0.2], k = [1.9, 2.2, 4.0] }\n\
                sigma_s = 0.03\nb = 2.0\nc = 2.5\nrgb_mode = \"integrated\"\n";
    let owned = MaterialDesc::from_toml_str(text).unwrap();
    let desc = owned.get();
    let spectral = desc.spectral.unwrap();
    let run = |material: MaterialDesc<'_>, input: &str| {
        let options = query::Options {
            material: Some(material.to_owned_desc()),
            ..query::Options::default()
        };
        run_with("brdf", &options, input)
    };
    let rows = [
        (0.45f32, [0.5f32, 0.0, 0.866], [-0.45f32, 0.05, 0.89]),
        (0.62, [0.1, 0.2, 0.97], [-0.3, -0.1, 0.95]),
        (0.38, [0.8, 0.0, 0.6], [-0.7, 0.3, 0.648]),
    ];
    let mut input = String::from("lambda,ix,iy,iz,ox,oy,oz\n");
    for (lambda, i, o) in rows {
        let v: Vec<String> = i
            .iter()
            .chain(&o)
            .map(|x| f64::from(*x).to_string())
            .collect();
        input.push_str(&format!("{},{}\n", f64::from(lambda), v.join(",")));
    }
    input.push_str("0.9,0,0,1,0,0,1\n");
    let (result, out, err) = run(desc, &input);
    assert_eq!(
        result.unwrap(),
        query::Summary {
            answered: 3,
            bad: 1
        }
    );
    assert!(
        err.contains("line 5: lambda = 0.9: must be in [0.36, 0.83]"),
        "{err}"
    );
    let set = twoscale::TableSet::open(suite::tables_dir()).unwrap();
    let tables = set.set().brdf_tables();
    let model = twoscale::brdf::Spectral::boxed(&tables, &spectral, desc.options);
    let params = generator::reference::brdf::Params::rgb(&desc.material).unwrap()[0];
    for (row, (lambda, i, o)) in out.lines().skip(1).zip(rows) {
        let fields: Vec<&str> = row.split(',').collect();
        let table: f32 = fields[7].parse().unwrap();
        assert_eq!(table.to_bits(), model.eval(i, o, lambda).to_bits(), "{row}");
        let eta = spectral.eta.at(lambda);
        let at = generator::reference::brdf::Params {
            n: eta.re.into(),
            k: eta.im.into(),
            lambda: lambda.into(),
            ..params
        };
        let reference: f64 = fields[8].parse().unwrap();
        let want = reference_total(&at, i, o, &desc.options);
        assert_eq!(reference, want, "{row}");
        // The model is within 3% of the reference at this λ.
        assert!((f64::from(table) / want - 1.0).abs() < 0.03, "{row}");
    }
    let (result, ..) = run(desc, "channel,ix,iy,iz,ox,oy,oz\n");
    assert!(matches!(
        result,
        Err(query::QueryError::IntegratedUnsupported)
    ));
    let rgb = MaterialDesc::from_toml_str(
        "[material]\nbeta = 0.2\np = 1\neta = [[0.2, 3.0], [0.5, 2.5], [1.2, 1.9]]\n",
    )
    .unwrap();
    let (result, ..) = run(rgb.get(), "lambda,ix,iy,iz,ox,oy,oz\n");
    assert!(matches!(result, Err(query::QueryError::NoSpectrum)));
}
