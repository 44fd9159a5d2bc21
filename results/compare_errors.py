#!/usr/bin/env python3
"""Position and velocity errors of bodies 1 and 16 in the controlled space-CP runs (both
readings of delay: <run> latency = tau, <run>_hold sample-and-hold; and the
online-measured runs <run>_online of the thesis reading),
relative to the monolithic reference (grid16_monolithic: same scene, no partition, no
delay), over growing horizons [0, H]. Reads results/<run>/trace.csv (every 100th step,
i.e. every 0.1 s). Usage: results/compare_errors.py [RESULTS_DIR]

Error over [0, H]: root mean square over the trace rows with t <= H of the Euclidean
distance |p_run - p_ref| (position, [m]) and |v_run - v_ref| (velocity, [m/s])."""
import csv, math, os, sys

root = sys.argv[1] if len(sys.argv) > 1 else os.path.dirname(os.path.abspath(__file__))
REF = "grid16_monolithic"
RUNS = [(n + suffix, f"{label}, {reading}")
        for suffix, reading in (("", "thesis reading"), ("_hold", "sample-and-hold"))
        for n, label in (("grid16_space_cp_no_opt", "no optimization (5/5 ms)"),
                         ("grid16_space_cp", "DSM, D_s 12 ms"),
                         ("grid16_space_cp_ds2", "DSM, D_s 2 ms"))]
# The online-measured DSM runs exist in the thesis reading only.
RUNS += [("grid16_space_cp_online", "DSM online, D_s 12 ms, thesis reading"),
         ("grid16_space_cp_ds2_online", "DSM online, D_s 2 ms, thesis reading")]
HORIZONS = [1, 2, 3, 5, 10, 20, 30]


def load(name):
    with open(os.path.join(root, name, "trace.csv")) as f:
        return [{k: float(v) for k, v in r.items()} for r in csv.DictReader(f)]


def rms(ref, run, body, kind, horizon):
    sq = [sum((a[f"{kind}{ax}_B{body}"] - b[f"{kind}{ax}_B{body}"]) ** 2 for ax in "xyz")
          for a, b in zip(ref, run) if a["t"] <= horizon + 1e-9]
    return math.sqrt(sum(sq) / len(sq))


ref = load(REF)
# Scale of the motion itself: rms |p - p(0)| and |v| of the reference over the horizon.
print(f"reference {REF}: rms displacement / speed of the body over [0, H]")
for body in (1, 16):
    cells = []
    for h in HORIZONS:
        rows = [r for r in ref if r["t"] <= h + 1e-9]
        d = math.sqrt(sum(sum((r[f"p{ax}_B{body}"] - ref[0][f"p{ax}_B{body}"]) ** 2
                              for ax in "xyz") for r in rows) / len(rows))
        s = math.sqrt(sum(sum(r[f"v{ax}_B{body}"] ** 2 for ax in "xyz") for r in rows) / len(rows))
        cells.append(f"{d:.3g} m / {s:.3g} m/s")
    print(f"  B{body}: " + "; ".join(f"H={h}: {c}" for h, c in zip(HORIZONS, cells)))
for kind, unit in (("p", "m"), ("v", "m/s")):
    what = "position" if kind == "p" else "velocity"
    print(f"rms {what} error [{unit}] against {REF}, over [0, H] s")
    print("  run | body | " + " | ".join(f"H={h}" for h in HORIZONS))
    for name, label in RUNS:
        run = load(name)
        # A run that diverged ends early: its horizons past the end are left out.
        assert [r["t"] for r in run] == [r["t"] for r in ref][:len(run)], name
        end = run[-1]["t"]
        for body in (1, 16):
            print(f"  {label} | B{body} | " + " | ".join(
                f"{rms(ref, run, body, kind, h):.3g}" if h <= end + 1e-9 else f"– (ends {end:g} s)"
                for h in HORIZONS))
