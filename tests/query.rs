//! `generator query g1` (docs/model.md §6): CSV in, CSV out; bad rows are reported and
//! skipped; `table` and `reference` agree with an independent reference.

use generator::query;
use generator::reference::epd;
use generator::rng::SplitMix64;
use generator::table_source::TableSource;

fn run(input: &str) -> (Result<query::Summary, query::QueryError>, String, String) {
    let mut out = Vec::new();
    let mut err = Vec::new();
    let result = query::run(
        "g1",
        &TableSource::Dir(suite::tables_dir()),
        &query::Options::default(),
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
