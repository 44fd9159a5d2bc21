//! `dsmcosim distance`: how far the bodies of runs drift from a reference run, step by
//! traced step — the horizon over which two runs of a chaotic scene stay comparable.
//!
//! Reads `trace.csv` of a reference run directory and of each compared run (all traced
//! at the same times; a run that stopped early, e.g. one that diverged, up to its end,
//! its cells empty after it), and writes `distance.csv` (`t`, then one column
//! `<run>_B<id>` per run (its directory as given) and body: `|p_run − p_ref|` [m]) and `distance.svg` (the same
//! on a log scale; zero distances, e.g. at t = 0, are not drawn on it).
//!
//! The trace files are read whole, so their size bounds the memory used; at most
//! [`MAX_CURVES`] runs × bodies are compared, the curves one plot can tell apart.

use std::path::{Path, PathBuf};

use crate::error::{Error, Result};
use crate::output::{create_out_dir, write_atomic};
use crate::report::{write_line_plot, LinePlot, Scale, Series};

/// Most (run, body) curves one comparison draws.
pub const MAX_CURVES: usize = 12;

/// A trace read back: its header and its rows of numbers.
struct Trace {
    file: PathBuf,
    header: Vec<String>,
    rows: Vec<Vec<f64>>,
}

impl Trace {
    fn read(dir: &Path) -> Result<Trace> {
        let file = dir.join("trace.csv");
        let text = std::fs::read_to_string(&file).map_err(|e| Error::io(&file, e))?;
        let mut reader = csv::ReaderBuilder::new()
            .has_headers(false)
            .flexible(true)
            .from_reader(text.as_bytes());
        let mut records = reader.records();
        let header: Vec<String> = match records.next() {
            Some(Ok(r)) => r.iter().map(str::to_string).collect(),
            _ => Vec::new(),
        };
        if header.first().map(String::as_str) != Some("t") {
            return Err(Error::invalid(
                file.display().to_string(),
                "is not a trace.csv (its first column is not `t`)",
            ));
        }
        let mut rows = Vec::new();
        for (i, record) in records.enumerate() {
            let line = record
                .as_ref()
                .ok()
                .and_then(|r| r.position())
                .map_or(i + 2, |p| p.line() as usize);
            let row: Option<Vec<f64>> = record
                .ok()
                .and_then(|r| r.iter().map(|f| f.parse::<f64>().ok()).collect());
            match row {
                Some(r) if r.len() == header.len() => rows.push(r),
                _ => {
                    return Err(Error::invalid(
                        format!("{}:{line}", file.display()),
                        format!("expected {} numbers", header.len()),
                    ))
                }
            }
        }
        Ok(Trace { file, header, rows })
    }

    /// Column indices of body `id`'s position.
    fn position(&self, id: u32) -> Result<[usize; 3]> {
        let col = |axis: &str| {
            let name = format!("p{axis}_B{id}");
            self.header.iter().position(|h| *h == name).ok_or_else(|| {
                Error::invalid(
                    format!("--bodies {id}"),
                    format!("{} has no column {name}", self.file.display()),
                )
            })
        };
        Ok([col("x")?, col("y")?, col("z")?])
    }
}

/// The name a run goes by in columns and legends: its directory as given (unique where
/// the last components of several runs are alike).
fn run_name(dir: &Path) -> String {
    dir.display().to_string().trim_end_matches('/').to_string()
}

/// Compares `runs` with `reference` for `bodies` and writes into `out`.
pub fn command(reference: &Path, runs: &[PathBuf], bodies: &[u32], out: &Path) -> Result<()> {
    crate::output::refuse_foreign_outputs(out, "distance.csv", |n| n == "distance.svg")?;
    let curves = runs.len() * bodies.len();
    if curves == 0 || curves > MAX_CURVES {
        return Err(Error::invalid(
            "--bodies",
            format!(
                "{} runs × {} bodies give {curves} curves; 1 to {MAX_CURVES} are drawn",
                runs.len(),
                bodies.len()
            ),
        ));
    }
    let refer = Trace::read(reference)?;
    let traces = runs
        .iter()
        .map(|d| Trace::read(d))
        .collect::<Result<Vec<_>>>()?;
    // Every trace must be sampled at the reference's times. A run that stopped early (it
    // diverged, or was interrupted) is compared up to its last traced time: its trace up
    // to there is its result.
    for t in &traces {
        let same = t.rows.len() <= refer.rows.len()
            && t.rows.iter().zip(&refer.rows).all(|(a, b)| a[0] == b[0]);
        if !same {
            return Err(Error::invalid(
                t.file.display().to_string(),
                format!(
                    "is not traced at the times of {} (same decimation needed, and a \
                     duration no longer than the reference's)",
                    refer.file.display()
                ),
            ));
        }
    }
    let mut columns = Vec::new();
    for (dir, trace) in runs.iter().zip(&traces) {
        for &id in bodies {
            let (a, b) = (refer.position(id)?, trace.position(id)?);
            let d: Vec<f64> = refer
                .rows
                .iter()
                .zip(&trace.rows)
                .map(|(r, x)| {
                    (0..3)
                        .map(|k| (x[b[k]] - r[a[k]]).powi(2))
                        .sum::<f64>()
                        .sqrt()
                })
                .collect();
            columns.push((format!("{}_B{id}", run_name(dir)), d));
        }
    }
    create_out_dir(out)?;
    // Through the CSV writer: a run path with a comma or a quote is one quoted field.
    let header = std::iter::once("t".to_string()).chain(columns.iter().map(|(n, _)| n.clone()));
    // A run that ended earlier leaves its cells empty past its end.
    let rows = refer.rows.iter().enumerate().map(|(i, row)| {
        std::iter::once(format!("{}", row[0]))
            .chain(
                columns
                    .iter()
                    .map(move |(_, d)| d.get(i).map_or(String::new(), |v| format!("{v}"))),
            )
            .collect::<Vec<String>>()
    });
    let csv = crate::output::csv_text(std::iter::once(header.collect::<Vec<String>>()).chain(rows));
    write_atomic(&out.join("distance.csv"), csv.as_bytes())?;
    let series: Vec<Series> = columns
        .iter()
        .map(|(name, d)| {
            let points = refer.rows.iter().map(|r| r[0]).zip(d.iter().copied());
            Series::new(name.clone(), points.collect())
        })
        .collect();
    let title = format!("Distance of body positions from {}", run_name(reference));
    write_line_plot(
        &out.join("distance.svg"),
        &LinePlot {
            y_scale: Scale::Log,
            ..LinePlot::new(&title, "time t [s]", "|p − p_ref| [m]", &series)
        },
    )
}
