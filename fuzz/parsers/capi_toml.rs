//! The C API's material-file fuzz harness (`ts_material_desc_from_toml` and
//! `ts_material_file_from_toml`), shared by the libFuzzer target
//! (`fuzz/fuzz_targets/capi_toml.rs`) and the stable-Rust replay
//! (`tests/fuzz_regressions.rs`).
//!
//! The input is the C string (up to its first NUL). Each entry point must
//! return a status, never `TS_ERR_PANIC`; a description or file that reads
//! must give a material (`ts_material_new`) whose `ts_eval_rgb`, `ts_pdf`
//! and `ts_sample_rgb` succeed with finite values, and the two entry points
//! must agree: the same status, and the same description where the first
//! can hold it (not for a spectrum, whose rows `ts_material_desc_from_toml`
//! refuses).

use std::ffi::CString;
use twoscale_capi::*;

/// The embedded tables' handle, freed with the thread.
struct Tables(*mut ts_tables);

impl Drop for Tables {
    fn drop(&mut self) {
        // SAFETY: a live handle, freed once.
        unsafe { ts_tables_free(self.0) };
    }
}

thread_local! {
    /// `ts_tables_embedded()` once per thread: validating the tables took
    /// 0.2 s of each input's run under ASan.
    static TABLES: Tables = {
        let t = ts_tables_embedded();
        assert!(!t.is_null());
        Tables(t)
    };
}

/// Runs one input (module documentation); true if the text read.
pub fn run(data: &[u8]) -> bool {
    let end = data.iter().position(|&b| b == 0).unwrap_or(data.len());
    let text = CString::new(&data[..end]).expect("no NUL before `end`");
    let mut desc = ts_material_desc::default();
    // SAFETY: a NUL-terminated string and a writable description.
    let status = unsafe { ts_material_desc_from_toml(text.as_ptr(), &mut desc) };
    assert_ne!(status, TS_ERR_PANIC, "{}", last_error());
    let mut file: *mut ts_material_file = std::ptr::null_mut();
    // SAFETY: as above; `file` is writable.
    let file_status = unsafe { ts_material_file_from_toml(text.as_ptr(), &mut file) };
    assert_ne!(file_status, TS_ERR_PANIC, "{}", last_error());
    assert_eq!(file_status == TS_OK, !file.is_null());
    let tables = TABLES.with(|t| t.0);
    if file_status == TS_OK {
        let mut from_file = ts_material_desc::default();
        // SAFETY: a live file handle and a writable description.
        assert_eq!(
            unsafe { ts_material_file_desc(file, &mut from_file) },
            TS_OK
        );
        if status == TS_OK {
            assert_eq!(desc, from_file);
        } else {
            // Only a spectrum reads as a file and not as a description.
            assert_eq!(status, TS_ERR_INVALID, "{}", last_error());
            assert!(!from_file.eta_rows.is_null());
        }
        evaluate(tables, &from_file);
    } else {
        assert_eq!(status, file_status, "{}", last_error());
    }
    // SAFETY: a live handle (or NULL), freed once.
    unsafe { ts_material_file_free(file) };
    file_status == TS_OK
}

fn last_error() -> String {
    // SAFETY: ts_last_error gives a NUL-terminated string of this thread.
    unsafe { std::ffi::CStr::from_ptr(ts_last_error()) }
        .to_string_lossy()
        .into_owned()
}

/// A material of `desc` evaluated, sampled and its pdf taken.
fn evaluate(tables: *mut ts_tables, desc: &ts_material_desc) {
    // SAFETY: a live tables handle and a description whose rows are live.
    let m = unsafe { ts_material_new(tables, desc) };
    assert!(
        !m.is_null(),
        "a description that read is refused: {}",
        last_error()
    );
    let (wi, wo, u) = (
        [0.6f32, 0.1, 0.8],
        [-0.55f32, -0.05, 0.83],
        [0.3f32, 0.7, 0.2],
    );
    let (mut rgb, mut pdf, mut sample) = ([0.0f32; 3], 0.0f32, ts_sample::default());
    // SAFETY: a live material and arrays of the documented sizes.
    unsafe {
        assert_eq!(
            ts_eval_rgb(m, wi.as_ptr(), wo.as_ptr(), rgb.as_mut_ptr()),
            TS_OK
        );
        assert_eq!(ts_pdf(m, wi.as_ptr(), wo.as_ptr(), &mut pdf), TS_OK);
        assert_eq!(
            ts_sample_rgb(m, wi.as_ptr(), u.as_ptr(), &mut sample),
            TS_OK
        );
        ts_material_free(m);
    }
    assert!(rgb.iter().all(|v| v.is_finite() && *v >= 0.0), "{rgb:?}");
    assert!(pdf.is_finite() && pdf >= 0.0, "{pdf}");
    assert!(sample.pdf.is_finite() && sample.value.iter().all(|v| v.is_finite()));
}
