"""The exceptions dsmcosim raises, each also an instance of the built-in exception a
Python user would catch for its kind: a bad scenario is a `ValueError`, a file that
cannot be read or written an `OSError` (`FileNotFoundError`, `PermissionError`), an
allocation that failed a `MemoryError`.

Every one carries `field` (what is wrong: a scenario field such as
`channels[0].tau`, a file, or an argument), `message` (what) and `exit_code` (what the
command line would exit with: 2 bad input, 3 a diverged or failed run, 1 a file).
Ctrl-C during a call raises Python's own `KeyboardInterrupt`.
"""

from typing import Optional


class DsmcosimError(Exception):
    """Any error of dsmcosim; the classes below say which kind."""

    field: str = ""
    message: str = ""
    exit_code: int = 1


class InvalidScenarioError(DsmcosimError, ValueError):
    """A scenario (or sweep, or argument) that cannot be run: `field` names it."""

    exit_code = 2


class FileError(DsmcosimError, OSError):
    """A file that could not be read or written: `filename` (and `field`) is its path,
    `errno` and `strerror` what the operating system said."""


class NotFoundError(FileError, FileNotFoundError):
    """A file that does not exist (a scenario, an FMU, a checkpoint)."""


class PermissionDeniedError(FileError, PermissionError):
    """A file or directory the process may not read or write."""


class SimulationError(DsmcosimError):
    """A run that could not go on: a numerical failure, an FMU's error."""

    exit_code = 3


class DivergedError(SimulationError):
    """A run whose state diverged: at `time` [s] on computing node `node`, in link
    `link` (`"L3"`), or joint `link` (`"J2"`) row `row`, or body `body` (`"B5"`) for a
    body without links, or an FMU's output `fmu_output` (`"plant.x"`) that is not a
    finite number; `what` says what was seen (`|w| = 1.3 m > bound 1 m`). The outputs
    up to the divergence are written."""

    time: float = 0.0
    node: int = 0
    link: Optional[str] = None
    row: Optional[int] = None
    body: Optional[str] = None
    fmu_output: Optional[str] = None
    what: str = ""


class OutOfMemoryError(DsmcosimError, MemoryError):
    """An allocation the run needed failed (the process's memory limit): nothing about
    the simulation is wrong."""


class StoppedError(DsmcosimError):
    """A sweep stopped by its progress callable returning False: the message counts the
    points finished; `sweep(..., resume=True)` runs the rest."""

    exit_code = 130


class DsmcosimWarning(UserWarning):
    """What the command line prints as `warning:` after a run (the SMC law left its
    boundary layer, did work on a joint, a channel's delays were not realized), issued
    through `warnings.warn`."""
