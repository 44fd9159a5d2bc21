//! The stability map: a scenario run over a grid of SMC `μ` × `dt`, every other setting
//! kept, each cell classified by what the run did:
//!
//! - `0`: ran to the horizon with `max |w| ≤ ε` (inside the boundary layer),
//! - `1`: ran to the horizon, but `max |w| > ε`,
//! - `2`: diverged (`|w|` beyond `divergence.max_violation`, non-finite state, or a
//!   failed multiplier solve).
//!
//! Writes `stability_map.csv`, `stability_map.md` (the grid as a table),
//! `stability_map.svg` (the outcome) and `stability_max_w.svg` (`log10 max |w|`).

use std::fmt::Write as _;
use std::path::Path;

use serde_json::{json, Value};

use super::measure::Counter;
use crate::cosim::{CoSim, Observer, StepValues};
use crate::error::{Error, Result};
use crate::kernel::SimTime;
use crate::output::{create_out_dir, write_atomic};
use crate::report::{write_heatmap, CellClass, Heatmap};
use crate::scenario::model::Stabilizer;
use crate::scenario::parse_str;

/// `μ` values of the map [s]: 1-2-5 steps over three decades.
pub const MU: [f64; 10] = [1e-3, 2e-3, 5e-3, 1e-2, 2e-2, 5e-2, 0.1, 0.2, 0.5, 1.0];

/// `dt` values of the map [s]: 1-2-5 steps over two decades. Every one divides 10 ms,
/// so any horizon that is a multiple of 10 ms is whole steps for all of them.
pub const DT: [f64; 7] = [1e-4, 2e-4, 5e-4, 1e-3, 2e-3, 5e-3, 1e-2];

/// One cell of the map.
#[derive(Debug, Clone)]
pub struct Cell {
    /// `μ` [s].
    pub mu: f64,
    /// `dt` [s].
    pub dt: f64,
    /// 0, 1 or 2 (see the module docs); `None` if the scenario format refused it.
    pub outcome: Option<u8>,
    /// Largest `|w|` over the steps run [m].
    pub max_violation: f64,
    /// The error that stopped the run (or refused the cell), empty if none.
    pub error: String,
}

/// The finished map.
#[derive(Debug, Clone)]
pub struct StabilityMap {
    /// Scenario name.
    pub name: String,
    /// Horizon.
    pub horizon: SimTime,
    /// Integrator name.
    pub integrator: &'static str,
    /// SMC gain K [m/s].
    pub k: f64,
    /// SMC boundary layer ε [m].
    pub epsilon: f64,
    /// Divergence bound [m].
    pub bound: f64,
    /// Cells, `μ`-major: `cells[i_mu * DT.len() + i_dt]`.
    pub cells: Vec<Cell>,
}

impl StabilityMap {
    /// The cell at (`MU[i_mu]`, `DT[i_dt]`).
    pub fn cell(&self, i_mu: usize, i_dt: usize) -> &Cell {
        &self.cells[i_mu * DT.len() + i_dt]
    }
}

struct Count<'a>(&'a mut Counter);

impl Observer for Count<'_> {
    fn on_step(&mut self, _: &StepValues) -> std::io::Result<()> {
        self.0.add(1);
        Ok(())
    }
}

/// Runs the map of the scenario file `path` (optionally over `duration` seconds instead
/// of the scenario's duration) and writes it into `out`.
pub fn stability_map(
    path: &Path,
    sets: &[String],
    out: &Path,
    duration: Option<f64>,
) -> Result<StabilityMap> {
    crate::output::refuse_foreign_outputs(out, "stability_map.csv", |n| {
        matches!(
            n,
            "stability_map.md" | "stability_map.svg" | "stability_max_w.svg"
        )
    })?;
    let (json, scenario) = super::load_json(path, sets)?;
    let Stabilizer::Smc { k, epsilon, .. } = scenario.stabilizer else {
        return Err(Error::invalid(
            "stabilizer",
            "the stability map varies the SMC μ; the scenario uses baumgarte",
        ));
    };
    let grid = SimTime::from_secs_f64(DT[DT.len() - 1]).unwrap_or(SimTime(1));
    let wanted = duration.map_or(scenario.duration, |d| {
        SimTime::from_secs_f64(d).unwrap_or(SimTime::ZERO)
    });
    let horizon = SimTime(wanted.as_nanos() / grid.as_nanos() * grid.as_nanos());
    if horizon == SimTime::ZERO {
        return Err(Error::invalid(
            "--duration",
            format!("must be at least the largest dt of the map ({grid})"),
        ));
    }
    let (base, base_scenario) = super::with_horizon(&json, horizon.as_secs_f64(), "--duration")?;
    let mut variants = Vec::new();
    for &mu in &MU {
        for &dt in &DT {
            let mut v = base.clone();
            v["stabilizer"] = json!({"kind": "smc", "mu": mu, "k": k, "epsilon": epsilon});
            v["dt"] = Value::from(dt);
            variants.push((mu, dt, parse_str(&v.to_string(), "stability map cell")));
        }
    }
    let total = variants
        .iter()
        .filter_map(|(_, _, s)| s.as_ref().ok().map(|s| s.steps.saturating_add(1)))
        .fold(0u64, u64::saturating_add);
    crate::run::budget::check_study_steps(total, "--duration")?;
    let mut counter = Counter::new(total);
    let mut cells = Vec::with_capacity(variants.len());
    for (mu, dt, parsed) in variants {
        let cell = match parsed {
            Err(e) => Cell {
                mu,
                dt,
                outcome: None,
                max_violation: f64::NAN,
                error: e.to_string(),
            },
            Ok(s) => {
                let mut world = CoSim::new(&s);
                let result = world.run_to_end(&mut Count(&mut counter));
                let max = world.max_violation();
                let (outcome, error) = match result {
                    Ok(()) if max <= epsilon => (0, String::new()),
                    Ok(()) => (1, String::new()),
                    Err(e) => (2, e.to_string()),
                };
                Cell {
                    mu,
                    dt,
                    outcome: Some(outcome),
                    max_violation: max,
                    error,
                }
            }
        };
        cells.push(cell);
    }
    counter.finish();
    let map = StabilityMap {
        name: base_scenario.name.clone(),
        horizon,
        integrator: base_scenario.integrator.name(),
        k,
        epsilon,
        bound: base_scenario.max_violation,
        cells,
    };
    write_map(out, &map)?;
    Ok(map)
}

/// The outcomes 0, 1, 2 as the map's legend names and colours them (blue, orange,
/// dark red: apart in hue and in lightness, so also in grey); refused cells are grey.
const OUTCOMES: [CellClass<'static>; 3] = [
    CellClass {
        name: "0: ran, max |w| ≤ ε",
        rgb: [0x2c, 0x7f, 0xb8],
    },
    CellClass {
        name: "1: ran, max |w| > ε",
        rgb: [0xfd, 0xb8, 0x63],
    },
    CellClass {
        name: "2: diverged",
        rgb: [0x7f, 0x00, 0x00],
    },
];

fn write_map(out: &Path, map: &StabilityMap) -> Result<()> {
    create_out_dir(out)?;
    let mut csv = String::from("mu,dt,outcome,max_violation,error\n");
    for c in &map.cells {
        let _ = writeln!(
            csv,
            "{},{},{},{},\"{}\"",
            c.mu,
            c.dt,
            c.outcome.map_or(String::new(), |o| o.to_string()),
            if c.max_violation.is_finite() {
                c.max_violation.to_string()
            } else {
                String::new()
            },
            c.error.replace('"', "\"\"")
        );
    }
    write_atomic(&out.join("stability_map.csv"), csv.as_bytes())?;
    write_atomic(&out.join("stability_map.md"), markdown(map).as_bytes())?;

    let x: Vec<f64> = DT.iter().map(|d| d.log10()).collect();
    let y: Vec<f64> = MU.iter().map(|m| m.log10()).collect();
    let grid = |f: &dyn Fn(&Cell) -> f64| -> Vec<Vec<f64>> {
        (0..MU.len())
            .map(|i| (0..DT.len()).map(|j| f(map.cell(i, j))).collect())
            .collect()
    };
    let outcome = grid(&|c| c.outcome.map_or(f64::NAN, f64::from));
    let title = format!(
        "Stability over μ × dt ({}, K = {}, ε = {}, {} s)",
        map.integrator,
        map.k,
        map.epsilon,
        map.horizon.as_secs_f64()
    );
    write_heatmap(
        &out.join("stability_map.svg"),
        &Heatmap {
            title: &title,
            x_label: "log10 dt [s]",
            y_label: "log10 μ [s]",
            value_label: "outcome of the run",
            x: &x,
            y: &y,
            values: &outcome,
            path_overlay: &[],
            line_overlay: &[],
            categories: [None, None],
            classes: Some(&OUTCOMES),
        },
    )?;
    let max_w = grid(&|c| match c.outcome {
        Some(0 | 1) => c.max_violation.max(1e-300).log10(),
        _ => f64::NAN,
    });
    let title = format!(
        "log10 max |w| over μ × dt ({}, grey = diverged)",
        map.integrator
    );
    write_heatmap(
        &out.join("stability_max_w.svg"),
        &Heatmap {
            title: &title,
            x_label: "log10 dt [s]",
            y_label: "log10 μ [s]",
            value_label: "log10 max |w| [m]",
            x: &x,
            y: &y,
            values: &max_w,
            path_overlay: &[],
            line_overlay: &[],
            categories: [None, None],
            classes: None,
        },
    )
}

fn markdown(map: &StabilityMap) -> String {
    let mut s = format!(
        "# Stability map: {}\n\n{} integrator, K = {} m/s, ε = {} m, horizon {} s, divergence \
         bound {} m. Cell: `0` ran with max |w| ≤ ε, `1` ran with max |w| > ε (value in m), \
         `2` diverged (time of divergence), `–` refused by the scenario format.\n\n",
        map.name,
        map.integrator,
        map.k,
        map.epsilon,
        map.horizon.as_secs_f64(),
        map.bound
    );
    s.push_str("| μ [s] \\ dt [s] |");
    for dt in DT {
        let _ = write!(s, " {dt} |");
    }
    s.push_str("\n|---|");
    s.push_str(&"---|".repeat(DT.len()));
    s.push('\n');
    for (i, mu) in MU.iter().enumerate() {
        let _ = write!(s, "| {mu} |");
        for j in 0..DT.len() {
            let c = map.cell(i, j);
            let text = match c.outcome {
                Some(0) => format!("0 ({:.1e})", c.max_violation),
                Some(1) => format!("1 ({:.1e})", c.max_violation),
                Some(_) => match c.error.split(" s ").next() {
                    Some(head) if head.starts_with("diverged at t = ") => {
                        format!("2 (t {} s)", trim_time(&head["diverged at t = ".len()..]))
                    }
                    _ => "2".into(),
                },
                None => "–".into(),
            };
            let _ = write!(s, " {text} |");
        }
        s.push('\n');
    }
    s
}

/// `3.040000000` → `3.04`.
fn trim_time(t: &str) -> &str {
    if t.contains('.') {
        t.trim_end_matches('0').trim_end_matches('.')
    } else {
        t
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_map_names_its_three_outcomes_in_a_legend() {
        let cells = MU
            .iter()
            .enumerate()
            .flat_map(|(i, &mu)| {
                DT.iter().enumerate().map(move |(j, &dt)| Cell {
                    mu,
                    dt,
                    outcome: match (i + j) % 4 {
                        3 => None,
                        o => Some(o as u8),
                    },
                    max_violation: 1e-3,
                    error: String::new(),
                })
            })
            .collect();
        let map = StabilityMap {
            name: "tiny".into(),
            horizon: SimTime::from_secs_f64(0.01).unwrap(),
            integrator: "euler",
            k: 10.0,
            epsilon: 0.1,
            bound: 1.0,
            cells,
        };
        let dir = std::env::temp_dir().join(format!("dsmcosim-stability-{}", std::process::id()));
        write_map(&dir, &map).unwrap();
        let svg = std::fs::read_to_string(dir.join("stability_map.svg")).unwrap();
        std::fs::remove_dir_all(&dir).unwrap();
        // The legend's rows in order (an entry may wrap over two).
        let rows = svg
            .lines()
            .map(str::trim)
            .filter(|l| !l.is_empty() && !l.starts_with('<'))
            .collect::<Vec<_>>()
            .join(" ");
        for class in &OUTCOMES {
            // plotters escapes `<`, `>` and `&` in text.
            let name = class.name.replace('>', "&gt;").replace('<', "&lt;");
            assert!(rows.contains(&name), "missing {name:?}");
            let [r, g, b] = class.rgb;
            assert!(svg.contains(&format!("fill=\"#{r:02X}{g:02X}{b:02X}\"")));
        }
        for text in [
            "no value",
            "outcome of the run",
            "log10 dt [s]",
            "log10 μ [s]",
        ] {
            assert!(svg.lines().any(|l| l.trim() == text), "missing {text:?}");
        }
    }
}
