//! `generator export`: the exported arrays are the runtime's values (through
//! the .npy writer and reader and through a compiled C header), the reduced
//! precisions stay within their budgets, and bad arguments are clear errors.

use std::path::{Path, PathBuf};
use std::process::Command;

use generator::export::{self, Precision, Source, c, npy};
use twoscale::tables::format::{AxisHeader, TableId};
use twoscale::tables::interp::{Axis, node_value};
use twoscale::tables::mmap::MappedFile;

const TABLES: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/../tables");

fn open(id: TableId) -> MappedFile {
    MappedFile::open(Path::new(TABLES).join(format!("{}.tbl", id.name()))).expect("table file")
}

fn scratch(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("generator-export-{name}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).expect("scratch directory");
    dir
}

#[test]
fn npy_round_trip_gives_the_runtime_values_and_the_same_table_file() {
    for id in export::EXPORTABLE {
        let file = open(id);
        let source = Source::new(file.bytes(), id).expect("valid table");
        let f32s = export::export_precision(&source, Precision::F32).expect("f32 is exported");
        assert_eq!(f32s.rounding, 0.0, "{}", id.name());
        let array = &f32s.arrays[0].array;
        let back = npy::decode(&npy::encode(array).unwrap()).unwrap();
        assert_eq!(&back, array);
        let npy::Data::F32(values) = back.data else {
            panic!("f32 array")
        };
        assert_eq!(back.shape.iter().product::<usize>(), values.len());
        // Put back into a table file, the values give the original bytes.
        let rebuilt = export::table_file(&source, &values).unwrap();
        assert!(rebuilt == file.bytes(), "{}: table file differs", id.name());
    }
}

#[test]
fn reduced_precisions_are_exported_within_their_budget_or_refused() {
    let allowed = |id| {
        let file = open(id);
        let source = Source::new(file.bytes(), id).unwrap();
        let budget = export::rounding_budget(&source);
        let mut names = Vec::new();
        for p in Precision::ALL {
            let encoded = export::encode_precision(&source, p);
            match export::export_precision(&source, p) {
                Ok(e) => {
                    assert!(e.rounding <= budget);
                    names.push(p.name());
                }
                Err(message) => {
                    assert!(encoded.rounding > budget);
                    assert!(message.contains("cannot be exported as"), "{message}");
                }
            }
        }
        names
    };
    assert_eq!(allowed(TableId::SmithG1), ["f32", "unorm16"]);
    assert_eq!(allowed(TableId::SigmaRatio), ["f32", "unorm16"]);
    assert_eq!(allowed(TableId::DiffuseFresnel), ["f32"]);
    assert_eq!(allowed(TableId::Convolution), ["f32", "unorm16"]);
    assert_eq!(allowed(TableId::Albedo), ["f32", "unorm16"]);
}

#[test]
fn t3_unorm16_is_the_files_codes_and_decodes_to_the_f32_export() {
    let file = open(TableId::Convolution);
    let source = Source::new(file.bytes(), TableId::Convolution).unwrap();
    let unorm = export::export_precision(&source, Precision::Unorm16).unwrap();
    let q = source.table.quantised().expect("T3 is quantised");
    assert_eq!(unorm.arrays[0].array.data, npy::Data::U16(q.codes.to_vec()));
    assert_eq!(
        unorm.arrays[1].array.data,
        npy::Data::F32(q.scales.to_vec())
    );
    assert_eq!(unorm.arrays[1].array.shape, [28, 10, 12, 12, 2]);
    let bits = |v: &[f32]| v.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
    assert_eq!(bits(&unorm.decoded), bits(&source.values));
}

/// Nodes `0, k, 2k, …` and the last of an axis (about 12 of them).
fn sample_nodes(axis: &AxisHeader) -> Vec<usize> {
    let n = axis.nodes as usize;
    let mut v: Vec<usize> = (0..n).step_by((n / 12).max(1)).collect();
    v.push(n - 1);
    v
}

#[test]
fn c_headers_compile_and_hold_the_runtime_values() {
    if Command::new("cc").arg("--version").output().is_err() {
        panic!("no C compiler `cc` on PATH (CI installs gcc)");
    }
    let dir = scratch("c");
    let mut program = String::from("#include <stdio.h>\n");
    // (what, runtime value) per printed line, in order.
    let mut expected: Vec<(String, f64, f64)> = Vec::new();
    let mut body = String::new();
    for id in export::EXPORTABLE {
        let file = open(id);
        let source = Source::new(file.bytes(), id).unwrap();
        // T3 as codes only: its f32 array adds 14 MB of C for the same values.
        let precisions: &[Precision] = if id == TableId::Convolution {
            &[Precision::Unorm16]
        } else {
            &[Precision::F32, Precision::Unorm16]
        };
        let encoded: Vec<_> = precisions
            .iter()
            .filter_map(|&p| export::export_precision(&source, p).ok())
            .collect();
        let stem = id.name();
        std::fs::write(dir.join(format!("{stem}.h")), c::header(&source, &encoded)).unwrap();
        program.push_str(&format!("#include \"{stem}.h\"\n"));
        let p = c::prefix(stem);
        let n = source.values.len();
        let stride = (n / 50).max(1);
        for e in &encoded {
            for k in (0..n).step_by(stride).chain([n - 1]) {
                let decode = match (e.precision, e.unorm) {
                    (Precision::F32, _) => format!("{p}_f32[{k}]"),
                    (_, Some(_)) => {
                        format!("{p}_unorm16_offset + (float){p}_unorm16[{k}] * {p}_unorm16_step")
                    }
                    (_, None) => {
                        let node = k / source.table.header().channels as usize;
                        format!(
                            "{p}_unorm16_scales[{}] + (float){p}_unorm16[{k}] * {p}_unorm16_scales[{}]",
                            2 * node,
                            2 * node + 1
                        )
                    }
                };
                body.push_str(&format!("    printf(\"%a\\n\", (double)({decode}));\n"));
                // Bit-exact: the same f32 decode as the exporter's.
                let value = f64::from(e.decoded[k]);
                expected.push((format!("{stem} {} [{k}]", e.precision.name()), value, 0.0));
            }
        }
        // The axis position functions land on their nodes, as the runtime's
        // Axis::locate does.
        let header = source.table.header();
        for (d, axis) in header.used_axes().iter().enumerate() {
            let name = id.axis_names()[d];
            let runtime = Axis::new(axis).unwrap();
            for i in sample_nodes(axis) {
                let x = node_value(axis, i) as f32;
                body.push_str(&format!(
                    "    printf(\"%a\\n\", (double){p}_{name}_position({x:e}f));\n"
                ));
                let (cell, t) = runtime.locate(x);
                assert!((cell as f64 + f64::from(t) - i as f64).abs() < 2e-3);
                expected.push((format!("{stem} {name} node {i}"), i as f64, 2e-3));
            }
        }
    }
    // T3's normalised angle in C against the runtime's.
    let t3_file = open(TableId::Convolution);
    let angle = twoscale::ConvTable::from_bytes(t3_file.bytes())
        .unwrap()
        .angle_params();
    let mut rng = generator::rng::SplitMix64::new(5);
    for _ in 0..200 {
        let tau = rng.log_uniform_in(1e-6, 2e4);
        let u = rng.log_uniform_in(1e-3, 3000.0);
        let beta = rng.log_uniform_in(0.002, 1.0);
        let p = rng.uniform_in(0.2, 5.0);
        body.push_str(&format!(
            "    printf(\"%a\\n\", ts_t3_convolution_normalised_angle({tau:e}, {u:e}, {beta:e}, {p:e}));\n"
        ));
        let xi = twoscale::tables::convolution::normalised_angle(tau, u, beta, p, &angle);
        expected.push((
            format!("xi(tau = {tau:e}, u = {u:e}, β = {beta:e}, p = {p})"),
            xi,
            1e-12,
        ));
    }
    // The C lookups of T1, T2, T5 (over the f32 arrays) against the runtime's.
    let (t1, t2, t5) = (
        open(TableId::SmithG1),
        open(TableId::SigmaRatio),
        open(TableId::DiffuseFresnel),
    );
    let smith = twoscale::SmithG1Table::from_bytes(t1.bytes()).unwrap();
    let sigma = twoscale::SigmaRatioTable::from_bytes(t2.bytes()).unwrap();
    let fresnel = twoscale::DiffuseFresnelTable::from_bytes(t5.bytes()).unwrap();
    for _ in 0..200 {
        let p = rng.uniform_in(0.2, 5.0) as f32;
        let a = rng.log_uniform_in(1e-4, 1e4) as f32;
        let k_p = twoscale::tables::smith_g1::asymptotic_slope(f64::from(p)) as f32;
        body.push_str(&format!(
            "    printf(\"%a\\n\", (double)ts_t1_smith_g1_g1({p:e}f, {a:e}f, {k_p:e}f));\n"
        ));
        let g1 = f64::from(smith.g1(p, a));
        expected.push((format!("G1(p = {p}, a = {a:e})"), g1, 1e-6));
        let cos = rng.uniform_in(0.0, 1.0) as f32;
        let big_b = rng.log_uniform_in(0.05, 3000.0) as f32;
        let c = (1.0 + rng.log_uniform_in(1e-3, 99.0)) as f32;
        body.push_str(&format!(
            "    printf(\"%a\\n\", (double)ts_t2_sigma_ratio_sigma_ratio({cos:e}f, {big_b:e}f, {c:e}f));\n"
        ));
        let r = f64::from(sigma.sigma_ratio_cos(cos, big_b, c));
        expected.push((format!("r(cos = {cos}, B = {big_b}, c = {c})"), r, 1e-5 * r));
        let eta = rng.uniform_in(1.0, 3.0) as f32;
        body.push_str(&format!(
            "    printf(\"%a\\n\", (double)ts_t5_diffuse_fresnel_f_dr({eta:e}f));\n"
        ));
        let f = f64::from(fresnel.f_dr_int(eta));
        // A few f32 ulps (summation order, logf of the position).
        expected.push((format!("F_dr(η = {eta})"), f, 4e-7));
    }
    // T6's C lookup (its coordinates in double, as the runtime) against the runtime's.
    let t6 = open(TableId::Albedo);
    let albedo = twoscale::AlbedoTable::from_bytes(t6.bytes()).unwrap();
    for k in 0..200 {
        let p = rng.uniform_in(0.2, 5.0) as f32;
        let beta = rng.log_uniform_in(1e-4, 10.0) as f32;
        let cos = if k % 2 == 0 {
            rng.uniform() as f32
        } else {
            rng.log_uniform_in(1e-6, 1.0) as f32
        };
        let masking = k % 2;
        body.push_str(&format!(
            "    printf(\"%a\\n\", (double)ts_t6_albedo_albedo({cos:e}f, {beta:e}f, {p:e}f, {masking}));\n"
        ));
        let m = [
            twoscale::material::Masking::Separable,
            twoscale::material::Masking::HeightCorrelated,
        ][masking];
        let e = f64::from(albedo.albedo(cos, beta, p, m));
        // f32 summation order (2.4e-7 at worst when written).
        expected.push((
            format!("E(cos = {cos:e}, β = {beta}, p = {p}, {m:?})"),
            e,
            1e-6,
        ));
    }
    // T3b's C lookup over the exported codes (u16 per node) against the runtime's.
    let conv = twoscale::ConvTable::from_bytes(t3_file.bytes()).unwrap();
    for _ in 0..200 {
        let theta = rng.uniform_in(0.0, std::f64::consts::FRAC_PI_2 - 1e-4);
        let tau = theta.tan();
        let u = rng.log_uniform_in(1e-2, 6000.0) as f32;
        let c = rng.uniform_in(1.0, 10.5) as f32;
        let beta = rng.log_uniform_in(0.002, 1.0) as f32;
        let p = rng.uniform_in(0.2, 5.0) as f32;
        body.push_str(&format!(
            "    printf(\"%a\\n\", (double)ts_t3_convolution_conv({tau:e}, {u:e}f, {c:e}f, {beta:e}f, {p:e}f));\n"
        ));
        let want = f64::from(conv.at_tan(tau, u, c, beta, p));
        expected.push((
            format!("C(tau = {tau:e}, u = {u}, c = {c}, β = {beta}, p = {p})"),
            want,
            1e-4 * want,
        ));
    }
    program.push_str("int main(void) {\n");
    program.push_str(&body);
    program.push_str("    return 0;\n}\n");
    let source_file = dir.join("nodes.c");
    std::fs::write(&source_file, program).unwrap();
    let binary = dir.join("nodes");
    let status = Command::new("cc")
        .args([
            "-std=c11",
            "-Wall",
            "-Wextra",
            "-Werror",
            "-pedantic",
            "-O0",
        ])
        .arg(&source_file)
        .arg("-o")
        .arg(&binary)
        .arg("-lm")
        .status()
        .expect("cc runs");
    assert!(status.success(), "the exported headers do not compile");
    let output = Command::new(&binary).output().expect("program runs");
    assert!(output.status.success());
    let text = String::from_utf8(output.stdout).unwrap();
    let lines: Vec<&str> = text.lines().collect();
    assert_eq!(lines.len(), expected.len());
    let mut worst = std::collections::BTreeMap::new();
    for (line, (what, want, tolerance)) in lines.iter().zip(&expected) {
        let got = parse_hex_float(line);
        let kind = what.split(['(', ' ']).next().unwrap_or("");
        let slot = worst.entry(kind.to_string()).or_insert((0.0f64, 0.0f64));
        let relative = if *want != 0.0 {
            ((got - want) / want).abs()
        } else {
            0.0
        };
        *slot = (slot.0.max((got - want).abs()), slot.1.max(relative));
        assert!(
            (got - want).abs() <= *tolerance,
            "{what}: C prints {got:e}, runtime {want:e}"
        );
    }
    eprintln!("largest (absolute, relative) |C − runtime| per kind: {worst:?}");
    let _ = std::fs::remove_dir_all(&dir);
}

/// Parses C's `%a` output, e.g. `0x1.99999ap-3` or `-0x0p+0`.
fn parse_hex_float(text: &str) -> f64 {
    let (sign, rest) = match text.strip_prefix('-') {
        Some(r) => (-1.0, r),
        None => (1.0, text),
    };
    let rest = rest.strip_prefix("0x").expect("hex float");
    let (mantissa, exponent) = rest.split_once('p').expect("binary exponent");
    let (int, frac) = mantissa.split_once('.').unwrap_or((mantissa, ""));
    let mut value = u64::from_str_radix(int, 16).unwrap() as f64;
    for (k, digit) in frac.chars().enumerate() {
        value += f64::from(digit.to_digit(16).unwrap()) / 16f64.powi(k as i32 + 1);
    }
    sign * value * 2f64.powi(exponent.parse::<i32>().unwrap())
}

#[test]
fn bad_arguments_are_clear_errors() {
    let out = scratch("cli");
    let run = |args: &[&str]| {
        let output = Command::new(env!("CARGO_BIN_EXE_generator"))
            .arg("export")
            .arg("--out")
            .arg(&out)
            .args(["--points", "0"])
            .args(args)
            .output()
            .expect("generator runs");
        assert!(!output.status.success(), "{args:?} succeeded");
        let stderr = String::from_utf8(output.stderr).unwrap();
        assert!(!stderr.contains("panicked"), "{stderr}");
        stderr
    };
    assert!(run(&["--table", "t9"]).contains("unknown table 't9'"));
    assert!(run(&["--table", "t4"]).contains("T4 (SH matrices) is not exported"));
    assert!(run(&["--precision", "f64"]).contains("unknown precision 'f64'"));
    assert!(run(&["--format", "csv"]).contains("unknown format 'csv'"));
    assert!(run(&["--dir", "/nonexistent-tables"]).contains("cannot open /nonexistent-tables/"));
    let refused = run(&["--table", "t5", "--precision", "unorm16"]);
    assert!(
        refused.contains("t5-diffuse-fresnel cannot be exported as unorm16"),
        "{refused}"
    );
    assert!(run(&["--table", "t1", "--precision", "f16"]).contains("use f32 or unorm16"));
    // A refused precision writes nothing.
    assert_eq!(std::fs::read_dir(&out).unwrap().count(), 0);
    let _ = std::fs::remove_dir_all(&out);
}

#[test]
fn npy_export_writes_the_documented_files() {
    let out = scratch("npy");
    let status = Command::new(env!("CARGO_BIN_EXE_generator"))
        .args([
            "export", "--points", "0", "--table", "t1", "--table", "t5", "--out",
        ])
        .arg(&out)
        .status()
        .expect("generator runs");
    assert!(status.success());
    let mut names: Vec<String> = std::fs::read_dir(&out)
        .unwrap()
        .map(|e| e.unwrap().file_name().into_string().unwrap())
        .collect();
    names.sort();
    assert_eq!(
        names,
        [
            "t1-smith-g1.aux.npy",
            "t1-smith-g1.f32.npy",
            "t1-smith-g1.unorm16.npy",
            "t5-diffuse-fresnel.f32.npy",
            "tables.json"
        ]
    );
    let t1 = npy::decode(&std::fs::read(out.join("t1-smith-g1.f32.npy")).unwrap()).unwrap();
    assert_eq!(t1.shape, [64, 1000]);
    let t5 = npy::decode(&std::fs::read(out.join("t5-diffuse-fresnel.f32.npy")).unwrap()).unwrap();
    assert_eq!(t5.shape, [50]);
    let _ = std::fs::remove_dir_all(&out);
}
