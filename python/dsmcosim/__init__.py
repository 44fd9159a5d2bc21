"""dsmcosim from Python: run, validate and sweep scenarios, and read their outputs as
pandas DataFrames.

    import dsmcosim
    run = dsmcosim.run("scenarios/grid16_space_fixed.json", duration=3.0)
    run.digest, run.summary["max_constraint_violation"]
    run.trace[["t", "w_L1"]]

The simulation is the crate's own (the same code as the `dsmcosim` command), so a run
from Python gives the same digest as the same run from the command line. See
docs/python.md.
"""

from ._native import __version__
from ._errors import (DivergedError, DsmcosimError, DsmcosimWarning, FileError,
                      InvalidScenarioError, NotFoundError, OutOfMemoryError,
                      PermissionDeniedError, SimulationError, StoppedError)
from ._api import (CoSim, Observation, Run, load, point, read_table, run, sweep,
                   validate)

__all__ = ["CoSim", "DivergedError", "DsmcosimError", "DsmcosimWarning", "FileError",
           "InvalidScenarioError", "NotFoundError", "Observation", "OutOfMemoryError",
           "PermissionDeniedError", "Run", "SimulationError", "StoppedError", "load", "point",
           "read_table", "run", "sweep", "validate", "__version__"]
