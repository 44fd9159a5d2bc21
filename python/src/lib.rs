//! `dsmcosim._native`: the few calls the Python package (`python/dsmcosim/`) makes into
//! the crate. Each takes plain values (text, paths, override strings) and gives plain
//! values back (JSON text, a digest), so the Python side builds its dicts and
//! DataFrames itself; every call releases the GIL while the crate works. An error of the
//! crate becomes `dsmcosim.DsmcosimError` with the field, the message and the exit code
//! the command line would print and return.

use std::path::{Path, PathBuf};

use dsmcosim::run::plan::RunPlan;
use dsmcosim::run::RunOptions;
use dsmcosim::scenario::{overrides, Scenario};
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

/// The scenario of a file (`path`) or of JSON `text` (relative FMU paths then read from
/// `base_dir`), with the `--set` overrides `sets` applied, and its text.
fn load(
    path: Option<&Path>,
    text: Option<&str>,
    base_dir: Option<&Path>,
    sets: &[String],
) -> dsmcosim::Result<(Scenario, String)> {
    match (path, text) {
        (Some(path), _) => overrides::load_with(path, sets),
        (None, Some(text)) => {
            // parse_at reads relative paths from the directory of the file it is given.
            let beside = base_dir.map(|d| d.join("scenario.json"));
            overrides::text_with(text, "<scenario>", beside.as_deref(), sets)
        }
        (None, None) => Err(dsmcosim::Error::invalid(
            "scenario",
            "give a scenario file's path or a scenario as a dict",
        )),
    }
}

/// Runs a scenario into `out` (as `dsmcosim run`, writing the same files, the scenario
/// as run included) and returns the run's digest. A run that diverged raises, its
/// outputs up to the divergence written.
#[pyfunction]
#[pyo3(signature = (out, sets, force, path=None, text=None, base_dir=None))]
fn run(
    py: Python<'_>,
    out: PathBuf,
    sets: Vec<String>,
    force: bool,
    path: Option<PathBuf>,
    text: Option<String>,
    base_dir: Option<PathBuf>,
) -> PyResult<String> {
    let result = py.detach(|| -> dsmcosim::Result<String> {
        let (scenario, text) = load(path.as_deref(), text.as_deref(), base_dir.as_deref(), &sets)?;
        let options = RunOptions {
            force,
            ..RunOptions::default()
        };
        let result = dsmcosim::run::run_with(&scenario, &out, options);
        if result.is_ok() || matches!(result, Err(dsmcosim::Error::Diverged(_))) {
            dsmcosim::output::write_atomic(&out.join("scenario.json"), text.as_bytes())?;
        }
        result.map(|outcome| outcome.digest)
    });
    result.map_err(|e| py_error(py, e))
}

/// The plan of a scenario (what `dsmcosim validate --json` writes), as JSON text,
/// after every check a run makes before it starts.
#[pyfunction]
#[pyo3(signature = (sets, path=None, text=None, base_dir=None))]
fn validate(
    py: Python<'_>,
    sets: Vec<String>,
    path: Option<PathBuf>,
    text: Option<String>,
    base_dir: Option<PathBuf>,
) -> PyResult<String> {
    let result = py.detach(|| -> dsmcosim::Result<String> {
        let (scenario, _) = load(path.as_deref(), text.as_deref(), base_dir.as_deref(), &sets)?;
        dsmcosim::run::preflight(&scenario, &RunOptions::default())?;
        let plan: RunPlan = dsmcosim::run::plan::plan(&scenario)?;
        serde_json::to_string(&plan).map_err(|e| dsmcosim::Error::invalid("plan", e.to_string()))
    });
    result.map_err(|e| py_error(py, e))
}

/// Runs the sweep file at `path` into `out` (as `dsmcosim sweep`); its table is
/// `out/sweep.csv`.
#[pyfunction]
#[pyo3(signature = (path, out, sets, keep, resume))]
fn sweep(
    py: Python<'_>,
    path: PathBuf,
    out: PathBuf,
    sets: Vec<String>,
    keep: &str,
    resume: bool,
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
    let result = py.detach(|| dsmcosim::sweep::run(&path, &out, &options).map(|_| ()));
    result.map_err(|e| py_error(py, e))
}

/// The native module.
#[pymodule]
fn _native(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add("DsmcosimError", m.py().get_type::<DsmcosimError>())?;
    m.add("__version__", env!("CARGO_PKG_VERSION"))?;
    m.add_function(wrap_pyfunction!(run, m)?)?;
    m.add_function(wrap_pyfunction!(validate, m)?)?;
    m.add_function(wrap_pyfunction!(sweep, m)?)?;
    Ok(())
}
