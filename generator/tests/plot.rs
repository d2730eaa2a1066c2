//! `generator plot` runs: one material's lobes (and, for a preset, its
//! lobes at five wavelengths) into a temporary directory give PNGs of the
//! documented size.

use std::path::PathBuf;
use std::process::Command;

#[test]
fn plot_writes_the_lobes_of_one_material() {
    let out = std::env::temp_dir().join(format!("generator-plot-test-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&out);
    let status = Command::new(env!("CARGO_BIN_EXE_generator"))
        .args(["plot", "--no-errors", "--material", "gold-rough", "--out"])
        .arg(&out)
        .status()
        .expect("generator runs");
    assert!(status.success(), "generator plot failed: {status}");
    let mut written: Vec<PathBuf> = std::fs::read_dir(&out)
        .expect("output directory")
        .map(|e| e.expect("entry").path())
        .collect();
    written.sort();
    assert_eq!(
        written,
        vec![
            out.join("lobes-gold-rough.png"),
            out.join("spectral-gold-rough.png")
        ]
    );
    for path in &written {
        let png = std::fs::read(path).expect("readable PNG");
        assert_eq!(&png[..8], b"\x89PNG\r\n\x1a\n", "not a PNG");
        // IHDR: width and height, big-endian, at bytes 16..24.
        let width = u32::from_be_bytes(png[16..20].try_into().unwrap());
        let height = u32::from_be_bytes(png[20..24].try_into().unwrap());
        assert_eq!((width, height), (800, 540));
        // Curves and text, not a blank canvas: a blank 800×540 PNG
        // compresses to a few kB.
        assert!(png.len() > 20_000, "{} bytes", png.len());
    }
    std::fs::remove_dir_all(&out).expect("clean up");
}

#[test]
fn plot_refuses_an_unknown_material() {
    let output = Command::new(env!("CARGO_BIN_EXE_generator"))
        .args([
            "plot",
            "--no-errors",
            "--material",
            "no-such-material",
            "--out",
        ])
        .arg(std::env::temp_dir().join("generator-plot-test-unknown"))
        .output()
        .expect("generator runs");
    assert!(!output.status.success());
    let stderr = String::from_utf8_lossy(&output.stderr);
    assert!(stderr.contains("no material no-such-material"), "{stderr}");
}

/// The committed lobe pictures are what `generator plot` draws from the
/// embedded tables and the shipped materials (byte for byte: the drawing is
/// deterministic, whatever the thread count). CI's installed-generator step
/// compares the error maps too (they repeat verify's 20 000 points).
#[test]
fn the_committed_lobes_are_what_plot_draws() {
    let out = std::env::temp_dir().join(format!("generator-plot-docs-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&out);
    let status = Command::new(env!("CARGO_BIN_EXE_generator"))
        .args(["plot", "--no-errors", "--out"])
        .arg(&out)
        .status()
        .expect("generator runs");
    assert!(status.success(), "generator plot failed: {status}");
    let docs = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../docs/img");
    let mut drawn: Vec<PathBuf> = std::fs::read_dir(&out)
        .expect("output directory")
        .map(|e| e.expect("entry").path())
        .collect();
    drawn.sort();
    // Per preset its lobes and its lobes at five wavelengths; gold's two RGBs.
    assert_eq!(drawn.len(), 2 * twoscale::materials::PRESETS.len() + 1);
    for path in &drawn {
        let name = path.file_name().expect("file name");
        let committed = std::fs::read(docs.join(name)).expect("committed picture");
        assert!(
            std::fs::read(path).expect("drawn picture") == committed,
            "docs/img/{} differs from what `generator plot --out docs/img` draws",
            name.to_string_lossy()
        );
    }
    std::fs::remove_dir_all(&out).expect("clean up");
}
