//! Record-by-record comparison of two runs' CSV outputs (`dsmcosim check`, the
//! regression test).
//!
//! Generic over the columns: a file is a header line and rows of comma-separated
//! values (RFC 4180, read with the `csv` crate, so a quoted text field may hold a comma);
//! the record's time is its `t` column, else its `t_start` column, else its
//! first column. So traces and epoch tables of every scenario kind compare alike,
//! including columns added later.
//!
//! - **Exact** ([`Tolerance::Exact`]): the text of every value must be equal. The run
//!   prints every `f64` in Rust's shortest round-trip form, so equal text means equal
//!   bits (and `-0` differs from `0`, as in the digest).
//! - **Relative** ([`Tolerance::Relative`]`(x)`): numbers agree when
//!   `|a − b| ≤ x · max(|a|, |b|)` (two zeros agree); a value that is not a number must
//!   match as text.
//!
//! Either way the header must be equal and both files must have the same number of rows,
//! and every row the same number of fields; the first disagreement is reported.

use std::fmt;
use std::path::Path;

use crate::error::{Error, Result};

/// The files every run writes and a comparison requires in both directories.
pub const REQUIRED_CSV: [&str; 2] = ["trace.csv", "epochs.csv"];

/// How values are compared.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Tolerance {
    /// Equal text, i.e. equal bits.
    Exact,
    /// `|a − b| ≤ x · max(|a|, |b|)` for numbers (x ≥ 0, dimensionless).
    Relative(f64),
}

/// The first disagreement between a stored and a new file.
#[derive(Debug, Clone, PartialEq)]
pub struct Difference {
    /// File name (`trace.csv`).
    pub file: String,
    /// What differs.
    pub kind: DifferenceKind,
}

/// What differs in a [`Difference`].
#[derive(Debug, Clone, PartialEq)]
pub enum DifferenceKind {
    /// The header lines differ: the first differing column (1-based), or the column
    /// counts.
    Header {
        /// 1-based column index of the first differing name (or the first missing one).
        column: usize,
        /// Stored column name (`None`: the stored header is shorter).
        stored: Option<String>,
        /// New column name (`None`: the new header is shorter).
        new: Option<String>,
    },
    /// A value differs (beyond the tolerance).
    Value {
        /// Record location.
        at: Record,
        /// Column name.
        column: String,
        /// Stored value as written.
        stored: String,
        /// New value as written.
        new: String,
        /// `|new − stored|` when both are numbers.
        abs: Option<f64>,
        /// `|new − stored| / max(|stored|, |new|)` when both are numbers (0 for two
        /// zeros).
        rel: Option<f64>,
    },
    /// A row has a different number of fields.
    Fields {
        /// Record location.
        at: Record,
        /// Fields in the stored row.
        stored: usize,
        /// Fields in the new row.
        new: usize,
    },
    /// The files have different numbers of rows; all common rows agree.
    Rows {
        /// Data rows (header excluded) in the stored file.
        stored: usize,
        /// Data rows in the new file.
        new: usize,
        /// Time of the first row only one file has.
        first_extra: Record,
    },
}

/// Where a record sits: its 1-based data row and its time.
#[derive(Debug, Clone, PartialEq)]
pub struct Record {
    /// 1-based data row (the header is row 0; the file line is `row + 1`).
    pub row: usize,
    /// Name of the time column (`t`, `t_start`, or the first column).
    pub time_column: String,
    /// The time column's text in that row.
    pub time: String,
}

impl fmt::Display for Record {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{} = {} (row {})", self.time_column, self.time, self.row)
    }
}

impl fmt::Display for Difference {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let file = &self.file;
        let name = |c: &Option<String>| match c {
            Some(c) => format!("`{c}`"),
            None => "nothing".to_string(),
        };
        match &self.kind {
            DifferenceKind::Header {
                column,
                stored,
                new,
            } => write!(
                f,
                "{file}: header differs at column {column}: stored {}, new {}",
                name(stored),
                name(new)
            ),
            DifferenceKind::Value {
                at,
                column,
                stored,
                new,
                abs,
                rel,
            } => {
                write!(
                    f,
                    "{file}, {at}, column {column}: stored {stored}, new {new}"
                )?;
                match (abs, rel) {
                    (Some(a), Some(r)) => write!(f, " (difference {a:.3e}, relative {r:.3e})"),
                    _ => write!(f, " (not numbers)"),
                }
            }
            DifferenceKind::Fields { at, stored, new } => write!(
                f,
                "{file}, {at}: stored row has {stored} fields, new row has {new}"
            ),
            DifferenceKind::Rows {
                stored,
                new,
                first_extra,
            } => write!(
                f,
                "{file}: stored has {stored} rows, new has {new}; the first {} agree, the {} run \
                 continues at {first_extra}",
                stored.min(new),
                if stored > new { "stored" } else { "new" }
            ),
        }
    }
}

/// Result of comparing one pair of files.
#[derive(Debug, Clone, PartialEq)]
pub struct FileComparison {
    /// File name.
    pub file: String,
    /// Data rows compared (up to the first difference).
    pub rows: usize,
    /// Values compared (up to the first difference).
    pub values: usize,
    /// Values whose text differs but that agree within the tolerance.
    pub differing: usize,
    /// Largest relative difference among the numbers compared (0 if all equal).
    pub max_rel: f64,
    /// The first disagreement, if any.
    pub difference: Option<Difference>,
}

/// Result of comparing two run directories.
#[derive(Debug, Clone, PartialEq)]
pub struct DirComparison {
    /// One entry per compared file, required ones first, then the others by name.
    pub files: Vec<FileComparison>,
    /// CSV files only one directory has (not compared, not a difference).
    pub unpaired: Vec<String>,
}

impl DirComparison {
    /// The first disagreement over all files, in file order.
    pub fn first_difference(&self) -> Option<&Difference> {
        self.files.iter().find_map(|f| f.difference.as_ref())
    }

    /// Largest relative difference over all compared numbers.
    pub fn max_rel(&self) -> f64 {
        self.files.iter().fold(0.0, |m, f| m.max(f.max_rel))
    }

    /// Values compared over all files.
    pub fn values(&self) -> usize {
        self.files.iter().map(|f| f.values).sum()
    }

    /// Values over all files whose text differs but that agree within the tolerance.
    pub fn differing(&self) -> usize {
        self.files.iter().map(|f| f.differing).sum()
    }
}

/// Compares the CSV text of a stored and a new file named `file`.
pub fn compare_csv(file: &str, stored: &str, new: &str, tol: Tolerance) -> FileComparison {
    let mut out = FileComparison {
        file: file.to_string(),
        rows: 0,
        values: 0,
        differing: 0,
        max_rel: 0.0,
        difference: None,
    };
    let diff = |kind| {
        Some(Difference {
            file: file.to_string(),
            kind,
        })
    };
    let mut s_lines = records(stored);
    let mut n_lines = records(new);
    let s_head = s_lines.next().unwrap_or_default();
    let n_head = n_lines.next().unwrap_or_default();
    if s_head != n_head {
        let column = s_head
            .iter()
            .zip(&n_head)
            .position(|(a, b)| a != b)
            .unwrap_or(s_head.len().min(n_head.len()));
        out.difference = diff(DifferenceKind::Header {
            column: column + 1,
            stored: s_head.get(column).map(str::to_string),
            new: n_head.get(column).map(str::to_string),
        });
        return out;
    }
    let time_col = ["t", "t_start"]
        .iter()
        .find_map(|name| s_head.iter().position(|h| h == *name))
        .unwrap_or(0);
    let record = |row: usize, fields: &csv::StringRecord| Record {
        row,
        time_column: s_head.get(time_col).unwrap_or_default().to_string(),
        time: fields.get(time_col).unwrap_or_default().to_string(),
    };
    let mut row = 0;
    loop {
        let (s, n) = (s_lines.next(), n_lines.next());
        let (s, n) = match (s, n) {
            (None, None) => return out,
            (Some(s), Some(n)) => (s, n),
            (s, n) => {
                let more = |first: &Option<csv::StringRecord>| usize::from(first.is_some());
                let stored_rows = row + more(&s) + s_lines.count();
                let new_rows = row + more(&n) + n_lines.count();
                let extra = s.or(n).unwrap_or_default();
                out.difference = diff(DifferenceKind::Rows {
                    stored: stored_rows,
                    new: new_rows,
                    first_extra: record(row + 1, &extra),
                });
                return out;
            }
        };
        row += 1;
        if s.len() != n.len() {
            out.difference = diff(DifferenceKind::Fields {
                at: record(row, &s),
                stored: s.len(),
                new: n.len(),
            });
            return out;
        }
        for (c, (a, b)) in s.iter().zip(&n).enumerate() {
            out.values += 1;
            if a == b {
                continue;
            }
            let numbers = a.parse::<f64>().ok().zip(b.parse::<f64>().ok());
            let (abs, rel) = match numbers {
                Some((x, y)) => {
                    let abs = (x - y).abs();
                    let scale = x.abs().max(y.abs());
                    let rel = if abs == 0.0 { 0.0 } else { abs / scale };
                    (Some(abs), Some(rel))
                }
                None => (None, None),
            };
            if let Some(r) = rel.filter(|r| !r.is_nan()) {
                out.max_rel = out.max_rel.max(r);
            }
            let agree = match (tol, rel) {
                (Tolerance::Exact, _) | (_, None) => false,
                // `!(r > x)` would accept a NaN; ask for `r ≤ x` explicitly.
                (Tolerance::Relative(x), Some(r)) => r <= x,
            };
            if !agree {
                out.difference = diff(DifferenceKind::Value {
                    at: record(row, &s),
                    column: s_head.get(c).unwrap_or("?").to_string(),
                    stored: a.to_string(),
                    new: b.to_string(),
                    abs,
                    rel,
                });
                return out;
            }
            out.differing += 1;
        }
        out.rows = row;
    }
}

/// The records of CSV `text` (the header first): every row, of any length (a row with
/// a different field count is a difference, not a parse error). Reading stops at the
/// first malformed row (invalid UTF-8 cannot occur in a `&str`), which then counts as
/// the end of the file.
fn records(text: &str) -> impl Iterator<Item = csv::StringRecord> + '_ {
    csv::ReaderBuilder::new()
        .has_headers(false)
        .flexible(true)
        .from_reader(text.as_bytes())
        .into_records()
        .map_while(|r| r.ok())
}

/// Compares the CSV files of a stored run directory with a new one: [`REQUIRED_CSV`]
/// (missing in either is an I/O error), then every other `*.csv` both directories hold,
/// by name.
pub fn compare_dirs(stored: &Path, new: &Path, tol: Tolerance) -> Result<DirComparison> {
    let s_names = csv_names(stored)?;
    let n_names = csv_names(new)?;
    let mut names: Vec<String> = REQUIRED_CSV.iter().map(|s| s.to_string()).collect();
    let mut unpaired = Vec::new();
    for name in s_names.iter().chain(&n_names) {
        if names.contains(name) || unpaired.contains(name) {
            continue;
        }
        if s_names.contains(name) && n_names.contains(name) {
            names.push(name.clone());
        } else {
            unpaired.push(name.clone());
        }
    }
    names[REQUIRED_CSV.len()..].sort();
    unpaired.sort();
    let mut files = Vec::new();
    for name in &names {
        let a = read(&stored.join(name))?;
        let b = read(&new.join(name))?;
        files.push(compare_csv(name, &a, &b, tol));
    }
    Ok(DirComparison { files, unpaired })
}

fn read(path: &Path) -> Result<String> {
    std::fs::read_to_string(path).map_err(|e| Error::io(path, e))
}

/// Names of the `*.csv` files directly in `dir`, sorted.
fn csv_names(dir: &Path) -> Result<Vec<String>> {
    let mut names = Vec::new();
    for entry in std::fs::read_dir(dir).map_err(|e| Error::io(dir, e))? {
        let entry = entry.map_err(|e| Error::io(dir, e))?;
        let name = entry.file_name().to_string_lossy().into_owned();
        if name.ends_with(".csv") && !name.starts_with('.') {
            names.push(name);
        }
    }
    names.sort();
    Ok(names)
}

#[cfg(test)]
mod tests {
    use super::*;

    const TRACE: &str = "t,w_L1,px_B1\n0,0,1.5\n0.1,0.0001,1.25\n0.2,-0.5,1e-300\n";

    fn value(d: &Difference) -> (&Record, &str, &str, &str, f64, f64) {
        match &d.kind {
            DifferenceKind::Value {
                at,
                column,
                stored,
                new,
                abs,
                rel,
            } => (
                at,
                column.as_str(),
                stored.as_str(),
                new.as_str(),
                abs.unwrap(),
                rel.unwrap(),
            ),
            other => panic!("expected a value difference, got {other:?}"),
        }
    }

    #[test]
    fn identical_files_match() {
        let c = compare_csv("trace.csv", TRACE, TRACE, Tolerance::Exact);
        assert_eq!(c.difference, None);
        assert_eq!((c.rows, c.values, c.differing, c.max_rel), (3, 9, 0, 0.0));
    }

    #[test]
    fn one_changed_digit_is_reported_with_file_time_and_column() {
        let new = TRACE.replace("1.25", "1.26");
        let c = compare_csv("trace.csv", TRACE, &new, Tolerance::Exact);
        let d = c.difference.expect("a difference");
        assert_eq!(d.file, "trace.csv");
        let (at, column, stored, new, abs, rel) = value(&d);
        assert_eq!(
            (at.row, at.time_column.as_str(), at.time.as_str()),
            (2, "t", "0.1")
        );
        assert_eq!((column, stored, new), ("px_B1", "1.25", "1.26"));
        assert!((abs - 0.01).abs() < 1e-12 && (rel - 0.01 / 1.26).abs() < 1e-12);
        let text = d.to_string();
        assert!(
            text.starts_with("trace.csv, t = 0.1 (row 2), column px_B1: stored 1.25, new 1.26"),
            "{text}"
        );
    }

    #[test]
    fn exact_means_equal_text_so_negative_zero_differs() {
        let new = TRACE.replacen("0,0,1.5", "0,-0,1.5", 1);
        let d = compare_csv("trace.csv", TRACE, &new, Tolerance::Exact)
            .difference
            .expect("-0 is not 0");
        let (_, column, _, _, abs, rel) = value(&d);
        assert_eq!((column, abs, rel), ("w_L1", 0.0, 0.0));
        // Within any tolerance they agree: both are zero.
        let c = compare_csv("trace.csv", TRACE, &new, Tolerance::Relative(0.0));
        assert_eq!(c.difference, None);
    }

    #[test]
    fn tolerance_accepts_small_and_rejects_large_differences() {
        let small = TRACE.replace("1.25", "1.2500000001");
        let c = compare_csv("trace.csv", TRACE, &small, Tolerance::Relative(1e-9));
        assert_eq!((c.difference, c.differing), (None, 1));
        assert!(c.max_rel > 7e-11 && c.max_rel < 9e-11, "{}", c.max_rel);
        let large = TRACE.replace("1e-300", "2e-300");
        let d = compare_csv("trace.csv", TRACE, &large, Tolerance::Relative(1e-9))
            .difference
            .expect("relative difference 0.5");
        let (at, column, _, _, _, rel) = value(&d);
        assert_eq!((at.time.as_str(), column, rel), ("0.2", "px_B1", 0.5));
    }

    #[test]
    fn differing_row_count_is_a_difference() {
        let short = TRACE.lines().take(3).collect::<Vec<_>>().join("\n");
        let d = compare_csv("trace.csv", TRACE, &short, Tolerance::Relative(1.0))
            .difference
            .expect("row counts differ");
        assert_eq!(
            d.kind,
            DifferenceKind::Rows {
                stored: 3,
                new: 2,
                first_extra: Record {
                    row: 3,
                    time_column: "t".into(),
                    time: "0.2".into()
                }
            }
        );
        assert!(d
            .to_string()
            .contains("the stored run continues at t = 0.2"));
    }

    #[test]
    fn differing_header_or_fields_is_a_difference() {
        let new = TRACE.replace("px_B1", "px_B2");
        let d = compare_csv("trace.csv", TRACE, &new, Tolerance::Exact)
            .difference
            .expect("headers differ");
        assert_eq!(
            d.kind,
            DifferenceKind::Header {
                column: 3,
                stored: Some("px_B1".into()),
                new: Some("px_B2".into())
            }
        );
        let new = TRACE.replace("0.1,0.0001,1.25", "0.1,0.0001,1.25,7");
        let d = compare_csv("trace.csv", TRACE, &new, Tolerance::Exact)
            .difference
            .expect("field counts differ");
        assert!(matches!(
            d.kind,
            DifferenceKind::Fields {
                stored: 3,
                new: 4,
                ..
            }
        ));
    }

    #[test]
    fn quoted_fields_may_hold_commas() {
        let a = "t,label,x\n0,\"one, two\",1\n";
        let b = "t,label,x\n0,\"one, two\",2\n";
        assert!(compare_csv("sweep.csv", a, a, Tolerance::Exact)
            .difference
            .is_none());
        let d = compare_csv("sweep.csv", a, b, Tolerance::Exact)
            .difference
            .unwrap();
        match d.kind {
            DifferenceKind::Value { column, .. } => assert_eq!(column, "x"),
            other => panic!("{other:?}"),
        }
    }

    #[test]
    fn epochs_are_timed_by_t_start() {
        let a = "t_start,t_end,cost\n0,1,0.5\n1,2,0.25\n";
        let b = "t_start,t_end,cost\n0,1,0.5\n1,2,0.26\n";
        let d = compare_csv("epochs.csv", a, b, Tolerance::Exact)
            .difference
            .expect("cost differs");
        let (at, column, ..) = value(&d);
        assert_eq!(
            (at.time_column.as_str(), at.time.as_str(), column),
            ("t_start", "1", "cost")
        );
    }
}
