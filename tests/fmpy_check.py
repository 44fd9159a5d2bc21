"""FMPy, an independent FMI importer, against dsmcosim on the test FMUs.

Usage: python tests/fmpy_check.py DSMCOSIM_BINARY FMU_DIR SCRATCH_DIR

1. FMPy's validation accepts each FMU's model description (msd, pd, faulty, and msd3,
   msd in FMI 3.0 form).
2. The mass-spring-damper FMU alone (m 1.5 kg, k 4 N/m, c 0.4 N s/m, x0 1 m, v0 0.5 m/s,
   a constant 2 N force), stepped at 1 ms for 3 s, gives the same x, v and a in FMPy and
   in a dsmcosim run of a scene holding only that FMU: both call the same binary at the
   same communication points. They agree to round-off, not to the bit: dsmcosim hands
   the FMU the step h = dt exactly, FMPy a step computed from floating-point times
   (which can move msd's substep count ceil(h / 0.1 ms) by one); the bound is 1e-12.
   The same for msd3 through FMPy's FMI 3.0 importer and dsmcosim's.
3. types (FMI 2.0) and types3 (FMI 3.0), an output of every type (types3 also the array
   y sized by the structural parameter n_y, and z), stepped at 0.1 s for 1 s: every
   output FMPy reads (all but Strings and Binary) is the same in FMPy and in dsmcosim's
   trace.csv, exactly: integers as integers (Int64 and UInt64 beyond any f64), floats
   bit for bit (Float32 as a float32), Booleans as 0/1, y[1]..y[3] as FMPy's y.

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
    for stem in ("msd", "pd", "faulty", "msd3", "types", "types3"):
        problems = validate_fmu(os.path.join(fmu_dir, stem + ".fmu"))
        if problems:
            sys.exit(f"FMPy rejects {stem}.fmu: {problems}")
        print(f"{stem}.fmu: FMPy accepts its model description")

    failed = [stem for stem in ("msd", "msd3") if not compare(binary, fmu_dir, scratch, stem)]
    failed += [s for s in ("types", "types3") if not compare_types(binary, fmu_dir, scratch, s)]
    if failed:
        sys.exit(f"dsmcosim and FMPy disagree on the same FMU: {', '.join(failed)}")


def compare(binary, fmu_dir, scratch, stem):
    """Runs the FMU `stem` alone in FMPy and in dsmcosim; True if they agree."""
    start = {"m": 1.5, "k": 4.0, "c": 0.4, "x0": 1.0, "v0": 0.5}
    force = 2.0
    msd = os.path.abspath(os.path.join(fmu_dir, stem + ".fmu"))
    ours = fmpy.simulate_fmu(
        msd,
        stop_time=3.0,
        output_interval=0.001,
        start_values=dict(start, F=force),
        output=["x", "v", "a"],
    )

    scene = {
        "name": f"fmpy_{stem}",
        "seed": 1,
        "duration": 3.0,
        "dt": 0.001,
        "output": {"decimation": 1},
        "fmus": [{"name": "plant", "path": msd, "start": dict(start, F=force)}],
    }
    path = os.path.join(scratch, f"fmpy_{stem}.json")
    with open(path, "w") as f:
        json.dump(scene, f)
    out = os.path.join(scratch, f"fmpy_{stem}")
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
    print(f"{stem}.fmu alone, 3 s at 1 ms: largest |dsmcosim - FMPy| over x, v, a = {worst:g}")
    return worst <= 1e-12


def compare_types(binary, fmu_dir, scratch, stem):
    """Runs the FMU `stem` (types or types3) alone in FMPy and in dsmcosim with its own
    start values; True if every output FMPy reads is the same in both, exactly."""
    import numpy as np

    path = os.path.abspath(os.path.join(fmu_dir, stem + ".fmu"))
    md = fmpy.read_model_description(path)
    outputs = [v for v in md.modelVariables
               if v.causality == "output" and v.type not in ("String", "Binary")]
    ours = fmpy.simulate_fmu(path, stop_time=1.0, output_interval=0.1,
                             output=[v.name for v in outputs])
    scene = {
        "name": f"fmpy_{stem}", "seed": 1, "duration": 1.0, "dt": 0.1,
        "output": {"decimation": 1},
        "fmus": [{"name": "u", "path": path}],
    }
    scene_path = os.path.join(scratch, f"fmpy_{stem}.json")
    with open(scene_path, "w") as f:
        json.dump(scene, f)
    out = os.path.join(scratch, f"fmpy_{stem}")
    subprocess.run([binary, "run", scene_path, "--out", out, "--force"], check=True,
                   stdout=subprocess.DEVNULL)
    with open(os.path.join(out, "trace.csv"), newline="") as f:
        rows = list(csv.DictReader(f))
    if len(rows) != len(ours):
        sys.exit(f"{stem}: {len(rows)} dsmcosim rows against {len(ours)} FMPy rows")

    def same(text, ref, type_):
        if type_ == "Boolean":
            return text == ("1" if ref else "0")
        if type_ == "Float32":
            return np.float32(text) == ref
        if type_ in ("Float64", "Real"):
            return float(text) == float(ref)
        return int(text) == int(ref)  # every integer type, exactly

    compared = 0
    for row, ref in zip(rows, ours):
        for v in outputs:
            values = np.atleast_1d(ref[v.name])
            names = ([f"u.{v.name}[{i + 1}]" for i in range(len(values))]
                     if v.dimensions else [f"u.{v.name}"])
            for name, value in zip(names, values):
                if not same(row[name], value, v.type):
                    print(f"{stem}: {name} at t = {row['t']}: dsmcosim {row[name]}, FMPy {value}")
                    return False
                compared += 1
    print(f"{stem}.fmu alone, 1 s at 0.1 s: {compared} values of {len(outputs)} outputs "
          "the same in dsmcosim and FMPy")
    return True


if __name__ == "__main__":
    main()
