//! `dsmcosim._native`: the few calls the Python package (`python/dsmcosim/`) makes into
//! the crate. Each takes plain values (text, paths, override strings) and gives plain
//! values back (JSON text, a digest), so the Python side builds its dicts and
//! DataFrames itself; every call releases the GIL while the crate works. An error of the
//! crate becomes `dsmcosim.DsmcosimError` with the field, the message and the exit code
//! the command line would print and return.

use std::path::{Path, PathBuf};
use std::sync::{Arc, Mutex};

use dsmcosim::control::Plant;
use dsmcosim::cosim::CoSim;
use dsmcosim::kernel::SimTime;
use dsmcosim::progress::{reporting_to, Listener};
use dsmcosim::run::plan::RunPlan;
use dsmcosim::run::RunOptions;
use dsmcosim::scenario::{overrides, Scenario};
use dsmcosim::trace::Recorder;
use pyo3::exceptions::PyException;
use pyo3::prelude::*;

pyo3::create_exception!(
    dsmcosim,
    DsmcosimError,
    PyException,
    "An error of dsmcosim: `field` names what is wrong (a scenario field such as \
     `channels[0].tau`, a file, or `--set ...`), `message` says what, and `exit_code` is \
     what the command line would exit with (2 bad input, 3 a diverged or failed run, \
     1 a file that could not be read or written)."
);

/// The crate's error as a Python exception with `field`, `message` and `exit_code`.
fn py_error(py: Python<'_>, e: dsmcosim::Error) -> PyErr {
    let (field, message) = match &e {
        dsmcosim::Error::Invalid { path, message } => (path.clone(), message.clone()),
        dsmcosim::Error::Parse {
            file, line, column, ..
        } => (format!("{file}:{line}:{column}"), e.to_string()),
        dsmcosim::Error::Io { path, .. } => (path.display().to_string(), e.to_string()),
        _ => (String::new(), e.to_string()),
    };
    let err = DsmcosimError::new_err(e.to_string());
    let value = err.value(py);
    // Setting attributes on a fresh exception instance cannot fail short of memory.
    let _ = value.setattr("field", field);
    let _ = value.setattr("message", message);
    let _ = value.setattr("exit_code", e.exit_code());
    err
}

/// Where a scenario comes from, as the package passes it (a dict with all three keys):
/// a file (`path`), or JSON `text` whose relative FMU paths are read from `base_dir`.
#[derive(FromPyObject)]
#[pyo3(from_item_all)]
struct Source {
    path: Option<PathBuf>,
    text: Option<String>,
    base_dir: Option<PathBuf>,
}

/// The scenario of `source` with the `--set` overrides `sets` applied, and its text.
fn load(source: &Source, sets: &[String]) -> dsmcosim::Result<(Scenario, String)> {
    match (&source.path, &source.text) {
        (Some(path), _) => overrides::load_with(path, sets),
        (None, Some(text)) => {
            // parse_at reads relative paths from the directory of the file it is given.
            let beside = source.base_dir.as_ref().map(|d| d.join("scenario.json"));
            overrides::text_with(text, "<scenario>", beside.as_deref(), sets)
        }
        (None, None) => Err(dsmcosim::Error::invalid(
            "scenario",
            "give a scenario file's path or a scenario as a dict",
        )),
    }
}

/// A Python callable `progress(position, total, unit)` as the crate's progress
/// listener, with the first exception it raised kept to be raised once the work is done
/// (the crate's loop cannot stop on it; later calls are skipped).
struct Reporter {
    listener: Option<Listener>,
    failed: Arc<Mutex<Option<PyErr>>>,
}

impl Reporter {
    fn new(progress: Option<Py<PyAny>>) -> Reporter {
        let failed: Arc<Mutex<Option<PyErr>>> = Arc::default();
        let listener = progress.map(|callable| {
            let failed = failed.clone();
            let listener: Listener = Arc::new(move |pos: u64, total: u64, unit: &str| {
                let mut first = failed.lock().unwrap_or_else(|p| p.into_inner());
                if first.is_some() {
                    return;
                }
                Python::attach(|py| {
                    if let Err(e) = callable.call1(py, (pos, total, unit)) {
                        *first = Some(e);
                    }
                });
            });
            listener
        });
        Reporter { listener, failed }
    }

    /// `result`, or the callable's exception if it raised one.
    fn finish<T>(self, py: Python<'_>, result: dsmcosim::Result<T>) -> PyResult<T> {
        let value = result.map_err(|e| py_error(py, e))?;
        let raised = self.failed.lock().unwrap_or_else(|p| p.into_inner()).take();
        match raised {
            Some(e) => Err(e),
            None => Ok(value),
        }
    }
}

/// Runs a scenario into `out` (as `dsmcosim run`, writing the same files, the scenario
/// as run included) and returns the run's digest. A run that diverged raises, its
/// outputs up to the divergence written. `progress(position, total, unit)` is called
/// as the run goes (steps, or windows under a controller).
#[pyfunction]
#[pyo3(signature = (source, out, sets, force, progress=None))]
fn run(
    py: Python<'_>,
    source: Source,
    out: PathBuf,
    sets: Vec<String>,
    force: bool,
    progress: Option<Py<PyAny>>,
) -> PyResult<String> {
    let reporter = Reporter::new(progress);
    let listener = reporter.listener.clone();
    let result = py.detach(|| {
        reporting_to(listener, || -> dsmcosim::Result<String> {
            let (scenario, text) = load(&source, &sets)?;
            let options = RunOptions {
                force,
                ..RunOptions::default()
            };
            dsmcosim::run::run_keeping_scenario(&scenario, &text, &out, options)
                .map(|outcome| outcome.digest)
        })
    });
    reporter.finish(py, result)
}

/// The plan of a scenario (what `dsmcosim validate --json` writes), as JSON text,
/// after every check a run makes before it starts.
#[pyfunction]
fn validate(py: Python<'_>, source: Source, sets: Vec<String>) -> PyResult<String> {
    let result = py.detach(|| -> dsmcosim::Result<String> {
        let (scenario, _) = load(&source, &sets)?;
        dsmcosim::run::preflight(&scenario, &RunOptions::default())?;
        let plan: RunPlan = dsmcosim::run::plan::plan(&scenario)?;
        serde_json::to_string(&plan).map_err(|e| dsmcosim::Error::invalid("plan", e.to_string()))
    });
    result.map_err(|e| py_error(py, e))
}

/// Runs the sweep file at `path` into `out` (as `dsmcosim sweep`); its table is
/// `out/sweep.csv`. `progress(position, total, "points")` is called as points finish.
#[pyfunction]
#[pyo3(signature = (path, out, sets, keep, resume, progress=None))]
fn sweep(
    py: Python<'_>,
    path: PathBuf,
    out: PathBuf,
    sets: Vec<String>,
    keep: &str,
    resume: bool,
    progress: Option<Py<PyAny>>,
) -> PyResult<()> {
    let keep = match keep {
        "summary" => dsmcosim::sweep::Keep::Summary,
        "trace" => dsmcosim::sweep::Keep::Trace,
        "all" => dsmcosim::sweep::Keep::All,
        other => {
            return Err(py_error(
                py,
                dsmcosim::Error::invalid(
                    "keep",
                    format!("must be \"summary\", \"trace\" or \"all\" (got {other:?})"),
                ),
            ))
        }
    };
    let options = dsmcosim::sweep::Options {
        keep,
        resume,
        shard: None,
        sets,
    };
    let reporter = Reporter::new(progress);
    let listener = reporter.listener.clone();
    let result = py.detach(|| {
        reporting_to(listener, || {
            dsmcosim::sweep::run(&path, &out, &options).map(|_| ())
        })
    });
    reporter.finish(py, result)
}

/// A co-simulation steered from Python window by window: the same world the command
/// line runs, with a recorder that digests every step (no files), so a steered run has
/// a digest comparable with the command line's. It advances, sets the periods and reads
/// the last window through `control::Plant`, the interface the crate's controllers use
/// (and forks it by `Clone`, as they do).
#[pyclass(name = "CoSim", module = "dsmcosim")]
struct PyCoSim {
    world: CoSim,
    recorder: Recorder,
    /// Every `set_periods` call: when, and the periods asked [s].
    decisions: Vec<(SimTime, Vec<f64>)>,
}

/// Simulated time [s] as the kernel's nanoseconds, or an error naming `what`.
fn sim_time(what: &str, seconds: f64) -> dsmcosim::Result<SimTime> {
    SimTime::from_secs_f64(seconds).ok_or_else(|| {
        dsmcosim::Error::invalid(
            what,
            format!(
                "must be a time ≥ 0 s (got {})",
                dsmcosim::error::num(seconds)
            ),
        )
    })
}

impl PyCoSim {
    fn build(scenario: &Scenario) -> dsmcosim::Result<PyCoSim> {
        if scenario.controller.is_some() {
            return Err(dsmcosim::Error::invalid(
                "controller",
                "a CoSim is steered from Python: give a scenario without a controller \
                 (its channels' tau are the periods it starts at)",
            ));
        }
        if !scenario.schedule.is_empty() {
            return Err(dsmcosim::Error::invalid(
                "schedule",
                "a CoSim is steered from Python: give a scenario without a schedule \
                 (set_periods makes those decisions; CoSim.schedule() writes them down)",
            ));
        }
        dsmcosim::run::preflight(scenario, &RunOptions::default())?;
        let recorder = Recorder::for_scenario(None, scenario)
            .map_err(|e| dsmcosim::Error::io(Path::new("<recorder>"), e))?;
        Ok(PyCoSim {
            world: CoSim::new(scenario),
            recorder,
            decisions: Vec::new(),
        })
    }

    /// An independent copy: the world cloned, the recorder's digest chains copied.
    fn copy(&self) -> dsmcosim::Result<PyCoSim> {
        let bytes = postcard::to_stdvec(&self.recorder)
            .map_err(|e| dsmcosim::Error::invalid("fork", e.to_string()))?;
        let recorder = postcard::from_bytes(&bytes)
            .map_err(|e| dsmcosim::Error::invalid("fork", e.to_string()))?;
        Ok(PyCoSim {
            world: self.world.clone(),
            recorder,
            decisions: self.decisions.clone(),
        })
    }
}

#[pymethods]
impl PyCoSim {
    /// Builds a co-simulation from a scenario `source` with `--set` overrides; the
    /// package's `dsmcosim.CoSim(...)` calls it.
    #[new]
    fn new(py: Python<'_>, source: Source, sets: Vec<String>) -> PyResult<PyCoSim> {
        let built = py.detach(|| {
            let (scenario, _) = load(&source, &sets)?;
            PyCoSim::build(&scenario)
        });
        built.map_err(|e| py_error(py, e))
    }

    /// Resumes a co-simulation from a checkpoint file written by `checkpoint`.
    #[staticmethod]
    fn resume(py: Python<'_>, path: PathBuf) -> PyResult<PyCoSim> {
        let cp = py.detach(|| dsmcosim::checkpoint::read(&path));
        let cp = cp.map_err(|e| py_error(py, e))?;
        if cp.controller.is_some() {
            return Err(py_error(
                py,
                dsmcosim::Error::invalid(
                    path.display().to_string(),
                    "is a controlled run's checkpoint (resume it with `dsmcosim resume`)",
                ),
            ));
        }
        Ok(PyCoSim {
            world: cp.world,
            recorder: cp.recorder,
            decisions: Vec::new(),
        })
    }

    /// Simulated time reached [s].
    #[getter]
    fn now(&self) -> f64 {
        self.world.now().as_secs_f64()
    }

    /// The scenario's end [s].
    #[getter]
    fn duration(&self) -> f64 {
        self.world.scenario().duration.as_secs_f64()
    }

    /// The channels' names, in the scenario's order.
    #[getter]
    fn channels(&self) -> Vec<String> {
        self.world
            .channels()
            .iter()
            .map(|c| c.spec.name.clone())
            .collect()
    }

    /// The periods each channel runs at [s] (achieved; on TDMA what the list in force
    /// serves).
    #[getter]
    fn periods(&self) -> Vec<f64> {
        self.world
            .channels()
            .iter()
            .map(|c| c.tau.as_secs_f64())
            .collect()
    }

    /// The periods last asked for [s].
    #[getter]
    fn requested(&self) -> Vec<f64> {
        self.world.channels().iter().map(|c| c.requested).collect()
    }

    /// The digest of everything recorded so far (hex): at the scenario's end, the same
    /// as the command line's run of the same scenario with the same decisions.
    #[getter]
    fn digest(&self) -> String {
        self.recorder.digest()
    }

    /// Whether the scenario's end is reached.
    #[getter]
    fn finished(&self) -> bool {
        self.world.finished()
    }

    /// Advances to `t` [s] (at most the scenario's end): every event before `t`, and
    /// the measurement window ending at `t`; at the end, everything left (the last
    /// step). Raises on divergence.
    fn advance(&mut self, py: Python<'_>, t: f64) -> PyResult<()> {
        let (world, recorder) = (&mut self.world, &mut self.recorder);
        let done = py.detach(|| -> dsmcosim::Result<()> {
            let target = sim_time("t", t)?;
            if target < world.now() || target > world.scenario().duration {
                return Err(dsmcosim::Error::invalid(
                    "t",
                    format!(
                        "must lie in [now, duration] = [{}, {}] s (got {t})",
                        world.now().as_secs_f64(),
                        world.scenario().duration.as_secs_f64()
                    ),
                ));
            }
            if target == world.scenario().duration {
                // The end: the step at `duration` too, as a run to its end takes it.
                world.run_to_end(recorder)
            } else {
                Plant::advance_to(world, target, recorder)
            }
        });
        done.map_err(|e| py_error(py, e))
    }

    /// Sets every channel's period [s] from now on, as the controller does at a window
    /// boundary; returns the periods achieved (an ideal channel runs the request to the
    /// nanosecond, at least one step; a TDMA network what its new slot list serves).
    fn set_periods(&mut self, py: Python<'_>, periods: Vec<f64>) -> PyResult<Vec<f64>> {
        let n = self.world.channels().len();
        let dt = self.world.scenario().dt;
        let checked = (|| -> dsmcosim::Result<Vec<SimTime>> {
            if periods.len() != n {
                return Err(dsmcosim::Error::invalid(
                    "periods",
                    format!("needs one per channel, {n} (got {})", periods.len()),
                ));
            }
            periods
                .iter()
                .enumerate()
                .map(|(i, &p)| {
                    sim_time(&format!("periods[{i}]"), p)?;
                    Ok(dsmcosim::network::channel::achieved_period(p, dt))
                })
                .collect()
        })();
        let achieved = checked.map_err(|e| py_error(py, e))?;
        let now = self.world.now();
        let set = Plant::set_taus(&mut self.world, now, &periods, &achieved).map_err(|e| {
            py_error(
                py,
                dsmcosim::Error::invalid(
                    "periods",
                    format!("the TDMA cycle cannot serve them: {e}"),
                ),
            )
        })?;
        self.decisions.push((now, periods));
        Ok(set.iter().map(|t| t.as_secs_f64()).collect())
    }

    /// The decisions made so far by `set_periods` as a scenario's `schedule` section:
    /// `[(at [s], [period per channel [s]]), ...]`. The scenario with it gives this
    /// run's digest through the command line. Raises for a decision a schedule cannot
    /// hold: one off a measurement window boundary, or a second at the same time.
    fn schedule(&self, py: Python<'_>) -> PyResult<Vec<(f64, Vec<f64>)>> {
        let period = self.world.scenario().measurement_period;
        let mut out: Vec<(f64, Vec<f64>)> = Vec::new();
        for (i, (at, tau)) in self.decisions.iter().enumerate() {
            let why = if at.0 % period.0 != 0 {
                Some(format!(
                    "was made at {} s, off the measurement window boundaries (multiples of \
                     {} s) where a schedule changes periods",
                    at.as_secs_f64(),
                    period.as_secs_f64()
                ))
            } else if i > 0 && self.decisions[i - 1].0 == *at {
                Some(format!(
                    "is a second decision at {} s; a schedule holds one per boundary",
                    at.as_secs_f64()
                ))
            } else {
                None
            };
            if let Some(why) = why {
                return Err(py_error(
                    py,
                    dsmcosim::Error::invalid(format!("decisions[{i}]"), why),
                ));
            }
            out.push((at.as_secs_f64(), tau.clone()));
        }
        Ok(out)
    }

    /// The last closed measurement window: `(t_end [s], cost [m])`, or None before the
    /// first (the scenario's `measurement.period` sets the windows).
    fn window_cost(&self) -> Option<(f64, f64)> {
        Plant::last_window(&self.world).map(|(end, cost)| (end.as_secs_f64(), cost))
    }

    /// An independent copy to try something on: advancing or steering it leaves this
    /// one as it was.
    fn fork(&self, py: Python<'_>) -> PyResult<PyCoSim> {
        py.detach(|| self.copy()).map_err(|e| py_error(py, e))
    }

    /// Writes a checkpoint of the co-simulation as it is now into `out/checkpoints/`
    /// and returns its path (resume it with `CoSim.resume`).
    fn checkpoint(&self, py: Python<'_>, out: PathBuf) -> PyResult<PathBuf> {
        let written = py.detach(|| {
            dsmcosim::checkpoint::write(&out, self.world.now(), &self.world, &self.recorder, None)
        });
        written.map_err(|e| py_error(py, e))
    }
}

/// The native module.
#[pymodule]
fn _native(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add("DsmcosimError", m.py().get_type::<DsmcosimError>())?;
    m.add("__version__", env!("CARGO_PKG_VERSION"))?;
    m.add_function(wrap_pyfunction!(run, m)?)?;
    m.add_function(wrap_pyfunction!(validate, m)?)?;
    m.add_function(wrap_pyfunction!(sweep, m)?)?;
    m.add_class::<PyCoSim>()?;
    Ok(())
}
