//! The `generator` command line as a user runs it: exit statuses, the
//! messages of bad inputs, and an installed binary that needs no source tree
//! (run from an empty directory, reading only what is compiled in).

use std::io::Write;
use std::path::{Path, PathBuf};
use std::process::{Command, Output, Stdio};

/// A fresh empty directory for one test.
fn scratch(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("generator-cli-{name}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).expect("scratch directory");
    dir
}

/// `generator ARGS` run in `cwd` with `HOME` there too, `stdin` on its input.
fn run_in(cwd: &Path, args: &[&str], stdin: &str) -> Output {
    let mut child = Command::new(env!("CARGO_BIN_EXE_generator"))
        .args(args)
        .current_dir(cwd)
        .env("HOME", cwd)
        .stdin(Stdio::piped())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .expect("generator runs");
    // A command that fails before reading its input closes the pipe: the
    // write may then fail, and the status says why.
    let _ = child
        .stdin
        .take()
        .expect("stdin")
        .write_all(stdin.as_bytes());
    child.wait_with_output().expect("generator finishes")
}

fn text(bytes: &[u8]) -> String {
    String::from_utf8_lossy(bytes).into_owned()
}

/// `generator query QUANTITY` in a scratch directory: (status, stdout, stderr).
fn query(name: &str, args: &[&str], input: &str) -> (Option<i32>, String, String) {
    let dir = scratch(name);
    let mut all = vec!["query"];
    all.extend_from_slice(args);
    let out = run_in(&dir, &all, input);
    std::fs::remove_dir_all(&dir).expect("clean up");
    (out.status.code(), text(&out.stdout), text(&out.stderr))
}

#[test]
fn g1_outside_t1_is_refused_with_its_domain_and_exit_1() {
    let (code, out, err) = query("g1", &["g1"], "p,a\n0.15,0.5\n1,0.5\n");
    assert_eq!(code, Some(1), "{out}{err}");
    assert!(
        err.contains("line 2: p = 0.15: must be in [0.2, 5] (T1's domain)"),
        "{err}"
    );
    // The other row is answered; the refused one is not printed.
    let lines: Vec<&str> = out.lines().collect();
    assert_eq!(lines.len(), 2, "{out}");
    assert!(lines[1].starts_with("1,0.5,"), "{out}");
}

#[test]
fn clamp_answers_outside_the_domain_and_says_so() {
    let (code, out, err) = query("clamp", &["g1", "--clamp"], "p,a\n0.15,0.5\n1,0.5\n");
    assert_eq!(code, Some(0), "{err}");
    let lines: Vec<&str> = out.lines().collect();
    assert_eq!(lines[0], "p,a,table,reference,in_domain");
    assert!(
        lines[1].starts_with("0.15,0.5,") && lines[1].ends_with(",false"),
        "{out}"
    );
    assert!(lines[2].ends_with(",true"), "{out}");
    // The clamped table value is T1's at p = 0.2, not the reference at 0.15.
    let (_, at_edge, _) = query("clamp-edge", &["g1"], "p,a\n0.2,0.5\n");
    let table = |line: &str| line.split(',').nth(2).map(str::to_string);
    assert_eq!(table(lines[1]), table(at_edge.lines().nth(1).unwrap()));
    // --clamp is for the lookups of one table.
    let (code, _, err) = query("clamp-brdf", &["brdf", "--clamp"], "beta\n");
    assert_eq!(code, Some(1));
    assert!(err.contains("--clamp applies to"), "{err}");
}

#[test]
fn conv_outside_t3_is_a_domain_error_not_a_quadrature_failure() {
    let input = "u,c,beta,p,theta_h\n100,2,5,1,0.01\n100,2,0.1,0.05,0.01\n100,2,0.1,1,0.01\n";
    let (code, out, err) = query("conv", &["conv"], input);
    assert_eq!(code, Some(1), "{out}{err}");
    assert!(
        err.contains("line 2: beta = 5: must be in [0.002, 1] (T3's domain)"),
        "{err}"
    );
    assert!(
        err.contains("line 3: p = 0.05: must be in [0.2, 5] (T3's domain)"),
        "{err}"
    );
    assert!(!err.contains("quadrature"), "{err}");
    assert_eq!(out.lines().count(), 2, "{out}");
}

#[test]
fn sigma_ratio_reports_the_angle_given() {
    let (code, _, err) = query(
        "sigma",
        &["sigma-ratio"],
        "theta_i,B,c\n2,3,2\n0.5,3,0.5\n0.5,3,2\n",
    );
    assert_eq!(code, Some(1), "{err}");
    assert!(err.contains("line 2: theta_i = 2: cos_theta_i = "), "{err}");
    assert!(err.contains("line 3: c = 0.5: must be in (1, "), "{err}");
}

#[test]
fn fresnel_refuses_negative_n_and_k() {
    let (code, out, err) = query(
        "fresnel",
        &["fresnel"],
        "n,k,cos_theta\n-1,0,0.5\n1.5,-1,0.5\n1.5,0,0.5\n",
    );
    assert_eq!(code, Some(1), "{err}");
    assert!(
        err.contains("line 2: n = -1: must be finite and > 0"),
        "{err}"
    );
    assert!(
        err.contains("line 3: k = -1: must be finite and ≥ 0"),
        "{err}"
    );
    assert_eq!(out.lines().count(), 2, "{out}");
}

#[test]
fn brdf_validates_the_material_and_names_lambda() {
    let head = "beta,p,sigma_s,b,c,n,k,lambda,ix,iy,iz,ox,oy,oz\n";
    let dirs = "0.6,0,0.8,-0.6,0,0.8";
    let input = format!(
        "{head}0.1,1,-0.1,3,2,0.2,3.5,0.5,{dirs}\n0.1,1,0.01,3,2,0.2,3.5,-4,{dirs}\n\
         0.1,1,0.01,3,2,0.2,-1,0.5,{dirs}\n0.1,1,0.01,3,2,0.2,3.5,0.5,{dirs}\n"
    );
    let (code, out, err) = query("brdf", &["brdf"], &input);
    assert_eq!(code, Some(1), "{err}");
    assert!(
        err.contains("line 2: sigma_s = -0.1: must be finite and ≥ 0"),
        "{err}"
    );
    assert!(err.contains("line 3: lambda = -4: must be in"), "{err}");
    assert!(!err.contains("B ="), "{err}");
    assert!(err.contains("line 4: k = -1"), "{err}");
    assert_eq!(out.lines().count(), 2, "{out}");
}

/// Small values print in exponent form, and every number reads back.
#[test]
fn numbers_print_in_their_shortest_form() {
    let (code, out, err) = query(
        "shortest",
        &["conv"],
        "u,c,beta,p,theta_h\n3000,1.5,0.002,1,1.5\n",
    );
    assert_eq!(code, Some(0), "{err}");
    let row = out.lines().nth(1).expect("one row");
    for field in row.split(',').skip(5) {
        let value: f64 = field.parse().expect("a number");
        assert!(value > 0.0 && value < 1e-8, "{row}");
        assert!(field.contains('e') && field.len() <= 24, "{row}");
    }
}

#[test]
fn verify_refuses_zero_points() {
    let dir = scratch("verify0");
    let out = run_in(&dir, &["verify", "--points", "0"], "");
    assert_eq!(out.status.code(), Some(1));
    assert!(
        text(&out.stderr).contains("--points 0"),
        "{}",
        text(&out.stderr)
    );
    assert!(!text(&out.stdout).contains("NaN"), "{}", text(&out.stdout));
    std::fs::remove_dir_all(&dir).expect("clean up");
}

#[test]
fn no_subcommand_prints_help_and_builds_nothing() {
    let dir = scratch("bare");
    let out = run_in(&dir, &[], "");
    assert_eq!(out.status.code(), Some(2));
    assert!(
        text(&out.stdout).contains("Usage: generator"),
        "{}",
        text(&out.stdout)
    );
    let left: Vec<_> = std::fs::read_dir(&dir).unwrap().collect();
    assert!(left.is_empty(), "it wrote {left:?}");
    std::fs::remove_dir_all(&dir).expect("clean up");
}

/// The defaults name no path of the source tree the binary was built from.
#[test]
fn help_shows_no_source_path() {
    let workspace = Path::new(env!("CARGO_MANIFEST_DIR"))
        .parent()
        .expect("workspace")
        .to_string_lossy()
        .into_owned();
    let dir = scratch("help");
    for sub in [
        "build",
        "merge",
        "verify",
        "spot-check",
        "plot",
        "export",
        "inspect",
        "query",
    ] {
        let out = run_in(&dir, &[sub, "--help"], "");
        assert!(out.status.success(), "{sub}");
        let help = text(&out.stdout);
        assert!(!help.contains(&workspace), "{sub} --help: {help}");
        assert!(!help.contains("CARGO_MANIFEST_DIR"), "{sub} --help: {help}");
    }
    std::fs::remove_dir_all(&dir).expect("clean up");
}

/// `help export` and `help verify` name every table of the set (T6 was
/// missing, and export said "all four" of the five it writes).
#[test]
fn help_names_every_table_of_the_set() {
    let dir = scratch("help-tables");
    let count = twoscale::table_set::TABLES.len();
    assert_eq!(count, 5, "update the help texts' count");
    for sub in ["export", "verify"] {
        let out = run_in(&dir, &["help", sub], "");
        assert!(out.status.success(), "{sub}");
        let help = text(&out.stdout).to_lowercase();
        for id in twoscale::table_set::TABLES {
            let tag = format!("t{}", id.number());
            assert!(
                help.contains(&tag),
                "help {sub} does not name {tag}: {help}"
            );
        }
        assert!(!help.contains("all four"), "help {sub}: {help}");
    }
    std::fs::remove_dir_all(&dir).expect("clean up");
}

/// `verify DIR` reads DIR: a directory that does not exist is an error,
/// and no row (the spectral bakes' included) is computed from the embedded
/// tables instead.
#[test]
fn verify_of_a_missing_directory_fails_and_marks_nothing_ok() {
    let dir = scratch("verify-missing");
    let missing = dir.join("nonexistent");
    let out = run_in(
        &dir,
        &["verify", missing.to_str().expect("utf-8"), "--points", "10"],
        "",
    );
    assert_eq!(out.status.code(), Some(1), "{}", text(&out.stdout));
    let (stdout, stderr) = (text(&out.stdout), text(&out.stderr));
    assert!(stderr.contains("nonexistent"), "{stderr}");
    assert!(
        !stdout.lines().any(|line| line.contains(" ok")),
        "rows marked ok: {stdout}"
    );
    // A directory that holds only some of the tables: the spectral row
    // fails too (it read the embedded ones).
    let some = dir.join("some");
    std::fs::create_dir_all(&some).expect("dir");
    let t1 = Path::new(env!("CARGO_MANIFEST_DIR")).join("../tables/t1-smith-g1.tbl");
    std::fs::copy(&t1, some.join("t1-smith-g1.tbl")).expect("copy T1");
    let out = run_in(
        &dir,
        &["verify", some.to_str().expect("utf-8"), "--points", "10"],
        "",
    );
    assert_eq!(out.status.code(), Some(1));
    let stdout = text(&out.stdout);
    let spectral: Vec<_> = stdout
        .lines()
        .filter(|line| line.to_lowercase().contains("spectral"))
        .collect();
    assert!(!spectral.is_empty(), "{stdout}");
    assert!(
        spectral.iter().all(|line| !line.contains(" ok")),
        "{stdout}"
    );
    std::fs::remove_dir_all(&dir).expect("clean up");
}

/// From an empty directory, `query`, `verify`, `inspect` read the embedded
/// tables and `build --out x` writes to `x`: the same bytes as the committed
/// file.
#[test]
fn works_from_an_empty_directory() {
    let dir = scratch("anywhere");
    let out = run_in(&dir, &["query", "g1"], "p,a\n1,0.5\n");
    assert!(out.status.success(), "{}", text(&out.stderr));
    assert!(text(&out.stdout).starts_with("p,a,table,reference\n1,0.5,0.99"));

    let out = run_in(&dir, &["verify", "--points", "200", "--table", "t1"], "");
    assert!(out.status.success(), "{}", text(&out.stderr));
    assert!(text(&out.stdout).contains("t1-smith-g1"));

    let out = run_in(&dir, &["inspect"], "");
    assert!(out.status.success(), "{}", text(&out.stderr));
    let listing = text(&out.stdout);
    for id in twoscale::table_set::TABLES {
        assert!(
            listing.contains(&format!("embedded {}.tbl", id.name())),
            "{listing}"
        );
    }
    assert_eq!(
        listing.matches("\n  valid\n").count(),
        twoscale::table_set::TABLES.len(),
        "{listing}"
    );
    assert!(
        listing.contains("param angles             32\n"),
        "{listing}"
    );

    let out = run_in(&dir, &["build", "t5", "--out", "x"], "");
    assert!(out.status.success(), "{}", text(&out.stderr));
    let built = std::fs::read(dir.join("x/t5-diffuse-fresnel.tbl")).expect("built file");
    let committed = Path::new(env!("CARGO_MANIFEST_DIR")).join("../tables/t5-diffuse-fresnel.tbl");
    assert!(built == std::fs::read(committed).unwrap(), "T5 differs");
    std::fs::remove_dir_all(&dir).expect("clean up");
}

/// `inspect DIR` inspects every table file in it; a wrong magic is shown
/// as text.
#[test]
fn inspect_reads_directories_and_shows_a_bad_magic_as_text() {
    let dir = scratch("inspect");
    let t5 = Path::new(env!("CARGO_MANIFEST_DIR")).join("../tables/t5-diffuse-fresnel.tbl");
    std::fs::copy(&t5, dir.join("t5-diffuse-fresnel.tbl")).unwrap();
    let mut bad = std::fs::read(&t5).unwrap();
    bad[..8].copy_from_slice(b"NOTTS\x00\x01\xff");
    std::fs::write(dir.join("bad.tbl"), &bad).unwrap();
    std::fs::write(dir.join("notes.txt"), "not a table").unwrap();
    let out = run_in(&dir, &["inspect", "."], "");
    assert_eq!(out.status.code(), Some(1), "{}", text(&out.stderr));
    let listing = text(&out.stdout);
    assert!(
        listing.contains("t5-diffuse-fresnel.tbl  (584 bytes)"),
        "{listing}"
    );
    assert!(
        listing.contains(r#"starts with "NOTTS\x00\x01\xff", expected "TWOSCALE""#),
        "{listing}"
    );
    assert!(!listing.contains("notes.txt"), "{listing}");
    std::fs::remove_dir_all(&dir).expect("clean up");
}

/// `query` opens only the tables it reads, and a bad file is named by its
/// path.
#[test]
fn query_opens_only_its_table_and_names_a_bad_file() {
    let dir = scratch("tables");
    let tables = Path::new(env!("CARGO_MANIFEST_DIR")).join("../tables");
    let t1 = std::fs::read(tables.join("t1-smith-g1.tbl")).unwrap();
    std::fs::write(dir.join("t1-smith-g1.tbl"), &t1[..1000]).unwrap();
    std::fs::copy(
        tables.join("t2-sigma-ratio.tbl"),
        dir.join("t2-sigma-ratio.tbl"),
    )
    .unwrap();
    let out = run_in(
        &dir,
        &["query", "sigma-ratio", "--tables", "."],
        "theta_i,B,c\n0.5,3,2\n",
    );
    assert!(out.status.success(), "{}", text(&out.stderr));
    let out = run_in(&dir, &["query", "g1", "--tables", "."], "p,a\n1,0.5\n");
    assert_eq!(out.status.code(), Some(1));
    let err = text(&out.stderr);
    assert!(err.contains("./t1-smith-g1.tbl: truncated"), "{err}");
    std::fs::remove_dir_all(&dir).expect("clean up");
}
