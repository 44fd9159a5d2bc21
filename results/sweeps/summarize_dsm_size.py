#!/usr/bin/env python3
"""Which simplex size D_s tracks best, per distribution and reading of delay: reads the
sweeps results/sweeps/dsm_size_cp/ (thesis reading) and dsm_size_cp_hold/ (sample and
hold), written by

    dsmcosim sweep scenarios/sweeps/dsm_size_cp.json --out results/sweeps/dsm_size_cp
    dsmcosim sweep scenarios/sweeps/dsm_size_cp_hold.json --out results/sweeps/dsm_size_cp_hold

Each point is the 30-s constrained experiment (space or time distribution) with the DSM
live at one D_s and the grid search and no optimization measured every window from the
live state. "Tracks best" = the lowest DSM/grid ratio of mean window costs (the grid
optimum is the best 1 ms point of each window, chosen with hindsight). The mean gap
|DSM delay - grid optimum| over the windows is read from the per-point epochs.csv
(points/<point>/, written by the sweep, not stored in git); "-" where they are absent.
Usage: results/sweeps/summarize_dsm_size.py [SWEEPS_DIR]"""
import csv, os, sys

def gap(epochs, channel):
    """Mean |requested delay - grid optimum| of the controlled channel [ms], or None."""
    if not os.path.isfile(epochs):
        return None
    rows = list(csv.DictReader(open(epochs)))
    d = [abs(float(r[f"tau_{channel}_requested"]) - float(r[f"grid_opt_tau_{channel}"])) for r in rows]
    return sum(d) / len(d) * 1e3


root = sys.argv[1] if len(sys.argv) > 1 else os.path.dirname(os.path.abspath(__file__))
for sweep, reading in (("dsm_size_cp", "thesis reading"), ("dsm_size_cp_hold", "sample and hold")):
    path = os.path.join(root, sweep, "sweep.csv")
    if not os.path.isfile(path):
        print(f"{sweep}: not found"); continue
    rows = list(csv.DictReader(open(path)))
    for dist in ("tau1", "state"):
        name = "space" if dist == "tau1" else "time"
        mine = [r for r in rows if r["distribution"] == name]
        print(f"== {reading}, {name} CP ({sweep})")
        print("   D_s [ms] | status | DSM [m] | grid [m] | no-opt [m] | DSM/grid | DSM/no-opt | mean gap [ms]")
        best = None
        for r in mine:
            if r["status"] != "ok":
                print(f"   {float(r['dsm_size']) * 1e3:g} | {r['status']} | | | | |"); continue
            dsm, grid, no = (float(r[k]) for k in ("mean_cost_dsm", "mean_cost_grid", "mean_cost_no_opt"))
            g = gap(os.path.join(root, sweep, "points", r["point"], "epochs.csv"), dist)
            gap_text = "-" if g is None else f"{g:.2f}"
            print(f"   {float(r['dsm_size']) * 1e3:g} | ok | {dsm:.4f} | {grid:.4f} | {no:.4f} | "
                  f"{dsm / grid:.3f} | {dsm / no:.3f} | {gap_text}")
            if best is None or dsm / grid < best[1]:
                best = (float(r["dsm_size"]) * 1e3, dsm / grid, dsm / no, gap_text)
        if best:
            print(f"   tracks best: D_s = {best[0]:g} ms (DSM/grid {best[1]:.4f}, DSM/no-opt "
                  f"{best[2]:.3f}, mean gap {best[3]} ms)")
