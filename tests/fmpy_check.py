"""FMPy, an independent FMI importer, against dsmcosim on the test FMUs.

Usage: python tests/fmpy_check.py DSMCOSIM_BINARY FMU_DIR SCRATCH_DIR

1. FMPy's validation accepts each FMU's model description (msd, pd, faulty).
2. The mass-spring-damper FMU alone (m 1.5 kg, k 4 N/m, c 0.4 N s/m, x0 1 m, v0 0.5 m/s,
   a constant 2 N force), stepped at 1 ms for 3 s, gives the same x, v and a in FMPy and
   in a dsmcosim run of a scene holding only that FMU: both call the same binary at the
   same communication points. They agree to round-off, not to the bit: dsmcosim hands
   the FMU the step h = dt exactly, FMPy a step computed from floating-point times
   (which can move msd's substep count ceil(h / 0.1 ms) by one); the bound is 1e-12.

.ci/run installs FMPy from PyPI into a fresh venv and runs this; exit 0 on success.
"""

import csv
import json
import os
import subprocess
import sys

import fmpy
from fmpy.validation import validate_fmu


def main():
    binary, fmu_dir, scratch = sys.argv[1:4]
    os.makedirs(scratch, exist_ok=True)
    for stem in ("msd", "pd", "faulty"):
        problems = validate_fmu(os.path.join(fmu_dir, stem + ".fmu"))
        if problems:
            sys.exit(f"FMPy rejects {stem}.fmu: {problems}")
        print(f"{stem}.fmu: FMPy accepts its model description")

    start = {"m": 1.5, "k": 4.0, "c": 0.4, "x0": 1.0, "v0": 0.5}
    force = 2.0
    msd = os.path.abspath(os.path.join(fmu_dir, "msd.fmu"))
    ours = fmpy.simulate_fmu(
        msd,
        stop_time=3.0,
        output_interval=0.001,
        start_values=dict(start, F=force),
        output=["x", "v", "a"],
    )

    scene = {
        "name": "fmpy_msd",
        "seed": 1,
        "duration": 3.0,
        "dt": 0.001,
        "output": {"decimation": 1},
        "fmus": [{"name": "plant", "path": msd, "start": dict(start, F=force)}],
    }
    path = os.path.join(scratch, "fmpy_msd.json")
    with open(path, "w") as f:
        json.dump(scene, f)
    out = os.path.join(scratch, "fmpy_msd")
    subprocess.run([binary, "run", path, "--out", out, "--force"], check=True,
                   stdout=subprocess.DEVNULL)
    with open(os.path.join(out, "trace.csv")) as f:
        rows = list(csv.DictReader(f))

    if len(rows) != len(ours):
        sys.exit(f"{len(rows)} dsmcosim rows against {len(ours)} FMPy rows")
    worst = 0.0
    for row, ref in zip(rows, ours):
        if abs(float(row["t"]) - ref["time"]) > 1e-9:
            sys.exit(f"times differ: {row['t']} against {ref['time']}")
        for var in ("x", "v", "a"):
            worst = max(worst, abs(float(row["plant." + var]) - ref[var]))
    print(f"msd.fmu alone, 3 s at 1 ms: largest |dsmcosim - FMPy| over x, v, a = {worst:g}")
    if not worst <= 1e-12:
        sys.exit("dsmcosim and FMPy disagree on the same FMU")


if __name__ == "__main__":
    main()
