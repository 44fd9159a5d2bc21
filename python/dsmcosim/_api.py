"""The package's functions over the native module (`dsmcosim._native`)."""

import json
import os
import shutil
import tempfile
from pathlib import Path
from typing import Any, Dict, List, Mapping, Optional, Union

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
        base_dir: Optional[Union[str, "os.PathLike[str]"]] = None, **overrides: Any) -> Run:
    """Runs `scenario` (a scenario file's path, or a scenario as a dict) and returns its
    `Run`.

    `out`: the directory the run writes (as `dsmcosim run --out`); None runs into a
    temporary directory that is removed once its files are read. Keyword `overrides`
    change the scenario as `--set` does: `duration=3.0` sets `/duration`, and `__`
    separates path steps (`channels__0__tau=0.004` sets `/channels/0/tau`); `set` takes
    JSON pointers for keys that are not identifiers (`set={"/network/drift_ppm": 100}`).
    `force` replaces another scenario's run in `out`. `base_dir`: where a dict
    scenario's relative paths (FMUs) are read from, default the working directory.

    Raises `DsmcosimError` for bad input (naming the field) and for a run that diverged
    (its outputs up to the divergence are in `out`). The GIL is released while it runs.
    """
    sets = _sets(overrides, set)
    source = _source(scenario, base_dir)
    keep = out is not None
    directory = Path(out) if keep else Path(tempfile.mkdtemp(prefix="dsmcosim-run-"))
    try:
        _native.run(source, os.fspath(directory), sets, force)
        return Run(directory, keep)
    finally:
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


def sweep(sweep_file: Union[str, "os.PathLike[str]"], out: Union[str, "os.PathLike[str]"], *,
          keep: str = "all", resume: bool = False, set: Optional[Mapping[str, Any]] = None,
          **overrides: Any) -> pd.DataFrame:
    """Runs the sweep file `sweep_file` into `out` (as `dsmcosim sweep`) and returns its
    table, `out/sweep.csv`, as a DataFrame (one row per point). `keep`: what each
    point keeps of its run (`"summary"`, `"trace"` or `"all"`); `resume` continues a
    sweep in `out`. Overrides change the base scenario, as `--set` does."""
    sets = _sets(overrides, set)
    _native.sweep(path=os.fspath(sweep_file), out=os.fspath(out), sets=sets, keep=keep,
                  resume=resume)
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

    The scenario must have no `controller` (Python is the controller); its channels'
    `tau` are the periods it starts at, and `measurement.period` sets the windows whose
    cost `window_cost()` gives. Same scenario and same decisions give the same digest,
    the command line's for the same scenario when the periods are never changed (or set
    once at t = 0 to the values the file would hold). The GIL is released while it
    advances.
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
