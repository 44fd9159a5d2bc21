//! The coupling study (`dsmcosim coupling`): every coupling scheme × delay τ × delay
//! distribution on one partitioned scenario, each cell measured against the monolithic
//! run and against the same scheme at τ = dt.
//!
//! ```text
//!   scenario.json ──▶ base (partitioned, ideal channels, no controller, --duration)
//!      ├─▶ monolithic reference (partition, channels and network dropped)
//!      ├─▶ per scheme × distribution: τ = dt, latency 0 (the convergence reference)
//!      └─▶ per scheme × distribution × τ: latency = τ (each sample arrives τ late)
//!                    │ positions of the first and last body over [0, 3 s],
//!                    │ kinetic energy, momentum and angular momentum over the
//!                    │ undriven tail, max |w|, wall time
//!                    ▼
//!          coupling.csv, coupling.md, error_vs_tau.svg, max_w_vs_tau.svg,
//!          energy_vs_tau.svg
//! ```
//!
//! Distributions (the thesis's two readings of which data travels on which channel):
//! `space` keeps the scenario's channels and their borders, every one at period τ;
//! `time` replaces them by a `state` and a `force` channel over every border, both at
//! τ. Every cell runs on ideal channels with the default latency (= τ) and without the
//! scenario's controller, so τ is the only thing that changes along a row.
//!
//! Errors are RMS over the steps of `[0, min(3 s, duration)]` of the position error of
//! the first and of the last body (the larger of the two is reported): the net's motion
//! is chaotic, and over 30 s every stable scheme (latency 0 included) ends metres away
//! from the monolithic run, so a long-horizon error measures the chaos, not the
//! coupling. Energy drift is the relative change of the kinetic energy
//! (translation and rotation, `trace::Invariants`; under gravity the change of kinetic
//! plus potential energy relative to the kinetic energy) over the undriven tail (from the
//! last force's switch-off to the end, or the whole run when the scene has no force,
//! when that tail is at least 1 s long); momentum drift the change of the total linear
//! momentum over the same tail [kg·m/s], angular-momentum drift the relative change of
//! the angular momentum about the centre of mass (both kept to round-off by the
//! monolithic run, which the markdown shows beside them; not reported where the world
//! acts on the net, through gravity or a joint to a world point). The fitted order in τ is the
//! least-squares slope of log(error vs τ = dt) against log τ over a row's bounded
//! cells. Cost per step is the wall time of the cell
//! divided by that of `reset` at the same τ and distribution (each the fastest of
//! [`TIMING_RUNS`] runs, one after the other on one core): the only non-deterministic
//! column, and a rough one; `cargo bench --bench coupling` measures it properly.

use std::path::Path;
use std::time::Instant;

use nalgebra::Vector3;
use serde_json::{json, Value};

mod write;

use self::write::{fmt, write_csv, write_markdown, write_plots};
use crate::cosim::{CoSim, Observer, StepValues};
use crate::error::{Error, Result};
use crate::output::create_out_dir;
use crate::scenario::{parse_str, Scenario};

/// The schemes the study compares: a label and the `partition.coupling` value (JSON).
/// `passive` is the default (40 J tank, transmission lines where a border's samples
/// can be older than 40 ms); `passive, no lines` is the same predictor and tank on
/// every border, what the default was before lines; `passive 1 J` shows what a 40-fold
/// tighter energy bound costs in accuracy; `tlm` makes every border link a line.
pub const SCHEMES: [(&str, &str); 6] = [
    ("reset", r#""reset""#),
    ("predict", r#""predict""#),
    ("passive", r#""passive""#),
    (
        "passive, no lines",
        r#"{"scheme": "passive", "lines_above": 1000}"#,
    ),
    ("passive 1 J", r#"{"scheme": "passive", "tank": 1.0}"#),
    ("tlm", r#""tlm""#),
];

/// Each cell's wall time is the fastest of this many runs (the first one also records).
pub const TIMING_RUNS: usize = 3;

/// The delays of the study [s] (the thesis scene's range).
pub const TAUS: [f64; 8] = [0.003, 0.005, 0.008, 0.010, 0.015, 0.020, 0.030, 0.050];

/// The delay distributions.
pub const DISTRIBUTIONS: [&str; 2] = ["space", "time"];

/// Length of the short horizon the errors are measured over [s].
pub const ERROR_HORIZON: f64 = 3.0;

/// One cell of the study.
#[derive(Debug, Clone)]
pub struct Cell {
    /// Coupling scheme.
    pub scheme: &'static str,
    /// Delay distribution.
    pub distribution: &'static str,
    /// Period and latency τ [s].
    pub tau: f64,
    /// The divergence error, if the run diverged.
    pub error: Option<String>,
    /// Largest |w| before the end or the divergence [m].
    pub max_w: f64,
    /// RMS position error vs the monolithic run over the short horizon [m].
    pub err_mono: f64,
    /// RMS position error vs the same scheme at τ = dt, latency 0 [m].
    pub err_dt: f64,
    /// Relative change of kinetic energy over the undriven tail (NaN without one).
    pub energy_drift: f64,
    /// Change of the total linear momentum over the undriven tail, `|P_end − P_start|`
    /// [kg·m/s] (NaN without a tail; the monolithic run keeps it to round-off).
    pub momentum_drift: f64,
    /// Relative change of the angular momentum about the centre of mass over the
    /// undriven tail, `|L_end − L_start| / |L_start|` (NaN without a tail).
    pub angular_drift: f64,
    /// Wall time per step [s].
    pub wall_per_step: f64,
}

impl Cell {
    /// Whether the run reached its end.
    pub fn bounded(&self) -> bool {
        self.error.is_none()
    }
}

/// What one run recorded.
struct Watch {
    /// Bodies watched: first and last.
    bodies: [usize; 2],
    /// Last step time recorded into `positions` [ns].
    horizon: u64,
    positions: Vec<[Vector3<f64>; 2]>,
    /// Start of the undriven tail [ns], if the scene has one.
    tail: Option<u64>,
    /// Energy at the tail's start and at the end [J] (kinetic; under gravity kinetic
    /// plus potential).
    ke_tail_start: f64,
    ke_end: f64,
    /// Kinetic energy at the tail's start [J]: the scale of the energy drift.
    kinetic_tail_start: f64,
    /// Momentum and angular momentum about the centre of mass at the tail's start and
    /// at the end.
    momenta_tail_start: [Vector3<f64>; 2],
    momenta_end: [Vector3<f64>; 2],
    max_w: f64,
    /// Gravity, whose potential joins the energy; `None` without.
    gravity: Option<Vector3<f64>>,
    /// Whether the world acts on the net (gravity, a joint to a world point): its
    /// momenta then change by physics, and their drifts are not reported.
    external: bool,
}

impl Watch {
    fn new(s: &Scenario) -> Watch {
        let n = s.bodies.len();
        let horizon = (ERROR_HORIZON.min(s.duration.as_secs_f64()) * 1e9) as u64;
        let end = s.duration.0;
        // A scene with no force at all is undriven from its start.
        let last_force = s
            .forces
            .iter()
            .map(|f| f.until.map_or(u64::MAX, |u| u.0))
            .max()
            .unwrap_or(0);
        let tail = Some(last_force)
            .filter(|&u| u < end && end - u >= 1_000_000_000)
            .map(|u| u.div_ceil(s.dt.0) * s.dt.0);
        Watch {
            bodies: [0, n - 1],
            horizon,
            positions: Vec::new(),
            tail,
            ke_tail_start: f64::NAN,
            ke_end: f64::NAN,
            kinetic_tail_start: f64::NAN,
            momenta_tail_start: [Vector3::repeat(f64::NAN); 2],
            momenta_end: [Vector3::repeat(f64::NAN); 2],
            max_w: 0.0,
            gravity: s.gravity,
            external: s.gravity.is_some()
                || s.links.iter().any(|l| l.world)
                || s.springs.iter().any(|sp| sp.b.is_none()),
        }
    }
}

impl Observer for Watch {
    fn on_step(&mut self, s: &StepValues) -> std::io::Result<()> {
        let t = s.time.0;
        if t <= self.horizon {
            self.positions
                .push([s.p[self.bodies[0]], s.p[self.bodies[1]]]);
        }
        if Some(t) == self.tail || s.last {
            let inv = s.invariants();
            let momenta = if self.external {
                [Vector3::repeat(f64::NAN); 2]
            } else {
                [inv.momentum, inv.angular_momentum]
            };
            // Under gravity the energy kept is kinetic plus potential, `−Σ m g·p`.
            let energy = match self.gravity {
                Some(g) => {
                    let potential: f64 =
                        s.p.iter()
                            .zip(s.bodies)
                            .map(|(p, b)| -b.mass * g.dot(p))
                            .sum();
                    inv.kinetic_energy + potential
                }
                None => inv.kinetic_energy,
            };
            if s.last {
                (self.ke_end, self.momenta_end) = (energy, momenta);
            } else {
                (self.ke_tail_start, self.momenta_tail_start) = (energy, momenta);
                self.kinetic_tail_start = inv.kinetic_energy;
            }
        }
        for w in s.w {
            self.max_w = self.max_w.max(w.abs());
        }
        Ok(())
    }
}

/// A run's record and outcome.
struct Ran {
    watch: Watch,
    error: Option<String>,
    wall_per_step: f64,
}

fn run(s: &Scenario) -> Ran {
    let mut watch = Watch::new(s);
    let mut world = CoSim::new(s);
    let start = Instant::now();
    let result = world.run_to_end(&mut watch);
    let mut wall = start.elapsed().as_secs_f64();
    for _ in 1..TIMING_RUNS {
        let mut again = CoSim::new(s);
        let start = Instant::now();
        let _ = again.run_to_end(&mut ());
        wall = wall.min(start.elapsed().as_secs_f64());
    }
    Ran {
        watch,
        error: result.err().map(|e| e.to_string()),
        wall_per_step: wall / world.steps_done().max(1) as f64,
    }
}

/// RMS over the common steps of the larger of the two bodies' position errors [m].
fn rms_error(a: &Watch, b: &Watch) -> f64 {
    let n = a.positions.len().min(b.positions.len());
    if n == 0 || n < a.positions.len().max(b.positions.len()) {
        // One of the runs stopped inside the horizon: no error to report.
        return f64::NAN;
    }
    let mut sums = [0.0; 2];
    for (pa, pb) in a.positions.iter().zip(&b.positions) {
        for k in 0..2 {
            sums[k] += (pa[k] - pb[k]).norm_squared();
        }
    }
    sums.iter()
        .map(|s| (s / n as f64).sqrt())
        .fold(0.0, f64::max)
}

fn parse(v: &Value, what: &str) -> Result<Scenario> {
    parse_str(&v.to_string(), what)
}

/// The cell's scenario: `base` with `scheme`, `distribution`, period `tau` and
/// latency `latency` (`None` = τ).
fn cell_scenario(
    base: &Value,
    scheme: &str,
    distribution: &str,
    tau: f64,
    latency: Option<f64>,
) -> Value {
    let mut v = base.clone();
    v["partition"]["coupling"] = serde_json::from_str(scheme).unwrap_or_else(|_| json!(scheme));
    let channels: Vec<Value> = match distribution {
        "space" => base["channels"]
            .as_array()
            .cloned()
            .unwrap_or_default()
            .into_iter()
            .map(|mut c| {
                let o = c.as_object_mut().expect("ok: a channel is an object");
                for k in ["latency", "phase", "kinds", "tau"] {
                    o.remove(k);
                }
                c
            })
            .collect(),
        _ => vec![
            json!({"name": "state", "kinds": ["state"]}),
            json!({"name": "force", "kinds": ["force"]}),
        ],
    };
    v["channels"] = Value::Array(
        channels
            .into_iter()
            .map(|mut c| {
                c["tau"] = json!(tau);
                if let Some(l) = latency {
                    c["latency"] = json!(l);
                }
                c
            })
            .collect(),
    );
    v
}

/// Runs the study of the scenario at `path` with the `--set` overrides `sets` applied
/// (over `duration` seconds if given) and writes its files into `out`. `progress` is
/// told each finished run.
pub fn study(
    path: &Path,
    sets: &[String],
    out: &Path,
    duration: Option<f64>,
    progress: &mut dyn FnMut(usize, usize),
) -> Result<Vec<Cell>> {
    crate::output::refuse_foreign_outputs(out, "coupling.csv", |n| {
        matches!(
            n,
            "coupling.md" | "error_vs_tau.svg" | "max_w_vs_tau.svg" | "energy_vs_tau.svg"
        )
    })?;
    let (scenario, text) = crate::scenario::load_with(path, sets)?;
    if scenario.partition.is_none() || scenario.links.is_empty() {
        return Err(Error::invalid(
            "partition",
            "the coupling study needs a partitioned scenario",
        ));
    }
    let mut base: Value = serde_json::from_str(&text)
        .map_err(|e| Error::invalid("scenario", format!("not JSON: {e}")))?;
    crate::scenario::anchor_fmu_paths(&mut base, path);
    if let Some(d) = duration {
        if !(d.is_finite() && d > 0.0 && d <= scenario.duration.as_secs_f64()) {
            return Err(Error::invalid(
                "--duration",
                format!(
                    "must be a positive number of seconds up to the scenario's {} s (got {d})",
                    scenario.duration.as_secs_f64()
                ),
            ));
        }
        base["duration"] = json!(d);
    }
    let o = base.as_object_mut().expect("ok: a scenario is an object");
    o.remove("controller");
    o.insert("network".into(), json!({"kind": "ideal"}));
    let dt = scenario.dt.as_secs_f64();
    let mut mono = base.clone();
    let m = mono.as_object_mut().expect("ok: an object");
    for k in ["partition", "channels", "network"] {
        m.remove(k);
    }
    // Validate every cell before anything runs.
    let mono = parse(&mono, "monolithic reference")?;
    // Every run has the monolithic reference's steps: what `run` refuses for one run,
    // the study refuses for all of its runs (each timed TIMING_RUNS times).
    let runs = 1 + SCHEMES.len() * DISTRIBUTIONS.len() * (1 + TAUS.len()) * TIMING_RUNS;
    crate::run::budget::check_study_steps(mono.steps.saturating_mul(runs as u64), "--duration")?;
    let mut plans = Vec::new();
    for &(scheme, value) in &SCHEMES {
        for &distribution in &DISTRIBUTIONS {
            let reference = parse(
                &cell_scenario(&base, value, distribution, dt, Some(0.0)),
                "τ = dt reference",
            )?;
            let cells = TAUS
                .iter()
                .map(|&tau| {
                    let what = format!("{scheme}, {distribution}, τ = {tau} s");
                    parse(&cell_scenario(&base, value, distribution, tau, None), &what)
                })
                .collect::<Result<Vec<_>>>()?;
            plans.push((scheme, distribution, reference, cells));
        }
    }
    let total = 1 + plans.iter().map(|p| 1 + p.3.len()).sum::<usize>();
    let mut done = 0;
    let mut tick = |done: &mut usize| {
        *done += 1;
        progress(*done, total);
    };
    let mono = run(&mono);
    tick(&mut done);
    let mut cells = Vec::new();
    for (scheme, distribution, reference, scenarios) in &plans {
        let reference = run(reference);
        tick(&mut done);
        for (s, &tau) in scenarios.iter().zip(&TAUS) {
            let r = run(s);
            tick(&mut done);
            let drift = (r.watch.ke_end - r.watch.ke_tail_start) / r.watch.kinetic_tail_start;
            let [p0, l0] = r.watch.momenta_tail_start;
            let [p1, l1] = r.watch.momenta_end;
            let ok = r.error.is_none();
            cells.push(Cell {
                scheme,
                distribution,
                tau,
                max_w: r.watch.max_w,
                err_mono: rms_error(&r.watch, &mono.watch),
                err_dt: rms_error(&r.watch, &reference.watch),
                energy_drift: if ok { drift } else { f64::NAN },
                momentum_drift: if ok { (p1 - p0).norm() } else { f64::NAN },
                angular_drift: if ok {
                    (l1 - l0).norm() / l0.norm()
                } else {
                    f64::NAN
                },
                error: r.error,
                wall_per_step: r.wall_per_step,
            });
        }
    }
    create_out_dir(out)?;
    write_csv(out, &cells)?;
    let mono_drift = (mono.watch.ke_end - mono.watch.ke_tail_start) / mono.watch.kinetic_tail_start;
    let [p0, l0] = mono.watch.momenta_tail_start;
    let [p1, l1] = mono.watch.momenta_end;
    let reference = format!(
        "The monolithic run: max |w| {:.3} m; over the undriven tail energy drift {}, \
         momentum drift {} kg·m/s, angular-momentum drift {}.",
        mono.watch.max_w,
        fmt(mono_drift),
        fmt((p1 - p0).norm()),
        fmt((l1 - l0).norm() / l0.norm())
    );
    write_markdown(out, &scenario.name, &reference, &cells)?;
    write_plots(out, &cells)?;
    Ok(cells)
}
