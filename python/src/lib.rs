//! `dsmcosim._native`: the few calls the Python package (`python/dsmcosim/`) makes into
//! the crate. Each takes plain values (text, paths, override strings) and gives plain
//! values back (JSON text, a digest), so the Python side builds its dicts and
//! DataFrames itself. Every call that simulates runs the crate on a worker thread while
//! the calling thread, the GIL released, looks for signals every 50 ms: Ctrl-C (or a
//! notebook's "Interrupt kernel") stops the work at its next slice of steps, as the
//! command line's Ctrl-C does, and raises `KeyboardInterrupt`. An error of the crate
//! becomes the exception of `dsmcosim._errors` its kind calls for, with the field, the
//! message and the exit code the command line would print and return.

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{Arc, Mutex};
use std::time::Duration;

use dsmcosim::control::experiment::WindowReport;
use dsmcosim::control::Plant;
use dsmcosim::cosim::{CoSim, EpochRecord, Observer, StepValues};
use dsmcosim::error::Place;
use dsmcosim::kernel::SimTime;
use dsmcosim::network::message::{Message, Payload};
use dsmcosim::network::tdma::CycleReport;
use dsmcosim::progress::{reporting_to, Listener};
use dsmcosim::run::plan::RunPlan;
use dsmcosim::run::RunOptions;
use dsmcosim::scenario::{overrides, Scenario};
use dsmcosim::trace::Recorder;
use pyo3::exceptions::PyKeyboardInterrupt;
use pyo3::prelude::*;
use pyo3::types::{PyBytes, PyDict};

/// The exception class `name` of `dsmcosim._errors`.
fn error_class<'py>(py: Python<'py>, name: &str) -> PyResult<Bound<'py, PyAny>> {
    py.import("dsmcosim._errors")?.getattr(name)
}

/// The crate's error as the Python exception of its kind (`dsmcosim._errors`), with
/// `field`, `message` and `exit_code`; a divergence also with `time`, `node`, `link`
/// and `what`.
fn py_error(py: Python<'_>, e: dsmcosim::Error) -> PyErr {
    match build_error(py, &e) {
        Ok(err) => err,
        Err(failed) => failed,
    }
}

fn build_error(py: Python<'_>, e: &dsmcosim::Error) -> PyResult<PyErr> {
    use dsmcosim::Error as E;
    let text = e.to_string();
    let (class, field, message) = match e {
        E::Invalid { path, message } => ("InvalidScenarioError", path.clone(), message.clone()),
        E::Parse {
            file, line, column, ..
        } => (
            "InvalidScenarioError",
            format!("{file}:{line}:{column}"),
            text.clone(),
        ),
        E::Io { path, source } => {
            let class = match source.kind() {
                std::io::ErrorKind::NotFound => "NotFoundError",
                std::io::ErrorKind::PermissionDenied => "PermissionDeniedError",
                _ => "FileError",
            };
            (class, path.display().to_string(), text.clone())
        }
        E::Diverged(_) => ("DivergedError", String::new(), text.clone()),
        E::OutOfMemory { .. } => ("OutOfMemoryError", String::new(), text.clone()),
        E::Interrupted { .. } => {
            return Ok(PyKeyboardInterrupt::new_err(text));
        }
        _ => ("SimulationError", String::new(), text.clone()),
    };
    let value = error_class(py, class)?.call1((text.clone(),))?;
    value.setattr("field", field)?;
    value.setattr("message", message)?;
    value.setattr("exit_code", e.exit_code())?;
    match e {
        E::Diverged(d) => {
            value.setattr("time", d.time.as_secs_f64())?;
            value.setattr("node", d.node)?;
            let (mut link, mut row, mut body, mut fmu_output) = (None, None, None, None);
            match &d.place {
                Place::Link(k) => link = Some(format!("L{k}")),
                Place::JointRow { joint, row: r } => {
                    link = Some(format!("J{joint}"));
                    row = Some(*r);
                }
                Place::Body(id) => body = Some(format!("B{id}")),
                Place::FmuOutput { fmu, variable } => {
                    fmu_output = Some(format!("{fmu}.{variable}"))
                }
            }
            value.setattr("link", link)?;
            value.setattr("row", row)?;
            value.setattr("body", body)?;
            value.setattr("fmu_output", fmu_output)?;
            value.setattr("what", d.what.clone())?;
        }
        E::Io { source, .. } => {
            value.setattr("filename", field_of(e))?;
            value.setattr("errno", source.raw_os_error())?;
            // Python's form, `[Errno 2] No such file or directory: 'path'`: the
            // description without Rust's ` (os error 2)`.
            let described = source.to_string();
            let strerror = match described.rfind(" (os error ") {
                Some(at) => described[..at].to_string(),
                None => described,
            };
            value.setattr("strerror", strerror)?;
        }
        _ => {}
    }
    Ok(PyErr::from_value(value))
}

/// The path an I/O error names.
fn field_of(e: &dsmcosim::Error) -> Option<String> {
    match e {
        dsmcosim::Error::Io { path, .. } => Some(path.display().to_string()),
        _ => None,
    }
}

/// Runs `work` on a worker thread while this thread, the GIL released, checks for
/// Python signals every 50 ms. A signal whose handler raised (Ctrl-C's
/// `KeyboardInterrupt`) asks the crate to stop ([`dsmcosim::interrupt::request`]) and
/// comes back beside `work`'s result once the worker has stopped.
///
/// The stop is the process's, as the command line's Ctrl-C is: every dsmcosim call
/// running in the process stops at its next slice. The flag is withdrawn once `work`
/// has returned.
fn interruptible<T: Send>(
    py: Python<'_>,
    work: impl FnOnce() -> T + Send,
) -> PyResult<(T, Option<PyErr>)> {
    let (tx, rx) = std::sync::mpsc::channel::<()>();
    std::thread::scope(|scope| {
        // The crate runs on the main thread under the command line: give the worker
        // the main thread's usual 8 MiB of stack, not a spawned thread's 2 MiB.
        let worker = std::thread::Builder::new()
            .name("dsmcosim".into())
            .stack_size(8 << 20)
            .spawn_scoped(scope, move || {
                let out = work();
                let _ = tx.send(());
                out
            })
            .map_err(|e| {
                pyo3::exceptions::PyOSError::new_err(format!("cannot start a thread: {e}"))
            })?;
        let mut signal = None;
        let mut rx = rx;
        loop {
            // The receiver goes into the GIL-free wait and back (it is Send, not Sync).
            let (done, back) = py.detach(move || {
                let waited = rx.recv_timeout(Duration::from_millis(50));
                let timed_out = matches!(waited, Err(std::sync::mpsc::RecvTimeoutError::Timeout));
                (!timed_out, rx)
            });
            rx = back;
            if done {
                break;
            }
            if signal.is_none() {
                if let Err(e) = py.check_signals() {
                    dsmcosim::interrupt::request();
                    signal = Some(e);
                }
            }
        }
        let out = match worker.join() {
            Ok(out) => out,
            Err(panic) => std::panic::resume_unwind(panic),
        };
        if signal.is_some() {
            dsmcosim::interrupt::clear();
        }
        Ok((out, signal))
    })
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
/// listener. Returning `False` asks the work to stop (a run ends as an interrupted run
/// does, its outputs written); raising does too, and the exception is raised once the
/// work has stopped (later calls are skipped).
struct Reporter {
    listener: Option<Listener>,
    failed: Arc<Mutex<Option<PyErr>>>,
    stopped: Arc<AtomicBool>,
}

impl Reporter {
    fn new(progress: Option<Py<PyAny>>) -> Reporter {
        let failed: Arc<Mutex<Option<PyErr>>> = Arc::default();
        let stopped: Arc<AtomicBool> = Arc::default();
        let listener = progress.map(|callable| {
            let (failed, stopped) = (failed.clone(), stopped.clone());
            let listener: Listener = Arc::new(move |pos: u64, total: u64, unit: &str| {
                let mut first = failed.lock().unwrap_or_else(|p| p.into_inner());
                if first.is_some() || stopped.load(Ordering::SeqCst) {
                    return;
                }
                Python::attach(|py| match callable.call1(py, (pos, total, unit)) {
                    Ok(answer) => {
                        let answer = answer.bind(py);
                        let is_false = answer.is_instance_of::<pyo3::types::PyBool>()
                            && !answer.is_truthy().unwrap_or(true);
                        if is_false {
                            stopped.store(true, Ordering::SeqCst);
                            dsmcosim::interrupt::request();
                        }
                    }
                    Err(e) => {
                        *first = Some(e);
                        dsmcosim::interrupt::request();
                    }
                });
            });
            listener
        });
        Reporter {
            listener,
            failed,
            stopped,
        }
    }

    /// `result` as Python sees it: the signal's exception (Ctrl-C) first, then the
    /// callable's, then the crate's error; `Ok(None)` for work the callable stopped by
    /// returning `False`.
    fn finish<T>(
        self,
        py: Python<'_>,
        result: dsmcosim::Result<T>,
        signal: Option<PyErr>,
    ) -> PyResult<Option<T>> {
        let raised = self.failed.lock().unwrap_or_else(|p| p.into_inner()).take();
        let stopped = self.stopped.load(Ordering::SeqCst);
        if stopped || raised.is_some() {
            dsmcosim::interrupt::clear();
        }
        if let Some(e) = signal.or(raised) {
            return Err(e);
        }
        match result {
            Ok(value) => Ok(Some(value)),
            Err(dsmcosim::Error::Interrupted { .. }) if stopped => Ok(None),
            Err(e) => Err(py_error(py, e)),
        }
    }
}

/// Runs a scenario into `out` (as `dsmcosim run`, writing the same files, the scenario
/// as run included). Returns `{"warnings": [...], "stopped": bool}`: the lines the
/// command line prints as `warning:`, and whether `progress` stopped the run by
/// returning `False` (its outputs are then those of an interrupted run). A run that
/// diverged raises, its outputs up to the divergence written; Ctrl-C stops it at its
/// next slice of steps and raises `KeyboardInterrupt`, the outputs up to there written.
#[pyfunction]
#[pyo3(signature = (source, out, sets, force, progress=None))]
fn run<'py>(
    py: Python<'py>,
    source: Source,
    out: PathBuf,
    sets: Vec<String>,
    force: bool,
    progress: Option<Py<PyAny>>,
) -> PyResult<Bound<'py, PyDict>> {
    let reporter = Reporter::new(progress);
    let listener = reporter.listener.clone();
    let (result, signal) = interruptible(py, || {
        reporting_to(listener, || -> dsmcosim::Result<Vec<String>> {
            let (scenario, text) = load(&source, &sets)?;
            let options = RunOptions {
                force,
                ..RunOptions::default()
            };
            dsmcosim::run::run_keeping_scenario(scenario, &text, &out, options)
                .map(|outcome| outcome.warnings())
        })
    })?;
    let finished = reporter.finish(py, result, signal)?;
    let outcome = PyDict::new(py);
    outcome.set_item("stopped", finished.is_none())?;
    outcome.set_item("warnings", finished.unwrap_or_default())?;
    Ok(outcome)
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
/// `out/sweep.csv`. `progress(position, total, "points")` is called as points finish;
/// Ctrl-C, or `progress` returning `False`, starts no further point and stops the
/// running ones (raising `KeyboardInterrupt`, or `StoppedError` counting the points
/// finished; `resume=True` runs the rest).
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
    let options = sweep_options(keep, resume, sets).map_err(|e| py_error(py, e))?;
    let reporter = Reporter::new(progress);
    let listener = reporter.listener.clone();
    let stopped = reporter.stopped.clone();
    let (result, signal) = interruptible(py, || {
        reporting_to(listener, || {
            dsmcosim::sweep::run(&path, &out, &options).map(|_| ())
        })
    })?;
    let result = match result {
        // The sweep stopped by the callable: its count of finished points, as an error
        // of its own (the table is written only by a sweep that ran every point).
        Err(dsmcosim::Error::Checks { message, code: 130 }) if stopped.load(Ordering::SeqCst) => {
            let err = error_class(py, "StoppedError")?.call1((message.clone(),))?;
            err.setattr("field", "progress")?;
            err.setattr("message", message)?;
            err.setattr("exit_code", 130)?;
            reporter.finish(py, Ok(()), signal)?;
            return Err(PyErr::from_value(err));
        }
        Err(dsmcosim::Error::Checks { message, code: 130 }) => {
            reporter.finish(py, Ok(()), signal)?;
            return Err(PyKeyboardInterrupt::new_err(message));
        }
        other => other,
    };
    reporter.finish(py, result, signal).map(|_| ())
}

/// `keep` as the crate's [`dsmcosim::sweep::Keep`], or an error naming `keep`.
fn keep_of(keep: &str) -> dsmcosim::Result<dsmcosim::sweep::Keep> {
    match keep {
        "summary" => Ok(dsmcosim::sweep::Keep::Summary),
        "trace" => Ok(dsmcosim::sweep::Keep::Trace),
        "all" => Ok(dsmcosim::sweep::Keep::All),
        other => Err(dsmcosim::Error::invalid(
            "keep",
            format!("must be \"summary\", \"trace\" or \"all\" (got {other:?})"),
        )),
    }
}

/// The options of a sweep run from Python: no shard (an executor's points are its
/// shards), `keep` named as the command line names it.
fn sweep_options(
    keep: &str,
    resume: bool,
    sets: Vec<String>,
) -> dsmcosim::Result<dsmcosim::sweep::Options> {
    Ok(dsmcosim::sweep::Options {
        keep: keep_of(keep)?,
        resume,
        shard: None,
        sets,
    })
}

/// A sweep on the caller's executor, first call: sets `out` up as `dsmcosim sweep`
/// does and returns the keys of the points to run (without those a `resume` finds
/// done), in index order.
#[pyfunction]
fn sweep_pending(
    py: Python<'_>,
    path: PathBuf,
    out: PathBuf,
    sets: Vec<String>,
    keep: &str,
    resume: bool,
) -> PyResult<Vec<String>> {
    let result =
        py.detach(|| dsmcosim::sweep::pending(&path, &out, &sweep_options(keep, resume, sets)?));
    result.map_err(|e| py_error(py, e))
}

/// Runs the point `key` of a sweep into `out/points/<key>/` (in any process that sees
/// `out`), as `dsmcosim sweep` runs each point; Ctrl-C stops it as it stops a run.
#[pyfunction]
fn sweep_point(
    py: Python<'_>,
    path: PathBuf,
    out: PathBuf,
    sets: Vec<String>,
    keep: &str,
    key: String,
) -> PyResult<()> {
    let keep = keep_of(keep).map_err(|e| py_error(py, e))?;
    let (result, signal) = interruptible(py, || {
        dsmcosim::sweep::run_one(&path, &out, &sets, keep, &key)
    })?;
    if let Some(signal) = signal {
        return Err(signal);
    }
    result.map_err(|e| py_error(py, e))
}

/// Writes a sweep's `sweep.csv`, `timing.csv` and figures once every point is done.
#[pyfunction]
fn sweep_finish(
    py: Python<'_>,
    path: PathBuf,
    out: PathBuf,
    sets: Vec<String>,
    keep: &str,
    ran: usize,
) -> PyResult<()> {
    let result = py.detach(|| {
        let options = sweep_options(keep, true, sets)?;
        dsmcosim::sweep::finish(&path, &out, &options, ran).map(|_| ())
    });
    result.map_err(|e| py_error(py, e))
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
    /// The last delivery on every route since this co-simulation was made or forked.
    deliveries: Deliveries,
}

/// The last delivery on every route a `CoSim` has seen since it was made (or forked):
/// by (channel, sending node, receiving node, kind, element: the body of a state, the
/// link of a force or a line's wave, the connection of an FMU signal), the sample's
/// time and its delivery's.
type Deliveries = BTreeMap<(usize, usize, usize, &'static str, usize), (SimTime, SimTime)>;

/// The recorder, with every delivery also noted in [`Deliveries`].
struct Noting<'a> {
    recorder: &'a mut Recorder,
    deliveries: &'a mut Deliveries,
}

impl Observer for Noting<'_> {
    fn on_step(&mut self, values: &StepValues) -> std::io::Result<()> {
        self.recorder.on_step(values)
    }

    fn on_cycle(&mut self, report: &CycleReport) -> std::io::Result<()> {
        self.recorder.on_cycle(report)
    }

    fn on_delivery(&mut self, t: SimTime, msg: &Message) {
        let (kind, element) = match &msg.payload {
            Payload::State { body, .. } => ("state", *body),
            Payload::Force { link, .. } => ("force", *link),
            Payload::Line(line) => ("line", line.link),
            Payload::Signal { connection, .. } => ("signal", *connection),
        };
        self.deliveries.insert(
            (msg.channel, msg.from, msg.to, kind, element),
            (msg.sent, t),
        );
        self.recorder.on_delivery(t, msg);
    }

    fn on_epoch(&mut self, epoch: &EpochRecord) {
        self.recorder.on_epoch(epoch);
    }

    fn on_window(&mut self, report: &WindowReport) {
        Observer::on_window(self.recorder, report);
    }
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
            deliveries: Deliveries::new(),
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
            deliveries: self.deliveries.clone(),
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
            deliveries: Deliveries::new(),
        })
    }

    /// Simulated time reached [s]: the state is at `now` (on the step grid; `advance(t)`
    /// leaves it at `t` rounded up to the grid).
    #[getter]
    fn now(&self) -> f64 {
        self.world.reached().as_secs_f64()
    }

    /// The step [s].
    #[getter]
    fn dt(&self) -> f64 {
        self.world.scenario().dt.as_secs_f64()
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

    /// Advances to `t` [s], rounded up to the step grid (a `t` past the scenario's end
    /// advances to the end): every event before it, and the measurement window ending
    /// at it; at the end, everything left (the last step). A `t` before `now` is
    /// refused. Raises on divergence; Ctrl-C stops it at the next slice of steps (`now`
    /// says where) and raises `KeyboardInterrupt`.
    fn advance(&mut self, py: Python<'_>, t: f64) -> PyResult<()> {
        let world = &mut self.world;
        let mut noting = Noting {
            recorder: &mut self.recorder,
            deliveries: &mut self.deliveries,
        };
        let target = (|| -> dsmcosim::Result<SimTime> {
            let asked = sim_time("t", t)?;
            let (dt, end, now) = (
                world.scenario().dt.0,
                world.scenario().duration,
                world.reached(),
            );
            let on_grid = SimTime(asked.0.div_ceil(dt).saturating_mul(dt)).min(end);
            if asked < now {
                return Err(dsmcosim::Error::invalid(
                    "t",
                    format!(
                        "must not lie before now = {} s (got {t} s): a co-simulation does \
                         not go back (fork it to try something from here)",
                        now.as_secs_f64()
                    ),
                ));
            }
            Ok(on_grid)
        })()
        .map_err(|e| py_error(py, e))?;
        let (done, signal) = interruptible(py, move || -> dsmcosim::Result<()> {
            // Slices as a run's: the world stops between two when asked (Ctrl-C).
            // Slicing changes nothing: events are processed in the same order.
            let steps = dsmcosim::run::slice_steps(world.scenario());
            let slice = world.scenario().dt.0.saturating_mul(steps);
            let end = world.scenario().duration;
            loop {
                let now = world.reached();
                let next = SimTime(now.0.saturating_add(slice)).min(target);
                world.advance_to(next, &mut noting)?;
                if next == target || dsmcosim::interrupt::requested() {
                    break;
                }
            }
            if target == end && !dsmcosim::interrupt::requested() {
                // The end: the step at `duration` too, as a run to its end takes it.
                world.run_to_end(&mut noting)?;
            }
            Ok(())
        })?;
        if let Some(signal) = signal {
            return Err(signal);
        }
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
                    let what = format!("periods[{i}]");
                    if !(p.is_finite() && p > 0.0) {
                        return Err(dsmcosim::Error::invalid(
                            what,
                            format!("must be a period > 0 s (got {})", dsmcosim::error::num(p)),
                        ));
                    }
                    sim_time(&what, p)?;
                    Ok(dsmcosim::network::channel::achieved_period(p, dt))
                })
                .collect()
        })();
        let achieved = checked.map_err(|e| py_error(py, e))?;
        let now = self.world.reached();
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

    /// The state at `now` as the step there records it, measured on a fork (this
    /// co-simulation is untouched): a dict of `time` [s], `bodies` (ids), `p`, `v`,
    /// `omega` ([x, y, z] per body), `q` ([w, x, y, z] per body; empty for point
    /// masses), `rows` (names), `w` [m] and `f` [N] per row, `max_w` [m], and `signals`
    /// (name → value of each traced FMU output: a float, an int, a bool, a str or bytes
    /// by its FMI type, an array element per name `y[i]`).
    fn observe<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        let seen = py
            .detach(|| self.world.observe())
            .map_err(|e| py_error(py, e))?;
        let scenario = self.world.scenario();
        // trace.csv's names: `L<k>`, or a joint's row `J<j>_<r>`.
        let rows: Vec<String> = (0..seen.w.len())
            .map(|k| scenario.links[k].name(k))
            .collect();
        let xyz = |vs: &[nalgebra::Vector3<f64>]| -> Vec<[f64; 3]> {
            vs.iter().map(|v| [v.x, v.y, v.z]).collect()
        };
        let out = PyDict::new(py);
        out.set_item("time", seen.time.as_secs_f64())?;
        out.set_item(
            "bodies",
            scenario.bodies.iter().map(|b| b.id).collect::<Vec<u32>>(),
        )?;
        out.set_item("p", xyz(&seen.p))?;
        out.set_item("v", xyz(&seen.v))?;
        out.set_item("omega", xyz(&seen.omega))?;
        let q: Vec<[f64; 4]> = seen.q.iter().map(|q| [q.w, q.i, q.j, q.k]).collect();
        out.set_item("q", q)?;
        out.set_item("rows", rows)?;
        out.set_item("w", seen.w)?;
        out.set_item("f", seen.f)?;
        out.set_item("max_w", seen.max_w)?;
        let signals = PyDict::new(py);
        for (name, value) in scenario.signal_names().into_iter().zip(seen.signals) {
            // Each FMU output as the Python value of its FMI type.
            use dsmcosim::fmu::Value;
            match value {
                Value::Float(x) => signals.set_item(name, x)?,
                Value::Float32(x) => signals.set_item(name, f64::from(x))?,
                Value::Int(i) => signals.set_item(name, i)?,
                Value::UInt(u) => signals.set_item(name, u)?,
                Value::Bool(b) => signals.set_item(name, b)?,
                Value::Text(t) => signals.set_item(name, t)?,
                Value::Bytes(b) => signals.set_item(name, PyBytes::new(py, &b))?,
            }
        }
        out.set_item("signals", signals)?;
        let channels = self.world.channels();
        let deliveries: Vec<_> = self
            .deliveries
            .iter()
            .map(|(&(c, from, to, kind, element), &(sent, delivered))| {
                let name = channels
                    .get(c)
                    .map_or(String::new(), |ch| ch.spec.name.clone());
                let element = match kind {
                    "state" => scenario
                        .bodies
                        .get(element)
                        .map_or(String::new(), |b| format!("B{}", b.id)),
                    "signal" => format!("connections[{element}]"),
                    _ => dsmcosim::scenario::model::row_name(element, None),
                };
                let times = (sent.as_secs_f64(), delivered.as_secs_f64());
                (name, from + 1, to + 1, kind, element, times.0, times.1)
            })
            .collect();
        out.set_item("deliveries", deliveries)?;
        Ok(out)
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
            let now = self.world.reached();
            dsmcosim::checkpoint::write(&out, now, &self.world, &self.recorder, None)
        });
        written.map_err(|e| py_error(py, e))
    }

    /// The co-simulation as bytes (a checkpoint's) and its decisions: what a pickle
    /// holds.
    #[allow(clippy::type_complexity)]
    fn state<'py>(&self, py: Python<'py>) -> PyResult<(Bound<'py, PyBytes>, Vec<(f64, Vec<f64>)>)> {
        let bytes = py.detach(|| {
            dsmcosim::checkpoint::to_bytes(self.world.reached(), &self.world, &self.recorder, None)
                .map_err(|e| dsmcosim::Error::invalid("pickle", e.to_string()))
        });
        let bytes = bytes.map_err(|e| py_error(py, e))?;
        let decisions = self
            .decisions
            .iter()
            .map(|(at, tau)| (at.as_secs_f64(), tau.clone()))
            .collect();
        Ok((PyBytes::new(py, &bytes), decisions))
    }

    /// The co-simulation `state` gave.
    #[staticmethod]
    fn from_state(
        py: Python<'_>,
        bytes: Vec<u8>,
        decisions: Vec<(f64, Vec<f64>)>,
    ) -> PyResult<PyCoSim> {
        let cp = py.detach(|| dsmcosim::checkpoint::from_bytes(&bytes, "pickle"));
        let cp = cp.map_err(|e| py_error(py, e))?;
        let decisions = decisions
            .into_iter()
            .map(|(at, tau)| Ok((sim_time("pickle", at)?, tau)))
            .collect::<dsmcosim::Result<Vec<_>>>()
            .map_err(|e| py_error(py, e))?;
        Ok(PyCoSim {
            world: cp.world,
            recorder: cp.recorder,
            decisions,
            deliveries: Deliveries::new(),
        })
    }
}

/// The native module.
#[pymodule]
fn _native(m: &Bound<'_, PyModule>) -> PyResult<()> {
    // The package draws its own bars (tqdm, or the caller's callable): the crate's
    // terminal bar would fight them for the line.
    dsmcosim::progress::silence();
    m.add("__version__", env!("CARGO_PKG_VERSION"))?;
    m.add_function(wrap_pyfunction!(run, m)?)?;
    m.add_function(wrap_pyfunction!(validate, m)?)?;
    m.add_function(wrap_pyfunction!(sweep, m)?)?;
    m.add_function(wrap_pyfunction!(sweep_pending, m)?)?;
    m.add_function(wrap_pyfunction!(sweep_point, m)?)?;
    m.add_function(wrap_pyfunction!(sweep_finish, m)?)?;
    m.add_class::<PyCoSim>()?;
    Ok(())
}
