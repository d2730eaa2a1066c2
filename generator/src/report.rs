//! What `generator verify` reports: the measured accuracy of each table, as
//! the terminal table it prints and as the markdown of `docs/accuracy.md`
//! (`verify --markdown`). Both are fixed functions of the measurements (no
//! timestamps, no paths), so that CI can regenerate the file and compare.

use crate::error::Error;
use crate::tables::Accuracy;
use std::fmt::Write;

/// The verification of one table file.
#[derive(Debug)]
pub struct TableReport {
    /// The file stem, e.g. `t1-smith-g1`.
    pub stem: String,
    /// The file's size in bytes (0 when it could not be read).
    pub bytes: u64,
    /// The measurements, or why there are none.
    pub outcome: Result<Vec<Accuracy>, Error>,
}

impl TableReport {
    /// Whether every gated figure met its target.
    pub fn passed(&self) -> bool {
        self.outcome
            .as_ref()
            .is_ok_and(|rows| rows.iter().all(Accuracy::passed))
    }
}

/// The terminal table: one line per measurement.
pub fn text(reports: &[TableReport]) -> String {
    let mut out = format!(
        "{:<22} {:>9}  {:<30} {:>7} {:>10} {:>10} {:>10} {:>10} {:>20}  result  worst at\n",
        "table", "bytes", "metric", "points", "max", "median", "p90", "p99", "target"
    );
    for r in reports {
        match &r.outcome {
            Ok(rows) => {
                for a in rows {
                    let _ = writeln!(
                        out,
                        "{:<22} {:>9}  {:<30} {:>7} {:>10.3e} {:>10.3e} {:>10.3e} {:>10.3e} {:>20}  {:<6}  {}",
                        r.stem,
                        r.bytes,
                        a.metric,
                        a.points,
                        a.max,
                        a.median,
                        a.p90,
                        a.p99,
                        a.target_text(),
                        a.verdict(),
                        a.worst_at
                    );
                }
            }
            Err(e) => {
                let _ = writeln!(out, "{:<22} {:>9}  FAIL: {e}", r.stem, "-");
            }
        }
    }
    out
}

/// A markdown table cell: `|` escaped, line breaks as spaces.
fn cell(s: &str) -> String {
    s.replace('|', "\\|").replace('\n', " ")
}

/// `docs/accuracy.md`: a title, the command that wrote it (`command`, e.g.
/// `generator verify --points 20000 --seed 2017`), then one section per
/// table with its measurements as a markdown table.
pub fn markdown(command: &str, reports: &[TableReport]) -> String {
    let mut out = String::new();
    let _ = write!(
        out,
        "# Accuracy of the tables\n\n\
         Written by `{command} --markdown docs/accuracy.md` (do not edit: CI \
         regenerates it and fails on any difference). Each table is measured \
         against the generator's f64 reference at random off-grid points; \
         the points are a fixed function of the seed.\n\n\
         Columns: the error metric; how many errors it summarises; their \
         maximum, median, 90th and 99th percentile; the target and whether \
         it is met (`ok` / `FAIL` decide `verify`'s exit status, `met` / \
         `missed` are reported only); where the largest error occurred.\n"
    );
    for r in reports {
        let _ = write!(out, "\n## {}\n\n", r.stem);
        match &r.outcome {
            Ok(rows) => {
                if r.bytes > 0 {
                    let _ = writeln!(out, "{} bytes.\n", r.bytes);
                }
                out.push_str(
                    "| metric | points | max | median | p90 | p99 | target | result | worst at |\n\
                     |---|---:|---:|---:|---:|---:|---|---|---|\n",
                );
                for a in rows {
                    let _ = writeln!(
                        out,
                        "| {} | {} | {:.3e} | {:.3e} | {:.3e} | {:.3e} | {} | {} | {} |",
                        cell(&a.metric),
                        a.points,
                        a.max,
                        a.median,
                        a.p90,
                        a.p99,
                        cell(&a.target_text()),
                        a.verdict(),
                        cell(&a.worst_at)
                    );
                }
            }
            Err(e) => {
                let _ = writeln!(out, "Not measured: {}", cell(&e.to_string()));
            }
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    fn report(stem: &str, target: f64) -> TableReport {
        let errors = (1..=100)
            .map(|k| (f64::from(k) * 1e-4, format!("x = {k}")))
            .collect();
        TableReport {
            stem: stem.into(),
            bytes: 1234,
            outcome: Ok(vec![Accuracy::from_errors("max |a - b|", target, errors)]),
        }
    }

    #[test]
    fn markdown_has_one_section_per_table_and_escapes_cells() {
        let reports = [
            report("t1-smith-g1", 1e-3),
            report("t2-sigma-ratio", 1e-2),
            TableReport {
                stem: "t5-missing".into(),
                bytes: 0,
                outcome: Err(Error::File {
                    action: crate::error::FileAction::Open,
                    path: "t5-missing.tbl".into(),
                    source: std::io::ErrorKind::NotFound.into(),
                }),
            },
        ];
        let md = markdown("generator verify --points 100 --seed 1", &reports);
        assert!(md.starts_with("# Accuracy of the tables\n"));
        assert!(
            md.contains("`generator verify --points 100 --seed 1 --markdown docs/accuracy.md`")
        );
        for stem in ["t1-smith-g1", "t2-sigma-ratio", "t5-missing"] {
            assert_eq!(md.matches(&format!("\n## {stem}\n")).count(), 1, "{md}");
        }
        // The metric's bars are escaped, so each row has the header's 10 bars.
        let row = md
            .lines()
            .find(|l| l.starts_with("| max"))
            .expect("a data row");
        assert_eq!(row.matches(" | ").count() + 2, 10, "{row}");
        assert!(row.contains("max \\|a - b\\|"));
        assert!(row.contains("| 1.000e-2 |"), "{row}");
        // First table misses its target (max 1e-2 > 1e-3), second meets it.
        assert!(row.contains("| FAIL |"), "{row}");
        assert!(md.contains("Not measured: cannot open t5-missing.tbl"));
        assert!(!reports[0].passed() && reports[1].passed() && !reports[2].passed());
        // The same input gives the same bytes.
        assert_eq!(
            md,
            markdown("generator verify --points 100 --seed 1", &reports)
        );
    }
}
