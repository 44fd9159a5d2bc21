"""The package's functions over the native module (`dsmcosim._native`)."""

import contextlib
import json
import os
import re
import shutil
import tempfile
import warnings
import weakref
from pathlib import Path
from typing import (Any, Callable, Dict, Iterator, List, Mapping, Optional, Sequence,
                    Tuple, Union)

import pandas as pd

from . import _native
from ._errors import DsmcosimError, DsmcosimWarning

Scenario = Union[str, "os.PathLike[str]", Mapping[str, Any]]

# The CSV files a run writes, by the attribute of `Run` that holds each.
_TABLES = {"trace": "trace.csv", "epochs": "epochs.csv", "network": "network.csv"}


def _pointer(name: str) -> str:
    """A keyword override's JSON pointer: `duration` -> `/duration`, and `__` separates
    the steps of a path: `channels__0__tau` -> `/channels/0/tau`."""
    return "/" + "/".join(name.split("__"))


def _sets(overrides: Mapping[str, Any],
          set: Optional[Mapping[str, Any]]) -> Tuple[List[str], List[Tuple[str, str]]]:
    """`--set POINTER=VALUE` strings, keyword overrides first, then `set`'s pointers, in
    the order given (a later one wins, as on the command line); and for each, how the
    caller spelled it in Python (for messages)."""
    pairs = [(_pointer(k), v, f"{k}={v!r}") for k, v in overrides.items()]
    pairs += [(p, v, f"set={{{p!r}: {v!r}}}") for p, v in (set or {}).items()]
    for pointer, _, _ in pairs:
        if not pointer.startswith("/"):
            raise ValueError(f"an override's JSON pointer starts with '/': {pointer!r}")
    strings = [f"{p}={json.dumps(v)}" for p, v, _ in pairs]
    return strings, [(text, spelled) for text, (_, _, spelled) in zip(strings, pairs)]


# The command line's options in messages, as the package's arguments.
_FLAGS = [(re.compile(r"--resume\b"), "resume=True"), (re.compile(r"--force\b"), "force=True")]


def _in_python_words(text: str, spellings: Sequence[Tuple[str, str]]) -> str:
    """A message of the crate with the command line's words (`--set /a/b=1`,
    `--force`, `--resume`) replaced by the arguments the Python caller used."""
    for cli, spelled in spellings:
        text = text.replace(f"--set {cli}", spelled)
    for flag, argument in _FLAGS:
        text = flag.sub(argument, text)
    return text


@contextlib.contextmanager
def _spoken(spellings: Sequence[Tuple[str, str]] = ()) -> Iterator[None]:
    """Re-raises a `DsmcosimError` with its message in Python's words."""
    try:
        yield
    except DsmcosimError as e:
        e.args = tuple(_in_python_words(a, spellings) if isinstance(a, str) else a
                       for a in e.args)
        e.message = _in_python_words(e.message, spellings)
        raise


def _source(scenario: Scenario,
            base_dir: Optional[Union[str, "os.PathLike[str]"]]) -> Dict[str, Optional[str]]:
    """The scenario as the native module takes it: a dict of `path`, `text` and
    `base_dir` (the one not used is None)."""
    if isinstance(scenario, Mapping):
        base = os.fspath(base_dir) if base_dir is not None else os.getcwd()
        return {"path": None, "text": json.dumps(scenario), "base_dir": base}
    if isinstance(scenario, (str, os.PathLike)):
        if base_dir is not None:
            raise ValueError("base_dir is for a scenario given as a dict; a file's "
                             "relative paths are read from its own directory")
        return {"path": os.fspath(scenario), "text": None, "base_dir": None}
    raise TypeError(f"a scenario is a path or a dict, not {type(scenario).__name__}")


# `progress=`: None or False (nothing), True (tqdm bars), or a callable
# `progress(position, total, unit)`.
Progress = Union[bool, Callable[[int, int, str], Any], None]


def _in_notebook() -> bool:
    """Whether the caller runs in a Jupyter kernel."""
    try:
        from IPython import get_ipython  # type: ignore[import-not-found, unused-ignore]
    except ImportError:
        return False
    shell = get_ipython()
    return shell is not None and type(shell).__name__ == "ZMQInteractiveShell"


def _tqdm() -> Any:
    """tqdm's bar class: a widget in a notebook that has ipywidgets, text elsewhere (a
    notebook without ipywidgets gets the text bar, not tqdm's warning)."""
    try:
        import tqdm  # type: ignore[import-untyped, unused-ignore]
    except ImportError as e:
        raise ImportError("progress=True draws tqdm bars: `pip install tqdm` "
                          "(or pass a callable progress(position, total, unit))") from e
    if _in_notebook():
        try:
            import ipywidgets  # type: ignore[import-not-found, unused-ignore]  # noqa: F401
            from tqdm.notebook import tqdm as widget  # type: ignore[import-untyped, unused-ignore]
            return widget
        except ImportError:
            pass
    return tqdm.tqdm


class _Bars:
    """tqdm bars for the crate's progress, one per unit it reports (`steps`, `windows`,
    `points`): a widget in a notebook with ipywidgets, text on a terminal."""

    def __init__(self) -> None:
        self._tqdm = _tqdm()
        self._bars: Dict[str, Any] = {}

    def __call__(self, position: int, total: int, unit: str) -> None:
        bar = self._bars.get(unit)
        if bar is None:
            bar = self._bars[unit] = self._tqdm(total=total, unit=f" {unit}", leave=True)
        if bar.total != total:
            bar.total = total
        bar.update(position - bar.n)

    def close(self) -> None:
        for bar in self._bars.values():
            bar.close()


def _reporter(progress: Progress) -> Tuple[Optional[Callable[[int, int, str], Any]], Callable[[], None]]:
    """The callable the native module calls with positions, and what closes it."""
    if progress is None or progress is False:
        return None, lambda: None
    if progress is True:
        bars = _Bars()
        return bars, bars.close
    if callable(progress):
        return progress, lambda: None
    raise TypeError("progress is True, False, None or a callable "
                    f"progress(position, total, unit), not {type(progress).__name__}")


# Columns whose values are whole numbers by nature (counts, indices, ids, seeds), as
# nullable integers (an empty cell is <NA>); every other numeric column is float64 and
# every text column text, whatever values a given run happens to hold.
_INTEGER = re.compile(r"^(index|cycle|slot|sender|bytes|lost|measurements|lost_frames|"
                      r"diverged_node|paired_n_.*|paired_wins_.*|paired_losses_.*)$")
_UNSIGNED = re.compile(r"^seed$")
_TEXT = re.compile(r"^(point|status|diverged_where|digest|kind|channel|info|"
                   r"paired_verdict_.*)$")


def _dtype(column: str, sweep_axes: Mapping[str, str]) -> str:
    if column in sweep_axes:
        return sweep_axes[column]
    if _UNSIGNED.match(column):
        return "UInt64"
    if _INTEGER.match(column):
        return "Int64"
    if _TEXT.match(column):
        return "object"
    return "float64"


# pandas' parser before 3.0 misreads some floats in the last digit unless asked for
# the round-trip parser; from 3.0 its default is exact and the option is deprecated.
_EXACT: Dict[str, Any] = ({"float_precision": "round_trip"}
                          if int(pd.__version__.split(".")[0]) < 3 else {})


# An FMU output's FMI type (summary.json's `fmus[].trace_columns`) → its column's dtype:
# integers exact (nullable Int64/UInt64, so an Int64 or a UInt64 never passes through
# a float), Booleans as their 0/1, Strings as text, Binary (hex in the file) as bytes, a
# Float32 read as the float32 it was and widened to float64 (as `observe()` gives it).
_FMI_DTYPES = {"Float64": "float64", "Float32": "float32", "UInt8": "UInt64",
               "UInt16": "UInt64", "UInt32": "UInt64", "UInt64": "UInt64",
               "String": "object", "Binary": "object"}


def _fmi_dtype(fmi_type: str) -> str:
    return _FMI_DTYPES.get(fmi_type, "Int64")  # Int8 … Int64, Boolean, Enumeration


def read_table(path: Union[str, "os.PathLike[str]"],
               columns: Optional[Sequence[str]] = None,
               sweep_axes: Optional[Mapping[str, str]] = None,
               fmi_types: Optional[Mapping[str, str]] = None) -> pd.DataFrame:
    """One of a run's (or a sweep's) CSV files as a DataFrame, `columns` only if given.

    Every float is the file's value to the bit (pandas' round-trip parser); each column
    has one type whatever its values: float64 for quantities (times included), nullable
    Int64 for counts and ids (UInt64 for seeds), object for text; an empty cell, a value
    the run did not produce, is NaN (or <NA>), as is a NaN the run wrote. `sweep_axes` gives a sweep's axis
    columns their types (from the sweep's values); `fmi_types` a trace's FMU columns
    theirs (column → FMI type): integers exact (Int64, UInt64), Booleans 0/1 (Int64), a
    Float32 as the float32 it was (widened), a String as written (an empty one or "NaN"
    included), a Binary as bytes."""
    header = pd.read_csv(path, nrows=0).columns
    wanted = list(header) if columns is None else list(columns)
    missing = [c for c in wanted if c not in header]
    if missing:
        raise KeyError(f"{os.fspath(path)} has no column {missing[0]!r} "
                       f"(it has {', '.join(header[:8])}{', …' if len(header) > 8 else ''})")
    fmi = fmi_types or {}
    dtypes: Dict[str, str] = {c: _fmi_dtype(fmi[c]) if c in fmi else _dtype(c, sweep_axes or {})
                              for c in wanted}
    text = {c for c in wanted if fmi.get(c) in ("String", "Binary")}
    na = {c: ["", "NaN"] for c in wanted if c not in text}
    table: pd.DataFrame = pd.read_csv(path, usecols=wanted, dtype=dtypes, keep_default_na=False,
                                      na_values=na, **_EXACT)
    for c in wanted:
        if fmi.get(c) == "Float32":
            table[c] = table[c].astype("float64")
        elif fmi.get(c) == "Binary":
            table[c] = table[c].map(bytes.fromhex)
    return table[wanted]


class Run:
    """A run: its `summary` (summary.json as a dict), its `digest`, its `status`
    ("ok", or "interrupted" for a run its progress callable stopped), its `warnings`,
    and its tables `trace`, `epochs` and `network` (None where the run wrote none) as
    DataFrames, each read from its file on first access (`table(name, columns)` reads
    only some columns). `directory` is where its files are; a run made with `out=None`
    keeps them in a temporary directory removed when the `Run` is."""

    def __init__(self, directory: Path, keep: bool, warnings: Sequence[str] = ()):
        with open(directory / "summary.json") as f:
            self.summary: Dict[str, Any] = json.load(f)
        self.digest: str = self.summary["digest"]
        self.status: str = self.summary.get("status", "ok")
        self.warnings: List[str] = list(warnings)
        self.directory: Path = directory
        self._tables: Dict[str, Optional[pd.DataFrame]] = {}
        if not keep:
            weakref.finalize(self, shutil.rmtree, os.fspath(directory), True)

    def table(self, name: str, columns: Optional[Sequence[str]] = None) -> Optional[pd.DataFrame]:
        """Table `name` ("trace", "epochs" or "network") read from its file, only
        `columns` if given (a large trace read in part); None if the run wrote none.
        """
        if name not in _TABLES:
            raise ValueError(f"a run's tables are {', '.join(_TABLES)}, not {name!r}")
        path = self.directory / _TABLES[name]
        fmi_types = {c["column"]: c["type"] for f in self.summary.get("fmus", [])
                     for c in f.get("trace_columns", [])} if name == "trace" else {}
        return read_table(path, columns, fmi_types=fmi_types) if path.is_file() else None

    def _cached(self, name: str) -> Optional[pd.DataFrame]:
        if name not in self._tables:
            self._tables[name] = self.table(name)
        return self._tables[name]

    @property
    def trace(self) -> Optional[pd.DataFrame]:
        """trace.csv: one row per recorded step."""
        return self._cached("trace")

    @property
    def epochs(self) -> Optional[pd.DataFrame]:
        """epochs.csv: one row per measurement window."""
        return self._cached("epochs")

    @property
    def network(self) -> Optional[pd.DataFrame]:
        """network.csv of a TDMA run: one row per frame."""
        return self._cached("network")

    def plot(self) -> Any:
        """The run's standard figures in one matplotlib Figure (matplotlib is an
        optional dependency: `pip install matplotlib`), one panel per quantity the run
        has: the largest constraint violation max |w| over the links [m] against time,
        each measurement window's cost, each channel's achieved period [ms] per window,
        and for a run without links its traced signals. Returns the Figure (save it
        with `fig.savefig("run.svg")`; a notebook shows it)."""
        try:
            import matplotlib.pyplot as plt  # type: ignore[import-not-found, unused-ignore]
        except ImportError as e:
            raise ImportError("Run.plot draws with matplotlib: `pip install matplotlib`") from e
        trace, epochs = self.trace, self.epochs
        panels: List[Callable[[Any], None]] = []
        links = [c for c in (trace.columns if trace is not None else []) if c.startswith("w_")]
        if trace is not None and links:
            def violation(ax: Any) -> None:
                assert trace is not None
                ax.plot(trace["t"], trace[links].abs().max(axis=1), color="C0",
                        label=f"max over {len(links)} rows")
                ax.set_ylabel("max |w| [m]")
                ax.set_title("Constraint violation")
                ax.legend(loc="upper left", bbox_to_anchor=(1.01, 1.0))
            panels.append(violation)
        elif trace is not None and len(trace.columns) > 1:
            # An FMU's outputs are `unit.variable`; the bodies' invariants (Px … KE)
            # are left out when there are such signals, and so are String and Binary
            # outputs (text, not numbers: no curve).
            numeric = set(trace.select_dtypes(include=["number", "bool"]).columns)
            named = [c for c in trace.columns if "." in c and c in numeric]
            signals = (named or [c for c in trace.columns if c != "t" and c in numeric])[:8]

            def traced(ax: Any) -> None:
                assert trace is not None
                for c in signals:
                    ax.plot(trace["t"], trace[c], label=c)
                ax.set_ylabel("value [signal's unit]")
                ax.set_title("Traced signals")
                ax.legend(loc="upper left", bbox_to_anchor=(1.01, 1.0))
            panels.append(traced)
        if epochs is not None and "cost" in epochs.columns and len(epochs) > 0:
            unit = "m" if links else "signal's unit"

            def cost(ax: Any) -> None:
                assert epochs is not None
                ax.step(epochs["t_end"], epochs["cost"], where="pre", color="C1",
                        label="window cost")
                ax.set_ylabel(f"cost [{unit}]")
                ax.set_title("Cost of each measurement window")
                ax.legend(loc="upper left", bbox_to_anchor=(1.01, 1.0))
            panels.append(cost)
            achieved = [c for c in epochs.columns
                        if c.startswith("tau_") and c.endswith("_achieved")]
            if achieved:
                def periods(ax: Any) -> None:
                    assert epochs is not None
                    for c in achieved:
                        ax.step(epochs["t_start"], 1000.0 * epochs[c], where="post",
                                label=c[len("tau_"):-len("_achieved")])
                    ax.set_ylabel("period [ms]")
                    ax.set_title("Achieved period of each channel")
                    ax.legend(loc="upper left", bbox_to_anchor=(1.01, 1.0))
                panels.append(periods)
        if not panels:
            raise ValueError("this run has no trace and no windows to plot")
        fig, axes = plt.subplots(len(panels), 1, sharex=True, squeeze=False,
                                 figsize=(9.0, 2.6 * len(panels)), constrained_layout=True)
        for draw, ax in zip(panels, axes[:, 0]):
            draw(ax)
            ax.grid(True, alpha=0.3)
        axes[-1, 0].set_xlabel("simulated time [s]")
        fig.suptitle(f"{self.summary.get('scenario', 'run')} ({self.status})")
        return fig

    def __repr__(self) -> str:
        return (f"Run(scenario={self.summary.get('scenario')!r}, "
                f"status={self.status!r}, digest={self.digest[:16]!r}…, "
                f"directory={str(self.directory)!r})")


def run(scenario: Scenario, out: Optional[Union[str, "os.PathLike[str]"]] = None, *,
        set: Optional[Mapping[str, Any]] = None, force: bool = False,
        base_dir: Optional[Union[str, "os.PathLike[str]"]] = None,
        progress: Progress = None, **overrides: Any) -> Run:
    """Runs `scenario` (a scenario file's path, or a scenario as a dict) and returns its
    `Run`.

    `out`: the directory the run writes (as `dsmcosim run --out`); None runs into a
    temporary directory that is removed once its files are read. Keyword `overrides`
    change the scenario as `--set` does: `duration=3.0` sets `/duration`, and `__`
    separates path steps (`channels__0__tau=0.004` sets `/channels/0/tau`); `set` takes
    JSON pointers for keys that are not identifiers (`set={"/network/drift_ppm": 100}`).
    `force` replaces another scenario's run in `out`. `base_dir`: where a dict
    scenario's relative paths (FMUs) are read from, default the working directory.

    `progress=True` shows a tqdm bar (a widget in a notebook) over the steps, or the
    windows under a controller; a callable `progress(position, total, unit)` is called
    instead (every slice of steps: 1024, fewer on a large model; every window). A callable that returns False stops the
    run there: its outputs are an interrupted run's and the `Run` says
    `status == "interrupted"`. Ctrl-C (a notebook's "Interrupt kernel") stops the run
    within a slice of steps and raises KeyboardInterrupt, the outputs up to there
    written and marked interrupted, as on the command line.

    Raises `InvalidScenarioError` (a ValueError) for bad input naming the field,
    `NotFoundError` (a FileNotFoundError) for a missing file, and `DivergedError` for a
    run that diverged (with `time`, `node` and `link`; its outputs up to the divergence
    are in `out`). What the command line prints as a warning is issued as a
    `DsmcosimWarning`. The GIL is released while it runs.
    """
    sets, spellings = _sets(overrides, set)
    source = _source(scenario, base_dir)
    report, close = _reporter(progress)
    keep = out is not None
    directory = Path(out) if out is not None else Path(tempfile.mkdtemp(prefix="dsmcosim-run-"))
    done = False
    try:
        with _spoken(spellings):
            outcome = _native.run(source, os.fspath(directory), sets, force, report)
        ran = Run(directory, keep, outcome["warnings"])
        done = True
    finally:
        close()
        if not keep and not done:
            shutil.rmtree(directory, ignore_errors=True)
    for line in ran.warnings:
        warnings.warn(line, DsmcosimWarning, stacklevel=2)
    return ran


def load(directory: Union[str, "os.PathLike[str]"]) -> Union[Run, pd.DataFrame]:
    """A stored run or sweep folder as `run` or `sweep` gives it: a `Run` for a run's
    folder (summary.json; `dsmcosim run --out`, a sweep point, `results/<name>`), the
    table `sweep.csv` for a sweep's folder. Nothing is copied; the files stay."""
    folder = Path(directory)
    if (folder / "summary.json").is_file():
        return Run(folder, keep=True)
    if (folder / "sweep.csv").is_file():
        return read_table(folder / "sweep.csv", sweep_axes=_axis_types(folder))
    if not folder.is_dir():
        raise FileNotFoundError(2, "No such directory", os.fspath(folder))
    raise ValueError(f"{os.fspath(folder)} holds neither a run (summary.json) nor a "
                     "finished sweep (sweep.csv)")


def validate(scenario: Scenario, *, set: Optional[Mapping[str, Any]] = None,
             base_dir: Optional[Union[str, "os.PathLike[str]"]] = None,
             **overrides: Any) -> Dict[str, Any]:
    """Checks `scenario` as a run would before it starts and returns its plan as a
    dict (what `dsmcosim validate --json` writes: nodes, channels with their achieved
    delays, the network, the coupling, the size of the run). Overrides as for `run`.
    Raises `InvalidScenarioError` naming the field of bad input."""
    sets, spellings = _sets(overrides, set)
    with _spoken(spellings):
        plan: Dict[str, Any] = json.loads(_native.validate(_source(scenario, base_dir), sets))
    return plan


def _axis_types(out: Path) -> Dict[str, str]:
    """The dtype of each axis column of the sweep in `out`, from its values: Int64
    when every value is an integer, float64 when every one is a number, else text."""
    try:
        with open(out / "sweep.json") as f:
            axes = json.load(f).get("axes", [])
    except (OSError, ValueError):
        return {}
    types = {}
    for axis in axes:
        values = axis.get("values") if isinstance(axis, dict) else None
        if not isinstance(axis, dict) or "name" not in axis:
            continue
        if values is None:
            types[axis["name"]] = "float64"
        elif all(isinstance(v, int) and not isinstance(v, bool) for v in values):
            types[axis["name"]] = "Int64"
        elif all(isinstance(v, (int, float)) and not isinstance(v, bool) for v in values):
            types[axis["name"]] = "float64"
        else:
            types[axis["name"]] = "object"
    return types


def sweep(sweep_file: Union[str, "os.PathLike[str]", Mapping[str, Any]],
          out: Union[str, "os.PathLike[str]"], *, keep: str = "all", resume: bool = False,
          set: Optional[Mapping[str, Any]] = None,
          base_dir: Optional[Union[str, "os.PathLike[str]"]] = None,
          progress: Progress = None, executor: Any = None,
          **overrides: Any) -> pd.DataFrame:
    """Runs a sweep into `out` (as `dsmcosim sweep`) and returns its table,
    `out/sweep.csv`, as a DataFrame (one row per point).

    `sweep_file`: a sweep file's path, or a sweep as a dict (its `base` scenario path
    read relative to `base_dir`, default the working directory). `keep`: what each
    point keeps of its run (`"summary"`, `"trace"` or `"all"`); `resume` continues a
    sweep in `out`. Overrides change the base scenario, as `--set` does.
    `progress=True` shows a tqdm bar over the points (or pass a callable
    `progress(position, total, unit)`). Ctrl-C starts no further point, stops the
    running ones and raises KeyboardInterrupt; a callable returning False does the same
    and raises `StoppedError`; `resume=True` runs the rest.

    `executor`: run the points on it instead of the crate's own thread pool — any
    `concurrent.futures.Executor` (a `ProcessPoolExecutor`, Dask's
    `client.get_executor()`), or a pool with `map` (`multiprocessing.Pool`, Ray's
    `ray.util.multiprocessing.Pool`). Each point is `dsmcosim.point(spec)`, run where
    the executor puts it; every worker must see `out` and the sweep's files at the same
    paths (one machine, or a shared file system). The table is the one `dsmcosim sweep`
    writes, byte for byte, and `resume=True` skips the points already done, by their
    content hash."""
    sets, spellings = _sets(overrides, set)
    report, close = _reporter(progress)
    scratch = None
    try:
        if isinstance(sweep_file, Mapping):
            spec = dict(sweep_file)
            base = spec.get("base")
            if not isinstance(base, str):
                raise TypeError("a sweep given as a dict names its `base` scenario by "
                                "path (a string)")
            root = Path(os.fspath(base_dir)) if base_dir is not None else Path.cwd()
            spec["base"] = os.fspath((root / base).resolve())
            scratch = tempfile.mkdtemp(prefix="dsmcosim-sweep-")
            path = os.path.join(scratch, "sweep.json")
            with open(path, "w") as f:
                json.dump(spec, f)
        elif isinstance(sweep_file, (str, os.PathLike)):
            if base_dir is not None:
                raise ValueError("base_dir is for a sweep given as a dict; a file's "
                                 "`base` is read from its own directory")
            path = os.fspath(sweep_file)
        else:
            raise TypeError(f"a sweep is a path or a dict, not {type(sweep_file).__name__}")
        with _spoken(spellings):
            if executor is None:
                _native.sweep(path=path, out=os.fspath(out), sets=sets, keep=keep,
                              resume=resume, progress=report)
            else:
                _on_executor(executor, os.path.abspath(path), os.path.abspath(out), sets,
                             keep, resume, report)
    finally:
        close()
        if scratch is not None:
            shutil.rmtree(scratch, ignore_errors=True)
    return read_table(Path(out) / "sweep.csv", sweep_axes=_axis_types(Path(out)))


def point(spec: Mapping[str, Any]) -> Dict[str, Any]:
    """Runs one point of a sweep, as `sweep(..., executor=...)` hands it out: `spec` is
    `{"sweep": path, "out": directory, "sets": [...], "keep": ..., "key": ...}` (plain
    values, so it pickles). The point's run goes into `out/points/<key>/` and its
    record (done.json without the wall-clock time: `key`, `index`, `status`, `digest`,
    `row`) is returned: the same record for the same spec, in any process. A point
    whose `done.json` already records this point is not run again."""
    out = Path(spec["out"])
    _native.sweep_point(spec["sweep"], os.fspath(out), list(spec["sets"]), spec["keep"],
                        spec["key"])
    with open(out / "points" / spec["key"] / "done.json") as f:
        record = json.load(f)
    return {"key": spec["key"], "index": record["index"], "status": record["row"]["status"],
            "digest": record["row"]["digest"], "row": record["row"]}


def _on_executor(executor: Any, path: str, out: str, sets: List[str], keep: str,
                 resume: bool, report: Optional[Callable[[int, int, str], Any]]) -> None:
    """`sweep` with its points on `executor`: the points left to run (all, or without
    those `resume` finds done), each `point(spec)` there, then the tables."""
    keys = _native.sweep_pending(path, out, sets, keep, resume)
    specs = [{"sweep": path, "out": out, "sets": sets, "keep": keep, "key": k} for k in keys]
    if hasattr(executor, "submit"):
        import concurrent.futures
        futures = [executor.submit(point, spec) for spec in specs]
        try:
            for done, future in enumerate(concurrent.futures.as_completed(futures), 1):
                future.result()
                if report is not None and report(done, len(specs), "points") is False:
                    raise _stopped(done, len(specs))
        except BaseException:
            for future in futures:
                future.cancel()
            raise
    elif hasattr(executor, "imap_unordered") or hasattr(executor, "map"):
        mapped = getattr(executor, "imap_unordered", None) or executor.map
        for done, _ in enumerate(mapped(point, specs), 1):
            if report is not None and report(done, len(specs), "points") is False:
                raise _stopped(done, len(specs))
    else:
        raise TypeError("executor is a concurrent.futures.Executor (with submit) or a "
                        f"pool with map, not {type(executor).__name__}")
    _native.sweep_finish(path, out, sets, keep, len(specs))


def _stopped(done: int, total: int) -> Exception:
    from ._errors import StoppedError
    e = StoppedError(f"stopped by the progress callable: {done} of the {total} points "
                     "to run finished; resume=True runs the rest")
    e.field, e.message = "progress", str(e)
    return e


class CoSim:
    """A co-simulation steered from Python, window by window, with exactly the data the
    delay controller has: advance it to a time, read the cost of the last measurement
    window, set the channels' periods, fork it to try a candidate, checkpoint it.

        sim = dsmcosim.CoSim("scenarios/grid16_space_fixed.json", duration=10.0)
        while not sim.finished:
            trial = sim.fork()                 # measure a candidate on a copy
            trial.set_periods([0.004, 0.006])
            trial.advance(sim.now + 1.0)
            ...
            sim.set_periods(best)              # then steer the live run
            sim.advance(sim.now + 1.0)
        sim.digest

    The scenario must have no `controller` and no `schedule` (Python is the
    controller; `schedule()` writes its decisions down as one); its channels'
    `tau` are the periods it starts at, and `measurement.period` sets the windows whose
    cost `window_cost()` gives. Same scenario and same decisions give the same digest:
    the command line's for the scenario with `schedule()` as its `schedule` when the
    decisions are made at window boundaries (the command line's for the scenario itself
    when the periods are never changed). The GIL is released while it advances.
    """

    def __init__(self, scenario: Scenario, *, set: Optional[Mapping[str, Any]] = None,
                 base_dir: Optional[Union[str, "os.PathLike[str]"]] = None, **overrides: Any):
        sets, spellings = _sets(overrides, set)
        with _spoken(spellings):
            self._sim = _native.CoSim(_source(scenario, base_dir), sets)

    @classmethod
    def _of(cls, sim: _native.CoSim) -> "CoSim":
        obj = cls.__new__(cls)
        obj._sim = sim
        return obj

    @classmethod
    def resume(cls, path: Union[str, "os.PathLike[str]"]) -> "CoSim":
        """The co-simulation saved by `checkpoint` at `path`."""
        return cls._of(_native.CoSim.resume(os.fspath(path)))

    @property
    def now(self) -> float:
        """Simulated time reached [s]: the state is at `now`, on the step grid
        (`advance(t)` leaves `now == t` for a `t` on the grid, else `t` rounded up)."""
        return self._sim.now

    @property
    def dt(self) -> float:
        """The step [s]: the grid `now` moves on."""
        return self._sim.dt

    @property
    def duration(self) -> float:
        """The scenario's end [s]."""
        return self._sim.duration

    @property
    def finished(self) -> bool:
        """Whether the scenario's end is reached."""
        return self._sim.finished

    @property
    def channels(self) -> List[str]:
        """The channels' names, in the scenario's order."""
        return self._sim.channels

    @property
    def periods(self) -> List[float]:
        """The periods the channels run at [s] (achieved)."""
        return self._sim.periods

    @property
    def requested(self) -> List[float]:
        """The periods last asked for [s]."""
        return self._sim.requested

    @property
    def digest(self) -> str:
        """The digest of everything recorded so far."""
        return self._sim.digest

    def advance(self, t: float) -> None:
        """Advances to `t` [s], rounded up to the step grid, so `now == t` after it (a
        `t` past `duration` advances to the end, so `while not sim.finished:
        sim.advance(sim.now + h)` ends), closing the measurement window that ends at
        `t`. A `t` before `now` is refused (`InvalidScenarioError` naming `t`). Raises
        `DivergedError` on divergence; Ctrl-C stops it within a slice of steps (`now`
        says where; the co-simulation can go on from there) and raises
        KeyboardInterrupt."""
        self._sim.advance(float(t))

    def set_periods(self, periods: Sequence[float]) -> List[float]:
        """Sets every channel's period [s] from now on, each > 0 (one per channel, in
        `channels` order); returns the achieved ones."""
        return self._sim.set_periods([float(p) for p in periods])

    def schedule(self) -> List[Dict[str, Any]]:
        """The decisions made by `set_periods`, as a scenario's `schedule` section
        (`[{"at": t, "tau": [...]}, ...]`): the scenario with it, run through the
        command line, gives this co-simulation's digest. Raises `DsmcosimError` naming
        a decision a schedule cannot hold (off a window boundary, or a second one at
        the same time). A resumed CoSim holds the decisions made since it resumed."""
        return [{"at": at, "tau": list(tau)} for at, tau in self._sim.schedule()]

    def window_cost(self) -> Optional[Tuple[float, float]]:
        """`(t_end, cost)` of the last closed measurement window ([s], [m]), or None."""
        return self._sim.window_cost()

    def observe(self) -> "Observation":
        """The state at `now` as the step there records it (what trace.csv would hold
        at `now`), as arrays, without writing files: measured on a fork, so this
        co-simulation and its digest are untouched. Once `finished`, the last step's."""
        return Observation(self._sim.observe())

    def fork(self) -> "CoSim":
        """An independent copy: what is done to it leaves this one as it was."""
        return CoSim._of(self._sim.fork())

    def __copy__(self) -> "CoSim":
        """`copy.copy` is a fork: a co-simulation has no shallow copy."""
        return self.fork()

    def __deepcopy__(self, memo: Dict[int, Any]) -> "CoSim":
        return self.fork()

    def __reduce__(self) -> Tuple[Any, Tuple[bytes, List[Tuple[float, List[float]]]]]:
        """A CoSim pickles as its checkpoint's bytes and its decisions, so it goes to
        multiprocessing, joblib, Dask or Ray; the unpickled one continues to the same
        digest."""
        state, decisions = self._sim.state()
        return (_unpickle, (bytes(state), decisions))

    def checkpoint(self, out: Union[str, "os.PathLike[str]"]) -> Path:
        """Writes a checkpoint into `out/checkpoints/` and returns its path."""
        return Path(self._sim.checkpoint(os.fspath(out)))

    def __repr__(self) -> str:
        return f"CoSim(now={self.now:g} s of {self.duration:g} s, periods={self.periods})"


class Observation:
    """What a controller can read of a co-simulation at `time` [s] (`CoSim.observe`),
    as numpy arrays in the scenario's order: `bodies` (ids), `positions` [m],
    `velocities` [m/s], `angular_velocities` [rad/s] (n × 3, world frame),
    `orientations` (n × 4 unit quaternions w, x, y, z, body to world; 0 × 4 for point
    masses), `rows` (constraint rows' names, `L1` or `J2_0`, as trace.csv names them),
    `w` [m] and `f` [N] per row, `max_w` [m], `signals` (each traced FMU output by
    its trace column name, `unit.variable`, an array's elements `unit.variable[i]`, as
    the Python value of its FMI type: float, int, bool, str or bytes), and `deliveries`: a DataFrame with the
    last delivery on every route seen since the co-simulation was made or forked (a
    resumed or unpickled one starts with none) — `channel`, `from_node`, `to_node`
    (1-based), `kind` (`state`, `force`, `line`, `signal`), `element` (the body `B3`,
    the link `L5`, or `connections[i]`), the sample's time `sent`, its `delivered` time
    and its `age` at `time` [s]."""

    def __init__(self, seen: Mapping[str, Any]):
        import numpy as np
        self.time: float = seen["time"]
        self.bodies = np.asarray(seen["bodies"], dtype=np.int64)
        self.positions = np.asarray(seen["p"], dtype=np.float64).reshape(-1, 3)
        self.velocities = np.asarray(seen["v"], dtype=np.float64).reshape(-1, 3)
        self.angular_velocities = np.asarray(seen["omega"], dtype=np.float64).reshape(-1, 3)
        self.orientations = np.asarray(seen["q"], dtype=np.float64).reshape(-1, 4)
        self.rows: List[str] = list(seen["rows"])
        self.w = np.asarray(seen["w"], dtype=np.float64)
        self.f = np.asarray(seen["f"], dtype=np.float64)
        self.max_w: float = seen["max_w"]
        self.signals: Dict[str, Any] = dict(seen["signals"])
        self.deliveries = pd.DataFrame(
            list(seen["deliveries"]),
            columns=["channel", "from_node", "to_node", "kind", "element", "sent",
                     "delivered"]).astype({"from_node": "int64", "to_node": "int64",
                                           "sent": "float64", "delivered": "float64"})
        self.deliveries["age"] = self.time - self.deliveries["sent"]

    def __repr__(self) -> str:
        return (f"Observation(time={self.time:g} s, {len(self.bodies)} bodies, "
                f"{len(self.rows)} rows, max_w={self.max_w:.3e} m, "
                f"{len(self.signals)} signals)")


def _unpickle(state: bytes, decisions: List[Tuple[float, List[float]]]) -> CoSim:
    """The CoSim a pickle holds (`CoSim.__reduce__`)."""
    return CoSim._of(_native.CoSim.from_state(state, decisions))
