"""The package's functions over the native module (`dsmcosim._native`)."""

import json
import os
import shutil
import tempfile
from pathlib import Path
from typing import Any, Callable, Dict, List, Mapping, Optional, Tuple, Union

import pandas as pd

from . import _native

Scenario = Union[str, "os.PathLike[str]", Mapping[str, Any]]

# The CSV files a run writes, by the attribute of `Run` that holds each.
_TABLES = {"trace": "trace.csv", "epochs": "epochs.csv", "network": "network.csv"}


def _pointer(name: str) -> str:
    """A keyword override's JSON pointer: `duration` -> `/duration`, and `__` separates
    the steps of a path: `channels__0__tau` -> `/channels/0/tau`."""
    return "/" + "/".join(name.split("__"))


def _sets(overrides: Mapping[str, Any], set: Optional[Mapping[str, Any]]) -> List[str]:
    """`--set POINTER=VALUE` strings, keyword overrides first, then `set`'s pointers, in
    the order given (a later one wins, as on the command line)."""
    pairs = [(_pointer(k), v) for k, v in overrides.items()]
    pairs += list((set or {}).items())
    for pointer, _ in pairs:
        if not pointer.startswith("/"):
            raise ValueError(f"an override's JSON pointer starts with '/': {pointer!r}")
    return [f"{p}={json.dumps(v)}" for p, v in pairs]


def _source(scenario: Scenario, base_dir: Optional[Union[str, "os.PathLike[str]"]]):
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


class _Bars:
    """tqdm bars (`tqdm.auto`: a widget in a notebook, text on a terminal) for the
    crate's progress, one per unit it reports (`steps`, `windows`, `points`)."""

    def __init__(self):
        try:
            from tqdm.auto import tqdm
        except ImportError as e:
            raise ImportError("progress=True draws tqdm bars: `pip install tqdm` "
                              "(or pass a callable progress(position, total, unit))") from e
        self._tqdm = tqdm
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


def read_table(path: Union[str, "os.PathLike[str]"]) -> pd.DataFrame:
    """One of a run's CSV files as a DataFrame: numbers as float64 or int64 columns
    (an empty cell, a value the run did not produce, is NaN), text as object."""
    return pd.read_csv(path, keep_default_na=False, na_values=[""])


class Run:
    """A finished run: its `summary` (summary.json as a dict), its `digest`, and its
    tables `trace`, `epochs` and `network` (None where the run wrote none) as
    DataFrames. `directory` is where its files are, or None for a run made with
    `out=None` (its files were read, then removed)."""

    def __init__(self, directory: Path, keep: bool):
        with open(directory / "summary.json") as f:
            self.summary: Dict[str, Any] = json.load(f)
        self.digest: str = self.summary["digest"]
        tables = {
            attr: read_table(directory / name) if (directory / name).is_file() else None
            for attr, name in _TABLES.items()
        }
        self.trace: Optional[pd.DataFrame] = tables["trace"]
        self.epochs: Optional[pd.DataFrame] = tables["epochs"]
        self.network: Optional[pd.DataFrame] = tables["network"]
        self.directory: Optional[Path] = directory if keep else None

    def __repr__(self) -> str:
        where = f", directory={str(self.directory)!r}" if self.directory else ""
        return (f"Run(scenario={self.summary.get('scenario')!r}, "
                f"status={self.summary.get('status')!r}, digest={self.digest[:16]!r}…{where})")


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
    instead (every 1024 steps, every window).

    Raises `DsmcosimError` for bad input (naming the field) and for a run that diverged
    (its outputs up to the divergence are in `out`). The GIL is released while it runs.
    """
    sets = _sets(overrides, set)
    source = _source(scenario, base_dir)
    report, close = _reporter(progress)
    keep = out is not None
    directory = Path(out) if keep else Path(tempfile.mkdtemp(prefix="dsmcosim-run-"))
    try:
        _native.run(source, os.fspath(directory), sets, force, report)
        return Run(directory, keep)
    finally:
        close()
        if not keep:
            shutil.rmtree(directory, ignore_errors=True)


def validate(scenario: Scenario, *, set: Optional[Mapping[str, Any]] = None,
             base_dir: Optional[Union[str, "os.PathLike[str]"]] = None,
             **overrides: Any) -> Dict[str, Any]:
    """Checks `scenario` as a run would before it starts and returns its plan as a
    dict (what `dsmcosim validate --json` writes: nodes, channels with their achieved
    delays, the network, the coupling, the size of the run). Overrides as for `run`.
    Raises `DsmcosimError` naming the field of bad input."""
    sets = _sets(overrides, set)
    return json.loads(_native.validate(_source(scenario, base_dir), sets))


def sweep(sweep_file: Union[str, "os.PathLike[str]", Mapping[str, Any]],
          out: Union[str, "os.PathLike[str]"], *, keep: str = "all", resume: bool = False,
          set: Optional[Mapping[str, Any]] = None,
          base_dir: Optional[Union[str, "os.PathLike[str]"]] = None,
          progress: Progress = None, **overrides: Any) -> pd.DataFrame:
    """Runs a sweep into `out` (as `dsmcosim sweep`) and returns its table,
    `out/sweep.csv`, as a DataFrame (one row per point).

    `sweep_file`: a sweep file's path, or a sweep as a dict (its `base` scenario path
    read relative to `base_dir`, default the working directory). `keep`: what each
    point keeps of its run (`"summary"`, `"trace"` or `"all"`); `resume` continues a
    sweep in `out`. Overrides change the base scenario, as `--set` does.
    `progress=True` shows a tqdm bar over the points (or pass a callable
    `progress(position, total, unit)`)."""
    sets = _sets(overrides, set)
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
        _native.sweep(path=path, out=os.fspath(out), sets=sets, keep=keep, resume=resume,
                      progress=report)
    finally:
        close()
        if scratch is not None:
            shutil.rmtree(scratch, ignore_errors=True)
    return read_table(Path(out) / "sweep.csv")


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
        self._sim = _native.CoSim(_source(scenario, base_dir), _sets(overrides, set))

    @classmethod
    def _of(cls, sim) -> "CoSim":
        obj = cls.__new__(cls)
        obj._sim = sim
        return obj

    @classmethod
    def resume(cls, path: Union[str, "os.PathLike[str]"]) -> "CoSim":
        """The co-simulation saved by `checkpoint` at `path`."""
        return cls._of(_native.CoSim.resume(os.fspath(path)))

    @property
    def now(self) -> float:
        """Simulated time reached [s]."""
        return self._sim.now

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
        """Advances to `t` [s] (at most `duration`), closing the measurement window
        that ends at `t`. Raises `DsmcosimError` on divergence."""
        self._sim.advance(float(t))

    def set_periods(self, periods: List[float]) -> List[float]:
        """Sets every channel's period [s] from now on; returns the achieved ones."""
        return self._sim.set_periods([float(p) for p in periods])

    def schedule(self) -> List[Dict[str, Any]]:
        """The decisions made by `set_periods`, as a scenario's `schedule` section
        (`[{"at": t, "tau": [...]}, ...]`): the scenario with it, run through the
        command line, gives this co-simulation's digest. Raises `DsmcosimError` naming
        a decision a schedule cannot hold (off a window boundary, or a second one at
        the same time). A resumed CoSim holds the decisions made since it resumed."""
        return [{"at": at, "tau": list(tau)} for at, tau in self._sim.schedule()]

    def window_cost(self) -> Optional[tuple]:
        """`(t_end, cost)` of the last closed measurement window ([s], [m]), or None."""
        return self._sim.window_cost()

    def fork(self) -> "CoSim":
        """An independent copy: what is done to it leaves this one as it was."""
        return CoSim._of(self._sim.fork())

    def checkpoint(self, out: Union[str, "os.PathLike[str]"]) -> Path:
        """Writes a checkpoint into `out/checkpoints/` and returns its path."""
        return Path(self._sim.checkpoint(os.fspath(out)))

    def __repr__(self) -> str:
        return f"CoSim(now={self.now:g} s of {self.duration:g} s, periods={self.periods})"
