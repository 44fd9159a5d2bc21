#!/usr/bin/env python3
"""Prints every figure of the slot-layout study (results/README.md, "Slot-layout study")
from the stored sweep: `python3 results/sweeps/summarize_slot_layouts.py [DIR]`
(DIR defaults to results/sweeps/tdma4_slot_layouts; any output directory of
`dsmcosim sweep scenarios/sweeps/tdma4_slot_layouts.json` works).

Layout names come from scenarios/sweeps/make_tdma4_slot_layouts.py, checked against
the layout values recorded in DIR/sweep.json.
"""

import csv
import json
import math
import os
import statistics as st
import sys

sys.dont_write_bytecode = True  # no __pycache__ beside the sweep file
ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
sys.path.insert(0, os.path.join(ROOT, "scenarios", "sweeps"))
import make_tdma4_slot_layouts as gen  # noqa: E402


def main():
    out = sys.argv[1] if len(sys.argv) > 1 else os.path.join(
        ROOT, "results", "sweeps", "tdma4_slot_layouts")
    sweep = json.load(open(os.path.join(out, "sweep.json")))
    values = sweep["axes"][0]["values"]
    names = [n for n, _ in gen.LAYOUTS]
    assert values == [json.loads(json.dumps(v)) for _, v in gen.LAYOUTS], \
        "sweep.json's layouts differ from make_tdma4_slot_layouts.py"
    # sweep.csv names each layout by its label from the sweep file.
    labels = sweep["axes"][0]["labels"]
    rows = list(csv.DictReader(open(os.path.join(out, "sweep.csv"))))
    for r in rows:
        r["li"] = labels.index(r["layout"])
        r["cost"] = float(r["mean_cost"])
        r["lost"] = int(r["lost_frames"])
        r["d"] = float(r["drift"])
        r["tau"] = max(float(r["tau_tau1_achieved"]), float(r["tau_tau2_achieved"]))
    drifts = sorted({r["d"] for r in rows})
    draws = len({r["draw"] for r in rows})
    w = max(map(len, names))

    print(f"{len(rows)} points: {len(names)} layouts x {len(drifts)} drift levels "
          f"x {draws} draws (seeds)\n")
    print("Per layout, over all its points (mean cost ± standard error of the mean; "
          "tau = the larger channel's achieved tau, mean over windows):")
    means = {i: st.mean(r["cost"] for r in rows if r["li"] == i) for i in range(len(names))}
    best = min(means, key=means.get)
    print(f"  {'layout':<{w}}  {'mean cost [m]':>16}  {'vs lowest':>9}  {'lossy pts':>9}  {'lost frames':>11}"
          f"  {'diverged':>8}  {'median tau [ms]':>15}  {'worst tau [ms]':>14}"
          f"  {'first loss at [ppm]':>19}")
    for i, name in enumerate(names):
        rs = [r for r in rows if r["li"] == i]
        c = [r["cost"] for r in rs]
        se = st.stdev(c) / math.sqrt(len(c))
        lossy = [r for r in rs if r["lost"] > 0]
        first = min((r["d"] for r in lossy), default=None)
        print(f"  {name:<{w}}  {st.mean(c):.4f} ± {se:.4f}  {means[i] / means[best]:>8.3f}×"
              f"  {len(lossy):>4} / {len(rs):<3}"
              f"  {sum(r['lost'] for r in rs):>11}  {sum(r['status'] != 'ok' for r in rs):>8}"
              f"  {1e3 * st.median(r['tau'] for r in rs):>15.3f}"
              f"  {1e3 * max(r['tau'] for r in rs):>14.1f}"
              f"  {'none' if first is None else f'{first:g}':>19}")

    print("\nMean cost [m] per drift level (mean over the draws; * = some draw lost frames):")
    print(f"  {'layout':<{w}}  " + "  ".join(f"{d:>8g}" for d in drifts))
    for i, name in enumerate(names):
        cells = []
        for d in drifts:
            rs = [r for r in rows if r["li"] == i and r["d"] == d]
            star = "*" if any(r["lost"] for r in rs) else " "
            cells.append(f"{st.mean(r['cost'] for r in rs):>7.4f}{star}")
        print(f"  {name:<{w}}  " + "  ".join(cells))

    print("\nSpread of the cost over the draws [m] (standard deviation, per drift level):")
    print(f"  {'layout':<{w}}  " + "  ".join(f"{d:>8g}" for d in drifts))
    for i, name in enumerate(names):
        cells = []
        for d in drifts:
            c = [r["cost"] for r in rows if r["li"] == i and r["d"] == d]
            cells.append(f"{st.stdev(c):>8.4f}")
        print(f"  {name:<{w}}  " + "  ".join(cells))

    print("\nLost frames per drift level (sum over the draws; lossy draws in brackets):")
    print(f"  {'layout':<{w}}  " + "  ".join(f"{d:>12g}" for d in drifts))
    for i, name in enumerate(names):
        cells = []
        for d in drifts:
            rs = [r for r in rows if r["li"] == i and r["d"] == d]
            cells.append(f"{sum(r['lost'] for r in rs):>7} ({sum(r['lost'] > 0 for r in rs):>2})")
        print(f"  {name:<{w}}  " + "  ".join(cells))

    lossless = [d for d in drifts
                if not any(r["lost"] or r["status"] != "ok" for r in rows if r["d"] == d)]
    print(f"\nDrift levels where no layout loses a frame: {', '.join(f'{d:g}' for d in lossless)} ppm;"
          " mean cost there:")
    for i, name in enumerate(names):
        c = [r["cost"] for r in rows if r["li"] == i and r["d"] in lossless]
        print(f"  {name:<{w}}  {st.mean(c):.4f} ± {st.stdev(c) / math.sqrt(len(c)):.4f}")

    print(f"\nLowest mean cost: {names[best]}; the others relative to it are in `vs lowest`.")

    print("\nPairs of layouts whose points all have the same digest:")
    digests = {i: [r["digest"] for r in rows if r["li"] == i] for i in range(len(names))}
    for i in range(len(names)):
        for j in range(i + 1, len(names)):
            if digests[i] == digests[j]:
                print(f"  {names[i]} = {names[j]} (all {len(digests[i])} points)")


if __name__ == "__main__":
    main()
