//! The output contract of `dsmcosim run SCENARIO --out DIR`, checked field by field.
//!
//! What a run directory must hold (docs/reference.md "Outputs"):
//! - `summary.json`: `scenario`, `seed`, `digest` (64 hex digits), `steps`, `sim_seconds`,
//!   `wall_seconds`, `max_constraint_violation`, `mean_cost`; on a controlled run also
//!   `unpaired_mean_cost_<method>` for every method with an objective column in epochs.csv;
//! - `summary.json` also: `invariants` with `start` and `end` (`t`, `momentum`,
//!   `angular_momentum`, `kinetic_energy`) and the drift fields; on SMC runs
//!   `boundary_layer` (`epsilon`, `steps_outside`, `share_outside`, `worst`,
//!   `worst_time`);
//! - `trace.csv`: `t`, then `w_L<k>` and `f_L<k>` for every link `k = 1..links`, then
//!   `px_B<i>,py_B<i>,pz_B<i>,vx_B<i>,vy_B<i>,vz_B<i>` per traced body, then
//!   `Px,Py,Pz,Lx,Ly,Lz,KE`, then (with `output.trace_rotation`)
//!   `qw_B<i>,qx_B<i>,qy_B<i>,qz_B<i>,wx_B<i>,wy_B<i>,wz_B<i>` per traced body in the
//!   same order; every value a finite number, every row as wide as the header, `t`
//!   increasing;
//! - `epochs.csv` (one row per measurement window): `t_start`, `t_end`, the requested
//!   and achieved τ of every channel, `bandwidth`, `cost`; on a controlled run the
//!   objective of every method (NaN where a method measured nothing in that window);
//! - the plots of the run's kind, each a well-formed SVG with text (title, axis labels).
//!
//! [`problems`] returns every breach it finds, so a failing test lists them all.

use std::path::Path;

use serde_json::Value;

/// Every breach of the output contract in run directory `dir` (empty when it conforms).
pub fn problems(dir: &Path) -> Vec<String> {
    let mut out = Vec::new();
    let summary = match std::fs::read_to_string(dir.join("summary.json")) {
        Ok(text) => match serde_json::from_str::<Value>(&text) {
            Ok(v) => v,
            Err(e) => return vec![format!("summary.json is not JSON: {e}")],
        },
        Err(e) => return vec![format!("no summary.json: {e}")],
    };
    check_summary(&summary, &mut out);
    let links = summary["links"].as_u64().unwrap_or(0) as usize;
    check_trace(dir, links, &mut out);
    let methods = check_epochs(dir, &summary, &mut out);
    check_methods(&summary, &methods, &mut out);
    check_plots(dir, &summary, &mut out);
    out
}

/// Whether the run was controlled (a controller chose the delays).
fn controlled(summary: &Value) -> bool {
    summary.get("controller").is_some_and(Value::is_object)
}

fn check_summary(s: &Value, out: &mut Vec<String>) {
    for key in ["scenario"] {
        if !s[key].is_string() {
            out.push(format!("summary.json: '{key}' is missing or not a string"));
        }
    }
    for key in ["seed", "steps"] {
        if !s[key].is_u64() {
            out.push(format!(
                "summary.json: '{key}' is missing or not a whole number"
            ));
        }
    }
    for key in [
        "sim_seconds",
        "wall_seconds",
        "max_constraint_violation",
        "mean_cost",
    ] {
        match s[key].as_f64() {
            Some(x) if x.is_finite() && x >= 0.0 => {}
            _ => out.push(format!(
                "summary.json: '{key}' is missing or not a finite number ≥ 0 (got {})",
                s[key]
            )),
        }
    }
    let inv = &s["invariants"];
    for end in ["start", "end"] {
        let e = &inv[end];
        let vector = |k: &str| {
            e[k].as_array()
                .is_some_and(|a| a.len() == 3 && a.iter().all(Value::is_f64))
        };
        let complete = e["t"].is_f64()
            && vector("momentum")
            && vector("angular_momentum")
            && e["kinetic_energy"].as_f64().is_some_and(|x| x >= 0.0);
        if !complete {
            out.push(format!(
                "summary.json: 'invariants.{end}' lacks t, momentum, angular_momentum or kinetic_energy ≥ 0: {e}"
            ));
        }
    }
    for key in [
        "momentum_drift",
        "angular_momentum_drift",
        "kinetic_energy_drift",
    ] {
        if inv.get(key).is_none() {
            out.push(format!("summary.json: no 'invariants.{key}'"));
        }
    }
    if s["stabilizer"]["kind"] == "smc" {
        let b = &s["boundary_layer"];
        let fine = b["epsilon"].as_f64() == s["stabilizer"]["epsilon"].as_f64()
            && b["steps_outside"].as_u64().is_some_and(|n| {
                let share = n as f64 / (s["steps"].as_f64().unwrap_or(0.0) + 1.0);
                b["share_outside"].as_f64() == Some(share)
            })
            && b["worst"].as_f64() == s["max_constraint_violation"].as_f64();
        if !fine {
            out.push(format!(
                "summary.json: 'boundary_layer' does not match the stabilizer, the steps and max |w|: {b}"
            ));
        }
    }
    let digest = s["digest"].as_str().unwrap_or("");
    if digest.len() != 64 || !digest.bytes().all(|b| b.is_ascii_hexdigit()) {
        out.push(format!(
            "summary.json: 'digest' is not 64 hex digits: {digest:?}"
        ));
    }
}

/// Every method with an objective column in epochs.csv has its mean cost in the summary,
/// and so has the controller's own method.
fn check_methods(s: &Value, methods: &[String], out: &mut Vec<String>) {
    if !controlled(s) {
        return;
    }
    if methods.is_empty() {
        out.push("epochs.csv: a controlled run has no objective_<method> column".into());
    }
    let own = s["controller"]["method"]
        .as_str()
        .unwrap_or("?")
        .to_string();
    for m in methods.iter().chain(std::iter::once(&own)) {
        let key = format!("unpaired_mean_cost_{m}");
        if !s.get(&key).is_some_and(|v| v.is_number() || v.is_null()) {
            out.push(format!("summary.json: no per-method mean cost '{key}'"));
        }
    }
}

/// Reads a CSV file of plain numbers and names: header and rows.
fn read_csv(dir: &Path, name: &str, out: &mut Vec<String>) -> Option<(Vec<String>, Vec<String>)> {
    let text = match std::fs::read_to_string(dir.join(name)) {
        Ok(t) => t,
        Err(e) => {
            out.push(format!("no {name}: {e}"));
            return None;
        }
    };
    let mut lines = text.lines();
    let head: Vec<String> = lines
        .next()
        .unwrap_or("")
        .split(',')
        .map(str::to_string)
        .collect();
    Some((head, lines.map(str::to_string).collect()))
}

fn check_trace(dir: &Path, links: usize, out: &mut Vec<String>) {
    let Some((head, rows)) = read_csv(dir, "trace.csv", out) else {
        return;
    };
    if head.first().map(String::as_str) != Some("t") {
        out.push("trace.csv: the first column is not 't'".into());
    }
    if links == 0 {
        out.push("summary.json: 'links' is missing or zero".into());
    }
    let mut expected: Vec<String> = vec!["t".into()];
    expected.extend((1..=links).map(|k| format!("w_L{k}")));
    expected.extend((1..=links).map(|k| format!("f_L{k}")));
    if head.len() < expected.len() || head[..expected.len()] != expected[..] {
        out.push(format!(
            "trace.csv: the header does not start with t, w_L1..w_L{links}, f_L1..f_L{links}"
        ));
    }
    let rest = &head[expected.len().min(head.len())..];
    let invariants = ["Px", "Py", "Pz", "Lx", "Ly", "Lz", "KE"];
    let Some(at) = rest.iter().position(|c| c == "Px") else {
        out.push("trace.csv: no invariant columns Px..KE".into());
        return;
    };
    let (bodies, rest) = rest.split_at(at);
    if rest.len() < invariants.len() || rest[..invariants.len()] != invariants {
        out.push(format!(
            "trace.csv: the body columns are not followed by {}",
            invariants.join(",")
        ));
        return;
    }
    let rotations = &rest[invariants.len()..];
    if !rotations.is_empty() {
        let want: Vec<String> = bodies
            .chunks(6)
            .flat_map(|g| {
                let id = g[0].strip_prefix("px_B").unwrap_or("?").to_string();
                ["qw", "qx", "qy", "qz", "wx", "wy", "wz"].map(|a| format!("{a}_B{id}"))
            })
            .collect();
        if rotations != &want[..] {
            out.push(format!(
                "trace.csv: rotation columns {rotations:?} are not qw..wz of each traced body in order"
            ));
        }
    }
    if bodies.is_empty() || bodies.len() % 6 != 0 {
        out.push(format!(
            "trace.csv: {} body columns, not a positive multiple of 6",
            bodies.len()
        ));
    }
    for group in bodies.chunks(6) {
        let id = group[0].strip_prefix("px_B").unwrap_or("?");
        let want: Vec<String> = ["px", "py", "pz", "vx", "vy", "vz"]
            .iter()
            .map(|a| format!("{a}_B{id}"))
            .collect();
        if group != &want[..] || id.parse::<u64>().is_err() {
            out.push(format!(
                "trace.csv: body columns {group:?} are not px..vz of one body"
            ));
        }
    }
    if rows.is_empty() {
        out.push("trace.csv: no rows".into());
    }
    let Some(values) = numbers("trace.csv", &head, &rows, &|_| true, out) else {
        return;
    };
    for (r, pair) in values.windows(2).enumerate() {
        if pair[1][0] <= pair[0][0] {
            out.push(format!("trace.csv row {}: t does not increase", r + 3));
            return;
        }
    }
}

/// Parses every row of a CSV file as numbers: each as wide as the header, each cell a
/// number, finite in the columns `finite` names. The rows, or `None` after reporting the
/// first breach (rows are numbered as in the file, the header being row 1).
fn numbers(
    file: &str,
    head: &[String],
    rows: &[String],
    finite: &dyn Fn(&str) -> bool,
    out: &mut Vec<String>,
) -> Option<Vec<Vec<f64>>> {
    let mut values = Vec::with_capacity(rows.len());
    for (r, row) in rows.iter().enumerate() {
        let cells: Vec<&str> = row.split(',').collect();
        if cells.len() != head.len() {
            out.push(format!(
                "{file} row {}: {} cells for {} columns",
                r + 2,
                cells.len(),
                head.len()
            ));
            return None;
        }
        let mut parsed = Vec::with_capacity(cells.len());
        for (col, cell) in head.iter().zip(&cells) {
            match cell.parse::<f64>() {
                Ok(x) if x.is_finite() || !finite(col) => parsed.push(x),
                _ => {
                    out.push(format!(
                        "{file} row {}, column {col}: not a finite number: {cell:?}",
                        r + 2
                    ));
                    return None;
                }
            }
        }
        values.push(parsed);
    }
    Some(values)
}

/// Checks epochs.csv; returns the methods that have an objective column.
fn check_epochs(dir: &Path, summary: &Value, out: &mut Vec<String>) -> Vec<String> {
    let Some((head, rows)) = read_csv(dir, "epochs.csv", out) else {
        return Vec::new();
    };
    let mut expected = vec!["t_start".to_string(), "t_end".into()];
    for ch in summary["channels"].as_array().into_iter().flatten() {
        let name = ch["name"].as_str().unwrap_or("?");
        expected.push(format!("tau_{name}_requested"));
        expected.push(format!("tau_{name}_achieved"));
    }
    expected.push("bandwidth".into());
    expected.push("cost".into());
    let methods: Vec<String> = head
        .iter()
        .filter_map(|c| c.strip_prefix("objective_").map(str::to_string))
        .collect();
    for col in &expected {
        if !head.contains(col) {
            out.push(format!("epochs.csv: no column '{col}'"));
        }
    }
    if rows.is_empty() {
        out.push("epochs.csv: no rows".into());
    }
    // A method that measured nothing in a window reports NaN for its objective.
    numbers(
        "epochs.csv",
        &head,
        &rows,
        &|col| expected.iter().any(|e| e == col),
        out,
    );
    methods
}

fn check_plots(dir: &Path, summary: &Value, out: &mut Vec<String>) {
    let mut want = vec!["constraints.svg", "bodies.svg", "cost.svg"];
    if summary["channels"]
        .as_array()
        .is_some_and(|c| !c.is_empty())
    {
        want.extend(["delays.svg", "bandwidth.svg"]);
    }
    if controlled(summary) {
        want.push("cost_methods.svg");
    }
    for name in want {
        let text = match std::fs::read_to_string(dir.join(name)) {
            Ok(t) => t,
            Err(e) => {
                out.push(format!("no {name}: {e}"));
                continue;
            }
        };
        match roxmltree::Document::parse(&text) {
            Ok(doc) => {
                let has_text = doc
                    .descendants()
                    .any(|n| n.tag_name().name() == "text" && n.text().is_some());
                if doc.root_element().tag_name().name() != "svg" || !has_text {
                    out.push(format!("{name}: not an SVG with text (title, axis labels)"));
                }
            }
            Err(e) => out.push(format!("{name}: not well-formed XML: {e}")),
        }
    }
}
